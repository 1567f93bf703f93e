//! The narrow phase's measured costs, for choosing how many pairs to test under a time budget.
use std::time::Duration;

/// The narrow phase's measured costs (time mode), as moving averages of wall-clock time:
/// a test, and an answer from memory (or for a bounds-only pair), both in parallel.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairCosts {
    pub test_us: f64,
    pub memory_us: f64,
}

impl Default for PairCosts {
    fn default() -> Self {
        Self {
            test_us: 2.0,
            memory_us: 0.05,
        }
    }
}

impl PairCosts {
    pub fn learn(value: &mut f64, count: usize, time: Duration) {
        // A handful of pairs says little about the cost of many (pool start-up dominates).
        if count >= 32 {
            *value = 0.8 * *value + 0.2 * time.as_secs_f64() * 1e6 / count as f64;
        }
    }
}

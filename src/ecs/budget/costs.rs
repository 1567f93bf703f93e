//! What the budget controller measures: the cost of a test and of an answer from memory, the
//! rate at which ADB tests visit node pairs.
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

/// What the budget learns from earlier runs (time mode): node pairs per microsecond of test
/// wall-clock time, as a moving average.
#[derive(Debug, Clone, Copy)]
pub(crate) struct WorkRate {
    pub node_pairs_per_us: f64,
}

impl Default for WorkRate {
    fn default() -> Self {
        Self {
            node_pairs_per_us: 20.0,
        }
    }
}

impl WorkRate {
    /// Folds in one run: `node_pairs` visited in `us` microseconds of tests.
    pub fn update(&mut self, node_pairs: u64, us: f64) {
        if us <= 1.0 || node_pairs == 0 {
            return;
        }
        let rate = node_pairs as f64 / us;
        self.node_pairs_per_us = 0.8 * self.node_pairs_per_us + 0.2 * rate;
    }
}

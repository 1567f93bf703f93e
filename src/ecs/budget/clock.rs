//! The clock the budget reads: the system's, or one a test moves by hand.
use std::fmt;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Where the [`BudgetController`](super::BudgetController) reads the time: every stage's
/// timing, the run's deadlines and the response budget come from it.
///
/// The default is [`SystemClock`]. A test installs a [`FakeClock`] with
/// [`BudgetController::set_clock`](super::BudgetController::set_clock) and moves it by hand, to
/// drive the controller through overload and recovery without depending on the machine's
/// speed. The narrow phase's tests (their deadlines and an ADB traversal's node cap) read this
/// clock; a tracker's search is given its deadline as an `Instant` of this clock but compares
/// it with the system clock, so under a `FakeClock` its cut follows real time.
pub trait BudgetClock: Send + Sync + fmt::Debug + 'static {
    /// The current time.
    fn now(&self) -> Instant;
}

/// The system's monotonic clock ([`Instant::now`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct SystemClock;

impl BudgetClock for SystemClock {
    #[inline]
    fn now(&self) -> Instant {
        Instant::now()
    }
}

/// A clock that stands still until it is moved ([`FakeClock::advance`]), or that moves by a
/// fixed step at every reading ([`FakeClock::ticking`]: the time a piece of work measures is
/// then the number of clock readings it made, a stand-in for its cost that is the same on
/// every machine). Clones share the same time, so a test keeps one handle and gives the
/// controller another.
///
/// ```
/// use std::time::Duration;
/// use stochastic_collision::ecs::{BudgetClock, FakeClock};
///
/// let clock = FakeClock::new();
/// let handle = clock.clone();
/// let t0 = clock.now();
/// handle.advance(Duration::from_millis(3));
/// assert_eq!(clock.now() - t0, Duration::from_millis(3));
///
/// let ticking = FakeClock::ticking(Duration::from_micros(1));
/// let t0 = ticking.now();
/// assert_eq!(ticking.now() - t0, Duration::from_micros(1));
/// ```
#[derive(Clone)]
pub struct FakeClock {
    start: Instant,
    nanos: Arc<AtomicU64>,
    tick: u64,
}

impl FakeClock {
    /// A clock standing at the moment it is made.
    pub fn new() -> Self {
        Self::ticking(Duration::ZERO)
    }

    /// A clock that moves forward by `step` after every reading.
    pub fn ticking(step: Duration) -> Self {
        Self {
            start: Instant::now(),
            nanos: Arc::new(AtomicU64::new(0)),
            tick: u64::try_from(step.as_nanos()).unwrap_or(u64::MAX),
        }
    }

    /// Moves the clock (and its clones) forward by `by`.
    pub fn advance(&self, by: Duration) {
        let by = u64::try_from(by.as_nanos()).unwrap_or(u64::MAX);
        self.nanos.fetch_add(by, Ordering::SeqCst);
    }

    /// How far the clock has been moved since it was made.
    pub fn elapsed(&self) -> Duration {
        Duration::from_nanos(self.nanos.load(Ordering::SeqCst))
    }
}

impl Default for FakeClock {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Debug for FakeClock {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FakeClock")
            .field("elapsed", &self.elapsed())
            .finish()
    }
}

impl BudgetClock for FakeClock {
    fn now(&self) -> Instant {
        let nanos = if self.tick == 0 {
            self.nanos.load(Ordering::SeqCst)
        } else {
            self.nanos.fetch_add(self.tick, Ordering::SeqCst)
        };
        self.start + Duration::from_nanos(nanos)
    }
}

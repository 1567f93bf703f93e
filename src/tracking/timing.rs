//! Where a tracker step's time went.

use std::time::{Duration, Instant};

/// Wall-clock time of each stage of the last [`Tracker`](super::Tracker) step. The surface
/// update before it (positions, refit, normals and cones) is
/// [`TrackedSurface::update_time`](super::TrackedSurface::update_time).
///
/// Measured with [`Instant`] around each stage (a few clock reads per step): a profile of
/// where the time goes. Without a time budget the tracker's answers never depend on it; under
/// [`TrackerConfig::time_budget`](super::TrackerConfig::time_budget) the pairs per frame adapt
/// to the budget beside `candidates`.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct StepTimes {
    /// Finding where new pairs can come from: the overlapping patch pairs of the incomplete
    /// hierarchy, the patch pairs already holding a contact, and the fold and crease edges.
    pub candidates: Duration,
    /// Drawing the new pairs (uniform picks, crease probes, random descents inside the
    /// candidate patch pairs).
    pub sampling: Duration,
    /// The local search of every kept and new pair.
    pub local_search: Duration,
    /// Pruning far, duplicate, redundant and surplus pairs.
    pub pruning: Duration,
    /// Contacts and collision propagation around them.
    pub propagation: Duration,
    /// The continuous check ([`TrackerConfig::continuous`](super::TrackerConfig::continuous)):
    /// the pairs' neighbourhoods over the step and the crossings' contacts.
    pub continuous: Duration,
}

impl StepTimes {
    /// The sum of the stages.
    pub fn total(&self) -> Duration {
        self.candidates
            + self.sampling
            + self.local_search
            + self.pruning
            + self.propagation
            + self.continuous
    }
}

/// A stopwatch for consecutive stages: each [`Lap::lap`] returns the time since the last.
pub(crate) struct Lap(Instant);

impl Lap {
    pub fn start() -> Self {
        Lap(Instant::now())
    }

    pub fn lap(&mut self) -> Duration {
        let now = Instant::now();
        let d = now - self.0;
        self.0 = now;
        d
    }
}

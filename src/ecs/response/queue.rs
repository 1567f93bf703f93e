//! The contact queue: this run's contacts waiting for a response, highest priority first,
//! consumed within the response budget.
use std::sync::Arc;
use std::time::Duration;

use bevy_ecs::prelude::*;

use super::super::budget::{BudgetClock, SystemClock};
use super::super::config::ResponseBudget;
use super::super::events::Contact;

/// Contacts waiting for a response, highest priority first.
///
/// Filled by the Report stage (when some response is registered: the built-in response
/// plugins do it, a custom response calls [`ContactQueue::enable`] once). A response consumes
/// contacts with [`ContactQueue::consume`] inside the per-run response budget
/// ([`CollisionConfig::response_budget`](crate::ecs::CollisionConfig::response_budget): a time, or a number of contacts); what it leaves
/// stays queued, counted, for the next run. A newer contact of the same pair replaces a
/// waiting one.
#[derive(Resource, Debug, Default)]
pub struct ContactQueue {
    enabled: bool,
    queue: Vec<Contact>,
    /// Contacts left to consume in this run (`None`: no count).
    remaining: Option<usize>,
    /// Time left to consume contacts in this run (`None`: no time limit).
    remaining_time: Option<Duration>,
    /// The budget's clock (the system clock until the first run).
    clock: Option<Arc<dyn BudgetClock>>,
    /// Contacts left unconsumed at the end of a run (carried into the next, or superseded
    /// there by a newer contact of the same pair), summed over runs.
    pub deferred_total: u64,
    /// Contacts consumed by responses.
    pub consumed_total: u64,
    /// Waiting contacts replaced by a newer contact of the same pair.
    pub superseded_total: u64,
    /// Reused buffers: the pairs of the fresh contacts, the sort keys, the sorted queue.
    fresh_pairs: Vec<(Entity, Entity)>,
    keys: Vec<(f32, u32)>,
    sorted: Vec<Contact>,
}

impl ContactQueue {
    /// Starts filling the queue (call once when adding a response system).
    pub fn enable(&mut self) {
        self.enabled = true;
    }

    /// Whether the queue is filled.
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Contacts waiting, highest priority first.
    pub fn waiting(&self) -> &[Contact] {
        &self.queue
    }

    /// Number of contacts waiting.
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// Whether no contact is waiting.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// Contacts this run's response budget still allows (`None`: it counts no contacts).
    pub fn remaining_contacts(&self) -> Option<usize> {
        self.remaining
    }

    /// Time this run's response budget still allows (`None`: it has no time limit).
    pub fn remaining_time(&self) -> Option<Duration> {
        self.remaining_time
    }

    /// Whether this run's response budget is spent (no contact will be offered).
    pub fn budget_spent(&self) -> bool {
        self.remaining == Some(0) || self.remaining_time == Some(Duration::ZERO)
    }

    /// Offers the waiting contacts to `respond`, highest priority first, until this run's
    /// response budget is spent. `respond` returns `true` if it consumed the contact (it
    /// leaves the queue and costs one unit of a count budget), `false` to leave it to another
    /// response. Under a time budget the time spent in this call is charged, and a contact is
    /// offered only while some is left.
    pub fn consume(&mut self, mut respond: impl FnMut(&Contact) -> bool) -> usize {
        if self.budget_spent() {
            return 0;
        }
        let clock = self.clock.clone().unwrap_or_else(|| Arc::new(SystemClock));
        let start = self.remaining_time.map(|_| clock.now());
        let deadline = start.zip(self.remaining_time).map(|(s, t)| s + t);
        let (mut consumed, mut offered, mut stopped) = (0, false, false);
        let mut remaining = self.remaining;
        self.queue.retain(|c| {
            stopped = stopped
                || remaining == Some(0)
                || (offered && deadline.is_some_and(|d| clock.now() >= d));
            if stopped {
                return true;
            }
            offered = true;
            if !respond(c) {
                return true;
            }
            consumed += 1;
            if let Some(r) = &mut remaining {
                *r -= 1;
            }
            false
        });
        self.remaining = remaining;
        if let (Some(start), Some(left)) = (start, &mut self.remaining_time) {
            *left = left.saturating_sub(clock.now().saturating_duration_since(start));
        }
        self.consumed_total += consumed as u64;
        consumed
    }

    pub(crate) fn refill(
        &mut self,
        fresh: &mut Vec<Contact>,
        budget: ResponseBudget,
        clock: Arc<dyn BudgetClock>,
    ) {
        (self.remaining, self.remaining_time) = match budget {
            ResponseBudget::Unlimited => (None, None),
            ResponseBudget::Time(t) => (None, Some(t)),
            ResponseBudget::Contacts(n) => (Some(n), None),
        };
        self.clock = Some(clock);
        if !self.enabled {
            return;
        }
        let before = self.queue.len();
        self.deferred_total += before as u64;
        if before > 0 {
            let fresh_pairs = &mut self.fresh_pairs;
            fresh_pairs.clear();
            fresh_pairs.extend(fresh.iter().map(|c| (c.a, c.b)));
            fresh_pairs.dedup();
            self.queue
                .retain(|c| fresh_pairs.binary_search(&(c.a, c.b)).is_err());
            self.superseded_total += (before - self.queue.len()) as u64;
        }
        // Sorted by small keys, then moved once (contacts are large): by priority, ties in
        // queue order (waiting contacts first, then the fresh ones in pair order), the same
        // for any thread count. Keys are unique (the index), so an unstable sort is exact.
        let keys = &mut self.keys;
        keys.clear();
        let all = self.queue.iter().chain(fresh.iter());
        keys.extend(all.enumerate().map(|(i, c)| (c.priority, i as u32)));
        keys.sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        let waiting = self.queue.len();
        let sorted = &mut self.sorted;
        sorted.clear();
        sorted.extend(
            keys.iter()
                .map(|&(_, i)| match (i as usize).checked_sub(waiting) {
                    None => self.queue[i as usize],
                    Some(f) => fresh[f],
                }),
        );
        std::mem::swap(&mut self.queue, sorted);
        fresh.clear();
    }
}

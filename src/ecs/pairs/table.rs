//! The persistent pair table: one stable slot per candidate pair of colliders, kept from run
//! to run. Created and removed by the broad phase, answered by the narrow phase and the
//! Tracking stage, read by the Report stage (its transitions only) and by users through
//! [`CollisionPairs`](super::CollisionPairs).
use bevy_ecs::prelude::*;
use glam::Vec3;

use super::super::contact::ContactPoint;
use super::super::narrow_phase::{Method, PairMemory, PairOutcome};
use super::super::stamp::{age_stamp, stamp, stamp_sweep_due};

/// What a pair's last answer was in full: read when it is reported, written when it is
/// computed (every run reads [`PairHot`] instead).
#[derive(Debug, Clone)]
pub(crate) struct PairSlot {
    /// The smaller entity.
    pub a: Entity,
    /// The larger entity (`a` itself for a self-collision).
    pub b: Entity,
    /// The last answer computed (by a test, or from memory for an exact pair under overload).
    pub outcome: PairOutcome,
    /// The last test's contact and the colliders' offset then (the second's translation
    /// less the first's), for answers from memory.
    pub contact: Option<ContactPoint>,
    pub offset: Vec3,
    /// The run from which the touching state holds.
    pub since: u64,
}

/// What every run reads of a pair, in a compact array of its own, so that going over the
/// pairs of the colliders that moved touches little memory. Run stamps are the run's number
/// modulo 2³² (compared for equality, or subtracted for ages), aged so that they never alias
/// ([`age_stamp`](super::super::stamp::age_stamp)).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PairEnds {
    /// The colliders' slots (the first is the smaller entity's).
    pub body_a: u32,
    pub body_b: u32,
    /// Where the pair is in each collider's list of pairs.
    pub pos_a: u32,
    pub pos_b: u32,
    /// The last run in which the pair was put on the active list (each pair once per run).
    pub active_run: u32,
    /// The last run in which its answer was computed or confirmed (world boxes apart).
    pub checked_run: u32,
    /// The last run in which the pair was put on the pending list.
    pub pending_run: u32,
    pub live: bool,
    /// In the waiting queue.
    pub waiting: bool,
    /// Answered, not colliding, of two colliders: while their world boxes stay apart,
    /// nothing about it needs work.
    pub quiet: bool,
    /// Rejected by the app's [`PairFilter`](super::PairFilter): never worked on, never
    /// touching, not listed by [`CollisionPairs`](super::CollisionPairs).
    pub excluded: bool,
}

/// What planning reads of a pair.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PairHot {
    /// Whether the pair touched as of the last Report.
    pub touching: bool,
    /// What the last test found (`None`: never tested).
    pub memory: Option<PairMemory>,
}

/// A pair whose touching state flipped in this run (or that was removed while touching).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Transition {
    pub a: Entity,
    pub b: Entity,
    pub started: bool,
    /// How the answer that flipped it was found, and its probability that the pair collides
    /// (a removed pair: [`Method::Bounds`], 0).
    pub method: Method,
    pub probability: f64,
    /// When in the step a swept pair's surfaces met (a start found by the continuous query).
    pub time_of_impact: Option<f32>,
}

/// What a test (or an answer computed from memory) leaves for later runs.
#[derive(Debug, Clone)]
pub(crate) struct Record {
    pub memory: PairMemory,
    pub contact: Option<ContactPoint>,
    pub offset: Vec3,
}

/// Every candidate pair of colliders, one stable slot each (see the module documentation).
///
/// A pair exists while the two colliders' broad-phase boxes overlap and their layers
/// interact, or, for a self-colliding deformable mesh, while it has the marker. Each run
/// works only on its *active* pairs (new, moved, unsettled, or waiting for a test); the
/// others keep their last answer, which still holds because nothing about them changed.
#[derive(Resource, Debug, Default)]
pub struct PairTable {
    pub(crate) slots: Vec<PairSlot>,
    /// Per slot, what every run reads, and what planning reads.
    pub(crate) ends: Vec<PairEnds>,
    pub(crate) hot: Vec<PairHot>,
    free: Vec<u32>,
    live: usize,
    /// Pairs that need work in the coming narrow phase: new ones (created by this run's broad
    /// phase, worked on in the same run), tracked ones and exact pairs a deadline left
    /// untested (in the next run).
    pub(crate) pending: Vec<u32>,
    /// Pairs waiting for a test (their last answer was kept, or cut by its budget), first
    /// come first served: each run takes as many as it may test.
    pub(crate) waiting: std::collections::VecDeque<u32>,
    /// The pairs worked on in this run (built by the narrow phase).
    pub(crate) active: Vec<u32>,
    /// Pairs handed to the Tracking stage in this run.
    pub(crate) tracked: Vec<u32>,
    /// Pairs answered in this run that collide (their contacts are this run's contacts).
    pub(crate) colliding: Vec<u32>,
    /// Touching states that flipped in this run, in the order found (the Report sorts them).
    pub(crate) transitions: Vec<Transition>,
    /// Whether a [`PairFilter`](super::PairFilter) is installed: pairs created are then
    /// listed in `created` for it.
    pub(crate) filtering: bool,
    /// Pairs of two colliders created since the filter last ran.
    pub(crate) created: Vec<u32>,
}

impl PairTable {
    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.live
    }

    /// Whether there is no pair.
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// The pairs worked on in the last run (answered by a test or from memory).
    pub fn active_pairs(&self) -> usize {
        self.active.len()
    }

    /// Touching states that flipped in the last run.
    pub fn transitions(&self) -> usize {
        self.transitions.len()
    }

    /// The last answer computed for every pair, in slot order (stable from run to run); its
    /// [`run`](PairOutcome::run) says when.
    pub fn outcomes(&self) -> impl Iterator<Item = &PairOutcome> {
        self.slots
            .iter()
            .zip(&self.ends)
            .filter(|(_, e)| e.live)
            .map(|(s, _)| &s.outcome)
    }

    /// Number of slots, live or free: [`PairTable::outcome_in_slot`] takes `0..slot_count()`.
    pub fn slot_count(&self) -> usize {
        self.slots.len()
    }

    /// The last answer of the pair in slot `slot`, `None` when the slot is free (or out of
    /// range). A pair keeps its slot while it lives, so picking slots at random and keeping the
    /// live ones samples the pairs uniformly, at a cost that does not grow with the table
    /// (what `examples/profile.rs` does to re-test a few pairs each frame).
    pub fn outcome_in_slot(&self, slot: usize) -> Option<&PairOutcome> {
        let live = self.ends.get(slot).is_some_and(|e| e.live);
        live.then(|| &self.slots[slot].outcome)
    }

    /// Pair `i`'s colliders and stamps.
    #[inline]
    pub(crate) fn ends(&self, i: u32) -> &PairEnds {
        &self.ends[i as usize]
    }

    /// What planning reads of pair `i`.
    #[inline]
    pub(crate) fn hot(&self, i: u32) -> &PairHot {
        &self.hot[i as usize]
    }

    /// The slot of pair `i`.
    #[inline]
    pub(crate) fn slot(&self, i: u32) -> &PairSlot {
        &self.slots[i as usize]
    }

    /// Creates the pair of colliders `(a, body_a)` and `(b, body_b)` (the same for a
    /// self-collision) and puts it on the pending list; returns its slot. The caller links it
    /// to both colliders.
    pub(crate) fn create(&mut self, a: (Entity, u32), b: (Entity, u32), run: u64) -> u32 {
        let i = self.insert(a, b, run);
        self.mark_pending(i, run);
        i
    }

    /// Creates the pair as [`create`](Self::create) does, but not on the pending list: the
    /// caller answers it or puts it there.
    pub(crate) fn insert(
        &mut self,
        (a, body_a): (Entity, u32),
        (b, body_b): (Entity, u32),
        run: u64,
    ) -> u32 {
        let ((a, body_a), (b, body_b)) = if a <= b {
            ((a, body_a), (b, body_b))
        } else {
            ((b, body_b), (a, body_a))
        };
        let slot = PairSlot {
            a,
            b,
            outcome: PairOutcome::untested((a, b), run),
            contact: None,
            offset: Vec3::ZERO,
            since: run,
        };
        let ends = PairEnds {
            body_a,
            body_b,
            pos_a: 0,
            pos_b: 0,
            active_run: stamp(run).wrapping_sub(1),
            checked_run: stamp(run),
            pending_run: stamp(run).wrapping_sub(1),
            live: true,
            waiting: false,
            quiet: false,
            excluded: false,
        };
        let hot = PairHot {
            touching: false,
            memory: None,
        };
        let i = match self.free.pop() {
            Some(i) => {
                self.slots[i as usize] = slot;
                self.ends[i as usize] = ends;
                self.hot[i as usize] = hot;
                i
            }
            None => {
                self.slots.push(slot);
                self.ends.push(ends);
                self.hot.push(hot);
                (self.slots.len() - 1) as u32
            }
        };
        self.live += 1;
        if self.filtering && a != b {
            self.created.push(i);
        }
        i
    }

    /// Excludes pair `i` (the pair filter rejected it): a touching pair's contact ends (a
    /// transition), its answer and memory are forgotten, and it is not worked on until
    /// [`include`](Self::include)d again.
    pub(crate) fn exclude(&mut self, i: u32, run: u64) {
        let e = &mut self.ends[i as usize];
        if !e.live || e.excluded {
            return;
        }
        e.excluded = true;
        e.waiting = false;
        e.quiet = false;
        self.forget(i);
        let s = &mut self.slots[i as usize];
        s.outcome = PairOutcome::untested((s.a, s.b), run);
        s.contact = None;
        s.since = run;
    }

    /// Includes pair `i` again (the pair filter accepts it now): it is worked on in this
    /// run's narrow phase, as a new pair.
    pub(crate) fn include(&mut self, i: u32, run: u64) {
        let e = &mut self.ends[i as usize];
        if e.live && e.excluded {
            e.excluded = false;
            self.mark_pending(i, run);
        }
    }

    /// Removes pair `i` (a touching pair's contact ends: a transition). The caller unlinks it
    /// from its colliders.
    pub(crate) fn remove(&mut self, i: u32) {
        if !self.ends[i as usize].live {
            return;
        }
        self.ends[i as usize] = PairEnds::default();
        self.forget(i);
        self.live -= 1;
        self.free.push(i);
    }

    /// Forgets pair `i`'s touching state and memory; a touching pair's contact ends (a
    /// transition, found by bounds with probability 0).
    fn forget(&mut self, i: u32) {
        let h = std::mem::take(&mut self.hot[i as usize]);
        if h.touching {
            let s = &self.slots[i as usize];
            self.transitions.push(Transition {
                a: s.a,
                b: s.b,
                started: false,
                method: Method::Bounds,
                probability: 0.0,
                time_of_impact: None,
            });
        }
    }

    /// Puts pair `i` on the pending list (once per run): it is worked on in the next run.
    #[inline]
    pub(crate) fn mark_pending(&mut self, i: u32, run: u64) {
        let e = &mut self.ends[i as usize];
        if e.pending_run != stamp(run) {
            e.pending_run = stamp(run);
            self.pending.push(i);
        }
    }

    /// Puts pair `i` in the waiting queue (once).
    #[inline]
    pub(crate) fn wait(&mut self, i: u32) {
        let e = &mut self.ends[i as usize];
        if e.live && !e.waiting && !e.excluded {
            e.waiting = true;
            self.waiting.push_back(i);
        }
    }

    /// The number of pairs waiting for a test.
    pub fn waiting(&self) -> usize {
        self.waiting.len()
    }

    /// Puts pair `i` on this run's active list (once per run).
    #[inline]
    pub(crate) fn activate(&mut self, i: u32, run: u64) {
        let e = &mut self.ends[i as usize];
        if e.active_run != stamp(run) && e.live && !e.excluded {
            e.active_run = stamp(run);
            self.active.push(i);
        }
    }

    /// Records pair `i`'s answer computed in this run: its touching state (a transition when
    /// it flips), its contacts for this run's Report, and `record` as its memory when given.
    pub(crate) fn answer(
        &mut self,
        i: u32,
        outcome: PairOutcome,
        record: Option<Record>,
        run: u64,
    ) {
        let (h, s) = (&mut self.hot[i as usize], &mut self.slots[i as usize]);
        let apart = record.as_ref().is_some_and(|r| r.memory.boxes_apart);
        match record {
            Some(r) => {
                h.memory = Some(r.memory);
                s.contact = r.contact;
                s.offset = r.offset;
            }
            // A tracked answer leaves no memory: what an earlier test found is out of date.
            None if matches!(outcome.method, Method::Tracking | Method::SelfCollision) => {
                h.memory = None;
            }
            None => {}
        }
        // Tracked pairs and answers from memory are worked on again in the next run, unless
        // the world boxes are apart (then nothing needs work until a collider moves).
        let (pending, waits) = match outcome.method {
            Method::Tracking | Method::SelfCollision | Method::Coherence => (!apart, false),
            _ => (false, outcome.budget_exhausted),
        };
        self.ends[i as usize].checked_run = stamp(outcome.computed_run);
        s.outcome = outcome;
        self.flip_if(i, self.slots[i as usize].outcome.collides, run);
        if pending {
            self.mark_pending(i, run);
        }
        if waits {
            self.wait(i);
        }
    }

    /// Pair `i` worked on in this run but not tested: its last answer stands (its touching
    /// state too), one run older (`cached`: it still holds, nothing moved); unless cached, it
    /// waits for a test.
    pub(crate) fn keep(&mut self, i: u32, cached: bool, run: u64) {
        let h = &mut self.hot[i as usize];
        let touching = h.touching;
        if !cached && let Some(m) = &mut h.memory {
            m.stale = m.stale.saturating_add(1);
        }
        self.flip_if(i, touching, run);
        if !cached {
            self.wait(i);
        }
    }

    /// Sets pair `i`'s touching state to `collides` (a transition when it flips) and lists it
    /// among this run's colliding pairs when it collides.
    fn flip_if(&mut self, i: u32, collides: bool, run: u64) {
        let h = &mut self.hot[i as usize];
        let e = &mut self.ends[i as usize];
        e.quiet = h.memory.is_some() && !collides && e.body_a != e.body_b;
        if collides != h.touching {
            h.touching = collides;
            let s = &mut self.slots[i as usize];
            s.since = run;
            self.transitions.push(Transition {
                a: s.a,
                b: s.b,
                started: collides,
                method: s.outcome.method,
                probability: s.outcome.probability,
                time_of_impact: s
                    .outcome
                    .contacts
                    .first()
                    .and_then(|c| c.time_of_impact)
                    .filter(|_| collides),
            });
        }
        if collides {
            self.colliding.push(i);
        }
    }

    /// Starts run `run`: clears the last run's lists of answers (and ages the stamps when
    /// due, [`age_stamp`](super::super::stamp::age_stamp)).
    pub(crate) fn begin_run(&mut self, run: u64) {
        self.tracked.clear();
        self.colliding.clear();
        self.transitions.clear();
        if stamp_sweep_due(run) {
            let now = stamp(run);
            for e in &mut self.ends {
                age_stamp(&mut e.active_run, now);
                age_stamp(&mut e.checked_run, now);
                age_stamp(&mut e.pending_run, now);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use smallvec::SmallVec;

    use super::*;
    use crate::ecs::narrow_phase::PairMemory;

    fn entities() -> (Entity, Entity) {
        (
            Entity::from_raw_u32(1).unwrap(),
            Entity::from_raw_u32(2).unwrap(),
        )
    }

    fn outcome(method: Method, collides: bool, run: u64) -> PairOutcome {
        let mut o = PairOutcome::exact(entities(), method, 0, 1.0, SmallVec::new(), run);
        o.collides = collides;
        o
    }

    fn exact_memory(collides: bool, run: u64) -> Record {
        Record {
            memory: PairMemory::exact_for_tests(collides, run),
            contact: None,
            offset: Vec3::ZERO,
        }
    }

    /// Slots of removed pairs read as free; the live ones give the same answers as
    /// `outcomes()`.
    #[test]
    fn outcome_in_slot_sees_the_live_pairs_only() {
        let e = |i| Entity::from_raw_u32(i).unwrap();
        let mut t = PairTable::default();
        let slots: Vec<u32> = (0..5)
            .map(|k| t.create((e(k), k), (e(10 + k), 10 + k), 1))
            .collect();
        t.remove(slots[1]);
        t.remove(slots[3]);
        assert_eq!(t.slot_count(), 5);
        let live: Vec<_> = (0..t.slot_count() + 2)
            .filter_map(|i| t.outcome_in_slot(i))
            .collect();
        assert_eq!(live, t.outcomes().collect::<Vec<_>>());
        let colliders_of = |k: u32| [e(k), e(10 + k)];
        assert_eq!(live.len(), 3);
        for (o, k) in live.iter().zip([0, 2, 4]) {
            assert!(colliders_of(k).contains(&o.a) && colliders_of(k).contains(&o.b));
        }
        // A freed slot is taken again by the next pair.
        let again = t.create((e(7), 7), (e(8), 8), 2);
        assert!(again == slots[1] || again == slots[3]);
        let reused = t.outcome_in_slot(again as usize).unwrap();
        assert!([reused.a, reused.b].contains(&e(7)));
    }

    #[test]
    fn a_kept_answer_keeps_the_touching_state_of_the_last_answer() {
        let (a, b) = entities();
        let mut t = PairTable::default();
        let i = t.create((a, 0), (b, 1), 1);
        // An exact test found them apart; then tracking (no memory of its own) finds contact.
        t.answer(
            i,
            outcome(Method::Exact, false, 1),
            Some(exact_memory(false, 1)),
            1,
        );
        t.begin_run(2);
        t.answer(i, outcome(Method::Tracking, true, 2), None, 2);
        assert!(t.hot(i).touching);
        assert_eq!(
            t.hot(i).memory,
            None,
            "the exact test's memory is out of date"
        );
        // Kept in the next runs (not tested): still touching, no transition, listed as colliding.
        for run in 3..6 {
            t.begin_run(run);
            t.keep(i, false, run);
            assert!(t.hot(i).touching, "run {run}");
            assert!(t.transitions.is_empty(), "run {run}");
            assert_eq!(t.colliding, vec![i], "run {run}");
        }
    }

    #[test]
    fn an_excluded_pair_ends_its_contact_and_is_never_worked_on() {
        let mut t = PairTable {
            filtering: true,
            ..Default::default()
        };
        let (a, b) = entities();
        let i = t.create((a, 0), (b, 1), 1);
        assert_eq!(t.created, vec![i]);
        t.answer(
            i,
            outcome(Method::Exact, true, 1),
            Some(exact_memory(true, 1)),
            1,
        );
        assert!(t.hot(i).touching);
        t.begin_run(2);
        t.exclude(i, 2);
        assert!(!t.hot(i).touching && t.hot(i).memory.is_none());
        assert_eq!(t.transitions.len(), 1);
        assert!(!t.transitions[0].started);
        t.wait(i);
        t.activate(i, 2);
        assert!(t.waiting.is_empty() && t.active.is_empty());
        t.include(i, 3);
        t.activate(i, 3);
        assert_eq!(t.active, vec![i]);
    }

    #[test]
    fn a_tracked_pair_with_its_boxes_apart_is_not_pending() {
        let (a, b) = entities();
        let mut t = PairTable::default();
        let i = t.create((a, 0), (b, 1), 1);
        t.pending.clear();
        let mut apart = exact_memory(false, 2);
        apart.memory.boxes_apart = true;
        apart.memory.method = Method::Tracking;
        t.answer(i, outcome(Method::Tracking, false, 2), Some(apart), 2);
        assert!(t.pending.is_empty());
        assert!(t.ends(i).quiet, "nothing to do until a collider moves");
        // With its boxes overlapping, a tracked pair is worked on in every run.
        t.answer(i, outcome(Method::Tracking, false, 3), None, 3);
        assert_eq!(t.pending, vec![i]);
    }

    #[test]
    fn stamps_do_not_alias_after_two_to_the_32_runs() {
        let (a, b) = entities();
        let mut t = PairTable::default();
        let i = t.create((a, 0), (b, 1), 5);
        t.activate(i, 5);
        t.active.clear();
        // Runs go by; the sweeps age the stamps.
        for k in 1..=4u64 {
            t.begin_run(k << 30);
        }
        let later = 5 + (1u64 << 32);
        t.begin_run(later);
        t.activate(i, later);
        assert_eq!(t.active, vec![i], "not taken for this run's stamp");
        t.mark_pending(i, later);
        assert_eq!(
            t.pending,
            vec![i, i],
            "created pending, and again in this run"
        );
    }
}

//! Executing a run of the narrow phase: the chosen pairs tested by their method, the others
//! answered from memory, in parallel runs of jobs, each writing its own answers in job order.
use std::cell::RefCell;
use std::time::{Duration, Instant};

use smallvec::SmallVec;

use super::super::budget::{BudgetClock, SliceShare};
use super::super::config::CollisionConfig;
use super::super::contact::{
    ContactPoint, bounds_contact, interpenetration_contact, node_contact, region_contact,
    triangle_pair_contact,
};
use super::super::pairs::{PairTable, Record};
use super::super::prepare::{ColliderEntry, ColliderTable};
use super::contained::contained_vertex_contacts;
use super::continuous::{swept_adb_contact, swept_contact, swept_deforming_contact};
use super::memory::exact_from_memory;
use super::outcome::{Method, PairOutcome};
use super::plan::Job;
use crate::adb::{AdbQuery, AdbWorkspace, Budget, adb_intersects};
use crate::bvh::{QueryWorkspace, TrianglePair, intersecting_pairs, intersects_with};
use crate::ccd::CcdWorkspace;

/// Intersecting triangle pairs a contact region is summarised from at most (evenly spread).
const REGION_PAIRS: usize = 64;

#[derive(Default)]
struct Workspaces {
    exact: QueryWorkspace,
    adb: AdbWorkspace,
    pairs: Vec<TrianglePair>,
    ccd: CcdWorkspace,
}

thread_local! {
    static WORKSPACES: RefCell<Workspaces> = RefCell::new(Workspaces::default());
}

/// Runs `f` with this thread's reusable query workspaces.
pub(crate) fn with_workspaces<R>(
    f: impl FnOnce(&mut QueryWorkspace, &mut AdbWorkspace, &mut Vec<TrianglePair>) -> R,
) -> R {
    WORKSPACES.with(|w| {
        let w = &mut *w.borrow_mut();
        f(&mut w.exact, &mut w.adb, &mut w.pairs)
    })
}

/// Runs `f` with this thread's reusable workspaces, the continuous query's among them.
fn with_all_workspaces<R>(
    f: impl FnOnce(
        &mut QueryWorkspace,
        &mut AdbWorkspace,
        &mut Vec<TrianglePair>,
        &mut CcdWorkspace,
    ) -> R,
) -> R {
    WORKSPACES.with(|w| {
        let w = &mut *w.borrow_mut();
        f(&mut w.exact, &mut w.adb, &mut w.pairs, &mut w.ccd)
    })
}

/// What a job's run made of it.
// Answers are written into a slot per job and read back once: boxing the large variant would
// allocate for every answered pair.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub(crate) enum Answer {
    /// An answer computed in this run, and the memory it leaves (`None`: the pair's memory
    /// stays as it is).
    Computed(PairOutcome, Option<Record>),
    /// Not answered: a deadline passed before its test (the last answer stands).
    Kept,
}

/// What a run of jobs did: its answers by kind, its work, and the time its thread spent in
/// tests and in answers from memory.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct RunCounts {
    pub node_pairs: u64,
    pub exact_node_pairs: u64,
    pub exact_pairs: u64,
    pub budget_exhausted: u64,
    pub coherence: u64,
    /// Exact pairs past their deadline answered exactly by a cheap test of their memory.
    pub confirmed: u64,
    pub tested: u64,
    pub test_time: Duration,
    pub memory_time: Duration,
    /// Pairs tested over a swept collider's motion, and how many of them the discrete test
    /// had found apart but met during the motion.
    pub swept: u64,
    pub caught: u64,
}

impl RunCounts {
    pub fn add(self, o: &Self) -> Self {
        Self {
            node_pairs: self.node_pairs + o.node_pairs,
            exact_node_pairs: self.exact_node_pairs + o.exact_node_pairs,
            exact_pairs: self.exact_pairs + o.exact_pairs,
            budget_exhausted: self.budget_exhausted + o.budget_exhausted,
            coherence: self.coherence + o.coherence,
            confirmed: self.confirmed + o.confirmed,
            tested: self.tested + o.tested,
            test_time: self.test_time + o.test_time,
            memory_time: self.memory_time + o.memory_time,
            swept: self.swept + o.swept,
            caught: self.caught + o.caught,
        }
    }

    fn count(&mut self, answer: &Answer, tested: bool) {
        let Answer::Computed(o, _) = answer else {
            self.coherence += 1;
            return;
        };
        self.node_pairs += o.node_pairs;
        if o.method == Method::Exact {
            self.exact_node_pairs += o.node_pairs;
            self.exact_pairs += u64::from(tested);
        }
        self.budget_exhausted += u64::from(o.budget_exhausted);
        self.coherence += u64::from(o.method == Method::Coherence);
        self.tested += u64::from(tested && matches!(o.method, Method::Adb | Method::Exact));
    }
}

/// One run of jobs and the slots its answers go to.
pub(crate) struct ChunkWork<'a> {
    pub jobs: &'a [Job],
    pub answers: &'a mut [Answer],
    pub counts: &'a mut RunCounts,
}

/// When the tests of a run stop (`None`: never): the optional ones, and the exact ones (later:
/// they were asked for, so only an overload of exact pairs alone cuts them).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Deadlines {
    pub others: Option<Instant>,
    pub exact: Option<Instant>,
}

impl Deadlines {
    pub fn at(others: Instant, exact: Instant) -> Self {
        Self {
            others: Some(others),
            exact: Some(exact),
        }
    }
}

/// A contact the continuous test found during the motion: the time of impact for a contact
/// the discrete test found too, else the pair collides with `probability` at that contact.
fn take_swept(o: &mut PairOutcome, hit: ContactPoint, probability: f64, s: &mut Scratch) {
    if o.collides {
        if let Some(c) = o.contacts.first_mut() {
            c.time_of_impact = hit.time_of_impact;
        }
    } else {
        s.caught += 1;
        o.collides = true;
        o.probability = probability;
        o.contacts.clear();
        o.contacts.push(hit);
    }
}

/// One thread's scratch for the tests of a run: the query settings, the workspaces, and the
/// most node pairs the next ADB test may visit (what is left of the time for tests).
struct Scratch<'w> {
    query: AdbQuery,
    exact: &'w mut QueryWorkspace,
    adb: &'w mut AdbWorkspace,
    pairs: &'w mut Vec<TrianglePair>,
    ccd: &'w mut CcdWorkspace,
    node_cap: u64,
    /// Pairs swept, and caught by the sweep only, in this run of jobs; exact pairs past their
    /// deadline answered exactly from memory.
    swept: u64,
    caught: u64,
    confirmed: u64,
}

/// What every run of jobs reads.
pub(crate) struct Context<'a> {
    pub colliders: &'a ColliderTable,
    pub pairs: &'a PairTable,
    pub config: &'a CollisionConfig,
    /// This run's number.
    pub run: u64,
    /// The share of the node-pair budget among the tested ADB pairs (`None`: unlimited).
    pub share: Option<SliceShare>,
    pub deadlines: Deadlines,
    /// The measured rate of the tests (time mode), for the cap of each test.
    pub node_pairs_per_us: f64,
    /// The budget's clock: the deadlines are its instants, the tests are timed with it.
    pub clock: &'a dyn BudgetClock,
}

impl Context<'_> {
    /// The ADB query settings of this run.
    fn query(&self) -> AdbQuery {
        AdbQuery {
            k_min: self.config.k_min,
            exact_leaves: self.config.adb_exact_leaves,
            decision: self.config.adb_decision,
            order: self.config.adb_order,
            collide_at: self.config.adb_collide_at,
            interior_after: self.config.adb_interior.then_some(0),
            ..AdbQuery::default()
        }
    }

    fn ends(&self, job: &Job) -> (&ColliderEntry, &ColliderEntry) {
        (
            self.colliders.entry(job.body_a),
            self.colliders.entry(job.body_b),
        )
    }

    /// Answers a run of jobs into its slots: first the chosen exact ones are tested, then in
    /// job order the other chosen ones are tested and the rest answered (apart, or from
    /// memory). Past a deadline, chosen jobs are answered from memory too.
    pub fn run_chunk(&self, w: &mut ChunkWork) {
        let clock = self.clock;
        let start = clock.now();
        let mut counts = RunCounts::default();
        with_all_workspaces(|exact, adb, pairs, ccd| {
            let s = &mut Scratch {
                query: self.query(),
                exact,
                adb,
                pairs,
                ccd,
                node_cap: u64::MAX,
                swept: 0,
                caught: 0,
                confirmed: 0,
            };
            let is_exact = |j: &Job| j.chosen && j.method == Method::Exact;
            let mut late = false;
            for (i, job) in w.jobs.iter().enumerate().filter(|(_, j)| is_exact(j)) {
                late = late || self.deadlines.exact.is_some_and(|d| clock.now() > d);
                let (answer, tested) = self.answer(job, late, s);
                counts.count(&answer, tested);
                w.answers[i] = answer;
            }
            counts.test_time = clock.now().saturating_duration_since(start);
            let mut late = false;
            for (i, job) in w.jobs.iter().enumerate().filter(|(_, j)| !is_exact(j)) {
                let (answer, tested) = if job.chosen {
                    let t = clock.now();
                    if let Some(d) = self.deadlines.others {
                        // No test runs far past the deadline: an ADB test visits at most
                        // the node pairs the measured rate gets done before it.
                        let left_us = d.saturating_duration_since(t).as_secs_f64() * 1e6;
                        late = late || left_us <= 0.0;
                        s.node_cap = (left_us * self.node_pairs_per_us) as u64;
                    }
                    let answer = self.answer(job, late, s);
                    counts.test_time += clock.now().saturating_duration_since(t);
                    answer
                } else {
                    self.answer(job, true, s)
                };
                counts.count(&answer, tested);
                w.answers[i] = answer;
            }
            counts.swept = s.swept;
            counts.caught = s.caught;
            counts.confirmed = s.confirmed;
        });
        counts.memory_time = clock
            .now()
            .saturating_duration_since(start)
            .saturating_sub(counts.test_time);
        *w.counts = counts;
    }

    /// The answer of a job (apart, bounds-only, tested, or past a deadline: from memory for
    /// an exact pair, kept for the others but swept ones) and whether it was tested.
    fn answer(&self, job: &Job, late: bool, s: &mut Scratch) -> (Answer, bool) {
        let (ea, eb) = self.ends(job);
        if job.apart {
            let (o, r) = apart_answer(job, (ea, eb), self.run);
            return (Answer::Computed(o, Some(r)), false);
        }
        // Past the deadline a rigid exact pair is answered from its memory; a pair with a
        // deformable is tested anyway: its memory describes a mesh that has moved since, and
        // one remembered contact is not what a response needs to hold a sheet on a floor.
        if late && job.method == Method::Exact && ea.is_rigid() && eb.is_rigid() {
            let memory = self.pairs.hot[job.pair as usize].memory.as_ref();
            let slot = self.pairs.slot(job.pair);
            let (o, r) = exact_from_memory(job, memory, slot, (ea, eb), self.run);
            s.confirmed += u64::from(o.method == Method::Exact);
            return (Answer::Computed(o, r), false);
        }
        // A swept pair is tested even past the deadline (with the smallest ADB budget): kept, it
        // would miss what happened during this run's motion.
        if late && job.method != Method::Bounds && !job.swept {
            return (Answer::Kept, false);
        }
        let mut o = self.test(job, (ea, eb), s);
        self.sweep(job, &mut o, (ea, eb), s);
        let r = Record::of_test(job, &o, (ea, eb), self.run);
        (Answer::Computed(o, Some(r)), true)
    }

    /// A pair with a collider swept in this run ([`ColliderEntry::is_swept`]), tested exactly
    /// or with ADB: if its test found it apart, or it did not touch before, the exact
    /// continuous query over both motions (for an ADB pair the time-critical one within its
    /// ADB budget, [`sweep_adb`](Self::sweep_adb); where a collider is deformable, the query
    /// over both meshes' vertices moving on straight lines in world coordinates,
    /// [`swept_deforming_contact`]); a contact found during the motion makes it collide
    /// (probability 1; the contact at the time of impact) or, when the test found a contact
    /// already, gives that contact its time of impact.
    fn sweep(
        &self,
        job: &Job,
        o: &mut PairOutcome,
        (ea, eb): (&ColliderEntry, &ColliderEntry),
        s: &mut Scratch,
    ) {
        if !ea.is_swept(self.run) && !eb.is_swept(self.run) {
            return;
        }
        if !matches!(o.method, Method::Exact | Method::Adb) {
            return;
        }
        let was_touching = self.pairs.slot(job.pair).outcome.collides;
        if o.collides && was_touching {
            return;
        }
        s.swept += 1;
        if o.method == Method::Adb {
            self.sweep_adb(job, o, (ea, eb), s);
            return;
        }
        let hit = if ea.is_rigid() && eb.is_rigid() {
            swept_contact(ea, eb, self.run, s.ccd)
        } else {
            swept_deforming_contact(ea, eb, self.run, s.ccd)
        };
        if let Some(hit) = hit {
            take_swept(o, hit, 1.0, s);
        }
    }

    /// [`sweep`](Self::sweep) for an ADB pair: the time-critical continuous query within the
    /// pair's ADB budget.
    fn sweep_adb(
        &self,
        job: &Job,
        o: &mut PairOutcome,
        (ea, eb): (&ColliderEntry, &ColliderEntry),
        s: &mut Scratch,
    ) {
        let settings = (
            self.sweep_budget(job, s),
            self.config.adb_collide_at,
            self.config.continuous_adb_conservative,
        );
        let Some(swept) = swept_adb_contact(ea, eb, self.run, settings, s.ccd) else {
            return;
        };
        o.node_pairs += swept.node_pairs;
        o.budget_exhausted |= swept.budget_exhausted;
        if let Some(hit) = swept.contact {
            take_swept(o, hit, swept.probability, s);
        }
    }

    /// The node pairs the continuous test of ADB pair `job` may visit in this run. Under a
    /// time budget: the largest slice (`CollisionConfig::max_slice`) that the time left
    /// allows, and an eighth of it (at least `min_slice`) even past the deadline, since a
    /// swept pair cannot wait for a later run (what its motion crossed has passed by then)
    /// and a search cut after a few node pairs can only guess (swept pairs are few: only
    /// colliders with `ContinuousCollision` that moved). Under a work budget: its share, as
    /// for its discrete test (the work stays what the budget says).
    fn sweep_budget(&self, job: &Job, s: &Scratch) -> Budget {
        match (self.share, self.deadlines.others) {
            (Some(_), Some(_)) => {
                let max = self.config.max_slice.max(self.config.min_slice);
                Budget::NodePairs(max.min(s.node_cap).max(self.config.timed_slice_floor()))
            }
            _ => self.adb_budget(job, s),
        }
    }

    /// The node pairs an ADB test of `job` may visit in this run.
    fn adb_budget(&self, job: &Job, s: &Scratch) -> Budget {
        match self.share {
            None => Budget::Unlimited,
            Some(share) => {
                let cap = s.node_cap.max(self.config.min_slice);
                Budget::NodePairs(share.slice(job.priority).min(cap))
            }
        }
    }

    /// Tests a job by its method.
    fn test(
        &self,
        job: &Job,
        (ea, eb): (&ColliderEntry, &ColliderEntry),
        s: &mut Scratch,
    ) -> PairOutcome {
        let ends = (ea.entity, eb.entity);
        let (ma, mb) = (ea.geometry.mesh(), eb.geometry.mesh());
        match job.method {
            Method::Bounds => {
                let contacts = smallvec::smallvec![bounds_contact(ea, eb)];
                PairOutcome::exact(ends, Method::Bounds, 0, job.priority, contacts, self.run)
            }
            Method::Exact if ea.is_rigid() && eb.is_rigid() && self.config.contact_regions => {
                // Every intersecting pair, summarised in one contact at the region's centre.
                s.pairs.clear();
                intersecting_pairs(ma, &ea.pose, mb, &eb.pose, s.exact, s.pairs);
                let contacts = region_contact(ma, &ea.pose, mb, &eb.pose, s.pairs, REGION_PAIRS)
                    .into_iter()
                    .collect();
                let nodes = s.exact.node_pairs_visited();
                PairOutcome::exact(ends, Method::Exact, nodes, job.priority, contacts, self.run)
            }
            Method::Exact if ea.is_rigid() && eb.is_rigid() => {
                // First hit only (stops early): one contact, as for ADB pairs.
                let hit = intersects_with(ma, &ea.pose, mb, &eb.pose, &Default::default(), s.exact);
                let contacts = hit
                    .witness
                    .map(|t| triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t))
                    .into_iter()
                    .collect();
                let nodes = hit.node_pairs_visited;
                PairOutcome::exact(ends, Method::Exact, nodes, job.priority, contacts, self.run)
            }
            Method::Exact => {
                s.pairs.clear();
                intersecting_pairs(ma, &ea.pose, mb, &eb.pose, s.exact, s.pairs);
                let max = self.config.max_contacts_per_pair;
                let mut contacts: SmallVec<_> = spread(s.pairs, max)
                    .map(|t| triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t))
                    .collect();
                // A deformable's vertices inside a closed partner (no surface crossing shows
                // a triangle that sank wholly into it): capped as the crossing contacts are, a
                // different share of them each run.
                let cap = (max, self.run);
                for (soft, solid, soft_first) in [(ea, eb, true), (eb, ea, false)] {
                    if !soft.is_rigid() {
                        let (m_soft, m_solid) = (soft.geometry.mesh(), solid.geometry.mesh());
                        let (soft_at, solid_at) = ((m_soft, &soft.pose), (m_solid, &solid.pose));
                        contained_vertex_contacts(
                            soft_at,
                            solid_at,
                            (soft_first, s.pairs),
                            cap,
                            &mut contacts,
                        );
                    }
                }
                let nodes = s.exact.node_pairs_visited();
                PairOutcome::exact(ends, Method::Exact, nodes, job.priority, contacts, self.run)
            }
            Method::Adb => {
                let (Some(ta), Some(tb)) = (ea.geometry.adb(), eb.geometry.adb()) else {
                    unreachable!("ADB pairs are rigid (planned so)")
                };
                s.query.p_min = job.p_min;
                s.query.budget = self.adb_budget(job, s);
                let r = adb_intersects(ta, &ea.pose, tb, &eb.pose, &s.query, s.adb);
                let mut out = PairOutcome::exact(
                    ends,
                    Method::Adb,
                    r.node_pairs_visited,
                    job.priority,
                    SmallVec::new(),
                    self.run,
                );
                out.collides = r.collides;
                out.probability = r.probability;
                out.budget_exhausted = r.budget_exhausted;
                if r.collides {
                    out.contacts.push(match (r.witness, r.interpenetration) {
                        (Some(w), Some(c)) => interpenetration_contact(&w, &c),
                        (Some(w), None) => match w.triangles {
                            Some(t) => triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t),
                            None => node_contact(ma, &ea.pose, mb, &eb.pose, &w, r.probability),
                        },
                        (None, _) => bounds_contact(ea, eb),
                    });
                }
                out
            }
            Method::Tracking | Method::SelfCollision | Method::Coherence => {
                unreachable!("not a narrow-phase test (planned so)")
            }
        }
    }
}

/// The answer of a pair whose world boxes are apart in `run` (`job.apart`): not colliding,
/// exactly, and the memory it leaves (its boxes were apart: it needs no work until they meet).
pub(crate) fn apart_answer(
    job: &Job,
    (ea, eb): (&ColliderEntry, &ColliderEntry),
    run: u64,
) -> (PairOutcome, Record) {
    let ends = (ea.entity, eb.entity);
    let o = PairOutcome::exact(ends, job.method, 0, job.priority, SmallVec::new(), run);
    let r = Record::of_test(job, &o, (ea, eb), run);
    (o, r)
}

/// At most `max` of `pairs`, evenly spread (deterministic).
pub(crate) fn spread(
    pairs: &[TrianglePair],
    max: usize,
) -> impl Iterator<Item = TrianglePair> + '_ {
    let step = pairs.len().div_ceil(max.max(1)).max(1);
    pairs.iter().step_by(step).copied()
}

//! Narrow phase: every candidate pair tested by its fidelity, in parallel, inside the budget.
//!
//! Each pair gets a priority ([`pair_priority`]: last confidence, closeness, speed, waiting).
//! Under a time budget the exact pairs and the most urgent others that fit (by the measured
//! cost of a test) are tested and the rest answered from memory; tested ADB pairs get
//! node-pair slices of the budget in proportion to their priority ([`slices`]), and an ADB
//! traversal stops at its slice and reports its best estimate. Runs of pairs are planned, then
//! tested or answered from memory, on the task pool, each thread with its own workspaces and
//! each run writing its answers in place, in pair order (by entity): the outcome is the same
//! for any number of threads.
use std::cell::RefCell;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use glam::Vec3;
use smallvec::SmallVec;

use super::broad_phase::{CandidatePair, CandidatePairs};
use super::budget::{SliceShare, WorkRate, pair_priority};
use super::components::Fidelity;
use super::contact::{ContactPoint, interpenetration_contact, node_contact, triangle_pair_contact};
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::plugin::{CollisionConfig, FrameBudget};
use super::pool::CollisionTaskPool;
use super::prepare::{ColliderEntry, ColliderFrame, Geometry};
use crate::adb::{AdbQuery, AdbWorkspace, Budget, adb_intersects};
use crate::bvh::{
    QueryWorkspace, TrianglePair, intersecting_pairs, intersects_with, root_boxes_overlap,
};

/// How a pair's answer was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// World boxes only.
    Bounds,
    /// The exact BVH query.
    Exact,
    /// The ADB traversal (cut by its slice of the budget).
    Adb,
    /// The Tracking stage (tracked pairs).
    Tracking,
    /// The self-collision pass of a deformable mesh (`a == b`).
    SelfCollision,
    /// Not tested: neither rigid entity moved since the last run (identical poses, e.g.
    /// sleeping bodies) and the last answer was settled, so it is reused as is.
    Cached,
    /// Not tested: under a time budget, the pair was not among the most urgent that fit, or
    /// the deadline passed before its turn (exact pairs are always chosen, tested first in
    /// their run of pairs and against a later deadline, so only an overload of exact pairs
    /// alone cuts them). A pair that collided in the
    /// previous run keeps that answer and contact (temporal coherence; an exact pair's contact
    /// is re-measured on its triangle pair at the current poses, other reused contacts have
    /// depth 0: they stop approach without pushing the same correction twice); any other pair
    /// gets the oriented root-box test: for an exact pair, overlapping boxes count as a contact
    /// with probability 0.5 and a box contact (level geometry must not be passed through); the
    /// others keep "not colliding" (with the last probability). Either way the pair waits less
    /// in the next run.
    Coherence,
}

/// The answer for one pair in one run.
#[derive(Debug, Clone, PartialEq)]
pub struct PairOutcome {
    /// First entity (the smaller).
    pub a: Entity,
    /// Second entity (`a` itself for a self-collision).
    pub b: Entity,
    /// How it was found.
    pub method: Method,
    /// Whether the pair is reported as colliding.
    pub collides: bool,
    /// Confidence that it collides (1 or 0 for exact answers).
    pub probability: f64,
    /// Node pairs (box tests or estimates) the query visited.
    pub node_pairs: u64,
    /// Whether an ADB query ran out of its slice before settling.
    pub budget_exhausted: bool,
    /// The pair's priority in this run.
    pub priority: f32,
    /// Contact points (empty when not colliding).
    pub contacts: SmallVec<[ContactPoint; 1]>,
}

impl PairOutcome {
    /// A slot not written yet.
    fn placeholder() -> Self {
        let ends = (Entity::PLACEHOLDER, Entity::PLACEHOLDER);
        Self::exact(ends, Method::Bounds, 0, 0.0, SmallVec::new())
    }

    /// An exact answer from contacts found: colliding iff there is one.
    pub(crate) fn exact(
        (a, b): (Entity, Entity),
        method: Method,
        node_pairs: u64,
        priority: f32,
        contacts: SmallVec<[ContactPoint; 1]>,
    ) -> Self {
        let collides = !contacts.is_empty();
        Self {
            a,
            b,
            method,
            collides,
            probability: f64::from(u8::from(collides)),
            node_pairs,
            budget_exhausted: false,
            priority,
            contacts,
        }
    }
}

/// The pair answers of the current run, sorted by `(a, b)` after the Report stage; also what
/// the narrow phase remembers (last confidences, the measured costs).
#[derive(Resource, Debug, Default)]
pub struct PairOutcomes {
    pub(crate) outcomes: Vec<PairOutcome>,
    pub(crate) tracked: Vec<CandidatePair>,
    /// This run's tested pairs, sorted, and their answers (the memory for the next run).
    pub(crate) history_keys: Vec<(Entity, Entity)>,
    pub(crate) history: Vec<PairMemory>,
    /// The previous run's (read while this run's are written; buffers swap each run).
    last_keys: Vec<(Entity, Entity)>,
    last: Vec<PairMemory>,
    /// Reused buffers: the jobs in pair order, what each run of them counted.
    jobs: Vec<Job>,
    plan_counts: Vec<PlanCounts>,
    run_counts: Vec<RunCounts>,
    pub(crate) rate: WorkRate,
    pub(crate) costs: PairCosts,
    /// The last planned run answered every pair from its cache, and the entries' fidelities
    /// then (see [`at_rest`]).
    all_cached: bool,
    fidelities: Vec<Fidelity>,
    pub(crate) exact_node_pairs: f64,
}

impl PairOutcomes {
    /// The answers of the last run, sorted by `(a, b)`.
    pub fn outcomes(&self) -> &[PairOutcome] {
        &self.outcomes
    }
}

/// What a pair's last answer was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PairMemory {
    probability: f64,
    collides: bool,
    settled: bool,
    /// Runs since the pair was last tested (answered from memory meanwhile).
    stale: u32,
    /// The run whose poses the answer was computed at.
    tested_run: u64,
    /// How it was asked for: the pair's method and `p_min` then (another fidelity asks anew).
    method: Method,
    p_min: f64,
    contact: Option<ContactPoint>,
}

impl Default for PairMemory {
    fn default() -> Self {
        Self {
            probability: 0.0,
            collides: false,
            settled: false,
            stale: 0,
            tested_run: 0,
            method: Method::Bounds,
            p_min: 1.0,
            contact: None,
        }
    }
}

/// The narrow phase's measured costs (time mode), as moving averages of wall-clock time:
/// a test, and an answer from memory (or for a bounds-only pair), both in parallel.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PairCosts {
    test_us: f64,
    memory_us: f64,
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
    fn learn(value: &mut f64, count: usize, time: Duration) {
        // A handful of pairs says little about the cost of many (pool start-up dominates).
        if count >= 32 {
            *value = 0.8 * *value + 0.2 * time.as_secs_f64() * 1e6 / count as f64;
        }
    }
}

#[derive(Debug, Clone, Copy)]
struct Job {
    pair: CandidatePair,
    method: Method,
    /// Priority bucket (0: highest), for choosing the pairs tested under a time budget.
    bucket: u8,
    /// The last answer is settled and still holds (answered from memory, no test needed).
    cached: bool,
    /// Tested in this run ([`choose_tests`]).
    chosen: bool,
    p_min: f64,
    priority: f32,
    /// Index of the pair's last answer.
    last: Option<u32>,
}

impl Job {
    /// A job not planned yet.
    fn new(pair: CandidatePair) -> Self {
        Self {
            pair,
            method: Method::Tracking,
            bucket: 0,
            cached: false,
            chosen: false,
            p_min: 1.0,
            priority: 0.0,
            last: None,
        }
    }

    /// Needs a test (not answered from a still valid memory, not a bounds-only pair).
    fn testable(&self) -> bool {
        !self.cached && self.method != Method::Bounds
    }

    /// Needs a test, and is tested only if the budget allows (not an exact pair).
    fn optional(&self) -> bool {
        self.testable() && self.method != Method::Exact
    }
}

#[derive(Default)]
struct Workspaces {
    exact: QueryWorkspace,
    adb: AdbWorkspace,
    pairs: Vec<TrianglePair>,
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

/// Number of priority buckets ([`priority_bucket`]).
const BUCKETS: usize = 32;

/// The bucket of a priority: 0 for the highest, quarter steps of `log2` (read off the float's
/// exponent and two leading mantissa bits: monotone, no `log2` call).
fn priority_bucket(p: f32) -> u8 {
    // 2^-4 and below share the last bucket, 2^4 and above the first.
    let lowest = 2f32.powi(-4).to_bits() >> 21;
    let step = (p.max(0.0).to_bits() >> 21).saturating_sub(lowest);
    (BUCKETS as u32 - 1).saturating_sub(step) as u8
}

/// Tests the candidate pairs (all but tracked ones) in parallel.
///
/// Under a time budget, the pairs tested are the most urgent ones that fit (by the measured
/// cost of a test); the others are answered from memory ([`Method::Coherence`]) and wait less
/// next time. The deadline stays as a safety net for the tests themselves.
///
/// Two parallel passes over runs of pairs: planning (method, memory, priority; each run counts
/// its pairs per priority bucket), then, once the pairs to test are marked, the tests and the
/// answers from memory, each run writing its answers straight into place (pair order).
pub fn narrow_phase(
    frame: Res<ColliderFrame>,
    candidates: Res<CandidatePairs>,
    config: Res<CollisionConfig>,
    pool: Res<CollisionTaskPool>,
    mut state: ResMut<PairOutcomes>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let state = &mut *state;
    let entries = &frame.entries;
    let run = diag.frame;
    let config_changed = config.is_changed();
    if at_rest(state, &candidates, entries, config_changed, run) {
        // Every answer of the last run stands as it is (the memory too).
        diag.counters.cached_pairs += state.outcomes.len() as u64;
        diag.record(
            Stage::NarrowPhase,
            start.elapsed(),
            state.outcomes.len() as u64,
        );
        diag.narrow_phase_ended();
        return;
    }
    state.fidelities.clear();
    state.fidelities.extend(entries.iter().map(|e| e.fidelity));
    state.tracked.clear();
    // This run's answers become the next run's memory; the last run's are read meanwhile.
    std::mem::swap(&mut state.history_keys, &mut state.last_keys);
    std::mem::swap(&mut state.history, &mut state.last);
    let (old_keys, old_memory) = (&state.last_keys, &state.last);
    // Plan in parallel over runs of candidates (the priorities need the last answers: each
    // run finds its place in them once, then merge-joins).
    let jobs = &mut state.jobs;
    jobs.clear();
    jobs.extend(candidates.pairs.iter().map(|&pair| Job::new(pair)));
    let chunk = pool.chunk_size(jobs.len(), 256);
    let plans = &mut state.plan_counts;
    plans.clear();
    plans.resize(jobs.len().div_ceil(chunk), PlanCounts::default());
    let mut work: Vec<_> = jobs.chunks_mut(chunk).zip(plans.iter_mut()).collect();
    pool.for_each_mut(&mut work, 1, |(c, counts)| {
        **counts = plan_jobs(c, entries, old_keys, old_memory, run, config_changed);
    });
    drop(work);
    let plan = plans.iter().fold(PlanCounts::default(), PlanCounts::add);
    // Tracked pairs go to the Tracking stage; the others keep their order.
    if plan.tracked > 0 {
        jobs.retain(|j| {
            if j.method == Method::Tracking {
                state.tracked.push(j.pair);
            }
            j.method != Method::Tracking
        });
    }
    // Which pairs are tested: all of them, or under a time budget the exact pairs (asked for:
    // level geometry, things that must not pass through each other) and the most urgent of
    // the others that fit.
    let (cut, deadlines, nodes) = match config.budget {
        FrameBudget::Time(budget) => {
            let target = diag.time_target(budget);
            let testable = plan.testable as usize;
            let now = Instant::now();
            let costs = &state.costs;
            let (count, deadline) = tests_that_fit(target, testable, jobs.len(), &diag, costs, now);
            let exact = testable - plan.optional.iter().sum::<u32>() as usize;
            let optional = count.saturating_sub(exact);
            // The ADB node pairs the measured rate gets done in the time for tests.
            let tests_us = deadline.saturating_duration_since(now).as_secs_f64() * 1e6;
            let rate = state.rate.node_pairs_per_us;
            let nodes = (tests_us * rate - state.exact_node_pairs).max(0.0);
            let cut = priority_cut(&plan.optional, optional);
            // Exact pairs may also use the time the answers from memory were given.
            let answers = Duration::from_secs_f64(jobs.len() as f64 * costs.memory_us * 1e-6);
            let deadlines = Deadlines::at(deadline, deadline + answers);
            (Some(cut), deadlines, Some(nodes as u64))
        }
        FrameBudget::NodePairs(n) => (None, Deadlines::default(), Some(n)),
        FrameBudget::Unlimited => (None, Deadlines::default(), None),
    };
    let chosen = choose_tests(jobs, cut);
    // ADB slices: the node pairs of the budget shared among the tested ADB pairs by priority.
    // In time mode the tests were chosen by what a test costs, so each gets enough to settle
    // (an eighth of the largest slice at least): a test cut short is wasted, tested again
    // next run and never answered from memory; the deadline still bounds the whole.
    let min_slice = match config.budget {
        FrameBudget::Time(_) => config.min_slice.max(config.max_slice / 8),
        _ => config.min_slice,
    };
    let share = nodes.map(|total| {
        SliceShare::from_sum(
            chosen.adb,
            chosen.adb_priority,
            total,
            min_slice,
            config.max_slice,
        )
    });
    let ctx = Context {
        entries,
        memory: old_memory,
        config: &config,
        run,
        share,
        deadlines,
        node_pairs_per_us: state.rate.node_pairs_per_us,
    };
    // Tests and answers from memory in parallel, each run of pairs writing its own slots.
    let n = jobs.len();
    let outcomes = &mut state.outcomes;
    outcomes.truncate(n);
    outcomes.resize(n, PairOutcome::placeholder());
    let keys = &mut state.history_keys;
    keys.resize(n, (Entity::PLACEHOLDER, Entity::PLACEHOLDER));
    let memory = &mut state.history;
    memory.resize(n, PairMemory::default());
    // Runs of at least 64 pairs, or fewer when most of them are tested (8 tests a run).
    let tested_share = chosen.count.max(1) as f64 / n.max(1) as f64;
    let chunk = pool.chunk_size(n, ((8.0 / tested_share) as usize).clamp(8, 64));
    let counts = &mut state.run_counts;
    counts.clear();
    counts.resize(n.div_ceil(chunk), RunCounts::default());
    let mut work: Vec<_> = jobs
        .chunks(chunk)
        .zip(outcomes.chunks_mut(chunk))
        .zip(keys.chunks_mut(chunk).zip(memory.chunks_mut(chunk)))
        .zip(counts.iter_mut())
        .map(|(((jobs, outcomes), (keys, memory)), counts)| ChunkWork {
            jobs,
            outcomes,
            keys,
            memory,
            counts,
        })
        .collect();
    let run_start = Instant::now();
    pool.for_each_mut(&mut work, 1, |w| ctx.run_chunk(w));
    let wall = run_start.elapsed();
    drop(work);
    let total = counts.iter().fold(RunCounts::default(), RunCounts::add);
    // Wall-clock costs: the threads' times over the parallelism the section had.
    let busy = total.test_time + total.memory_time;
    let parallel =
        (busy.as_secs_f64() / wall.as_secs_f64().max(1e-9)).clamp(1.0, pool.threads() as f64);
    let test_time = total.test_time.div_f64(parallel);
    let memory_time = total.memory_time.div_f64(parallel);
    let c = &mut diag.counters;
    c.node_pairs += total.node_pairs;
    c.adb_pairs += u64::from(plan.adb);
    c.exact_pairs += total.exact_pairs;
    c.budget_exhausted_pairs += total.budget_exhausted;
    c.coherence_pairs += total.coherence;
    c.cached_pairs += total.cached;
    c.tested_pairs += total.tested;
    c.test_time += test_time;
    state
        .rate
        .update(total.node_pairs, test_time.as_secs_f64() * 1e6);
    state.exact_node_pairs = 0.7 * state.exact_node_pairs + 0.3 * total.exact_node_pairs as f64;
    let costs = &mut state.costs;
    PairCosts::learn(&mut costs.test_us, total.tested as usize, test_time);
    PairCosts::learn(&mut costs.memory_us, n, memory_time);
    state.all_cached = plan.tracked == 0 && total.cached == n as u64;
    diag.record(Stage::NarrowPhase, start.elapsed(), n as u64);
    diag.narrow_phase_ended();
}

/// Whether this run's answers are the last run's: a scene at rest. The broad phase reused its
/// pairs (no entity came, went, or changed its box or layers), no pose or geometry changed,
/// no fidelity and no configuration either, the last run answered every pair from its cache
/// (rigid pairs whose settled answers still hold; nothing tracked) and nothing was added to its
/// answers since (a self-collision pass).
fn at_rest(
    state: &PairOutcomes,
    candidates: &CandidatePairs,
    entries: &[ColliderEntry],
    config_changed: bool,
    run: u64,
) -> bool {
    candidates.reused
        && state.all_cached
        && !config_changed
        && state.outcomes.len() == state.jobs.len()
        && state.fidelities.len() == entries.len()
        && entries
            .iter()
            .zip(&state.fidelities)
            .all(|(e, f)| e.still_since < run && e.fidelity == *f)
}

/// What a run of jobs counted while planning.
#[derive(Debug, Clone, Copy, Default)]
struct PlanCounts {
    /// Optional jobs (tested if the budget allows) per priority bucket.
    optional: [u32; BUCKETS],
    /// Jobs that need a test (optional and exact).
    testable: u32,
    /// Jobs handed over to the Tracking stage.
    tracked: u32,
    /// ADB jobs.
    adb: u32,
}

impl PlanCounts {
    fn add(mut self, other: &Self) -> Self {
        for (a, b) in self.optional.iter_mut().zip(&other.optional) {
            *a += b;
        }
        self.testable += other.testable;
        self.tracked += other.tracked;
        self.adb += other.adb;
        self
    }

    fn count(jobs: &[Job]) -> Self {
        let mut counts = Self::default();
        for j in jobs {
            if j.optional() {
                counts.optional[usize::from(j.bucket)] += 1;
            }
            counts.testable += u32::from(j.testable());
            counts.tracked += u32::from(j.method == Method::Tracking);
            counts.adb += u32::from(j.method == Method::Adb);
        }
        counts
    }
}

/// What a run of jobs did: its answers by kind, its work, and the time its thread spent in
/// tests and in answers from memory.
#[derive(Debug, Clone, Copy, Default)]
struct RunCounts {
    node_pairs: u64,
    exact_node_pairs: u64,
    exact_pairs: u64,
    budget_exhausted: u64,
    coherence: u64,
    cached: u64,
    tested: u64,
    test_time: Duration,
    memory_time: Duration,
}

impl RunCounts {
    fn add(self, o: &Self) -> Self {
        Self {
            node_pairs: self.node_pairs + o.node_pairs,
            exact_node_pairs: self.exact_node_pairs + o.exact_node_pairs,
            exact_pairs: self.exact_pairs + o.exact_pairs,
            budget_exhausted: self.budget_exhausted + o.budget_exhausted,
            coherence: self.coherence + o.coherence,
            cached: self.cached + o.cached,
            tested: self.tested + o.tested,
            test_time: self.test_time + o.test_time,
            memory_time: self.memory_time + o.memory_time,
        }
    }

    fn count(&mut self, o: &PairOutcome) {
        self.node_pairs += o.node_pairs;
        if o.method == Method::Exact {
            self.exact_node_pairs += o.node_pairs;
            self.exact_pairs += 1;
        }
        self.budget_exhausted += u64::from(o.budget_exhausted);
        self.coherence += u64::from(o.method == Method::Coherence);
        self.cached += u64::from(o.method == Method::Cached);
        self.tested += u64::from(matches!(o.method, Method::Adb | Method::Exact));
    }
}

/// One run of jobs and the slots its answers go to.
struct ChunkWork<'a> {
    jobs: &'a [Job],
    outcomes: &'a mut [PairOutcome],
    keys: &'a mut [(Entity, Entity)],
    memory: &'a mut [PairMemory],
    counts: &'a mut RunCounts,
}

/// When the tests of a run stop (`None`: never): the optional ones, and the exact ones (later:
/// they were asked for, so only an overload of exact pairs alone cuts them).
#[derive(Debug, Clone, Copy, Default)]
struct Deadlines {
    others: Option<Instant>,
    exact: Option<Instant>,
}

impl Deadlines {
    fn at(others: Instant, exact: Instant) -> Self {
        Self {
            others: Some(others),
            exact: Some(exact),
        }
    }
}

/// What [`choose_tests`] chose: how many, and the ADB ones' count and summed priority (for
/// their node-pair slices).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Chosen {
    count: usize,
    adb: u64,
    adb_priority: f64,
}

/// Fills in each job of a run of candidates (in pair order): its method (`Tracking`: handed
/// over to the Tracking stage), last answer, whether that answer still holds, and priority
/// (`run`: this run's number; after a change of configuration no answer is reused as is).
fn plan_jobs(
    jobs: &mut [Job],
    entries: &[ColliderEntry],
    old_keys: &[(Entity, Entity)],
    old_memory: &[PairMemory],
    run: u64,
    config_changed: bool,
) -> PlanCounts {
    let Some(first) = jobs.first() else {
        return PlanCounts::default();
    };
    let key_of = |j: &Job| {
        (
            entries[j.pair.a as usize].entity,
            entries[j.pair.b as usize].entity,
        )
    };
    let mut cursor = old_keys.partition_point(|k| *k < key_of(first));
    for job in jobs.iter_mut() {
        let (ea, eb) = (&entries[job.pair.a as usize], &entries[job.pair.b as usize]);
        (job.method, job.p_min) = match ea.fidelity.combine(eb.fidelity) {
            Fidelity::Tracking { .. } => continue,
            Fidelity::Bounds => (Method::Bounds, 1.0),
            Fidelity::Exact => (Method::Exact, 1.0),
            Fidelity::Adb { p_min } if both_rigid(ea, eb) => (Method::Adb, p_min),
            Fidelity::Adb { .. } => (Method::Exact, 1.0),
        };
        let key = (ea.entity, eb.entity);
        while cursor < old_keys.len() && old_keys[cursor] < key {
            cursor += 1;
        }
        job.last = (old_keys.get(cursor) == Some(&key)).then_some(cursor as u32);
        let memory = job.last.map(|i| &old_memory[i as usize]);
        // Settled, asked for the same way, the configuration the same, and neither pose nor
        // geometry changed since: the answer still holds.
        job.cached = !config_changed
            && memory.is_some_and(|m| {
                m.settled
                    && (m.method, m.p_min) == (job.method, job.p_min)
                    && m.tested_run >= ea.still_since.max(eb.still_since)
            });
        // A cached answer that does not collide needs no priority (no test, no contact).
        if job.cached && !memory.is_some_and(|m| m.collides) {
            continue;
        }
        let mut priority = pair_priority(
            memory.map(|m| m.probability),
            &ea.aabb,
            &eb.aabb,
            eb.motion - ea.motion,
        );
        if job.method == Method::Exact {
            // Exact pairs were asked for: tested before the others.
            priority *= 4.0;
        }
        // New pairs first (collisions start there); a pair answered from memory waits less
        // each run, so none starves under overload.
        match memory {
            None => priority *= 4.0,
            Some(m) => priority *= (1 + m.stale.min(15)) as f32,
        }
        // Both stopped (unchanged since the last run) but the answer is not settled: one test
        // now is answered from memory for as long as they rest.
        let still = ea.still_since < run && eb.still_since < run;
        if still && memory.is_some_and(|m| !m.settled) {
            priority *= 4.0;
        }
        job.priority = priority;
        job.bucket = priority_bucket(priority);
    }
    PlanCounts::count(jobs)
}

/// How many pairs can be tested in what is left of the time budget, by the measured costs,
/// and the deadline of the tests. `testable` of the `all` pairs need a test; the others (and
/// the tested ones past the deadline) are answered from memory, which takes time too.
fn tests_that_fit(
    budget: Duration,
    testable: usize,
    all: usize,
    diag: &CollisionDiagnostics,
    costs: &PairCosts,
    now: Instant,
) -> (usize, Instant) {
    let spent = now.saturating_duration_since(diag.frame_start);
    let reserve = diag.reserve_after_narrow();
    let left_us = budget
        .saturating_sub(spent)
        .saturating_sub(reserve)
        .as_secs_f64()
        * 1e6;
    // At least a sixteenth of the budget goes to tests, whatever the overhead: without tests
    // nothing ever settles (and pairs that stopped moving cannot be cached).
    let tests_us = (left_us - all as f64 * costs.memory_us).max(budget.as_secs_f64() * 0.0625e6);
    let count = ((tests_us / costs.test_us.max(1e-3)) as usize).min(testable);
    (count, now + Duration::from_secs_f64(tests_us * 1e-6))
}

/// Marks the jobs tested in this run: every testable exact job, and the optional ones above
/// the `cut` (all of them without a cut; within the cut's bucket the first in pair order).
fn choose_tests(jobs: &mut [Job], cut: Option<(u8, usize)>) -> Chosen {
    let mut chosen = Chosen::default();
    let mut taken_at_cut = 0;
    for j in jobs.iter_mut() {
        j.chosen = j.testable()
            && (j.method == Method::Exact
                || match cut {
                    None => true,
                    Some((bucket, _)) if j.bucket < bucket => true,
                    Some((bucket, room)) if j.bucket == bucket && taken_at_cut < room => {
                        taken_at_cut += 1;
                        true
                    }
                    Some(_) => false,
                });
        if j.chosen {
            chosen.count += 1;
            if j.method == Method::Adb {
                chosen.adb += 1;
                chosen.adb_priority += f64::from(j.priority);
            }
        }
    }
    chosen
}

/// The priority bucket at which `count` of the jobs counted `per_bucket` are reached (from
/// the most urgent), and how many of that bucket fit.
fn priority_cut(per_bucket: &[u32; BUCKETS], count: usize) -> (u8, usize) {
    let mut before = 0;
    for (b, &n) in per_bucket.iter().enumerate() {
        let n = n as usize;
        if before + n >= count {
            return (b as u8, count - before);
        }
        before += n;
    }
    (BUCKETS as u8, 0)
}

/// One thread's scratch for the tests of a run: the query settings, the workspaces, and the
/// most node pairs the next ADB test may visit (what is left of the time for tests).
struct Scratch<'w> {
    query: AdbQuery,
    exact: &'w mut QueryWorkspace,
    adb: &'w mut AdbWorkspace,
    pairs: &'w mut Vec<TrianglePair>,
    node_cap: u64,
}

struct Context<'a> {
    entries: &'a [ColliderEntry],
    memory: &'a [PairMemory],
    config: &'a CollisionConfig,
    /// This run's number.
    run: u64,
    /// The share of the node-pair budget among the tested ADB pairs (`None`: unlimited).
    share: Option<SliceShare>,
    deadlines: Deadlines,
    /// The measured rate of the tests (time mode), for the cap of each test.
    node_pairs_per_us: f64,
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

    /// Answers a run of jobs into its slots: first the chosen exact ones are tested, then in
    /// pair order the other chosen ones are tested and the rest answered from memory. Past a
    /// deadline, chosen jobs are answered from memory too.
    fn run_chunk(&self, w: &mut ChunkWork) {
        let start = Instant::now();
        let mut counts = RunCounts::default();
        with_workspaces(|exact, adb, pairs| {
            let s = &mut Scratch {
                query: self.query(),
                exact,
                adb,
                pairs,
                node_cap: u64::MAX,
            };
            let mut put = |i: usize, (o, m): (PairOutcome, PairMemory), counts: &mut RunCounts| {
                counts.count(&o);
                w.keys[i] = (o.a, o.b);
                w.memory[i] = m;
                w.outcomes[i] = o;
            };
            let is_exact = |j: &Job| j.chosen && j.method == Method::Exact;
            let mut late = false;
            for (i, job) in w.jobs.iter().enumerate().filter(|(_, j)| is_exact(j)) {
                late = late || self.deadlines.exact.is_some_and(|d| Instant::now() > d);
                let answer = self.answer(job, late, s);
                put(i, answer, &mut counts);
            }
            counts.test_time = start.elapsed();
            let mut late = false;
            for (i, job) in w.jobs.iter().enumerate().filter(|(_, j)| !is_exact(j)) {
                let answer = if job.chosen {
                    let t = Instant::now();
                    if let Some(d) = self.deadlines.others {
                        // No test runs far past the deadline: an ADB test visits at most
                        // the node pairs the measured rate gets done before it.
                        let left_us = d.saturating_duration_since(t).as_secs_f64() * 1e6;
                        late = late || left_us <= 0.0;
                        s.node_cap = (left_us * self.node_pairs_per_us) as u64;
                    }
                    let answer = self.answer(job, late, s);
                    counts.test_time += t.elapsed();
                    answer
                } else {
                    self.answer(job, true, s)
                };
                put(i, answer, &mut counts);
            }
        });
        counts.memory_time = start.elapsed().saturating_sub(counts.test_time);
        *w.counts = counts;
    }

    /// The answer of a job from its memory, when that needs no geometry: [`Method::Cached`]
    /// if the memory still holds, else for an ADB pair [`Method::Coherence`] (its old contact
    /// without depth: it stops approach but does not push the same correction twice). `None`
    /// otherwise: no memory, or an exact pair (its contact is re-measured by `run_job`).
    fn remembered(&self, job: &Job) -> Option<(PairOutcome, PairMemory)> {
        let m = &self.memory[job.last? as usize];
        let method = match job.method {
            _ if job.cached => Method::Cached,
            Method::Adb => Method::Coherence,
            // Exact pairs (re-measured contact, root-box fallback) take the full path.
            _ => return None,
        };
        let (ea, eb) = (
            &self.entries[job.pair.a as usize],
            &self.entries[job.pair.b as usize],
        );
        let contact = m.contact.filter(|_| m.collides);
        let outcome = PairOutcome {
            a: ea.entity,
            b: eb.entity,
            method,
            collides: m.collides,
            probability: m.probability,
            node_pairs: 0,
            budget_exhausted: false,
            priority: job.priority,
            contacts: match (method, contact) {
                (_, None) => SmallVec::new(),
                (Method::Cached, Some(c)) => smallvec::smallvec![c],
                // The old contact without its depth (see `Method::Coherence`).
                (_, Some(c)) => smallvec::smallvec![ContactPoint { depth: 0.0, ..c }],
            },
        };
        let memory = match method {
            Method::Cached => *m,
            _ => PairMemory {
                stale: m.stale + 1,
                ..*m
            },
        };
        Some((outcome, memory))
    }

    /// The answer of a job (from memory when `late`) and the memory it leaves.
    fn answer(&self, job: &Job, late: bool, s: &mut Scratch) -> (PairOutcome, PairMemory) {
        if (job.cached || late)
            && let Some(answer) = self.remembered(job)
        {
            return answer;
        }
        let o = self.run_job(job, late, s);
        let (ea, eb) = (
            &self.entries[job.pair.a as usize],
            &self.entries[job.pair.b as usize],
        );
        // An answer from memory keeps the memory (with the run it was computed in, so a pair
        // that stops moving can be cached); a test makes a new one.
        let memory = match (o.method, job.last) {
            (Method::Coherence, Some(i)) => PairMemory {
                stale: self.memory[i as usize].stale + 1,
                ..self.memory[i as usize]
            },
            _ => PairMemory {
                probability: o.probability,
                collides: o.collides,
                settled: !o.budget_exhausted && o.method != Method::Coherence && both_rigid(ea, eb),
                stale: 0,
                tested_run: self.run,
                method: job.method,
                p_min: job.p_min,
                contact: o.contacts.first().copied(),
            },
        };
        (o, memory)
    }

    fn run_job(&self, job: &Job, late: bool, s: &mut Scratch) -> PairOutcome {
        let (ea, eb) = (
            &self.entries[job.pair.a as usize],
            &self.entries[job.pair.b as usize],
        );
        let mut out = PairOutcome {
            a: ea.entity,
            b: eb.entity,
            method: job.method,
            collides: false,
            probability: 0.0,
            node_pairs: 0,
            budget_exhausted: false,
            priority: job.priority,
            contacts: SmallVec::new(),
        };
        let (ma, mb) = (ea.geometry.mesh(), eb.geometry.mesh());
        // Cached answers and ADB pairs with a memory never get here ([`Self::remembered`]).
        let last = job.last.map(|i| self.memory[i as usize]);
        match job.method {
            Method::Bounds => {
                out.collides = true;
                out.probability = 1.0;
                out.contacts.push(bounds_contact(ea, eb));
            }
            Method::Adb | Method::Exact if late => {
                out.method = Method::Coherence;
                match last {
                    Some(m) if m.collides => {
                        out.collides = true;
                        out.probability = m.probability;
                        // An exact pair's contact re-measured on its triangle pair at the
                        // current poses (cheap): level geometry keeps pushing out what sinks
                        // into it. A box contact (no triangles) stays, without its depth.
                        out.contacts.extend(m.contact.map(|c| match c.triangles {
                            Some(t) => triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t),
                            None => ContactPoint { depth: 0.0, ..c },
                        }));
                    }
                    // An exact pair (level geometry, things that must not pass through each
                    // other), new or apart last time: err on the side of a contact.
                    _ if job.method == Method::Exact
                        && root_boxes_overlap(ma, &ea.pose, mb, &eb.pose) =>
                    {
                        out.collides = true;
                        out.probability = 0.5;
                        let mut c = bounds_contact(ea, eb);
                        c.depth *= 0.5;
                        out.contacts.push(c);
                    }
                    // Other pairs: "not colliding", as uncertain as last time.
                    _ => out.probability = last.map_or(0.5, |m| m.probability),
                }
            }
            Method::Exact if both_rigid(ea, eb) => {
                // First hit only (stops early): one contact, as for ADB pairs.
                let hit = intersects_with(ma, &ea.pose, mb, &eb.pose, &Default::default(), s.exact);
                let contacts = hit
                    .witness
                    .map(|t| triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t))
                    .into_iter()
                    .collect();
                let (ends, nodes) = ((ea.entity, eb.entity), hit.node_pairs_visited);
                return PairOutcome::exact(ends, Method::Exact, nodes, job.priority, contacts);
            }
            Method::Exact => {
                s.pairs.clear();
                intersecting_pairs(ma, &ea.pose, mb, &eb.pose, s.exact, s.pairs);
                let contacts = spread(s.pairs, self.config.max_contacts_per_pair)
                    .map(|t| triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t))
                    .collect();
                let (ends, nodes) = ((ea.entity, eb.entity), s.exact.node_pairs_visited());
                return PairOutcome::exact(ends, Method::Exact, nodes, job.priority, contacts);
            }
            Method::Adb => {
                let (ta, tb) = (
                    ea.geometry.adb().expect("ADB pairs are rigid"),
                    eb.geometry.adb().expect("ADB pairs are rigid"),
                );
                s.query.p_min = job.p_min;
                s.query.budget = match self.share {
                    None => Budget::Unlimited,
                    Some(share) => {
                        let cap = s.node_cap.max(self.config.min_slice);
                        Budget::NodePairs(share.slice(job.priority).min(cap))
                    }
                };
                let r = adb_intersects(ta, &ea.pose, tb, &eb.pose, &s.query, s.adb);
                out.node_pairs = r.node_pairs_visited;
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
            }
            Method::Tracking | Method::SelfCollision | Method::Coherence | Method::Cached => {
                unreachable!("not a narrow-phase job")
            }
        }
        out
    }
}

fn both_rigid(a: &ColliderEntry, b: &ColliderEntry) -> bool {
    matches!(
        (&a.geometry, &b.geometry),
        (Geometry::Rigid(_), Geometry::Rigid(_))
    )
}

/// At most `max` of `pairs`, evenly spread (deterministic).
pub(crate) fn spread(
    pairs: &[TrianglePair],
    max: usize,
) -> impl Iterator<Item = TrianglePair> + '_ {
    let step = pairs.len().div_ceil(max.max(1)).max(1);
    pairs.iter().step_by(step).copied()
}

/// The contact of two overlapping boxes: the centre of their overlap, the axis of least
/// overlap (from the first towards the second), that overlap as depth.
fn bounds_contact(a: &ColliderEntry, b: &ColliderEntry) -> ContactPoint {
    let lo = a.aabb.min.max(b.aabb.min);
    let hi = a.aabb.max.min(b.aabb.max);
    let overlap = (hi - lo).max(Vec3::ZERO);
    let axis = overlap.min_position();
    let mut normal = Vec3::ZERO;
    normal[axis] = if b.aabb.center()[axis] >= a.aabb.center()[axis] {
        1.0
    } else {
        -1.0
    };
    ContactPoint {
        point: (lo + hi) * 0.5,
        normal,
        depth: overlap[axis],
        triangles: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(method: Method, priority: f32, cached: bool) -> Job {
        Job {
            method,
            bucket: priority_bucket(priority),
            cached,
            priority,
            ..Job::new(CandidatePair { a: 0, b: 1 })
        }
    }

    fn chosen(jobs: &[Job]) -> Vec<usize> {
        (0..jobs.len()).filter(|&i| jobs[i].chosen).collect()
    }

    #[test]
    fn buckets_follow_the_priority_in_quarter_octaves() {
        let b = |p: f32| priority_bucket(p);
        assert_eq!(b(16.0), 0);
        assert_eq!(b(1000.0), 0);
        assert_eq!(b(1.0), 15);
        assert_eq!(b(0.0625), 31);
        assert_eq!(b(0.0), 31);
        assert_eq!(b(1.0) - b(2.0), 4);
        let mut last = 0;
        for k in 0..400 {
            let bucket = b(20.0 * 0.98f32.powi(k));
            assert!(bucket >= last, "monotone");
            last = bucket;
        }
    }

    #[test]
    fn exact_jobs_are_always_chosen_then_the_most_urgent_that_fit() {
        let mut jobs = [
            job(Method::Adb, 0.5, false),
            job(Method::Exact, 0.1, false),
            job(Method::Adb, 8.0, false),
            job(Method::Adb, 9.0, true),
            job(Method::Bounds, 9.0, false),
            job(Method::Adb, 2.0, false),
            job(Method::Exact, 0.1, true),
            job(Method::Adb, 2.0, false),
        ];
        let plan = PlanCounts::count(&jobs);
        assert_eq!(plan.testable, 5);
        assert_eq!(plan.optional.iter().sum::<u32>(), 4);
        assert_eq!(plan.adb, 5);
        // Two optional tests fit: the 8.0 job and the first 2.0 job (pair order in a bucket).
        let cut = priority_cut(&plan.optional, 2);
        let c = choose_tests(&mut jobs, Some(cut));
        assert_eq!(chosen(&jobs), vec![1, 2, 5]);
        assert_eq!((c.count, c.adb, c.adb_priority), (3, 2, 10.0));
        // No cut (work budgets): every testable job.
        assert_eq!(choose_tests(&mut jobs, None).count, 5);
        assert_eq!(chosen(&jobs), vec![0, 1, 2, 5, 7]);
        // Nothing fits: the exact job still.
        let cut = priority_cut(&plan.optional, 0);
        choose_tests(&mut jobs, Some(cut));
        assert_eq!(chosen(&jobs), vec![1]);
        // More than there are: all of them.
        let cut = priority_cut(&plan.optional, 100);
        choose_tests(&mut jobs, Some(cut));
        assert_eq!(chosen(&jobs), vec![0, 1, 2, 5, 7]);
    }

    #[test]
    fn the_tests_that_fit_follow_the_measured_costs() {
        let diag = CollisionDiagnostics::default();
        let costs = PairCosts {
            test_us: 2.0,
            memory_us: 0.1,
        };
        let now = diag.frame_start;
        // 2000 µs, 5000 pairs answered at 0.1 µs: 1500 µs for tests of 2 µs.
        let budget = Duration::from_micros(2000);
        let (count, deadline) = tests_that_fit(budget, 10_000, 5000, &diag, &costs, now);
        assert_eq!(count, 750);
        assert_eq!(deadline - now, Duration::from_micros(1500));
        // Never more than the testable ones.
        assert_eq!(tests_that_fit(budget, 10, 5000, &diag, &costs, now).0, 10);
        // Overhead beyond the budget: a sixteenth of it still goes to tests.
        let (count, _) = tests_that_fit(budget, 10_000, 50_000, &diag, &costs, now);
        assert_eq!(count, 62);
    }
}

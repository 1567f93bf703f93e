//! Narrow phase: every candidate pair tested by its fidelity, in parallel, inside the budget.
//!
//! Pairs are ordered by priority ([`pair_priority`]) and ADB pairs get node-pair slices of the
//! frame budget in proportion to it ([`slices`]); an ADB traversal stops at its slice and
//! reports its best estimate. Chunks of pairs run on the task pool, each thread with its own
//! workspaces; results are merged in pair order (by entity), so the outcome is the same for
//! any number of threads.
use std::cell::RefCell;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use glam::Vec3;
use smallvec::SmallVec;

use super::broad_phase::{CandidatePair, CandidatePairs};
use super::budget::{WorkRate, pair_priority, slices};
use super::components::Fidelity;
use super::contact::{ContactPoint, node_contact, triangle_pair_contact};
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::plugin::{CollisionConfig, FrameBudget};
use super::pool::CollisionTaskPool;
use super::prepare::{ColliderEntry, ColliderFrame, Geometry};
use crate::adb::{AdbQuery, AdbWorkspace, Budget, adb_intersects};
use crate::bvh::{
    QueryWorkspace, TrianglePair, intersecting_pairs, intersects_with, root_boxes_overlap,
};
use crate::geometry::Pose;

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
    /// Not tested: the time budget's deadline passed before the pair's turn. A pair that
    /// collided in the previous run keeps that answer and contact (temporal coherence); any
    /// other pair gets the oriented root-box test: for an exact pair, overlapping boxes count
    /// as a contact with probability 0.5 and a box contact (level geometry must not be passed
    /// through); the others keep "not colliding" (with the last probability). Reused contacts
    /// have depth 0 (they stop approach without pushing the same correction twice). Either way
    /// the pair waits less in the next run.
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
/// the narrow phase remembers (last confidences, the measured work rate).
#[derive(Resource, Debug, Default)]
pub struct PairOutcomes {
    pub(crate) outcomes: Vec<PairOutcome>,
    pub(crate) tracked: Vec<CandidatePair>,
    /// Last answers' pairs, sorted, and the answers.
    pub(crate) history_keys: Vec<(Entity, Entity)>,
    pub(crate) history: Vec<PairMemory>,
    pub(crate) rate: WorkRate,
    pub(crate) exact_node_pairs: f64,
    /// Serial time of the last run outside the pair tests (kept free before the deadline).
    pub(crate) overhead: Duration,
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
    poses: (Pose, Pose),
    contact: Option<ContactPoint>,
}

#[derive(Debug, Clone, Copy)]
struct Job {
    /// Position in pair order.
    pos: u32,
    pair: CandidatePair,
    method: Method,
    p_min: f64,
    priority: f32,
    slice: u64,
    /// Index of the pair's last answer.
    last: Option<u32>,
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

/// Tests the candidate pairs (all but tracked ones) in parallel.
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
    state.outcomes.clear();
    state.tracked.clear();
    // Candidates and the last run's answers are both sorted by entity pair: a merge join.
    let (old_keys, old_memory) = (
        std::mem::take(&mut state.history_keys),
        std::mem::take(&mut state.history),
    );
    let mut cursor = 0;
    let mut jobs = Vec::with_capacity(candidates.pairs.len());
    for &pair in &candidates.pairs {
        let (ea, eb) = (&entries[pair.a as usize], &entries[pair.b as usize]);
        let (method, p_min) = match ea.fidelity.combine(eb.fidelity) {
            Fidelity::Tracking { .. } => {
                state.tracked.push(pair);
                continue;
            }
            Fidelity::Bounds => (Method::Bounds, 1.0),
            Fidelity::Exact => (Method::Exact, 1.0),
            Fidelity::Adb { p_min } if both_rigid(ea, eb) => (Method::Adb, p_min),
            Fidelity::Adb { .. } => (Method::Exact, 1.0),
        };
        let key = (ea.entity, eb.entity);
        while cursor < old_keys.len() && old_keys[cursor] < key {
            cursor += 1;
        }
        let last = (old_keys.get(cursor) == Some(&key)).then_some(cursor as u32);
        let p_last = last.map(|i| old_memory[i as usize].probability);
        let stale = last.map_or(0, |i| old_memory[i as usize].stale);
        let mut priority = pair_priority(p_last, &ea.aabb, &eb.aabb, eb.motion - ea.motion);
        if method == Method::Exact {
            // Exact pairs were asked for: tested before the others.
            priority *= 4.0;
        }
        // New pairs first (collisions start there); a pair answered from memory waits less
        // each run, so none starves under overload.
        if last.is_none() {
            priority *= 4.0;
        }
        priority *= (1 + stale.min(15)) as f32;
        jobs.push(Job {
            pos: jobs.len() as u32,
            pair,
            method,
            p_min,
            priority,
            slice: u64::MAX,
            last,
        });
    }
    let (total, deadline) = node_budget(&config, &diag, state, Instant::now());
    let mut adb_pairs = 0u64;
    if let Some(total) = total {
        let adb: Vec<usize> = (0..jobs.len())
            .filter(|&i| jobs[i].method == Method::Adb)
            .collect();
        let pr: Vec<f32> = adb.iter().map(|&i| jobs[i].priority).collect();
        for (&i, s) in adb
            .iter()
            .zip(slices(&pr, total, config.min_slice, config.max_slice))
        {
            jobs[i].slice = s;
        }
        adb_pairs = adb.len() as u64;
    } else {
        adb_pairs += jobs.iter().filter(|j| j.method == Method::Adb).count() as u64;
    }
    // Highest priority first when a deadline may cut the run (buckets of priority, pair order
    // within a bucket: linear and deterministic).
    let order = if deadline.is_some() {
        by_priority(&jobs)
    } else {
        jobs.clone()
    };
    let ctx = Context {
        entries,
        memory: &old_memory,
        config: &config,
        deadline,
    };
    let chunk = pool.chunk_size(order.len(), 8);
    let run_start = Instant::now();
    let results = pool.map_chunks(&order, chunk, |c| ctx.run_chunk(c));
    let run_time = run_start.elapsed();
    // Back in pair order (by entity), whatever the processing order and thread count.
    let mut slots: Vec<Option<(PairOutcome, PairMemory)>> = vec![None; jobs.len()];
    for (pos, outcome, memory) in results.into_iter().flatten() {
        slots[pos as usize] = Some((outcome, memory));
    }
    let c = &mut diag.counters;
    let (mut np, mut exact_np) = (0, 0);
    for (o, m) in slots.into_iter().flatten() {
        np += o.node_pairs;
        if o.method == Method::Exact {
            exact_np += o.node_pairs;
            c.exact_pairs += 1;
        }
        c.budget_exhausted_pairs += u64::from(o.budget_exhausted);
        c.coherence_pairs += u64::from(o.method == Method::Coherence);
        c.cached_pairs += u64::from(o.method == Method::Cached);
        state.history_keys.push((o.a, o.b));
        state.history.push(m);
        state.outcomes.push(o);
    }
    c.node_pairs += np;
    c.adb_pairs += adb_pairs;
    let elapsed = start.elapsed();
    state
        .rate
        .update(np, state.outcomes.len(), elapsed.as_secs_f64() * 1e6);
    state.exact_node_pairs = 0.7 * state.exact_node_pairs + 0.3 * exact_np as f64;
    state.overhead = elapsed.saturating_sub(run_time);
    diag.record(Stage::NarrowPhase, elapsed, state.outcomes.len() as u64);
}

/// The jobs, highest priority first: 32 buckets of `log2(priority)`, each in pair order.
fn by_priority(jobs: &[Job]) -> Vec<Job> {
    let bucket = |p: f32| 31 - ((p.max(1e-6).log2() * 4.0 + 16.0).clamp(0.0, 31.0) as usize);
    let mut counts = [0usize; 33];
    for j in jobs {
        counts[bucket(j.priority) + 1] += 1;
    }
    for i in 1..33 {
        counts[i] += counts[i - 1];
    }
    let mut out = jobs.to_vec();
    for j in jobs {
        let b = bucket(j.priority);
        out[counts[b]] = *j;
        counts[b] += 1;
    }
    out
}

/// The ADB node pairs of this run (`None`: unlimited) and, in time mode, the deadline after
/// which ADB pairs are answered by temporal coherence ([`Method::Coherence`]).
fn node_budget(
    config: &CollisionConfig,
    diag: &CollisionDiagnostics,
    state: &PairOutcomes,
    now: Instant,
) -> (Option<u64>, Option<Instant>) {
    match config.budget {
        FrameBudget::Unlimited => (None, None),
        FrameBudget::NodePairs(n) => (Some(n), None),
        FrameBudget::Time(budget) => {
            let spent = now.saturating_duration_since(diag.frame_start);
            // The serial overhead is about half before the tests (spent by now), half after.
            let reserve = diag.reserve_after_narrow() + state.overhead / 2;
            // At least a quarter of the budget goes to tests, whatever the overhead: without
            // tests nothing ever settles (and pairs that stopped moving cannot be cached).
            let left = budget
                .saturating_sub(spent)
                .saturating_sub(reserve)
                .max(budget / 4);
            let work = left.as_secs_f64() * 1e6 * state.rate.node_pairs_per_us;
            let adb_work = (work - state.exact_node_pairs).max(0.0);
            (Some(adb_work as u64), Some(now + left))
        }
    }
}

struct Context<'a> {
    entries: &'a [ColliderEntry],
    memory: &'a [PairMemory],
    config: &'a CollisionConfig,
    deadline: Option<Instant>,
}

impl Context<'_> {
    fn run_chunk(&self, jobs: &[Job]) -> Vec<(u32, PairOutcome, PairMemory)> {
        let mut query = AdbQuery {
            k_min: self.config.k_min,
            exact_leaves: self.config.adb_exact_leaves,
            ..AdbQuery::default()
        };
        let mut late = false;
        with_workspaces(|exact, adb, pairs| {
            jobs.iter()
                .enumerate()
                .map(|(k, job)| {
                    // The clock is read every 8 pairs.
                    if k % 8 == 0 && !late {
                        late = self.deadline.is_some_and(|d| Instant::now() > d);
                    }
                    let o = self.run_job(job, late, &mut query, exact, adb, pairs);
                    let (ea, eb) = (
                        &self.entries[job.pair.a as usize],
                        &self.entries[job.pair.b as usize],
                    );
                    // An answer from memory keeps the memory (with the poses it was computed
                    // at, so a pair that stops moving can be cached); a test makes a new one.
                    let memory = match (o.method, job.last) {
                        (Method::Coherence, Some(i)) => PairMemory {
                            stale: self.memory[i as usize].stale + 1,
                            ..self.memory[i as usize]
                        },
                        (Method::Cached, Some(i)) => self.memory[i as usize],
                        _ => PairMemory {
                            probability: o.probability,
                            collides: o.collides,
                            settled: !o.budget_exhausted
                                && o.method != Method::Coherence
                                && both_rigid(ea, eb),
                            stale: 0,
                            poses: (ea.pose, eb.pose),
                            contact: o.contacts.first().copied(),
                        },
                    };
                    (job.pos, o, memory)
                })
                .collect()
        })
    }

    fn run_job(
        &self,
        job: &Job,
        late: bool,
        query: &mut AdbQuery,
        exact: &mut QueryWorkspace,
        adb: &mut AdbWorkspace,
        pairs: &mut Vec<TrianglePair>,
    ) -> PairOutcome {
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
        let last = job.last.map(|i| self.memory[i as usize]);
        if let Some(m) = last.filter(|m| m.settled && m.poses == (ea.pose, eb.pose)) {
            out.method = Method::Cached;
            out.collides = m.collides;
            out.probability = m.probability;
            out.contacts.extend(m.contact.filter(|_| m.collides));
            return out;
        }
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
                        // The old contact without its depth: it stops approach (an impulse)
                        // but does not push the same correction twice.
                        out.contacts
                            .extend(m.contact.map(|c| ContactPoint { depth: 0.0, ..c }));
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
                let hit = intersects_with(ma, &ea.pose, mb, &eb.pose, &Default::default(), exact);
                let contacts = hit
                    .witness
                    .map(|t| triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t))
                    .into_iter()
                    .collect();
                let (ends, nodes) = ((ea.entity, eb.entity), hit.node_pairs_visited);
                return PairOutcome::exact(ends, Method::Exact, nodes, job.priority, contacts);
            }
            Method::Exact => {
                pairs.clear();
                intersecting_pairs(ma, &ea.pose, mb, &eb.pose, exact, pairs);
                let contacts = spread(pairs, self.config.max_contacts_per_pair)
                    .map(|t| triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t))
                    .collect();
                let (ends, nodes) = ((ea.entity, eb.entity), exact.node_pairs_visited());
                return PairOutcome::exact(ends, Method::Exact, nodes, job.priority, contacts);
            }
            Method::Adb => {
                let (ta, tb) = (
                    ea.geometry.adb().expect("ADB pairs are rigid"),
                    eb.geometry.adb().expect("ADB pairs are rigid"),
                );
                query.p_min = job.p_min;
                query.budget = match job.slice {
                    u64::MAX => Budget::Unlimited,
                    s => Budget::NodePairs(s),
                };
                let r = adb_intersects(ta, &ea.pose, tb, &eb.pose, query, adb);
                out.node_pairs = r.node_pairs_visited;
                out.collides = r.collides;
                out.probability = r.probability;
                out.budget_exhausted = r.budget_exhausted;
                if r.collides {
                    out.contacts.push(match r.witness {
                        Some(w) => match w.triangles {
                            Some(t) => triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t),
                            None => node_contact(ma, &ea.pose, mb, &eb.pose, &w, r.probability),
                        },
                        None => bounds_contact(ea, eb),
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

//! Narrow phase: every candidate pair tested by its fidelity, in parallel, inside the budget.
//!
//! Pairs are ordered by priority ([`pair_priority`]) and ADB pairs get node-pair slices of the
//! frame budget in proportion to it ([`slices`]); an ADB traversal stops at its slice and
//! reports its best estimate. Chunks of pairs run on the task pool, each thread with its own
//! workspaces; results are merged in pair order (by entity), so the outcome is the same for
//! any number of threads.
use std::cell::RefCell;
use std::collections::HashMap;
use std::time::Instant;

use bevy_ecs::prelude::*;
use glam::Vec3;
use smallvec::SmallVec;

use super::broad_phase::{CandidatePair, CandidatePairs};
use super::budget::{WorkRate, pair_priority, slices};
use super::components::Fidelity;
use super::contact::{ContactPoint, box_depth, triangle_pair_contact};
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::plugin::{CollisionConfig, FrameBudget};
use super::pool::CollisionTaskPool;
use super::prepare::{ColliderEntry, ColliderFrame, Geometry};
use crate::adb::{AdbQuery, AdbWorkspace, Budget, adb_intersects};
use crate::bvh::{QueryWorkspace, TrianglePair, intersecting_pairs, intersects_with};

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
    pub contacts: SmallVec<[ContactPoint; 4]>,
}

impl PairOutcome {
    /// An exact answer from contacts found: colliding iff there is one.
    pub(crate) fn exact(
        (a, b): (Entity, Entity),
        method: Method,
        node_pairs: u64,
        priority: f32,
        contacts: SmallVec<[ContactPoint; 4]>,
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
    pub(crate) history: HashMap<(Entity, Entity), f64>,
    pub(crate) rate: WorkRate,
    pub(crate) exact_node_pairs: f64,
}

impl PairOutcomes {
    /// The answers of the last run, sorted by `(a, b)`.
    pub fn outcomes(&self) -> &[PairOutcome] {
        &self.outcomes
    }
}

#[derive(Debug, Clone, Copy)]
struct Job {
    pair: CandidatePair,
    method: Method,
    p_min: f64,
    priority: f32,
    slice: u64,
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
    let mut jobs = Vec::with_capacity(candidates.pairs.len());
    for &pair in &candidates.pairs {
        let (ea, eb) = (&entries[pair.a as usize], &entries[pair.b as usize]);
        let fidelity = ea.fidelity.combine(eb.fidelity);
        let (method, p_min) = match fidelity {
            Fidelity::Tracking { .. } => {
                state.tracked.push(pair);
                continue;
            }
            Fidelity::Bounds => (Method::Bounds, 1.0),
            Fidelity::Exact => (Method::Exact, 1.0),
            Fidelity::Adb { p_min } => match (&ea.geometry, &eb.geometry) {
                (Geometry::Rigid(_), Geometry::Rigid(_)) => (Method::Adb, p_min),
                _ => (Method::Exact, 1.0),
            },
        };
        let last = state.history.get(&(ea.entity, eb.entity)).copied();
        let priority = pair_priority(last, &ea.aabb, &eb.aabb, eb.motion - ea.motion);
        jobs.push(Job {
            pair,
            method,
            p_min,
            priority,
            slice: u64::MAX,
        });
    }
    // Highest priority first (ties by pair: deterministic).
    jobs.sort_by(|x, y| y.priority.total_cmp(&x.priority).then(x.pair.cmp(&y.pair)));
    let (total, deadline) = node_budget(&config, &diag, state, start);
    let adb: Vec<usize> = (0..jobs.len())
        .filter(|&i| jobs[i].method == Method::Adb)
        .collect();
    if let Some(total) = total {
        let pr: Vec<f32> = adb.iter().map(|&i| jobs[i].priority).collect();
        for (&i, s) in adb
            .iter()
            .zip(slices(&pr, total, config.min_slice, config.max_slice))
        {
            jobs[i].slice = s;
        }
    }
    let ctx = Context {
        entries,
        config: &config,
        deadline,
    };
    let chunk = pool.chunk_size(jobs.len(), 8);
    let results = pool.map_chunks(&jobs, chunk, |c| ctx.run_chunk(c));
    let mut outcomes: Vec<(CandidatePair, PairOutcome)> = results.into_iter().flatten().collect();
    outcomes.sort_unstable_by_key(|(p, _)| *p);
    state.outcomes.extend(outcomes.into_iter().map(|(_, o)| o));
    // Learn the rate and the exact work for the next run's budget.
    let (mut np, mut exact_np, mut exhausted) = (0u64, 0u64, 0u64);
    for o in &state.outcomes {
        np += o.node_pairs;
        if o.method == Method::Exact {
            exact_np += o.node_pairs;
        }
        exhausted += u64::from(o.budget_exhausted);
    }
    let elapsed = start.elapsed();
    state
        .rate
        .update(np, state.outcomes.len(), elapsed.as_secs_f64() * 1e6);
    state.exact_node_pairs = 0.7 * state.exact_node_pairs + 0.3 * exact_np as f64;
    state.history = state
        .outcomes
        .iter()
        .map(|o| ((o.a, o.b), o.probability))
        .collect();
    diag.record(Stage::NarrowPhase, elapsed, state.outcomes.len() as u64);
    let c = &mut diag.counters;
    c.node_pairs += np;
    c.adb_pairs += adb.len() as u64;
    c.budget_exhausted_pairs += exhausted;
    c.exact_pairs += state
        .outcomes
        .iter()
        .filter(|o| o.method == Method::Exact)
        .count() as u64;
}

/// The ADB node pairs of this run (`None`: unlimited) and, in time mode, the deadline after
/// which pairs get only their minimum slice.
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
            let reserve = diag.reserve_after_narrow();
            let left = budget.saturating_sub(spent).saturating_sub(reserve);
            let work = left.as_secs_f64() * 1e6 * state.rate.node_pairs_per_us;
            let adb_work = (work - state.exact_node_pairs).max(0.0);
            (Some(adb_work as u64), Some(now + left))
        }
    }
}

struct Context<'a> {
    entries: &'a [ColliderEntry],
    config: &'a CollisionConfig,
    deadline: Option<Instant>,
}

impl Context<'_> {
    fn run_chunk(&self, jobs: &[Job]) -> Vec<(CandidatePair, PairOutcome)> {
        let mut query = AdbQuery {
            k_min: self.config.k_min,
            ..AdbQuery::default()
        };
        with_workspaces(|exact, adb, pairs| {
            jobs.iter()
                .map(|job| (job.pair, self.run_job(job, &mut query, exact, adb, pairs)))
                .collect()
        })
    }

    fn run_job(
        &self,
        job: &Job,
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
        match job.method {
            Method::Bounds => {
                out.collides = true;
                out.probability = 1.0;
                out.contacts.push(bounds_contact(ea, eb));
            }
            Method::Exact if both_rigid(ea, eb) => {
                let hit = intersects_with(ma, &ea.pose, mb, &eb.pose, &Default::default(), exact);
                out.node_pairs = hit.node_pairs_visited;
                out.collides = hit.collides;
                out.probability = f64::from(u8::from(hit.collides));
                if let Some(t) = hit.witness {
                    out.contacts
                        .push(triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t));
                }
            }
            Method::Exact => {
                pairs.clear();
                intersecting_pairs(ma, &ea.pose, mb, &eb.pose, exact, pairs);
                out.node_pairs = exact.node_pairs_visited();
                out.collides = !pairs.is_empty();
                out.probability = f64::from(u8::from(out.collides));
                let max = self.config.max_self_contacts;
                out.contacts.extend(
                    spread(pairs, max)
                        .map(|t| triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t)),
                );
            }
            Method::Adb => {
                let (ta, tb) = (
                    ea.geometry.adb().expect("ADB pairs are rigid"),
                    eb.geometry.adb().expect("ADB pairs are rigid"),
                );
                let late = self.deadline.is_some_and(|d| Instant::now() > d);
                query.p_min = job.p_min;
                query.budget = match (job.slice, late) {
                    (u64::MAX, _) => Budget::Unlimited,
                    (_, true) => Budget::NodePairs(self.config.min_slice),
                    (s, false) => Budget::NodePairs(s),
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
                            None => ContactPoint {
                                point: w.point,
                                normal: w.normal,
                                depth: box_depth(&ea.aabb, &eb.aabb, w.normal),
                                triangles: None,
                            },
                        },
                        None => bounds_contact(ea, eb),
                    });
                }
            }
            Method::Tracking | Method::SelfCollision => unreachable!("not a narrow-phase job"),
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

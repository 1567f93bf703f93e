//! Tracking stage: pairs with [`Fidelity::Tracking`] and self-collision of deformable meshes.
//!
//! A self-colliding deformable mesh with [`Fidelity::Tracking`] and every pair whose fidelity
//! is `Tracking` run the stochastic closest-feature [`Tracker`]: its pairs persist from run to
//! run (in [`TrackingState`], one tracker per pair or mesh, seeded from the configured seed
//! and the two entities, so results do not depend on thread scheduling), and its contacts come
//! with points, normals and depths. Other self-colliding meshes get the exact BVH pass
//! (`self_intersections`). Trackers and surfaces run in parallel; the outcomes are merged in
//! pair order. Each entity's [`FeaturePairs`] lists the triangle pairs in contact with each
//! partner, as of the last run.
//!
//! [`Fidelity::Tracking`]: super::Fidelity::Tracking
//! [`SelfCollision`]: super::SelfCollision
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

use bevy_ecs::entity::{EntityHashMap, EntityHashSet};
use bevy_ecs::prelude::*;
use smallvec::SmallVec;

use super::components::Fidelity;
use super::config::{CollisionConfig, FrameBudget};
use super::contact::{ContactPoint, triangle_pair_contact};
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::narrow_phase::{Method, PairOutcome, spread, with_workspaces};
use super::pairs::PairTable;
use super::pool::CollisionTaskPool;
use super::prepare::{ColliderEntry, ColliderTable, Geometry};
use crate::bvh::{CollisionMesh, TrianglePair, self_intersections};
use crate::geometry::Pose;
use crate::tracking::{Contact, TrackedSurface, Tracker, TrackerConfig};

/// The feature pairs an entity is tracking against each partner (itself for self-collision),
/// as of the last run: kept across runs, dropped with the entity. Inserted by the Tracking
/// stage on both entities of each tracked pair, every partner listed, each pair as (this
/// entity's triangle, the partner's).
#[derive(Component, bevy_reflect::Reflect, Debug, Clone, Default, PartialEq)]
#[reflect(opaque, Component, Clone, Debug, PartialEq)]
pub struct FeaturePairs {
    /// Per partner entity, the triangle pairs (this entity's, the partner's) in contact.
    pub partners: SmallVec<[(Entity, Vec<TrianglePair>); 2]>,
}

impl FeaturePairs {
    /// The pairs tracked against `partner`.
    pub fn with(&self, partner: Entity) -> &[TrianglePair] {
        self.partners
            .iter()
            .find(|(e, _)| *e == partner)
            .map_or(&[], |(_, p)| p.as_slice())
    }
}

/// A mesh prepared for tracking, and the geometry it was prepared from.
struct Surface {
    /// Identity of a rigid source tree (its `Arc`'s address; 0 for a deformable mesh, which
    /// is recognised by its triangles): a swapped collider rebuilds.
    source: usize,
    surface: Arc<TrackedSurface>,
}

/// The stochastic trackers between runs: one [`TrackedSurface`] per tracked entity (rigid
/// meshes share one per collider mesh) and one [`Tracker`] per tracked pair or self-colliding
/// mesh. Entries of entities that left the tracking stage are dropped every run, so memory
/// stays bounded.
#[derive(Resource, Default)]
pub struct TrackingState {
    surfaces: EntityHashMap<Surface>,
    shared: HashMap<usize, Arc<TrackedSurface>>,
    trackers: HashMap<(Entity, Entity), Tracker>,
}

impl TrackingState {
    /// Trackers alive (pairs and self-colliding meshes being tracked).
    pub fn trackers(&self) -> usize {
        self.trackers.len()
    }

    /// The tracker of a pair (`(e, e)` for a self-colliding mesh), if it is being tracked.
    pub fn tracker(&self, a: Entity, b: Entity) -> Option<&Tracker> {
        self.trackers.get(&(a.min(b), a.max(b)))
    }
}

/// Brings the surfaces of `entries` up to date: rigid meshes once per shared tree, deformable
/// ones built once and moved to the refitted positions every run (in parallel). A swapped
/// collider (another tree, or a deformable with other triangles) gets a new surface, and the
/// trackers involving it start over.
fn update_surfaces(
    state: &mut TrackingState,
    entries: &[&ColliderEntry],
    pool: &CollisionTaskPool,
) {
    let mut deformed: EntityHashMap<&CollisionMesh> = EntityHashMap::default();
    for e in entries {
        let (source, same) = match &e.geometry {
            Geometry::Rigid(tree) => {
                let source = Arc::as_ptr(tree) as usize;
                (
                    source,
                    state
                        .surfaces
                        .get(&e.entity)
                        .is_some_and(|s| s.source == source),
                )
            }
            Geometry::Deformable(mesh) => {
                deformed.insert(e.entity, &**mesh);
                let same = state.surfaces.get(&e.entity).is_some_and(|s| {
                    s.source == 0 && s.surface.mesh().triangles() == mesh.mesh().triangles()
                });
                (0, same)
            }
        };
        if same {
            continue;
        }
        let surface = match &e.geometry {
            Geometry::Rigid(tree) => state
                .shared
                .entry(source)
                .or_insert_with(|| {
                    Arc::new(TrackedSurface::new(tree.collision_mesh().mesh().clone()))
                })
                .clone(),
            Geometry::Deformable(mesh) => Arc::new(TrackedSurface::new(mesh.mesh().clone())),
        };
        if state
            .surfaces
            .insert(e.entity, Surface { source, surface })
            .is_some()
        {
            state
                .trackers
                .retain(|k, _| k.0 != e.entity && k.1 != e.entity);
        }
    }
    let mut jobs: Vec<(&mut Arc<TrackedSurface>, &CollisionMesh)> = state
        .surfaces
        .iter_mut()
        .filter_map(|(entity, slot)| deformed.get(entity).map(|m| (&mut slot.surface, *m)))
        .collect();
    pool.for_each_mut(&mut jobs, 1, |(surface, mesh)| {
        // Deformable surfaces are not shared: no copy. Positions come from a validated refit.
        let s = Arc::make_mut(surface);
        if s.mesh().positions() != mesh.mesh().positions() {
            let _ = s.set_positions(mesh.mesh().positions());
        }
    });
}

/// The tracker configuration of a pair: thickness from the meshes, pairs per frame from the
/// fidelity, a seed from the configured seed and the two entities, continuous tracking when
/// either has [`ContinuousCollision`](super::ContinuousCollision).
fn tracker_config(
    a: &TrackedSurface,
    b: &TrackedSurface,
    pairs_per_frame: u32,
    seed: u64,
    ea: Entity,
    eb: Entity,
    continuous: bool,
) -> TrackerConfig {
    let mut config = TrackerConfig::for_surface(a);
    config.continuous = continuous;
    config.thickness = 0.05 * (a.mean_edge_length() + b.mean_edge_length());
    config.pairs_per_frame = pairs_per_frame.max(1) as usize;
    config.seed = seed ^ ea.to_bits().rotate_left(17) ^ eb.to_bits().rotate_left(41);
    config
}

/// A tracker contact as a contact point in world space.
fn world_contact(c: &Contact, pose_a: &Pose, self_mode: bool) -> ContactPoint {
    let (pa, pb, n) = if self_mode {
        (
            pose_a.transform_point(c.point_a),
            pose_a.transform_point(c.point_b),
            pose_a.transform_vector(c.normal),
        )
    } else {
        (c.point_a, c.point_b, c.normal)
    };
    ContactPoint {
        point: (pa + pb) * 0.5,
        normal: n,
        depth: c.depth,
        triangles: Some(TrianglePair {
            a: c.triangle_a,
            b: c.triangle_b,
        }),
        time_of_impact: c.time_of_impact,
    }
}

/// One tracker's work in a run.
struct Job {
    key: (Entity, Entity),
    /// The pair's slot in the pair table, and its colliders' slots.
    pair: u32,
    a: u32,
    b: u32,
    tracker: Tracker,
    contacts: SmallVec<[ContactPoint; 1]>,
    pairs: Vec<TrianglePair>,
}

/// The job of pair slot `pair` between colliders `a` and `b` (the same for a self-colliding
/// mesh): the pair's tracker, taken out of `state` or made with the pair's fidelity (pairs
/// per frame) and seed. Their surfaces must be up to date.
fn job(
    state: &mut TrackingState,
    colliders: &ColliderTable,
    (pair, a, b): (u32, u32, u32),
    seed: u64,
) -> Job {
    let (ea, eb) = (colliders.entry(a), colliders.entry(b));
    let key = (ea.entity, eb.entity);
    let continuous = ea.continuous.is_some() || eb.continuous.is_some();
    let mut tracker = state.trackers.remove(&key).unwrap_or_else(|| {
        let n = match ea.fidelity.combine(eb.fidelity) {
            Fidelity::Tracking { pairs_per_frame } => pairs_per_frame,
            _ => 1,
        };
        let (sa, sb) = (
            &state.surfaces[&ea.entity].surface,
            &state.surfaces[&eb.entity].surface,
        );
        Tracker::new(tracker_config(
            sa, sb, n, seed, ea.entity, eb.entity, continuous,
        ))
    });
    if tracker.config().continuous != continuous {
        let config = TrackerConfig {
            continuous,
            ..tracker.config().clone()
        };
        tracker.set_config(config);
    }
    Job {
        key,
        pair,
        a,
        b,
        tracker,
        contacts: SmallVec::new(),
        pairs: Vec::new(),
    }
}

/// Runs `jobs` of run `run` in parallel, each on its own tracker; past `deadline` the trackers
/// cut their work (see [`Tracker::step_self_until`]). A continuous tracker between two meshes
/// sweeps both colliders' motions in the run. The earliest contact with a time of impact
/// comes first (the started event's time of impact), then at most `max_contacts` in all.
fn run_jobs(
    jobs: &mut [Job],
    colliders: &ColliderTable,
    state: &TrackingState,
    pool: &CollisionTaskPool,
    (max_contacts, run): (usize, u64),
    deadline: Option<Instant>,
) {
    pool.for_each_mut(jobs, 1, |job| {
        let (ea, eb) = (colliders.entry(job.a), colliders.entry(job.b));
        let sa = &state.surfaces[&ea.entity].surface;
        let self_mode = job.a == job.b;
        let found: &[Contact] = if self_mode {
            job.tracker.step_self_until(sa, deadline)
        } else if job.tracker.config().continuous {
            let sb = &state.surfaces[&eb.entity].surface;
            let (ma, mb) = (ea.motion_in(run), eb.motion_in(run));
            job.tracker
                .step_pair_moving_until(sa, &ma, sb, &mb, deadline)
        } else {
            let sb = &state.surfaces[&eb.entity].surface;
            job.tracker
                .step_pair_until(sa, &ea.pose, sb, &eb.pose, deadline)
        };
        let max = max_contacts.max(1);
        let first_impact = found
            .iter()
            .enumerate()
            .filter_map(|(i, c)| c.time_of_impact.map(|t| (t, i)))
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .map(|(_, i)| i);
        let step = found.len().div_ceil(max).max(1);
        job.contacts = first_impact
            .into_iter()
            .chain(
                (0..found.len())
                    .step_by(step)
                    .filter(|&i| Some(i) != first_impact),
            )
            .take(max)
            .map(|i| world_contact(&found[i], &ea.pose, self_mode))
            .collect();
        job.pairs = found
            .iter()
            .map(|c| TrianglePair {
                a: c.triangle_a,
                b: c.triangle_b,
            })
            .collect();
    });
}

/// Feature pairs of this run for entities that have no [`FeaturePairs`] yet, inserted once
/// each at the end (every partner kept, none overwritten by another's insert).
#[derive(Default)]
struct NewFeaturePairs(EntityHashMap<FeaturePairs>);

/// Records `pairs` (`a`'s triangle, `b`'s) as `a`'s feature pairs with `b` and, swapped, as
/// `b`'s with `a`.
fn record_pairs(
    features: &mut Query<&mut FeaturePairs>,
    new: &mut NewFeaturePairs,
    (a, b): (Entity, Entity),
    pairs: &[TrianglePair],
) {
    let swapped: Vec<TrianglePair> = pairs
        .iter()
        .map(|t| TrianglePair { a: t.b, b: t.a })
        .collect();
    let sides: [(Entity, Entity, &[TrianglePair]); 2] = [(a, b, pairs), (b, a, &swapped)];
    for &(owner, partner, list) in &sides[..if a == b { 1 } else { 2 }] {
        let set = |f: &mut FeaturePairs| {
            f.partners.retain(|(e, _)| *e != partner);
            if !list.is_empty() {
                f.partners.push((partner, list.to_vec()));
            }
        };
        match features.get_mut(owner) {
            Ok(mut f) => set(&mut f),
            Err(_) if !list.is_empty() => set(new.0.entry(owner).or_default()),
            Err(_) => {}
        }
    }
}

impl NewFeaturePairs {
    fn insert(self, commands: &mut Commands) {
        let mut new: Vec<_> = self.0.into_iter().collect();
        new.sort_unstable_by_key(|(e, _)| *e);
        for (e, f) in new {
            commands.entity(e).try_insert(f);
        }
    }
}

/// Drops the feature pairs of partners that are no longer tracked (apart, despawned, or
/// changed fidelity), so each entity's lists hold only live pairs.
pub fn prune_feature_pairs(pairs: Res<PairTable>, mut q: Query<(Entity, &mut FeaturePairs)>) {
    let mut live: Vec<(Entity, Entity)> = pairs
        .tracked
        .iter()
        .flat_map(|&p| {
            let s = pairs.slot(p);
            [(s.a, s.b), (s.b, s.a)]
        })
        .collect();
    live.sort_unstable();
    for (owner, mut f) in &mut q {
        if f.partners
            .iter()
            .any(|(p, _)| live.binary_search(&(owner, *p)).is_err())
        {
            f.partners
                .retain(|(p, _)| live.binary_search(&(owner, *p)).is_ok());
        }
    }
}

/// The tracked pairs of this run: `(pair, collider a, collider b)`, self-collisions
/// (`a == b`) or pairs of two colliders.
fn tracked(pairs: &PairTable, self_pairs: bool) -> Vec<(u32, u32, u32)> {
    pairs
        .tracked
        .iter()
        .map(|&p| (p, pairs.ends(p).body_a, pairs.ends(p).body_b))
        .filter(|&(_, a, b)| (a == b) == self_pairs)
        .collect()
}

/// Run condition: the narrow phase handed over some self-colliding mesh.
pub fn needs_self_pass(pairs: Res<PairTable>) -> bool {
    pairs
        .tracked
        .iter()
        .any(|&p| pairs.ends(p).body_a == pairs.ends(p).body_b)
}

/// Run condition: the narrow phase handed over some tracked pair of two colliders.
pub fn needs_tracking(pairs: Res<PairTable>) -> bool {
    pairs
        .tracked
        .iter()
        .any(|&p| pairs.ends(p).body_a != pairs.ends(p).body_b)
}

/// What the Tracking stage's systems share: the tables, the trackers, the task pool.
#[derive(bevy_ecs::system::SystemParam)]
pub struct TrackingContext<'w, 's> {
    colliders: Res<'w, ColliderTable>,
    pairs: ResMut<'w, PairTable>,
    config: Res<'w, CollisionConfig>,
    pool: Res<'w, CollisionTaskPool>,
    state: ResMut<'w, TrackingState>,
    features: Query<'w, 's, &'static mut FeaturePairs>,
    commands: Commands<'w, 's>,
    diag: ResMut<'w, CollisionDiagnostics>,
}

/// Self-collision of every [`SelfCollision`] deformable mesh, in parallel per mesh: the
/// stochastic tracker for meshes with [`Fidelity::Tracking`], the exact pass for the others.
pub fn self_collision(mut cx: TrackingContext) {
    let start = Instant::now();
    let run = cx.diag.frame;
    let meshes = tracked(&cx.pairs, true);
    let colliders = &*cx.colliders;
    let (stochastic, exact): (Vec<_>, Vec<_>) = meshes
        .iter()
        .partition(|&&(_, i, _)| matches!(colliders.entry(i).fidelity, Fidelity::Tracking { .. }));
    let max = cx.config.max_self_contacts;
    let results = cx.pool.map_chunks(&exact, 1, |chunk| {
        let (pair, i, _) = chunk[0];
        let e = colliders.entry(i);
        let mesh = e.geometry.mesh();
        with_workspaces(|ws, _, pairs| {
            pairs.clear();
            self_intersections(mesh, ws, pairs);
            let contacts: SmallVec<_> = spread(pairs, max)
                .map(|t| triangle_pair_contact(mesh, &e.pose, mesh, &e.pose, t))
                .collect();
            let ends = (e.entity, e.entity);
            let nodes = ws.node_pairs_visited();
            let o = PairOutcome::exact(ends, Method::SelfCollision, nodes, 1.0, contacts, run);
            (pair, o)
        })
    });
    cx.diag.counters.node_pairs += results.iter().map(|(_, o)| o.node_pairs).sum::<u64>();
    for (pair, o) in results {
        cx.pairs.answer(pair, o, None, run);
    }
    let jobs = tracked_jobs(&mut cx, &stochastic);
    finish_jobs(&mut cx, jobs, Method::SelfCollision);
    cx.diag
        .record(Stage::SelfCollision, start.elapsed(), meshes.len() as u64);
}

/// The tracker jobs of `pairs` (`(pair, collider a, collider b)`; `a == b` for a
/// self-colliding mesh), run: the surfaces of the colliders involved brought up to date
/// first, at most `max_self_contacts` contacts each, the trackers' searches cut at the run's
/// deadline under a time budget.
fn tracked_jobs(cx: &mut TrackingContext, pairs: &[(u32, u32, u32)]) -> Vec<Job> {
    let (seed, max, run) = (cx.config.seed, cx.config.max_self_contacts, cx.diag.frame);
    let deadline = tracking_deadline(&cx.config, &cx.diag);
    let mut involved: Vec<u32> = pairs.iter().flat_map(|&(_, a, b)| [a, b]).collect();
    involved.sort_unstable();
    involved.dedup();
    let colliders = &*cx.colliders;
    let entries: Vec<&ColliderEntry> = involved.iter().map(|&i| colliders.entry(i)).collect();
    let state = &mut *cx.state;
    update_surfaces(state, &entries, &cx.pool);
    let mut jobs: Vec<Job> = pairs
        .iter()
        .map(|&ends| job(state, colliders, ends, seed))
        .collect();
    run_jobs(&mut jobs, colliders, state, &cx.pool, (max, run), deadline);
    jobs
}

/// Records finished jobs: answers in pair order, feature pairs, trackers kept.
fn finish_jobs(cx: &mut TrackingContext, jobs: Vec<Job>, method: Method) {
    let run = cx.diag.frame;
    let mut new = NewFeaturePairs::default();
    for job in jobs {
        cx.diag.counters.tracker_steps_cut += u64::from(job.tracker.stats().cut);
        let evaluations = job.tracker.stats().evaluations;
        let o = PairOutcome::exact(job.key, method, evaluations, 1.0, job.contacts, run);
        cx.pairs.answer(job.pair, o, None, run);
        record_pairs(&mut cx.features, &mut new, job.key, &job.pairs);
        cx.state.trackers.insert(job.key, job.tracker);
    }
    new.insert(&mut cx.commands);
}

/// When the trackers of this run stop searching: under a time budget, what the run's target
/// leaves after the Report stage (see [`CollisionDiagnostics::tracking_deadline`]).
fn tracking_deadline(config: &CollisionConfig, diag: &CollisionDiagnostics) -> Option<Instant> {
    match config.budget {
        FrameBudget::Time(budget) => Some(diag.tracking_deadline(budget, Instant::now())),
        _ => None,
    }
}

/// Tracked pairs: the stochastic tracker between the two meshes, in parallel per pair; its
/// contacts become the pair's contacts, at most `max_self_contacts` of them.
pub fn track_pairs(mut cx: TrackingContext) {
    let start = Instant::now();
    let pairs = tracked(&cx.pairs, false);
    let jobs = tracked_jobs(&mut cx, &pairs);
    finish_jobs(&mut cx, jobs, Method::Tracking);
    cx.diag
        .record(Stage::Tracking, start.elapsed(), pairs.len() as u64);
}

/// Run condition: something is being tracked (or was until now), so [`forget_untracked`]
/// has something to drop.
pub fn holds_tracking_state(state: Res<TrackingState>) -> bool {
    !(state.trackers.is_empty() && state.surfaces.is_empty() && state.shared.is_empty())
}

/// Drops trackers and surfaces of entities that are no longer tracked (despawned, or moved to
/// another fidelity), after the Tracking stage: memory stays bounded however long the app runs.
pub fn forget_untracked(pairs: Res<PairTable>, mut state: ResMut<TrackingState>) {
    let mut live: EntityHashSet = EntityHashSet::default();
    let mut keys: std::collections::HashSet<(Entity, Entity)> = Default::default();
    for &p in &pairs.tracked {
        let s = pairs.slot(p);
        live.insert(s.a);
        live.insert(s.b);
        keys.insert((s.a, s.b));
    }
    state.trackers.retain(|k, _| keys.contains(k));
    state.surfaces.retain(|e, _| live.contains(e));
    let used: std::collections::HashSet<usize> = state
        .surfaces
        .values()
        .map(|s| Arc::as_ptr(&s.surface) as usize)
        .collect();
    state
        .shared
        .retain(|_, s| used.contains(&(Arc::as_ptr(s) as usize)));
}

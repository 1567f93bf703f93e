//! Tracking stage: pairs with [`Fidelity::Tracking`] and self-collision of deformable meshes.
//!
//! A self-colliding deformable mesh with [`Fidelity::Tracking`] and every pair whose fidelity
//! is `Tracking` run the stochastic closest-feature [`Tracker`]: its pairs persist from run to
//! run (in [`TrackingState`], one tracker per pair or mesh, seeded from the configured seed
//! and the two entities, so results do not depend on thread scheduling), and its contacts come
//! with points, normals and depths. Other self-colliding meshes get the exact BVH pass
//! (`self_intersections`). Trackers and surfaces run in parallel; the outcomes are merged in
//! entity order. Each entity's [`FeaturePairs`] lists the triangle pairs in contact with each
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

use super::components::{Deformable, Fidelity, SelfCollision};
use super::contact::{ContactPoint, triangle_pair_contact};
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::narrow_phase::{Method, PairOutcome, PairOutcomes, spread, with_workspaces};
use super::plugin::{CollisionConfig, FrameBudget};
use super::pool::CollisionTaskPool;
use super::prepare::{ColliderEntry, ColliderFrame, Geometry};
use crate::bvh::{CollisionMesh, TrianglePair, self_intersections};
use crate::geometry::Pose;
use crate::tracking::{Contact, TrackedSurface, Tracker, TrackerConfig};

/// The feature pairs an entity is tracking against each partner (itself for self-collision),
/// as of the last run: kept across runs, dropped with the entity. Inserted by the Tracking
/// stage on the first (smaller) entity of each tracked pair.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct FeaturePairs {
    /// Per partner entity, the triangle pairs (this entity's, the partner's) in contact.
    pub partners: SmallVec<[(Entity, SmallVec<[TrianglePair; 4]>); 2]>,
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
/// fidelity, a seed from the configured seed and the two entities.
fn tracker_config(
    a: &TrackedSurface,
    b: &TrackedSurface,
    pairs_per_frame: u32,
    seed: u64,
    ea: Entity,
    eb: Entity,
) -> TrackerConfig {
    let mut config = TrackerConfig::for_surface(a);
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
    }
}

/// One tracker's work in a run.
struct Job {
    key: (Entity, Entity),
    a: u32,
    b: u32,
    tracker: Tracker,
    contacts: SmallVec<[ContactPoint; 1]>,
    pairs: SmallVec<[TrianglePair; 4]>,
}

/// The job of entries `a` and `b` (the same for a self-colliding mesh): the pair's tracker,
/// taken out of `state` or made with the pair's fidelity (pairs per frame) and seed. Their
/// surfaces must be up to date.
fn job(state: &mut TrackingState, frame: &ColliderFrame, a: u32, b: u32, seed: u64) -> Job {
    let (ea, eb) = (&frame.entries[a as usize], &frame.entries[b as usize]);
    let key = (ea.entity, eb.entity);
    let tracker = state.trackers.remove(&key).unwrap_or_else(|| {
        let n = match ea.fidelity.combine(eb.fidelity) {
            Fidelity::Tracking { pairs_per_frame } => pairs_per_frame,
            _ => 1,
        };
        let (sa, sb) = (
            &state.surfaces[&ea.entity].surface,
            &state.surfaces[&eb.entity].surface,
        );
        Tracker::new(tracker_config(sa, sb, n, seed, ea.entity, eb.entity))
    });
    Job {
        key,
        a,
        b,
        tracker,
        contacts: SmallVec::new(),
        pairs: SmallVec::new(),
    }
}

/// Runs `jobs` in parallel, each on its own tracker; past `deadline` the trackers cut their
/// work (see [`Tracker::step_self_until`]).
fn run_jobs(
    jobs: &mut [Job],
    frame: &ColliderFrame,
    state: &TrackingState,
    pool: &CollisionTaskPool,
    max_contacts: usize,
    deadline: Option<Instant>,
) {
    pool.for_each_mut(jobs, 1, |job| {
        let (ea, eb) = (
            &frame.entries[job.a as usize],
            &frame.entries[job.b as usize],
        );
        let sa = &state.surfaces[&ea.entity].surface;
        let self_mode = job.a == job.b;
        let found: &[Contact] = if self_mode {
            job.tracker.step_self_until(sa, deadline)
        } else {
            let sb = &state.surfaces[&eb.entity].surface;
            job.tracker
                .step_pair_until(sa, &ea.pose, sb, &eb.pose, deadline)
        };
        let step = found.len().div_ceil(max_contacts.max(1)).max(1);
        job.contacts = found
            .iter()
            .step_by(step)
            .map(|c| world_contact(c, &ea.pose, self_mode))
            .collect();
        job.pairs = found
            .iter()
            .take(16)
            .map(|c| TrianglePair {
                a: c.triangle_a,
                b: c.triangle_b,
            })
            .collect();
    });
}

/// Records `pairs` as `a`'s feature pairs with `b` (inserting the component if needed).
fn record_pairs(
    features: &mut Query<&mut FeaturePairs>,
    commands: &mut Commands,
    a: Entity,
    b: Entity,
    pairs: SmallVec<[TrianglePair; 4]>,
) {
    match features.get_mut(a) {
        Ok(mut f) => {
            let f = &mut *f;
            f.partners.retain(|(e, _)| *e != b);
            if !pairs.is_empty() {
                f.partners.push((b, pairs));
            }
        }
        Err(_) if !pairs.is_empty() => {
            let mut f = FeaturePairs::default();
            f.partners.push((b, pairs));
            commands.entity(a).try_insert(f);
        }
        Err(_) => {}
    }
}

/// Drops the feature pairs of partners that are no longer tracked (apart, despawned, or
/// changed fidelity), so each entity's lists hold only live pairs; a self-colliding mesh
/// keeps its own.
pub fn prune_feature_pairs(
    frame: Res<ColliderFrame>,
    outcomes: Res<PairOutcomes>,
    mut q: Query<(Entity, &mut FeaturePairs)>,
) {
    let mut live: Vec<(Entity, Entity)> = outcomes
        .tracked
        .iter()
        .map(|p| {
            (
                frame.entries[p.a as usize].entity,
                frame.entries[p.b as usize].entity,
            )
        })
        .chain(
            frame
                .entries
                .iter()
                .filter(|e| e.self_collision)
                .map(|e| (e.entity, e.entity)),
        )
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

/// Run condition: some deformable mesh has the [`SelfCollision`] marker.
pub fn needs_self_pass(q: Query<(), (With<SelfCollision>, With<Deformable>)>) -> bool {
    !q.is_empty()
}

/// Run condition: the narrow phase handed over some tracked pair.
pub fn needs_tracking(outcomes: Res<PairOutcomes>) -> bool {
    !outcomes.tracked.is_empty()
}

/// Self-collision of every [`SelfCollision`] deformable mesh, in parallel per mesh: the
/// stochastic tracker for meshes with [`Fidelity::Tracking`], the exact pass for the others.
#[allow(clippy::too_many_arguments)]
pub fn self_collision(
    frame: Res<ColliderFrame>,
    config: Res<CollisionConfig>,
    pool: Res<CollisionTaskPool>,
    mut state: ResMut<TrackingState>,
    mut outcomes: ResMut<PairOutcomes>,
    mut features: Query<&mut FeaturePairs>,
    mut commands: Commands,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let meshes: Vec<u32> = (0..frame.entries.len() as u32)
        .filter(|&i| frame.entries[i as usize].self_collision)
        .collect();
    let (tracked, exact): (Vec<u32>, Vec<u32>) = meshes.iter().partition(|&&i| {
        matches!(
            frame.entries[i as usize].fidelity,
            Fidelity::Tracking { .. }
        )
    });
    let max = config.max_self_contacts;
    let results = pool.map_chunks(&exact, 1, |chunk| {
        let e = &frame.entries[chunk[0] as usize];
        let mesh = e.geometry.mesh();
        with_workspaces(|ws, _, pairs| {
            pairs.clear();
            self_intersections(mesh, ws, pairs);
            let contacts: SmallVec<_> = spread(pairs, max)
                .map(|t| triangle_pair_contact(mesh, &e.pose, mesh, &e.pose, t))
                .collect();
            let ends = (e.entity, e.entity);
            PairOutcome::exact(
                ends,
                Method::SelfCollision,
                ws.node_pairs_visited(),
                1.0,
                contacts,
            )
        })
    });
    diag.counters.node_pairs += results.iter().map(|o| o.node_pairs).sum::<u64>();
    outcomes.outcomes.extend(results);

    // Stochastic self-collision.
    let pairs: Vec<(u32, u32)> = tracked.iter().map(|&i| (i, i)).collect();
    let jobs = tracked_jobs(&mut state, &frame, &pool, &config, &diag, &pairs);
    finish_jobs(
        jobs,
        &mut state,
        &mut outcomes,
        &mut features,
        &mut commands,
        &mut diag,
        Method::SelfCollision,
    );
    diag.record(Stage::SelfCollision, start.elapsed(), meshes.len() as u64);
}

/// The tracker jobs of `pairs` (entry indices; `(i, i)` for a self-colliding mesh), run: the
/// surfaces of the entries involved brought up to date first, at most `max_self_contacts`
/// contacts each, the trackers' searches cut at the run's deadline under a time budget.
fn tracked_jobs(
    state: &mut TrackingState,
    frame: &ColliderFrame,
    pool: &CollisionTaskPool,
    config: &CollisionConfig,
    diag: &CollisionDiagnostics,
    pairs: &[(u32, u32)],
) -> Vec<Job> {
    let (seed, max) = (config.seed, config.max_self_contacts);
    let deadline = tracking_deadline(config, diag);
    let mut involved: Vec<u32> = pairs.iter().flat_map(|&(a, b)| [a, b]).collect();
    involved.sort_unstable();
    involved.dedup();
    let entries: Vec<&ColliderEntry> = involved
        .iter()
        .map(|&i| &frame.entries[i as usize])
        .collect();
    update_surfaces(state, &entries, pool);
    let mut jobs: Vec<Job> = pairs
        .iter()
        .map(|&(a, b)| job(state, frame, a, b, seed))
        .collect();
    run_jobs(&mut jobs, frame, state, pool, max, deadline);
    jobs
}

/// Merges finished jobs: outcomes in entity order, feature pairs recorded, trackers kept.
fn finish_jobs(
    jobs: Vec<Job>,
    state: &mut TrackingState,
    outcomes: &mut PairOutcomes,
    features: &mut Query<&mut FeaturePairs>,
    commands: &mut Commands,
    diag: &mut CollisionDiagnostics,
    method: Method,
) {
    for job in jobs {
        diag.counters.tracker_steps_cut += u64::from(job.tracker.stats().cut);
        let (a, b) = job.key;
        outcomes.outcomes.push(PairOutcome::exact(
            (a, b),
            method,
            job.tracker.stats().evaluations,
            1.0,
            job.contacts,
        ));
        record_pairs(features, commands, a, b, job.pairs);
        state.trackers.insert(job.key, job.tracker);
    }
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
#[allow(clippy::too_many_arguments)]
pub fn track_pairs(
    frame: Res<ColliderFrame>,
    config: Res<CollisionConfig>,
    pool: Res<CollisionTaskPool>,
    mut state: ResMut<TrackingState>,
    mut outcomes: ResMut<PairOutcomes>,
    mut features: Query<&mut FeaturePairs>,
    mut commands: Commands,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let pairs: Vec<(u32, u32)> = outcomes.tracked.iter().map(|p| (p.a, p.b)).collect();
    let jobs = tracked_jobs(&mut state, &frame, &pool, &config, &diag, &pairs);
    finish_jobs(
        jobs,
        &mut state,
        &mut outcomes,
        &mut features,
        &mut commands,
        &mut diag,
        Method::Tracking,
    );
    diag.record(Stage::Tracking, start.elapsed(), pairs.len() as u64);
}

/// Run condition: something is being tracked (or was until now), so [`forget_untracked`]
/// has something to drop.
pub fn holds_tracking_state(state: Res<TrackingState>) -> bool {
    !(state.trackers.is_empty() && state.surfaces.is_empty() && state.shared.is_empty())
}

/// Drops trackers and surfaces of entities that are no longer tracked (despawned, or moved to
/// another fidelity), after the Tracking stage: memory stays bounded however long the app runs.
pub fn forget_untracked(
    frame: Res<ColliderFrame>,
    outcomes: Res<PairOutcomes>,
    mut state: ResMut<TrackingState>,
) {
    let mut live: EntityHashSet = EntityHashSet::default();
    let mut pairs: std::collections::HashSet<(Entity, Entity)> = Default::default();
    for o in &outcomes.outcomes {
        if matches!(o.method, Method::Tracking | Method::SelfCollision) {
            live.insert(o.a);
            live.insert(o.b);
            pairs.insert((o.a, o.b));
        }
    }
    state.trackers.retain(|k, _| pairs.contains(k));
    state
        .surfaces
        .retain(|e, _| live.contains(e) && frame.get(*e).is_some());
    let used: std::collections::HashSet<usize> = state
        .surfaces
        .values()
        .map(|s| Arc::as_ptr(&s.surface) as usize)
        .collect();
    state
        .shared
        .retain(|_, s| used.contains(&(Arc::as_ptr(s) as usize)));
}

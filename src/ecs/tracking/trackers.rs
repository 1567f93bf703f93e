//! The trackers and tracked surfaces kept between runs, and one run of tracker jobs in
//! parallel.
use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy_ecs::entity::EntityHashMap;
use bevy_ecs::prelude::*;
use smallvec::SmallVec;

use super::super::components::Fidelity;
use super::super::contact::ContactPoint;
use super::super::parallel::CollisionTaskPool;
use super::super::prepare::{ColliderEntry, ColliderTable, Geometry};
use crate::bvh::{CollisionMesh, TrianglePair};
use crate::geometry::Pose;
use crate::tracking::{Contact, TrackedSurface, Tracker, TrackerConfig};

/// A mesh prepared for tracking, and the geometry it was prepared from.
pub(super) struct Surface {
    /// Identity of a rigid source tree (its `Arc`'s address; 0 for a deformable mesh, which
    /// is recognised by its triangles): a swapped collider rebuilds.
    pub(super) source: usize,
    pub(super) surface: Arc<TrackedSurface>,
}

/// The stochastic trackers between runs: one [`TrackedSurface`] per tracked entity (rigid
/// meshes share one per collider mesh) and one [`Tracker`] per tracked pair or self-colliding
/// mesh. Entries of entities that left the tracking stage are dropped every run, so memory
/// stays bounded.
#[derive(Resource, Default)]
pub struct TrackingState {
    pub(super) surfaces: EntityHashMap<Surface>,
    pub(super) shared: HashMap<usize, Arc<TrackedSurface>>,
    pub(super) trackers: HashMap<(Entity, Entity), Tracker>,
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
pub(super) fn update_surfaces(
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
pub(super) struct Job {
    pub(super) key: (Entity, Entity),
    /// The pair's slot in the pair table, and its colliders' slots.
    pub(super) pair: u32,
    pub(super) a: u32,
    pub(super) b: u32,
    pub(super) tracker: Tracker,
    pub(super) contacts: SmallVec<[ContactPoint; 1]>,
    pub(super) pairs: Vec<TrianglePair>,
}

/// The job of pair slot `pair` between colliders `a` and `b` (the same for a self-colliding
/// mesh): the pair's tracker, taken out of `state` or made with the pair's fidelity (pairs
/// per frame) and seed, with `time_budget` as its own (`None`: the fixed pairs per frame).
/// Their surfaces must be up to date.
pub(super) fn job(
    state: &mut TrackingState,
    colliders: &ColliderTable,
    (pair, a, b): (u32, u32, u32),
    seed: u64,
    time_budget: Option<Duration>,
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
    if tracker.config().continuous != continuous || tracker.config().time_budget != time_budget {
        let config = TrackerConfig {
            continuous,
            time_budget,
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
pub(super) fn run_jobs(
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

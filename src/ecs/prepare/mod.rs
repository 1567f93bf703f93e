//! Prepare stage: poses, refit of deformed meshes, validation, world boxes, kept in the
//! [`ColliderTable`] from run to run and updated only where the ECS says something changed.
mod colliders;
mod deformed;
mod scaled;
#[cfg(feature = "transform")]
mod transforms;
mod world_box;

use std::sync::{Arc, LazyLock};

use bevy_ecs::entity::EntityHashSet;
use bevy_ecs::prelude::*;
use bevy_ecs::query::QueryItem;
use bevy_ecs::system::SystemParam;
use glam::Vec3;

pub(crate) use colliders::BodyPlan;
pub use colliders::{ColliderEntry, ColliderTable, Geometry};
use scaled::ScaledTrees;
#[cfg(feature = "transform")]
pub use transforms::sync_transforms;
#[cfg(feature = "transform")]
pub(crate) use transforms::{Parents, Placement, place, shift};

/// Without bevy_transform, bodies move through their pose alone.
#[cfg(not(feature = "transform"))]
pub(crate) type Placement = ();
#[cfg(not(feature = "transform"))]
pub(crate) type Parents<'w, 's> = ();

/// Moves a body by `delta` (world space).
#[cfg(not(feature = "transform"))]
pub(crate) fn shift(pose: &mut ColliderPose, _: &mut (), _: &Parents, delta: Vec3) {
    pose.0.translation += delta;
}

/// Puts a body at `world` (world space).
#[cfg(not(feature = "transform"))]
pub(crate) fn place(pose: &mut ColliderPose, _: &mut (), _: &Parents, world: Pose) {
    pose.0 = world;
}
use deformed::DeformedStates;
use world_box::tight_world_aabb;
pub(crate) use world_box::world_aabb;

use super::budget::BudgetController;
use super::components::{
    ColliderPose, ColliderScale, ContinuousCollision, Deformable, Fidelity, MeshCollider,
    SelfCollision,
};
use super::config::CollisionConfig;
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::events::{CollisionError, CollisionErrorKind};
use super::layers::ContactLayers;
use super::parallel::CollisionTaskPool;
use crate::bvh::CollisionMesh;
use crate::geometry::{Aabb, Pose};
use crate::mesh::{MeshError, TriMesh};

/// What Prepare remembers between runs: the entities reported invalid (reported once), the
/// scaled trees in use.
#[derive(Resource, Debug, Default)]
pub struct PrepareState {
    invalid: EntityHashSet,
    scaled: ScaledTrees,
}

/// Entities that lost one of the components a collider is made of (or were despawned) since
/// the last run, noted by an observer the moment it happens: unlike `RemovedComponents`,
/// which forgets after two frames, nothing is lost when the plugin's schedule does not run
/// in a frame (`FixedPostUpdate` without a fixed step).
#[derive(Resource, Debug, Default)]
pub struct RemovedColliders {
    entities: Vec<Entity>,
}

/// The components whose removal changes or removes a collider.
type ColliderParts = (
    MeshCollider,
    ColliderScale,
    Deformable,
    Fidelity,
    ContactLayers,
    SelfCollision,
    ColliderPose,
);

/// Observer: notes an entity that lost a part of its collider (see [`RemovedColliders`]).
pub fn note_removed(removed: On<Remove<ColliderParts>>, mut list: ResMut<RemovedColliders>) {
    list.entities.push(removed.entity);
}

/// Whether a deformable mesh needs a refit: new positions, or a new (valid) scale.
fn needs_refit(d: &Deformable, scale: Option<&ColliderScale>) -> bool {
    let scale = deformable_scale(scale);
    d.stale || scale.is_some_and(|s| s != d.scale_applied)
}

/// The scale a deformable mesh is refitted at (`None`: invalid, reported by the update).
fn deformable_scale(scale: Option<&ColliderScale>) -> Option<Vec3> {
    let scale = scale.copied().unwrap_or_default();
    (scale.is_valid() && scale.0.min_element() > 0.0).then_some(scale.0)
}

/// Run condition: some deformable mesh has new positions (or a new scale).
pub fn any_stale(q: Query<(&Deformable, Option<&ColliderScale>)>) -> bool {
    q.iter().any(|(d, scale)| needs_refit(d, scale))
}

/// A mesh the table holds for a deformable collider while its own is refitted in place.
static REFITTING: LazyLock<Arc<CollisionMesh>> = LazyLock::new(|| {
    let triangle = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]])
        .expect("a valid triangle");
    Arc::new(CollisionMesh::new(triangle))
});

/// Refits the BVHs of deformable meshes whose positions changed, in parallel.
pub fn refit_deformables(
    mut q: Query<(Entity, &mut Deformable, Option<&ColliderScale>)>,
    mut table: ResMut<ColliderTable>,
    pool: Res<CollisionTaskPool>,
    mut budget: ResMut<BudgetController>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    // The first system of a run when it runs (a deformable mesh has new positions).
    let run = budget.begin_run(true);
    diag.begin_run(run);
    let start = budget.now();
    let mut stale: Vec<(Entity, Mut<Deformable>, Vec3, Option<MeshError>)> = q
        .iter_mut()
        .filter(|(_, d, scale)| needs_refit(d, *scale))
        .map(|(e, d, scale)| {
            let scale = deformable_scale(scale).unwrap_or(d.scale_applied);
            (e, d, scale, None)
        })
        .collect();
    // The table's share of each mesh is let go first, so the refit happens in place (the
    // update after this puts the refitted mesh back).
    for (entity, _, _, _) in &stale {
        if let Some(i) = table.slot_of(*entity) {
            table.entry_mut(i).geometry = Geometry::Deformable(REFITTING.clone());
        }
    }
    let chunk = pool.chunk_size(stale.len(), 1);
    pool.for_each_mut(&mut stale, chunk, |(_, d, scale, err)| {
        let d = &mut **d;
        d.stale = false;
        d.scale_applied = *scale;
        let positions = if *scale == Vec3::ONE {
            &d.positions
        } else {
            d.scaled.clear();
            d.scaled.extend(d.positions.iter().map(|&p| p * *scale));
            &d.scaled
        };
        *err = Arc::make_mut(&mut d.mesh).set_positions(positions).err();
    });
    for (_, d, _, err) in &mut stale {
        d.broken = err.take();
    }
    let time = budget.stage_done(Stage::Refit, start);
    diag.record(Stage::Refit, time, stale.len() as u64);
}

/// What a collider's components say.
type ColliderData<'a> = (
    Entity,
    &'a ColliderPose,
    Option<&'a ColliderScale>,
    Option<&'a MeshCollider>,
    Option<&'a Deformable>,
    Option<&'a Fidelity>,
    Option<&'a ContactLayers>,
    Has<SelfCollision>,
    Option<&'a ContinuousCollision>,
);

/// One entity's [`ColliderData`].
type ColliderItem<'a> = QueryItem<'a, 'a, ColliderData<'static>>;

type IsCollider = Or<(With<MeshCollider>, With<Deformable>)>;

type AnyChange = Or<(
    Changed<ColliderPose>,
    Changed<ColliderScale>,
    Changed<MeshCollider>,
    Changed<Deformable>,
    Changed<Fidelity>,
    Changed<ContactLayers>,
    Changed<SelfCollision>,
    Changed<ContinuousCollision>,
)>;

/// The colliders whose components changed since the last run, or were removed.
#[derive(SystemParam)]
pub struct ColliderChanges<'w, 's> {
    all: Query<'w, 's, ColliderData<'static>, IsCollider>,
    changed: Query<'w, 's, ColliderData<'static>, (IsCollider, AnyChange)>,
    removed: ResMut<'w, RemovedColliders>,
}

/// Brings the [`ColliderTable`] up to date: validates and adds new colliders, updates those
/// whose components changed, removes those gone (or invalid: reported once with a
/// [`CollisionError`] and skipped until fixed). Everything after a change of configuration.
pub fn update_colliders(
    mut changes: ColliderChanges,
    config: Res<CollisionConfig>,
    mut table: ResMut<ColliderTable>,
    mut state: ResMut<PrepareState>,
    mut errors: MessageWriter<CollisionError>,
    mut budget: ResMut<BudgetController>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let run = budget.begin_run(false);
    diag.begin_run(run);
    let start = budget.now();
    table.begin_run(run);
    let full = config.is_changed();
    let state = &mut *state;
    let mut update = Update {
        table: &mut table,
        invalid: &mut state.invalid,
        scaled: &mut state.scaled,
        errors: &mut errors,
        config: &config,
        run,
        full,
    };
    let mut again = std::mem::take(&mut changes.removed.entities);
    if full {
        for data in &changes.all {
            update.entry(data);
        }
    } else {
        for data in &changes.changed {
            update.entry(data);
        }
    }
    again.sort_unstable();
    again.dedup();
    for &entity in &again {
        match changes.all.get(entity) {
            // Updated above already (twice would read as a move of zero).
            Ok(_) if full || changes.changed.contains(entity) => {}
            Ok(data) => update.entry(data),
            Err(_) => {
                update.invalid.remove(&entity);
                update.table.remove(entity);
            }
        }
    }
    // The buffer is kept for the next run's removals.
    again.clear();
    changes.removed.entities = again;
    let items = table.changed().len() as u64;
    let time = budget.stage_done(Stage::Prepare, start);
    diag.record(Stage::Prepare, time, items);
}

/// One run's updates of the table.
struct Update<'a, 'w> {
    table: &'a mut ColliderTable,
    invalid: &'a mut EntityHashSet,
    scaled: &'a mut ScaledTrees,
    errors: &'a mut MessageWriter<'w, CollisionError>,
    config: &'a CollisionConfig,
    run: u64,
    /// Everything is updated (the configuration changed: margins, default fidelity).
    full: bool,
}

impl Update<'_, '_> {
    /// Updates the collider of one entity from its components.
    fn entry(&mut self, data: ColliderItem) {
        let (entity, pose, scale, collider, deformable, fidelity, layers, self_marker, continuous) =
            data;
        let continuous = continuous.copied();
        let scale = scale.copied().unwrap_or_default();
        let scale_problem = || CollisionErrorKind::InvalidScale {
            scale: scale.0.to_array(),
        };
        let (geometry, default_fidelity, problem) = match (deformable, collider) {
            (Some(d), _) => (
                Geometry::Deformable(d.mesh.clone()),
                Fidelity::Exact,
                if deformable_scale(Some(&scale)).is_none() {
                    Some(scale_problem())
                } else {
                    d.broken.clone().map(CollisionErrorKind::Mesh)
                },
            ),
            (None, Some(c)) if !scale.is_valid() => (
                Geometry::Rigid(c.tree().clone()),
                self.config.default_fidelity,
                Some(scale_problem()),
            ),
            (None, Some(c)) => match self.scaled.tree(c.tree(), scale.0) {
                Ok(tree) => (Geometry::Rigid(tree), self.config.default_fidelity, None),
                Err(e) => (
                    Geometry::Rigid(c.tree().clone()),
                    self.config.default_fidelity,
                    Some(CollisionErrorKind::Mesh(e)),
                ),
            },
            (None, None) => {
                self.table.remove(entity);
                return;
            }
        };
        if let Some(kind) = problem.or_else(|| check_pose(&pose.0).err()) {
            if self.invalid.insert(entity) {
                self.errors.write(CollisionError { entity, kind });
            }
            self.table.remove(entity);
            return;
        }
        self.invalid.remove(&entity);
        let pose = normalized(&pose.0);
        let fidelity = fidelity.copied().unwrap_or(default_fidelity);
        let layers = layers.copied().unwrap_or_default();
        let self_collision = self_marker && deformable.is_some();
        let margin = self.config.aabb_margin;
        let run = self.run;
        let Some(i) = self.table.slot_of(entity) else {
            let aabb = tight_world_aabb(geometry.mesh().bvh(), &pose).inflated(margin);
            // A continuous deformable's first state: where its first motion starts.
            let deformed = match (&geometry, continuous) {
                (Geometry::Deformable(m), Some(_)) => Some(DeformedStates::updated(None, m, &pose)),
                _ => None,
            };
            let i = self.table.insert(ColliderEntry {
                entity,
                geometry_id: geometry.id(),
                geometry,
                pose,
                aabb,
                fidelity,
                layers,
                self_collision,
                motion: Vec3::ZERO,
                previous_pose: pose,
                end_pose: pose,
                continuous,
                swept_run: 0,
                deformed,
                still_since: run,
                geometry_since: run,
                pairs: Default::default(),
                changed_run: 0,
                filter_run: run,
            });
            self.table.mark_changed(i, run, false);
            return;
        };
        let e = self.table.entry_mut(i);
        // (The table holds a placeholder while a deformable mesh is refitted in place: the
        // identity kept says whether it is the same mesh.)
        let same_geometry = e.geometry_id == geometry.id();
        // A deformable mesh updated here was refitted (or its marker changed): it moved.
        let moved = e.pose != pose || !same_geometry || !e.is_rigid();
        let filters = e.layers != layers || e.self_collision != self_collision;
        if !(moved || filters || e.fidelity != fidelity || e.continuous != continuous || self.full)
        {
            // Written with the same values.
            return;
        }
        if moved {
            e.motion = if same_geometry {
                pose.translation - e.pose.translation
            } else {
                Vec3::ZERO
            };
            e.still_since = run;
            if !same_geometry {
                e.geometry_since = run;
                e.geometry_id = geometry.id();
            }
            e.previous_pose = if same_geometry { e.end_pose } else { pose };
            e.pose = pose;
            e.end_pose = pose;
            e.geometry = geometry;
        }
        e.continuous = continuous;
        // A continuous deformable keeps its state in world coordinates: the start of its
        // next motion.
        match (&e.geometry, continuous) {
            (Geometry::Deformable(m), Some(_)) if moved => {
                e.deformed = Some(DeformedStates::updated(e.deformed.take(), m, &e.pose));
            }
            (Geometry::Deformable(_), Some(_)) => {}
            _ => e.deformed = None,
        }
        if moved || self.full {
            let end = tight_world_aabb(e.geometry.mesh().bvh(), &e.pose);
            let fraction = self.config.continuous_motion;
            let swept = moved
                .then(|| match (&e.deformed, continuous) {
                    (Some(d), Some(c)) => d.swept_box(c, fraction),
                    _ => swept_box(e, &end, fraction),
                })
                .flatten();
            e.aabb = match swept {
                Some(swept) => {
                    e.swept_run = run;
                    swept
                }
                None => end,
            }
            .inflated(margin);
        }
        if filters {
            e.filter_run = run;
        }
        e.fidelity = fidelity;
        e.layers = layers;
        e.self_collision = self_collision;
        self.table.mark_changed(i, run, moved);
    }
}

/// Colliders that may be swept whose pose changed.
type SweptAndMoved = (With<ContinuousCollision>, Changed<ColliderPose>);

/// After the responses: the poses in which swept-capable colliders end the run (a response
/// may have moved them since Prepare), where their next motion starts.
pub fn note_end_poses(
    moved: Query<(Entity, &ColliderPose), SweptAndMoved>,
    mut table: ResMut<ColliderTable>,
) {
    for (entity, pose) in &moved {
        if let Some(i) = table.slot_of(entity) {
            let e = table.entry_mut(i);
            if e.pose != pose.0 {
                e.end_pose = normalized(&pose.0);
            }
        }
    }
}

/// The world box covering a collider's motion from its previous pose to its pose (`end`: its
/// box there), if it is swept in this run: it has [`ContinuousCollision`], is rigid, moved,
/// and (for [`ContinuousCollision::WhenFast`]) moved farther than `fraction` of `end`'s
/// smallest extent. The union of the boxes at both ends, grown by how far a vertex's arc
/// strays from its chord when the collider also turns.
fn swept_box(e: &ColliderEntry, end: &Aabb, fraction: f32) -> Option<Aabb> {
    let continuous = e.continuous?;
    if !e.is_rigid() || e.previous_pose == e.pose {
        return None;
    }
    let bvh = e.geometry.mesh().bvh();
    let start = tight_world_aabb(bvh, &e.previous_pose);
    let travel = (e.pose.translation - e.previous_pose.translation).length();
    let angle = e.previous_pose.rotation.angle_between(e.pose.rotation);
    let root = bvh.root_aabb();
    let radius = root.min.abs().max(root.max.abs()).length();
    // The farthest any point moves: its translation plus its turn (chord 2r·sin(θ/2)).
    let reach = travel + 2.0 * radius * (0.5 * angle.min(std::f32::consts::PI)).sin();
    let fast = match continuous {
        ContinuousCollision::Always => true,
        ContinuousCollision::WhenFast => reach > fraction * end.extents().min_element(),
    };
    if !fast {
        return None;
    }
    let bulge = radius * (1.0 - (0.5 * angle.min(std::f32::consts::PI)).cos());
    Some(start.union(end).inflated(bulge))
}

fn check_pose(pose: &Pose) -> Result<(), CollisionErrorKind> {
    let finite = pose.translation.is_finite() && pose.rotation.is_finite();
    let len = pose.rotation.length();
    if !finite || !(0.5..=2.0).contains(&len) {
        return Err(CollisionErrorKind::InvalidPose {
            translation: pose.translation.to_array(),
            rotation: pose.rotation.to_array(),
        });
    }
    Ok(())
}

fn normalized(pose: &Pose) -> Pose {
    Pose::new(pose.translation, pose.rotation.normalize())
}

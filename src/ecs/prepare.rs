//! Prepare stage: poses, refit of deformed meshes, validation, world boxes.
use std::sync::Arc;
use std::time::Instant;

use bevy_ecs::entity::{EntityHashMap, EntityHashSet};
use bevy_ecs::prelude::*;
use glam::{Mat3, Vec3};

use super::components::{
    Collider, ColliderPose, CollisionLayers, Deformable, Fidelity, SelfCollision,
};
use super::diagnostics::{CollisionDiagnostics, Stage, begin_frame};
use super::events::{CollisionError, CollisionErrorKind};
use super::plugin::CollisionConfig;
use super::pool::CollisionTaskPool;
use crate::adb::AdbTree;
use crate::bvh::CollisionMesh;
use crate::geometry::{Aabb, Pose};
use crate::mesh::MeshError;

/// The geometry of one entity in this run: a shared rigid tree or a deformable mesh.
#[derive(Debug, Clone)]
pub enum Geometry {
    /// A rigid collider's shared ADB-tree (and BVH).
    Rigid(Arc<AdbTree>),
    /// A deformable mesh as refitted in this run.
    Deformable(Arc<CollisionMesh>),
}

impl Geometry {
    /// The mesh and its BVH.
    #[inline]
    pub fn mesh(&self) -> &CollisionMesh {
        match self {
            Geometry::Rigid(t) => t.collision_mesh(),
            Geometry::Deformable(m) => m,
        }
    }

    /// The ADB-tree (rigid colliders only).
    #[inline]
    pub fn adb(&self) -> Option<&AdbTree> {
        match self {
            Geometry::Rigid(t) => Some(t),
            Geometry::Deformable(_) => None,
        }
    }
}

/// One valid collider as the pipeline sees it in this run.
#[derive(Debug, Clone)]
pub struct ColliderEntry {
    /// The entity.
    pub entity: Entity,
    /// Its geometry.
    pub geometry: Geometry,
    /// Its pose.
    pub pose: Pose,
    /// Its world box (inflated by the configured margin).
    pub aabb: Aabb,
    /// Its fidelity.
    pub fidelity: Fidelity,
    /// Its layers.
    pub layers: CollisionLayers,
    /// Whether it has the [`SelfCollision`] marker and is deformable.
    pub self_collision: bool,
    /// Translation since the last run (an estimate of speed × time step).
    pub motion: Vec3,
    /// The run ([`CollisionDiagnostics::frame`]) since which the entity's pose and geometry
    /// are unchanged: an answer computed in that run or later still holds for a rigid pair.
    pub still_since: u64,
}

/// The colliders of the current run, sorted by entity (read-only for users: what the stages
/// saw, valid until the next run starts).
#[derive(Resource, Debug, Default)]
pub struct ColliderFrame {
    pub(crate) entries: Vec<ColliderEntry>,
    pub(crate) index: EntityHashMap<u32>,
}

impl ColliderFrame {
    /// The valid colliders of the last run, sorted by entity.
    pub fn entries(&self) -> &[ColliderEntry] {
        &self.entries
    }

    /// The entry of `entity`, if it was a valid collider in the last run.
    pub fn get(&self, entity: Entity) -> Option<&ColliderEntry> {
        self.index.get(&entity).map(|&i| &self.entries[i as usize])
    }
}

/// What Prepare remembers between runs.
#[derive(Resource, Debug, Default)]
pub struct PrepareState {
    invalid: EntityHashSet,
    last_seen: EntityHashMap<LastSeen>,
}

/// An entity's pose and geometry in the last run it was valid, since when they hold, and its
/// world box (before the margin).
#[derive(Debug, Clone, Copy)]
struct LastSeen {
    pose: Pose,
    geometry: usize,
    since: u64,
    aabb: Aabb,
}

/// Run condition: some deformable mesh has new positions.
pub fn any_stale(q: Query<&Deformable>) -> bool {
    q.iter().any(|d| d.stale)
}

/// Copies `GlobalTransform` into [`ColliderPose`] (rotation and translation).
#[cfg(feature = "transform")]
pub fn sync_global_transforms(
    mut q: Query<
        (
            &bevy_transform::components::GlobalTransform,
            &mut ColliderPose,
        ),
        Changed<bevy_transform::components::GlobalTransform>,
    >,
) {
    for (gt, mut pose) in &mut q {
        let (_, rotation, translation) = gt.to_scale_rotation_translation();
        pose.0 = Pose::new(translation, rotation);
    }
}

/// Refits the BVHs of deformable meshes whose positions changed, in parallel.
pub fn refit_deformables(
    mut q: Query<(Entity, &mut Deformable)>,
    mut frame: ResMut<ColliderFrame>,
    pool: Res<CollisionTaskPool>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    // The first system of a run when it runs (a deformable mesh has new positions).
    begin_frame(&mut diag);
    diag.begun_by_refit = true;
    let start = Instant::now();
    // Last run's entries hold clones of the meshes' `Arc`s: drop them so refits happen in place.
    frame.entries.clear();
    frame.index.clear();
    let mut stale: Vec<(Entity, Mut<Deformable>, Option<MeshError>)> = q
        .iter_mut()
        .filter(|(_, d)| d.stale)
        .map(|(e, d)| (e, d, None))
        .collect();
    let chunk = pool.chunk_size(stale.len(), 1);
    pool.for_each_mut(&mut stale, chunk, |(_, d, err)| {
        let d = &mut **d;
        d.stale = false;
        *err = Arc::make_mut(&mut d.mesh).set_positions(&d.positions).err();
    });
    for (_, d, err) in &mut stale {
        d.broken = err.take();
    }
    diag.record(Stage::Refit, start.elapsed(), stale.len() as u64);
}

/// Validates every collider and builds the run's [`ColliderFrame`] (sorted by entity).
#[allow(clippy::type_complexity)]
pub fn gather_colliders(
    q: Query<
        (
            Entity,
            &ColliderPose,
            Option<&Collider>,
            Option<&Deformable>,
            Option<&Fidelity>,
            Option<&CollisionLayers>,
            Has<SelfCollision>,
        ),
        Or<(With<Collider>, With<Deformable>)>,
    >,
    config: Res<CollisionConfig>,
    mut frame: ResMut<ColliderFrame>,
    mut state: ResMut<PrepareState>,
    mut errors: MessageWriter<CollisionError>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    if !std::mem::take(&mut diag.begun_by_refit) {
        begin_frame(&mut diag);
    }
    let start = Instant::now();
    let frame = &mut *frame;
    let state = &mut *state;
    frame.entries.clear();
    frame.index.clear();
    let mut now_invalid = EntityHashSet::default();
    for (entity, pose, collider, deformable, fidelity, layers, self_marker) in &q {
        let (geometry, default_fidelity, problem) = match (deformable, collider) {
            (Some(d), _) => (
                Geometry::Deformable(d.mesh.clone()),
                Fidelity::Exact,
                d.broken.clone().map(CollisionErrorKind::Mesh),
            ),
            (None, Some(c)) => (
                Geometry::Rigid(c.tree().clone()),
                config.default_fidelity,
                None,
            ),
            (None, None) => continue,
        };
        let problem = problem.or_else(|| check_pose(&pose.0).err());
        if let Some(kind) = problem {
            if !state.invalid.contains(&entity) {
                errors.write(CollisionError { entity, kind });
            }
            now_invalid.insert(entity);
            continue;
        }
        let pose = normalized(&pose.0);
        // The geometry's identity: a swapped collider is a change (a deformable mesh is
        // refitted in place, but deformable pairs are never answered from memory).
        let (geometry_id, rigid) = match &geometry {
            Geometry::Rigid(t) => (Arc::as_ptr(t) as usize, true),
            Geometry::Deformable(m) => (Arc::as_ptr(m) as usize, false),
        };
        let last = state.last_seen.get_mut(&entity);
        let unchanged = last
            .as_ref()
            .is_some_and(|l| l.pose == pose && l.geometry == geometry_id);
        // A rigid body that did not move keeps its box (sleeping bodies cost nothing here).
        let tight = match &last {
            Some(l) if unchanged && rigid => l.aabb,
            _ => tight_world_aabb(geometry.mesh().bvh(), &pose),
        };
        let seen = LastSeen {
            pose,
            geometry: geometry_id,
            since: diag.frame,
            aabb: tight,
        };
        let (motion, since) = match last {
            Some(l) if unchanged => (Vec3::ZERO, l.since),
            Some(l) => {
                let motion = pose.translation - l.pose.translation;
                *l = seen;
                (motion, diag.frame)
            }
            None => {
                state.last_seen.insert(entity, seen);
                (Vec3::ZERO, diag.frame)
            }
        };
        let aabb = tight.inflated(config.aabb_margin);
        frame.entries.push(ColliderEntry {
            entity,
            self_collision: self_marker && deformable.is_some(),
            geometry,
            pose,
            aabb,
            fidelity: fidelity.copied().unwrap_or(default_fidelity),
            layers: layers.copied().unwrap_or_default(),
            motion,
            still_since: since,
        });
    }
    state.invalid = now_invalid;
    if state.last_seen.len() > 2 * frame.entries.len() + 64 {
        let alive: EntityHashSet = frame.entries.iter().map(|e| e.entity).collect();
        state.last_seen.retain(|e, _| alive.contains(e));
    }
    frame.entries.sort_unstable_by_key(|e| e.entity);
    for (i, e) in frame.entries.iter().enumerate() {
        frame.index.insert(e.entity, i as u32);
    }
    diag.record(Stage::Prepare, start.elapsed(), frame.entries.len() as u64);
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

/// The world box of a mesh under a rigid pose: the union of the world boxes of its tree's
/// nodes a few levels down (up to [`TIGHT_LEVELS`] levels: 8 small boxes). A rotated box's
/// world box grows by up to √3 per axis; smaller boxes grow less, so the union is much
/// tighter than the root's (fewer broad-phase pairs that do not touch) for a few box
/// transforms per moving body.
pub(crate) fn tight_world_aabb(bvh: &crate::bvh::Bvh, pose: &Pose) -> Aabb {
    let nodes = bvh.nodes();
    let rotation = BoxRotation::new(pose);
    let mut out = Aabb::EMPTY;
    let mut stack = [(0u32, 0u32); 2 * TIGHT_LEVELS as usize + 2];
    let mut len = 1;
    while len > 0 {
        len -= 1;
        let (i, level) = stack[len];
        let node = &nodes[i as usize];
        if node.is_leaf() || level == TIGHT_LEVELS {
            out = out.union(&rotation.world_box(&node.aabb(), pose.translation));
        } else {
            stack[len] = (node.left(), level + 1);
            stack[len + 1] = (node.left() + 1, level + 1);
            len += 2;
        }
    }
    out
}

/// Levels of the tree below the root whose boxes make an entity's world box.
const TIGHT_LEVELS: u32 = 3;

/// The world box of a local box under a rigid pose.
pub(crate) fn world_aabb(local: &Aabb, pose: &Pose) -> Aabb {
    BoxRotation::new(pose).world_box(local, pose.translation)
}

/// A pose's rotation as a matrix and its absolute value, for the world boxes of local boxes.
struct BoxRotation {
    m: Mat3,
    abs: Mat3,
}

impl BoxRotation {
    fn new(pose: &Pose) -> Self {
        let m = Mat3::from_quat(pose.rotation);
        let abs = Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        Self { m, abs }
    }

    /// The world box of `local` rotated, then moved by `translation`.
    fn world_box(&self, local: &Aabb, translation: Vec3) -> Aabb {
        let center = translation + self.m * local.center();
        let half = self.abs * local.half_extents();
        Aabb::new(center - half, center + half)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::CollisionMesh;
    use crate::mesh::generate;
    use glam::Quat;

    #[test]
    fn the_tight_box_holds_every_vertex_inside_the_root_box() {
        let meshes = [
            generate::icosphere(1.0, 3),
            generate::cuboid(Vec3::new(2.0, 0.1, 0.5), 4),
            generate::torus(1.0, 0.2, 24, 8),
        ];
        for mesh in meshes {
            let cm = CollisionMesh::new(mesh);
            for k in 0..20 {
                let axis = Vec3::new(1.0, k as f32 * 0.37, -0.5 + k as f32 * 0.11).normalize();
                let pose = Pose::new(
                    Vec3::new(k as f32, -3.0, 0.5),
                    Quat::from_axis_angle(axis, k as f32 * 0.7),
                );
                let tight = tight_world_aabb(cm.bvh(), &pose);
                let loose = world_aabb(&cm.bvh().root_aabb(), &pose);
                for &v in cm.mesh().positions() {
                    let w = pose.transform_point(v);
                    assert!(
                        tight.inflated(1e-4).contains_point(w),
                        "{w} outside {tight:?}"
                    );
                }
                assert!(loose.inflated(1e-4).contains_point(tight.min));
                assert!(loose.inflated(1e-4).contains_point(tight.max));
            }
        }
    }
}

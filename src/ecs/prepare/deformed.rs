//! Continuous collision of deformable colliders: a deformable mesh with
//! [`ContinuousCollision`](super::super::ContinuousCollision) keeps its last state in world
//! coordinates, and in a run in which it changed (positions or pose) its pairs are swept from
//! that state to the new one, each vertex on a straight line
//! ([`deforming_time_of_impact`](crate::ccd::deforming_time_of_impact)). Partners are placed
//! in world coordinates for the sweep too: a rigid one at its poses before and after its
//! motion in the run (its vertices taken on straight lines between them), a deformable one
//! without continuous collision where it is now.
use std::sync::Arc;

use super::super::components::ContinuousCollision;
use crate::bvh::CollisionMesh;
use crate::geometry::{Aabb, Pose};

/// A continuous deformable collider's mesh in world coordinates: as of its last update, and
/// the state before that update (where its motion in the run of the update started), when the
/// two have the same tree structure.
#[derive(Debug, Clone)]
pub(crate) struct DeformedStates {
    pub(crate) now: Arc<CollisionMesh>,
    pub(crate) before: Option<Arc<CollisionMesh>>,
}

impl DeformedStates {
    /// The states after an update to `mesh` at `pose`, `last` the states before it (`None`:
    /// none, or a collider that was not continuous): the old current state becomes the start
    /// of the motion when it has the same triangles and tree structure.
    pub(crate) fn updated(last: Option<DeformedStates>, mesh: &CollisionMesh, pose: &Pose) -> Self {
        let now = Arc::new(placed(mesh, pose));
        let before = last.map(|l| l.now).filter(|b| same_structure(b, &now));
        Self { now, before }
    }

    /// The world box covering the motion from `before` to `now`, if the collider is swept:
    /// `Always`, or `WhenFast` when some vertex moved farther than `fraction` of the current
    /// box's smallest extent.
    pub(crate) fn swept_box(&self, continuous: ContinuousCollision, fraction: f32) -> Option<Aabb> {
        let before = self.before.as_ref()?;
        let end = self.now.bvh().root_aabb();
        let fast = match continuous {
            ContinuousCollision::Always => true,
            ContinuousCollision::WhenFast => {
                let reach = before
                    .mesh()
                    .positions()
                    .iter()
                    .zip(self.now.mesh().positions())
                    .map(|(p, q)| p.distance_squared(*q))
                    .fold(0.0f32, f32::max)
                    .sqrt();
                reach > fraction * end.extents().min_element()
            }
        };
        fast.then(|| before.bvh().root_aabb().union(&end))
    }
}

/// `mesh` with its vertices placed at `pose` (a copy; the same tree structure, refitted).
pub(super) fn placed(mesh: &CollisionMesh, pose: &Pose) -> CollisionMesh {
    let mut out = mesh.clone();
    if *pose != Pose::IDENTITY {
        let world: Vec<_> = mesh
            .mesh()
            .positions()
            .iter()
            .map(|&p| pose.transform_point(p))
            .collect();
        // Poses are validated and positions finite: placing them cannot fail.
        out.set_positions(&world)
            .expect("a valid pose keeps positions finite");
    }
    out
}

/// Whether two states of a mesh have the same triangles and tree structure (what a sweep
/// between them needs).
fn same_structure(a: &CollisionMesh, b: &CollisionMesh) -> bool {
    a.mesh().triangles() == b.mesh().triangles()
        && a.bvh().nodes().len() == b.bvh().nodes().len()
        && a.bvh().leaf_triangles() == b.bvh().leaf_triangles()
}

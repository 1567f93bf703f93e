//! A mesh as the continuous query sees it over one piece of the step: the boxes its BVH nodes
//! sweep and the straight paths of its vertices.

use super::primitive::Trajectory;
use crate::bvh::{Bvh, CollisionMesh};
use crate::geometry::{Aabb, Pose, PoseF64};

/// A rigid mesh between two poses (the ends of one piece of the step): its vertices move on
/// the chords between their positions at both poses.
pub(crate) struct RigidPiece<'a> {
    pub mesh: &'a CollisionMesh,
    start: Pose,
    end: Pose,
    start64: PoseF64,
    end64: PoseF64,
}

impl<'a> RigidPiece<'a> {
    pub fn new(mesh: &'a CollisionMesh, start: Pose, end: Pose) -> Self {
        Self {
            mesh,
            start,
            end,
            start64: start.to_f64(),
            end64: end.to_f64(),
        }
    }
}

/// What the query reads of a moving mesh over a piece of the step.
pub(crate) trait SweptMesh {
    /// The tree (its structure; boxes through [`SweptMesh::node_box`]).
    fn bvh(&self) -> &Bvh;
    /// The mesh's triangles.
    fn triangles(&self) -> &[[u32; 3]];
    /// The world box that node `i` sweeps over the piece (the chords of its vertices included).
    fn node_box(&self, i: usize) -> Aabb;
    /// Vertex `v`'s path over the piece.
    fn vertex(&self, v: u32) -> Trajectory;
}

impl SweptMesh for RigidPiece<'_> {
    fn bvh(&self) -> &Bvh {
        self.mesh.bvh()
    }

    fn triangles(&self) -> &[[u32; 3]] {
        self.mesh.mesh().triangles()
    }

    fn node_box(&self, i: usize) -> Aabb {
        let local = self.mesh.bvh().nodes()[i].aabb();
        // A chord lies in the box of its two ends: the union of the node's world boxes at both
        // poses holds every chord of its vertices.
        let b = self
            .start
            .transform_aabb(&local)
            .union(&self.end.transform_aabb(&local));
        // Grown for the f32 rounding of the boxes.
        b.inflated(f32::EPSILON * 4.0 * (1.0 + b.max_abs()))
    }

    fn vertex(&self, v: u32) -> Trajectory {
        let p = self.mesh.mesh().positions()[v as usize];
        Trajectory::new(
            self.start64.transform_point(p),
            self.end64.transform_point(p),
        )
    }
}

/// A deforming mesh between two sets of vertex positions with one tree structure: every
/// vertex moves on the straight line between its positions.
pub(crate) struct DeformingPiece<'a> {
    pub start: &'a CollisionMesh,
    pub end: &'a CollisionMesh,
}

impl SweptMesh for DeformingPiece<'_> {
    fn bvh(&self) -> &Bvh {
        self.start.bvh()
    }

    fn triangles(&self) -> &[[u32; 3]] {
        self.start.mesh().triangles()
    }

    fn node_box(&self, i: usize) -> Aabb {
        // Both trees have the same structure (checked by the caller): node i bounds the same
        // triangles at both ends.
        let b = self.start.bvh().nodes()[i]
            .aabb()
            .union(&self.end.bvh().nodes()[i].aabb());
        b.inflated(f32::EPSILON * 4.0 * (1.0 + b.max_abs()))
    }

    fn vertex(&self, v: u32) -> Trajectory {
        let (p, q) = (
            self.start.mesh().positions()[v as usize],
            self.end.mesh().positions()[v as usize],
        );
        Trajectory::new(p.as_dvec3(), q.as_dvec3())
    }
}

/// How far from its chord a point at distance `radius` from the body's origin strays while
/// the body turns by `angle` (radians): the sagitta of the arc.
pub(crate) fn chord_deviation(radius: f64, angle: f64) -> f64 {
    radius * (1.0 - (0.5 * angle).cos())
}

/// The largest distance of a vertex from the mesh's origin (its frame's).
pub(crate) fn mesh_radius(mesh: &CollisionMesh) -> f64 {
    let b = mesh.bvh().root_aabb();
    let far = b.min.abs().max(b.max.abs());
    far.as_dvec3().length()
}

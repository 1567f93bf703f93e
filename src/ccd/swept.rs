//! A mesh as the continuous query sees it over one piece of the step: the boxes its BVH nodes
//! sweep and the straight paths of its vertices.

use super::primitive::Trajectory;
use super::window::MovingBox;
use crate::bvh::{Bvh, CollisionMesh};
use crate::geometry::{Aabb, Pose, PoseF64};
use glam::{DMat3, DQuat, DVec3, Mat3, Vec3};

/// A rigid mesh between two poses (the ends of one piece of the step): its vertices move on
/// the chords between their positions at both poses. Its node boxes are given in the piece's
/// [`BoxFrame`].
pub(crate) struct RigidPiece<'a> {
    pub mesh: &'a CollisionMesh,
    /// `None`: the node boxes are the tree's own (the mesh is the frame).
    start: Option<BoxTransform>,
    /// `None` when the boxes do not move over the piece.
    end: Option<BoxTransform>,
    start64: PoseF64,
    end64: PoseF64,
}

/// The frame in which both meshes' node boxes move over a piece. A box holds a vertex's path
/// only in a frame where that path is straight: the world, or the frame of a mesh that does
/// not turn (its translation is linear in time, so the world's straight paths stay straight
/// in it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum BoxFrame {
    /// World coordinates.
    World,
    /// The frame of a mesh that moves from the first pose to the second over the piece without
    /// turning.
    Mesh(Pose, Pose),
}

impl BoxFrame {
    /// The frame's pose at the piece's start and end (`None` for the world).
    fn poses(&self) -> Option<(PoseF64, PoseF64)> {
        match self {
            BoxFrame::World => None,
            BoxFrame::Mesh(s, e) => Some((s.to_f64(), e.to_f64())),
        }
    }

    /// How much a distance in the max norm of world coordinates can grow in the max norm of
    /// the frame's (the frame may be turned): `√3`, or 1 in the world.
    pub fn max_norm_growth(&self) -> f64 {
        match self {
            BoxFrame::World => 1.0,
            BoxFrame::Mesh(..) => 3f64.sqrt(),
        }
    }
}

impl<'a> RigidPiece<'a> {
    /// The mesh moving from `start` to `end` over the piece, its boxes in `frame`; `own` when
    /// the frame is this mesh's (its boxes are then the tree's own).
    pub fn new(
        mesh: &'a CollisionMesh,
        start: Pose,
        end: Pose,
        frame: BoxFrame,
        own: bool,
    ) -> Self {
        let (start64, end64) = (start.to_f64(), end.to_f64());
        let relative = |pose: &PoseF64, frame: &PoseF64| {
            let inv = frame.inverse();
            BoxTransform::new_f64(
                (inv.rotation * pose.rotation).normalize(),
                inv.rotation * pose.translation + inv.translation,
            )
        };
        let (start_box, end_box) = match (own, frame.poses()) {
            (true, _) => (None, None),
            (false, None) => (
                Some(BoxTransform::new_f64(start64.rotation, start64.translation)),
                (end != start).then(|| BoxTransform::new_f64(end64.rotation, end64.translation)),
            ),
            (false, Some((f0, f1))) => (Some(relative(&start64, &f0)), Some(relative(&end64, &f1))),
        };
        Self {
            mesh,
            start: start_box,
            end: end_box,
            start64,
            end64,
        }
    }
}

/// [`Pose::transform_aabb`] with the pose's matrices worked out once.
struct BoxTransform {
    rotation: Mat3,
    abs: Mat3,
    translation: Vec3,
}

impl BoxTransform {
    fn new_f64(rotation: DQuat, translation: DVec3) -> Self {
        let m = DMat3::from_quat(rotation).as_mat3();
        Self {
            rotation: m,
            abs: Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs()),
            translation: translation.as_vec3(),
        }
    }

    fn apply(&self, local: &Aabb) -> Aabb {
        let center = self.translation + self.rotation * local.center();
        let half = self.abs * local.half_extents();
        Aabb::new(center - half, center + half)
    }
}

/// What the query reads of a moving mesh over a piece of the step.
pub(crate) trait SweptMesh {
    /// The tree (its structure; boxes through [`SweptMesh::node_box`]).
    fn bvh(&self) -> &Bvh;
    /// The mesh's triangles.
    fn triangles(&self) -> &[[u32; 3]];
    /// Node `i`'s box at each time of the piece, in the piece's frame: its vertices, moving on
    /// their paths, stay inside it.
    fn node_box(&self, i: usize) -> MovingBox;
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

    fn node_box(&self, i: usize) -> MovingBox {
        let local = self.mesh.bvh().nodes()[i].aabb();
        // The node's boxes at both poses hold its vertices' chords' ends, so the box between
        // them holds the chords.
        let b0 = rounding_grown(match &self.start {
            Some(start) => start.apply(&local),
            None => local,
        });
        match &self.end {
            Some(end) => MovingBox::new(&b0, &rounding_grown(end.apply(&local))),
            None => MovingBox::new(&b0, &b0),
        }
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

    fn node_box(&self, i: usize) -> MovingBox {
        // Both trees have the same structure (checked by the caller): node i bounds the same
        // triangles at both ends.
        MovingBox::new(
            &rounding_grown(self.start.bvh().nodes()[i].aabb()),
            &rounding_grown(self.end.bvh().nodes()[i].aabb()),
        )
    }

    fn vertex(&self, v: u32) -> Trajectory {
        let (p, q) = (
            self.start.mesh().positions()[v as usize],
            self.end.mesh().positions()[v as usize],
        );
        Trajectory::new(p.as_dvec3(), q.as_dvec3())
    }
}

/// `b` grown for the `f32` rounding of a box computed from `f32` positions and poses (a few
/// ulps of its coordinates; 32 leave room to spare).
fn rounding_grown(b: Aabb) -> Aabb {
    b.inflated(f32::EPSILON * 32.0 * (1.0 + b.max_abs()))
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

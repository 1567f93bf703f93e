//! A mesh as the continuous query sees it over the step: the step cut into pieces over which
//! its vertices move on straight paths, the boxes its BVH nodes sweep over any run of pieces,
//! and its vertices' paths over each piece.

use std::cell::OnceCell;

use glam::{DMat3, DQuat, DVec3, Mat3, Vec3};

use super::motion::{RigidMotion, Trajectory};
use super::window::{MovingBox, MovingSlab};
use crate::bvh::{Bvh, CollisionMesh, NodeSlab};
use crate::geometry::{Aabb, PoseF64};

/// A run of consecutive pieces of the step, `[first, end)`.
pub(crate) type Span = (u32, u32);

/// What the query reads of a moving mesh over the step.
pub(crate) trait SweptMesh {
    /// The tree (its structure; boxes through [`SweptMesh::node_box`]).
    fn bvh(&self) -> &Bvh;
    /// The mesh's triangles.
    fn triangles(&self) -> &[[u32; 3]];
    /// How many pieces the step is cut into.
    fn pieces(&self) -> u32;
    /// Node `i`'s box over the pieces of `span`, in the step's frame, moving linearly from the
    /// span's start to its end: the node's vertices, moving on their paths over each piece of
    /// the span, stay inside it.
    fn node_box(&self, i: usize, span: Span) -> MovingBox;
    /// How much [`SweptMesh::node_box`] is grown over `span` for the mesh's turning (0 over
    /// one piece).
    fn turn_slack(&self, span: Span) -> f64;
    /// Vertex `v`'s straight path over piece `piece`.
    fn vertex(&self, v: u32, piece: u32) -> Trajectory;
    /// Node `i`'s slab in the step's frame over the pieces of `span`, its bounds moving
    /// linearly from the span's start to its end so that the node's vertices stay inside it:
    /// for a rigid mesh that does not turn in that frame; `None` otherwise, or where the node
    /// has no slab ([`NodeSlab`]).
    fn node_slab(&self, _i: usize, _span: Span) -> Option<MovingSlab> {
        None
    }
}

/// The frame in which both meshes' node boxes move. A box holds a vertex's path only in a
/// frame where that path is straight: the world, or the frame of a mesh that does not turn
/// (its translation is linear in time, so the world's straight paths stay straight in it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum BoxFrame {
    /// World coordinates.
    World,
    /// The frame of a mesh that moves so over the step, without turning.
    Mesh(RigidMotion),
}

impl BoxFrame {
    /// How much a distance in the max norm of world coordinates can grow in the max norm of
    /// the frame's (the frame may be turned): `√3`, or 1 in the world.
    pub fn max_norm_growth(&self) -> f64 {
        match self {
            BoxFrame::World => 1.0,
            BoxFrame::Mesh(..) => 3f64.sqrt(),
        }
    }
}

/// A rigid mesh moving over the step, cut into `pieces`: over each its vertices move on the
/// chords between their positions at the piece's ends. Its node boxes are in the step's
/// [`BoxFrame`].
pub(crate) struct RigidStep<'a> {
    mesh: &'a CollisionMesh,
    motion: RigidMotion,
    frame: BoxFrame,
    /// The frame is this mesh's: its boxes are the tree's own.
    own: bool,
    pieces: u32,
    /// How far a vertex is from the mesh's origin, at most.
    radius: f64,
    /// The angle turned over the whole step.
    angle: f64,
    /// Per piece boundary: the mesh's poses, worked out when first read.
    poses: &'a PoseCache,
}

/// Per piece boundary `k` of a step: a mesh's pose in the step's frame (for its boxes) and in
/// the world (for its vertices), each worked out when first read. Kept in the workspace, so a
/// query allocates nothing once it has grown.
#[derive(Debug, Default, Clone)]
pub(crate) struct PoseCache {
    in_frame: Vec<OnceCell<BoxTransform>>,
    in_frame_f64: Vec<OnceCell<PoseF64>>,
    in_world: Vec<OnceCell<PoseF64>>,
}

impl PoseCache {
    /// Empties the cache for a step of `pieces` pieces.
    pub fn reset(&mut self, pieces: u32) {
        let boundaries = pieces as usize + 1;
        self.in_frame.clear();
        self.in_frame.resize_with(boundaries, OnceCell::new);
        self.in_frame_f64.clear();
        self.in_frame_f64.resize_with(boundaries, OnceCell::new);
        self.in_world.clear();
        self.in_world.resize_with(boundaries, OnceCell::new);
    }
}

impl<'a> RigidStep<'a> {
    /// `mesh` moving by `motion`, cut into `pieces`, its boxes in `frame` (`own`: the frame is
    /// this mesh's); `poses` was [reset](PoseCache::reset) for `pieces`.
    pub fn new(
        mesh: &'a CollisionMesh,
        motion: RigidMotion,
        (pieces, poses): (u32, &'a PoseCache),
        frame: BoxFrame,
        own: bool,
    ) -> Self {
        debug_assert_eq!(poses.in_world.len(), pieces as usize + 1);
        Self {
            mesh,
            motion,
            frame,
            own,
            pieces,
            radius: mesh_radius(mesh),
            angle: motion.angle(),
            poses,
        }
    }

    /// The time of boundary `k` (as the pieces are cut: `k / pieces` in `f32`).
    fn boundary_time(&self, k: u32) -> f32 {
        k as f32 / self.pieces as f32
    }

    fn world_pose(&self, k: u32) -> &PoseF64 {
        self.poses.in_world[k as usize]
            .get_or_init(|| self.motion.at(self.boundary_time(k)).to_f64())
    }

    /// The mesh's pose in the step's frame at boundary `k`.
    fn frame_pose(&self, k: u32) -> &PoseF64 {
        self.poses.in_frame_f64[k as usize].get_or_init(|| {
            let pose = *self.world_pose(k);
            match self.frame {
                BoxFrame::World => pose,
                BoxFrame::Mesh(frame) => {
                    let inv = frame.at(self.boundary_time(k)).to_f64().inverse();
                    PoseF64 {
                        rotation: (inv.rotation * pose.rotation).normalize(),
                        translation: inv.rotation * pose.translation + inv.translation,
                    }
                }
            }
        })
    }

    fn frame_transform(&self, k: u32) -> &BoxTransform {
        self.poses.in_frame[k as usize].get_or_init(|| {
            let pose = self.frame_pose(k);
            BoxTransform::new(pose.rotation, pose.translation)
        })
    }
}

impl SweptMesh for RigidStep<'_> {
    fn bvh(&self) -> &Bvh {
        self.mesh.bvh()
    }

    fn triangles(&self) -> &[[u32; 3]] {
        self.mesh.mesh().triangles()
    }

    fn pieces(&self) -> u32 {
        self.pieces
    }

    fn node_box(&self, i: usize, span: Span) -> MovingBox {
        let local = self.mesh.bvh().nodes()[i].aabb();
        if self.own {
            let b = rounding_grown(local);
            return MovingBox::new(&b, &b);
        }
        // The node's boxes at the span's ends hold its vertices there; the box between them
        // holds the chords between those ends, and grown by how far an arc strays from its
        // chord over the span, every piece's chords (each lies between two points of the arc).
        let slack = self.turn_slack(span) as f32;
        let at = |k: u32| {
            let b = self.frame_transform(k).apply(&local);
            rounding_grown(b.inflated(slack))
        };
        MovingBox::new(&at(span.0), &at(span.1))
    }

    fn turn_slack(&self, span: Span) -> f64 {
        if span.1 - span.0 <= 1 || self.angle == 0.0 {
            return 0.0;
        }
        let turned = self.angle * (span.1 - span.0) as f64 / self.pieces as f64;
        // A vertex at time s on its arc against the point at s on the chord between the span's
        // ends: across the chord by at most the sagitta, along it by `r |sin(θu) − 2u sin(θ/2)|`
        // (u = s − ½ in span time), which stays below `r θ³ / 12` for θ ≤ π. Rounded up a
        // little: the box must hold the arc.
        let along = self.radius * turned.powi(3) / 12.0;
        (chord_deviation(self.radius, turned) + along) * (1.0 + 1e-6) + 1e-12 * self.radius
    }

    fn vertex(&self, v: u32, piece: u32) -> Trajectory {
        let p = self.mesh.mesh().positions()[v as usize];
        Trajectory::new(
            self.world_pose(piece).transform_point(p),
            self.world_pose(piece + 1).transform_point(p),
        )
    }

    fn node_slab(&self, i: usize, span: Span) -> Option<MovingSlab> {
        // A turning mesh's slabs turn with it: not a slab that moves linearly.
        if !self.own && self.motion.start.rotation != self.motion.end.rotation {
            return None;
        }
        let slab = self.mesh.node_slabs()[i];
        if !slab.is_bounded() {
            return None;
        }
        // Grown, as the boxes are, for the f32 poses the boundaries are placed at.
        let pad = |reach: f64| f32::EPSILON as f64 * 32.0 * (1.0 + self.radius + reach);
        if self.own {
            // Still in its own frame: its slabs are its tree's own.
            let p = pad(0.0);
            return Some(MovingSlab::still(&NodeSlab {
                lo: slab.lo - p,
                hi: slab.hi + p,
                ..slab
            }));
        }
        // Translating without turning: the normal turned into the frame once, the bounds
        // shifted by the translation along it at the span's ends (in between the vertices move
        // on straight lines).
        let (start, end) = (self.frame_pose(span.0), self.frame_pose(span.1));
        let normal = start.rotation * slab.normal;
        let bounds = |pose: &PoseF64| {
            let (shift, p) = (normal.dot(pose.translation), pad(pose.translation.length()));
            (slab.lo + shift - p, slab.hi + shift + p)
        };
        Some(MovingSlab {
            normal,
            start: bounds(start),
            end: bounds(end),
        })
    }
}

/// [`Pose::transform_aabb`](crate::geometry::Pose::transform_aabb) for a pose worked out in
/// `f64`, its matrices computed once.
#[derive(Debug, Clone, Copy)]
struct BoxTransform {
    rotation: Mat3,
    abs: Mat3,
    translation: Vec3,
}

impl BoxTransform {
    fn new(rotation: DQuat, translation: DVec3) -> Self {
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

/// A deforming mesh between two sets of vertex positions with one tree structure: every
/// vertex moves on the straight line between its positions (one piece).
pub(crate) struct DeformingStep<'a> {
    pub start: &'a CollisionMesh,
    pub end: &'a CollisionMesh,
}

impl SweptMesh for DeformingStep<'_> {
    fn bvh(&self) -> &Bvh {
        self.start.bvh()
    }

    fn triangles(&self) -> &[[u32; 3]] {
        self.start.mesh().triangles()
    }

    fn pieces(&self) -> u32 {
        1
    }

    fn node_box(&self, i: usize, _span: Span) -> MovingBox {
        // Both trees have the same structure (checked by the caller): node i bounds the same
        // triangles at both ends.
        MovingBox::new(
            &rounding_grown(self.start.bvh().nodes()[i].aabb()),
            &rounding_grown(self.end.bvh().nodes()[i].aabb()),
        )
    }

    fn turn_slack(&self, _span: Span) -> f64 {
        0.0
    }

    fn vertex(&self, v: u32, _piece: u32) -> Trajectory {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Pose;
    use crate::mesh::generate;
    use glam::{Quat, Vec3};

    #[test]
    fn a_turning_meshs_boxes_over_a_run_of_pieces_hold_every_pieces_paths() {
        // Off-centre so that the radius is not the sphere's; turns up to half a turn.
        let mesh = CollisionMesh::new(
            generate::icosphere(0.5, 1)
                .translated(Vec3::new(0.7, -0.2, 0.1))
                .expect("finite"),
        );
        for (angle, pieces) in [(0.3f32, 16u32), (1.5, 9), (3.1, 24)] {
            let motion = RigidMotion::new(
                Pose::new(Vec3::new(1.0, 2.0, 3.0), Quat::from_rotation_x(0.4)),
                Pose::new(
                    Vec3::new(2.0, 1.0, 3.5),
                    Quat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), angle)
                        * Quat::from_rotation_x(0.4),
                ),
            );
            let mut poses = PoseCache::default();
            poses.reset(pieces);
            let step = RigidStep::new(&mesh, motion, (pieces, &poses), BoxFrame::World, false);
            let nodes = mesh.bvh().nodes();
            for span in [(0, pieces), (1, pieces / 2 + 1), (pieces / 3, pieces)] {
                for (i, node) in nodes.iter().enumerate().filter(|(_, n)| n.is_leaf()) {
                    let moving = step.node_box(i, span);
                    for &t in mesh.bvh().triangles_of(node) {
                        for v in mesh.mesh().triangles()[t as usize] {
                            for piece in span.0..span.1 {
                                let path = step.vertex(v, piece);
                                for k in 0..=8 {
                                    let s = k as f64 / 8.0;
                                    let u = (piece as f64 + s - span.0 as f64)
                                        / (span.1 - span.0) as f64;
                                    let (lo, hi) = moving.at(u);
                                    let p = path.at(s);
                                    let slop = DVec3::splat(1e-9);
                                    assert!(
                                        (p + slop).cmpge(lo).all() && (p - slop).cmple(hi).all(),
                                        "angle {angle}, span {span:?}, node {i}: {p} not in {lo}..{hi}"
                                    );
                                }
                            }
                        }
                    }
                }
            }
        }
    }
}

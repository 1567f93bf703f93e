//! Contact points from what a query found: an intersecting triangle pair, or an ADB witness.
use glam::Vec3;

use crate::bvh::{CollisionMesh, TrianglePair};
use crate::geometry::{Aabb, Pose};

/// One contact point between two meshes (or within one), in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    /// Where the surfaces touch (approximately).
    pub point: Vec3,
    /// Unit direction in which to push the second entity away from the first.
    pub normal: Vec3,
    /// Estimated penetration along `normal` (0 when merely touching).
    pub depth: f32,
    /// The triangle pair (first entity, second entity), when the contact comes from one.
    pub triangles: Option<TrianglePair>,
}

fn world_triangle(mesh: &CollisionMesh, pose: &Pose, t: u32) -> [Vec3; 3] {
    mesh.mesh()
        .triangle(t as usize)
        .map(|p| pose.transform_point(p))
}

fn unit_normal(t: &[Vec3; 3]) -> Vec3 {
    (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero()
}

fn centroid(t: &[Vec3; 3]) -> Vec3 {
    (t[0] + t[1] + t[2]) / 3.0
}

/// The contact of an intersecting triangle pair: point between the centroids, normal from the
/// two face normals (outward normals of closed meshes: push the second along the first's
/// normal and against its own), depth of the second triangle below the first's plane.
pub(crate) fn triangle_pair_contact(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    pair: TrianglePair,
) -> ContactPoint {
    let ta = world_triangle(a, pose_a, pair.a);
    let tb = world_triangle(b, pose_b, pair.b);
    let (ca, cb) = (centroid(&ta), centroid(&tb));
    let mut normal = (unit_normal(&ta) - unit_normal(&tb)).normalize_or_zero();
    if normal == Vec3::ZERO {
        normal = (cb - ca).normalize_or(Vec3::Y);
    }
    let depth_b = tb
        .iter()
        .map(|v| (ca - *v).dot(normal))
        .fold(0.0f32, f32::max);
    let depth_a = ta
        .iter()
        .map(|v| (*v - cb).dot(normal))
        .fold(0.0f32, f32::max);
    ContactPoint {
        point: (ca + cb) * 0.5,
        normal,
        depth: depth_a.min(depth_b),
        triangles: Some(pair),
    }
}

/// Depth estimate from the world boxes: their overlap along `normal`, at most a quarter of
/// the smaller box's extent along it (an ADB witness carries no depth).
pub(crate) fn box_depth(a: &Aabb, b: &Aabb, normal: Vec3) -> f32 {
    let project = |bx: &Aabb| {
        let c = bx.center().dot(normal);
        let r = bx.half_extents().dot(normal.abs());
        (c - r, c + r)
    };
    let ((a0, a1), (b0, b1)) = (project(a), project(b));
    let overlap = (a1.min(b1) - a0.max(b0)).max(0.0);
    overlap.min(0.5 * (a1 - a0).min(b1 - b0) * 0.5)
}

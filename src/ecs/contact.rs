//! Contact points from what a query found: an intersecting triangle pair, or an ADB witness.
use glam::Vec3;

use super::prepare::{ColliderEntry, world_aabb};
use crate::adb::{ContactWitness, Interpenetration};
use crate::bvh::{CollisionMesh, TrianglePair};
use crate::geometry::{Aabb, Pose};

/// One contact point between two meshes (or within one), in world space.
#[derive(bevy_reflect::Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Clone, Debug, PartialEq)]
pub struct ContactPoint {
    /// Where the surfaces touch (approximately).
    pub point: Vec3,
    /// Unit direction in which to push the second entity away from the first.
    pub normal: Vec3,
    /// Estimated penetration along `normal` (0 when merely touching).
    pub depth: f32,
    /// The triangle pair (first entity, second entity), when the contact comes from one.
    #[reflect(remote = super::reflect::OptionTrianglePairReflect)]
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

/// The contact of an intersecting triangle pair: point between the centroids, normal of the
/// larger triangle (the reference face, as in box-box manifolds: a face meeting an edge or a
/// corner; outward normals of closed meshes push the second along the first's normal and
/// against its own), depth of the deeper triangle behind the other's plane (the
/// smaller of the two, so a huge triangle's far corners do not count).
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
    let (na, nb) = (unit_normal(&ta), unit_normal(&tb));
    let area = |t: &[Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).length_squared();
    let mut normal = if area(&ta) >= area(&tb) { na } else { -nb };
    if normal == Vec3::ZERO {
        normal = (cb - ca).normalize_or(Vec3::Y);
    }
    // How far each triangle's corners reach behind the other's plane.
    let behind =
        |t: &[Vec3; 3], c: Vec3, n: Vec3| t.iter().map(|v| (c - *v).dot(n)).fold(0.0f32, f32::max);
    let depth = behind(&tb, ca, na).min(behind(&ta, cb, nb));
    ContactPoint {
        point: (ca + cb) * 0.5,
        normal,
        depth,
        triangles: Some(pair),
    }
}

/// The contact of an interpenetration certificate: the sample found inside the other mesh, the
/// witness's normal (from the first mesh's box centre to the second's), and how deep the sample
/// lies.
pub(crate) fn interpenetration_contact(w: &ContactWitness, c: &Interpenetration) -> ContactPoint {
    ContactPoint {
        point: w.point,
        normal: w.normal,
        depth: c.depth,
        triangles: None,
    }
}

/// The contact of an ADB witness (a probable node pair, no triangle pair): its point; its
/// normal, turned to agree with the direction between the two nodes' centres (a node's mean
/// surface normal can point anywhere when the node is large); as depth, the nodes' overlap
/// along the normal, at most half the thinner node's extent along it, scaled by the
/// confidence (an uncertain contact pushes gently).
pub(crate) fn node_contact(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    w: &ContactWitness,
    probability: f64,
) -> ContactPoint {
    let (na, nb) = w.nodes;
    let box_a = world_aabb(&a.bvh().nodes()[na as usize].aabb(), pose_a);
    let box_b = world_aabb(&b.bvh().nodes()[nb as usize].aabb(), pose_b);
    let apart = box_b.center() - box_a.center();
    let normal = if w.normal.dot(apart) >= 0.0 || apart == Vec3::ZERO {
        w.normal
    } else {
        apart.normalize()
    };
    let project = |bx: &Aabb| {
        let c = bx.center().dot(normal);
        let r = bx.half_extents().dot(normal.abs());
        (c - r, c + r)
    };
    let ((a0, a1), (b0, b1)) = (project(&box_a), project(&box_b));
    let overlap = (a1.min(b1) - a0.max(b0)).max(0.0);
    let depth = overlap.min(0.5 * (a1 - a0).min(b1 - b0)) * probability as f32;
    ContactPoint {
        point: w.point,
        normal,
        depth,
        triangles: None,
    }
}

/// The contact of two overlapping boxes: the centre of their overlap, the axis of least
/// overlap (from the first towards the second), that overlap as depth.
pub(crate) fn bounds_contact(a: &ColliderEntry, b: &ColliderEntry) -> ContactPoint {
    let lo = a.aabb.min.max(b.aabb.min);
    let hi = a.aabb.max.min(b.aabb.max);
    let overlap = (hi - lo).max(Vec3::ZERO);
    let axis = overlap.min_position();
    let mut normal = Vec3::ZERO;
    normal[axis] = if b.aabb.center()[axis] >= a.aabb.center()[axis] {
        1.0
    } else {
        -1.0
    };
    ContactPoint {
        point: (lo + hi) * 0.5,
        normal,
        depth: overlap[axis],
        triangles: None,
    }
}

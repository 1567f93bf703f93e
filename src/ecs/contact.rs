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
    /// For a pair tested over a swept collider's motion
    /// ([`ContinuousCollision`](super::ContinuousCollision)): when in the run's step the
    /// surfaces first met, as a fraction of the motion in `[0, 1]` (0: they touched already
    /// where the motion started). `None` for contacts found at the run's poses only.
    pub time_of_impact: Option<f32>,
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

/// Where two triangles' planes cut each triangle: the part of line `origin + t·direction`
/// inside `t`, as its two ends (`(t, point)`), or `None` when no edge crosses the plane.
fn plane_cut(
    t: &[Vec3; 3],
    plane_point: Vec3,
    plane_normal: Vec3,
    direction: Vec3,
) -> Option<[(f32, Vec3); 2]> {
    let d = t.map(|v| (v - plane_point).dot(plane_normal));
    let mut ends: Option<[(f32, Vec3); 2]> = None;
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        let crossing = if d[i] == 0.0 {
            Some(t[i])
        } else if (d[i] < 0.0) != (d[j] < 0.0) && d[j] != 0.0 {
            Some(t[i] + (t[j] - t[i]) * (d[i] / (d[i] - d[j])))
        } else {
            None
        };
        if let Some(p) = crossing {
            let at = (p.dot(direction), p);
            ends = Some(match ends {
                None => [at, at],
                Some([lo, hi]) => [
                    if at.0 < lo.0 { at } else { lo },
                    if at.0 > hi.0 { at } else { hi },
                ],
            });
        }
    }
    ends
}

/// The open mesh's face normal `n` at `point`, turned to point towards (`towards = 1`) or away
/// from (`-1`) the centre of the closed mesh's box; `None` when that centre lies (nearly) in the
/// face's plane.
fn open_face_normal(
    n: Vec3,
    closed: &CollisionMesh,
    pose: &Pose,
    point: Vec3,
    towards: f32,
) -> Option<Vec3> {
    let bounds = closed.bvh().root_aabb();
    let centre = pose.transform_point(bounds.center());
    let to_centre = centre - point;
    let side = n.dot(to_centre);
    (side.abs() > 1e-3 * to_centre.length()).then(|| n * side.signum() * towards)
}

/// A point where two intersecting triangles meet: the middle of their intersection segment
/// (the overlap of each triangle's cut by the other's plane), or, for coplanar or nearly
/// coplanar triangles, the smaller triangle's centroid on the larger one's plane.
fn meeting_point(ta: &[Vec3; 3], tb: &[Vec3; 3]) -> Vec3 {
    let na = (ta[1] - ta[0]).cross(ta[2] - ta[0]);
    let nb = (tb[1] - tb[0]).cross(tb[2] - tb[0]);
    let direction = na.cross(nb);
    let cuts = (direction.length_squared() > 1e-6 * na.length_squared() * nb.length_squared())
        .then(|| {
            Some((
                plane_cut(ta, tb[0], nb, direction)?,
                plane_cut(tb, ta[0], na, direction)?,
            ))
        })
        .flatten();
    if let Some(([a_lo, a_hi], [b_lo, b_hi])) = cuts {
        let lo = if a_lo.0 >= b_lo.0 { a_lo } else { b_lo };
        let hi = if a_hi.0 <= b_hi.0 { a_hi } else { b_hi };
        if lo.0 <= hi.0 {
            return (lo.1 + hi.1) * 0.5;
        }
        // Rounding made the two cuts miss each other: between them.
        return (a_lo.1 + a_hi.1 + b_lo.1 + b_hi.1) * 0.25;
    }
    let (small, large, n) = if na.length_squared() <= nb.length_squared() {
        (ta, tb, nb)
    } else {
        (tb, ta, na)
    };
    let c = centroid(small);
    let n = n.normalize_or_zero();
    c - n * (c - large[0]).dot(n)
}

/// The contact of an intersecting triangle pair: point in the middle of the segment where
/// they cross (see `meeting_point`), normal of the reference face: between an open mesh and a
/// closed one no larger than it, the open one's triangle turned towards the closed one's
/// centre (the closed one's outward normal when that centre lies in the plane); between an open
/// mesh and a larger closed one, the closed one's outward normal; else the larger triangle (as in
/// box-box manifolds: a face meeting an edge or a corner; outward normals of closed meshes push
/// the second along the first's normal and against its own), depth of the deeper triangle behind the other's plane (the
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
    let size = |m: &CollisionMesh| m.bvh().root_aabb().extents().length_squared();
    let mut normal = match (a.is_closed(), b.is_closed()) {
        // An open mesh's face normals can point either way (a sheet has no outside). Against a
        // closed mesh no larger than it (a ball on a sheet), its face normal turned towards
        // the closed mesh's centre: the closed one is pushed off the sheet to the side where
        // its bulk is. Against a larger closed mesh (an open body on a floor), the closed
        // one's outward normal: the centre of a floor's box says nothing about which way is
        // out where a small body touches it.
        (false, true) if size(a) >= size(b) => {
            open_face_normal(na, b, pose_b, ca, 1.0).unwrap_or(-nb)
        }
        (false, true) => -nb,
        (true, false) if size(b) >= size(a) => {
            open_face_normal(nb, a, pose_a, cb, -1.0).unwrap_or(na)
        }
        (true, false) => na,
        _ if area(&ta) >= area(&tb) => na,
        _ => -nb,
    };
    if normal == Vec3::ZERO {
        normal = (cb - ca).normalize_or(Vec3::Y);
    }
    // How far each triangle's corners reach behind the other's plane.
    let behind =
        |t: &[Vec3; 3], c: Vec3, n: Vec3| t.iter().map(|v| (c - *v).dot(n)).fold(0.0f32, f32::max);
    let depth = behind(&tb, ca, na).min(behind(&ta, cb, nb));
    ContactPoint {
        point: meeting_point(&ta, &tb),
        normal,
        depth,
        triangles: Some(pair),
        time_of_impact: None,
    }
}

/// One contact summarising the contact region of the intersecting triangle `pairs` (at least
/// one): the mean of their meeting points, the mean of their normals (the deepest pair's
/// normal when they cancel), the largest depth, the deepest pair as its triangle pair. At most
/// `max` pairs, evenly spread, are looked at.
pub(crate) fn region_contact(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    pairs: &[TrianglePair],
    max: usize,
) -> Option<ContactPoint> {
    let step = pairs.len().div_ceil(max.max(1)).max(1);
    let mut deepest: Option<ContactPoint> = None;
    let (mut point, mut normal, mut count) = (Vec3::ZERO, Vec3::ZERO, 0u32);
    for &pair in pairs.iter().step_by(step) {
        let c = triangle_pair_contact(a, pose_a, b, pose_b, pair);
        point += c.point;
        normal += c.normal;
        count += 1;
        if deepest.is_none_or(|d| c.depth > d.depth) {
            deepest = Some(c);
        }
    }
    let deepest = deepest?;
    let mean = normal / count as f32;
    Some(ContactPoint {
        point: point / count as f32,
        normal: if mean.length_squared() > 0.01 {
            mean.normalize()
        } else {
            deepest.normal
        },
        ..deepest
    })
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
        time_of_impact: None,
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
        time_of_impact: None,
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
        time_of_impact: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_meeting_point_lies_on_both_triangles_not_between_their_centroids() {
        // A large floor triangle and a small one crossing it far from the floor's centroid.
        let floor = [
            Vec3::ZERO,
            Vec3::new(20.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 20.0),
        ];
        let small = [
            Vec3::new(0.5, -1.0, -0.25),
            Vec3::new(0.5, -1.0, 1.75),
            Vec3::new(0.5, 1.0, 0.75),
        ];
        // `small` meets the floor plane along x = 0.5, z in [0.25, 1.25] (its cut), inside
        // the floor triangle's cut z in [0, 19.5]: the middle is (0.5, 0, 0.75).
        let p = meeting_point(&floor, &small);
        assert!((p - Vec3::new(0.5, 0.0, 0.75)).length() < 1e-5, "{p}");
        assert_eq!(meeting_point(&small, &floor), p);
        // Coplanar: the small triangle's centroid, on the floor.
        let flat = [
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 2.0),
        ];
        let c = meeting_point(&floor, &flat);
        assert!((c - centroid(&flat)).length() < 1e-6);
    }

    #[test]
    fn an_open_body_on_a_large_closed_floor_is_pushed_up() {
        use crate::mesh::{TriMesh, generate};
        // A wide closed floor slab (top at y = 0) and a small open bowl (a box without its
        // top) sunk a little into it, far from the floor's centre.
        let floor = CollisionMesh::new(generate::cuboid(Vec3::new(10.0, 0.5, 10.0), 4));
        let floor_pose = Pose::from_translation(Vec3::new(0.0, -0.5, 0.0));
        let cube = generate::cuboid(Vec3::splat(0.2), 1);
        let (p, t) = (cube.positions(), cube.triangles());
        // Keep every triangle but those of the top face (all three corners at y = +0.2).
        let bowl: Vec<[u32; 3]> = t
            .iter()
            .copied()
            .filter(|tri| !tri.iter().all(|&i| p[i as usize].y > 0.1))
            .collect();
        let bowl = CollisionMesh::new(TriMesh::new(p.to_vec(), bowl).expect("a valid mesh"));
        assert!(floor.is_closed() && !bowl.is_closed());
        let bowl_pose = Pose::from_translation(Vec3::new(7.0, 0.19, 3.0));
        let mut pairs = Vec::new();
        let mut ws = crate::bvh::QueryWorkspace::default();
        crate::bvh::intersecting_pairs(&floor, &floor_pose, &bowl, &bowl_pose, &mut ws, &mut pairs);
        assert!(!pairs.is_empty());
        for &pair in &pairs {
            // The floor's outward normal pushes the bowl up, whichever way its faces point.
            let c = triangle_pair_contact(&floor, &floor_pose, &bowl, &bowl_pose, pair);
            assert!(c.normal.dot(Vec3::Y) > 0.99, "{:?}", c.normal);
            let swapped = TrianglePair {
                a: pair.b,
                b: pair.a,
            };
            let c = triangle_pair_contact(&bowl, &bowl_pose, &floor, &floor_pose, swapped);
            assert!(c.normal.dot(Vec3::Y) < -0.99, "{:?}", c.normal);
        }
    }
}

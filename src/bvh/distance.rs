//! Distance and closest points between two meshes (branch and bound over both trees).
use glam::Vec3;

use super::box_test::{RelativeFrame, node_size};
use super::collision_mesh::CollisionMesh;
use super::workspace::{QueryWorkspace, TrianglePair, triangle_f64};
use crate::geometry::{Pose, closest_points_triangle_triangle};

/// The closest points between two meshes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshDistance {
    /// Distance between the surfaces (0 when they touch or intersect), computed in `f64`; it
    /// saturates at `f32::MAX` when the surfaces are farther apart than `f32` can say (never
    /// infinite).
    pub distance: f32,
    /// Closest point on the first mesh, in world space.
    pub point_a: Vec3,
    /// Closest point on the second mesh, in world space.
    pub point_b: Vec3,
    /// The triangles the points lie on.
    pub triangles: TrianglePair,
}

/// Distance and closest points between the surfaces of `a` at `pose_a` and `b` at `pose_b`,
/// or `None` if they are farther apart than `max_distance` (pass `f32::INFINITY` for no limit)
/// or a pose is not [finite](Pose::is_finite).
/// Exact up to `f64` rounding of the closest-point computation; stops early at distance 0.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// let ball = CollisionMesh::new(generate::icosphere(1.0, 3));
/// let mut ws = QueryWorkspace::new();
/// let b = Pose::from_translation(Vec3::new(3.0, 0.0, 0.0));
/// let d = closest_points(&ball, &Pose::IDENTITY, &ball, &b, f32::INFINITY, &mut ws).unwrap();
/// assert!((d.distance - 1.0).abs() < 0.01);
/// assert!(closest_points(&ball, &Pose::IDENTITY, &ball, &b, 0.5, &mut ws).is_none());
/// ```
pub fn closest_points(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    max_distance: f32,
    ws: &mut QueryWorkspace,
) -> Option<MeshDistance> {
    let rel = pose_a.inverse_mul(pose_b);
    if !rel.is_finite() {
        ws.node_pairs_visited = 0;
        return None; // a pose that is not finite places its mesh nowhere
    }
    let (ta, tb) = (a.bvh(), b.bvh());
    let frame = RelativeFrame::new(&rel, ta, tb);
    let rel64 = rel.to_f64();
    let (pos_a, pos_b) = (a.mesh().positions(), b.mesh().positions());
    let (tris_a, tris_b) = (a.mesh().triangles(), b.mesh().triangles());
    let (na, nb) = (ta.nodes(), tb.nodes());
    ws.cache.begin(pos_b.len());
    ws.distance_stack.clear();
    ws.node_pairs_visited = 1;
    let mut best = f64::from(max_distance);
    let mut found = None;
    let lb = frame.distance_lower_bound(&na[0], &nb[0]);
    if f64::from(lb) > best {
        return None;
    }
    ws.distance_stack.push((0, 0, lb));
    while let Some((ia, ib, lb)) = ws.distance_stack.pop() {
        if f64::from(lb) > best || best == 0.0 {
            continue;
        }
        let (node_a, node_b) = (&na[ia as usize], &nb[ib as usize]);
        if node_a.is_leaf() && node_b.is_leaf() {
            for &t in ta.triangles_of(node_a) {
                let tri_a = triangle_f64(tris_a[t as usize], pos_a);
                for &u in tb.triangles_of(node_b) {
                    let tri_b = ws.cache.triangle(tris_b[u as usize], pos_b, &rel64);
                    let c = closest_points_triangle_triangle(&tri_a, &tri_b);
                    if c.distance <= best {
                        best = c.distance;
                        found = Some((c, TrianglePair { a: t, b: u }));
                    }
                }
            }
            continue;
        }
        let split_a =
            !node_a.is_leaf() && (node_b.is_leaf() || node_size(node_a) >= node_size(node_b));
        let children = if split_a {
            let l = node_a.left();
            [(l, ib), (l + 1, ib)]
        } else {
            let l = node_b.left();
            [(ia, l), (ia, l + 1)]
        };
        let bounds = children.map(|(x, y)| {
            ws.node_pairs_visited += 1;
            frame.distance_lower_bound(&na[x as usize], &nb[y as usize])
        });
        // Push the farther pair first so the nearer one is explored first.
        let order = if bounds[0] <= bounds[1] {
            [1, 0]
        } else {
            [0, 1]
        };
        for k in order {
            if f64::from(bounds[k]) <= best {
                ws.distance_stack
                    .push((children[k].0, children[k].1, bounds[k]));
            }
        }
    }
    let (c, triangles) = found?;
    Some(MeshDistance {
        distance: (c.distance as f32).min(f32::MAX),
        point_a: pose_a.transform_point(c.point_a.as_vec3()),
        point_b: pose_a.transform_point(c.point_b.as_vec3()),
        triangles,
    })
}

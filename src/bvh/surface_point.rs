//! The point of a mesh's surface closest to a given point (branch and bound over its tree).
use glam::{DVec3, Vec3};

use super::collision_mesh::CollisionMesh;
use super::workspace::triangle_f64;
use crate::geometry::closest_point_on_triangle;

/// The point of a mesh's surface closest to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// The closest point, in the mesh's own frame.
    pub point: Vec3,
    /// The triangle it lies on.
    pub triangle: u32,
    /// Its distance from the query point (computed in `f64`).
    pub distance: f32,
}

/// The point of `mesh`'s surface closest to `point` (both in the mesh's own frame), or `None`
/// when `point` is not finite. Exact up to `f64` rounding of the closest-point computation;
/// nodes whose boxes are farther than the best distance so far are skipped, the nearer child
/// first.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::bvh::closest_surface_point;
/// let cube = CollisionMesh::new(generate::cuboid(Vec3::ONE, 2));
/// let near = closest_surface_point(&cube, Vec3::new(0.2, 0.9, 0.1)).unwrap();
/// assert!((near.distance - 0.1).abs() < 1e-6);
/// assert!((near.point - Vec3::new(0.2, 1.0, 0.1)).length() < 1e-6);
/// ```
pub fn closest_surface_point(mesh: &CollisionMesh, point: Vec3) -> Option<SurfacePoint> {
    if !point.is_finite() {
        return None;
    }
    let p = point.as_dvec3();
    let bvh = mesh.bvh();
    let nodes = bvh.nodes();
    let (positions, triangles) = (mesh.mesh().positions(), mesh.mesh().triangles());
    let box_distance_sq = |i: u32| {
        let n = &nodes[i as usize];
        let d = (n.min.as_dvec3() - p)
            .max(p - n.max.as_dvec3())
            .max(DVec3::ZERO);
        d.length_squared()
    };
    let mut best_sq = f64::INFINITY;
    let mut best: Option<(DVec3, u32)> = None;
    let mut stack: smallvec::SmallVec<[(u32, f64); 64]> =
        smallvec::smallvec![(0, box_distance_sq(0))];
    while let Some((i, bound)) = stack.pop() {
        if bound > best_sq {
            continue;
        }
        let n = &nodes[i as usize];
        if n.is_leaf() {
            for &t in bvh.triangles_of(n) {
                let tri = triangle_f64(triangles[t as usize], positions);
                let q = closest_point_on_triangle(p, &tri);
                let d = q.distance_squared(p);
                if d < best_sq || best.is_none() {
                    best_sq = d;
                    best = Some((q, t));
                }
            }
            continue;
        }
        let l = n.left();
        let (dl, dr) = (box_distance_sq(l), box_distance_sq(l + 1));
        // The nearer child is popped first.
        let (first, second) = if dl <= dr {
            ((l, dl), (l + 1, dr))
        } else {
            ((l + 1, dr), (l, dl))
        };
        for (child, d) in [second, first] {
            if d <= best_sq {
                stack.push((child, d));
            }
        }
    }
    let (q, triangle) = best?;
    Some(SurfacePoint {
        point: q.as_vec3(),
        triangle,
        distance: q.distance(p) as f32,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use rand::{RngExt, SeedableRng};

    /// The branch and bound finds the brute-force closest point (every triangle) for points
    /// inside, on and outside a ball and a torus.
    #[test]
    fn matches_brute_force() {
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(3);
        for mesh in [
            generate::icosphere(0.7, 2),
            generate::torus(1.0, 0.3, 24, 12),
        ] {
            let cm = CollisionMesh::new(mesh.clone());
            for _ in 0..300 {
                let p = Vec3::new(
                    rng.random_range(-1.6..1.6),
                    rng.random_range(-1.6..1.6),
                    rng.random_range(-1.6..1.6),
                );
                let got = closest_surface_point(&cm, p).unwrap();
                let brute = (0..mesh.triangle_count())
                    .map(|t| {
                        let tri = mesh.triangle(t).map(|c| c.as_dvec3());
                        closest_point_on_triangle(p.as_dvec3(), &tri).distance(p.as_dvec3())
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    (f64::from(got.distance) - brute).abs() <= 1e-6,
                    "{p}: {got:?} {brute}"
                );
                let tri = mesh.triangle(got.triangle as usize).map(|c| c.as_dvec3());
                let on = closest_point_on_triangle(got.point.as_dvec3(), &tri);
                assert!(
                    on.distance(got.point.as_dvec3()) < 1e-5,
                    "the point lies on its triangle"
                );
            }
        }
        let cm = CollisionMesh::new(generate::icosphere(1.0, 1));
        assert!(closest_surface_point(&cm, Vec3::NAN).is_none());
    }
}

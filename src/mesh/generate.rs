//! Mesh generators for tests and examples.
//!
//! Every generator welds its seams (no two vertices share a position), so closed shapes are
//! closed by index ([`Topology::is_closed`](super::Topology::is_closed)), and orients every
//! triangle counter-clockwise seen from outside (normals `(b − a) × (c − a)` point out; open
//! surfaces face +Y or away from their axis). Segment counts below a shape's minimum are raised
//! to it rather than refused; negative sizes are taken as their absolute value.
//!
//! # Panics
//! Every generator panics if a size is NaN or infinite (the mesh would not be valid).
//!
//! Next: [`crate::bvh::CollisionMesh`] turns a generated mesh into a collider of the exact
//! queries, [`crate::ecs::MeshCollider`] into a collider of the plugin.

mod random_shapes;

use std::collections::HashMap;
use std::f32::consts::TAU;

use glam::Vec3;

use super::TriMesh;
pub use random_shapes::{noisy_sphere, random_tube};

/// Highest subdivision level [`icosphere`] accepts (20·4¹⁰ ≈ 21 million triangles); higher
/// levels are lowered to it.
pub const MAX_ICOSPHERE_SUBDIVISIONS: u32 = 10;

fn build(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>, what: &str) -> TriMesh {
    match TriMesh::new(positions, triangles) {
        Ok(mesh) => mesh,
        Err(e) => panic!("generate::{what}: {e} (sizes must be finite)"),
    }
}

/// A sphere of `radius` around the origin: a regular icosahedron whose triangles are split
/// `subdivisions` times into four, new vertices pushed out onto the sphere.
///
/// `20·4^s` triangles and `10·4^s + 2` vertices, all at distance `radius` from the origin;
/// closed, genus 0. `subdivisions` above [`MAX_ICOSPHERE_SUBDIVISIONS`] is lowered to it.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::generate;
/// let sphere = generate::icosphere(2.0, 2);
/// assert_eq!(sphere.triangle_count(), 320);
/// assert_eq!(sphere.vertex_count(), 162);
/// assert!(sphere.is_closed());
/// assert!(sphere.positions().iter().all(|p| (p.length() - 2.0).abs() < 1e-5));
/// ```
pub fn icosphere(radius: f32, subdivisions: u32) -> TriMesh {
    let radius = radius.abs();
    let subdivisions = subdivisions.min(MAX_ICOSPHERE_SUBDIVISIONS);
    let t = (1.0 + 5.0f32.sqrt()) / 2.0;
    let mut unit: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .into_iter()
    .map(|p| Vec3::from_array(p).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> =
            HashMap::with_capacity(triangles.len() * 3 / 2);
        let mut next = Vec::with_capacity(triangles.len() * 4);
        let mut midpoint = |a: u32, b: u32, unit: &mut Vec<Vec3>| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                unit.push((unit[a as usize] + unit[b as usize]).normalize());
                (unit.len() - 1) as u32
            })
        };
        for &[a, b, c] in &triangles {
            let ab = midpoint(a, b, &mut unit);
            let bc = midpoint(b, c, &mut unit);
            let ca = midpoint(c, a, &mut unit);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    let positions = unit.into_iter().map(|p| p * radius).collect();
    build(positions, triangles, "icosphere")
}

/// A torus around the Y axis: a circle of `minor_radius` swept around a circle of
/// `major_radius` in the XZ plane.
///
/// `2·M·N` triangles and `M·N` vertices for `M = major_segments` (at least 3) and
/// `N = minor_segments` (at least 3); closed, genus 1. Meant for `major_radius > minor_radius`
/// (otherwise the surface passes through itself).
///
/// # Example
/// ```
/// use stochastic_collision::mesh::generate;
/// let ring = generate::torus(1.0, 0.25, 32, 12);
/// assert_eq!(ring.triangle_count(), 2 * 32 * 12);
/// assert_eq!(ring.vertex_count(), 32 * 12);
/// assert!(ring.is_closed());
/// // Segment counts are clamped to at least 3.
/// assert_eq!(generate::torus(1.0, 0.25, 0, 1).vertex_count(), 9);
/// ```
pub fn torus(
    major_radius: f32,
    minor_radius: f32,
    major_segments: u32,
    minor_segments: u32,
) -> TriMesh {
    let (big, small) = (major_radius.abs(), minor_radius.abs());
    let (m, n) = (major_segments.max(3), minor_segments.max(3));
    let mut positions = Vec::with_capacity((m * n) as usize);
    for i in 0..m {
        let (sin_t, cos_t) = (TAU * i as f32 / m as f32).sin_cos();
        for j in 0..n {
            let (sin_p, cos_p) = (TAU * j as f32 / n as f32).sin_cos();
            let r = big + small * cos_p;
            positions.push(Vec3::new(r * cos_t, small * sin_p, r * sin_t));
        }
    }
    let index = |i: u32, j: u32| (i % m) * n + (j % n);
    let mut triangles = Vec::with_capacity((2 * m * n) as usize);
    for i in 0..m {
        for j in 0..n {
            let (a, b, c, d) = (
                index(i, j),
                index(i, j + 1),
                index(i + 1, j + 1),
                index(i + 1, j),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    build(positions, triangles, "torus")
}

/// An axis-aligned box from `-half_extents` to `half_extents`, each face split into a grid of
/// `(s + 1) × (s + 1)` squares (`s = subdivisions`) of two triangles each.
///
/// `12·(s + 1)²` triangles and `6·(s + 1)² + 2` vertices, welded along the box's edges;
/// closed, genus 0.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::generate;
/// use glam::Vec3;
/// let cube = generate::cuboid(Vec3::new(1.0, 2.0, 3.0), 0);
/// assert_eq!(cube.triangle_count(), 12);
/// assert_eq!(cube.vertex_count(), 8);
/// let fine = generate::cuboid(Vec3::ONE, 3);
/// assert_eq!(fine.triangle_count(), 12 * 16);
/// assert!(fine.is_closed());
/// ```
pub fn cuboid(half_extents: Vec3, subdivisions: u32) -> TriMesh {
    let h = half_extents.abs();
    let n = subdivisions.saturating_add(1) as usize;
    let side = n + 1;
    // Lattice points (i, j, k) in 0..=n on the surface get vertices, created on first use.
    let mut ids = HashMap::with_capacity(6 * side * side);
    let mut positions = Vec::with_capacity(6 * n * n + 2);
    let mut vertex = |p: [usize; 3], positions: &mut Vec<Vec3>| -> u32 {
        *ids.entry(p).or_insert_with(|| {
            let f = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / n as f32;
            positions.push(-h + 2.0 * h * f);
            (positions.len() - 1) as u32
        })
    };
    let mut triangles = Vec::with_capacity(12 * n * n);
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for positive in [false, true] {
            for a in 0..n {
                for b in 0..n {
                    let corner = |da: usize, db: usize| {
                        let mut p = [0; 3];
                        p[axis] = if positive { n } else { 0 };
                        p[u] = a + da;
                        p[v] = b + db;
                        p
                    };
                    let q = [
                        vertex(corner(0, 0), &mut positions),
                        vertex(corner(1, 0), &mut positions),
                        vertex(corner(1, 1), &mut positions),
                        vertex(corner(0, 1), &mut positions),
                    ];
                    // e_u × e_v = e_axis: counter-clockwise seen from +axis.
                    if positive {
                        triangles.push([q[0], q[1], q[2]]);
                        triangles.push([q[0], q[2], q[3]]);
                    } else {
                        triangles.push([q[0], q[2], q[1]]);
                        triangles.push([q[0], q[3], q[2]]);
                    }
                }
            }
        }
    }
    build(positions, triangles, "cuboid")
}

/// An open, flat grid in the `y = 0` plane centred on the origin, `width` along X and `depth`
/// along Z, of `nx × nz` rectangles (each at least 1) split into two triangles; facing +Y.
///
/// `2·nx·nz` triangles, `(nx + 1)·(nz + 1)` vertices (row by row: vertex `i + j·(nx + 1)`
/// is at column `i` along X, row `j` along Z), `2·(nx + nz)` boundary edges. A cloth.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::{Topology, generate};
/// let cloth = generate::cloth_grid(1.0, 1.0, 50, 50);
/// assert_eq!(cloth.triangle_count(), 5000);
/// assert_eq!(cloth.vertex_count(), 51 * 51);
/// assert_eq!(Topology::new(&cloth).boundary_edge_count(), 200);
/// ```
pub fn cloth_grid(width: f32, depth: f32, nx: u32, nz: u32) -> TriMesh {
    let (w, d) = (width.abs(), depth.abs());
    let (nx, nz) = (nx.max(1), nz.max(1));
    let row = nx + 1;
    let mut positions = Vec::with_capacity((row * (nz + 1)) as usize);
    for j in 0..=nz {
        let z = d * (j as f32 / nz as f32 - 0.5);
        for i in 0..=nx {
            let x = w * (i as f32 / nx as f32 - 0.5);
            positions.push(Vec3::new(x, 0.0, z));
        }
    }
    let mut triangles = Vec::with_capacity((2 * nx * nz) as usize);
    for j in 0..nz {
        for i in 0..nx {
            let a = i + j * row; // (x, z)
            let (b, c, e) = (a + row, a + row + 1, a + 1); // (x, z+1), (x+1, z+1), (x+1, z)
            // e_z × e_x = +Y.
            triangles.push([a, b, c]);
            triangles.push([a, c, e]);
        }
    }
    build(positions, triangles, "cloth_grid")
}

/// A cylindrical tube of `radius` along the Y axis, from `y = -length/2` to `length/2`, of
/// `radial_segments` (at least 3) around and `length_segments` (at least 1) along.
///
/// Open at both ends unless `capped`, in which case each end is closed by a fan around a centre
/// vertex (the last two vertices: bottom, then top). With `R` radial and `L` length segments:
/// `2·R·L` triangles (`+ 2·R` capped) and `R·(L + 1)` vertices (`+ 2` capped); open, it has
/// `2·R` boundary edges and Euler characteristic 0, capped it is closed with genus 0.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::generate;
/// let open = generate::tube(0.5, 2.0, 16, 4, false);
/// assert_eq!(open.triangle_count(), 2 * 16 * 4);
/// assert!(!open.is_closed());
/// let capped = generate::tube(0.5, 2.0, 16, 4, true);
/// assert_eq!(capped.triangle_count(), 2 * 16 * 4 + 2 * 16);
/// assert!(capped.is_closed());
/// ```
pub fn tube(
    radius: f32,
    length: f32,
    radial_segments: u32,
    length_segments: u32,
    capped: bool,
) -> TriMesh {
    let (r, len) = (radius.abs(), length.abs());
    let (rs, ls) = (radial_segments.max(3), length_segments.max(1));
    let mut positions = Vec::with_capacity((rs * (ls + 1) + 2) as usize);
    for k in 0..=ls {
        let y = len * (k as f32 / ls as f32 - 0.5);
        for j in 0..rs {
            let (sin, cos) = (TAU * j as f32 / rs as f32).sin_cos();
            positions.push(Vec3::new(r * cos, y, r * sin));
        }
    }
    let index = |k: u32, j: u32| k * rs + j % rs;
    let mut triangles = Vec::with_capacity((2 * rs * ls + 2 * rs) as usize);
    for k in 0..ls {
        for j in 0..rs {
            // ∂y × ∂θ points away from the axis.
            let (a, b, c, d) = (
                index(k, j),
                index(k + 1, j),
                index(k + 1, j + 1),
                index(k, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    if capped {
        let bottom = positions.len() as u32;
        positions.push(Vec3::new(0.0, -len / 2.0, 0.0));
        let top = bottom + 1;
        positions.push(Vec3::new(0.0, len / 2.0, 0.0));
        for j in 0..rs {
            triangles.push([bottom, index(0, j), index(0, j + 1)]);
            triangles.push([top, index(ls, j + 1), index(ls, j)]);
        }
    }
    build(positions, triangles, "tube")
}

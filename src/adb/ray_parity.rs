//! Exact ray parity on a voxel grid: for every voxel, whether the axis-aligned ray through
//! the centres of its row crosses a mesh's surface an odd number of times below the voxel's
//! centre, one bit per axis. The ground of the [`InteriorMap`](super::InteriorMap)'s inside
//! and outside.
//!
//! Whether a ray passes through a triangle is decided exactly: orientation in the plane
//! across the ray with [`robust::orient2d`], and a ray that runs exactly through an edge or a
//! vertex is counted as if moved by an infinitesimal `(ε, ε²)` in that plane (simulation of
//! simplicity). The moved ray passes through no edge and no vertex, and through a
//! triangle seen edge-on never, so along it every crossing is counted once: where every edge
//! of the mesh is used by an even number of triangles, its parity is the parity of the
//! surface at every point off the surface, whatever the mesh's alignment with the grid.
use glam::DVec3;
use robust::{Coord, orient2d};

use super::voxel_grid::VoxelGrid;
use crate::mesh::TriMesh;

/// Rows (in row units) by which a triangle's box is widened before rows are tested exactly.
const ROW_SLACK: f64 = 1e-6;

/// A triangle's edges as vertex pairs, each opposite the vertex of the same index.
const EDGES: [(usize, usize); 3] = [(1, 2), (2, 0), (0, 1)];

/// For every voxel of `grid`, bit `axis` set when the ray along `axis` through the voxel
/// centres of its row crosses `mesh` an odd number of times below the voxel's centre (see the
/// module documentation). A voxel whose centre is within rounding of the surface may get
/// either bit; [`VoxelGrid::surface_voxels`] marks every such voxel.
pub(super) fn odd_parity(grid: &VoxelGrid, mesh: &TriMesh) -> Vec<u8> {
    let mut odd = vec![0u8; grid.voxels()];
    if odd.is_empty() {
        return odd;
    }
    for axis in 0..3 {
        axis_parity(grid, mesh, axis, &mut odd);
    }
    odd
}

/// Sets bit `axis` of `odd` for every voxel with an odd number of crossings below its centre
/// along `axis`.
fn axis_parity(grid: &VoxelGrid, mesh: &TriMesh, axis: usize, odd: &mut [u8]) {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let dims = grid.dims.map(|d| d as usize);
    let origin = grid.origin.as_dvec3();
    let cell = f64::from(grid.cell);
    let row_centre = |i: usize, k: usize| origin[k] + (i as f64 + 0.5) * cell;
    // (row, coordinate along the axis) of every crossing.
    let mut crossings: Vec<(u32, f64)> = Vec::new();
    for t in 0..mesh.triangle_count() {
        let tri: [DVec3; 3] = mesh.triangle(t).map(|p| p.as_dvec3());
        let flat = tri.map(|p| Coord { x: p[u], y: p[v] });
        let area = orient2d(flat[0], flat[1], flat[2]);
        if area == 0.0 || !area.is_finite() {
            // Seen edge-on (or degenerate): the moved ray never passes through it.
            continue;
        }
        let (min_u, max_u) = min_max(tri.map(|p| p[u]));
        let (min_v, max_v) = min_max(tri.map(|p| p[v]));
        // The rows whose centres may lie in the triangle's box, widened by far more than the
        // rounding of the division (at most a few units in the last place of a row index
        // below 2^11): the exact test below decides.
        let first = |min: f64, k: usize| {
            (((min - origin[k]) / cell - 0.5 - ROW_SLACK).ceil()).clamp(0.0, dims[k] as f64)
                as usize
        };
        let last = |max: f64, k: usize| {
            (((max - origin[k]) / cell - 0.5 + ROW_SLACK).floor()).clamp(-1.0, dims[k] as f64 - 1.0)
        };
        let (u0, u1) = (first(min_u, u), last(max_u, u));
        let (v0, v1) = (first(min_v, v), last(max_v, v));
        if u1 < u0 as f64 || v1 < v0 as f64 {
            continue;
        }
        let positive = area > 0.0;
        let (lo, hi) = min_max(tri.map(|p| p[axis]));
        for iu in u0..=u1 as usize {
            for iv in v0..=v1 as usize {
                let p = Coord {
                    x: row_centre(iu, u),
                    y: row_centre(iv, v),
                };
                let w = EDGES.map(|(q, r)| orient2d(p, flat[q], flat[r]));
                let inside = w.iter().zip(EDGES).all(|(&w, (q, r))| {
                    moved_orientation_is_positive(w, flat[q], flat[r]) == positive
                });
                if inside {
                    let weights = w.map(f64::abs);
                    let total: f64 = weights.iter().sum();
                    let along = (weights[0] * tri[0][axis]
                        + weights[1] * tri[1][axis]
                        + weights[2] * tri[2][axis])
                        / total;
                    crossings.push(((iu * dims[v] + iv) as u32, along.clamp(lo, hi)));
                }
            }
        }
    }
    crossings.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
    let strides = [1, dims[0], dims[0] * dims[1]];
    let bit = 1u8 << axis;
    let mut start = 0;
    while start < crossings.len() {
        let row = crossings[start].0;
        let end = start + crossings[start..].partition_point(|c| c.0 == row);
        let (iu, iv) = (row as usize / dims[v], row as usize % dims[v]);
        let base = iu * strides[u] + iv * strides[v];
        let mut below = start;
        for i in 0..dims[axis] {
            let centre = row_centre(i, axis);
            while below < end && crossings[below].1 < centre {
                below += 1;
            }
            if (below - start) % 2 == 1 {
                odd[base + i * strides[axis]] |= bit;
            }
        }
        start = end;
    }
}

/// The sign of the orientation of `(p + (ε, ε²), q, r)` for an infinitesimal `ε`, given
/// `orientation`, the exact sign of `(p, q, r)`: the orientation is linear in `p`, with
/// gradient `(q.y − r.y, r.x − q.x)`, so where `p` lies on the line through `q` and `r` the
/// first non-zero of those decides. `q ≠ r` (the triangle is not seen edge-on), so one is.
#[inline]
fn moved_orientation_is_positive(orientation: f64, q: Coord<f64>, r: Coord<f64>) -> bool {
    if orientation != 0.0 {
        orientation > 0.0
    } else if q.y != r.y {
        // The sign of a difference of two floats is exact.
        q.y > r.y
    } else {
        r.x > q.x
    }
}

fn min_max(x: [f64; 3]) -> (f64, f64) {
    (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{CollisionMesh, contains_point};
    use crate::mesh::generate;
    use glam::Vec3;
    use proptest::prelude::*;

    /// A grid of `n³` unit voxels from the origin: voxel centres at half-integers, which
    /// meshes with half-integer vertices hit exactly.
    fn unit_grid(n: u32) -> VoxelGrid {
        VoxelGrid {
            origin: Vec3::ZERO,
            cell: 1.0,
            inv_cell: 1.0,
            dims: [n; 3],
        }
    }

    /// `mesh` with every vertex moved by `offset`.
    fn moved(mesh: &TriMesh, offset: Vec3) -> TriMesh {
        mesh.translated(offset).expect("finite offset")
    }

    /// The union of meshes' triangle lists (no welding).
    fn merged(parts: &[TriMesh]) -> TriMesh {
        TriMesh::merged(parts).expect("valid parts")
    }

    /// A closed octahedron around `centre` with vertices `radius` away along the axes.
    fn octahedron(centre: Vec3, radius: f32) -> TriMesh {
        let mut positions = Vec::new();
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            positions.push(centre + axis * radius);
            positions.push(centre - axis * radius);
        }
        // Vertices +x 0, -x 1, +y 2, -y 3, +z 4, -z 5; outward faces.
        let triangles = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        TriMesh::new(positions, triangles).expect("valid mesh")
    }

    /// Every voxel no triangle comes near has all three parity bits equal to the exact
    /// inside of its centre; returns how many voxels were checked, and how many inside.
    fn check(grid: &VoxelGrid, mesh: &TriMesh) -> (usize, usize) {
        let odd = odd_parity(grid, mesh);
        let surface = grid.surface_voxels(mesh);
        let reference = CollisionMesh::new(mesh.clone());
        let [nx, ny, nz] = grid.dims;
        let (mut checked, mut inside) = (0, 0);
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let i = grid.index(x, y, z);
                    if surface[i] {
                        continue;
                    }
                    let centre =
                        grid.origin + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * grid.cell;
                    let truth = contains_point(&reference, centre);
                    let expected = if truth { 0b111 } else { 0 };
                    assert_eq!(odd[i], expected, "voxel ({x}, {y}, {z}) at {centre}");
                    checked += 1;
                    inside += usize::from(truth);
                }
            }
        }
        (checked, inside)
    }

    /// Boxes whose faces lie on the planes of voxel centres and whose face diagonals and
    /// edges run through voxel centres, every subdivision; an octahedron whose vertices are
    /// voxel centres and whose edges run through the centres' diagonals; a box nested in a
    /// box; overlapping parts. The rays through those centres meet edges and vertices
    /// exactly, and the parity is still the exact one.
    #[test]
    fn parity_is_exact_where_rays_run_through_edges_and_vertices() {
        let grid = unit_grid(12);
        let mut shapes = Vec::new();
        for subdivisions in 0..4 {
            // Half extents 3 and 4 around half-integer and integer centres.
            for (half, centre) in [(3.0, 5.5), (4.0, 6.0), (2.5, 6.0)] {
                shapes.push(moved(
                    &generate::cuboid(Vec3::splat(half), subdivisions),
                    Vec3::splat(centre),
                ));
            }
        }
        shapes.push(octahedron(Vec3::splat(5.5), 4.0));
        shapes.push(octahedron(Vec3::new(6.0, 5.5, 6.0), 3.0));
        shapes.push(merged(&[
            moved(&generate::cuboid(Vec3::splat(5.0), 0), Vec3::splat(6.0)),
            moved(&generate::cuboid(Vec3::splat(1.0), 2), Vec3::splat(6.5)),
        ]));
        shapes.push(merged(&[
            moved(&generate::cuboid(Vec3::splat(2.0), 1), Vec3::splat(4.5)),
            octahedron(Vec3::splat(6.5), 3.0),
        ]));
        for (k, shape) in shapes.iter().enumerate() {
            let (checked, inside) = check(&grid, shape);
            assert!(
                inside > 0 && checked > inside,
                "shape {k}: {inside} of {checked}"
            );
        }
    }

    /// Two triangles sharing an edge that a point lies exactly on: the moved point is in
    /// exactly one of them, whichever way round the edge is walked; a point on a vertex shared
    /// by a fan of triangles around it is in exactly one of the fan.
    #[test]
    fn a_point_on_a_shared_edge_or_vertex_is_in_exactly_one_triangle() {
        let c = |x: f64, y: f64| Coord { x, y };
        let inside = |p: Coord<f64>, t: [Coord<f64>; 3]| {
            let area = orient2d(t[0], t[1], t[2]);
            let w = [
                orient2d(p, t[1], t[2]),
                orient2d(p, t[2], t[0]),
                orient2d(p, t[0], t[1]),
            ];
            w.iter()
                .zip([(1, 2), (2, 0), (0, 1)])
                .all(|(&w, (q, r))| moved_orientation_is_positive(w, t[q], t[r]) == (area > 0.0))
        };
        // A fan of eight triangles around the origin, both windings.
        let ring: Vec<Coord<f64>> = (0..8)
            .map(|k| {
                let a = k as f64 * std::f64::consts::FRAC_PI_4;
                c(a.cos().round(), a.sin().round())
            })
            .collect();
        for clockwise in [false, true] {
            let fan: Vec<[Coord<f64>; 3]> = (0..8)
                .map(|k| {
                    let (a, b) = (ring[k], ring[(k + 1) % 8]);
                    if clockwise {
                        [c(0.0, 0.0), b, a]
                    } else {
                        [c(0.0, 0.0), a, b]
                    }
                })
                .collect();
            // The centre, points on the spokes, and midpoints of the rim.
            let mut points = vec![c(0.0, 0.0)];
            points.extend(ring.iter().map(|p| c(p.x * 0.5, p.y * 0.5)));
            for p in points {
                let hits = fan.iter().filter(|&&t| inside(p, t)).count();
                assert_eq!(hits, 1, "({}, {}) clockwise {clockwise}", p.x, p.y);
            }
        }
    }

    /// A closed shape of boxes and octahedra with vertices on a lattice of quarter voxels
    /// (so on voxel-centre rays, planes and diagonals far more often than by chance).
    fn lattice_shape() -> impl Strategy<Value = TriMesh> {
        let part = (0u32..3, 0u32..3, (8i32..40, 8i32..40, 8i32..40), 2i32..16);
        proptest::collection::vec(part, 1..4).prop_map(|parts| {
            let meshes: Vec<TriMesh> = parts
                .into_iter()
                .map(|(kind, subdivisions, (x, y, z), size)| {
                    let centre = Vec3::new(x as f32, y as f32, z as f32) * 0.25;
                    let half = size as f32 * 0.25;
                    if kind == 0 {
                        octahedron(centre, half)
                    } else {
                        let extents = Vec3::new(half, half * 0.5 + 0.25, half);
                        moved(&generate::cuboid(extents, subdivisions), centre)
                    }
                })
                .collect();
            merged(&meshes)
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

        /// Against exact point-in-mesh parity at every classified voxel centre, on shapes
        /// laid out on the grid's lattice.
        #[test]
        fn parity_equals_exact_point_in_mesh_on_lattice_shapes(shape in lattice_shape()) {
            check(&unit_grid(14), &shape);
        }
    }
}

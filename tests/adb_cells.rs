//! Well-filled cell counts for ADB-tree nodes (`adb::cells`).
//!
//! * The clipped areas are checked against independent references. Per cell, the reference
//!   is a plain Sutherland–Hodgman clip of the triangle against the cell's six planes. Per box,
//!   it is a clip against the box's six planes. A third check samples the triangle's barycentric
//!   domain densely and counts the samples per cell.
//! * Half-open cells: polygons lying in a grid plane, on the box's faces or along grid lines
//!   are counted exactly once.
//! * `MaxArea`: a cell's diagonal rectangle fills it; a slightly smaller rectangle, or an
//!   axis-aligned square the size of a face, does not.
//! * Flat boxes, degenerate triangles, far offsets and extreme power-of-two scales.
//! * Scratch reuse: repeatable counts, and no allocation after warm-up.
//!
//! `per_triangle_cost` (ignored) times `accumulate_triangle` and a whole-tree count. Run it
//! with `cargo test --release --test adb_cells -- --ignored --nocapture`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::time::{Duration, Instant};

use glam::{DVec3, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::adb::cells::{
    CellGrid, CellScratch, accumulate_triangle, count_well_filled, max_cell_area,
};
use stochastic_collision::geometry::Aabb;

// ---------------------------------------------------------------------------------------------
// Allocation counting, per thread, so that tests running in parallel do not interfere.

struct CountingAlloc;

thread_local! {
    static ALLOCS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

fn allocations() -> usize {
    ALLOCS.with(Cell::get)
}

// ---------------------------------------------------------------------------------------------
// Independent references.

type Tri = [Vec3; 3];

fn v3(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

fn tri_area(t: Tri) -> f64 {
    let d = t.map(|v| v.as_dvec3());
    0.5 * (d[1] - d[0]).cross(d[2] - d[0]).length()
}

/// Newell's formula: the area of a planar polygon.
fn polygon_area(p: &[DVec3]) -> f64 {
    if p.len() < 3 {
        return 0.0;
    }
    let mut n = DVec3::ZERO;
    for i in 0..p.len() {
        let (a, b) = (p[i] - p[0], p[(i + 1) % p.len()] - p[0]);
        n += a.cross(b);
    }
    0.5 * n.length()
}

/// Textbook Sutherland–Hodgman against the closed box `[lo, hi]`.
fn clip_to_box(t: Tri, lo: DVec3, hi: DVec3) -> Vec<DVec3> {
    let mut poly: Vec<DVec3> = t.iter().map(|v| v.as_dvec3()).collect();
    for axis in 0..3 {
        for (plane, sign) in [(lo[axis], 1.0), (hi[axis], -1.0)] {
            let mut out = Vec::new();
            for i in 0..poly.len() {
                let a = poly[i];
                let b = poly[(i + 1) % poly.len()];
                let da = sign * (a[axis] - plane);
                let db = sign * (b[axis] - plane);
                if da >= 0.0 {
                    out.push(a);
                }
                if (da >= 0.0) != (db >= 0.0) {
                    out.push(a + (b - a) * (da / (da - db)));
                }
            }
            poly = out;
            if poly.is_empty() {
                return poly;
            }
        }
    }
    poly
}

fn cell_box(bounds: Aabb, n: u32, i: u32, j: u32, k: u32) -> (DVec3, DVec3) {
    let (min, ext) = (bounds.min.as_dvec3(), bounds.extents().as_dvec3());
    let nf = f64::from(n);
    let at = |c: [u32; 3]| min + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * ext / nf;
    (at([i, j, k]), at([i + 1, j + 1, k + 1]))
}

fn areas_of(grid: &CellGrid, tris: &[Tri]) -> Vec<f64> {
    let mut areas = vec![0.0; grid.cell_count()];
    for t in tris {
        accumulate_triangle(grid, *t, &mut areas);
    }
    areas
}

fn cells(n: u32) -> impl Iterator<Item = (u32, u32, u32)> {
    (0..n).flat_map(move |i| (0..n).flat_map(move |j| (0..n).map(move |k| (i, j, k))))
}

fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

fn random_box(r: &mut Xoshiro256PlusPlus) -> Aabb {
    let min = v3(
        r.random_range(-3.0..3.0),
        r.random_range(-3.0..3.0),
        r.random_range(-3.0..3.0),
    );
    let ext = v3(
        r.random_range(0.2..4.0),
        r.random_range(0.2..4.0),
        r.random_range(0.2..4.0),
    );
    Aabb::new(min, min + ext)
}

/// A random point in `b` grown by `grow` times its extents on every side.
fn point_around(r: &mut Xoshiro256PlusPlus, b: Aabb, grow: f32) -> Vec3 {
    let e = b.extents();
    let lo = b.min - e * grow;
    let hi = b.max + e * grow;
    v3(
        r.random_range(lo.x..=hi.x),
        r.random_range(lo.y..=hi.y),
        r.random_range(lo.z..=hi.z),
    )
}

// ---------------------------------------------------------------------------------------------
// Areas against the references.

#[test]
fn areas_match_independent_box_and_cell_clips() {
    let mut r = rng(1);
    for case in 0..300 {
        let bounds = random_box(&mut r);
        let n = [1, 2, 3, 4, 5, 7, 16][case % 7];
        let grid = CellGrid::new(bounds, n);
        let grow = if case % 3 == 0 { 0.0 } else { 0.6 };
        let t: Tri = [0; 3].map(|_| point_around(&mut r, bounds, grow));
        let areas = areas_of(&grid, &[t]);
        assert!(areas.iter().all(|a| a.is_finite() && *a >= 0.0));
        let total: f64 = areas.iter().sum();
        let (lo, hi) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
        let want = if grow == 0.0 {
            tri_area(t)
        } else {
            polygon_area(&clip_to_box(t, lo, hi))
        };
        let tol = 1e-9 * want + 1e-13 * tri_area(t);
        assert!(
            (total - want).abs() <= tol,
            "case {case}: cells sum to {total}, box clip gives {want}"
        );
        if n <= 7 {
            for (i, j, k) in cells(n) {
                let (clo, chi) = cell_box(bounds, n, i, j, k);
                let want = polygon_area(&clip_to_box(t, clo, chi));
                let got = areas[grid.cell_index(i, j, k)];
                assert!(
                    (got - want).abs() <= 1e-9 * want + 1e-12 * tri_area(t),
                    "case {case}: cell ({i},{j},{k}) has {got}, clip gives {want}"
                );
            }
        }
    }
}

#[test]
fn cell_areas_match_barycentric_sampling() {
    const M: usize = 160;
    let mut r = rng(2);
    for n in [1, 2, 3, 4, 7] {
        for _ in 0..3 {
            let bounds = random_box(&mut r);
            let grid = CellGrid::new(bounds, n);
            let t: Tri = [0; 3].map(|_| point_around(&mut r, bounds, 0.3));
            let area = tri_area(t);
            let areas = areas_of(&grid, &[t]);
            // M² equal sub-triangles; sample each at its centroid.
            let mut hits = vec![0usize; grid.cell_count()];
            let d = t.map(|v| v.as_dvec3());
            let (min, ext) = (bounds.min.as_dvec3(), bounds.extents().as_dvec3());
            let mut sample = |a: f64, b: f64| {
                let p = d[0] + (d[1] - d[0]) * a + (d[2] - d[0]) * b;
                let rel = (p - min) / ext * f64::from(n);
                if rel.min_element() < 0.0 || rel.max_element() > f64::from(n) {
                    return;
                }
                let c = rel.as_uvec3().min(glam::UVec3::splat(n - 1));
                hits[grid.cell_index(c.x, c.y, c.z)] += 1;
            };
            let m = M as f64;
            for i in 0..M {
                for j in 0..M - i {
                    sample((i as f64 + 1.0 / 3.0) / m, (j as f64 + 1.0 / 3.0) / m);
                    if i + j + 1 < M {
                        sample((i as f64 + 2.0 / 3.0) / m, (j as f64 + 2.0 / 3.0) / m);
                    }
                }
            }
            for (c, (&got, &h)) in areas.iter().zip(&hits).enumerate() {
                let est = h as f64 / (m * m) * area;
                assert!(
                    (got - est).abs() <= 0.005 * area,
                    "n = {n}, cell {c}: clipped {got}, sampled {est} (triangle area {area})"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Half-open cells.

fn grid4() -> CellGrid {
    CellGrid::new(Aabb::new(Vec3::ZERO, Vec3::splat(4.0)), 4)
}

/// The cells with positive area, as `((i, j, k), area)`.
fn filled(grid: &CellGrid, tris: &[Tri]) -> Vec<((u32, u32, u32), f64)> {
    let areas = areas_of(grid, tris);
    cells(grid.resolution())
        .map(|c| (c, areas[grid.cell_index(c.0, c.1, c.2)]))
        .filter(|(_, a)| *a > 0.0)
        .collect()
}

#[test]
fn triangle_in_a_grid_plane_goes_to_the_layer_above() {
    let g = grid4();
    let t = [
        v3(2.0, 0.25, 0.25),
        v3(2.0, 0.75, 0.25),
        v3(2.0, 0.25, 0.75),
    ];
    assert_eq!(filled(&g, &[t]), vec![((2, 0, 0), 0.125)]);
    // A square covering the whole plane x = 2: every cell of layer 2 gets area 1, layer 1 none.
    let sq = [
        [v3(2.0, 0.0, 0.0), v3(2.0, 4.0, 0.0), v3(2.0, 4.0, 4.0)],
        [v3(2.0, 0.0, 0.0), v3(2.0, 4.0, 4.0), v3(2.0, 0.0, 4.0)],
    ];
    let f = filled(&g, &sq);
    assert_eq!(f.len(), 16);
    for ((i, _, _), a) in f {
        assert_eq!(i, 2);
        assert!((a - 1.0).abs() < 1e-12);
    }
    // The same in y and z.
    let ty = [
        v3(0.25, 3.0, 0.25),
        v3(0.75, 3.0, 0.25),
        v3(0.25, 3.0, 0.75),
    ];
    assert_eq!(filled(&g, &[ty]), vec![((0, 3, 0), 0.125)]);
    let tz = [
        v3(0.25, 0.25, 1.0),
        v3(0.75, 0.25, 1.0),
        v3(0.25, 0.75, 1.0),
    ];
    assert_eq!(filled(&g, &[tz]), vec![((0, 0, 1), 0.125)]);
    // Spanning a grid line inside the plane: split along it, still only in layer 2.
    let wide = [v3(2.0, 0.5, 0.5), v3(2.0, 1.5, 0.5), v3(2.0, 0.5, 1.5)];
    let f = filled(&g, &[wide]);
    assert_eq!(
        f,
        vec![((2, 0, 0), 0.25), ((2, 0, 1), 0.125), ((2, 1, 0), 0.125)]
    );
}

#[test]
fn triangles_on_the_box_faces_are_counted() {
    let g = grid4();
    let max_x = [
        v3(4.0, 0.25, 0.25),
        v3(4.0, 0.75, 0.25),
        v3(4.0, 0.25, 0.75),
    ];
    assert_eq!(filled(&g, &[max_x]), vec![((3, 0, 0), 0.125)]);
    let min_x = [
        v3(0.0, 0.25, 0.25),
        v3(0.0, 0.75, 0.25),
        v3(0.0, 0.25, 0.75),
    ];
    assert_eq!(filled(&g, &[min_x]), vec![((0, 0, 0), 0.125)]);
    let max_z = [
        v3(3.75, 3.75, 4.0),
        v3(3.25, 3.75, 4.0),
        v3(3.75, 3.25, 4.0),
    ];
    assert_eq!(filled(&g, &[max_z]), vec![((3, 3, 3), 0.125)]);
    // In the max-y face with an edge on the box edge y = z = 4: the top corner cell.
    let edge_fold = [v3(3.0, 4.0, 4.0), v3(4.0, 4.0, 4.0), v3(3.5, 4.0, 3.5)];
    assert_eq!(filled(&g, &[edge_fold]), vec![((3, 3, 3), 0.25)]);
    // On the max face but reaching beyond the box: clipped to the unit square, last layer.
    let crossing = [v3(4.0, 3.0, 3.0), v3(4.0, 5.0, 3.0), v3(4.0, 3.0, 5.0)];
    assert_eq!(filled(&g, &[crossing]), vec![((3, 3, 3), 1.0)]);
    // Touching the box only along an edge or at a corner: nothing.
    let edge = [v3(4.0, 1.0, 1.0), v3(4.0, 2.0, 1.0), v3(5.0, 1.0, 1.0)];
    let corner = [v3(4.0, 4.0, 4.0), v3(5.0, 4.0, 4.0), v3(4.0, 5.0, 5.0)];
    assert!(filled(&g, &[edge, corner]).is_empty());
}

#[test]
fn triangles_along_grid_lines() {
    let g = grid4();
    // In the plane z = 2 with an edge on the grid line x = 2, z = 2, extending to x > 2.
    let right = [v3(2.0, 1.2, 2.0), v3(2.0, 1.8, 2.0), v3(2.6, 1.5, 2.0)];
    let f = filled(&g, &[right]);
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].0, (2, 1, 2));
    assert!((f[0].1 - tri_area(right)).abs() < 1e-12);
    // The mirror image, extending to x < 2: the edge on the plane does not leak above.
    let left = [v3(2.0, 1.2, 2.0), v3(2.0, 1.8, 2.0), v3(1.5, 1.5, 2.0)];
    let f = filled(&g, &[left]);
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].0, (1, 1, 2));
    // In the plane x = 1, straddling the grid line y = 2 (on the line z = 3, too).
    let straddle = [v3(1.0, 1.0, 3.0), v3(1.0, 3.0, 3.0), v3(1.0, 2.0, 3.5)];
    let f = filled(&g, &[straddle]);
    assert_eq!(
        f.iter().map(|x| x.0).collect::<Vec<_>>(),
        [(1, 1, 3), (1, 2, 3)]
    );
    assert!((f[0].1 - 0.25).abs() < 1e-12 && (f[1].1 - 0.25).abs() < 1e-12);
    // In the box face z = 0, with its right-angle corner on the grid point x = y = 1.
    let corner = [v3(1.0, 1.0, 0.0), v3(2.0, 1.0, 0.0), v3(1.0, 2.0, 0.0)];
    assert_eq!(filled(&g, &[corner]), vec![((1, 1, 0), 0.5)]);
    // A diagonal triangle through grid lines: the total is conserved exactly once.
    let diag = [v3(0.0, 0.0, 0.0), v3(4.0, 4.0, 0.0), v3(4.0, 4.0, 4.0)];
    let total: f64 = filled(&g, &[diag]).iter().map(|x| x.1).sum();
    assert!((total - tri_area(diag)).abs() < 1e-12);
}

// ---------------------------------------------------------------------------------------------
// MaxArea.

/// Two triangles forming the rectangle with corners `a, b, c, d` (in order).
fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [Tri; 2] {
    [[a, b, c], [a, c, d]]
}

/// The diagonal rectangle of the box `[lo, hi]` through its edge along x at (y, z) = lo and
/// the opposite one, shrunk around its centre by `s`.
fn diagonal_rect(lo: Vec3, hi: Vec3, s: f32) -> [Tri; 2] {
    let c = (lo + hi) * 0.5;
    let shrink = |p: Vec3| c + (p - c) * s;
    quad(
        shrink(lo),
        shrink(v3(hi.x, lo.y, lo.z)),
        shrink(hi),
        shrink(v3(lo.x, hi.y, hi.z)),
    )
}

fn count(grid: &CellGrid, tris: &[Tri]) -> u32 {
    count_well_filled(grid, tris.iter().copied(), &mut CellScratch::new())
}

#[test]
fn diagonal_rectangle_fills_a_cube_cell_and_smaller_shapes_do_not() {
    let g = CellGrid::new(Aabb::new(Vec3::ZERO, Vec3::splat(3.0)), 3);
    assert!((g.max_area() - 2f64.sqrt()).abs() < 1e-15);
    for (i, j, k) in [(1, 1, 1), (0, 0, 0), (2, 2, 2), (2, 0, 1)] {
        let lo = v3(i as f32, j as f32, k as f32);
        let hi = lo + Vec3::ONE;
        let rect = diagonal_rect(lo, hi, 1.0);
        assert_eq!(count(&g, &rect), 1, "cell ({i},{j},{k})");
        assert_eq!(filled(&g, &rect).len(), 1);
        assert_eq!(count(&g, &diagonal_rect(lo, hi, 0.999)), 0);
        // A face-sized axis-aligned square (area 1 < √2), inside the cell.
        let z = lo.z + 0.5;
        let sq = quad(
            v3(lo.x, lo.y, z),
            v3(hi.x, lo.y, z),
            v3(hi.x, hi.y, z),
            v3(lo.x, hi.y, z),
        );
        assert_eq!(count(&g, &sq), 0);
        // Two such squares stacked: area 2 ≥ √2.
        let sq2 = quad(
            v3(lo.x, lo.y, z + 0.25),
            v3(hi.x, lo.y, z + 0.25),
            v3(hi.x, hi.y, z + 0.25),
            v3(lo.x, hi.y, z + 0.25),
        );
        assert_eq!(count(&g, &[sq[0], sq[1], sq2[0], sq2[1]]), 1);
    }
    // Cell sides not representable in f32 (1/3): the f32 corners stick out by round-off only.
    let g = CellGrid::new(Aabb::new(Vec3::ZERO, Vec3::ONE), 3);
    let rect = diagonal_rect(Vec3::splat(1.0 / 3.0), Vec3::splat(2.0 / 3.0), 1.0);
    assert_eq!(count(&g, &rect), 1);
    assert_eq!(
        count(
            &g,
            &diagonal_rect(Vec3::splat(1.0 / 3.0), Vec3::splat(2.0 / 3.0), 0.999)
        ),
        0
    );
}

#[test]
fn cuboid_cells_use_the_largest_diagonal_rectangle() {
    // Cells 2 × 1 × 0.5: MaxArea = 2·√(1 + 0.25).
    let g = CellGrid::new(Aabb::new(Vec3::ZERO, v3(4.0, 2.0, 1.0)), 2);
    assert_eq!(g.cell_sides(), v3(2.0, 1.0, 0.5));
    assert_eq!(g.max_area(), 2.0 * 1.25f64.sqrt());
    assert_eq!(g.max_area(), max_cell_area(DVec3::new(2.0, 1.0, 0.5)));
    let (lo, hi) = (v3(2.0, 1.0, 0.5), v3(4.0, 2.0, 1.0));
    assert_eq!(count(&g, &diagonal_rect(lo, hi, 1.0)), 1);
    assert_eq!(count(&g, &diagonal_rect(lo, hi, 0.999)), 0);
    // The diagonal rectangle across the long side (area 1·√(4 + 0.25)) is smaller: not filled.
    let other = quad(lo, v3(lo.x, hi.y, lo.z), hi, v3(hi.x, lo.y, hi.z));
    assert!(tri_area(other[0]) * 2.0 < g.max_area());
    assert_eq!(count(&g, &other), 0);
}

// ---------------------------------------------------------------------------------------------
// Flat boxes and degenerate triangles.

/// A `k × k` grid of unit quads in the plane z = `z`, two triangles each.
fn flat_sheet(k: u32, z: f32) -> Vec<Tri> {
    let mut out = Vec::new();
    for i in 0..k {
        for j in 0..k {
            let (x, y) = (i as f32, j as f32);
            out.extend(quad(
                v3(x, y, z),
                v3(x + 1.0, y, z),
                v3(x + 1.0, y + 1.0, z),
                v3(x, y + 1.0, z),
            ));
        }
    }
    out
}

#[test]
fn flat_boxes_count_covered_cells() {
    // A node of a flat cloth: zero thickness in z.
    let g = CellGrid::new(Aabb::new(Vec3::ZERO, v3(4.0, 4.0, 0.0)), 4);
    assert_eq!(g.max_area(), 1.0);
    assert_eq!(count(&g, &flat_sheet(4, 0.0)), 16);
    let areas = areas_of(&g, &flat_sheet(4, 0.0));
    assert!(areas.iter().all(|a| a.is_finite()));
    for (i, j, k) in cells(4) {
        let a = areas[g.cell_index(i, j, k)];
        assert!(if k == 0 {
            (a - 1.0).abs() < 1e-12
        } else {
            a == 0.0
        });
    }
    // One big triangle covering half the box: the 6 cells below the diagonal are covered, the
    // 4 diagonal ones half.
    let half = [v3(0.0, 0.0, 0.0), v3(4.0, 0.0, 0.0), v3(0.0, 4.0, 0.0)];
    assert_eq!(count(&g, &[half]), 6);
    // A sheet just off the plane, or a triangle crossing it, meets the box in zero area.
    assert_eq!(count(&g, &flat_sheet(4, 1e-3)), 0);
    let tilted = [v3(0.0, 0.0, -1.0), v3(4.0, 0.0, 1.0), v3(0.0, 4.0, 1.0)];
    assert!(areas_of(&g, &[tilted]).iter().all(|a| *a == 0.0));
    // The sheet reaching beyond the flat box is clipped to it.
    let g2 = CellGrid::new(Aabb::new(v3(1.0, 1.0, 0.0), v3(3.0, 3.0, 0.0)), 2);
    assert_eq!(count(&g2, &flat_sheet(4, 0.0)), 4);
    // Flat in two axes (a segment) and in three (a point): nothing, no NaN.
    for b in [
        Aabb::new(Vec3::ZERO, v3(4.0, 0.0, 0.0)),
        Aabb::new(Vec3::ONE, Vec3::ONE),
    ] {
        let g = CellGrid::new(b, 3);
        let tris = [
            [v3(0.0, 0.0, 0.0), v3(4.0, 0.0, 0.0), v3(0.0, 4.0, 0.0)],
            [v3(1.0, 1.0, 1.0), v3(2.0, 1.0, 1.0), v3(1.0, 2.0, 1.0)],
        ];
        assert!(areas_of(&g, &tris).iter().all(|a| *a == 0.0));
        assert_eq!(count(&g, &tris), 0);
    }
}

#[test]
fn degenerate_triangles_add_nothing() {
    let g = grid4();
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let tris = [
        [v3(0.5, 0.5, 0.5), v3(3.5, 3.5, 3.5), v3(2.0, 2.0, 2.0)], // collinear
        [v3(0.5, 0.5, 0.5), v3(0.5, 0.5, 0.5), v3(3.5, 1.0, 2.0)], // repeated corner
        [Vec3::splat(2.0); 3],                                     // a point, on grid planes
        [v3(nan, 0.5, 0.5), v3(3.5, 1.0, 2.0), v3(1.0, 3.0, 2.0)],
        [v3(inf, 0.5, 0.5), v3(3.5, 1.0, 2.0), v3(1.0, 3.0, 2.0)],
        [v3(-inf, 0.5, 0.5), v3(inf, 1.0, 2.0), v3(1.0, 3.0, 2.0)],
    ];
    let areas = areas_of(&g, &tris);
    assert!(areas.iter().all(|a| *a == 0.0));
    assert_eq!(count(&g, &tris), 0);
    // A needle sliver crossing many cells: finite, conserved.
    let sliver = [
        v3(0.0, 0.0, 0.0),
        v3(4.0, 4.0, 4.0),
        v3(4.0, 4.0, 4.0 - 1e-6),
    ];
    let areas = areas_of(&g, &[sliver]);
    assert!(areas.iter().all(|a| a.is_finite() && *a >= 0.0));
    let total: f64 = areas.iter().sum();
    assert!((total - tri_area(sliver)).abs() <= 1e-6 * tri_area(sliver));
}

// ---------------------------------------------------------------------------------------------
// Offsets and scales.

/// Random triangles with corners on a 1/16 lattice in [-1, 5]³, so that offsets up to 3e5
/// and power-of-two scales keep every coordinate exact in `f32`.
fn lattice_tris(r: &mut Xoshiro256PlusPlus, count: usize) -> Vec<Tri> {
    (0..count)
        .map(|_| {
            [0; 3].map(|_| Vec3::from_array([0; 3].map(|_| r.random_range(-16..=80) as f32 / 16.0)))
        })
        .collect()
}

#[test]
fn offsets_and_power_of_two_scales_give_identical_areas_and_counts() {
    let mut r = rng(3);
    let tris = lattice_tris(&mut r, 40);
    for (bounds, n) in [
        (Aabb::new(Vec3::ZERO, Vec3::splat(4.0)), 4),
        (Aabb::new(v3(0.5, 0.0, 1.0), v3(4.0, 2.0, 3.0)), 3),
        (Aabb::new(Vec3::ZERO, v3(4.0, 4.0, 0.0)), 2),
    ] {
        let base_grid = CellGrid::new(bounds, n);
        let base = areas_of(&base_grid, &tris);
        let base_count = count(&base_grid, &tris);
        let flat = bounds.extents().min_element() == 0.0;
        if !flat {
            assert!(
                base_count > 0 && (base_count as usize) < base_grid.cell_count(),
                "uninformative configuration: {base_count} of {}",
                base_grid.cell_count()
            );
        }
        for exp in [-13, -7, 0, 5, 18] {
            let s = 2f32.powi(exp);
            for offset in [Vec3::ZERO, v3(1e5, -3e5, 2.5e5), Vec3::splat(-1e5)] {
                let map = |p: Vec3| (p + offset) * s;
                let g = CellGrid::new(Aabb::new(map(bounds.min), map(bounds.max)), n);
                let moved: Vec<Tri> = tris.iter().map(|t| t.map(map)).collect();
                let areas = areas_of(&g, &moved);
                let s2 = f64::from(s) * f64::from(s);
                for (a, b) in areas.iter().zip(&base) {
                    assert_eq!(*a, b * s2, "scale 2^{exp}, offset {offset}");
                }
                assert_eq!(
                    count(&g, &moved),
                    base_count,
                    "scale 2^{exp}, offset {offset}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Scratch reuse.

#[test]
fn scratch_reuse_is_repeatable_and_allocation_free() {
    let mut r = rng(4);
    let tris = lattice_tris(&mut r, 60);
    let g4 = CellGrid::new(Aabb::new(Vec3::ZERO, Vec3::splat(4.0)), 4);
    let g7 = CellGrid::new(Aabb::new(v3(-1.0, 0.0, 0.0), v3(5.0, 4.0, 3.0)), 7);
    let g2 = CellGrid::new(Aabb::new(Vec3::ONE, Vec3::splat(3.0)), 2);
    // The counter sees this thread's allocations.
    let before = allocations();
    let mut scratch = CellScratch::new();
    assert!(allocations() > before);
    let first = [&g4, &g7, &g2].map(|g| count_well_filled(g, tris.iter().copied(), &mut scratch));
    let cap = scratch.area_capacity();
    assert!(cap >= 343);
    let before = allocations();
    for _ in 0..3 {
        for (g, want) in [&g2, &g7, &g4]
            .into_iter()
            .zip([first[2], first[1], first[0]])
        {
            assert_eq!(
                count_well_filled(g, tris.iter().copied(), &mut scratch),
                want
            );
        }
    }
    assert_eq!(allocations(), before, "counting allocated after warm-up");
    assert_eq!(scratch.area_capacity(), cap);
    // Fresh scratch agrees; a pre-sized one never grows.
    for (g, want) in [&g4, &g7, &g2].into_iter().zip(first) {
        assert_eq!(count(g, &tris), want);
    }
    let mut sized = CellScratch::with_cells(343);
    let cap = sized.area_capacity();
    let before = allocations();
    count_well_filled(&g7, tris.iter().copied(), &mut sized);
    assert_eq!(allocations(), before);
    assert_eq!(sized.area_capacity(), cap);
    // An empty set, and a set entirely outside the box.
    assert_eq!(count_well_filled(&g4, [], &mut scratch), 0);
    let far: Vec<Tri> = tris
        .iter()
        .map(|t| t.map(|p| p + Vec3::splat(10.0)))
        .collect();
    assert_eq!(count_well_filled(&g4, far.iter().copied(), &mut scratch), 0);
}

#[test]
#[should_panic(expected = "resolution")]
fn resolution_out_of_range_panics() {
    CellGrid::new(Aabb::new(Vec3::ZERO, Vec3::ONE), 17);
}

// ---------------------------------------------------------------------------------------------
// Timing (ignored by default).

/// A torus of about `2·u·v` triangles with radii 1 and 0.3.
fn torus(u: u32, v: u32) -> Vec<Tri> {
    let p = |i: u32, j: u32| {
        let a = i as f32 / u as f32 * std::f32::consts::TAU;
        let b = j as f32 / v as f32 * std::f32::consts::TAU;
        let r = 1.0 + 0.3 * b.cos();
        v3(r * a.cos(), r * a.sin(), 0.3 * b.sin())
    };
    let mut out = Vec::new();
    for i in 0..u {
        for j in 0..v {
            out.extend(quad(p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)));
        }
    }
    out
}

fn tri_box(t: &Tri) -> Aabb {
    Aabb::from_points(t.iter().copied())
}

/// Median-split tree over centroids; each node counts over the triangles overlapping its
/// box, taken from its parent's list (as a box query would). Returns the number of nodes, the
/// number of triangle visits, and the time spent in `count_well_filled`.
fn count_tree(
    tris: &[Tri],
    ids: &mut [usize],
    parent_set: &[usize],
    n: u32,
    scratch: &mut CellScratch,
) -> (usize, usize, Duration) {
    let bounds = ids
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(&tri_box(&tris[i])));
    let grid = CellGrid::new(bounds, n);
    let set: Vec<usize> = parent_set
        .iter()
        .copied()
        .filter(|&i| tri_box(&tris[i]).intersects(&bounds))
        .collect();
    let t0 = Instant::now();
    std::hint::black_box(count_well_filled(
        &grid,
        set.iter().map(|&i| tris[i]),
        scratch,
    ));
    let mut out = (1, set.len(), t0.elapsed());
    if ids.len() > 2 {
        let axis = bounds.extents().max_position();
        let key = |i: &usize| {
            let t = &tris[*i];
            (t[0] + t[1] + t[2])[axis]
        };
        let mid = ids.len() / 2;
        ids.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
        let (l, r) = ids.split_at_mut(mid);
        for half in [l, r] {
            let (a, b, c) = count_tree(tris, half, &set, n, scratch);
            out.0 += a;
            out.1 += b;
            out.2 += c;
        }
    }
    out
}

#[test]
#[ignore = "timing; run in release with --ignored --nocapture"]
fn per_triangle_cost() {
    let mut r = rng(5);
    for n in [4, 8] {
        let bounds = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let grid = CellGrid::new(bounds, n);
        let mut areas = vec![0.0; grid.cell_count()];
        for (label, size) in [
            ("small (~0.1 cell)", 0.1),
            ("cell-sized", 1.0),
            ("node-sized", n as f32),
        ] {
            let side = size / n as f32;
            let tris: Vec<Tri> = (0..200_000)
                .map(|_| {
                    let c = point_around(&mut r, bounds, 0.0);
                    [0; 3]
                        .map(|_| c + (point_around(&mut r, bounds, 0.0) - Vec3::splat(0.5)) * side)
                })
                .collect();
            let t0 = Instant::now();
            for t in &tris {
                accumulate_triangle(&grid, *t, &mut areas);
            }
            let dt = t0.elapsed();
            std::hint::black_box(&areas);
            println!(
                "n = {n}, {label}: {:.0} ns / triangle",
                dt.as_secs_f64() * 1e9 / tris.len() as f64
            );
        }
    }
    let tris = torus(250, 200);
    let mut scratch = CellScratch::new();
    for n in [4, 8] {
        let t0 = Instant::now();
        let mut ids: Vec<usize> = (0..tris.len()).collect();
        let all = ids.clone();
        let (nodes, visits, counting) = count_tree(&tris, &mut ids, &all, n, &mut scratch);
        println!(
            "tree over {} triangles, n = {n}: {nodes} nodes, {visits} triangle visits \
             ({:.1} per triangle), counting {:.2} s ({:.0} ns per visit), total with the naive \
             box queries {:.2} s",
            tris.len(),
            visits as f64 / tris.len() as f64,
            counting.as_secs_f64(),
            counting.as_secs_f64() * 1e9 / visits as f64,
            t0.elapsed().as_secs_f64()
        );
    }
}

//! Per-node "well-filled cell" counts for ADB-trees (Klein & Zachmann 2003).
//!
//! An ADB-tree node stores one number: how many cells of an `n × n × n` grid over its box are
//! *possible collision cells* ("well-filled" cells). A cell `c` is well-filled iff the total area
//! of the node's triangles `P(A)` (those in **or crossing** the box), clipped exactly to `c`, is at
//! least `MaxArea(c)`, the area of the largest planar polygon that fits in `c`.
//!
//! # Conventions
//!
//! - **Coordinates.** All clipping and area sums run in `f64`, relative to the box's `min`
//!   corner, so boxes far from the origin (1e5) and scales from 1e-4 to 1e6 behave like the same
//!   configuration at unit scale. Scaling a configuration by a power of two and offsetting it by an
//!   exactly representable amount gives bit-identical areas and identical counts. The only
//!   precision limit is that of the `f32` input itself.
//! - **Half-open cells.** On each axis a cell covers `[lo, hi)`, except the last cell, which
//!   is closed `[lo, hi]` so that the box's max faces are not lost. The box as a whole is closed:
//!   triangles on its min or max faces belong to it. A polygon lying exactly in an interior grid
//!   plane is counted once, in the cell layer *above* the plane, never twice and never zero times.
//! - **`MaxArea` for cuboids.** For a cube of side `a` the largest planar polygon is the
//!   diagonal rectangle `a × a√2`, area `a²√2`. For a cuboid with sorted sides `a ≥ b ≥ c`,
//!   this module uses the largest of the three diagonal rectangles, `a·√(b² + c²)`
//!   ([`max_cell_area`]). The papers do not give a formula for non-cubic cells. This one reduces to
//!   `a²√2` for cubes and to the face area `a·b` for zero-thickness cells.
//! - **Flat boxes.** A box axis of zero extent (for example a node over a flat cloth patch) puts
//!   every coordinate in cell 0 on that axis, and the cells with index `> 0` on it stay empty.
//!   Only triangles lying exactly in a flat box's plane contribute area; a triangle that
//!   crosses it meets the box in a segment of zero area. A zero-thickness cell has
//!   `MaxArea = a·b`, so it is well-filled when it is covered. A cell with two zero sides has
//!   `MaxArea = 0`, but it can never hold positive area. Note the discontinuity this
//!   implies: a covered cell of a box with a small positive thickness `c` needs area
//!   `a·√(b² + c²) > a·b`, so a perfectly flat sheet in a slightly thick box fills nothing.
//! - **Degenerate input.** Zero-area triangles (collinear or repeated corners) and triangles
//!   with non-finite coordinates contribute nothing. No NaN reaches the accumulators.
//! - **Well-filled test.** A cell counts iff its area is `> 0` and
//!   `≥ MaxArea · (1 − `[`WELL_FILLED_REL_TOL`]`)`. The small tolerance lets an exact diagonal
//!   rectangle, built from two triangles with `f32` corners, count despite round-off.
//!
//! # Cost
//!
//! A triangle is first tested against the box. If it lies inside and within a single cell (the
//! common case in the upper tree levels), its area is added directly. Otherwise it is clipped to
//! the box (only against the planes it crosses) and split by the grid planes, along x into slices,
//! each slice along y, and each of those along z. Only the cells its bounding box overlaps are
//! visited. Polygons live in fixed-size arrays: [`count_well_filled`] keeps them in its
//! [`CellScratch`] and allocates nothing once the scratch has grown to the grid size, while
//! [`accumulate_triangle`] zeroes about 4.6 KiB of stack buffers whenever a triangle needs
//! splitting. Use the former for bulk work.
//!
//! Next: [`super::probability`] turns two nodes' counts into the probability that they hold
//! intersecting triangles.

use glam::{DVec3, Vec3};

use crate::geometry::Aabb;

/// Largest supported grid resolution (cells per axis).
pub const MAX_RESOLUTION: u32 = 16;

/// Relative slack of the well-filled test: a cell counts when its area is at least
/// `MaxArea · (1 − WELL_FILLED_REL_TOL)` (and positive).
pub const WELL_FILLED_REL_TOL: f64 = 1e-6;

/// Vertex capacity of a clipped polygon. A triangle clipped to an axis-aligned box has at most
/// 9 vertices in exact arithmetic. The extra room absorbs the vertices round-off can add. A
/// vertex beyond the capacity is dropped (the polygon's area is then underestimated), never
/// written out of bounds.
const POLY_CAP: usize = 16;

/// The area of the largest planar polygon this module assumes fits in a cuboid with side
/// lengths `sides`.
///
/// With the sides sorted `a ≥ b ≥ c`, this is `a·√(b² + c²)`, the largest of the three diagonal
/// rectangles. It is `a²√2` for a cube, `a·b` for a zero-thickness cell, and 0 when two sides are 0.
pub fn max_cell_area(sides: DVec3) -> f64 {
    let mut s = [sides.x.abs(), sides.y.abs(), sides.z.abs()];
    s.sort_by(|p, q| q.total_cmp(p));
    let [a, b, c] = s;
    a * b.hypot(c)
}

/// An `n × n × n` grid of equal cuboidal cells over a node's box.
///
/// Cells are numbered by [`CellGrid::cell_index`] with z varying fastest.
#[derive(Debug, Clone)]
pub struct CellGrid {
    bounds: Aabb,
    n: u32,
    /// `bounds.min` in `f64`: the origin of all internal coordinates.
    origin: DVec3,
    /// `bounds.max - bounds.min` in `f64` (exact).
    extents: DVec3,
    /// Cell side lengths (`extents / n`).
    sides: DVec3,
    /// `n / extents` per axis, 0 on flat axes: the first guess for a coordinate's cell.
    inv_sides: DVec3,
    /// Axes of zero extent.
    flat: [bool; 3],
    /// `planes[axis][i] = extents[axis] · i / n` for `i` in `0..=n`, with `planes[axis][n]`
    /// exactly `extents[axis]`.
    planes: [[f64; MAX_RESOLUTION as usize + 1]; 3],
    max_area: f64,
    /// Fraction of `max_area` a cell's area must reach to count as well-filled.
    fill: f64,
}

impl CellGrid {
    /// The grid of `resolution³` cells over `bounds`.
    ///
    /// # Panics
    ///
    /// If `resolution` is not in `1..=`[`MAX_RESOLUTION`], or if `bounds` is empty or not finite.
    pub fn new(bounds: Aabb, resolution: u32) -> CellGrid {
        assert!(
            (1..=MAX_RESOLUTION).contains(&resolution),
            "cell grid resolution {resolution} is not in 1..={MAX_RESOLUTION}"
        );
        assert!(
            bounds.min.is_finite() && bounds.max.is_finite() && !bounds.is_empty(),
            "cell grid bounds must be finite and non-empty, got {bounds:?}"
        );
        let origin = bounds.min.as_dvec3();
        let extents = bounds.max.as_dvec3() - origin;
        let nf = f64::from(resolution);
        let sides = extents / nf;
        let mut flat = [false; 3];
        let mut inv_sides = DVec3::ZERO;
        let mut planes = [[0.0; MAX_RESOLUTION as usize + 1]; 3];
        for axis in 0..3 {
            let e = extents[axis];
            flat[axis] = e == 0.0;
            if !flat[axis] {
                inv_sides[axis] = nf / e;
            }
            for (i, plane) in planes[axis][..resolution as usize].iter_mut().enumerate() {
                *plane = e * i as f64 / nf;
            }
            planes[axis][resolution as usize] = e;
        }
        CellGrid {
            bounds,
            n: resolution,
            origin,
            extents,
            sides,
            inv_sides,
            flat,
            planes,
            max_area: max_cell_area(sides),
            fill: 1.0,
        }
    }

    /// The same grid, counting a cell as well-filled once its area reaches
    /// `fraction · MaxArea` (clamped to `(0, 1]`; the papers' definition is 1).
    ///
    /// A single smooth surface crossing a cell covers at most about `a²` of it, below the
    /// papers' `a²√2`, so with the papers' threshold only folded or layered geometry (dense CAD
    /// parts) ever fills a cell; a smaller fraction lets ordinary meshes' cells count.
    pub fn with_fill_fraction(mut self, fraction: f64) -> CellGrid {
        self.fill = if fraction.is_finite() {
            fraction.clamp(f64::MIN_POSITIVE, 1.0)
        } else {
            1.0
        };
        self
    }

    /// The fill fraction in use (see [`CellGrid::with_fill_fraction`]).
    #[inline]
    pub fn fill_fraction(&self) -> f64 {
        self.fill
    }

    /// The box the grid covers.
    #[inline]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Cells per axis (`n`).
    #[inline]
    pub fn resolution(&self) -> u32 {
        self.n
    }

    /// Total number of cells, `n³`.
    #[inline]
    pub fn cell_count(&self) -> usize {
        (self.n as usize).pow(3)
    }

    /// Side lengths of every cell (`extents / n`, rounded to `f32`).
    #[inline]
    pub fn cell_sides(&self) -> Vec3 {
        self.sides.as_vec3()
    }

    /// `MaxArea` of every cell: see [`max_cell_area`].
    #[inline]
    pub fn max_area(&self) -> f64 {
        self.max_area
    }

    /// Index of cell `(i, j, k)` (x, y, z) in an area buffer: `(i·n + j)·n + k`.
    ///
    /// # Panics
    ///
    /// If an index is `>= n`.
    #[inline]
    pub fn cell_index(&self, i: u32, j: u32, k: u32) -> usize {
        assert!(
            i < self.n && j < self.n && k < self.n,
            "cell ({i}, {j}, {k}) outside a {0}×{0}×{0} grid",
            self.n
        );
        self.index(i, j, k)
    }

    /// Whether a cell holding this much clipped area is well-filled (a possible collision cell):
    /// `area > 0` and `area ≥ fill · MaxArea · (1 − `[`WELL_FILLED_REL_TOL`]`)`, `fill` being
    /// 1 (the papers) unless set by [`CellGrid::with_fill_fraction`].
    #[inline]
    pub fn is_well_filled(&self, area: f64) -> bool {
        area > 0.0 && area >= self.fill * self.max_area * (1.0 - WELL_FILLED_REL_TOL)
    }

    #[inline]
    fn index(&self, i: u32, j: u32, k: u32) -> usize {
        let n = self.n as usize;
        (i as usize * n + j as usize) * n + k as usize
    }

    /// The half-open cell holding relative coordinate `x` (in `[0, extent]`) on `axis`.
    #[inline]
    fn cell_of(&self, axis: usize, x: f64) -> u32 {
        if self.flat[axis] {
            return 0;
        }
        let last = self.n - 1;
        // `as` saturates (and maps NaN to 0); the loops fix the guess against the exact planes.
        let mut c = ((x * self.inv_sides[axis]) as u32).min(last);
        let planes = &self.planes[axis];
        while c > 0 && x < planes[c as usize] {
            c -= 1;
        }
        while c < last && x >= planes[c as usize + 1] {
            c += 1;
        }
        c
    }

    #[inline]
    fn cell_range(&self, lo: DVec3, hi: DVec3) -> CellRange {
        // Written out: `[_; 3].map` with this closure does not inline well.
        CellRange {
            lo: [
                self.cell_of(0, lo.x),
                self.cell_of(1, lo.y),
                self.cell_of(2, lo.z),
            ],
            hi: [
                self.cell_of(0, hi.x),
                self.cell_of(1, hi.y),
                self.cell_of(2, hi.z),
            ],
        }
    }
}

/// Reusable buffers for [`count_well_filled`]: the per-cell area accumulator and the clipping
/// polygons (fixed-size arrays, about 4.6 KiB, boxed). After the first call on a grid of a given
/// size, counting allocates nothing.
#[derive(Clone)]
pub struct CellScratch {
    /// Per-cell area accumulator. All zeros between calls unless `dirty`.
    areas: Vec<f64>,
    /// Set while a count runs; still set if one panicked midway.
    dirty: bool,
    polys: Box<PolyBufs>,
}

impl Default for CellScratch {
    fn default() -> Self {
        Self::with_cells(0)
    }
}

impl std::fmt::Debug for CellScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CellScratch")
            .field("area_capacity", &self.areas.capacity())
            .finish_non_exhaustive()
    }
}

impl CellScratch {
    /// Fresh buffers; the area accumulator grows on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// Buffers ready for grids of up to `cells` cells.
    pub fn with_cells(cells: usize) -> Self {
        Self {
            areas: vec![0.0; cells],
            dirty: false,
            polys: Box::new(PolyBufs::EMPTY),
        }
    }

    /// Capacity of the per-cell area accumulator, in cells (for checking that reuse does not
    /// grow it).
    pub fn area_capacity(&self) -> usize {
        self.areas.capacity()
    }
}

/// Inclusive per-axis cell index ranges.
#[derive(Debug, Clone, Copy)]
struct CellRange {
    lo: [u32; 3],
    hi: [u32; 3],
}

impl CellRange {
    #[inline]
    fn union(self, o: CellRange) -> CellRange {
        let (a, b) = (self.lo, o.lo);
        let (c, d) = (self.hi, o.hi);
        CellRange {
            lo: [a[0].min(b[0]), a[1].min(b[1]), a[2].min(b[2])],
            hi: [c[0].max(d[0]), c[1].max(d[1]), c[2].max(d[2])],
        }
    }
}

/// Adds the area of `tri ∩ cell` to `areas[cell]` for every cell of `grid`, using the
/// half-open convention described in the [module docs](self).
///
/// Triangles outside the box, degenerate triangles, and triangles with non-finite corners add
/// nothing.
///
/// # Panics
///
/// If `areas.len() < grid.cell_count()`.
pub fn accumulate_triangle(grid: &CellGrid, tri: [Vec3; 3], areas: &mut [f64]) {
    assert!(
        areas.len() >= grid.cell_count(),
        "area buffer holds {} cells, grid has {}",
        areas.len(),
        grid.cell_count()
    );
    if let Prepared::Split(job) = prepare(grid, tri, areas) {
        let mut bufs = PolyBufs::EMPTY;
        accumulate_split(grid, &job, areas, &mut bufs);
    }
}

/// The number of well-filled cells (possible collision cells) of `grid` for this set of
/// triangles: cells whose summed clipped area passes [`CellGrid::is_well_filled`].
///
/// Pass the node's `P(A)`, meaning every triangle in or crossing the box. Triangles that miss
/// the box are ignored, so a superset is also fine.
pub fn count_well_filled(
    grid: &CellGrid,
    triangles: impl IntoIterator<Item = [Vec3; 3]>,
    scratch: &mut CellScratch,
) -> u32 {
    let cells = grid.cell_count();
    if scratch.dirty {
        scratch.areas.fill(0.0);
    }
    if scratch.areas.len() < cells {
        scratch.areas.resize(cells, 0.0);
    }
    scratch.dirty = true;
    let areas = &mut scratch.areas[..cells];
    let mut touched: Option<CellRange> = None;
    let bufs = &mut *scratch.polys;
    for tri in triangles {
        let r = match prepare(grid, tri, areas) {
            Prepared::Skip => continue,
            Prepared::Done(r) => r,
            Prepared::Split(job) => match accumulate_split(grid, &job, areas, bufs) {
                Some(r) => r,
                None => continue,
            },
        };
        touched = Some(touched.map_or(r, |t| t.union(r)));
    }
    let mut count = 0;
    if let Some(r) = touched {
        for i in r.lo[0]..=r.hi[0] {
            for j in r.lo[1]..=r.hi[1] {
                for k in r.lo[2]..=r.hi[2] {
                    let idx = grid.index(i, j, k);
                    count += u32::from(grid.is_well_filled(areas[idx]));
                    areas[idx] = 0.0;
                }
            }
        }
    }
    scratch.dirty = false;
    count
}

/// A convex polygon in box-relative `f64` coordinates, in a fixed-size buffer.
#[derive(Clone, Copy)]
struct Poly {
    len: usize,
    v: [DVec3; POLY_CAP],
}

impl Poly {
    const EMPTY: Poly = Poly {
        len: 0,
        v: [DVec3::ZERO; POLY_CAP],
    };

    #[inline]
    fn push(&mut self, p: DVec3) {
        if self.len < POLY_CAP {
            self.v[self.len] = p;
            self.len += 1;
        }
    }

    #[inline]
    fn verts(&self) -> &[DVec3] {
        &self.v[..self.len]
    }
}

/// Where a polygon lies relative to a plane `x[axis] = p`.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Side {
    /// Every vertex has `x <= p`, and some has `x < p`.
    Below,
    /// Every vertex has `x >= p`, and some has `x > p`.
    Above,
    /// Every vertex has `x == p`.
    InPlane,
    /// Vertices on both sides: `below` and `above` hold the two pieces.
    Split,
}

/// Splits `src` by the plane `x[axis] = p`. Only when the result is [`Side::Split`] are `below`
/// and `above` written. Then `below` is the part with `x <= p` and `above` the part with
/// `x >= p`. Vertices on the plane go to both pieces, and each crossing edge's intersection
/// point, with its `axis` coordinate snapped to exactly `p`, goes to both.
#[inline]
fn split<const AXIS: usize>(src: &Poly, p: f64, below: &mut Poly, above: &mut Poly) -> Side {
    let v = src.verts();
    let (mut any_below, mut any_above) = (false, false);
    for q in v {
        any_below |= q[AXIS] < p;
        any_above |= q[AXIS] > p;
    }
    match (any_below, any_above) {
        (false, false) => return Side::InPlane,
        (true, false) => return Side::Below,
        (false, true) => return Side::Above,
        (true, true) => {}
    }
    below.len = 0;
    above.len = 0;
    let m = v.len();
    for i in 0..m {
        let a = v[i];
        let b = v[if i + 1 == m { 0 } else { i + 1 }];
        let da = a[AXIS] - p;
        let db = b[AXIS] - p;
        if da < 0.0 {
            below.push(a);
        } else if da > 0.0 {
            above.push(a);
        } else {
            below.push(a);
            above.push(a);
        }
        if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
            // Interpolate from the vertex below the plane, so that the point does not depend on
            // the edge's direction.
            let (lo, hi, dlo, dhi) = if da < 0.0 {
                (a, b, da, db)
            } else {
                (b, a, db, da)
            };
            let t = dlo / (dlo - dhi);
            let mut x = lo + (hi - lo) * t;
            x[AXIS] = p;
            below.push(x);
            above.push(x);
        }
    }
    Side::Split
}

/// Working polygons of the slow path: box clipping, then one set per split axis.
#[derive(Clone)]
struct PolyBufs {
    clip: [Poly; 3],
    x: [Poly; 3],
    y: [Poly; 3],
    z: [Poly; 3],
}

impl PolyBufs {
    const EMPTY: PolyBufs = PolyBufs {
        clip: [Poly::EMPTY; 3],
        x: [Poly::EMPTY; 3],
        y: [Poly::EMPTY; 3],
        z: [Poly::EMPTY; 3],
    };
}

/// Calls `f(cell, piece)` for every piece of `poly` in the cells along `axis` that its extent
/// covers. The split uses the half-open rule: a piece lying exactly in a plane goes to the cell
/// above. `bufs` is this level's working storage and must not alias `poly`.
#[inline]
fn for_each_slice<const AXIS: usize>(
    grid: &CellGrid,
    poly: &Poly,
    bufs: &mut [Poly; 3],
    mut f: impl FnMut(u32, &Poly),
) {
    let v = poly.verts();
    let (mut min, mut max) = (v[0][AXIS], v[0][AXIS]);
    for q in &v[1..] {
        min = min.min(q[AXIS]);
        max = max.max(q[AXIS]);
    }
    let (lo, hi) = (grid.cell_of(AXIS, min), grid.cell_of(AXIS, max));
    if lo == hi {
        f(lo, poly);
        return;
    }
    let [slice, rem_a, rem_b] = bufs;
    let (mut rem, mut next) = (rem_a, rem_b);
    let mut from_input = true;
    for i in lo..hi {
        let plane = grid.planes[AXIS][i as usize + 1];
        let src: &Poly = if from_input { poly } else { rem };
        match split::<AXIS>(src, plane, slice, next) {
            Side::Below => {
                f(i, src);
                return;
            }
            Side::Above | Side::InPlane => {}
            Side::Split => {
                f(i, slice);
                std::mem::swap(&mut rem, &mut next);
                from_input = false;
            }
        }
    }
    f(hi, if from_input { poly } else { rem });
}

/// A triangle that needs clipping or splitting, in box-relative coordinates.
struct SplitJob {
    p: [DVec3; 3],
    normal: DVec3,
    lo: DVec3,
    hi: DVec3,
    needs_clip: bool,
}

/// What [`prepare`] did with a triangle.
enum Prepared {
    /// Nothing to add: degenerate, outside the box, or crossing a flat box.
    Skip,
    /// Inside one cell: its area was added, to the cell in this range.
    Done(CellRange),
    /// Needs [`accumulate_split`].
    Split(SplitJob),
}

/// The fast path: rejects triangles that add nothing, and adds a triangle that lies inside one
/// cell directly.
#[inline]
fn prepare(grid: &CellGrid, tri: [Vec3; 3], areas: &mut [f64]) -> Prepared {
    let o = grid.origin;
    let p = [
        tri[0].as_dvec3() - o,
        tri[1].as_dvec3() - o,
        tri[2].as_dvec3() - o,
    ];
    let normal = (p[1] - p[0]).cross(p[2] - p[0]);
    let len2 = normal.length_squared();
    // Rejects zero area, NaN and infinities alike.
    if !(len2 > 0.0 && len2.is_finite()) {
        return Prepared::Skip;
    }
    let lo = p[0].min(p[1]).min(p[2]);
    let hi = p[0].max(p[1]).max(p[2]);
    let ext = grid.extents;
    if lo.cmpgt(ext).any() || hi.cmplt(DVec3::ZERO).any() {
        return Prepared::Skip;
    }
    for axis in 0..3 {
        // A triangle that does not lie in a flat box's plane meets the box in a segment at most.
        if grid.flat[axis] && (lo[axis] != 0.0 || hi[axis] != 0.0) {
            return Prepared::Skip;
        }
    }
    let needs_clip = lo.cmplt(DVec3::ZERO).any() || hi.cmpgt(ext).any();
    if !needs_clip {
        let c = [
            grid.cell_of(0, lo.x),
            grid.cell_of(1, lo.y),
            grid.cell_of(2, lo.z),
        ];
        let last = grid.n - 1;
        let inside = |axis: usize| {
            let c = c[axis];
            c == last || grid.flat[axis] || hi[axis] < grid.planes[axis][c as usize + 1]
        };
        if inside(0) && inside(1) && inside(2) {
            areas[grid.index(c[0], c[1], c[2])] += 0.5 * len2.sqrt();
            return Prepared::Done(CellRange { lo: c, hi: c });
        }
    }
    Prepared::Split(SplitJob {
        p,
        normal,
        lo,
        hi,
        needs_clip,
    })
}

/// Clips the polygon in `bufs.0` to the closed slab `0 ≤ x[AXIS] ≤ extent` where the triangle
/// crosses it, leaving the result in `bufs.0`. `None` if nothing of positive area is left. The
/// box is closed: a polygon lying in one of its faces is kept.
#[inline]
fn clip_axis<'a, const AXIS: usize>(
    grid: &CellGrid,
    job: &SplitJob,
    bufs: &mut (&'a mut Poly, &'a mut Poly, &'a mut Poly),
) -> Option<()> {
    let (poly, below, above) = bufs;
    if job.lo[AXIS] < 0.0 {
        match split::<AXIS>(poly, 0.0, below, above) {
            Side::Above | Side::InPlane => {}
            Side::Below => return None,
            Side::Split => std::mem::swap(poly, above),
        }
    }
    let e = grid.extents[AXIS];
    if job.hi[AXIS] > e {
        match split::<AXIS>(poly, e, below, above) {
            Side::Below | Side::InPlane => {}
            Side::Above => return None,
            Side::Split => std::mem::swap(poly, below),
        }
    }
    Some(())
}

/// The slow path: clip to the box, then split along x, y and z.
#[inline(never)]
fn accumulate_split(
    grid: &CellGrid,
    job: &SplitJob,
    areas: &mut [f64],
    bufs: &mut PolyBufs,
) -> Option<CellRange> {
    let [b0, b1, b2] = &mut bufs.clip;
    b0.len = 3;
    b0.v[..3].copy_from_slice(&job.p);
    let mut bufs3 = (b0, b1, b2);
    if job.needs_clip {
        clip_axis::<0>(grid, job, &mut bufs3)?;
        clip_axis::<1>(grid, job, &mut bufs3)?;
        clip_axis::<2>(grid, job, &mut bufs3)?;
    }
    let poly: &Poly = bufs3.0;
    if poly.len < 3 {
        return None;
    }
    let (mut plo, mut phi) = (poly.v[0], poly.v[0]);
    for q in &poly.verts()[1..] {
        plo = plo.min(*q);
        phi = phi.max(*q);
    }
    let range = grid.cell_range(plo, phi);

    // Areas come from the projection on the plane that drops the normal's dominant axis,
    // scaled back up by |n| / |n_dom|. Each piece's fan is taken around its first vertex.
    let normal = job.normal;
    let an = normal.abs();
    let dom = if an.x >= an.y && an.x >= an.z {
        0
    } else if an.y >= an.z {
        1
    } else {
        2
    };
    let (u, w) = ((dom + 1) % 3, (dom + 2) % 3);
    let scale = 0.5 * normal.length() / an[dom];
    let piece_area = |q: &Poly| -> f64 {
        let v = q.verts();
        if v.len() < 3 {
            return 0.0;
        }
        let o = v[0];
        let mut s = 0.0;
        for e in v[1..].windows(2) {
            let (a, b) = (e[0] - o, e[1] - o);
            s += a[u] * b[w] - a[w] * b[u];
        }
        s.abs() * scale
    };

    let PolyBufs { x, y, z, .. } = bufs;
    for_each_slice::<0>(grid, poly, x, |i, xs| {
        for_each_slice::<1>(grid, xs, y, |j, ys| {
            for_each_slice::<2>(grid, ys, z, |k, zs| {
                areas[grid.index(i, j, k)] += piece_area(zs);
            });
        });
    });
    Some(range)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_grid(n: u32) -> CellGrid {
        CellGrid::new(Aabb::new(Vec3::ZERO, Vec3::splat(n as f32)), n)
    }

    #[test]
    fn max_area_of_cube_flat_and_line_cells() {
        let s2 = 2f64.sqrt();
        assert_eq!(max_cell_area(DVec3::splat(2.0)), 4.0 * s2);
        assert_eq!(max_cell_area(DVec3::new(1.0, 3.0, 2.0)), 3.0 * 5f64.sqrt());
        assert_eq!(max_cell_area(DVec3::new(2.0, 0.0, 3.0)), 6.0);
        assert_eq!(max_cell_area(DVec3::new(0.0, 0.0, 3.0)), 0.0);
    }

    #[test]
    fn cell_of_is_half_open_with_closed_last_cell() {
        let g = unit_grid(4);
        assert_eq!(g.cell_of(0, 0.0), 0);
        assert_eq!(g.cell_of(0, 0.999), 0);
        assert_eq!(g.cell_of(0, 1.0), 1);
        assert_eq!(g.cell_of(0, 3.0), 3);
        assert_eq!(g.cell_of(0, 4.0), 3);
        let flat = CellGrid::new(Aabb::new(Vec3::ZERO, Vec3::new(4.0, 4.0, 0.0)), 4);
        assert_eq!(flat.cell_of(2, 0.0), 0);
        assert_eq!(flat.cell_of(0, 2.5), 2);
    }

    #[test]
    fn split_keeps_in_plane_vertices_on_both_sides_and_snaps_crossings() {
        let mut t = Poly::EMPTY;
        for q in [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
        ] {
            t.push(q);
        }
        let (mut b, mut a) = (Poly::EMPTY, Poly::EMPTY);
        // The plane x = 1 passes through the apex: 4 + 3 vertices, no duplicates.
        assert!(split::<0>(&t, 1.0, &mut b, &mut a) == Side::Split);
        assert_eq!((b.len, a.len), (3, 3));
        assert!(b.verts().iter().all(|q| q.x <= 1.0));
        assert!(a.verts().iter().all(|q| q.x >= 1.0));
        assert!(split::<2>(&t, 0.0, &mut b, &mut a) == Side::InPlane);
        assert!(split::<0>(&t, 0.0, &mut b, &mut a) == Side::Above);
        assert!(split::<0>(&t, 2.0, &mut b, &mut a) == Side::Below);
    }

    #[test]
    fn single_cell_fast_path_and_split_path_agree_on_total() {
        let g = unit_grid(4);
        let mut areas = vec![0.0; g.cell_count()];
        let small = [
            Vec3::new(0.1, 0.1, 0.1),
            Vec3::new(0.9, 0.2, 0.3),
            Vec3::new(0.4, 0.8, 0.6),
        ];
        accumulate_triangle(&g, small, &mut areas);
        let d = small.map(|v| v.as_dvec3());
        let want = 0.5 * (d[1] - d[0]).cross(d[2] - d[0]).length();
        assert!((areas[0] - want).abs() <= 1e-15 * want);
        areas.fill(0.0);
        let big = small.map(|v| v * 3.0);
        accumulate_triangle(&g, big, &mut areas);
        let total: f64 = areas.iter().sum();
        let d = big.map(|v| v.as_dvec3());
        let want = 0.5 * (d[1] - d[0]).cross(d[2] - d[0]).length();
        assert!((total - want).abs() <= 1e-12 * want);
        assert!(areas.iter().filter(|a| **a > 0.0).count() > 1);
    }
}

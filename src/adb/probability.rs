//! The ADB-tree probability model (Klein & Zachmann 2003), computed stably.
//!
//! One node pair `(A, B)` of two ADB-trees is scored in four steps:
//!
//! 1. [`overlap_volume`]: an estimate `V̂` of `Vol(A ∩ B)` from the two boxes' side lengths and
//!    the distance of their centres (the paper's `max{V1, V2, V3}` for boxes of similar size,
//!    the bounding spheres' lens otherwise).
//! 2. [`cell_counts`]: the three integers of the balls-in-bins model: `s` cells in `A ∩ B`, of
//!    which `s_A` are possible collision cells of `A` and `s_B` of `B`.
//! 3. [`prob_at_least`] (Eq. 8): `Pr[c(A∩B) ≥ x]`, the hypergeometric upper tail.
//! 4. [`collision_probability`] (Eq. 9): `max_x Pr[c ≥ x] · (1 − (1 − LB)^x)`, with the
//!    curvature term `LB` ([`depth_lower_bound`] is the paper's; the estimators in
//!    [`crate::adb`] supply others).
//!
//! For the traversal's hot path use
//! [`collision_probability_tabled`](super::tables::collision_probability_tabled), which reads
//! Eq. 8 from a precomputed table and falls back to the functions here.
//!
//! # Numerics
//!
//! No binomial coefficient is ever formed. The hypergeometric terms come from their ratio
//! recurrence, anchored either at the first term of the support (computed in log space from
//! [`ln_factorial`]) when the head `Σ_{t<x} P(t)` is at most ½, so that `1 − head` loses
//! nothing, or at the mode (weight 1, normalised by the sum of all non-negligible terms) when
//! the tail is small, so that small tails keep their relative accuracy. Every result is finite
//! and in `[0, 1]` for every input, including `s` in the hundreds of thousands.
//!
//! The reconstruction choices (the papers do not give them) are marked *\[RECON\]*.
//!
//! Next: [`super::tables`], the precomputed Eq. 8 the traversal reads.

use std::f64::consts::PI;
use std::sync::LazyLock;

/// Largest ratio between the two (thickened) box volumes for which [`overlap_volume`] still
/// uses the box formula; above it, it uses the bounding spheres' lens. *\[RECON\]*: the papers
/// say only "if the boxes differ in size by more than a threshold".
///
/// The value 4 (about 1.6× in each side for similar shapes) balances the two formulas' errors.
/// The box formula assumes equal boxes: when a smaller box sits inside a larger one it
/// underestimates the overlap (it starts decreasing at `d = 0`, while the true overlap stays
/// the small box's volume until `d ≈ (a_B − a_A)/2`); at a side ratio of 1.6 that error is
/// at most about 30%. The sphere lens overestimates for boxes of similar size (a cube's
/// bounding sphere is 2.7× its volume, and two face-touching cubes still get a large lens), so
/// switching to it early costs more than it saves. (A BVH child often has around half its
/// parent's volume, so 4 keeps most node pairs met in a simultaneous descent, at equal or
/// adjacent depths of similar meshes, on the box formula. Tune it against exact detection.)
pub const SIZE_RATIO_THRESHOLD: f64 = 4.0;

/// Each side of a node box is taken as at least this fraction of its longest side in
/// [`overlap_volume`] and [`node_volume`]. *\[RECON\]*: flat nodes (a planar patch has a zero
/// side) otherwise have zero volume, so every overlap estimate and every cell count would be 0
/// and flat geometry could never be reported.
///
/// 0.25 makes a flat node one cell layer thick on the default 4×4×4 grid
/// ([`S_MAX`](super::tables::S_MAX) = 64 cells): a flat node crossing a full node then covers
/// about `n²` of its `n³` cells, which is what a plane crossing a grid does. For two flat nodes
/// the cell count does not depend on this value at all (it cancels in `V̂ / v`).
pub const MIN_SIDE_RATIO: f64 = 0.25;

/// The cap on the number `x` of collision cells in Eq. 9 used by the papers ("in practice the
/// maximum is reached at small `x`", S1 §6.4).
pub const DEFAULT_X_MAX: u32 = 10;

/// Relative size below which the remaining hypergeometric terms are dropped (`2^-60`).
const TRUNC_EPS: f64 = 8.673_617_379_884_035e-19;

/// Terms below this, relative to the mode's weight 1, are flushed to 0 by the streaming
/// evaluation. Carrying them would push the weights into subnormals, where the ratio recurrence
/// stalls (a subnormal times 1.3 can round back to itself) and corrupts the sums. Their total is
/// below `2^32 · 10⁻²⁸⁰`, so only probabilities under about `10⁻²⁷⁰` are affected (returned as
/// 0).
const WEIGHT_FLOOR: f64 = 1e-280;

/// The head path starts from `P(lo)` itself only when `ln P(lo)` is above this
/// (`P(lo) > 10⁻²⁶⁰`, far from subnormals); below, it only checks whether the head is negligible.
const HEAD_MIN_LN: f64 = -600.0;

/// A head below `e^-700 ≈ 10⁻³⁰⁴` leaves every tail at exactly 1 in `f64`.
const HEAD_NEGLIGIBLE_LN: f64 = -700.0;

// ---------------------------------------------------------------------------------------------
// Volumes
// ---------------------------------------------------------------------------------------------

/// Sides as `f64`, sorted longest first; NaN and non-positive sides become 0.
#[inline]
fn sorted_sides(sides: [f32; 3]) -> [f64; 3] {
    let [mut a, mut b, mut c] = sides.map(|x| if x > 0.0 { f64::from(x) } else { 0.0 });
    // Three compare-exchanges (no NaN is left to order; this runs twice per node pair).
    if a < b {
        std::mem::swap(&mut a, &mut b);
    }
    if b < c {
        std::mem::swap(&mut b, &mut c);
    }
    if a < b {
        std::mem::swap(&mut a, &mut b);
    }
    [a, b, c]
}

/// Sorted sides with every side raised to at least [`MIN_SIDE_RATIO`] × the longest.
#[inline]
fn thickened_sides(sides: [f32; 3]) -> [f64; 3] {
    let [a, b, c] = sorted_sides(sides);
    let min = MIN_SIDE_RATIO * a;
    [a, b.max(min), c.max(min)]
}

/// Distance as a non-negative `f64`; `None` for NaN.
fn sanitize_distance(d: f64) -> Option<f64> {
    if d.is_nan() { None } else { Some(d.abs()) }
}

/// `max{V1, V2, V3}` on already sorted, sanitised sides (longest first) of both boxes.
fn box_overlap_sorted(a_sides: [f64; 3], b_sides: [f64; 3], d: f64) -> f64 {
    let a = a_sides[0].min(b_sides[0]);
    let b = a_sides[1].min(b_sides[1]);
    let c = a_sides[2].min(b_sides[2]);
    let vol = a * b * c;
    let Some(d) = sanitize_distance(d) else {
        return 0.0;
    };
    if vol.is_nan() || vol <= 0.0 {
        return 0.0;
    }
    // Squares in f64 of f32-sized sides cannot overflow, and `sqrt` is several times faster
    // than `hypot` (this runs once per node pair of a traversal).
    let l2 = (a * a + b * b).sqrt();
    let l3 = (a * a + b * b + c * c).sqrt();
    // Each base is clamped at 0 before the power: otherwise (1 − d/L)² turns positive again.
    let b1 = (1.0 - d / a).max(0.0);
    let b2 = (1.0 - d / l2).max(0.0);
    let b3 = (1.0 - d / l3).max(0.0);
    let v = vol * b1.max(b2 * b2).max(b3 * b3 * b3);
    if v.is_nan() { 0.0 } else { v.min(vol) }
}

/// Klein & Zachmann's overlap-volume estimate for two boxes of nearly equal size (S1 §6.5):
/// `max{V1, V2, V3}` with
///
/// ```text
/// V1 = abc·(1 − d/a),  V2 = abc·(1 − d/√(a²+b²))²,  V3 = abc·(1 − d/√(a²+b²+c²))³
/// ```
///
/// where `d` is the distance of the box centres (any relative orientation), and each base is
/// clamped at 0 before the power (unclamped, `V2` becomes positive again for large `d`).
///
/// `a ≥ b ≥ c` are the **elementwise minimum of the two boxes' sorted sides** *\[RECON\]*: the
/// paper states the formula for equal boxes. This choice is symmetric in `A` and `B`,
/// continuous in the inputs (taking "the smaller box" jumps when the volumes cross), equals the
/// paper's for equal boxes, and `abc` is exactly the intersection of the two boxes when they are
/// centred and aligned with matching axes, which is the largest intersection of any aligned
/// configuration. The result never exceeds the smaller box's volume.
///
/// Raw formula: a box with a zero side gives 0 (see [`overlap_volume`] for flat nodes); NaN
/// sides count as 0, a negative `d` as `|d|`, a NaN `d` gives 0. Never NaN.
pub fn box_overlap_volume(sides_a: [f32; 3], sides_b: [f32; 3], d: f32) -> f64 {
    box_overlap_sorted(sorted_sides(sides_a), sorted_sides(sides_b), f64::from(d))
}

/// Volume of a ball of radius `r`.
fn ball_volume(r: f64) -> f64 {
    4.0 / 3.0 * PI * r * r * r
}

/// Volume of the intersection (lens) of two balls of radii `r1`, `r2` whose centres are `d`
/// apart:
///
/// ```text
/// V = π (r1 + r2 − d)² (d² + 2d(r1 + r2) − 3(r1 − r2)²) / (12 d)      for |r1 − r2| < d < r1 + r2
/// ```
///
/// the smaller ball's volume when it is contained (`d ≤ |r1 − r2|`, including `d = 0`), and 0
/// when the balls are disjoint or touch (`d ≥ r1 + r2`). The second factor is written with
/// `−3(r1 − r2)²` so that equal radii at tiny `d` do not cancel. The result is clamped to the
/// smaller ball's volume. Negative or NaN radii count as 0, a negative `d` as `|d|`, a NaN `d`
/// gives 0. Never NaN.
pub fn sphere_lens_volume(r1: f64, r2: f64, d: f64) -> f64 {
    let r1 = if r1 > 0.0 { r1 } else { 0.0 };
    let r2 = if r2 > 0.0 { r2 } else { 0.0 };
    let (big, small) = if r1 >= r2 { (r1, r2) } else { (r2, r1) };
    let Some(d) = sanitize_distance(d) else {
        return 0.0;
    };
    if small == 0.0 || d >= big + small {
        return 0.0;
    }
    let small_volume = ball_volume(small);
    if d <= big - small {
        return small_volume;
    }
    let sum = big + small;
    let diff = big - small;
    let v = PI * (sum - d) * (sum - d) * (d * (d + 2.0 * sum) - 3.0 * diff * diff) / (12.0 * d);
    if v.is_nan() {
        0.0
    } else {
        v.clamp(0.0, small_volume)
    }
}

/// Volume of a node box as the probability model sees it: the product of its sides after
/// raising each to at least [`MIN_SIDE_RATIO`] × the longest side, so flat nodes keep a
/// positive volume. Pass this (not the raw box volume) as `volume_a`/`volume_b` to
/// [`cell_counts`], so that it matches [`overlap_volume`]. 0 only for a box whose sides are all
/// 0 (or NaN).
pub fn node_volume(sides: [f32; 3]) -> f64 {
    ModelBox::new(sides).volume()
}

/// A node box as the probability model sees it: its sides sorted and thickened (as in
/// [`node_volume`]) and their product, computed once per node of a pair and shared by
/// [`overlap_volume`] and the two [`node_volume`]s.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ModelBox {
    sides: [f64; 3],
    /// The product of the sides (NaN possible: `node_volume` reads it as 0).
    product: f64,
}

impl ModelBox {
    #[inline]
    pub(crate) fn new(sides: [f32; 3]) -> Self {
        let t = thickened_sides(sides);
        Self {
            sides: t,
            product: t[0] * t[1] * t[2],
        }
    }

    /// [`node_volume`] of this box.
    #[inline]
    pub(crate) fn volume(&self) -> f64 {
        if self.product.is_nan() {
            0.0
        } else {
            self.product
        }
    }
}

/// The overlap-volume estimate `V̂` used by the model: the box formula
/// ([`box_overlap_volume`]) when the two node volumes differ by at most
/// [`SIZE_RATIO_THRESHOLD`], otherwise the lens of the bounding spheres
/// ([`sphere_lens_volume`], radius = half the box diagonal), as in S1 §6.5.
///
/// Both use the sides thickened as in [`node_volume`] (flat nodes get a positive volume), and
/// the result is clamped to the smaller [`node_volume`]: it is an upper-bound-style estimate
/// `≤ min(node_volume(A), node_volume(B))`. The formula only sees the centre distance, so it is
/// positive for some disjoint boxes: run a real box-overlap test first. Never NaN.
pub fn overlap_volume(sides_a: [f32; 3], sides_b: [f32; 3], d: f32) -> f64 {
    overlap_volume_of(&ModelBox::new(sides_a), &ModelBox::new(sides_b), d)
}

/// [`overlap_volume`] of two prepared boxes.
#[inline]
pub(crate) fn overlap_volume_of(a: &ModelBox, b: &ModelBox, d: f32) -> f64 {
    let (ta, tb) = (a.sides, b.sides);
    let (va, vb) = (a.product, b.product);
    let (vmin, vmax) = if va <= vb { (va, vb) } else { (vb, va) };
    if vmin.is_nan() || vmin <= 0.0 {
        return 0.0;
    }
    let d = f64::from(d);
    let v = if vmax > SIZE_RATIO_THRESHOLD * vmin {
        let diagonal = |t: [f64; 3]| (t[0] * t[0] + t[1] * t[1] + t[2] * t[2]).sqrt();
        let (ra, rb) = (0.5 * diagonal(ta), 0.5 * diagonal(tb));
        sphere_lens_volume(ra, rb, d)
    } else {
        box_overlap_sorted(ta, tb, d)
    };
    if v.is_nan() { 0.0 } else { v.min(vmin) }
}

// ---------------------------------------------------------------------------------------------
// Cell counts
// ---------------------------------------------------------------------------------------------

/// The three integers of the balls-in-bins model for one node pair (S1 §6.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct CellCounts {
    /// Number of cells in `A ∩ B`.
    pub s: u32,
    /// Number of possible collision ("well-filled") cells of `A` in `A ∩ B`; `≤ s`.
    pub s_a: u32,
    /// Number of possible collision cells of `B` in `A ∩ B`; `≤ s`.
    pub s_b: u32,
}

/// `round(count · s / cells)` in exact integer arithmetic (halves round up).
#[inline]
fn scaled_count(count: u32, s: u32, cells: u32) -> u32 {
    let count = count.min(cells);
    // Grids of up to 2^15 cells per node (all the traversal meets: s and count ≤ cells) fit a
    // u32; larger ones a u64, and beyond 2^31 a 128-bit division.
    if cells <= 1 << 15 && s <= cells {
        return ((2 * count * s + cells) / (2 * cells)).min(s);
    }
    if count < 1 << 31 && s < 1 << 31 {
        let (count, s, cells) = (u64::from(count), u64::from(s), u64::from(cells));
        return ((2 * count * s + cells) / (2 * cells)).min(s) as u32;
    }
    let count = u128::from(count);
    let num = 2 * count * u128::from(s) + u128::from(cells);
    let r = num / (2 * u128::from(cells));
    r.min(u128::from(s)) as u32
}

/// The runtime numbers `s`, `s_A`, `s_B` of a node pair (the §1.4 reconstruction
/// *\[RECON\]*; the papers defer it):
///
/// - `v = max(volume_a, volume_b) / cells_per_node`: the cell volume of the coarser grid;
/// - `s = max(1, round(V̂ / v))`, at most `cells_per_node` (the overlap cannot hold more cells
///   than a node), and `s = 0` when `V̂ = 0` (no overlap: probability 0);
/// - `s_A = min(s, round(ρ_A · s))`, `s_B = min(s, round(ρ_B · s))` with the fill densities
///   `ρ = well_filled / cells_per_node` (counts above `cells_per_node` are clamped).
///
/// `volume_a`/`volume_b` should be [`node_volume`]s, `overlap_volume` an [`overlap_volume`].
/// Degenerate input: `cells_per_node = 0`, or `V̂` zero, negative or NaN, gives all zeros.
/// When both volumes are zero, NaN or infinite while `V̂ > 0` (the caller passed raw volumes
/// of flat nodes), there is no scale to measure `V̂` against, and the overlap is taken as a
/// whole node: `s = cells_per_node` (the conservative choice: it maximises the probability).
/// Integer rounding of `ρ·s` is exact (no float), halves round up. Never overflows.
pub fn cell_counts(
    overlap_volume: f64,
    volume_a: f64,
    volume_b: f64,
    well_filled_a: u32,
    well_filled_b: u32,
    cells_per_node: u32,
) -> CellCounts {
    cell_counts_of_grids(
        overlap_volume,
        (volume_a, well_filled_a, cells_per_node),
        (volume_b, well_filled_b, cells_per_node),
    )
}

/// [`cell_counts`] for two trees whose nodes have grids of different resolutions: each node
/// given as `(volume, well-filled cells, cells per node)`. `s` is counted in the finer grid
/// (`n = max(cells_a, cells_b)` cells per node), and each tree's fill density is its own:
/// `s_A = min(s, round(well_filled_a / cells_a · s))`, likewise `s_B`. With equal grids it is
/// [`cell_counts`]. A tree with 0 cells per node gives all zeros.
pub fn cell_counts_of_grids(
    overlap_volume: f64,
    (volume_a, well_filled_a, cells_a): (f64, u32, u32),
    (volume_b, well_filled_b, cells_b): (f64, u32, u32),
) -> CellCounts {
    let cells_per_node = cells_a.max(cells_b);
    if cells_a == 0 || cells_b == 0 || overlap_volume.is_nan() || overlap_volume <= 0.0 {
        return CellCounts::default();
    }
    // Positive and finite, else 0 (two comparisons: NaN fails both).
    let clean = |v: f64| if v > 0.0 && v < f64::INFINITY { v } else { 0.0 };
    let vmax = clean(volume_a).max(clean(volume_b));
    let n = cells_per_node;
    let s = if vmax > 0.0 {
        let cells = overlap_volume / vmax * f64::from(n);
        // `cells` > 0 here (both operands positive); it may be +inf. Rounded half up by
        // `+ 0.5` and truncation (saturating: +inf gives u32::MAX), which is `round` for every
        // value at least 0.5 below 2^52, and below 0.5 both give 1 after the clamp.
        ((cells + 0.5) as u32).clamp(1, n)
    } else {
        n
    };
    CellCounts {
        s,
        s_a: scaled_count(well_filled_a, s, cells_a),
        s_b: scaled_count(well_filled_b, s, cells_b),
    }
}

// ---------------------------------------------------------------------------------------------
// ln n!
// ---------------------------------------------------------------------------------------------

/// Entries of the cached `ln n!` table.
const LN_FACT_TABLE_LEN: usize = 4096;

static LN_FACT: LazyLock<Box<[f64]>> = LazyLock::new(|| {
    (0..LN_FACT_TABLE_LEN as u32)
        .map(ln_factorial_uncached)
        .collect()
});

/// `ln n!` without the table: exact product up to 22! (all exactly representable in `f64`),
/// Stirling's series (terms to `n⁻⁹`, truncation error below `10⁻¹⁷`) beyond.
fn ln_factorial_uncached(n: u32) -> f64 {
    if n <= 22 {
        let mut p = 1.0f64;
        for i in 2..=n {
            p *= f64::from(i);
        }
        return p.ln();
    }
    const HALF_LN_2PI: f64 = 0.918_938_533_204_672_8;
    let x = f64::from(n);
    (x + 0.5) * x.ln() - x + HALF_LN_2PI + stirling_series(x)
}

/// `1/(12x) − 1/(360x³) + 1/(1260x⁵) − 1/(1680x⁷) + 1/(1188x⁹)`: the correction terms of
/// Stirling's series for `ln x!`.
fn stirling_series(x: f64) -> f64 {
    let inv = 1.0 / x;
    let inv2 = inv * inv;
    inv * (1.0 / 12.0
        - inv2 * (1.0 / 360.0 - inv2 * (1.0 / 1260.0 - inv2 * (1.0 / 1680.0 - inv2 / 1188.0))))
}

/// `ln n!`, accurate to a few units in the last place (about `10⁻¹⁵` relative) for every `n`:
/// a lazily built table for `n < 4096` (32 KiB), Stirling's series beyond.
#[inline]
pub fn ln_factorial(n: u32) -> f64 {
    match LN_FACT.get(n as usize) {
        Some(&v) => v,
        None => ln_factorial_uncached(n),
    }
}

/// `ln(n! / (n − k)!)` for `k ≤ n`. Beyond the table it subtracts the two Stirling series
/// analytically, `(m + ½)·ln(1 + k/m) + k·ln n − k + series(n) − series(m)` with `m = n − k`,
/// so the rounding error is relative to the result, not to `ln n!` (10⁻¹² instead of 10⁻¹⁰
/// absolute at `n = 10⁵`).
fn ln_falling(n: u32, k: u32) -> f64 {
    if k == 0 {
        return 0.0;
    }
    let m = n - k;
    if (n as usize) < LN_FACT_TABLE_LEN || m <= 22 {
        return ln_factorial(n) - ln_factorial(m);
    }
    let (nf, mf, kf) = (f64::from(n), f64::from(m), f64::from(k));
    (mf + 0.5) * (kf / mf).ln_1p() + kf * nf.ln() - kf + stirling_series(nf) - stirling_series(mf)
}

// ---------------------------------------------------------------------------------------------
// Hypergeometric law
// ---------------------------------------------------------------------------------------------

/// `P(t) = C(s_B, t)·C(s − s_B, s_A − t) / C(s, s_A)` on its support `lo..=hi`.
#[derive(Debug, Clone, Copy)]
struct Hyper {
    s: f64,
    sa: f64,
    sb: f64,
    s_u: u32,
    sa_u: u32,
    sb_u: u32,
    lo: u32,
    hi: u32,
}

impl Hyper {
    /// Counts above `s` are clamped to `s`.
    fn new(s: u32, s_a: u32, s_b: u32) -> Self {
        let sa = s_a.min(s);
        let sb = s_b.min(s);
        let lo = (u64::from(sa) + u64::from(sb)).saturating_sub(u64::from(s)) as u32;
        Self {
            s: f64::from(s),
            sa: f64::from(sa),
            sb: f64::from(sb),
            s_u: s,
            sa_u: sa,
            sb_u: sb,
            lo,
            hi: sa.min(sb),
        }
    }

    /// `P(t+1) / P(t)` for `lo ≤ t < hi`.
    #[inline]
    fn ratio_up(&self, t: u32) -> f64 {
        let t = f64::from(t);
        ((self.sb - t) * (self.sa - t)) / ((t + 1.0) * (self.s - self.sa - self.sb + t + 1.0))
    }

    /// `P(t−1) / P(t)` for `lo < t ≤ hi`.
    #[inline]
    fn ratio_down(&self, t: u32) -> f64 {
        let t = f64::from(t);
        (t * (self.s - self.sa - self.sb + t)) / ((self.sb - t + 1.0) * (self.sa - t + 1.0))
    }

    /// A mode, `⌊(s_A+1)(s_B+1)/(s+2)⌋`, clamped to the support.
    fn mode(&self) -> u32 {
        let m =
            (u128::from(self.sa_u) + 1) * (u128::from(self.sb_u) + 1) / (u128::from(self.s_u) + 2);
        (m.min(u128::from(self.hi)) as u32).max(self.lo)
    }

    /// `ln P(lo)`, as a difference of two log falling factorials with the smaller count (the
    /// law is symmetric), so that the error scales with `ln P`'s parts, not with `ln s!`.
    fn ln_p_lo(&self) -> f64 {
        let (mn, mx) = (self.hi, self.sa_u.max(self.sb_u));
        let s = self.s_u;
        if self.lo == 0 {
            // P(0) = C(s − max, min) / C(s, min)
            ln_falling(s - mx, mn) - ln_falling(s, mn)
        } else {
            // P(lo) = min!·max! / (lo!·s!) = [min!/lo!] / [s!/max!], with min − lo = s − max.
            ln_falling(mn, s - mx) - ln_falling(s, s - mx)
        }
    }

    /// The streaming evaluation, accurate in relative terms for every tail. Calls
    /// `visit(x, U(x))` with the unnormalised upper tail `U(x) = Σ_{t ≥ x} w(t)` for every
    /// `x` in `lo < x ≤ min(k, hi)`, in descending order, and returns the normaliser
    /// `Σ_t w(t)`, so that `Pr[c ≥ x] = U(x) / returned`.
    ///
    /// The weights are anchored at the mode (`w = 1`, no overflow or underflow of the bulk) and
    /// summed outward, with the sums of positive terms only (no cancellation). Terms are dropped
    /// once a geometric bound (valid because the law is log-concave) shows the rest is below
    /// `2^-60` of the running sum; the cost is `O(k + width)`, the width being about 18
    /// standard deviations.
    fn walk(&self, k: u32, mut visit: impl FnMut(u32, f64)) -> f64 {
        let kk = k.min(self.hi);
        let m = self.mode();

        // Upward pass from the mode: find where the upper terms become negligible.
        let mut t = m;
        let mut w = 1.0f64;
        let mut beyond = if m > kk { 1.0 } else { 0.0 };
        while t < self.hi {
            let nw = w * self.ratio_up(t);
            if nw < WEIGHT_FLOOR {
                break; // every later term is below 10⁻²⁸⁰ of the mode: flushed to 0
            }
            t += 1;
            w = nw;
            if t > kk {
                beyond += w;
                if t < self.hi {
                    let r = self.ratio_up(t);
                    if r < 1.0 && w * r <= TRUNC_EPS * beyond * (1.0 - r) {
                        break;
                    }
                }
            }
        }

        // Tails above the last non-negligible term are 0.
        let mut x = kk;
        while x > t && x > self.lo {
            visit(x, 0.0);
            x -= 1;
        }

        // Downward pass: running suffix sums.
        let mut u = 0.0f64;
        loop {
            u += w;
            if t <= kk && t > self.lo {
                visit(t, u);
            }
            if t <= self.lo {
                break;
            }
            let nw = w * self.ratio_down(t);
            let negligible = nw < WEIGHT_FLOOR
                || (t - 1 > self.lo && {
                    let r = self.ratio_down(t - 1);
                    r < 1.0 && nw <= TRUNC_EPS * u * (1.0 - r)
                });
            if negligible {
                let mut x = (t - 1).min(kk);
                while x > self.lo {
                    visit(x, u);
                    x -= 1;
                }
                break;
            }
            t -= 1;
            w = nw;
        }
        u
    }

    /// The head path: for `x = lo+1, lo+2, …, kk` while the head `Σ_{lo ≤ t < x} P(t)` is at
    /// most ½, calls `emit(x, 1 − head)` (no cancellation worth the name: the result is at least
    /// ½). `P(lo)` comes from log space, the rest from the ratio recurrence, so this costs
    /// `O(x − lo)`. Stops early when `emit` returns `false`.
    ///
    /// The choice between this and [`Self::walk`] is made per `x` (by its own head), so a tail
    /// never depends on how many tails are asked for.
    fn head_pass(&self, kk: u32, mut emit: impl FnMut(u32, f64) -> bool) -> HeadEnd {
        let ln_p = self.ln_p_lo();
        if ln_p > HEAD_MIN_LN {
            let mut p = ln_p.exp();
            let mut head = 0.0f64;
            let mut x = self.lo + 1;
            while x <= kk {
                head += p;
                if head > 0.5 {
                    break;
                }
                if !emit(x, 1.0 - head) {
                    return HeadEnd::Stopped;
                }
                if x < kk {
                    p *= self.ratio_up(x - 1);
                }
                x += 1;
            }
            return if x > kk {
                HeadEnd::Done
            } else {
                HeadEnd::Walk(x)
            };
        }
        // P(lo) is near or below f64's range: measure the head scaled by 1/P(lo). When even
        // the head at kk is below 1e-304, every tail is 1 in f64.
        let mut p = 1.0f64;
        let mut head = 0.0f64;
        for x in self.lo + 1..=kk {
            head += p;
            if !head.is_finite() {
                break;
            }
            if x < kk {
                p *= self.ratio_up(x - 1);
            }
        }
        if head.is_finite() && head.ln() + ln_p < HEAD_NEGLIGIBLE_LN {
            for x in self.lo + 1..=kk {
                if !emit(x, 1.0) {
                    return HeadEnd::Stopped;
                }
            }
            return HeadEnd::Done;
        }
        HeadEnd::Walk(self.lo + 1)
    }

    /// `out[i] = Pr[c ≥ i + 1]` for every `i < out.len()`.
    fn tails_into(&self, out: &mut [f64]) {
        let len = u32::try_from(out.len()).unwrap_or(u32::MAX);
        // Trivial entries: forced (pigeonhole) collisions and impossible counts.
        for (i, o) in out.iter_mut().enumerate() {
            let x = i as u64 + 1;
            *o = if x <= u64::from(self.lo) {
                1.0
            } else if x > u64::from(self.hi) {
                0.0
            } else {
                continue;
            };
        }
        let kk = len.min(self.hi);
        if kk <= self.lo {
            return;
        }
        let end = self.head_pass(kk, |x, t| {
            out[x as usize - 1] = t;
            true
        });
        let HeadEnd::Walk(split) = end else {
            return;
        };
        // Small tails: streaming sums from the mode, relative accuracy kept.
        let total = self.walk(kk, |x, u| {
            if x >= split {
                out[x as usize - 1] = u;
            }
        });
        for o in &mut out[split as usize - 1..kk as usize] {
            *o = (*o / total).min(1.0);
        }
    }
}

/// How [`Hyper::head_pass`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum HeadEnd {
    /// Every requested `x` was emitted.
    Done,
    /// The callback asked to stop.
    Stopped,
    /// The tails from this `x` on are below ½: use the streaming path.
    Walk(u32),
}

/// Fills `out[i] = Pr[c(A∩B) ≥ i + 1]` (Eq. 8) for `i = 0..out.len()`, all in one pass of the
/// ratio recurrence. Same model, values and guarantees as [`prob_at_least`]; no allocation.
/// Entries are non-increasing in `i`. Counts above `s` are clamped to `s`.
pub fn tail_probabilities(s: u32, s_a: u32, s_b: u32, out: &mut [f64]) {
    Hyper::new(s, s_a, s_b).tails_into(out);
}

/// Eq. 8: the probability that at least `x` collision cells exist in `A ∩ B`,
///
/// ```text
/// Pr[c ≥ x] = 1 − Σ_{t<x} C(s_B, t)·C(s − s_B, s_A − t) / C(s, s_A)
/// ```
///
/// (the hypergeometric upper tail: `s` bins, `s_A` blue and `s_B` red balls, at most one ball
/// of each colour per bin). Symmetric in `s_A` and `s_B`.
///
/// - `x = 0` → 1; `x > min(s_A, s_B)` → 0 (so `s = 0`, `s_A = 0` or `s_B = 0` give 0 for
///   `x ≥ 1`).
/// - Pigeonhole: if `s_A + s_B > s`, at least `s_A + s_B − s` cells are forced to collide, and
///   the result is exactly 1 for `x ≤ s_A + s_B − s`.
/// - Counts above `s` are clamped to `s`.
///
/// Computed without binomials (see the [module docs](self)). Measured against exact rational
/// arithmetic: absolute error below `5·10⁻¹⁴` for `s ≤ 60` and about `2·10⁻¹³` at `s = 10⁵`;
/// tails below ½ keep a relative accuracy of about `10⁻¹³` down to `10⁻²⁷⁰`, below which they
/// are returned as 0. Cost `O(x)` when the result is at least ½, otherwise `O(x)` plus the
/// law's width (about 18 standard deviations). Always finite, in `[0, 1]`.
pub fn prob_at_least(s: u32, s_a: u32, s_b: u32, x: u32) -> f64 {
    if x == 0 {
        return 1.0;
    }
    let h = Hyper::new(s, s_a, s_b);
    if x <= h.lo {
        return 1.0;
    }
    if x > h.hi {
        return 0.0;
    }
    let mut result = 0.0;
    let end = h.head_pass(x, |xx, t| {
        result = t;
        xx < x
    });
    if !matches!(end, HeadEnd::Walk(_)) {
        return result;
    }
    let mut ux = 0.0;
    let total = h.walk(x, |xx, u| {
        if xx == x {
            ux = u;
        }
    });
    (ux / total).min(1.0)
}

/// `LB` clamped to `[0, 1]`, NaN as 0.
#[inline]
fn clamp_lb(lb: f64) -> f64 {
    if lb > 0.0 { lb.min(1.0) } else { 0.0 }
}

/// Eq. 9: the estimated probability that the polygons of a node pair intersect,
///
/// ```text
/// max_{1 ≤ x ≤ min(s_A, s_B, x_max)}  Pr[c ≥ x] · (1 − (1 − LB)^x)
/// ```
///
/// (`1 − (1 − LB)^x` is the chance that at least one of `x` collision cells really collides;
/// it is evaluated as `−expm1(x·ln(1 − LB))`, accurate even for tiny `LB`.) `LB` is clamped to
/// `[0, 1]` (NaN counts as 0): `LB = 0` gives 0, `LB = 1` gives `Pr[c ≥ 1]`. `x_max = 0`,
/// `s_A = 0` or `s_B = 0` give 0. The papers cap `x` at [`DEFAULT_X_MAX`]. Non-decreasing in
/// `LB` and in `x_max`; always in `[0, 1]`. All tails come from one pass of the recurrence, and
/// the scan stops as soon as no larger `x` can win; no allocation.
///
/// The traversal should call
/// [`collision_probability_tabled`](super::tables::collision_probability_tabled) instead
/// (the same value within `3·10⁻⁸`, read from a table built once instead of evaluated).
pub fn collision_probability(counts: CellCounts, lb: f64, x_max: u32) -> f64 {
    let lb = clamp_lb(lb);
    if lb == 0.0 {
        return 0.0;
    }
    let h = Hyper::new(counts.s, counts.s_a, counts.s_b);
    let k = h.hi.min(x_max);
    if k == 0 {
        return 0.0;
    }
    // 1 − (1−LB)^x = −expm1(x·ln(1−LB)), accurate to a few ulps even for tiny LB.
    let g = (-lb).ln_1p();
    let f = |x: u32| -(f64::from(x) * g).exp_m1();
    // Forced collisions: Pr[c ≥ x] = 1 for x ≤ lo, where f is largest at min(lo, k).
    let mut best = if h.lo > 0 { f(h.lo.min(k)) } else { 0.0 };
    if k <= h.lo {
        return best.min(1.0);
    }
    let end = h.head_pass(k, |x, t| {
        if t <= best {
            return false; // tails are non-increasing and f ≤ 1: nothing later can win
        }
        best = best.max(t * f(x));
        true
    });
    if let HeadEnd::Walk(split) = end {
        let mut best_u = 0.0f64;
        let total = h.walk(k, |x, u| {
            if x >= split {
                best_u = best_u.max(u * f(x));
            }
        });
        best = best.max(best_u / total);
    }
    if best.is_nan() {
        0.0
    } else {
        best.clamp(0.0, 1.0)
    }
}

// ---------------------------------------------------------------------------------------------
// Curvature term
// ---------------------------------------------------------------------------------------------

/// The paper's curvature term (S1 §6.4): `LB ≈ (d_A + d_B) / (d_maxA + d_maxB)`, the node
/// depths over the hierarchies' maximum depths. 0 when both maximum depths are 0 (single-node
/// trees); clamped to `[0, 1]` (a depth above its maximum gives at most 1). No overflow.
#[inline]
pub fn depth_lower_bound(depth_a: u32, depth_b: u32, max_depth_a: u32, max_depth_b: u32) -> f64 {
    let num = f64::from(depth_a) + f64::from(depth_b);
    let den = f64::from(max_depth_a) + f64::from(max_depth_b);
    if den > 0.0 { (num / den).min(1.0) } else { 0.0 }
}

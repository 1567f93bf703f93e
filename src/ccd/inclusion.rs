//! The inclusion-based root finder behind every continuous test: the earliest time at which a
//! vertex meets a triangle, or an edge meets an edge, when every vertex moves linearly over the
//! step (in the spirit of Tight Inclusion CCD, Wang et al. 2021).
//!
//! Both tests look for a zero of a function `F(t, u, v)` in ℝ³ over a parameter box: for a
//! vertex `p` and a triangle `abc`, `F = p(t) − a(t) − u (b(t) − a(t)) − v (c(t) − a(t))` with
//! `u, v ≥ 0, u + v ≤ 1`; for edges `p₀p₁` and `q₀q₁`, `F = p₀(t) + u (p₁(t) − p₀(t)) − q₀(t) −
//! v (q₁(t) − q₀(t))` with `u, v ∈ [0, 1]`; `t ∈ [0, 1]`. With linear motion `F` is
//! *multilinear* (of degree at most one in each of `t`, `u`, `v`), so over any box its range
//! is the convex hull of its values at the box's eight corners: the corners give an inclusion
//! that is exact up to rounding. The solver splits boxes, earliest first, and discards a box
//! when some coordinate of `F` stays above `δ` or below `−δ` on all eight corners (there the
//! two features are more than `δ` apart, in the max norm). Corners are evaluated in `f64` from
//! `f32` input: rounding is far below any `δ` used here, so a discarded box never holds a root.
//!
//! What it promises, for a tolerance `δ` and a time tolerance `τ`:
//! - **No root is missed**: if the features meet at some time `t*` in the step, a time
//!   `t ≤ t*` is returned.
//! - **No early report far from contact**: at every time before the returned one, the
//!   features are more than `δ` apart (max norm) — except within `τ` of it, when the search
//!   stops on a box `τ` wide in time (very fast features) or on its box budget.
//! - The returned time is the lower end of the first box kept, so it errs early, never late.
use glam::DVec3;

/// A parameter box: `[t₀, t₁] × [u₀, u₁] × [v₀, v₁]`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cell {
    lo: [f64; 3],
    hi: [f64; 3],
}

/// Which function is searched: its corner values come from `eval`, its domain from `simplex`.
pub(crate) struct Problem<F: Fn(f64, f64, f64) -> DVec3> {
    /// `F(t, u, v)`.
    pub eval: F,
    /// `u + v ≤ 1` (vertex–face) rather than the unit square (edge–edge).
    pub simplex: bool,
}

/// The solver's tolerances and limits.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tolerances {
    /// `δ`: features closer than this (max norm) count as touching.
    pub distance: f64,
    /// `τ`: a box this narrow in time is not split in time.
    pub time: f64,
    /// `u` and `v` boxes this narrow are not split further.
    pub parameter: f64,
    /// Boxes examined before the search stops on the earliest box it still holds.
    pub max_cells: usize,
}

/// The earliest time in `[0, t_limit)` at which `F` comes within `δ` of zero (see the module
/// documentation), or `None`, searched within `window`, which must hold every such time
/// (outside it the features are known to be more than `δ` apart).
///
/// A depth-first branch and bound: the earlier half of a box is searched first, a box kept
/// (small enough, and not excluded) lowers the bound, boxes are cut at the bound and those
/// that start at or after it dropped. When the box budget runs out, the earliest start among the boxes kept
/// and not yet searched is the answer (early, never late).
pub(crate) fn earliest_root<F: Fn(f64, f64, f64) -> DVec3>(
    problem: &Problem<F>,
    tol: &Tolerances,
    window: (f64, f64),
    t_limit: f64,
    stack: &mut Vec<Cell>,
) -> Option<f64> {
    stack.clear();
    stack.push(Cell {
        lo: [window.0.max(0.0), 0.0, 0.0],
        hi: [window.1.min(1.0), 1.0, 1.0],
    });
    let mut limit = t_limit;
    let mut found = None;
    let mut examined = 0usize;
    while let Some(mut cell) = stack.pop() {
        if cell.lo[0] >= limit || (problem.simplex && cell.lo[1] + cell.lo[2] > 1.0) {
            continue;
        }
        // Only a root before the bound matters: the box ends there.
        cell.hi[0] = cell.hi[0].min(limit);
        if examined >= tol.max_cells {
            // Out of budget: the earliest box that might hold a root.
            let earliest = stack.iter().map(|c| c.lo[0]).fold(cell.lo[0], f64::min);
            return Some(earliest);
        }
        examined += 1;
        let corners = corner_values(problem, &cell);
        if excludes_zero(&corners, tol.distance) {
            continue;
        }
        let (split, widest) = split_dimension(&corners, &cell, tol);
        let Some(d) = split.filter(|_| widest > tol.distance) else {
            // Within tolerance here (or narrow in every parameter): a contact at `lo[0]`.
            limit = cell.lo[0];
            found = Some(limit);
            continue;
        };
        let mid = 0.5 * (cell.lo[d] + cell.hi[d]);
        let (mut first, mut second) = (cell, cell);
        first.hi[d] = mid;
        second.lo[d] = mid;
        stack.push(second);
        stack.push(first);
    }
    found
}

/// `F` at the eight corners of `cell` (corner `k`: bit 0 picks `t`, bit 1 `u`, bit 2 `v`).
fn corner_values<F: Fn(f64, f64, f64) -> DVec3>(problem: &Problem<F>, cell: &Cell) -> [DVec3; 8] {
    std::array::from_fn(|k| {
        let pick = |d: usize| {
            if k >> d & 1 == 0 {
                cell.lo[d]
            } else {
                cell.hi[d]
            }
        };
        (problem.eval)(pick(0), pick(1), pick(2))
    })
}

/// Whether some coordinate of `F` is above `δ` (or below `−δ`) at every corner.
fn excludes_zero(corners: &[DVec3; 8], delta: f64) -> bool {
    let (mut lo, mut hi) = (corners[0], corners[0]);
    for c in &corners[1..] {
        lo = lo.min(*c);
        hi = hi.max(*c);
    }
    lo.cmpgt(DVec3::splat(delta)).any() || hi.cmplt(DVec3::splat(-delta)).any()
}

/// The dimension to split (the one along which `F` varies most, among those still wider than
/// their tolerance) and the widest extent of `F`'s range over the box (max norm).
fn split_dimension(corners: &[DVec3; 8], cell: &Cell, tol: &Tolerances) -> (Option<usize>, f64) {
    let (mut lo, mut hi) = (corners[0], corners[0]);
    for c in &corners[1..] {
        lo = lo.min(*c);
        hi = hi.max(*c);
    }
    let widest = (hi - lo).max_element();
    let mut best: Option<(usize, f64)> = None;
    for d in 0..3 {
        let min_width = if d == 0 { tol.time } else { tol.parameter };
        if cell.hi[d] - cell.lo[d] <= min_width {
            continue;
        }
        // How much F changes along d: the largest change between corners that differ in d only.
        let bit = 1 << d;
        let change = (0..8)
            .filter(|k| k & bit == 0)
            .map(|k| (corners[k | bit] - corners[k]).abs().max_element())
            .fold(0.0, f64::max);
        if best.is_none_or(|(_, c)| change > c) {
            best = Some((d, change));
        }
    }
    (best.map(|(d, _)| d), widest)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tol() -> Tolerances {
        Tolerances {
            distance: 1e-9,
            time: 1e-6,
            parameter: 1e-9,
            max_cells: 1_000_000,
        }
    }

    #[test]
    fn a_point_crossing_a_plane_is_found_at_its_time() {
        // A point moving along z from 1 to -1 through the triangle z = 0: root at t = 0.5.
        let problem = Problem {
            eval: |t: f64, u: f64, v: f64| {
                let p = DVec3::new(0.2, 0.2, 1.0 - 2.0 * t);
                p - (DVec3::ZERO + u * DVec3::X + v * DVec3::Y)
            },
            simplex: true,
        };
        let t = earliest_root(&problem, &tol(), (0.0, 1.0), 1.0, &mut Vec::new()).unwrap();
        assert!((t - 0.5).abs() < 1e-6, "{t}");
        assert!(t <= 0.5);
        // Not before a limit earlier than the root.
        assert!(earliest_root(&problem, &tol(), (0.0, 1.0), 0.4, &mut Vec::new()).is_none());
    }

    #[test]
    fn a_point_passing_beside_the_triangle_is_not_a_root() {
        let problem = Problem {
            eval: |t: f64, u: f64, v: f64| {
                let p = DVec3::new(0.6, 0.6, 1.0 - 2.0 * t); // u + v = 1.2 > 1
                p - (u * DVec3::X + v * DVec3::Y)
            },
            simplex: true,
        };
        assert!(earliest_root(&problem, &tol(), (0.0, 1.0), 1.0, &mut Vec::new()).is_none());
    }
}

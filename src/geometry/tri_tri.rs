//! Exact triangle–triangle intersection test on closed triangles.
//!
//! Every decision is the sign of an exact adaptive predicate ([`robust::orient3d`],
//! [`robust::orient2d`]) evaluated on the `f64` corners, which are taken as exact. No tolerance is
//! involved anywhere, so the answer is right for touching, coplanar, sliver and degenerate input
//! at any scale and any distance from the origin.
//!
//! # Algorithm
//!
//! * **Boxes apart**: triangles whose bounding boxes are apart along an axis are disjoint (a
//!   comparison of the given coordinates, exact), before any predicate.
//! * **Fast path** (both triangles proper and not coplanar): the interval formulation of
//!   Guigue & Devillers, *Faster triangle-triangle intersection tests* (2003). Three `orient3d` of
//!   `b`'s corners against `a`'s plane (early out when all strictly on one side), three of `a`'s
//!   corners against `b`'s plane (same), then two `orient3d` that compare the ends of the two
//!   intervals `a ∩ L` and `b ∩ L` on the line `L` where the planes meet. The permutation logic
//!   is derived afresh (see [`pivot`] and the comments in [`triangles_intersect`]) rather than
//!   copied from the published tables.
//! * **Slow path** (rare: coplanar triangles, or a degenerate triangle, which has all four-point
//!   orientations zero): each triangle is classified exactly as a proper triangle, a segment
//!   (collinear corners) or a point, and the pair is decided by exact segment–triangle,
//!   point–triangle, segment–segment or point tests. Coplanar work is done in the coordinate
//!   plane where a proper triangle's projection is non-degenerate (dropping a coordinate is
//!   exact); two coplanar proper triangles are disjoint iff an edge line of one has the other
//!   strictly outside (at most 20 `orient2d`).

use glam::{DVec3, Vec3};
use robust::{Coord, orient2d};

use super::predicates::orient3d as o3;

/// Exact triangle–triangle intersection test. Touching counts as intersecting.
///
/// Returns `true` iff the two *closed* triangles share at least one point: a shared vertex, a
/// shared edge, a vertex on the other's face, edges touching or crossing, coplanar overlap, ….
/// Degenerate triangles are handled as the point sets they are: collinear corners give a
/// segment, three equal corners a point. The corners are taken as exact `f64` values and every
/// sign comes from an exact predicate, so the result is exact as long as the predicates'
/// intermediate products neither overflow nor underflow: always for corners in the `f32`
/// range (the crate's storage), and for `f64` corners whose nonzero coordinates and nonzero
/// coordinate differences are roughly within `[1e-60, 1e60]` in magnitude. Corners beyond
/// about `2^300 ≈ 2e90` (where orientations could overflow), or all below about `2^-200 ≈
/// 6e-61` (where they could underflow), are first scaled by a power of two, which is exact,
/// so larger and smaller finite input is decided just as exactly (short of coordinates far
/// smaller than the largest one underflowing). A triangle with a NaN or infinite coordinate is no point set: the result is
/// `false`.
#[inline]
pub fn triangles_intersect(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    // Boxes apart along an axis: disjoint (comparisons of the given coordinates, exact; a NaN
    // compares false and is left to the test below).
    let (a_lo, a_hi) = (a[0].min(a[1]).min(a[2]), a[0].max(a[1]).max(a[2]));
    let (b_lo, b_hi) = (b[0].min(b[1]).min(b[2]), b[0].max(b[1]).max(b[2]));
    if a_hi.cmplt(b_lo).any() || b_hi.cmplt(a_lo).any() {
        return false;
    }
    // The sum of all |coordinates| bounds each of them, and is NaN or infinite when one is
    // (and NaN compares false): one branch on the hot path.
    let sum =
        (a[0].abs() + a[1].abs() + a[2].abs() + b[0].abs() + b[1].abs() + b[2].abs()).element_sum();
    if sum <= MAX_DIRECT && (sum >= MIN_DIRECT || sum == 0.0) {
        intersect_in_range(a, b)
    } else {
        intersect_out_of_range(a, b)
    }
}

/// Smallest nonzero sum of coordinate magnitudes decided without rescaling: below it the
/// predicates' products could underflow, so the corners are scaled up by a power of two first.
const MIN_DIRECT: f64 = 6.223_015_277_861_142e-61; // 2^-200

/// Largest sum of coordinate magnitudes decided without rescaling: coordinates are then at most
/// `2^300` and differences `2^301`, so the orientations' products (degree 3, at most `2^906`)
/// cannot overflow.
const MAX_DIRECT: f64 = 2.037_035_976_334_486e90; // 2^300

/// [`triangles_intersect`] for corners beyond [`MAX_DIRECT`], all below [`MIN_DIRECT`], or not
/// finite: `false` for a NaN or infinite corner, else the test on the corners scaled by a
/// power of two that brings the largest coordinate to between 1/2 and 1 (exact, short of
/// underflow of coordinates far smaller than the largest).
#[cold]
fn intersect_out_of_range(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    let corners = a.iter().chain(b);
    if !corners.clone().all(|p| p.is_finite()) {
        return false;
    }
    let m = corners.fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let e = -(m.log2().ceil() as i32);
    // 2^e may not be a finite f64 itself (e up to 1074 for subnormal input): two steps.
    let (k1, k2) = (2f64.powi(e / 2), 2f64.powi(e - e / 2));
    let scale = |p: DVec3| p * k1 * k2;
    intersect_in_range(&a.map(scale), &b.map(scale))
}

/// The test on corners within [`MAX_DIRECT`].
#[inline(always)]
fn intersect_in_range(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    // Sides of b's corners with respect to a's plane.
    let sb = [
        sign(o3(a[0], a[1], a[2], b[0])),
        sign(o3(a[0], a[1], a[2], b[1])),
        sign(o3(a[0], a[1], a[2], b[2])),
    ];
    if all_strictly_same(sb) {
        return false;
    }
    // All zero: `a` is degenerate (its orientation with any fourth point is zero), or `a` is
    // proper and `b` lies in its plane.
    if sb == [0, 0, 0] {
        return intersect_slow(a, b, true);
    }
    // From here on `a` is proper (one of its orientations is nonzero) and `b` is not in its
    // plane. Sides of a's corners with respect to b's plane.
    let sa = [
        sign(o3(b[0], b[1], b[2], a[0])),
        sign(o3(b[0], b[1], b[2], a[1])),
        sign(o3(b[0], b[1], b[2], a[2])),
    ];
    if all_strictly_same(sa) {
        return false;
    }
    // All zero with `b` not in a's plane: `b` is degenerate.
    if sa == [0, 0, 0] {
        return intersect_slow(a, b, false);
    }

    // Both triangles are proper, the planes are not parallel and each plane meets the other
    // triangle. a ∩ plane(b) and b ∩ plane(a) are segments (or points) of the line L common to
    // both planes, and the triangles meet iff these two intervals of L overlap.
    //
    // Rotate each triangle (cyclically, which keeps its plane orientation) so that its first
    // corner `p` is the pivot: the two edges leaving `p` each cut the other plane in exactly
    // one point, and those two points are the ends of the interval (see `pivot`).
    let (ia, ea) = pivot(sa);
    let (ib, eb) = pivot(sb);
    let (p1, q1, r1) = (a[ia], a[(ia + 1) % 3], a[(ia + 2) % 3]);
    let (p2, q2, r2) = (b[ib], b[(ib + 1) % 3], b[(ib + 2) % 3]);
    // With n_a = (q1-p1)×(r1-p1), n_b = (q2-p2)×(r2-p2) and L directed along n_a×n_b, the end on
    // edge p1-r1 comes first along L when p1 is on the positive side of n_b, which for robust's
    // sign convention (orient3d > 0 means "below") is `ea < 0`; for b the end on p2-q2 comes
    // first when p2 is on the positive side of n_a, i.e. `eb < 0`.
    let (lo_a, hi_a) = if ea < 0 { (r1, q1) } else { (q1, r1) };
    let (lo_b, hi_b) = if eb < 0 { (q2, r2) } else { (r2, q2) };
    // For X on edge p1-u and Y on edge p2-v, orient3d(p1, u, p2, v) has the sign of
    // (Y - X)·(n_a×n_b) times -ea·eb (zero iff X == Y). The intervals overlap iff
    // lo_b <= hi_a and lo_a <= hi_b along L.
    let e = f64::from(ea * eb);
    e * o3(p1, hi_a, p2, lo_b) >= 0.0 && e * o3(p1, lo_a, p2, hi_b) <= 0.0
}

/// [`triangles_intersect`] on `f32` corners (converted exactly to `f64`).
pub fn triangles_intersect_f32(a: [Vec3; 3], b: [Vec3; 3]) -> bool {
    triangles_intersect(&a.map(|p| p.as_dvec3()), &b.map(|p| p.as_dvec3()))
}

/// A point shared by the closed triangles `a` and `b`, or `None` when they are disjoint.
///
/// `Some` exactly when [`triangles_intersect`] is `true` (the decision uses the same exact
/// predicates). The point is, in this order of preference, found on an edge of `a` meeting `b`
/// or on an edge of `b` meeting `a` (one always exists when the triangles meet): a corner lying
/// on the other triangle (returned exactly), the point where an edge crosses the other
/// triangle's plane (interpolated from the exact orientations, accurate to rounding), or the
/// crossing point of two coplanar edges (likewise).
pub(crate) fn intersection_point(a: &[DVec3; 3], b: &[DVec3; 3]) -> Option<DVec3> {
    let shape_a = Shape::of(a);
    let shape_b = Shape::of(b);
    for i in 0..3 {
        if let Some(x) = segment_shape_point(a[i], a[(i + 1) % 3], b, shape_b) {
            return Some(x);
        }
    }
    for i in 0..3 {
        if let Some(x) = segment_shape_point(b[i], b[(i + 1) % 3], a, shape_a) {
            return Some(x);
        }
    }
    None
}

// ---------------------------------------------------------------------------------------------
// Predicates and small helpers.

#[inline(always)]
fn sign(x: f64) -> i8 {
    i8::from(x > 0.0) - i8::from(x < 0.0)
}

#[inline(always)]
fn all_strictly_same(s: [i8; 3]) -> bool {
    (s[0] == 1 && s[1] == 1 && s[2] == 1) || (s[0] == -1 && s[1] == -1 && s[2] == -1)
}

/// Chooses the pivot corner `v` of a triangle from the sides `s` of its corners with respect to
/// the other plane (not all zero, not all strictly on one side), and returns it with the side
/// `e` (±1) that `v` is on, where a pivot on the plane counts as being on the side opposite the
/// other two corners.
///
/// The pivot is the corner such that the edges `v-u` and `v-w` to the two other corners each
/// meet the plane in exactly one point, and these two points bound the triangle's intersection
/// with the plane: `s[v]·s[u] <= 0`, `s[v]·s[w] <= 0`, neither edge lies in the plane, and the
/// third edge `u-w` does not cross the plane strictly (`s[u]·s[w] >= 0`). Such a corner always
/// exists: the lone corner of `(+,+,-)`, the zero corner of `(0,+,+)`, the nonzero corner of
/// `(+,0,0)`, a nonzero corner of `(+,-,0)`. Both edges then cross the plane in the same
/// direction, which the ordering argument in [`triangles_intersect`] relies on.
#[inline]
fn pivot(s: [i8; 3]) -> (usize, i8) {
    for v in 0..3 {
        let (sv, su, sw) = (s[v], s[(v + 1) % 3], s[(v + 2) % 3]);
        if sv * su <= 0 && sv * sw <= 0 && su * sw >= 0 && (sv != 0 || (su != 0 && sw != 0)) {
            return (v, if sv != 0 { sv } else { -su });
        }
    }
    unreachable!("pivot: sides {s:?} are all zero or all strictly on one side")
}

/// Drops coordinate `axis` (0 = x, 1 = y, 2 = z) of `p`; exact.
#[inline(always)]
fn proj(p: DVec3, axis: usize) -> Coord<f64> {
    match axis {
        0 => Coord { x: p.y, y: p.z },
        1 => Coord { x: p.z, y: p.x },
        _ => Coord { x: p.x, y: p.y },
    }
}

#[inline(always)]
fn o2(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>) -> i8 {
    sign(orient2d(a, b, c))
}

/// What a (possibly degenerate) triangle is as a point set, decided exactly.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shape {
    /// A proper triangle; the payload is a coordinate to drop so that its projection is a proper
    /// 2D triangle (the one with the largest projected area).
    Triangle(usize),
    /// Collinear corners, not all equal: the segment between the two extreme corners.
    Segment(DVec3, DVec3),
    /// Three equal corners.
    Point(DVec3),
}

impl Shape {
    fn of(t: &[DVec3; 3]) -> Shape {
        // The corners are collinear iff all three coordinate projections are.
        let mut best = (0usize, 0.0f64);
        for axis in 0..3 {
            let d = orient2d(proj(t[0], axis), proj(t[1], axis), proj(t[2], axis)).abs();
            if d > best.1 {
                best = (axis, d);
            }
        }
        if best.1 > 0.0 {
            return Shape::Triangle(best.0);
        }
        // Collinear: along the line, lexicographic order of the coordinates is monotone, so the
        // lexicographic extremes are the segment's ends (exact comparisons).
        let lex_less = |p: DVec3, q: DVec3| (p.x, p.y, p.z) < (q.x, q.y, q.z);
        let (mut lo, mut hi) = (t[0], t[0]);
        for &p in &t[1..] {
            if lex_less(p, lo) {
                lo = p;
            }
            if lex_less(hi, p) {
                hi = p;
            }
        }
        if lo == hi {
            Shape::Point(lo)
        } else {
            Shape::Segment(lo, hi)
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 2D tests in a coordinate plane (all exact).

/// `r` (known collinear with `p`, `q`) lies in the bounding box of `p`, `q`.
#[inline]
fn in_box_2d(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>) -> bool {
    p.x.min(q.x) <= r.x && r.x <= p.x.max(q.x) && p.y.min(q.y) <= r.y && r.y <= p.y.max(q.y)
}

/// Closed segments `pq` and `rs` meet (either may have zero length; collinear overlap counts).
fn segments_meet_2d(p: Coord<f64>, q: Coord<f64>, r: Coord<f64>, s: Coord<f64>) -> bool {
    let d1 = o2(p, q, r);
    let d2 = o2(p, q, s);
    let d3 = o2(r, s, p);
    let d4 = o2(r, s, q);
    (d1 * d2 < 0 && d3 * d4 < 0)
        || (d1 == 0 && in_box_2d(p, q, r))
        || (d2 == 0 && in_box_2d(p, q, s))
        || (d3 == 0 && in_box_2d(r, s, p))
        || (d4 == 0 && in_box_2d(r, s, q))
}

/// `x` lies in the closed proper 2D triangle `t`.
#[inline]
fn point_in_triangle_2d(x: Coord<f64>, t: [Coord<f64>; 3]) -> bool {
    let d1 = o2(t[0], t[1], x);
    let d2 = o2(t[1], t[2], x);
    let d3 = o2(t[2], t[0], x);
    let has_neg = d1 < 0 || d2 < 0 || d3 < 0;
    let has_pos = d1 > 0 || d2 > 0 || d3 > 0;
    !(has_neg && has_pos)
}

/// Closed segment `pq` meets the closed proper 2D triangle `t`.
fn segment_meets_triangle_2d(p: Coord<f64>, q: Coord<f64>, t: [Coord<f64>; 3]) -> bool {
    point_in_triangle_2d(p, t)
        || point_in_triangle_2d(q, t)
        || (0..3).any(|i| segments_meet_2d(p, q, t[i], t[(i + 1) % 3]))
}

/// Closed proper 2D triangles meet.
///
/// Two disjoint convex polygons are always separated by the line through an edge of one of
/// them (an edge of their Minkowski difference separates it from the origin), with the other
/// polygon strictly on the outer side. So the triangles meet iff no edge line has all three
/// corners of the other triangle strictly outside.
fn triangles_meet_2d(a: [Coord<f64>; 3], b: [Coord<f64>; 3]) -> bool {
    !(separated_by_an_edge_of(a, b) || separated_by_an_edge_of(b, a))
}

/// Some edge line of the proper 2D triangle `t` has all corners of `u` strictly outside `t`.
#[inline]
fn separated_by_an_edge_of(t: [Coord<f64>; 3], u: [Coord<f64>; 3]) -> bool {
    let outside = -o2(t[0], t[1], t[2]);
    (0..3).any(|i| u.iter().all(|&x| o2(t[i], t[(i + 1) % 3], x) == outside))
}

// ---------------------------------------------------------------------------------------------
// 3D tests (all exact).

/// Closed 3D segments `pq` and `rs` meet (zero lengths allowed).
///
/// They must be coplanar; then they meet iff their projections meet in all three coordinate
/// planes: necessary always, and sufficient because at least one of the projections is
/// injective on a plane (or line) containing both segments.
fn segments_meet_3d(p: DVec3, q: DVec3, r: DVec3, s: DVec3) -> bool {
    o3(p, q, r, s) == 0.0
        && (0..3).all(|axis| {
            segments_meet_2d(proj(p, axis), proj(q, axis), proj(r, axis), proj(s, axis))
        })
}

/// The line through `p`, `q` (not parallel to the plane of the proper triangle `t`) passes
/// through the closed triangle: the three edge orientations have no two strictly opposite signs
/// (they are the barycentric coordinates of the piercing point times one common factor).
#[inline]
fn line_pierces_triangle(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> bool {
    let d1 = sign(o3(p, q, t[0], t[1]));
    let d2 = sign(o3(p, q, t[1], t[2]));
    let d3 = sign(o3(p, q, t[2], t[0]));
    let has_neg = d1 < 0 || d2 < 0 || d3 < 0;
    let has_pos = d1 > 0 || d2 > 0 || d3 > 0;
    !(has_neg && has_pos)
}

/// Closed segment `pq` (possibly of zero length) meets the closed proper triangle `t`, whose
/// projection dropping `axis` is proper.
fn segment_meets_triangle_3d(p: DVec3, q: DVec3, t: &[DVec3; 3], axis: usize) -> bool {
    let sp = sign(o3(t[0], t[1], t[2], p));
    let sq = sign(o3(t[0], t[1], t[2], q));
    if sp * sq > 0 {
        return false;
    }
    if sp == 0 && sq == 0 {
        let t2 = t.map(|c| proj(c, axis));
        return segment_meets_triangle_2d(proj(p, axis), proj(q, axis), t2);
    }
    // The segment crosses or touches the plane in exactly one point, on the line pq.
    line_pierces_triangle(p, q, t)
}

/// The general exact test for any pair of (possibly degenerate) triangles.
///
/// Used by [`triangles_intersect`] for coplanar and degenerate input, with `coplanar_if_proper`
/// set when both triangles being proper implies that they are coplanar. For two proper
/// non-coplanar triangles it falls back on "some edge of one meets the other", which holds
/// because the common part of the two intervals on the planes' common line ends at an interval
/// end, and every interval end lies on an edge.
fn intersect_slow(a: &[DVec3; 3], b: &[DVec3; 3], coplanar_if_proper: bool) -> bool {
    match (Shape::of(a), Shape::of(b)) {
        (Shape::Triangle(axis), Shape::Triangle(axis_b)) => {
            let coplanar = coplanar_if_proper || (0..3).all(|i| o3(a[0], a[1], a[2], b[i]) == 0.0);
            if coplanar {
                triangles_meet_2d(a.map(|c| proj(c, axis)), b.map(|c| proj(c, axis)))
            } else {
                (0..3).any(|i| segment_meets_triangle_3d(a[i], a[(i + 1) % 3], b, axis_b))
                    || (0..3).any(|i| segment_meets_triangle_3d(b[i], b[(i + 1) % 3], a, axis))
            }
        }
        (Shape::Triangle(axis), Shape::Segment(p, q)) => segment_meets_triangle_3d(p, q, a, axis),
        (Shape::Segment(p, q), Shape::Triangle(axis)) => segment_meets_triangle_3d(p, q, b, axis),
        (Shape::Triangle(axis), Shape::Point(x)) => segment_meets_triangle_3d(x, x, a, axis),
        (Shape::Point(x), Shape::Triangle(axis)) => segment_meets_triangle_3d(x, x, b, axis),
        (Shape::Segment(p, q), Shape::Segment(r, s)) => segments_meet_3d(p, q, r, s),
        (Shape::Segment(p, q), Shape::Point(x)) | (Shape::Point(x), Shape::Segment(p, q)) => {
            segments_meet_3d(p, q, x, x)
        }
        (Shape::Point(x), Shape::Point(y)) => x == y,
    }
}

// ---------------------------------------------------------------------------------------------
// Witness points (for the closest-points query).

/// A point common to the closed segment `pq` (possibly of zero length) and the triangle `t`
/// whose exact shape is `shape`.
fn segment_shape_point(p: DVec3, q: DVec3, t: &[DVec3; 3], shape: Shape) -> Option<DVec3> {
    match shape {
        Shape::Triangle(axis) => segment_triangle_point(p, q, t, axis),
        Shape::Segment(r, s) => segment_segment_point(p, q, r, s),
        Shape::Point(x) => segments_meet_3d(p, q, x, x).then_some(x),
    }
}

fn segment_triangle_point(p: DVec3, q: DVec3, t: &[DVec3; 3], axis: usize) -> Option<DVec3> {
    let dp = o3(t[0], t[1], t[2], p);
    let dq = o3(t[0], t[1], t[2], q);
    let (sp, sq) = (sign(dp), sign(dq));
    if sp * sq > 0 {
        return None;
    }
    if sp == 0 && sq == 0 {
        let t2 = t.map(|c| proj(c, axis));
        if point_in_triangle_2d(proj(p, axis), t2) {
            return Some(p);
        }
        if point_in_triangle_2d(proj(q, axis), t2) {
            return Some(q);
        }
        return (0..3).find_map(|i| segment_segment_point(p, q, t[i], t[(i + 1) % 3]));
    }
    if !line_pierces_triangle(p, q, t) {
        return None;
    }
    if sp == 0 {
        return Some(p);
    }
    if sq == 0 {
        return Some(q);
    }
    // Opposite strict signs: dp / (dp - dq) is in (0, 1). The adaptive predicate returns a
    // close approximation of the determinant (exact sign), so the crossing point is accurate
    // to rounding.
    Some(p + (q - p) * (dp / (dp - dq)))
}

/// A point common to the closed 3D segments `pq` and `rs` (zero lengths allowed).
fn segment_segment_point(p: DVec3, q: DVec3, r: DVec3, s: DVec3) -> Option<DVec3> {
    if !segments_meet_3d(p, q, r, s) {
        return None;
    }
    // An end lying on the other segment is an exact answer.
    if segments_meet_3d(r, s, p, p) {
        return Some(p);
    }
    if segments_meet_3d(r, s, q, q) {
        return Some(q);
    }
    if segments_meet_3d(p, q, r, r) {
        return Some(r);
    }
    if segments_meet_3d(p, q, s, s) {
        return Some(s);
    }
    // A proper crossing of two non-parallel coplanar segments: interpolate in a coordinate
    // plane where the projection is injective on their plane, which is exactly where p and q
    // are strictly on opposite sides of rs (elsewhere the projections are collinear, all
    // orientations zero). Try the plane that best preserves theirs first.
    let n = (q - p).cross(s - r).abs();
    let best = if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    };
    for axis in [best, (best + 1) % 3, (best + 2) % 3] {
        let (r2, s2) = (proj(r, axis), proj(s, axis));
        let dp = orient2d(r2, s2, proj(p, axis));
        let dq = orient2d(r2, s2, proj(q, axis));
        if sign(dp) * sign(dq) < 0 {
            return Some(p + (q - p) * (dp / (dp - dq)));
        }
    }
    // Not reachable: a proper crossing has an injective projection.
    Some(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    #[test]
    fn max_direct_is_two_to_the_300() {
        assert_eq!(MAX_DIRECT, 2f64.powi(300));
        assert_eq!(MIN_DIRECT, 2f64.powi(-200));
    }

    /// Checks the answer under corner permutations, swapping and a few exact transforms.
    fn check(a: [DVec3; 3], b: [DVec3; 3], expected: bool) {
        const PERMS: [[usize; 3]; 6] = [
            [0, 1, 2],
            [1, 2, 0],
            [2, 0, 1],
            [0, 2, 1],
            [2, 1, 0],
            [1, 0, 2],
        ];
        for pa in PERMS {
            for pb in PERMS {
                for (scale, offset) in [(1.0, 0.0), (0.25, 0.0), (1024.0, 1.0e6)] {
                    let t = |t: &[DVec3; 3], p: [usize; 3]| p.map(|i| t[i] * scale + offset);
                    let (a2, b2) = (t(&a, pa), t(&b, pb));
                    assert_eq!(triangles_intersect(&a2, &b2), expected, "{a2:?} {b2:?}");
                    assert_eq!(triangles_intersect(&b2, &a2), expected, "{b2:?} {a2:?}");
                    assert_eq!(intersect_slow(&a2, &b2, false), expected, "{a2:?} {b2:?}");
                    assert_eq!(intersection_point(&a2, &b2).is_some(), expected);
                }
                // Far below the predicates' direct range (down to subnormal corners): scaled
                // up exactly first.
                for e in [-150, -400, -900, -1040] {
                    let k = 2f64.powi(e / 2) * 2f64.powi(e - e / 2);
                    let t = |t: &[DVec3; 3], p: [usize; 3]| p.map(|i| t[i] * k);
                    let (a2, b2) = (t(&a, pa), t(&b, pb));
                    assert_eq!(
                        triangles_intersect(&a2, &b2),
                        expected,
                        "2^{e}: {a2:?} {b2:?}"
                    );
                    assert_eq!(
                        triangles_intersect(&b2, &a2),
                        expected,
                        "2^{e}: {b2:?} {a2:?}"
                    );
                }
            }
        }
    }

    const T: [DVec3; 3] = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(4.0, 0.0, 0.0),
        DVec3::new(0.0, 4.0, 0.0),
    ];

    #[test]
    fn separated_by_plane() {
        check(T, [v(0., 0., 1.), v(1., 0., 1.), v(0., 1., 2.)], false);
    }

    #[test]
    fn piercing() {
        check(T, [v(1., 1., -1.), v(1., 1., 1.), v(5., 5., 0.5)], true);
    }

    #[test]
    fn lines_overlap_but_intervals_do_not() {
        // b crosses a's plane along y = 1, x in [5, 7]; a spans x in [0, 3] there.
        check(T, [v(5., 1., -1.), v(7., 1., -1.), v(6., 1., 1.)], false);
        // Intervals touching at one end point (x = 3 on a's hypotenuse at y = 1).
        check(T, [v(3., 1., -1.), v(5., 1., -1.), v(3., 1., 1.)], true);
    }

    #[test]
    fn vertex_on_face_and_edge_on_edge() {
        check(T, [v(1., 1., 0.), v(1., 1., 3.), v(2., 3., 3.)], true);
        check(T, [v(2., -1., 0.), v(2., 1., 0.), v(2., 0., 3.)], true);
        check(T, [v(2., -1., 1.), v(2., 1., 1.), v(2., 0., 3.)], false);
    }

    #[test]
    fn coplanar_cases() {
        // overlapping, nested, edge touching, vertex touching, disjoint
        check(T, [v(1., 1., 0.), v(5., 1., 0.), v(1., 5., 0.)], true);
        check(T, [v(1., 1., 0.), v(2., 1., 0.), v(1., 2., 0.)], true);
        check(T, [v(0., 0., 0.), v(4., 0., 0.), v(2., -3., 0.)], true);
        check(T, [v(4., 0., 0.), v(6., 0., 0.), v(6., 2., 0.)], true);
        check(T, [v(2.5, 2.0, 0.), v(6., 2., 0.), v(6., 5., 0.)], false);
        check(T, [v(2.0, 2.0, 0.), v(6., 2., 0.), v(6., 5., 0.)], true);
    }

    #[test]
    fn degenerate_cases() {
        let seg_through = [v(1., 1., -1.), v(1., 1., 1.), v(1., 1., 0.5)];
        check(T, seg_through, true);
        let seg_above = [v(1., 1., 0.5), v(1., 1., 1.), v(1., 1., 2.)];
        check(T, seg_above, false);
        let seg_in_plane = [v(-1., 1., 0.), v(5., 1., 0.), v(2., 1., 0.)];
        check(T, seg_in_plane, true);
        let pt_on_edge = [v(2., 2., 0.); 3];
        check(T, pt_on_edge, true);
        let pt_off = [v(2., 2.0000001, 0.); 3];
        check(T, pt_off, false);
        // segment vs segment: crossing, collinear overlap, collinear disjoint, skew
        let s1 = [v(0., 0., 0.), v(2., 2., 0.), v(1., 1., 0.)];
        check(s1, [v(0., 2., 0.), v(2., 0., 0.), v(2., 0., 0.)], true);
        check(s1, [v(2., 2., 0.), v(3., 3., 0.), v(3., 3., 0.)], true);
        check(s1, [v(2.5, 2.5, 0.), v(3., 3., 0.), v(3., 3., 0.)], false);
        check(s1, [v(0., 2., 1.), v(2., 0., 1.), v(2., 0., 1.)], false);
        check(s1, [v(1., 1., 0.); 3], true);
        check([v(1., 1., 0.); 3], [v(1., 1., 0.); 3], true);
        check([v(1., 1., 0.); 3], [v(1., 1., 1.); 3], false);
    }

    #[test]
    fn pivot_is_valid() {
        for s0 in -1..=1i8 {
            for s1 in -1..=1i8 {
                for s2 in -1..=1i8 {
                    let s = [s0, s1, s2];
                    if s == [0, 0, 0] || all_strictly_same(s) {
                        continue;
                    }
                    let (v, e) = pivot(s);
                    assert!(e == 1 || e == -1);
                    assert!(s[v] == e || (s[v] == 0 && s[(v + 1) % 3] == -e));
                }
            }
        }
    }

    /// Small-integer triangles hit every touching and degenerate configuration; the fast path
    /// must agree with the edge-based general test.
    #[test]
    fn fast_path_matches_general_on_grid() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            f64::from((state % 4) as u32) - 1.0
        };
        let mut hits = 0;
        for _ in 0..20_000 {
            let mut tri = || [(); 3].map(|_| v(next(), next(), next()));
            let (a, b) = (tri(), tri());
            let fast = triangles_intersect(&a, &b);
            assert_eq!(fast, intersect_slow(&a, &b, false), "{a:?} {b:?}");
            assert_eq!(fast, intersection_point(&a, &b).is_some(), "{a:?} {b:?}");
            hits += usize::from(fast);
        }
        assert!(hits > 1000);
    }

    #[test]
    fn f32_wrapper() {
        let a = T.map(|p| p.as_vec3());
        let b = [
            Vec3::new(1., 1., -1.),
            Vec3::new(1., 1., 1.),
            Vec3::new(5., 5., 0.5),
        ];
        assert!(triangles_intersect_f32(a, b));
    }
}

//! Closest points between points, segments and triangles.
//!
//! These are floating-point computations (the answer is a distance, not a sign), written to be
//! safe on every finite input: degenerate triangles (collinear or coincident corners), parallel
//! and zero-length segments never produce NaN. Inputs whose coordinates are within the `f32`
//! range (the crate's storage) never overflow the `f64` intermediates; for more extreme
//! magnitudes the computation is redone in coordinates rescaled by a power of two.
//!
//! The only exact part is the intersection decision of [`closest_points_triangle_triangle`],
//! which is [`triangles_intersect`].

use glam::DVec3;

use super::tri_tri::{intersection_point, triangles_intersect};

/// A pair of closest points and their distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoints {
    /// Distance between the two features (0 when they intersect).
    pub distance: f64,
    /// Closest point on the first feature.
    pub point_a: DVec3,
    /// Closest point on the second feature.
    pub point_b: DVec3,
}

impl ClosestPoints {
    #[inline]
    fn new(point_a: DVec3, point_b: DVec3) -> Self {
        ClosestPoints {
            distance: distance(point_a, point_b),
            point_a,
            point_b,
        }
    }
}

/// `|a - b|`, without spurious overflow or underflow of the squared length.
#[inline]
fn distance(a: DVec3, b: DVec3) -> f64 {
    let d = a - b;
    let l2 = d.length_squared();
    if l2 > 1e-290 && l2 < 1e290 {
        return l2.sqrt();
    }
    let m = d.abs().max_element();
    if m == 0.0 || !m.is_finite() {
        return m;
    }
    m * (d / m).length()
}

/// A triangle whose height relative to its longest edge, squared, is at most this, is handled
/// as its three edges: `h / L <= 1e-8`. The error of doing so is at most `h`, and below this
/// thinness the face-region arithmetic loses more than that to rounding.
const SLIVER: f64 = 1e-16;

/// Segments whose directions have `sin²(angle) <= PARALLEL` are treated as parallel.
const PARALLEL: f64 = 1e-26;

/// Closest point to `p` on the (possibly degenerate) triangle `tri`.
///
/// Ericson's Voronoi-region method (*Real-Time Collision Detection*, §5.1.5), with two
/// safeguards: a degenerate or extremely thin triangle (collinear or coincident corners;
/// `height / longest edge <= 1e-8`) is handled as the union of its three edges, and the
/// face-region point is the orthogonal projection onto the plane (better conditioned on slivers
/// than the barycentric formula). Never NaN for finite input.
#[inline]
pub fn closest_point_on_triangle(p: DVec3, tri: &[DVec3; 3]) -> DVec3 {
    let m = max_abs(&[tri[1] - tri[0], tri[2] - tri[0], p - tri[0]]);
    if in_safe_range(m) {
        return point_triangle(p, tri);
    }
    // Magnitudes whose 4th powers would overflow or underflow: redo the work in coordinates
    // scaled by a power of two (exact), then scale back.
    let k = rescale_factor(m, &[p, tri[0], tri[1], tri[2]]);
    let x = point_triangle(p * k, &tri.map(|c| c * k)) / k;
    if x.is_finite() { x } else { tri[0] }
}

/// Closest points between segments `p0p1` and `q0q1` (parallel and zero-length safe).
///
/// Ericson's clamped line–line method (*Real-Time Collision Detection*, §5.1.9), with the
/// unclamped parameter computed from the cross product of the directions (no cancellation for
/// nearly parallel segments). Either or both segments may have zero length; parallel segments
/// get one of their closest pairs. `point_a` is on `p0p1`, `point_b` on `q0q1`. Never NaN for
/// finite input.
#[inline]
pub fn closest_points_segment_segment(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> ClosestPoints {
    let m = max_abs(&[p1 - p0, q0 - p0, q1 - p0]);
    let (s, t) = if in_safe_range(m) {
        segment_params(p0, p1, q0, q1)
    } else {
        let k = rescale_factor(m, &[p0, p1, q0, q1]);
        segment_params(p0 * k, p1 * k, q0 * k, q1 * k)
    };
    let result = ClosestPoints::new(p0 + (p1 - p0) * s, q0 + (q1 - q0) * t);
    if result.point_a.is_finite() && result.point_b.is_finite() {
        result
    } else {
        // Differences overflowed (corners near the limits of f64): convex combinations cannot.
        ClosestPoints::new(p0 * (1.0 - s) + p1 * s, q0 * (1.0 - t) + q1 * t)
    }
}

/// Closest points between two (possibly degenerate) triangles; distance 0 when they intersect.
///
/// * When [`triangles_intersect`]`(a, b)` (exact), the result has `distance == 0.0` and
///   `point_a == point_b`, a point of `a ∩ b` accurate to rounding: a corner of one triangle
///   lying on the other (exact), else the point where an edge of one crosses the other (or, for
///   coplanar triangles, where two edges cross), interpolated from the exact orientations.
///   Edges of `a` against `b` are tried before edges of `b` against `a`.
/// * Otherwise the minimum over the 6 corner–triangle and 9 edge–edge candidates, which is the
///   distance of two disjoint triangles (degenerate ones included: their edges cover them).
///   Triangles apart by less than rounding may get a distance that rounds to 0.
///
/// `point_a` lies on `a`, `point_b` on `b`. Never NaN for finite input; for a NaN or infinite
/// corner the distance is `+∞` (such a triangle is no point set) and the points are the
/// first corners.
pub fn closest_points_triangle_triangle(a: &[DVec3; 3], b: &[DVec3; 3]) -> ClosestPoints {
    if !a.iter().chain(b).all(|p| p.is_finite()) {
        return ClosestPoints {
            distance: f64::INFINITY,
            point_a: a[0],
            point_b: b[0],
        };
    }
    let intersecting = triangles_intersect(a, b);
    if intersecting && let Some(x) = intersection_point(a, b) {
        return ClosestPoints {
            distance: 0.0,
            point_a: x,
            point_b: x,
        };
    }

    let m = max_abs(&[
        a[1] - a[0],
        a[2] - a[0],
        b[0] - a[0],
        b[1] - a[0],
        b[2] - a[0],
    ]);
    let best = if (1e-60..=1e60).contains(&m) {
        separated_in_range(a, b)
    } else {
        separated_any_range(a, b)
    };
    if intersecting {
        // Unreachable (the two exact tests agree); keep the promise of distance 0 anyway.
        let mid = best.point_a.midpoint(best.point_b);
        return ClosestPoints {
            distance: 0.0,
            point_a: mid,
            point_b: mid,
        };
    }
    best
}

/// The minimum over the 6 corner–triangle and 9 edge–edge candidates when every difference
/// of the corners is within `[1e-60, 1e60]` (twice that at most between two corners): the same
/// arithmetic as [`separated_any_range`] (whose parts check each candidate's range and rescale
/// where needed) with each triangle's edges and normal computed once. A candidate whose
/// points are all within 1e-70 of each other, which the checked path would rescale, is
/// computed as it is: never NaN, off by less than that scale.
#[inline]
fn separated_in_range(a: &[DVec3; 3], b: &[DVec3; 3]) -> ClosestPoints {
    let (frame_a, frame_b) = (TriangleFrame::new(a), TriangleFrame::new(b));
    // Compared by squared length (one square root at the end): the same order as by length
    // wherever the squares are normal, that is for every candidate farther apart than 1e-145.
    let mut best = (frame_a.closest(b[0]), b[0]);
    let mut best_sq = (best.0 - best.1).length_squared();
    let mut consider = |p: DVec3, q: DVec3| {
        let sq = (p - q).length_squared();
        if sq < best_sq {
            (best, best_sq) = ((p, q), sq);
        }
    };
    for &q in &b[1..] {
        consider(frame_a.closest(q), q);
    }
    for &p in a {
        consider(p, frame_b.closest(p));
    }
    let edges = |t: &[DVec3; 3]| [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    let (edges_a, edges_b) = (edges(a), edges(b));
    for i in 0..3 {
        for j in 0..3 {
            let (s, t) = segment_params_along(a[i], edges_a[i], b[j], edges_b[j]);
            consider(a[i] + edges_a[i] * s, b[j] + edges_b[j] * t);
        }
    }
    ClosestPoints::new(best.0, best.1)
}

/// The minimum over the 6 corner–triangle and 9 edge–edge candidates, each computed in
/// rescaled coordinates where its magnitudes need it.
fn separated_any_range(a: &[DVec3; 3], b: &[DVec3; 3]) -> ClosestPoints {
    let mut best = ClosestPoints::new(closest_point_on_triangle(b[0], a), b[0]);
    let mut consider = |c: ClosestPoints| {
        if c.distance < best.distance {
            best = c;
        }
    };
    for &q in &b[1..] {
        consider(ClosestPoints::new(closest_point_on_triangle(q, a), q));
    }
    for &p in a {
        consider(ClosestPoints::new(p, closest_point_on_triangle(p, b)));
    }
    for i in 0..3 {
        for j in 0..3 {
            consider(closest_points_segment_segment(
                a[i],
                a[(i + 1) % 3],
                b[j],
                b[(j + 1) % 3],
            ));
        }
    }
    best
}

// ---------------------------------------------------------------------------------------------

#[inline]
fn clamp01(x: f64) -> f64 {
    // NaN maps to 0.
    if x > 0.0 { x.min(1.0) } else { 0.0 }
}

/// `num / den` clamped to `[0, 1]`, and 0 when `den` is not positive.
#[inline]
fn ratio01(num: f64, den: f64) -> f64 {
    if den > 0.0 { clamp01(num / den) } else { 0.0 }
}

#[inline]
fn max_abs(v: &[DVec3]) -> f64 {
    v.iter().fold(0.0, |m, c| m.max(c.abs().max_element()))
}

/// Differences of magnitude `m` are safe when their 4th powers (the highest degree in these
/// computations) neither overflow nor underflow. Always true for `f32`-range coordinates.
#[inline]
fn in_safe_range(m: f64) -> bool {
    m == 0.0 || (1e-70..=1e70).contains(&m)
}

/// A power of two that brings the largest difference `m` (or, when the differences overflowed,
/// the largest coordinate of `points`) near 1. Multiplying by it is exact (short of underflow
/// of parts far below the scale of the problem).
fn rescale_factor(m: f64, points: &[DVec3]) -> f64 {
    let m = if m.is_finite() { m } else { max_abs(points) };
    if m.is_nan() || m <= 0.0 || m.is_infinite() {
        return 1.0;
    }
    let e = m.log2().round().clamp(-1000.0, 1000.0) as i32;
    2f64.powi(-e)
}

/// Closest point to `p` on the closed segment `ab` (zero length allowed).
#[inline]
fn closest_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    a + ab * ratio01((p - a).dot(ab), ab.length_squared())
}

fn point_triangle(p: DVec3, tri: &[DVec3; 3]) -> DVec3 {
    TriangleFrame::new(tri).closest(p)
}

/// A triangle's edge vectors and normal, computed once for the closest points of several
/// points ([`point_triangle`] is `TriangleFrame::new(tri).closest(p)`).
struct TriangleFrame {
    corners: [DVec3; 3],
    ab: DVec3,
    ac: DVec3,
    n: DVec3,
    nn: f64,
    /// Degenerate or hopelessly thin: handled as the union of its edges.
    thin: bool,
}

impl TriangleFrame {
    #[inline]
    fn new(&[a, b, c]: &[DVec3; 3]) -> Self {
        let ab = b - a;
        let ac = c - a;
        let n = ab.cross(ac);
        let nn = n.length_squared();
        let longest = ab
            .length_squared()
            .max(ac.length_squared())
            .max((c - b).length_squared());
        TriangleFrame {
            corners: [a, b, c],
            ab,
            ac,
            n,
            nn,
            thin: nn.is_nan() || nn <= SLIVER * longest * longest,
        }
    }

    #[inline]
    fn closest(&self, p: DVec3) -> DVec3 {
        let [a, b, c] = self.corners;
        let (ab, ac) = (self.ab, self.ac);
        if self.thin {
            // Degenerate (or hopelessly thin): the triangle is the union of its edges.
            let candidates = [
                closest_on_segment(p, a, b),
                closest_on_segment(p, b, c),
                closest_on_segment(p, c, a),
            ];
            return candidates
                .into_iter()
                .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
                .unwrap_or(a);
        }

        // Vertex region A.
        let ap = p - a;
        let d1 = ab.dot(ap);
        let d2 = ac.dot(ap);
        if d1 <= 0.0 && d2 <= 0.0 {
            return a;
        }
        // Vertex region B.
        let bp = p - b;
        let d3 = ab.dot(bp);
        let d4 = ac.dot(bp);
        if d3 >= 0.0 && d4 <= d3 {
            return b;
        }
        // Edge region AB.
        let vc = d1 * d4 - d3 * d2;
        if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            return a + ab * ratio01(d1, d1 - d3);
        }
        // Vertex region C.
        let cp = p - c;
        let d5 = ab.dot(cp);
        let d6 = ac.dot(cp);
        if d6 >= 0.0 && d5 <= d6 {
            return c;
        }
        // Edge region AC.
        let vb = d5 * d2 - d1 * d6;
        if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            return a + ac * ratio01(d2, d2 - d6);
        }
        // Edge region BC.
        let va = d3 * d6 - d5 * d4;
        let (e4, e5) = (d4 - d3, d5 - d6);
        if va <= 0.0 && e4 >= 0.0 && e5 >= 0.0 {
            return b + (c - b) * ratio01(e4, e4 + e5);
        }
        // Face region: orthogonal projection onto the plane.
        p - self.n * (self.n.dot(ap) / self.nn)
    }
}

/// Ericson's clamped segment parameters `(s, t)` in `[0, 1]²`.
fn segment_params(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (f64, f64) {
    segment_params_along(p0, p1 - p0, q0, q1 - q0)
}

/// [`segment_params`] of the segments from `p0` along `d1` and from `q0` along `d2`.
#[inline]
fn segment_params_along(p0: DVec3, d1: DVec3, q0: DVec3, d2: DVec3) -> (f64, f64) {
    let r = p0 - q0;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(r);
    if a.is_nan() || a <= 0.0 {
        // First segment is a point (or lengths overflowed; the caller then rescales).
        return (0.0, ratio01(f, e));
    }
    let c = d1.dot(r);
    if e.is_nan() || e <= 0.0 {
        return (ratio01(-c, a), 0.0);
    }
    let b = d1.dot(d2);
    let n = d1.cross(d2);
    let nn = n.length_squared();
    // s of the closest points of the two lines, (b f - c e) / (a e - b²), written as
    // n·(d2×r) / |n|² (Lagrange's identity) to avoid the cancellation in a e - b².
    let s = if nn > PARALLEL * a * e {
        clamp01(n.dot(d2.cross(r)) / nn)
    } else {
        0.0
    };
    let t_num = b * s + f;
    if t_num < 0.0 {
        (ratio01(-c, a), 0.0)
    } else if t_num > e {
        (ratio01(b - c, a), 1.0)
    } else {
        (s, t_num / e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    const T: [DVec3; 3] = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(4.0, 0.0, 0.0),
        DVec3::new(0.0, 4.0, 0.0),
    ];

    fn close(a: DVec3, b: DVec3) -> bool {
        a.distance(b) <= 1e-12 * (1.0 + a.abs().max_element())
    }

    /// The in-range path (each triangle's edges and normal computed once, candidates compared
    /// by squared length) gives the checked path's distance and closest points on random,
    /// nearly coplanar, degenerate and far-from-the-origin triangles: bit for bit, except
    /// where two candidates tie (a degenerate triangle's coinciding edges), and then within
    /// rounding.
    #[test]
    fn in_range_path_matches_the_checked_path() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::Xoshiro256PlusPlus::seed_from_u64(7);
        let mut point = |scale: f64, offset: f64| {
            DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * scale
                + DVec3::splat(offset)
        };
        let mut identical = 0;
        for k in 0..20_000 {
            let (scale, offset) = [(1.0, 0.0), (1e-3, 5.0), (1e4, -3e5), (1e-30, 1e-29)][k % 4];
            let mut a = [0; 3].map(|_| point(scale, offset));
            let mut b = [0; 3].map(|_| point(scale, offset));
            match k % 5 {
                // Degenerate: a repeated corner, collinear corners.
                1 => a[2] = a[0],
                2 => b[2] = b[0].lerp(b[1], 0.25),
                // Nearly coplanar and parallel.
                3 => b = a.map(|c| c + DVec3::new(0.0, 0.0, 1e-9 * scale)),
                _ => {}
            }
            let (fast, checked) = (separated_in_range(&a, &b), separated_any_range(&a, &b));
            if fast == checked {
                identical += 1;
                continue;
            }
            let near = |x: DVec3, y: DVec3| x.distance(y) <= 1e-12 * scale;
            assert!(
                (fast.distance - checked.distance).abs() <= 1e-14 * checked.distance
                    && near(fast.point_a, checked.point_a)
                    && near(fast.point_b, checked.point_b),
                "{a:?} {b:?}: {fast:?} {checked:?}"
            );
        }
        assert!(identical >= 19_000, "{identical} of 20000 bit for bit");
    }

    #[test]
    fn point_triangle_regions() {
        let cases = [
            (v(-1., -1., 3.), v(0., 0., 0.)), // vertex A
            (v(5., -1., 3.), v(4., 0., 0.)),  // vertex B
            (v(-1., 5., -3.), v(0., 4., 0.)), // vertex C
            (v(2., -3., 1.), v(2., 0., 0.)),  // edge AB
            (v(-3., 2., 1.), v(0., 2., 0.)),  // edge AC
            (v(3., 3., 7.), v(2., 2., 0.)),   // edge BC
            (v(1., 1., -5.), v(1., 1., 0.)),  // face
            (v(1., 1., 0.), v(1., 1., 0.)),   // on face
        ];
        for (p, want) in cases {
            assert!(close(closest_point_on_triangle(p, &T), want), "{p}");
            // Corner order does not matter.
            let t2 = [T[2], T[1], T[0]];
            assert!(close(closest_point_on_triangle(p, &t2), want), "{p}");
        }
    }

    #[test]
    fn point_degenerate_triangles() {
        let seg = [v(0., 0., 0.), v(4., 0., 0.), v(2., 0., 0.)];
        assert!(close(
            closest_point_on_triangle(v(1., 1., 1.), &seg),
            v(1., 0., 0.)
        ));
        assert!(close(
            closest_point_on_triangle(v(9., 1., 1.), &seg),
            v(4., 0., 0.)
        ));
        let seg2 = [v(1., 1., 1.), v(1., 1., 1.), v(3., 1., 1.)];
        assert!(close(
            closest_point_on_triangle(v(2., 5., 1.), &seg2),
            v(2., 1., 1.)
        ));
        let pt = [v(1., 2., 3.); 3];
        assert_eq!(closest_point_on_triangle(v(9., 9., 9.), &pt), v(1., 2., 3.));
        // Exactly collinear far from the origin, where the cross product rounds to nonzero.
        let far = [
            v(1e6 + 0.1, 1e6 + 0.2, 1e6 + 0.3),
            v(1e6 + 0.7, 1e6 + 1.4, 1e6 + 2.1),
            v(1e6 + 0.3, 1e6 + 0.6, 1e6 + 0.9),
        ];
        let x = closest_point_on_triangle(v(0., 0., 0.), &far);
        assert!(x.is_finite());
    }

    #[test]
    fn never_nan_on_extreme_input() {
        for s in [1e-300, 1e-160, 1e160, 1e300] {
            let t = T.map(|c| c * s);
            let x = closest_point_on_triangle(v(1., 1., -1.) * s, &t);
            assert!(x.is_finite(), "{s}: {x}");
            assert!(close(x / s, v(1., 1., 0.)), "{s}: {x}");
            let r = closest_points_segment_segment(t[0], t[1], t[2], t[2] + v(s, s, s));
            assert!(r.point_a.is_finite() && r.point_b.is_finite());
            assert!((r.distance / s - 4.0).abs() < 1e-12, "{s}: {r:?}");
        }
        // The triangle–triangle query relies on the exact predicates, which must not underflow.
        for s in [1e-60, 1e-20, 1e20, 1e60] {
            let t = T.map(|c| c * s);
            let r = closest_points_triangle_triangle(&t, &t.map(|c| c + v(0., 0., 2.0 * s)));
            assert!((r.distance / s - 2.0).abs() < 1e-12, "{s}: {r:?}");
        }
    }

    #[test]
    fn segment_segment_cases() {
        // Crossing.
        let r = closest_points_segment_segment(
            v(0., 0., 0.),
            v(2., 2., 0.),
            v(0., 2., 1.),
            v(2., 0., 1.),
        );
        assert!(close(r.point_a, v(1., 1., 0.)) && close(r.point_b, v(1., 1., 1.)));
        assert!((r.distance - 1.0).abs() < 1e-12);
        // Endpoint to interior.
        let r = closest_points_segment_segment(
            v(0., 0., 0.),
            v(2., 0., 0.),
            v(1., 3., 0.),
            v(1., 5., 0.),
        );
        assert!(close(r.point_a, v(1., 0., 0.)) && close(r.point_b, v(1., 3., 0.)));
        // Parallel, overlapping and not.
        let r = closest_points_segment_segment(
            v(0., 0., 0.),
            v(2., 0., 0.),
            v(1., 1., 0.),
            v(3., 1., 0.),
        );
        assert!((r.distance - 1.0).abs() < 1e-12);
        let r = closest_points_segment_segment(
            v(0., 0., 0.),
            v(2., 0., 0.),
            v(5., 1., 0.),
            v(3., 1., 0.),
        );
        assert!(close(r.point_a, v(2., 0., 0.)) && close(r.point_b, v(3., 1., 0.)));
        let r = closest_points_segment_segment(
            v(0., 0., 0.),
            v(2., 0., 0.),
            v(-1., 1., 0.),
            v(-3., 1., 0.),
        );
        assert!(close(r.point_a, v(0., 0., 0.)) && close(r.point_b, v(-1., 1., 0.)));
        // Zero-length, either or both.
        let r = closest_points_segment_segment(
            v(1., 1., 1.),
            v(1., 1., 1.),
            v(0., 0., 0.),
            v(2., 0., 0.),
        );
        assert!(close(r.point_b, v(1., 0., 0.)));
        let r = closest_points_segment_segment(
            v(0., 0., 0.),
            v(2., 0., 0.),
            v(3., 1., 1.),
            v(3., 1., 1.),
        );
        assert!(close(r.point_a, v(2., 0., 0.)));
        let r = closest_points_segment_segment(
            v(0., 0., 0.),
            v(0., 0., 0.),
            v(3., 4., 0.),
            v(3., 4., 0.),
        );
        assert_eq!(r.distance, 5.0);
    }

    #[test]
    fn triangle_triangle_cases() {
        // Piercing: the witness is where b's edge crosses a.
        let b = [v(1., 1., -1.), v(1., 1., 1.), v(9., 9., 9.)];
        let r = closest_points_triangle_triangle(&T, &b);
        assert_eq!(r.distance, 0.0);
        assert_eq!(r.point_a, r.point_b);
        assert!(close(r.point_a, v(1., 1., 0.)), "{r:?}");
        // Parallel planes one apart.
        let b = [v(1., 1., 1.), v(2., 1., 1.), v(1., 2., 1.)];
        let r = closest_points_triangle_triangle(&T, &b);
        assert!((r.distance - 1.0).abs() < 1e-12);
        // Edge-edge.
        let b = [v(3., 3., -1.), v(3., 3., 1.), v(5., 5., 0.)];
        let r = closest_points_triangle_triangle(&T, &b);
        assert!((r.distance - 2f64.sqrt()).abs() < 1e-12, "{r:?}");
        assert!(close(r.point_a, v(2., 2., 0.)) && close(r.point_b, v(3., 3., 0.)));
        // Degenerate against degenerate.
        let s = [v(0., 0., 1.), v(1., 0., 1.), v(2., 0., 1.)];
        let p = [v(1., 3., 1.); 3];
        let r = closest_points_triangle_triangle(&s, &p);
        assert!((r.distance - 3.0).abs() < 1e-12 && close(r.point_a, v(1., 0., 1.)));
        // Coplanar crossing edges: the witness is on both.
        let b = [v(1., -1., 0.), v(1., 5., 0.), v(-3., 2., 0.)];
        let r = closest_points_triangle_triangle(&T, &b);
        assert_eq!(r.distance, 0.0);
        assert!(closest_point_on_triangle(r.point_a, &T).distance(r.point_a) < 1e-12);
        assert!(closest_point_on_triangle(r.point_a, &b).distance(r.point_a) < 1e-12);
    }
}

//! Continuous tests of one pair of features moving linearly over the step: a vertex against a
//! triangle, an edge against an edge. Positions are given at the start and the end of the step
//! (in `f64`); the answer is the earliest time of contact in `[0, 1]` (see
//! [`inclusion`](super::inclusion) for what is promised).
use glam::DVec3;

use super::inclusion::{Cell, Problem, Tolerances, earliest_root};
use super::motion::Trajectory;
use super::window::{MovingBox, overlap_window};

/// The tolerances of a continuous test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrimitiveTolerances {
    /// Features closer than this (in every coordinate) count as touching.
    pub distance: f64,
    /// A time interval this short is not split further (the answer's time resolution where
    /// the features move fast).
    pub time: f64,
    /// Boxes of the parameter space examined before the search stops on the earliest one it
    /// holds (an early, conservative answer).
    pub max_cells: usize,
}

impl Default for PrimitiveTolerances {
    fn default() -> Self {
        Self {
            distance: 1e-7,
            time: 1e-6,
            max_cells: 100_000,
        }
    }
}

impl PrimitiveTolerances {
    fn solver(&self) -> Tolerances {
        Tolerances {
            distance: self.distance,
            time: self.time,
            parameter: 1e-9,
            max_cells: self.max_cells,
        }
    }
}

/// Where within `window` the features can be within `delta` (max norm) of each other, judged
/// by their distance from the plane through them: `None` when they stay on one side of it,
/// farther than that, for all of the window (a cheap proof that they do not meet), else the
/// part of the window outside of which they do (never narrower than the true part).
///
/// `e1`, `e2` span the plane (the face's edges, or the two edges' directions) and `d` goes from
/// the plane's point to the other feature, each given by a function of time that is linear
/// over the window; so `n = e1 × e2` is quadratic in time and `f = n · d` cubic, and their
/// Bernstein coefficients over a window bound them. Where `|f| / |n|`, the distance from the
/// plane, exceeds `√3 δ` (a Euclidean distance that large is more than `δ` in the max norm),
/// the features are apart. The curve `f` lies in the convex hull of its control points, so the
/// times where the hull meets the band `|f| ≤ √3 δ max |n|` hold every time it can be close:
/// the window is clipped to them (Bézier clipping) and the clip repeated while it narrows the
/// window by more than a fifth.
fn plane_window(
    ends: impl Fn(f64, f64) -> [[DVec3; 2]; 3],
    delta: f64,
    window: (f64, f64),
) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = window;
    for _ in 0..6 {
        let [e1, e2, d] = ends(lo, hi);
        let n = [
            e1[0].cross(e2[0]),
            0.5 * (e1[0].cross(e2[1]) + e1[1].cross(e2[0])),
            e1[1].cross(e2[1]),
        ];
        let f = [
            n[0].dot(d[0]),
            (2.0 * n[1].dot(d[0]) + n[0].dot(d[1])) / 3.0,
            (n[2].dot(d[0]) + 2.0 * n[1].dot(d[1])) / 3.0,
            n[2].dot(d[1]),
        ];
        let n_max = n.iter().map(|v| v.length()).fold(0.0, f64::max);
        let d_max = d[0].length().max(d[1].length());
        // Rounding of the products, far above f64's error, far below any tolerance used.
        let band = 3f64.sqrt() * delta * n_max + 1e-9 * n_max * d_max;
        let (u0, u1) = band_clip(&f, band)?;
        // Back to the window's time, widened for the rounding of the division.
        let width = hi - lo;
        let (new_lo, new_hi) = (
            (lo + u0 * width - 1e-12).max(lo),
            (lo + u1 * width + 1e-12).min(hi),
        );
        let narrowed = (new_hi - new_lo) < 0.8 * width;
        (lo, hi) = (new_lo, new_hi);
        if !narrowed {
            break;
        }
    }
    Some((lo, hi))
}

/// The parameters in `[0, 1]` where the convex hull of the control points `(k / 3, f[k])` of a
/// cubic meets the band `|y| ≤ band`, or `None` where it does not. The hull's edges join pairs
/// of control points: the extremes of the hull inside the band lie on those segments.
fn band_clip(f: &[f64; 4], band: f64) -> Option<(f64, f64)> {
    if f.iter().all(|&y| y > band) || f.iter().all(|&y| y < -band) {
        return None;
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in 0..4 {
        for j in i..4 {
            let (s0, s1) = (i as f64 / 3.0, j as f64 / 3.0);
            let (y0, y1) = (f[i], f[j]);
            // The part of the segment from (s0, y0) to (s1, y1) inside the band.
            let (mut a, mut b) = (0.0f64, 1.0f64);
            for (g0, g1) in [(y0 - band, y1 - band), (-band - y0, -band - y1)] {
                // Keep g(λ) = g0 + λ (g1 − g0) ≤ 0.
                if g0 > 0.0 && g1 > 0.0 {
                    a = 1.0;
                    b = 0.0;
                } else if g0 > 0.0 {
                    a = a.max(g0 / (g0 - g1));
                } else if g1 > 0.0 {
                    b = b.min(g0 / (g0 - g1));
                }
            }
            if a <= b {
                lo = lo.min(s0 + a * (s1 - s0));
                hi = hi.max(s0 + b * (s1 - s0));
            }
        }
    }
    (lo <= hi).then_some((lo.max(0.0), hi.min(1.0)))
}

/// Scratch memory of the continuous tests (reuse it: no allocation per test).
#[derive(Debug, Default, Clone)]
pub struct CcdScratch {
    stack: Vec<Cell>,
}

/// The earliest time in `[0, t_limit)` at which vertex `p` touches triangle `tri` (all moving
/// linearly over the step), with the triangle's barycentric coordinates `(u, v)` of the
/// contact (the point is `a + u (b − a) + v (c − a)`), or `None`.
pub fn vertex_face_time(
    p: &Trajectory,
    tri: &[Trajectory; 3],
    tol: &PrimitiveTolerances,
    t_limit: f64,
    scratch: &mut CcdScratch,
) -> Option<f64> {
    let window = overlap_window(
        &MovingBox::around(std::slice::from_ref(p)),
        &MovingBox::around(tri),
        tol.distance,
        (0.0, t_limit.min(1.0)),
    )?;
    let [a, b, c] = *tri;
    let window = plane_window(
        |w0, w1| {
            let gap = |x: &Trajectory, y: &Trajectory| [x.at(w0) - y.at(w0), x.at(w1) - y.at(w1)];
            [gap(&b, &a), gap(&c, &a), gap(p, &a)]
        },
        tol.distance,
        window,
    )?;
    let problem = Problem {
        eval: |t: f64, u: f64, v: f64| {
            let at = a.at(t);
            p.at(t) - at - u * (b.at(t) - at) - v * (c.at(t) - at)
        },
        simplex: true,
    };
    earliest_root(&problem, &tol.solver(), window, t_limit, &mut scratch.stack)
}

/// The earliest time in `[0, t_limit)` at which edge `p` touches edge `q` (all moving linearly
/// over the step), or `None`.
pub fn edge_edge_time(
    p: &[Trajectory; 2],
    q: &[Trajectory; 2],
    tol: &PrimitiveTolerances,
    t_limit: f64,
    scratch: &mut CcdScratch,
) -> Option<f64> {
    let window = overlap_window(
        &MovingBox::around(p),
        &MovingBox::around(q),
        tol.distance,
        (0.0, t_limit.min(1.0)),
    )?;
    let ([p0, p1], [q0, q1]) = (*p, *q);
    let window = plane_window(
        |w0, w1| {
            let gap = |x: &Trajectory, y: &Trajectory| [x.at(w0) - y.at(w0), x.at(w1) - y.at(w1)];
            [gap(&p1, &p0), gap(&q1, &q0), gap(&q0, &p0)]
        },
        tol.distance,
        window,
    )?;
    let problem = Problem {
        eval: |t: f64, u: f64, v: f64| {
            let (pa, qa) = (p0.at(t), q0.at(t));
            pa + u * (p1.at(t) - pa) - qa - v * (q1.at(t) - qa)
        },
        simplex: false,
    };
    earliest_root(&problem, &tol.solver(), window, t_limit, &mut scratch.stack)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn still_triangle() -> [Trajectory; 3] {
        [DVec3::ZERO, DVec3::X, DVec3::Y].map(Trajectory::still)
    }

    /// When `p` meets the still unit triangle in the plane z = 0.
    fn against_still_triangle(p: &Trajectory) -> Option<f64> {
        let tol = PrimitiveTolerances::default();
        vertex_face_time(p, &still_triangle(), &tol, 1.0, &mut Default::default())
    }

    #[test]
    fn a_vertex_through_a_face_at_a_known_time() {
        let p = Trajectory::new(DVec3::new(0.25, 0.25, 0.3), DVec3::new(0.25, 0.25, -0.7));
        let t = against_still_triangle(&p).unwrap();
        assert!(t <= 0.3 && t > 0.3 - 2e-6, "{t}");
    }

    #[test]
    fn a_vertex_reaching_the_face_exactly_at_the_end_of_the_step() {
        let p = Trajectory::new(DVec3::new(0.2, 0.3, 1.0), DVec3::new(0.2, 0.3, 0.0));
        let t = against_still_triangle(&p).unwrap();
        assert!(t <= 1.0 && t > 1.0 - 2e-6, "{t}");
    }

    #[test]
    fn crossing_edges_meet_at_a_known_time_and_parallel_ones_too() {
        // p along x at z = 1 - 2t, q along y at z = 0: they meet at t = 0.5.
        let p = [
            Trajectory::new(DVec3::new(-1.0, 0.0, 1.0), DVec3::new(-1.0, 0.0, -1.0)),
            Trajectory::new(DVec3::new(1.0, 0.0, 1.0), DVec3::new(1.0, 0.0, -1.0)),
        ];
        let q = [DVec3::new(0.0, -1.0, 0.0), DVec3::new(0.0, 1.0, 0.0)].map(Trajectory::still);
        let mut s = CcdScratch::default();
        let tol = PrimitiveTolerances::default();
        let t = edge_edge_time(&p, &q, &tol, 1.0, &mut s).unwrap();
        assert!(t <= 0.5 && t > 0.5 - 2e-6, "{t}");
        // Parallel edges (both along x), overlapping in x, approaching in z: t = 0.5.
        let q = [DVec3::new(-0.5, 0.0, 0.0), DVec3::new(2.0, 0.0, 0.0)].map(Trajectory::still);
        let t = edge_edge_time(&p, &q, &tol, 1.0, &mut s).unwrap();
        assert!(t <= 0.5 && t > 0.5 - 2e-6, "{t}");
        // Parallel, passing beside each other (1 apart in y): no contact.
        let q = [DVec3::new(-0.5, 1.0, 0.0), DVec3::new(2.0, 1.0, 0.0)].map(Trajectory::still);
        assert!(edge_edge_time(&p, &q, &tol, 1.0, &mut s).is_none());
    }

    #[test]
    fn the_plane_window_holds_every_time_the_features_come_close() {
        use crate::geometry::{closest_point_on_triangle, closest_points_segment_segment};
        // Random features moving through a small region: every sampled time at which they are
        // within delta (max norm) lies in the window the plane test leaves (none when it says
        // they are apart).
        let mut seed = 99u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let delta = 0.05;
        let (mut dropped, mut narrowed, mut close) = (0, 0, 0);
        for _ in 0..4000 {
            let mut path = || {
                Trajectory::new(
                    DVec3::new(next(), next(), next()),
                    DVec3::new(next(), next(), next()),
                )
            };
            let (p, tri) = (path(), [path(), path(), path()]);
            let edges = ([path(), path()], [path(), path()]);
            let gap = |w0: f64, w1: f64, x: &Trajectory, y: &Trajectory| {
                [x.at(w0) - y.at(w0), x.at(w1) - y.at(w1)]
            };
            let vf_window = plane_window(
                |w0, w1| {
                    [
                        gap(w0, w1, &tri[1], &tri[0]),
                        gap(w0, w1, &tri[2], &tri[0]),
                        gap(w0, w1, &p, &tri[0]),
                    ]
                },
                delta,
                (0.0, 1.0),
            );
            let (e, f) = edges;
            let ee_window = plane_window(
                |w0, w1| {
                    [
                        gap(w0, w1, &e[1], &e[0]),
                        gap(w0, w1, &f[1], &f[0]),
                        gap(w0, w1, &f[0], &e[0]),
                    ]
                },
                delta,
                (0.0, 1.0),
            );
            for k in 0..=400 {
                let t = k as f64 / 400.0;
                let q = tri.map(|v| v.at(t));
                let vf = (p.at(t) - closest_point_on_triangle(p.at(t), &q)).abs();
                let c =
                    closest_points_segment_segment(e[0].at(t), e[1].at(t), f[0].at(t), f[1].at(t));
                let ee = (c.point_a - c.point_b).abs();
                for (window, gap) in [(vf_window, vf), (ee_window, ee)] {
                    if gap.max_element() <= delta {
                        close += 1;
                        let (lo, hi) = window.expect("not dropped");
                        assert!(lo <= t && t <= hi, "{t} outside [{lo}, {hi}], gap {gap:?}");
                    }
                }
            }
            for w in [vf_window, ee_window] {
                match w {
                    None => dropped += 1,
                    Some((lo, hi)) => narrowed += usize::from(hi - lo < 0.5),
                }
            }
        }
        // The filter drops pairs and narrows windows, and pairs do come close: the test can
        // fail both ways.
        assert!(
            dropped > 300 && narrowed > 1000 && close > 1000,
            "{dropped} dropped, {narrowed} narrowed, {close} close"
        );
    }

    #[test]
    fn features_that_touch_and_do_not_move_touch_at_time_zero() {
        let p = Trajectory::still(DVec3::new(0.5, 0.25, 0.0));
        let t = against_still_triangle(&p);
        assert_eq!(t, Some(0.0));
        let apart = Trajectory::still(DVec3::new(0.5, 0.25, 1e-3));
        let t = against_still_triangle(&apart);
        assert_eq!(t, None);
    }
}

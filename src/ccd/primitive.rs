//! Continuous tests of one pair of features moving linearly over the step: a vertex against a
//! triangle, an edge against an edge. Positions are given at the start and the end of the step
//! (in `f64`); the answer is the earliest time of contact in `[0, 1]` (see
//! [`inclusion`](super::inclusion) for what is promised).
use glam::DVec3;

use super::inclusion::{Cell, Problem, Tolerances, earliest_root};
use super::window::{MovingBox, overlap_window};

/// A point's positions at the start and the end of the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trajectory {
    /// Position at the start of the step.
    pub start: DVec3,
    /// Position at the end of the step.
    pub end: DVec3,
}

impl Trajectory {
    /// A point that moves from `start` to `end`.
    #[inline]
    pub fn new(start: DVec3, end: DVec3) -> Self {
        Self { start, end }
    }

    /// A point that does not move.
    #[inline]
    pub fn still(p: DVec3) -> Self {
        Self { start: p, end: p }
    }

    /// The position at time `t` of the step.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.start + t * (self.end - self.start)
    }
}

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

/// Whether the features stay on one side of the plane through them for all of `window`, farther
/// than `delta` in the max norm: a cheap proof that they do not meet there. `e1`, `e2` span the
/// plane (the face's edges, or the two edges' directions) and `d` goes from the plane's point to
/// the other feature; all move linearly, so `n = e1 × e2` is quadratic in time and `f = n · d`
/// cubic, and their Bernstein coefficients over the window bound them. Where `|f| / |n|`, the
/// distance from the plane, exceeds `√3 δ` (a Euclidean distance that large is more than `δ` in
/// every max-norm sense) for all of the window, the features are apart.
fn apart_from_plane(e1: [DVec3; 2], e2: [DVec3; 2], d: [DVec3; 2], delta: f64) -> bool {
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
    let bound = 3f64.sqrt() * delta * n_max + 1e-9 * n_max * d_max;
    f.iter().all(|&x| x > bound) || f.iter().all(|&x| x < -bound)
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
    let (w0, w1) = window;
    let ends = |x: &Trajectory| [x.at(w0), x.at(w1)];
    let (pa, pb, pc, pp) = (ends(&a), ends(&b), ends(&c), ends(p));
    let minus = |x: [DVec3; 2], y: [DVec3; 2]| [x[0] - y[0], x[1] - y[1]];
    if apart_from_plane(minus(pb, pa), minus(pc, pa), minus(pp, pa), tol.distance) {
        return None;
    }
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
    let (w0, w1) = window;
    let ends = |x: &Trajectory| [x.at(w0), x.at(w1)];
    let minus = |x: [DVec3; 2], y: [DVec3; 2]| [x[0] - y[0], x[1] - y[1]];
    let (a0, a1, b0, b1) = (ends(&p0), ends(&p1), ends(&q0), ends(&q1));
    if apart_from_plane(minus(a1, a0), minus(b1, b0), minus(b0, a0), tol.distance) {
        return None;
    }
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
    fn the_plane_filter_never_drops_features_that_come_close() {
        use crate::geometry::{closest_point_on_triangle, closest_points_segment_segment};
        // Random features moving through a small region: whenever the filter says "apart" over
        // the step, the features are more than delta apart (max norm) at every sampled time.
        let mut seed = 99u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let delta = 0.05;
        let (mut dropped, mut close) = (0, 0);
        for _ in 0..4000 {
            let mut path = || {
                Trajectory::new(
                    DVec3::new(next(), next(), next()),
                    DVec3::new(next(), next(), next()),
                )
            };
            let (p, tri) = (path(), [path(), path(), path()]);
            let edges = ([path(), path()], [path(), path()]);
            let at = |x: &Trajectory| [x.start, x.end];
            let minus = |x: [DVec3; 2], y: [DVec3; 2]| [x[0] - y[0], x[1] - y[1]];
            let vf_apart = apart_from_plane(
                minus(at(&tri[1]), at(&tri[0])),
                minus(at(&tri[2]), at(&tri[0])),
                minus(at(&p), at(&tri[0])),
                delta,
            );
            let (e, f) = edges;
            let ee_apart = apart_from_plane(
                minus(at(&e[1]), at(&e[0])),
                minus(at(&f[1]), at(&f[0])),
                minus(at(&f[0]), at(&e[0])),
                delta,
            );
            for k in 0..=200 {
                let t = k as f64 / 200.0;
                let q = tri.map(|v| v.at(t));
                let vf = (p.at(t) - closest_point_on_triangle(p.at(t), &q)).abs();
                let c =
                    closest_points_segment_segment(e[0].at(t), e[1].at(t), f[0].at(t), f[1].at(t));
                let ee = (c.point_a - c.point_b).abs();
                for (apart, gap) in [(vf_apart, vf), (ee_apart, ee)] {
                    if gap.max_element() <= delta {
                        close += 1;
                        assert!(!apart, "dropped features {gap:?} apart at {t}");
                    }
                }
            }
            dropped += vf_apart as usize + ee_apart as usize;
        }
        // The filter does drop pairs, and pairs do come close: the test can fail both ways.
        assert!(
            dropped > 300 && close > 1000,
            "{dropped} dropped, {close} close"
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

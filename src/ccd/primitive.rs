//! Continuous tests of one pair of features moving linearly over the step: a vertex against a
//! triangle, an edge against an edge. Positions are given at the start and the end of the step
//! (in `f64`); the answer is the earliest time of contact in `[0, 1]` (see
//! [`inclusion`](super::inclusion) for what is promised).
use glam::DVec3;

use super::inclusion::{Cell, Problem, Tolerances, earliest_root};

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

    fn lo(&self) -> DVec3 {
        self.start.min(self.end)
    }

    fn hi(&self) -> DVec3 {
        self.start.max(self.end)
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

/// Whether the boxes swept by two groups of points, grown by `margin`, overlap.
fn swept_boxes_overlap(a: &[Trajectory], b: &[Trajectory], margin: f64) -> bool {
    let bounds = |ps: &[Trajectory]| {
        ps.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(p.lo()), hi.max(p.hi())),
        )
    };
    let ((alo, ahi), (blo, bhi)) = (bounds(a), bounds(b));
    (alo - DVec3::splat(margin)).cmple(bhi).all() && (blo - DVec3::splat(margin)).cmple(ahi).all()
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
    if !swept_boxes_overlap(std::slice::from_ref(p), tri, tol.distance) {
        return None;
    }
    let [a, b, c] = *tri;
    let problem = Problem {
        eval: |t: f64, u: f64, v: f64| {
            let at = a.at(t);
            p.at(t) - at - u * (b.at(t) - at) - v * (c.at(t) - at)
        },
        simplex: true,
    };
    earliest_root(&problem, &tol.solver(), t_limit, &mut scratch.stack)
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
    if !swept_boxes_overlap(p, q, tol.distance) {
        return None;
    }
    let ([p0, p1], [q0, q1]) = (*p, *q);
    let problem = Problem {
        eval: |t: f64, u: f64, v: f64| {
            let (pa, qa) = (p0.at(t), q0.at(t));
            pa + u * (p1.at(t) - pa) - qa - v * (q1.at(t) - qa)
        },
        simplex: false,
    };
    earliest_root(&problem, &tol.solver(), t_limit, &mut scratch.stack)
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
    fn features_that_touch_and_do_not_move_touch_at_time_zero() {
        let p = Trajectory::still(DVec3::new(0.5, 0.25, 0.0));
        let t = against_still_triangle(&p);
        assert_eq!(t, Some(0.0));
        let apart = Trajectory::still(DVec3::new(0.5, 0.25, 1e-3));
        let t = against_still_triangle(&apart);
        assert_eq!(t, None);
    }
}

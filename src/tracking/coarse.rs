//! Multiresolution starts (Guy & Debunne): a new pair is first moved over the meshes'
//! vertices, a coarse level where one step measures a handful of point distances, and only
//! the pairs that come close there are refined to triangles and searched by the exact
//! local search. A vertex pair that stays far, or that slides along the sheet into the
//! excluded rings, costs no triangle distance at all.
//!
//! The cut: every point of a triangle with corner `v` lies within `ρ(v)`, the longest edge
//! at `v`, of `v` (the distance to `v` is convex over the triangle, largest at a corner, and
//! its other corners are neighbours of `v`). So any two triangles at vertices `v` and `w`
//! are at least `|v w| − ρ(v) − ρ(w)` apart. A start whose bound exceeds what the pruning
//! keeps (`k·d_min + ε`, with `d_min` bounded from above by the closest kept pair and by the
//! vertex pairs the step's refined starts came to rest on) would start a triangle pair that the
//! pruning drops, unless its search slid far from there: the cut is a bet, as the local
//! search is, not a proof.

use glam::DVec3;
use smallvec::SmallVec;

use super::surface::{ExcludedPairs, Placed};

/// Largest number of vertex steps (each moves one side, then the other) of a coarse start.
const MAX_COARSE_STEPS: u32 = 64;

/// What became of one coarse start.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CoarseStart {
    /// Close enough to refine: the triangle pair to search from.
    Refine(u32, u32),
    /// The vertex pair came to rest too far apart for any triangle pair around it to be kept.
    Far,
    /// Self-collision: the pair slid along the sheet towards the excluded rings.
    Sliding,
}

/// Counts of the coarse level over one step.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct CoarseCounts {
    /// New pairs that went through the coarse level.
    pub started: usize,
    /// Of them, refined to a triangle pair and searched.
    pub refined: usize,
    /// Left at the coarse level: too far apart.
    pub far: usize,
    /// Left at the coarse level: sliding into the excluded rings.
    pub sliding: usize,
    /// Left at the coarse level: they came to rest on a vertex pair of a pair already kept,
    /// or of an earlier start in the same step.
    pub duplicate: usize,
    /// Vertex distances measured.
    pub distances: u64,
}

/// The coarse level of one step.
pub(crate) struct CoarseSearch<'a> {
    pub a: Placed<'a>,
    pub b: Placed<'a>,
    /// One mesh against itself: vertex pairs whose triangles are excluded are not stepped to.
    pub excluded_pairs: Option<ExcludedPairs<'a>>,
    /// The pruning's rule: pairs farther than `far_factor · d_min + far_epsilon` (and than
    /// the thickness) are dropped.
    pub far_factor: f64,
    pub far_epsilon: f64,
    pub thickness: f64,
    /// An upper bound of the closest pair's distance `d_min` after this step: the closest
    /// kept pair's, lowered by the vertex pair of every start refined (the triangles at a
    /// vertex pair are at most as far apart as the vertices, and a search only gets closer).
    pub closest: f64,
    /// A self pair this far apart that has a closer excluded neighbour is sliding.
    pub slide_limit: f64,
}

impl CoarseSearch<'_> {
    /// Whether the triangles around vertices `v` (of `a`) and `w` (of `b`) are left out of
    /// self-collision: the first triangle at each vertex decides (the exact exclusion of the
    /// refined triangle pair is checked by the local search).
    fn excluded(&self, v: u32, w: u32) -> bool {
        let Some(e) = self.excluded_pairs else {
            return false;
        };
        if v == w {
            return true;
        }
        let (tv, tw) = (
            self.a.topology().vertex_triangles(v),
            self.b.topology().vertex_triangles(w),
        );
        match (tv.first(), tw.first()) {
            (Some(&x), Some(&y)) => e.excludes(x, y),
            _ => true,
        }
    }

    /// A lower bound of the distance between any triangle at vertex `v` (of `a`, at `p`) and
    /// any at `w` (of `b`, at `q`), `d2` the squared distance of the two vertices.
    fn lower_bound(
        &self,
        v: u32,
        p: DVec3,
        w: u32,
        q: DVec3,
        d2: f64,
        counts: &mut CoarseCounts,
    ) -> f64 {
        counts.distances += (self.a.topology().vertex_neighbours(v).len()
            + self.b.topology().vertex_neighbours(w).len()) as u64;
        d2.sqrt() - Self::reach(&self.a, v, p) - Self::reach(&self.b, w, q)
    }

    /// The longest edge at vertex `v` of `side`.
    fn reach(side: &Placed, v: u32, p: DVec3) -> f64 {
        side.topology()
            .vertex_neighbours(v)
            .iter()
            .map(|&n| side.point(n).distance_squared(p))
            .fold(0.0, f64::max)
            .sqrt()
    }

    /// Moves the pair of triangles `(ta, tb)` to a locally closest pair of vertices (from
    /// their closest corners, each step taking the neighbour of one side closest to the other
    /// side's vertex, then the same for the other side) and says whether to refine it.
    /// Returns the vertex pair it came to rest on with the outcome.
    pub fn start(
        &mut self,
        ta: u32,
        tb: u32,
        counts: &mut CoarseCounts,
    ) -> (CoarseStart, (u32, u32)) {
        counts.started += 1;
        let (ca, cb) = (self.a.corners(ta), self.b.corners(tb));
        let (pa, pb) = (ca.map(|v| self.a.point(v)), cb.map(|w| self.b.point(w)));
        let mut best = (f64::INFINITY, 0, 0);
        for (i, x) in pa.iter().enumerate() {
            for (j, y) in pb.iter().enumerate() {
                let d = x.distance_squared(*y);
                if d < best.0 {
                    best = (d, i, j);
                }
            }
        }
        counts.distances += 9;
        let (mut v, mut w) = (ca[best.1], cb[best.2]);
        let (mut p, mut q) = (pa[best.1], pb[best.2]);
        let mut d2 = best.0;
        let slide2 = self.slide_limit * self.slide_limit;
        for _ in 0..MAX_COARSE_STEPS {
            let mut moved = false;
            // One side, then the other.
            for side in 0..2 {
                let (placed, from, towards) = if side == 0 {
                    (&self.a, v, q)
                } else {
                    (&self.b, w, p)
                };
                // The closest neighbour; the excluded rings are asked about it only (and,
                // when it lies in them, about the others that are closer than now).
                let neighbours = placed.topology().vertex_neighbours(from);
                counts.distances += neighbours.len() as u64;
                let mut step: Option<(f64, u32, DVec3)> = None;
                for &n in neighbours {
                    let pn = placed.point(n);
                    let dn = pn.distance_squared(towards);
                    if dn < step.map_or(d2, |s| s.0) {
                        step = Some((dn, n, pn));
                    }
                }
                let refused = |n: u32| {
                    if side == 0 {
                        self.excluded(n, w)
                    } else {
                        self.excluded(v, n)
                    }
                };
                if step.is_some_and(|(_, n, _)| refused(n)) {
                    if d2 > slide2 && self.lower_bound(v, p, w, q, d2, counts) > self.slide_limit {
                        // A closer step lands in the excluded rings: sliding towards its
                        // own neighbourhood, and no triangle pair around it is within the
                        // slide limit (closer, it goes on: a tight crease's two sides touch
                        // just beyond them). Stopped at once, as the exact search does.
                        counts.sliding += 1;
                        return (CoarseStart::Sliding, (v, w));
                    }
                    step = None;
                    for &n in neighbours {
                        let pn = placed.point(n);
                        let dn = pn.distance_squared(towards);
                        if dn < step.map_or(d2, |s| s.0) && !refused(n) {
                            step = Some((dn, n, pn));
                        }
                    }
                }
                if let Some((dn, n, pn)) = step {
                    moved = true;
                    d2 = dn;
                    if side == 0 {
                        (v, p) = (n, pn);
                    } else {
                        (w, q) = (n, pn);
                    }
                }
            }
            if !moved {
                break;
            }
        }
        // Refined, this start's triangles are at most `d` apart: `d_min` is at most `d`.
        let d = d2.sqrt();
        let closest = self.closest.min(d);
        let keep = (self.far_factor * closest + self.far_epsilon).max(self.thickness);
        if self.lower_bound(v, p, w, q, d2, counts) > keep {
            counts.far += 1;
            return (CoarseStart::Far, (v, w));
        }
        match self.triangles_at(v, w) {
            Some((x, y)) => {
                self.closest = closest;
                (CoarseStart::Refine(x, y), (v, w))
            }
            None => {
                counts.sliding += 1;
                (CoarseStart::Sliding, (v, w))
            }
        }
    }

    /// The pair of triangles at vertices `v` and `w`, not excluded, whose centroids are
    /// closest (the first of equals, in the order of the vertices' triangle lists; the exact
    /// search refines it). The exclusion is asked only of a pair closer than the best so far.
    fn triangles_at(&self, v: u32, w: u32) -> Option<(u32, u32)> {
        let centroid = |side: &Placed, t: u32| {
            let [x, y, z] = side.triangle(t);
            (x + y + z) / 3.0
        };
        let at_w: SmallVec<[(u32, DVec3); 16]> = self
            .b
            .topology()
            .vertex_triangles(w)
            .iter()
            .map(|&y| (y, centroid(&self.b, y)))
            .collect();
        let mut best: Option<(f64, u32, u32)> = None;
        for &x in self.a.topology().vertex_triangles(v) {
            let cx = centroid(&self.a, x);
            for &(y, cy) in &at_w {
                let d = cx.distance_squared(cy);
                let closer = best.is_none_or(|(e, _, _)| d < e);
                if closer && !self.excluded_pairs.is_some_and(|e| e.excludes(x, y)) {
                    best = Some((d, x, y));
                }
            }
        }
        best.map(|(_, x, y)| (x, y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deform::Whirl;
    use crate::geometry::closest_points_triangle_triangle;
    use crate::mesh::generate;
    use crate::tracking::TrackedSurface;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// The coarse level between `a` and `b` with no exclusion, no pair kept yet, the pruning's
    /// `k` and no `ε`.
    fn between<'a>(a: Placed<'a>, b: Placed<'a>) -> CoarseSearch<'a> {
        CoarseSearch {
            a,
            b,
            excluded_pairs: None,
            far_factor: 1.2,
            far_epsilon: 0.0,
            thickness: 0.0,
            closest: f64::INFINITY,
            slide_limit: 0.0,
        }
    }

    /// The cut's bound is at most the distance of every pair of triangles at the two
    /// vertices, on a tube whirled through itself (uneven edges, pairs near and far), and it
    /// is tight enough to matter: above zero for most random pairs.
    #[test]
    fn the_coarse_bound_never_exceeds_a_distance_of_the_triangles_at_the_vertices() {
        let tube = generate::tube(0.1, 1.5, 16, 60, true);
        let whirl = Whirl::new(&tube, 40, 5);
        let mut surface = TrackedSurface::new(tube.clone());
        let mut positions = Vec::new();
        whirl.positions(30, &mut positions);
        surface.set_positions(&positions).unwrap();
        let placed = Placed {
            surface: &surface,
            pose: None,
        };
        let coarse = between(placed, placed);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let n = tube.vertex_count() as u32;
        let (mut positive, mut counts) = (0, CoarseCounts::default());
        for _ in 0..2000 {
            let (v, w) = (rng.random_range(0..n), rng.random_range(0..n));
            let (p, q) = (placed.point(v), placed.point(w));
            let bound = coarse.lower_bound(v, p, w, q, p.distance_squared(q), &mut counts);
            positive += usize::from(bound > 0.0);
            for &x in placed.topology().vertex_triangles(v) {
                for &y in placed.topology().vertex_triangles(w) {
                    let d =
                        closest_points_triangle_triangle(&placed.triangle(x), &placed.triangle(y))
                            .distance;
                    assert!(
                        bound <= d + 1e-12,
                        "vertices {v}, {w}: bound {bound} above the distance {d} of {x}, {y}"
                    );
                }
            }
        }
        assert!(positive > 1000, "{positive} of 2000 bounds above zero");
    }

    /// A start moves to a vertex pair no neighbour of which is closer (on either side): on a
    /// sheet tilted above another, down to their closest edge from anywhere, and reports the
    /// triangle pair at it to refine.
    #[test]
    fn a_start_comes_to_rest_on_a_locally_closest_vertex_pair() {
        let sheet = generate::cloth_grid(1.0, 1.0, 12, 12);
        let lower = TrackedSurface::new(sheet.clone());
        let upper = TrackedSurface::new(sheet.clone());
        let a = Placed {
            surface: &lower,
            pose: None,
        };
        // The second sheet tilted above the first: closest along its low edge.
        let pose = crate::geometry::PoseF64 {
            rotation: glam::DQuat::from_rotation_x(0.3),
            translation: DVec3::new(0.0, 0.2, 0.0),
        };
        let b = Placed {
            surface: &upper,
            pose: Some(pose),
        };
        let mut coarse = between(a, b);
        let mut counts = CoarseCounts::default();
        let triangles = sheet.triangle_count() as u32;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(2);
        for _ in 0..50 {
            let (ta, tb) = (
                rng.random_range(0..triangles),
                rng.random_range(0..triangles),
            );
            let (outcome, (v, w)) = coarse.start(ta, tb, &mut counts);
            let d = a.point(v).distance(b.point(w));
            for &n in a.topology().vertex_neighbours(v) {
                assert!(a.point(n).distance(b.point(w)) >= d);
            }
            for &n in b.topology().vertex_neighbours(w) {
                assert!(a.point(v).distance(b.point(n)) >= d);
            }
            // The closest vertex pairs, along the tilted sheet's low edge, are 0.0565 apart;
            // the grids' vertices do not lie above each other, so a start may rest a little
            // farther, within an edge (1/12), not on the far side (up to 0.35 apart).
            assert!(
                d < 0.0565 + 1.0 / 12.0,
                "start {ta}, {tb} came to rest {d} apart"
            );
            let CoarseStart::Refine(x, y) = outcome else {
                panic!("start {ta}, {tb}: {outcome:?}");
            };
            assert!(a.corners(x).contains(&v) && b.corners(y).contains(&w));
        }
        assert_eq!((counts.started, counts.far, counts.sliding), (50, 0, 0));
    }
}

//! Local search: move a triangle pair to a locally closest pair by strict descent over the
//! neighbours that the mesh topology gives, with a deterministic tie-break.

use glam::DVec3;
use smallvec::SmallVec;

use super::boxes::{box_gap, triangle_box};
use super::config::SearchMode;
use super::feature::{Feature, reduce_to_feature};
use super::surface::{ExcludedPairs, Placed};
use crate::geometry::{ClosestPoints, closest_points_triangle_triangle};

/// Where a pair's search ended.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Located {
    pub ta: u32,
    pub tb: u32,
    pub cp: ClosestPoints,
    pub fa: Feature,
    pub fb: Feature,
}

/// Counters of one frame's searches.
#[derive(Debug, Default, Clone, Copy)]
pub(crate) struct SearchCounters {
    pub iterations: u64,
    pub evaluations: u64,
}

pub(crate) struct Searcher<'a> {
    pub a: Placed<'a>,
    pub b: Placed<'a>,
    /// One mesh against itself: adjacent triangles are excluded.
    pub self_mode: bool,
    /// Self mode: the pairs left out (within the exclusion rings); `None` for two meshes.
    pub excluded_pairs: Option<ExcludedPairs<'a>>,
    pub mode: SearchMode,
    pub max_iterations: u32,
    /// Strict-decrease margin (absolute).
    pub epsilon: f64,
    /// Contact distance: self pairs within it are never treated as sliding.
    pub thickness: f64,
    /// A sliding self pair farther than this stops its descent at once (closer, it goes on:
    /// it may be at a tight crease whose two sides touch just beyond the excluded zone).
    pub slide_limit: f64,
}

/// A candidate pair with its corners and closest points.
type Candidate = (u32, u32, [DVec3; 3], [DVec3; 3], ClosestPoints);

/// Outcome of one descent step.
enum Step {
    Moved(Located),
    Stuck,
    /// A self pair whose neighbourhood touches its partner: it slides along the sheet.
    Sliding,
}

impl Searcher<'_> {
    pub fn excluded(&self, ta: u32, tb: u32) -> bool {
        self.self_mode && self.excluded_pairs.is_some_and(|e| e.excludes(ta, tb))
    }

    pub fn locate(&self, ta: u32, tb: u32, counters: &mut SearchCounters) -> Located {
        counters.evaluations += 1;
        let (a, b) = (self.a.triangle(ta), self.b.triangle(tb));
        let cp = closest_points_triangle_triangle(&a, &b);
        self.located(ta, tb, &a, &b, cp)
    }

    fn located(
        &self,
        ta: u32,
        tb: u32,
        a: &[DVec3; 3],
        b: &[DVec3; 3],
        cp: ClosestPoints,
    ) -> Located {
        let fa = reduce_to_feature(cp.point_a, ta, a, self.a.corners(ta), self.a.topology());
        let fb = reduce_to_feature(cp.point_b, tb, b, self.b.corners(tb), self.b.topology());
        Located { ta, tb, cp, fa, fb }
    }

    /// Triangles to try instead of `t`, whose closest feature is `f`: around a closest corner
    /// or edge, all triangles at those corners; from a face, the edge-adjacent triangles.
    fn candidates(side: &Placed, t: u32, f: Feature, out: &mut SmallVec<[u32; 48]>) {
        out.clear();
        let topo = side.topology();
        match f {
            Feature::Vertex(v) => out.extend_from_slice(topo.vertex_triangles(v)),
            Feature::Edge(e) => {
                let [v0, v1] = topo.edge(e).vertices;
                out.extend_from_slice(topo.vertex_triangles(v0));
                out.extend_from_slice(topo.vertex_triangles(v1));
                out.sort_unstable();
                out.dedup();
            }
            Feature::Triangle(_) => out.extend_from_slice(topo.triangle_neighbours(t)),
        }
        out.retain(|x| *x != t);
    }

    /// Strict descent from `(ta, tb)` until no neighbour pair is closer by more than
    /// `epsilon`, the pair is in contact (within the thickness), or `max_iterations` steps. Ties keep the first (ascending) candidate.
    /// Returns where it stopped and whether it stopped because the pair was sliding (a self
    /// pair farther than the thickness whose neighbourhood touches its partner: descent from
    /// it slides along the sheet into the excluded zone instead of across a gap, so it is not
    /// a contact between distinct parts of the surface).
    ///
    /// The third value says whether the pair settled: it stopped in contact or with no closer
    /// neighbour pair, not at `max_iterations` (a settled pair's search ends where it starts
    /// as long as the triangles around its two triangles stay where they are).
    pub fn descend(&self, start: Located, counters: &mut SearchCounters) -> (Located, bool, bool) {
        let mut cur = start;
        let mut ca: SmallVec<[u32; 48]> = SmallVec::new();
        let mut cb: SmallVec<[u32; 48]> = SmallVec::new();
        for _ in 0..self.max_iterations {
            if cur.cp.distance <= self.thickness {
                // In contact (nothing is strictly closer than touching): propagation explores
                // the neighbourhood.
                return (cur, false, true);
            }
            counters.iterations += 1;
            let mut moved = false;
            match self.mode {
                SearchMode::TwoStep => {
                    Self::candidates(&self.a, cur.ta, cur.fa, &mut ca);
                    match self.best_of(&cur, ca.iter().map(|&x| (x, cur.tb)), counters) {
                        Step::Moved(n) => (cur, moved) = (n, true),
                        Step::Sliding => return (cur, true, false),
                        Step::Stuck => {}
                    }
                    Self::candidates(&self.b, cur.tb, cur.fb, &mut cb);
                    match self.best_of(&cur, cb.iter().map(|&y| (cur.ta, y)), counters) {
                        Step::Moved(n) => (cur, moved) = (n, true),
                        Step::Sliding => return (cur, true, false),
                        Step::Stuck => {}
                    }
                }
                SearchMode::Full => {
                    Self::candidates(&self.a, cur.ta, cur.fa, &mut ca);
                    Self::candidates(&self.b, cur.tb, cur.fb, &mut cb);
                    ca.insert(0, cur.ta);
                    cb.insert(0, cur.tb);
                    let pairs = ca
                        .iter()
                        .flat_map(|&x| cb.iter().map(move |&y| (x, y)))
                        .filter(|&p| p != (cur.ta, cur.tb));
                    match self.best_of(&cur, pairs, counters) {
                        Step::Moved(n) => (cur, moved) = (n, true),
                        Step::Sliding => return (cur, true, false),
                        Step::Stuck => {}
                    }
                }
            }
            if !moved {
                return (cur, false, true);
            }
        }
        // Out of steps; settled only if the last step found the pair in contact.
        let settled = cur.cp.distance <= self.thickness;
        (cur, false, settled)
    }

    /// The candidate strictly closer than `cur` by more than `epsilon` (the closest; the
    /// first of equals), skipping excluded pairs and those whose boxes are already too far.
    fn best_of(
        &self,
        cur: &Located,
        candidates: impl Iterator<Item = (u32, u32)>,
        counters: &mut SearchCounters,
    ) -> Step {
        let mut best_d = cur.cp.distance - self.epsilon;
        let mut best: Option<Candidate> = None;
        let may_slide = self.self_mode && cur.cp.distance > self.thickness;
        let mut closest_excluded = f64::INFINITY;
        // Separation along the current closest direction bounds every candidate's distance
        // from below: the gap between the two triangles' projections on it.
        let gap = cur.cp.point_b - cur.cp.point_a;
        let dir = if cur.cp.distance > 0.0 {
            gap / gap.length()
        } else {
            DVec3::ZERO
        };
        for (x, y) in candidates {
            // Bounds first (cheap): nothing at or beyond `best_d` matters, excluded or not.
            let (a, b) = (self.a.triangle(x), self.b.triangle(y));
            // A lower bound of the distance of two triangles: the gap of their boxes.
            let mut gap = box_gap(&triangle_box(&a), &triangle_box(&b));
            if gap < best_d && dir != DVec3::ZERO {
                let max_a = a
                    .iter()
                    .map(|p| p.dot(dir))
                    .fold(f64::NEG_INFINITY, f64::max);
                let min_b = b.iter().map(|q| q.dot(dir)).fold(f64::INFINITY, f64::min);
                gap = gap.max(min_b - max_a);
            }
            if gap >= best_d {
                continue;
            }
            let excluded = self.excluded(x, y);
            if excluded && (!may_slide || gap >= closest_excluded) {
                continue;
            }
            counters.evaluations += 1;
            let cp = closest_points_triangle_triangle(&a, &b);
            if excluded {
                closest_excluded = closest_excluded.min(cp.distance);
            } else if cp.distance < best_d {
                best_d = cp.distance;
                best = Some((x, y, a, b, cp));
            }
        }
        // The descent would rather step into the excluded zone than across a gap: the pair
        // slides along the sheet. Far from contact, give up at once; near it, go on among the
        // allowed neighbours, which may reach a contact at a tight crease.
        if closest_excluded < best_d && cur.cp.distance > self.slide_limit {
            return Step::Sliding;
        }
        match best {
            Some((x, y, a, b, cp)) => Step::Moved(self.located(x, y, &a, &b, cp)),
            None => Step::Stuck,
        }
    }

    /// Whether a self pair farther than `slide_limit` would step into the excluded zone: some
    /// excluded neighbour pair is strictly closer than it (see [`Searcher::descend`]). Closer
    /// pairs are kept: they may be the two sides of a fold closing up, followed until they
    /// touch.
    pub fn sliding(&self, l: &Located) -> bool {
        if !self.self_mode || l.cp.distance <= self.slide_limit {
            return false;
        }
        let mut ca: SmallVec<[u32; 48]> = SmallVec::new();
        let mut cb: SmallVec<[u32; 48]> = SmallVec::new();
        Self::candidates(&self.a, l.ta, l.fa, &mut ca);
        Self::candidates(&self.b, l.tb, l.fb, &mut cb);
        let closer = |x: u32, y: u32| {
            self.excluded(x, y)
                && closest_points_triangle_triangle(&self.a.triangle(x), &self.b.triangle(y))
                    .distance
                    < l.cp.distance - self.epsilon
        };
        ca.iter().any(|&x| closer(x, l.tb)) || cb.iter().any(|&y| closer(l.ta, y))
    }
}

//! Local search: move a triangle pair to a locally closest pair by strict descent over the
//! neighbours that the mesh topology gives, with a deterministic tie-break.

use glam::DVec3;
use smallvec::SmallVec;

use super::boxes::{Box64, box_gap, triangle_box};
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

/// One side's triangle as [`Searcher::best_of`] reads it: its corners, its box, its extreme
/// projection on the search direction (the largest for the first side, the smallest for the
/// second), its unit normal (zero for a degenerate triangle) and its corners' extent along it.
#[derive(Clone, Copy)]
struct SideTriangle {
    corners: [DVec3; 3],
    bounds: Box64,
    extreme: f64,
    normal: DVec3,
    span: (f64, f64),
}

impl SideTriangle {
    /// Triangle `corners`, with its extreme projection on `dir` chosen by `pick`.
    #[inline]
    fn new(corners: [DVec3; 3], dir: DVec3, pick: fn(f64, f64) -> f64) -> Self {
        let [p, q, r] = corners.map(|c| c.dot(dir));
        let normal = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize_or_zero();
        let [u, v, w] = corners.map(|c| c.dot(normal));
        SideTriangle {
            corners,
            bounds: triangle_box(&corners),
            extreme: pick(pick(p, q), r),
            normal,
            span: (u.min(v).min(w), u.max(v).max(w)),
        }
    }

    /// A lower bound of the distance from this triangle to `other`: the gap between the two
    /// triangles' extents along this one's normal (0 when they overlap). It holds for any
    /// unit direction, so a nearly degenerate triangle's inexact normal keeps it sound.
    #[inline]
    fn plane_gap(&self, other: &[DVec3; 3]) -> f64 {
        let [p, q, r] = other.map(|c| c.dot(self.normal));
        let (lo, hi) = self.span;
        (p.min(q).min(r) - hi).max(lo - p.max(q).max(r)).max(0.0)
    }
}

/// The last triangle read on one side, kept while the candidates keep it.
#[derive(Default)]
struct SideCache {
    last: Option<(u32, SideTriangle)>,
}

impl SideCache {
    /// Triangle `t` of `side`, read again only when it is not the last one read; `pick`
    /// chooses its extreme projection on `dir` (`f64::max` or `f64::min`).
    #[inline]
    fn read(
        &mut self,
        side: &Placed,
        t: u32,
        dir: DVec3,
        pick: fn(f64, f64) -> f64,
    ) -> &SideTriangle {
        if self.last.as_ref().is_some_and(|(u, _)| *u != t) {
            self.last = None;
        }
        let (_, s) = self
            .last
            .get_or_insert_with(|| (t, SideTriangle::new(side.triangle(t), dir, pick)));
        s
    }
}

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
    ///
    /// A candidate is skipped when a lower bound of its distance reaches the best so far:
    /// the gap of the triangles' boxes, of their projections on the current closest
    /// direction, or of their extents along either triangle's normal. Each side's triangle
    /// ([`SideTriangle`]) is read once for a run of candidates that share it: one side is
    /// fixed in a two-step search, and the first varies slowest in a full one.
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
        let mut side_a = SideCache::default();
        let mut side_b = SideCache::default();
        for (x, y) in candidates {
            // Bounds first (cheap): nothing at or beyond `best_d` matters, excluded or not.
            let a = side_a.read(&self.a, x, dir, f64::max);
            let b = side_b.read(&self.b, y, dir, f64::min);
            // A lower bound of the distance of two triangles: the gap of their boxes.
            let mut gap = box_gap(&a.bounds, &b.bounds);
            if gap < best_d && dir != DVec3::ZERO {
                gap = gap.max(b.extreme - a.extreme);
            }
            // Each triangle's plane separates the other's corners by at least the distance.
            if gap < best_d {
                gap = gap
                    .max(a.plane_gap(&b.corners))
                    .max(b.plane_gap(&a.corners));
            }
            if gap >= best_d {
                continue;
            }
            let excluded = self.excluded(x, y);
            if excluded && (!may_slide || gap >= closest_excluded) {
                continue;
            }
            counters.evaluations += 1;
            let cp = closest_points_triangle_triangle(&a.corners, &b.corners);
            if excluded {
                closest_excluded = closest_excluded.min(cp.distance);
            } else if cp.distance < best_d {
                best_d = cp.distance;
                best = Some((x, y, a.corners, b.corners, cp));
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// Every bound `best_of` skips a candidate by (box gap, projections on a direction, each
    /// triangle's plane) is at most the triangles' distance, on random, crossing, coplanar,
    /// parallel and degenerate triangles; the plane bound is exact for a triangle above a
    /// parallel one.
    #[test]
    fn the_search_bounds_never_exceed_the_distance() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let mut point = |scale: f64| {
            DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            ) * scale
        };
        let mut cases: Vec<([DVec3; 3], [DVec3; 3])> = Vec::new();
        for k in 0..4000 {
            let a = [point(1.0), point(1.0), point(1.0)];
            let shift = point(3.0);
            let mut b = [point(1.0) + shift, point(1.0) + shift, point(1.0) + shift];
            match k % 4 {
                // Coplanar with a (z = 0 both).
                1 => {
                    let flat = |t: [DVec3; 3]| t.map(|p| DVec3::new(p.x, p.y, 0.0));
                    cases.push((flat(a), flat(b)));
                    continue;
                }
                // b a copy of a, lifted along a's normal.
                2 => {
                    let n = (a[1] - a[0]).cross(a[2] - a[0]).normalize_or_zero();
                    b = a.map(|p| p + n * shift.x.abs());
                }
                // A degenerate b (a segment).
                3 => b[2] = (b[0] + b[1]) * 0.5,
                _ => {}
            }
            cases.push((a, b));
        }
        for (a, b) in cases {
            let d = closest_points_triangle_triangle(&a, &b).distance;
            let dir = (b[0] - a[1]).normalize_or_zero();
            let (sa, sb) = (
                SideTriangle::new(a, dir, f64::max),
                SideTriangle::new(b, dir, f64::min),
            );
            let slack = 1e-12 * (1.0 + d);
            assert!(box_gap(&sa.bounds, &sb.bounds) <= d + slack);
            assert!(sb.extreme - sa.extreme <= d + slack);
            assert!(sa.plane_gap(&b) <= d + slack, "{a:?} {b:?}");
            assert!(sb.plane_gap(&a) <= d + slack, "{a:?} {b:?}");
        }
        // A unit triangle 0.5 above a parallel one: the plane bound is the distance.
        let low = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let high = low.map(|p| p + DVec3::Z * 0.5);
        let s = SideTriangle::new(low, DVec3::Z, f64::max);
        assert!((s.plane_gap(&high) - 0.5).abs() < 1e-15);
        assert_eq!(
            s.plane_gap(&[DVec3::Z, -DVec3::Z, DVec3::X]),
            0.0,
            "straddles"
        );
    }
}

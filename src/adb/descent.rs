//! The default traversal of [`adb_intersects`](super::adb_intersects): depth first in
//! [`Order::Straddle`](super::Order::Straddle), exact leaves, and estimates only where the
//! answer needs them (at the evidence checks and for the confidence of an answer it did not
//! settle). With no estimate to make between two checks, each step is a box test and a
//! stack push: this loop does only that, and hands everything else back to its caller.
use std::time::Instant;

use super::options::{Budget, TIME_CHECK_INTERVAL, UNESTIMATED};
use super::queue::Entry;
use super::tree::{AdbTree, prepare_first, prepare_second};
use crate::bvh::box_test::RelativeFrame;
use crate::bvh::{BvhNode, QueryWorkspace, TrianglePair};
use crate::geometry::{PoseF64, triangles_intersect};
use crate::prefetch::prefetch;

/// Triangle tests that count as one pop toward the time budget's clock check.
pub(super) const TRIANGLE_TESTS_PER_POP: u32 = 4;

/// Both trees, the second placed in the first's frame, and the query's budget.
pub(super) struct DescentFrame<'t> {
    pub a: &'t AdbTree,
    pub b: &'t AdbTree,
    pub frame: &'t RelativeFrame,
    pub rel64: &'t PoseF64,
    pub budget: Budget,
    /// When the query began (read only for a time budget).
    pub start: Option<Instant>,
}

/// Why [`Descent::run`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum DescentEnd {
    /// No node pair is left: no leaf pair holds intersecting triangles.
    Done,
    /// The leaf pair `nodes` holds the intersecting triangle pair `triangles`.
    Hit {
        nodes: (u32, u32),
        triangles: TrianglePair,
    },
    /// The budget ran out (the pair about to be expanded is queued again).
    Budget,
    /// The evidence check said to stop.
    Evidence,
    /// The pop to pause at came (the pair about to be expanded is queued again, and the pop
    /// not counted).
    Paused,
}

/// A depth-first descent's counters, kept across pauses.
#[derive(Debug, Clone, Copy)]
pub(super) struct Descent {
    /// Pairs popped.
    pub pops: u32,
    /// Work since the last clock read, in pops (a leaf pair's triangle tests count too).
    pub unclocked: u32,
    /// The pop at which the evidence is checked next (doubling after each check).
    pub next_check: u32,
    /// Node pairs whose boxes were tested (the root pair counts).
    pub visited: u64,
    /// Whether children are expanded in straddle order (the most squarely straddling first),
    /// or simply in index order. The order decides how soon a collision is found; where
    /// there is probably none to find, every overlapping pair is expanded whatever the
    /// order, and index order spares the straddle's arithmetic and lets the next pop go
    /// ahead before this one's box tests are done.
    pub ordered: bool,
}

impl Descent {
    /// Expands the pairs of `stack` depth first, children in straddle order (the most
    /// squarely straddling popped first) or, unless [`Descent::ordered`], in index order,
    /// until one of [`DescentEnd`]. `evidence` is asked at
    /// the checks (with the pair about to be expanded queued again) whether to stop;
    /// `pause_at` is a pop at which to hand back before expanding.
    pub(super) fn run(
        &mut self,
        f: &DescentFrame<'_>,
        stack: &mut Vec<Entry>,
        cache: &mut QueryWorkspace,
        pause_at: Option<u32>,
        evidence: &mut dyn FnMut(&mut [Entry]) -> bool,
    ) -> DescentEnd {
        let (ma, mb) = (f.a.collision_mesh(), f.b.collision_mesh());
        let (na, nb) = (ma.bvh().nodes(), mb.bvh().nodes());
        while let Some(e) = stack.pop() {
            self.pops += 1;
            self.unclocked += 1;
            if pause_at == Some(self.pops) {
                stack.push(e);
                self.pops -= 1;
                self.unclocked -= 1;
                return DescentEnd::Paused;
            }
            // The root pair is always expanded: a budget cannot end a query before it has
            // looked.
            if self.pops > 1 && budget_spent(f.budget, self.visited, &mut self.unclocked, f.start) {
                stack.push(e);
                return DescentEnd::Budget;
            }
            if self.pops >= self.next_check {
                self.next_check = self.next_check.saturating_mul(2);
                stack.push(e);
                if evidence(stack) {
                    return DescentEnd::Evidence;
                }
                stack.pop();
            }
            let (x, y) = (&na[e.a as usize], &nb[e.b as usize]);
            if x.is_leaf() && y.is_leaf() {
                let (hit, tests) = leaf_pair_hit((f.a, x), (f.b, y), f.rel64, cache);
                if let Some(triangles) = hit {
                    return DescentEnd::Hit {
                        nodes: (e.a, e.b),
                        triangles,
                    };
                }
                self.unclocked += tests / TRIANGLE_TESTS_PER_POP;
                continue;
            }
            let (kids, n) = if self.ordered {
                self.overlapping_children::<true>(f, (x, e.a), (y, e.b))
            } else {
                self.overlapping_children::<false>(f, (x, e.a), (y, e.b))
            };
            stack.extend_from_slice(&kids[..n]);
        }
        DescentEnd::Done
    }

    /// The child pairs of `(x, y)` whose boxes and slabs may overlap (a leaf, and the smaller
    /// of two nodes of very different sizes, stands for itself), not estimated, in push order:
    /// with `ORDERED`, least squarely straddling first; without, in index order (so the last
    /// child pair is popped first), all ranked 0.
    #[inline]
    fn overlapping_children<const ORDERED: bool>(
        &mut self,
        f: &DescentFrame<'_>,
        (x, ia): (&BvhNode, u32),
        (y, ib): (&BvhNode, u32),
    ) -> ([Entry; 4], usize) {
        // Both nodes are split when they are of similar size; where one is more than four times
        // the other (a small mesh against a large one), only the larger, so the small node is
        // not split into pairs that each descend the large tree's upper levels again. A leaf
        // stands for itself.
        let (size_a, size_b) = (
            f.a.nodes()[ia as usize].sides[0],
            f.b.nodes()[ib as usize].sides[0],
        );
        let split_a = !x.is_leaf() && (y.is_leaf() || 4.0 * size_a >= size_b);
        let split_b = !y.is_leaf() && (x.is_leaf() || 4.0 * size_b >= size_a);
        let children = |n: &BvhNode, i: u32, split: bool| {
            if split {
                [n.left(), n.left() + 1]
            } else {
                [i, u32::MAX]
            }
        };
        let (kids_a, kids_b) = (children(x, ia, split_a), children(y, ib, split_b));
        // Each child of the second node prepared once for its (up to) two box tests.
        let prepare = |ib: u32| (ib != u32::MAX).then(|| prepare_second(f.b, f.frame, ib));
        let prepared_b = [prepare(kids_b[0]), prepare(kids_b[1])];
        // Per child pair `g` (its first child's slot, then its second's: the order in which
        // `Entry`'s tie-break ranks them, last first), a sort key: 0 if its boxes are apart,
        // else 1 + its straddle's bits (a non-negative `f32`: the bits order as the values; at
        // most 1.0, so they still fit shifted by two) and the tie-break below them. Sorted without a branch on the data, which would be
        // mispredicted about one pop in two.
        let mut keys = [0u32; 4];
        let mut pairs = [(0u32, 0u32); 4];
        let (mut unordered, mut n_unordered) = ([Entry::default(); 4], 0);
        for (slot_a, &ca) in kids_a.iter().enumerate() {
            if ca == u32::MAX {
                continue;
            }
            let first = prepare_first(f.a, f.frame, ca);
            for (slot_b, (&cb, second)) in kids_b.iter().zip(&prepared_b).enumerate() {
                let Some(second) = second else {
                    continue;
                };
                self.visited += 1;
                // The centre distance is left for the estimate to work out, if the pair is
                // ever estimated (most are expanded first): a square root per pair saved.
                let Some(overlap) = f.frame.overlap_prepared(&first, second) else {
                    continue;
                };
                if ORDERED {
                    let g = 2 * slot_a + slot_b;
                    pairs[g] = (ca, cb);
                    keys[g] = ((overlap.straddle.to_bits() << 2) | (3 - g as u32)) + 1;
                } else {
                    // Unordered, the straddle is never read (nor, inlined, worked out).
                    unordered[n_unordered] = unestimated(ca, cb, 0.0);
                    n_unordered += 1;
                    prefetch_children(f.a, ca);
                    prefetch_children(f.b, cb);
                }
            }
        }
        if !ORDERED {
            return (unordered, n_unordered);
        }
        for (i, j) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
            let (lo, hi) = (keys[i].min(keys[j]), keys[i].max(keys[j]));
            (keys[i], keys[j]) = (lo, hi);
        }
        let mut kids = [Entry::default(); 4];
        let mut n = 0;
        for key in keys.into_iter().filter(|&k| k != 0) {
            let (ca, cb) = pairs[3 - ((key - 1) & 3) as usize];
            kids[n] = unestimated(ca, cb, f32::from_bits((key - 1) >> 2));
            n += 1;
        }
        (kids, n)
    }
}

/// Whether `budget` is spent after `visited` node pairs, `unclocked` pops since the clock was
/// last read (the clock is read, and `unclocked` reset, every [`TIME_CHECK_INTERVAL`] pops),
/// for a query begun at `start`.
#[inline]
pub(super) fn budget_spent(
    budget: Budget,
    visited: u64,
    unclocked: &mut u32,
    start: Option<Instant>,
) -> bool {
    match budget {
        Budget::Unlimited => false,
        Budget::NodePairs(n) => visited >= n,
        Budget::Time(t) => {
            *unclocked >= TIME_CHECK_INTERVAL && {
                *unclocked = 0;
                start.is_some_and(|s| s.elapsed() >= t)
            }
        }
    }
}

/// Asks for the children of node `i` of `tree` (their boxes and slabs) to be brought into the
/// cache, for when the pair is expanded: on the largest meshes the nodes do not stay cached
/// from one query to the next, and the next pair's loads would otherwise wait on memory.
/// (In index order only: in straddle order the extra loads would sit on the path to the next
/// pop.)
#[inline]
fn prefetch_children(tree: &AdbTree, i: u32) {
    let nodes = tree.collision_mesh().bvh().nodes();
    let n = &nodes[i as usize];
    if !n.is_leaf() {
        let left = n.left() as usize;
        prefetch(nodes.as_ptr().wrapping_add(left).cast());
        prefetch(tree.nodes().as_ptr().wrapping_add(left).cast());
    }
}

/// A queued pair `(a, b)` of straddle `rank`, neither estimated nor its centre distance
/// worked out.
#[inline]
fn unestimated(a: u32, b: u32, rank: f32) -> Entry {
    Entry {
        p: UNESTIMATED,
        rank: f64::from(rank),
        a,
        b,
        center_distance: f32::NAN,
    }
}

/// The exact test of a leaf pair: the first intersecting triangle pair, if any, and how many
/// triangle pairs were tested.
#[inline]
pub(super) fn leaf_pair_hit(
    (a, x): (&AdbTree, &BvhNode),
    (b, y): (&AdbTree, &BvhNode),
    rel64: &PoseF64,
    cache: &mut QueryWorkspace,
) -> (Option<TrianglePair>, u32) {
    let (ma, mb) = (a.collision_mesh(), b.collision_mesh());
    let mut tests = 0u32;
    for &t in ma.bvh().triangles_of(x) {
        let tri_a = ma.mesh().triangle(t as usize).map(|p| p.as_dvec3());
        for &u in mb.bvh().triangles_of(y) {
            let tri_b = cache.cached_triangle(
                mb.mesh().triangles()[u as usize],
                mb.mesh().positions(),
                rel64,
            );
            tests += 1;
            if triangles_intersect(&tri_a, &tri_b) {
                return (Some(TrianglePair { a: t, b: u }), tests);
            }
        }
    }
    (None, tests)
}

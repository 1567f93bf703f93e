//! "Estimate parameters" (the papers' preprocessing step), made concrete: learn from the mesh
//! itself how often node pairs with a given raw estimate really contain intersecting triangles,
//! and turn any estimator into a calibrated one.
use std::sync::Arc;

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::estimator::{CollisionEstimator, NodePair};
use super::tree::{AdbTree, nodes_overlap, overlap_distance};
use crate::bvh::QueryWorkspace;
use crate::bvh::box_test::RelativeFrame;
use crate::bvh::traverse_pair::subtrees_intersect;
use crate::poses::near_contact_poses;

/// Depth buckets of the fitted table (by `(d_A + d_B) / (d_maxA + d_maxB)`).
pub const DEPTH_BUCKETS: usize = 8;
/// Bins of the base estimator's raw probability.
pub const RAW_BINS: usize = 20;

/// Options of [`FittedEstimator::fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Training poses (near first contact, seeded; never the poses you evaluate on).
    pub poses: usize,
    /// Random descents from the root pair per pose; every node pair on the way is a sample.
    pub walks_per_pose: usize,
    /// Offsets of the training poses from first contact, as a fraction of the size.
    pub spread: f32,
    /// Seed of the poses and walks.
    pub seed: u64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            poses: 48,
            walks_per_pose: 24,
            spread: 0.15,
            seed: 0xF17,
        }
    }
}

/// A base estimator whose raw output is mapped, per depth bucket, to the frequency with which
/// node pairs of that raw estimate truly contain intersecting triangles, measured on the mesh
/// itself ([`FittedEstimator::fit`]). The mapping is monotone in the raw estimate (pool
/// adjacent violators) and smoothed with a Beta(½, ½) prior, so it never claims certainty from
/// a handful of samples.
#[derive(Debug, Clone)]
pub struct FittedEstimator {
    base: Arc<dyn CollisionEstimator>,
    calibration: Calibration,
}

/// A fitted mapping from a raw estimate to a calibrated probability, per depth bucket
/// (see [`FittedEstimator`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    table: [[f32; RAW_BINS]; DEPTH_BUCKETS],
    samples: usize,
}

impl Calibration {
    /// The calibrated probability of a raw estimate for this pair.
    #[inline]
    /// Depth buckets the fit never sampled (possible for pairs of two different trees) keep the
    /// raw estimate.
    pub fn map(&self, pair: &NodePair<'_>, raw: f64) -> f64 {
        let raw = raw.clamp(0.0, 1.0);
        let fitted = self.table[bucket(pair)][raw_bin(raw)];
        if fitted.is_nan() {
            raw
        } else {
            f64::from(fitted)
        }
    }

    /// The table: `[depth bucket][raw-probability bin]` → probability (NaN: no samples).
    pub fn table(&self) -> &[[f32; RAW_BINS]; DEPTH_BUCKETS] {
        &self.table
    }

    /// Node pairs sampled by the fit.
    pub fn samples(&self) -> usize {
        self.samples
    }
}

impl FittedEstimator {
    /// Fits the mapping for queries between `a` and `b` (pass the same tree twice for a mesh
    /// against copies of itself) from random descents at seeded near-contact training poses.
    /// Each sampled node pair's truth is an exact subtree–subtree query.
    pub fn fit(
        a: &AdbTree,
        b: &AdbTree,
        base: Arc<dyn CollisionEstimator>,
        options: FitOptions,
    ) -> Self {
        let (ma, mb) = (a.collision_mesh(), b.collision_mesh());
        let poses = near_contact_poses(ma, mb, options.poses, options.spread, options.seed);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(options.seed ^ 0x5A5A_5A5A);
        let mut ws = QueryWorkspace::new();
        let mut counts = [[(0u32, 0u32); RAW_BINS]; DEPTH_BUCKETS];
        let mut samples = 0;
        let (na, nb) = (ma.bvh().nodes(), mb.bvh().nodes());
        for p in &poses {
            let rel = p.pose;
            let frame = RelativeFrame::new(&rel, ma.bvh(), mb.bvh());
            for _ in 0..options.walks_per_pose {
                let (mut ia, mut ib) = (0u32, 0u32);
                loop {
                    let (x, y) = (&na[ia as usize], &nb[ib as usize]);
                    let Some(center_distance) = overlap_distance(a, b, &frame, ia, ib) else {
                        break;
                    };
                    if (ia, ib) != (0, 0) {
                        let pair = NodePair::at_distance(a, b, center_distance, ia, ib, false);
                        let raw = base.probability(&pair).clamp(0.0, 1.0);
                        let truth = subtrees_intersect(ma, mb, &rel, ia, ib, &mut ws);
                        let cell = &mut counts[bucket(&pair)][raw_bin(raw)];
                        cell.0 += 1;
                        cell.1 += u32::from(truth);
                        samples += 1;
                    }
                    if x.is_leaf() && y.is_leaf() {
                        break;
                    }
                    // Step to a random overlapping child pair.
                    let children = |n: &crate::bvh::BvhNode, i: u32| {
                        if n.is_leaf() {
                            [i, i]
                        } else {
                            [n.left(), n.left() + 1]
                        }
                    };
                    let mut next = [(0u32, 0u32); 4];
                    let mut count = 0;
                    for u in children(x, ia) {
                        for v in children(y, ib) {
                            let fresh = !next[..count].contains(&(u, v));
                            if fresh && nodes_overlap(a, b, &frame, u, v) {
                                next[count] = (u, v);
                                count += 1;
                            }
                        }
                    }
                    if count == 0 {
                        break;
                    }
                    (ia, ib) = next[rng.random_range(0..count)];
                }
            }
        }
        let mut table = [[0f32; RAW_BINS]; DEPTH_BUCKETS];
        for (row, cells) in table.iter_mut().zip(&counts) {
            *row = monotone_rates(cells);
        }
        Self {
            base,
            calibration: Calibration { table, samples },
        }
    }

    /// The fitted mapping.
    pub fn calibration(&self) -> &Calibration {
        &self.calibration
    }

    /// Node pairs sampled by the fit.
    pub fn samples(&self) -> usize {
        self.calibration.samples
    }

    /// The mapping alone (to store in a tree).
    pub fn into_calibration(self) -> Calibration {
        self.calibration
    }
}

#[inline]
fn bucket(pair: &NodePair<'_>) -> usize {
    let total = (pair.max_depth_a + pair.max_depth_b).max(1) as f32;
    let d = f32::from(pair.a.depth) + f32::from(pair.b.depth);
    ((d / total * DEPTH_BUCKETS as f32) as usize).min(DEPTH_BUCKETS - 1)
}

#[inline]
pub(super) fn raw_bin(raw: f64) -> usize {
    ((raw * RAW_BINS as f64) as usize).min(RAW_BINS - 1)
}

/// Per-bin hit rates with a Beta(½, ½) prior, made non-decreasing by pooling adjacent
/// violators (weighted by sample counts); empty bins take their neighbours' values.
pub(super) fn monotone_rates(cells: &[(u32, u32); RAW_BINS]) -> [f32; RAW_BINS] {
    // Blocks of (weight, rate, first bin, last bin) over the non-empty bins.
    let mut blocks: Vec<(f64, f64, usize, usize)> = Vec::new();
    for (i, &(n, hits)) in cells.iter().enumerate() {
        if n == 0 {
            continue;
        }
        let rate = (f64::from(hits) + 0.5) / (f64::from(n) + 1.0);
        blocks.push((f64::from(n), rate, i, i));
        while blocks.len() >= 2 && blocks[blocks.len() - 2].1 > blocks[blocks.len() - 1].1 {
            let (w2, r2, _, e2) = blocks.pop().expect("two blocks");
            let (w1, r1, s1, _) = blocks.pop().expect("two blocks");
            blocks.push((w1 + w2, (w1 * r1 + w2 * r2) / (w1 + w2), s1, e2));
        }
    }
    let mut out = [f32::NAN; RAW_BINS];
    for &(_, rate, s, e) in &blocks {
        for v in &mut out[s..=e] {
            *v = rate as f32;
        }
    }
    // Fill empty bins: from the left neighbour, else the right one. A row with no samples at
    // all stays NaN, and `Calibration::map` then returns the raw estimate unchanged.
    let Some(first) = out.iter().copied().find(|v| !v.is_nan()) else {
        return out;
    };
    let mut last = first;
    for v in &mut out {
        if v.is_nan() {
            *v = last;
        } else {
            last = *v;
        }
    }
    out
}

impl CollisionEstimator for FittedEstimator {
    #[inline]
    fn probability(&self, pair: &NodePair<'_>) -> f64 {
        self.calibration.map(pair, self.base.probability(pair))
    }

    fn name(&self) -> &'static str {
        "fitted"
    }
}

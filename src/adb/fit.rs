//! "Estimate parameters" (the papers' preprocessing step), made concrete: learn from the mesh
//! itself how often node pairs with a given raw estimate really contain intersecting triangles,
//! and turn any estimator into a calibrated one.
use std::sync::Arc;

use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::calibration::{Calibration, DEPTH_BUCKETS, RAW_BINS, monotone_rates, raw_bin};
use super::estimator::{CollisionEstimator, NodePair, bucket};
use super::options::FitOptions;
use super::tree::{AdbTree, nodes_overlap, overlap_distance};
use crate::bvh::QueryWorkspace;
use crate::bvh::box_test::RelativeFrame;
use crate::bvh::traverse_pair::subtrees_intersect;
use crate::poses::near_contact_poses;

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
            calibration: Calibration::new(table, samples),
        }
    }

    /// The fitted mapping.
    pub fn calibration(&self) -> &Calibration {
        &self.calibration
    }

    /// Node pairs sampled by the fit.
    pub fn samples(&self) -> usize {
        self.calibration.samples()
    }

    /// The mapping alone (to store in a tree).
    pub fn into_calibration(self) -> Calibration {
        self.calibration
    }
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

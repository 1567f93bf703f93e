//! The confidence of answers that an interpenetration certificate tried and failed to settle,
//! calibrated on the mesh itself.
//!
//! A failed certificate is evidence: the deep overlaps, which the frontier's estimates rate as
//! most likely to collide, are the poses a certificate settles. The unsettled answers left
//! after it (near first contact, cut by a budget) collide far less often than the frontier's
//! confidence alone says. So, as the pair estimates are fitted on the mesh ([`super::fit`]),
//! the reported confidence of those answers is mapped to the frequency with which such answers
//! truly collide, measured on seeded training poses of the mesh against itself under a range of
//! node budgets. It applies to a tree queried against itself, the pairs it was fitted on;
//! between different trees the frontier's confidence stands (what a failed certificate says
//! depends on both meshes: against a thin wall, whose map has next to no inside, very little).
use super::calibration::{ConfidenceCalibration, RAW_BINS, monotone_rates, raw_bin};
use super::options::{Budget, FitOptions};
use super::traverse::{AdbQuery, AdbWorkspace, AnswerConfidence, adb_intersects};
use super::tree::AdbTree;
use crate::bvh::{QueryWorkspace, intersects};
use crate::geometry::Pose;
use crate::poses::near_contact_poses;

/// Node budgets of the training queries: small enough that most near-contact answers are cut.
const TRAINING_BUDGETS: [u64; 5] = [15, 30, 60, 120, 240];

/// Training poses of the confidence fit per pose of the pair fit ([`FitOptions::poses`]).
const POSES_PER_FIT_POSE: usize = 2;

impl ConfidenceCalibration {
    /// Fits the mapping on `tree` against copies of itself. `tree` must carry an interior map
    /// and no confidence calibration yet (its answers are the raw confidences); `None` when the
    /// training queries leave no unsettled answer to learn from.
    pub(super) fn fit(tree: &AdbTree, options: FitOptions) -> Option<Self> {
        let mesh = tree.collision_mesh();
        let poses = near_contact_poses(
            mesh,
            mesh,
            options.poses * POSES_PER_FIT_POSE,
            options.spread,
            options.seed ^ 0xC0FF_EE00,
        );
        let (mut ws, mut exact_ws) = (AdbWorkspace::new(), QueryWorkspace::new());
        let mut cells = [(0u32, 0u32); RAW_BINS];
        let mut samples = 0;
        for p in &poses {
            let mut truth = None;
            for budget in TRAINING_BUDGETS {
                // The raw frontier confidence is what the fit maps (the tree has no fit yet,
                // so `PerMesh` leaves it raw; the answer model would replace it).
                let query = AdbQuery {
                    answer_confidence: AnswerConfidence::PerMesh,
                    ..AdbQuery::with_budget(Budget::NodePairs(budget))
                };
                let out = adb_intersects(tree, &Pose::IDENTITY, tree, &p.pose, &query, &mut ws);
                if out.interpenetration.is_some()
                    || !(out.probability > 0.0 && out.probability < 1.0)
                {
                    continue;
                }
                let truth = *truth.get_or_insert_with(|| {
                    intersects(mesh, &Pose::IDENTITY, mesh, &p.pose, &mut exact_ws)
                });
                let cell = &mut cells[raw_bin(out.probability)];
                cell.0 += 1;
                cell.1 += u32::from(truth);
                samples += 1;
            }
        }
        (samples > 0).then(|| Self::new(monotone_rates(&cells), samples))
    }
}

//! ADB-trees (Klein & Zachmann 2003): time-critical, probability-guided mesh–mesh collision
//! queries that stop within a budget and say how sure their answer is.
//!
//! - [`AdbTree`]: a [`CollisionMesh`](crate::bvh::CollisionMesh)'s BVH whose nodes also store
//!   the number of "well-filled" cells of a grid over the node ([`cells`]), the node's depth and
//!   shape data, and, by default, an [`InteriorMap`] of the mesh's inside and the fits that
//!   calibrate its estimates ([`AdbBuildOptions`]).
//! - [`probability`] and [`tables`]: the overlap-volume estimate, the runtime numbers
//!   `s, s_A, s_B`, Eq. 8 (hypergeometric tail) and Eq. 9 (curvature term), computed stably,
//!   with lookup tables built once per process.
//! - [`CollisionEstimator`]: the pluggable probability model ([`PaperEstimator`], and
//!   [`PlanarityEstimator`] whose curvature term comes from the mesh).
//! - [`adb_intersects`]: the probability-guided traversal (the papers' best-first priority
//!   queue, evidence first and then depth first, depth first, or by default depth first with
//!   estimates on demand: [`Order`]) with `p_min`, `k_min`, budgets (node pairs or time) and
//!   optional exact leaves; its [`AdbOutcome`] says whether the meshes collide, with what
//!   confidence, whether the budget ran out, and where the contact probably is.
//! - [`AnswerModel`]: the confidence of an answer the traversal did not settle, from its
//!   [`Frontier`] (what is left, how deep, what the certificate said, how much was seen): a
//!   logistic model fitted once on many pairs of meshes ([`AnswerModel::FITTED`]), for any
//!   pair of trees ([`AdbQuery::answer_confidence`]).
//! - [`InteriorMap`]: the interpenetration certificate that [`AdbQuery::interior_after`]
//!   tries first: a surface sample of one mesh inside the other and one of the same
//!   connected surface outside it prove that the surfaces cross.
//! - [`certified_intersects`]: the exact query with that certificate as a pre-pass, trusted
//!   only in exact maps: always the answer of [`crate::bvh::intersects`], often sooner.
//! - [`exact_intersects`]: the fastest exact query of the crate ([`AdbQuery::exact`]): the
//!   certificate where it is exact, then the ADB traversal with its slabs and straddle order
//!   and exact leaves, never an estimate: always [`crate::bvh::intersects`]'s answer.
//!
//! # Which answers are certain
//! "Collision" is certain (probability 1) when an exact leaf test found an intersecting
//! triangle pair, or when the certificate was found in an [exact](InteriorMap::is_exact) map:
//! the map of a mesh whose every edge is used by an even number of triangles (a closed mesh);
//! an open mesh's map is approximate. "No collision" is certain when, with exact leaves and no
//! pruning, the traversal emptied its queue: every overlapping pair was ruled out by box or
//! triangle tests. Every other answer (a budget ran out, `k_min` estimated pairs counted as
//! evidence ([`Decision`]), the confidence reached [`AdbQuery::collide_at`], a certificate
//! from an open mesh's map) is an estimate, and may be wrong. So the query as a whole gives
//! the exact query's answer ([`crate::bvh::intersects`]) only with exact leaves,
//! `p_min = 1`, `p_prune = 0` and no budget ([`AdbQuery::exact_leaves`]); the default query
//! (`p_min = 0.99`) may decide from estimates.
//!
//! Next: [`crate::tracking`] follows the contacts of deforming and self-colliding meshes,
//! where an ADB-tree (built once per rigid mesh) does not apply.

mod answer_model;
mod build;
mod calibration;
pub mod cells;
mod certificate_confidence;
mod certified;
mod clearance;
mod confidence_fit;
mod descent;
mod estimator;
mod exact;
mod fit;
mod frontier;
mod interior;
pub(crate) mod logistic;
mod options;
pub mod probability;
mod queue;
mod ray_parity;
mod sample_lookup;
mod surface_samples;
pub mod tables;
mod traverse;
mod tree;
mod voxel_grid;
mod voxel_map;

pub use answer_model::{ANSWER_FEATURES, AnswerModel};
pub use calibration::{Calibration, ConfidenceCalibration, DEPTH_BUCKETS, RAW_BINS};
pub use certificate_confidence::CertificateReliability;
pub use certified::certified_intersects;
pub use estimator::{
    CalibratedEstimator, CollisionEstimator, NodePair, PaperEstimator, PlanarityEstimator,
    eq9_probability,
};
pub use exact::exact_intersects;
pub use fit::FittedEstimator;
pub use frontier::{CertificateHint, Frontier};
pub use interior::{
    InteriorMap, Interpenetration, MAX_SURFACE_SAMPLES, PairCrossing, PairLookup, SampleLookup,
};
pub use options::{
    AdbBuildOptions, Budget, Decision, FitOptions, Order, TRAINING_MESHES, TRAINING_SEEDS,
};
pub use surface_samples::CERTIFY_CHUNK;
pub use traverse::{
    AdbOutcome, AdbQuery, AdbWorkspace, AnswerConfidence, ContactWitness, adb_intersects,
};
pub use tree::{AdbBuildProgress, AdbNode, AdbTree};

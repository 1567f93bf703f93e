//! ADB-trees (Klein & Zachmann 2003): time-critical, probability-guided mesh–mesh collision
//! queries that trade accuracy for time, on purpose and measurably.
//!
//! - [`AdbTree`]: a [`CollisionMesh`](crate::bvh::CollisionMesh)'s BVH whose nodes also store
//!   the number of "well-filled" cells of a grid over the node ([`cells`]), the node's depth and
//!   shape data.
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

mod build;
mod calibration;
pub mod cells;
mod certificate_confidence;
mod clearance;
mod confidence_fit;
mod descent;
mod estimator;
mod fit;
mod interior;
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

pub use calibration::{Calibration, ConfidenceCalibration, DEPTH_BUCKETS, RAW_BINS};
pub use certificate_confidence::CertificateReliability;
pub use estimator::{
    CalibratedEstimator, CollisionEstimator, NodePair, PaperEstimator, PlanarityEstimator,
    eq9_probability,
};
pub use fit::FittedEstimator;
pub use interior::{
    InteriorMap, Interpenetration, MAX_SURFACE_SAMPLES, PairCrossing, PairLookup, SampleLookup,
};
pub use options::{AdbBuildOptions, Budget, Decision, FitOptions, Order};
pub use surface_samples::CERTIFY_CHUNK;
pub use traverse::{AdbOutcome, AdbQuery, AdbWorkspace, ContactWitness, adb_intersects};
pub use tree::{AdbBuildProgress, AdbNode, AdbTree};

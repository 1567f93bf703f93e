//! Stochastic closest-feature tracking for deforming, non-convex and self-colliding meshes
//! (Raghupathi et al. 2004, Guy and Debunne 2004, Kimmerle et al. 2004).
//!
//! Instead of testing every pair of primitives, a [`Tracker`] keeps a small list of feature
//! pairs (vertex, edge or triangle of each mesh) that are *locally* closest, and updates it
//! every frame in a small, fixed time: new random pairs are drawn (uniformly, by velocity, or
//! inside the overlapping patches of a shallow hierarchy), each pair descends to a locally
//! closest pair through the mesh topology, unwanted pairs are pruned, and the pairs closer
//! than the surfaces' thickness are reported as [`Contact`]s, extended by propagation to
//! their neighbourhood. Pairs persist across frames, so a contact found once is followed as
//! the surfaces move.
//!
//! - [`TrackedSurface`]: a mesh prepared for tracking (topology, sampling tables, patches);
//!   deform it with [`TrackedSurface::set_positions`].
//! - [`Tracker`]: the pair list and the per-frame step, for a pair of meshes
//!   ([`Tracker::step_pair`]) or one mesh against itself ([`Tracker::step_self`]).
//! - [`TrackerConfig`]: pairs per frame, sampling, search variant, thickness, thresholds, seed.
//!
//! What it costs and misses against the exact self-collision pass
//! ([`crate::bvh::self_contacts`]) is measured by `examples/tracking_quality.rs`.

mod config;
mod contact;
mod feature;
mod local_search;
mod patch_tree;
mod pruning;
mod sampling;
mod surface;
mod tracker;

pub use config::{Sampling, SearchMode, TrackerConfig};
pub use contact::Contact;
pub use feature::{Feature, FeatureShape, FeatureVertices, feature_distance};
pub use local_search::triangles_within_rings;
pub use pruning::PruneCounts;
pub use surface::{DEFAULT_PATCH_SIZE, TrackedSurface};
pub use tracker::{PairList, StepStats, TrackedPair, Tracker};

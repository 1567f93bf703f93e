//! Stochastic closest-feature tracking for deforming, non-convex and self-colliding meshes
//! (Raghupathi et al. 2004, Guy and Debunne 2004, Kimmerle et al. 2004).
//!
//! Instead of testing every pair of primitives, a [`Tracker`] keeps a bounded list of feature
//! pairs (vertex, edge or triangle of each mesh) that are *locally* closest, and updates it
//! every frame: new random pairs are drawn (uniformly, by velocity, or inside the overlapping
//! patches of a shallow hierarchy), each pair descends to a locally closest pair through the
//! mesh topology (a new pair first over the vertices, and over triangles only where it can be
//! kept: [`TrackerConfig::multiresolution`]), unwanted pairs are pruned, and the pairs closer
//! than the surfaces' thickness are reported as [`Contact`]s, extended by propagation to their
//! neighbourhood. Pairs persist across frames, so a contact found once is followed as the
//! surfaces move. The answer is approximate: a contact region no pair has reached yet is not
//! reported.
//!
//! - [`TrackedSurface`]: a mesh prepared for tracking (topology, sampling tables, patches, the
//!   self-collision exclusion);
//!   deform it with [`TrackedSurface::set_positions`].
//! - [`Tracker`]: the pair list and the per-frame step, for a pair of meshes
//!   ([`Tracker::step_pair`]) or one mesh against itself ([`Tracker::step_self`]).
//! - [`TrackerConfig`]: pairs per frame, sampling, search variant, thickness, thresholds, seed.
//!
//! # What a frame costs
//! The work on feature pairs is bounded by the configuration:
//! [`TrackerConfig::pairs_per_frame`] new pairs, or by default more where the surfaces come
//! close to each other in many places (one per [`TrackerConfig::overlaps_per_pair`]
//! overlapping patch pairs, so that a large, coiled surface is sampled as densely as a small
//! one; never more than [`TrackerConfig::max_active_pairs`]), at most
//! [`TrackerConfig::max_active_pairs`] kept ones, each searched for at most
//! [`TrackerConfig::max_iterations`] steps (in self-collision a kept pair whose search settled
//! and around which no vertex moved is kept without one, [`StepStats::still`]), at most
//! [`TrackerConfig::propagation_limit`] propagated contacts. The rest of a frame grows with
//! the mesh: [`TrackedSurface::set_positions`] refits the whole patch tree and every
//! triangle normal, and [`Sampling::Velocity`] weighs every triangle. With
//! [`Sampling::Hierarchy`] (the default), self-collision keeps its candidates between steps
//! (the overlapping patch pairs and the sharp edges, per part of the patch tree) and finds
//! them again only where the surface moved: a surface at rest costs nothing there, a motion
//! in one place the parts it reached (where everything moves, as much as finding them all:
//! every overlapping patch pair, and the edges of every patch that may hold a fold, its
//! normal cone, or its cone with an adjacent patch's, 45° wide or more, or a collapsed edge).
//! Between two meshes the overlapping patch pairs are found anew at each step. [`StepStats::times`] ([`StepTimes`]) and
//! [`TrackedSurface::update_time`] say where a frame's time went. A deadline ([`Tracker::step_self_until`]) cuts the searching, not that
//! work. What tracking finds and misses against the exact self-collision pass with the same
//! exclusion ([`crate::bvh::self_contacts_excluding`] with a [`crate::mesh::SelfExclusion`] of
//! [`TrackerConfig::exclusion_rings`]) is measured by `examples/tracking_quality.rs`; on small
//! and flat meshes that exact pass can cost less than a tracker step (`docs/tracking.md`).
//!
//! Next: [`crate::ccd`], continuous collision over a time step; or [`crate::ecs`], whose
//! plugin runs a tracker for every pair and self-colliding mesh with
//! [`Fidelity::Tracking`](crate::ecs::Fidelity::Tracking).

mod boxes;
mod candidates;
mod coarse;
mod config;
mod contact;
mod feature;
mod local_search;
mod patch_reach;
mod patch_tree;
mod pruning;
mod sampling;
mod sharp_edges;
mod surface;
mod sweep;
mod timing;
mod tracker;

pub use crate::mesh::triangles_within_rings;
pub use coarse::CoarseCounts;
pub use config::{Sampling, SearchMode, TRAINING_MESHES, TRAINING_SEEDS, TrackerConfig};
pub use contact::Contact;
pub use feature::{Feature, FeatureShape, FeatureVertices, feature_distance};
pub use pruning::PruneCounts;
pub use surface::{DEFAULT_EXCLUSION_RINGS, DEFAULT_PATCH_SIZE, TrackedSurface};
pub use sweep::MAX_SWEEP_RINGS;
pub use timing::StepTimes;
pub use tracker::{PairList, StepStats, TrackedPair, Tracker};

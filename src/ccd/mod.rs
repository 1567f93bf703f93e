//! Continuous collision detection: when, within a step, two moving meshes first touch, so that
//! fast bodies never pass through thin ones unseen.
//!
//! - [`time_of_impact`]: two rigid meshes, each moving from one [`Pose`](crate::geometry::Pose)
//!   to another over the step ([`RigidMotion`]: linear translation, rotation at a constant rate).
//! - [`deforming_time_of_impact`]: two deforming meshes, each vertex moving linearly between
//!   two states of the mesh.
//! - [`adb_time_of_impact`]: two rigid ADB-trees within a budget: the exact answer when the
//!   search ends in time, else an estimate of the node pairs left (or, conservative, a contact
//!   whenever one is left) with a confidence.
//! - [`vertex_face_time`] and [`edge_edge_time`]: one pair of features moving linearly, the
//!   building block of all three.
//!
//! Every pair of features whose swept boxes meet is decided by an inclusion-based root finder
//! that never misses a root: the answer is never later than the first contact, and no earlier
//! than the last moment the features were more than a stated distance tolerance apart (see
//! [`CcdOptions`]). Both trees are descended together, node pairs in the order of the earliest
//! time their moving boxes can meet, and each feature pair is searched only over the times its
//! own moving boxes meet. Where a mesh does not turn over the step, its nodes are bounded by
//! their slabs too ([`NodeSlab`](crate::bvh::NodeSlab): thin where the surface is nearly
//! flat), and every triangle by its plane: two facing patches' boxes meet long before the
//! patches do, their slabs only when the patches come within the tolerance.
//!
//! The plugin calls [`time_of_impact`] for colliders marked
//! [`ContinuousCollision`](crate::ecs::ContinuousCollision).
//!
//! Next: [`crate::ecs`], the Bevy plugin that runs the discrete queries every step.

mod descent;
mod impact;
mod inclusion;
mod motion;
mod primitive;
mod query;
mod swept;
mod swept_answer_model;
mod time_critical;
pub(crate) mod window;

pub use impact::{ImpactFeatures, TimeOfImpact};
pub use motion::{RigidMotion, Trajectory};
pub use primitive::{CcdScratch, PrimitiveTolerances, edge_edge_time, vertex_face_time};
pub use query::{CcdError, CcdOptions, CcdWorkspace, deforming_time_of_impact, time_of_impact};
pub use swept_answer_model::{SWEPT_FEATURES, SweptAnswerModel, SweptFrontier};
pub use time_critical::{
    ContinuousAdbOutcome, ContinuousAdbQuery, SweptConfidence, SweptWitness, adb_time_of_impact,
};

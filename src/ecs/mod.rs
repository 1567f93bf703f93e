//! The Bevy integration: a plugin running the collision pipeline in a schedule, components to
//! describe colliders, collision events, a frame-time budget and budgeted responses.
//!
//! # Overview
//! Add [`StochasticCollisionPlugin`], give entities a [`Collider`] (rigid, shared mesh and
//! ADB-tree) or a [`Deformable`] (owned, refitted mesh) and a pose ([`ColliderPose`], or
//! bevy_transform's `GlobalTransform` with the `transform` feature), and read
//! [`CollisionStarted`], [`CollisionEnded`] and [`Contact`] messages, or observe them per
//! entity ([`CollisionEventsEnabled`]).
//!
//! Each run goes through the chained [`CollisionSystems`]:
//! 1. **Prepare**: poses, refit of deformed meshes (parallel), validation (bad entities are
//!    reported with a [`CollisionError`] and skipped), world boxes.
//! 2. **BroadPhase**: sweep and prune with temporal coherence, [`CollisionLayers`] filtering.
//! 3. **NarrowPhase**: per pair, in parallel, by [`Fidelity`]: exact, ADB (cut by its share of
//!    the [`FrameBudget`], priority by last confidence, closeness and speed) or bounds.
//! 4. **Tracking**: tracked pairs and self-collision of [`SelfCollision`] meshes, in parallel.
//! 5. **Report**: started/ended/contact messages in a deterministic order,
//!    [`CollidingEntities`], observer events, the [`ContactQueue`].
//! 6. **Response**: the built-in [`ImpulseResponsePlugin`] and [`PenaltyResponsePlugin`], or
//!    your own systems, consuming contacts by priority within the response budget.
//!
//! A stage runs only when some entity needs it; [`CollisionDiagnostics`] has each stage's time
//! (`None` when it did not run) and the work done.
//!
//! # Determinism
//! Pairs are processed in parallel and merged in entity order; with a
//! [`FrameBudget::NodePairs`] budget (or none), a run gives the same events for any number of
//! threads. A [`FrameBudget::Time`] budget adapts to the machine's speed, so its results
//! depend on timing.
mod broad_phase;
mod budget;
mod components;
mod contact;
mod diagnostics;
mod events;
mod narrow_phase;
mod plugin;
mod pool;
mod prepare;
mod response;
mod schedule;
mod tracking_systems;

pub use broad_phase::{BroadPhaseState, CandidatePair, CandidatePairs};
pub use budget::{pair_priority, pair_seed, slices};
pub use components::{
    Collider, ColliderPose, CollidingEntities, CollisionEventsEnabled, CollisionLayers, Deformable,
    Fidelity, SelfCollision,
};
pub use contact::ContactPoint;
#[cfg(feature = "diagnostic")]
pub use diagnostics::store as diagnostics_store;
pub use diagnostics::{CollisionCounters, CollisionDiagnostics, Stage, StageRecord};
pub use events::{
    CollisionEnded, CollisionError, CollisionErrorKind, CollisionStarted, Contact, ContactQueue,
    ReportState,
};
pub use narrow_phase::{Method, PairOutcome, PairOutcomes};
pub use plugin::{CollisionConfig, FrameBudget, StochasticCollisionPlugin};
pub use pool::CollisionTaskPool;
pub use prepare::{ColliderEntry, ColliderFrame, Geometry, PrepareState};
pub use response::{
    ImpulseResponsePlugin, ImpulseSettings, Mass, PenaltyResponsePlugin, PenaltySettings, Rest,
    Velocity, impulse_response, integrate_velocities, penalty_response, sleep_bodies,
};
pub use schedule::CollisionSystems;
pub use tracking_systems::{FeaturePairs, TrackingState};

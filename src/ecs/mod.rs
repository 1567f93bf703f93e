//! The Bevy integration: a plugin running the collision pipeline in a schedule, components to
//! describe colliders, collision events, a frame-time budget and budgeted responses.
//!
//! # Overview
//! Add [`StochasticCollisionPlugin`], give entities a [`MeshCollider`] (rigid, shared mesh and
//! ADB-tree) or a [`Deformable`] (owned, refitted mesh) placed with bevy_transform's
//! `Transform` (with the `transform` feature, the default; else [`ColliderPose`] and
//! [`ColliderScale`]), and read [`CollisionStarted`] and [`CollisionEnded`] messages (with
//! the method and confidence of the answer), or observe them per entity
//! ([`ObserveCollisions`]); read contacts, touching or not, with their confidence and
//! age through the [`CollisionPairs`] system parameter ([`Contact`] messages on request:
//! [`CollisionConfig::contact_messages`]).
//!
//! With the `bevy_mesh` feature (on by default), colliders also come from bevy_mesh's `Mesh`
//! assets: converted on the spot (`MeshCollider::from_bevy_mesh`), or built off the main
//! thread for `Mesh3d` entities and whole scene hierarchies such as glTF scenes
//! (`MeshColliderConstructor`, `MeshColliderConstructorHierarchy`).
//!
//! The plugin keeps its world between runs: a [`ColliderTable`] (one slot per collider) and a
//! [`PairTable`] (one slot per pair of close colliders, with its last answer). A run works
//! only on what changed, through the chained [`CollisionSystems`]:
//! 1. **Prepare**: poses and scales from `Transform` (composed with the ancestors'); the
//!    colliders whose pose, scale, mesh, fidelity or layers changed (Bevy's change
//!    detection), refit of deformed meshes (parallel), validation (bad entities are reported
//!    with a [`CollisionError`] and skipped), world boxes.
//! 2. **BroadPhase**: colliders whose world box left their broad-phase (fat) box, and only
//!    they, get a new one; pairs are created and removed at that moment (sweep and prune over
//!    the fat boxes, [`ContactLayers`] filtering, then the app's [`PairFilter`] if any).
//! 3. **NarrowPhase**: the *active* pairs (of colliders that changed, new, or waiting for a
//!    test), in parallel, by [`Fidelity`]: exact, ADB (cut by its share of the
//!    [`FrameBudget`], priority by last confidence, closeness, speed and waiting) or bounds;
//!    under a time budget the pairs not tested keep their last answer, one run older.
//! 4. **Tracking**: tracked pairs and self-collision of [`SelfCollision`] meshes, in parallel.
//! 5. **Report**: the pairs whose touching state flipped: started/ended messages in a
//!    deterministic order, [`TouchingEntities`], observer events; this run's contacts to the
//!    [`ContactQueue`].
//! 6. **Response**: the built-in [`ImpulseResponsePlugin`] and [`PenaltyResponsePlugin`], or
//!    your own systems, consuming contacts by priority within the response budget.
//!
//! What each stage reads and writes (the modules are named after the stages):
//!
//! | set | systems | reads | writes |
//! |---|---|---|---|
//! | Prepare (`prepare/`) | `sync_transforms`, `refit_deformables`, `update_colliders` | `Transform`s, the collider components that changed ([`RemovedColliders`] for removals) | [`ColliderTable`], [`CollisionError`] |
//! | BroadPhase (`broad_phase/`) | `update_broad_phase`, then `filter_pairs` with a [`PairFilter`] | the colliders that changed | fat boxes ([`BroadPhaseState`]), pairs created and removed in the [`PairTable`] |
//! | NarrowPhase (`narrow_phase/`) | `narrow_phase` | the active pairs, the [`BudgetController`]'s plan | answers, memory and transitions in the [`PairTable`] |
//! | Tracking (`tracking/`) | `self_collision`, `track_pairs`, `prune_feature_pairs`, `forget_untracked` | the tracked pairs | answers in the [`PairTable`], [`TrackingState`], [`FeaturePairs`] |
//! | Report (`events.rs`) | `report_collisions` | transitions and this run's contacts | [`CollisionStarted`], [`CollisionEnded`], [`Contact`], [`TouchingEntities`], observer events, the [`ContactQueue`] |
//! | Response (`response/`) | the built-in responses, yours | the [`ContactQueue`] within the [`ResponseBudget`] | `Transform`s, velocities, deformable positions |
//!
//! One [`BudgetController`] times every stage with its clock (the system clock, or a
//! [`FakeClock`] a test moves) and plans each run under a [`FrameBudget::Time`] budget from
//! what it measured: what Prepare and BroadPhase took, what Tracking and Report took last
//! time, what a test and an answer from memory cost; the narrow phase tests what fits (a
//! quarter of the tests for the pairs that waited longest, so none starves), the trackers
//! stop at the run's deadline, and the Response stage has a [`ResponseBudget`] of its own.
//! [`BudgetController::plan`] shows the last plan.
//!
//! A stage runs only when some entity needs it; [`CollisionDiagnostics`] (read-only output)
//! has each stage's time (`None` when it did not run) and the work done. In a scene at rest (no collider changed)
//! the broad phase does not sweep, and the narrow phase works only on the pairs still waiting
//! for a test.
//!
//! # Determinism
//! Pairs are processed in parallel and recorded in an order that depends only on the history
//! of the tables; with a [`FrameBudget::NodePairs`] budget (or none), a run gives the same
//! events for any number of threads. A [`FrameBudget::Time`] budget adapts to the machine's
//! speed, so its results depend on timing.
//!
//! Next: [`CollisionConfig`] (budgets, ADB settings, contacts), [`Fidelity`] (how each pair
//! is answered) and [`CollisionPairs`] (reading contacts); the `pile`, `cannonball`, `cloth`
//! and `intestine` examples run whole scenes.
#[cfg(feature = "bevy_mesh")]
mod bevy_mesh;
mod broad_phase;
mod budget;
mod components;
mod config;
mod contact;
#[cfg(feature = "debug_render")]
mod debug_render;
mod diagnostics;
mod events;
mod layers;
mod narrow_phase;
mod pairs;
mod parallel;
mod plugin;
mod plugin_group;
mod prepare;
mod reflect;
mod response;
mod schedule;
mod stamp;
mod tracking;

#[cfg(feature = "bevy_mesh")]
pub use bevy_mesh::{
    BevyMeshError, MeshColliderCache, MeshColliderConstructor, MeshColliderConstructorHierarchy,
    MeshColliderSystems, MeshNameFilter, trimesh_from_bevy_mesh,
};
pub use broad_phase::BroadPhaseState;
pub use budget::{
    BudgetClock, BudgetController, FakeClock, RunPlan, SystemClock, pair_priority, pair_seed,
    slices,
};
pub use components::{
    ColliderPose, ColliderScale, CollisionSensor, ContinuousCollision, Deformable, Fidelity,
    MeshCollider, ObserveCollisions, SelfCollision, TouchingEntities,
};
pub use config::{CollisionConfig, FrameBudget, ResponseBudget};
pub use contact::ContactPoint;
#[cfg(feature = "debug_render")]
pub use debug_render::{
    CollisionDebugPlugin, CollisionGizmos, NormalLength, draw_collider_boxes, draw_contacts,
    draw_feature_pairs,
};
#[cfg(feature = "diagnostic")]
pub use diagnostics::store as diagnostics_store;
pub use diagnostics::{CollisionCounters, CollisionDiagnostics, Stage, StageRecord};
pub use events::{CollisionEnded, CollisionError, CollisionErrorKind, CollisionStarted, Contact};
pub use layers::{ContactLayer, ContactLayers};
pub use narrow_phase::{Method, NarrowPhaseState, PairOutcome};
pub use pairs::{
    CollisionPairs, PairFilter, PairFilterPlugin, PairTable, PairView, RefilterPairs, filter_pairs,
};
pub use parallel::CollisionTaskPool;
pub use plugin::StochasticCollisionPlugin;
pub use plugin_group::StochasticCollisionPlugins;
pub use prepare::{ColliderEntry, ColliderTable, Geometry, PrepareState, RemovedColliders};
pub use reflect::{
    DecisionReflect, OptionTrianglePairReflect, OrderReflect, PoseReflect, TrianglePairReflect,
    register_response_types, register_types,
};
pub use response::{
    BodyAngularVelocity, BodyInertia, BodyMass, BodyVelocity, ContactQueue, DEFAULT_STEP,
    ImpulseResponsePlugin, ImpulseSettings, InertiaSource, PenaltyResponsePlugin, PenaltySettings,
    Rest, impulse_response, integrate_velocities, penalty_response, sleep_bodies,
    update_body_inertia,
};
pub use schedule::{CollisionSchedule, CollisionSystems};
pub use tracking::{FeaturePairs, TrackingState};

//! The public, chained system sets of the collision pipeline.
use bevy_ecs::intern::Interned;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;

/// The stages of one run of the collision pipeline, chained in this order in the plugin's
/// schedule. Order your systems around them, for example a game's reaction
/// `.after(CollisionSystems::Report)` or a custom response `.in_set(CollisionSystems::Response)`.
///
/// Every stage runs only when some entity needs it (run conditions): with no deformable mesh
/// there is no refit, with no [`SelfCollision`](super::SelfCollision) marker no self pass, with
/// no tracked pair no tracking; [`CollisionDiagnostics`](super::CollisionDiagnostics) shows
/// idle stages as not run.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CollisionSystems {
    /// Poses and scales from `Transform` (composed with the ancestors'), `GlobalTransform`
    /// or [`ColliderPose`](super::ColliderPose) and [`ColliderScale`](super::ColliderScale),
    /// refit of deformed meshes, validation, world boxes.
    Prepare,
    /// Pairs created and removed where colliders left their broad-phase boxes (sweep and
    /// prune), filtered by layers.
    BroadPhase,
    /// Per active pair, in parallel: exact, ADB (cut by the budget) or bounds.
    NarrowPhase,
    /// Tracked pairs and self-collision of deformable meshes, in parallel.
    Tracking,
    /// The pairs whose touching state flipped: started/ended messages, `TouchingEntities`,
    /// observer events; this run's contacts to the contact queue (and as messages, on request).
    Report,
    /// Responses consuming the contact queue (built-in plugins or your own systems).
    Response,
}

/// The schedule the [`StochasticCollisionPlugin`](super::StochasticCollisionPlugin) runs in
/// (a resource it inserts; the response plugins read it).
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct CollisionSchedule(pub Interned<dyn ScheduleLabel>);

//! Reflection: the plugin's components, resources and messages derive bevy_reflect's
//! `Reflect` and are registered by [`StochasticCollisionPlugin`](super::StochasticCollisionPlugin),
//! so inspectors, scenes and `bevy_remote` see them.
//!
//! The geometry core does not depend on Bevy; the core types that appear in reflected fields
//! ([`Pose`], [`TrianglePair`], the ADB traversal's [`Order`] and [`Decision`]) are reflected
//! through the mirrors below (bevy_reflect's remote reflection): a field of such a type reads
//! and writes as a struct or enum of the same shape.
//!
//! Meshes and trees ([`MeshCollider`](super::MeshCollider), [`Deformable`](super::Deformable))
//! are reflected as opaque values: an inspector sees that they are there, a reflected clone
//! shares the tree, but their triangles are not fields. The pipeline's internal state (the
//! collider and pair tables, workspaces, the task pool) is not reflected: read it through
//! [`CollisionPairs`](super::CollisionPairs), [`ColliderTable`](super::ColliderTable) and
//! [`CollisionDiagnostics`](super::CollisionDiagnostics).
use bevy_app::App;
use bevy_reflect::reflect_remote;
use glam::{Quat, Vec3};

use crate::adb::{Decision, Order};
use crate::bvh::TrianglePair;
use crate::geometry::Pose;

/// The reflected shape of [`Pose`].
#[reflect_remote(Pose)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, Clone, PartialEq)]
pub struct PoseReflect {
    /// Rotation (unit quaternion).
    pub rotation: Quat,
    /// Translation.
    pub translation: Vec3,
}

/// The reflected shape of [`TrianglePair`].
#[reflect_remote(TrianglePair)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, Clone, PartialEq)]
pub struct TrianglePairReflect {
    /// Triangle of the first mesh.
    pub a: u32,
    /// Triangle of the second mesh.
    pub b: u32,
}

/// The reflected shape of an optional [`TrianglePair`].
#[reflect_remote(Option<TrianglePair>)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, Clone, PartialEq)]
pub enum OptionTrianglePairReflect {
    /// No triangle pair.
    None,
    /// This triangle pair.
    Some(#[reflect(remote = TrianglePairReflect)] TrianglePair),
}

/// The reflected shape of the ADB traversal [`Order`].
#[reflect_remote(Order)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, Clone, PartialEq)]
pub enum OrderReflect {
    /// See [`Order::BestFirst`].
    BestFirst,
    /// See [`Order::EvidenceFirst`].
    EvidenceFirst,
    /// See [`Order::DepthFirst`].
    DepthFirst,
    /// See [`Order::Straddle`].
    Straddle,
}

/// The reflected shape of the ADB [`Decision`] rule.
#[reflect_remote(Decision)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, Clone, PartialEq)]
pub enum DecisionReflect {
    /// See [`Decision::Paper`].
    Paper,
    /// See [`Decision::Confidence`].
    Confidence,
    /// See [`Decision::Evidence`].
    Evidence,
}

/// Registers every reflected type of the plugin (called by the plugins; calling it again is
/// harmless).
pub fn register_types(app: &mut App) {
    use super::*;
    app.register_type::<MeshCollider>()
        .register_type::<Deformable>()
        .register_type::<Fidelity>()
        .register_type::<SelfCollision>()
        .register_type::<ContinuousCollision>()
        .register_type::<ContactLayers>()
        .register_type::<TouchingEntities>()
        .register_type::<ColliderPose>()
        .register_type::<ColliderScale>()
        .register_type::<CollisionSensor>()
        .register_type::<ObserveCollisions>()
        .register_type::<FeaturePairs>()
        .register_type::<CollisionConfig>()
        .register_type::<FrameBudget>()
        .register_type::<ResponseBudget>()
        .register_type::<RunPlan>()
        .register_type::<CollisionDiagnostics>()
        .register_type::<Stage>()
        .register_type::<StageRecord>()
        .register_type::<CollisionCounters>()
        .register_type::<CollisionStarted>()
        .register_type::<CollisionEnded>()
        .register_type::<Contact>()
        .register_type::<CollisionError>()
        .register_type::<CollisionErrorKind>()
        .register_type::<ContactPoint>()
        .register_type::<Method>();
}

/// Registers the reflected types of the built-in responses.
pub fn register_response_types(app: &mut App) {
    use super::*;
    app.register_type::<BodyVelocity>()
        .register_type::<BodyAngularVelocity>()
        .register_type::<BodyInertia>()
        .register_type::<InertiaSource>()
        .register_type::<BodyMass>()
        .register_type::<Rest>()
        .register_type::<ImpulseSettings>()
        .register_type::<PenaltySettings>();
}

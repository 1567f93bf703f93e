//! The components a user puts on an entity: its collision geometry, how precisely it collides,
//! with what, and where it is.
mod collider;
mod fidelity;
mod markers;
mod pose;

pub use collider::{Deformable, MeshCollider};
pub use fidelity::{ContinuousCollision, Fidelity, SelfCollision};
pub use markers::{CollisionSensor, ObserveCollisions, TouchingEntities};
pub use pose::{ColliderPose, ColliderScale};

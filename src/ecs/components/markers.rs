//! Markers and per-entity outputs: the entities it touches, sensors, observed entities.

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;

/// The entities this entity currently collides with (sorted), kept up to date by the Report
/// stage. Inserted automatically with [`MeshCollider`](crate::ecs::MeshCollider) and [`Deformable`](crate::ecs::Deformable); a mesh's own
/// self-collision is not listed.
#[derive(Component, Reflect, Clone, Debug, Default, PartialEq, Eq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct TouchingEntities(pub(crate) Vec<Entity>);

impl TouchingEntities {
    /// The colliding entities, sorted.
    #[inline]
    pub fn entities(&self) -> &[Entity] {
        &self.0
    }

    /// Whether this entity collides with `other`.
    #[inline]
    pub fn contains(&self, other: Entity) -> bool {
        self.0.binary_search(&other).is_ok()
    }

    /// Number of colliding entities.
    #[inline]
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether the entity collides with nothing.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    pub(crate) fn insert(&mut self, e: Entity) {
        if let Err(i) = self.0.binary_search(&e) {
            self.0.insert(i, e);
        }
    }

    pub(crate) fn remove(&mut self, e: Entity) {
        if let Ok(i) = self.0.binary_search(&e) {
            self.0.remove(i);
        }
    }
}

/// Marks a collider as a sensor (a trigger volume): its pairs are detected and reported as
/// usual (events, [`TouchingEntities`], contacts through
/// [`CollisionPairs`](crate::ecs::CollisionPairs) and [`Contact`](crate::ecs::Contact) messages), but its
/// contacts never reach the [`ContactQueue`](crate::ecs::ContactQueue): no response pushes
/// anything out of it or away from it. Named so that it does not clash with avian's and
/// bevy_rapier's `Sensor`.
///
/// Contact is contact of surfaces: with [`Fidelity::Exact`](crate::ecs::Fidelity::Exact) a body wholly inside a closed
/// sensor mesh does not touch it (ADB's interpenetration certificate does count it).
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Clone, Debug, Default)]
pub struct CollisionSensor;

/// Opt in to per-entity observer events ([`CollisionStarted`](crate::ecs::CollisionStarted) and
/// [`CollisionEnded`](crate::ecs::CollisionEnded) triggered on this entity, observed with
/// `On<CollisionStarted>`). The marker is read when events are emitted, so adding it to an
/// entity that already exists works.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Clone, Debug, Default)]
pub struct ObserveCollisions;

//! Where a collider is without bevy_transform (or as the Prepare stage read it): its pose and
//! scale.

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;
use glam::Vec3;

use crate::geometry::Pose;

/// The pose the collision stages use (rotation and translation; the scale is
/// [`ColliderScale`]).
///
/// With the `transform` feature (default), an entity with bevy_transform's `Transform` gets
/// this (and its [`ColliderScale`]) from its `Transform` composed with its ancestors', at the
/// start of every run (see [`CollisionSystems::Prepare`](crate::ecs::CollisionSystems)): the
/// pose of this very run, without waiting for transform propagation, and for a new entity
/// the pose it was spawned at. An entity with only a `GlobalTransform` gets it from that.
/// Otherwise set it yourself (headless apps, simulations that own their poses).
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct ColliderPose(#[reflect(remote = super::super::reflect::PoseReflect)] pub Pose);

impl ColliderPose {
    /// A pose at `translation`, not rotated.
    pub fn from_translation(translation: Vec3) -> Self {
        Self(Pose::from_translation(translation))
    }
}

/// The scale of a collider's mesh along its local axes, applied before its
/// [`ColliderPose`] (default 1: the mesh as built). Non-uniform and negative (mirroring)
/// factors are allowed; a factor that is zero, not finite or below `1e-6` in magnitude makes
/// the entity invalid (a [`CollisionError`](crate::ecs::CollisionError), the entity skipped).
///
/// With the `transform` feature, entities with a `Transform` get it from the `Transform`
/// (see [`ColliderPose`]).
///
/// # Example
/// ```
/// use bevy_app::prelude::*;
/// use bevy_ecs::prelude::*;
/// use stochastic_collision::prelude::*;
///
/// let mut app = App::new();
/// app.add_plugins(StochasticCollisionPlugin::in_schedule(PostUpdate));
/// let ball = MeshCollider::new(generate::icosphere(1.0, 2));
/// // Radius 2 (scaled) at the origin reaches a ball of radius 1 at x = 2.5.
/// app.world_mut().spawn((ball.clone(), ColliderScale::uniform(2.0)));
/// app.world_mut().spawn((ball, ColliderPose::from_translation(Vec3::X * 2.5)));
/// app.update();
/// assert_eq!(app.world().resource::<Messages<CollisionStarted>>().len(), 1);
/// ```
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct ColliderScale(pub Vec3);

impl Default for ColliderScale {
    fn default() -> Self {
        Self(Vec3::ONE)
    }
}

impl ColliderScale {
    /// The same factor along every axis.
    pub fn uniform(factor: f32) -> Self {
        Self(Vec3::splat(factor))
    }

    /// Whether the factors are usable: finite and at least `1e-6` in magnitude.
    pub fn is_valid(&self) -> bool {
        self.0.is_finite() && self.0.abs().min_element() >= 1e-6
    }
}

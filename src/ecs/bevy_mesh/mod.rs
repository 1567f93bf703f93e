//! Colliders from Bevy meshes (the `bevy_mesh` feature, on by default): bevy_mesh's `Mesh`
//! assets, `Mesh3d` entities and whole scene hierarchies such as glTF scenes.
//!
//! # Overview
//! - **From a `&Mesh`**, on the calling thread: [`MeshCollider::from_bevy_mesh`],
//!   [`Deformable::from_bevy_mesh`], or the triangles alone with [`trimesh_from_bevy_mesh`].
//!   Triangle lists and strips, indexed (`u16` or `u32`) or not; strips are read as a GPU
//!   draws them (alternate triangles swapped so that all face the same way, degenerate joining
//!   triangles dropped, the primitive-restart index starting a new strip). Points, lines and
//!   missing or non-`Float32x3` positions are a [`BevyMeshError`].
//! - **From an entity's `Mesh3d`**: put a [`MeshColliderConstructor`] next to it. When the
//!   asset is in `Assets<Mesh>` (now or later), the collider is built on bevy_tasks'
//!   `AsyncComputeTaskPool`, inserted ([`MeshCollider`] or [`Deformable`]) and the
//!   constructor removed. The entity is not a collider before that, and the frame is never
//!   stalled by a large mesh: it only copies the positions and indices out of the asset.
//! - **From a scene** (a glTF scene's root, whose descendants carry `Mesh3d` and spawn after
//!   the asset loads): put a [`MeshColliderConstructorHierarchy`] on the root; every `Mesh3d`
//!   entity under it, now or later, gets a constructor (optionally filtered by
//!   [`MeshNameFilter`]). Each collider is placed by its entity's `Transform` composed with its
//!   ancestors' (scale included), as every collider is.
//!
//! Builds are shared through the [`MeshColliderCache`], keyed by the mesh's asset id and
//! the constructor: one mesh used by many entities is built once and its tree shared. A
//! modified or removed asset drops its entry. A mesh that cannot be converted is reported
//! as a [`CollisionError`](crate::ecs::CollisionError) with
//! [`CollisionErrorKind::BevyMesh`](crate::ecs::CollisionErrorKind::BevyMesh) for each
//! entity using it, and skipped; the other entities go on.
//!
//! # Schedule
//! [`StochasticCollisionPlugin`](crate::ecs::StochasticCollisionPlugin) runs the
//! constructors in `PreUpdate` ([`MeshColliderSystems`]), every frame whatever the
//! collision schedule, when the app has `Assets<Mesh>` (bevy_asset's `AssetPlugin` and
//! `init_asset::<Mesh>()`, which Bevy's `DefaultPlugins` do). A build that finishes during
//! a frame is inserted in the next frame's `PreUpdate`, so the collision schedule of that
//! frame sees it; an asset already loaded when the constructor appears is built in that
//! `PreUpdate` and inserted, at the earliest, in the next.
//!
//! # Example
//! ```
//! use bevy_app::prelude::*;
//! use bevy_asset::{AssetApp, AssetPlugin, Assets};
//! use bevy_ecs::prelude::*;
//! use bevy_mesh::{Mesh, Mesh3d, Meshable};
//! use stochastic_collision::prelude::*;
//!
//! let mut app = App::new();
//! app.add_plugins((AssetPlugin::default(), StochasticCollisionPlugin::in_schedule(PostUpdate)))
//!     .init_asset::<Mesh>();
//! let ball = app
//!     .world_mut()
//!     .resource_mut::<Assets<Mesh>>()
//!     .add(bevy_shape::Sphere::new(1.0).mesh().ico(2).unwrap());
//! let e = app.world_mut().spawn((Mesh3d(ball), MeshColliderConstructor::Rigid)).id();
//! while app.world().get::<MeshCollider>(e).is_none() {
//!     app.update();
//! }
//! assert!(app.world().get::<MeshColliderConstructor>(e).is_none());
//! ```
mod build_cache;
mod components;
mod constructor;
mod convert;

use bevy_app::prelude::*;
use bevy_asset::Assets;
use bevy_ecs::prelude::*;
use bevy_mesh::Mesh;

pub use build_cache::MeshColliderCache;
pub use components::{MeshColliderConstructor, MeshColliderConstructorHierarchy, MeshNameFilter};
pub use convert::{BevyMeshError, trimesh_from_bevy_mesh};

#[cfg(doc)]
use crate::ecs::{Deformable, MeshCollider};

/// The systems that build colliders from `Mesh3d` entities, in `PreUpdate`.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MeshColliderSystems;

/// Adds the cache, the constructors' types and systems (called by the collision plugin).
pub(crate) fn build(app: &mut App) {
    use constructor::{build_mesh_colliders, forget_changed_meshes, hierarchy_constructors};
    app.init_resource::<MeshColliderCache>()
        .register_type::<MeshColliderConstructor>()
        .register_type::<MeshColliderConstructorHierarchy>()
        .register_type::<MeshNameFilter>()
        .configure_sets(
            PreUpdate,
            MeshColliderSystems.run_if(resource_exists::<Assets<Mesh>>),
        )
        .add_systems(
            PreUpdate,
            (
                forget_changed_meshes,
                hierarchy_constructors
                    .run_if(any_with_component::<MeshColliderConstructorHierarchy>),
                build_mesh_colliders.run_if(any_with_component::<MeshColliderConstructor>),
            )
                .chain()
                .in_set(MeshColliderSystems),
        );
}

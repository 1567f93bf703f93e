//! The constructor components: a collider for an entity's `Mesh3d`, or for every `Mesh3d` of
//! a scene hierarchy, built when the asset is there (the systems that build them:
//! `constructor`).
use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;

use crate::adb::AdbBuildOptions;

/// Builds a collider from the entity's `Mesh3d` once its asset is loaded (at once if it is,
/// later if not), inserts it and removes itself.
///
/// The build runs off the main thread, shared through the [`MeshColliderCache`](super::MeshColliderCache): entities
/// using the same mesh asset and the same constructor share one build (and a rigid
/// collider's tree). Until the collider is inserted, the entity is not a collider. A mesh
/// that cannot be made into a collider is reported as a [`CollisionError`](crate::ecs::CollisionError) with
/// [`CollisionErrorKind::BevyMesh`](crate::ecs::CollisionErrorKind::BevyMesh) for each entity using it, whose constructor is then
/// removed. An entity that has a constructor but no `Mesh3d` waits for one. A collider
/// already on the entity is replaced.
///
/// # Example
/// ```
/// # use bevy_asset::Assets;
/// # use bevy_ecs::prelude::*;
/// # use bevy_mesh::{Mesh, Mesh3d, Meshable};
/// # use stochastic_collision::prelude::*;
/// fn spawn_rock(mut commands: Commands, mut meshes: ResMut<Assets<Mesh>>) {
///     let rock = meshes.add(bevy_shape::Sphere::new(1.0).mesh().ico(2).unwrap());
///     commands.spawn((Mesh3d(rock), MeshColliderConstructor::Rigid));
/// }
/// # bevy_ecs::system::assert_is_system(spawn_rock);
/// ```
#[derive(Component, Reflect, Clone, Debug, Default, PartialEq)]
#[reflect(opaque, Component, Clone, Debug, Default, PartialEq)]
pub enum MeshColliderConstructor {
    /// A [`MeshCollider`](crate::ecs::MeshCollider) with the default ADB-tree options.
    #[default]
    Rigid,
    /// A [`MeshCollider`](crate::ecs::MeshCollider) whose ADB-tree is built with these options.
    RigidWith(AdbBuildOptions),
    /// A [`Deformable`](crate::ecs::Deformable) starting at the mesh's positions.
    Deformable,
}

/// Which entities of a hierarchy a [`MeshColliderConstructorHierarchy`] gives a collider, by
/// the [`Name`](bevy_ecs::name::Name) of the entity or of one of its ancestors below the root (a glTF node's mesh
/// primitives are children of the node's entity, which carries the node's name).
#[derive(Reflect, Clone, Debug, Default, PartialEq)]
#[reflect(Clone, Debug, Default, PartialEq)]
pub enum MeshNameFilter {
    /// Every entity with a `Mesh3d`.
    #[default]
    All,
    /// Only entities with one of these names (on them or an ancestor below the root).
    Only(Vec<String>),
    /// Every entity but those with one of these names (on them or an ancestor below the
    /// root).
    Except(Vec<String>),
}

impl MeshNameFilter {
    /// Whether an entity whose own and ancestors' names are `names` passes.
    pub fn accepts<'a>(&self, mut names: impl Iterator<Item = &'a str>) -> bool {
        match self {
            MeshNameFilter::All => true,
            MeshNameFilter::Only(list) => names.any(|n| list.iter().any(|l| l == n)),
            MeshNameFilter::Except(list) => !names.any(|n| list.iter().any(|l| l == n)),
        }
    }
}

/// Gives every entity with a `Mesh3d` in this entity's hierarchy (itself and its
/// descendants through `ChildOf`, as a glTF scene spawns them) a
/// [`MeshColliderConstructor`], now and whenever one appears later (a scene spawns its
/// children after the asset loads), unless the entity already has a collider or a
/// constructor. Stays on the root. A descendant under another root with this component
/// belongs to the nearest root.
///
/// # Example
/// ```
/// # use bevy_ecs::prelude::*;
/// # use stochastic_collision::prelude::*;
/// # let mut world = World::new();
/// // A level: a rigid collider for every mesh but the ones named "Grass".
/// world.spawn(MeshColliderConstructorHierarchy {
///     filter: MeshNameFilter::Except(vec!["Grass".into()]),
///     ..Default::default()
/// });
/// ```
#[derive(Component, Reflect, Clone, Debug, Default, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct MeshColliderConstructorHierarchy {
    /// The constructor given to each entity.
    pub constructor: MeshColliderConstructor,
    /// Which entities get one.
    pub filter: MeshNameFilter,
}

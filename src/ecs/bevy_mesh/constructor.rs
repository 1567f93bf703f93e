//! The constructor components: a collider for an entity's `Mesh3d`, or for every `Mesh3d` of
//! a scene hierarchy, built when the asset is there.
use bevy_asset::{AssetEvent, Assets};
use bevy_ecs::name::Name;
use bevy_ecs::prelude::*;
use bevy_mesh::{Mesh, Mesh3d};
use bevy_reflect::prelude::*;

use super::build_cache::{Built, Lookup, MeshColliderCache};
use crate::adb::AdbBuildOptions;
use crate::ecs::components::{Deformable, MeshCollider};
use crate::ecs::events::{CollisionError, CollisionErrorKind};

/// Builds a collider from the entity's `Mesh3d` once its asset is loaded (at once if it is,
/// later if not), inserts it and removes itself.
///
/// The build runs off the main thread, shared through the [`MeshColliderCache`]: entities
/// using the same mesh asset and the same constructor share one build (and a rigid
/// collider's tree). Until the collider is inserted, the entity is not a collider. A mesh
/// that cannot be made into a collider is reported as a [`CollisionError`] with
/// [`CollisionErrorKind::BevyMesh`] for each entity using it, whose constructor is then
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
    /// A [`MeshCollider`] with the default ADB-tree options.
    #[default]
    Rigid,
    /// A [`MeshCollider`] whose ADB-tree is built with these options.
    RigidWith(AdbBuildOptions),
    /// A [`Deformable`] starting at the mesh's positions.
    Deformable,
}

/// Which entities of a hierarchy a [`MeshColliderConstructorHierarchy`] gives a collider, by
/// the [`Name`] of the entity or of one of its ancestors below the root (a glTF node's mesh
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

/// Drops the cache entries of modified and removed `Mesh` assets.
pub(crate) fn forget_changed_meshes(
    mut events: MessageReader<AssetEvent<Mesh>>,
    mut cache: ResMut<MeshColliderCache>,
) {
    for event in events.read() {
        if let AssetEvent::Modified { id } | AssetEvent::Removed { id } = event {
            cache.invalidate(*id);
        }
    }
}

/// Entities that could get a constructor from a hierarchy.
type Candidate = (
    With<Mesh3d>,
    Without<MeshCollider>,
    Without<Deformable>,
    Without<MeshColliderConstructor>,
);

/// `Mesh3d` entities that appeared, or moved under another parent, since the last run.
type NewCandidate = (Candidate, Or<(Added<Mesh3d>, Changed<ChildOf>)>);

/// Which constructor a hierarchy gives an entity.
#[derive(bevy_ecs::system::SystemParam)]
pub(crate) struct HierarchyRoots<'w, 's> {
    roots: Query<'w, 's, &'static MeshColliderConstructorHierarchy>,
    candidates: Query<'w, 's, (), Candidate>,
    parents: Query<'w, 's, &'static ChildOf>,
    names: Query<'w, 's, &'static Name>,
}

impl HierarchyRoots<'_, '_> {
    /// The constructor of `entity`'s nearest root (itself or an ancestor), if `entity` is a
    /// candidate and passes the root's filter.
    fn constructor_for(&self, entity: Entity) -> Option<MeshColliderConstructor> {
        if !self.candidates.contains(entity) {
            return None;
        }
        // The names of the entity and of its ancestors below the root.
        let mut names = Vec::new();
        let mut at = entity;
        let root = loop {
            let name = self.names.get(at).ok().map(Name::as_str);
            if let Ok(root) = self.roots.get(at) {
                if at == entity {
                    names.extend(name);
                }
                break root;
            }
            names.extend(name);
            at = self.parents.get(at).ok()?.parent();
        };
        root.filter
            .accepts(names.into_iter())
            .then(|| root.constructor.clone())
    }
}

/// Gives a [`MeshColliderConstructor`] to the `Mesh3d` entities of the hierarchies: all of
/// them under a new (or changed) root, and those that appeared or moved under a root since
/// the last run.
pub(crate) fn hierarchy_constructors(
    mut commands: Commands,
    new_roots: Query<Entity, Changed<MeshColliderConstructorHierarchy>>,
    new_meshes: Query<Entity, NewCandidate>,
    children: Query<&Children>,
    roots: HierarchyRoots,
) {
    let entities = new_roots
        .iter()
        .flat_map(|root| std::iter::once(root).chain(children.iter_descendants(root)))
        .chain(&new_meshes);
    for entity in entities {
        if let Some(constructor) = roots.constructor_for(entity) {
            commands.entity(entity).insert(constructor);
        }
    }
}

/// Inserts the colliders whose build finished (and starts the builds of assets that became
/// available), removing the constructors; reports the meshes that failed.
pub(crate) fn build_mesh_colliders(
    mut commands: Commands,
    mut cache: ResMut<MeshColliderCache>,
    assets: Res<Assets<Mesh>>,
    waiting: Query<(Entity, &Mesh3d, &MeshColliderConstructor)>,
    mut errors: MessageWriter<CollisionError>,
) {
    for (entity, mesh, constructor) in &waiting {
        let Lookup::Ready(result) = cache.lookup(mesh.id(), constructor, &assets) else {
            continue;
        };
        let mut entity_commands = commands.entity(entity);
        entity_commands.remove::<MeshColliderConstructor>();
        match result {
            Ok(Built::Rigid(collider)) => {
                entity_commands
                    .remove::<Deformable>()
                    .insert(collider.clone());
            }
            Ok(Built::Deformable(mesh)) => {
                entity_commands
                    .remove::<MeshCollider>()
                    .insert(Deformable::from_shared_mesh(mesh.clone()));
            }
            Err(e) => {
                errors.write(CollisionError {
                    entity,
                    kind: CollisionErrorKind::BevyMesh(e.clone()),
                });
            }
        }
    }
}

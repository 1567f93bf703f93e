//! The systems behind the constructor components ([`MeshColliderConstructor`],
//! [`MeshColliderConstructorHierarchy`]): constructors handed down a hierarchy, colliders built
//! when the mesh asset is there.
use bevy_asset::{AssetEvent, Assets};
use bevy_ecs::name::Name;
use bevy_ecs::prelude::*;
use bevy_mesh::{Mesh, Mesh3d};

use super::build_cache::{Built, Lookup, MeshColliderCache};
use super::components::{MeshColliderConstructor, MeshColliderConstructorHierarchy};
use crate::ecs::components::{Deformable, MeshCollider};
use crate::ecs::events::{CollisionError, CollisionErrorKind};

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

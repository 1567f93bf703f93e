//! The shared cache of colliders built from `Mesh` assets, keyed by the asset and what is
//! built from it; the builds run on bevy_tasks' `AsyncComputeTaskPool`.
use std::collections::{HashMap, hash_map};
use std::sync::Arc;

use bevy_asset::{AssetId, Assets};
use bevy_ecs::prelude::*;
use bevy_mesh::Mesh;
use bevy_tasks::futures::check_ready;
use bevy_tasks::{AsyncComputeTaskPool, Task, TaskPool};

use super::components::MeshColliderConstructor;
use super::convert::{BevyMeshError, MeshSource};
use crate::bvh::CollisionMesh;
use crate::ecs::components::MeshCollider;

/// What a finished build holds: a rigid collider (cloned, so its tree is shared, by every
/// entity that uses it) or a deformable mesh (shared until an entity first moves its
/// vertices).
#[derive(Clone, Debug)]
pub(crate) enum Built {
    /// A rigid collider.
    Rigid(MeshCollider),
    /// The mesh and BVH of a deformable collider.
    Deformable(Arc<CollisionMesh>),
}

/// What is built from one asset: the second half of a cache key. Build options are keyed by
/// their `Debug` text, which tells every two different options apart (floats print exactly)
/// and keeps equal ones, NaN included, equal.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum BuildKind {
    Rigid,
    RigidWith(String),
    Deformable,
}

impl BuildKind {
    fn of(constructor: &MeshColliderConstructor) -> Self {
        match constructor {
            MeshColliderConstructor::Rigid => Self::Rigid,
            MeshColliderConstructor::RigidWith(options) => Self::RigidWith(format!("{options:?}")),
            MeshColliderConstructor::Deformable => Self::Deformable,
        }
    }
}

type BuildResult = Result<Built, BevyMeshError>;

enum Entry {
    Building(Task<BuildResult>),
    Ready(BuildResult),
}

/// Where an entity's collider stands.
pub(crate) enum Lookup<'a> {
    /// The asset is not loaded yet, or its build has not finished.
    Waiting,
    /// The build finished, with this result.
    Ready(&'a BuildResult),
}

/// Colliders built from `Mesh` assets, shared by every entity that uses the same asset with
/// the same [`MeshColliderConstructor`]: one mesh used by a thousand entities is converted
/// and its tree built once.
///
/// The build (conversion, validation, BVH and ADB-tree) runs on bevy_tasks'
/// `AsyncComputeTaskPool` (initialised with one thread per core if nobody did it before);
/// the frame only copies the mesh's positions and indices out of the asset. A failed build
/// is kept too, so that every entity using the mesh is reported once and the mesh is not
/// converted again. An entry is dropped when its asset is modified (the next entity using
/// it builds anew; colliders already inserted keep the old geometry) or removed, and a build
/// still running for it is cancelled.
#[derive(Resource, Default)]
pub struct MeshColliderCache {
    entries: HashMap<(AssetId<Mesh>, BuildKind), Entry>,
    builds: u64,
}

impl MeshColliderCache {
    /// Builds started since the app began (finished, failed or running), a build per asset
    /// and kind of collider unless the asset changed.
    pub fn builds(&self) -> u64 {
        self.builds
    }

    /// Entries held (finished or running builds).
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no entry is held.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Builds still running.
    pub fn running(&self) -> usize {
        self.entries
            .values()
            .filter(|e| matches!(e, Entry::Building(_)))
            .count()
    }

    /// Whether a finished build of `mesh` is held (any kind of collider).
    pub fn is_ready(&self, mesh: AssetId<Mesh>) -> bool {
        self.entries
            .iter()
            .any(|((id, _), e)| *id == mesh && matches!(e, Entry::Ready(_)))
    }

    /// Drops every entry of `mesh` (running builds are cancelled).
    pub fn invalidate(&mut self, mesh: AssetId<Mesh>) {
        self.entries.retain(|(id, _), _| *id != mesh);
    }

    /// Drops every entry.
    pub fn clear(&mut self) {
        self.entries.clear();
    }

    /// The collider `constructor` makes from `mesh`: starts its build when the asset is
    /// loaded and nobody started it, and collects a finished build.
    pub(crate) fn lookup(
        &mut self,
        mesh: AssetId<Mesh>,
        constructor: &MeshColliderConstructor,
        assets: &Assets<Mesh>,
    ) -> Lookup<'_> {
        let entry = match self.entries.entry((mesh, BuildKind::of(constructor))) {
            hash_map::Entry::Occupied(entry) => entry.into_mut(),
            hash_map::Entry::Vacant(slot) => {
                let Some(asset) = assets.get(mesh) else {
                    return Lookup::Waiting;
                };
                self.builds += 1;
                slot.insert(match MeshSource::read(asset) {
                    Ok(source) => Entry::Building(spawn_build(source, constructor.clone())),
                    Err(e) => Entry::Ready(Err(e)),
                })
            }
        };
        if let Entry::Building(task) = entry
            && let Some(result) = check_ready(task)
        {
            *entry = Entry::Ready(result);
        }
        match entry {
            Entry::Building(_) => Lookup::Waiting,
            Entry::Ready(result) => Lookup::Ready(result),
        }
    }
}

/// Converts and builds on the `AsyncComputeTaskPool`.
fn spawn_build(source: MeshSource, constructor: MeshColliderConstructor) -> Task<BuildResult> {
    AsyncComputeTaskPool::get_or_init(TaskPool::default).spawn(async move {
        let mesh = source.to_trimesh()?;
        Ok(match constructor {
            MeshColliderConstructor::Rigid => Built::Rigid(MeshCollider::new(mesh)),
            MeshColliderConstructor::RigidWith(options) => {
                Built::Rigid(MeshCollider::with_options(mesh, options))
            }
            MeshColliderConstructor::Deformable => {
                Built::Deformable(Arc::new(CollisionMesh::new(mesh)))
            }
        })
    })
}

//! A collider's geometry: a rigid mesh with its shared ADB-tree, or a deformable mesh refitted
//! as it moves.
use std::sync::Arc;

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;
use glam::Vec3;

use crate::adb::{AdbBuildOptions, AdbTree};
use crate::bvh::CollisionMesh;
use crate::mesh::{MeshError, TriMesh};

use super::markers::TouchingEntities;
use super::pose::{ColliderPose, ColliderScale};

/// A rigid collider: one mesh and its ADB-tree, shared (`Arc`) by every entity that uses it.
///
/// Cloning a `MeshCollider` clones the `Arc`, not the mesh: spawn a thousand boulders from one
/// `MeshCollider` and there is one tree in memory. Building the ADB-tree costs more than the BVH
/// (cell counts and a calibration fit), so build each mesh once and clone the collider.
///
/// Inserting a `MeshCollider` also inserts, if missing, a [`ColliderPose`], a [`ColliderScale`]
/// and a [`TouchingEntities`] (required components). A scaled collider is queried with a
/// scaled copy of the tree, built once per mesh and scale and shared by every entity that
/// uses that mesh at that scale.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// let ball = MeshCollider::new(generate::icosphere(0.5, 1));
/// let same_tree = ball.clone();
/// assert!(std::sync::Arc::ptr_eq(ball.tree(), same_tree.tree()));
/// ```
#[derive(Component, Reflect, Clone, Debug)]
#[reflect(opaque, Component, Clone, Debug)]
#[require(ColliderPose, ColliderScale, TouchingEntities)]
pub struct MeshCollider {
    tree: Arc<AdbTree>,
}

impl MeshCollider {
    /// Builds the BVH and the ADB-tree of `mesh` (default options).
    pub fn new(mesh: TriMesh) -> Self {
        Self::from_tree(Arc::new(AdbTree::new(CollisionMesh::new(mesh))))
    }

    /// Builds the ADB-tree with `options` (for example `fit: None` for a quicker build whose
    /// ADB estimates are uncalibrated).
    pub fn with_options(mesh: TriMesh, options: AdbBuildOptions) -> Self {
        Self::from_tree(Arc::new(AdbTree::build_with(
            CollisionMesh::new(mesh),
            options,
        )))
    }

    /// A collider sharing an existing tree.
    pub fn from_tree(tree: Arc<AdbTree>) -> Self {
        Self { tree }
    }

    /// Loads an OBJ file and builds its collider.
    ///
    /// # Errors
    /// As [`TriMesh::from_obj`].
    pub fn from_obj(path: impl AsRef<std::path::Path>) -> Result<Self, MeshError> {
        Ok(Self::new(TriMesh::from_obj(path)?))
    }

    /// The shared ADB-tree.
    #[inline]
    pub fn tree(&self) -> &Arc<AdbTree> {
        &self.tree
    }

    /// The shared mesh and its BVH.
    #[inline]
    pub fn collision_mesh(&self) -> &CollisionMesh {
        self.tree.collision_mesh()
    }
}

/// A deformable mesh: the entity owns its vertex positions (in its local frame) and its BVH,
/// which the Prepare stage refits (never rebuilds) in parallel when the positions changed.
///
/// Move vertices through [`Deformable::positions_mut`]; the refit happens in the next run of
/// the collision schedule. Non-finite positions are reported as a
/// [`CollisionError`](crate::ecs::CollisionError) and the entity is skipped until they are fixed.
/// Deformable meshes have no ADB-tree (its cell counts are not refittable): a pair with a
/// deformable mesh and [`Fidelity::Adb`](crate::ecs::Fidelity::Adb) is tested exactly. A [`ColliderScale`] scales the
/// positions at each refit (positive factors only: a mirrored deformable mesh is reported
/// invalid).
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// let mut cloth = Deformable::new(generate::cloth_grid(1.0, 1.0, 4, 4));
/// for p in cloth.positions_mut() {
///     p.y += 0.1 * p.x;
/// }
/// assert_eq!(cloth.positions().len(), 25);
/// ```
#[derive(Component, Reflect, Clone, Debug)]
#[reflect(opaque, Component, Clone, Debug)]
#[require(ColliderPose, ColliderScale, TouchingEntities)]
pub struct Deformable {
    pub(crate) mesh: Arc<CollisionMesh>,
    pub(crate) positions: Vec<Vec3>,
    pub(crate) stale: bool,
    pub(crate) broken: Option<MeshError>,
    /// The [`ColliderScale`] the mesh was last refitted at (its positions times this).
    pub(crate) scale_applied: Vec3,
    /// Reused buffer of scaled positions.
    pub(crate) scaled: Vec<Vec3>,
}

impl Deformable {
    /// A deformable mesh starting at the mesh's positions.
    pub fn new(mesh: TriMesh) -> Self {
        let positions = mesh.positions().to_vec();
        Self {
            mesh: Arc::new(CollisionMesh::new(mesh)),
            positions,
            stale: false,
            broken: None,
            scale_applied: Vec3::ONE,
            scaled: Vec::new(),
        }
    }

    /// The current vertex positions (local frame), as last written.
    #[inline]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// The vertex positions, to move them; the tree is refitted in the next Prepare stage.
    #[inline]
    pub fn positions_mut(&mut self) -> &mut [Vec3] {
        self.stale = true;
        &mut self.positions
    }

    /// The mesh and tree as of the last refit, scaled by the entity's [`ColliderScale`] (what
    /// the collision stages see).
    #[inline]
    pub fn collision_mesh(&self) -> &CollisionMesh {
        &self.mesh
    }

    /// Why the last positions were rejected (the entity is skipped until they are fixed).
    #[inline]
    pub fn error(&self) -> Option<&MeshError> {
        self.broken.as_ref()
    }
}

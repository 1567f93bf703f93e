//! The components a user puts on an entity: its collision geometry, how precisely it collides,
//! with what, and where it is.
use std::sync::Arc;

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;
use glam::Vec3;

use crate::adb::{AdbBuildOptions, AdbTree};
use crate::bvh::CollisionMesh;
use crate::geometry::Pose;
use crate::mesh::{MeshError, TriMesh};

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
/// [`CollisionError`](super::CollisionError) and the entity is skipped until they are fixed.
/// Deformable meshes have no ADB-tree (its cell counts are not refittable): a pair with a
/// deformable mesh and [`Fidelity::Adb`] is tested exactly. A [`ColliderScale`] scales the
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

/// How precisely an entity's pairs are tested. A pair uses the more accurate fidelity of its
/// two entities (`Exact` > `Tracking` > `Adb` > `Bounds`; two `Adb` take the higher `p_min`).
///
/// An entity without this component uses [`CollisionConfig::default_fidelity`]
/// (rigid colliders) or `Exact` (deformables).
///
/// [`CollisionConfig::default_fidelity`]: super::CollisionConfig::default_fidelity
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Clone, Debug, PartialEq)]
pub enum Fidelity {
    /// The exact BVH query: a certain answer. Not cut by a work budget; under a time budget,
    /// exact pairs are tested first, and those whose turn comes after the deadline get an
    /// answer from their memory ([`Method::Coherence`](super::Method::Coherence)).
    Exact,
    /// The time-critical ADB traversal with this confidence target, cut by the pair's slice
    /// of the frame budget: the answer carries its probability.
    Adb {
        /// Confidence the answer needs (the papers use 0.99; lower: the traversal may stop
        /// sooner, on weaker evidence).
        p_min: f64,
    },
    /// Stochastic closest-feature tracking (contacts with points, normals and depths),
    /// tracking this many feature pairs per frame. Runs in the Tracking stage.
    Tracking {
        /// Feature pairs tracked per frame and pair.
        pairs_per_frame: u32,
    },
    /// World boxes only: the pair collides when the boxes overlap (triggers, far objects).
    Bounds,
}

impl Fidelity {
    /// Rank for "the more accurate wins".
    pub(crate) fn rank(&self) -> u8 {
        match self {
            Fidelity::Bounds => 0,
            Fidelity::Adb { .. } => 1,
            Fidelity::Tracking { .. } => 2,
            Fidelity::Exact => 3,
        }
    }

    /// The fidelity of a pair: the more accurate of the two.
    pub fn combine(self, other: Fidelity) -> Fidelity {
        match (self, other) {
            (Fidelity::Adb { p_min: a }, Fidelity::Adb { p_min: b }) => {
                Fidelity::Adb { p_min: a.max(b) }
            }
            (
                Fidelity::Tracking { pairs_per_frame: a },
                Fidelity::Tracking { pairs_per_frame: b },
            ) => Fidelity::Tracking {
                pairs_per_frame: a.max(b),
            },
            (a, b) if b.rank() > a.rank() => b,
            (a, _) => a,
        }
    }
}

/// Marks a [`Deformable`] whose mesh may collide with itself: the self-collision pass (in the
/// Tracking stage) runs only when some entity has this marker. Ignored on rigid colliders (a
/// rigid mesh's self-intersections never change).
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Clone, Debug, Default)]
pub struct SelfCollision;

/// Continuous collision: a collider with it cannot pass through a thin mesh between two runs
/// unseen.
///
/// - **Rigid pairs tested exactly or with ADB**: in a run where a rigid collider with it
///   moved, its pairs are tested over the whole motion since the last run (from its last
///   pose to this one, translation and rotation). Its broad-phase box covers the motion; a
///   pair whose discrete test finds no contact, or that did not touch before, gets the exact
///   continuous query ([`ccd::time_of_impact`](crate::ccd::time_of_impact)), and a contact it
///   finds carries its time of impact
///   ([`ContactPoint::time_of_impact`](super::ContactPoint::time_of_impact)).
/// - **Tracked pairs and tracked self-collision** ([`Fidelity::Tracking`], rigid or
///   [`Deformable`]): the pair's tracker is continuous
///   ([`TrackerConfig::continuous`](crate::tracking::TrackerConfig::continuous)) in every run,
///   whichever variant: the neighbourhoods of its feature pairs are checked over both
///   colliders' motions in the run and their deformation since the last run, so a fold, a
///   sheet or a thin body passing through between two runs is reported, with its time of
///   impact. Approximate, as the tracking is: a crossing far from every feature pair is not
///   seen.
///
/// A move is swept as a straight motion whatever caused it: remove the component for a
/// teleport. A swept pair that a time budget leaves untested in a run (past the deadline) is
/// not swept in it. Deformable meshes in exact pairs are not swept by the plugin (the core has
/// [`ccd::deforming_time_of_impact`](crate::ccd::deforming_time_of_impact)).
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub enum ContinuousCollision {
    /// Swept whenever it moves.
    Always,
    /// Swept in runs where it moves farther than
    /// [`CollisionConfig::continuous_motion`](super::CollisionConfig::continuous_motion) of its
    /// world box's smallest extent (fast enough to pass through something thin); otherwise
    /// tested at its pose, as other colliders.
    #[default]
    WhenFast,
}

/// The entities this entity currently collides with (sorted), kept up to date by the Report
/// stage. Inserted automatically with [`MeshCollider`] and [`Deformable`]; a mesh's own
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

/// The pose the collision stages use (rotation and translation; the scale is
/// [`ColliderScale`]).
///
/// With the `transform` feature (default), an entity with bevy_transform's `Transform` gets
/// this (and its [`ColliderScale`]) from its `Transform` composed with its ancestors', at the
/// start of every run (see [`CollisionSystems::Prepare`](super::CollisionSystems)): the
/// pose of this very run, without waiting for transform propagation, and for a new entity
/// the pose it was spawned at. An entity with only a `GlobalTransform` gets it from that.
/// Otherwise set it yourself (headless apps, simulations that own their poses).
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct ColliderPose(#[reflect(remote = super::reflect::PoseReflect)] pub Pose);

impl ColliderPose {
    /// A pose at `translation`, not rotated.
    pub fn from_translation(translation: Vec3) -> Self {
        Self(Pose::from_translation(translation))
    }
}

/// The scale of a collider's mesh along its local axes, applied before its
/// [`ColliderPose`] (default 1: the mesh as built). Non-uniform and negative (mirroring)
/// factors are allowed; a factor that is zero, not finite or below `1e-6` in magnitude makes
/// the entity invalid (a [`CollisionError`](super::CollisionError), the entity skipped).
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

/// Marks a collider as a sensor (a trigger volume): its pairs are detected and reported as
/// usual (events, [`TouchingEntities`], contacts through
/// [`CollisionPairs`](super::CollisionPairs) and [`Contact`](super::Contact) messages), but its
/// contacts never reach the [`ContactQueue`](super::ContactQueue): no response pushes
/// anything out of it or away from it. Named so that it does not clash with avian's and
/// bevy_rapier's `Sensor`.
///
/// Contact is contact of surfaces: with [`Fidelity::Exact`] a body wholly inside a closed
/// sensor mesh does not touch it (ADB's interpenetration certificate does count it).
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Clone, Debug, Default)]
pub struct CollisionSensor;

/// Opt in to per-entity observer events ([`CollisionStarted`](super::CollisionStarted) and
/// [`CollisionEnded`](super::CollisionEnded) triggered on this entity, observed with
/// `On<CollisionStarted>`). The marker is read when events are emitted, so adding it to an
/// entity that already exists works.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Clone, Debug, Default)]
pub struct ObserveCollisions;

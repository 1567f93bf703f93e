//! # stochastic_collision
//!
//! Time-critical, approximate collision detection for triangle meshes, rigid and deformable,
//! for Bevy games and simulations.
//!
//! This crate trades accuracy for time, on purpose and measurably. Its foundation is an
//! **exact** baseline: validated triangle meshes ([`mesh::TriMesh`]), robust primitives
//! ([`geometry`]), and a bounding-volume hierarchy ([`bvh::CollisionMesh`]) that answers "do
//! these two meshes touch?", "which triangle pairs intersect?", "how far apart are they?" and
//! "does this mesh intersect itself?". On top of it, ADB-trees ([`adb`]) answer "do they
//! collide?" with a confidence, inside a node-pair or time budget, and stochastic
//! closest-feature tracking ([`tracking`]) follows the contacts of deforming, self-colliding
//! meshes in a small time per frame.
//!
//! ```
//! use stochastic_collision::prelude::*;
//!
//! // Two unit spheres, 1.5 apart: they overlap.
//! let ball = CollisionMesh::new(generate::icosphere(1.0, 2));
//! let mut ws = QueryWorkspace::new();
//! let near = Pose::from_translation(Vec3::X * 1.5);
//! let far = Pose::from_translation(Vec3::X * 2.5);
//! assert!(intersects(&ball, &Pose::IDENTITY, &ball, &near, &mut ws));
//! assert!(!intersects(&ball, &Pose::IDENTITY, &ball, &far, &mut ws));
//! let gap = closest_points(&ball, &Pose::IDENTITY, &ball, &far, f32::INFINITY, &mut ws).unwrap();
//! assert!((gap.distance - 0.5).abs() < 0.05);
//!
//! // Time-critical: an ADB-tree (built once per mesh), a budget (here 200 node pairs, which is
//! // deterministic; `Budget::Time` bounds the wall-clock time instead), a confidence.
//! let tree = AdbTree::new(ball.clone());
//! let mut adb_ws = AdbWorkspace::new();
//! let query = AdbQuery::with_budget(Budget::NodePairs(200));
//! let out = adb_intersects(&tree, &Pose::IDENTITY, &tree, &near, &query, &mut adb_ws);
//! assert!(out.collides && out.probability > 0.5);
//! ```
//!
//! Layers: `mesh` and `geometry` at the bottom, `bvh` on top of them, `adb`, `tracking` and
//! `ccd` (continuous collision: the first time of impact within a step) on top of `bvh`; `poses` and `deform` generate benchmark scenarios. None of them imports Bevy: the engine integration is
//! [`ecs`] alone ([`ecs::StochasticCollisionPlugin`], collision events, budgets, responses).
#![warn(missing_docs)]

pub mod adb;
pub mod bvh;
pub mod ccd;
pub mod deform;
pub mod ecs;
pub mod geometry;
pub mod mesh;
pub mod poses;
pub mod tracking;

/// The types most programs need, in one import.
pub mod prelude {
    pub use crate::adb::{AdbOutcome, AdbQuery, AdbTree, AdbWorkspace, Budget, adb_intersects};
    pub use crate::bvh::{
        Bvh, CollisionMesh, ExactOptions, ExactOutcome, MeshDistance, QueryWorkspace, TrianglePair,
        closest_points, intersecting_pairs, intersects, intersects_with, self_intersections,
    };
    #[cfg(feature = "bevy_mesh")]
    pub use crate::ecs::{
        BevyMeshError, MeshColliderConstructor, MeshColliderConstructorHierarchy, MeshNameFilter,
    };
    pub use crate::ecs::{
        BodyMass, BodyVelocity, ColliderPose, ColliderScale, CollisionConfig, CollisionDiagnostics,
        CollisionEnded, CollisionError, CollisionPairs, CollisionSensor, CollisionStarted,
        CollisionSystems, Contact, ContactLayer, ContactLayers, ContactQueue, Deformable, Fidelity,
        FrameBudget, ImpulseResponsePlugin, MeshCollider, Method, ObserveCollisions, PairFilter,
        PairFilterPlugin, PenaltyResponsePlugin, RefilterPairs, SelfCollision,
        StochasticCollisionPlugin, StochasticCollisionPlugins, TouchingEntities,
    };
    #[cfg(feature = "debug_render")]
    pub use crate::ecs::{CollisionDebugPlugin, CollisionGizmos};
    pub use crate::geometry::{Aabb, Pose};
    pub use crate::mesh::{MeshError, Topology, TriMesh, generate};
    pub use glam::{Quat, Vec3};
}

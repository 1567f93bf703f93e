//! # stochastic_collision
//!
//! Collision detection between triangle meshes, rigid or deforming, for Bevy games and
//! simulations that must keep to a frame budget. An exact baseline answers "do these meshes
//! touch, where, how far apart?"; on top of it ADB-trees answer "do they collide?" inside a
//! budget with a confidence, and stochastic closest-feature tracking follows the contacts of
//! deforming and self-colliding surfaces. The plugin says of every collision how it was found
//! and how sure it is. Use it as a Bevy plugin ([`ecs::StochasticCollisionPlugin`]) or call
//! the queries directly, without Bevy.
//!
//! ## Quick start: the plugin
//!
//! Add the plugin, give entities a [`MeshCollider`](ecs::MeshCollider) and a `Transform`,
//! and read [`CollisionStarted`](ecs::CollisionStarted) messages after
//! [`CollisionSystems::Report`](ecs::CollisionSystems::Report). A game's `DefaultPlugins`
//! bring `TimePlugin` and `TransformPlugin`; this headless app names them and steps
//! `Time<Fixed>` once per update.
//!
//! ```
//! # #[cfg(feature = "transform")] {
//! use bevy_app::prelude::*;
//! use bevy_ecs::prelude::*;
//! use bevy_time::{TimePlugin, TimeUpdateStrategy};
//! use bevy_transform::{TransformPlugin, components::Transform};
//! use stochastic_collision::prelude::*;
//!
//! #[derive(Resource, Default)]
//! struct Hits(u32);
//!
//! fn on_hit(mut started: MessageReader<CollisionStarted>, mut hits: ResMut<Hits>) {
//!     for e in started.read() {
//!         // How the answer was found (Exact, Adb, Tracking, ...) and how sure it is.
//!         println!("{} hit {}: {:?}, p = {:.2}", e.entity, e.other, e.method, e.probability);
//!         hits.0 += 1;
//!     }
//! }
//!
//! let mut app = App::new();
//! app.add_plugins((TimePlugin, TransformPlugin))
//!     .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
//!     // Runs in FixedPostUpdate; poses and scales come from each entity's Transform.
//!     .add_plugins(StochasticCollisionPlugin::default())
//!     .init_resource::<Hits>()
//!     .add_systems(FixedPostUpdate, on_hit.after(CollisionSystems::Report));
//!
//! // One mesh and its ADB-tree, built once and shared by every clone.
//! let ball = MeshCollider::new(generate::icosphere(0.5, 2));
//! app.world_mut().spawn((ball.clone(), Transform::from_xyz(0.0, 0.0, 0.0)));
//! app.world_mut().spawn((
//!     ball,
//!     Transform::from_xyz(0.8, 0.0, 0.0),
//!     Fidelity::Exact, // or Adb { p_min } (the default), Tracking { .. }, Bounds
//! ));
//! // The first update starts the clocks; each later one runs one fixed step.
//! for _ in 0..3 {
//!     app.update();
//! }
//! assert_eq!(app.world().resource::<Hits>().0, 1); // started once, then kept touching
//! # }
//! ```
//!
//! Responses are optional plugins ([`ecs::ImpulseResponsePlugin`],
//! [`ecs::PenaltyResponsePlugin`], or your own systems in
//! [`CollisionSystems::Response`](ecs::CollisionSystems::Response)); [`ecs`] describes the
//! pipeline, its budget and its messages.
//!
//! ## Quick start: the queries, without Bevy
//!
//! ```
//! use stochastic_collision::prelude::*;
//!
//! // Exact: two unit spheres 1.5 apart overlap; 2.5 apart they are 0.5 apart.
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
//! ## Feature flags
//!
//! | Feature | Default | What it adds |
//! |---|---|---|
//! | `transform` | yes | Poses and scales read from bevy_transform's `Transform` (else only [`ColliderPose`](ecs::ColliderPose) and [`ColliderScale`](ecs::ColliderScale)). |
//! | `bevy_mesh` | yes | Colliders from bevy_mesh's `Mesh` assets, `Mesh3d` entities and scene hierarchies such as glTF scenes, built off the main thread. Turns on `transform`. |
//! | `diagnostic` | no | The stage timings in bevy_diagnostic's `DiagnosticsStore` (`ecs::diagnostics_store`). |
//! | `debug_render` | no | `CollisionDebugPlugin`: world boxes, contacts, normals and feature pairs drawn with bevy_gizmos. |
//!
//! ## Modules
//!
//! Each module's docs end with the one to read next, in this order:
//!
//! - [`mesh`]: validated triangle meshes, adjacency, OBJ loading and generators.
//! - [`geometry`]: boxes, poses, the exact triangle–triangle test, closest points.
//! - [`bvh`]: the bounding-volume hierarchy and the exact queries (intersection, intersecting
//!   pairs, distance, self-intersection).
//! - [`adb`]: ADB-trees and the time-critical query with a budget and a confidence.
//! - [`tracking`]: stochastic closest-feature tracking of deforming and self-colliding meshes.
//! - [`ccd`]: continuous collision, the first time of impact within a step.
//! - [`ecs`]: the Bevy plugin: components, pipeline, budgets, messages, responses.
//! - [`poses`] and [`deform`]: near-contact poses and deformations for benchmarks and tests.
//! - [`prelude`]: the types most programs need, in one import.
//!
//! Only [`ecs`] depends on Bevy; the other modules work on glam's vectors without it.
#![warn(missing_docs)]

pub mod adb;
pub mod bvh;
pub mod ccd;
pub mod deform;
pub mod ecs;
pub mod geometry;
pub mod mesh;
pub mod poses;
mod prefetch;
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
        BodyAngularVelocity, BodyInertia, BodyMass, BodyVelocity, ColliderPose, ColliderScale,
        CollisionConfig, CollisionDiagnostics, CollisionEnded, CollisionError, CollisionPairs,
        CollisionSensor, CollisionStarted, CollisionSystems, Contact, ContactLayer, ContactLayers,
        ContactQueue, ContinuousCollision, Deformable, Fidelity, FrameBudget,
        ImpulseResponsePlugin, MeshCollider, Method, ObserveCollisions, PairFilter,
        PairFilterPlugin, PenaltyResponsePlugin, RefilterPairs, ResponseBudget, SelfCollision,
        StochasticCollisionPlugin, StochasticCollisionPlugins, TouchingEntities,
    };
    #[cfg(feature = "debug_render")]
    pub use crate::ecs::{CollisionDebugPlugin, CollisionGizmos};
    pub use crate::geometry::{Aabb, Pose};
    pub use crate::mesh::{MeshError, Topology, TriMesh, generate};
    pub use glam::{Quat, Vec3};
}

//! # stochastic_collision
//!
//! Time-critical, approximate collision detection for triangle meshes, rigid and deformable,
//! for Bevy games and simulations.
//!
//! This crate trades accuracy for time, on purpose and measurably. Its foundation, documented
//! here, is an **exact** baseline: validated triangle meshes ([`mesh::TriMesh`]), robust
//! primitives ([`geometry`]), and a bounding-volume hierarchy ([`bvh::CollisionMesh`]) that answers
//! "do these two meshes touch?", "which triangle pairs intersect?", "how far apart are they?"
//! and "does this mesh intersect itself?".
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
//! ```
//!
//! Layers: `mesh` and `geometry` at the bottom, `bvh` on top of them. None of them imports
//! Bevy; the engine integration lives in its own layer.
#![warn(missing_docs)]

pub mod adb;
pub mod bvh;
pub mod geometry;
pub mod mesh;
pub mod poses;

/// The types most programs need, in one import.
pub mod prelude {
    pub use crate::bvh::{
        Bvh, CollisionMesh, ExactOptions, ExactOutcome, MeshDistance, QueryWorkspace, TrianglePair,
        closest_points, intersecting_pairs, intersects, intersects_with, self_intersections,
    };
    pub use crate::geometry::{Aabb, Pose};
    pub use crate::mesh::{MeshError, Topology, TriMesh, generate};
    pub use glam::{Quat, Vec3};
}

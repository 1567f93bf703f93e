//! Bounding-volume hierarchy and the exact mesh–mesh queries built on it.
//!
//! - [`Bvh`]: a binary AABB tree in one flat node array (binned-SAH build, `O(n)` refit).
//! - [`CollisionMesh`]: a [`TriMesh`](crate::mesh::TriMesh) with its [`Bvh`], kept consistent
//!   (deform it with [`CollisionMesh::set_positions`], which refits, never rebuilds).
//! - Exact queries between two meshes at [`Pose`](crate::geometry::Pose)s:
//!   [`intersects`] (first hit, early exit), [`intersects_with`] (with options and a witness),
//!   [`intersecting_pairs`] (all intersecting triangle pairs), [`closest_points`] (distance and
//!   closest points), and [`self_intersections`] of one mesh.
//! - A point against one mesh: [`contains_point`] (inside a closed mesh) and
//!   [`closest_surface_point`].
//! - [`QueryWorkspace`]: the reusable scratch memory that keeps queries allocation-free.
//!
//! All queries descend both trees simultaneously; boxes are culled in `f32` with a
//! conservative margin, and every triangle pair that survives is decided by the exact `f64`
//! test of [`crate::geometry::triangles_intersect`]. Surfaces are what collide (as in parry):
//! a mesh entirely inside another does not touch its surface. For closed meshes,
//! [`ExactOptions::solid`] adds the containment check.
//!
//! Next: [`crate::adb`] builds on these trees for queries with a budget and a confidence;
//! [`crate::tracking`] and [`crate::ccd`] use them for deforming and moving meshes.

pub(crate) mod box_test;
mod build;
mod collision_mesh;
mod distance;
mod node_slabs;
mod refit;
mod solid;
mod surface_point;
pub(crate) mod traverse_pair;
mod traverse_self;
mod tree;
mod workspace;

pub use build::BvhBuildOptions;
pub use collision_mesh::CollisionMesh;
pub(crate) use collision_mesh::component_labels;
pub use distance::{MeshDistance, closest_points};
pub use node_slabs::NodeSlab;
pub use solid::contains_point;
pub use surface_point::{SurfacePoint, closest_surface_point};
pub use traverse_pair::{
    ExactOptions, ExactOutcome, intersecting_pairs, intersects, intersects_with,
    root_boxes_overlap, triangle_pair_intersects,
};
pub(crate) use traverse_self::within_thickness;
pub use traverse_self::{
    SelfContact, self_contacts, self_contacts_excluding, self_intersections, self_intersects,
};
pub use tree::{Bvh, BvhNode};
pub use workspace::{QueryWorkspace, TrianglePair};

//! Geometric primitives: boxes, poses, the exact triangle–triangle test and closest points.
//!
//! Storage is `f32` (glam, as Bevy holds it); every computation whose *sign* decides an answer
//! runs in `f64` with exact adaptive predicates ([`robust`]), so results stay right on touching,
//! coplanar and degenerate input, at any scale and far from the origin.
//!
//! - [`Aabb`]: an axis-aligned box; [`Pose`]: a rigid transform (rotation, then translation),
//!   one per mesh in every query.
//! - [`triangles_intersect`]: the exact test of two closed triangles (touching counts), which
//!   decides every triangle pair of the exact queries.
//! - [`closest_points_triangle_triangle`], [`closest_points_segment_segment`] and
//!   [`closest_point_on_triangle`]: distances and closest points.
//! - [`barycentric_weights`] and [`spread_to_corners`]: a correction at a point of a triangle
//!   spread to its corners (the deformable penalty response).
//! - [`predicates`]: the exact orientation predicates underneath.
//!
//! Next: [`crate::bvh`] runs these tests over whole meshes.

mod aabb;
mod barycentric;
mod closest_points;
mod pose;
pub mod predicates;
mod tri_tri;

pub use aabb::Aabb;
pub use barycentric::{barycentric_weights, spread_to_corners};
pub use closest_points::{
    ClosestPoints, closest_point_on_triangle, closest_points_segment_segment,
    closest_points_triangle_triangle,
};
pub use pose::{Pose, PoseF64};
pub use tri_tri::{triangles_intersect, triangles_intersect_f32};

//! Triangle meshes: validated storage ([`TriMesh`]), adjacency ([`Topology`]), mass properties
//! ([`MassProperties`]), OBJ loading and
//! generators for tests and examples ([`generate`]).
//!
//! Degenerate (zero-area) triangles, duplicate and unreferenced vertices, open boundaries and
//! non-manifold edges are all *valid* input: every query in this crate stays correct on them.
//! Only what cannot be a mesh is refused ([`MeshError`]): no triangles, an index out of range,
//! a coordinate that is NaN or infinite, an unreadable or malformed file.
//!
//! Next: [`crate::geometry`], the exact primitives the queries decide with; or
//! [`crate::bvh`], which wraps a mesh in the tree every query descends.

mod combine;
mod error;
pub mod generate;
mod local_exclusion;
mod mass;
mod obj;
mod rings;
mod topology;
mod tri_mesh;
mod weld;

pub use error::MeshError;
pub(crate) use local_exclusion::LocalExclusion;
pub use mass::{MassModel, MassProperties};
pub(crate) use rings::{RingWalk, VertexList};
pub use rings::{SelfExclusion, adjacent, triangles_within_rings};
pub use topology::{Edge, Topology};
pub use tri_mesh::TriMesh;
pub use weld::coincident_representatives;
#[cfg(test)]
pub(crate) use weld::triangle_soup;

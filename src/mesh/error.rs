use std::path::{Path, PathBuf};

/// Why a mesh could not be built or loaded. Every variant names what is wrong and where.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum MeshError {
    /// The mesh has no triangles (or no vertices).
    #[error(
        "empty mesh: {vertices} vertices and {triangles} triangles; at least one triangle is needed"
    )]
    Empty {
        /// Number of vertices given.
        vertices: usize,
        /// Number of triangles given.
        triangles: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error(
        "triangle {triangle} refers to vertex {index}, but the mesh has only {vertices} vertices"
    )]
    IndexOutOfRange {
        /// Index of the offending triangle.
        triangle: usize,
        /// The out-of-range vertex index.
        index: u32,
        /// Number of vertices in the mesh.
        vertices: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate ({value:?})")]
    NonFinite {
        /// Index of the offending vertex.
        vertex: usize,
        /// The offending position.
        value: [f32; 3],
    },
    /// The mesh has more vertices than a `u32` index can address.
    #[error("mesh has {vertices} vertices; at most u32::MAX can be indexed")]
    TooManyVertices {
        /// Number of vertices given.
        vertices: usize,
    },
    /// New positions for [`TriMesh::set_positions`](crate::mesh::TriMesh::set_positions) do not match the vertex count.
    #[error("expected {expected} positions (the mesh's vertex count), got {got}")]
    PositionCount {
        /// The mesh's vertex count.
        expected: usize,
        /// The number of positions given.
        got: usize,
    },
    /// A scale factor is zero, not finite, or below `1e-6` in magnitude (the mesh would
    /// collapse).
    #[error("invalid scale {scale:?}: every factor must be finite and at least 1e-6 in magnitude")]
    InvalidScale {
        /// The scale given.
        scale: [f32; 3],
    },
    /// A per-mesh structure (such as a [`SelfExclusion`](crate::mesh::SelfExclusion)) was
    /// built for another mesh.
    #[error(
        "built for a mesh of {} vertices and {} triangles, used with one of {} vertices and {} triangles",
        expected.0, expected.1, got.0, got.1
    )]
    TopologyMismatch {
        /// Vertex and triangle counts of the mesh it was built for.
        expected: (usize, usize),
        /// Vertex and triangle counts of the mesh it was used with.
        got: (usize, usize),
    },
    /// The file could not be read.
    #[error("cannot read {path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        message: String,
    },
    /// The file was read but is not a valid OBJ mesh.
    #[error("{}: {message}", located(path, *line))]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line number (0 when the problem is not tied to one line).
        line: usize,
        /// What is wrong.
        message: String,
    },
}

/// `file:line`, or just `file` when the problem is not tied to one line (line 0).
fn located(path: &Path, line: usize) -> String {
    if line == 0 {
        path.display().to_string()
    } else {
        format!("{}:{line}", path.display())
    }
}

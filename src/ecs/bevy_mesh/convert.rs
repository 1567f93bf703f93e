//! From a bevy_mesh [`Mesh`] to the crate's [`TriMesh`], and the colliders built on it.
use std::sync::Arc;

use bevy_mesh::{Indices, Mesh, MeshAccessError, PrimitiveTopology, VertexAttributeValues};
use glam::Vec3;

use crate::adb::AdbBuildOptions;
use crate::bvh::CollisionMesh;
use crate::ecs::components::{Deformable, MeshCollider};
use crate::mesh::{MeshError, TriMesh};

/// Why a bevy_mesh [`Mesh`] could not be made into a collider. Every variant names what is
/// wrong and where.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BevyMeshError {
    /// The mesh draws points or lines, which enclose no surface.
    #[error(
        "primitive topology {0:?} has no triangles: only TriangleList and TriangleStrip meshes make colliders"
    )]
    UnsupportedTopology(PrimitiveTopology),
    /// The mesh has no `Mesh::ATTRIBUTE_POSITION`.
    #[error("the mesh has no vertex positions (Mesh::ATTRIBUTE_POSITION)")]
    MissingPositions,
    /// The positions are stored in another format than three `f32`s.
    #[error("vertex positions are {format:?}, not Float32x3")]
    PositionFormat {
        /// The format of the position attribute.
        format: bevy_mesh::VertexFormat,
    },
    /// The mesh's data lives only in the render world (its `asset_usage` lacks
    /// `MAIN_WORLD`), so the main world cannot read it.
    #[error(
        "the mesh's vertex data was extracted to the render world (its asset_usage must include MAIN_WORLD)"
    )]
    ExtractedToRenderWorld,
    /// An index refers to a vertex that does not exist.
    #[error(
        "index {position} of the index buffer is {index}, but the mesh has {vertices} vertices"
    )]
    IndexOutOfRange {
        /// Position of the index in the index buffer.
        position: usize,
        /// The index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A triangle list whose index count (or, without indices, vertex count) is not a
    /// multiple of 3.
    #[error("a triangle list of {count} {} is not a whole number of triangles", if *.indexed { "indices" } else { "vertices" })]
    PartialTriangle {
        /// The number of indices, or of vertices without indices.
        count: usize,
        /// Whether `count` counts indices.
        indexed: bool,
    },
    /// The triangles were read but the crate's mesh validation rejected them (no triangle,
    /// a non-finite position, too many vertices).
    #[error("invalid mesh: {0}")]
    Mesh(#[from] MeshError),
}

impl From<MeshAccessError> for BevyMeshError {
    fn from(e: MeshAccessError) -> Self {
        match e {
            MeshAccessError::ExtractedToRenderWorld => Self::ExtractedToRenderWorld,
            MeshAccessError::NotFound => Self::MissingPositions,
        }
    }
}

/// What a conversion reads from a [`Mesh`]: its topology, positions and indices (copied out
/// of the asset so that the conversion can run on another thread).
#[derive(Debug, Clone)]
pub(crate) struct MeshSource {
    topology: PrimitiveTopology,
    positions: VertexAttributeValues,
    indices: Option<Indices>,
}

impl MeshSource {
    /// Copies what the conversion needs; the topology and the positions are checked here.
    pub(crate) fn read(mesh: &Mesh) -> Result<Self, BevyMeshError> {
        let topology = mesh.primitive_topology();
        if !matches!(
            topology,
            PrimitiveTopology::TriangleList | PrimitiveTopology::TriangleStrip
        ) {
            return Err(BevyMeshError::UnsupportedTopology(topology));
        }
        let positions = mesh.try_attribute(Mesh::ATTRIBUTE_POSITION)?;
        if !matches!(positions, VertexAttributeValues::Float32x3(_)) {
            return Err(BevyMeshError::PositionFormat {
                format: positions.into(),
            });
        }
        Ok(Self {
            topology,
            positions: positions.clone(),
            indices: mesh.try_indices_option()?.cloned(),
        })
    }

    /// The triangles, validated.
    pub(crate) fn to_trimesh(&self) -> Result<TriMesh, BevyMeshError> {
        let VertexAttributeValues::Float32x3(raw) = &self.positions else {
            return Err(BevyMeshError::PositionFormat {
                format: (&self.positions).into(),
            });
        };
        let positions: Vec<Vec3> = raw.iter().map(|&p| Vec3::from_array(p)).collect();
        let vertices = positions.len();
        let indices: Vec<u32> = match &self.indices {
            Some(Indices::U16(i)) => i.iter().map(|&i| u32::from(i)).collect(),
            Some(Indices::U32(i)) => i.clone(),
            None => (0..vertices as u32).collect(),
        };
        let indexed = self.indices.is_some();
        let restart = match &self.indices {
            Some(Indices::U16(_)) => Some(u32::from(u16::MAX)),
            Some(Indices::U32(_)) => Some(u32::MAX),
            None => None,
        };
        let strip = self.topology == PrimitiveTopology::TriangleStrip;
        for (position, &index) in indices.iter().enumerate() {
            let is_restart = strip && Some(index) == restart;
            if index as usize >= vertices && !is_restart {
                return Err(BevyMeshError::IndexOutOfRange {
                    position,
                    index,
                    vertices,
                });
            }
        }
        let triangles = if strip {
            strip_triangles(&indices, restart)
        } else {
            list_triangles(&indices, indexed)?
        };
        Ok(TriMesh::new(positions, triangles)?)
    }
}

/// A triangle list: consecutive triples.
fn list_triangles(indices: &[u32], indexed: bool) -> Result<Vec<[u32; 3]>, BevyMeshError> {
    if !indices.len().is_multiple_of(3) {
        return Err(BevyMeshError::PartialTriangle {
            count: indices.len(),
            indexed,
        });
    }
    Ok(indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect())
}

/// A triangle strip, as GPUs draw it: triangle `i` of a strip is `(v[i], v[i+1], v[i+2])`,
/// with the last two swapped for odd `i` so that every triangle faces the same way; triangles
/// with a repeated index (the degenerate triangles that join strips) are dropped; the
/// primitive-restart index (`u16::MAX` or `u32::MAX`, as WebGPU reads indexed strips) starts
/// a new strip, whose winding starts over.
fn strip_triangles(indices: &[u32], restart: Option<u32>) -> Vec<[u32; 3]> {
    let mut triangles = Vec::with_capacity(indices.len().saturating_sub(2));
    for strip in indices.split(|&i| Some(i) == restart) {
        for (i, w) in strip.windows(3).enumerate() {
            let [a, b, c] = [w[0], w[1], w[2]];
            if a == b || b == c || a == c {
                continue;
            }
            triangles.push(if i % 2 == 0 { [a, b, c] } else { [a, c, b] });
        }
    }
    triangles
}

/// The triangles of a bevy_mesh [`Mesh`]: triangle lists and strips, indexed (`u16` or
/// `u32`) or not. Vertices are kept as they are (unreferenced ones included), so vertex `i`
/// of the result is vertex `i` of the mesh.
///
/// # Errors
/// [`BevyMeshError`]: points or lines, no positions or positions not in `Float32x3`, data
/// only in the render world, an index out of range, a list that is not a whole number of
/// triangles, or a mesh that [`TriMesh::new`] rejects (wrapped in [`BevyMeshError::Mesh`]).
pub fn trimesh_from_bevy_mesh(mesh: &Mesh) -> Result<TriMesh, BevyMeshError> {
    MeshSource::read(mesh)?.to_trimesh()
}

impl MeshCollider {
    /// A rigid collider of a bevy_mesh [`Mesh`]'s triangles (see [`trimesh_from_bevy_mesh`]),
    /// with the default ADB-tree options. The tree is built on the calling thread: to build
    /// off the main thread when a `Mesh3d` asset loads, use
    /// [`MeshColliderConstructor`](super::MeshColliderConstructor).
    ///
    /// # Example
    /// ```
    /// use bevy_mesh::{Indices, Mesh, PrimitiveTopology};
    /// use bevy_asset::RenderAssetUsages;
    /// use stochastic_collision::prelude::*;
    ///
    /// let quad = Mesh::new(PrimitiveTopology::TriangleList, RenderAssetUsages::default())
    ///     .with_inserted_attribute(
    ///         Mesh::ATTRIBUTE_POSITION,
    ///         vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
    ///     )
    ///     .with_inserted_indices(Indices::U16(vec![0, 1, 2, 0, 2, 3]));
    /// let collider = MeshCollider::from_bevy_mesh(&quad)?;
    /// assert_eq!(collider.collision_mesh().mesh().triangle_count(), 2);
    ///
    /// let lines = Mesh::new(PrimitiveTopology::LineList, RenderAssetUsages::default());
    /// assert!(matches!(
    ///     MeshCollider::from_bevy_mesh(&lines),
    ///     Err(BevyMeshError::UnsupportedTopology(PrimitiveTopology::LineList))
    /// ));
    /// # Ok::<(), BevyMeshError>(())
    /// ```
    ///
    /// # Errors
    /// As [`trimesh_from_bevy_mesh`].
    pub fn from_bevy_mesh(mesh: &Mesh) -> Result<Self, BevyMeshError> {
        Ok(Self::new(trimesh_from_bevy_mesh(mesh)?))
    }

    /// As [`MeshCollider::from_bevy_mesh`], the ADB-tree built with `options`.
    ///
    /// # Errors
    /// As [`trimesh_from_bevy_mesh`].
    pub fn from_bevy_mesh_with(
        mesh: &Mesh,
        options: AdbBuildOptions,
    ) -> Result<Self, BevyMeshError> {
        Ok(Self::with_options(trimesh_from_bevy_mesh(mesh)?, options))
    }
}

impl Deformable {
    /// A deformable collider starting at a bevy_mesh [`Mesh`]'s positions (see
    /// [`trimesh_from_bevy_mesh`]; vertex `i` of [`Deformable::positions`] is vertex `i` of
    /// the mesh).
    ///
    /// # Errors
    /// As [`trimesh_from_bevy_mesh`].
    pub fn from_bevy_mesh(mesh: &Mesh) -> Result<Self, BevyMeshError> {
        Ok(Self::new(trimesh_from_bevy_mesh(mesh)?))
    }

    /// A deformable collider sharing `mesh` until its positions first change (then the
    /// entity gets its own copy).
    pub(crate) fn from_shared_mesh(mesh: Arc<CollisionMesh>) -> Self {
        let positions = mesh.mesh().positions().to_vec();
        Self {
            mesh,
            positions,
            stale: false,
            broken: None,
            scale_applied: Vec3::ONE,
            scaled: Vec::new(),
        }
    }
}

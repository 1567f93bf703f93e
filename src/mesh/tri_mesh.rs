use glam::Vec3;

use super::MeshError;
use crate::geometry::Aabb;

/// An indexed triangle mesh: vertex positions and triangles as triples of vertex indices.
///
/// Built only through [`TriMesh::new`] (or [`TriMesh::from_obj`]), which validates it, so every
/// `TriMesh` has at least one triangle, every index in range and every coordinate finite.
/// Degenerate triangles, duplicate or unreferenced vertices, holes and non-manifold edges are
/// kept as they are: they are valid input.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::TriMesh;
/// use glam::Vec3;
/// let mesh = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]])?;
/// assert_eq!(mesh.triangle_count(), 1);
/// assert!(TriMesh::new(vec![Vec3::ZERO], vec![[0, 1, 2]]).is_err());
/// # Ok::<(), stochastic_collision::mesh::MeshError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct TriMesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Validates and builds a mesh.
    ///
    /// # Errors
    /// [`MeshError::Empty`] without triangles, [`MeshError::IndexOutOfRange`] for a bad index,
    /// [`MeshError::NonFinite`] for a NaN or infinite coordinate,
    /// [`MeshError::TooManyVertices`] past `u32::MAX` vertices.
    pub fn new(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if triangles.is_empty() || positions.is_empty() {
            return Err(MeshError::Empty {
                vertices: positions.len(),
                triangles: triangles.len(),
            });
        }
        if positions.len() > u32::MAX as usize {
            return Err(MeshError::TooManyVertices {
                vertices: positions.len(),
            });
        }
        check_finite(&positions)?;
        let n = positions.len();
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    triangle: t,
                    index,
                    vertices: n,
                });
            }
        }
        Ok(Self {
            positions,
            triangles,
        })
    }

    /// Vertex positions.
    #[inline]
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Triangles, as vertex indices.
    #[inline]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Number of vertices (including unreferenced ones).
    #[inline]
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles.
    #[inline]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corners of triangle `t`.
    ///
    /// # Panics
    /// If `t >= self.triangle_count()`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Axis-aligned bounds of the referenced vertices (unreferenced ones do not count).
    pub fn aabb(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        for tri in &self.triangles {
            for &i in tri {
                b.grow(self.positions[i as usize]);
            }
        }
        b
    }

    /// Replaces all vertex positions (a deformation: same topology), after validating them.
    /// Bounding-volume hierarchies built on this mesh must then be refitted, never rebuilt:
    /// [`CollisionMesh::set_positions`](crate::bvh::CollisionMesh::set_positions) does both.
    ///
    /// # Errors
    /// [`MeshError::PositionCount`] if the count differs, [`MeshError::NonFinite`] for a NaN or
    /// infinite coordinate; the mesh is unchanged on error.
    pub fn set_positions(&mut self, positions: &[Vec3]) -> Result<(), MeshError> {
        if positions.len() != self.positions.len() {
            return Err(MeshError::PositionCount {
                expected: self.positions.len(),
                got: positions.len(),
            });
        }
        check_finite(positions)?;
        self.positions.copy_from_slice(positions);
        Ok(())
    }

    /// Whether the mesh is closed: every edge (by vertex index) is shared by exactly two
    /// triangles. Only closed meshes have a well-defined inside (see
    /// [`crate::bvh::ExactOptions::solid`]).
    pub fn is_closed(&self) -> bool {
        super::Topology::new(self).is_closed()
    }
}

fn check_finite(positions: &[Vec3]) -> Result<(), MeshError> {
    match positions.iter().position(|p| !p.is_finite()) {
        Some(vertex) => Err(MeshError::NonFinite {
            vertex,
            value: positions[vertex].to_array(),
        }),
        None => Ok(()),
    }
}

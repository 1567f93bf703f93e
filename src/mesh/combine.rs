//! Building a mesh from others: a translated or scaled copy, and the union of several meshes'
//! triangles.
use glam::Vec3;

use super::{MeshError, TriMesh};

impl TriMesh {
    /// A copy with every vertex moved by `offset`; same triangles.
    ///
    /// # Errors
    /// [`MeshError::NonFinite`] if a moved coordinate is not finite (a non-finite `offset`, or
    /// one that overflows `f32`).
    ///
    /// # Example
    /// ```
    /// use glam::Vec3;
    /// use stochastic_collision::mesh::generate;
    /// let cube = generate::cuboid(Vec3::ONE, 0);
    /// let moved = cube.translated(Vec3::X * 3.0)?;
    /// assert_eq!(moved.aabb().min, Vec3::new(2.0, -1.0, -1.0));
    /// # Ok::<(), stochastic_collision::mesh::MeshError>(())
    /// ```
    pub fn translated(&self, offset: Vec3) -> Result<TriMesh, MeshError> {
        let positions = self.positions().iter().map(|&p| p + offset).collect();
        TriMesh::new(positions, self.triangles().to_vec())
    }

    /// A copy with every vertex scaled by `scale` along the axes (non-uniform scale allowed).
    /// A negative product of the factors mirrors the mesh: each triangle's vertex order is
    /// reversed, so triangles keep facing outwards.
    ///
    /// # Errors
    /// [`MeshError::InvalidScale`] when a factor is zero, not finite, or so small that the
    /// mesh would collapse (below `1e-6` in magnitude); [`MeshError::NonFinite`] if a scaled
    /// coordinate overflows `f32`.
    ///
    /// # Example
    /// ```
    /// use glam::Vec3;
    /// use stochastic_collision::mesh::generate;
    /// let cube = generate::cuboid(Vec3::ONE, 0);
    /// let slab = cube.scaled(Vec3::new(2.0, 0.5, 1.0))?;
    /// assert_eq!(slab.aabb().max, Vec3::new(2.0, 0.5, 1.0));
    /// let mirrored = cube.scaled(Vec3::new(-1.0, 1.0, 1.0))?;
    /// let [a, b, c] = cube.triangles()[0];
    /// assert_eq!(mirrored.triangles()[0], [a, c, b], "still facing outwards");
    /// # Ok::<(), stochastic_collision::mesh::MeshError>(())
    /// ```
    pub fn scaled(&self, scale: Vec3) -> Result<TriMesh, MeshError> {
        if !scale.is_finite() || scale.abs().min_element() < 1e-6 {
            return Err(MeshError::InvalidScale {
                scale: scale.to_array(),
            });
        }
        let positions = self.positions().iter().map(|&p| p * scale).collect();
        let mirrored = scale.x * scale.y * scale.z < 0.0;
        let triangles = self
            .triangles()
            .iter()
            .map(|&[a, b, c]| if mirrored { [a, c, b] } else { [a, b, c] })
            .collect();
        TriMesh::new(positions, triangles)
    }

    /// One mesh holding every part's vertices and triangles, in order (no welding: vertices
    /// the parts share in space stay distinct).
    ///
    /// # Errors
    /// [`MeshError::Empty`] for no parts, [`MeshError::TooManyVertices`] past `u32::MAX`
    /// vertices in all.
    ///
    /// # Example
    /// ```
    /// use glam::Vec3;
    /// use stochastic_collision::mesh::{TriMesh, generate};
    /// let a = generate::cuboid(Vec3::ONE, 0);
    /// let b = a.translated(Vec3::X * 3.0)?;
    /// let both = TriMesh::merged(&[a.clone(), b])?;
    /// assert_eq!(both.triangle_count(), 2 * a.triangle_count());
    /// assert!(both.is_closed());
    /// # Ok::<(), stochastic_collision::mesh::MeshError>(())
    /// ```
    pub fn merged(parts: &[TriMesh]) -> Result<TriMesh, MeshError> {
        let vertices: usize = parts.iter().map(TriMesh::vertex_count).sum();
        if vertices > u32::MAX as usize {
            return Err(MeshError::TooManyVertices { vertices });
        }
        let mut positions = Vec::with_capacity(vertices);
        let mut triangles = Vec::with_capacity(parts.iter().map(TriMesh::triangle_count).sum());
        for part in parts {
            let first = positions.len() as u32;
            positions.extend_from_slice(part.positions());
            triangles.extend(part.triangles().iter().map(|t| t.map(|v| v + first)));
        }
        TriMesh::new(positions, triangles)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn merged_parts_keep_their_triangles_and_indices() {
        let a = generate::icosphere(1.0, 1);
        let b = generate::cuboid(Vec3::ONE, 1)
            .translated(Vec3::X * 5.0)
            .unwrap();
        let both = TriMesh::merged(&[a.clone(), b.clone()]).unwrap();
        assert_eq!(both.vertex_count(), a.vertex_count() + b.vertex_count());
        for t in 0..a.triangle_count() {
            assert_eq!(both.triangle(t), a.triangle(t));
        }
        for t in 0..b.triangle_count() {
            assert_eq!(both.triangle(a.triangle_count() + t), b.triangle(t));
        }
        assert!(matches!(TriMesh::merged(&[]), Err(MeshError::Empty { .. })));
    }

    #[test]
    fn a_non_finite_offset_is_an_error() {
        let a = generate::icosphere(1.0, 0);
        assert!(matches!(
            a.translated(Vec3::new(f32::NAN, 0.0, 0.0)),
            Err(MeshError::NonFinite { vertex: 0, .. })
        ));
    }

    /// Six times the enclosed volume, positive when the triangles face outwards.
    fn signed_volume(m: &TriMesh) -> f32 {
        m.triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| m.positions()[v as usize]);
                a.dot(b.cross(c))
            })
            .sum()
    }

    #[test]
    fn scaling_scales_the_volume_and_keeps_triangles_facing_outwards() {
        let ball = generate::icosphere(1.0, 2);
        let v = signed_volume(&ball);
        assert!(v > 0.0);
        for s in [
            Vec3::splat(2.0),
            Vec3::new(0.5, 3.0, 1.0),
            Vec3::new(-1.0, 1.0, 1.0),
            Vec3::new(-2.0, -1.0, 0.5),
            Vec3::splat(-1.0),
        ] {
            let scaled = ball.scaled(s).unwrap();
            let expected = v * (s.x * s.y * s.z).abs();
            let got = signed_volume(&scaled);
            assert!(
                (got - expected).abs() < 1e-4 * expected,
                "{s}: {got} vs {expected}"
            );
        }
    }

    #[test]
    fn degenerate_scales_are_errors() {
        let ball = generate::icosphere(1.0, 0);
        for s in [
            Vec3::ZERO,
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, f32::NAN, 1.0),
            Vec3::splat(f32::INFINITY),
            Vec3::splat(1e-7),
        ] {
            assert!(
                matches!(ball.scaled(s), Err(MeshError::InvalidScale { .. })),
                "{s}"
            );
        }
    }
}

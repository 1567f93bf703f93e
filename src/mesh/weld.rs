//! Vertices that share a position: the seams and poles a mesh exporter leaves unwelded, joined
//! for the questions that ask which triangles are neighbours on the surface.

use std::borrow::Cow;

use glam::Vec3;

use super::TriMesh;

/// Per vertex, the lowest-index vertex at exactly the same position (bit for bit, `-0.0` and
/// `0.0` alike), itself when no lower one shares it. `O(n log n)` for `n` vertices.
///
/// # Example
/// ```
/// use glam::Vec3;
/// use stochastic_collision::mesh::coincident_representatives;
/// let p = [Vec3::ZERO, Vec3::X, Vec3::new(-0.0, 0.0, 0.0), Vec3::X];
/// assert_eq!(coincident_representatives(&p), vec![0, 1, 0, 1]);
/// ```
pub fn coincident_representatives(positions: &[Vec3]) -> Vec<u32> {
    // Adding 0.0 turns -0.0 into 0.0 and leaves every other finite value as it is.
    let key = |p: Vec3| (p + Vec3::ZERO).to_array().map(f32::to_bits);
    let mut order: Vec<u32> = (0..positions.len() as u32).collect();
    order.sort_unstable_by_key(|&v| (key(positions[v as usize]), v));
    let mut representative: Vec<u32> = (0..positions.len() as u32).collect();
    let mut first = None;
    for &v in &order {
        let k = key(positions[v as usize]);
        match first {
            Some((fk, fv)) if fk == k => representative[v as usize] = fv,
            _ => first = Some((k, v)),
        }
    }
    representative
}

impl TriMesh {
    /// The mesh with every triangle corner replaced by the lowest-index vertex at the same
    /// position ([`coincident_representatives`]): the same positions (the replaced vertices
    /// stay, unreferenced), triangles joined across unwelded seams and poles. Borrowed when no
    /// corner changes.
    ///
    /// Self-collision uses it to decide which triangles are neighbours
    /// ([`SelfExclusion`](super::SelfExclusion)): two triangles on either side of a seam touch
    /// by construction, they are not in contact. A triangle may get a repeated corner (a sliver
    /// at a pole); that is valid input.
    ///
    /// # Example
    /// ```
    /// use glam::Vec3;
    /// use stochastic_collision::mesh::{Topology, TriMesh};
    /// // Two triangles along the diagonal of a square, each with its own copy of it.
    /// let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0), Vec3::X, Vec3::Y];
    /// let mesh = TriMesh::new(p, vec![[0, 1, 2], [3, 5, 4]])?;
    /// assert!(Topology::new(&mesh).triangle_neighbours(0).is_empty());
    /// let welded = mesh.welded();
    /// assert_eq!(welded.triangles(), &[[0, 1, 2], [3, 2, 1]]);
    /// assert_eq!(Topology::new(&welded).triangle_neighbours(0), &[1]);
    /// # Ok::<(), stochastic_collision::mesh::MeshError>(())
    /// ```
    pub fn welded(&self) -> Cow<'_, TriMesh> {
        let representative = coincident_representatives(self.positions());
        let joined = |tri: &[u32; 3]| tri.map(|v| representative[v as usize]);
        if self.triangles().iter().all(|tri| joined(tri) == *tri) {
            return Cow::Borrowed(self);
        }
        let triangles = self.triangles().iter().map(joined).collect();
        Cow::Owned(
            TriMesh::new(self.positions().to_vec(), triangles)
                .expect("the same positions, indices into them"),
        )
    }
}

/// `mesh` with every triangle given its own three vertices: a seam along every edge (tests).
#[cfg(test)]
pub(crate) fn triangle_soup(mesh: &TriMesh) -> TriMesh {
    let mut positions = Vec::with_capacity(3 * mesh.triangle_count());
    let mut triangles = Vec::with_capacity(mesh.triangle_count());
    for t in 0..mesh.triangle_count() {
        let base = positions.len() as u32;
        positions.extend(mesh.triangle(t));
        triangles.push([base, base + 1, base + 2]);
    }
    TriMesh::new(positions, triangles).expect("indices into the positions just made")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Topology, generate};

    #[test]
    fn a_mesh_without_shared_positions_is_borrowed() {
        let sheet = generate::cloth_grid(1.0, 1.0, 5, 5);
        assert!(matches!(sheet.welded(), Cow::Borrowed(_)));
    }

    #[test]
    fn a_grid_cut_into_separate_triangles_welds_back_to_the_grid() {
        let sheet = generate::cloth_grid(1.0, 1.0, 6, 4);
        let soup = triangle_soup(&sheet);
        assert_eq!(
            Topology::new(&soup).boundary_edge_count(),
            3 * soup.triangle_count()
        );
        let welded = soup.welded();
        let (a, b) = (Topology::new(&welded), Topology::new(&sheet));
        assert_eq!(a.edges().len(), b.edges().len());
        assert_eq!(a.boundary_edge_count(), b.boundary_edge_count());
        for t in 0..sheet.triangle_count() as u32 {
            assert_eq!(a.triangle_neighbours(t), b.triangle_neighbours(t));
        }
        assert_eq!(welded.positions(), soup.positions());
    }
}

//! A regular grid of cubic voxels around a mesh, and which voxels its surface comes near: the
//! ground of the [`InteriorMap`](super::InteriorMap).
use glam::{UVec3, Vec3};

use crate::mesh::TriMesh;

/// The grid's origin is moved off the mesh's box by these fractions of a voxel (on top of one
/// voxel of padding), a different one per axis, so that the voxel centres of a mesh laid out
/// on a regular grid rarely lie on its faces or its diagonals. Only the map's share of
/// classified voxels depends on it: the parity is exact wherever the rays pass
/// ([`super::ray_parity`]).
const GRID_SHIFT: [f32; 3] = [0.137_036, 0.271_828, 0.414_213];

/// Voxels this close to a triangle (as a fraction of a voxel, on top of a relative `f32`
/// rounding margin) count as touched by it: far more than the rounding of a point's transform,
/// so a point found in an untouched voxel is on that voxel's side of the surface.
const SURFACE_MARGIN: f32 = 1e-3;

/// Cubic voxels over a mesh's box, padded by a voxel (and the [`GRID_SHIFT`] of its axis) on every side, so
/// that every point beyond the grid is away from the surface. Voxel `(x, y, z)` is at index
/// `(z · dims[1] + y) · dims[0] + x`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct VoxelGrid {
    /// The lowest corner of voxel `(0, 0, 0)`.
    pub origin: Vec3,
    /// Side of a voxel.
    pub cell: f32,
    /// `1 / cell`.
    pub inv_cell: f32,
    /// Voxels along each axis (all 0 for an empty grid).
    pub dims: [u32; 3],
}

impl VoxelGrid {
    /// A grid with no voxels: every point is beyond it.
    const EMPTY: VoxelGrid = VoxelGrid {
        origin: Vec3::ZERO,
        cell: 0.0,
        inv_cell: 0.0,
        dims: [0; 3],
    };

    /// `resolution` voxels (at least 1) along the longest side of `mesh`'s box; empty for a
    /// mesh with no triangles or no extent.
    pub fn around(mesh: &TriMesh, resolution: u32) -> Self {
        let aabb = mesh.aabb();
        let extent = aabb.max - aabb.min;
        let longest = extent.max_element();
        if mesh.triangle_count() == 0 || !longest.is_finite() || longest <= 0.0 {
            return Self::EMPTY;
        }
        let cell = longest / resolution.clamp(1, 1024) as f32;
        Self {
            origin: aabb.min - cell * (Vec3::ONE + Vec3::from_array(GRID_SHIFT)),
            cell,
            inv_cell: 1.0 / cell,
            dims: extent
                .to_array()
                .map(|e| ((e / cell).ceil() as u32 + 3).max(3)),
        }
    }

    /// Number of voxels.
    pub fn voxels(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Index of voxel `(x, y, z)`.
    #[inline]
    pub fn index(&self, x: u32, y: u32, z: u32) -> usize {
        (z as usize * self.dims[1] as usize + y as usize) * self.dims[0] as usize + x as usize
    }

    /// The voxel holding `p`, or `None` beyond the grid (or for a point that is not finite).
    #[inline]
    pub fn voxel_of(&self, p: Vec3) -> Option<usize> {
        let q = (p - self.origin) * self.inv_cell;
        if !q.cmpge(Vec3::ZERO).all() {
            return None;
        }
        let (x, y, z) = (q.x as u32, q.y as u32, q.z as u32);
        (x < self.dims[0] && y < self.dims[1] && z < self.dims[2]).then(|| self.index(x, y, z))
    }

    /// The voxels that a triangle of `mesh` comes near (its box, grown by the margin, overlaps
    /// them, and so does its plane).
    pub fn surface_voxels(&self, mesh: &TriMesh) -> Vec<bool> {
        let mut surface = vec![false; self.voxels()];
        if surface.is_empty() {
            return surface;
        }
        let half = self.cell * 0.5;
        let max = UVec3::from(self.dims) - UVec3::ONE;
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t);
            let scale = a.abs().max(b.abs()).max(c.abs()).max_element();
            let margin = self.cell * SURFACE_MARGIN + scale * 1e-5;
            let lo = (a.min(b).min(c) - Vec3::splat(margin) - self.origin) * self.inv_cell;
            let hi = (a.max(b).max(c) + Vec3::splat(margin) - self.origin) * self.inv_cell;
            let lo = lo.floor().max(Vec3::ZERO).as_uvec3().min(max);
            let hi = hi.floor().max(Vec3::ZERO).as_uvec3().min(max);
            let n = (b - a).cross(c - a);
            let reach = n.abs().dot(Vec3::splat(half)) + n.length() * margin;
            for z in lo.z..=hi.z {
                for y in lo.y..=hi.y {
                    for x in lo.x..=hi.x {
                        let centre = self.origin
                            + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * self.cell;
                        // A degenerate triangle (n = 0) marks its whole box.
                        if n.dot(centre - a).abs() <= reach * (1.0 + 1e-4) {
                            surface[self.index(x, y, z)] = true;
                        }
                    }
                }
            }
        }
        surface
    }
}

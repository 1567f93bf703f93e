//! A coarse map of a mesh's solid (which voxels lie wholly inside, wholly outside, or near the
//! surface) and a few surface samples of the mesh, for the interpenetration certificate of the
//! ADB traversal: if one sample of a connected surface lies inside the other mesh and another
//! sample of the same surface lies outside it, the surface crosses the other mesh's surface
//! somewhere between them, so the meshes collide, wherever the triangles that cross are.
//!
//! Deep overlaps are where a collision query without this spends most: the two surfaces cross
//! everywhere around a deep interpenetration, yet a traversal must still descend to one
//! intersecting triangle pair (or gather its evidence) through many node pairs whose boxes
//! overlap around the crossing. Looking a few dozen surface points up in the other mesh's map
//! settles such a pose before that.
//!
//! "Inside" is the parity of ray crossings, as in [`crate::bvh::contains_point`]. Where every
//! edge of the mesh is used by an even number of triangles (a closed surface, self-intersecting
//! or made of several components as it may be), the parity is the same along every ray, it
//! changes exactly where a path crosses the surface, and the certificate is exact: a voxel is
//! classified only when no triangle comes near it and the three axis-aligned rays through its
//! centre agree. For an open mesh (holes, boundary edges) parity depends on the ray: two of the
//! three rays decide, and the map is an approximation ([`InteriorMap::is_exact`]) whose
//! certificate's confidence is measured ([`InteriorMap::certificate_confidence`]). The
//! crossings along each ray are decided exactly, whatever the mesh's alignment with the grid
//! (exact orientation predicates, simulation of simplicity for rays through edges and vertices).
//!
//! The samples are vertices, each with its connected component (an inside and an outside
//! sample must belong to one component), of three kinds ([`SurfaceSamples`]):
//! - per direction (a bin of a cube map), the vertices a mesh leads with when it moves that
//!   way, and the trailing vertices of the same components: looked up first, towards the other
//!   mesh, they settle the overlaps of protruding parts (horns, arms, spikes) that evenly
//!   spread samples seldom hit;
//! - coarse samples spread over the surface in the BVH's leaf order (so spatially coherent
//!   chunks), always looked up;
//! - finer samples of each coarse chunk's part of the surface, looked up only when a coarse
//!   sample of the chunk came into or near the other mesh.
//!
//! A chunk of samples whose bounding sphere lies wholly outside the other mesh (or wholly
//! inside it) is settled by one lookup in the map's [`Clearance`] (per block of voxels, the
//! distance to the nearest voxel not wholly outside, and to the nearest not wholly inside), so
//! a pose short of contact looks up only the few chunks that come near the other mesh.
use glam::Vec3;

use super::clearance::Clearance;
use super::ray_parity;
use super::surface_samples::{CERTIFY_CHUNK, SurfaceSamples};
use super::voxel_grid::VoxelGrid;
use crate::bvh::CollisionMesh;
use crate::mesh::Topology;

/// Class of a voxel in an [`InteriorMap`]: a triangle comes near it.
const SURFACE: u8 = 0;
/// Class of a voxel wholly outside.
pub(super) const OUTSIDE: u8 = 1;
/// Class of a voxel wholly inside.
const INSIDE: u8 = 2;
/// Class of a voxel no triangle comes near whose three rays disagree (an open mesh, seen
/// through a hole).
const AMBIGUOUS: u8 = 3;

/// Most coarse surface samples an [`InteriorMap`] keeps (in at most 64 chunks).
pub const MAX_SURFACE_SAMPLES: usize = 64 * CERTIFY_CHUNK;

/// Most voxels [`Interpenetration::depth`] reaches in each direction.
const MAX_DEPTH_STEPS: u32 = 64;

/// A voxel map of the inside and outside of a mesh, and the mesh's surface samples (see the
/// module documentation). Built by [`InteriorMap::build`]; part of an
/// [`AdbTree`](super::AdbTree) built with a non-zero
/// [`interior_resolution`](super::AdbBuildOptions::interior_resolution).
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::adb::InteriorMap;
/// let ball = CollisionMesh::new(generate::icosphere(1.0, 3));
/// let map = InteriorMap::build(&ball, 32, 64);
/// assert!(map.is_exact());
/// assert_eq!(map.classify(Vec3::ZERO), Some(true));
/// assert_eq!(map.classify(Vec3::new(1.3, 0.0, 0.0)), Some(false));
/// assert_eq!(map.classify(Vec3::new(1.0, 0.0, 0.0)), None); // on the surface
/// ```
#[derive(Debug, Clone)]
pub struct InteriorMap {
    pub(super) grid: VoxelGrid,
    /// The class of every voxel, 2 bits each, four to a byte (x fastest, then y, then z), so
    /// that a map of a million voxels takes a quarter of a megabyte and stays in cache.
    pub(super) classes: Vec<u8>,
    pub(super) exact: bool,
    pub(super) samples: SurfaceSamples,
    /// How far each block of voxels is from the nearest voxel not wholly outside, and from the
    /// nearest not wholly inside.
    pub(super) clearance: Clearance,
    /// Per voxel, [`InteriorMap::build_depth_steps`]: a certificate's depth, in voxel steps.
    depth_steps: Vec<u8>,
    /// The confidence of a certificate found in this map: 1 for an exact map, else as
    /// measured ([`InteriorMap::certificate_confidence`]).
    pub(super) certificate_confidence: f64,
}

/// What [`InteriorMap::certify`] found: a sample of one surface inside the other mesh (and one
/// of the same connected surface outside it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interpenetration {
    /// The sample found inside, in the frame of the mesh it lies in.
    pub inside_point: Vec3,
    /// The vertex (of the sampled mesh) that sample is.
    pub vertex: u32,
    /// Whether the map it was looked up in is exact ([`InteriorMap::is_exact`]).
    pub exact: bool,
    /// About how deep the sample lies inside: the distance, along the nearest of the six axis
    /// directions, to the first voxel not wholly inside (a response's penetration depth).
    pub depth: f32,
}

/// What [`InteriorMap::look_up`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SampleLookup {
    /// A sample inside the other mesh and one of the same surface outside it: the surfaces
    /// cross.
    Crossing(Interpenetration),
    /// No sample lies inside the other mesh or near its surface: every one is in a voxel
    /// classified outside, beyond the map, or where the map's rays disagree (an open mesh).
    AllOutside,
    /// Neither: some sample lies near the other mesh's surface, or inside it with no sample
    /// of the same component outside.
    Undecided,
}

impl InteriorMap {
    /// Builds the map of `mesh` with `resolution` voxels along the longest side of its box
    /// (at least 1), up to `samples` (at most [`MAX_SURFACE_SAMPLES`]) coarse surface samples
    /// (vertices spread evenly over the BVH's leaf order, so over the surface) with their finer
    /// samples, and the leading samples of every direction (see the module documentation).
    pub fn build(mesh: &CollisionMesh, resolution: u32, samples: usize) -> Self {
        let tri_mesh = mesh.mesh();
        let topology = Topology::new(tri_mesh);
        let exact = !topology.edges().is_empty()
            && topology.edges().iter().all(|e| e.triangles.len() % 2 == 0);
        let samples = SurfaceSamples::build(mesh, samples.min(MAX_SURFACE_SAMPLES));
        let grid = VoxelGrid::around(tri_mesh, resolution);
        let voxels = grid.voxels();
        let mut map = Self {
            grid,
            classes: vec![0; voxels.div_ceil(4)],
            exact: exact && voxels > 0,
            samples,
            clearance: Clearance::default(),
            depth_steps: Vec::new(),
            certificate_confidence: if exact { 1.0 } else { 0.0 },
        };
        let surface = grid.surface_voxels(tri_mesh);
        // Odd parity along each axis, one bit per axis.
        let odd = ray_parity::odd_parity(&grid, tri_mesh);
        for i in 0..voxels {
            // Where parity is the same along every ray (a closed mesh) the three exact rays
            // agree on every voxel no triangle comes near; all three must, so a disagreement
            // leaves the voxel unclassified. Where it is not (an open mesh), two of three
            // decide, and the map is an approximation.
            let votes = odd[i].count_ones();
            let class = if surface[i] {
                SURFACE
            } else if votes == 3 || (!exact && votes == 2) {
                INSIDE
            } else if votes == 0 || (!exact && votes == 1) {
                OUTSIDE
            } else {
                AMBIGUOUS
            };
            map.classes[i / 4] |= class << (2 * (i % 4));
        }
        map.clearance = Clearance::build(grid.dims, |i| match map.class(i) {
            OUTSIDE => Some(false),
            INSIDE => Some(true),
            _ => None,
        });
        map.depth_steps = map.build_depth_steps();
        map
    }

    /// Whether parity is the same along every ray (every edge of the mesh is used by an even
    /// number of triangles): then a point classified inside is inside, one classified outside
    /// is outside, and [`InteriorMap::certify`] is never wrong. False for open meshes.
    pub fn is_exact(&self) -> bool {
        self.exact
    }

    /// The confidence a certificate found in this map is given: 1 for an
    /// [exact](InteriorMap::is_exact) map; for an open mesh's, 0 until measured
    /// ([`InteriorMap::measure_certificate`], which an [`AdbTree`](super::AdbTree) build does
    /// by default: [`AdbBuildOptions::certificate_poses`](super::AdbBuildOptions::certificate_poses)),
    /// then the measured lower bound on its rate of being right. A certificate settles a query
    /// only where this reaches the query's `p_min`.
    pub fn certificate_confidence(&self) -> f64 {
        self.certificate_confidence
    }

    /// Voxels along each axis (0 for an empty map).
    pub fn dims(&self) -> [u32; 3] {
        self.grid.dims
    }

    /// Number of coarse surface samples (the ones always looked up; each chunk of
    /// [`CERTIFY_CHUNK`] of them has its finer samples besides).
    pub fn sample_count(&self) -> usize {
        self.samples.coarse_chunks * CERTIFY_CHUNK
    }

    /// Voxels classified inside and outside (the rest are near the surface or undecided).
    pub fn classified_voxels(&self) -> (usize, usize) {
        let count = |class| {
            (0..self.grid.voxels())
                .filter(|&i| self.class(i) == class)
                .count()
        };
        let (inside, outside) = (count(INSIDE), count(OUTSIDE));
        (inside, outside)
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.classes.capacity()
            + self.samples.chunks.capacity()
                * std::mem::size_of::<super::surface_samples::ChunkSamples>()
            + self.samples.vertex.capacity() * std::mem::size_of::<u32>()
            + self.samples.chunk_spheres.capacity() * std::mem::size_of::<(Vec3, f32)>()
            + self.samples.chunk_components.capacity() * std::mem::size_of::<u64>()
            + self.clearance.memory_bytes()
            + self.depth_steps.capacity()
    }

    /// `Some(true)` if `p` (in the mesh's frame) lies in a voxel classified inside,
    /// `Some(false)` if outside (every point beyond the map is), `None` near the surface or
    /// where the rays disagree. A point that is not finite is `None`.
    #[inline]
    pub fn classify(&self, p: Vec3) -> Option<bool> {
        if !p.is_finite() {
            return None;
        }
        match self.class_at(p) {
            INSIDE => Some(true),
            OUTSIDE => Some(false),
            _ => None,
        }
    }

    /// The class of the voxel holding `p`; beyond the map (which pads the mesh's box by a
    /// voxel), outside.
    #[inline]
    fn class_at(&self, p: Vec3) -> u8 {
        self.grid.voxel_of(p).map_or(OUTSIDE, |i| self.class(i))
    }

    /// The class of voxel `i`.
    #[inline]
    pub(super) fn class(&self, i: usize) -> u8 {
        (self.classes[i / 4] >> (2 * (i % 4))) & 0b11
    }

    /// How far `p` (in this mesh's frame, in a voxel classified inside) is from the first voxel
    /// along one of the six axis directions that is not classified inside, from the centre of
    /// its voxel: at least half a voxel, at most [`MAX_DEPTH_STEPS`] voxels. One lookup in
    /// [`InteriorMap::build_depth_steps`].
    pub(super) fn depth_inside(&self, p: Vec3) -> f32 {
        let steps = self
            .grid
            .voxel_of(p)
            .and_then(|i| self.depth_steps.get(i).copied())
            .unwrap_or(1);
        (f32::from(steps) - 0.5) * self.grid.cell
    }

    /// Per voxel, the steps along the nearest of the six axis directions to the first voxel
    /// beyond it that is not classified inside (or off the map), at most
    /// [`MAX_DEPTH_STEPS`]: two sweeps along every row of voxels per axis, so a
    /// certificate's depth is one lookup instead of a search at query time (six voxels per step,
    /// in scattered cache lines).
    fn build_depth_steps(&self) -> Vec<u8> {
        let dims = self.grid.dims.map(|d| d as usize);
        let voxels = self.grid.voxels();
        let inside: Vec<bool> = (0..voxels).map(|i| self.class(i) == INSIDE).collect();
        let cap = MAX_DEPTH_STEPS as u8;
        let mut steps = vec![cap; voxels];
        let strides = [1, dims[0], dims[0] * dims[1]];
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for a in 0..dims[u] {
                for b in 0..dims[v] {
                    let start = a * strides[u] + b * strides[v];
                    for towards_end in [true, false] {
                        // Steps from the voxel at hand to the first one beyond it (in the
                        // direction looked along) not inside: 1 at the map's edge.
                        let mut run = 1u8;
                        for j in 0..dims[axis] {
                            let c = if towards_end { dims[axis] - 1 - j } else { j };
                            let voxel = start + c * strides[axis];
                            steps[voxel] = steps[voxel].min(run);
                            run = if inside[voxel] { (run + 1).min(cap) } else { 1 };
                        }
                    }
                }
            }
        }
        steps
    }
}

/// What [`InteriorMap::look_up_pair`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairLookup {
    /// The surfaces cross: a sample inside the other mesh and one of the same surface outside.
    Crossing(PairCrossing),
    /// No crossing, and the second mesh's spread samples all lay outside the first mesh and
    /// away from its surface: most often a pose short of contact, though a part too thin for
    /// the samples to land in may still collide.
    Apart,
    /// No crossing, and no sign either way (or nothing to look up).
    Undecided,
}

/// Which mesh's sample [`InteriorMap::certify_pair`] found inside the other.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PairCrossing {
    /// A sample of the second mesh inside the first (its point in the first mesh's frame).
    SecondInFirst(Interpenetration),
    /// A sample of the first mesh inside the second (its point in the second mesh's frame).
    FirstInSecond(Interpenetration),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    /// The depth looked up equals the depth found step by step from the first, along the six
    /// axis directions, for points deep and shallow inside.
    #[test]
    fn depth_from_the_table_equals_the_full_search() {
        let mesh = CollisionMesh::new(generate::icosphere(1.0, 3));
        let map = InteriorMap::build(&mesh, 96, 64);
        let grid = map.grid;
        let full = |p: Vec3| {
            let at = ((p - grid.origin) * grid.inv_cell).floor();
            let steps = (1..=MAX_DEPTH_STEPS)
                .find(|&k| {
                    [Vec3::X, Vec3::Y, Vec3::Z].iter().any(|&axis| {
                        [k as f32, -(k as f32)].iter().any(|&s| {
                            let c = at + axis * s + 0.5;
                            map.class_at(grid.origin + c * grid.cell) != INSIDE
                        })
                    })
                })
                .unwrap_or(MAX_DEPTH_STEPS);
            (steps as f32 - 0.5) * grid.cell
        };
        let mut deep = 0;
        for i in 0..2000 {
            let t = i as f32 * 0.618_034;
            let p =
                Vec3::new(t.sin(), (1.7 * t).cos(), (2.3 * t).sin()) * 0.95 * (i as f32 / 2000.0);
            if map.classify(p) == Some(true) {
                assert_eq!(map.depth_inside(p), full(p), "{p}");
                deep += usize::from(map.depth_inside(p) > 20.0 * grid.cell);
            }
        }
        assert!(deep > 10, "{deep} points deeper than 20 voxels");
    }
}

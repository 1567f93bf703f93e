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
//! three rays decide, and the map is an approximation ([`InteriorMap::is_exact`]).
//!
//! The samples are vertices spread over the surface in the BVH's leaf order (so spatially
//! coherent chunks), each with its connected component: an inside and an outside sample must
//! belong to one component. A few coarse samples are always looked up; each chunk of them has
//! finer samples of the same part of the surface, looked up only when a coarse sample of the
//! chunk came into or near the other mesh, where a deep overlap whose coarse samples missed
//! the other's inside is found.
use glam::{DVec3, Mat3, Vec3};

use super::voxel_grid::VoxelGrid;
use crate::bvh::{CollisionMesh, component_labels};
use crate::geometry::Pose;
use crate::mesh::Topology;

/// Class of a voxel in an [`InteriorMap`]: a triangle comes near it.
const SURFACE: u8 = 0;
/// Class of a voxel wholly outside.
const OUTSIDE: u8 = 1;
/// Class of a voxel wholly inside.
const INSIDE: u8 = 2;
/// Class of a voxel no triangle comes near whose three rays disagree (an open mesh, seen
/// through a hole).
const AMBIGUOUS: u8 = 3;

/// Most coarse surface samples an [`InteriorMap`] keeps (in at most 64 chunks).
pub const MAX_SURFACE_SAMPLES: usize = 64 * CERTIFY_CHUNK;

/// The component rank of samples whose component is not among the 63 largest: such samples
/// never certify (components are tracked in a `u64`).
const NO_COMPONENT: u8 = 63;

/// Finer samples per coarse chunk, looked up only where the coarse samples came into or near
/// the other mesh ([`InteriorMap::look_up`]): deep overlaps whose coarse samples straddle the
/// other surface without one inside it get a denser look there.
const REFINEMENT: usize = 64;

/// Voxels searched in each direction for [`Interpenetration::depth`].
const DEPTH_SEARCH_VOXELS: u32 = 64;

/// Samples looked up between two checks of whether the certificate is found (a multiple of 4,
/// at most 8: a chunk's 2-bit classes fill 16 bits).
pub const CERTIFY_CHUNK: usize = 8;

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
    grid: VoxelGrid,
    /// The class of every voxel, 2 bits each, four to a byte (x fastest, then y, then z), so
    /// that a map of a million voxels takes a quarter of a megabyte and stays in cache.
    classes: Vec<u8>,
    /// Voxels in the map.
    voxels: usize,
    exact: bool,
    samples: SurfaceSamples,
}

/// Points on a mesh's surface, spread over it (with their connected components), in
/// structure-of-arrays form, padded to whole chunks by repeating the last sample: the coarse
/// samples, then per coarse chunk the finer samples of the same part of the surface.
#[derive(Debug, Clone, Default)]
struct SurfaceSamples {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    /// Per sample, the vertex it is.
    vertex: Vec<u32>,
    /// Per sample, the size rank of its connected component (below [`NO_COMPONENT`]), or
    /// [`NO_COMPONENT`].
    component: Vec<u8>,
    /// Per chunk of [`CERTIFY_CHUNK`] samples, a sphere around them (centre, radius).
    chunk_spheres: Vec<(Vec3, f32)>,
    /// The coarse samples' chunks (the first ones); the refinement of coarse chunk `c` is the
    /// [`REFINEMENT`] samples after them at `coarse_chunks + c · REFINEMENT / CERTIFY_CHUNK`.
    coarse_chunks: usize,
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
    /// (at least 1), and up to `samples` (at most [`MAX_SURFACE_SAMPLES`]) surface samples:
    /// vertices spread evenly over the BVH's leaf order, so over the surface.
    pub fn build(mesh: &CollisionMesh, resolution: u32, samples: usize) -> Self {
        let tri_mesh = mesh.mesh();
        let topology = Topology::new(tri_mesh);
        let exact = !topology.edges().is_empty()
            && topology.edges().iter().all(|e| e.triangles.len() % 2 == 0);
        let samples = surface_samples(mesh, samples.min(MAX_SURFACE_SAMPLES));
        let grid = VoxelGrid::around(tri_mesh, resolution);
        let voxels = grid.voxels();
        let mut map = Self {
            grid,
            classes: vec![0; voxels.div_ceil(4)],
            voxels,
            exact: exact && voxels > 0,
            samples,
        };
        let surface = grid.surface_voxels(tri_mesh);
        // Odd parity along each axis, one bit per axis.
        let mut odd = vec![0u8; voxels];
        for axis in 0..3 {
            map.axis_parity(mesh, axis, &mut odd);
        }
        for i in 0..voxels {
            // All three rays must agree where parity is the same along every ray (then a
            // disagreement is a rounding accident); where it is not (an open mesh), two of
            // three decide, and the map is an approximation anyway.
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
        map
    }

    /// Whether parity is the same along every ray (every edge of the mesh is used by an even
    /// number of triangles): then a point classified inside is inside, one classified outside
    /// is outside, and [`InteriorMap::certify`] is never wrong. False for open meshes.
    pub fn is_exact(&self) -> bool {
        self.exact
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
        let count = |class| (0..self.voxels).filter(|&i| self.class(i) == class).count();
        let (inside, outside) = (count(INSIDE), count(OUTSIDE));
        (inside, outside)
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.classes.capacity()
            + (self.samples.x.capacity() + self.samples.y.capacity() + self.samples.z.capacity())
                * std::mem::size_of::<f32>()
            + self.samples.vertex.capacity() * std::mem::size_of::<u32>()
            + self.samples.chunk_spheres.capacity() * std::mem::size_of::<(Vec3, f32)>()
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
    fn class(&self, i: usize) -> u8 {
        (self.classes[i / 4] >> (2 * (i % 4))) & 0b11
    }

    /// Looks this mesh's surface samples up in `other`'s map, `to_other` taking this mesh's
    /// frame to `other`'s: `Some` once a sample lies inside `other` while a sample of the same
    /// connected component lies outside it (then the surfaces cross: see the module
    /// documentation). `None` if no sample pair shows it.
    pub fn certify(&self, other: &InteriorMap, to_other: &Pose) -> Option<Interpenetration> {
        match self.look_up(other, to_other) {
            SampleLookup::Crossing(found) => Some(found),
            SampleLookup::AllOutside | SampleLookup::Undecided => None,
        }
    }

    /// [`InteriorMap::certify`], and when it finds nothing, whether no sample came into or near
    /// `other` (then the surfaces are apart where the samples are, and looking the other way
    /// round is unlikely to find a crossing).
    pub fn look_up(&self, other: &InteriorMap, to_other: &Pose) -> SampleLookup {
        if other.classes.is_empty() || self.samples.x.is_empty() || !to_other.is_finite() {
            return SampleLookup::Undecided;
        }
        // The transform and the voxel lookup in one affine map, to voxel coordinates.
        let grid = &other.grid;
        let m = Mat3::from_quat(to_other.rotation) * grid.inv_cell;
        let t = (to_other.translation - grid.origin) * grid.inv_cell;
        let map = VoxelMap {
            rows: [m.row(0), m.row(1), m.row(2)],
            translation: t,
            dims: grid.dims.map(|d| d as f32),
        };
        let samples = &self.samples;
        // A chunk's voxel indices and on-map mask (`None`: its sphere lies beyond the map, so
        // all of it is outside), the bytes it will read prefetched: computed one chunk ahead,
        // so that the lookups of one chunk overlap the cache misses of the next.
        let prepare = |chunk: usize| {
            let (centre, radius) = samples.chunk_spheres[chunk];
            let q = m * centre + t;
            let r = radius * grid.inv_cell;
            if (0..3).any(|i| q[i] + r < 0.0 || q[i] - r > map.dims[i]) {
                return None;
            }
            let range = chunk * CERTIFY_CHUNK..(chunk + 1) * CERTIFY_CHUNK;
            // Branch-free (vectorised where the target allows): where a sample lands does not
            // predict well.
            let (index, on_map) = map.voxel_indices(
                [&samples.x, &samples.y, &samples.z]
                    .map(|c| <&Chunk>::try_from(&c[range.clone()]).expect("whole chunks")),
            );
            for &i in &index {
                prefetch(&other.classes[i as usize / 4]);
            }
            Some((index, on_map))
        };
        // Per component rank, whether a sample of it was seen inside, outside.
        let (mut inside_seen, mut outside_seen) = (0u64, 0u64);
        // Per component rank, the first sample of it seen inside (for the witness).
        let mut first_inside = [u16::MAX; 64];
        // Scans `chunks`, one ahead: `Some(sample)` (the first seen inside of its component)
        // once a sample of one component was seen inside and one outside, over all scans; sets
        // bit `c % 64` of `touched` for each chunk `c` with a sample inside or near the other
        // surface.
        let mut scan = |chunks: std::ops::Range<usize>, touched: &mut u64| {
            let mut next = prepare(chunks.start);
            for chunk in chunks.clone() {
                let current = next;
                if chunk + 1 < chunks.end {
                    next = prepare(chunk + 1);
                }
                let Some((index, on_map)) = current else {
                    for &c in &samples.component[chunk * CERTIFY_CHUNK..][..CERTIFY_CHUNK] {
                        outside_seen |= 1 << c;
                    }
                    continue;
                };
                // The chunk's classes, 2 bits per sample, those off the map outside; then the
                // samples inside and outside as bit masks, without a branch per sample.
                let mut classes = 0u32;
                for (k, &index) in index.iter().enumerate() {
                    classes |= u32::from(other.class(index as usize)) << (2 * k);
                }
                let off_map = spread_bits(!on_map & ((1 << CERTIFY_CHUNK) - 1));
                classes = (classes & !(off_map * 0b11)) | (off_map * u32::from(OUTSIDE));
                let inside = (classes >> 1) & !classes & EVEN_BITS;
                let outside_here = classes & !(classes >> 1) & EVEN_BITS;
                let components = &samples.component[chunk * CERTIFY_CHUNK..][..CERTIFY_CHUNK];
                for (k, &c) in components.iter().enumerate() {
                    let is_inside = (inside >> (2 * k)) & 1;
                    if is_inside != 0 && first_inside[usize::from(c)] == u16::MAX {
                        first_inside[usize::from(c)] = (chunk * CERTIFY_CHUNK + k) as u16;
                    }
                    inside_seen |= u64::from(is_inside) << c;
                    outside_seen |= u64::from((outside_here >> (2 * k)) & 1) << c;
                }
                // Inside or near the other surface (class 0 or 2: bit 0 clear); a voxel where
                // the rays disagree says nothing of where the surface is.
                if !classes & EVEN_BITS != 0 {
                    *touched |= 1 << (chunk % 64);
                }
                let crossing = inside_seen & outside_seen & !(1 << NO_COMPONENT);
                if crossing != 0 {
                    return Some(usize::from(
                        first_inside[crossing.trailing_zeros() as usize],
                    ));
                }
            }
            None
        };
        let coarse = samples.coarse_chunks;
        let per_chunk = REFINEMENT / CERTIFY_CHUNK;
        let mut touched = 0u64;
        let mut found = scan(0..coarse, &mut touched);
        // Refine where the coarse samples came into or near the other mesh (the coarse
        // chunks are at most 64: a mesh's samples are at most MAX_SURFACE_SAMPLES).
        let mut refined = 0u64;
        let mut left = touched;
        while found.is_none() && left != 0 {
            let c = left.trailing_zeros() as usize;
            left &= left - 1;
            let first = coarse + c * per_chunk;
            found = scan(first..first + per_chunk, &mut refined);
        }
        match found {
            Some(j) => {
                let p =
                    to_other.transform_point(Vec3::new(samples.x[j], samples.y[j], samples.z[j]));
                SampleLookup::Crossing(Interpenetration {
                    inside_point: p,
                    vertex: samples.vertex[j],
                    exact: other.exact,
                    depth: other.depth_inside(p),
                })
            }
            None if touched == 0 => SampleLookup::AllOutside,
            None => SampleLookup::Undecided,
        }
    }

    /// How far `p` (in this mesh's frame, in a voxel classified inside) is from the first voxel
    /// along one of the six axis directions that is not classified inside, from the centre of
    /// its voxel: at least half a voxel, at most [`DEPTH_SEARCH_VOXELS`] voxels.
    fn depth_inside(&self, p: Vec3) -> f32 {
        let grid = &self.grid;
        let q = ((p - grid.origin) * grid.inv_cell).floor();
        let steps = (1..=DEPTH_SEARCH_VOXELS)
            .find(|&k| {
                let k = k as f32;
                [Vec3::X, Vec3::Y, Vec3::Z].iter().any(|&axis| {
                    [k, -k].iter().any(|&s| {
                        let c = q + axis * s + 0.5;
                        self.class_at(grid.origin + c * grid.cell) != INSIDE
                    })
                })
            })
            .unwrap_or(DEPTH_SEARCH_VOXELS);
        (steps as f32 - 0.5) * grid.cell
    }

    /// Sets bit `axis` of `odd` for every voxel whose centre has an odd number of surface
    /// crossings below it along `axis` (on the ray through the voxel centres of its row).
    fn axis_parity(&self, mesh: &CollisionMesh, axis: usize, odd: &mut [u8]) {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let dims = self.grid.dims.map(|d| d as usize);
        let origin = self.grid.origin.as_dvec3();
        let cell = f64::from(self.grid.cell);
        let row_centre = |i: usize, k: usize| origin[k] + (i as f64 + 0.5) * cell;
        // (row, coordinate along the axis) of every crossing.
        let mut crossings: Vec<(u32, f64)> = Vec::new();
        for t in 0..mesh.mesh().triangle_count() {
            let tri: [DVec3; 3] = mesh.mesh().triangle(t).map(|p| p.as_dvec3());
            let orient = |p: (f64, f64), q: &DVec3, r: &DVec3| {
                (q[u] - p.0) * (r[v] - p.1) - (q[v] - p.1) * (r[u] - p.0)
            };
            let area = orient((tri[0][u], tri[0][v]), &tri[1], &tri[2]);
            if area == 0.0 || !area.is_finite() {
                continue; // edge-on: a ray does not pass through it, but along it
            }
            let (min_u, max_u) = min_max(tri.map(|p| p[u]));
            let (min_v, max_v) = min_max(tri.map(|p| p[v]));
            let first = |min: f64, k: usize| ((min - origin[k]) / cell - 0.5).ceil().max(0.0);
            let last = |max: f64, k: usize, d: usize| {
                ((max - origin[k]) / cell - 0.5).floor().min(d as f64 - 1.0)
            };
            let (u0, u1) = (first(min_u, u), last(max_u, u, dims[u]));
            let (v0, v1) = (first(min_v, v), last(max_v, v, dims[v]));
            if u1 < u0 || v1 < v0 {
                continue;
            }
            for iu in u0 as usize..=u1 as usize {
                for iv in v0 as usize..=v1 as usize {
                    let p = (row_centre(iu, u), row_centre(iv, v));
                    let w = [
                        orient(p, &tri[1], &tri[2]),
                        orient(p, &tri[2], &tri[0]),
                        orient(p, &tri[0], &tri[1]),
                    ];
                    let inside = if area > 0.0 {
                        w.iter().all(|&x| x >= 0.0)
                    } else {
                        w.iter().all(|&x| x <= 0.0)
                    };
                    if inside {
                        let along =
                            (w[0] * tri[0][axis] + w[1] * tri[1][axis] + w[2] * tri[2][axis])
                                / (w[0] + w[1] + w[2]);
                        crossings.push(((iu * dims[v] + iv) as u32, along));
                    }
                }
            }
        }
        crossings.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.total_cmp(&y.1)));
        let stride = |k: usize| match k {
            0 => 1,
            1 => dims[0],
            _ => dims[0] * dims[1],
        };
        let bit = 1u8 << axis;
        let mut start = 0;
        while start < crossings.len() {
            let row = crossings[start].0;
            let end = start + crossings[start..].partition_point(|c| c.0 == row);
            let (iu, iv) = (row as usize / dims[v], row as usize % dims[v]);
            let base = iu * stride(u) + iv * stride(v);
            let mut below = start;
            for i in 0..dims[axis] {
                let centre = row_centre(i, axis);
                while below < end && crossings[below].1 < centre {
                    below += 1;
                }
                if (below - start) % 2 == 1 {
                    odd[base + i * stride(axis)] |= bit;
                }
            }
            start = end;
        }
    }
}

/// One chunk of sample coordinates.
type Chunk = [f32; CERTIFY_CHUNK];

/// A map from a mesh's frame to voxel coordinates of another mesh's [`InteriorMap`].
struct VoxelMap {
    rows: [Vec3; 3],
    translation: Vec3,
    dims: [f32; 3],
}

impl VoxelMap {
    /// The voxel index of each of [`CERTIFY_CHUNK`] points (computed in `f32`: exact below
    /// 2^24 voxels) and a bit mask of those that lie on the map (the others' indices are those
    /// of the nearest voxel, never out of range).
    #[inline]
    fn voxel_indices(&self, [xs, ys, zs]: [&Chunk; 3]) -> ([i32; CERTIFY_CHUNK], u32) {
        #[cfg(target_arch = "x86_64")]
        {
            self.voxel_indices_sse2([xs, ys, zs])
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            self.voxel_indices_scalar([xs, ys, zs])
        }
    }

    /// [`VoxelMap::voxel_indices`] one point at a time: the same IEEE operations in the same
    /// order as the vectorised form, so the same results.
    #[cfg_attr(target_arch = "x86_64", allow(dead_code))]
    fn voxel_indices_scalar(&self, [xs, ys, zs]: [&Chunk; 3]) -> ([i32; CERTIFY_CHUNK], u32) {
        let (mut index, mut on_map) = ([0i32; CERTIFY_CHUNK], 0u32);
        let [dx, dy, _] = self.dims;
        for k in 0..CERTIFY_CHUNK {
            let coordinate = |r: Vec3| r.x * xs[k] + r.y * ys[k] + r.z * zs[k];
            let q = [
                coordinate(self.rows[0]) + self.translation.x,
                coordinate(self.rows[1]) + self.translation.y,
                coordinate(self.rows[2]) + self.translation.z,
            ];
            let within = (0..3).all(|i| q[i] >= 0.0 && q[i] < self.dims[i]);
            on_map |= u32::from(within) << k;
            let c = [0, 1, 2].map(|i| (q[i].max(0.0).min(self.dims[i] - 1.0) as i32) as f32);
            index[k] = (c[0] + c[1] * dx + c[2] * (dx * dy)) as i32;
        }
        (index, on_map)
    }

    /// [`VoxelMap::voxel_indices`] four points at a time (SSE2, always there on x86_64).
    #[cfg(target_arch = "x86_64")]
    #[inline]
    fn voxel_indices_sse2(&self, [xs, ys, zs]: [&Chunk; 3]) -> ([i32; CERTIFY_CHUNK], u32) {
        use std::arch::x86_64::*;
        let (mut index, mut on_map) = ([0i32; CERTIFY_CHUNK], 0u32);
        // SAFETY: SSE2 is part of the x86_64 baseline; the loads and stores are unaligned
        // ones of four f32/i32 within the arrays (CERTIFY_CHUNK is a multiple of 4).
        unsafe {
            let splat = |v: f32| _mm_set1_ps(v);
            let zero = _mm_setzero_ps();
            let dims = self.dims.map(splat);
            let last = self.dims.map(|d| splat(d - 1.0));
            let (dx, dxy) = (splat(self.dims[0]), splat(self.dims[0] * self.dims[1]));
            for lane in (0..CERTIFY_CHUNK).step_by(4) {
                let x = _mm_loadu_ps(xs.as_ptr().add(lane));
                let y = _mm_loadu_ps(ys.as_ptr().add(lane));
                let z = _mm_loadu_ps(zs.as_ptr().add(lane));
                let mut within = _mm_castsi128_ps(_mm_set1_epi32(-1));
                let mut c = [zero; 3];
                for i in 0..3 {
                    let r = self.rows[i];
                    let q = _mm_add_ps(
                        _mm_add_ps(
                            _mm_add_ps(_mm_mul_ps(splat(r.x), x), _mm_mul_ps(splat(r.y), y)),
                            _mm_mul_ps(splat(r.z), z),
                        ),
                        splat(self.translation[i]),
                    );
                    within = _mm_and_ps(within, _mm_cmpge_ps(q, zero));
                    within = _mm_and_ps(within, _mm_cmplt_ps(q, dims[i]));
                    let clamped = _mm_min_ps(_mm_max_ps(q, zero), last[i]);
                    c[i] = _mm_cvtepi32_ps(_mm_cvttps_epi32(clamped));
                }
                let flat = _mm_add_ps(
                    _mm_add_ps(c[0], _mm_mul_ps(c[1], dx)),
                    _mm_mul_ps(c[2], dxy),
                );
                _mm_storeu_si128(index.as_mut_ptr().add(lane).cast(), _mm_cvttps_epi32(flat));
                on_map |= (_mm_movemask_ps(within) as u32) << lane;
            }
        }
        (index, on_map)
    }
}

/// Asks the CPU to bring `byte` into the cache (a hint: no effect on the result; nothing on
/// targets without the instruction).
#[inline(always)]
fn prefetch(byte: &u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch never faults and reads nothing the program sees; SSE is part of the
    // x86_64 baseline.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(std::ptr::from_ref(byte).cast());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = byte;
}

/// The even bits of a chunk's 2-bit classes (one per sample).
const EVEN_BITS: u32 = 0x5555;

/// Moves bit `k` of an 8-bit mask to bit `2k`.
#[inline]
fn spread_bits(mask: u32) -> u32 {
    let x = (mask | (mask << 4)) & 0x0F0F;
    let x = (x | (x << 2)) & 0x3333;
    (x | (x << 1)) & EVEN_BITS
}

fn min_max(x: [f64; 3]) -> (f64, f64) {
    (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]))
}

/// Up to `count` vertices of the largest connected component (by triangles), spread over it:
/// one per equal share of the component's triangles in the BVH's leaf order (spatially
/// coherent, so the samples cover the surface), padded to whole chunks.
fn surface_samples(mesh: &CollisionMesh, count: usize) -> SurfaceSamples {
    let triangles = mesh.mesh().triangles();
    let positions = mesh.mesh().positions();
    let mut samples = SurfaceSamples::default();
    if triangles.is_empty() || count == 0 {
        return samples;
    }
    // Components ranked by size (0 the largest; the ones beyond the 63 largest share rank 63,
    // which never certifies).
    let labels = component_labels(mesh.mesh());
    let mut sizes = std::collections::HashMap::<u32, usize>::new();
    for tri in triangles {
        *sizes.entry(labels[tri[0] as usize]).or_default() += 1;
    }
    let mut ranked: Vec<(usize, u32)> = sizes.iter().map(|(&label, &n)| (n, label)).collect();
    ranked.sort_by_key(|&(n, label)| (std::cmp::Reverse(n), label));
    let rank: std::collections::HashMap<u32, u8> = ranked
        .iter()
        .enumerate()
        .map(|(i, &(_, label))| (label, i.min(usize::from(NO_COMPONENT)) as u8))
        .collect();
    let order = mesh.bvh().leaf_triangles();
    let count = count.min(order.len());
    let mut push = |position: usize| {
        let vertex = triangles[order[position] as usize][0];
        let p = positions[vertex as usize];
        samples.x.push(p.x);
        samples.y.push(p.y);
        samples.z.push(p.z);
        samples.vertex.push(vertex);
        samples.component.push(rank[&labels[vertex as usize]]);
    };
    // The coarse samples: one per equal share of the leaf order, padded to whole chunks.
    let coarse = count.next_multiple_of(CERTIFY_CHUNK);
    for j in 0..coarse {
        push((j.min(count - 1) * order.len() + order.len() / 2) / count);
    }
    // The refinement of each coarse chunk: REFINEMENT samples spread over the share of the
    // leaf order its samples stand for.
    let share = |c: usize| (c * CERTIFY_CHUNK).min(count) * order.len() / count;
    for c in 0..coarse / CERTIFY_CHUNK {
        let (from, to) = (share(c), share(c + 1).max(share(c) + 1).min(order.len()));
        for j in 0..REFINEMENT {
            push(from + (j * (to - from) + (to - from) / 2) / REFINEMENT);
        }
    }
    samples.coarse_chunks = coarse / CERTIFY_CHUNK;
    samples.chunk_spheres = (0..samples.x.len())
        .step_by(CERTIFY_CHUNK)
        .map(|start| {
            let points: Vec<Vec3> = (start..start + CERTIFY_CHUNK)
                .map(|j| Vec3::new(samples.x[j], samples.y[j], samples.z[j]))
                .collect();
            let (lo, hi) = points.iter().fold((points[0], points[0]), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
            let centre = (lo + hi) * 0.5;
            let radius = points
                .iter()
                .map(|p| p.distance(centre))
                .fold(0.0, f32::max);
            // Grown a little: the radius must hold the samples whatever the rounding.
            (
                centre,
                radius * (1.0 + 1e-4) + 1e-6 * centre.abs().max_element(),
            )
        })
        .collect();
    samples
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// The vectorised voxel indices are those of the scalar form, to the bit, on points on,
    /// beside and far off the map (negative coordinates, huge ones, the map's faces).
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn vectorised_voxel_indices_equal_the_scalar_ones() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        for _ in 0..200 {
            let rotation = glam::Quat::from_euler(
                glam::EulerRot::XYZ,
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
            );
            let scale = rng.random_range(0.5f32..50.0);
            let m = Mat3::from_quat(rotation) * scale;
            let map = VoxelMap {
                rows: [m.row(0), m.row(1), m.row(2)],
                translation: Vec3::new(
                    rng.random_range(-20.0..20.0),
                    rng.random_range(-20.0..20.0),
                    rng.random_range(-20.0..20.0),
                ),
                dims: [
                    rng.random_range(3..200) as f32,
                    rng.random_range(3..200) as f32,
                    rng.random_range(3..200) as f32,
                ],
            };
            let mut coordinate = || match rng.random_range(0..8) {
                0 => 0.0,
                1 => -1e30,
                2 => 1e30,
                3 => rng.random_range(-1.0f32..1.0) * 1e-6,
                _ => rng.random_range(-5.0f32..5.0),
            };
            let xs: [f32; CERTIFY_CHUNK] = std::array::from_fn(|_| coordinate());
            let ys: [f32; CERTIFY_CHUNK] = std::array::from_fn(|_| coordinate());
            let zs: [f32; CERTIFY_CHUNK] = std::array::from_fn(|_| coordinate());
            let scalar = map.voxel_indices_scalar([&xs, &ys, &zs]);
            assert_eq!(map.voxel_indices_sse2([&xs, &ys, &zs]), scalar);
            let voxels = map.dims.iter().product::<f32>() as i32;
            assert!(scalar.0.iter().all(|&i| (0..voxels).contains(&i)));
        }
    }
}

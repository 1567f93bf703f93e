//! One mesh's surface samples looked up in another mesh's [`InteriorMap`]: the work of the
//! interpenetration certificate ([`InteriorMap::certify_pair`], [`InteriorMap::look_up`]).
use glam::Mat3;

use super::interior::{
    InteriorMap, Interpenetration, OUTSIDE, PairCrossing, PairLookup, SampleLookup,
};
use super::surface_samples::{CERTIFY_CHUNK, NO_COMPONENT, REFINEMENT, SurfaceSamples};
use super::voxel_map::VoxelMap;
use crate::geometry::Pose;
use crate::prefetch::prefetch;

/// The interpenetration certificate's queries of an [`InteriorMap`] (the data and its build are
/// in the map's own module).
impl InteriorMap {
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
    /// round is unlikely to find a crossing). The samples that lead towards `other` (from this
    /// mesh's box centre to `other`'s) are looked up first, then the ones spread over the
    /// surface, then finer ones where those came into or near `other`.
    pub fn look_up(&self, other: &InteriorMap, to_other: &Pose) -> SampleLookup {
        let Some(mut lookup) = Lookup::new(self, other, to_other) else {
            return SampleLookup::Undecided;
        };
        match lookup.support().or_else(|| lookup.spread()) {
            Some(j) => SampleLookup::Crossing(lookup.crossing(j)),
            None if !lookup.touched => SampleLookup::AllOutside,
            None => SampleLookup::Undecided,
        }
    }

    /// The certificate both ways between two meshes, `second_to_first` taking the second
    /// mesh's frame to the first's: the samples each mesh leads with towards the other first
    /// (where a collision begins and goes deepest), then the second mesh's samples spread over
    /// its surface in the first's map, then, unless every one of those lay outside the first
    /// mesh and away from its surface (a pose short of contact, almost always), the first's in
    /// the second's. `None` if no sample pair shows a crossing.
    ///
    /// # Example
    /// ```
    /// use stochastic_collision::prelude::*;
    /// use stochastic_collision::adb::{InteriorMap, PairCrossing};
    /// let ball = CollisionMesh::new(generate::icosphere(1.0, 3));
    /// let map = InteriorMap::build(&ball, 32, 64);
    /// let deep = Pose::from_translation(Vec3::new(1.2, 0.0, 0.0));
    /// assert!(matches!(
    ///     InteriorMap::certify_pair(&map, &map, &deep),
    ///     Some(PairCrossing::SecondInFirst(_) | PairCrossing::FirstInSecond(_))
    /// ));
    /// let apart = Pose::from_translation(Vec3::new(2.5, 0.0, 0.0));
    /// assert_eq!(InteriorMap::certify_pair(&map, &map, &apart), None);
    /// ```
    pub fn certify_pair(
        first: &InteriorMap,
        second: &InteriorMap,
        second_to_first: &Pose,
    ) -> Option<PairCrossing> {
        match Self::look_up_pair(first, second, second_to_first) {
            PairLookup::Crossing(found) => Some(found),
            PairLookup::Apart | PairLookup::Undecided => None,
        }
    }

    /// [`InteriorMap::certify_pair`], and when it finds nothing, whether that is because the
    /// second mesh's samples spread over its surface all lay outside the first mesh and away
    /// from its surface ([`PairLookup::Apart`]: most often a pose short of contact).
    pub fn look_up_pair(
        first: &InteriorMap,
        second: &InteriorMap,
        second_to_first: &Pose,
    ) -> PairLookup {
        let mut second_in_first = Lookup::new(second, first, second_to_first);
        let found_in_first = |l: &Lookup<'_>, j| PairCrossing::SecondInFirst(l.crossing(j));
        let found_in_second = |l: &Lookup<'_>, j| PairCrossing::FirstInSecond(l.crossing(j));
        if let Some(l) = &mut second_in_first
            && let Some(j) = l.support()
        {
            return PairLookup::Crossing(found_in_first(l, j));
        }
        // Made only once the second mesh's leading samples have settled nothing.
        let mut first_in_second = Lookup::new(first, second, &second_to_first.inverse());
        if let Some(l) = &mut first_in_second
            && let Some(j) = l.support()
        {
            return PairLookup::Crossing(found_in_second(l, j));
        }
        if let Some(l) = &mut second_in_first
            && let Some(j) = l.spread()
        {
            return PairLookup::Crossing(found_in_first(l, j));
        }
        if second_in_first.as_ref().is_some_and(|l| !l.touched) {
            // Every spread sample of the second mesh lay outside the first and away from its
            // surface: most often a pose short of contact.
            return PairLookup::Apart;
        }
        let Some(l) = first_in_second.as_mut() else {
            return PairLookup::Undecided;
        };
        match l.spread() {
            Some(j) => PairLookup::Crossing(found_in_second(l, j)),
            None => PairLookup::Undecided,
        }
    }
}

/// One mesh's samples being looked up in another mesh's map, and what they showed so far.
pub(super) struct Lookup<'a> {
    samples: &'a SurfaceSamples,
    other: &'a InteriorMap,
    /// The samples' frame to the other's.
    to_other: Pose,
    /// The samples' frame to the other map's voxel coordinates.
    map: VoxelMap,
    /// Per component rank, whether a sample of it was seen inside, outside.
    inside_seen: u64,
    outside_seen: u64,
    /// Per component rank, the first sample of it seen inside (for the witness).
    first_inside: [u16; 64],
    /// Whether a spread sample (not a support one) came inside or near the other surface.
    pub(super) touched: bool,
}

impl<'a> Lookup<'a> {
    /// `None` when there is nothing to look up: an empty map, no samples, a pose that is not
    /// finite.
    pub(super) fn new(
        this: &'a InteriorMap,
        other: &'a InteriorMap,
        to_other: &Pose,
    ) -> Option<Self> {
        if other.classes.is_empty() || this.samples.chunks.is_empty() || !to_other.is_finite() {
            return None;
        }
        // The transform and the voxel lookup in one affine map, to voxel coordinates.
        let grid = &other.grid;
        let m = Mat3::from_quat(to_other.rotation) * grid.inv_cell;
        Some(Self {
            samples: &this.samples,
            other,
            to_other: *to_other,
            map: VoxelMap::new(
                [m.row(0), m.row(1), m.row(2)],
                (to_other.translation - grid.origin) * grid.inv_cell,
                grid.dims.map(|d| d as f32),
            ),
            inside_seen: 0,
            outside_seen: 0,
            first_inside: [u16::MAX; 64],
            touched: false,
        })
    }

    /// Looks the support chunk up: the samples that lead towards the other mesh (from this
    /// mesh's box centre to the other's).
    pub(super) fn support(&mut self) -> Option<usize> {
        let leading = self.leading_chunk()?;
        // Leading samples come near the other surface on every pose close to contact: whether
        // one did says nothing of whether the spread samples will find a crossing.
        let touched = self.touched;
        let mut found = self.scan(leading..leading + 1, &mut 0);
        if found.is_none() && self.inside_seen & !self.outside_seen != 0 {
            // A leading sample inside: the trailing ones of the same components are the
            // likeliest outside.
            found = self.scan(leading + 1..leading + 2, &mut 0);
        }
        self.touched = touched;
        found
    }

    /// The chunk of samples that lead towards the other mesh (from this mesh's box centre to
    /// the other's), if any.
    #[inline]
    pub(super) fn leading_chunk(&self) -> Option<usize> {
        let towards = self
            .to_other
            .inverse()
            .transform_point(self.other.samples.centre)
            - self.samples.centre;
        self.samples.support_chunk(towards)
    }

    /// Looks the coarse samples up, then the refinement of every coarse chunk that came into
    /// or near the other mesh.
    pub(super) fn spread(&mut self) -> Option<usize> {
        let coarse = self.samples.coarse_chunks;
        let per_chunk = REFINEMENT / CERTIFY_CHUNK;
        let mut touched = 0u64;
        if let Some(j) = self.scan(0..coarse, &mut touched) {
            return Some(j);
        }
        // The coarse chunks are at most 64: a mesh's samples are at most MAX_SURFACE_SAMPLES.
        let mut left = touched;
        while left != 0 {
            let c = left.trailing_zeros() as usize;
            left &= left - 1;
            let first = coarse + c * per_chunk;
            if let Some(j) = self.scan(first..first + per_chunk, &mut 0) {
                return Some(j);
            }
        }
        None
    }

    /// A chunk's voxel indices and on-map mask, the bytes it will read prefetched.
    #[inline]
    fn prepare(&self, chunk: usize) -> ([i32; CERTIFY_CHUNK], u32) {
        let c = &self.samples.chunks[chunk];
        // Branch-free (vectorised where the target allows): where a sample lands does not
        // predict well.
        let (index, on_map) = self.map.voxel_indices([&c.x, &c.y, &c.z]);
        for &i in &index {
            prefetch(self.other.classes.as_ptr().wrapping_add(i as usize / 4));
        }
        (index, on_map)
    }

    /// Scans `chunks` (at most 64): first every chunk whose sphere lies beyond the other map
    /// or wholly outside or inside the other mesh (all its samples on that side, from one
    /// test), then the others' samples one by one, preparing one chunk ahead (so that the
    /// lookups of one chunk overlap the cache misses of the next). `Some(sample)` (the first
    /// seen inside of its component) once a sample of one component was seen inside and one
    /// outside, over all scans; sets bit `c % 64` of `touched` for each chunk `c` with a
    /// sample inside or near the other surface.
    fn scan(&mut self, chunks: std::ops::Range<usize>, touched: &mut u64) -> Option<usize> {
        let samples = self.samples;
        let inv_cell = self.other.grid.inv_cell;
        let mut live = [0u16; 64];
        let mut n_live = 0;
        for chunk in chunks {
            let (centre, radius) = samples.chunk_spheres[chunk];
            match self
                .map
                .sphere_side(&self.other.clearance, centre, radius * inv_cell)
            {
                Some(false) => self.outside_seen |= samples.chunk_components[chunk],
                Some(true) => {
                    *touched |= 1 << (chunk % 64);
                    self.touched = true;
                    let components = &samples.chunks[chunk].component;
                    for (k, &c) in components.iter().enumerate() {
                        if self.first_inside[usize::from(c)] == u16::MAX {
                            self.first_inside[usize::from(c)] = (chunk * CERTIFY_CHUNK + k) as u16;
                        }
                    }
                    self.inside_seen |= samples.chunk_components[chunk];
                }
                None => {
                    live[n_live] = chunk as u16;
                    n_live += 1;
                }
            }
        }
        let live = &live[..n_live];
        // Samples seen inside before, of a component these chunks showed outside.
        if let Some(j) = self.crossing_sample() {
            return Some(j);
        }
        let mut next = live.first().map(|&c| self.prepare(usize::from(c)));
        for (i, &chunk) in live.iter().enumerate() {
            let chunk = usize::from(chunk);
            let Some((index, on_map)) = next else {
                break;
            };
            next = live.get(i + 1).map(|&c| self.prepare(usize::from(c)));
            // The chunk's classes, 2 bits per sample, those off the map outside; then the
            // samples inside and outside as bit masks, without a branch per sample.
            let mut classes = 0u32;
            for (k, &index) in index.iter().enumerate() {
                classes |= u32::from(self.other.class(index as usize)) << (2 * k);
            }
            let off_map = spread_bits(!on_map & ((1 << CERTIFY_CHUNK) - 1));
            classes = (classes & !(off_map * 0b11)) | (off_map * u32::from(OUTSIDE));
            let inside = gather_bits((classes >> 1) & !classes);
            let outside = gather_bits(classes & !(classes >> 1));
            let components = &samples.chunks[chunk].component;
            if outside == (1 << CERTIFY_CHUNK) - 1 {
                self.outside_seen |= samples.chunk_components[chunk];
            } else {
                for k in BitIndices(outside) {
                    self.outside_seen |= 1 << components[k];
                }
                for k in BitIndices(inside) {
                    let c = components[k];
                    if self.first_inside[usize::from(c)] == u16::MAX {
                        self.first_inside[usize::from(c)] = (chunk * CERTIFY_CHUNK + k) as u16;
                    }
                    self.inside_seen |= 1 << c;
                }
            }
            // Inside or near the other surface (class 0 or 2: bit 0 clear); a voxel where
            // the rays disagree says nothing of where the surface is.
            if !classes & EVEN_BITS != 0 {
                *touched |= 1 << (chunk % 64);
                self.touched = true;
            }
            if let Some(j) = self.crossing_sample() {
                return Some(j);
            }
        }
        None
    }

    /// The first sample seen inside of the first component seen both inside and outside.
    #[inline]
    fn crossing_sample(&self) -> Option<usize> {
        let crossing = self.inside_seen & self.outside_seen & !(1 << NO_COMPONENT);
        (crossing != 0).then(|| usize::from(self.first_inside[crossing.trailing_zeros() as usize]))
    }

    /// The certificate of sample `j` found inside.
    pub(super) fn crossing(&self, j: usize) -> Interpenetration {
        let s = self.samples;
        let p = self.to_other.transform_point(s.point(j));
        Interpenetration {
            inside_point: p,
            vertex: s.vertex[j],
            exact: self.other.exact,
            depth: self.other.depth_inside(p),
        }
    }
}

/// The even bits of a chunk's 2-bit classes (one per sample).
const EVEN_BITS: u32 = 0x5555;

/// Moves bit `2k` of a chunk's 2-bit classes to bit `k` ([`spread_bits`]'s inverse; odd bits
/// ignored).
#[inline]
fn gather_bits(classes: u32) -> u32 {
    let x = classes & EVEN_BITS;
    let x = (x | (x >> 1)) & 0x3333;
    let x = (x | (x >> 2)) & 0x0F0F;
    (x | (x >> 4)) & 0xFF
}

/// The indices of the set bits of a mask, lowest first.
struct BitIndices(u32);

impl Iterator for BitIndices {
    type Item = usize;

    #[inline]
    fn next(&mut self) -> Option<usize> {
        (self.0 != 0).then(|| {
            let k = self.0.trailing_zeros() as usize;
            self.0 &= self.0 - 1;
            k
        })
    }
}

/// Moves bit `k` of an 8-bit mask to bit `2k`.
#[inline]
fn spread_bits(mask: u32) -> u32 {
    let x = (mask | (mask << 4)) & 0x0F0F;
    let x = (x | (x << 2)) & 0x3333;
    (x | (x << 1)) & EVEN_BITS
}

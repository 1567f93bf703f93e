//! The affine map from one mesh's frame to the voxel coordinates of another mesh's
//! [`InteriorMap`](super::InteriorMap), applied to a chunk of surface samples at a time.
use glam::{Mat3A, Vec3, Vec3A};

use super::clearance::Clearance;
use super::surface_samples::CERTIFY_CHUNK;

/// One chunk of sample coordinates.
pub(super) type Chunk = [f32; CERTIFY_CHUNK];

/// A map from a mesh's frame to voxel coordinates of another mesh's
/// [`InteriorMap`](super::InteriorMap).
pub(super) struct VoxelMap {
    /// Rows of the linear part (rotation and scale to voxels).
    pub rows: [Vec3; 3],
    pub translation: Vec3,
    /// Voxels along each axis.
    pub dims: [f32; 3],
    /// The linear part, for one point at a time.
    linear: Mat3A,
    translation_a: Vec3A,
    dims_a: Vec3A,
}

impl VoxelMap {
    /// The map `p ↦ (rows · p + translation)`, onto a grid of `dims` voxels.
    pub fn new(rows: [Vec3; 3], translation: Vec3, dims: [f32; 3]) -> Self {
        Self {
            rows,
            translation,
            dims,
            linear: Mat3A::from_cols(rows[0].into(), rows[1].into(), rows[2].into()).transpose(),
            translation_a: translation.into(),
            dims_a: Vec3A::from_array(dims),
        }
    }

    /// The voxel coordinates of `p`.
    #[inline]
    pub fn apply(&self, p: Vec3) -> Vec3A {
        self.linear * Vec3A::from(p) + self.translation_a
    }

    /// Whether the sphere of `radius` around `centre` (in the mesh's frame, `radius` in voxels)
    /// lies wholly beyond the other map or in voxels classified outside (`Some(false)`), or
    /// wholly in voxels classified inside (`Some(true)`), from the map's `clearance`.
    #[inline]
    pub fn sphere_side(&self, clearance: &Clearance, centre: Vec3, radius: f32) -> Option<bool> {
        let q = self.apply(centre);
        if (q + radius).cmplt(Vec3A::ZERO).any() || (q - radius).cmpgt(self.dims_a).any() {
            return Some(false);
        }
        clearance.sphere_side(q, radius)
    }

    /// The voxel index of each of [`CERTIFY_CHUNK`] points (computed in `f32`: exact below
    /// 2^24 voxels) and a bit mask of those that lie on the map (the others' indices are those
    /// of the nearest voxel, never out of range).
    #[inline]
    pub fn voxel_indices(&self, [xs, ys, zs]: [&Chunk; 3]) -> ([i32; CERTIFY_CHUNK], u32) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;
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
            let map = VoxelMap::new(
                [m.row(0), m.row(1), m.row(2)],
                Vec3::new(
                    rng.random_range(-20.0..20.0),
                    rng.random_range(-20.0..20.0),
                    rng.random_range(-20.0..20.0),
                ),
                [
                    rng.random_range(3..200) as f32,
                    rng.random_range(3..200) as f32,
                    rng.random_range(3..200) as f32,
                ],
            );
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

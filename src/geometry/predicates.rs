//! Exact orientation predicates on `f64` points (adaptive, via [`robust`]): the sign of the
//! result is always right, whatever the rounding of a direct evaluation would say.
//!
//! Next: [`crate::bvh`], whose queries end in these tests.
use glam::DVec3;
use robust::{Coord3D, orient3d as robust_orient3d};

/// Shewchuk's error bound of the direct evaluation of [`orient3d`] (`O3DERRBOUND_A`, as in
/// [`robust`]): `(7 + 56ε)ε` times the permanent, with ε = 2⁻⁵³.
const ORIENT3D_BOUND: f64 = (7.0 + 56.0 * f64::EPSILON / 2.0) * (f64::EPSILON / 2.0);

/// Orientation of `d` against the plane of `a, b, c`: positive when `d` is below it (`a, b, c`
/// counter-clockwise seen from above), i.e. the sign of `-det(b - a, c - a, d - a)`; exactly 0
/// when the four points are coplanar. Only the sign is exact.
///
/// The direct evaluation and its error bound are those [`robust::orient3d`] starts with,
/// inlined here (the hot path of every triangle test): where the bound decides the sign the
/// value is the one `robust` would return; elsewhere `robust` decides, adaptively and exactly.
#[inline(always)]
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let (bdxcdy, cdxbdy) = (bd.x * cd.y, cd.x * bd.y);
    let (cdxady, adxcdy) = (cd.x * ad.y, ad.x * cd.y);
    let (adxbdy, bdxady) = (ad.x * bd.y, bd.x * ad.y);
    let det = ad.z * (bdxcdy - cdxbdy) + bd.z * (cdxady - adxcdy) + cd.z * (adxbdy - bdxady);
    let permanent = (bdxcdy.abs() + cdxbdy.abs()) * ad.z.abs()
        + (cdxady.abs() + adxcdy.abs()) * bd.z.abs()
        + (adxbdy.abs() + bdxady.abs()) * cd.z.abs();
    let bound = ORIENT3D_BOUND * permanent;
    if det > bound || -det > bound {
        return det;
    }
    let k = |p: DVec3| Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    robust_orient3d(k(a), k(b), k(c), k(d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    #[test]
    fn the_inlined_fast_path_returns_what_robust_returns() {
        let robust = |a: DVec3, b: DVec3, c: DVec3, d: DVec3| {
            let k = |p: DVec3| Coord3D {
                x: p.x,
                y: p.y,
                z: p.z,
            };
            robust_orient3d(k(a), k(b), k(c), k(d))
        };
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        let p = |rng: &mut Xoshiro256PlusPlus, s: f64| {
            DVec3::new(
                rng.random_range(-s..s),
                rng.random_range(-s..s),
                rng.random_range(-s..s),
            )
        };
        for k in 0..20_000 {
            let (a, b, c) = (p(&mut rng, 1.0), p(&mut rng, 1.0), p(&mut rng, 1.0));
            // Random points, points on the plane of a, b, c (up to rounding), and nearly
            // coplanar ones, at several scales and far from the origin.
            let s = [1.0, 1e-6, 1e6][k % 3];
            let shift = DVec3::splat([0.0, 1e3, -1e7][(k / 3) % 3]);
            let (u, v) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
            let on_plane = a + u * (b - a) + v * (c - a);
            let d = match k % 4 {
                0 => p(&mut rng, 1.0),
                1 => on_plane,
                2 => on_plane + p(&mut rng, 1e-12),
                _ => a.lerp(b, 0.5),
            };
            let (a, b, c, d) = (a * s + shift, b * s + shift, c * s + shift, d * s + shift);
            assert_eq!(orient3d(a, b, c, d).to_bits(), robust(a, b, c, d).to_bits());
        }
    }
}

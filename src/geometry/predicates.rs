//! Exact orientation predicates on `f64` points (adaptive, via [`robust`]): the sign of the
//! result is always right, whatever the rounding of a direct evaluation would say.
//!
//! Next: [`crate::bvh`], whose queries end in these tests.
use glam::DVec3;
use robust::{Coord3D, orient3d as robust_orient3d};

/// Orientation of `d` against the plane of `a, b, c`: positive when `d` is below it (`a, b, c`
/// counter-clockwise seen from above), i.e. the sign of `-det(b - a, c - a, d - a)`; exactly 0
/// when the four points are coplanar. Only the sign is exact.
#[inline(always)]
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let k = |p: DVec3| Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    robust_orient3d(k(a), k(b), k(c), k(d))
}

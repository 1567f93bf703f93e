//! Exact orientation predicates on `f64` points (adaptive, via [`robust`]): the sign of the
//! result is always right, whatever the rounding of a direct evaluation would say.
use glam::DVec3;
use robust::{Coord3D, orient3d as robust_orient3d};

/// Sign of the volume of tetrahedron `abcd`: positive, negative or exactly 0 when coplanar.
/// Only the sign is exact.
#[inline]
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    let k = |p: DVec3| Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    robust_orient3d(k(a), k(b), k(c), k(d))
}

//! When, within a piece of the step, two moving boxes can overlap: the time window that bounds
//! every continuous test, from the tree's node pairs down to single feature pairs.
//!
//! A point that moves linearly from `p₀` to `p₁` is at `p₀ + s (p₁ − p₀)` at time `s`; if `p₀`
//! lies in a box `B₀` and `p₁` in `B₁`, that point lies in the box whose corners are
//! interpolated the same way, `B(s) = B₀ + s (B₁ − B₀)`, at every `s`. So the time window in
//! which two such boxes (one grown by a margin) overlap holds every time at which a point of
//! one comes within the margin of a point of the other. The window is the intersection of six
//! half-lines, one per face pair, each from a linear inequality in `s`.
use glam::DVec3;

use super::primitive::Trajectory;
use crate::geometry::Aabb;

/// A box whose corners move linearly over the piece, from `[lo0, hi0]` to `[lo1, hi1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MovingBox {
    lo0: DVec3,
    hi0: DVec3,
    lo1: DVec3,
    hi1: DVec3,
}

/// Added to each end of a window, so that rounding in its division never cuts a time out.
const SLACK: f64 = 1e-9;

impl MovingBox {
    /// The box that goes from `start` to `end`.
    pub fn new(start: &Aabb, end: &Aabb) -> Self {
        Self {
            lo0: start.min.as_dvec3(),
            hi0: start.max.as_dvec3(),
            lo1: end.min.as_dvec3(),
            hi1: end.max.as_dvec3(),
        }
    }

    /// The box around the points of `paths` at each time of the piece.
    pub fn around(paths: &[Trajectory]) -> Self {
        let mut b = Self {
            lo0: DVec3::splat(f64::INFINITY),
            hi0: DVec3::splat(f64::NEG_INFINITY),
            lo1: DVec3::splat(f64::INFINITY),
            hi1: DVec3::splat(f64::NEG_INFINITY),
        };
        for p in paths {
            b.lo0 = b.lo0.min(p.start);
            b.hi0 = b.hi0.max(p.start);
            b.lo1 = b.lo1.min(p.end);
            b.hi1 = b.hi1.max(p.end);
        }
        b
    }

    /// The box's corners at time `s` of its piece.
    pub fn at(&self, s: f64) -> (DVec3, DVec3) {
        (self.lo0.lerp(self.lo1, s), self.hi0.lerp(self.hi1, s))
    }

    /// The box's centres at the start and the end of its run.
    pub fn centres(&self) -> (DVec3, DVec3) {
        (0.5 * (self.lo0 + self.hi0), 0.5 * (self.lo1 + self.hi1))
    }

    /// The longest side of the box around both ends.
    pub fn largest_side(&self) -> f64 {
        (self.hi0.max(self.hi1) - self.lo0.min(self.lo1)).max_element()
    }

    /// A size measure of the box over the piece (half the surface area of the box around both
    /// ends): the larger of two boxes is the one to split.
    pub fn size(&self) -> f64 {
        let d = self.hi0.max(self.hi1) - self.lo0.min(self.lo1);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// How deep two boxes `(lo, hi)` overlap: over the three axes, the least overlap over the
/// smaller of the two extents on that axis, clamped to `[0, 1]` (1: on every axis one box
/// spans the other's extent or more, as a ball crossing a thin wall; 0: apart or touching).
pub(crate) fn overlap_depth(a: (DVec3, DVec3), b: (DVec3, DVec3)) -> f64 {
    let overlap = a.1.min(b.1) - a.0.max(b.0);
    let extent = (a.1 - a.0).min(b.1 - b.0);
    (0..3)
        .map(|k| {
            if extent[k] > 0.0 {
                (overlap[k] / extent[k]).clamp(0.0, 1.0)
            } else if overlap[k] >= 0.0 {
                1.0
            } else {
                0.0
            }
        })
        .fold(1.0, f64::min)
}

/// The times within `window` (a sub-interval of `[0, 1]`) at which `a`, grown by `margin` on
/// every side, overlaps `b`; `None` if there are none. The window returned may be wider than the
/// true one by a rounding slack, never narrower.
pub(crate) fn overlap_window(
    a: &MovingBox,
    b: &MovingBox,
    margin: f64,
    window: (f64, f64),
) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = window;
    for k in 0..3 {
        // a's lower face below b's upper face, and b's lower face below a's upper face.
        let below = (a.lo0[k] - margin - b.hi0[k], a.lo1[k] - margin - b.hi1[k]);
        let above = (b.lo0[k] - margin - a.hi0[k], b.lo1[k] - margin - a.hi1[k]);
        for (g0, g1) in [below, above] {
            if !keep_nonpositive(&mut lo, &mut hi, g0, g1) {
                return None;
            }
        }
    }
    Some((lo, hi))
}

/// Narrows `[lo, hi]` to the times at which `g(s) = g0 + s (g1 − g0)` is not positive; false
/// when none is left.
fn keep_nonpositive(lo: &mut f64, hi: &mut f64, g0: f64, g1: f64) -> bool {
    if g0 > 0.0 && g1 > 0.0 {
        return false;
    }
    if g0 > 0.0 {
        // Rising to zero at s: from then on.
        let s = g0 / (g0 - g1);
        *lo = lo.max(s - SLACK);
    } else if g1 > 0.0 {
        // Zero at s, positive after.
        let s = g0 / (g0 - g1);
        *hi = hi.min(s + SLACK);
    }
    !(*lo > *hi || g0.is_nan() || g1.is_nan())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cube(at: Vec3) -> Aabb {
        Aabb::new(at - Vec3::splat(0.5), at + Vec3::splat(0.5))
    }

    #[test]
    fn overlap_depth_is_the_least_relative_overlap_over_the_axes() {
        let b = |lo: [f64; 3], hi: [f64; 3]| (DVec3::from(lo), DVec3::from(hi));
        // A small box crossing a thin, wide slab: it spans the slab's thickness, and the slab
        // spans its height and depth.
        let slab = b([-0.01, -3.0, -8.0], [0.01, 3.0, 8.0]);
        assert_eq!(
            overlap_depth(b([-0.15, 0.0, 0.0], [0.15, 0.3, 0.3]), slab),
            1.0
        );
        // Half of a unit cube inside another along x, all of it along y and z.
        let unit = b([0.0; 3], [1.0; 3]);
        assert_eq!(
            overlap_depth(b([0.5, 0.0, 0.0], [1.5, 1.0, 1.0]), unit),
            0.5
        );
        // Touching faces, and apart.
        assert_eq!(
            overlap_depth(b([1.0, 0.0, 0.0], [2.0, 1.0, 1.0]), unit),
            0.0
        );
        assert_eq!(
            overlap_depth(b([3.0, 0.0, 0.0], [4.0, 1.0, 1.0]), unit),
            0.0
        );
        // A flat box (zero extent on y) inside the other's y range counts as spanned there.
        assert_eq!(
            overlap_depth(b([0.25, 0.5, 0.0], [0.75, 0.5, 1.0]), unit),
            1.0
        );
    }

    #[test]
    fn a_box_passing_through_another_overlaps_it_while_it_crosses() {
        let still = MovingBox::new(&cube(Vec3::ZERO), &cube(Vec3::ZERO));
        // From x = -4 to x = 4: touching from x = -1 (s = 3/8) to x = 1 (s = 5/8).
        let shot = MovingBox::new(
            &cube(Vec3::new(-4.0, 0.0, 0.0)),
            &cube(Vec3::new(4.0, 0.0, 0.0)),
        );
        let (lo, hi) = overlap_window(&shot, &still, 0.0, (0.0, 1.0)).unwrap();
        assert!((lo - 0.375).abs() < 1e-8 && lo <= 0.375, "{lo}");
        assert!((hi - 0.625).abs() < 1e-8 && hi >= 0.625, "{hi}");
        // The margin widens it symmetrically (0.8 units is 0.05 of the step each side).
        let (lo, hi) = overlap_window(&shot, &still, 0.4, (0.0, 1.0)).unwrap();
        assert!((lo - 0.325).abs() < 1e-8 && (hi - 0.675).abs() < 1e-8);
        // Clipped by the window it is given.
        let (lo, hi) = overlap_window(&still, &shot, 0.0, (0.5, 0.55)).unwrap();
        assert_eq!((lo, hi), (0.5, 0.55));
        assert!(overlap_window(&still, &shot, 0.0, (0.7, 1.0)).is_none());
    }

    #[test]
    fn a_box_passing_beside_another_never_overlaps_it() {
        let still = MovingBox::new(&cube(Vec3::ZERO), &cube(Vec3::ZERO));
        let beside = MovingBox::new(
            &cube(Vec3::new(-4.0, 1.5, 0.0)),
            &cube(Vec3::new(4.0, 1.5, 0.0)),
        );
        assert!(overlap_window(&beside, &still, 0.0, (0.0, 1.0)).is_none());
        assert!(overlap_window(&beside, &still, 0.6, (0.0, 1.0)).is_some());
    }

    #[test]
    fn every_interpolated_point_lies_in_the_interpolated_box() {
        // Points moving between random positions: the box around them holds them at every time,
        // and two groups within the margin at some time have a window holding that time.
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0
        };
        for _ in 0..200 {
            let mut paths = |n: usize| -> Vec<Trajectory> {
                (0..n)
                    .map(|_| {
                        Trajectory::new(
                            DVec3::new(next(), next(), next()),
                            DVec3::new(next(), next(), next()),
                        )
                    })
                    .collect()
            };
            let (pa, pb) = (paths(3), paths(2));
            let (ba, bb) = (MovingBox::around(&pa), MovingBox::around(&pb));
            let window = overlap_window(&ba, &bb, 0.3, (0.0, 1.0));
            for k in 0..=100 {
                let s = k as f64 / 100.0;
                let close = pa.iter().any(|p| {
                    pb.iter()
                        .any(|q| (p.at(s) - q.at(s)).abs().max_element() <= 0.3)
                });
                if close {
                    let (lo, hi) = window.expect("a window where points come close");
                    assert!(lo <= s && s <= hi, "{s} outside [{lo}, {hi}]");
                }
            }
        }
    }
}

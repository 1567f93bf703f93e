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

use super::motion::Trajectory;
use crate::bvh::NodeSlab;
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

/// A slab whose bounds move linearly over a run of pieces: `{p : lo(u) ≤ normal · p ≤ hi(u)}`
/// at time `u` of the run, holding a node's vertices (its [`NodeSlab`] placed in the step's
/// frame, for a mesh that does not turn there) or a triangle's ([`MovingSlab::around`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MovingSlab {
    /// Unit normal.
    pub normal: DVec3,
    /// The bounds `(lo, hi)` at the start and at the end of the run.
    pub start: (f64, f64),
    pub end: (f64, f64),
}

impl MovingSlab {
    /// The slab along the unit `normal` around points moving on `paths`: its bounds at the
    /// run's ends are the points' least and greatest `normal · p` there. In between, each
    /// point's `normal · p` moves linearly, so the least of them lies above the chord between
    /// its ends and the greatest below it: the points stay inside.
    pub fn around(normal: DVec3, paths: &[Trajectory]) -> Self {
        let span = |at: &dyn Fn(&Trajectory) -> DVec3| {
            paths
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                    let d = normal.dot(at(p));
                    (lo.min(d), hi.max(d))
                })
        };
        Self {
            normal,
            start: span(&|p| p.start),
            end: span(&|p| p.end),
        }
    }

    /// A node's slab that stays where it is.
    pub fn still(slab: &NodeSlab) -> Self {
        Self {
            normal: slab.normal,
            start: (slab.lo, slab.hi),
            end: (slab.lo, slab.hi),
        }
    }
}

/// An interval whose ends move linearly: `(lo, hi)` at the start and at the end of the run.
type MovingInterval = [(f64, f64); 2];

/// Where `b` lies along the unit direction `n`: its centre's projection and its half-extent's
/// both move linearly.
fn box_along(b: &MovingBox, n: DVec3) -> MovingInterval {
    let n_abs = n.abs();
    let at = |lo: DVec3, hi: DVec3| {
        let (c, r) = (n.dot(0.5 * (lo + hi)), n_abs.dot(0.5 * (hi - lo)));
        (c - r, c + r)
    };
    [at(b.lo0, b.hi0), at(b.lo1, b.hi1)]
}

/// Where the points of both `b` and `slab` lie along the unit direction `n`: with
/// `λ = n · m` (`m` the slab's normal), `n · p = λ (m · p) + (n − λ m) · p`, the first term
/// bounded by the slab and the second by the box. Nearly as thin as the slab when `n` is close
/// to `±m`: two facing patches' slabs bound them along either normal.
fn slab_along(slab: &MovingSlab, b: &MovingBox, n: DVec3) -> MovingInterval {
    let lambda = n.dot(slab.normal);
    let rest = box_along(b, n - lambda * slab.normal);
    let at = |(lo, hi): (f64, f64), (r_lo, r_hi): (f64, f64)| {
        let (x, y) = (lambda * lo, lambda * hi);
        (x.min(y) + r_lo, x.max(y) + r_hi)
    };
    [at(slab.start, rest[0]), at(slab.end, rest[1])]
}

/// Narrows `window` to the times at which `range` comes within `margin` of `target`.
fn near_interval(
    target: MovingInterval,
    range: MovingInterval,
    margin: f64,
    window: (f64, f64),
) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = window;
    // The range's top reaches the target's bottom, and its bottom stays below the target's top.
    let below = (
        target[0].0 - margin - range[0].1,
        target[1].0 - margin - range[1].1,
    );
    let above = (
        range[0].0 - target[0].1 - margin,
        range[1].0 - target[1].1 - margin,
    );
    for (g0, g1) in [below, above] {
        if !keep_nonpositive(&mut lo, &mut hi, g0, g1) {
            return None;
        }
    }
    Some((lo, hi))
}

/// The times within `window` at which two nodes, each bounded by its moving box and (where it
/// has one) its moving slab, can come within Euclidean distance `margin` of each other, as far
/// as the slabs tell: along each slab's normal, the other node's points (bounded by its box,
/// and by its slab too where it has one) must come within the margin of the slab. Apply after
/// [`overlap_window`]: every contact's time lies in both. `None` if there is none; wider than
/// the true window by a rounding slack, never narrower.
pub(crate) fn slab_window(
    (box_a, slab_a): (&MovingBox, Option<&MovingSlab>),
    (box_b, slab_b): (&MovingBox, Option<&MovingSlab>),
    margin: f64,
    window: (f64, f64),
) -> Option<(f64, f64)> {
    let mut w = window;
    for (slab, (other_box, other_slab)) in [(slab_a, (box_b, slab_b)), (slab_b, (box_a, slab_a))] {
        let Some(slab) = slab else {
            continue;
        };
        let target = [slab.start, slab.end];
        w = near_interval(target, box_along(other_box, slab.normal), margin, w)?;
        if let Some(other) = other_slab {
            let range = slab_along(other, other_box, slab.normal);
            w = near_interval(target, range, margin, w)?;
        }
    }
    Some(w)
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
    fn a_box_crossing_a_slab_meets_it_while_it_crosses() {
        // The slab 0 ≤ x ≤ 0.1 (a normal along x), a unit cube from x = -4 to x = 4: it
        // reaches the slab when its right face is at 0 (centre -0.5, s = 7/16) and leaves it
        // when its left face passes 0.1 (centre 0.6, s = 4.6/8).
        let slab = MovingSlab::still(&NodeSlab {
            normal: DVec3::X,
            lo: 0.0,
            hi: 0.1,
        });
        let shot = MovingBox::new(
            &cube(Vec3::new(-4.0, 0.0, 0.0)),
            &cube(Vec3::new(4.0, 0.0, 0.0)),
        );
        let wide = MovingBox::new(
            &cube(Vec3::ZERO).inflated(9.0),
            &cube(Vec3::ZERO).inflated(9.0),
        );
        let (lo, hi) = slab_window((&wide, Some(&slab)), (&shot, None), 0.0, (0.0, 1.0)).unwrap();
        assert!((lo - 3.5 / 8.0).abs() < 1e-8 && lo <= 3.5 / 8.0, "{lo}");
        assert!((hi - 4.6 / 8.0).abs() < 1e-8 && hi >= 4.6 / 8.0, "{hi}");
        // Either side may hold the slab.
        let swapped = slab_window((&shot, None), (&wide, Some(&slab)), 0.0, (0.0, 1.0));
        assert_eq!(swapped, Some((lo, hi)));
        // A tilted slab 2 units out along its normal, which the cube reaches to 0.7 of: never met
        // without a margin, met with 1.4.
        let tilted = MovingSlab::still(&NodeSlab {
            normal: DVec3::new(0.0, 0.6, 0.8),
            lo: 2.0,
            hi: 2.0,
        });
        assert!(slab_window((&wide, Some(&tilted)), (&shot, None), 0.0, (0.0, 1.0)).is_none());
        assert!(slab_window((&wide, Some(&tilted)), (&shot, None), 1.4, (0.0, 1.0)).is_some());
    }

    #[test]
    fn two_facing_slabs_meet_when_the_slabs_do_not_when_the_boxes_do() {
        // Two thin tilted patches, one still and one moving straight at it: their boxes meet
        // long before the patches' slabs do.
        let n = DVec3::new(1.0, 1.0, 0.0).normalize();
        let patch = |along: f64| -> Vec<DVec3> {
            let (u, v) = (DVec3::new(-1.0, 1.0, 0.0).normalize(), DVec3::Z);
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(a, b)| n * along + u * a + v * b)
                .to_vec()
        };
        let slab_of = |points: &[DVec3]| {
            let d: Vec<f64> = points.iter().map(|p| n.dot(*p)).collect();
            (
                d.iter().copied().fold(f64::INFINITY, f64::min),
                d.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            )
        };
        let still = patch(0.0);
        let box_of = |points: &[DVec3]| {
            MovingBox::around(
                &points
                    .iter()
                    .map(|p| Trajectory::new(*p, *p))
                    .collect::<Vec<_>>(),
            )
        };
        let a = (
            box_of(&still),
            MovingSlab {
                normal: n,
                start: slab_of(&still),
                end: slab_of(&still),
            },
        );
        // The other patch from 3 units away along n to 1 unit past it (contact at s = 3/4),
        // its normal the opposite one.
        let (from, to) = (patch(3.0), patch(-1.0));
        let paths: Vec<Trajectory> = from
            .iter()
            .zip(&to)
            .map(|(p, q)| Trajectory::new(*p, *q))
            .collect();
        let (f, t) = (slab_of(&from), slab_of(&to));
        let b = (
            MovingBox::around(&paths),
            MovingSlab {
                normal: -n,
                start: (-f.1, -f.0),
                end: (-t.1, -t.0),
            },
        );
        let boxes = overlap_window(&a.0, &b.0, 0.0, (0.0, 1.0)).unwrap();
        assert!(boxes.0 < 0.5, "the boxes meet early ({boxes:?})");
        let both = slab_window((&a.0, Some(&a.1)), (&b.0, Some(&b.1)), 0.0, boxes).unwrap();
        assert!((both.0 - 0.75).abs() < 1e-8 && both.0 <= 0.75, "{both:?}");
    }

    #[test]
    fn points_near_each_other_lie_in_the_slab_window() {
        // A still group of points and a moving one, each with a slab along a random normal (the
        // moving one's bounds following its points): at every time at which a moving point
        // comes within the margin of a still one, the window holds.
        let mut seed = 777u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 4.0 - 2.0
        };
        let mut checked = 0;
        for case in 0..400 {
            let still: Vec<DVec3> = (0..4)
                .map(|_| DVec3::new(next(), next(), next()) * 0.5)
                .collect();
            let (na, nb) = (
                DVec3::new(next(), next(), next()).normalize(),
                DVec3::new(next(), next(), next()).normalize(),
            );
            let span = |n: DVec3, points: &mut dyn Iterator<Item = DVec3>| {
                points.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                    (l.min(n.dot(p)), h.max(n.dot(p)))
                })
            };
            let a_slab = span(na, &mut still.iter().copied());
            let offset = DVec3::new(next(), next(), next());
            let moving: Vec<Trajectory> = (0..3)
                .map(|_| {
                    // A rigid translation (so that a slab moves with its points), or not.
                    let p = DVec3::new(next(), next(), next());
                    if case % 2 == 0 {
                        Trajectory::new(p, p + offset)
                    } else {
                        Trajectory::new(p, DVec3::new(next(), next(), next()))
                    }
                })
                .collect();
            let b_slab = MovingSlab {
                normal: nb,
                start: span(nb, &mut moving.iter().map(|q| q.start)),
                end: span(nb, &mut moving.iter().map(|q| q.end)),
            };
            let a = (
                MovingBox::around(
                    &still
                        .iter()
                        .map(|p| Trajectory::new(*p, *p))
                        .collect::<Vec<_>>(),
                ),
                MovingSlab {
                    normal: na,
                    start: a_slab,
                    end: a_slab,
                },
            );
            let b_box = MovingBox::around(&moving);
            // The moving slab holds its points at every time only for a translation.
            let b_slab = (case % 2 == 0).then_some(&b_slab);
            let window = overlap_window(&a.0, &b_box, 0.3, (0.0, 1.0))
                .and_then(|w| slab_window((&a.0, Some(&a.1)), (&b_box, b_slab), 0.3, w));
            for k in 0..=100 {
                let s = k as f64 / 100.0;
                let close = still
                    .iter()
                    .any(|p| moving.iter().any(|q| (*p - q.at(s)).length() <= 0.3));
                if close {
                    checked += 1;
                    let (lo, hi) = window.expect("a window where points come close");
                    assert!(lo <= s && s <= hi, "case {case}: {s} outside [{lo}, {hi}]");
                }
            }
        }
        assert!(
            checked > 100,
            "the cases come close often enough ({checked})"
        );
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

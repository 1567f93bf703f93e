//! Box–box tests between two trees in different frames (separating axes of both boxes).
use glam::{Mat3, Mat3A, Vec3, Vec3A};

use super::tree::{Bvh, BvhNode};
use crate::geometry::Pose;

/// The second tree's frame seen from the first's, prepared for many box tests.
///
/// Overlap uses the six face axes of the two boxes (the 9 edge–edge axes rarely cull more on
/// tree nodes and cost as much again). All tests are *conservative*: a margin proportional to
/// the scene's coordinate scale absorbs `f32` rounding, so no pair whose triangles touch is
/// ever culled; the exact triangle test decides.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RelativeFrame {
    rot: Mat3,
    rot_t: Mat3,
    abs_rot: Mat3,
    abs_rot_t: Mat3,
    translation: Vec3,
    margin: f32,
    /// The same in SIMD form, for the prepared tests of the ADB traversal.
    simd: SimdFrame,
}

/// [`RelativeFrame`]'s transforms as 16-byte SIMD vectors: lane by lane the same IEEE
/// operations in the same order as the scalar `Vec3` code, so the same results to the bit, in
/// fewer instructions.
#[derive(Debug, Clone, Copy)]
struct SimdFrame {
    rot: Mat3A,
    rot_t: Mat3A,
    abs_rot: Mat3A,
    abs_rot_t: Mat3A,
    translation: Vec3A,
}

/// What [`RelativeFrame::overlap_prepared`] knows of two boxes that may overlap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BoxOverlap {
    /// Distance between the box centres.
    pub(crate) center_distance: f32,
    /// How squarely each box straddles the middle plane of the other node's slab (the plane
    /// its surface lies near), multiplied over both: in `[0, 1]`, 1 when each box is centred
    /// on the other's plane, 0 when either lies on one side of it. Surfaces cross only where
    /// each reaches both sides of the other, so pairs that straddle are the likelier to hold
    /// intersecting triangles. ½ per side whose slab is unbounded (no plane to straddle).
    pub(crate) straddle: f32,
}

/// How squarely the interval `[d − r, d + r]` straddles the middle of `[lo, hi]`: the shorter
/// of its two parts on either side of the middle, over `r`, clamped to `[0, 1]` (0 for NaN);
/// ½ for an unbounded slab or an empty interval.
///
/// Without a branch on the data: which way each test goes cannot be predicted (pairs straddle
/// or not about as often), so the result is selected by bit masks instead of branches.
#[inline]
fn straddle(d: f32, r: f32, lo: f32, hi: f32) -> f32 {
    let middle = 0.5 * (lo + hi);
    let share = (middle - (d - r)).min((d + r) - middle) / r;
    // NaN (a NaN centre) and negative shares count as no straddle (`clamp` would keep the
    // NaN); `+ 0.0` turns a −0 into +0, so that the ranks compare as they always did.
    #[allow(clippy::manual_clamp)]
    let clamped = share.max(0.0).min(1.0) + 0.0;
    let bounded = r > 0.0 && middle.is_finite();
    select(bounded, clamped, 0.5)
}

/// `if take { a } else { b }`, as a bit mask rather than a branch.
#[inline(always)]
fn select(take: bool, a: f32, b: f32) -> f32 {
    let mask = (take as u32).wrapping_neg();
    f32::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask))
}

/// A node of the first tree prepared for box tests ([`RelativeFrame::prepare_first`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct FirstBox {
    center: Vec3A,
    half: Vec3A,
    /// `|Rᵀ| half`: the half extents' reach along the second frame's axes.
    half_in_second: Vec3A,
    normal: Vec3A,
    /// `|Rᵀ n|`.
    normal_in_second: Vec3A,
    slab: [f32; 2],
}

/// A node of the second tree prepared for box tests ([`RelativeFrame::prepare_second`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct SecondBox {
    center_in_first: Vec3A,
    half: Vec3A,
    /// `|R| half`: the half extents' reach along the first frame's axes.
    half_in_first: Vec3A,
    /// `R n`.
    normal_in_first: Vec3A,
    /// `(R n)·t`.
    normal_offset: f32,
    slab: [f32; 2],
}

impl RelativeFrame {
    /// `rel` maps the second tree's frame into the first's.
    pub(crate) fn new(rel: &Pose, a: &Bvh, b: &Bvh) -> Self {
        let rot = Mat3::from_quat(rel.rotation);
        let abs_rot = Mat3::from_cols(
            rot.x_axis.abs() + Vec3::splat(1e-6),
            rot.y_axis.abs() + Vec3::splat(1e-6),
            rot.z_axis.abs() + Vec3::splat(1e-6),
        );
        let scale = a
            .root_aabb()
            .max_abs()
            .max(rel.translation.abs().max_element() + b.root_aabb().max_abs());
        Self {
            rot,
            rot_t: rot.transpose(),
            abs_rot,
            abs_rot_t: abs_rot.transpose(),
            translation: rel.translation,
            simd: SimdFrame {
                rot: Mat3A::from(rot),
                rot_t: Mat3A::from(rot.transpose()),
                abs_rot: Mat3A::from(abs_rot),
                abs_rot_t: Mat3A::from(abs_rot.transpose()),
                translation: Vec3A::from(rel.translation),
            },
            // The exact tests transform in f64 from the same quaternion; the f32 matrix and the
            // f32 arithmetic here differ from that by a few ulps of the scale. 32 ulps covers
            // it with room to spare and culls nothing measurable less.
            // (The constant is folded first: `scale * 32.0` would overflow above 1e37.)
            margin: scale * (32.0 * f32::EPSILON) + f32::MIN_POSITIVE,
        }
    }

    /// A node of the first tree with its slab (`[normal, lo, hi]`, first frame), prepared for
    /// [`overlap_prepared`](Self::overlap_prepared) against several nodes of the second tree:
    /// what depends on this node alone is computed once.
    #[inline]
    pub(crate) fn prepare_first(&self, a: &BvhNode, slab: (Vec3, f32, f32)) -> FirstBox {
        let (min, max) = (Vec3A::from(a.min), Vec3A::from(a.max));
        let half = (max - min) * 0.5;
        let normal = Vec3A::from(slab.0);
        FirstBox {
            center: (min + max) * 0.5,
            half,
            half_in_second: self.simd.abs_rot_t * half,
            normal,
            normal_in_second: (self.simd.rot_t * normal).abs(),
            slab: [slab.1, slab.2],
        }
    }

    /// A node of the second tree with its slab (`[normal, lo, hi]`, second frame), prepared
    /// for [`overlap_prepared`](Self::overlap_prepared) against several nodes of the first
    /// tree.
    #[inline]
    pub(crate) fn prepare_second(&self, b: &BvhNode, slab: (Vec3, f32, f32)) -> SecondBox {
        let f = &self.simd;
        let (min, max) = (Vec3A::from(b.min), Vec3A::from(b.max));
        let half = (max - min) * 0.5;
        let normal_in_first = f.rot * Vec3A::from(slab.0);
        SecondBox {
            // Its centre in the first frame, exactly as `setup` computes it.
            center_in_first: f.rot * ((min + max) * 0.5) + f.translation,
            half,
            half_in_first: f.abs_rot * half,
            normal_in_first,
            normal_offset: normal_in_first.dot(f.translation),
            slab: [slab.1, slab.2],
        }
    }

    /// Whether two prepared boxes may overlap (touching counts) and neither lies outside the
    /// other's slab: if they may, the distance between the box centres and how squarely each
    /// box straddles the other node's slab; `None` if not. The box test is
    /// [`overlap`](Self::overlap)'s, with the same arithmetic (the same answer and centre
    /// distance to the bit), then the two slab tests.
    #[inline]
    pub(crate) fn overlap_prepared(&self, a: &FirstBox, b: &SecondBox) -> Option<BoxOverlap> {
        let t = b.center_in_first - a.center;
        // `separated` in SIMD form.
        if t.is_finite() {
            let margin = Vec3A::splat(self.margin);
            if t.abs().cmpgt(a.half + b.half_in_first + margin).any() {
                return None;
            }
            let tb = self.simd.rot_t * t;
            if tb.abs().cmpgt(b.half + a.half_in_second + margin).any() {
                return None;
            }
        }
        // The second box against the first node's slab `{p : lo ≤ n·p ≤ hi}` (first frame):
        // culled only when its whole interval along `n` lies outside, by more than the margin.
        let [lo, hi] = a.slab;
        let r = a.normal_in_second.dot(b.half);
        let d = a.normal.dot(b.center_in_first);
        if d - r > hi + self.margin || d + r < lo - self.margin {
            return None;
        }
        let straddle_a = straddle(d, r, lo, hi);
        // The first box against the second node's slab (second frame): `p_b = Rᵀ (p_a − t)`,
        // so `n·p_b = (R n)·p_a − (R n)·t`.
        let [lo, hi] = b.slab;
        let m = b.normal_in_first;
        let r = m.abs().dot(a.half);
        let d = m.dot(a.center) - b.normal_offset;
        if d - r > hi + self.margin || d + r < lo - self.margin {
            return None;
        }
        Some(BoxOverlap {
            center_distance: t.length(),
            straddle: straddle_a * straddle(d, r, lo, hi),
        })
    }

    /// Centre offset in the first frame, then each box's half extents.
    #[inline]
    fn setup(&self, a: &BvhNode, b: &BvhNode) -> (Vec3, Vec3, Vec3) {
        let ca = (a.min + a.max) * 0.5;
        let ea = (a.max - a.min) * 0.5;
        let cb = (b.min + b.max) * 0.5;
        let eb = (b.max - b.min) * 0.5;
        (self.rot * cb + self.translation - ca, ea, eb)
    }

    /// Whether the boxes may overlap (touching counts).
    #[inline]
    pub(crate) fn overlap(&self, a: &BvhNode, b: &BvhNode) -> bool {
        let (t, ea, eb) = self.setup(a, b);
        !self.separated(t, ea, eb)
    }

    /// Whether one of the six face axes separates boxes of half extents `ea` and `eb` whose
    /// centres are `t` apart (first frame), by more than the margin. Never on overflow (boxes
    /// near the limits of the `f32` range): then they cannot be culled.
    #[inline(always)]
    fn separated(&self, t: Vec3, ea: Vec3, eb: Vec3) -> bool {
        if !t.is_finite() {
            return false;
        }
        let ra = ea + self.abs_rot * eb + Vec3::splat(self.margin);
        if t.abs().cmpgt(ra).any() {
            return true;
        }
        let tb = self.rot_t * t;
        let rb = eb + self.abs_rot_t * ea + Vec3::splat(self.margin);
        tb.abs().cmpgt(rb).any()
    }

    /// The second frame's rotation and translation in the first frame.
    #[inline]
    pub(crate) fn transform_point(&self, p: Vec3) -> Vec3 {
        self.rot * p + self.translation
    }

    /// A lower bound on the distance between the boxes (largest gap along the six axes); 0
    /// when the `f32` arithmetic overflowed (boxes near the limits of the range), which is
    /// conservative.
    #[inline]
    pub(crate) fn distance_lower_bound(&self, a: &BvhNode, b: &BvhNode) -> f32 {
        let (t, ea, eb) = self.setup(a, b);
        let gap_a = t.abs() - ea - self.abs_rot * eb;
        let tb = self.rot_t * t;
        let gap_b = tb.abs() - eb - self.abs_rot_t * ea;
        let lb = gap_a.max(gap_b).max_element() - self.margin;
        if lb.is_finite() { lb.max(0.0) } else { 0.0 }
    }
}

/// Size measure used to pick which node to descend: the larger one is split.
#[inline]
pub(crate) fn node_size(n: &BvhNode) -> f32 {
    (n.max - n.min).element_sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::CollisionMesh;
    use crate::mesh::generate;
    use crate::poses::near_contact_poses;

    /// The range of `along` over the eight corners of `node`'s box.
    fn interval(node: &BvhNode, along: impl Fn(Vec3) -> f32) -> (f32, f32) {
        (0..8)
            .map(|i| {
                along(Vec3::new(
                    if i & 1 == 0 { node.min.x } else { node.max.x },
                    if i & 2 == 0 { node.min.y } else { node.max.y },
                    if i & 4 == 0 { node.min.z } else { node.max.z },
                ))
            })
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), v| {
                (l.min(v), h.max(v))
            })
    }

    /// The prepared test of two nodes with their slabs (`[normal, lo, hi]` of the first node
    /// in the first frame, then of the second in the second): the centre distance if they may
    /// overlap.
    fn overlap_with_slabs(
        frame: &RelativeFrame,
        a: &BvhNode,
        b: &BvhNode,
        slab_a: (Vec3, f32, f32),
        slab_b: (Vec3, f32, f32),
    ) -> Option<f32> {
        frame
            .overlap_prepared(
                &frame.prepare_first(a, slab_a),
                &frame.prepare_second(b, slab_b),
            )
            .map(|o| o.center_distance)
    }

    /// The straddle is 1 for an interval centred on the slab's middle, falls off linearly as
    /// the middle moves toward either end of it, is 0 once the middle is outside, and ½ when
    /// there is no plane (an unbounded slab) or no extent.
    #[test]
    fn straddle_measures_how_squarely_an_interval_crosses_the_middle_plane() {
        // Slab [0, 2], middle 1; intervals of half width 1 at centres d.
        assert_eq!(straddle(1.0, 1.0, 0.0, 2.0), 1.0);
        assert_eq!(straddle(1.5, 1.0, 0.0, 2.0), 0.5);
        assert_eq!(straddle(0.5, 1.0, 0.0, 2.0), 0.5);
        assert_eq!(straddle(2.0, 1.0, 0.0, 2.0), 0.0);
        assert_eq!(straddle(-3.0, 1.0, 0.0, 2.0), 0.0);
        assert_eq!(straddle(1.0, 1.0, f32::NEG_INFINITY, f32::INFINITY), 0.5);
        assert_eq!(straddle(1.0, 0.0, 0.0, 2.0), 0.5);
        assert_eq!(straddle(f32::NAN, 1.0, 0.0, 2.0), 0.0);
        assert_eq!(straddle(1.0, f32::NAN, 0.0, 2.0), 0.5);
        // No straddle is +0, never −0 (ranks compare with `total_cmp`).
        for (d, lo, hi) in [(2.0, -1.0, 1.0), (-3.0, -1.0, 1.0), (f32::NAN, -1.0, 1.0)] {
            assert_eq!(straddle(d, 1.0, lo, hi).to_bits(), 0);
        }
        // A share of −0 (the middle −0, the interval's end +0).
        assert_eq!(straddle(1.0, 1.0, -0.0, -0.0).to_bits(), 0);
    }

    /// The combined test answers as the box test alone when the slabs are unbounded, with the
    /// same centre distance; a slab (of either frame) that holds the other box never culls
    /// it, and one beside it always does.
    #[test]
    fn overlap_with_slabs_agrees_with_the_box_test_and_culls_by_slab() {
        let a = CollisionMesh::new(generate::icosphere(1.0, 3));
        let b = CollisionMesh::new(generate::torus(1.0, 0.3, 24, 12));
        let unbounded = (Vec3::ZERO, f32::NEG_INFINITY, f32::INFINITY);
        let (mut overlapping, mut culled) = (0, 0);
        for p in near_contact_poses(&a, &b, 8, 0.1, 3) {
            let frame = RelativeFrame::new(&p.pose, a.bvh(), b.bvh());
            for x in a.bvh().nodes().iter().take(40) {
                for y in b.bvh().nodes().iter().take(40) {
                    let both = overlap_with_slabs(&frame, x, y, unbounded, unbounded);
                    assert_eq!(both.is_some(), frame.overlap(x, y));
                    let Some(d) = both else { continue };
                    overlapping += 1;
                    assert_eq!(d.to_bits(), frame.setup(x, y).0.length().to_bits());
                    // `y`'s box along a normal of the first frame: its interval holds the box.
                    let n = Vec3::new(0.6, 0.0, 0.8);
                    let (lo, hi) = interval(y, |c| n.dot(frame.transform_point(c)));
                    let holding = (n, lo, hi);
                    assert!(overlap_with_slabs(&frame, x, y, holding, unbounded).is_some());
                    let width = hi - lo + 1.0;
                    let beside = (n, lo - 2.0 * width, lo - width);
                    assert!(overlap_with_slabs(&frame, x, y, beside, unbounded).is_none());
                    // The same for `x`'s box against a slab of the second frame.
                    let (lo, hi) = interval(x, |c| n.dot(frame.rot_t * (c - frame.translation)));
                    assert!(overlap_with_slabs(&frame, x, y, unbounded, (n, lo, hi)).is_some());
                    let width = hi - lo + 1.0;
                    let beside = (n, hi + width, hi + 2.0 * width);
                    assert!(overlap_with_slabs(&frame, x, y, unbounded, beside).is_none());
                    culled += 1;
                }
            }
        }
        assert!(overlapping > 100 && culled > 100, "{overlapping} {culled}");
    }
}

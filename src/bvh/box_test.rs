//! Box–box tests between two trees in different frames (separating axes of both boxes).
use glam::{Mat3, Vec3};

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
            // The exact tests transform in f64 from the same quaternion; the f32 matrix and the
            // f32 arithmetic here differ from that by a few ulps of the scale. 32 ulps covers
            // it with room to spare and culls nothing measurable less.
            // (The constant is folded first: `scale * 32.0` would overflow above 1e37.)
            margin: scale * (32.0 * f32::EPSILON) + f32::MIN_POSITIVE,
        }
    }

    /// Whether the boxes may overlap (touching counts) and neither lies outside the other's
    /// slab (`slabs` gives `[normal, lo, hi]` of the first node in the first frame, then of the
    /// second in the second; called only once the boxes overlap, so a culled pair never loads
    /// them): the distance between the box centres if they may, `None` if not. The same tests
    /// as [`overlap`](Self::overlap) and the two slab tests, sharing their transforms.
    #[inline]
    pub(crate) fn overlap_with_slabs(
        &self,
        a: &BvhNode,
        b: &BvhNode,
        slabs: impl FnOnce() -> ((Vec3, f32, f32), (Vec3, f32, f32)),
    ) -> Option<f32> {
        let ca = (a.min + a.max) * 0.5;
        let ea = (a.max - a.min) * 0.5;
        let cb = (b.min + b.max) * 0.5;
        let eb = (b.max - b.min) * 0.5;
        // `b`'s centre in the first frame; `t` exactly as `setup` computes it.
        let cb_in_a = self.rot * cb + self.translation;
        let t = cb_in_a - ca;
        if self.separated(t, ea, eb) {
            return None;
        }
        let (slab_a, slab_b) = slabs();
        // The second box against the first node's slab `{p : lo ≤ n·p ≤ hi}` (first frame):
        // culled only when its whole interval along `n` lies outside, by more than the margin.
        let (n, lo, hi) = slab_a;
        let r = (self.rot_t * n).abs().dot(eb);
        let d = n.dot(cb_in_a);
        if d - r > hi + self.margin || d + r < lo - self.margin {
            return None;
        }
        // The first box against the second node's slab (second frame): `p_b = Rᵀ (p_a − t)`,
        // so `n·p_b = (R n)·p_a − (R n)·t`.
        let (n, lo, hi) = slab_b;
        let m = self.rot * n;
        let r = m.abs().dot(ea);
        let d = m.dot(ca) - m.dot(self.translation);
        if d - r > hi + self.margin || d + r < lo - self.margin {
            return None;
        }
        Some(t.length())
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
                    let both = frame.overlap_with_slabs(x, y, || (unbounded, unbounded));
                    assert_eq!(both.is_some(), frame.overlap(x, y));
                    let Some(d) = both else { continue };
                    overlapping += 1;
                    assert_eq!(d.to_bits(), frame.setup(x, y).0.length().to_bits());
                    // `y`'s box along a normal of the first frame: its interval holds the box.
                    let n = Vec3::new(0.6, 0.0, 0.8);
                    let (lo, hi) = interval(y, |c| n.dot(frame.transform_point(c)));
                    let holding = (n, lo, hi);
                    assert!(
                        frame
                            .overlap_with_slabs(x, y, || (holding, unbounded))
                            .is_some()
                    );
                    let width = hi - lo + 1.0;
                    let beside = (n, lo - 2.0 * width, lo - width);
                    assert!(
                        frame
                            .overlap_with_slabs(x, y, || (beside, unbounded))
                            .is_none()
                    );
                    // The same for `x`'s box against a slab of the second frame.
                    let (lo, hi) = interval(x, |c| n.dot(frame.rot_t * (c - frame.translation)));
                    assert!(
                        frame
                            .overlap_with_slabs(x, y, || (unbounded, (n, lo, hi)))
                            .is_some()
                    );
                    let width = hi - lo + 1.0;
                    let beside = (n, hi + width, hi + 2.0 * width);
                    assert!(
                        frame
                            .overlap_with_slabs(x, y, || (unbounded, beside))
                            .is_none()
                    );
                    culled += 1;
                }
            }
        }
        assert!(overlapping > 100 && culled > 100, "{overlapping} {culled}");
    }
}

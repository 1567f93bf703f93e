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
        if !t.is_finite() {
            return true; // overflow (boxes near the limits of the f32 range): cannot cull
        }
        let ra = ea + self.abs_rot * eb + Vec3::splat(self.margin);
        if t.abs().cmpgt(ra).any() {
            return false;
        }
        let tb = self.rot_t * t;
        let rb = eb + self.abs_rot_t * ea + Vec3::splat(self.margin);
        !tb.abs().cmpgt(rb).any()
    }

    /// Distance between the two boxes' centres.
    #[inline]
    pub(crate) fn center_distance(&self, a: &BvhNode, b: &BvhNode) -> f32 {
        self.setup(a, b).0.length()
    }

    /// The second frame's rotation and translation in the first frame.
    #[inline]
    pub(crate) fn transform_point(&self, p: Vec3) -> Vec3 {
        self.rot * p + self.translation
    }

    /// Whether the box `b` (second frame) lies entirely outside the slab
    /// `{p : lo ≤ n·p ≤ hi}` of the first frame (conservatively: never for a touching box).
    #[inline]
    pub(crate) fn second_box_outside_slab(&self, b: &BvhNode, n: Vec3, lo: f32, hi: f32) -> bool {
        let c = self.rot * ((b.min + b.max) * 0.5) + self.translation;
        let r = (self.rot_t * n).abs().dot((b.max - b.min) * 0.5);
        let d = n.dot(c);
        d - r > hi + self.margin || d + r < lo - self.margin
    }

    /// Whether the box `a` (first frame) lies entirely outside the slab
    /// `{p : lo ≤ n·p ≤ hi}` of the second frame (conservatively).
    #[inline]
    pub(crate) fn first_box_outside_slab(&self, a: &BvhNode, n: Vec3, lo: f32, hi: f32) -> bool {
        // p_b = Rᵀ (p_a − t), so n·p_b = (R n)·p_a − (R n)·t.
        let m = self.rot * n;
        let r = m.abs().dot((a.max - a.min) * 0.5);
        let d = m.dot((a.min + a.max) * 0.5) - m.dot(self.translation);
        d - r > hi + self.margin || d + r < lo - self.margin
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

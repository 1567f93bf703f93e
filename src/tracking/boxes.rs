//! Axis-aligned boxes of the tracker: a triangle's box, the gap between two boxes, and
//! whether two boxes come within a margin.

use glam::{DVec3, Vec3};

/// A box as (min, max) corners, in f64.
pub(crate) type Box64 = (DVec3, DVec3);

/// The box of a triangle.
#[inline]
pub(crate) fn triangle_box(t: &[DVec3; 3]) -> Box64 {
    (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
}

/// The Euclidean gap between two boxes: a lower bound of the distance between anything
/// inside them (0 when they meet).
#[inline]
pub(crate) fn box_gap(a: &Box64, b: &Box64) -> f64 {
    (a.0 - b.1).max(b.0 - a.1).max(DVec3::ZERO).length()
}

/// The largest gap between two boxes along one axis (0 or less when they meet): the boxes
/// come within `h` of each other along every axis when it is at most `h`.
#[inline]
pub(crate) fn box_axis_gap(a: &Box64, b: &Box64) -> f64 {
    (a.0 - b.1).max(b.0 - a.1).max_element()
}

/// Whether the f32 boxes `[a_min, a_max]` and `[b_min, b_max]` come within `margin` of each
/// other along every axis.
#[inline]
pub(crate) fn boxes_meet(a_min: Vec3, a_max: Vec3, b_min: Vec3, b_max: Vec3, margin: f32) -> bool {
    (a_min - margin).cmple(b_max).all() && b_min.cmple(a_max + margin).all()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gaps_and_meeting_agree_with_hand_computed_boxes() {
        let a = triangle_box(&[DVec3::ZERO, DVec3::X, DVec3::Y]);
        assert_eq!(a, (DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0)));
        let b = (DVec3::new(4.0, 5.0, 0.0), DVec3::new(6.0, 6.0, 1.0));
        assert_eq!(box_gap(&a, &b), 5.0); // (3, 4, 0) apart
        assert_eq!(box_axis_gap(&a, &b), 4.0);
        assert_eq!(box_gap(&a, &a), 0.0);
        assert!(box_axis_gap(&a, &a) <= 0.0);
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        assert!(boxes_meet(lo, hi, Vec3::splat(1.5), Vec3::splat(2.0), 0.5));
        assert!(!boxes_meet(
            lo,
            hi,
            Vec3::splat(1.5),
            Vec3::splat(2.0),
            0.49
        ));
        assert!(!boxes_meet(
            lo,
            hi,
            Vec3::new(0.5, 0.5, 2.0),
            Vec3::splat(3.0),
            0.9
        ));
    }
}

//! Contacts reported by the tracker: closest points, normal and depth of a feature pair.

use glam::{DVec3, Vec3};

use super::feature::Feature;
use super::local_search::Located;
use super::surface::Placed;

/// A contact between two features closer than the thickness (or intersecting).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Triangle of the first mesh realising the contact.
    pub triangle_a: u32,
    /// Triangle of the second mesh (the same mesh in self-collision).
    pub triangle_b: u32,
    /// Closest feature of the first mesh: a vertex, an edge or the triangle's interior.
    pub feature_a: Feature,
    /// Closest feature of the second mesh.
    pub feature_b: Feature,
    /// Closest point on the first mesh.
    pub point_a: Vec3,
    /// Closest point on the second mesh.
    pub point_b: Vec3,
    /// Unit direction in which the second mesh should move to separate (from `a` towards `b`).
    pub normal: Vec3,
    /// Distance of the features (0 when they intersect).
    pub distance: f32,
    /// How far the second mesh must move along `normal` to be `thickness` apart:
    /// `thickness − distance` when apart; for intersecting triangles, the thickness plus the
    /// deepest corner of `b` behind `a`'s plane.
    pub depth: f32,
    /// Found by collision propagation from another contact rather than by a tracked pair.
    pub propagated: bool,
    /// For a contact found by the continuous check
    /// ([`TrackerConfig::continuous`](super::TrackerConfig::continuous)): the earliest time in
    /// `[0, 1)` of the step at which its two triangles touched, the surfaces having passed
    /// into or through each other since. `None` for contacts found at the step's end.
    pub time_of_impact: Option<f32>,
}

impl Contact {
    pub(crate) fn new(
        a: &Placed,
        b: &Placed,
        l: &Located,
        thickness: f32,
        propagated: bool,
    ) -> Self {
        let (ta, tb) = (a.triangle(l.ta), b.triangle(l.tb));
        let centroid = |t: &[DVec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
        let face_normal = |t: &[DVec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero();
        let d = l.cp.distance;
        let gap = l.cp.point_b - l.cp.point_a;
        let scale = (ta[1] - ta[0])
            .length()
            .max((tb[1] - tb[0]).length())
            .max(f64::MIN_POSITIVE);
        let (normal, depth) = if d > 1e-9 * scale && gap.length() > 0.0 {
            (gap / gap.length(), thickness as f64 - d)
        } else {
            // Touching or crossing: `a`'s face normal, turned towards `b`'s side.
            let mut n = face_normal(&ta);
            if n == DVec3::ZERO {
                n = -face_normal(&tb);
            }
            if n == DVec3::ZERO {
                n = DVec3::Y;
            }
            if n.dot(centroid(&tb) - centroid(&ta)) < 0.0 {
                n = -n;
            }
            let behind = tb
                .iter()
                .map(|&q| -n.dot(q - l.cp.point_a))
                .fold(0.0, f64::max);
            (n, thickness as f64 + behind)
        };
        Contact {
            triangle_a: l.ta,
            triangle_b: l.tb,
            feature_a: l.fa,
            feature_b: l.fb,
            point_a: l.cp.point_a.as_vec3(),
            point_b: l.cp.point_b.as_vec3(),
            normal: normal.as_vec3(),
            distance: d as f32,
            depth: depth.max(0.0) as f32,
            propagated,
            time_of_impact: None,
        }
    }
}

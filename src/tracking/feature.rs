//! Features of a triangle mesh (vertex, edge, triangle) and the distance between two of them.

use glam::DVec3;

use crate::geometry::{
    ClosestPoints, closest_point_on_triangle, closest_points_segment_segment,
    closest_points_triangle_triangle,
};
use crate::mesh::Topology;

/// A feature of a triangle mesh: a vertex, an edge (by [`Topology`] edge id) or a triangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Feature {
    /// A vertex index.
    Vertex(u32),
    /// An edge id of the mesh's [`Topology`].
    Edge(u32),
    /// A triangle index.
    Triangle(u32),
}

impl Feature {
    /// The feature's vertex indices: one, two or three.
    pub fn vertices(&self, topology: &Topology, triangles: &[[u32; 3]]) -> FeatureVertices {
        match *self {
            Feature::Vertex(v) => FeatureVertices::One(v),
            Feature::Edge(e) => {
                let [a, b] = topology.edge(e).vertices;
                FeatureVertices::Two(a, b)
            }
            Feature::Triangle(t) => FeatureVertices::Three(triangles[t as usize]),
        }
    }

    /// The feature's dimension: 0 for a vertex, 1 for an edge, 2 for a triangle.
    pub fn dimension(&self) -> u8 {
        match self {
            Feature::Vertex(_) => 0,
            Feature::Edge(_) => 1,
            Feature::Triangle(_) => 2,
        }
    }
}

/// The vertex indices of a [`Feature`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeatureVertices {
    /// A vertex.
    One(u32),
    /// An edge's two ends.
    Two(u32, u32),
    /// A triangle's three corners.
    Three([u32; 3]),
}

impl FeatureVertices {
    /// The first vertex (a representative for ring distances).
    pub fn first(&self) -> u32 {
        match *self {
            FeatureVertices::One(v) | FeatureVertices::Two(v, _) => v,
            FeatureVertices::Three(t) => t[0],
        }
    }
}

/// A feature's geometry: a point, a segment or a triangle, in `f64`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FeatureShape {
    /// A vertex.
    Point(DVec3),
    /// An edge.
    Segment(DVec3, DVec3),
    /// A triangle.
    Triangle([DVec3; 3]),
}

/// Closest points between two features of any kind (distance 0 when they intersect), from the
/// exact-decision primitives of [`crate::geometry`]: point–point, point–segment,
/// point–triangle, segment–segment directly; segment–triangle and triangle–triangle through
/// the triangle–triangle routine (a segment is a degenerate triangle there, handled exactly).
/// `point_a` lies on `a`, `point_b` on `b`. Never NaN for finite input.
pub fn feature_distance(a: &FeatureShape, b: &FeatureShape) -> ClosestPoints {
    use FeatureShape::*;
    let cp = |pa: DVec3, pb: DVec3| ClosestPoints {
        distance: (pa - pb).length(),
        point_a: pa,
        point_b: pb,
    };
    match (*a, *b) {
        (Point(p), Point(q)) => cp(p, q),
        (Point(p), Segment(q0, q1)) => closest_points_segment_segment(p, p, q0, q1),
        (Segment(p0, p1), Point(q)) => closest_points_segment_segment(p0, p1, q, q),
        (Point(p), Triangle(t)) => cp(p, closest_point_on_triangle(p, &t)),
        (Triangle(t), Point(q)) => cp(closest_point_on_triangle(q, &t), q),
        (Segment(p0, p1), Segment(q0, q1)) => closest_points_segment_segment(p0, p1, q0, q1),
        (Segment(p0, p1), Triangle(t)) => closest_points_triangle_triangle(&[p0, p1, p1], &t),
        (Triangle(t), Segment(q0, q1)) => closest_points_triangle_triangle(&t, &[q0, q1, q1]),
        (Triangle(s), Triangle(t)) => closest_points_triangle_triangle(&s, &t),
    }
}

/// Relative tolerance (of the triangle's longest edge) within which a closest point counts as
/// lying on an edge or at a corner.
const ON_BOUNDARY: f64 = 1e-6;

/// The lowest-dimensional feature of triangle `t` (corners `tri`, indices `corners`) that
/// contains the point `p` of the triangle: a corner, an edge, or the triangle itself.
pub(crate) fn reduce_to_feature(
    p: DVec3,
    t: u32,
    tri: &[DVec3; 3],
    corners: [u32; 3],
    topology: &Topology,
) -> Feature {
    let scale = (tri[1] - tri[0])
        .length()
        .max((tri[2] - tri[1]).length())
        .max((tri[0] - tri[2]).length());
    let tol = ON_BOUNDARY * scale;
    for k in 0..3 {
        if (p - tri[k]).length() <= tol {
            return Feature::Vertex(corners[k]);
        }
    }
    let edges = topology.triangle_edges(t);
    for k in 0..3 {
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        let q = closest_points_segment_segment(p, p, a, b);
        if q.distance <= tol && edges[k] != Topology::NO_EDGE {
            return Feature::Edge(edges[k]);
        }
    }
    Feature::Triangle(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn distances_between_every_kind_agree_with_hand_computed_values() {
        let p = FeatureShape::Point(DVec3::new(0.0, 1.0, 0.0));
        let s = FeatureShape::Segment(DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0));
        let t = FeatureShape::Triangle([
            DVec3::new(0.0, -1.0, -1.0),
            DVec3::new(0.0, -1.0, 1.0),
            DVec3::new(0.0, 1.0, 0.0),
        ]);
        assert!((feature_distance(&p, &s).distance - 1.0).abs() < 1e-12);
        assert!((feature_distance(&s, &p).distance - 1.0).abs() < 1e-12);
        // The segment pierces the triangle.
        assert_eq!(feature_distance(&s, &t).distance, 0.0);
        assert_eq!(feature_distance(&t, &s).distance, 0.0);
        assert_eq!(feature_distance(&p, &t).distance, 0.0);
        let far = FeatureShape::Point(DVec3::new(3.0, 0.0, 0.0));
        assert!((feature_distance(&far, &t).distance - 3.0).abs() < 1e-12);
        assert!((feature_distance(&t, &t).distance).abs() < 1e-12);
    }

    #[test]
    fn closest_points_reduce_to_corner_edge_or_face() {
        let mesh = generate::cuboid(glam::Vec3::ONE, 0);
        let topo = Topology::new(&mesh);
        let t = 0u32;
        let corners = mesh.triangles()[0];
        let tri = mesh.triangle(0).map(|p| p.as_dvec3());
        assert_eq!(
            reduce_to_feature(tri[1], t, &tri, corners, &topo),
            Feature::Vertex(corners[1])
        );
        let mid = (tri[0] + tri[1]) * 0.5;
        let e = topo.triangle_edges(t)[0];
        assert_eq!(
            reduce_to_feature(mid, t, &tri, corners, &topo),
            Feature::Edge(e)
        );
        let centre = (tri[0] + tri[1] + tri[2]) / 3.0;
        assert_eq!(
            reduce_to_feature(centre, t, &tri, corners, &topo),
            Feature::Triangle(t)
        );
    }
}

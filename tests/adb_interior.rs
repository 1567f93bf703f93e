//! The interior map and the interpenetration certificate of ADB-trees: the map never
//! classifies a point on the wrong side of a closed surface (against exact ray parity), and a
//! certificate is never found where the surfaces do not cross (against the exact query), on
//! generated meshes (grid-aligned, self-intersecting, several components, open, flat) and on
//! the shared meshes; it settles most deep overlaps; the ADB query reports it.
mod common;

use glam::{Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::adb::{
    AdbBuildOptions, AdbQuery, AdbTree, AdbWorkspace, CERTIFY_CHUNK, InteriorMap,
    MAX_SURFACE_SAMPLES, PairCrossing, PairLookup, adb_intersects,
};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, contains_point, intersects};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::{TriMesh, generate};
use stochastic_collision::poses::near_contact_poses;

/// Checks the map of `mesh` against exact ray parity at `count` seeded random points of its
/// box (grown by 10 %); returns the share of points the map classifies.
fn check_against_parity(name: &str, mesh: &CollisionMesh, map: &InteriorMap, count: usize) -> f64 {
    let aabb = mesh.bvh().root_aabb();
    let grow = (aabb.max - aabb.min) * 0.1;
    let (lo, hi) = (aabb.min - grow, aabb.max + grow);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let mut classified = 0;
    for _ in 0..count {
        let p = Vec3::new(
            rng.random_range(lo.x..=hi.x),
            rng.random_range(lo.y..=hi.y),
            rng.random_range(lo.z..=hi.z),
        );
        if let Some(inside) = map.classify(p) {
            classified += 1;
            assert_eq!(inside, contains_point(mesh, p), "{name}: {p}");
        }
    }
    classified as f64 / count as f64
}

#[test]
fn the_map_agrees_with_exact_parity_on_closed_meshes() {
    let ball = generate::icosphere(1.0, 3);
    let meshes = [
        ("icosphere", ball.clone()),
        ("torus", generate::torus(1.0, 0.3, 48, 16)),
        // Grid-aligned: vertices on regular coordinates, faces parallel to the rays.
        ("cuboid", generate::cuboid(Vec3::new(1.0, 0.5, 0.25), 4)),
        // Two overlapping balls in one mesh: where they overlap the parity is even, so that
        // region is "outside" for the map as for `contains_point`, and the certificate stays
        // sound (a path from odd to even parity crosses the surface).
        (
            "overlapping balls",
            TriMesh::merged(&[
                ball.clone(),
                ball.translated(Vec3::new(0.8, 0.1, 0.0)).unwrap(),
            ])
            .unwrap(),
        ),
    ];
    for (name, mesh) in meshes {
        let mesh = CollisionMesh::new(mesh);
        for resolution in [8, 32, 64] {
            let map = InteriorMap::build(&mesh, resolution, 64);
            assert!(map.is_exact(), "{name}");
            let share = check_against_parity(name, &mesh, &map, 2000);
            println!("{name} at {resolution}: {:.0} % classified", share * 100.0);
            // A coarse map leaves more near the surface unclassified (at 8 voxels the thin
            // cuboid's share depends on where the grid's offset puts its two layers).
            let least = if resolution < 32 { 0.25 } else { 0.5 };
            assert!(
                share > least,
                "{name} at {resolution}: only {share:.2} classified"
            );
        }
    }
}

#[test]
fn open_flat_empty_and_odd_input_give_no_false_inside() {
    // An open mesh: no parity the rays agree on through the hole, and the map says it is not
    // exact.
    let ball = generate::icosphere(1.0, 3);
    let open = TriMesh::new(
        ball.positions().to_vec(),
        ball.triangles()[..ball.triangle_count() - 40].to_vec(),
    )
    .expect("valid mesh");
    let open = CollisionMesh::new(open);
    let map = InteriorMap::build(&open, 32, 64);
    assert!(!map.is_exact());
    // Far from the hole the inside is still inside.
    assert!(map.classified_voxels().0 > 0);

    // A flat cloth has no inside at all.
    let cloth = CollisionMesh::new(generate::cloth_grid(1.0, 1.0, 8, 8));
    let map = InteriorMap::build(&cloth, 32, 64);
    assert_eq!(map.classified_voxels().0, 0, "a flat mesh has no inside");
    assert!(map.certify(&map, &Pose::IDENTITY).is_none());

    // A mesh of degenerate (zero-area) triangles only: no inside, no NaN.
    let degenerate = TriMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::Y],
        vec![[0, 1, 2], [1, 2, 0]],
    )
    .expect("valid mesh");
    let map = InteriorMap::build(&CollisionMesh::new(degenerate), 16, 8);
    assert_eq!(map.classified_voxels().0, 0);

    // Resolution 1 and sample counts of 0 and beyond the maximum are accepted.
    let ball = CollisionMesh::new(ball);
    let coarse = InteriorMap::build(&ball, 1, 0);
    assert_eq!(coarse.sample_count(), 0);
    assert!(coarse.certify(&coarse, &Pose::IDENTITY).is_none());
    let many = InteriorMap::build(&ball, 16, 1 << 20);
    assert_eq!(many.sample_count(), MAX_SURFACE_SAMPLES);
    let few = InteriorMap::build(&ball, 16, 3);
    assert_eq!(few.sample_count(), CERTIFY_CHUNK, "padded to a whole chunk");

    // Points and poses that are not finite are never classified or certified.
    let map = InteriorMap::build(&ball, 16, 64);
    assert_eq!(map.classify(Vec3::NAN), None);
    assert_eq!(map.classify(Vec3::INFINITY), None);
    let bad = Pose {
        rotation: Quat::IDENTITY,
        translation: Vec3::new(f32::NAN, 0.0, 0.0),
    };
    assert!(map.certify(&map, &bad).is_none());
}

/// For every pose, the certificate (both ways) is found only where the exact query says the
/// meshes collide; returns (certified, colliding) over the deep overlaps (offsets beyond 3 %
/// of the size into each other).
fn certificate_is_sound(
    name: &str,
    a: &CollisionMesh,
    b: &CollisionMesh,
    poses: usize,
) -> (usize, usize) {
    let (map_a, map_b) = (
        InteriorMap::build(a, 128, 128),
        InteriorMap::build(b, 128, 128),
    );
    let mut ws = QueryWorkspace::new();
    let (mut certified, mut deep) = (0, 0);
    let (mut apart, mut apart_colliding) = (0, 0);
    for p in near_contact_poses(a, b, poses, 0.15, 0x1E7) {
        let truth = intersects(a, &Pose::IDENTITY, b, &p.pose, &mut ws);
        let one_way = map_b.certify(&map_a, &p.pose).is_some()
            || map_a.certify(&map_b, &p.pose.inverse()).is_some();
        let pair = InteriorMap::certify_pair(&map_a, &map_b, &p.pose);
        let offset = p.offset / p.size;
        // The look-up behind it says the same; "apart" (the second mesh's spread samples all
        // outside the first and away from its surface) is mostly said of poses short of
        // contact: counted below (on ogre's few poses here, a third of them collide; a
        // traversal decides those exactly).
        match InteriorMap::look_up_pair(&map_a, &map_b, &p.pose) {
            PairLookup::Crossing(found) => assert_eq!(Some(found), pair, "{name}"),
            PairLookup::Apart => {
                assert!(pair.is_none(), "{name}");
                apart += 1;
                apart_colliding += usize::from(truth);
            }
            PairLookup::Undecided => assert!(pair.is_none(), "{name}"),
        }
        assert!(
            !(one_way || pair.is_some()) || truth,
            "{name}: certified at offset {offset} without a collision"
        );
        // The sample found inside is inside (by exact parity, where the mesh is a closed
        // manifold: `contains_point` says nothing of other meshes).
        match pair {
            Some(PairCrossing::SecondInFirst(c)) if a.is_closed() => {
                assert!(contains_point(a, c.inside_point), "{name} at {offset}");
                assert!(c.depth > 0.0);
            }
            Some(PairCrossing::FirstInSecond(c)) if b.is_closed() => {
                assert!(contains_point(b, c.inside_point), "{name} at {offset}");
                assert!(c.depth > 0.0);
            }
            _ => {}
        }
        if offset < -0.03 {
            deep += 1;
            certified += usize::from(pair.is_some());
        }
    }
    println!("{name}: {apart_colliding} of {apart} poses found apart collide");
    // Near-contact poses are about half short of contact: some are found apart.
    assert!(apart > 0, "{name}: no pose found apart");
    assert!(
        apart_colliding * 2 <= apart,
        "{name}: {apart_colliding} of {apart} poses found apart collide"
    );
    (certified, deep)
}

#[test]
fn the_certificate_is_sound_and_settles_most_deep_overlaps_on_generated_meshes() {
    let ball = generate::icosphere(1.0, 3);
    let pair = TriMesh::merged(&[
        ball.clone(),
        ball.translated(Vec3::new(3.0, 0.0, 0.0)).unwrap(),
    ])
    .unwrap();
    let meshes = [
        ("icosphere", CollisionMesh::new(ball.clone())),
        (
            "torus",
            CollisionMesh::new(generate::torus(1.0, 0.3, 48, 16)),
        ),
        ("cuboid", CollisionMesh::new(generate::cuboid(Vec3::ONE, 3))),
        // Two components: the samples come from one, the other may be anywhere.
        ("two balls", CollisionMesh::new(pair)),
    ];
    for (name, mesh) in &meshes {
        let (certified, deep) = certificate_is_sound(name, mesh, mesh, 60);
        println!("{name}: {certified} of {deep} deep overlaps certified");
        assert!(deep >= 10, "{name}: {deep} deep poses");
        assert!(
            certified * 10 >= deep * 6,
            "{name}: only {certified} of {deep} deep overlaps certified"
        );
    }
    // Different meshes, both ways round.
    let (ball, torus) = (&meshes[0].1, &meshes[1].1);
    certificate_is_sound("icosphere-torus", ball, torus, 40);
    certificate_is_sound("torus-icosphere", torus, ball, 40);
}

#[test]
fn the_certificate_is_sound_on_the_shared_meshes() {
    // Closed (exact map) and open or non-manifold (approximate map) meshes alike: a few poses
    // each keep the suite quick; the report checks hundreds.
    for file in [
        "bunny.obj",
        "dragon_50k.obj",
        "stanford-bunny.obj",
        "ogre.obj",
    ] {
        let Some(path) = common::shared_mesh(file) else {
            return;
        };
        let mesh = CollisionMesh::new(TriMesh::from_obj(&path).expect("shared mesh loads"));
        let (certified, deep) = certificate_is_sound(file, &mesh, &mesh, 24);
        println!("{file}: {certified} of {deep} deep overlaps certified");
        assert!(certified * 2 >= deep, "{file}: {certified} of {deep}");
    }
}

/// A ball with one vertex pulled out into a long thin spike: closed, its tip one vertex among
/// thousands, which evenly spread samples almost never include.
fn spiky_ball() -> (TriMesh, u32) {
    let ball = generate::icosphere(1.0, 4);
    let mut positions = ball.positions().to_vec();
    let tip = (0..positions.len())
        .max_by(|&i, &j| positions[i].x.total_cmp(&positions[j].x))
        .expect("vertices");
    positions[tip] = Vec3::new(2.5, 0.0, 0.0);
    let mesh = TriMesh::new(positions, ball.triangles().to_vec()).expect("valid mesh");
    (mesh, tip as u32)
}

#[test]
fn the_leading_samples_settle_a_spike_that_the_spread_samples_miss() {
    let (spiky, tip) = spiky_ball();
    let spiky = CollisionMesh::new(spiky);
    let ball = CollisionMesh::new(generate::icosphere(1.0, 3));
    let (map_spiky, map_ball) = (
        InteriorMap::build(&spiky, 64, 128),
        InteriorMap::build(&ball, 64, 128),
    );
    assert!(map_spiky.is_exact() && map_ball.is_exact());
    // The spike's tip 0.3 into the ball, the spiky ball's body well clear of it.
    let pose = Pose::from_translation(Vec3::new(-3.2, 0.0, 0.0));
    let mut ws = QueryWorkspace::new();
    assert!(intersects(&ball, &Pose::IDENTITY, &spiky, &pose, &mut ws));
    // Only the tip and the spike's shaft near it are inside: evenly spread samples miss them.
    let inside: Vec<usize> = (0..spiky.mesh().vertex_count())
        .filter(|&v| contains_point(&ball, pose.transform_point(spiky.mesh().positions()[v])))
        .collect();
    assert_eq!(inside, vec![tip as usize]);
    match InteriorMap::certify_pair(&map_ball, &map_spiky, &pose) {
        Some(PairCrossing::SecondInFirst(c)) => {
            assert_eq!(c.vertex, tip);
            assert!(c.exact && (c.inside_point - Vec3::new(-0.7, 0.0, 0.0)).length() < 1e-4);
        }
        other => panic!("the spike's tip is the spiky ball's leading vertex: {other:?}"),
    }
    // The other way round, the same crossing, from the first mesh's side.
    match InteriorMap::certify_pair(&map_spiky, &map_ball, &pose.inverse()) {
        Some(PairCrossing::FirstInSecond(c)) => assert_eq!(c.vertex, tip),
        other => panic!("{other:?}"),
    }
    // And the ADB query settles it by the certificate.
    let (tree_ball, tree_spiky) = (AdbTree::new(ball), AdbTree::new(spiky));
    let out = adb_intersects(
        &tree_ball,
        &Pose::IDENTITY,
        &tree_spiky,
        &pose,
        &AdbQuery::default(),
        &mut AdbWorkspace::new(),
    );
    assert!(out.collides && out.interpenetration.is_some_and(|c| c.vertex == tip));
    // Pulled back so that the tip stops short of the ball: nothing certified.
    let short = Pose::from_translation(Vec3::new(-3.6, 0.0, 0.0));
    assert!(!intersects(
        tree_ball.collision_mesh(),
        &Pose::IDENTITY,
        tree_spiky.collision_mesh(),
        &short,
        &mut ws
    ));
    assert_eq!(
        InteriorMap::certify_pair(&map_ball, &map_spiky, &short),
        None
    );
}

#[test]
fn the_adb_query_reports_the_certificate_and_its_confidence() {
    let ball = AdbTree::new(CollisionMesh::new(generate::icosphere(1.0, 3)));
    let deep = Pose::new(Vec3::new(1.2, 0.1, 0.0), Quat::from_rotation_y(0.3));
    let mut ws = AdbWorkspace::new();
    let query = AdbQuery::default();
    let out = adb_intersects(&ball, &Pose::IDENTITY, &ball, &deep, &query, &mut ws);
    let cert = out
        .interpenetration
        .expect("a deep overlap of closed balls is certified");
    assert!(out.collides && cert.exact);
    assert_eq!(out.probability, 1.0);
    // Settled before any node pair below the roots.
    assert_eq!(out.node_pairs_visited, 1);
    let w = out.witness.expect("a certified answer has a witness");
    assert!(w.triangles.is_none());
    assert!((w.normal.length() - 1.0).abs() < 1e-5);
    // The witness point is the sample found inside: a vertex of one ball inside the other.
    let (da, db) = (w.point.length(), (w.point - deep.translation).length());
    assert!(
        da.min(db) < 1.0 && (da.max(db) - 1.0).abs() < 1e-3,
        "{da} {db}"
    );

    // Without the certificate the same pose is answered by the traversal, the same way.
    let off = AdbQuery {
        interior_after: None,
        ..AdbQuery::default()
    };
    let plain = adb_intersects(&ball, &Pose::IDENTITY, &ball, &deep, &off, &mut ws);
    assert!(plain.collides && plain.interpenetration.is_none() && plain.node_pairs_visited > 1);

    // Tried after some pops instead: a query that has not settled by then is settled there.
    let later = AdbQuery {
        interior_after: Some(3),
        ..AdbQuery::default()
    };
    let out = adb_intersects(&ball, &Pose::IDENTITY, &ball, &deep, &later, &mut ws);
    assert!(out.collides);
    if out.interpenetration.is_some() {
        assert!(out.node_pairs_visited > 1);
    }

    // A tree built without a map never certifies.
    let options = AdbBuildOptions {
        interior_resolution: 0,
        ..AdbBuildOptions::default()
    };
    let bare = AdbTree::build_with(CollisionMesh::new(generate::icosphere(1.0, 3)), options);
    assert!(bare.interior().is_none());
    let out = adb_intersects(&bare, &Pose::IDENTITY, &bare, &deep, &query, &mut ws);
    assert!(out.collides && out.interpenetration.is_none());

    // An open mesh's map is approximate: its certificate's confidence is measured at build
    // (the lower 95 % bound on how often it was right on training poses), and it settles a
    // query only where that reaches p_min.
    let full = generate::icosphere(1.0, 3);
    let open = TriMesh::new(
        full.positions().to_vec(),
        full.triangles()[..full.triangle_count() - 8].to_vec(),
    )
    .expect("valid mesh");
    let open = AdbTree::new(CollisionMesh::new(open));
    let map = open.interior().expect("built with a map");
    assert!(!map.is_exact());
    let measured = map.certificate_confidence();
    let mut remeasured = map.clone();
    let found = remeasured
        .measure_certificate(open.collision_mesh(), 400, 5)
        .expect("an open map is measured");
    println!("open ball: {found:?}, confidence at build {measured}");
    assert!(
        found.certified > 50 && found.correct <= found.certified,
        "{found:?}"
    );
    assert_eq!(remeasured.certificate_confidence(), found.confidence);
    assert!(measured > 0.9 && measured < 1.0, "{measured}");
    for p_min in [measured, 0.99, 1.0] {
        let query = AdbQuery {
            p_min,
            ..AdbQuery::default()
        };
        let out = adb_intersects(&open, &Pose::IDENTITY, &open, &deep, &query, &mut ws);
        assert!(out.collides);
        if measured >= p_min {
            let cert = out
                .interpenetration
                .expect("the open ball's deep overlap is certified");
            assert!(!cert.exact);
            assert_eq!(out.probability, measured);
        } else {
            assert!(out.interpenetration.is_none(), "p_min {p_min}");
        }
    }
    // Without the measurement, an open mesh's certificate never settles a query.
    let unmeasured = AdbTree::build_with(
        open.collision_mesh().clone(),
        AdbBuildOptions {
            certificate_poses: 0,
            ..AdbBuildOptions::default()
        },
    );
    assert_eq!(unmeasured.interior().unwrap().certificate_confidence(), 0.0);
    let lenient = AdbQuery {
        p_min: 0.0,
        ..AdbQuery::default()
    };
    let out = adb_intersects(
        &unmeasured,
        &Pose::IDENTITY,
        &unmeasured,
        &deep,
        &lenient,
        &mut ws,
    );
    assert!(out.interpenetration.is_none());
}

#[test]
fn the_certificate_is_deterministic() {
    let mesh = CollisionMesh::new(generate::torus(1.0, 0.3, 48, 16));
    let build = || InteriorMap::build(&mesh, 64, 128);
    let (m1, m2) = (build(), build());
    assert_eq!(m1.classified_voxels(), m2.classified_voxels());
    for p in near_contact_poses(&mesh, &mesh, 30, 0.15, 5) {
        assert_eq!(m1.certify(&m1, &p.pose), m2.certify(&m2, &p.pose));
        assert_eq!(
            InteriorMap::certify_pair(&m1, &m1, &p.pose),
            InteriorMap::certify_pair(&m2, &m2, &p.pose)
        );
    }
}

//! The time-critical continuous query over ADB-trees (`ccd::adb_time_of_impact`) against the
//! exact continuous query: without a budget it is the exact answer; the conservative variant
//! never misses a contact at any budget and never reports one later than it happens; the
//! estimating variant's confidence is a probability, 1 only for contacts it found, and its
//! answers are reproducible.
use glam::{Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::adb::{AdbTree, Budget};
use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::ccd::{
    CcdError, CcdOptions, CcdWorkspace, ContinuousAdbQuery, RigidMotion, SweptConfidence,
    TimeOfImpact, adb_time_of_impact, time_of_impact,
};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::generate;

/// Random rigid motions of pairs of generated meshes: shots through a thin wall, turning bars,
/// balls passing each other; a third touch during the step, some at its start.
fn cases() -> Vec<(usize, usize, RigidMotion, RigidMotion)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(23);
    let v3 = |rng: &mut Xoshiro256PlusPlus, s: f32| {
        Vec3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    };
    let rot = |rng: &mut Xoshiro256PlusPlus, max: f32| {
        Quat::from_axis_angle(
            v3(rng, 1.0).normalize_or(Vec3::X),
            rng.random_range(0.0..max),
        )
    };
    (0..90)
        .map(|k| {
            let (i, j) = (k % 3, (k / 3) % 3);
            // A third of the cases do not turn (the frame of a still mesh), the rest do.
            let turn = if k % 3 == 0 { 0.0 } else { 0.8 };
            let ma = RigidMotion::new(
                Pose::new(v3(&mut rng, 2.5), rot(&mut rng, 1.0)),
                Pose::new(v3(&mut rng, 2.5), rot(&mut rng, 1.0)),
            );
            let still = rot(&mut rng, 3.0);
            let mb = RigidMotion::new(
                Pose::new(v3(&mut rng, 0.5), still),
                Pose::new(v3(&mut rng, 0.5), still * rot(&mut rng, turn + 1e-3)),
            );
            (i, j, ma, mb)
        })
        .collect()
}

/// The exact continuous query's answer.
fn exact_time(
    a: &AdbTree,
    ma: &RigidMotion,
    b: &AdbTree,
    mb: &RigidMotion,
    ws: &mut CcdWorkspace,
) -> Option<TimeOfImpact> {
    let options = CcdOptions::default();
    time_of_impact(a.collision_mesh(), ma, b.collision_mesh(), mb, &options, ws).unwrap()
}

fn trees() -> Vec<AdbTree> {
    [
        generate::icosphere(0.4, 3),
        generate::cuboid(Vec3::new(0.05, 1.2, 1.2), 6),
        generate::torus(0.6, 0.15, 32, 12),
    ]
    .into_iter()
    .map(|m| AdbTree::new(CollisionMesh::new(m)))
    .collect()
}

#[test]
fn without_a_budget_it_is_the_exact_continuous_query() {
    let trees = trees();
    let mut ws = CcdWorkspace::new();
    let (mut hits, mut misses) = (0, 0);
    for (k, (i, j, ma, mb)) in cases().into_iter().enumerate() {
        let (a, b) = (&trees[i], &trees[j]);
        let exact = exact_time(a, &ma, b, &mb, &mut ws);
        let out =
            adb_time_of_impact(a, &ma, b, &mb, &ContinuousAdbQuery::default(), &mut ws).unwrap();
        assert!(out.settled && !out.budget_exhausted, "case {k}");
        assert_eq!(out.collides, exact.is_some(), "case {k}");
        assert_eq!(out.time, exact.map(|h| h.time), "case {k}");
        assert_eq!(out.impact, exact, "case {k}");
        assert_eq!(out.probability, if out.collides { 1.0 } else { 0.0 });
        if out.collides { hits += 1 } else { misses += 1 }
    }
    assert!(hits >= 15 && misses >= 15, "{hits} hits, {misses} misses");
}

#[test]
fn the_conservative_query_never_misses_and_is_never_late_at_any_budget() {
    let trees = trees();
    let mut ws = CcdWorkspace::new();
    let (mut cut, mut apart_early, mut crossings) = (0, 0, 0);
    for (k, (i, j, ma, mb)) in cases().into_iter().enumerate() {
        let (a, b) = (&trees[i], &trees[j]);
        let exact = exact_time(a, &ma, b, &mb, &mut ws);
        crossings += exact.is_some() as usize;
        for budget in [1, 3, 10, 30, 100, 300] {
            let query = ContinuousAdbQuery::conservative(Budget::NodePairs(budget));
            let out = adb_time_of_impact(a, &ma, b, &mb, &query, &mut ws).unwrap();
            assert!(out.node_pairs_visited <= budget, "case {k}: {out:?}");
            cut += out.budget_exhausted as usize;
            if let Some(hit) = exact {
                assert!(out.collides, "case {k}, budget {budget}: missed {hit:?}");
                let t = out.time.expect("a time with a collision");
                assert!(
                    t <= hit.time,
                    "case {k}, budget {budget}: {t} after {}",
                    hit.time
                );
            } else if !out.collides {
                // Settled apart within the budget: the exact answer.
                assert!(out.settled, "case {k}");
                apart_early += 1;
            }
            if out.settled {
                assert_eq!(out.collides, exact.is_some(), "case {k}");
            }
        }
    }
    // The budgets do cut searches short, and some pairs are proved apart within them.
    assert!(
        cut > 100 && apart_early > 20 && crossings > 15,
        "{cut} {apart_early} {crossings}"
    );
}

#[test]
fn the_estimate_is_a_probability_certain_only_for_contacts_found_and_reproducible() {
    let trees = trees();
    let mut ws = CcdWorkspace::new();
    let mut estimated = 0;
    for (k, (i, j, ma, mb)) in cases().into_iter().enumerate() {
        let (a, b) = (&trees[i], &trees[j]);
        let query = ContinuousAdbQuery::with_budget(Budget::NodePairs(20));
        let out = adb_time_of_impact(a, &ma, b, &mb, &query, &mut ws).unwrap();
        let again = adb_time_of_impact(a, &ma, b, &mb, &query, &mut ws).unwrap();
        assert_eq!(out, again, "case {k}");
        assert!((0.0..=1.0).contains(&out.probability), "case {k}");
        if out.probability == 1.0 {
            assert!(out.impact.is_some(), "case {k}: certain without a contact");
        }
        if !out.settled && out.impact.is_none() {
            estimated += 1;
            assert!(out.probability < 1.0);
            assert_eq!(out.collides, out.probability >= 0.5);
            let w = out.witness.expect("a witness for the pairs left");
            assert!((0.0..=1.0).contains(&w.time) && w.normal.is_normalized());
            assert!(out.frontier_pairs > 0);
            // The swept answer model's input, and the combined estimates it replaces.
            let f = out.frontier.expect("what the search left");
            assert_eq!(f.pairs, out.frontier_pairs);
            assert!(f.visited == out.node_pairs_visited && f.earliest <= f64::from(w.time) + 1e-6);
            assert!((0.0..=1.0).contains(&f.raw_confidence) && f.max_probability <= 1.0);
            let combined = ContinuousAdbQuery {
                confidence: SweptConfidence::Combined,
                ..query.clone()
            };
            let raw = adb_time_of_impact(a, &ma, b, &mb, &combined, &mut ws).unwrap();
            assert_eq!(raw.probability, f.raw_confidence, "case {k}");
            assert_eq!(raw.frontier, out.frontier, "case {k}");
        } else {
            assert!(out.frontier.is_none(), "case {k}");
        }
    }
    assert!(estimated > 10, "{estimated}");
}

#[test]
fn a_pose_that_is_not_finite_is_a_typed_error() {
    let trees = trees();
    let bad = RigidMotion::new(
        Pose::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
        Pose::IDENTITY,
    );
    let still = RigidMotion::still(Pose::IDENTITY);
    let out = adb_time_of_impact(
        &trees[0],
        &bad,
        &trees[1],
        &still,
        &ContinuousAdbQuery::default(),
        &mut CcdWorkspace::new(),
    );
    assert!(matches!(
        out,
        Err(CcdError::InvalidPose {
            which: "first",
            end: "start",
            ..
        })
    ));
}

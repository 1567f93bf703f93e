//! Runtime input the ECS must survive: infinite poses and vertices, a collider swapped in the
//! middle of a contact (rigid and tracked), and a tracked deformable that turns bad: the bad
//! entity is reported and skipped, the rest go on, and events stay consistent.
mod plugin_support;

use bevy_app::App;
use bevy_ecs::entity::Entity;
use plugin_support::*;
use stochastic_collision::adb::{Decision, Order};
use stochastic_collision::ecs::{
    ColliderTable, CollisionErrorKind, Method, PairOutcome, PairTable, TrackingState,
};
use stochastic_collision::prelude::*;

#[test]
fn infinite_pose_is_an_error_for_that_entity_only() {
    let mut app = app();
    let ball = ball(1.0);
    let a = spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball.clone(), at(1.5, 0.0, 0.0)));
    let c = spawn(&mut app, (ball, at(20.0, 0.0, 0.0)));
    app.update();
    app.world_mut()
        .get_mut::<ColliderPose>(c)
        .unwrap()
        .0
        .translation
        .x = f32::INFINITY;
    for _ in 0..3 {
        app.update();
    }
    let l = log(&app);
    assert_eq!(l.errors.len(), 1);
    assert_eq!(l.errors[0].entity, c);
    assert!(matches!(
        l.errors[0].kind,
        CollisionErrorKind::InvalidPose { .. }
    ));
    assert_eq!(l.started, vec![pair(a, b)]);
    assert!(l.ended.is_empty());
}

/// The answer of the first pair of the table.
fn first_outcome(app: &App) -> PairOutcome {
    let table = app.world().resource::<PairTable>();
    table.outcomes().next().expect("a pair").clone()
}

/// Two balls at rest, touching, after a few runs (their contact started once).
fn touching_balls(fidelity: Fidelity) -> (App, Entity, Entity) {
    let mut app = app();
    let a = spawn(&mut app, (ball(1.0), at(0.0, 0.0, 0.0), fidelity));
    let b = spawn(&mut app, (ball(1.0), at(1.5, 0.0, 0.0), fidelity));
    for _ in 0..4 {
        app.update();
    }
    assert_eq!(log(&app).started, vec![pair(a, b)], "{fidelity:?}");
    (app, a, b)
}

#[test]
fn a_scene_at_rest_keeps_its_answers_until_a_fidelity_or_the_configuration_changes() {
    let (mut app, a, b) = touching_balls(Fidelity::Adb { p_min: 0.99 });
    let outcomes = |app: &App| {
        app.world()
            .resource::<PairTable>()
            .outcomes()
            .cloned()
            .collect::<Vec<_>>()
    };
    let run = |app: &App| app.world().resource::<CollisionDiagnostics>().frame;
    let worked_on = |app: &App| app.world().resource::<PairTable>().active_pairs();
    // At rest: the pair is not worked on; its answer (from the run it was tested in) stands,
    // no contact is sent again, no event.
    let rest = outcomes(&app);
    assert_eq!(rest.len(), 1);
    assert!(rest[0].collides && rest[0].method == Method::Adb);
    let contacts = log(&app).contacts.len();
    for _ in 0..3 {
        app.update();
        assert_eq!(outcomes(&app), rest);
        assert_eq!(worked_on(&app), 0);
    }
    assert!(rest[0].run < run(&app));
    assert_eq!(log(&app).contacts.len(), contacts);
    assert_eq!(log(&app).started, vec![pair(a, b)]);
    assert!(log(&app).ended.is_empty());
    // A fidelity changed alone (nothing moves): the pair is answered by its new fidelity (a
    // pair's is the more accurate of its two).
    app.world_mut().entity_mut(a).insert(Fidelity::Exact);
    app.update();
    assert_eq!(outcomes(&app)[0].method, Method::Exact);
    assert_eq!(outcomes(&app)[0].run, run(&app));
    app.world_mut()
        .entity_mut(a)
        .insert(Fidelity::Adb { p_min: 0.99 });
    app.update();
    let tested = run(&app);
    assert_eq!(outcomes(&app)[0].method, Method::Adb);
    for _ in 0..3 {
        app.update();
    }
    assert_eq!(outcomes(&app)[0].run, tested, "not worked on again");
    // The configuration changed (the evidence an ADB query needs): answered anew, then left.
    app.world_mut().resource_mut::<CollisionConfig>().k_min = 4;
    app.update();
    assert_eq!(outcomes(&app)[0].method, Method::Adb);
    assert_eq!(outcomes(&app)[0].run, run(&app));
    app.update();
    assert_eq!(worked_on(&app), 0);
    // A fidelity for colliders without one: planned again.
    app.world_mut().entity_mut(a).remove::<Fidelity>();
    app.world_mut().entity_mut(b).remove::<Fidelity>();
    app.world_mut()
        .resource_mut::<CollisionConfig>()
        .default_fidelity = Fidelity::Bounds;
    app.update();
    assert_eq!(outcomes(&app)[0].method, Method::Bounds);
    // Still one contact interval throughout.
    assert_eq!(log(&app).started, vec![pair(a, b)]);
    assert!(log(&app).ended.is_empty());
}

#[test]
fn swapping_a_collider_mid_contact_ends_and_restarts_consistently() {
    // Rigid pairs at rest are answered from memory (cached) until a pose or the geometry
    // changes: the swap itself must count as a change.
    for fidelity in [
        Fidelity::Exact,
        Fidelity::Adb { p_min: 0.99 },
        Fidelity::Tracking {
            pairs_per_frame: 16,
        },
    ] {
        let (mut app, a, b) = touching_balls(fidelity);
        // A smaller mesh no longer reaches the other: the contact ends, once.
        app.world_mut().entity_mut(b).insert(ball(0.2));
        for _ in 0..3 {
            app.update();
        }
        assert_eq!(log(&app).ended, vec![pair(a, b)], "{fidelity:?}");
        assert!(!app.world().get::<TouchingEntities>(a).unwrap().contains(b));
        // A larger one reaches it again: started again, once.
        app.world_mut().entity_mut(b).insert(ball(1.0));
        for _ in 0..3 {
            app.update();
        }
        let l = log(&app);
        assert_eq!(l.started, vec![pair(a, b), pair(a, b)], "{fidelity:?}");
        assert!(l.errors.is_empty());
        for c in &l.contacts {
            assert!(c.point.is_finite() && c.normal.is_finite() && c.depth.is_finite());
        }
    }
}

#[test]
fn a_tracked_deformable_with_an_infinite_vertex_is_skipped_and_recovers() {
    let mut app = app();
    let tracked = Fidelity::Tracking {
        pairs_per_frame: 16,
    };
    let cloth_mesh = generate::cloth_grid(1.0, 1.0, 12, 12);
    let cloth = spawn(
        &mut app,
        (
            Deformable::new(cloth_mesh.clone()),
            SelfCollision,
            tracked,
            at(0.0, 0.0, 0.0),
        ),
    );
    let a = spawn(&mut app, (ball(1.0), at(10.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball(1.0), at(11.5, 0.0, 0.0)));
    app.update();
    app.world_mut()
        .get_mut::<Deformable>(cloth)
        .unwrap()
        .positions_mut()[5]
        .y = f32::NEG_INFINITY;
    for _ in 0..3 {
        app.update();
    }
    let l = log(&app);
    assert_eq!(l.errors.len(), 1);
    assert_eq!(l.errors[0].entity, cloth);
    assert_eq!(l.started, vec![pair(a, b)]);
    // While it is bad, nothing is tracked for it.
    assert!(
        app.world()
            .resource::<TrackingState>()
            .tracker(cloth, cloth)
            .is_none()
    );
    // Fixed: tracked again, no contact on a flat sheet, no further error.
    app.world_mut()
        .get_mut::<Deformable>(cloth)
        .unwrap()
        .positions_mut()
        .copy_from_slice(cloth_mesh.positions());
    for _ in 0..3 {
        app.update();
    }
    let l = log(&app);
    assert_eq!(l.errors.len(), 1);
    assert_eq!(l.started, vec![pair(a, b)]);
    assert!(
        app.world()
            .resource::<TrackingState>()
            .tracker(cloth, cloth)
            .is_some()
    );
}

#[test]
fn a_collider_swapped_at_rest_is_tested_again_not_answered_from_memory() {
    // Two balls at rest, touching: after a few runs their pair is answered from memory (neither
    // pose changes). Then the second gets a mesh that stays inside the same boxes (the broad
    // phase keeps the pair) but no longer touches the first: the contact must end.
    let tucked_away = {
        let small = generate::icosphere(0.2, 2);
        let offset = Vec3::new(-0.6, 0.75, 0.75);
        let moved: Vec<Vec3> = small.positions().iter().map(|&p| p + offset).collect();
        MeshCollider::new(TriMesh::new(moved, small.triangles().to_vec()).unwrap())
    };
    for fidelity in [Fidelity::Exact, Fidelity::Adb { p_min: 0.99 }] {
        let (mut app, a, b) = touching_balls(fidelity);
        app.world_mut().entity_mut(b).insert(tucked_away.clone());
        for _ in 0..3 {
            app.update();
        }
        let frame = app.world().resource::<ColliderTable>();
        let (ba, bb) = (frame.get(a).unwrap().aabb, frame.get(b).unwrap().aabb);
        assert!(ba.intersects(&bb), "the boxes still overlap");
        assert_eq!(log(&app).ended, vec![pair(a, b)], "{fidelity:?}");
    }
}

/// Node pairs the ADB query of two unit balls `distance` apart visited in one unbudgeted frame
/// under `config` (which must leave the pair to ADB, and the balls colliding).
fn adb_node_pairs_of_two_balls(config: CollisionConfig, distance: f32) -> u64 {
    let config = CollisionConfig {
        budget: FrameBudget::Unlimited,
        ..config
    };
    let mut app = app_with(config.clone(), 1);
    spawn(&mut app, (ball(1.0), at(0.0, 0.0, 0.0)));
    spawn(&mut app, (ball(1.0), at(distance, 0.0, 0.0)));
    app.update();
    let o = first_outcome(&app);
    assert!(o.method == Method::Adb && o.collides, "{config:?}: {o:?}");
    o.node_pairs
}

#[test]
fn the_configured_adb_interior_is_the_one_the_queries_use() {
    // Deeply overlapping balls: with the interpenetration certificate (the default) the pair is
    // settled before any node pair below the roots, its contact the sample found inside, as
    // deep as the sample lies and pushing the second ball away along +x; without it, the
    // traversal answers the same after many node pairs.
    let with = CollisionConfig {
        budget: FrameBudget::Unlimited,
        ..Default::default()
    };
    let mut app = app_with(with.clone(), 1);
    spawn(&mut app, (ball(1.0), at(0.0, 0.0, 0.0)));
    spawn(&mut app, (ball(1.0), at(1.0, 0.0, 0.0)));
    app.update();
    let o = first_outcome(&app);
    assert!(
        o.method == Method::Adb && o.collides && o.probability == 1.0,
        "{o:?}"
    );
    assert_eq!(o.node_pairs, 1);
    let c = o.contacts[0];
    assert!(
        c.triangles.is_none() && c.depth > 0.0 && c.depth < 1.0,
        "{c:?}"
    );
    let centre = |e: Entity| app.world().get::<ColliderPose>(e).unwrap().0.translation;
    let apart = (centre(o.b) - centre(o.a)).normalize();
    assert!(c.normal.dot(apart) > 0.9, "{c:?} against {apart}");
    let without = CollisionConfig {
        adb_interior: false,
        ..with
    };
    assert!(adb_node_pairs_of_two_balls(without, 1.0) > 1);
}

#[test]
fn the_configured_adb_decision_is_the_one_the_queries_use() {
    // Deeply overlapping balls, estimated leaves: the evidence decision stops as soon as a few
    // confident pairs carry `p_min`, the confidence decision waits for `k_min` of them.
    let visited = |adb_decision: Decision| {
        // The decision alone: no interpenetration certificate settles the pose first.
        let config = CollisionConfig {
            adb_exact_leaves: false,
            adb_decision,
            adb_interior: false,
            ..Default::default()
        };
        adb_node_pairs_of_two_balls(config, 1.0)
    };
    let (confidence, evidence) = (visited(Decision::Confidence), visited(Decision::Evidence));
    assert!(evidence < confidence, "{evidence} ≥ {confidence}");
}

#[test]
fn the_configured_adb_order_is_the_one_the_queries_use() {
    // Balls just past first contact, exact leaves: evidence first dives to an intersecting
    // triangle pair after fewer node pairs than best first, which expands every shallower
    // pair that looks more likely than the leaves first.
    let visited = |adb_order: Order| {
        let config = CollisionConfig {
            adb_order,
            adb_interior: false,
            ..Default::default()
        };
        adb_node_pairs_of_two_balls(config, 1.95)
    };
    let (evidence_first, best_first) = (visited(Order::EvidenceFirst), visited(Order::BestFirst));
    assert!(
        evidence_first < best_first,
        "{evidence_first} ≥ {best_first}"
    );
}

#[test]
fn the_configured_adb_collide_at_decides_unsettled_answers() {
    // Balls a hair apart along a diagonal (so that their boxes overlap), estimated leaves:
    // the traversal leaves its leaf pairs to their
    // estimates, so the answer is a confidence strictly between 0 and 1, and the configured
    // threshold alone decides it.
    let outcome = |adb_collide_at: f64| {
        let config = CollisionConfig {
            budget: FrameBudget::Unlimited,
            adb_exact_leaves: false,
            adb_collide_at,
            ..Default::default()
        };
        let mut app = app_with(config, 1);
        spawn(&mut app, (ball(1.0), at(0.0, 0.0, 0.0)));
        spawn(&mut app, (ball(1.0), at(1.42, 1.42, 0.0)));
        app.update();
        first_outcome(&app)
    };
    let (eager, strict) = (outcome(1e-6), outcome(1.0));
    assert_eq!(eager.method, Method::Adb);
    assert!(
        eager.probability > 0.0 && eager.probability < 1.0,
        "{eager:?}"
    );
    assert_eq!(eager.probability, strict.probability);
    assert!(eager.collides && !strict.collides, "{eager:?} {strict:?}");
}

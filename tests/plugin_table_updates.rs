//! The plugin's tables follow every change the ECS makes to a collider, however rarely its
//! schedule runs: removals seen frames later, a pose removed alone, a deformable mesh that
//! moves while it is refitted, pairs at rest that need no work. (An exact pair answered from
//! memory after its mesh was swapped: `narrow_phase::memory`'s unit tests.)
mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use plugin_support::*;
use stochastic_collision::ecs::{ColliderTable, PairTable};
use stochastic_collision::prelude::*;

#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
struct CollisionStep;

/// The plugin in a schedule that runs only when the test says so (as `FixedPostUpdate` does
/// not run in frames without a fixed step).
fn app_run_by_hand() -> App {
    let mut app = App::new();
    app.add_plugins(
        StochasticCollisionPlugin::in_schedule(CollisionStep).with_config(CollisionConfig {
            budget: FrameBudget::Unlimited,
            ..Default::default()
        }),
    )
    .init_resource::<EventLog>()
    .add_systems(Last, log_events);
    app
}

fn step(app: &mut App) {
    app.world_mut().run_schedule(CollisionStep);
    app.update();
}

#[test]
fn a_removal_in_a_frame_without_a_collision_run_is_not_lost() {
    for what in ["despawn", "collider", "pose"] {
        let mut app = app_run_by_hand();
        let a = spawn(&mut app, (ball(1.0), at(0.0, 0.0, 0.0)));
        let b = spawn(&mut app, (ball(1.0), at(1.5, 0.0, 0.0)));
        step(&mut app);
        assert_eq!(log(&app).started, vec![pair(a, b)], "{what}");
        match what {
            "despawn" => {
                app.world_mut().despawn(b);
            }
            "collider" => {
                app.world_mut().entity_mut(b).remove::<MeshCollider>();
            }
            _ => {
                app.world_mut().entity_mut(b).remove::<ColliderPose>();
            }
        }
        // Frames go by (the ECS's removal buffers turn over) before the next collision run.
        for _ in 0..4 {
            app.update();
        }
        step(&mut app);
        assert_eq!(
            log(&app).ended,
            vec![pair(a, b)],
            "{what}: the contact ends"
        );
        let table = app.world().resource::<ColliderTable>();
        assert!(table.get(b).is_none(), "{what}: b left the table");
        assert_eq!(table.len(), 1, "{what}");
        assert!(app.world().resource::<PairTable>().is_empty(), "{what}");
        let colliding = app.world().get::<TouchingEntities>(a).unwrap();
        assert!(!colliding.contains(b), "{what}");
        // And it comes back when its parts do.
        if what != "despawn" {
            app.world_mut()
                .entity_mut(b)
                .insert((ball(1.0), at(1.5, 0.0, 0.0)));
            step(&mut app);
            assert_eq!(log(&app).started, vec![pair(a, b); 2], "{what}: back");
        }
    }
}

#[test]
fn a_deformable_mesh_moved_and_refitted_in_one_run_has_its_motion() {
    let mut app = app();
    let cloth = Deformable::new(generate::cloth_grid(1.0, 1.0, 4, 4));
    let e = spawn(&mut app, (cloth, at(0.0, 0.0, 0.0), SelfCollision));
    app.update();
    for (k, remove_marker) in [(1, false), (2, true)] {
        // New positions (a refit) and a new pose in the same run; the second time the
        // self-collision marker goes too (the entity is both changed and among the removals).
        let mut entity = app.world_mut().entity_mut(e);
        for p in entity.get_mut::<Deformable>().unwrap().positions_mut() {
            p.z += 0.01;
        }
        entity.get_mut::<ColliderPose>().unwrap().0.translation.x = 0.5 * k as f32;
        if remove_marker {
            entity.remove::<SelfCollision>();
        }
        app.update();
        let table = app.world().resource::<ColliderTable>();
        let entry = table.get(e).expect("the cloth is a collider");
        assert_eq!(entry.motion, Vec3::new(0.5, 0.0, 0.0), "run {k}");
        assert_eq!(entry.self_collision, !remove_marker, "run {k}");
    }
    // At rest again: no motion.
    app.update();
    let table = app.world().resource::<ColliderTable>();
    assert_eq!(table.get(e).unwrap().motion, Vec3::ZERO);
}

#[test]
fn tracked_pairs_whose_boxes_are_apart_need_no_work_at_rest() {
    let mut app = app();
    let tracking = Fidelity::Tracking { pairs_per_frame: 8 };
    let ball = ball(1.0);
    spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0), tracking));
    let b = spawn(&mut app, (ball, at(2.6, 0.0, 0.0), tracking));
    app.update();
    // b moves close: fat boxes overlap, world boxes stay apart.
    app.world_mut()
        .get_mut::<ColliderPose>(b)
        .unwrap()
        .0
        .translation
        .x = 2.1;
    app.update();
    assert_eq!(app.world().resource::<PairTable>().len(), 1, "a pair");
    for _ in 0..3 {
        app.update();
        let pairs = app.world().resource::<PairTable>();
        assert_eq!(pairs.active_pairs(), 0, "nothing moved, nothing to do");
    }
    assert!(log(&app).started.is_empty());
}

/// A pair created while its world boxes are apart (the fat boxes overlap: a collider moved
/// towards the other) is answered in the run it is created in, not colliding, exactly for
/// exact and ADB fidelity, without a narrow-phase job; once the boxes meet it is worked on
/// as a new pair and its contact starts.
#[test]
fn a_new_pair_whose_boxes_are_apart_is_answered_without_a_job() {
    for fidelity in [
        Fidelity::Exact,
        Fidelity::Adb { p_min: 0.99 },
        Fidelity::Bounds,
    ] {
        let mut app = app_run_by_hand();
        let a = spawn(&mut app, (ball(1.0), at(0.0, 0.0, 0.0), fidelity));
        let b = spawn(&mut app, (ball(1.0), at(3.0, 0.0, 0.0), fidelity));
        step(&mut app);
        assert!(
            app.world().resource::<PairTable>().is_empty(),
            "{fidelity:?}"
        );
        // b moves towards a: its fat box (stretched along the motion) reaches a's, its world
        // box does not.
        let mut x = 3.0;
        let mut created_in = None;
        for run in 0..3 {
            x -= 0.3;
            app.world_mut()
                .get_mut::<ColliderPose>(b)
                .unwrap()
                .0
                .translation
                .x = x;
            step(&mut app);
            let pairs = app.world().resource::<PairTable>();
            if created_in.is_none() && pairs.len() == 1 {
                created_in = Some(run);
                assert_eq!(pairs.active_pairs(), 0, "{fidelity:?}: no job for it");
                let o = pairs.outcomes().next().unwrap();
                assert_eq!((o.a, o.b), (a.min(b), a.max(b)));
                assert!(!o.collides && o.probability == 0.0, "{fidelity:?}");
                assert_eq!(o.run, o.computed_run, "{fidelity:?}: answered in this run");
                let method = match fidelity {
                    Fidelity::Bounds => Method::Bounds,
                    Fidelity::Exact => Method::Exact,
                    _ => Method::Adb,
                };
                assert_eq!(o.method, method, "{fidelity:?}");
            }
        }
        assert!(created_in.is_some(), "{fidelity:?}: the pair was created");
        assert!(log(&app).started.is_empty(), "{fidelity:?}");
        // The boxes meet and the balls overlap: a new pair's work, and its contact starts.
        app.world_mut()
            .get_mut::<ColliderPose>(b)
            .unwrap()
            .0
            .translation
            .x = 1.5;
        step(&mut app);
        assert_eq!(log(&app).started, vec![pair(a, b)], "{fidelity:?}");
    }
}

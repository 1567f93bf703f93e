//! Stages run only when some entity needs them; diagnostics show idle stages as not run.
mod plugin_support;

use plugin_support::*;
use stochastic_collision::ecs::Stage;
use stochastic_collision::prelude::*;

#[test]
fn rigid_scene_runs_no_deformable_stage() {
    let mut app = app();
    let ball = ball(1.0);
    spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    app.world_mut().spawn((ball, at(1.5, 0.0, 0.0)));
    app.update();
    let d = app.world().resource::<CollisionDiagnostics>();
    for s in [
        Stage::Prepare,
        Stage::BroadPhase,
        Stage::NarrowPhase,
        Stage::Report,
    ] {
        assert!(d.stage(s).last.is_some(), "{s:?} should run");
    }
    for s in [Stage::Refit, Stage::SelfCollision, Stage::Tracking] {
        assert_eq!(d.stage(s).last, None, "{s:?} should not run");
        assert_eq!(d.stage(s).runs, 0);
    }
}

#[test]
fn deformable_with_self_collision_runs_refit_and_self_pass() {
    let mut app = app();
    // A strip folded onto itself: the two halves cross.
    let mut cloth = Deformable::new(generate::cloth_grid(2.0, 0.5, 16, 4));
    for p in cloth.positions_mut() {
        if p.x > 0.0 {
            *p = Vec3::new(-p.x + 0.05, 0.3 - 0.5 * p.x, p.z);
        }
    }
    let e = app
        .world_mut()
        .spawn((cloth, SelfCollision, at(0.0, 0.0, 0.0)))
        .id();
    app.update();
    let d = app.world().resource::<CollisionDiagnostics>();
    assert!(d.stage(Stage::Refit).last.is_some());
    assert!(d.stage(Stage::SelfCollision).last.is_some());
    assert_eq!(d.stage(Stage::Tracking).last, None);
    assert_eq!(log(&app).started, vec![(e, e)], "self-contact interval");
    assert!(
        log(&app)
            .contacts
            .iter()
            .all(|c| c.a == e && c.b == e && c.triangles.is_some())
    );
    // Nothing moved: no refit in the next run.
    app.update();
    let d = app.world().resource::<CollisionDiagnostics>();
    assert_eq!(d.stage(Stage::Refit).last, None);
    assert_eq!(d.stage(Stage::Refit).runs, 1);
    assert!(app.world().get::<TouchingEntities>(e).unwrap().is_empty());
}

#[test]
fn tracked_pairs_run_in_the_tracking_stage() {
    let mut app = app();
    let ball = ball(1.0);
    let tracked = Fidelity::Tracking { pairs_per_frame: 8 };
    let a = spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0), tracked));
    let b = spawn(&mut app, (ball, at(1.5, 0.0, 0.0)));
    app.update();
    let d = app.world().resource::<CollisionDiagnostics>();
    assert!(d.stage(Stage::Tracking).last.is_some());
    let contacts = &log(&app).contacts;
    assert!(!contacts.is_empty());
    let first = a.min(b);
    let features = app
        .world()
        .get::<stochastic_collision::ecs::FeaturePairs>(first)
        .expect("feature pairs kept on the first entity");
    assert!(!features.with(a.max(b)).is_empty());
    // Apart: the partner's feature pairs are dropped.
    app.world_mut()
        .get_mut::<ColliderPose>(b)
        .unwrap()
        .0
        .translation
        .x = 10.0;
    app.update();
    let features = app
        .world()
        .get::<stochastic_collision::ecs::FeaturePairs>(first)
        .unwrap();
    assert!(features.partners.is_empty());
}

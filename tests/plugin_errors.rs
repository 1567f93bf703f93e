//! Bad input: the entity gets one error message and is skipped, the others go on.
mod plugin_support;

use plugin_support::*;
use stochastic_collision::ecs::CollisionErrorKind;
use stochastic_collision::mesh::MeshError;
use stochastic_collision::prelude::*;

#[test]
fn nan_pose_reports_once_skips_the_entity_and_others_go_on() {
    let mut app = app();
    let ball = ball(1.0);
    let a = spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball.clone(), at(1.5, 0.0, 0.0)));
    let c = spawn(&mut app, (ball.clone(), at(10.0, 0.0, 0.0)));
    let d = spawn(&mut app, (ball, at(11.5, 0.0, 0.0)));
    app.update();
    assert_eq!(log(&app).started.len(), 2);
    app.world_mut()
        .get_mut::<ColliderPose>(c)
        .unwrap()
        .0
        .translation
        .y = f32::NAN;
    for _ in 0..3 {
        app.update();
    }
    let l = log(&app);
    assert_eq!(l.errors.len(), 1, "one error while the entity stays bad");
    assert_eq!(l.errors[0].entity, c);
    assert!(matches!(
        l.errors[0].kind,
        CollisionErrorKind::InvalidPose { .. }
    ));
    assert_eq!(l.ended, vec![pair(c, d)]);
    assert!(app.world().get::<TouchingEntities>(a).unwrap().contains(b));
    assert!(!app.world().get::<TouchingEntities>(d).unwrap().contains(c));
    // Fixed: collides again; broken again: a second error.
    app.world_mut()
        .get_mut::<ColliderPose>(c)
        .unwrap()
        .0
        .translation
        .y = 0.0;
    app.update();
    assert_eq!(log(&app).started.len(), 3);
    app.world_mut()
        .get_mut::<ColliderPose>(c)
        .unwrap()
        .0
        .rotation = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    app.update();
    assert_eq!(log(&app).errors.len(), 2);
    assert_eq!(log(&app).ended.len(), 2);
}

#[cfg(feature = "transform")]
#[test]
fn nan_global_transform_is_reported() {
    use bevy_transform::components::GlobalTransform;
    let mut app = app();
    let ball = ball(1.0);
    let a = spawn(
        &mut app,
        (ball.clone(), GlobalTransform::from_translation(Vec3::ZERO)),
    );
    let b = spawn(
        &mut app,
        (ball, GlobalTransform::from_translation(Vec3::X * 1.5)),
    );
    app.update();
    assert!(app.world().get::<TouchingEntities>(a).unwrap().contains(b));
    *app.world_mut().get_mut::<GlobalTransform>(b).unwrap() =
        GlobalTransform::from_translation(Vec3::new(f32::INFINITY, 0.0, 0.0));
    app.update();
    let l = log(&app);
    assert_eq!(l.errors.len(), 1);
    assert_eq!(l.errors[0].entity, b);
    assert_eq!(l.ended, vec![pair(a, b)]);
}

#[test]
fn nan_vertex_of_a_deformable_is_reported_and_the_rest_goes_on() {
    let mut app = app();
    let ball = ball(1.0);
    let a = spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball.clone(), at(1.5, 0.0, 0.0)));
    let cloth = spawn(
        &mut app,
        (
            Deformable::new(generate::cloth_grid(4.0, 4.0, 8, 8)),
            at(10.0, 0.0, 0.0),
        ),
    );
    let rock = spawn(&mut app, (ball, at(10.0, 0.5, 0.0)));
    app.update();
    assert_eq!(log(&app).started.len(), 2);
    app.world_mut()
        .get_mut::<Deformable>(cloth)
        .unwrap()
        .positions_mut()[3]
        .x = f32::NAN;
    app.update();
    app.update();
    let l = log(&app);
    assert_eq!(l.errors.len(), 1);
    assert_eq!(l.errors[0].entity, cloth);
    assert!(matches!(
        l.errors[0].kind,
        CollisionErrorKind::Mesh(MeshError::NonFinite { vertex: 3, .. })
    ));
    assert_eq!(l.ended, vec![pair(cloth, rock)]);
    assert!(app.world().get::<TouchingEntities>(a).unwrap().contains(b));
    assert!(
        app.world()
            .get::<Deformable>(cloth)
            .unwrap()
            .error()
            .is_some()
    );
    // Fixed: the refit accepts the positions, the contact starts again.
    app.world_mut()
        .get_mut::<Deformable>(cloth)
        .unwrap()
        .positions_mut()[3]
        .x = 0.0;
    app.update();
    assert_eq!(log(&app).started.len(), 3);
    assert!(
        app.world()
            .get::<Deformable>(cloth)
            .unwrap()
            .error()
            .is_none()
    );
}

//! The plugin as a game uses it: bevy_time's `TimePlugin` and bevy_transform's
//! `TransformPlugin`, the default `FixedPostUpdate` schedule (one fixed step per app update,
//! `Time<Fixed>` at its default 64 Hz), entities placed with `Transform`: scale, hierarchy,
//! entities spawned during the fixed step, responses written back to `Transform`, the time
//! step from `Time<Fixed>`, and the confidence that events carry.
#![cfg(feature = "transform")]
mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use bevy_time::{TimePlugin, TimeUpdateStrategy};
use bevy_transform::TransformPlugin;
use bevy_transform::components::{GlobalTransform, Transform};
use plugin_support::*;
use stochastic_collision::ecs::{ColliderTable, CollisionErrorKind, DEFAULT_STEP};
use stochastic_collision::prelude::*;

fn placed(x: f32, y: f32, z: f32) -> Transform {
    Transform::from_xyz(x, y, z)
}

fn touching(app: &App, a: Entity, b: Entity) -> bool {
    app.world().get::<TouchingEntities>(a).unwrap().contains(b)
}

#[test]
fn scale_is_honoured_uniform_and_not() {
    let mut app = game();
    let ball = ball(1.0);
    // (scale of the first ball, position of the second, whether they touch)
    let cases = [
        (Vec3::splat(2.0), Vec3::new(2.5, 0.0, 0.0), true),
        (Vec3::splat(0.5), Vec3::new(1.8, 0.0, 0.0), false),
        (Vec3::new(3.0, 1.0, 1.0), Vec3::new(3.5, 0.0, 0.0), true),
        (Vec3::new(3.0, 1.0, 1.0), Vec3::new(0.0, 2.5, 0.0), false),
        (Vec3::new(-2.0, 1.0, 1.0), Vec3::new(-2.5, 0.0, 0.0), true),
    ];
    let mut pairs = Vec::new();
    for (k, (scale, at, _)) in cases.iter().enumerate() {
        // Each case far from the others.
        let base = Vec3::new(0.0, 0.0, 20.0 * k as f32);
        let a = spawn(
            &mut app,
            (
                ball.clone(),
                Transform::from_translation(base).with_scale(*scale),
            ),
        );
        let b = spawn(
            &mut app,
            (ball.clone(), Transform::from_translation(base + *at)),
        );
        pairs.push((a, b));
    }
    steps(&mut app, 2);
    for ((a, b), (scale, at, expect)) in pairs.iter().zip(&cases) {
        assert_eq!(
            touching(&app, *a, *b),
            *expect,
            "scale {scale} against a ball at {at}"
        );
        assert_eq!(app.world().get::<ColliderScale>(*a).unwrap().0, *scale);
    }
    // Growing a ball makes it touch; the copies of one mesh at one scale share one tree.
    let (a, b) = pairs[1];
    app.world_mut().get_mut::<Transform>(a).unwrap().scale = Vec3::splat(1.0);
    steps(&mut app, 1);
    assert!(touching(&app, a, b), "unscaled, radius 1 reaches x = 1.8");
    let table = app.world().resource::<ColliderTable>();
    let tree = |e: Entity| table.get(e).unwrap().geometry.adb().unwrap() as *const _;
    assert_eq!(
        tree(pairs[2].0),
        tree(pairs[3].0),
        "same mesh, same scale: one tree"
    );
    assert_ne!(tree(pairs[0].0), tree(pairs[2].0));
}

#[test]
fn a_zero_scale_is_reported_and_the_others_go_on() {
    let mut app = game();
    let ball = ball(1.0);
    let bad = spawn(
        &mut app,
        (
            ball.clone(),
            placed(0.0, 0.0, 0.0).with_scale(Vec3::new(1.0, 0.0, 1.0)),
        ),
    );
    let a = spawn(&mut app, (ball.clone(), placed(10.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball, placed(11.5, 0.0, 0.0)));
    steps(&mut app, 2);
    let log = log(&app);
    assert_eq!(log.errors.len(), 1);
    assert_eq!(log.errors[0].entity, bad);
    assert!(matches!(
        log.errors[0].kind,
        CollisionErrorKind::InvalidScale { .. }
    ));
    assert!(touching(&app, a, b));
}

#[derive(Resource)]
struct SpawnAt(Option<Vec3>);

#[test]
fn a_collider_spawned_in_the_fixed_step_is_tested_where_it_was_placed() {
    let mut app = game();
    let ball = ball(1.0);
    let origin = spawn(&mut app, (ball.clone(), placed(0.0, 0.0, 0.0)));
    steps(&mut app, 2);
    app.insert_resource(SpawnAt(Some(Vec3::new(10.0, 0.0, 0.0))));
    app.add_systems(
        FixedUpdate,
        move |mut commands: Commands, mut at: ResMut<SpawnAt>| {
            if let Some(p) = at.0.take() {
                commands.spawn((ball.clone(), Transform::from_translation(p)));
            }
        },
    );
    for _ in 0..3 {
        app.update();
        assert!(
            log(&app).started.is_empty(),
            "never touches the ball at the origin"
        );
        assert!(
            app.world()
                .get::<TouchingEntities>(origin)
                .unwrap()
                .is_empty()
        );
    }
    assert_eq!(app.world().resource::<ColliderTable>().len(), 2);
}

#[derive(Resource)]
struct ParentAt(Entity, f32);

#[test]
fn a_child_collider_follows_its_parent_in_the_same_step() {
    let mut app = game();
    let ball = ball(1.0);
    let other = spawn(&mut app, (ball.clone(), placed(0.0, 0.0, 0.0)));
    let parent = spawn(&mut app, placed(6.0, 0.0, 0.0));
    // The child sits 0.5 to the parent's right, its parent scaled by 2 (the offset too).
    let child = app
        .world_mut()
        .spawn((ball, placed(0.5, 0.0, 0.0), ChildOf(parent)))
        .id();
    app.world_mut().get_mut::<Transform>(parent).unwrap().scale = Vec3::splat(2.0);
    steps(&mut app, 2);
    assert!(!touching(&app, other, child));
    let pose = app.world().get::<ColliderPose>(child).unwrap().0;
    assert!((pose.translation.x - 7.0).abs() < 1e-5, "{pose:?}");
    assert_eq!(
        app.world().get::<ColliderScale>(child).unwrap().0,
        Vec3::splat(2.0)
    );
    // A gameplay system in FixedUpdate moves the parent; the child is tested there in the
    // same fixed step (radius 2 at x = 1.5 + 1 reaches the ball of radius 1 at the origin).
    app.insert_resource(ParentAt(parent, 1.5));
    app.add_systems(
        FixedUpdate,
        |at: Res<ParentAt>, mut q: Query<&mut Transform>| {
            q.get_mut(at.0).unwrap().translation.x = at.1;
        },
    );
    steps(&mut app, 1);
    assert!(touching(&app, other, child), "same step");
    assert_eq!(log(&app).started, vec![pair(other, child)]);
}

/// A floor (top at y = 0) and a ball of radius 0.25 at rest 1 above it, with a velocity;
/// returns the ball.
fn floor_and_falling_ball(app: &mut App) -> Entity {
    let floor = MeshCollider::new(generate::cuboid(Vec3::new(3.0, 0.5, 3.0), 8));
    spawn(app, (floor, placed(0.0, -0.5, 0.0), Fidelity::Exact));
    spawn(
        app,
        (
            ball(0.25),
            placed(0.0, 1.0, 0.0),
            BodyVelocity(Vec3::ZERO),
            Fidelity::Exact,
        ),
    )
}

#[test]
fn responses_move_the_transform_with_the_fixed_time_step() {
    let mut app = game();
    app.add_plugins(ImpulseResponsePlugin::default());
    let ball = floor_and_falling_ball(&mut app);
    // The first update starts the clock (no fixed step yet); then one step per update.
    steps(&mut app, 2);
    let settings = *app
        .world()
        .resource::<stochastic_collision::ecs::ImpulseSettings>();
    let v = app.world().get::<BodyVelocity>(ball).unwrap().0;
    let dt = DEFAULT_STEP;
    let expected = settings.gravity.y * dt * (1.0 - settings.damping * dt);
    assert!(
        (v.y - expected).abs() < 1e-6,
        "one step of 1/64 s: {} vs {expected}",
        v.y
    );
    steps(&mut app, 120);
    let y = |app: &App| app.world().get::<Transform>(ball).unwrap().translation.y;
    let rest = y(&app);
    assert!(
        rest < 0.35 && rest > 0.15,
        "rests on the floor (top at 0), radius 0.25: {rest}"
    );
    let pose = app.world().get::<ColliderPose>(ball).unwrap().0;
    assert!(
        (pose.translation.y - rest).abs() < 1e-5,
        "the pose is the Transform's"
    );
    let drawn = app
        .world()
        .get::<GlobalTransform>(ball)
        .unwrap()
        .translation();
    assert!((drawn.y - rest).abs() < 1e-5, "what a renderer draws");
    // A rotation written by the game does not snap the body back.
    app.world_mut().get_mut::<Transform>(ball).unwrap().rotation = Quat::from_rotation_y(1.0);
    steps(&mut app, 3);
    assert!((y(&app) - rest).abs() < 0.02, "{} vs {rest}", y(&app));
}

#[test]
fn events_say_how_sure_they_are() {
    let mut app = game();
    let ball = ball(1.0);
    let a = spawn(
        &mut app,
        (ball.clone(), placed(0.0, 0.0, 0.0), Fidelity::Exact),
    );
    let b = spawn(
        &mut app,
        (ball.clone(), placed(1.5, 0.0, 0.0), Fidelity::Exact),
    );
    let c = spawn(
        &mut app,
        (ball.clone(), placed(20.0, 0.0, 0.0), Fidelity::Bounds),
    );
    let d = spawn(&mut app, (ball, placed(21.9, 0.0, 0.0), Fidelity::Bounds));
    let mut started = Vec::new();
    app.add_systems(Last, move |mut r: MessageReader<CollisionStarted>| {
        started.extend(r.read().copied());
        for e in &started {
            if (e.entity, e.other) == pair(a, b) {
                assert_eq!((e.method, e.probability), (Method::Exact, 1.0));
                assert!(e.is_certain());
            } else {
                assert_eq!((e.entity, e.other), pair(c, d));
                assert_eq!(e.method, Method::Bounds);
                assert!(!e.is_certain());
            }
        }
    });
    steps(&mut app, 2);
    assert_eq!(log(&app).started.len(), 2);
    // A despawned partner ends the contact: removed pairs end with Bounds, probability 0.
    app.world_mut().despawn(b);
    let ended = app.world_mut().register_system(
        |mut r: MessageReader<CollisionEnded>| -> Vec<CollisionEnded> {
            r.read().copied().collect()
        },
    );
    steps(&mut app, 1);
    let ended: Vec<CollisionEnded> = app.world_mut().run_system(ended).unwrap();
    assert_eq!(ended.len(), 1);
    assert_eq!(
        (ended[0].method, ended[0].probability),
        (Method::Bounds, 0.0)
    );
}

#[test]
fn a_response_plugin_in_another_schedule_is_refused_at_startup() {
    let result = std::panic::catch_unwind(|| {
        let mut app = App::new();
        app.add_plugins(StochasticCollisionPlugin::default())
            .add_plugins(ImpulseResponsePlugin::in_schedule(Update));
    });
    let message = *result.unwrap_err().downcast::<String>().unwrap();
    assert!(
        message.contains("ImpulseResponsePlugin in Update"),
        "{message}"
    );
    let result = std::panic::catch_unwind(|| {
        App::new().add_plugins(PenaltyResponsePlugin::default());
    });
    let message = *result.unwrap_err().downcast::<String>().unwrap();
    assert!(
        message.contains("add StochasticCollisionPlugin before it"),
        "{message}"
    );
    // The default takes the collision plugin's schedule, whichever it is.
    let mut app = App::new();
    app.add_plugins(StochasticCollisionPlugin::in_schedule(PostUpdate))
        .add_plugins((
            ImpulseResponsePlugin::default(),
            PenaltyResponsePlugin::default(),
        ));
    app.update();
}

#[test]
fn a_sensor_reports_contacts_and_nothing_responds_to_them() {
    let mut app = game();
    app.add_plugins(ImpulseResponsePlugin::default());
    // Thinner than the ball: one contact interval from entering to leaving (exact contact
    // is contact of surfaces, so a ball wholly inside a thick slab would not touch it).
    let slab = MeshCollider::new(generate::cuboid(Vec3::new(3.0, 0.1, 3.0), 8));
    let trigger = spawn(
        &mut app,
        (
            slab,
            placed(0.0, -0.1, 0.0),
            Fidelity::Exact,
            CollisionSensor,
        ),
    );
    let ball = spawn(
        &mut app,
        (
            ball(0.25),
            placed(0.0, 1.0, 0.0),
            BodyVelocity(Vec3::ZERO),
            Fidelity::Exact,
        ),
    );
    steps(&mut app, 90);
    // It fell into the trigger volume and through it: reported, never pushed back.
    assert_eq!(log(&app).started, vec![pair(trigger, ball)]);
    let y = app.world().get::<Transform>(ball).unwrap().translation.y;
    assert!(y < -1.5, "fell through the sensor: {y}");
    assert!(app.world().resource::<ContactQueue>().is_empty());
}

#[test]
fn the_plugin_group_adds_the_pipeline_and_both_responses_in_its_schedule() {
    let mut app = App::new();
    app.add_plugins((
        TimePlugin,
        TransformPlugin,
        StochasticCollisionPlugins::default(),
    ))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    let ball = floor_and_falling_ball(&mut app);
    steps(&mut app, 120);
    let y = app.world().get::<Transform>(ball).unwrap().translation.y;
    assert!(
        y > 0.15 && y < 0.35,
        "fell in FixedPostUpdate and rests on the floor: {y}"
    );
    assert!(
        app.world()
            .contains_resource::<stochastic_collision::ecs::PenaltySettings>()
    );
    assert_eq!(
        app.world()
            .resource::<stochastic_collision::ecs::CollisionSchedule>()
            .0,
        FixedPostUpdate.intern()
    );
}

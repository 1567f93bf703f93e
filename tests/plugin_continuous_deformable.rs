//! Continuous collision of deformable colliders in the plugin, in a real app (`TimePlugin`,
//! `TransformPlugin`, the default schedule, entities placed with `Transform`): a fast rigid
//! ball with `ContinuousCollision` passes through a thin deformable wall, and a deformable
//! sheet with `ContinuousCollision` is moved through a ball within one step. The discrete test
//! sees neither; with continuous collision each crossing is reported once, with a time of
//! impact where the surfaces first meet; a slow swept sheet starts touching once.
#![cfg(feature = "transform")]
mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_transform::components::Transform;
use plugin_support::*;
use stochastic_collision::ecs::DEFAULT_STEP;
use stochastic_collision::prelude::*;

const RADIUS: f32 = 0.15;
const WALL_HALF: f32 = 0.015;
/// Per step (1/64 s): 3.125 units.
const SPEED: f32 = 200.0;
/// The ball moves once before the plugin first sees it (at x = -2), and crosses the wall in
/// the next step (to x = 1.125).
const START: f32 = -5.125;

fn game_with_starts() -> App {
    let mut app = game();
    app.init_resource::<Starts>()
        .add_systems(Last, record_starts);
    app
}

/// A thin deformable wall in the x = 0 plane and a rigid ball flying along +x, moved by the
/// scene one step per fixed step.
fn ball_through_deformable_wall(continuous: Option<ContinuousCollision>) -> App {
    let mut app = game_with_starts();
    app.add_systems(
        FixedUpdate,
        |mut q: Query<&mut Transform, With<BodyVelocity>>| {
            for mut t in &mut q {
                t.translation.x += SPEED * DEFAULT_STEP;
            }
        },
    );
    let wall = Deformable::new(generate::cuboid(Vec3::new(WALL_HALF, 2.0, 2.0), 4));
    spawn(&mut app, (wall, Transform::default()));
    let ball = app
        .world_mut()
        .spawn((
            MeshCollider::new(generate::icosphere(RADIUS, 2)),
            Transform::from_xyz(START, 0.0, 0.0),
            BodyVelocity(Vec3::X * SPEED),
        ))
        .id();
    if let Some(c) = continuous {
        app.world_mut().entity_mut(ball).insert(c);
    }
    app
}

#[test]
fn a_fast_ball_is_caught_by_a_deformable_wall_only_with_continuous_collision() {
    let mut app = ball_through_deformable_wall(None);
    steps(&mut app, 6);
    assert!(app.world().resource::<Starts>().0.is_empty(), "tunnelled");

    let mut app = ball_through_deformable_wall(Some(ContinuousCollision::Always));
    steps(&mut app, 6);
    let starts = &app.world().resource::<Starts>().0;
    assert_eq!(starts.len(), 1, "{starts:?}");
    assert!(starts[0].is_certain());
    // The surfaces meet when the centre is at -(WALL_HALF + r), r between the icosphere's
    // inner radius and RADIUS, in the step from x = -2 to x = 1.125.
    let t = starts[0].time_of_impact.expect("a time of impact");
    let at = |r: f32| (-(WALL_HALF + r) + 2.0) / (SPEED * DEFAULT_STEP);
    assert!(
        t >= at(RADIUS) - 1e-4 && t <= at(0.9 * RADIUS),
        "time of impact {t} outside [{}, {}]",
        at(RADIUS),
        at(0.9 * RADIUS)
    );
    let d = app.world().resource::<CollisionDiagnostics>().counters;
    assert!(d.swept_pairs >= 1 && d.caught_by_sweep >= 1, "{d:?}");
}

/// How far the sheet moves per step (along -y).
#[derive(Resource)]
struct SheetStep(f32);

/// A 1 × 1 deformable sheet in the plane y = 1, moved down each fixed step by its vertices
/// (or, `by_transform`, by its `Transform`), and a rigid ball at the origin.
fn sheet_moved_through_ball(
    continuous: Option<ContinuousCollision>,
    step: f32,
    by_transform: bool,
) -> App {
    let mut app = game_with_starts();
    app.insert_resource(SheetStep(step));
    if by_transform {
        app.add_systems(
            FixedUpdate,
            |mut q: Query<&mut Transform, With<Deformable>>, step: Res<SheetStep>| {
                for mut t in &mut q {
                    t.translation.y -= step.0;
                }
            },
        );
    } else {
        app.add_systems(
            FixedUpdate,
            |mut q: Query<&mut Deformable>, step: Res<SheetStep>| {
                for mut d in &mut q {
                    for p in d.positions_mut() {
                        p.y -= step.0;
                    }
                }
            },
        );
    }
    let sheet = generate::cloth_grid(1.0, 1.0, 10, 10)
        .translated(Vec3::Y)
        .expect("a finite offset");
    let sheet = app
        .world_mut()
        .spawn((Deformable::new(sheet), Transform::default()))
        .id();
    if let Some(c) = continuous {
        app.world_mut().entity_mut(sheet).insert(c);
    }
    spawn(
        &mut app,
        (
            MeshCollider::new(generate::icosphere(RADIUS, 2)),
            Transform::default(),
        ),
    );
    app
}

fn sheet_through_ball(continuous: Option<ContinuousCollision>, step: f32) -> App {
    sheet_moved_through_ball(continuous, step, false)
}

#[test]
fn a_deformable_sheet_moved_through_a_ball_is_caught_with_continuous_collision() {
    // 0.8 per step: the sheet is at y = 1 - 0.8 k after k steps (the first update runs none):
    // 0.2 after the first, -0.6 after the second; it passes the ball (|y| < 0.15) in between.
    let mut app = sheet_through_ball(None, 0.8);
    steps(&mut app, 5);
    assert!(
        app.world().resource::<Starts>().0.is_empty(),
        "passed through"
    );

    for kind in [ContinuousCollision::Always, ContinuousCollision::WhenFast] {
        let mut app = sheet_through_ball(Some(kind), 0.8);
        steps(&mut app, 5);
        let starts = &app.world().resource::<Starts>().0;
        assert_eq!(starts.len(), 1, "{kind:?}: {starts:?}");
        assert!(starts[0].is_certain());
        // From y = 0.2 to y = -0.6: the sheet meets the top of the ball (y = r, r between
        // the icosphere's inner radius and RADIUS) at t = (0.2 - r) / 0.8.
        let t = starts[0].time_of_impact.expect("a time of impact");
        let at = |r: f32| (0.2 - r) / 0.8;
        assert!(
            t >= at(RADIUS) - 1e-4 && t <= at(0.9 * RADIUS),
            "{kind:?}: time of impact {t} outside [{}, {}]",
            at(RADIUS),
            at(0.9 * RADIUS)
        );
    }
    // Moved by its Transform instead of its vertices: the same.
    let mut app = sheet_moved_through_ball(None, 0.8, true);
    steps(&mut app, 5);
    assert!(
        app.world().resource::<Starts>().0.is_empty(),
        "passed through"
    );
    let mut app = sheet_moved_through_ball(Some(ContinuousCollision::Always), 0.8, true);
    steps(&mut app, 5);
    let starts = &app.world().resource::<Starts>().0;
    assert_eq!(starts.len(), 1, "by its transform: {starts:?}");
    let t = starts[0].time_of_impact.expect("a time of impact");
    assert!((0.06..=0.085).contains(&t), "by its transform: {t}");
}

#[test]
fn a_slow_swept_sheet_starts_touching_once() {
    // 0.01 per step: the sheet reaches the ball's top after about 85 steps. Swept every step
    // (a flat sheet's smallest extent is nil, so `WhenFast` counts any motion as fast), the
    // contact starts once, no earlier than the sheet reaches the ball, and stays.
    for kind in [ContinuousCollision::Always, ContinuousCollision::WhenFast] {
        let mut app = sheet_through_ball(Some(kind), 0.01);
        steps(&mut app, 80);
        assert!(
            app.world().resource::<Starts>().0.is_empty(),
            "{kind:?}: too early"
        );
        steps(&mut app, 20);
        let starts = &app.world().resource::<Starts>().0;
        assert_eq!(starts.len(), 1, "{kind:?}: {starts:?}");
        let d = app.world().resource::<CollisionDiagnostics>().counters;
        assert!(d.swept_pairs >= 1, "{kind:?}: {d:?}");
        assert_eq!(d.ended, 0, "{kind:?}: {d:?}");
    }
}

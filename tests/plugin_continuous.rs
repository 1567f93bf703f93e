//! Continuous collision in the plugin, in a real app (`TimePlugin`, `TransformPlugin`, the
//! default `FixedPostUpdate` at 64 Hz, entities placed with `Transform`): a fast ball passes
//! through a thin wall unseen by the discrete test; with `ContinuousCollision` the contact is
//! reported, with the time of impact of a reference computed from the ball's path, and the
//! impulse response sends the ball back from the wall. `WhenFast` sweeps only fast motion.
//! With ADB fidelity the pair is swept with the time-critical continuous query: exact without
//! a budget, and under a budget too small to settle it the conservative query still reports
//! the crossing, never later than it happens; under a time budget whose deadline has always
//! passed, the swept pair still gets enough node pairs to settle, and the estimating query
//! reports the crossing exactly.
#![cfg(feature = "transform")]
mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_transform::components::Transform;
use plugin_support::*;
use std::time::Duration;

use stochastic_collision::ecs::{BudgetController, DEFAULT_STEP, FakeClock, ImpulseSettings};
use stochastic_collision::prelude::*;

const RADIUS: f32 = 0.15;
/// A tenth of the ball's diameter.
const WALL_HALF: f32 = 0.015;
/// Per step (1/64 s): 3.125 units, ten wall-and-ball widths.
const SPEED: f32 = 200.0;
/// Where the ball is spawned: it moves once before the plugin first sees it (at x = -2), and
/// crosses the wall in the next step (to x = 1.125).
const START: f32 = -5.125;

/// A thin wall in the x = 0 plane and a ball at `x0` flying along +x (moved by the scene
/// itself, one step per fixed step, or by the impulse response with `response`).
fn scene(
    continuous: Option<ContinuousCollision>,
    x0: f32,
    speed: f32,
    response: bool,
) -> (App, Entity) {
    adb_scene(continuous, x0, speed, response, Fidelity::Exact)
}

/// [`scene`] with both colliders at `fidelity`.
fn adb_scene(
    continuous: Option<ContinuousCollision>,
    x0: f32,
    speed: f32,
    response: bool,
    fidelity: Fidelity,
) -> (App, Entity) {
    let mut app = game();
    app.init_resource::<Starts>()
        .add_systems(Last, record_starts);
    if response {
        app.add_plugins(
            ImpulseResponsePlugin::default().with_settings(ImpulseSettings {
                gravity: Vec3::ZERO,
                damping: 0.0,
                restitution: 1.0,
                ..Default::default()
            }),
        );
    } else {
        app.add_systems(
            FixedUpdate,
            move |mut q: Query<&mut Transform, With<BodyVelocity>>| {
                for mut t in &mut q {
                    t.translation.x += speed * DEFAULT_STEP;
                }
            },
        );
    }
    let wall = MeshCollider::new(generate::cuboid(Vec3::new(WALL_HALF, 2.0, 2.0), 4));
    spawn(&mut app, (wall, Transform::default(), fidelity));
    let ball = app
        .world_mut()
        .spawn((
            MeshCollider::new(generate::icosphere(RADIUS, 2)),
            Transform::from_xyz(x0, 0.0, 0.0),
            BodyVelocity(Vec3::X * speed),
            fidelity,
        ))
        .id();
    if let Some(c) = continuous {
        app.world_mut().entity_mut(ball).insert(c);
    }
    (app, ball)
}

#[test]
fn a_fast_ball_tunnels_through_a_thin_wall_without_continuous_collision() {
    let (mut app, ball) = scene(None, START, SPEED, false);
    steps(&mut app, 6);
    let x = app.world().get::<Transform>(ball).unwrap().translation.x;
    assert!(x > 5.0, "the ball flew past the wall: {x}");
    assert!(
        app.world().resource::<Starts>().0.is_empty(),
        "no contact seen"
    );
}

#[test]
fn continuous_collision_reports_the_crossing_with_its_time_of_impact() {
    for kind in [ContinuousCollision::Always, ContinuousCollision::WhenFast] {
        let (mut app, _) = scene(Some(kind), START, SPEED, false);
        steps(&mut app, 6);
        let starts = &app.world().resource::<Starts>().0;
        assert_eq!(starts.len(), 1, "{kind:?}: one contact, {starts:?}");
        let s = starts[0];
        assert!(s.is_certain());
        // It crosses in the step from x = -2 to x = 1.125. The surfaces meet when the
        // centre is at -(WALL_HALF + r), r between the icosphere's inner radius and RADIUS.
        let t = s.time_of_impact.expect("a time of impact");
        let travel = SPEED * DEFAULT_STEP;
        let at = |r: f32| (-(WALL_HALF + r) + 2.0) / travel;
        assert!(
            t >= at(RADIUS) - 1e-4 && t <= at(0.9 * RADIUS),
            "{kind:?}: time of impact {t} outside [{}, {}]",
            at(RADIUS),
            at(0.9 * RADIUS)
        );
        let d = app.world().resource::<CollisionDiagnostics>().counters;
        assert!(d.caught_by_sweep >= 1 && d.swept_pairs >= 1, "{d:?}");
    }
}

#[test]
fn when_fast_leaves_slow_motion_to_the_discrete_test() {
    // 0.5 per second: 0.008 per step, far below a quarter of the ball's 0.3.
    let (mut app, _) = scene(Some(ContinuousCollision::WhenFast), -0.4, 0.5, false);
    steps(&mut app, 40);
    let d = app.world().resource::<CollisionDiagnostics>().counters;
    assert_eq!(d.swept_pairs, 0, "{d:?}");
    // It reaches the wall (0.4 - 0.165 = 0.235 away) after about 30 steps: a discrete start.
    let starts = &app.world().resource::<Starts>().0;
    assert_eq!(starts.len(), 1);
    assert_eq!(starts[0].time_of_impact, None);
}

#[test]
fn the_impulse_response_sends_a_swept_ball_back_from_the_wall() {
    let (mut app, ball) = scene(Some(ContinuousCollision::Always), START, SPEED, true);
    steps(&mut app, 4);
    let x = app.world().get::<Transform>(ball).unwrap().translation.x;
    let v = app.world().get::<BodyVelocity>(ball).unwrap().0;
    assert!(x < 0.0, "the ball stays on its side of the wall: x = {x}");
    assert!(v.x < -0.5 * SPEED, "and bounces back: {v}");
    // Without continuous collision the response never sees the wall.
    let (mut app, ball) = scene(None, START, SPEED, true);
    steps(&mut app, 4);
    let x = app.world().get::<Transform>(ball).unwrap().translation.x;
    assert!(x > 2.0, "{x}");
}

#[test]
fn adb_pairs_are_swept_with_the_time_critical_query() {
    let travel = SPEED * DEFAULT_STEP;
    // The surfaces meet when the centre is at -(WALL_HALF + RADIUS) at the latest.
    let latest = (-(WALL_HALF + 0.9 * RADIUS) + 2.0) / travel;
    let adb = Fidelity::Adb { p_min: 0.99 };
    for (budget, conservative, settled) in [
        (FrameBudget::Unlimited, true, true),
        (FrameBudget::NodePairs(8), true, false),
        (FrameBudget::NodePairs(8), false, false),
    ] {
        let (mut app, _) = adb_scene(Some(ContinuousCollision::Always), START, SPEED, false, adb);
        {
            let mut config = app.world_mut().resource_mut::<CollisionConfig>();
            config.budget = budget;
            config.continuous_adb_conservative = conservative;
        }
        steps(&mut app, 6);
        let starts = &app.world().resource::<Starts>().0;
        let d = app.world().resource::<CollisionDiagnostics>().counters;
        assert!(d.swept_pairs >= 1, "{budget:?}: {d:?}");
        if !conservative {
            // The estimate may or may not say "collision": only what it says is checked.
            for s in starts {
                assert!(s.time_of_impact.is_some_and(|t| t <= latest), "{s:?}");
            }
            continue;
        }
        assert_eq!(starts.len(), 1, "{budget:?}: one contact, {starts:?}");
        let s = starts[0];
        let t = s.time_of_impact.expect("a time of impact");
        assert!(t <= latest, "{budget:?}: {t} after {latest}");
        // Settled: the exact answer, probability 1; cut short: earlier, an estimate below 1.
        assert_eq!(s.probability == 1.0, settled, "{budget:?}: {s:?}");
        if settled {
            assert!(t >= (-(WALL_HALF + RADIUS) + 2.0) / travel - 1e-4, "{t}");
        }
    }
}

/// Under a time budget, a swept ADB pair tested past the run's deadline (a clock that moves a
/// millisecond at every reading: every deadline has passed when the tests start) still gets an
/// eighth of `max_slice` for its continuous test: enough to settle a ball against a wall, so
/// the estimating query reports the crossing exactly (probability 1, the path's time of
/// impact), once.
#[test]
fn a_swept_adb_pair_past_its_deadline_still_settles() {
    let travel = SPEED * DEFAULT_STEP;
    let (mut app, _) = adb_scene(
        Some(ContinuousCollision::Always),
        START,
        SPEED,
        false,
        Fidelity::Adb { p_min: 0.99 },
    );
    {
        let world = app.world_mut();
        let mut config = world.resource_mut::<CollisionConfig>();
        config.budget = FrameBudget::Time(Duration::from_micros(200));
        config.continuous_adb_conservative = false;
        world
            .resource_mut::<BudgetController>()
            .set_clock(FakeClock::ticking(Duration::from_millis(1)));
    }
    steps(&mut app, 6);
    let d = app.world().resource::<CollisionDiagnostics>().counters;
    assert!(d.swept_pairs >= 1, "{d:?}");
    assert!(d.overrun_runs >= 1, "every run is over its budget: {d:?}");
    let starts = &app.world().resource::<Starts>().0;
    assert_eq!(starts.len(), 1, "one contact: {starts:?}");
    let s = starts[0];
    assert_eq!(s.probability, 1.0, "settled: {s:?}");
    let t = s.time_of_impact.expect("a time of impact");
    let first = (-(WALL_HALF + RADIUS) + 2.0) / travel;
    let latest = (-(WALL_HALF + 0.9 * RADIUS) + 2.0) / travel;
    assert!(
        t >= first - 1e-4 && t <= latest,
        "{t} not in [{first}, {latest}]"
    );
}

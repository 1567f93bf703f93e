//! The stochastic tracker in the plugin: self-collision of a deformable with
//! `Fidelity::Tracking`, tracked rigid pairs, persistence, determinism across thread counts,
//! and bounded state when entities go.

mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use plugin_support::*;
use stochastic_collision::ecs::{FeaturePairs, TrackingState};
use stochastic_collision::prelude::*;

/// A cloth whose part beyond x = 0.1 is turned over and cut through the rest.
fn folded_cloth() -> (TriMesh, Vec<Vec3>) {
    let flat = generate::cloth_grid(1.0, 1.0, 20, 20);
    let folded = flat
        .positions()
        .iter()
        .map(|p| {
            if p.x > 0.1 {
                Vec3::new(0.2 - p.x, -0.04 * (1.0 - 4.0 * (p.x - 0.1)), p.z)
            } else {
                *p
            }
        })
        .collect();
    (flat, folded)
}

fn spawn_folded(app: &mut App) -> Entity {
    let (flat, folded) = folded_cloth();
    let mut cloth = Deformable::new(flat);
    cloth.positions_mut().copy_from_slice(&folded);
    spawn(
        app,
        (
            cloth,
            SelfCollision,
            Fidelity::Tracking {
                pairs_per_frame: 32,
            },
            at(0.0, 0.0, 0.0),
        ),
    )
}

#[test]
fn tracked_self_collision_reports_the_fold_once_and_keeps_its_pairs() {
    let mut app = app();
    let cloth = spawn_folded(&mut app);
    for _ in 0..6 {
        app.update();
    }
    let events = log(&app);
    assert_eq!(
        events.started,
        vec![(cloth, cloth)],
        "started once, for the cloth itself"
    );
    assert!(events.ended.is_empty());
    assert!(!events.contacts.is_empty());
    for c in &events.contacts {
        assert!(c.point.is_finite() && c.normal.is_finite() && c.depth.is_finite());
    }
    let pairs = app
        .world()
        .get::<FeaturePairs>(cloth)
        .expect("feature pairs recorded");
    assert!(!pairs.with(cloth).is_empty());
    let state = app.world().resource::<TrackingState>();
    assert_eq!(state.trackers(), 1);
    assert!(
        state.tracker(cloth, cloth).unwrap().frame() >= 6,
        "one tracker, persistent"
    );

    // Unfold: the contact ends once, the tracker state goes when nothing is tracked.
    let flat = generate::cloth_grid(1.0, 1.0, 20, 20);
    app.world_mut()
        .get_mut::<Deformable>(cloth)
        .unwrap()
        .positions_mut()
        .copy_from_slice(flat.positions());
    for _ in 0..3 {
        app.update();
    }
    assert_eq!(log(&app).ended, vec![(cloth, cloth)]);
    app.world_mut().despawn(cloth);
    app.update();
    assert_eq!(app.world().resource::<TrackingState>().trackers(), 0);
}

#[test]
fn a_spent_time_budget_cuts_the_trackers_but_the_fold_is_still_found() {
    // A budget far too small for anything: every tracker step runs past its deadline.
    let config = CollisionConfig {
        budget: FrameBudget::Time(std::time::Duration::from_nanos(1)),
        ..Default::default()
    };
    let mut app = app_with(config, 2);
    let cloth = spawn_folded(&mut app);
    for _ in 0..32 {
        app.update();
    }
    let counters = app.world().resource::<CollisionDiagnostics>().counters;
    assert!(
        counters.tracker_steps_cut >= 30,
        "{} tracker steps cut",
        counters.tracker_steps_cut
    );
    let events = log(&app);
    assert_eq!(events.started, vec![(cloth, cloth)], "found, more slowly");
    for c in &events.contacts {
        assert!(c.point.is_finite() && c.normal.is_finite() && c.depth.is_finite());
    }
}

#[test]
fn tracked_rigid_pairs_find_their_contact() {
    let mut app = app();
    let tracked = Fidelity::Tracking {
        pairs_per_frame: 16,
    };
    let a = spawn(&mut app, (ball(1.0), tracked, at(0.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball(1.0), tracked, at(1.7, 0.0, 0.0)));
    let c = spawn(&mut app, (ball(1.0), tracked, at(0.0, 2.3, 0.0)));
    for _ in 0..5 {
        app.update();
    }
    let events = log(&app);
    assert_eq!(
        events.started,
        vec![pair(a, b)],
        "only the overlapping pair"
    );
    let _ = c;
    for contact in &events.contacts {
        // Between the two balls: on the plane x = 0.85, near the axis.
        assert!((contact.point.x - 0.85).abs() < 0.1, "{contact:?}");
    }
}

fn run(threads: usize) -> EventLog {
    let mut app = app_with(
        CollisionConfig {
            budget: FrameBudget::Unlimited,
            ..Default::default()
        },
        threads,
    );
    for k in 0..3 {
        let e = spawn_folded(&mut app);
        let mut pose = app.world_mut().get_mut::<ColliderPose>(e).unwrap();
        *pose = at(3.0 * k as f32, 0.0, 0.0);
    }
    for _ in 0..5 {
        app.update();
    }
    log(&app).clone()
}

#[test]
fn tracking_gives_the_same_events_with_one_or_two_threads() {
    let one = run(1);
    assert!(!one.contacts.is_empty());
    assert_eq!(one, run(2));
}

/// The folded cloth's tracker after `runs` runs under `budget`: its pairs per frame now, and
/// its own time budget.
fn tracker_under(budget: FrameBudget, runs: usize) -> (usize, Option<std::time::Duration>) {
    let mut app = app_with(
        CollisionConfig {
            budget,
            ..Default::default()
        },
        1,
    );
    let cloth = spawn_folded(&mut app);
    for _ in 0..runs {
        app.update();
    }
    let state = app.world().resource::<TrackingState>();
    let tracker = state.tracker(cloth, cloth).expect("tracked");
    (tracker.pairs_per_frame_now(), tracker.config().time_budget)
}

#[test]
fn under_a_time_budget_a_tracker_spends_its_share() {
    // No time budget: the fidelity's 32 pairs per frame, reproducible.
    assert_eq!(tracker_under(FrameBudget::Unlimited, 8), (32, None));
    assert_eq!(tracker_under(FrameBudget::NodePairs(10_000), 8), (32, None));
    // A generous budget (the only tracker, nothing else to do): the tracker's share is most
    // of it, and its pairs per frame grow towards what the share allows.
    let (pairs, own) = tracker_under(FrameBudget::Time(std::time::Duration::from_millis(50)), 8);
    assert!(pairs > 32, "grew to {pairs}");
    assert!(
        own.is_some_and(|t| t > std::time::Duration::from_millis(2)),
        "{own:?}"
    );
    // A budget that cannot hold a step: the share is a sliver, and the pairs shrink.
    let (pairs, own) = tracker_under(FrameBudget::Time(std::time::Duration::from_micros(1)), 8);
    assert!(pairs < 32, "shrank to {pairs}");
    assert!(
        own.is_some_and(|t| t < std::time::Duration::from_micros(1)),
        "{own:?}"
    );
}

//! Collision events: once per contact interval, `TouchingEntities`, despawn, observers,
//! readers that run less often than the collision schedule.
mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use bevy_ecs::system::RunSystemOnce;
use plugin_support::*;
use stochastic_collision::prelude::*;

#[test]
fn started_and_ended_once_per_contact_interval() {
    for fidelity in [Fidelity::Exact, Fidelity::Adb { p_min: 0.99 }] {
        let mut app = app();
        let ball = ball(1.0);
        let a = spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0), fidelity));
        let b = spawn(&mut app, (ball, at(5.0, 0.0, 0.0), fidelity));
        // b travels from x = 5 to x = -5 and back twice: contact while |x| < 2.
        let path: Vec<f32> = (0..=40)
            .map(|i| 5.0 - 0.5 * i as f32)
            .chain((0..=20).map(|i| -5.0 + 0.5 * i as f32))
            .collect();
        let mut touching_frames = 0;
        for x in &path {
            app.world_mut()
                .get_mut::<ColliderPose>(b)
                .unwrap()
                .0
                .translation
                .x = *x;
            app.update();
            let ca = app.world().get::<TouchingEntities>(a).unwrap();
            let cb = app.world().get::<TouchingEntities>(b).unwrap();
            let expect = x.abs() < 1.9;
            if x.abs() > 2.1 || x.abs() < 1.9 {
                assert_eq!(ca.contains(b), expect, "{fidelity:?} at x = {x}");
                assert_eq!(cb.contains(a), expect, "{fidelity:?} at x = {x}");
            }
            touching_frames += usize::from(ca.contains(b));
        }
        let log = log(&app);
        // Contact intervals: x from 2 down to -2 (one), back from -2 to 2 within the
        // reverse pass… the reverse pass stops at x = 5: two intervals in all.
        assert_eq!(log.started, vec![pair(a, b); 2], "{fidelity:?}");
        assert_eq!(log.ended, vec![pair(a, b); 2], "{fidelity:?}");
        assert!(touching_frames > 10);
        assert!(!log.contacts.is_empty());
        for c in &log.contacts {
            assert_eq!((c.a, c.b), pair(a, b));
            assert!(c.normal.is_normalized(), "{c:?}");
            assert!(c.probability > 0.5 && c.probability <= 1.0);
        }
    }
}

#[test]
fn despawn_mid_contact_ends_the_contact() {
    let mut app = app();
    let ball = ball(1.0);
    let a = spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball.clone(), at(1.5, 0.0, 0.0)));
    let c = spawn(&mut app, (ball, at(-1.5, 0.0, 0.0)));
    app.update();
    let mut both = [b, c];
    both.sort();
    assert_eq!(
        app.world().get::<TouchingEntities>(a).unwrap().entities(),
        &both[..]
    );
    app.world_mut().despawn(b);
    app.update();
    app.update();
    let log = log(&app);
    assert_eq!(log.started.len(), 2);
    assert_eq!(log.ended, vec![pair(a, b)]);
    assert_eq!(
        app.world().get::<TouchingEntities>(a).unwrap().entities(),
        &[c][..]
    );
}

#[test]
fn layers_filter_pairs() {
    let mut app = app();
    let ball = ball(1.0);
    let a = spawn(
        &mut app,
        (ball.clone(), at(0.0, 0.0, 0.0), ContactLayers::new(1, 2)),
    );
    let b = spawn(
        &mut app,
        (ball.clone(), at(1.5, 0.0, 0.0), ContactLayers::new(1, 2)),
    );
    let c = spawn(
        &mut app,
        (ball, at(-1.5, 0.0, 0.0), ContactLayers::new(2, 1)),
    );
    app.update();
    assert_eq!(log(&app).started, vec![pair(a, c)]);
    assert!(!app.world().get::<TouchingEntities>(b).unwrap().contains(a));
}

#[derive(Resource, Default)]
struct Observed(Vec<(&'static str, Entity, Entity)>);

#[test]
fn observers_fire_for_opted_in_entities_even_when_added_later() {
    let mut app = app();
    app.init_resource::<Observed>();
    let ball = ball(1.0);
    let a = spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball, at(5.0, 0.0, 0.0)));
    app.update();
    // Opt in after spawning (avian#1066).
    app.world_mut()
        .entity_mut(b)
        .insert(ObserveCollisions)
        .observe(|e: On<CollisionStarted>, mut o: ResMut<Observed>| {
            o.0.push(("started", e.entity, e.other));
        })
        .observe(|e: On<CollisionEnded>, mut o: ResMut<Observed>| {
            o.0.push(("ended", e.entity, e.other));
        });
    for x in [1.5, 1.4, 5.0] {
        app.world_mut()
            .get_mut::<ColliderPose>(b)
            .unwrap()
            .0
            .translation
            .x = x;
        app.update();
    }
    assert_eq!(
        app.world().resource::<Observed>().0,
        vec![("started", b, a), ("ended", b, a)]
    );
}

#[derive(ScheduleLabel, Debug, Clone, PartialEq, Eq, Hash)]
struct CollisionStep;

#[derive(Resource, Default)]
struct Updates(u64);

#[test]
fn a_reader_running_less_often_than_the_collision_schedule_sees_every_event() {
    // The collision schedule runs 3 times per app update (like fixed steps), the reader only
    // every other update.
    let mut app = App::new();
    app.add_plugins(
        StochasticCollisionPlugin::in_schedule(CollisionStep).with_config(CollisionConfig {
            budget: FrameBudget::Unlimited,
            contact_messages: true,
            ..Default::default()
        }),
    )
    .init_resource::<EventLog>()
    .init_resource::<Updates>()
    .add_systems(Update, |world: &mut World| {
        for _ in 0..3 {
            world.run_schedule(CollisionStep);
        }
    })
    .add_systems(
        Last,
        (
            log_events.run_if(|u: Res<Updates>| u.0 % 2 == 1),
            |mut u: ResMut<Updates>| u.0 += 1,
        )
            .chain(),
    );
    let ball = ball(1.0);
    spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball, at(5.0, 0.0, 0.0)));
    // Move b once per collision run: in and out of contact many times.
    app.add_systems(
        CollisionStep,
        (move |mut q: Query<&mut ColliderPose>, d: Res<CollisionDiagnostics>| {
            let x = if (d.frame / 2).is_multiple_of(2) {
                1.5
            } else {
                5.0
            };
            q.get_mut(b).unwrap().0.translation.x = x;
        })
        .before(CollisionSystems::Prepare),
    );
    for _ in 0..20 {
        app.update();
    }
    let counters = app.world().resource::<CollisionDiagnostics>().counters;
    let log = log(&app);
    assert!(counters.started >= 10);
    assert_eq!(log.started.len() as u64, counters.started);
    assert_eq!(log.ended.len() as u64, counters.ended);
    assert_eq!(log.contacts.len() as u64, counters.contacts);
    assert!(counters.contacts >= 10);
}

#[test]
fn contacts_are_read_through_collisions_and_sent_as_messages_only_on_request() {
    let mut app = App::new();
    app.add_plugins(
        StochasticCollisionPlugin::in_schedule(PostUpdate).with_config(CollisionConfig {
            budget: FrameBudget::Unlimited,
            ..Default::default()
        }),
    )
    .init_resource::<EventLog>()
    .add_systems(Last, log_events);
    let ball = ball(1.0);
    let a = spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    let b = spawn(&mut app, (ball, at(1.5, 0.0, 0.0)));
    let view = |app: &mut App| {
        app.world_mut()
            .run_system_once(move |c: CollisionPairs| {
                let p = c.get(b, a).expect("the pair exists");
                let others: Vec<Entity> = c.touching_of(a).map(|p| p.other(a)).collect();
                (
                    p.touching(),
                    p.contacts().len(),
                    p.probability(),
                    p.age(),
                    others,
                )
            })
            .unwrap()
    };
    app.update();
    let (touching, contacts, probability, age, others) = view(&mut app);
    assert!(touching && contacts > 0 && probability > 0.5);
    assert_eq!((age, others), (0, vec![b]));
    for _ in 0..3 {
        app.update();
    }
    // At rest: still touching, the answer three runs old (nothing moved, so it holds), no
    // contact message ever (not asked for), one start.
    let (touching, contacts, _, age, _) = view(&mut app);
    assert!(touching && contacts > 0);
    assert_eq!(age, 3);
    assert!(log(&app).contacts.is_empty());
    assert_eq!(log(&app).started, vec![pair(a, b)]);
    // Asked for: the contacts of the pairs answered in a run come as messages.
    app.world_mut()
        .resource_mut::<CollisionConfig>()
        .contact_messages = true;
    app.update();
    assert!(!log(&app).contacts.is_empty());
}

#[test]
fn bounds_fidelity_collides_on_box_overlap() {
    let mut app = app();
    let ball = ball(1.0);
    // Diagonal: boxes overlap, spheres do not.
    let a = spawn(
        &mut app,
        (ball.clone(), at(0.0, 0.0, 0.0), Fidelity::Bounds),
    );
    let b = spawn(
        &mut app,
        (ball.clone(), at(1.7, 1.7, 0.0), Fidelity::Bounds),
    );
    let c = spawn(&mut app, (ball, at(-1.7, -1.7, 0.0), Fidelity::Exact));
    app.update();
    assert_eq!(log(&app).started, vec![pair(a, b)]);
    assert!(!app.world().get::<TouchingEntities>(c).unwrap().contains(a));
}

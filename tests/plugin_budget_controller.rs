//! The budget controller driven by a fake clock, in an app: plans that follow the measured
//! costs, a run ten times over its time budget, recovery, no pair starving, every event
//! delivered, and a response budget in time.
//!
//! The clock ticks one microsecond at every reading (`FakeClock::ticking`), so the time a
//! piece of work measures is the number of clock readings it made: the same on every machine.
//! One thread, so that the readings come in one order.
mod plugin_support;

use std::collections::HashSet;
use std::time::Duration;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use plugin_support::*;
use stochastic_collision::ecs::{BudgetController, FakeClock};
use stochastic_collision::prelude::*;

const BUDGET: Duration = Duration::from_micros(2000);
/// Runs ten times over the budget: enough for every pair to wait its turn a few times.
const OVERLOADED: usize = 150;
const SIDE: usize = 24;

/// What an overloaded run costs besides its tests (added to the clock in the BroadPhase stage).
#[derive(Resource, Default)]
struct Overload(Duration);

/// Every pair's answer age seen after each run, and the runs' plans.
#[derive(Resource, Default)]
struct Seen {
    max_age: Vec<u64>,
    tests: Vec<usize>,
    margins: Vec<Duration>,
    overran: Vec<bool>,
}

#[derive(Resource, Clone)]
struct Clock(FakeClock);

/// Whether the balls shiver.
#[derive(Resource)]
struct Shivering(bool);

/// A grid of balls, each overlapping its four neighbours and close to its diagonal ones, that
/// all shiver every run: every pair is active in every run, far more than a run can test.
fn shivering_grid(response_budget: ResponseBudget) -> App {
    let mut app = app_with(
        CollisionConfig {
            budget: FrameBudget::Time(BUDGET),
            response_budget,
            ..Default::default()
        },
        1,
    );
    let clock = FakeClock::ticking(Duration::from_micros(1));
    app.world_mut()
        .resource_mut::<BudgetController>()
        .set_clock(clock.clone());
    let ball = MeshCollider::new(generate::icosphere(0.5, 2));
    for i in 0..SIDE {
        for j in 0..SIDE {
            let p = Vec3::new(i as f32 * 0.9, 0.0, j as f32 * 0.9);
            app.world_mut()
                .spawn((ball.clone(), ColliderPose::from_translation(p)));
        }
    }
    app.insert_resource(Clock(clock))
        .init_resource::<Overload>()
        .init_resource::<Seen>()
        .insert_resource(Shivering(true))
        .add_systems(Update, shiver.run_if(|s: Res<Shivering>| s.0))
        .add_systems(
            PostUpdate,
            (
                overload.in_set(CollisionSystems::BroadPhase),
                look.after(CollisionSystems::Report),
            ),
        );
    app
}

/// Moves every ball a little, differently each run (deterministic).
fn shiver(mut q: Query<&mut ColliderPose>, mut run: Local<u32>) {
    *run += 1;
    for (k, mut pose) in q.iter_mut().enumerate() {
        let phase = (k as f32 * 0.37 + *run as f32 * 0.61).sin();
        pose.0.translation.y = 0.03 * phase;
    }
}

fn overload(overload: Res<Overload>, clock: Res<Clock>) {
    clock.0.advance(overload.0);
}

fn look(
    pairs: CollisionPairs,
    budget: Res<BudgetController>,
    diag: Res<CollisionDiagnostics>,
    mut seen: ResMut<Seen>,
    mut overruns: Local<u64>,
) {
    seen.max_age
        .push(pairs.iter().map(|p| p.age()).max().unwrap_or(0));
    seen.tests.push(budget.plan().planned_tests);
    seen.margins.push(budget.margin());
    seen.overran.push(
        diag.counters.overrun_runs > std::mem::replace(&mut *overruns, diag.counters.overrun_runs),
    );
}

#[test]
fn ten_times_over_the_budget_the_controller_degrades_and_recovers() {
    let mut app = shivering_grid(ResponseBudget::Unlimited);
    // Quiet runs: the costs are learnt (a test reads the clock a few times).
    for _ in 0..20 {
        app.update();
    }
    let quiet_tests = *app.world().resource::<Seen>().tests.last().unwrap();
    let pairs = app
        .world_mut()
        .run_system_once(|p: CollisionPairs| p.iter().count())
        .unwrap();
    assert!(pairs > 600, "{pairs} pairs");
    assert!(
        quiet_tests > 0 && quiet_tests < pairs,
        "within the budget some but not all of the {pairs} pairs are tested: {quiet_tests}"
    );
    // Ten times over: the stages before the narrow phase alone take ten budgets.
    app.world_mut().resource_mut::<Overload>().0 = BUDGET * 10;
    for _ in 0..OVERLOADED {
        app.update();
    }
    {
        let world = app.world();
        let seen = world.resource::<Seen>();
        let budget = world.resource::<BudgetController>();
        let plan = budget.plan();
        assert!(
            seen.overran[20..].iter().all(|&o| o),
            "every overloaded run overran"
        );
        assert_eq!(seen.overran.len(), 20 + OVERLOADED);
        assert_eq!(budget.margin(), BUDGET / 4, "the margin is at its cap");
        assert!(plan.before_narrow >= BUDGET * 10, "{plan:?}");
        // The tests still get a sixteenth of the budget: fewer than within the budget, not none.
        assert_eq!(plan.tests, BUDGET / 16, "{plan:?}");
        let overloaded = *seen.tests.last().unwrap();
        assert!(
            overloaded > 0 && overloaded < quiet_tests,
            "{overloaded} tests overloaded, {quiet_tests} within the budget"
        );
        // No pair starves: a quarter of the tests go to the longest waiting pairs, so no
        // answer gets much older than 4 × pairs / tests runs (less than the overload lasts).
        let bound = (4 * pairs / overloaded.max(1)) as u64 + 4;
        assert!(bound < OVERLOADED as u64, "{bound}");
        let worst = seen.max_age[20..].iter().max().copied().unwrap();
        assert!(
            worst <= bound,
            "an answer {worst} runs old with {overloaded} tests per run for {pairs} pairs"
        );
    }
    // Recovery: the overload goes, the margin comes down and the tests come back.
    app.world_mut().resource_mut::<Overload>().0 = Duration::ZERO;
    for _ in 0..60 {
        app.update();
    }
    let seen = app.world().resource::<Seen>();
    let after = 20 + OVERLOADED + 5;
    let overruns = seen.overran[after..].iter().filter(|&&o| o).count();
    assert!(
        overruns <= 3,
        "{overruns} overruns once the overload is gone"
    );
    assert!(seen.margins.last().unwrap() < &(BUDGET / 4));
    let recovered = *seen.tests.last().unwrap();
    let overloaded = seen.tests[20 + OVERLOADED - 1];
    assert!(
        recovered > 4 * overloaded && recovered * 10 >= quiet_tests * 6,
        "{recovered} tests after recovery, {overloaded} overloaded, {quiet_tests} before"
    );
}

#[test]
fn every_event_is_delivered_under_overload() {
    let mut app = shivering_grid(ResponseBudget::Unlimited);
    app.world_mut().resource_mut::<Overload>().0 = BUDGET * 10;
    for _ in 0..40 {
        app.update();
    }
    // The shivering stops: every pair is tested in time and settles.
    app.world_mut().resource_mut::<Overload>().0 = Duration::ZERO;
    app.world_mut().resource_mut::<Shivering>().0 = false;
    for _ in 0..100 {
        app.update();
    }
    let log = log(&app).clone();
    // Each pair's count of started messages is its count of ended ones, plus one if it is
    // touching now.
    let mut touching: HashSet<(Entity, Entity)> = HashSet::new();
    let mut balance: std::collections::HashMap<(Entity, Entity), i64> = Default::default();
    for p in &log.started {
        *balance.entry(*p).or_default() += 1;
    }
    for p in &log.ended {
        *balance.entry(*p).or_default() -= 1;
    }
    for (p, b) in &balance {
        assert!(*b == 0 || *b == 1, "{p:?}: {b} more starts than ends");
        if *b == 1 {
            touching.insert(*p);
        }
    }
    let table: HashSet<(Entity, Entity)> = app
        .world_mut()
        .run_system_once(|p: CollisionPairs| {
            p.iter()
                .filter(|v| v.touching())
                .map(|v| v.entities())
                .collect::<HashSet<_>>()
        })
        .unwrap();
    assert_eq!(touching, table, "every start and end was delivered");
    assert!(
        touching.len() > SIDE * (SIDE - 1),
        "{} touching",
        touching.len()
    );
    // And TouchingEntities agrees.
    let mut q = app.world_mut().query::<(Entity, &TouchingEntities)>();
    let from_components: usize = q.iter(app.world()).map(|(_, t)| t.len()).sum();
    assert_eq!(from_components, 2 * table.len());
}

#[derive(Resource, Default)]
struct Responded(Vec<usize>);

#[test]
fn the_response_budget_is_a_time() {
    // Each contact offered reads the clock at least once (1 µs): a 40 µs budget takes at most
    // 40 contacts per run; the rest waits, highest priority first.
    let mut app = shivering_grid(ResponseBudget::Time(Duration::from_micros(40)));
    app.init_resource::<Responded>().add_systems(
        PostUpdate,
        (|mut queue: ResMut<ContactQueue>, mut responded: ResMut<Responded>| {
            let n = queue.consume(|_| true);
            assert!(queue.budget_spent() || queue.is_empty());
            responded.0.push(n);
        })
        .in_set(CollisionSystems::Response),
    );
    app.world_mut().resource_mut::<ContactQueue>().enable();
    for _ in 0..10 {
        app.update();
    }
    let world = app.world();
    let responded = &world.resource::<Responded>().0;
    let queue = world.resource::<ContactQueue>();
    assert!(
        responded.iter().all(|&n| (1..=40).contains(&n)),
        "{responded:?}"
    );
    assert!(!queue.is_empty(), "the rest waits");
    assert!(queue.deferred_total > 0);
    assert_eq!(queue.remaining_contacts(), None);
}

#[test]
fn a_spent_response_budget_offers_nothing_more_in_the_run() {
    let mut app = shivering_grid(ResponseBudget::Time(Duration::from_micros(5)));
    app.init_resource::<Responded>().add_systems(
        PostUpdate,
        (
            (|mut queue: ResMut<ContactQueue>| {
                queue.consume(|_| true);
            }),
            (|mut queue: ResMut<ContactQueue>, mut responded: ResMut<Responded>| {
                // A second response in the same run shares what the first left.
                responded.0.push(queue.consume(|_| true));
            }),
        )
            .chain()
            .in_set(CollisionSystems::Response),
    );
    app.world_mut().resource_mut::<ContactQueue>().enable();
    for _ in 0..5 {
        app.update();
    }
    assert!(
        app.world()
            .resource::<Responded>()
            .0
            .iter()
            .all(|&n| n == 0)
    );
}

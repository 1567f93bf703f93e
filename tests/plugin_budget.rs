//! Budgets: a scene ten times over its work budget stays within it (asserted on counted work,
//! not on wall-clock time), and the response budget defers contacts to the next run.
mod plugin_support;

use std::time::Duration;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use plugin_support::*;
use stochastic_collision::ecs::{ColliderTable, CollisionCounters, Method, PairOutcome, PairTable};
use stochastic_collision::prelude::*;

/// A cluster of overlapping detailed spheres: many ADB pairs that need work to settle.
fn cluster(config: CollisionConfig) -> App {
    let mut app = app_with(config, 2);
    let ball = MeshCollider::new(generate::icosphere(1.0, 3));
    for i in 0..5 {
        for j in 0..5 {
            let p = Vec3::new(i as f32 * 1.6, (i + j) as f32 * 0.1, j as f32 * 1.6);
            app.world_mut()
                .spawn((ball.clone(), ColliderPose::from_translation(p)));
        }
    }
    app
}

fn counters(app: &App) -> CollisionCounters {
    app.world().resource::<CollisionDiagnostics>().counters
}

#[test]
fn ten_times_over_the_work_budget_stays_within_it() {
    // What the scene needs per run without a budget.
    let mut free = cluster(CollisionConfig {
        budget: FrameBudget::Unlimited,
        adb_exact_leaves: false,
        ..Default::default()
    });
    free.update();
    let needed = counters(&free).node_pairs;
    let pairs = counters(&free).adb_pairs;
    assert!(pairs >= 40, "{pairs} ADB pairs");
    let budget = needed / 10;
    let config = CollisionConfig {
        budget: FrameBudget::NodePairs(budget),
        adb_exact_leaves: false,
        ..Default::default()
    };
    let min_slice = config.min_slice;
    let mut tight = cluster(config);
    for run in 1..=5u64 {
        tight.update();
        let c = counters(&tight);
        // Each traversal may overshoot its slice by one expansion (at most 3 node pairs) and
        // always expands the root pair.
        let bound = budget.max(pairs * min_slice) + pairs * 4;
        assert!(
            c.node_pairs <= run * bound,
            "run {run}: {} node pairs for a budget of {budget} ({needed} needed)",
            c.node_pairs
        );
    }
    let c = counters(&tight);
    assert!(
        c.budget_exhausted_pairs > 0,
        "the budget cut some traversals"
    );
    // Degraded, not blind: the deep overlaps are still found.
    assert!(!log(&tight).started.is_empty());
}

#[test]
fn an_exhausted_time_budget_answers_from_the_last_run() {
    let mut app = cluster(CollisionConfig {
        budget: FrameBudget::Unlimited,
        ..Default::default()
    });
    app.update();
    let touching = log(&app).started.len();
    // Now (almost) no time at all: the pairs keep their last answers.
    app.world_mut().resource_mut::<CollisionConfig>().budget =
        FrameBudget::Time(Duration::from_nanos(1));
    let before = counters(&app);
    app.update();
    let after = counters(&app);
    assert_eq!(after.node_pairs, before.node_pairs, "no pair was tested");
    assert!(
        after.coherence_pairs + after.cached_pairs > before.coherence_pairs + before.cached_pairs
    );
    assert_eq!(log(&app).ended.len(), 0, "no contact was dropped");
    assert_eq!(log(&app).started.len(), touching);
}

#[test]
fn level_geometry_holds_when_the_time_budget_is_spent() {
    // The cluster, then a slab of level geometry (exact) rising into it while no time at all
    // is left: no pair is tested, the ADB pairs keep their last answers, and every slab pair
    // whose oriented boxes overlap reports a contact (nothing may pass through level geometry
    // because the frame was busy).
    let mut app = cluster(CollisionConfig {
        budget: FrameBudget::Unlimited,
        ..Default::default()
    });
    let slab = MeshCollider::new(generate::cuboid(Vec3::new(5.0, 0.5, 5.0), 4));
    let floor = app
        .world_mut()
        .spawn((
            slab,
            ColliderPose::from_translation(Vec3::new(3.2, -2.0, 3.2)),
            Fidelity::Exact,
        ))
        .id();
    app.update();
    app.world_mut().resource_mut::<CollisionConfig>().budget =
        FrameBudget::Time(Duration::from_nanos(1));
    for run in 0..4 {
        app.world_mut()
            .get_mut::<ColliderPose>(floor)
            .unwrap()
            .0
            .translation
            .y += 0.2;
        app.update();
        let outcomes: Vec<_> = app
            .world()
            .resource::<PairTable>()
            .outcomes()
            .cloned()
            .collect();
        // The slab's pairs whose world boxes overlap (the others are close, not touching).
        let colliders = app.world().resource::<ColliderTable>();
        let boxes_overlap = |o: &PairOutcome| {
            let aabb = |e| colliders.get(e).unwrap().aabb;
            aabb(o.a).intersects(&aabb(o.b))
        };
        let slab_pairs: Vec<_> = outcomes
            .iter()
            .filter(|o| (o.a == floor || o.b == floor) && boxes_overlap(o))
            .collect();
        for o in &slab_pairs {
            assert!(
                o.collides && o.probability >= 0.5 && !o.contacts.is_empty(),
                "run {run}: {o:?}"
            );
        }
        if run == 3 {
            assert!(slab_pairs.len() >= 5, "{} slab pairs", slab_pairs.len());
        }
        // The others were not tested: their last answers stand, from an earlier run.
        let now = app.world().resource::<CollisionDiagnostics>().frame;
        assert!(
            outcomes
                .iter()
                .filter(|o| o.a != floor && o.b != floor)
                .all(|o| o.run < now || o.method == Method::Coherence)
        );
    }
}

#[derive(Resource, Default)]
struct Consumed(Vec<(u64, f32)>);

#[test]
fn the_response_budget_defers_contacts_by_priority() {
    let mut app = cluster(CollisionConfig {
        budget: FrameBudget::Unlimited,
        response_budget: ResponseBudget::Contacts(3),
        ..Default::default()
    });
    app.init_resource::<Consumed>().add_systems(
        PostUpdate,
        (|mut queue: ResMut<ContactQueue>,
          mut consumed: ResMut<Consumed>,
          d: Res<CollisionDiagnostics>| {
            let highest: Vec<f32> = queue.waiting().iter().take(3).map(|c| c.priority).collect();
            let mut got = Vec::new();
            queue.consume(|c| {
                got.push(c.priority);
                true
            });
            assert_eq!(got, highest, "highest priority first");
            consumed.0.extend(got.into_iter().map(|p| (d.frame, p)));
        })
        .in_set(CollisionSystems::Response),
    );
    app.world_mut().resource_mut::<ContactQueue>().enable();
    for _ in 0..3 {
        app.update();
    }
    let consumed = &app.world().resource::<Consumed>().0;
    assert_eq!(consumed.len(), 9, "3 per run");
    let queue = app.world().resource::<ContactQueue>();
    assert!(!queue.is_empty(), "the rest waits");
    assert!(queue.deferred_total > 0, "and is counted");
    assert_eq!(queue.consumed_total, 9);
}

//! Determinism: a seeded run gives the same event stream with 1 and 2 compute threads.
mod plugin_support;
#[path = "../examples/support/mod.rs"]
mod support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use plugin_support::{EventLog, log_events};
use stochastic_collision::prelude::*;
use support::{Options, Scene};

/// Everything observable of a run, bit for bit.
fn run(threads: usize) -> (EventLog, Vec<[u32; 3]>) {
    let options = Options {
        entities: 80,
        threads,
        node_budget: Some(3000),
        seed: 7,
        contact_messages: true,
        ..Options::default()
    };
    let mut app = Scene::Pile.build(&options);
    app.init_resource::<EventLog>()
        .add_systems(Last, log_events);
    for _ in 0..90 {
        app.update();
    }
    let world = app.world_mut();
    let mut q = world.query_filtered::<(Entity, &ColliderPose), With<BodyVelocity>>();
    let mut poses: Vec<_> = q.iter(world).map(|(e, p)| (e, p.0.translation)).collect();
    poses.sort_by_key(|(e, _)| *e);
    let poses = poses
        .into_iter()
        .map(|(_, t)| t.to_array().map(f32::to_bits))
        .collect();
    (world.resource::<EventLog>().clone(), poses)
}

#[test]
fn same_events_with_one_and_two_threads() {
    let (one, poses_one) = run(1);
    let (two, poses_two) = run(2);
    assert!(
        one.started.len() > 20,
        "the pile collides: {}",
        one.started.len()
    );
    assert!(one.contacts.len() > 100);
    assert_eq!(one.started, two.started);
    assert_eq!(one.ended, two.ended);
    assert_eq!(one.contacts.len(), two.contacts.len());
    for (x, y) in one.contacts.iter().zip(&two.contacts) {
        // Bitwise: PartialEq on floats would also accept -0 == 0.
        assert_eq!(
            (x.a, x.b, x.frame, x.triangles),
            (y.a, y.b, y.frame, y.triangles)
        );
        assert_eq!(
            x.point.to_array().map(f32::to_bits),
            y.point.to_array().map(f32::to_bits)
        );
        assert_eq!(
            x.normal.to_array().map(f32::to_bits),
            y.normal.to_array().map(f32::to_bits)
        );
        assert_eq!(x.depth.to_bits(), y.depth.to_bits());
        assert_eq!(x.probability.to_bits(), y.probability.to_bits());
    }
    assert_eq!(poses_one, poses_two, "the simulations stay identical");
}

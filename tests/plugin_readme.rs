//! The README's "The plugin in an app" example, kept compiling and running (fewer bodies and
//! frames).
#![cfg(feature = "transform")]
use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_time::{TimePlugin, TimeUpdateStrategy};
use bevy_transform::{TransformPlugin, components::Transform};
use stochastic_collision::prelude::*;

#[test]
fn readme_example_runs() {
    let mut app = App::new();
    app.add_plugins((TimePlugin, TransformPlugin))
        .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
        .add_plugins(StochasticCollisionPlugin::default().with_threads(2))
        .add_plugins(ImpulseResponsePlugin::default())
        .init_resource::<Seen>()
        .add_systems(FixedPostUpdate, on_hit.after(CollisionSystems::Report));
    let floor = MeshCollider::new(generate::cuboid(Vec3::new(50.0, 0.5, 2.0), 16));
    app.world_mut()
        .spawn((floor, Transform::from_xyz(0.0, -0.5, 0.0), Fidelity::Exact));
    let rock = MeshCollider::new(generate::icosphere(0.5, 2));
    let rocks: Vec<Entity> = (0..20)
        .map(|i| {
            app.world_mut()
                .spawn((
                    rock.clone(),
                    Transform::from_xyz(i as f32 * 0.9, 3.0, 0.0).with_scale(Vec3::splat(0.8)),
                    BodyVelocity(Vec3::ZERO),
                    Fidelity::Adb { p_min: 0.9 },
                ))
                .id()
        })
        .collect();
    app.world_mut().resource_mut::<CollisionConfig>().budget =
        FrameBudget::Time(std::time::Duration::from_micros(2000));
    for _ in 0..90 {
        app.update();
    }
    // Scaled to radius 0.4, neighbours 0.9 apart do not touch: every rock lands on the floor.
    let seen = app.world().resource::<Seen>();
    assert!(seen.started >= 20, "{}", seen.started);
    assert!(seen.contacts >= 20, "every start has a contact");
    for r in rocks {
        let y = app.world().get::<Transform>(r).unwrap().translation.y;
        assert!((0.3..0.5).contains(&y), "resting on the floor: {y}");
    }
}

fn on_hit(
    mut started: MessageReader<CollisionStarted>,
    collisions: CollisionPairs,
    mut seen: ResMut<Seen>,
) {
    for e in started.read() {
        let _ = (e.method, e.probability);
        seen.started += 1;
        let pair = collisions
            .get(e.entity, e.other)
            .expect("a started pair is in the table");
        for c in pair.contacts() {
            let _ = (c.point, c.normal, c.depth);
            seen.contacts += 1;
        }
    }
}

/// What the README's reader saw (the README prints it).
#[derive(Resource, Default)]
struct Seen {
    started: u64,
    contacts: u64,
}

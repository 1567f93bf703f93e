//! The README's "Using the plugin" example, kept compiling and running (fewer frames).
use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use stochastic_collision::prelude::*;

#[test]
fn readme_example_runs() {
    let mut app = App::new();
    app.add_plugins(StochasticCollisionPlugin::in_schedule(PostUpdate).with_threads(2))
        .add_plugins(ImpulseResponsePlugin::in_schedule(PostUpdate))
        .init_resource::<Seen>()
        .add_systems(PostUpdate, on_hit.after(CollisionSystems::Report));
    let rock = Collider::new(generate::icosphere(0.5, 2));
    for i in 0..20 {
        app.world_mut().spawn((
            rock.clone(),
            ColliderPose::from_translation(Vec3::new(i as f32 * 0.9, 3.0, 0.0)),
            Velocity(Vec3::ZERO),
            Fidelity::Adb { p_min: 0.9 },
        ));
    }
    app.world_mut().resource_mut::<CollisionConfig>().budget =
        FrameBudget::Time(std::time::Duration::from_micros(2000));
    for _ in 0..10 {
        app.update();
    }
    // Neighbours 0.9 apart with radius 0.5 overlap from the start.
    assert!(
        app.world()
            .resource::<CollisionDiagnostics>()
            .counters
            .started
            >= 19
    );
    assert!(
        app.world().resource::<Seen>().0 >= 19,
        "every start has a contact"
    );
}

fn on_hit(
    mut started: MessageReader<CollisionStarted>,
    collisions: Collisions,
    mut seen: ResMut<Seen>,
) {
    for e in started.read() {
        let pair = collisions
            .get(e.entity, e.other)
            .expect("a started pair is in the table");
        for c in pair.contacts() {
            let _ = (c.point, c.normal, c.depth, pair.probability());
            seen.0 += 1;
        }
    }
}

/// Contacts the README's reader saw (the README's prints them).
#[derive(Resource, Default)]
struct Seen(u64);

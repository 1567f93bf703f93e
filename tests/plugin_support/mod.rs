//! Helpers shared by the plugin tests: a headless app, an event log.
#![allow(dead_code)]

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use stochastic_collision::prelude::*;

/// Every collision message seen by [`log_events`], in order.
#[derive(Resource, Default, Debug, Clone, PartialEq)]
pub struct EventLog {
    pub started: Vec<(Entity, Entity)>,
    pub ended: Vec<(Entity, Entity)>,
    pub contacts: Vec<Contact>,
    pub errors: Vec<CollisionError>,
}

/// Appends every collision message to the [`EventLog`].
pub fn log_events(
    mut log: ResMut<EventLog>,
    mut started: MessageReader<CollisionStarted>,
    mut ended: MessageReader<CollisionEnded>,
    mut contacts: MessageReader<Contact>,
    mut errors: MessageReader<CollisionError>,
) {
    log.started
        .extend(started.read().map(|e| (e.entity, e.other)));
    log.ended.extend(ended.read().map(|e| (e.entity, e.other)));
    log.contacts.extend(contacts.read().copied());
    log.errors.extend(errors.read().cloned());
}

/// Every `CollisionStarted` message as it came (with its method, probability and time of
/// impact), recorded by [`record_starts`].
#[derive(Resource, Default)]
pub struct Starts(pub Vec<CollisionStarted>);

/// Appends every `CollisionStarted` message to [`Starts`].
pub fn record_starts(mut starts: ResMut<Starts>, mut reader: MessageReader<CollisionStarted>) {
    starts.0.extend(reader.read().copied());
}

/// Runs `n` updates of `app`.
pub fn steps(app: &mut App, n: usize) {
    for _ in 0..n {
        app.update();
    }
}

/// A headless app: the plugin in `PostUpdate` with `config` and `threads`, the log in `Last`.
/// Contact messages are on (the tests read contacts from the log).
pub fn app_with(config: CollisionConfig, threads: usize) -> App {
    let config = CollisionConfig {
        contact_messages: true,
        ..config
    };
    let mut app = App::new();
    app.add_plugins(
        StochasticCollisionPlugin::in_schedule(PostUpdate)
            .with_config(config)
            .with_threads(threads),
    )
    .init_resource::<EventLog>()
    .add_systems(Last, log_events);
    app
}

/// [`app_with`] with an unlimited budget, one thread.
pub fn app() -> App {
    app_with(
        CollisionConfig {
            budget: FrameBudget::Unlimited,
            ..Default::default()
        },
        1,
    )
}

pub fn ball(radius: f32) -> MeshCollider {
    MeshCollider::new(generate::icosphere(radius, 2))
}

pub fn at(x: f32, y: f32, z: f32) -> ColliderPose {
    ColliderPose::from_translation(Vec3::new(x, y, z))
}

pub fn log(app: &App) -> &EventLog {
    app.world().resource::<EventLog>()
}

/// Spawns `bundle`, returns the entity.
pub fn spawn(app: &mut App, bundle: impl Bundle) -> Entity {
    app.world_mut().spawn(bundle).id()
}

/// A pair as the messages give it (smaller entity first).
pub fn pair(a: Entity, b: Entity) -> (Entity, Entity) {
    (a.min(b), a.max(b))
}

/// A game: bevy_time's `TimePlugin` and bevy_transform's `TransformPlugin`, the plugin in its
/// default schedule without a budget, one fixed step per update (the first update of an app
/// runs none), the log in `Last`.
#[cfg(feature = "transform")]
pub fn game() -> App {
    let mut app = App::new();
    app.add_plugins((
        bevy_time::TimePlugin,
        bevy_transform::TransformPlugin,
        StochasticCollisionPlugin::default().with_config(CollisionConfig {
            budget: FrameBudget::Unlimited,
            ..Default::default()
        }),
    ))
    .insert_resource(bevy_time::TimeUpdateStrategy::FixedTimesteps(1))
    .init_resource::<EventLog>()
    .add_systems(Last, log_events);
    app
}

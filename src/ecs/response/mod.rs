//! Response stage: built-in responses that consume the [`ContactQueue`], as optional plugins.
//!
//! - [`ImpulseResponsePlugin`]: simple rigid bodies ([`BodyVelocity`], [`BodyAngularVelocity`],
//!   optional [`BodyMass`] and [`BodyInertia`], by default from the collider's mesh): integrates
//!   velocities under gravity before the pipeline, and resolves contacts with impulses at the
//!   contact point (restitution, friction, turning the bodies) and position correction.
//!   Bodies without `BodyVelocity` are static.
//! - [`PenaltyResponsePlugin`]: deformable meshes: pushes the vertices of the contact triangles
//!   apart along the contact normal (position correction), as a penalty force would.
//!
//! Each consumes contacts in priority order within the response budget
//! ([`CollisionConfig::response_budget`](crate::ecs::CollisionConfig::response_budget)); the
//! contacts it leaves stay queued for the next run.
//!
//! # Writing your own response
//! A system in [`CollisionSystems::Response`] that takes the contacts it handles:
//! ```
//! use bevy_app::prelude::*;
//! use bevy_ecs::prelude::*;
//! use stochastic_collision::prelude::*;
//!
//! #[derive(Component)]
//! struct Health(f32);
//!
//! fn damage(mut queue: ResMut<ContactQueue>, mut health: Query<&mut Health>) {
//!     queue.consume(|c| match health.get_mut(c.b) {
//!         Ok(mut h) => {
//!             h.0 -= c.depth * c.probability as f32;
//!             true // consumed
//!         }
//!         Err(_) => false, // not ours: leave it to other responses
//!     });
//! }
//!
//! let mut app = App::new();
//! app.add_plugins(StochasticCollisionPlugin::in_schedule(PostUpdate))
//!     .add_systems(PostUpdate, damage.in_set(CollisionSystems::Response));
//! app.world_mut().resource_mut::<ContactQueue>().enable();
//! ```
//!
//! [`CollisionSystems::Response`]: crate::ecs::CollisionSystems::Response
mod body;
mod impulse;
mod penalty;
mod queue;

use bevy_app::prelude::*;
use bevy_ecs::intern::Interned;
use bevy_ecs::schedule::ScheduleLabel;

pub use body::{BodyAngularVelocity, BodyInertia, BodyMass, BodyVelocity, InertiaSource, Rest};
pub use impulse::{
    DEFAULT_STEP, ImpulseResponsePlugin, ImpulseSettings, impulse_response, integrate_velocities,
    sleep_bodies, update_body_inertia,
};
pub use penalty::{PenaltyResponsePlugin, PenaltySettings, penalty_response};
pub use queue::ContactQueue;

use super::schedule::CollisionSchedule;

/// The schedule a response plugin runs in: the collision plugin's ([`CollisionSchedule`]).
///
/// # Panics
/// When the collision plugin was not added first, or `given` is another schedule: the
/// response's systems would run unordered with the pipeline (a set of the same name in a
/// schedule the pipeline is not in), a mistake better seen at startup than as contacts that
/// are never resolved.
pub(super) fn response_schedule(
    app: &App,
    given: Option<Interned<dyn ScheduleLabel>>,
    plugin: &str,
) -> Interned<dyn ScheduleLabel> {
    let Some(collision) = app.world().get_resource::<CollisionSchedule>() else {
        panic!("{plugin}: add StochasticCollisionPlugin before it (it runs in that schedule)");
    };
    match given {
        Some(s) if s != collision.0 => panic!(
            "{plugin} in {s:?}, but StochasticCollisionPlugin runs in {:?}: use \
             {plugin}::default(), which takes the collision plugin's schedule",
            collision.0
        ),
        _ => collision.0,
    }
}

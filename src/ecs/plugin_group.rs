//! The pipeline and the built-in responses in one plugin group, in one schedule.
use bevy_app::{PluginGroup, PluginGroupBuilder};
use bevy_ecs::schedule::ScheduleLabel;

use super::config::CollisionConfig;
use super::plugin::StochasticCollisionPlugin;
use super::response::{
    ImpulseResponsePlugin, ImpulseSettings, PenaltyResponsePlugin, PenaltySettings,
};

/// [`StochasticCollisionPlugin`] with [`ImpulseResponsePlugin`] (rigid bodies with
/// [`BodyVelocity`](super::BodyVelocity)) and [`PenaltyResponsePlugin`] (deformable meshes),
/// all in the collision plugin's schedule (default `FixedPostUpdate`). Leave a response out
/// with Bevy's `disable::<…>()`.
///
/// # Example
/// ```
/// use bevy_app::prelude::*;
/// use stochastic_collision::prelude::*;
///
/// let mut app = App::new();
/// app.add_plugins(StochasticCollisionPlugins::in_schedule(PostUpdate).build().disable::<PenaltyResponsePlugin>());
/// app.update();
/// ```
#[derive(Default)]
pub struct StochasticCollisionPlugins {
    /// The pipeline.
    pub collision: StochasticCollisionPlugin,
    /// The impulse response's settings.
    pub impulse: ImpulseSettings,
    /// The penalty response's settings.
    pub penalty: PenaltySettings,
}

impl StochasticCollisionPlugins {
    /// Everything in `schedule`, default settings.
    pub fn in_schedule(schedule: impl ScheduleLabel) -> Self {
        Self {
            collision: StochasticCollisionPlugin::in_schedule(schedule),
            ..Default::default()
        }
    }

    /// With this configuration of the pipeline.
    pub fn with_config(mut self, config: CollisionConfig) -> Self {
        self.collision.config = config;
        self
    }
}

impl PluginGroup for StochasticCollisionPlugins {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(self.collision)
            .add(ImpulseResponsePlugin::default().with_settings(self.impulse))
            .add(PenaltyResponsePlugin::default().with_settings(self.penalty))
    }
}

//! The plugin: the pipeline's systems in one schedule, its messages and resources.
use bevy_app::prelude::*;
use bevy_ecs::intern::Interned;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;

use super::broad_phase::{BroadPhaseState, update_broad_phase};
use super::budget::BudgetController;
use super::config::CollisionConfig;
use super::diagnostics::CollisionDiagnostics;
use super::events::{CollisionEnded, CollisionError, CollisionStarted, Contact, report_collisions};
use super::narrow_phase::{NarrowPhaseState, narrow_phase};
use super::pairs::PairTable;
use super::parallel::CollisionTaskPool;
use super::prepare::{
    ColliderTable, PrepareState, RemovedColliders, note_removed, refit_deformables,
    update_colliders,
};
use super::response::ContactQueue;
use super::schedule::{CollisionSchedule, CollisionSystems};
use super::tracking::{
    FeaturePairs, TrackingState, forget_untracked, holds_tracking_state, needs_self_pass,
    needs_tracking, prune_feature_pairs, self_collision, track_pairs,
};

/// Time-critical collision detection for triangle meshes, as a Bevy plugin.
///
/// Adds the pipeline ([`CollisionSystems`]: Prepare, BroadPhase, NarrowPhase, Tracking, Report,
/// Response, chained) to one schedule, the messages ([`CollisionStarted`], [`CollisionEnded`],
/// [`Contact`], [`CollisionError`]), and the resources ([`CollisionConfig`],
/// [`CollisionDiagnostics`], [`ContactQueue`]).
///
/// **Schedule.** The default is `FixedPostUpdate`, as for physics: it runs only with a time
/// plugin (bevy_time's `TimePlugin`, part of Bevy's `DefaultPlugins` and `MinimalPlugins`).
/// In a bare `App` from bevy_app alone, nothing ticks `FixedPostUpdate`: use
/// [`StochasticCollisionPlugin::in_schedule`] with `PostUpdate` (as the examples and tests do),
/// or run your own schedule label by hand.
///
/// **Threads.** Pairs are tested on bevy_tasks' `ComputeTaskPool` (initialised with one thread
/// per core if nobody did it before). On 2 cores, `TaskPoolPlugin::default()` gives that pool
/// only **one** thread; either configure the pool or set [`StochasticCollisionPlugin::threads`],
/// which gives the plugin its own pool of exactly that many threads (`Some(1)`: no pool).
///
/// # Example
/// ```
/// use bevy_app::prelude::*;
/// use bevy_ecs::prelude::*;
/// use stochastic_collision::prelude::*;
///
/// let mut app = App::new();
/// app.add_plugins(StochasticCollisionPlugin::in_schedule(PostUpdate));
/// let ball = MeshCollider::new(generate::icosphere(1.0, 2));
/// let a = app.world_mut().spawn((ball.clone(), ColliderPose::from_translation(Vec3::ZERO))).id();
/// let b = app.world_mut().spawn((ball, ColliderPose::from_translation(Vec3::X * 1.5))).id();
/// app.update();
///
/// let started = app.world().resource::<Messages<CollisionStarted>>();
/// assert_eq!(started.len(), 1);
/// assert!(app.world().get::<TouchingEntities>(a).unwrap().contains(b));
/// ```
pub struct StochasticCollisionPlugin {
    /// The schedule the pipeline runs in (default `FixedPostUpdate`).
    pub schedule: Interned<dyn ScheduleLabel>,
    /// The initial [`CollisionConfig`].
    pub config: CollisionConfig,
    /// Threads testing pairs: `None` uses bevy's `ComputeTaskPool`; `Some(n)` a pool of
    /// exactly `n` threads owned by the plugin (`Some(1)`: on the calling thread, no pool).
    pub threads: Option<usize>,
}

impl Default for StochasticCollisionPlugin {
    fn default() -> Self {
        Self::in_schedule(FixedPostUpdate)
    }
}

impl StochasticCollisionPlugin {
    /// The plugin running in `schedule`, default configuration.
    pub fn in_schedule(schedule: impl ScheduleLabel) -> Self {
        Self {
            schedule: schedule.intern(),
            config: CollisionConfig::default(),
            threads: None,
        }
    }

    /// With this configuration.
    pub fn with_config(mut self, config: CollisionConfig) -> Self {
        self.config = config;
        self
    }

    /// With a pool of exactly `threads` threads for the pair tests.
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.threads = Some(threads);
        self
    }
}

impl Plugin for StochasticCollisionPlugin {
    fn build(&self, app: &mut App) {
        use CollisionSystems::*;
        let s = self.schedule;
        super::reflect::register_types(app);
        app.add_message::<CollisionStarted>()
            .add_message::<CollisionEnded>()
            .add_message::<Contact>()
            .add_message::<CollisionError>()
            .insert_resource(self.config.clone())
            .insert_resource(CollisionSchedule(s))
            .insert_resource(CollisionTaskPool::new(self.threads))
            .init_resource::<CollisionDiagnostics>()
            .init_resource::<BudgetController>()
            .init_resource::<ColliderTable>()
            .init_resource::<PrepareState>()
            .init_resource::<RemovedColliders>()
            .add_observer(note_removed)
            .init_resource::<BroadPhaseState>()
            .init_resource::<PairTable>()
            .init_resource::<NarrowPhaseState>()
            .init_resource::<TrackingState>()
            .init_resource::<ContactQueue>()
            .configure_sets(
                s,
                (Prepare, BroadPhase, NarrowPhase, Tracking, Report, Response).chain(),
            )
            .add_systems(
                s,
                (
                    (
                        refit_deformables.run_if(super::prepare::any_stale),
                        update_colliders,
                    )
                        .chain()
                        .in_set(Prepare),
                    update_broad_phase.in_set(BroadPhase),
                    narrow_phase.in_set(NarrowPhase),
                    (
                        self_collision.run_if(needs_self_pass),
                        prune_feature_pairs.run_if(any_with_component::<FeaturePairs>),
                        track_pairs.run_if(needs_tracking),
                        forget_untracked.run_if(holds_tracking_state),
                    )
                        .chain()
                        .in_set(Tracking),
                    report_collisions.in_set(Report),
                    super::prepare::note_end_poses
                        .after(Response)
                        .run_if(any_with_component::<super::ContinuousCollision>),
                ),
            );
        #[cfg(feature = "transform")]
        app.add_systems(
            s,
            super::prepare::sync_transforms
                .in_set(Prepare)
                .before(update_colliders)
                .before(refit_deformables),
        );
        #[cfg(feature = "diagnostic")]
        super::diagnostics::store::register(app, s);
        #[cfg(feature = "bevy_mesh")]
        super::bevy_mesh::build(app);
    }
}

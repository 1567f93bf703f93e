//! The plugin and its configuration.
use std::time::Duration;

use bevy_app::prelude::*;
use bevy_ecs::intern::Interned;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;

use super::broad_phase::{BroadPhaseState, CandidatePairs, sweep_and_prune};
use super::components::Fidelity;
use super::diagnostics::CollisionDiagnostics;
use super::events::{
    CollisionEnded, CollisionError, CollisionStarted, Contact, ContactQueue, ReportState,
    report_collisions,
};
use super::narrow_phase::{PairOutcomes, narrow_phase};
use super::pool::CollisionTaskPool;
use super::prepare::{ColliderFrame, PrepareState, gather_colliders, refit_deformables};
use super::schedule::CollisionSystems;
use super::tracking_systems::{
    FeaturePairs, TrackingState, forget_untracked, holds_tracking_state, needs_self_pass,
    needs_tracking, prune_feature_pairs, self_collision, track_pairs,
};
use crate::adb::{Decision, Order};

/// How much work the collision stages (Prepare to Report) may do per run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrameBudget {
    /// No limit: ADB pairs run until their `p_min`/`k_min` rule settles them.
    Unlimited,
    /// A wall-clock budget for the collision stages (Prepare to Report). The narrow phase
    /// measures what a test and an answer from memory cost, and what came after it in the
    /// last run; it tests the exact pairs and then the most urgent others that fit in what is
    /// left (aiming a little below the budget when runs overran), sharing node pairs among the
    /// tested ADB pairs by priority. The others keep their previous answer
    /// ([`Method::Coherence`](super::Method::Coherence)). The Tracking stages (tracked pairs,
    /// self-collision) share the budget: past the run's deadline each tracker does an eighth
    /// of its work ([`Tracker::step_self_until`](crate::tracking::Tracker::step_self_until)).
    /// Results then depend on timing: use `NodePairs` for reproducible runs.
    Time(Duration),
    /// A work budget: this many ADB node pairs per run, shared among the ADB pairs by
    /// priority. Deterministic (same results for any thread count and machine).
    NodePairs(u64),
}

/// The plugin's configuration, a resource (change it at run time).
#[derive(Resource, Debug, Clone, PartialEq)]
pub struct CollisionConfig {
    /// Budget of the collision stages per run.
    pub budget: FrameBudget,
    /// Fidelity of rigid colliders without a [`Fidelity`] component.
    pub default_fidelity: Fidelity,
    /// `k_min` of the ADB queries (pieces of evidence needed).
    pub k_min: u32,
    /// ADB traversals test the triangles of the leaf pairs they reach exactly: a hit is a
    /// certain collision whose contact comes from the triangle pair (a good normal and depth);
    /// without, contacts come from the most probable node pair.
    pub adb_exact_leaves: bool,
    /// How ADB traversals decide ([`Decision`]). With exact leaves the two rules cost the same
    /// within the noise (the `accuracy_vs_time` report; the `profile` example's pile with
    /// `--adb-decision`); [`Decision::Confidence`], the default, more often ends a colliding
    /// query at an exact leaf hit, whose contact comes from the triangle pair.
    pub adb_decision: Decision,
    /// In which order ADB traversals expand node pairs ([`Order`]). The default,
    /// [`Order::Straddle`], dives to a first intersecting triangle pair and, with exact leaves,
    /// estimates only the pairs its evidence checks and its confidence need: the fastest
    /// order on the `accuracy_vs_time` report's poses, at the same error. Without exact leaves
    /// every pair is estimated whatever the order, and only the ranking differs.
    pub adb_order: Order,
    /// The confidence from which an ADB answer that its traversal did not settle (its slice
    /// ran out, or leaf pairs were left to their estimates) counts as a collision
    /// ([`AdbQuery::collide_at`](crate::adb::AdbQuery::collide_at); ½ by default, the fewest
    /// errors). Lower it where a missed contact costs more than a false one, as the
    /// `cannonball` example does for shots that would otherwise pass through the wall.
    pub adb_collide_at: f64,
    /// ADB queries first try the interpenetration certificate
    /// ([`AdbQuery::interior_after`](crate::adb::AdbQuery::interior_after)): a deep overlap is
    /// settled by a few dozen voxel lookups instead of a traversal, its contact the sample
    /// found inside the other mesh. On by default. Turn it off for scenes of small objects
    /// against thin parts (a ball against walls a few voxels thick): samples seldom land
    /// inside such parts, so it settles little there and costs its lookups on every pair (the
    /// `cannonball` example runs without it: half as much narrow-phase time again with it).
    pub adb_interior: bool,
    /// Node pairs every tested ADB pair gets whatever the budget (the root pair is always
    /// expanded). Under a time budget a tested pair gets at least an eighth of `max_slice`
    /// (the pairs tested were chosen by what a test costs; one cut short would be wasted),
    /// less only when the tests' deadline is that close.
    pub min_slice: u64,
    /// Node pairs an ADB pair gets at most, however generous the budget.
    pub max_slice: u64,
    /// Seed of all randomness (per pair: `(seed, frame, entities)`), so results do not depend on
    /// thread scheduling.
    pub seed: u64,
    /// Distance by which world boxes are inflated before the broad phase.
    pub aabb_margin: f32,
    /// Contacts reported per pair with a deformable mesh at most (rigid pairs report the
    /// first contact found).
    pub max_contacts_per_pair: usize,
    /// Contacts reported per self-colliding mesh at most.
    pub max_self_contacts: usize,
    /// Contacts the Response stage may consume per run (`None`: all of them). What is left
    /// stays in the [`ContactQueue`] for the next run, highest priority first.
    pub response_budget: Option<usize>,
}

impl Default for CollisionConfig {
    fn default() -> Self {
        Self {
            budget: FrameBudget::Time(Duration::from_micros(2000)),
            default_fidelity: Fidelity::Adb { p_min: 0.99 },
            k_min: 10,
            adb_exact_leaves: true,
            adb_decision: Decision::Confidence,
            adb_order: Order::Straddle,
            adb_collide_at: 0.5,
            adb_interior: true,
            min_slice: 4,
            max_slice: 4096,
            seed: 0x5eed,
            aabb_margin: 0.0,
            max_contacts_per_pair: 64,
            max_self_contacts: 256,
            response_budget: None,
        }
    }
}

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
/// let ball = Collider::new(generate::icosphere(1.0, 2));
/// let a = app.world_mut().spawn((ball.clone(), ColliderPose::from_translation(Vec3::ZERO))).id();
/// let b = app.world_mut().spawn((ball, ColliderPose::from_translation(Vec3::X * 1.5))).id();
/// app.update();
///
/// let started = app.world().resource::<Messages<CollisionStarted>>();
/// assert_eq!(started.len(), 1);
/// assert!(app.world().get::<CollidingEntities>(a).unwrap().contains(b));
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
        app.add_message::<CollisionStarted>()
            .add_message::<CollisionEnded>()
            .add_message::<Contact>()
            .add_message::<CollisionError>()
            .insert_resource(self.config.clone())
            .insert_resource(CollisionTaskPool::new(self.threads))
            .init_resource::<CollisionDiagnostics>()
            .init_resource::<ColliderFrame>()
            .init_resource::<PrepareState>()
            .init_resource::<BroadPhaseState>()
            .init_resource::<CandidatePairs>()
            .init_resource::<PairOutcomes>()
            .init_resource::<TrackingState>()
            .init_resource::<ReportState>()
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
                        gather_colliders,
                    )
                        .chain()
                        .in_set(Prepare),
                    sweep_and_prune.in_set(BroadPhase),
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
                ),
            );
        #[cfg(feature = "transform")]
        app.add_systems(
            s,
            super::prepare::sync_global_transforms
                .in_set(Prepare)
                .before(gather_colliders)
                .before(refit_deformables),
        );
        #[cfg(feature = "diagnostic")]
        super::diagnostics::store::register(app, s);
    }
}

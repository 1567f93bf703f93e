//! The pair filter hook: the app decides, with any read-only system parameter, which pairs of
//! close colliders are tested at all.
use std::marker::PhantomData;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_ecs::system::{ReadOnlySystemParam, StaticSystemParam, SystemParamItem};
use bevy_reflect::prelude::*;

use super::super::broad_phase::update_broad_phase;
use super::super::budget::BudgetController;
use super::super::prepare::ColliderTable;
use super::super::schedule::{CollisionSchedule, CollisionSystems};
use super::table::PairTable;

/// Decides whether a pair of colliders is tested: a read-only system parameter (queries,
/// resources) whose [`test_pair`](PairFilter::test_pair) is asked when the pair is created
/// (the broad phase found the two colliders close: their fat boxes started to overlap, or
/// one of them is new) and again when either collider's [`ContactLayers`] change or a
/// [`RefilterPairs`] message names one of them (write it when what the filter reads
/// changed, such as a team). A rejected
/// pair is never tested, never touching (a touching pair that is rejected ends its contact
/// with a `CollisionEnded`), and not listed by [`CollisionPairs`](super::CollisionPairs).
/// [`ContactLayers`] are applied first: the filter only sees pairs whose layers interact.
/// A mesh's own self-collision is not filtered.
///
/// Installed with [`PairFilterPlugin`]; an app has at most one (compose several rules in one
/// parameter).
///
/// [`ContactLayers`]: super::super::ContactLayers
///
/// # Example
/// Projectiles never hit the entity that shot them:
/// ```
/// use bevy_app::prelude::*;
/// use bevy_ecs::prelude::*;
/// use bevy_ecs::system::SystemParam;
/// use stochastic_collision::prelude::*;
///
/// #[derive(Component)]
/// struct ShotBy(Entity);
///
/// #[derive(SystemParam)]
/// struct NotTheShooter<'w, 's> {
///     shots: Query<'w, 's, &'static ShotBy>,
/// }
///
/// impl PairFilter for NotTheShooter<'_, '_> {
///     fn test_pair(&self, a: Entity, b: Entity) -> bool {
///         let shot_by = |x: Entity, y: Entity| self.shots.get(x).is_ok_and(|s| s.0 == y);
///         !shot_by(a, b) && !shot_by(b, a)
///     }
/// }
///
/// let mut app = App::new();
/// app.add_plugins((
///     StochasticCollisionPlugin::in_schedule(PostUpdate),
///     PairFilterPlugin::<NotTheShooter>::default(),
/// ));
/// let ball = MeshCollider::new(generate::icosphere(1.0, 2));
/// let gun = app.world_mut().spawn((ball.clone(), ColliderPose::default())).id();
/// let shot = app.world_mut().spawn((ball.clone(), ColliderPose::default(), ShotBy(gun))).id();
/// let wall = app.world_mut().spawn((ball, ColliderPose::from_translation(Vec3::X))).id();
/// app.update();
/// let touching = |a, b| app.world().get::<TouchingEntities>(a).unwrap().contains(b);
/// assert!(!touching(shot, gun));
/// assert!(touching(shot, wall) && touching(gun, wall));
/// ```
pub trait PairFilter: ReadOnlySystemParam + Send + Sync {
    /// Whether the pair of colliders `a` and `b` (`a < b`) is tested.
    fn test_pair(&self, a: Entity, b: Entity) -> bool;
}

/// Asks the app's [`PairFilter`] again about every pair of this entity, in the next run (the
/// message is registered by [`PairFilterPlugin`]).
#[derive(Message, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
#[reflect(Clone, Debug, PartialEq)]
pub struct RefilterPairs(pub Entity);

/// Installs the app's [`PairFilter`] `F` in the collision plugin's schedule, right after the
/// broad phase.
///
/// # Panics
/// When [`StochasticCollisionPlugin`](super::super::StochasticCollisionPlugin) was not added
/// first, or another pair filter is installed.
pub struct PairFilterPlugin<F>(PhantomData<fn() -> F>);

impl<F> Default for PairFilterPlugin<F> {
    fn default() -> Self {
        Self(PhantomData)
    }
}

/// The installed pair filter's type name.
#[derive(Resource)]
struct InstalledPairFilter(&'static str);

impl<F: PairFilter + 'static> Plugin for PairFilterPlugin<F>
where
    for<'w, 's> SystemParamItem<'w, 's, F>: PairFilter,
{
    fn build(&self, app: &mut App) {
        let name = std::any::type_name::<F>();
        let Some(schedule) = app.world().get_resource::<CollisionSchedule>() else {
            panic!("PairFilterPlugin<{name}>: add StochasticCollisionPlugin before it");
        };
        let schedule = schedule.0;
        if let Some(other) = app.world().get_resource::<InstalledPairFilter>() {
            panic!(
                "PairFilterPlugin<{name}>: the pair filter {} is installed already; an app has \
                 one pair filter (compose the rules in one system parameter)",
                other.0
            );
        }
        app.insert_resource(InstalledPairFilter(name))
            .add_message::<RefilterPairs>()
            .register_type::<RefilterPairs>();
        app.world_mut().resource_mut::<PairTable>().filtering = true;
        app.add_systems(
            schedule,
            filter_pairs::<F>
                .in_set(CollisionSystems::BroadPhase)
                .after(update_broad_phase),
        );
    }
}

/// Asks the filter about the pairs created since it last ran, the pairs of colliders whose
/// layers changed in this run and those of the entities named by [`RefilterPairs`];
/// excludes the rejected ones and includes the accepted ones that were excluded.
pub fn filter_pairs<F: PairFilter + 'static>(
    filter: StaticSystemParam<F>,
    mut pairs: ResMut<PairTable>,
    colliders: Res<ColliderTable>,
    budget: Res<BudgetController>,
    mut refilter: MessageReader<RefilterPairs>,
) where
    for<'w, 's> SystemParamItem<'w, 's, F>: PairFilter,
{
    let run = budget.run();
    let pairs = &mut *pairs;
    let mut asked = std::mem::take(&mut pairs.created);
    for &body in colliders.changed() {
        let e = colliders.entry(body);
        if e.filter_run == run {
            asked.extend_from_slice(e.pair_slots());
        }
    }
    for RefilterPairs(entity) in refilter.read() {
        if let Some(e) = colliders.get(*entity) {
            asked.extend_from_slice(e.pair_slots());
        }
    }
    asked.sort_unstable();
    asked.dedup();
    for &p in &asked {
        let (ends, slot) = (pairs.ends(p), pairs.slot(p));
        if !ends.live || slot.a == slot.b {
            continue;
        }
        if filter.test_pair(slot.a, slot.b) {
            pairs.include(p, run);
        } else {
            pairs.exclude(p, run);
        }
    }
    asked.clear();
    pairs.created = asked;
}

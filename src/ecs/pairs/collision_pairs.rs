//! Reading the pairs from any system: an entity's or a pair's contacts, touching or not, with
//! confidence and age, without a message per contact per run.
use bevy_ecs::prelude::*;
use bevy_ecs::system::SystemParam;

use super::super::budget::BudgetController;
use super::super::contact::ContactPoint;
use super::super::narrow_phase::{Method, PairOutcome, decayed_probability};
use super::super::prepare::ColliderTable;
use super::super::stamp::stamp;
use super::table::{PairEnds, PairHot, PairSlot, PairTable};

/// The collision pipeline's pairs, as a system parameter (read-only: any number of systems
/// may read it in parallel).
///
/// A pair exists while two colliders are close (their broad-phase boxes overlap); it is
/// *touching* from the run its `CollisionStarted` was written until its `CollisionEnded`.
/// Its answer holds until one of its colliders changes; [`PairView::age`] says how many runs
/// ago it was computed.
///
/// # Example
/// ```
/// use bevy_app::prelude::*;
/// use bevy_ecs::prelude::*;
/// use stochastic_collision::prelude::*;
///
/// fn report(collisions: CollisionPairs, q: Query<Entity, With<MeshCollider>>) {
///     for e in &q {
///         for pair in collisions.touching_of(e) {
///             let depth = pair.contacts().iter().map(|c| c.depth).fold(0.0, f32::max);
///             println!("{e:?} touches {:?}: p = {}, depth {depth}", pair.other(e), pair.probability());
///         }
///     }
/// }
///
/// let mut app = App::new();
/// app.add_plugins(StochasticCollisionPlugin::in_schedule(PostUpdate))
///     .add_systems(PostUpdate, report.after(CollisionSystems::Report));
/// let ball = MeshCollider::new(generate::icosphere(1.0, 2));
/// let a = app.world_mut().spawn((ball.clone(), ColliderPose::from_translation(Vec3::ZERO))).id();
/// let b = app.world_mut().spawn((ball, ColliderPose::from_translation(Vec3::X * 1.5))).id();
/// app.update();
/// let touching = app
///     .world_mut()
///     .run_system_once(move |c: CollisionPairs| c.touching(a, b))
///     .unwrap();
/// assert!(touching);
/// # use bevy_ecs::system::RunSystemOnce;
/// ```
#[derive(SystemParam)]
pub struct CollisionPairs<'w> {
    pairs: Res<'w, PairTable>,
    colliders: Res<'w, ColliderTable>,
    budget: Res<'w, BudgetController>,
}

impl<'w> CollisionPairs<'w> {
    /// The pair of `a` and `b` (in either order), if they are close.
    pub fn get(&self, a: Entity, b: Entity) -> Option<PairView<'_>> {
        let (a, b) = (a.min(b), a.max(b));
        self.of(a).find(|p| p.slot.a == a && p.slot.b == b)
    }

    /// Whether `a` and `b` are touching.
    pub fn touching(&self, a: Entity, b: Entity) -> bool {
        self.get(a, b).is_some_and(|p| p.touching())
    }

    /// Every pair `entity` is in (touching or not; `(entity, entity)` for a self-colliding
    /// mesh).
    pub fn of(&self, entity: Entity) -> impl Iterator<Item = PairView<'_>> {
        let run = self.budget.run();
        self.colliders
            .get(entity)
            .into_iter()
            .flat_map(|e| e.pair_slots().iter())
            .filter(|&&p| !self.pairs.ends(p).excluded)
            .map(move |&p| self.view(p, run))
    }

    /// The pairs `entity` is touching in.
    pub fn touching_of(&self, entity: Entity) -> impl Iterator<Item = PairView<'_>> {
        self.of(entity).filter(PairView::touching)
    }

    /// Every pair, in a stable order.
    pub fn iter(&self) -> impl Iterator<Item = PairView<'_>> {
        let run = self.budget.run();
        (0..self.pairs.slots.len() as u32)
            .filter(|&p| self.pairs.ends(p).live && !self.pairs.ends(p).excluded)
            .map(move |p| self.view(p, run))
    }

    fn view(&self, p: u32, run: u64) -> PairView<'_> {
        PairView {
            slot: self.pairs.slot(p),
            hot: self.pairs.hot(p),
            ends: self.pairs.ends(p),
            colliders: &self.colliders,
            run,
        }
    }
}

/// One pair as [`CollisionPairs`] shows it.
#[derive(Clone, Copy)]
pub struct PairView<'a> {
    slot: &'a PairSlot,
    hot: &'a PairHot,
    ends: &'a PairEnds,
    colliders: &'a ColliderTable,
    run: u64,
}

impl<'a> PairView<'a> {
    /// The two entities, smaller first (the same twice for a self-collision).
    pub fn entities(&self) -> (Entity, Entity) {
        (self.slot.a, self.slot.b)
    }

    /// The entity of the pair that is not `entity`.
    pub fn other(&self, entity: Entity) -> Entity {
        if self.slot.a == entity {
            self.slot.b
        } else {
            self.slot.a
        }
    }

    /// Whether the pair is touching (as the last Report said).
    pub fn touching(&self) -> bool {
        self.hot.touching
    }

    /// The run from which the touching state holds (the contact interval's start, or the
    /// run it ended or the pair appeared).
    pub fn since(&self) -> u64 {
        self.slot.since
    }

    /// Confidence that the pair collides now: the last answer's (1 or 0 for exact
    /// answers), drawn towards ½ as the colliders moved relative to each other since it was
    /// computed, when the pair was not tested since they moved.
    pub fn probability(&self) -> f64 {
        let o = &self.slot.outcome;
        let ends = (self.colliders.get(o.a), self.colliders.get(o.b));
        match (&self.hot.memory, ends) {
            (Some(m), (Some(ea), Some(eb))) if self.age() > 0 && o.a != o.b => {
                decayed_probability(m, self.slot.offset, (ea, eb))
            }
            _ => o.probability,
        }
    }

    /// How the answer was found.
    pub fn method(&self) -> Method {
        self.slot.outcome.method
    }

    /// The contact points (empty when not touching).
    pub fn contacts(&self) -> &'a [ContactPoint] {
        &self.slot.outcome.contacts
    }

    /// Runs since the answer was computed or confirmed (0: at this run's poses; a pair whose
    /// world boxes are apart is confirmed "not colliding" without a test). An answer of a pair
    /// none of whose colliders changed since holds whatever its age; an answer from memory
    /// ([`Method::Coherence`]) is that old.
    pub fn age(&self) -> u64 {
        u64::from(stamp(self.run).wrapping_sub(self.ends.checked_run))
    }

    /// The whole last answer.
    pub fn outcome(&self) -> &'a PairOutcome {
        &self.slot.outcome
    }
}

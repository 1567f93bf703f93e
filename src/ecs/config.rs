//! The plugin's configuration: budgets, ADB settings, contacts. A leaf module: it uses no
//! other module of the plugin but the components' [`Fidelity`].
use std::time::Duration;

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;

use super::components::Fidelity;
use crate::adb::{Decision, Order};

/// How much work the collision stages (Prepare to Report) may do per run.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Clone, Debug, PartialEq)]
pub enum FrameBudget {
    /// No limit: ADB pairs run until their `p_min`/`k_min` rule settles them.
    Unlimited,
    /// A wall-clock budget for the collision stages (Prepare to Report), planned by the
    /// [`BudgetController`](super::BudgetController) from measured costs: the narrow phase
    /// tests the exact pairs and the pairs with a collider swept in the run
    /// ([`ContinuousCollision`](super::ContinuousCollision): put off, their test would miss
    /// the motion; past the deadline an ADB one gets the smallest budget) and then, in what is
    /// left (aiming a little below the budget when runs overran), the pairs that waited
    /// longest (a quarter of the tests) and the most urgent others, sharing node pairs among
    /// the tested ADB pairs by priority. The others keep their last answer, one run older
    /// ([`PairView::age`](super::PairView::age); an exact pair past its deadline gets one
    /// from memory: exact where its remembered crossing triangle pair still crosses or its
    /// root boxes are apart, else [`Method::Coherence`](super::Method::Coherence)), and wait
    /// for a test.
    /// The Tracking stages (tracked pairs, self-collision) share the budget: each tracker
    /// spends its share of the time left before the run's deadline as its own
    /// [`TrackerConfig::time_budget`](crate::tracking::TrackerConfig::time_budget) (its pairs
    /// per frame adapt to it), and past the deadline each tracker does an eighth of its work
    /// ([`Tracker::step_self_until`](crate::tracking::Tracker::step_self_until)).
    /// Results then depend on timing: use `NodePairs` for reproducible runs.
    Time(Duration),
    /// A work budget: this many ADB node pairs per run, shared among the ADB pairs by
    /// priority. Deterministic (same results for any thread count and machine).
    NodePairs(u64),
}

/// How much the Response stage may do per run: the built-in responses and
/// [`ContactQueue::consume`](super::ContactQueue::consume) stop offering contacts once it is
/// spent; what is left stays queued, highest priority first, for the next run.
#[derive(Reflect, Debug, Clone, Copy, PartialEq, Default)]
#[reflect(Clone, Debug, Default, PartialEq)]
pub enum ResponseBudget {
    /// Every contact is offered.
    #[default]
    Unlimited,
    /// A wall-clock budget, like the collision stages' [`FrameBudget::Time`]: the time spent
    /// inside `consume` (the responses' work on each contact) on the
    /// [`BudgetController`](super::BudgetController)'s clock, shared by every response of the
    /// run. A run always offers at least one contact while the budget is not zero, so the
    /// queue drains however slow a response is.
    Time(Duration),
    /// At most this many contacts consumed per run: a work budget, reproducible on any
    /// machine.
    Contacts(usize),
}

/// The plugin's configuration, a resource (change it at run time).
#[derive(Resource, Reflect, Debug, Clone, PartialEq)]
#[reflect(Resource, Clone, Debug, Default, PartialEq)]
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
    /// How ADB traversals decide ([`Decision`]). [`Decision::Confidence`], the default, more
    /// often ends a colliding query at an exact leaf hit, whose contact comes from the triangle
    /// pair, than [`Decision::Evidence`], which may stop earlier on a contact region (the
    /// `accuracy_vs_time` report and the `profile` example's `--adb-decision` compare them).
    #[reflect(remote = super::reflect::DecisionReflect)]
    pub adb_decision: Decision,
    /// In which order ADB traversals expand node pairs ([`Order`]). The default,
    /// [`Order::Straddle`], dives to a first intersecting triangle pair and, with exact leaves,
    /// estimates only the pairs its evidence checks and its confidence need (the
    /// `accuracy_vs_time` report compares the orders). Without exact leaves every pair is
    /// estimated whatever the order, and only the ranking differs.
    #[reflect(remote = super::reflect::OrderReflect)]
    pub adb_order: Order,
    /// The confidence from which an ADB answer that its traversal did not settle (its slice
    /// ran out, or leaf pairs were left to their estimates) counts as a collision
    /// ([`AdbQuery::collide_at`](crate::adb::AdbQuery::collide_at); ½ by default, the fewest
    /// errors when the confidence is calibrated). Lower it where a missed contact costs more
    /// than a false one, as the `cannonball` example does for shots that would otherwise pass
    /// through the wall.
    pub adb_collide_at: f64,
    /// ADB queries first try the interpenetration certificate
    /// ([`AdbQuery::interior_after`](crate::adb::AdbQuery::interior_after)): a deep overlap is
    /// settled by a few dozen voxel lookups instead of a traversal, its contact the sample
    /// found inside the other mesh. On by default. Turn it off for scenes of small objects
    /// against thin parts (a ball against walls a few voxels thick): samples seldom land
    /// inside such parts, so it settles little there and costs its lookups on every pair (the
    /// `cannonball` example runs without it unless its last argument is `on`).
    pub adb_interior: bool,
    /// Node pairs every tested ADB pair gets whatever the budget (the root pair is always
    /// expanded). Under a time budget a tested pair gets at least an eighth of `max_slice`
    /// (the pairs tested were chosen by what a test costs; one cut short would be wasted),
    /// less only when the tests' deadline is that close.
    pub min_slice: u64,
    /// Node pairs an ADB pair gets at most, however generous the budget. The continuous test
    /// of a swept ADB pair (`ContinuousCollision`) gets, under a time budget, this much as far
    /// as the time left allows, and an eighth of it even past the deadline.
    pub max_slice: u64,
    /// Seed of all randomness (per pair: `(seed, frame, entities)`), so results do not depend on
    /// thread scheduling.
    pub seed: u64,
    /// Distance by which world boxes are inflated before the broad phase.
    pub aabb_margin: f32,
    /// How far a collider may move before the broad phase looks at it again, as a fraction
    /// of its world box's largest extent: its broad-phase (fat) box is its world box grown
    /// by this much and stretched along six times its last motion. Larger: fewer broad-phase
    /// updates, more pairs whose world boxes are checked for overlap.
    pub proxy_margin: f32,
    /// Write a [`Contact`](super::Contact) message per contact point of every pair answered
    /// in a run (off by default: contacts are read through
    /// [`CollisionPairs`](super::CollisionPairs), and responses take them from the
    /// [`ContactQueue`](super::ContactQueue)).
    pub contact_messages: bool,
    /// Contacts reported per pair with a deformable mesh at most, evenly spread over the
    /// crossing triangle pairs (rigid pairs report one contact, see
    /// [`CollisionConfig::contact_regions`]). In an exact pair, a deformable's vertices wholly
    /// inside a closed partner get as many again at most, a different share of them each run.
    pub max_contacts_per_pair: usize,
    /// The one contact of a rigid pair tested exactly summarises its whole contact region:
    /// the mean of the meeting points of every intersecting triangle pair, their mean normal,
    /// the largest depth. Without, it is the first intersecting triangle pair found (a test
    /// that stops early, but whose point can lie anywhere in the region: a response that
    /// turns bodies would spin them about it). Off by default;
    /// [`ImpulseResponsePlugin`](super::ImpulseResponsePlugin) turns it on.
    pub contact_regions: bool,
    /// Contacts reported per self-colliding mesh at most.
    pub max_self_contacts: usize,
    /// How far (a fraction of its world box's smallest extent) a collider with
    /// [`ContinuousCollision::WhenFast`](super::ContinuousCollision::WhenFast) must move in a
    /// run to be swept. Default ¼: a ball moving a quarter of its diameter per run cannot
    /// pass through anything at least half its diameter thick between runs.
    pub continuous_motion: f32,
    /// How a swept pair tested with ADB is tested over its motion: with the time-critical
    /// continuous query ([`ccd::adb_time_of_impact`](crate::ccd::adb_time_of_impact)) within
    /// the pair's ADB budget. Conservative (the default): when the budget runs out with node
    /// pairs left, the pair collides at the earliest time one can meet (no tunnelling is ever
    /// missed, some contacts are false). Otherwise it collides when the confidence of what
    /// is left (the fitted [`SweptAnswerModel`](crate::ccd::SweptAnswerModel)) reaches
    /// [`adb_collide_at`](Self::adb_collide_at).
    pub continuous_adb_conservative: bool,
    /// How much the Response stage may do per run ([`ResponseBudget`]; unlimited by default).
    /// What is left stays in the [`ContactQueue`](super::ContactQueue) for the next run,
    /// highest priority first.
    pub response_budget: ResponseBudget,
}

impl CollisionConfig {
    /// The fewest node pairs a tested ADB pair gets under a time budget: an eighth of
    /// `max_slice`, and `min_slice` at least (its tests were chosen by what a test costs, so
    /// each gets enough to settle; a test cut short is wasted).
    pub(crate) fn timed_slice_floor(&self) -> u64 {
        self.min_slice.max(self.max_slice / 8)
    }
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
            proxy_margin: 0.1,
            contact_messages: false,
            max_contacts_per_pair: 64,
            contact_regions: false,
            max_self_contacts: 256,
            continuous_motion: 0.25,
            continuous_adb_conservative: true,
            response_budget: ResponseBudget::Unlimited,
        }
    }
}

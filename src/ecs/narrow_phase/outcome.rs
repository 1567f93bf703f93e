//! What a pair's answer is: how it was found, whether it collides and how surely, its contacts.
use bevy_ecs::prelude::*;
use smallvec::SmallVec;

use super::super::contact::ContactPoint;

/// How a pair's answer was found.
#[derive(bevy_reflect::Reflect, Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[reflect(Clone, Debug, PartialEq, Hash)]
pub enum Method {
    /// World boxes only.
    Bounds,
    /// The exact BVH query.
    Exact,
    /// The ADB traversal (cut by its slice of the budget).
    Adb,
    /// The Tracking stage (tracked pairs).
    Tracking,
    /// The self-collision pass of a deformable mesh (`a == b`).
    SelfCollision,
    /// Not tested: under a time budget, the deadline passed before an exact pair's turn
    /// (exact pairs are always chosen and tested first, so only an overload of exact pairs
    /// alone cuts them). Such a pair is first answered exactly where a cheap test at the
    /// current poses decides it (then its method is `Exact`): its remembered crossing triangle
    /// pair still crosses (it collides), or its oriented root boxes are apart (it does not).
    /// Otherwise the answer comes from the pair's memory (`Coherence`): a pair that collided
    /// keeps colliding, with a probability that decays with the motion since its test, its
    /// contact re-measured on its triangle pair at the current poses; one that did not, or
    /// was never tested, collides (its oriented root boxes overlap; level geometry must not be
    /// passed through) with probability 0.5 and a box contact.
    /// Other pairs not tested keep their last answer instead: its
    /// [`run`](PairOutcome::run) is earlier, its touching state and contacts stand (the
    /// contacts without depth in this run's contact queue: they stop approach without
    /// pushing the same correction twice).
    Coherence,
}

impl Method {
    /// Whether an answer found by this method with `probability` is certain: an exact test,
    /// the Tracking stage or the self-collision pass, with probability 1 (not estimated,
    /// guessed from boxes, answered from memory, or decayed since it was computed).
    pub fn is_certain(self, probability: f64) -> bool {
        matches!(
            self,
            Method::Exact | Method::SelfCollision | Method::Tracking
        ) && probability >= 1.0
    }
}

/// The answer for one pair.
#[derive(Debug, Clone, PartialEq)]
pub struct PairOutcome {
    /// First entity (the smaller).
    pub a: Entity,
    /// Second entity (`a` itself for a self-collision).
    pub b: Entity,
    /// How it was found.
    pub method: Method,
    /// Whether the pair is reported as colliding.
    pub collides: bool,
    /// Confidence that it collides (1 or 0 for exact answers).
    pub probability: f64,
    /// Node pairs (box tests or estimates) the query visited.
    pub node_pairs: u64,
    /// Whether an ADB query ran out of its slice before settling.
    pub budget_exhausted: bool,
    /// The pair's priority in the run it was answered.
    pub priority: f32,
    /// Contact points (empty when not colliding).
    pub contacts: SmallVec<[ContactPoint; 1]>,
    /// The run ([`CollisionDiagnostics::frame`](super::super::CollisionDiagnostics::frame))
    /// in which this answer was given.
    pub run: u64,
    /// The run at whose poses the answer was computed: `run` for a test, earlier for an
    /// answer from memory. A pair not worked on keeps its answer; `run` and `computed_run`
    /// then say how old it is (it still holds: neither collider changed since).
    pub computed_run: u64,
}

impl PairOutcome {
    /// The answer of a pair not worked on yet: not colliding, as uncertain as can be.
    pub(crate) fn untested((a, b): (Entity, Entity), run: u64) -> Self {
        Self {
            probability: 0.5,
            ..Self::exact((a, b), Method::Bounds, 0, 0.0, SmallVec::new(), run)
        }
    }

    /// An exact answer from contacts found in `run`: colliding iff there is one.
    pub(crate) fn exact(
        (a, b): (Entity, Entity),
        method: Method,
        node_pairs: u64,
        priority: f32,
        contacts: SmallVec<[ContactPoint; 1]>,
        run: u64,
    ) -> Self {
        let collides = !contacts.is_empty();
        Self {
            a,
            b,
            method,
            collides,
            probability: f64::from(u8::from(collides)),
            node_pairs,
            budget_exhausted: false,
            priority,
            contacts,
            run,
            computed_run: run,
        }
    }
}

//! How precisely an entity collides: its fidelity, self-collision, continuous collision.

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;

/// How precisely an entity's pairs are tested. A pair uses the more accurate fidelity of its
/// two entities (`Exact` > `Tracking` > `Adb` > `Bounds`; two `Adb` take the higher `p_min`).
///
/// An entity without this component uses [`CollisionConfig::default_fidelity`]
/// (rigid colliders) or `Exact` (deformables).
///
/// [`CollisionConfig::default_fidelity`]: crate::ecs::CollisionConfig::default_fidelity
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Component, Clone, Debug, PartialEq)]
pub enum Fidelity {
    /// The exact BVH query: a certain answer. Not cut by a work budget; under a time budget,
    /// exact pairs are tested first, and those whose turn comes after the deadline get an
    /// answer from their memory: exact where their remembered crossing triangle pair still
    /// crosses or their root boxes are apart, else
    /// [`Method::Coherence`](crate::ecs::Method::Coherence).
    Exact,
    /// The time-critical ADB traversal with this confidence target, cut by the pair's slice
    /// of the frame budget: the answer carries its probability.
    Adb {
        /// Confidence the answer needs (the papers use 0.99; lower: the traversal may stop
        /// sooner, on weaker evidence).
        p_min: f64,
    },
    /// Stochastic closest-feature tracking (contacts with points, normals and depths),
    /// tracking this many feature pairs per frame. Runs in the Tracking stage.
    Tracking {
        /// New feature pairs drawn per frame and pair: under a time budget
        /// ([`FrameBudget::Time`](crate::ecs::FrameBudget::Time)) where the tracker starts
        /// before it adapts to its share, otherwise the least it draws (more where its
        /// surfaces come close to each other in many places:
        /// [`TrackerConfig::overlaps_per_pair`](crate::tracking::TrackerConfig::overlaps_per_pair)).
        pairs_per_frame: u32,
    },
    /// World boxes only: the pair collides when the boxes overlap (triggers, far objects).
    Bounds,
}

impl Fidelity {
    /// Rank for "the more accurate wins".
    pub(crate) fn rank(&self) -> u8 {
        match self {
            Fidelity::Bounds => 0,
            Fidelity::Adb { .. } => 1,
            Fidelity::Tracking { .. } => 2,
            Fidelity::Exact => 3,
        }
    }

    /// The fidelity of a pair: the more accurate of the two.
    pub fn combine(self, other: Fidelity) -> Fidelity {
        match (self, other) {
            (Fidelity::Adb { p_min: a }, Fidelity::Adb { p_min: b }) => {
                Fidelity::Adb { p_min: a.max(b) }
            }
            (
                Fidelity::Tracking { pairs_per_frame: a },
                Fidelity::Tracking { pairs_per_frame: b },
            ) => Fidelity::Tracking {
                pairs_per_frame: a.max(b),
            },
            (a, b) if b.rank() > a.rank() => b,
            (a, _) => a,
        }
    }
}

/// Marks a [`Deformable`](crate::ecs::Deformable) whose mesh may collide with itself: the self-collision pass (in the
/// Tracking stage) runs only when some entity has this marker. Ignored on rigid colliders (a
/// rigid mesh's self-intersections never change).
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Clone, Debug, Default)]
pub struct SelfCollision;

/// Continuous collision: a collider with it cannot pass through a thin mesh between two runs
/// unseen.
///
/// - **Rigid pairs tested exactly or with ADB**: in a run where a rigid collider with it
///   moved, its pairs are tested over the whole motion since the last run (from its last
///   pose to this one, translation and rotation). Its broad-phase box covers the motion; a
///   pair whose discrete test finds no contact, or that did not touch before, gets the exact
///   continuous query ([`ccd::time_of_impact`](crate::ccd::time_of_impact)), and a contact it
///   finds carries its time of impact
///   ([`ContactPoint::time_of_impact`](crate::ecs::ContactPoint::time_of_impact)).
/// - **Exact pairs with a [`Deformable`](crate::ecs::Deformable)**: a deformable with it keeps
///   its mesh in world coordinates as of its last update; in a run where it changed
///   (vertices or pose), its pairs are tested over the motion from that state to the new one,
///   each vertex on a straight line, and so are a swept rigid collider's pairs with any
///   deformable
///   ([`ccd::deforming_time_of_impact`](crate::ccd::deforming_time_of_impact): the rigid
///   partner placed at its poses before and after its motion, its vertices on straight lines
///   between them; a deformable partner without the component where it is now). It costs a
///   copy of the mesh per run for each continuous deformable that changed, and per swept pair
///   with a deformable the partners' meshes placed in world coordinates.
/// - **Tracked pairs and tracked self-collision** ([`Fidelity::Tracking`], rigid or
///   [`Deformable`](crate::ecs::Deformable)): the pair's tracker is continuous
///   ([`TrackerConfig::continuous`](crate::tracking::TrackerConfig::continuous)) in every run,
///   whichever variant: the neighbourhoods of its feature pairs are checked over both
///   colliders' motions in the run and their deformation since the last run, so a fold, a
///   sheet or a thin body passing through between two runs is reported, with its time of
///   impact. Approximate, as the tracking is: a crossing far from every feature pair is not
///   seen.
///
/// A move is swept as a straight motion whatever caused it: remove the component for a
/// teleport. A swept pair is tested in its run whatever the time budget (an ADB one past the
/// deadline with the smallest node budget). A flat deformable's smallest extent is nil, so
/// `WhenFast` sweeps it whenever it changes.
#[derive(Component, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub enum ContinuousCollision {
    /// Swept whenever it moves.
    Always,
    /// Swept in runs where it moves farther than
    /// [`CollisionConfig::continuous_motion`](crate::ecs::CollisionConfig::continuous_motion) of its
    /// world box's smallest extent (fast enough to pass through something thin); otherwise
    /// tested at its pose, as other colliders.
    #[default]
    WhenFast,
}

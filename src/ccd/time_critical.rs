//! The time-critical continuous query over ADB-trees: whether, and when, two rigid meshes touch
//! during a step, within a budget, with a confidence.
//!
//! It runs the exact continuous search ([`time_of_impact`](super::time_of_impact)'s) until the
//! budget runs out. If the search ends first, the answer is exact. Otherwise the node pairs it
//! left unexplored are what could still hold an earlier (or the only) contact: each is given
//! the ADB probability model's estimate at the moment in the step when its boxes' centres come
//! closest (the swept pair at its deepest, the pose where the discrete model sees it most
//! likely to collide); the answer's confidence is the [`SweptAnswerModel`]'s, fitted on swept
//! pairs, from those estimates and what else the search left.
//! The conservative variant answers "collision" whenever any pair is left, at the earliest
//! time one can meet: at a given budget it never misses a contact, it only adds false ones.
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;

use super::descent::{SearchLimit, search};
use super::impact::TimeOfImpact;
use super::motion::RigidMotion;
use super::query::{
    CcdError, CcdOptions, CcdWorkspace, RigidPair, overlap_at_start, validate_motions,
};
use super::swept_answer_model::{SweptAnswerModel, SweptFrontier};
use crate::adb::{AdbTree, Budget, CalibratedEstimator, CollisionEstimator, NodePair};

/// Disjoint node pairs of one contact region count as one piece of evidence per this many, as
/// in the discrete query's confidence.
const REDUNDANCY: f64 = 2.0;

/// The highest probability an estimate may give (only an exact contact is certain).
const MAX_ESTIMATE: f64 = 1.0 - 1e-9;

/// Parameters of [`adb_time_of_impact`].
#[derive(Debug, Clone)]
pub struct ContinuousAdbQuery {
    /// When the search stops: [`Budget::NodePairs`] counts the node pairs it examines,
    /// [`Budget::Time`] the time since the query started (read every 16 node pairs).
    pub budget: Budget,
    /// The probability model for the node pairs left when the budget runs out.
    pub estimator: Arc<dyn CollisionEstimator>,
    /// How those estimates become the answer's confidence (by default the fitted
    /// [`SweptAnswerModel`]).
    pub confidence: SweptConfidence,
    /// The confidence from which an unsettled answer says "collision" (½ by default; not read
    /// when [`conservative`](Self::conservative)). A confidence of 0 never says "collision".
    pub collide_at: f64,
    /// An unsettled answer with any node pair left says "collision", at the earliest time that
    /// pair's boxes can meet: no contact is ever missed, whatever the budget.
    pub conservative: bool,
    /// Tolerances of the exact search.
    pub options: CcdOptions,
}

impl Default for ContinuousAdbQuery {
    /// No budget (the exact answer), the calibrated estimator, the fitted answer model,
    /// `collide_at` ½, not conservative.
    fn default() -> Self {
        Self {
            budget: Budget::Unlimited,
            estimator: Arc::new(CalibratedEstimator::default()),
            confidence: SweptConfidence::Model(SweptAnswerModel::FITTED),
            collide_at: 0.5,
            conservative: false,
            options: CcdOptions::default(),
        }
    }
}

impl ContinuousAdbQuery {
    /// The conservative query within `budget`: never misses a contact.
    pub fn conservative(budget: Budget) -> Self {
        Self {
            budget,
            conservative: true,
            ..Self::default()
        }
    }

    /// The estimating query within `budget`.
    pub fn with_budget(budget: Budget) -> Self {
        Self {
            budget,
            ..Self::default()
        }
    }
}

/// How an unsettled continuous answer's confidence is made from what the search left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SweptConfidence {
    /// A logistic model of the [`SweptFrontier`]'s features, fitted on swept pairs (the
    /// default: [`SweptAnswerModel::FITTED`]).
    Model(SweptAnswerModel),
    /// The node pairs' estimates combined as the discrete query combines its frontier,
    /// `1 − (Π (1 − p))^(1/2)` ([`SweptFrontier::raw_confidence`]): not calibrated on swept
    /// pairs (too low under a tight budget, too high under a looser one).
    Combined,
}

/// Where an unsettled "collision" probably is: the most probable node pair left, at the moment
/// its boxes' centres come closest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweptWitness {
    /// Midway between the two nodes' box centres then (world coordinates).
    pub point: Vec3,
    /// The direction from the second mesh towards the first: along the second node's motion
    /// relative to the first's over the step (the way it came), or between their centres
    /// when they do not move relative to each other.
    pub normal: Vec3,
    /// The node pair (first tree, second tree).
    pub nodes: (u32, u32),
    /// That moment, as a fraction of the step.
    pub time: f32,
    /// The pair's estimated probability.
    pub probability: f64,
}

/// The answer of [`adb_time_of_impact`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContinuousAdbOutcome {
    /// Whether the meshes are reported as touching during the step.
    pub collides: bool,
    /// Confidence that they touch: 1 when an exact contact was found, 0 when the search ended
    /// without one; otherwise the query's [`SweptConfidence`] of what the search left (by
    /// default the fitted [`SweptAnswerModel`]), an estimate.
    pub probability: f64,
    /// When they touch, if reported so: never later than the first contact. Settled: the time
    /// of impact; otherwise the earliest time a node pair left (or the contact found) can meet.
    pub time: Option<f32>,
    /// The earliest exact contact found (the first contact when the search settled).
    pub impact: Option<TimeOfImpact>,
    /// Where an unsettled collision probably is.
    pub witness: Option<SweptWitness>,
    /// Whether the search ran to its end (the answer is the exact query's).
    pub settled: bool,
    /// Whether the budget ran out first.
    pub budget_exhausted: bool,
    /// Node pairs examined.
    pub node_pairs_visited: u64,
    /// Node pairs left when the budget ran out.
    pub frontier_pairs: u32,
    /// What the search left when the budget ran out before it found a contact (the answer
    /// model's input).
    pub frontier: Option<SweptFrontier>,
}

/// Whether, when and how likely two rigid ADB-trees moving over a step touch, within the
/// query's budget. With [`Budget::Unlimited`] the answer is the exact
/// [`time_of_impact`](super::time_of_impact)'s.
///
/// The exact continuous search runs until the budget runs out. If it ends first, the answer
/// is exact. Otherwise the node pairs it left are what could still hold an earlier (or the
/// only) contact: each is given the ADB probability model's estimate at the moment in the step
/// when its boxes' centres come closest (the swept pair at its deepest), and the answer's
/// confidence is the query's [`SweptConfidence`] of them and of what else the search left
/// (by default the [`SweptAnswerModel`] fitted on swept pairs). The conservative
/// variant says "collision" whenever a pair is left, at the earliest time one can meet: at a
/// given budget it misses no contact, it only adds false ones.
///
/// # Example
/// A ball shot through a thin wall in one step, with a budget of 40 node pairs: the
/// conservative query never misses it.
/// ```
/// use stochastic_collision::adb::{AdbTree, Budget};
/// use stochastic_collision::ccd::{
///     CcdWorkspace, ContinuousAdbQuery, RigidMotion, adb_time_of_impact,
/// };
/// use stochastic_collision::prelude::*;
///
/// let ball = AdbTree::new(CollisionMesh::new(generate::icosphere(0.5, 3)));
/// let wall = AdbTree::new(CollisionMesh::new(generate::cuboid(Vec3::new(0.05, 2.0, 2.0), 4)));
/// let shot = RigidMotion::new(
///     Pose::from_translation(Vec3::new(-3.0, 0.3, 0.0)),
///     Pose::from_translation(Vec3::new(3.0, 0.3, 0.0)),
/// );
/// let still = RigidMotion::still(Pose::IDENTITY);
/// let mut ws = CcdWorkspace::new();
/// let query = ContinuousAdbQuery::conservative(Budget::NodePairs(40));
/// let out = adb_time_of_impact(&ball, &shot, &wall, &still, &query, &mut ws).unwrap();
/// assert!(out.collides);
/// // Never later than the contact (after 2.45 of the 6 units).
/// assert!(out.time.unwrap() <= 2.45 / 6.0);
/// ```
pub fn adb_time_of_impact(
    a: &AdbTree,
    motion_a: &RigidMotion,
    b: &AdbTree,
    motion_b: &RigidMotion,
    query: &ContinuousAdbQuery,
    ws: &mut CcdWorkspace,
) -> Result<ContinuousAdbOutcome, CcdError> {
    let start = Instant::now();
    validate_motions(motion_a, motion_b)?;
    let (ma, mb) = (a.collision_mesh(), b.collision_mesh());
    ws.triangle_pairs = 0;
    ws.descent.triangle_pairs = 0;
    let mut out = ContinuousAdbOutcome {
        collides: false,
        probability: 0.0,
        time: None,
        impact: None,
        witness: None,
        settled: true,
        budget_exhausted: false,
        node_pairs_visited: 0,
        frontier_pairs: 0,
        frontier: None,
    };
    if let Some(hit) = overlap_at_start(ma, &motion_a.start, mb, &motion_b.start, ws) {
        return Ok(ContinuousAdbOutcome {
            collides: true,
            probability: 1.0,
            time: Some(0.0),
            impact: Some(hit),
            ..out
        });
    }
    let step = RigidPair::new(
        (ma, motion_a),
        (mb, motion_b),
        &query.options,
        &mut ws.poses,
    );
    let mut limit = match query.budget {
        Budget::Unlimited => SearchLimit::default(),
        Budget::NodePairs(n) => SearchLimit {
            pops: Some(n.max(1)),
            deadline: None,
        },
        Budget::Time(d) => SearchLimit {
            pops: None,
            deadline: Some(start + d),
        },
    };
    let end = search(
        &step.a,
        &step.b,
        &step.tol,
        step.growth,
        &mut limit,
        &mut ws.descent,
    );
    ws.triangle_pairs = ws.descent.triangle_pairs;
    out.node_pairs_visited = end.pops;
    out.settled = end.settled;
    out.budget_exhausted = !end.settled;
    out.impact = end.hit;
    if end.settled {
        out.collides = end.hit.is_some();
        out.probability = if out.collides { 1.0 } else { 0.0 };
        out.time = end.hit.map(|h| h.time);
        return Ok(out);
    }
    // The pairs left: each at its closest approach, combined as the discrete query does.
    let radius = |tree: &AdbTree, i: u32| {
        f64::from(
            tree.collision_mesh().bvh().nodes()[i as usize]
                .aabb()
                .extents()
                .length(),
        ) * 0.5
    };
    let mut log_miss = 0.0f64;
    let mut earliest = f64::INFINITY;
    let mut windows = 0.0f64;
    let mut nearest = f64::INFINITY;
    let mut deepest = 0.0f64;
    let mut best: Option<(f64, super::descent::FrontierPair)> = None;
    for pair in ws.descent.frontier(step.pieces, end.until) {
        out.frontier_pairs += 1;
        earliest = earliest.min(pair.from);
        windows += (pair.to - pair.from).max(0.0);
        let reach = radius(a, pair.a) + radius(b, pair.b);
        nearest = nearest.min(if reach > 0.0 {
            pair.centre_distance / reach
        } else {
            0.0
        });
        deepest = deepest.max(pair.depth);
        let estimate =
            NodePair::at_distance(a, b, pair.centre_distance as f32, pair.a, pair.b, true);
        let p = query
            .estimator
            .probability(&estimate)
            .clamp(0.0, MAX_ESTIMATE);
        log_miss += (1.0 - p).ln();
        if best.as_ref().is_none_or(|(q, _)| p > *q) {
            best = Some((p, pair));
        }
    }
    let left = out.frontier_pairs > 0;
    let raw = if left {
        1.0 - (log_miss / REDUNDANCY).exp()
    } else {
        0.0
    };
    let diagonal =
        |tree: &AdbTree| f64::from(tree.collision_mesh().bvh().root_aabb().extents().length());
    let frontier = SweptFrontier {
        raw_confidence: raw,
        max_probability: best.as_ref().map_or(0.0, |(p, _)| *p),
        pairs: out.frontier_pairs,
        visited: end.pops,
        nearest_centres: if left { nearest } else { 0.0 },
        mean_window: windows / f64::from(out.frontier_pairs.max(1)),
        earliest: if left { earliest.clamp(0.0, 1.0) } else { 0.0 },
        size_ratio: diagonal(a) / diagonal(b).max(f64::MIN_POSITIVE),
        tree_nodes: (ma.bvh().nodes().len() + mb.bvh().nodes().len()) as u64,
        deepest,
    };
    let estimated = match (left, query.confidence) {
        (false, _) => 0.0,
        (true, SweptConfidence::Combined) => raw,
        (true, SweptConfidence::Model(model)) => model.confidence(&frontier),
    };
    let earliest = earliest.clamp(0.0, 1.0) as f32;
    if let Some(hit) = end.hit {
        // A contact exists; an earlier one may lie in the pairs left.
        out.collides = true;
        out.probability = 1.0;
        out.time = Some(if left {
            hit.time.min(earliest)
        } else {
            hit.time
        });
    } else {
        out.frontier = left.then_some(frontier);
        out.probability = estimated;
        out.collides =
            left && (query.conservative || (estimated > 0.0 && estimated >= query.collide_at));
        out.time = out.collides.then_some(earliest);
    }
    if let Some((p, pair)) = best {
        let t = pair.at as f32;
        let (pa, pb) = (motion_a.at(t), motion_b.at(t));
        let centre = |tree: &AdbTree, i: u32| {
            tree.collision_mesh().bvh().nodes()[i as usize]
                .aabb()
                .center()
        };
        let (ca, cb) = (centre(a, pair.a), centre(b, pair.b));
        let (wa, wb) = (pa.transform_point(ca), pb.transform_point(cb));
        // The second node's motion relative to the first's over the step.
        let moved =
            |m: &RigidMotion, c: Vec3| m.end.transform_point(c) - m.start.transform_point(c);
        let relative = moved(motion_b, cb) - moved(motion_a, ca);
        let normal = relative
            .try_normalize()
            .or_else(|| (wa - wb).try_normalize())
            .unwrap_or(Vec3::X);
        out.witness = Some(SweptWitness {
            point: 0.5 * (wa + wb),
            normal,
            nodes: (pair.a, pair.b),
            time: t,
            probability: p,
        });
    }
    Ok(out)
}

//! The probability-guided, time-critical traversal of two ADB-trees.
use std::cell::OnceCell;
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;

use super::answer_model::AnswerModel;
use super::descent::{
    Descent, DescentEnd, DescentFrame, TRIANGLE_TESTS_PER_POP, budget_spent, leaf_pair_hit,
};
use super::estimator::{CalibratedEstimator, CollisionEstimator, NodePair, PaperEstimator};
use super::frontier::{CertificateHint, Frontier};
use super::interior::{InteriorMap, Interpenetration, PairCrossing, PairLookup};
use super::options::{
    Budget, Decision, EVIDENCE_REDUNDANCY, FIRST_EVIDENCE_CHECK, MAX_ESTIMATE, Order,
    STRADDLE_FLOOR, UNESTIMATED,
};
use super::queue::{Entry, Queue};
use super::tree::{AdbTree, nodes_overlap, overlap_distance, prepare_first, prepare_second};
use crate::bvh::box_test::RelativeFrame;
use crate::bvh::{BvhNode, QueryWorkspace, TrianglePair};
use crate::geometry::{Pose, PoseF64};

/// Parameters of [`adb_intersects`].
#[derive(Debug, Clone)]
pub struct AdbQuery {
    /// A node pair with at least this probability counts as a collision pair (papers: 0.99).
    pub p_min: f64,
    /// Collision pairs needed to answer "collision" (papers: 10).
    pub k_min: u32,
    /// When to stop regardless.
    pub budget: Budget,
    /// Test the triangles of leaf pairs exactly: an intersecting pair is a certain collision,
    /// and no overlapping pair is pruned for a zero estimate, so with `p_min = 1` and no budget
    /// the answer equals the exact query's. On by default: poses just short of contact are
    /// where estimates err (leaf pairs a hair apart look like colliding ones), and a leaf hit
    /// ends a colliding query without waiting for the estimates to gather `k_min` pairs. Off,
    /// the traversal never touches a triangle.
    pub exact_leaves: bool,
    /// The probability model.
    pub estimator: Arc<dyn CollisionEstimator>,
    /// Node pairs with a probability at most this are not expanded (the papers: 0, "insert if
    /// p > 0"). With a calibrated estimator ([`FittedEstimator`](super::FittedEstimator)) a
    /// small value such as 0.01 skips unlikely regions, at that risk per pair. With exact
    /// leaves, 0 prunes nothing (a pair estimated at 0 is still explored and its leaves
    /// tested); a positive value prunes as without them.
    pub p_prune: f64,
    /// How the answer is decided when `k_min` pairs were not found.
    pub decision: Decision,
    /// In which order node pairs are expanded.
    pub order: Order,
    /// For [`Decision::Confidence`] and [`Decision::Evidence`]: the confidence from which an
    /// answer the traversal did not settle (no exact hit, no `k_min` pieces of evidence, not
    /// every pair ruled out: a budget ran out, or leaf pairs were left to their estimates) says
    /// "collision". ½ (the default) makes the fewest errors when the confidence is calibrated;
    /// lower it where a missed contact costs more than a false one (a fast projectile that
    /// would pass through a wall), raise it where a false contact costs more. An answer with
    /// confidence 0 never says "collision".
    pub collide_at: f64,
    /// After how many queue pops without an answer the traversal tries the interpenetration
    /// certificate, once ([`InteriorMap::certify_pair`](super::InteriorMap::certify_pair): the
    /// samples each mesh leads with towards the other, then the second mesh's spread samples
    /// in the first mesh's map, then the other way round unless every one lay outside): a
    /// surface sample of one mesh inside the other and one of the same
    /// connected surface outside it prove that the surfaces cross, so the query ends with
    /// "collision" there. `None` never tries it; neither does a query between trees built
    /// without an [`InteriorMap`](super::InteriorMap). With a map that is not
    /// [exact](super::InteriorMap::is_exact) (an open mesh) the certificate's confidence is
    /// the map's measured [`certificate_confidence`](super::InteriorMap::certificate_confidence)
    /// and it counts only if that reaches `p_min`, so with `p_min = 1` the answer stays the
    /// exact query's. `Some(0)` (before the traversal) by default.
    pub interior_after: Option<u32>,
    /// How the confidence of an answer the traversal did not settle is made from its
    /// [`Frontier`] (by default [`AnswerModel::FITTED`], for any pair of trees).
    pub answer_confidence: AnswerConfidence,
}

impl Default for AdbQuery {
    /// The papers' `p_min = 0.99`, `k_min = 10`, no budget, with the calibrated estimator
    /// ([`CalibratedEstimator`]), the confidence decision ([`Decision::Confidence`]), exact
    /// leaves, the straddle order with estimates on demand ([`Order::Straddle`]) and the
    /// answer model for cut answers ([`AnswerConfidence::Model`]): what this crate recommends.
    fn default() -> Self {
        Self {
            p_min: 0.99,
            k_min: 10,
            budget: Budget::Unlimited,
            exact_leaves: true,
            estimator: Arc::new(CalibratedEstimator::default()),
            p_prune: 0.0,
            decision: Decision::Confidence,
            order: Order::Straddle,
            collide_at: 0.5,
            interior_after: Some(0),
            answer_confidence: AnswerConfidence::Model(AnswerModel::FITTED),
        }
    }
}

impl AdbQuery {
    /// Our reconstruction of Klein & Zachmann's published rule: [`PaperEstimator`] (depth-ratio
    /// curvature term), `p_min = 0.99`, `k_min = 10`, the papers' decision rule, best-first
    /// order, no pruning beyond `p = 0`, no triangle tests. It runs on the trees as this crate
    /// builds them (their fill fraction and normal slab), not as the papers build theirs.
    pub fn paper() -> Self {
        Self {
            estimator: Arc::new(PaperEstimator::default()),
            decision: Decision::Paper,
            order: Order::BestFirst,
            exact_leaves: false,
            interior_after: None,
            answer_confidence: AnswerConfidence::PerMesh,
            ..Self::default()
        }
    }

    /// The exact query on ADB-trees: `p_min = 1`, no budget, exact leaves, no pruning, the
    /// straddle order, and the interpenetration certificate first (it settles a query only in
    /// an [exact](super::InteriorMap::is_exact) map). Only exact hits, exact certificates and
    /// an emptied queue answer, so the answer is [`crate::bvh::intersects`]'s; the nodes'
    /// slabs, the straddle order and the certificate make it faster
    /// ([`exact_intersects`](super::exact_intersects)).
    pub fn exact() -> Self {
        Self {
            p_min: 1.0,
            ..Self::default()
        }
    }

    /// The default query with a time budget.
    pub fn with_budget(budget: Budget) -> Self {
        Self {
            budget,
            ..Self::default()
        }
    }
}

/// An approximate contact region: where the most probable colliding node pair overlaps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactWitness {
    /// Approximate contact point (world space): the probability-weighted centre of the leaf
    /// pairs the traversal left in its frontier, or between the two nodes' box centres.
    pub point: Vec3,
    /// Approximate contact normal (world space, unit): the direction to push the second mesh
    /// away from the first (from the nodes' mean surface normals, weighted like the point).
    pub normal: Vec3,
    /// The node pair (first tree, second tree).
    pub nodes: (u32, u32),
    /// The intersecting triangle pair, when an exact leaf test found one.
    pub triangles: Option<TrianglePair>,
}

/// The answer of [`adb_intersects`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdbOutcome {
    /// Whether the meshes are reported as colliding.
    pub collides: bool,
    /// Confidence that they collide, in `[0, 1]`: 1 for an exact hit (or a certificate from an
    /// [exact](super::InteriorMap::is_exact) map), the certificate's confidence for one from
    /// an approximate map, 0 when no pair was left (every overlapping pair was ruled out),
    /// else made from the traversal's final [`Frontier`] (the pairs queued, and the leaf pairs
    /// and pruned pairs it did not expand, which together cover every overlapping leaf pair):
    /// `1 − (Π (1 − p))^(1/r)` over their probabilities, `r` = 2 disjoint pairs counting as one
    /// independent piece, for an answer the evidence decided; for the others, as
    /// [`AdbQuery::answer_confidence`] says (by default the [`AnswerModel`] of that frontier).
    ///
    /// Short of 1 or 0 it is an estimate, not a guarantee. With a calibrated estimator the
    /// pair probabilities are fitted on seeded near-contact poses of each mesh against itself
    /// (of the pairs given about `p` there, about `p` hold intersecting triangles), and the
    /// answer model on many pairs of meshes; how closely the reported confidence follows the
    /// frequency of collisions on other poses is what the `accuracy_vs_time` report's
    /// reliability curves show. Under
    /// [`Decision::Paper`] the answer follows the papers' rule, which ignores every pair below
    /// `p_min`: "no collision" may then come with a high confidence (the pairs below `p_min`
    /// together make a collision likely), and that disagreement is why that rule misses
    /// collisions.
    pub probability: f64,
    /// Node pairs counted as evidence when the traversal stopped (see [`Decision`]; exact hits
    /// included).
    pub pairs_found: u32,
    /// Node pairs visited (probability estimates or box tests).
    pub node_pairs_visited: u64,
    /// Whether the budget ran out before the answer was settled.
    pub budget_exhausted: bool,
    /// Highest pair probability estimated ([`Order::Straddle`] estimates only some pairs).
    pub max_pair_probability: f64,
    /// Where the collision probably is: the most probable node pair seen, or the exact hit
    /// (`None` if no node pair below the roots overlapped).
    pub witness: Option<ContactWitness>,
    /// The interpenetration certificate that settled the answer, if one did
    /// ([`AdbQuery::interior_after`]): then the witness has no triangle pair, its point is the
    /// sample found inside and its normal points from the first mesh's box centre to the
    /// second's.
    pub interpenetration: Option<Interpenetration>,
    /// What an answer the traversal did not settle rests on (`None` for a settled answer: an
    /// exact hit, a certificate, an emptied queue).
    pub frontier: Option<Frontier>,
}

/// How [`adb_intersects`] makes the confidence of an answer it did not settle (a budget ran
/// out, or leaf pairs were left to their estimates; an answer the evidence decided keeps the
/// evidence's confidence).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnswerConfidence {
    /// The frontier's raw confidence, mapped by the tree's own
    /// [`ConfidenceCalibration`](super::ConfidenceCalibration) for a tree against itself after
    /// a failed certificate (the per-mesh fit, made at build time on the mesh against itself).
    PerMesh,
    /// The answer model for every pair of trees. The default, with [`AnswerModel::FITTED`]:
    /// on the `accuracy_vs_time` report's held-out runs (another seed, shallow contacts, pairs
    /// of different meshes) its answers under a 20 µs budget score better than the per-mesh
    /// fit's on most meshes (`docs/adb.md`).
    Model(AnswerModel),
    /// The per-mesh fit where it applies (a tree against itself after a failed certificate),
    /// the answer model elsewhere (pairs of different trees, answers without a certificate).
    PerMeshElseModel(AnswerModel),
}

impl AnswerConfidence {
    /// Whether the tree's own fit is used where it applies.
    fn uses_per_mesh_fit(&self) -> bool {
        !matches!(self, Self::Model(_))
    }

    /// The answer model, if any.
    fn model(&self) -> Option<AnswerModel> {
        match *self {
            Self::PerMesh => None,
            Self::Model(m) | Self::PerMeshElseModel(m) => Some(m),
        }
    }
}

/// Reusable memory of the ADB traversal (the queue and the exact-leaf workspace).
#[derive(Debug, Default)]
pub struct AdbWorkspace {
    queue: Queue,
    exact: QueryWorkspace,
}

impl AdbWorkspace {
    /// An empty workspace.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Time-critical collision query between two ADB-trees at poses (Klein & Zachmann's
/// traversal): node pairs are expanded in the query's [`Order`] (the papers': by their
/// estimated probability of containing intersecting triangles, globally; or evidence first,
/// or depth first; by default depth first, estimating pairs only where the answer needs
/// them); the answer is "collision" once `k_min` pairs reach `p_min`, "no
/// collision" when no pair with a positive probability is left, and the best estimate so far
/// when the budget runs out. A pose that is not [finite](Pose::is_finite) places its mesh
/// nowhere: no collision, probability 0.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::adb::{AdbQuery, AdbTree, AdbWorkspace, adb_intersects};
/// let ball = AdbTree::new(CollisionMesh::new(generate::icosphere(1.0, 3)));
/// let mut ws = AdbWorkspace::new();
/// let deep = Pose::from_translation(Vec3::new(1.0, 0.0, 0.0));
/// let out = adb_intersects(&ball, &Pose::IDENTITY, &ball, &deep, &AdbQuery::default(), &mut ws);
/// assert!(out.collides && out.probability > 0.9);
/// let apart = Pose::from_translation(Vec3::new(2.5, 0.0, 0.0));
/// let out = adb_intersects(&ball, &Pose::IDENTITY, &ball, &apart, &AdbQuery::default(), &mut ws);
/// assert!(!out.collides);
/// ```
pub fn adb_intersects(
    a: &AdbTree,
    pose_a: &Pose,
    b: &AdbTree,
    pose_b: &Pose,
    query: &AdbQuery,
    ws: &mut AdbWorkspace,
) -> AdbOutcome {
    // The clock is read only for a time budget.
    let start = matches!(query.budget, Budget::Time(_)).then(Instant::now);
    let rel = pose_a.inverse_mul(pose_b);
    let mut out = AdbOutcome {
        collides: false,
        probability: 0.0,
        pairs_found: 0,
        node_pairs_visited: 1,
        budget_exhausted: false,
        max_pair_probability: 0.0,
        witness: None,
        interpenetration: None,
        frontier: None,
    };
    // A pose that is not finite places its mesh nowhere.
    if !rel.is_finite() {
        return out;
    }
    // Root spheres apart (a few flops): the pair is apart, with no certificate to try. (The
    // root boxes are tested exactly once the certificate has had its turn.)
    if root_spheres_apart(a, b, &rel) {
        return out;
    }
    // The certificate comes first by default, before anything the traversal needs is set up:
    // a certified answer costs the certificate alone. (A sample it finds inside the other mesh
    // lies in both root boxes, so it never certifies a pose whose root boxes are apart.)
    // `Some(apart)` when it was tried and settled nothing, `apart` when it found the pose
    // probably apart ([`PairLookup::Apart`]).
    let mut failed = None;
    if query.interior_after == Some(0) {
        match certificate((a, pose_a), (b, pose_b), &rel, query, &mut out) {
            Certificate::Settled => return out,
            Certificate::Failed { apart } => failed = Some(apart),
            Certificate::Unavailable => {}
        }
    }
    let frame = RelativeFrame::new(&rel, a.collision_mesh().bvh(), b.collision_mesh().bvh());
    if !nodes_overlap(a, b, &frame, 0, 0) {
        return out;
    }
    let scene = Scene::new((a, pose_a), (b, pose_b), rel, frame, query, start);
    let found = Found {
        out,
        evidence: 0.0,
        frontier_log_miss: 0.0,
        region: (Vec3::ZERO, Vec3::ZERO, 0.0),
        best: None,
        certificate: match failed {
            None => CertificateHint::NotTried,
            Some(true) => CertificateHint::Apart,
            Some(false) => CertificateHint::Undecided,
        },
        left: (0, 0.0),
    };
    Traversal { scene, found }.run(ws, failed == Some(true))
}

/// What one query's traversal reads and never changes: the two trees placed, the query, and
/// the rules derived from it.
struct Scene<'q> {
    a: &'q AdbTree,
    b: &'q AdbTree,
    pose_a: &'q Pose,
    pose_b: &'q Pose,
    /// The second tree's frame to the first's.
    rel: Pose,
    frame: RelativeFrame,
    rel64: PoseF64,
    query: &'q AdbQuery,
    /// When the query began (read only for a time budget).
    start: Option<Instant>,
    /// Which pairs count toward k_min: the papers count every pair with p ≥ p_min; the
    /// confidence decision counts disjoint frontier pairs with p ≥ 1 − (1 − p_min)^(r/k_min),
    /// so that k_min of them, worth k_min/r independent pieces of evidence, reach p_min.
    disjoint_evidence: bool,
    /// `Decision::Evidence` needs the evidence sum; the other rules only count pairs.
    count_evidence: bool,
    /// What the evidence `Σ −ln(1 − p)` must reach for `Decision::Evidence` to stop.
    evidence_needed: f64,
    /// Worked out when first needed (a `powf`): an answer that leaves no queued pair to weigh
    /// (most non-colliding ones) never needs it.
    pair_threshold: OnceCell<f64>,
    /// Estimate a pair only when its estimate is needed: with exact leaves, no pruning and
    /// disjoint evidence, a `Straddle` traversal needs the probabilities of its queued pairs
    /// only at its evidence checks and for the confidence of an answer it did not settle.
    on_demand: bool,
}

/// What the traversal has found so far: the outcome being written, and the frontier's sums.
struct Found {
    out: AdbOutcome,
    /// Σ −ln(1 − p) over the frontier pairs that count as evidence (`Decision::Evidence`).
    evidence: f64,
    /// Σ ln(1 − p) over the pairs left in the frontier for good (leaf pairs not tested, pruned
    /// pairs); with the queued pairs, the frontier covers every overlapping leaf pair. Under
    /// independence, the probability that no pair collides is exp(Σ ln(1 − p)) over all of it.
    frontier_log_miss: f64,
    /// Σ p·point, Σ p·normal, Σ p over the leaf pairs left in the frontier: the contact region.
    region: (Vec3, Vec3, f64),
    /// The most probable pair, probabilities compared in steps of 1/20 and ties going to the
    /// deeper pair (whose boxes localise the contact better).
    best: Option<((u32, u32), u32, u32)>,
    /// What the interpenetration certificate said, if it was tried and settled nothing.
    certificate: CertificateHint,
    /// Pairs left in the frontier for good (counted in `frontier_log_miss`), and the highest
    /// probability among them.
    left: (u32, f64),
}

/// One query's traversal: [`Traversal::descend`] (the default order's lean loop, in
/// [`super::descent`]) or [`Traversal::expand`] (the other orders), both ending in the same
/// hit, budget and certificate handling ([`Found`]), then [`Traversal::finish`].
struct Traversal<'q> {
    scene: Scene<'q>,
    found: Found,
}

impl<'q> Scene<'q> {
    fn new(
        (a, pose_a): (&'q AdbTree, &'q Pose),
        (b, pose_b): (&'q AdbTree, &'q Pose),
        rel: Pose,
        frame: RelativeFrame,
        query: &'q AdbQuery,
        start: Option<Instant>,
    ) -> Self {
        let disjoint_evidence = query.decision != Decision::Paper;
        Self {
            a,
            b,
            pose_a,
            pose_b,
            rel,
            frame,
            rel64: rel.to_f64(),
            query,
            start,
            disjoint_evidence,
            count_evidence: query.decision == Decision::Evidence,
            evidence_needed: match query.decision {
                Decision::Evidence => {
                    -(1.0 - query.p_min.clamp(0.0, MAX_ESTIMATE)).ln() * EVIDENCE_REDUNDANCY
                }
                _ => f64::INFINITY,
            },
            pair_threshold: OnceCell::new(),
            on_demand: query.order == Order::Straddle
                && query.exact_leaves
                && query.p_prune <= 0.0
                && disjoint_evidence,
        }
    }

    /// The probability a pair needs to count as evidence.
    fn pair_threshold(&self) -> f64 {
        *self.pair_threshold.get_or_init(|| {
            if self.disjoint_evidence {
                let independent = f64::from(self.query.k_min.max(1)) / EVIDENCE_REDUNDANCY;
                1.0 - (1.0 - self.query.p_min.clamp(0.0, 1.0)).powf(1.0 / independent.max(1.0))
            } else {
                self.query.p_min
            }
        })
    }

    /// The estimate of nodes `ia`, `ib` whose boxes' centres are `center_distance` apart.
    #[inline]
    fn estimate(&self, ia: u32, ib: u32, center_distance: f32) -> f64 {
        let pair = NodePair::at_distance(self.a, self.b, center_distance, ia, ib, true);
        let p = self.query.estimator.probability(&pair);
        // A NaN from a custom estimator counts as 0 rather than poisoning the confidence.
        if p.is_nan() {
            0.0
        } else {
            p.clamp(0.0, MAX_ESTIMATE)
        }
    }

    /// The contact witness of nodes `ia`, `ib` (between their box centres).
    fn witness(&self, ia: u32, ib: u32, triangles: Option<TrianglePair>) -> ContactWitness {
        let (na, nb) = (
            self.a.collision_mesh().bvh().nodes(),
            self.b.collision_mesh().bvh().nodes(),
        );
        let (x, y) = (&na[ia as usize], &nb[ib as usize]);
        let ca = self.pose_a.transform_point(x.aabb().center());
        let cb = self
            .pose_a
            .transform_point(self.frame.transform_point(y.aabb().center()));
        let n = self
            .pose_a
            .transform_vector(self.a.nodes()[ia as usize].normal)
            - self
                .pose_b
                .transform_vector(self.b.nodes()[ib as usize].normal);
        let normal = n
            .try_normalize()
            .or_else(|| (cb - ca).try_normalize())
            .unwrap_or(Vec3::Y);
        ContactWitness {
            point: (ca + cb) * 0.5,
            normal,
            nodes: (ia, ib),
            triangles,
        }
    }
}

impl Found {
    /// Records a pair's estimate `p` in the highest probability seen and the most probable pair.
    #[inline]
    fn note_estimate(&mut self, s: &Scene<'_>, p: f64, ia: u32, ib: u32) {
        self.out.max_pair_probability = self.out.max_pair_probability.max(p);
        let depth =
            u32::from(s.a.nodes()[ia as usize].depth) + u32::from(s.b.nodes()[ib as usize].depth);
        let key = ((p * 20.0) as u32, depth);
        if p > 0.0 && self.best.is_none_or(|(k, _, _)| key > k) {
            self.best = Some((key, ia, ib));
        }
    }

    /// Estimates the queued pairs that have no estimate yet (on-demand mode); returns how many
    /// queued pairs count as evidence, and their evidence `Σ −ln(1 − p)`.
    fn estimate_queued(&mut self, s: &Scene<'_>, queued: &mut [Entry]) -> (u32, f64) {
        let (mut found, mut sum) = (0u32, 0.0f64);
        for e in queued {
            if e.p == UNESTIMATED {
                // The descent leaves the centre distance to be worked out here (the same
                // arithmetic as its box test).
                let d = if e.center_distance.is_nan() {
                    overlap_distance(s.a, s.b, &s.frame, e.a, e.b).unwrap_or(0.0)
                } else {
                    e.center_distance
                };
                e.p = s.estimate(e.a, e.b, d);
                self.note_estimate(s, e.p, e.a, e.b);
            }
            if e.p >= s.pair_threshold() && (e.a, e.b) != (0, 0) {
                found += 1;
                sum -= (1.0 - e.p).ln();
            }
        }
        (found, sum)
    }

    /// A pair of probability `p` left in the frontier for good.
    fn leave(&mut self, p: f64) {
        self.frontier_log_miss += (1.0 - p).ln();
        self.left = (self.left.0 + 1, self.left.1.max(p));
    }

    /// An exact hit: the leaf pair `nodes` holds the intersecting triangles.
    fn hit(&mut self, s: &Scene<'_>, nodes: (u32, u32), triangles: TrianglePair) {
        self.out.collides = true;
        self.out.probability = 1.0;
        self.out.max_pair_probability = 1.0;
        self.out.pairs_found += 1;
        self.out.witness = Some(s.witness(nodes.0, nodes.1, Some(triangles)));
    }

    /// Tries the interpenetration certificate during the traversal.
    fn certificate(&mut self, s: &Scene<'_>) -> Certificate {
        let c = certificate(
            (s.a, s.pose_a),
            (s.b, s.pose_b),
            &s.rel,
            s.query,
            &mut self.out,
        );
        if let Certificate::Failed { apart } = c {
            self.certificate = if apart {
                CertificateHint::Apart
            } else {
                CertificateHint::Undecided
            };
        }
        c
    }
}

impl Traversal<'_> {
    /// Runs the traversal from the root pair; `apart` when the certificate already found the
    /// pose probably apart.
    fn run(mut self, ws: &mut AdbWorkspace, apart: bool) -> AdbOutcome {
        let s = &self.scene;
        // The evidence bar matters to `Order::EvidenceFirst` only.
        let evidence_bar = if s.query.order == Order::EvidenceFirst {
            s.pair_threshold()
        } else {
            0.0
        };
        ws.queue.reset(s.query.order, evidence_bar);
        ws.queue.push(Entry {
            p: 1.0,
            rank: 1.0,
            a: 0,
            b: 0,
            center_distance: 0.0,
        });
        // Leaf pairs are tested exactly in exact-leaves mode, and so is a root pair of two leaves.
        ws.exact
            .cache_begin(s.b.collision_mesh().mesh().vertex_count());
        let settled = if s.on_demand {
            self.descend(ws, apart)
        } else {
            self.expand(ws)
        };
        if settled {
            return self.found.out;
        }
        self.finish(ws)
    }

    /// The on-demand straddle order ([`Descent`]) until it ends; whether a certificate
    /// settled the answer.
    fn descend(&mut self, ws: &mut AdbWorkspace, apart: bool) -> bool {
        let (s, found) = (&self.scene, &mut self.found);
        // Where the certificate found the pose probably apart, the order buys nothing: with no
        // budget to cut the traversal short, every overlapping pair is expanded whatever the
        // order. (Under a budget, the order decides what the frontier looks like when the
        // budget ends: kept.)
        let straddle_order = |apart: bool| !(apart && s.query.budget == Budget::Unlimited);
        let f = DescentFrame {
            a: s.a,
            b: s.b,
            frame: &s.frame,
            rel64: &s.rel64,
            budget: s.query.budget,
            start: s.start,
        };
        let mut descent = Descent {
            pops: 0,
            unclocked: 0,
            // With `p_min = 1` no estimate can count as evidence: no check is made.
            next_check: if s.query.p_min >= 1.0 {
                u32::MAX
            } else {
                FIRST_EVIDENCE_CHECK
            },
            visited: found.out.node_pairs_visited,
            ordered: straddle_order(apart),
        };
        // The certificate's pop, if it comes during the traversal.
        let mut pause = s.query.interior_after.filter(|&k| k > 0);
        loop {
            let end = descent.run(
                &f,
                ws.queue.stack_mut(),
                &mut ws.exact,
                pause,
                &mut |queued| {
                    let (n, sum) = found.estimate_queued(s, queued);
                    n >= s.query.k_min || sum >= s.evidence_needed
                },
            );
            found.out.node_pairs_visited = descent.visited;
            match end {
                DescentEnd::Paused => {
                    pause = None;
                    match found.certificate(s) {
                        Certificate::Settled => return true,
                        Certificate::Failed { apart } => descent.ordered = straddle_order(apart),
                        Certificate::Unavailable => {}
                    }
                }
                DescentEnd::Done => return false,
                DescentEnd::Hit { nodes, triangles } => {
                    found.hit(s, nodes, triangles);
                    return false;
                }
                DescentEnd::Budget => {
                    found.out.budget_exhausted = true;
                    return false;
                }
                DescentEnd::Evidence => {
                    found.out.collides = true;
                    return false;
                }
            }
        }
    }

    /// The queue of the other orders until it ends; whether a certificate settled the answer.
    fn expand(&mut self, ws: &mut AdbWorkspace) -> bool {
        let (s, found) = (&self.scene, &mut self.found);
        let query = s.query;
        let (na, nb) = (
            s.a.collision_mesh().bvh().nodes(),
            s.b.collision_mesh().bvh().nodes(),
        );
        let mut pops = 0u32;
        // Work since the last clock read, in pops (a leaf pair's triangle tests count too).
        let mut unclocked = 0u32;
        while let Some(e) = ws.queue.pop() {
            let pair_threshold = s.pair_threshold();
            pops += 1;
            unclocked += 1;
            if query.interior_after == Some(pops)
                && let Certificate::Settled = found.certificate(s)
            {
                return true;
            }
            // The root pair is always expanded: a budget cannot end a query before it has
            // looked.
            let over = pops > 1
                && budget_spent(
                    query.budget,
                    found.out.node_pairs_visited,
                    &mut unclocked,
                    s.start,
                );
            if over {
                found.out.budget_exhausted = true;
                ws.queue.push(e);
                return false;
            }
            if (e.a, e.b) != (0, 0) && s.disjoint_evidence && e.p >= pair_threshold {
                // Replaced by its children: only disjoint pairs count as evidence.
                found.out.pairs_found -= 1;
                if s.count_evidence {
                    found.evidence += (1.0 - e.p).ln();
                }
            }
            let (x, y) = (&na[e.a as usize], &nb[e.b as usize]);
            if x.is_leaf() && y.is_leaf() {
                // Queued in exact-leaves mode (or the root pair of two single-leaf trees):
                // decide exactly.
                let (hit, tests) = leaf_pair_hit((s.a, x), (s.b, y), &s.rel64, &mut ws.exact);
                if let Some(triangles) = hit {
                    found.hit(s, (e.a, e.b), triangles);
                    return false;
                }
                unclocked += tests / TRIANGLE_TESTS_PER_POP;
                continue;
            }
            let (mut queued, n_queued, done) = found.expand_pair(s, (x, e.a), (y, e.b));
            ws.queue.push_children(&mut queued[..n_queued]);
            if done {
                return false;
            }
        }
        false
    }

    /// The answer from what was found: the frontier's confidence and the decision rule, and
    /// the witness.
    fn finish(self, ws: &mut AdbWorkspace) -> AdbOutcome {
        let Traversal {
            scene: s,
            found: mut f,
        } = self;
        let query = s.query;
        if f.out.probability < 1.0 {
            // The queued part of the frontier, summed only now: most pairs are expanded, and a
            // traversal that runs to the end leaves none (an empty frontier sums to 0: no
            // collision).
            if s.on_demand {
                // The queued pairs not estimated yet are estimated now, and the evidence rule
                // applies to them as at the checks.
                let (n, sum) = f.estimate_queued(&s, ws.queue.stack_mut());
                f.out.pairs_found = n;
                f.out.collides |= n >= query.k_min || sum >= s.evidence_needed;
            }
            let mut frontier = Frontier {
                pairs: f.left.0,
                max_probability: f.left.1,
                certificate: f.certificate,
                ..Frontier::default()
            };
            let (mut queued, mut depth_sum, mut n) = (0.0, 0u64, 0u32);
            for e in ws.queue.iter() {
                queued += (1.0 - e.p).ln();
                frontier.max_probability = frontier.max_probability.max(e.p);
                depth_sum += u64::from(s.a.nodes()[e.a as usize].depth)
                    + u64::from(s.b.nodes()[e.b as usize].depth);
                n += 1;
            }
            frontier.pairs += n;
            if n > 0 {
                let max_depths = (s.a.max_depth() + s.b.max_depth()).max(1);
                frontier.mean_depth =
                    (depth_sum as f64 / f64::from(n) / f64::from(max_depths)) as f32;
            }
            // Disjoint pairs of one contact region are correlated: `r` of them count as one
            // independent piece, as in the evidence rules.
            let log_miss = (f.frontier_log_miss + queued) / EVIDENCE_REDUNDANCY;
            f.out.probability = (1.0 - log_miss.exp()).clamp(0.0, 1.0);
            frontier.raw_confidence = f.out.probability;
            if frontier.pairs > 0 {
                f.out.frontier = Some(frontier);
            }
            // A failed certificate is evidence against the deep overlaps. The tree's own fit
            // (calibrated for such answers on the mesh itself) applies to a tree against itself after a failed certificate;
            // the answer model, where the query has one, to the other answers the evidence did
            // not decide (an answer on evidence keeps the evidence's confidence).
            let per_mesh = (f.certificate != CertificateHint::NotTried && std::ptr::eq(s.a, s.b))
                .then(|| s.a.confidence_calibration())
                .flatten()
                .filter(|_| query.answer_confidence.uses_per_mesh_fit());
            let unsettled = f.out.probability > 0.0 && f.out.probability < 1.0;
            if let Some(c) = per_mesh
                && unsettled
            {
                f.out.probability = c.map(f.out.probability).clamp(0.0, MAX_ESTIMATE);
            } else if let Some(model) = query.answer_confidence.model()
                && unsettled
                && !f.out.collides
                && let Some(frontier) = &f.out.frontier
            {
                let size = |t: &AdbTree| {
                    f64::from(t.collision_mesh().bvh().root_aabb().extents().length())
                };
                let ratio = size(s.a) / size(s.b).max(f64::MIN_POSITIVE);
                let nodes = (s.a.nodes().len() + s.b.nodes().len()) as u64;
                f.out.probability = model
                    .confidence(frontier, f.out.node_pairs_visited, ratio, nodes)
                    .clamp(0.0, MAX_ESTIMATE);
            }
            if !f.out.collides {
                f.out.collides = match query.decision {
                    Decision::Confidence | Decision::Evidence => {
                        f.out.probability > 0.0 && f.out.probability >= query.collide_at
                    }
                    Decision::Paper => f.out.budget_exhausted && f.out.pairs_found >= 1,
                };
            }
        }
        if f.out.witness.is_none() {
            let mut region = f.region;
            f.out.witness = f.best.map(|(_, ia, ib)| {
                let mut w = s.witness(ia, ib, None);
                // The contact region is the probability-weighted centre and mean normal of the
                // frontier's leaf pairs, or of its queued pairs that count as evidence when the
                // traversal stopped before reaching leaves (the best pair's boxes may be large).
                if region.2 == 0.0 {
                    for e in ws
                        .queue
                        .iter()
                        .filter(|e| e.p >= s.pair_threshold() && (e.a, e.b) != (0, 0))
                    {
                        let w = s.witness(e.a, e.b, None);
                        region.0 += w.point * e.p as f32;
                        region.1 += w.normal * e.p as f32;
                        region.2 += e.p;
                    }
                }
                if region.2 > 0.0 {
                    w.point = region.0 / region.2 as f32;
                    w.normal = region.1.try_normalize().unwrap_or(w.normal);
                }
                w
            });
        }
        f.out
    }
}

impl Found {
    /// Estimates the overlapping child pairs of `(x, y)` (a leaf stands for itself) and sorts
    /// each into the queue or the frontier; returns the pairs to queue and whether `k_min`
    /// pairs (or enough evidence) are now found (then the children estimated so far are
    /// queued, so that the frontier is complete, and the traversal ends).
    fn expand_pair(
        &mut self,
        s: &Scene<'_>,
        (x, ia0): (&BvhNode, u32),
        (y, ib0): (&BvhNode, u32),
    ) -> ([Entry; 4], usize, bool) {
        let query = s.query;
        let pair_threshold = s.pair_threshold();
        let (na, nb) = (
            s.a.collision_mesh().bvh().nodes(),
            s.b.collision_mesh().bvh().nodes(),
        );
        let mut queued = [Entry {
            p: 0.0,
            rank: 0.0,
            a: 0,
            b: 0,
            center_distance: 0.0,
        }; 4];
        let mut n_queued = 0;
        let children = |n: &BvhNode, i: u32| {
            if n.is_leaf() {
                [i, u32::MAX]
            } else {
                [n.left(), n.left() + 1]
            }
        };
        // Each child prepared once for its (up to) two box tests.
        let (kids_a, kids_b) = (children(x, ia0), children(y, ib0));
        let prepare = |ib: u32| (ib != u32::MAX).then(|| prepare_second(s.b, &s.frame, ib));
        let prepared_b = [prepare(kids_b[0]), prepare(kids_b[1])];
        for ia in kids_a {
            if ia == u32::MAX {
                continue;
            }
            let first = prepare_first(s.a, &s.frame, ia);
            for (&ib, second) in kids_b.iter().zip(&prepared_b) {
                let Some(second) = second else {
                    continue;
                };
                self.out.node_pairs_visited += 1;
                let (cx, cy) = (&na[ia as usize], &nb[ib as usize]);
                let Some(overlap) = s.frame.overlap_prepared(&first, second) else {
                    continue;
                };
                let p = s.estimate(ia, ib, overlap.center_distance);
                self.note_estimate(s, p, ia, ib);
                if p >= pair_threshold {
                    self.out.pairs_found += 1;
                    if s.count_evidence {
                        self.evidence -= (1.0 - p).ln();
                    }
                    if self.out.pairs_found >= query.k_min || self.evidence >= s.evidence_needed {
                        self.out.collides = true;
                        // It stays in the frontier (not queued: it does not shape the region).
                        self.leave(p);
                        return (queued, n_queued, true);
                    }
                }
                let both_leaves = cx.is_leaf() && cy.is_leaf();
                let expand = if query.exact_leaves {
                    query.p_prune <= 0.0 || p > query.p_prune
                } else {
                    p > query.p_prune && !both_leaves
                };
                if expand {
                    let rank = match query.order {
                        Order::DepthFirst => p * (STRADDLE_FLOOR + f64::from(overlap.straddle)),
                        Order::Straddle => f64::from(overlap.straddle),
                        Order::BestFirst | Order::EvidenceFirst => p,
                    };
                    queued[n_queued] = Entry {
                        p,
                        rank,
                        a: ia,
                        b: ib,
                        center_distance: overlap.center_distance,
                    };
                    n_queued += 1;
                } else {
                    // Left in the frontier for good (a leaf pair, or pruned).
                    self.leave(p);
                    if both_leaves && p > 0.0 {
                        // A leaf pair left in the frontier shapes the contact region.
                        let w = s.witness(ia, ib, None);
                        self.region.0 += w.point * p as f32;
                        self.region.1 += w.normal * p as f32;
                        self.region.2 += p;
                    }
                }
            }
        }
        (queued, n_queued, false)
    }
}

/// What [`certificate`] did.
enum Certificate {
    /// It settled the answer.
    Settled,
    /// It was tried and settled nothing (nothing found, or a confidence below `p_min`);
    /// `apart` when it found the pose probably apart ([`PairLookup::Apart`]).
    Failed { apart: bool },
    /// A mesh has no interior map.
    Unavailable,
}

/// The interpenetration certificate both ways ([`InteriorMap::look_up_pair`]), `rel` taking
/// the second mesh's frame to the first's. When it settles the answer, the answer is written
/// to `out`: a collision with the certificate's confidence, its witness at the sample found
/// inside.
fn certificate(
    (a, pose_a): (&AdbTree, &Pose),
    (b, pose_b): (&AdbTree, &Pose),
    rel: &Pose,
    query: &AdbQuery,
    out: &mut AdbOutcome,
) -> Certificate {
    let (Some(map_a), Some(map_b)) = (a.interior(), b.interior()) else {
        return Certificate::Unavailable;
    };
    // A crossing counts only in a map whose confidence reaches `p_min`: where neither map's
    // does (two open meshes under `p_min = 1`), the lookups could settle nothing.
    let may_settle = |map: &InteriorMap| {
        map.certificate_confidence() >= query.p_min && map.certificate_confidence() > 0.0
    };
    if !may_settle(map_a) && !may_settle(map_b) {
        return Certificate::Unavailable;
    }
    // The sample was looked up in the map of the mesh it lies in: that map's confidence.
    let (cert, frame_pose, confidence) = match InteriorMap::look_up_pair(map_a, map_b, rel) {
        PairLookup::Crossing(PairCrossing::SecondInFirst(c)) => {
            (c, pose_a, map_a.certificate_confidence())
        }
        PairLookup::Crossing(PairCrossing::FirstInSecond(c)) => {
            (c, pose_b, map_b.certificate_confidence())
        }
        PairLookup::Apart => return Certificate::Failed { apart: true },
        PairLookup::Undecided => return Certificate::Failed { apart: false },
    };
    if confidence < query.p_min || confidence <= 0.0 {
        return Certificate::Failed { apart: false };
    }
    out.collides = true;
    out.probability = confidence;
    out.max_pair_probability = out.max_pair_probability.max(confidence);
    out.pairs_found += 1;
    let centre = |tree: &AdbTree, pose: &Pose| {
        pose.transform_point(tree.collision_mesh().bvh().root_aabb().center())
    };
    out.interpenetration = Some(cert);
    out.witness = Some(ContactWitness {
        point: frame_pose.transform_point(cert.inside_point),
        normal: (centre(b, pose_b) - centre(a, pose_a))
            .try_normalize()
            .unwrap_or(Vec3::Y),
        nodes: (0, 0),
        triangles: None,
    });
    Certificate::Settled
}

/// Whether the spheres around the two root boxes (`rel` taking the second tree's frame to the
/// first's) are apart, with a margin for rounding: then so are the boxes, and the meshes.
#[inline]
fn root_spheres_apart(a: &AdbTree, b: &AdbTree, rel: &Pose) -> bool {
    let (ba, bb) = (
        a.collision_mesh().bvh().root_aabb(),
        b.collision_mesh().bvh().root_aabb(),
    );
    let reach = ba.half_extents().length() + bb.half_extents().length();
    let gap = rel.transform_point(bb.center()).distance(ba.center());
    // Relative to the scene's scale, far above `f32` rounding; NaN (empty or non-finite
    // boxes) never separates.
    let scale = ba.max_abs() + bb.max_abs() + rel.translation.abs().max_element();
    gap > reach + scale * 1e-4
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{CollisionMesh, root_boxes_overlap};
    use crate::mesh::generate;
    use glam::Quat;
    use rand::rngs::Xoshiro256PlusPlus;
    use rand::{RngExt, SeedableRng};

    /// The root-sphere test only ever rejects pairs whose root boxes are apart, and does
    /// reject most pairs far apart.
    #[test]
    fn root_spheres_apart_only_when_the_root_boxes_are() {
        let a = AdbTree::new(CollisionMesh::new(generate::torus(1.0, 0.3, 24, 8)));
        let b = AdbTree::new(CollisionMesh::new(generate::cuboid(
            Vec3::new(2.0, 0.2, 0.5),
            1,
        )));
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let (mut rejected, mut far) = (0, 0);
        for _ in 0..4000 {
            let axis = Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5;
            let rotation = Quat::from_axis_angle(
                axis.try_normalize().unwrap_or(Vec3::X),
                rng.random::<f32>() * 6.3,
            );
            let t = (Vec3::new(rng.random(), rng.random(), rng.random()) - 0.5) * 10.0;
            let rel = Pose::new(t, rotation);
            let apart = root_spheres_apart(&a, &b, &rel);
            let overlap = root_boxes_overlap(
                a.collision_mesh(),
                &Pose::IDENTITY,
                b.collision_mesh(),
                &rel,
            );
            assert!(!(apart && overlap), "{rel:?}");
            if t.length() > 4.0 {
                far += 1;
                rejected += usize::from(apart);
            }
        }
        assert!(rejected * 10 >= far * 9, "{rejected} of {far}");
    }
}

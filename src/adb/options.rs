//! The options of ADB-tree builds and queries, and the traversal's constants: plain data that
//! every other part of `adb/` reads and that depends on none of them.
use std::time::Duration;

/// The meshes the ADB defaults were chosen on (the traversal's constants here, the default
/// build options, the default query): the `accuracy_vs_time` report's same-mesh set, each mesh
/// against itself, at the poses of [`TRAINING_SEEDS`]. Every other mesh, pair of meshes and
/// seed is held out: the report labels its runs by these, and its held-out runs measure how the
/// defaults carry over. (The answer model's training pairs are named in
/// `examples/fit_answer_model.rs`; the build-time fits train on the mesh itself, on seeds of
/// their own.)
pub const TRAINING_MESHES: [&str; 8] = [
    "icosphere_20k",
    "torus_32k",
    "bunny",
    "armadillo",
    "dragon_50k",
    "stanford-bunny",
    "small_intestine_100k",
    "ogre",
];

/// The seed of the poses the ADB defaults were chosen on, with [`TRAINING_MESHES`]: the
/// `accuracy_vs_time` report's default seed.
pub const TRAINING_SEEDS: [u64; 1] = [0xACC0];

/// When the traversal must stop, whatever it has found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Budget {
    /// No limit: stop only on the `p_min`/`k_min` rule or an empty queue.
    #[default]
    Unlimited,
    /// Stop once about this many node pairs have been visited (checked before each expansion,
    /// which visits up to 4: at most 3 more; deterministic, run to run). The root pair is
    /// always expanded.
    NodePairs(u64),
    /// Stop once this much time has passed since the query started (checked every
    /// 16 queue pops, a leaf pair's exact triangle tests counting as pops too, so that the
    /// clock is read rarely and an exact leaf cannot hide a late clock).
    Time(Duration),
}

/// How many disjoint node pairs of one contact region count as one independent piece of
/// evidence in [`Decision::Confidence`] and [`Decision::Evidence`], and in the reported
/// confidence ([`AdbOutcome::probability`](super::AdbOutcome::probability)). Disjoint pairs of
/// the same surfaces are correlated (neighbouring patches of one crossing), so counting each as
/// fully independent would overstate the evidence.
pub(crate) const EVIDENCE_REDUNDANCY: f64 = 2.0;

/// Queue pops between two clock reads of a [`Budget::Time`] query.
pub(crate) const TIME_CHECK_INTERVAL: u32 = 16;

/// The probability of a queued pair not estimated yet ([`Order::Straddle`]).
pub(crate) const UNESTIMATED: f64 = -1.0;

/// Queue pops before an [`Order::Straddle`] traversal first estimates its queued pairs and
/// checks their evidence; the next checks come after twice as many pops each time, so the
/// checks estimate a bounded share of the pairs.
pub(crate) const FIRST_EVIDENCE_CHECK: u32 = 64;

/// Highest probability an *estimate* may report: only an exact triangle test is certain, so
/// with `p_min = 1` only exact hits count.
pub(crate) const MAX_ESTIMATE: f64 = 1.0 - 1e-9;

/// The order in which [`adb_intersects`](super::adb_intersects) expands node pairs. Whichever
/// the order, the frontier (every queued, leaf and pruned pair) covers all overlapping leaf
/// pairs, the same rules decide, and ties are broken by node indices, so answers are deterministic. A pair's
/// children are estimated when it is expanded, except in [`Order::Straddle`], which estimates
/// them when its rules need their probabilities.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Order {
    /// The papers' traversal: one max-heap of all queued pairs, the most probable expanded
    /// next, wherever it is in the trees. Spreads over every likely region before it goes
    /// deep: a collision near first contact, whose leaf pairs look less likely than the
    /// shallower pairs around them, is reached only after all of those are expanded.
    BestFirst,
    /// The pairs that count as evidence ([`Decision`]: `p` at least the per-pair bar) first,
    /// the most probable first, as in best first: their children often count too, so a deep
    /// overlap gathers `k_min` pieces within a few levels. The other pairs depth first, the
    /// most probable child of the pair just expanded first (a stack): a collision near first
    /// contact reaches leaf pairs, and with exact leaves its first intersecting triangle pair,
    /// after far fewer node pairs than best first.
    EvidenceFirst,
    /// Depth first: the most promising child pair of the pair just expanded next (a stack), a
    /// child's promise being its probability `p` times `0.05 + s`, where `s` in
    /// `[0, 1]` says how squarely each of the two boxes straddles the middle plane of the
    /// other node's slab (the plane its surface lies near; 1 when both are centred on the
    /// other's plane, 0 when either lies to one side). Surfaces cross only where each reaches
    /// both sides of the other, so among equally probable children those that straddle hold
    /// intersecting triangles more often. Pairs still count as evidence ([`Decision`]) as in
    /// the other orders, but are not expanded ahead of the rest: on deep overlaps, expanding
    /// every evidence pair first ([`Order::EvidenceFirst`]) spends node pairs that a dive to
    /// the first intersecting triangle pair does not. Every pair is estimated when its parent
    /// is expanded (compare [`Order::Straddle`]).
    DepthFirst,
    /// Depth first like [`Order::DepthFirst`], the child pairs ranked by their straddle `s`
    /// alone, and with exact leaves (no pruning, a disjoint-evidence [`Decision`]) a pair's
    /// probability estimated only when it is needed: at the evidence checks (after
    /// 64 pops, then after twice as many each time), for the pairs then
    /// queued, and at the end of an answer the traversal did not settle (budget, evidence),
    /// for the pairs left in its frontier. Most node pairs then cost a box test and no
    /// estimate. The rules are those of the other orders (`k_min` disjoint frontier pairs at the
    /// evidence bar mean "collision"; the confidence is the frontier's), checked less often:
    /// an unbudgeted query ends on an exact triangle hit, an emptied queue or the evidence, as
    /// before. Without exact leaves, or with pruning, every pair is estimated as in the other
    /// orders and only the ranking differs. The default (the `accuracy_vs_time` report compares
    /// the orders).
    #[default]
    Straddle,
}

/// The weight of a child pair's probability that [`Order::DepthFirst`] keeps whatever its
/// straddle (see there): small, so that straddling decides among similar probabilities, yet
/// positive, so that a pair with no straddle is still ranked by its probability.
pub(crate) const STRADDLE_FLOOR: f64 = 0.05;

/// How [`adb_intersects`](super::adb_intersects) turns pair probabilities into an answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Decision {
    /// The papers' rule: every pair with `p ≥ p_min` counts, `k_min` of them mean
    /// "collision"; an emptied queue means "no collision"; an exhausted budget means
    /// "collision" if any pair counted.
    Paper,
    /// For calibrated estimators: `p_min` is the confidence the answer needs and `k_min` the
    /// number of pieces of evidence. A pair counts while it is in the frontier (not yet replaced
    /// by its children, so counted pairs are disjoint) with `p ≥ 1 − (1 − p_min)^(r/k_min)`,
    /// `r` = 2 (disjoint pairs of one contact region are correlated): `k_min` such pairs, worth `k_min / r` independent ones,
    /// together give at least `p_min` (0.60 per pair for the defaults 0.99 and 10).
    /// Without `k_min` of them, "collision" iff the reported confidence
    /// ([`AdbOutcome::probability`](super::AdbOutcome::probability)) is at least
    /// [`AdbQuery::collide_at`](super::AdbQuery::collide_at) (½ by default). The default.
    #[default]
    Confidence,
    /// [`Decision::Confidence`], and besides: "collision" as soon as the pairs that count as
    /// evidence together reach `p_min`, `r` of them counting as one independent piece as in
    /// `Confidence` (`Σ −ln(1 − p) ≥ r · −ln(1 − p_min)`). `k_min` pairs at the threshold
    /// carry that much (for `k_min ≥ r`) and the `k_min` rule still applies, so this never
    /// stops later than `Confidence`, and earlier when fewer, more certain pairs carry the same
    /// evidence. `k_min` only sets the bar a pair must reach to count, so a larger `k_min`
    /// lets weaker pairs count (to never stop on evidence, use `Confidence` with a `k_min` no
    /// traversal can reach). An answer given on evidence has a contact region, not the triangle
    /// pair of an exact leaf hit.
    Evidence,
}

/// Options of [`AdbTree::build_with`](super::AdbTree::build_with).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdbBuildOptions {
    /// Cells per axis of each node's grid (`resolution³` cells, clamped to 1..=8). 4 (64 cells,
    /// within the papers' one-byte count) by default; the `accuracy_vs_time` report's
    /// `--resolution R` compares others.
    pub resolution: u32,
    /// Fraction of the papers' MaxArea at which a cell counts as well-filled (see
    /// [`CellGrid::with_fill_fraction`](super::cells::CellGrid::with_fill_fraction)).
    pub fill_fraction: f32,
    /// Worker threads for the build (0: one per available core).
    pub threads: usize,
    /// Fit a [`Calibration`](super::Calibration) of the
    /// [`PlanarityEstimator`](super::PlanarityEstimator) on the mesh itself (the papers'
    /// "estimate parameters" step: random descents at seeded near-contact poses of the mesh
    /// against itself, each node pair checked exactly; used by the default
    /// [`CalibratedEstimator`](super::CalibratedEstimator)) and, with
    /// [`confidence_fit`](AdbBuildOptions::confidence_fit), the confidence calibration. `None`
    /// skips both: [`AdbTree::calibration`](super::AdbTree::calibration) is then `None` and the
    /// calibrated estimator returns the raw estimate.
    pub fit: Option<FitOptions>,
    /// Voxels along the longest side of the mesh's box in its
    /// [`InteriorMap`](super::InteriorMap) (the map of its inside and outside that the
    /// interpenetration certificate looks surface samples up in:
    /// [`AdbQuery::interior_after`](super::AdbQuery::interior_after)); 0 builds no map (and then
    /// neither the certificate measurement nor the confidence fit runs). 128 by default, a
    /// quarter of a byte per voxel; a finer map keeps thinner parts inside (the
    /// `accuracy_vs_time` report's `--interior-resolution` compares others).
    pub interior_resolution: u32,
    /// Coarse surface samples of the mesh that the certificate always looks up in the other
    /// mesh's map (at most [`MAX_SURFACE_SAMPLES`](super::MAX_SURFACE_SAMPLES); each chunk of
    /// them also has finer samples, looked up only where it came near the other mesh; the map
    /// also holds the leading samples of 384 directions, whatever this is). 128 by default (the
    /// `accuracy_vs_time` report's `--interior-samples` compares others).
    pub interior_samples: usize,
    /// Poses of the mesh against itself on which the build measures how often the
    /// certificate of an open mesh's map (not [exact](super::InteriorMap::is_exact)) is right
    /// ([`InteriorMap::measure_certificate`](super::InteriorMap::measure_certificate)), for its
    /// [`certificate_confidence`](super::InteriorMap::certificate_confidence): a certified pose
    /// costs one exact query. 0 skips the measurement (an open mesh's
    /// `certificate_confidence` then stays 0), and then its certificate never settles a query. 2000 by default: with every
    /// certificate right, the lower 95 % bound reaches 0.99 once 299 of the poses are
    /// certified. Closed meshes are never measured (their certificate is exact).
    pub certificate_poses: usize,
    /// With a [`fit`](AdbBuildOptions::fit) and an interior map, also fit the
    /// [`ConfidenceCalibration`](super::ConfidenceCalibration) of answers a failed
    /// interpenetration certificate leaves unsettled (seeded queries of the mesh against itself
    /// under node budgets, each checked by the exact query), which a query of the tree against
    /// itself applies to such answers. `false` skips it, and those answers keep the frontier's
    /// confidence. On by default.
    pub confidence_fit: bool,
    /// Bound each node's triangles also by the slab along their mean normal
    /// ([`AdbNode::slab`](super::AdbNode::slab)): with the box a tighter volume, so near misses
    /// between nearly flat patches are culled exactly. On by default; the papers' nodes are
    /// boxes only ([`AdbBuildOptions::paper`]).
    pub normal_slabs: bool,
}

impl AdbBuildOptions {
    /// Trees as Klein & Zachmann build them: a cell is well filled at the published MaxArea
    /// (fill fraction 1), nodes are boxes only (no slab), and none of this crate's additions
    /// (no fitted calibrations, no interior map). The grid is the default 4³ (the papers do
    /// not give theirs). For checking [`AdbQuery::paper`](super::AdbQuery::paper) as published.
    pub fn paper() -> Self {
        Self {
            fill_fraction: 1.0,
            fit: None,
            interior_resolution: 0,
            certificate_poses: 0,
            confidence_fit: false,
            normal_slabs: false,
            ..Self::default()
        }
    }
}

impl Default for AdbBuildOptions {
    fn default() -> Self {
        Self {
            normal_slabs: true,
            resolution: 4,
            fill_fraction: 0.5,
            threads: 0,
            fit: Some(FitOptions::default()),
            interior_resolution: 128,
            interior_samples: 128,
            certificate_poses: 2000,
            confidence_fit: true,
        }
    }
}

/// Options of [`FittedEstimator::fit`](super::FittedEstimator::fit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitOptions {
    /// Training poses (near first contact, seeded; never the poses you evaluate on).
    pub poses: usize,
    /// Random descents from the root pair per pose; every node pair on the way is a sample.
    pub walks_per_pose: usize,
    /// Offsets of the training poses from first contact, as a fraction of the size.
    pub spread: f32,
    /// Seed of the poses and walks.
    pub seed: u64,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            poses: 48,
            walks_per_pose: 24,
            spread: 0.15,
            seed: 0xF17,
        }
    }
}

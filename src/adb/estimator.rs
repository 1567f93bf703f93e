//! Pluggable estimators of the probability that two nodes contain intersecting triangles.
use super::calibration::{Calibration, DEPTH_BUCKETS};
use super::probability::{
    DEFAULT_X_MAX, ModelBox, cell_counts_of_grids, depth_lower_bound, overlap_volume_of,
};
use super::tables::collision_probability_tabled;
use super::tree::{AdbNode, AdbTree};

/// Everything an estimator may use about one pair of overlapping nodes.
#[derive(Debug, Clone, Copy)]
pub struct NodePair<'a> {
    /// The first tree's node.
    pub a: &'a AdbNode,
    /// The second tree's node.
    pub b: &'a AdbNode,
    /// Maximum depth of the first tree.
    pub max_depth_a: u32,
    /// Maximum depth of the second tree.
    pub max_depth_b: u32,
    /// Distance between the two boxes' centres.
    pub center_distance: f32,
    /// Cells per node of the first tree's grids.
    pub cells_a: u32,
    /// Cells per node of the second tree's grids.
    pub cells_b: u32,
    /// The first tree's fitted calibration, if it has one.
    pub calibration_a: Option<&'a Calibration>,
    /// The second tree's fitted calibration, if it has one.
    pub calibration_b: Option<&'a Calibration>,
}

impl<'a> NodePair<'a> {
    /// The pair of node `ia` of `a` and node `ib` of `b` whose boxes' centres are
    /// `center_distance` apart.
    #[inline]
    pub(crate) fn at_distance(
        a: &'a AdbTree,
        b: &'a AdbTree,
        center_distance: f32,
        ia: u32,
        ib: u32,
        calibrated: bool,
    ) -> Self {
        NodePair {
            a: &a.nodes()[ia as usize],
            b: &b.nodes()[ib as usize],
            max_depth_a: a.max_depth(),
            max_depth_b: b.max_depth(),
            center_distance,
            cells_a: a.cells_per_node(),
            cells_b: b.cells_per_node(),
            calibration_a: if calibrated { a.calibration() } else { None },
            calibration_b: if calibrated { b.calibration() } else { None },
        }
    }
}

/// Estimates the probability that two overlapping nodes contain intersecting triangles.
///
/// Implementations must be deterministic and return a value in `[0, 1]`. The traversal calls
/// this once per overlapping node pair it estimates, so it should be cheap (a few arithmetic
/// operations and table lookups, like the estimators here).
pub trait CollisionEstimator: Send + Sync + std::fmt::Debug {
    /// The probability for this pair.
    fn probability(&self, pair: &NodePair<'_>) -> f64;
    /// A short name for reports.
    fn name(&self) -> &'static str;
}

/// The papers' estimate: overlap volume → `s, s_A, s_B` → Eq. 8 → Eq. 9 with the curvature term
/// `LB = (d_A + d_B) / (d_maxA + d_maxB)` and `x ≤ x_max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperEstimator {
    /// Cap on the number of collision cells `x` in Eq. 9 (the papers: [`DEFAULT_X_MAX`](super::probability::DEFAULT_X_MAX)).
    pub x_max: u32,
}

impl Default for PaperEstimator {
    fn default() -> Self {
        Self {
            x_max: DEFAULT_X_MAX,
        }
    }
}

/// Beyond the papers: the curvature term from the mesh itself. Each node stores how flat its
/// surface is ([`AdbNode::planarity`]); `LB` is the geometric mean of the two planarities, so
/// flat patches deep or shallow in the tree count as likely to intersect and curved ones do not,
/// whatever their depth. Everything else as [`PaperEstimator`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarityEstimator {
    /// Cap on the number of collision cells `x` in Eq. 9.
    pub x_max: u32,
}

impl Default for PlanarityEstimator {
    fn default() -> Self {
        Self {
            x_max: DEFAULT_X_MAX,
        }
    }
}

/// Eq. 9 for this pair with the given curvature term.
#[inline]
pub fn eq9_probability(pair: &NodePair<'_>, lb: f64, x_max: u32) -> f64 {
    let (a, b) = (pair.a, pair.b);
    let (box_a, box_b) = (ModelBox::new(a.sides), ModelBox::new(b.sides));
    let v = overlap_volume_of(&box_a, &box_b, pair.center_distance);
    // Each tree's fill density over its own grid (the trees may differ in resolution).
    let counts = cell_counts_of_grids(
        v,
        (box_a.volume(), u32::from(a.well_filled), pair.cells_a),
        (box_b.volume(), u32::from(b.well_filled), pair.cells_b),
    );
    collision_probability_tabled(counts, lb, x_max)
}

impl CollisionEstimator for PaperEstimator {
    #[inline]
    fn probability(&self, pair: &NodePair<'_>) -> f64 {
        let lb = depth_lower_bound(
            u32::from(pair.a.depth),
            u32::from(pair.b.depth),
            pair.max_depth_a,
            pair.max_depth_b,
        );
        eq9_probability(pair, lb, self.x_max)
    }

    fn name(&self) -> &'static str {
        "paper"
    }
}

impl CollisionEstimator for PlanarityEstimator {
    #[inline]
    fn probability(&self, pair: &NodePair<'_>) -> f64 {
        let lb = (f64::from(pair.a.planarity) * f64::from(pair.b.planarity)).sqrt();
        eq9_probability(pair, lb, self.x_max)
    }

    fn name(&self) -> &'static str {
        "planarity"
    }
}

/// The recommended estimator: [`PlanarityEstimator`]'s raw value mapped through the
/// calibrations each [`AdbTree`](super::AdbTree) fits on its own mesh at build time
/// ([`AdbBuildOptions::fit`](super::AdbBuildOptions::fit)); the mean of the two trees'
/// calibrated values, or the raw value for a tree built without one.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CalibratedEstimator {
    /// The raw estimate.
    pub base: PlanarityEstimator,
}

impl CollisionEstimator for CalibratedEstimator {
    #[inline]
    fn probability(&self, pair: &NodePair<'_>) -> f64 {
        let raw = self.base.probability(pair);
        match (pair.calibration_a, pair.calibration_b) {
            // A mesh against a copy of itself: one map (the mean of two equal values).
            (Some(a), Some(b)) if std::ptr::eq(a, b) => a.map(pair, raw),
            (Some(a), Some(b)) => 0.5 * (a.map(pair, raw) + b.map(pair, raw)),
            (Some(c), None) | (None, Some(c)) => c.map(pair, raw),
            (None, None) => raw,
        }
    }

    fn name(&self) -> &'static str {
        "calibrated"
    }
}

/// The calibration's query for a node pair (its depth bucket), beside [`NodePair`], which
/// it reads.
impl Calibration {
    /// The calibrated probability of a raw estimate for this pair. Depth buckets the fit never
    /// sampled (possible for pairs of two different trees) keep the raw estimate.
    #[inline]
    pub fn map(&self, pair: &NodePair<'_>, raw: f64) -> f64 {
        self.lookup(bucket(pair), raw.clamp(0.0, 1.0))
    }
}

/// The depth bucket of a pair: `(d_A + d_B) / (d_maxA + d_maxB)` in [`DEPTH_BUCKETS`] steps.
#[inline]
pub(super) fn bucket(pair: &NodePair<'_>) -> usize {
    let total = (pair.max_depth_a + pair.max_depth_b).max(1) as f32;
    let d = f32::from(pair.a.depth) + f32::from(pair.b.depth);
    ((d / total * DEPTH_BUCKETS as f32) as usize).min(DEPTH_BUCKETS - 1)
}

//! The confidence of a continuous ADB answer the budget cut short, from features of what the
//! search left: a logistic model fitted once on swept pairs of training meshes
//! (`examples/fit_swept_answer_model.rs`), as [`AnswerModel`](crate::adb::AnswerModel) is for
//! the discrete query.
//!
//! The node pairs' estimates, each taken at its closest approach by the discrete probability
//! model, are one feature (their combination, and the largest); the model learns how far to
//! trust them given how many pairs are left, how deep the boxes meet, how much of the step
//! their windows span, how much the search saw and how different the meshes' sizes are.
use crate::adb::logistic::{fit_logistic, logistic, logit};

/// Number of features of [`SweptAnswerModel`] (the bias included).
pub const SWEPT_FEATURES: usize = 11;

/// What an unsettled continuous ADB query left when its budget ran out: the inputs of
/// [`SweptAnswerModel::features`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweptFrontier {
    /// The node pairs' estimates combined as the discrete query combines its frontier:
    /// `1 − (Π (1 − p))^(1/2)`, each `p` at the pair's closest approach.
    pub raw_confidence: f64,
    /// The largest of those estimates.
    pub max_probability: f64,
    /// Node pairs left.
    pub pairs: u32,
    /// Node pairs examined.
    pub visited: u64,
    /// Over the pairs left, the smallest distance between their boxes' centres at closest
    /// approach, over the sum of their boxes' half diagonals (0: the centres meet; 1 and more:
    /// the boxes' bounding spheres do not overlap).
    pub nearest_centres: f64,
    /// The mean length of the pairs' windows (when their moving boxes can meet), as a fraction
    /// of the step.
    pub mean_window: f64,
    /// The earliest time a pair left can meet, as a fraction of the step.
    pub earliest: f64,
    /// Over the pairs left, the deepest overlap of their boxes at closest approach: per axis
    /// the overlap over the smaller box's extent, the least of the three (1: on every axis one
    /// box spans the other, as a ball crossing a thin wall; 0: the boxes only touch).
    pub deepest: f64,
    /// The first tree's root box diagonal over the second's.
    pub size_ratio: f64,
    /// The two trees' node counts together.
    pub tree_nodes: u64,
}

/// A logistic model of how often an unsettled continuous answer with given [`SweptFrontier`]
/// features truly touches during the step: `confidence = 1 / (1 + exp(−w·x))` over
/// [`SweptAnswerModel::features`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SweptAnswerModel {
    /// Weights, in the order of [`SweptAnswerModel::features`].
    pub weights: [f64; SWEPT_FEATURES],
}

impl SweptAnswerModel {
    /// The model [`adb_time_of_impact`](super::adb_time_of_impact) uses by default, fitted by
    /// `cargo run --release --example fit_swept_answer_model` on its named training meshes and
    /// seeds; `continuous_adb_reliability` evaluates it on other meshes and seeds. Stored
    /// output: `docs/ccd/swept_answer_model.txt`. The nearness of the closest pair's box centres
    /// carries most of it (weight −5.9 on their distance over the boxes' sizes), then the
    /// pairs' windows (+2.2) and how deep their boxes overlap (+1.7): a pair left whose boxes'
    /// centres come within a small fraction of their sizes usually touches, one whose boxes
    /// only graze usually does not.
    pub const FITTED: SweptAnswerModel = SweptAnswerModel {
        weights: [
            2.2938284290768745,
            0.06819030932187414,
            0.11823272501771656,
            0.5983723697178815,
            -0.5790213295689683,
            -5.937220056880328,
            2.2367050279972127,
            0.7076555510527204,
            0.0023310215311783365,
            -0.11961560116843867,
            1.7189266631203528,
        ],
    };

    /// The features of an unsettled answer: a bias; the combined and the largest estimate as
    /// log-odds; the logs of the pairs left and of the node pairs examined; how near the
    /// closest pair's box centres come (clamped to 4); the mean window and the earliest time;
    /// the absolute log-ratio of the trees' sizes; the log of their node count together; how
    /// deep the deepest pair's boxes overlap.
    pub fn features(f: &SweptFrontier) -> [f64; SWEPT_FEATURES] {
        [
            1.0,
            logit(f.raw_confidence),
            logit(f.max_probability),
            f64::from(f.pairs.max(1)).ln(),
            (f.visited.max(1) as f64).ln(),
            f.nearest_centres.clamp(0.0, 4.0),
            f.mean_window.clamp(0.0, 1.0),
            f.earliest.clamp(0.0, 1.0),
            f.size_ratio.max(f64::MIN_POSITIVE).ln().abs(),
            (f.tree_nodes.max(1) as f64).ln(),
            f.deepest.clamp(0.0, 1.0),
        ]
    }

    /// The model's confidence for features `x`.
    pub fn confidence_of(&self, x: &[f64; SWEPT_FEATURES]) -> f64 {
        logistic(&self.weights, x)
    }

    /// The model's confidence for an unsettled answer.
    pub fn confidence(&self, frontier: &SweptFrontier) -> f64 {
        self.confidence_of(&Self::features(frontier))
    }

    /// Fits the model to `samples` (features, whether the meshes truly touch during the step)
    /// by Newton's method on the log-likelihood with a ridge penalty `ridge` (not on the bias).
    /// Deterministic; `None` when there are no samples or the Newton steps fail.
    pub fn fit(samples: &[([f64; SWEPT_FEATURES], bool)], ridge: f64) -> Option<Self> {
        fit_logistic(samples, ridge).map(|weights| SweptAnswerModel { weights })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frontier(raw: f64) -> SweptFrontier {
        SweptFrontier {
            raw_confidence: raw,
            max_probability: raw,
            pairs: 12,
            visited: 100,
            nearest_centres: 0.5,
            mean_window: 0.3,
            earliest: 0.2,
            size_ratio: 1.0,
            tree_nodes: 2000,
            deepest: 0.5,
        }
    }

    /// Answers drawn with a known frequency of contact per raw estimate (other features
    /// random and irrelevant) are fitted to a model that reports that frequency.
    #[test]
    fn the_fit_reports_the_observed_frequency() {
        let mut samples = Vec::new();
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        // The truth: contact with probability logistic(2·logit(raw) − 1), whatever else.
        let truth = |raw: f64| 1.0 / (1.0 + (1.0 - 2.0 * logit(raw)).exp());
        for _ in 0..20_000 {
            let raw = 0.02 + 0.96 * next();
            let mut f = frontier(raw);
            f.pairs = 1 + (next() * 50.0) as u32;
            f.nearest_centres = 2.0 * next();
            f.deepest = next();
            samples.push((SweptAnswerModel::features(&f), next() < truth(raw)));
        }
        let model = SweptAnswerModel::fit(&samples, 1e-3).unwrap();
        for raw in [0.2, 0.5, 0.8] {
            let c = model.confidence(&frontier(raw));
            assert!(
                (c - truth(raw)).abs() < 0.03,
                "{raw}: {c} against {}",
                truth(raw)
            );
        }
        assert!(SweptAnswerModel::fit(&[], 1e-3).is_none());
    }
}

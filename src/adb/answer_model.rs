//! The confidence of an answer the ADB traversal did not settle, from features that mean the
//! same for any pair of trees: a logistic model fitted once on a training set of many mesh
//! pairs (`examples/fit_answer_model.rs`), not per mesh against itself.
//!
//! A budget-cut answer rests on its frontier ([`Frontier`]): the node pairs left, their
//! estimates, how deep they are, what the interpenetration certificate said, how much of the
//! trees the traversal saw, and how different the two meshes' sizes are. The frontier's raw
//! confidence (the pair estimates combined) is one of these features; the model learns how far
//! to trust it given the others.
use super::frontier::{CertificateHint, Frontier};
use super::logistic::{fit_logistic, logistic, logit};

/// Number of features (the bias included).
pub const ANSWER_FEATURES: usize = 10;

/// A logistic model of how often an unsettled answer with given [`Frontier`] features truly
/// collides: `confidence = 1 / (1 + exp(−w·x))` over [`AnswerModel::features`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnswerModel {
    /// Weights, in the order of [`AnswerModel::features`].
    pub weights: [f64; ANSWER_FEATURES],
}

impl AnswerModel {
    /// The model this crate's traversal uses, fitted by `cargo run --release --example
    /// fit_answer_model` on its named training pairs and seeds (`training_pairs`,
    /// `TRAINING_SEEDS` there); the `accuracy_vs_time` report evaluates it on other meshes,
    /// pairs and seeds.
    /// Stored output: `docs/adb/answer_model/output.txt`.
    pub const FITTED: AnswerModel = AnswerModel {
        weights: [
            -1.2118599665085623,
            0.26939881570399987,
            -0.10060199849444897,
            0.3614358403329986,
            -0.22438910032589304,
            -1.3843646979335933,
            1.3843646979267987,
            -0.46159912544557496,
            0.40947141169623275,
            0.2780565793533133,
        ],
    };

    /// The features of an unsettled answer: a bias; the frontier's raw confidence and its
    /// highest pair probability as log-odds; the log of its pair count; its mean relative
    /// depth; whether the certificate found the pose probably apart, or undecided; the log of
    /// the node pairs visited; the absolute log-ratio of the two trees' sizes (their root
    /// boxes' diagonals); and the log of the two trees' node count together (how much there is
    /// to search: the same work covers more of a small tree).
    pub fn features(
        frontier: &Frontier,
        visited: u64,
        size_ratio: f64,
        tree_nodes: u64,
    ) -> [f64; ANSWER_FEATURES] {
        [
            1.0,
            logit(frontier.raw_confidence),
            logit(frontier.max_probability),
            f64::from(frontier.pairs.max(1)).ln(),
            f64::from(frontier.mean_depth),
            f64::from(u8::from(frontier.certificate == CertificateHint::Apart)),
            f64::from(u8::from(frontier.certificate == CertificateHint::Undecided)),
            (visited.max(1) as f64).ln(),
            size_ratio.max(f64::MIN_POSITIVE).ln().abs(),
            (tree_nodes.max(1) as f64).ln(),
        ]
    }

    /// The model's confidence for features `x`.
    pub fn confidence_of(&self, x: &[f64; ANSWER_FEATURES]) -> f64 {
        logistic(&self.weights, x)
    }

    /// The model's confidence for an unsettled answer.
    pub fn confidence(
        &self,
        frontier: &Frontier,
        visited: u64,
        size_ratio: f64,
        tree_nodes: u64,
    ) -> f64 {
        self.confidence_of(&Self::features(frontier, visited, size_ratio, tree_nodes))
    }

    /// Fits the model to `samples` (features, whether the pose truly collides) by Newton's
    /// method on the log-likelihood with a small ridge penalty `ridge` (not on the bias).
    /// Deterministic; `None` when there are no samples or the Newton steps fail.
    pub fn fit(samples: &[([f64; ANSWER_FEATURES], bool)], ridge: f64) -> Option<Self> {
        fit_logistic(samples, ridge).map(|weights| AnswerModel { weights })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples drawn from a known logistic model are fitted back to close to its weights.
    #[test]
    fn fit_recovers_a_known_model() {
        let truth = [0.5, 1.5, -0.7, 0.3, 0.0, -1.0, 0.4, -0.2, 0.6, -0.4];
        let model = AnswerModel { weights: truth };
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let samples: Vec<_> = (0..20_000)
            .map(|_| {
                let mut x = [1.0; ANSWER_FEATURES];
                for v in &mut x[1..] {
                    *v = 4.0 * next() - 2.0;
                }
                let y = next() < model.confidence_of(&x);
                (x, y)
            })
            .collect();
        let fitted = AnswerModel::fit(&samples, 1e-6).unwrap();
        for (f, t) in fitted.weights.iter().zip(truth) {
            assert!((f - t).abs() < 0.15, "{:?} vs {truth:?}", fitted.weights);
        }
    }

    #[test]
    fn no_samples_no_model() {
        assert!(AnswerModel::fit(&[], 1e-3).is_none());
    }
}

//! The confidence of an answer the ADB traversal did not settle, from features that mean the
//! same for any pair of trees: a logistic model fitted once on a training set of many mesh
//! pairs (`examples/fit_answer_model.rs`), not per mesh against itself.
//!
//! A budget-cut answer rests on its frontier ([`Frontier`]): the node pairs left, their
//! estimates, how deep they are, what the interpenetration certificate said, how much of the
//! trees the traversal saw, and how different the two meshes' sizes are. The frontier's raw
//! confidence (the pair estimates combined) is one of these features; the model learns how far
//! to trust it given the others.
use super::traverse::{CertificateHint, Frontier};

/// Number of features (the bias included).
pub const ANSWER_FEATURES: usize = 10;

/// A logistic model of how often an unsettled answer with given [`Frontier`] features truly
/// collides: `confidence = 1 / (1 + exp(−w·x))` over [`AnswerModel::features`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnswerModel {
    /// Weights, in the order of [`AnswerModel::features`].
    pub weights: [f64; ANSWER_FEATURES],
}

/// Logits are clamped to this magnitude (probabilities within about 5e-5 of 0 or 1).
const LOGIT_CLAMP: f64 = 10.0;

/// The log-odds of `p`, clamped.
fn logit(p: f64) -> f64 {
    let p = p.clamp(1e-12, 1.0 - 1e-12);
    (p / (1.0 - p)).ln().clamp(-LOGIT_CLAMP, LOGIT_CLAMP)
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
        let z: f64 = self.weights.iter().zip(x).map(|(w, v)| w * v).sum();
        1.0 / (1.0 + (-z.clamp(-4.0 * LOGIT_CLAMP, 4.0 * LOGIT_CLAMP)).exp())
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
        if samples.is_empty() {
            return None;
        }
        const N: usize = ANSWER_FEATURES;
        let mut w = [0.0f64; N];
        for _ in 0..50 {
            let model = AnswerModel { weights: w };
            let mut grad = [0.0f64; N];
            let mut hess = [[0.0f64; N]; N];
            for (x, y) in samples {
                let p = model.confidence_of(x);
                let r = f64::from(u8::from(*y)) - p;
                let v = (p * (1.0 - p)).max(1e-12);
                for i in 0..N {
                    grad[i] += r * x[i];
                    for j in 0..N {
                        hess[i][j] += v * x[i] * x[j];
                    }
                }
            }
            for i in 1..N {
                grad[i] -= ridge * w[i];
                hess[i][i] += ridge;
            }
            hess[0][0] += 1e-9;
            let step = solve(hess, grad)?;
            let mut largest = 0.0f64;
            for i in 0..N {
                w[i] += step[i];
                largest = largest.max(step[i].abs());
            }
            if largest < 1e-9 {
                break;
            }
        }
        w.iter()
            .all(|v| v.is_finite())
            .then_some(AnswerModel { weights: w })
    }
}

/// Solves `a · x = b` by Gaussian elimination with partial pivoting; `None` when singular.
fn solve<const N: usize>(mut a: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for col in 0..N {
        let pivot = (col..N).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let (pivot_row, pivot_b) = (a[col], b[col]);
        for (row, b_row) in a.iter_mut().zip(b.iter_mut()).skip(col + 1) {
            let f = row[col] / pivot_row[col];
            for (v, p) in row.iter_mut().zip(pivot_row).skip(col) {
                *v -= f * p;
            }
            *b_row -= f * pivot_b;
        }
    }
    let mut x = [0.0f64; N];
    for row in (0..N).rev() {
        let s: f64 = (row + 1..N).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    Some(x)
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

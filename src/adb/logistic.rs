//! Logistic models of "does this unsettled answer truly collide": the probability of a feature
//! vector, and the fit of the weights (Newton's method with a small ridge), shared by the
//! discrete [`AnswerModel`](super::AnswerModel) and the continuous query's
//! [`SweptAnswerModel`](crate::ccd::SweptAnswerModel).

/// Logits are clamped to this magnitude (probabilities within about 5e-5 of 0 or 1).
const LOGIT_CLAMP: f64 = 10.0;

/// The log-odds of `p`, clamped to ±10.
pub(crate) fn logit(p: f64) -> f64 {
    let p = p.clamp(1e-12, 1.0 - 1e-12);
    (p / (1.0 - p)).ln().clamp(-LOGIT_CLAMP, LOGIT_CLAMP)
}

/// `1 / (1 + exp(−w·x))`, the sum clamped to ±40.
pub(crate) fn logistic<const N: usize>(w: &[f64; N], x: &[f64; N]) -> f64 {
    let z: f64 = w.iter().zip(x).map(|(w, v)| w * v).sum();
    1.0 / (1.0 + (-z.clamp(-4.0 * LOGIT_CLAMP, 4.0 * LOGIT_CLAMP)).exp())
}

/// The weights of a logistic model fitted to `samples` (features, the first of them a bias
/// of 1; whether the answer truly collides) by Newton's method on the log-likelihood with a
/// ridge penalty `ridge` on every weight but the bias's. Deterministic; `None` when there are
/// no samples or the Newton steps fail.
pub(crate) fn fit_logistic<const N: usize>(
    samples: &[([f64; N], bool)],
    ridge: f64,
) -> Option<[f64; N]> {
    if samples.is_empty() {
        return None;
    }
    let mut w = [0.0f64; N];
    for _ in 0..50 {
        let mut grad = [0.0f64; N];
        let mut hess = [[0.0f64; N]; N];
        for (x, y) in samples {
            let p = logistic(&w, x);
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
    w.iter().all(|v| v.is_finite()).then_some(w)
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

//! The fitted tables that calibrate ADB estimates and confidences, and the arithmetic their fits
//! share: the data an [`AdbTree`](super::AdbTree) stores from its build-time fits
//! ([`super::fit`], [`super::confidence_fit`]).

/// Depth buckets of the fitted table (by `(d_A + d_B) / (d_maxA + d_maxB)`).
pub const DEPTH_BUCKETS: usize = 8;
/// Bins of the base estimator's raw probability.
pub const RAW_BINS: usize = 20;

/// A fitted mapping from a raw estimate to a calibrated probability, per depth bucket
/// (see [`FittedEstimator`](super::FittedEstimator)).
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    table: [[f32; RAW_BINS]; DEPTH_BUCKETS],
    samples: usize,
}

impl Calibration {
    /// The calibrated probability of `raw` (in `[0, 1]`) in depth bucket `bucket`; `raw` itself
    /// where the fit never sampled that bucket.
    #[inline]
    pub(super) fn lookup(&self, bucket: usize, raw: f64) -> f64 {
        let fitted = self.table[bucket][raw_bin(raw)];
        if fitted.is_nan() {
            raw
        } else {
            f64::from(fitted)
        }
    }

    /// The mapping of a fit (see [`monotone_rates`]) from `samples` node pairs.
    pub(super) fn new(table: [[f32; RAW_BINS]; DEPTH_BUCKETS], samples: usize) -> Self {
        Self { table, samples }
    }

    /// The table: `[depth bucket][raw-probability bin]` → probability (NaN: no samples).
    pub fn table(&self) -> &[[f32; RAW_BINS]; DEPTH_BUCKETS] {
        &self.table
    }

    /// Node pairs sampled by the fit.
    pub fn samples(&self) -> usize {
        self.samples
    }
}

/// The bin of a raw probability in `[0, 1]`.
#[inline]
pub(super) fn raw_bin(raw: f64) -> usize {
    ((raw * RAW_BINS as f64) as usize).min(RAW_BINS - 1)
}

/// Per-bin hit rates with a Beta(½, ½) prior, made non-decreasing by pooling adjacent
/// violators (weighted by sample counts); empty bins take their neighbours' values.
pub(super) fn monotone_rates(cells: &[(u32, u32); RAW_BINS]) -> [f32; RAW_BINS] {
    // Blocks of (weight, rate, first bin, last bin) over the non-empty bins.
    let mut blocks: Vec<(f64, f64, usize, usize)> = Vec::new();
    for (i, &(n, hits)) in cells.iter().enumerate() {
        if n == 0 {
            continue;
        }
        let rate = (f64::from(hits) + 0.5) / (f64::from(n) + 1.0);
        blocks.push((f64::from(n), rate, i, i));
        while blocks.len() >= 2 && blocks[blocks.len() - 2].1 > blocks[blocks.len() - 1].1 {
            let (w2, r2, _, e2) = blocks.pop().expect("two blocks");
            let (w1, r1, s1, _) = blocks.pop().expect("two blocks");
            blocks.push((w1 + w2, (w1 * r1 + w2 * r2) / (w1 + w2), s1, e2));
        }
    }
    let mut out = [f32::NAN; RAW_BINS];
    for &(_, rate, s, e) in &blocks {
        for v in &mut out[s..=e] {
            *v = rate as f32;
        }
    }
    // Fill empty bins: from the left neighbour, else the right one. A row with no samples at
    // all stays NaN, and `Calibration::map` then returns the raw estimate unchanged.
    let Some(first) = out.iter().copied().find(|v| !v.is_nan()) else {
        return out;
    };
    let mut last = first;
    for v in &mut out {
        if v.is_nan() {
            *v = last;
        } else {
            last = *v;
        }
    }
    out
}

/// A fitted mapping from the frontier's confidence of an answer that a failed interpenetration
/// certificate left unsettled to the frequency with which such answers collide (see the module
/// documentation; monotone, with a Beta(½, ½) prior per bin). Stored in an [`AdbTree`](super::AdbTree) built
/// with both a fit and an [`InteriorMap`](super::InteriorMap).
#[derive(Debug, Clone, PartialEq)]
pub struct ConfidenceCalibration {
    table: [f32; RAW_BINS],
    samples: usize,
}

impl ConfidenceCalibration {
    /// The mapping of a fit from `samples` training answers.
    pub(super) fn new(table: [f32; RAW_BINS], samples: usize) -> Self {
        Self { table, samples }
    }

    /// The calibrated confidence of a raw frontier confidence (every bin has a value: the fit
    /// keeps a calibration only when some answer was sampled, and empty bins take their
    /// neighbours').
    #[inline]
    pub fn map(&self, raw: f64) -> f64 {
        f64::from(self.table[raw_bin(raw.clamp(0.0, 1.0))])
    }

    /// The table: raw-confidence bin → frequency of collision.
    pub fn table(&self) -> &[f32; RAW_BINS] {
        &self.table
    }

    /// Training answers the fit learned from.
    pub fn samples(&self) -> usize {
        self.samples
    }
}

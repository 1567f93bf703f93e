//! Reliability bins shared by the reports: answers sorted into ten bins of reported
//! probability, each bin's answers, how many were right to say "collision", and the summed
//! probability.

/// Per bin of reported probability (`[0, 0.1)`, …, `[0.9, 1]`): answers, collisions, summed
/// reported probability.
pub type Bins = [(usize, usize, f64); 10];

/// Adds an answer of reported probability `p` whose truth was `collides`.
pub fn add(bins: &mut Bins, p: f64, collides: bool) {
    let b = ((p * 10.0) as usize).min(9);
    bins[b].0 += 1;
    bins[b].1 += usize::from(collides);
    bins[b].2 += p;
}

/// Each non-empty bin as a point: its mean reported probability, its observed frequency.
pub fn points(bins: &Bins) -> Vec<(f64, f64)> {
    bins.iter()
        .filter(|b| b.0 > 0)
        .map(|b| (b.2 / b.0 as f64, b.1 as f64 / b.0 as f64))
        .collect()
}

/// The non-empty bins as text: `[0.1,0.2): 0.12 (48), …` (observed frequency, answers).
pub fn line(bins: &Bins) -> String {
    bins.iter()
        .enumerate()
        .filter(|(_, b)| b.0 > 0)
        .map(|(j, b)| {
            format!(
                "[{:.1},{:.1}): {:.2} ({})",
                j as f64 / 10.0,
                (j + 1) as f64 / 10.0,
                b.1 as f64 / b.0 as f64,
                b.0
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

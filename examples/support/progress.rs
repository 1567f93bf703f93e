//! The progress bar of the examples that show long work on stderr (`accuracy_vs_time`,
//! `tracking_quality`, `query`).

/// Characters of the bar.
pub const WIDTH: usize = 30;

/// `[#####     ]  NN%` for `done` of `total` (an empty `total` counts as done).
pub fn bar(done: usize, total: usize) -> String {
    let total = total.max(1);
    let done = done.min(total);
    let filled = done * WIDTH / total;
    format!(
        "[{}{}] {:>3}%",
        "#".repeat(filled),
        " ".repeat(WIDTH - filled),
        done * 100 / total
    )
}

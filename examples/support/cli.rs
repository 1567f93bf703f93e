//! Command-line helpers shared by the examples that take named choices (`query`, `profile`).
use stochastic_collision::adb::{Decision, Order};

/// The names of the ADB decisions a command line may choose (`--decision`, `--adb-decision`).
pub const DECISIONS: &[(&str, Decision)] = &[
    ("confidence", Decision::Confidence),
    ("evidence", Decision::Evidence),
];

/// The names of the ADB traversal orders (`--order`, `--adb-order`).
pub const ORDERS: &[(&str, Order)] = &[
    ("depth-first", Order::DepthFirst),
    ("straddle", Order::Straddle),
    ("evidence-first", Order::EvidenceFirst),
    ("best-first", Order::BestFirst),
];

/// The value of `flag` among the `known` names, or an error naming them.
pub fn parse_choice<T: Copy>(value: &str, flag: &str, known: &[(&str, T)]) -> Result<T, String> {
    known
        .iter()
        .find(|(name, _)| *name == value)
        .map(|&(_, v)| v)
        .ok_or_else(|| {
            let names: Vec<&str> = known.iter().map(|(name, _)| *name).collect();
            format!(
                "{flag}: invalid value `{value}` (known: {})",
                names.join(", ")
            )
        })
}

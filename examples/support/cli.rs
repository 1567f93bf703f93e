//! Command-line helpers shared by the examples that take named choices (`query`, `profile`).

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

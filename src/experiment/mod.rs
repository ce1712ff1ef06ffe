//! Experiment harnesses behind `strata bench`, `strata scaling` (and its
//! prediction past this machine's cores, `predict`) and `strata converge`: they measure the renderer, they do not render for
//! users. Each writes numbers a chart or a table can show; none decides
//! what the renderer does.

pub mod bench;
pub mod converge;
pub mod predict;
pub mod scaling;

/// A table's columns with what each means, as lines for `--help` or for
/// printing under the table: each name (or names sharing a meaning)
/// padded to one width, then its meaning.
pub fn column_key(columns: &[(&str, &str)]) -> String {
    let width = columns
        .iter()
        .map(|(n, _)| n.chars().count())
        .max()
        .unwrap_or(0);
    columns
        .iter()
        .map(|(name, meaning)| format!("  {name:<width$}  {meaning}\n"))
        .collect()
}

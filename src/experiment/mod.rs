//! Experiment harnesses behind `strata bench`, `strata scaling` (and its
//! prediction past this machine's cores, `predict`) and `strata converge`: they measure the renderer, they do not render for
//! users. Each writes numbers a chart or a table can show; none decides
//! what the renderer does.

pub mod bench;
pub mod converge;
pub mod predict;
pub mod scaling;

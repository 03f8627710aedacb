//! gait-opt: the host-side optimiser over gait-core's paper-mode problem
//! (`gait_core::problem::PaperProblem`), human-data baselines, and the
//! serialisable report the `exogait` CLI writes and re-checks.
//!
//! - [`optimize`]: IPOP-CMA-ES with successive-halving exploration and a
//!   pattern-search polish, budgeted by evaluation count (deterministic).
//! - [`baseline()`]: a swing step built from reference joint angles.
//! - [`cost_from_phi`]: J from a Φ sequence (for baselines), cross-checked
//!   against `PaperProblem::cost`.
//! - [`Report`]: everything needed to recompute J from the JSON alone;
//!   [`optimise_and_report`] does search, baseline and report in one call.
//! - `plot_report` (feature `plot`, default): SVG or PNG of a report.
//!
//! See `docs/optimiser.md` for the method and the measured figures.

pub mod baseline;
pub mod clinical;
pub mod clinical_report;
mod compass;
pub mod encoding;
pub mod family;
pub mod human;
pub mod phi_cost;
#[cfg(feature = "plot")]
pub mod plot;
pub mod report;
pub mod residual_limit;
pub mod run;
pub mod solver;
pub mod tables;

pub use baseline::{
    Baseline, BaselineError, Source, baseline, baseline_for_problem, baseline_from,
    default_data_dir,
};
pub use phi_cost::{PhiCostError, cost_from_phi};
#[cfg(feature = "plot")]
pub use plot::{PlotError, plot_report};
pub use report::{Report, ReportError};
pub use run::{RunError, optimise_and_report};
pub use solver::{OptimizeConfig, OptimizeError, OptimizeResult, Phase, Progress, optimize};

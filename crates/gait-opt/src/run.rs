//! One call for the CLI: optimise a case, build its baseline, and return
//! the report.

use crate::baseline::{BaselineError, baseline};
use crate::report::{Report, ReportError};
use crate::solver::{OptimizeConfig, OptimizeError, Progress, optimize};

/// Why [`optimise_and_report`] failed.
#[derive(Debug)]
pub enum RunError {
    /// The search failed.
    Optimize(OptimizeError),
    /// The baseline could not be built (e.g. the data folder is missing).
    Baseline(BaselineError),
    /// The report could not be assembled.
    Report(ReportError),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Optimize(e) => write!(f, "{e}"),
            Self::Baseline(e) => write!(f, "baseline: {e}"),
            Self::Report(e) => write!(f, "report: {e}"),
        }
    }
}

impl std::error::Error for RunError {}

/// Optimises `config.case`, builds the primary baseline from
/// [`crate::default_data_dir`], and assembles the [`Report`].
pub fn optimise_and_report(
    config: &OptimizeConfig,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Report, RunError> {
    let result = optimize(config, progress).map_err(RunError::Optimize)?;
    let base = baseline(config.case).map_err(RunError::Baseline)?;
    Report::new(&result, Some(&base)).map_err(RunError::Report)
}

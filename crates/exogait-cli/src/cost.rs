//! `exogait cost FILE.json`: recomputes J from a report's problem and
//! control points alone and compares it with the J the file states.

use std::path::Path;

use gait_opt::Report;
use serde::Serialize;

/// Largest relative difference between the recomputed and the stored J
/// that still counts as agreement.
pub const TOLERANCE: f64 = 1e-9;

/// The answer, one JSON line on stdout.
#[derive(Debug, Serialize)]
pub struct CostAnswer {
    file: String,
    case: String,
    /// Recomputed J and its parts.
    #[serde(rename = "J")]
    j: f64,
    torque: f64,
    velocity: f64,
    peak_ankle_speed_m_s: f64,
    #[serde(rename = "tau_rms_Nm")]
    tau_rms_nm: f64,
    #[serde(rename = "tau_peak_Nm")]
    tau_peak_nm: f64,
    /// J as stored in the file.
    #[serde(rename = "stored_J")]
    stored_j: f64,
    /// |J − stored J| / |stored J|.
    relative_difference: f64,
    /// relative_difference ≤ [`TOLERANCE`].
    agrees: bool,
}

/// Reads, checks and re-evaluates a report. `Err` (exit 2) names the file
/// and what is wrong with it.
pub fn run(path: &Path) -> Result<CostAnswer, String> {
    let name = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: cannot read: {e}"))?;
    let report = Report::from_json(&text).map_err(|e| format!("{name}: {e}"))?;
    let cost = report
        .recompute_cost()
        .map_err(|e| format!("{name}: {e}"))?;
    let stored = report.j.j;
    if !stored.is_finite() {
        return Err(format!("{name}: J: stored value is not a finite number"));
    }
    let relative_difference = if stored == cost.j {
        0.0
    } else {
        (cost.j - stored).abs() / stored.abs().max(f64::MIN_POSITIVE)
    };
    Ok(CostAnswer {
        file: path.display().to_string(),
        case: report.problem.case.clone(),
        j: cost.j,
        torque: cost.torque,
        velocity: cost.velocity,
        peak_ankle_speed_m_s: cost.peak_ankle_speed_m_s,
        tau_rms_nm: cost.tau_rms_nm,
        tau_peak_nm: cost.tau_peak_nm,
        stored_j: stored,
        relative_difference,
        agrees: relative_difference <= TOLERANCE,
    })
}

impl CostAnswer {
    /// Whether the recomputed J agrees with the file's.
    pub fn agrees(&self) -> bool {
        self.agrees
    }
}

//! `exogait cost FILE.json`: recomputes J from a report's problem and
//! control points alone (paper mode), or from a clinical report's search
//! point on the device (clinical mode), and compares it with the J the
//! file states.

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

/// A clinical report's recomputed J.
#[derive(Debug, Serialize)]
pub struct ClinicalCostAnswer {
    file: String,
    mode: &'static str,
    gait: String,
    /// Recomputed J: the predicted balance part plus the penalties, N·s.
    #[serde(rename = "J")]
    j: f64,
    #[serde(rename = "balance_Ns")]
    balance_ns: f64,
    penalty: f64,
    /// J as stored in the file.
    #[serde(rename = "stored_J")]
    stored_j: f64,
    /// |J − stored J| / |stored J|.
    relative_difference: f64,
    /// relative_difference ≤ [`TOLERANCE`].
    agrees: bool,
}

/// The answer of either kind of report.
#[derive(Debug, Serialize)]
#[serde(untagged)]
pub enum Answer {
    /// A paper-mode report's.
    Paper(CostAnswer),
    /// A clinical report's.
    Clinical(ClinicalCostAnswer),
}

impl Answer {
    /// Whether the recomputed J agrees with the file's.
    pub fn agrees(&self) -> bool {
        match self {
            Self::Paper(a) => a.agrees,
            Self::Clinical(a) => a.agrees,
        }
    }
}

fn relative(recomputed: f64, stored: f64) -> f64 {
    if stored == recomputed {
        0.0
    } else {
        (recomputed - stored).abs() / stored.abs().max(f64::MIN_POSITIVE)
    }
}

/// Reads, checks and re-evaluates a report of either mode. `Err` (exit 2)
/// names the file and what is wrong with it.
pub fn run(path: &Path) -> Result<Answer, String> {
    let name = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{name}: cannot read: {e}"))?;
    if text.contains("\"mode\"") {
        let r = gait_opt::clinical_report::ClinicalReport::from_json(&text)
            .map_err(|e| format!("{name}: {e}"))?;
        let device = exogait_device::DeviceConfig::exogait()
            .map_err(|e| format!("device configuration: {e:?}"))?;
        let (_, e) = r.phi(&device).map_err(|e| format!("{name}: {e}"))?;
        if !r.j.is_finite() {
            return Err(format!("{name}: j: stored value is not a finite number"));
        }
        let d = relative(e.j, r.j);
        return Ok(Answer::Clinical(ClinicalCostAnswer {
            file: path.display().to_string(),
            mode: "clinical",
            gait: r.gait.clone(),
            j: e.j,
            balance_ns: e.balance_ns,
            penalty: e.penalty,
            stored_j: r.j,
            relative_difference: d,
            agrees: d <= TOLERANCE,
        }));
    }
    paper(path, &text).map(Answer::Paper)
}

fn paper(path: &Path, text: &str) -> Result<CostAnswer, String> {
    let name = path.display();
    let report = Report::from_json(text).map_err(|e| format!("{name}: {e}"))?;
    let cost = report
        .recompute_cost()
        .map_err(|e| format!("{name}: {e}"))?;
    let stored = report.j.j;
    if !stored.is_finite() {
        return Err(format!("{name}: J: stored value is not a finite number"));
    }
    let relative_difference = relative(cost.j, stored);
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

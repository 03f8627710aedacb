//! The JSON report of a clinical-mode search: enough to rebuild the step
//! exactly (the gait, its geometry and timing, the point of the search box)
//! and the figures it was found with. `exogait table` turns it into a
//! table; `exogait simulate --table` plays it.

use exogait_device::DeviceConfig;
use gait_core::kinematics::Phi;
use gait_core::tables::GaitKind;
use serde::{Deserialize, Serialize};

use crate::clinical::{
    ClinicalCase, ClinicalResult, DIM, EvalError, Evaluation, decode, evaluate_phi, step_phi,
};

/// Marks a clinical report (paper-mode reports have no `mode`).
pub const CLINICAL_MODE: &str = "clinical";

/// A clinical-mode report.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClinicalReport {
    /// Always [`CLINICAL_MODE`].
    pub mode: String,
    /// "walk", "stair_up" or "stair_down".
    pub gait: String,
    /// Front ankle relative to the back one in double support, m.
    pub spacing_m: [f64; 2],
    /// Step time, s.
    pub step_time_s: f64,
    /// The point of the search box the step is decoded from.
    pub x: Vec<f64>,
    /// Seed and evaluations of the search.
    pub seed: u64,
    /// Evaluations used.
    pub evaluations: usize,
    /// Predicted balance part of the crutch impulse, N·s.
    pub predicted_balance_ns: f64,
    /// Peak |pilot torque|, N·m.
    pub pilot_peak_nm: f64,
    /// Peak |torque| of stance knee, stance hip, swing hip, swing knee, N·m.
    pub joint_peak_nm: [f64; 4],
    /// Peak |speed| of the same, rad/s.
    pub joint_speed_peak_rad_s: [f64; 4],
    /// Swing-foot clearance, m.
    pub clearance_m: f64,
    /// The cost J and its penalty part, N·s.
    pub j: f64,
    /// Penalty part of J, N·s.
    pub penalty: f64,
}

/// Why a report could not be used.
#[derive(Debug)]
pub enum ClinicalReportError {
    /// Not JSON of this shape.
    Json(serde_json::Error),
    /// A field is unusable (which, and why).
    Field(String),
    /// The step could not be rebuilt.
    Eval(EvalError),
}

impl std::fmt::Display for ClinicalReportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Json(e) => write!(f, "not a clinical report: {e}"),
            Self::Field(m) => write!(f, "clinical report: {m}"),
            Self::Eval(e) => write!(f, "clinical report: the step cannot be rebuilt: {e}"),
        }
    }
}

impl std::error::Error for ClinicalReportError {}

/// The name of a gait kind in reports.
pub fn gait_name(kind: GaitKind) -> &'static str {
    match kind {
        GaitKind::Walk => "walk",
        GaitKind::StairUp => "stair_up",
        GaitKind::StairDown => "stair_down",
    }
}

/// The gait kind of a report name.
pub fn gait_kind(name: &str) -> Option<GaitKind> {
    match name {
        "walk" => Some(GaitKind::Walk),
        "stair_up" => Some(GaitKind::StairUp),
        "stair_down" => Some(GaitKind::StairDown),
        _ => None,
    }
}

impl ClinicalReport {
    /// The report of a search on `case`.
    pub fn new(case: &ClinicalCase, result: &ClinicalResult, seed: u64) -> Self {
        let e: &Evaluation = &result.evaluation;
        Self {
            mode: CLINICAL_MODE.into(),
            gait: gait_name(case.gait).into(),
            spacing_m: case.spacing_m,
            step_time_s: case.step_time_s,
            x: result.x.to_vec(),
            seed,
            evaluations: result.evaluations,
            predicted_balance_ns: e.balance_ns,
            pilot_peak_nm: e.pilot_peak_nm,
            joint_peak_nm: e.joint_peak_nm,
            joint_speed_peak_rad_s: e.joint_speed_peak_rad_s,
            clearance_m: e.clearance_m,
            j: e.j,
            penalty: e.penalty,
        }
    }

    /// Reads and checks a report.
    pub fn from_json(text: &str) -> Result<Self, ClinicalReportError> {
        let r: Self = serde_json::from_str(text).map_err(ClinicalReportError::Json)?;
        if r.mode != CLINICAL_MODE {
            return Err(ClinicalReportError::Field(format!(
                "mode is {:?}, not {CLINICAL_MODE:?}",
                r.mode
            )));
        }
        if gait_kind(&r.gait).is_none() {
            return Err(ClinicalReportError::Field(format!(
                "unknown gait {:?}",
                r.gait
            )));
        }
        if r.x.len() != DIM || !r.x.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)) {
            return Err(ClinicalReportError::Field(format!(
                "x must hold {DIM} numbers in [0, 1]"
            )));
        }
        let timing = r.step_time_s.is_finite() && r.step_time_s > 0.5 && r.step_time_s < 5.0;
        if !(timing && r.spacing_m.iter().all(|v| v.is_finite())) {
            return Err(ClinicalReportError::Field(
                "step time or spacing unusable".into(),
            ));
        }
        Ok(r)
    }

    /// The report as JSON.
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        serde_json::to_string_pretty(self)
    }

    /// The case the report's step belongs to, on `device`.
    pub fn case(&self, device: &DeviceConfig) -> Result<ClinicalCase, ClinicalReportError> {
        let kind = gait_kind(&self.gait)
            .ok_or_else(|| ClinicalReportError::Field(format!("unknown gait {:?}", self.gait)))?;
        let mut case = ClinicalCase::for_gait(kind, device);
        case.spacing_m = self.spacing_m;
        case.step_time_s = self.step_time_s;
        Ok(case)
    }

    /// Φ at every table sample of the report's step, and its evaluation.
    pub fn phi(
        &self,
        device: &DeviceConfig,
    ) -> Result<(Vec<Phi<f64>>, Evaluation), ClinicalReportError> {
        let case = self.case(device)?;
        let mut x = [0.0; DIM];
        for (o, v) in x.iter_mut().zip(&self.x) {
            *o = *v;
        }
        let step = decode(&case, &x).map_err(|e| ClinicalReportError::Eval(EvalError::Step(e)))?;
        let phi = step_phi(&case, &step).map_err(ClinicalReportError::Eval)?;
        let e = evaluate_phi(&case, &phi).map_err(ClinicalReportError::Eval)?;
        Ok((phi, e))
    }
}

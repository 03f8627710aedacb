//! The serialisable result of one optimisation: the problem's every
//! paper-mode definition (so J can be recomputed from the JSON alone), the
//! control points, J and its parts, the human-data baseline, reductions,
//! solver figures and the per-sample trajectory.
//!
//! The problem's part of the file is in `spec.rs` ([`ProblemSpec`]).

mod spec;

pub use spec::{LinkSpec, ProblemSpec, StanceSpec};

use gait_core::gait::{
    CONTACT_THRESHOLD_M, ControlPoints, GaitError, StepEvent, contact_weight, evaluate_step,
};
use gait_core::kinematics::theta_from_phi;
use gait_core::problem::{Cost, PaperCase, PaperProblem};
use serde::{Deserialize, Serialize};

use crate::baseline::{Baseline, Source};
use crate::phi_cost::phi_samples;
use crate::solver::OptimizeResult;

/// Format tag written into every report.
pub const REPORT_FORMAT: &str = "exogait-report/1";
/// J and its parts.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CostFigures {
    /// J = torque + velocity + joint motion.
    #[serde(rename = "J")]
    pub j: f64,
    /// (1/(N−1)) Σ c_k τ_k², N²·m².
    pub torque: f64,
    /// v_p · peak swing-ankle speed.
    pub velocity: f64,
    /// The joint-motion term (0 in paper mode).
    #[serde(default)]
    pub joint_motion: f64,
    /// Peak swing-ankle speed, m/s.
    pub peak_ankle_speed_m_s: f64,
    /// RMS of τ over the swing samples, N·m.
    #[serde(rename = "tau_rms_Nm")]
    pub tau_rms_nm: f64,
    /// Peak |τ| over the swing samples, N·m.
    #[serde(rename = "tau_peak_Nm")]
    pub tau_peak_nm: f64,
    /// Samples with c_k = 1.
    pub swing_samples: usize,
}

impl From<Cost<f64>> for CostFigures {
    fn from(c: Cost<f64>) -> Self {
        Self {
            j: c.j,
            torque: c.torque,
            velocity: c.velocity,
            joint_motion: c.joint_motion,
            peak_ankle_speed_m_s: c.peak_ankle_speed_m_s,
            tau_rms_nm: c.tau_rms_nm,
            tau_peak_nm: c.tau_peak_nm,
            swing_samples: c.swing_samples,
        }
    }
}

/// One time sample.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SampleRow {
    /// t_k, s.
    pub t_s: f64,
    /// Φ, rad.
    pub phi_rad: [f64; 5],
    /// Θ, rad.
    pub theta_rad: [f64; 5],
    /// Joint torques T_Θ, N·m (`[0]` = τ); null for k < 2.
    #[serde(rename = "tau_Nm")]
    pub tau_nm: Option<[f64; 5]>,
    /// Swing-ankle position, m.
    pub p5_m: [f64; 2],
    /// c_k of eq. (dground): 0 while the swing ankle is within 2 mm of its
    /// start or landing (τ_k not counted in J), else 1.
    pub c_k: f64,
}

/// Fills in c_k once p5(0) and p5(N) are known.
fn set_contact(rows: &mut [SampleRow]) {
    let (Some(first), Some(last)) = (rows.first().map(|r| r.p5_m), rows.last().map(|r| r.p5_m))
    else {
        return;
    };
    for r in rows {
        r.c_k = contact_weight(r.p5_m, first, last, CONTACT_THRESHOLD_M);
    }
}

/// The baseline's figures and trajectory.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BaselineFigures {
    /// Which data set.
    pub source: Source,
    /// File and events used.
    pub source_detail: String,
    /// Amplitude factor applied to the reference angles.
    pub amplitude_scale: f64,
    /// End corrections of (φ2, φ4, φ5) at t = 0 and ts, rad.
    pub end_correction_rad: [[f64; 3]; 2],
    /// J and its parts, from the Φ samples.
    #[serde(rename = "J")]
    pub j: CostFigures,
    /// Per-sample trajectory.
    pub samples: Vec<SampleRow>,
}

/// Reductions of the optimised gait against the baseline, percent.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reductions {
    /// Of the torque part of J.
    pub torque_part: f64,
    /// Of τ RMS over the swing.
    pub tau_rms: f64,
    /// Of peak |τ|.
    pub tau_peak: f64,
    /// Of J itself.
    #[serde(rename = "J")]
    pub j: f64,
}

/// What the solver did.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverFigures {
    /// Method name.
    pub name: String,
    /// Seed.
    pub seed: u64,
    /// Cost evaluations in all.
    pub evaluations: usize,
    /// Of which CMA-ES.
    pub cmaes_evaluations: usize,
    /// CMA-ES runs.
    pub runs: usize,
    /// Wall-clock seconds (informative).
    pub wall_s: f64,
}

/// The full report (JSON via serde).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Report {
    /// [`REPORT_FORMAT`].
    pub format: String,
    /// The problem, complete.
    pub problem: ProblemSpec,
    /// P, 19×2, SI units, the paper's row order.
    pub control_points: ControlPoints<f64>,
    /// J and its parts at P.
    #[serde(rename = "J")]
    pub j: CostFigures,
    /// τ RMS over the swing, N·m.
    #[serde(rename = "tau_rms_Nm")]
    pub tau_rms_nm: f64,
    /// Peak |τ| over the swing, N·m.
    #[serde(rename = "tau_peak_Nm")]
    pub tau_peak_nm: f64,
    /// The human-data baseline, if one was built.
    pub baseline: Option<BaselineFigures>,
    /// Why `baseline` is null, when it is (absent from older reports).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub baseline_note: Option<String>,
    /// Reductions against the baseline.
    pub reduction_pct: Option<Reductions>,
    /// Solver figures.
    pub solver: SolverFigures,
    /// Per-sample trajectory of the optimised step.
    pub samples: Vec<SampleRow>,
}

/// What is wrong with a report.
#[derive(Debug)]
pub enum ReportError {
    /// Not valid JSON for a report (serde's message names field and place).
    Json(serde_json::Error),
    /// A field holds a value the problem cannot take.
    Field {
        /// Dotted path of the field.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// P is infeasible or cannot be evaluated (names the entry or sample).
    Infeasible(String),
    /// The step could not be sampled for the trajectory.
    Gait(GaitError),
}

impl std::fmt::Display for ReportError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Json(e) => write!(f, "not a valid report: {e}"),
            Self::Field { field, message } => write!(f, "{field}: {message}"),
            Self::Infeasible(m) => write!(f, "control_points: {m}"),
            Self::Gait(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ReportError {}

fn case_name(case: PaperCase) -> &'static str {
    match case {
        PaperCase::Walk => "walk",
        PaperCase::StairUp => "stair_up",
    }
}

/// Samples an optimised step: Φ (IK at every k), Θ, τ (k ≥ 2), p5.
pub fn step_samples(
    problem: &PaperProblem<f64>,
    p: &ControlPoints<f64>,
) -> Result<Vec<SampleRow>, ReportError> {
    let step = problem.step(p);
    let ik = step.ik(&problem.model);
    let mut rows: Vec<SampleRow> = Vec::new();
    evaluate_step::<f64, GaitError>(&problem.model, &step, problem.differences, |ev| {
        match ev {
            StepEvent::Sample(s) => {
                let sol = s.solve(&ik)?;
                rows.push(SampleRow {
                    t_s: s.t_s,
                    phi_rad: sol.phi,
                    theta_rad: sol.theta,
                    tau_nm: None,
                    p5_m: s.p5,
                    c_k: 1.0,
                });
            }
            StepEvent::Dynamics(d) => {
                if let Some(r) = rows.get_mut(d.gait.k) {
                    r.tau_nm = Some(d.torque);
                }
            }
        }
        Ok(())
    })
    .map_err(ReportError::Gait)?;
    set_contact(&mut rows);
    Ok(rows)
}

fn pct_reduction(base: f64, new: f64) -> f64 {
    if base != 0.0 {
        100.0 * (base - new) / base
    } else {
        0.0
    }
}

impl Report {
    /// Builds the report of an optimisation, with its baseline if given.
    pub fn new(result: &OptimizeResult, baseline: Option<&Baseline>) -> Result<Self, ReportError> {
        let problem = PaperProblem::<f64>::paper(result.case);
        Self::for_problem(case_name(result.case), &problem, result, baseline)
    }

    /// Builds the report of an optimisation of `problem` (any geometry, step
    /// time or model; `label` names the case in `problem.case`), with its
    /// baseline if given (which must have been built for `problem`).
    pub fn for_problem(
        label: &str,
        problem: &PaperProblem<f64>,
        result: &OptimizeResult,
        baseline: Option<&Baseline>,
    ) -> Result<Self, ReportError> {
        let problem = *problem;
        let samples = step_samples(&problem, &result.control_points)?;
        let j = CostFigures::from(result.cost);
        let baseline_figures = match baseline {
            Some(b) => {
                let cost = crate::phi_cost::cost_from_phi(&problem, &b.phi)
                    .map_err(|e| ReportError::Infeasible(format!("baseline: {e}")))?;
                let dt = problem.sampling.dt_s;
                let mut rows: Vec<SampleRow> = phi_samples(&problem, &b.phi)
                    .iter()
                    .zip(&b.phi)
                    .enumerate()
                    .map(|(k, (s, phi))| SampleRow {
                        t_s: k as f64 * dt,
                        phi_rad: *phi,
                        theta_rad: theta_from_phi(phi),
                        tau_nm: s.torque,
                        p5_m: s.p5,
                        c_k: 1.0,
                    })
                    .collect();
                set_contact(&mut rows);
                Some(BaselineFigures {
                    source: b.source,
                    source_detail: b.source_detail.clone(),
                    amplitude_scale: b.amplitude_scale,
                    end_correction_rad: b.end_correction_rad,
                    j: cost.into(),
                    samples: rows,
                })
            }
            None => None,
        };
        let reduction_pct = baseline_figures.as_ref().map(|b| Reductions {
            torque_part: pct_reduction(b.j.torque, j.torque),
            tau_rms: pct_reduction(b.j.tau_rms_nm, j.tau_rms_nm),
            tau_peak: pct_reduction(b.j.tau_peak_nm, j.tau_peak_nm),
            j: pct_reduction(b.j.j, j.j),
        });
        Ok(Self {
            format: REPORT_FORMAT.into(),
            problem: ProblemSpec::labelled(label, &problem),
            control_points: result.control_points,
            j,
            tau_rms_nm: j.tau_rms_nm,
            tau_peak_nm: j.tau_peak_nm,
            baseline: baseline_figures,
            baseline_note: None,
            reduction_pct,
            solver: SolverFigures {
                name: "IPOP-CMA-ES (cmaes crate) with successive-halving starts + compass-search polish".into(),
                seed: result.seed,
                evaluations: result.evaluations,
                cmaes_evaluations: result.cmaes_evaluations,
                runs: result.runs,
                wall_s: result.wall_s,
            },
            samples,
        })
    }

    /// Pretty JSON.
    pub fn to_json(&self) -> Result<String, ReportError> {
        serde_json::to_string_pretty(self).map_err(ReportError::Json)
    }

    /// Parses a report (errors name the field and position).
    pub fn from_json(text: &str) -> Result<Self, ReportError> {
        let r: Self = serde_json::from_str(text).map_err(ReportError::Json)?;
        if r.format != REPORT_FORMAT {
            return Err(ReportError::Field {
                field: "format".into(),
                message: format!("expected {REPORT_FORMAT:?}, got {:?}", r.format),
            });
        }
        Ok(r)
    }

    /// Rebuilds the problem from `problem` and evaluates J at
    /// `control_points` (feasibility checked), ignoring every stored figure.
    pub fn recompute_cost(&self) -> Result<Cost<f64>, ReportError> {
        let problem = self.problem.problem()?;
        problem
            .cost(&self.control_points)
            .map_err(|e| ReportError::Infeasible(e.to_string()))
    }
}

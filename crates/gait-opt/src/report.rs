//! The serialisable result of one optimisation: the problem's every
//! paper-mode definition (so J can be recomputed from the JSON alone), the
//! control points, J and its parts, the human-data baseline, reductions,
//! solver figures and the per-sample trajectory.

use gait_core::foot::StanceFoot;
use gait_core::gait::{
    CONTACT_THRESHOLD_M, ControlPoints, Differences, GaitError, Sampling, StanceAnkleProfile,
    StepEvent, contact_weight, evaluate_step,
};
use gait_core::ik::{IkOptions, KneeRange};
use gait_core::kinematics::theta_from_phi;
use gait_core::model::{BodyModel, JointLimits, Link};
use gait_core::problem::{
    Cost, EndPosture, JointMotionLimit, JointRangeLimit, PaperCase, PaperProblem, StepCase,
};
use serde::{Deserialize, Serialize};

use crate::baseline::{Baseline, Source};
use crate::phi_cost::phi_samples;
use crate::solver::OptimizeResult;

/// Format tag written into every report.
pub const REPORT_FORMAT: &str = "exogait-report/1";

/// The stance-ankle profile φ1(t) = a + (b − a)/(1 + e^(−k (t − t_c))).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StanceSpec {
    /// a, rad.
    pub a_rad: f64,
    /// b, rad.
    pub b_rad: f64,
    /// k, 1/s.
    pub k_per_s: f64,
    /// t_c, s.
    pub t_c_s: f64,
}

/// One link of Table III.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// l_i, m.
    pub length_m: f64,
    /// d_i (proximal joint to centre of mass), m.
    pub com_m: f64,
    /// m_i, kg.
    pub mass_kg: f64,
    /// I_i about the centre of mass, kg·m².
    pub inertia_kgm2: f64,
}

/// Every paper-mode definition of the problem.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProblemSpec {
    /// "walk" or "stair_up".
    pub case: String,
    /// Swing-ankle start (x, y), m (stance ankle at the origin).
    pub start_m: [f64; 2],
    /// Swing-ankle landing (x, y), m.
    pub landing_m: [f64; 2],
    /// Step time ts, s.
    pub step_time_s: f64,
    /// Assumed stance-ankle profile.
    pub stance_ankle: StanceSpec,
    /// r2 at the start (P[0][1]).
    pub r2_start: f64,
    /// φ3 at the start (P[5][1]), rad.
    pub phi3_start_rad: f64,
    /// (r2, φ3 rad) fixed at the landing (periodic steps); absent when free.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_posture: Option<[f64; 2]>,
    /// Whether the step starts and ends at rest (periodic device tables).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub rest_at_ends: bool,
    /// The stance foot's toe rocker (toe m, ankle height m, heel-off rad);
    /// absent for the paper's flat foot.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub foot: Option<[f64; 3]>,
    /// The IK's stance-knee cap, rad; absent for the paper's 45°.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stance_knee_max_rad: Option<f64>,
    /// Whether r2 maps onto the human range alone (`KneeRange::Human`);
    /// absent for the paper's reach-narrowed range.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub knee_range_human: bool,
    /// Δt, s.
    pub dt_s: f64,
    /// N (samples t_k = kΔt, k = 0…N).
    pub intervals: usize,
    /// Points of the uniform u grid (linear interpolation in t).
    pub grid: usize,
    /// v_p, N²·m² per (m/s).
    pub velocity_weight: f64,
    /// (speed rad/s, its weight, acceleration rad/s², its weight) of the
    /// joint-motion term; absent in paper mode.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_motion_limit: Option<[f64; 4]>,
    /// Soft joint-range limit (margin rad, weight) inside the model's
    /// Table I stops; absent in paper mode.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint_range_limit: Option<[f64; 2]>,
    /// τ² counted at every sample (c_k = 1 throughout; device tables).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub count_every_sample: bool,
    /// "backward" (eq. (ee2)) or "central".
    pub differences: String,
    /// c_k = 0 within this distance of p5(0) or p5(N), m.
    pub contact_threshold_m: f64,
    /// Eq. (cons) lower bound B, 19×2, SI units (derived from the case).
    pub lower_bound: ControlPoints<f64>,
    /// Eq. (cons) upper bound U.
    pub upper_bound: ControlPoints<f64>,
    /// Rows of P whose time column is non-decreasing: [first, end) per curve.
    pub time_ordered_rows: [[usize; 2]; 3],
    /// Links 1–5 (stance shank, stance thigh, torso, swing thigh, swing shank).
    pub links: [LinkSpec; 5],
    /// The J formula, for a reader.
    pub cost_definition: String,
}

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

/// Cost definition text stored in every report.
const COST_TEXT: &str = "J = (1/(N-1)) sum_{k=2..N} c_k tau_k^2 + v_p max_{k=1..N} |p5(k)-p5(k-1)|/dt; \
    tau = T_theta1 (stance-ankle joint torque) from inverse dynamics with backward differences \
    dPhi(k) = (Phi(k)-Phi(k-1))/dt, ddPhi(k) = (dPhi(k)-dPhi(k-1))/dt; c_k = 0 if p5(k) is within \
    contact_threshold_m of p5(0) or p5(N), else 1; curve values at t by linear interpolation in t on \
    a uniform u grid of `grid` points; p5 = path(z(t)); IK of the paper (docs/model.md)";

impl ProblemSpec {
    /// The specification of a problem.
    pub fn of(case: PaperCase, p: &PaperProblem<f64>) -> Self {
        Self::labelled(case_name(case), p)
    }

    /// The specification of any problem of the paper's form, `label` naming
    /// its case (e.g. "stair_down").
    pub fn labelled(label: &str, p: &PaperProblem<f64>) -> Self {
        let (lo, hi) = p.bounds();
        let links = p.model.links().map(|l| LinkSpec {
            length_m: l.length_m,
            com_m: l.com_m,
            mass_kg: l.mass_kg,
            inertia_kgm2: l.inertia_kgm2,
        });
        let c = &p.case;
        Self {
            case: label.into(),
            start_m: c.start_m,
            landing_m: c.landing_m,
            step_time_s: c.step_time_s,
            stance_ankle: StanceSpec {
                a_rad: c.stance.a_rad,
                b_rad: c.stance.b_rad,
                k_per_s: c.stance.k_per_s,
                t_c_s: c.stance.t_c_s,
            },
            r2_start: c.r2_start,
            phi3_start_rad: c.phi3_start_rad,
            end_posture: c.end_posture.map(|e| [e.r2, e.phi3_rad]),
            rest_at_ends: c.rest_at_ends,
            foot: c.foot.map(|f| [f.toe_m, f.ankle_height_m, f.heel_off_rad]),
            stance_knee_max_rad: (c.ik != IkOptions::paper()).then_some(c.ik.stance_knee_max_rad),
            knee_range_human: c.ik.knee_range == KneeRange::Human,
            dt_s: p.sampling.dt_s,
            intervals: p.sampling.intervals,
            grid: p.sampling.grid,
            velocity_weight: p.velocity_weight,
            joint_range_limit: p.joint_range_limit.map(|r| [r.margin_rad, r.weight]),
            joint_motion_limit: p.joint_motion_limit.map(|l| {
                [
                    l.speed_rad_s,
                    l.speed_weight,
                    l.accel_rad_s2,
                    l.accel_weight,
                ]
            }),
            count_every_sample: p.count_every_sample,
            differences: match p.differences {
                Differences::Backward => "backward".into(),
                Differences::Central => "central".into(),
            },
            contact_threshold_m: CONTACT_THRESHOLD_M,
            lower_bound: lo,
            upper_bound: hi,
            time_ordered_rows: [[0, 5], [5, 10], [15, 19]],
            links,
            cost_definition: COST_TEXT.into(),
        }
    }

    /// Rebuilds the problem, checking every field against what gait-core
    /// can evaluate (errors name the field).
    pub fn problem(&self) -> Result<PaperProblem<f64>, ReportError> {
        let bad = |field: &str, message: String| ReportError::Field {
            field: format!("problem.{field}"),
            message,
        };
        let differences = match self.differences.as_str() {
            "backward" => Differences::Backward,
            "central" => Differences::Central,
            other => {
                return Err(bad(
                    "differences",
                    format!("expected \"backward\" or \"central\", got {other:?}"),
                ));
            }
        };
        if self.contact_threshold_m != CONTACT_THRESHOLD_M {
            return Err(bad(
                "contact_threshold_m",
                format!(
                    "gait-core's threshold is {CONTACT_THRESHOLD_M} m, got {}",
                    self.contact_threshold_m
                ),
            ));
        }
        if !(self.dt_s.is_finite() && self.dt_s > 0.0) {
            return Err(bad("dt_s", format!("must be positive, got {}", self.dt_s)));
        }
        if let Some(f) = self.foot {
            let [toe, height, heel_off] = f;
            let sane = toe.is_finite()
                && toe > 0.0
                && height.is_finite()
                && height >= 0.0
                && heel_off.is_finite()
                && heel_off.abs() < std::f64::consts::FRAC_PI_2;
            if !sane {
                return Err(bad(
                    "foot",
                    format!(
                        "expected [toe > 0 m, ankle height >= 0 m, heel-off in (-pi/2, pi/2) rad], got {f:?}"
                    ),
                ));
            }
        }
        let cap_ok = |cap: f64| cap.is_finite() && cap > 0.0 && cap <= std::f64::consts::FRAC_PI_2;
        if let Some(cap) = self.stance_knee_max_rad.filter(|&c| !cap_ok(c)) {
            return Err(bad(
                "stance_knee_max_rad",
                format!("must be in (0, pi/2], got {cap}"),
            ));
        }
        let range_ok = |[margin, weight]: [f64; 2]| {
            margin.is_finite() && margin >= 0.0 && weight.is_finite() && weight >= 0.0
        };
        if let Some([margin, weight]) = self.joint_range_limit.filter(|&r| !range_ok(r)) {
            return Err(bad(
                "joint_range_limit",
                format!(
                    "expected [margin >= 0 rad, weight >= 0], got {:?}",
                    [margin, weight]
                ),
            ));
        }
        if self.intervals < 2 || self.intervals + 1 > gait_core::problem::MAX_SAMPLES {
            return Err(bad(
                "intervals",
                format!(
                    "must be in 2..{}, got {}",
                    gait_core::problem::MAX_SAMPLES - 1,
                    self.intervals
                ),
            ));
        }
        if self.grid < 2 {
            return Err(bad(
                "grid",
                format!("must be at least 2, got {}", self.grid),
            ));
        }
        let links = self.links.map(|l| Link {
            length_m: l.length_m,
            com_m: l.com_m,
            mass_kg: l.mass_kg,
            inertia_kgm2: l.inertia_kgm2,
        });
        let model = BodyModel::new(links, JointLimits::paper_table_i())
            .map_err(|e| bad("links", format!("{e:?}")))?;
        let s = &self.stance_ankle;
        let case = StepCase {
            start_m: self.start_m,
            landing_m: self.landing_m,
            step_time_s: self.step_time_s,
            stance: StanceAnkleProfile {
                a_rad: s.a_rad,
                b_rad: s.b_rad,
                k_per_s: s.k_per_s,
                t_c_s: s.t_c_s,
            },
            r2_start: self.r2_start,
            phi3_start_rad: self.phi3_start_rad,
            end_posture: self
                .end_posture
                .map(|[r2, phi3_rad]| EndPosture { r2, phi3_rad }),
            rest_at_ends: self.rest_at_ends,
            foot: self
                .foot
                .map(|[toe_m, ankle_height_m, heel_off_rad]| StanceFoot {
                    toe_m,
                    ankle_height_m,
                    heel_off_rad,
                }),
            ik: IkOptions {
                stance_knee_max_rad: self
                    .stance_knee_max_rad
                    .unwrap_or(std::f64::consts::FRAC_PI_4),
                knee_range: if self.knee_range_human {
                    KneeRange::Human
                } else {
                    KneeRange::Reach
                },
            },
        };
        let problem = PaperProblem {
            case,
            model,
            sampling: Sampling {
                dt_s: self.dt_s,
                intervals: self.intervals,
                grid: self.grid,
            },
            velocity_weight: self.velocity_weight,
            differences,
            joint_motion_limit: self.joint_motion_limit.map(
                |[speed_rad_s, speed_weight, accel_rad_s2, accel_weight]| JointMotionLimit {
                    speed_rad_s,
                    speed_weight,
                    accel_rad_s2,
                    accel_weight,
                },
            ),
            joint_range_limit: self
                .joint_range_limit
                .map(|[margin_rad, weight]| JointRangeLimit {
                    limits: *model.limits(),
                    margin_rad,
                    weight,
                }),
            count_every_sample: self.count_every_sample,
        };
        let (lo, hi) = problem.bounds();
        for (name, json, derived) in [
            ("lower_bound", &self.lower_bound, &lo),
            ("upper_bound", &self.upper_bound, &hi),
        ] {
            for (r, (a, b)) in json.iter().zip(derived).enumerate() {
                for (c, (x, y)) in a.iter().zip(b).enumerate() {
                    if (x - y).abs() > 1e-12 * (1.0 + y.abs()) {
                        return Err(bad(
                            &format!("{name}[{r}][{c}]"),
                            format!("{x} disagrees with eq. (cons) for this case ({y})"),
                        ));
                    }
                }
            }
        }
        if self.time_ordered_rows != [[0, 5], [5, 10], [15, 19]] {
            return Err(bad(
                "time_ordered_rows",
                "must be [[0,5],[5,10],[15,19]]".into(),
            ));
        }
        Ok(problem)
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

//! The problem as a report stores it ([`ProblemSpec`]): every paper-mode
//! definition in plain numbers and names, written from a [`PaperProblem`]
//! and read back through gait-core's checked constructors, whose errors are
//! given the field's name. The conversion only: what a valid problem is,
//! gait-core decides.

use gait_core::foot::StanceFoot;
use gait_core::gait::{
    CONTACT_THRESHOLD_M, ControlPoints, Differences, Sampling, SamplingError, StanceAnkleProfile,
};
use gait_core::ik::{IkOptions, KneeRange};
use gait_core::model::{BodyModel, JointLimits, Link};
use gait_core::problem::{
    EndPosture, JointMotionLimit, JointRangeLimit, PaperCase, PaperProblem, StepCase,
    TIME_ORDERED_ROWS,
};
use serde::{Deserialize, Serialize};

use super::{ReportError, case_name};

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
            differences: p.differences.name().into(),
            contact_threshold_m: CONTACT_THRESHOLD_M,
            lower_bound: lo,
            upper_bound: hi,
            time_ordered_rows: TIME_ORDERED_ROWS,
            links,
            cost_definition: COST_TEXT.into(),
        }
    }

    /// Rebuilds the problem through gait-core's checked constructors; their
    /// errors are given the name of the field they come from.
    pub fn problem(&self) -> Result<PaperProblem<f64>, ReportError> {
        let bad = |field: &str, message: String| ReportError::Field {
            field: format!("problem.{field}"),
            message,
        };
        let differences = Differences::from_name(&self.differences).ok_or_else(|| {
            bad(
                "differences",
                format!(
                    "expected {:?} or {:?}, got {:?}",
                    Differences::Backward.name(),
                    Differences::Central.name(),
                    self.differences
                ),
            )
        })?;
        if self.contact_threshold_m != CONTACT_THRESHOLD_M {
            return Err(bad(
                "contact_threshold_m",
                format!(
                    "gait-core's threshold is {CONTACT_THRESHOLD_M} m, got {}",
                    self.contact_threshold_m
                ),
            ));
        }
        let sampling =
            Sampling::new(self.dt_s, self.intervals, self.grid).map_err(|e| match e {
                SamplingError::Period => bad("dt_s", format!("{e}, got {}", self.dt_s)),
                SamplingError::Intervals => {
                    bad("intervals", format!("{e}, got {}", self.intervals))
                }
                SamplingError::Grid => bad("grid", format!("{e}, got {}", self.grid)),
            })?;
        let foot = self
            .foot
            .map(|f @ [toe_m, ankle_height_m, heel_off_rad]| {
                StanceFoot::new(toe_m, ankle_height_m, heel_off_rad).map_err(|e| {
                    bad(
                        "foot",
                        format!("{e}; got {f:?} as [toe m, ankle height m, heel-off rad]"),
                    )
                })
            })
            .transpose()?;
        let knee_range = if self.knee_range_human {
            KneeRange::Human
        } else {
            KneeRange::Reach
        };
        let cap = self
            .stance_knee_max_rad
            .unwrap_or(IkOptions::<f64>::paper().stance_knee_max_rad);
        let ik = IkOptions::new(cap, knee_range)
            .map_err(|e| bad("stance_knee_max_rad", format!("{e}, got {cap}")))?;
        let links = self.links.map(|l| Link {
            length_m: l.length_m,
            com_m: l.com_m,
            mass_kg: l.mass_kg,
            inertia_kgm2: l.inertia_kgm2,
        });
        let model = BodyModel::new(links, JointLimits::paper_table_i())
            .map_err(|e| bad("links", e.to_string()))?;
        let joint_range_limit = self
            .joint_range_limit
            .map(|r @ [margin_rad, weight]| {
                JointRangeLimit::new(*model.limits(), margin_rad, weight).map_err(|e| {
                    bad(
                        "joint_range_limit",
                        format!("{e}; got {r:?} as [margin rad, weight]"),
                    )
                })
            })
            .transpose()?;
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
            foot,
            ik,
        };
        let problem = PaperProblem {
            case,
            model,
            sampling,
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
            joint_range_limit,
            count_every_sample: self.count_every_sample,
        };
        problem
            .check_bounds_copy(&self.lower_bound, &self.upper_bound)
            .map_err(|m| {
                let name = if m.upper {
                    "upper_bound"
                } else {
                    "lower_bound"
                };
                bad(
                    &format!("{name}[{}][{}]", m.row, m.col),
                    format!(
                        "{} disagrees with eq. (cons) for this case ({})",
                        m.stored, m.derived
                    ),
                )
            })?;
        if self.time_ordered_rows != TIME_ORDERED_ROWS {
            return Err(bad(
                "time_ordered_rows",
                format!("must be {TIME_ORDERED_ROWS:?}"),
            ));
        }
        Ok(problem)
    }
}

//! Clinical mode: gait tables for the device we ship, optimised for what the
//! pilot feels — the crutch load — within what the drives and the
//! supervisor allow (paper mode, in [`crate::solver`], stays the paper's
//! problem and is the record).
//!
//! - The step is a [`ClinicalStep`] (gait-core): double support first, the
//!   stance shank a decision variable, smooth curves, the IK's continuous
//!   knee range, periodic.
//! - The cost is the predicted **balance part of the crutch impulse**,
//!   Σ |τ_pilot| Δt / lever over the step and the weight transfer after it,
//!   from gait-core's [`playback`] (the same sharing of the load between
//!   the feet and the same passive ankle spring the controller's
//!   feed-forward and the simulator use; the pilot's constant lean on the
//!   crutches is not in it: no gait changes it).
//! - Soft limits (quadratic penalties, heavy enough that the optimum sits
//!   inside them): every hip and knee torque within a share of what the
//!   drive can give at that speed; the drives' I²t over two steps (each
//!   joint is a stance joint one step and a swing joint the next) below the
//!   continuous rating; joint speed and acceleration; joint range inside
//!   Table I; the swing foot's clearance over the floor or the nosing; the
//!   pilot's and the stance ankle's peak no higher than the human gait's;
//!   enough weight on the stance foot at the start for the readiness gate.
//!
//! Evaluations are deterministic; the search ([`optimize_clinical`]) is
//! seeded and budgeted by evaluation count, so a table regenerates byte for
//! byte. `docs/optimiser.md` ("Clinical mode") gives each choice and its
//! reason.

use std::cell::RefCell;

use cmaes::{CMAESOptions, DVector};
use exogait_device::DeviceConfig;
use exogait_device::drive::DriveSpec;
use gait_core::BodyModel;
use gait_core::clinical::{
    ClinicalError, ClinicalStep, HEEL_M, StartPosture, SwingPath, ground_level,
    riser_behind_stance_x,
};
use gait_core::foot::StanceFoot;
use gait_core::ik::{IkOptions, KneeRange};
use gait_core::kinematics::{Phi, anatomical_angles, theta_from_phi};
use gait_core::model::{GRAVITY_M_S2, LINKS};
use gait_core::playback::{self, PlaybackError, PlaybackSample};
use gait_core::tables::GaitKind;

use crate::compass::compass_search;

/// Sample period of the tables, s (the paper's Δt).
pub const TABLE_PERIOD_S: f64 = 0.01;

/// What the device and the pilot allow, for one gait.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClinicalLimits {
    /// The hip and knee drive.
    pub drive: DriveSpec,
    /// Share of the torque the drive can give (at the joint's speed) that
    /// the table's feed-forward may use: the rest is for the position loop
    /// (tracking, model error, the landing).
    pub torque_share: f64,
    /// Share of the continuous current² the two-step mean of I² may use.
    pub i2t_share: f64,
    /// Largest hip and knee speed, rad/s.
    pub joint_speed_rad_s: f64,
    /// Largest hip and knee acceleration, rad/s².
    pub joint_accel_rad_s2: f64,
    /// The supervisor's envelope, (lowest, highest) anatomical angle, rad:
    /// hip, knee, and the stance ankle's dorsiflexion.
    pub envelope_rad: [(f64, f64); 3],
    /// How far inside the envelope the table stays, rad.
    pub range_margin_rad: f64,
    /// The exoskeleton ankle's passive spring, N·m/rad.
    pub ankle_spring_nm_per_rad: f64,
    /// Weight transfer after the landing (both feet down, the table's last
    /// posture held), s.
    pub transfer_s: f64,
    /// Largest share of the body's weight the trailing foot may carry at
    /// the start (the stance foot must carry the readiness gate's load and
    /// the crutches some too).
    pub start_trailing_share: f64,
    /// Swing-foot clearance over the floor (level) or over the nosing it
    /// crosses (stairs), m: (lowest, highest).
    pub clearance_m: (f64, f64),
}

/// Caps from the human-data gait at the same geometry and timing: the
/// table may not ask more of the pilot or of the stance ankle at any
/// instant than replayed human gait does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HumanCaps {
    /// Peak |pilot torque|, N·m.
    pub pilot_peak_nm: f64,
    /// Peak |stance-ankle torque| (T_θ1 after sharing), N·m.
    pub ankle_peak_nm: f64,
}

/// One gait's clinical problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClinicalCase {
    /// Which gait.
    pub gait: GaitKind,
    /// Front ankle relative to the back one in double support, m.
    pub spacing_m: [f64; 2],
    /// Step time, s.
    pub step_time_s: f64,
    /// Pilot plus exoskeleton.
    pub model: BodyModel<f64>,
    /// The feet's toe rocker.
    pub foot: StanceFoot<f64>,
    /// The IK's options (continuous human knee range).
    pub ik: IkOptions<f64>,
    /// The device's limits.
    pub limits: ClinicalLimits,
    /// The human gait's peaks (infinite where none is given).
    pub caps: HumanCaps,
    /// Lever that turns the pilot's torque into crutch force, m (the
    /// simulated pilot's; only scales the reported impulse).
    pub crutch_lever_m: f64,
}

/// The pilot's crutch lever used to report impulses in newton-seconds, m
/// (sim's `PilotConfig::default`; the optimum does not depend on it).
pub const CRUTCH_LEVER_M: f64 = 0.45;

impl ClinicalCase {
    /// The case of `gait` on `device`: walking 0.3 m steps in 2.24 s, stairs
    /// (tread 0.275 m, rise 0.0935 m, the paper's) up or down in 2.28 s —
    /// the paper's geometry and timing.
    pub fn for_gait(gait: GaitKind, device: &DeviceConfig) -> Self {
        let (spacing_m, step_time_s, knee_cap_deg) = match gait {
            GaitKind::Walk => ([0.3, 0.0], 2.24, 60.0),
            GaitKind::StairUp => ([0.275, 0.0935], 2.28, 70.0),
            GaitKind::StairDown => ([0.275, -0.0935], 2.28, 90.0),
        };
        let model = device.body;
        let drive = device.drives[1];
        let seq = device.controller.sequencer;
        Self {
            gait,
            spacing_m,
            step_time_s,
            model,
            foot: StanceFoot::for_model(&model),
            ik: IkOptions {
                stance_knee_max_rad: f64::to_radians(knee_cap_deg),
                knee_range: KneeRange::Human,
            },
            limits: ClinicalLimits {
                drive,
                torque_share: 0.75,
                i2t_share: 0.85,
                joint_speed_rad_s: 1.8,
                joint_accel_rad_s2: 20.0,
                envelope_rad: {
                    let sv = &device.supervisor;
                    let r = |a: gait_control::supervisor::AngleRange| {
                        (f64::from(a.min_rad), f64::from(a.max_rad))
                    };
                    [
                        r(sv.joint_range[0]),
                        r(sv.joint_range[1]),
                        r(sv.ankle_range[0]),
                    ]
                },
                range_margin_rad: 5f64.to_radians(),
                ankle_spring_nm_per_rad: device.ankle_spring_nm_per_rad,
                transfer_s: f64::from(seq.transfer_s),
                // The stance foot carries at least a fifth of the body at
                // the start: the step begins from a stable double support.
                start_trailing_share: 0.8,
                // The clinical band is 3–8 cm; the table aims inside it so
                // that tracking lag does not take the foot out.
                clearance_m: (0.04, 0.07),
            },
            caps: HumanCaps {
                pilot_peak_nm: f64::INFINITY,
                ankle_peak_nm: f64::INFINITY,
            },
            crutch_lever_m: CRUTCH_LEVER_M,
        }
    }
}

impl ClinicalCase {
    /// The case on another body model: its mass properties, and its joint
    /// limits as the envelope (the supervisor's construction from them).
    pub fn with_model(mut self, model: BodyModel<f64>) -> Self {
        let m32: BodyModel<f32> = model.cast();
        let sv = gait_control::supervisor::SupervisorConfig::default_for(m32.limits());
        let r =
            |a: gait_control::supervisor::AngleRange| (f64::from(a.min_rad), f64::from(a.max_rad));
        self.limits.envelope_rad = [
            r(sv.joint_range[0]),
            r(sv.joint_range[1]),
            r(sv.ankle_range[0]),
        ];
        self.foot = StanceFoot::for_model(&model);
        self.model = model;
        self
    }
}

/// What a table asks, from gait-core's playback of its Φ samples.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// The cost: predicted balance impulse plus penalties, N·s.
    pub j: f64,
    /// Predicted balance part of the crutch impulse over the step and the
    /// transfer (Σ |τ_pilot| Δt / lever), N·s.
    pub balance_ns: f64,
    /// Sum of the penalties, N·s.
    pub penalty: f64,
    /// Peak |pilot torque|, N·m.
    pub pilot_peak_nm: f64,
    /// Peak |stance-ankle torque| after sharing, N·m.
    pub ankle_peak_nm: f64,
    /// Peak |torque| of the stance knee, stance hip, swing hip, swing knee
    /// (after sharing), N·m.
    pub joint_peak_nm: [f64; 4],
    /// Largest share of the drive's available torque any hip or knee uses.
    pub drive_use: f64,
    /// Peak |speed| of those joints, rad/s.
    pub joint_speed_peak_rad_s: [f64; 4],
    /// Peak |acceleration| of those joints, rad/s².
    pub joint_accel_peak_rad_s2: f64,
    /// Two-step mean of I² over the continuous current², for the knee and
    /// the hip (1: the continuous rating).
    pub i2t_ratio: [f64; 2],
    /// Swing-foot clearance (over the floor, or over the nosing), m.
    pub clearance_m: f64,
    /// Lowest sole height above the ground under it while the foot is in
    /// the air (negative: it would touch), m.
    pub sole_margin_m: f64,
    /// Share of the body's weight the trailing foot carries at the start.
    pub start_trailing_share: f64,
    /// Time the swing foot is planned on the ground at the start, s.
    pub double_support_s: f64,
}

/// Why a step could not be evaluated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EvalError {
    /// The step could not be sampled.
    Step(ClinicalError),
    /// The samples could not be played.
    Playback(PlaybackError),
}

impl From<ClinicalError> for EvalError {
    fn from(e: ClinicalError) -> Self {
        Self::Step(e)
    }
}

impl From<PlaybackError> for EvalError {
    fn from(e: PlaybackError) -> Self {
        Self::Playback(e)
    }
}

impl std::fmt::Display for EvalError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Step(e) => write!(f, "step: {e:?}"),
            Self::Playback(e) => write!(f, "playback: {e:?}"),
        }
    }
}

impl std::error::Error for EvalError {}

/// Φ at every table sample of `step`.
pub fn step_phi(case: &ClinicalCase, step: &ClinicalStep<f64>) -> Result<Vec<Phi<f64>>, EvalError> {
    let mut out = Vec::with_capacity(256);
    step.for_each_sample::<EvalError>(&case.model, TABLE_PERIOD_S, |_, phi| {
        out.push(*phi);
        Ok(())
    })?;
    Ok(out)
}

/// Weight of a squared excess, N·s per unit².
const W_TORQUE: f64 = 50.0; // per (share of the drive over the allowed)² per sample
const W_I2T: f64 = 2.0e4; // per (ratio over the allowed)²
const W_SPEED: f64 = 200.0; // per (rad/s)² per sample
const W_ACCEL: f64 = 0.5; // per (rad/s²)² per sample
const W_RANGE: f64 = 2.0e4; // per rad² per sample
const W_CLEARANCE: f64 = 1.0e6; // per m²
const W_PEAK: f64 = 0.5; // per (N·m)²
const W_START: f64 = 5.0e3; // per (share)²

/// Plays Φ samples (10 ms apart) of a step of `case` and scores them (see
/// the module documentation). Works for any table of the case's geometry:
/// clinical optima, flash tables, the human-data gait.
pub fn evaluate_phi(case: &ClinicalCase, phi: &[Phi<f64>]) -> Result<Evaluation, EvalError> {
    let l = &case.limits;
    let dt = TABLE_PERIOD_S;
    let weight = case.model.total_mass_kg() * GRAVITY_M_S2;
    let drive = &l.drive;
    let per_amp = f64::from(drive.joint_torque_per_amp());
    let nominal_sq = f64::from(drive.motor.nominal_current_a).powi(2);
    let mut samples: Vec<PlaybackSample<f64>> = Vec::with_capacity(phi.len());
    playback::for_each_sample::<f64, EvalError>(
        &case.model,
        &case.foot,
        l.ankle_spring_nm_per_rad,
        phi.len(),
        dt,
        |k| phi.get(k).copied(),
        |s| {
            samples.push(*s);
            Ok(())
        },
    )?;
    let (Some(first), Some(last)) = (samples.first(), samples.last()) else {
        return Err(EvalError::Playback(PlaybackError::TooShort));
    };
    let mut ev = Evaluation {
        j: 0.0,
        balance_ns: 0.0,
        penalty: 0.0,
        pilot_peak_nm: 0.0,
        ankle_peak_nm: 0.0,
        joint_peak_nm: [0.0; 4],
        drive_use: 0.0,
        joint_speed_peak_rad_s: [0.0; 4],
        joint_accel_peak_rad_s2: 0.0,
        i2t_ratio: [0.0; 2],
        clearance_m: f64::NAN,
        sole_margin_m: f64::INFINITY,
        start_trailing_share: first.reaction_n[1] / weight,
        double_support_s: 0.0,
    };
    let mut pen = 0.0;
    // I² sums per role (stance knee, stance hip, swing hip, swing knee).
    let mut i_sq = [0.0f64; 4];
    let zero = theta_from_phi(&[0.0; LINKS]);
    let range = role_ranges(&l.envelope_rad, l.range_margin_rad);
    let ankle_low = l.envelope_rad[2].0 + l.range_margin_rad;
    let (lo_clear, hi_clear) = l.clearance_m;
    let nosing = nosing_crossed(case);
    let mut crossing: Option<f64> = None;
    let mut peak_lift = f64::NEG_INFINITY;
    let mut lifted = false;
    let landing = last.swing_ankle_m;
    let mut approach_m = 0.0f64;
    for s in &samples {
        ev.balance_ns += s.pilot_nm.abs() * dt / case.crutch_lever_m;
        ev.pilot_peak_nm = ev.pilot_peak_nm.max(s.pilot_nm.abs());
        ev.ankle_peak_nm = ev.ankle_peak_nm.max(s.torques[0].abs());
        if s.other_share > 0.0 && !lifted {
            ev.double_support_s = s.t_s;
        } else {
            lifted = true;
        }
        let angles = anatomical_angles(&theta_from_phi(&s.phi));
        // The stance ankle reads φ1 (the stop once the heel is up): only
        // its plantarflexion side can leave the envelope.
        let below = (ankle_low - s.phi[0]).max(0.0);
        pen += W_RANGE * below * below;
        let th = theta_from_phi(&s.dphi);
        let thdd = theta_from_phi(&s.ddphi);
        for j in 0..4 {
            let i = j + 1;
            let rate = th[i] - zero[i];
            let accel = thdd[i] - zero[i];
            let torque = s.torques[i];
            let sign = if torque >= 0.0 { 1.0 } else { -1.0 };
            let available = f64::from(drive.available_torque_nm(rate as f32, sign as f32));
            let use_share = torque.abs() / available.max(1e-6);
            ev.drive_use = ev.drive_use.max(use_share);
            pen += W_TORQUE * sq_excess(use_share, l.torque_share) * 100.0;
            ev.joint_peak_nm[j] = ev.joint_peak_nm[j].max(torque.abs());
            ev.joint_speed_peak_rad_s[j] = ev.joint_speed_peak_rad_s[j].max(rate.abs());
            ev.joint_accel_peak_rad_s2 = ev.joint_accel_peak_rad_s2.max(accel.abs());
            pen += W_SPEED * sq_excess(rate.abs(), l.joint_speed_rad_s);
            pen += W_ACCEL * sq_excess(accel.abs(), l.joint_accel_rad_s2);
            let (lo, hi) = range[j];
            let q = angles[i];
            let out = (lo - q).max(q - hi).max(0.0);
            pen += W_RANGE * out * out;
            let current = torque / per_amp;
            i_sq[j] += current * current * dt;
        }
        // Clearance: the swing foot over what is under it.
        if s.other_share <= 0.0 {
            let [x, y] = s.swing_ankle_m;
            // The last centimetre down is straight down: a foot that is
            // still travelling forward that low touches down early.
            if y - landing[1] < LANDING_HEIGHT_M && s.k > samples.len() / 2 {
                approach_m = approach_m.max((x - landing[0]).abs());
            }
            let under = ground_under_sole(case, x);
            ev.sole_margin_m = ev.sole_margin_m.min(y - under);
            peak_lift = peak_lift.max(y - ground_level(case.spacing_m, &case.foot, x));
            if let Some((nx, level)) = nosing {
                if x - HEEL_M <= nx && nx <= x + case.foot.toe_m {
                    let c = y - level;
                    crossing = Some(crossing.map_or(c, |m: f64| m.min(c)));
                }
            }
        }
    }
    // After the landing: the transfer holds the last posture on both feet.
    let hold = last;
    ev.balance_ns += hold.pilot_nm.abs() * l.transfer_s / case.crutch_lever_m;
    for (j, acc) in i_sq.iter_mut().enumerate() {
        let current = hold.torques[j + 1] / per_amp;
        *acc += current * current * l.transfer_s;
    }
    let cycle = phi.len() as f64 * dt + l.transfer_s;
    // Each physical joint is a stance joint one step, a swing joint the next.
    let knee = 0.5 * (i_sq[0] + i_sq[3]) / cycle / nominal_sq;
    let hip = 0.5 * (i_sq[1] + i_sq[2]) / cycle / nominal_sq;
    ev.i2t_ratio = [knee, hip];
    pen += W_I2T * (sq_excess(knee, l.i2t_share) + sq_excess(hip, l.i2t_share));
    ev.clearance_m = match nosing {
        Some(_) => crossing.unwrap_or(f64::NEG_INFINITY),
        None => peak_lift,
    };
    let c = ev.clearance_m;
    let out_of_band = (lo_clear - c).max(c - hi_clear).max(0.0);
    pen += W_CLEARANCE * out_of_band * out_of_band;
    pen += W_CLEARANCE * sq_excess(-ev.sole_margin_m, -0.005);
    pen += W_CLEARANCE * sq_excess(approach_m, LANDING_TRAVEL_M);
    pen += W_PEAK * sq_excess(ev.pilot_peak_nm, case.caps.pilot_peak_nm);
    pen += W_PEAK * sq_excess(ev.ankle_peak_nm, case.caps.ankle_peak_nm);
    pen += W_START * sq_excess(ev.start_trailing_share, l.start_trailing_share);
    ev.penalty = pen;
    ev.j = ev.balance_ns + pen;
    Ok(ev)
}

/// Below this height above the landing point, m …
const LANDING_HEIGHT_M: f64 = 0.01;
/// … the swing ankle is at most this far from it horizontally, m.
const LANDING_TRAVEL_M: f64 = 0.01;

/// (x − limit)² where x exceeds limit, else 0.
fn sq_excess(x: f64, limit: f64) -> f64 {
    let e = x - limit;
    if e > 0.0 { e * e } else { 0.0 }
}

/// Allowed anatomical range of stance knee, stance hip, swing hip, swing
/// knee: the supervisor's envelope less the margin (a straight knee, at
/// the envelope's small hyperextension allowance, stays allowed).
fn role_ranges(envelope: &[(f64, f64); 3], margin: f64) -> [(f64, f64); 4] {
    let [hip, knee, _] = *envelope;
    let hip = (hip.0 + margin, hip.1 - margin);
    let knee = (knee.0.min(0.0), knee.1 - margin);
    [knee, hip, hip, knee]
}

/// The nosing the swing foot crosses on stairs, (x from the stance ankle,
/// its ground level), m: the next step's going up, the stance tread's edge
/// going down; `None` on level ground.
fn nosing_crossed(case: &ClinicalCase) -> Option<(f64, f64)> {
    let riser = riser_behind_stance_x(case.spacing_m, &case.foot)?;
    let [tread, rise] = case.spacing_m;
    let x = riser + tread;
    // The ground just before the edge (ascent: the stance tread's level
    // steps up to the next one at the edge; descent: the stance tread ends).
    let level = if rise > 0.0 { rise } else { 0.0 };
    Some((x, level))
}

/// The highest ground under a sole whose ankle is at `x`, ankle-level
/// convention, m.
fn ground_under_sole(case: &ClinicalCase, x: f64) -> f64 {
    let f = |x: f64| ground_level(case.spacing_m, &case.foot, x);
    let (a, b) = (x - HEEL_M, x + case.foot.toe_m);
    let mut m = f(a).max(f(b));
    if let Some(riser) = riser_behind_stance_x(case.spacing_m, &case.foot) {
        let tread = case.spacing_m[0];
        // Every edge between heel and toe.
        let mut e = riser + tread * ((a - riser) / tread).ceil();
        while e <= b {
            m = m.max(f(e)).max(f(e - 1e-9));
            e += tread;
        }
    }
    m
}

/// Free variables of the search.
pub const DIM: usize = 17;

/// Ranges of the start posture and of the curves' deviations.
const PHI1_START: (f64, f64) = (-0.25, 0.35);
const PHI3_START: (f64, f64) = (-0.25, 0.45);
const LIFT: (f64, f64) = (0.05, 0.6);
/// Largest deviation of an interior control value from the straight line
/// between the ends: φ1, φ3 (rad), r2.
const CURVE_SPAN: [f64; 3] = [0.35, 0.35, 0.8];
const PROGRESS: (f64, f64) = (-0.4, 1.4);
const LIFT_HEIGHT: (f64, f64) = (-0.05, 0.2);

fn lerp((a, b): (f64, f64), x: f64) -> f64 {
    a + (b - a) * x.clamp(0.0, 1.0)
}

/// The step a point x ∈ [0, 1]^DIM of the search box describes.
pub fn decode(case: &ClinicalCase, x: &[f64; DIM]) -> Result<ClinicalStep<f64>, ClinicalError> {
    let start = StartPosture {
        phi1_rad: lerp(PHI1_START, x[0]),
        phi3_rad: lerp(PHI3_START, x[1]),
        r2: x[2].clamp(0.0, 1.0),
    };
    let mut step = ClinicalStep {
        spacing_m: case.spacing_m,
        step_time_s: case.step_time_s,
        foot: case.foot,
        ik: case.ik,
        start,
        lift_fraction: lerp(LIFT, x[3]),
        curves: [[0.0; 3]; 3],
        path: SwingPath {
            progress: [lerp(PROGRESS, x[13]), lerp(PROGRESS, x[14])],
            lift_m: [lerp(LIFT_HEIGHT, x[15]), lerp(LIFT_HEIGHT, x[16])],
        },
    };
    let ends = step.ends(&case.model)?;
    for (c, curve) in step.curves.iter_mut().enumerate() {
        let (a, b) = (ends.values[0][c], ends.values[1][c]);
        for (j, v) in curve.iter_mut().enumerate() {
            // Control point j + 2 of 0 … 6 on the straight line, moved.
            let along = a + (b - a) * (j as f64 + 2.0) / 6.0;
            let dev = CURVE_SPAN[c] * (2.0 * x[4 + 3 * c + j].clamp(0.0, 1.0) - 1.0);
            *v = along + dev;
        }
    }
    Ok(step)
}

/// A plausible start of the search: shank upright, torso slightly forward,
/// knee nearly straight, half the step in double support, a plain swing.
pub fn initial_point(case: &ClinicalCase) -> [f64; DIM] {
    let mut x = [0.5; DIM];
    let inv = |(a, b): (f64, f64), v: f64| ((v - a) / (b - a)).clamp(0.0, 1.0);
    x[0] = inv(PHI1_START, 0.0);
    x[1] = inv(PHI3_START, 0.1);
    x[2] = if case.spacing_m[1] < 0.0 { 0.8 } else { 0.3 };
    x[3] = inv(LIFT, 0.35);
    x[13] = inv(PROGRESS, 0.0);
    x[14] = inv(PROGRESS, 1.0);
    x[15] = inv(LIFT_HEIGHT, 0.08);
    x[16] = inv(LIFT_HEIGHT, 0.08);
    x
}

/// The score of a search point: J, or a large value that still ranks
/// failures (a later IK failure is better), plus the distance to the box.
fn score(case: &ClinicalCase, x: &[f64]) -> (f64, Option<Evaluation>) {
    let mut xc = [0.0; DIM];
    let mut outside = 0.0;
    for (o, &v) in xc.iter_mut().zip(x) {
        let c = v.clamp(0.0, 1.0);
        outside += (v - c) * (v - c);
        *o = c;
    }
    let box_pen = 1e5 * outside;
    let result = decode(case, &xc)
        .map_err(EvalError::from)
        .and_then(|step| step_phi(case, &step))
        .and_then(|phi| evaluate_phi(case, &phi));
    match result {
        Ok(ev) => (ev.j + box_pen, Some(ev)),
        Err(EvalError::Step(ClinicalError::Ik { k, .. })) => {
            (1e8 + 1e5 * (1000.0 - k as f64).max(0.0) + box_pen, None)
        }
        Err(_) => (1e9 + box_pen, None),
    }
}

/// Search settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClinicalConfig {
    /// Seed.
    pub seed: u64,
    /// Cost evaluations in all.
    pub max_evals: usize,
}

impl Default for ClinicalConfig {
    fn default() -> Self {
        Self {
            seed: 1,
            max_evals: 12_000,
        }
    }
}

/// What the search found.
#[derive(Clone, Debug, PartialEq)]
pub struct ClinicalResult {
    /// The best point of the box.
    pub x: [f64; DIM],
    /// Its step.
    pub step: ClinicalStep<f64>,
    /// Its Φ samples.
    pub phi: Vec<Phi<f64>>,
    /// Its evaluation.
    pub evaluation: Evaluation,
    /// Evaluations used.
    pub evaluations: usize,
}

/// Why the search failed.
#[derive(Clone, Debug, PartialEq)]
pub enum ClinicalSearchError {
    /// The CMA-ES library refused its options.
    Cmaes(String),
    /// No point could be evaluated.
    NoFeasiblePoint,
}

impl std::fmt::Display for ClinicalSearchError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Cmaes(m) => write!(f, "CMA-ES: {m}"),
            Self::NoFeasiblePoint => f.write_str("no point of the box could be evaluated"),
        }
    }
}

impl std::error::Error for ClinicalSearchError {}

struct Best {
    evals: usize,
    best: Option<(f64, [f64; DIM])>,
}

/// Minimises the clinical cost of `case`: CMA-ES from [`initial_point`]
/// (σ 0.2), then runs from the best point with a smaller step and a
/// doubled population (IPOP), then a compass search. Deterministic.
pub fn optimize_clinical(
    case: &ClinicalCase,
    config: &ClinicalConfig,
    progress: &mut dyn FnMut(usize, f64),
) -> Result<ClinicalResult, ClinicalSearchError> {
    let state = RefCell::new(Best {
        evals: 0,
        best: None,
    });
    let polish_budget = config.max_evals / 6;
    let cma_budget = config.max_evals - polish_budget;
    let objective = |x: &DVector<f64>| {
        let (v, _) = score(case, x.as_slice());
        let mut s = state.borrow_mut();
        s.evals += 1;
        if s.best.is_none_or(|(b, _)| v < b) {
            let mut xb = [0.0; DIM];
            for (o, &vi) in xb.iter_mut().zip(x.iter()) {
                *o = vi.clamp(0.0, 1.0);
            }
            s.best = Some((v, xb));
        }
        v
    };
    let default_lambda = 4 + (3.0 * (DIM as f64).ln()).floor() as usize;
    let mut lambda = default_lambda;
    let mut sigma = 0.2;
    let mut run = 0u64;
    while state.borrow().evals + 20 * lambda <= cma_budget {
        let mean = state
            .borrow()
            .best
            .map_or_else(|| initial_point(case), |(_, x)| x);
        let left = cma_budget - state.borrow().evals;
        let mut cma = CMAESOptions::new(mean.to_vec(), sigma)
            .population_size(lambda)
            .seed(
                config
                    .seed
                    .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                    .wrapping_add(run),
            )
            .max_function_evals(left)
            .tol_fun(1e-4)
            .tol_x(1e-6)
            .build(objective)
            .map_err(|e| ClinicalSearchError::Cmaes(format!("{e:?}")))?;
        loop {
            let done = cma.next();
            let s = state.borrow();
            progress(s.evals, s.best.map_or(f64::INFINITY, |(b, _)| b));
            if done.is_some() || s.evals + lambda > cma_budget {
                break;
            }
        }
        run += 1;
        lambda *= 2;
        sigma = 0.05;
    }
    // Compass search around the best point.
    let Some((fbest, x)) = state.borrow().best else {
        return Err(ClinicalSearchError::NoFeasiblePoint);
    };
    let mut evals = state.borrow().evals;
    let budget = config.max_evals.saturating_sub(evals);
    let (x, _, _) = compass_search(
        &mut evals,
        x,
        fbest,
        1e-5,
        budget,
        |evals, y| {
            *evals += 1;
            score(case, y).0
        },
        |evals, f| progress(*evals, f),
    );
    let step_found = decode(case, &x).map_err(|_| ClinicalSearchError::NoFeasiblePoint)?;
    let phi = step_phi(case, &step_found).map_err(|_| ClinicalSearchError::NoFeasiblePoint)?;
    let evaluation = evaluate_phi(case, &phi).map_err(|_| ClinicalSearchError::NoFeasiblePoint)?;
    Ok(ClinicalResult {
        x,
        step: step_found,
        phi,
        evaluation,
        evaluations: evals,
    })
}

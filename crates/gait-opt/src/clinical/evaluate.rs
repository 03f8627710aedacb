//! The cost of a clinical table: gait-core's playback of its Φ samples
//! turned into the predicted crutch impulse plus the soft limits'
//! penalties ([`evaluate_phi`]). Deterministic, so the search regenerates a
//! table byte for byte.

use gait_core::clinical::{
    ClinicalError, ClinicalStep, HEEL_M, ground_level, riser_behind_stance_x,
};
use gait_core::kinematics::{Phi, anatomical_angles, theta_from_phi};
use gait_core::model::{GRAVITY_M_S2, LINKS};
use gait_core::playback::{self, PlaybackError, PlaybackSample};

use super::{ClinicalCase, TABLE_PERIOD_S};

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

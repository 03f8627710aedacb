//! What a closed-loop run did to the pilot, fault by fault: the figures a
//! fault injection is judged by (`exogait simulate --json`, the fault
//! campaigns). Tracking is the true joint angle against the reference;
//! limit margins are against Table I's stops; a fall is the plant's (hip
//! down, a link running away) or the torso pitched past 60°.

use gait_control::faults::{FaultCode, Reaction};
use gait_control::sequencer::Phase;

use crate::closed_loop::Rig;
use crate::plant::SimError;

/// The torso pitched further than this from upright counts as a fall, rad.
pub const TORSO_FALL_RAD: f64 = 60.0 * std::f64::consts::PI / 180.0;

/// One fault the controller latched.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultOutcome {
    /// Its code.
    pub code: FaultCode,
    /// When the injected fault behind it struck, s (the last injection at
    /// or before the detection; `None`: nothing was injected, a false trip
    /// or a consequence).
    pub injected_s: Option<f64>,
    /// When the controller latched it (the start of that tick), s.
    pub detected_s: f64,
    /// Detection latency, ticks.
    pub latency_ticks: Option<u64>,
    /// Its reaction.
    pub reaction: Reaction,
    /// The channel the supervisor's log first names it on (joint, ankle,
    /// force sensor or motor index; `None`: none, or no longer logged).
    pub channel: Option<u8>,
    /// When the reaction's state was reached, s: the safe hold's ramp
    /// done, standing after the finished step, or the motors off.
    pub safe_state_s: Option<f64>,
}

/// The run, as a fault injection judges it.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    /// Landings.
    pub landings: usize,
    /// Per joint (joint order): RMS of reference − true angle, rad.
    pub tracking_rms_rad: [f64; 4],
    /// Per joint: its largest |reference − true angle|, rad.
    pub tracking_peak_rad: [f64; 4],
    /// The smallest distance of any hip or knee to its Table I stop over
    /// the run, rad (negative: a stop was crossed), and the joint.
    pub worst_limit_margin_rad: f64,
    /// The joint of [`Outcome::worst_limit_margin_rad`] (joint order).
    pub worst_limit_joint: usize,
    /// Per joint: its smallest distance to a stop over the run, rad, and
    /// whether that stop is its flexion stop (else its extension stop).
    pub limit_margins: [(f64, bool); 4],
    /// When a hip or knee first crossed its stop, s (`None`: none did).
    pub first_stop_crossed_s: Option<f64>,
    /// When the pilot fell, s (`None`: they did not): the hips' fall ends
    /// the run, the torso's pitch past 60° is found in the trace.
    pub fell_s: Option<f64>,
    /// Per joint: the controller braked its drive at some tick of the run
    /// (a joint 0x0404 only held in place is not; the e-stop's brake on
    /// every drive is the e-stop's, not counted here).
    pub braked_joints: [bool; 4],
    /// Per joint: when it first crossed the stop of its smallest margin
    /// ([`Outcome::limit_margins`]), its drive had been given its full
    /// torque against that stop for the [`RESISTED_TICKS`] ticks
    /// before (so not braked either): a load beyond the device took it
    /// there (the drive not stopping it: [`NOT_SLOWING_SHARE`]). 0x0401's
    /// own record comes later, after its debounce.
    pub resisted_at_limit: [bool; 4],
    /// Why the pilot fell, if they did.
    pub fell: Option<String>,
    /// The faults latched, in the order they were.
    pub faults: Vec<FaultOutcome>,
}

/// The outcome of `rig`'s run, which ended with `ended_by` (`None`: it
/// ran to its end).
pub fn outcome(rig: &Rig<'_>, ended_by: Option<&SimError>) -> Outcome {
    let trace = &rig.trace;
    let dt = rig.plant.config().dt_s;
    let limits = rig.plant.config().model.limits();
    let range = [
        (-limits.hip_extension_rad, limits.hip_flexion_rad),
        (-limits.knee_extension_rad, limits.knee_flexion_rad),
    ];
    let mut sq = [0.0f64; 4];
    let mut peak = [0.0f64; 4];
    let mut worst = (f64::INFINITY, 0);
    let mut margins = [(f64::INFINITY, false); 4];
    let mut first_crossed: Option<f64> = None;
    // Per joint, the sample at which it first crossed its extension (0)
    // and its flexion stop (1).
    let mut crossed_at: [[Option<usize>; 2]; 4] = [[None; 2]; 4];
    let mut torso: Option<f64> = None;
    for (k, s) in trace.iter().enumerate() {
        for j in 0..4 {
            let q = s.state.joint_angles_rad[j];
            let e = f64::from(s.report.reference_rad[j]) - q;
            if e.is_finite() {
                sq[j] += e * e;
                peak[j] = peak[j].max(e.abs());
            }
            let (lo, hi) = range[j % 2];
            let margin = (q - lo).min(hi - q);
            if margin < worst.0 {
                worst = (margin, j);
            }
            if margin < margins[j].0 {
                margins[j] = (margin, hi - q < q - lo);
            }
            if margin < 0.0 && first_crossed.is_none() {
                first_crossed = Some(s.state.time_s);
            }
            if margin < 0.0 {
                let stop = usize::from(hi - q < q - lo);
                if let Some(at @ None) = crossed_at[j].get_mut(stop) {
                    *at = Some(k);
                }
            }
        }
        let pitch = s.state.phi[2];
        if torso.is_none() && pitch.abs() > TORSO_FALL_RAD {
            torso = Some(s.state.time_s);
        }
    }
    let n = trace.len().max(1) as f64;
    let (fell, fell_s) = match ended_by {
        Some(e @ (SimError::Fell { .. } | SimError::Runaway { .. })) => {
            (Some(e.to_string()), trace.last().map(|s| s.state.time_s))
        }
        _ => (
            torso.map(|t| format!("the torso pitched past 60° at {t:.3} s")),
            torso,
        ),
    };
    Outcome {
        landings: rig.plant.landings().len(),
        tracking_rms_rad: sq.map(|v| (v / n).sqrt()),
        tracking_peak_rad: peak,
        worst_limit_margin_rad: if worst.0.is_finite() { worst.0 } else { 0.0 },
        worst_limit_joint: worst.1,
        braked_joints: core::array::from_fn(|j| trace.iter().any(|s| s.braked[j])),
        resisted_at_limit: core::array::from_fn(|j| {
            let flexion = margins[j].1;
            crossed_at[j][usize::from(flexion)]
                .is_some_and(|k| resisted_at_limit(rig, j, k, flexion))
        }),
        limit_margins: margins.map(|(m, f)| (if m.is_finite() { m } else { 0.0 }, f)),
        first_stop_crossed_s: first_crossed,
        fell_s,
        fell,
        faults: fault_outcomes(rig, dt),
    }
}

/// The joint's speed towards the stop over the window's last half, as a
/// share of that over its first half, at or above which the drive at its
/// full torque is not stopping it: a 5 ms half loses less than a tenth of
/// its speed (for a loaded knee, some 3 kg·m² about it, sinking at
/// 0.6 rad/s: the drive beats the load by under 35 N·m of its 150; a
/// joint the drive is stopping loses far more).
pub const NOT_SLOWING_SHARE: f64 = 0.9;

/// How long a drive must have been at its full torque against a stop
/// before its joint crossed it to count as having resisted it, ticks.
pub const RESISTED_TICKS: usize = 10;

/// Joint `j` crossed its flexion (`flexion`) or extension stop at trace
/// sample `k` with its drive commanded its full torque against the stop
/// (towards extension for the flexion stop) on each of the
/// [`RESISTED_TICKS`] samples up to it, and not being stopped by it: its
/// true speed towards the stop over the window's last half at least
/// [`NOT_SLOWING_SHARE`] of that over its first half (a load the drive
/// cannot overcome took it there, not momentum the drive was braking).
fn resisted_at_limit(rig: &Rig<'_>, j: usize, k: usize, flexion: bool) -> bool {
    let Some(limit) = rig
        .controller
        .config()
        .gains
        .get(j)
        .map(|g| g.torque_limit_nm)
    else {
        return false;
    };
    let against = |t: f32| {
        let t = if flexion { -t } else { t };
        t >= 0.99 * limit
    };
    // Speed towards the stop over the window's first and last halves.
    let toward = |a: usize, b: usize| {
        let q = |i: usize| rig.trace.get(i).map(|s| s.state.joint_angles_rad[j]);
        q(a).zip(q(b))
            .map(|(qa, qb)| if flexion { qb - qa } else { qa - qb })
    };
    let half = RESISTED_TICKS / 2;
    let not_slowing = k >= RESISTED_TICKS
        && toward(k - RESISTED_TICKS, k - half)
            .zip(toward(k - half, k))
            .is_some_and(|(early, late)| early > 0.0 && late >= NOT_SLOWING_SHARE * early);
    not_slowing
        && limit > 0.0
        && rig.trace.get(k + 1 - RESISTED_TICKS..=k).is_some_and(|w| {
            w.iter()
                .all(|s| s.report.command_nm.get(j).is_some_and(|&t| against(t)))
        })
}

fn fault_outcomes(rig: &Rig<'_>, dt: f64) -> Vec<FaultOutcome> {
    let trace = &rig.trace;
    let hold_ramp = f64::from(rig.controller.config().sequencer.hold_ramp_s);
    let mut out: Vec<FaultOutcome> = Vec::new();
    for (k, s) in trace.iter().enumerate() {
        for code in s.report.faults.iter() {
            if out.iter().any(|f| f.code == code) {
                continue;
            }
            // The tick's start: when it read what it latched.
            let detected_s = s.state.time_s - dt;
            let injected_s = rig
                .injected()
                .iter()
                .map(|&(_, t)| t)
                .rfind(|&t| t <= detected_s + 1e-9);
            let reaction = code.reaction();
            let reached = |x: &crate::closed_loop::Sample| match reaction {
                Reaction::None | Reaction::PlayTable => true,
                Reaction::FinishStepThenHold => {
                    matches!(x.report.phase, Phase::Standing | Phase::SafeHold { .. })
                }
                Reaction::SafeHold => matches!(
                    x.report.phase,
                    Phase::SafeHold { t_s } if f64::from(t_s) >= hold_ramp - 1e-6
                ),
                Reaction::DisableMotors => !x.report.motors_enabled,
            };
            let safe_state_s = trace
                .get(k..)
                .and_then(|rest| rest.iter().find(|x| reached(x)))
                .map(|x| x.state.time_s - dt);
            out.push(FaultOutcome {
                code,
                injected_s,
                detected_s,
                latency_ticks: injected_s.map(|t| ((detected_s - t) / dt).round().max(0.0) as u64),
                reaction,
                channel: rig
                    .controller
                    .supervisor()
                    .log()
                    .find(|r| r.code == code)
                    .map(|r| r.channel)
                    .filter(|&c| c != gait_control::supervisor::NO_CHANNEL),
                safe_state_s,
            });
        }
    }
    out
}

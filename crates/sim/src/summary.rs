//! What a closed-loop run did, in numbers a clinician or an engineer reads:
//! when the swing ran, where the foot landed against the plan, how well the
//! joints tracked, what the crutches carried (the paper's metric
//! F = T_s Σ (f_l + f_r), measured on board by the controller and in the
//! plant's truth), the pilot's ankle torque, and every fault.

use gait_control::faults::Reaction;
use gait_control::sequencer::Phase;

use crate::closed_loop::Sample;
use crate::plant::Landing;

/// Summary of one closed-loop run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSummary {
    /// Simulated time, s.
    pub duration_s: f64,
    /// Swing start (first tick in `Phase::Swing`), s.
    pub swing_start_s: Option<f64>,
    /// First landing of the swing foot in the plant.
    pub landing: Option<Landing>,
    /// Every landing (steps completed).
    pub landings: usize,
    /// Each landing: the leg and where its ankle came down (world x, m).
    pub landing_points: Vec<(crate::plant::Side, f64)>,
    /// Mean progression speed from the first swing's start to the last
    /// landing, m/s (with ≥ 2 landings).
    pub progression_m_s: Option<f64>,
    /// Swings started (the controller entered `Phase::Swing`).
    pub swings_started: usize,
    /// Planned landing x in the world frame, m.
    pub planned_landing_x_m: f64,
    /// Highest swing-ankle height above its start, m.
    pub foot_clearance_m: f64,
    /// RMS of (true − reference) per joint over the swing (left hip, left
    /// knee, right hip, right knee), rad.
    pub tracking_rms_rad: [f64; 4],
    /// Largest |true − reference| over the swing, rad.
    pub tracking_peak_rad: f64,
    /// The paper's crutch metric over the swing from the plant's true crutch
    /// forces, N·s.
    pub crutch_impulse_ns: f64,
    /// The same from the controller's on-board log (its force sensors), N·s.
    pub crutch_impulse_on_board_ns: Option<f64>,
    /// Peak force on the left and right crutch over the swing, N.
    pub crutch_peak_n: [f64; 2],
    /// RMS and peak of the pilot's ankle torque over the swing, N·m (the
    /// model's counterpart of the paper's minimised τ).
    pub pilot_torque_rms_nm: f64,
    /// Peak |pilot ankle torque| over the swing, N·m.
    pub pilot_torque_peak_nm: f64,
    /// First tick with a reaction other than `None`, its time (s) and the
    /// reaction.
    pub first_reaction: Option<(f64, Reaction)>,
    /// Names of the faults latched at the end.
    pub faults: Vec<&'static str>,
    /// The controller's phase at the end.
    pub final_phase: Phase,
}

/// Summarises a trace (`planned_landing_x_m`: where the table lands the
/// swing foot, world frame).
pub fn summarise(
    trace: &[Sample],
    landings: &[Landing],
    planned_landing_x_m: f64,
    faults: Vec<&'static str>,
    on_board_impulse_ns: Option<f64>,
    dt_s: f64,
) -> RunSummary {
    // The first step's swing: swing ticks before the first landing.
    let first_landing_s = landings.first().map_or(f64::INFINITY, |l| l.time_s);
    let swing: Vec<&Sample> = trace
        .iter()
        .filter(|s| {
            matches!(s.report.phase, Phase::Swing { .. }) && s.state.time_s <= first_landing_s
        })
        .collect();
    let swings_started = trace
        .windows(2)
        .filter(|w| {
            matches!(w[1].report.phase, Phase::Swing { .. })
                && !matches!(w[0].report.phase, Phase::Swing { .. })
        })
        .count();
    let swing_start_s = swing.first().map(|s| s.state.time_s - dt_s);
    let start_y = swing.first().map_or(0.0, |s| s.state.points_m[5][1]);
    let foot_clearance_m = swing
        .iter()
        .map(|s| s.state.points_m[5][1] - start_y)
        .fold(0.0, f64::max);
    let mut sq = [0.0f64; 4];
    let mut peak = 0.0f64;
    let (mut crutch, mut peaks) = (0.0, [0.0f64; 2]);
    let (mut pilot_sq, mut pilot_peak) = (0.0, 0.0f64);
    for s in &swing {
        for (j, acc) in sq.iter_mut().enumerate() {
            let e = s.state.joint_angles_rad[j] - f64::from(s.report.reference_rad[j]);
            *acc += e * e;
            peak = peak.max(e.abs());
        }
        crutch += (s.state.crutch_forces_n[0] + s.state.crutch_forces_n[1]) * dt_s;
        peaks[0] = peaks[0].max(s.state.crutch_forces_n[0]);
        peaks[1] = peaks[1].max(s.state.crutch_forces_n[1]);
        pilot_sq += s.state.pilot_torque_nm * s.state.pilot_torque_nm;
        pilot_peak = pilot_peak.max(s.state.pilot_torque_nm.abs());
    }
    let n = swing.len().max(1) as f64;
    RunSummary {
        duration_s: trace.last().map_or(0.0, |s| s.state.time_s),
        swing_start_s,
        landing: landings.first().copied(),
        landings: landings.len(),
        landing_points: landings.iter().map(|l| (l.side, l.position_m[0])).collect(),
        progression_m_s: match (swing_start_s, landings.last()) {
            (Some(t0), Some(last)) if landings.len() >= 2 && last.time_s > t0 => {
                Some(last.position_m[0] / (last.time_s - t0))
            }
            _ => None,
        },
        swings_started,
        planned_landing_x_m,
        foot_clearance_m,
        tracking_rms_rad: sq.map(|v| (v / n).sqrt()),
        tracking_peak_rad: peak,
        crutch_impulse_ns: crutch,
        crutch_impulse_on_board_ns: on_board_impulse_ns,
        crutch_peak_n: peaks,
        pilot_torque_rms_nm: (pilot_sq / n).sqrt(),
        pilot_torque_peak_nm: pilot_peak,
        first_reaction: trace
            .iter()
            .find(|s| s.report.reaction != Reaction::None)
            .map(|s| (s.state.time_s, s.report.reaction)),
        faults,
        final_phase: trace.last().map_or(Phase::Standing, |s| s.report.phase),
    }
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "simulated time           {:.2} s", self.duration_s)?;
        match self.swing_start_s {
            Some(t) => writeln!(f, "swing started            {t:.3} s")?,
            None => writeln!(f, "swing started            never")?,
        }
        match &self.landing {
            Some(l) => writeln!(
                f,
                "landed                   {:.3} s at x = {:.3} m (plan {:.3} m, error {:+.1} mm), descending {:.2} m/s",
                l.time_s,
                l.position_m[0],
                self.planned_landing_x_m,
                1000.0 * (l.position_m[0] - self.planned_landing_x_m),
                l.descent_speed_m_s
            )?,
            None => writeln!(f, "landed                   no")?,
        }
        writeln!(
            f,
            "steps                    {} swing(s) started, {} landing(s)",
            self.swings_started, self.landings
        )?;
        if self.landing_points.len() > 1 {
            let points: Vec<String> = self
                .landing_points
                .iter()
                .map(|(side, x)| {
                    let leg = match side {
                        crate::plant::Side::Left => "L",
                        crate::plant::Side::Right => "R",
                    };
                    format!("{leg} {x:.3}")
                })
                .collect();
            writeln!(f, "landings (leg, x m)      {}", points.join(", "))?;
        }
        if let Some(v) = self.progression_m_s {
            writeln!(
                f,
                "progression              {v:.3} m/s (first swing start to last landing)"
            )?;
        }
        writeln!(
            f,
            "foot clearance           {:.3} m (first swing)",
            self.foot_clearance_m
        )?;
        writeln!(
            f,
            "tracking RMS (1st swing) L hip {:.4}  L knee {:.4}  R hip {:.4}  R knee {:.4} rad; peak {:.4} rad",
            self.tracking_rms_rad[0],
            self.tracking_rms_rad[1],
            self.tracking_rms_rad[2],
            self.tracking_rms_rad[3],
            self.tracking_peak_rad
        )?;
        writeln!(
            f,
            "crutch load F (1st swing) {:.1} N·s (plant){}",
            self.crutch_impulse_ns,
            self.crutch_impulse_on_board_ns
                .map_or(String::new(), |v| format!(
                    ", {v:.1} N·s (on-board log, 1st step)"
                ))
        )?;
        writeln!(
            f,
            "crutch peaks (1st swing) left {:.0} N, right {:.0} N",
            self.crutch_peak_n[0], self.crutch_peak_n[1]
        )?;
        writeln!(
            f,
            "pilot ankle torque (1st) RMS {:.1} N·m, peak {:.1} N·m",
            self.pilot_torque_rms_nm, self.pilot_torque_peak_nm
        )?;
        match self.first_reaction {
            Some((t, r)) => writeln!(f, "first supervisor action  {t:.3} s: {}", reaction_text(r))?,
            None => writeln!(f, "first supervisor action  none")?,
        }
        if self.faults.is_empty() {
            writeln!(f, "faults latched           none")?;
        } else {
            writeln!(f, "faults latched           {}", self.faults.join(", "))?;
        }
        write!(
            f,
            "final phase              {}",
            phase_text(&self.final_phase)
        )
    }
}

/// A reaction as a user reads it.
fn reaction_text(r: gait_control::faults::Reaction) -> &'static str {
    use gait_control::faults::Reaction;
    match r {
        Reaction::None => "none",
        Reaction::PlayTable => "play the table",
        Reaction::FinishStepThenHold => "finish the step, then hold",
        Reaction::SafeHold => "safe hold",
        Reaction::DisableMotors => "motors disabled",
    }
}

/// A phase as a user reads it: the phase, its stance leg and time.
fn phase_text(p: &Phase) -> String {
    let leg = |s: &crate::Side| match s {
        crate::Side::Left => "left",
        crate::Side::Right => "right",
    };
    match p {
        Phase::Standing => "standing".into(),
        Phase::WaitingReady { stance } => {
            format!("waiting for the pilot ({} leg stance)", leg(stance))
        }
        Phase::Swing { stance, t_s } => format!("swing, {} leg stance, {t_s:.2} s in", leg(stance)),
        Phase::Transfer { stance, t_s } => {
            format!(
                "weight transfer onto the {} leg, {t_s:.2} s in",
                leg(stance)
            )
        }
        Phase::SafeHold { .. } => "safe hold".into(),
    }
}

/// Per swing in `trace`: the time the device waited for the pilot before
/// it (ticks in `WaitingReady` since the previous swing began), s.
pub fn waited_before_swings(trace: &[Sample], dt_s: f64) -> Vec<f64> {
    let mut out = Vec::new();
    let mut waiting = 0u64;
    let mut in_swing = false;
    for s in trace {
        match s.report.phase {
            gait_control::sequencer::Phase::WaitingReady { .. } => waiting += 1,
            gait_control::sequencer::Phase::Swing { .. } if !in_swing => {
                out.push(waiting as f64 * dt_s);
                waiting = 0;
            }
            _ => {}
        }
        in_swing = matches!(s.report.phase, gait_control::sequencer::Phase::Swing { .. });
    }
    out
}

//! What the simulated pilot aims the stance shank at, tick by tick: the
//! pilot's behaviour (a fixed target, a learnt profile, the table's own
//! shank) and where it puts the shank in each phase of the controller.
//! The pilot is the simulation's alone (no device has one).

use gait_control::sequencer::Phase;
use gait_core::gait::StanceAnkleProfile;
use gait_core::tables::GaitTable;

use crate::pilot::{PilotConfig, PilotTarget};
use crate::plant::Side;

/// How the simulated pilot uses the crutches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PilotBehaviour {
    /// A fixed target for the whole run.
    Fixed(PilotTarget),
    /// A pilot who has learnt a logistic stance-shank profile: during each
    /// swing the stance shank follows it, timed from the swing's start as
    /// the controller reports it; between swings it is held at the
    /// profile's start angle.
    FollowsPlan(StanceAnkleProfile<f64>),
    /// A pilot who has learnt the gait (the paper's pilots practised 25
    /// cycles first): during each swing the stance shank follows the one
    /// the table being played plans (its φ1), timed from the swing's start;
    /// between swings it is held at the table's start.
    FollowsTable,
}

/// Where the pilot's stance shank should be, given the controller's phase
/// and the table it plays: the table's stance shank during a swing; during
/// the weight transfer a smooth move from where the shank was at landing to
/// the table's start (as the controller's transfer plans it); otherwise
/// held at the table's start.
pub(crate) fn pilot_target(
    b: &PilotBehaviour,
    swapped: bool,
    phase: &Phase,
    table: Option<&GaitTable<'_>>,
    transfer_from: Option<f64>,
    transfer_s: f32,
    now_s: f64,
) -> PilotTarget {
    let start = |fallback: f64| table.map_or(fallback, |t| f64::from(t.first()[0]));
    match *b {
        PilotBehaviour::Fixed(t) => t,
        PilotBehaviour::FollowsPlan(profile) => {
            follow(phase, profile.at(0.0), transfer_from, transfer_s, |t_s| {
                PilotTarget::Profile {
                    profile,
                    t0_s: now_s - t_s,
                }
            })
        }
        PilotBehaviour::FollowsTable => {
            let to = start(0.0);
            follow(phase, to, transfer_from, transfer_s, |t_s| match table {
                Some(tb) => {
                    let (phi1, rate) = table_stance_shank(tb, t_s, swapped);
                    PilotTarget::Track {
                        phi1_rad: phi1,
                        rate_rad_s: rate,
                        t0_s: now_s,
                    }
                }
                None => PilotTarget::Hold { phi1_rad: to },
            })
        }
    }
}

/// The pilot's habit ([`PilotConfig::habit_lean_rad`]): the lean over the
/// plan this tick, rad — the whole habit from each weight transfer (and
/// while standing) on, corrected towards the plan once a step has kept
/// the pilot waiting longer than their patience, and kept as it is through
/// the swing that follows.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Habit {
    lean_rad: Option<f64>,
    waited_s: f64,
}

impl Habit {
    pub(crate) fn lean(&mut self, cfg: &PilotConfig, phase: &Phase, dt_s: f64) -> f64 {
        let habit = cfg.habit_lean_rad;
        let lean = self.lean_rad.get_or_insert(habit);
        match phase {
            Phase::Standing | Phase::Transfer { .. } => {
                *lean = habit;
                self.waited_s = 0.0;
            }
            Phase::WaitingReady { .. } => {
                self.waited_s += dt_s;
                if self.waited_s > cfg.patience_s {
                    let step = cfg.correction_rad_s * dt_s;
                    *lean = if lean.abs() <= step {
                        0.0
                    } else {
                        *lean - step * lean.signum()
                    };
                }
            }
            Phase::Swing { .. } | Phase::SafeHold { .. } => {}
        }
        *lean
    }
}

/// The pilot's reaction to a safe hold ([`PilotConfig::hold_reaction_s`],
/// [`PilotConfig::hold_recovery_s`]): what the pilot aimed at before the
/// hold, kept for the reaction time, then a move from where the shank is
/// to the hold's aim. A foot set down in the hold becomes the plant's
/// stance foot: the move then starts again from that foot's shank, since
/// the angle it started from was the other leg's.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HoldReaction {
    /// The aim of the last tick outside a hold.
    before: Option<PilotTarget>,
    /// When the hold began, s.
    struck_s: Option<f64>,
    /// Where the shank was when the pilot began to move it, rad, the
    /// plant's stance foot then, and when, s.
    from: Option<(f64, Side, f64)>,
}

impl HoldReaction {
    /// The pilot's aim this tick, `aim` being where the phase alone puts
    /// it, `stance` the plant's stance foot and `phi1` what tells its
    /// shank's angle now, `now_s` the time.
    pub(crate) fn aim(
        &mut self,
        cfg: &PilotConfig,
        in_hold: bool,
        aim: PilotTarget,
        stance: Side,
        phi1: impl FnOnce() -> f64,
        now_s: f64,
    ) -> PilotTarget {
        if !in_hold {
            *self = Self {
                before: Some(aim),
                ..Self::default()
            };
            return aim;
        }
        let since = now_s - *self.struck_s.get_or_insert(now_s);
        if since < cfg.hold_reaction_s {
            return self.before.unwrap_or(aim);
        }
        let (Some((to, _)), true) = (aim.desired(now_s, 0.0), cfg.hold_recovery_s > 0.0) else {
            return aim;
        };
        let (from, _, moved_s) = match self.from {
            Some(f) if f.1 == stance => f,
            _ => *self.from.insert((phi1(), stance, now_s)),
        };
        let x = ((now_s - moved_s) / cfg.hold_recovery_s).clamp(0.0, 1.0);
        let s = smoothstep(x);
        let ds = if x < 1.0 {
            6.0 * x * (1.0 - x) / cfg.hold_recovery_s
        } else {
            0.0
        };
        PilotTarget::Track {
            phi1_rad: from + s * (to - from),
            rate_rad_s: ds * (to - from),
            t0_s: now_s,
        }
    }
}

/// The stance shank a table plans at `t_s` and its rate (central
/// differences over one table period, inside the table), rad and rad/s;
/// held at the last sample once the table has ended.
/// With `swapped` (the plant has already put the swing foot down and made
/// it the stance foot, the controller not yet), the shank of that foot in
/// the table's posture.
pub fn table_stance_shank(table: &GaitTable<'_>, t_s: f64, swapped: bool) -> (f64, f64) {
    let h = f64::from(table.period_s());
    let end = f64::from(table.duration_s());
    let at = |t: f64| {
        let phi = table.at_time(t as f32).map(f64::from);
        if swapped {
            gait_core::kinematics::swap_legs(&phi)[0]
        } else {
            phi[0]
        }
    };
    if t_s >= end {
        return (at(end), 0.0);
    }
    let tc = t_s.max(h).min(end - h);
    (at(t_s), (at(tc + h) - at(tc - h)) / (2.0 * h))
}

/// The pilot's target in each phase: `swing(t)` during a swing `t` seconds
/// in; the smoothstep from the landing's shank to `start` during the
/// transfer; `start` otherwise.
fn follow(
    phase: &Phase,
    start: f64,
    transfer_from: Option<f64>,
    transfer_s: f32,
    swing: impl FnOnce(f64) -> PilotTarget,
) -> PilotTarget {
    match *phase {
        Phase::Swing { t_s, .. } => swing(f64::from(t_s)),
        Phase::Transfer { t_s, .. } => {
            let from = transfer_from.unwrap_or(start);
            let x = if transfer_s > 0.0 {
                f64::from(t_s / transfer_s).clamp(0.0, 1.0)
            } else {
                1.0
            };
            let s = smoothstep(x);
            PilotTarget::Hold {
                phi1_rad: from + s * (start - from),
            }
        }
        _ => PilotTarget::Hold { phi1_rad: start },
    }
}

/// 3x² − 2x³ for x in [0, 1]: an eased move, at rest at both ends.
fn smoothstep(x: f64) -> f64 {
    x * x * (3.0 - 2.0 * x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_control::posture::Side;

    const LEFT: crate::plant::Side = crate::plant::Side::Left;

    fn held(t: PilotTarget) -> f64 {
        match t {
            PilotTarget::Hold { phi1_rad } => phi1_rad,
            other => panic!("not a hold: {other:?}"),
        }
    }

    /// The pilot's reaction to a hold: the aim before it for the reaction
    /// time, then an eased move from where the shank is to the hold's
    /// aim; none at all with both times 0; and it starts again at the
    /// next hold.
    #[test]
    fn a_hold_is_met_after_the_pilot_s_reaction_time_by_an_eased_move() {
        let cfg = PilotConfig {
            hold_reaction_s: 0.15,
            hold_recovery_s: 0.6,
            ..PilotConfig::default()
        };
        let swing = PilotTarget::Track {
            phi1_rad: 0.3,
            rate_rad_s: 0.5,
            t0_s: 1.0,
        };
        let hold = PilotTarget::Hold { phi1_rad: -0.1 };
        let mut r = HoldReaction::default();
        assert_eq!(r.aim(&cfg, false, swing, LEFT, || 0.3, 1.0), swing);
        // Through the reaction time: what the pilot was doing.
        for t in [1.001, 1.1, 1.15] {
            assert_eq!(
                r.aim(&cfg, true, hold, LEFT, || panic!("not yet"), t),
                swing
            );
        }
        // Then from where the shank is (0.35) to the aim, eased.
        let at = |r: &mut HoldReaction, t: f64| match r.aim(&cfg, true, hold, LEFT, || 0.35, t) {
            PilotTarget::Track {
                phi1_rad,
                rate_rad_s,
                ..
            } => (phi1_rad, rate_rad_s),
            other => panic!("not a move: {other:?}"),
        };
        let (start, v0) = at(&mut r, 1.151);
        assert!((start - 0.35).abs() < 1e-9 && v0.abs() < 1e-9);
        let (mid, v) = at(&mut r, 1.451);
        assert!((mid - 0.5 * (0.35 - 0.1)).abs() < 1e-6, "{mid}");
        assert!((v - 1.5 * (-0.1 - 0.35) / 0.6).abs() < 1e-6, "{v}");
        let (end, v_end) = at(&mut r, 2.0);
        assert!((end + 0.1).abs() < 1e-9 && v_end == 0.0, "{end} {v_end}");
        // A new hold after leaving this one reacts again.
        assert_eq!(r.aim(&cfg, false, swing, LEFT, || 0.3, 3.0), swing);
        assert_eq!(r.aim(&cfg, true, hold, LEFT, || 0.3, 3.01), swing);
        // Times 0: the hold's aim at once.
        let instant = PilotConfig::default();
        let mut r = HoldReaction::default();
        r.aim(&instant, false, swing, LEFT, || 0.3, 1.0);
        assert_eq!(r.aim(&instant, true, hold, LEFT, || 0.3, 1.001), hold);
    }

    /// A foot set down in a hold becomes the plant's stance foot: the
    /// pilot's move starts again from that foot's shank, not from the
    /// other leg's angle (a descent's left shank at 0.49 rad, the landed
    /// right one at −0.03: going on from 0.49, the crutches would shove the
    /// body over the lower foot at their full 300 N·m).
    #[test]
    fn a_foot_set_down_in_a_hold_restarts_the_move_from_its_own_shank() {
        let cfg = PilotConfig {
            hold_reaction_s: 0.1,
            hold_recovery_s: 1.0,
            ..PilotConfig::default()
        };
        let right = crate::plant::Side::Right;
        let hold = PilotTarget::Hold { phi1_rad: 0.1 };
        let phi = |t: PilotTarget| match t {
            PilotTarget::Track { phi1_rad, .. } => phi1_rad,
            other => panic!("not a move: {other:?}"),
        };
        let mut r = HoldReaction::default();
        r.aim(&cfg, false, hold, LEFT, || 0.49, 1.0);
        r.aim(&cfg, true, hold, LEFT, || 0.49, 1.0);
        assert!((phi(r.aim(&cfg, true, hold, LEFT, || 0.49, 1.1)) - 0.49).abs() < 1e-9);
        let left_mid = phi(r.aim(&cfg, true, hold, LEFT, || 0.0, 1.3));
        assert!(left_mid < 0.49 && left_mid > 0.1, "{left_mid}");
        // The right foot lands: the aim is where its shank is, then eases
        // from there to the hold's aim over the whole recovery time.
        let landed = r.aim(&cfg, true, hold, right, || -0.03, 1.3);
        assert!((phi(landed) + 0.03).abs() < 1e-9, "{landed:?}");
        let half = phi(r.aim(&cfg, true, hold, right, || 9.0, 1.8));
        assert!((half - 0.5 * (0.1 - 0.03)).abs() < 1e-6, "{half}");
        assert!((phi(r.aim(&cfg, true, hold, right, || 9.0, 2.3)) - 0.1).abs() < 1e-9);
    }

    /// What the campaign's figures rest on: the pilot's aim in a safe hold
    /// moves the falls of a 10,000-run campaign by hundreds
    /// (`docs/campaign.md`), so a change
    /// here must be deliberate.
    #[test]
    fn the_pilot_aims_at_the_step_s_start_but_in_a_swing_and_a_transfer() {
        let (start, landed) = (0.05, 0.30);
        let swing_target = PilotTarget::Hold { phi1_rad: 9.0 };
        let aim =
            |phase: Phase, from: Option<f64>| follow(&phase, start, from, 0.5, |_| swing_target);
        // A swing: the table's shank (here a marker).
        let swing = Phase::Swing {
            stance: Side::Left,
            t_s: 0.2,
        };
        assert_eq!(aim(swing, None), swing_target);
        // A transfer: from the landing's shank to the start, smoothstep.
        let transfer = |t_s| Phase::Transfer {
            stance: Side::Right,
            t_s,
        };
        assert_eq!(held(aim(transfer(0.0), Some(landed))), landed);
        assert!((held(aim(transfer(0.25), Some(landed))) - 0.5 * (start + landed)).abs() < 1e-6);
        assert!((held(aim(transfer(0.5), Some(landed))) - start).abs() < 1e-12);
        assert!((held(aim(transfer(2.0), Some(landed))) - start).abs() < 1e-12);
        // A safe hold, standing, waiting: the step's start posture, at
        // once (the crutches' full 120 N·m if the shank is far from it).
        assert_eq!(held(aim(Phase::SafeHold { t_s: 0.0 }, Some(landed))), start);
        assert_eq!(held(aim(Phase::Standing, None)), start);
        let waiting = Phase::WaitingReady { stance: Side::Left };
        assert_eq!(held(aim(waiting, None)), start);
    }
}

//! The windowed checks: the rules that judge a channel over many ticks
//! (a joint's velocity, frozen counts, tracking and torque residual; an
//! ankle's heel-off and stuck readings; the force sensors' and drive
//! monitors' debounces; the crutches left at rest through a swing). None
//! of them can trip on one tick's facts alone, and together they are most
//! of the supervisor's work. (The pilot's
//! balance at the ankles, 0x0701 and 0x0702, is judged over ticks too but
//! stays in the tick: a pilot losing balance is held a millisecond sooner.)
//!
//! So the controller runs them a tick late, off the tick: it hands each
//! tick's facts over as a [`WindowedJob`] and applies the [`Findings`] of
//! the last one at the next tick's guard, before that tick's own checks.
//! On the board the model task works them out between the two ticks
//! ([`crate::feedforward::ModelTask`], through a
//! [`CheckSlot`](crate::check_slot::CheckSlot)); without a task (the
//! simulator, tests) the controller works them out itself at the end of
//! its guard. The same arithmetic on the same facts: the verdicts are
//! equal bit for bit. What needs one tick to be seen (an e-stop, a bad or
//! out-of-range frame, a motor's flags, the deadline) stays in the tick.
//!
//! [`Supervisor::check`] runs both on the same tick's facts (the rules'
//! own tests).

use super::crutch_idle::CrutchIdleTrack;
use super::findings::{Findings, Marks};
use super::tracks::{ForceTrack, JointMotion};
use super::*;

/// One tick's facts for the windowed checks.
#[derive(Debug, Clone, Copy, Default)]
pub struct WindowedJob {
    /// The tick's facts, as its guard saw them.
    pub input: SupervisorInput,
    /// Its encoder frames, joints then ankles.
    pub frames: [EncoderFrame; ENCODERS],
    /// The latch's marks after the guard ([`Supervisor::mark`]).
    pub(super) marks: Marks,
}

impl WindowedJob {
    /// The tick the facts are from.
    pub const fn tick(&self) -> u32 {
        self.input.tick
    }
}

/// The windowed checks' memory of each channel.
#[derive(Debug, Clone)]
pub struct WindowedChecks {
    pub(super) cfg: SupervisorConfig,
    /// 0x0404's observer constants, from `cfg.response`.
    observer: response::Observer,
    pub(super) joints: [JointMotion; JOINTS],
    /// Consecutive ticks each ankle has rested on its stop unplanned.
    heel_off_ticks: [u32; ANKLES],
    /// Consecutive frames each ankle has read its dorsiflexion stop,
    /// unchanged, with its foot in the air (0x0207's stuck ankle).
    stuck_in_air_ticks: [u32; ANKLES],
    /// The plan of each stance ankle when its counts last changed (NaN
    /// outside a swing's stance): 0x0207's frozen stance ankle.
    plan_since_moved: [f32; ANKLES],
    forces: [ForceTrack; FORCES],
    pub(super) drive_currents: [drive_current::DriveCurrentTrack; JOINTS],
    /// The crutches' resting load and idle stretch (0x0703).
    crutch_idle: CrutchIdleTrack,
    previous_reference_rad: Option<[f32; JOINTS]>,
}

impl WindowedChecks {
    /// Each joint's torque residual d̂ at the last tick checked, N·m
    /// (0x0404; 0 where its observer is stopped), for observers.
    pub fn residuals_nm(&self) -> [f32; JOINTS] {
        let mut out = [0.0; JOINTS];
        for (o, j) in out.iter_mut().zip(&self.joints) {
            *o = j.residual.last_nm;
        }
        out
    }

    /// Fresh memory for the checks of `cfg` (validated by the
    /// [`Supervisor`] it belongs to).
    pub(super) fn new(cfg: &SupervisorConfig) -> Self {
        Self {
            observer: response::Observer::new(&cfg.response, cfg.dt_s),
            cfg: *cfg,
            joints: [JointMotion::default(); JOINTS],
            heel_off_ticks: [0; ANKLES],
            stuck_in_air_ticks: [0; ANKLES],
            plan_since_moved: [f32::NAN; ANKLES],
            forces: [ForceTrack::default(); FORCES],
            drive_currents: Default::default(),
            crutch_idle: CrutchIdleTrack::default(),
            previous_reference_rad: None,
        }
    }

    /// The checks of one tick's facts.
    pub fn run(&mut self, job: &WindowedJob) -> Findings {
        let mut f = Findings::new(job.input.tick, job.marks);
        self.check_joints(&job.input, &job.frames, &mut f);
        self.check_ankles(&job.input, &job.frames, &mut f);
        self.check_forces(&job.input, &mut f);
        self.check_crutches(&job.input, &mut f);
        self.check_drive_current(&job.input, &mut f);
        self.previous_reference_rad = Some(job.input.joint_reference_rad);
        f
    }
}

/// `|x| ≤ limit`; false for NaN, so `!within(..)` trips on NaN.
pub(super) fn within(x: f32, limit: f32) -> bool {
    x.abs() <= limit
}

impl WindowedChecks {
    fn check_joints(
        &mut self,
        input: &SupervisorInput,
        frames: &[EncoderFrame; ENCODERS],
        f: &mut Findings,
    ) {
        let cfg = &self.cfg;
        // 0x0404's limit on each joint this tick (the stance hip of a swing
        // may have its gait's own; a leaning pilot's hip a higher one).
        let ahead = |a: usize| {
            let plan = input.ankle_plan_rad.get(a).copied().unwrap_or(f32::NAN);
            frames
                .get(JOINTS + a)
                .and_then(|t| t.accepted())
                .map_or(f32::NAN, |(angle, _, _)| angle - plan)
        };
        let residual_limit = self.observer.limits(
            input.swing_leg,
            input.stance_hip_residual_nm,
            [ahead(0), ahead(1)],
        );
        for i in 0..JOINTS {
            let ch = i as u8;
            let (Some(taken), Some(&reference), Some(&vmax), Some(motor), Some(track)) = (
                frames.get(i),
                input.joint_reference_rad.get(i),
                cfg.velocity_limit_rad_s.get(i),
                input.motors.get(i),
                self.joints.get_mut(i),
            ) else {
                continue;
            };
            let reference_speed = match self.previous_reference_rad.as_ref().and_then(|p| p.get(i))
            {
                Some(&previous) => (reference - previous).abs() / cfg.dt_s,
                None => 0.0,
            };
            // NaN speed or command counts as driven.
            let driven = !(reference_speed < cfg.frozen_reference_speed_rad_s
                && motor.commanded_nm.abs() < cfg.frozen_command_fraction * motor.limit_nm);
            if let Some((angle_rad, delta, previous_angle_rad)) = taken.accepted() {
                match delta {
                    Some((counts, elapsed)) => {
                        let elapsed_s = cfg.dt_s * elapsed.max(1) as f32;
                        let raw_velocity = (angle_rad - previous_angle_rad) / elapsed_s;
                        // Starts from 0 after a (re-)seed, so one noisy
                        // difference cannot trip the limit alone.
                        if !track.velocity_rad_s.is_finite() {
                            track.velocity_rad_s = 0.0;
                        }
                        track.velocity_rad_s +=
                            cfg.velocity_filter_alpha * (raw_velocity - track.velocity_rad_s);
                        track.velocity_valid = true;
                        // A still stretch is timed only while there is a
                        // count to restart (a driven tick starts it at 0).
                        if counts != 0 {
                            track.frozen_ticks = 0;
                        } else if driven {
                            track.frozen_ticks = track.frozen_ticks.saturating_add(1);
                            track.still_ticks = 0;
                        } else if track.frozen_ticks > 0 {
                            track.still_ticks = track.still_ticks.saturating_add(1);
                            if track.still_ticks >= cfg.frozen_still_reset_ticks {
                                track.frozen_ticks = 0;
                            }
                        }
                    }
                    None => {
                        // (Re-)seeded: no velocity from a single sample.
                        track.velocity_rad_s = 0.0;
                        track.velocity_valid = false;
                        track.frozen_ticks = 0;
                    }
                }
                // A lost encoder's frames (a frozen one still sends valid
                // ones) say nothing of the joint's motion: no tracking or
                // residual check on them.
                let trusted = !f.marks.angle_lost.get(i).copied().unwrap_or(true);
                let error = angle_rad - reference;
                if !trusted || error.abs() <= cfg.tracking_error_limit_rad {
                    track.tracking_ticks = 0;
                } else {
                    track.tracking_ticks = track.tracking_ticks.saturating_add(1);
                }
                if track.tracking_ticks >= cfg.tracking_error_ticks {
                    f.raise(FaultCode::TrackingError, ch, error);
                }
                // A reference faster than the joint can go is a jump of the
                // plan (a hold's start, a reset), not a motion to check
                // against: the observer restarts from it.
                if trusted && motor.enabled && delta.is_some() && reference_speed <= vmax {
                    let o = &self.observer;
                    let swing = input.swing_leg.is_some_and(|leg| leg.has_joint(i));
                    let d = track.residual.update(
                        o,
                        error,
                        motor.applied_nm,
                        motor.feedforward_nm,
                        o.inertia(i, swing),
                    );
                    let limit = residual_limit.get(i).copied().unwrap_or(o.limit_nm);
                    if within(d, limit) {
                        track.residual.over_ticks = 0;
                    } else {
                        track.residual.over_ticks = track.residual.over_ticks.saturating_add(1);
                    }
                    if track.residual.over_ticks >= o.ticks
                        && f.raise_on_joint(FaultCode::MotorResponse, i, d)
                    {
                        // Held in place: 10 more ticks over the limit brake
                        // it (the observer restarted there measured the
                        // same on the campaign's drive and encoder runs).
                        track.residual.over_ticks = 0;
                    }
                    if !d.is_finite() {
                        track.residual.stop(motor.feedforward_nm);
                    }
                } else {
                    track.residual.stop(motor.feedforward_nm);
                }
            } else {
                track.residual.stop(motor.feedforward_nm);
            }
            // Conditions that persist while frames are rejected.
            if track.velocity_valid && !within(track.velocity_rad_s, vmax) {
                f.raise(FaultCode::JointVelocityLimit, ch, track.velocity_rad_s);
            }
            if track.frozen_ticks >= cfg.frozen_ticks {
                f.raise(FaultCode::EncoderFrozen, ch, track.frozen_ticks as f32);
            }
        }
    }
}

impl WindowedChecks {
    fn check_ankles(
        &mut self,
        input: &SupervisorInput,
        frames: &[EncoderFrame; ENCODERS],
        f: &mut Findings,
    ) {
        let cfg = &self.cfg;
        for i in 0..ANKLES {
            let ch = i as u8;
            let Some((angle_rad, delta, _)) = frames.get(JOINTS + i).and_then(|t| t.accepted())
            else {
                continue;
            };
            // Resting on the stop while the plan is well below it (a NaN
            // plan never counts; a rejected frame neither counts nor
            // resets).
            let plan = input.ankle_plan_rad.get(i).copied().unwrap_or(f32::NAN);
            let on_stop = angle_rad >= cfg.heel_off_rad - cfg.heel_off_reading_tolerance_rad;
            let unplanned = plan < cfg.heel_off_rad - cfg.heel_off_plan_margin_rad;
            if let Some(n) = self.heel_off_ticks.get_mut(i) {
                *n = if on_stop && unplanned {
                    n.saturating_add(1)
                } else {
                    0
                };
                if *n >= cfg.heel_off_ticks {
                    f.raise(FaultCode::UnplannedHeelOff, ch, angle_rad);
                }
            }
            // Only a toe pushed up by the ground holds an ankle on its
            // dorsiflexion stop: in the air its spring takes it off within
            // tens of milliseconds. Counts that stay on the stop, unchanged,
            // with the foot in the air are an encoder stuck where the foot
            // left the ground (read as a lean, it set a stair descent's
            // landing on the stop and dropped the pilot); control stops
            // taking them until they move.
            let in_air = input.airborne_leg.is_some_and(|leg| leg.ankle() == i);
            let moved = delta.is_some_and(|(counts, _)| counts != 0);
            if let (Some(n), Some(stuck)) =
                (self.stuck_in_air_ticks.get_mut(i), f.ankle_stuck.get_mut(i))
            {
                *n = if in_air && on_stop && delta.is_some() && !moved {
                    n.saturating_add(1)
                } else {
                    0
                };
                if moved {
                    *stuck = Some(false);
                }
                if *n >= cfg.frozen_ticks {
                    *stuck = Some(true);
                    f.raise(FaultCode::AnkleEncoder, ch, *n as f32);
                }
            }
            // A stance ankle in a swing turns with its shank: counts that
            // do not change once while the plan turns it by
            // `frozen_ankle_plan_rad` are a frozen encoder (its stale
            // reading set the posture a walk's step played on with past its
            // table's end, and the residual braked the stance knee). Off
            // the stop only: a heel up rests there; and within one swing,
            // whose plan is continuous.
            let stance_in_swing = input.swing_leg.is_some_and(|leg| leg.other().ankle() == i);
            let planned = stance_in_swing && plan.is_finite() && !on_stop;
            if let Some(from) = self.plan_since_moved.get_mut(i) {
                if !planned {
                    *from = f32::NAN;
                } else if moved || from.is_nan() {
                    *from = plan;
                } else if delta.is_some() && (plan - *from).abs() >= cfg.frozen_ankle_plan_rad {
                    if let Some(stuck) = f.ankle_stuck.get_mut(i) {
                        *stuck = Some(true);
                    }
                    f.raise(FaultCode::AnkleEncoder, ch, plan - *from);
                }
            }
        }
    }

    /// 0x0703: the crutches at their resting load through a swing.
    fn check_crutches(&mut self, input: &SupervisorInput, f: &mut Findings) {
        let sum = checks::crutch_sum_n(input);
        let swinging = input.step_in_progress && input.swing_leg.is_some();
        let cfg = &self.cfg;
        if let Some(above) = self
            .crutch_idle
            .update(&cfg.crutch_idle, sum, swinging, cfg.dt_s)
        {
            f.raise(FaultCode::PilotNotBalancing, NO_CHANNEL, above);
        }
    }

    fn check_forces(&mut self, input: &SupervisorInput, f: &mut Findings) {
        let cfg = &self.cfg;
        for i in 0..FORCES {
            let ch = i as u8;
            let (Some(sense), Some(track)) = (input.forces.get(i), self.forces.get_mut(i)) else {
                continue;
            };
            let mut immediate = false;
            let bad = match sense.status {
                ForceStatus::BusError => Some(FaultCode::ForceBusError),
                ForceStatus::Open => Some(FaultCode::ForceOpen),
                ForceStatus::Shorted => Some(FaultCode::ForceShorted),
                ForceStatus::OutOfRange => Some(FaultCode::ForceOutOfRange),
                ForceStatus::Ok => {
                    if !sense.newtons.is_finite() {
                        immediate = true;
                        Some(FaultCode::ForceOutOfRange)
                    } else if cfg.force_min_n <= sense.newtons && sense.newtons <= cfg.force_max_n {
                        None
                    } else {
                        Some(FaultCode::ForceOutOfRange)
                    }
                }
            };
            track
                .window
                .push(bad.is_some(), cfg.force_debounce.window_ticks);
            if bad.is_some() {
                track.last_bad = bad;
            }
            let n = track.window.count();
            let tripped = if n >= u32::from(cfg.force_debounce.count) {
                track.last_bad
            } else {
                None
            };
            if immediate {
                f.raise(FaultCode::ForceOutOfRange, ch, sense.newtons);
            }
            if let Some(code) = tripped {
                let value = if bad.is_some() {
                    sense.newtons
                } else {
                    n as f32
                };
                f.raise(code, ch, value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn supervisor() -> Supervisor {
        Supervisor::new(SupervisorConfig::paper()).unwrap()
    }

    /// A tick's facts whose left-foot sensor reads Ok but not finite:
    /// 0x0304 at once (the windowed checks' force rule).
    fn bad_force(tick: u32) -> WindowedJob {
        let mut job = WindowedJob::default();
        job.input.tick = tick;
        job.input.forces[0] = ForceSense {
            status: ForceStatus::Ok,
            newtons: f32::NAN,
        };
        job
    }

    #[test]
    fn findings_latch_at_the_next_check_with_their_own_tick_in_the_log() {
        let mut sup = supervisor();
        let job = bad_force(7);
        let found = sup.run_windowed(&job);
        assert!(found.contains(FaultCode::ForceOutOfRange));
        let mut now = job;
        now.input.tick = 8;
        now.input.forces[0].newtons = 100.0;
        let v = sup.check_after(&now.input, &now.frames, &found, false);
        assert!(v.new.contains(FaultCode::ForceOutOfRange));
        // Logged with the tick of the facts it was found in.
        let record = sup
            .log()
            .find(|r| r.code == FaultCode::ForceOutOfRange)
            .copied()
            .unwrap();
        assert_eq!(record.tick, 7);
    }

    #[test]
    fn overflowed_findings_latch_0x0608_and_a_late_answer_is_a_missed_deadline() {
        let mut sup = supervisor();
        let job = bad_force(1);
        let one = sup.run_windowed(&job);
        let mut many = one;
        for _ in 0..MAX_RAISES {
            many.merge(&one);
        }
        assert!(many.overflowed());
        let v = sup.check_after(&job.input, &job.frames, &many, false);
        assert!(v.new.contains(FaultCode::ChecksLate));
        assert_eq!(v.reaction, crate::faults::Reaction::SafeHold);
        // Late answers count as deadline misses: the third latches 0x0601.
        let mut sup = supervisor();
        let quiet = WindowedJob::default();
        for n in 1..=3 {
            let v = sup.check_after(&quiet.input, &quiet.frames, &Findings::NONE, true);
            assert_eq!(sup.deadline_misses(), n);
            assert_eq!(v.latched.contains(FaultCode::DeadlineMissed), n == 3);
        }
    }
}

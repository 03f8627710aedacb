//! The checks of one tick, one method per group of the fault table
//! (operator inputs, deadline, motors, joints, ankles, force sensors); each
//! raises the codes `docs/safety.md` lists for it.

use super::*;

/// Both crutches' load, N; NaN unless both sensors read.
fn crutch_sum_n(input: &SupervisorInput) -> f32 {
    use crate::layout::force::{LEFT_CRUTCH, RIGHT_CRUTCH};
    let read = |c: usize| match input.forces.get(c) {
        Some(f) if f.status == ForceStatus::Ok => f.newtons,
        _ => f32::NAN,
    };
    read(LEFT_CRUTCH) + read(RIGHT_CRUTCH)
}

/// `|x| ≤ limit`; false for NaN, so `!within(..)` trips on NaN.
fn within(x: f32, limit: f32) -> bool {
    x.abs() <= limit
}

impl Supervisor {
    pub(super) fn check_operator_inputs(&mut self, input: &SupervisorInput, t: &mut Tick) {
        if input.e_stop_pressed {
            self.latch
                .raise(t, FaultCode::EStopPressed, NO_CHANNEL, 1.0);
        }
        if input.e_stop_read_error {
            self.latch
                .raise(t, FaultCode::EStopInputFault, NO_CHANNEL, 1.0);
        }
        if input.button_input_fault {
            self.latch
                .raise(t, FaultCode::ButtonInputFault, NO_CHANNEL, 1.0);
        }
    }

    pub(super) fn check_deadline(&mut self, input: &SupervisorInput, t: &mut Tick) {
        if input.deadline_missed {
            self.deadline_misses_total = self.deadline_misses_total.saturating_add(1);
            if let Some(slot) = self.misses.get_mut(usize::from(self.miss_next)) {
                *slot = self.calls;
            }
            self.miss_next = (self.miss_next + 1) % MAX_DEADLINE_MISSES;
        }
        if self.deadline_misses_total == 0 {
            return;
        }
        let now = self.calls;
        let window = self.cfg.deadline_window_ticks;
        // The newest miss outside the window: none to count (most ticks).
        let newest = usize::from((self.miss_next + MAX_DEADLINE_MISSES - 1) % MAX_DEADLINE_MISSES);
        if self
            .misses
            .get(newest)
            .is_none_or(|&at| now.wrapping_sub(at) >= window)
        {
            return;
        }
        let held = self
            .deadline_misses_total
            .min(u32::from(MAX_DEADLINE_MISSES)) as usize;
        let recent = self
            .misses
            .iter()
            .take(held)
            .filter(|&&at| now.wrapping_sub(at) < window)
            .count();
        if recent >= usize::from(self.cfg.deadline_miss_count) {
            self.latch
                .raise(t, FaultCode::DeadlineMissed, NO_CHANNEL, recent as f32);
        }
    }

    pub(super) fn check_motors(&mut self, input: &SupervisorInput, t: &mut Tick) {
        let limit_ticks = self.cfg.saturation_ticks;
        for (i, m) in input.motors.iter().enumerate() {
            let ch = i as u8;
            let finite = m.commanded_nm.is_finite() && m.applied_nm.is_finite();
            // `!(limit > 0)` so NaN trips; infinity is caught by is_finite.
            let limit_ok = m.limit_nm.is_finite() && m.limit_nm > 0.0;
            if !(finite && limit_ok) {
                let bad = [m.commanded_nm, m.applied_nm, m.limit_nm]
                    .into_iter()
                    .find(|v| !v.is_finite())
                    .unwrap_or(m.limit_nm);
                self.latch.raise(t, FaultCode::ControlValueInvalid, ch, bad);
            }
            let Some(track) = self.joints.get_mut(i) else {
                continue;
            };
            if m.commanded_nm.abs() < m.limit_nm {
                track.saturated_ticks = 0;
            } else {
                track.saturated_ticks = track.saturated_ticks.saturating_add(1);
            }
            let saturated = track.saturated_ticks >= limit_ticks;
            if saturated {
                self.latch
                    .raise(t, FaultCode::MotorSaturated, ch, m.commanded_nm);
            }
            if m.thermal_fault {
                self.latch
                    .raise(t, FaultCode::MotorThermal, ch, m.applied_nm);
            }
            if m.output_fault {
                self.latch
                    .raise(t, FaultCode::MotorOutputStage, ch, m.commanded_nm);
            }
        }
    }

    pub(super) fn check_joints(
        &mut self,
        input: &SupervisorInput,
        frames: &[EncoderFrame; ENCODERS],
        t: &mut Tick,
    ) {
        let cfg = &self.cfg;
        for i in 0..JOINTS {
            let ch = i as u8;
            let Some(taken) = frames.get(i) else {
                continue;
            };
            let invalid = taken.invalid();
            let (Some(&reference), Some(range), Some(&vmax), Some(motor)) = (
                input.joint_reference_rad.get(i),
                cfg.joint_range.get(i),
                cfg.velocity_limit_rad_s.get(i),
                input.motors.get(i),
            ) else {
                continue;
            };
            if !reference.is_finite() {
                self.latch
                    .raise(t, FaultCode::ControlValueInvalid, ch, reference);
            }
            let reference_speed = match self.previous_reference_rad.as_ref().and_then(|p| p.get(i))
            {
                Some(&previous) => (reference - previous).abs() / cfg.dt_s,
                None => 0.0,
            };
            // NaN speed or command counts as driven.
            let driven = !(reference_speed < cfg.frozen_reference_speed_rad_s
                && motor.commanded_nm.abs() < cfg.frozen_command_fraction * motor.limit_nm);

            let Some(track) = self.joints.get_mut(i) else {
                continue;
            };
            // Raised in this order (the log's order within a tick).
            let latch = &mut self.latch;
            if let Some(v) = invalid {
                latch.raise(t, FaultCode::EncoderInvalidValue, ch, v);
            }
            if let Some((angle_rad, delta, previous_angle_rad)) = taken.accepted() {
                if !range.contains(angle_rad) {
                    latch.raise(t, FaultCode::JointPositionLimit, ch, angle_rad);
                }
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
                let trusted = !latch.angle_lost.get(i).copied().unwrap_or(true);
                let error = angle_rad - reference;
                if !trusted || error.abs() <= cfg.tracking_error_limit_rad {
                    track.tracking_ticks = 0;
                } else {
                    track.tracking_ticks = track.tracking_ticks.saturating_add(1);
                }
                if track.tracking_ticks >= cfg.tracking_error_ticks {
                    latch.raise(t, FaultCode::TrackingError, ch, error);
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
                    if within(d, o.limit_nm) {
                        track.residual.over_ticks = 0;
                    } else {
                        track.residual.over_ticks = track.residual.over_ticks.saturating_add(1);
                    }
                    if track.residual.over_ticks >= o.ticks
                        && latch.raise_on_joint(t, FaultCode::MotorResponse, i, d)
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
                self.encoder_offsets |= track.encoder.offset_counts != 0;
            }
            // Conditions that persist while frames are rejected.
            if track.velocity_valid && !within(track.velocity_rad_s, vmax) {
                latch.raise(t, FaultCode::JointVelocityLimit, ch, track.velocity_rad_s);
            }
            if track.frozen_ticks >= cfg.frozen_ticks {
                latch.raise(t, FaultCode::EncoderFrozen, ch, track.frozen_ticks as f32);
            }
            if let Some((code, n)) = track.encoder.tripped(cfg.encoder_debounce) {
                latch.raise(t, code, ch, n as f32);
            }
        }
    }

    pub(super) fn check_ankles(
        &mut self,
        input: &SupervisorInput,
        frames: &[EncoderFrame; ENCODERS],
        t: &mut Tick,
    ) {
        let cfg = &self.cfg;
        // Both ankles' balance check reads the crutches: summed once.
        let crutches = crutch_sum_n(input);
        for i in 0..ANKLES {
            let ch = i as u8;
            let Some(taken) = frames.get(JOINTS + i) else {
                continue;
            };
            let invalid = taken.invalid();
            let (Some(range), Some(track)) = (cfg.ankle_range.get(i), self.ankles.get_mut(i))
            else {
                continue;
            };
            let tripped = track.tripped(cfg.encoder_debounce);
            if let Some(v) = invalid {
                self.latch.raise(t, FaultCode::AnkleEncoder, ch, v);
            }
            if let Some((_, n)) = tripped {
                self.latch.raise(t, FaultCode::AnkleEncoder, ch, n as f32);
            }
            if let Some((angle_rad, delta, _)) = taken.accepted() {
                if !range.contains(angle_rad) {
                    self.latch
                        .raise(t, FaultCode::AnklePositionLimit, ch, angle_rad);
                }
                // Resting on the stop while the plan is well below it (a
                // NaN plan never counts; a rejected frame neither counts
                // nor resets).
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
                        self.latch
                            .raise(t, FaultCode::UnplannedHeelOff, ch, angle_rad);
                    }
                }
                // The pilot losing balance: the error from the plan
                // growing away from it. Not on the stop: with the heel up
                // the encoder no longer sees the shank. With both feet
                // down, only a foot planned flat (a trailing foot's plan
                // past the stop is its shank's angle, heel up); in a
                // swing, a plan past the stop is the stop for the reading,
                // which cannot go further.
                let swing = input.swing_leg.is_some();
                let watched = plan.is_finite() && (swing || plan <= cfg.heel_off_rad);
                if let Some(track) = self.balance.get_mut(i) {
                    if watched && !on_stop {
                        let sample = balance::BalanceSample {
                            angle_rad,
                            plan_rad: plan.min(cfg.heel_off_rad),
                            swing,
                            crutches_n: crutches,
                            elapsed_ticks: delta.map(|(_, n)| n),
                        };
                        if let Some(e) = track.update(&cfg.balance, &sample, cfg.dt_s) {
                            let code = if e > 0.0 {
                                FaultCode::PilotFallingForward
                            } else {
                                FaultCode::PilotFallingBack
                            };
                            self.latch.raise(t, code, ch, e);
                        }
                    } else {
                        track.restart();
                    }
                }
                // Only a toe pushed up by the ground holds an ankle on its
                // dorsiflexion stop: in the air its spring takes it off
                // within tens of milliseconds. Counts that stay on the stop,
                // unchanged, with the foot in the air are an encoder stuck
                // where the foot left the ground (read as a lean, it set
                // a stair descent's landing on the stop and dropped the
                // pilot); control stops taking them until they move.
                let in_air = input.airborne_leg.is_some_and(|leg| leg.ankle() == i);
                let moved = delta.is_some_and(|(counts, _)| counts != 0);
                if let (Some(n), Some(stuck)) = (
                    self.stuck_in_air_ticks.get_mut(i),
                    self.ankle_stuck.get_mut(i),
                ) {
                    *n = if in_air && on_stop && delta.is_some() && !moved {
                        n.saturating_add(1)
                    } else {
                        0
                    };
                    if moved {
                        *stuck = false;
                    }
                    if *n >= cfg.frozen_ticks {
                        *stuck = true;
                        self.latch.raise(t, FaultCode::AnkleEncoder, ch, *n as f32);
                    }
                }
                // A stance ankle in a swing turns with its shank: counts
                // that do not change once while the plan turns it by
                // `frozen_ankle_plan_rad` are a frozen encoder (its stale
                // reading set the posture a walk's step played on with
                // past its table's end, and the residual braked the
                // stance knee). Off the stop only: a heel up rests there;
                // and within one swing, whose plan is continuous.
                let stance_in_swing = input.swing_leg.is_some_and(|leg| leg.other().ankle() == i);
                let planned = stance_in_swing && plan.is_finite() && !on_stop;
                if let (Some(from), Some(stuck)) = (
                    self.plan_since_moved.get_mut(i),
                    self.ankle_stuck.get_mut(i),
                ) {
                    if !planned {
                        *from = f32::NAN;
                    } else if moved || from.is_nan() {
                        *from = plan;
                    } else if delta.is_some() && (plan - *from).abs() >= cfg.frozen_ankle_plan_rad {
                        *stuck = true;
                        self.latch
                            .raise(t, FaultCode::AnkleEncoder, ch, plan - *from);
                    }
                }
            } else {
                self.encoder_offsets |= track.offset_counts != 0;
            }
        }
    }

    pub(super) fn check_forces(&mut self, input: &SupervisorInput, t: &mut Tick) {
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
                self.latch
                    .raise(t, FaultCode::ForceOutOfRange, ch, sense.newtons);
            }
            if let Some(code) = tripped {
                let value = if bad.is_some() {
                    sense.newtons
                } else {
                    n as f32
                };
                self.latch.raise(t, code, ch, value);
            }
        }
    }
}

//! The tick's own checks, one method per group of the fault table
//! (operator inputs, deadline, motors, the encoders' frames, the pilot's
//! balance): what one tick's facts show, and the balance, which must not
//! wait a tick. Each raises the codes `docs/safety.md` lists for it;
//! the rules that judge a channel over many ticks are the windowed checks
//! (`windowed.rs`).

use super::*;

impl<W> Supervisor<W> {
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

    /// `missed`: the last tick overran, or the windowed checks had not
    /// answered its facts (which only a tick that left the task no time
    /// causes: one miss).
    pub(super) fn check_deadline(&mut self, missed: bool, t: &mut Tick) {
        if missed {
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
            let (Some(taken), Some(&reference), Some(range), Some(track)) = (
                frames.get(i),
                input.joint_reference_rad.get(i),
                cfg.joint_range.get(i),
                self.joints.get(i),
            ) else {
                continue;
            };
            if !reference.is_finite() {
                self.latch
                    .raise(t, FaultCode::ControlValueInvalid, ch, reference);
            }
            if let Some(v) = taken.invalid() {
                self.latch.raise(t, FaultCode::EncoderInvalidValue, ch, v);
            }
            match taken.accepted() {
                Some((angle_rad, _, _)) => {
                    if !range.contains(angle_rad) {
                        self.latch
                            .raise(t, FaultCode::JointPositionLimit, ch, angle_rad);
                    }
                }
                None => self.encoder_offsets |= track.encoder.offset_counts != 0,
            }
            if let Some((code, n)) = track.encoder.tripped(cfg.encoder_debounce) {
                self.latch.raise(t, code, ch, n as f32);
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
            let (Some(taken), Some(range), Some(track)) = (
                frames.get(JOINTS + i),
                cfg.ankle_range.get(i),
                self.ankles.get(i),
            ) else {
                continue;
            };
            if let Some(v) = taken.invalid() {
                self.latch.raise(t, FaultCode::AnkleEncoder, ch, v);
            }
            if let Some((_, n)) = track.tripped(cfg.encoder_debounce) {
                self.latch.raise(t, FaultCode::AnkleEncoder, ch, n as f32);
            }
            let Some((angle_rad, delta, _)) = taken.accepted() else {
                self.encoder_offsets |= track.offset_counts != 0;
                continue;
            };
            if !range.contains(angle_rad) {
                self.latch
                    .raise(t, FaultCode::AnklePositionLimit, ch, angle_rad);
            }
            let plan = input.ankle_plan_rad.get(i).copied().unwrap_or(f32::NAN);
            let on_stop = angle_rad >= cfg.heel_off_rad - cfg.heel_off_reading_tolerance_rad;
            // The pilot losing balance: the error from the plan growing
            // away from it. Not on the stop: with the heel up the encoder
            // no longer sees the shank. With both feet down, only a foot
            // planned flat (a trailing foot's plan past the stop is its
            // shank's angle, heel up); in a swing, a plan past the stop is
            // the stop for the reading, which cannot go further.
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
        }
    }
}

/// Both crutches' load, N; NaN unless both sensors read.
pub(super) fn crutch_sum_n(input: &SupervisorInput) -> f32 {
    use crate::layout::force::{LEFT_CRUTCH, RIGHT_CRUTCH};
    let read = |c: usize| match input.forces.get(c) {
        Some(f) if f.status == ForceStatus::Ok => f.newtons,
        _ => f32::NAN,
    };
    read(LEFT_CRUTCH) + read(RIGHT_CRUTCH)
}

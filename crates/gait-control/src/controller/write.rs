//! *write*: the motors enabled only as the verdict allows (every one for
//! its reaction, one by one for the braked joints) and the commands
//! written; indicators; the crutch-load metric and the re-planner's
//! faults in the log; the tick's report.

use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;

use crate::drivers::motor;
use crate::faults::{FaultCode, Reaction};
use crate::layout::force;
use crate::position_loop::JointLoop;
use crate::posture::JOINTS;
use crate::replan::{ReplanOutcome, ReplanResult};
use crate::sequencer::SeqEvent;
use crate::supervisor::Verdict;

use super::act::Actuation;
use super::sense::Senses;
use super::{Controller, Hardware, Planned, TickReport};

impl Controller<'_> {
    /// Stage 5: motors (enabled only as the verdict allows), indicators,
    /// the crutch-load metric; the tick's report.
    #[inline(always)]
    pub(super) fn write<ENC, ADC, PWM, DIR, EN, IN, OUT, PwmE, PinE>(
        &mut self,
        hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
        s: &Senses,
        plan: &Planned,
        a: &Actuation,
        verdict: &Verdict,
    ) -> TickReport
    where
        PWM: SetDutyCycle<Error = PwmE>,
        DIR: OutputPin<Error = PinE>,
        EN: OutputPin<Error = PinE>,
        OUT: OutputPin,
    {
        let written = self.write_motors(hw, &a.command_nm, verdict);
        let op = &plan.operator;
        let fb = op.feedback;
        let _ = hw.gait_led.update(fb.gait_led, op.tick);
        let _ = hw.fault_led.update(fb.fault_led, op.tick);
        let _ = hw.buzzer.update(fb.buzzer, op.tick);
        self.log_events(s, plan, verdict.reaction);
        TickReport {
            tick: self.tick,
            joints_rad: s.sensed.joints_rad,
            reference_rad: plan.reference.angle_rad,
            feedforward_nm: a.feedforward_nm,
            command_nm: written,
            forces_n: s.forces_n,
            phase: self.seq_status.phase,
            reaction: verdict.reaction,
            faults: verdict.latched,
            motors_enabled: self.motors_enabled,
        }
    }

    /// Enables or disables the motors as the verdict allows (every one
    /// for its reaction, one by one for the braked joints) and writes the
    /// commands; returns what the drivers applied (0 when disabled).
    #[inline(always)]
    fn write_motors<ENC, ADC, PWM, DIR, EN, IN, OUT, PwmE, PinE>(
        &mut self,
        hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
        command: &[f32; JOINTS],
        verdict: &Verdict,
    ) -> [f32; JOINTS]
    where
        PWM: SetDutyCycle<Error = PwmE>,
        DIR: OutputPin<Error = PinE>,
        EN: OutputPin<Error = PinE>,
    {
        let enable = verdict.reaction < Reaction::DisableMotors;
        if enable && !self.motors_enabled {
            let mut all_ok = true;
            for (m, &braked) in hw.motors.iter_mut().zip(&verdict.braked_joints) {
                if !braked {
                    all_ok &= m.enable().is_ok();
                }
            }
            self.motors_enabled = all_ok;
            self.loops.iter_mut().for_each(JointLoop::reset);
        } else if !enable && self.motors_enabled {
            for m in hw.motors.iter_mut() {
                let _ = m.disable();
            }
            self.motors_enabled = false;
        }
        let mut written = [0.0f32; JOINTS];
        for (i, m) in hw.motors.iter_mut().enumerate() {
            let braked = verdict.braked_joints.get(i).copied().unwrap_or(false);
            if let Some(was) = self.braked.get_mut(i) {
                if braked && !*was {
                    let _ = m.disable();
                } else if !braked && *was && self.motors_enabled {
                    // Released by a reset: back on, from a fresh loop.
                    let _ = m.enable();
                    if let Some(lp) = self.loops.get_mut(i) {
                        lp.reset();
                    }
                }
                *was = braked;
            }
            let on = self.motors_enabled && !braked;
            let cmd = if on {
                command.get(i).copied().unwrap_or(0.0)
            } else {
                0.0
            };
            let sense = self.motor_sense.get_mut(i);
            let result = m.update(cmd);
            if let Some(s) = sense {
                s.enabled = on && m.at_full_authority();
                s.thermal_fault = matches!(result, Err(motor::Error::Thermal));
                s.output_fault = matches!(
                    result,
                    Err(motor::Error::OutputFault | motor::Error::Pwm(_) | motor::Error::Pin(_))
                );
                s.applied_nm = result.as_ref().map_or(0.0, |r| r.applied_nm);
                if let Some(w) = written.get_mut(i) {
                    *w = s.applied_nm;
                }
            }
        }
        written
    }

    /// A re-plan late or refused: the sequencer played the table; the
    /// code goes into the log (once a step at most: kept off the tick's
    /// usual path).
    #[cold]
    #[inline(never)]
    fn log_replan(&mut self, result: ReplanResult) {
        let code = match result {
            ReplanResult::Late => FaultCode::ReplanLate,
            ReplanResult::Answered(ReplanOutcome::Refused) => FaultCode::ReplanRefused,
            ReplanResult::Answered(ReplanOutcome::Replanned | ReplanOutcome::Declined) => return,
        };
        self.supervisor.log_played_table(self.tick, code);
    }

    /// The crutch-load metric (a step's log opens with its swing and closes
    /// when the gait stops or a fatal reaction ends it), and the
    /// re-planner's faults, whose table the sequencer played this tick.
    #[inline(always)]
    fn log_events(&mut self, s: &Senses, plan: &Planned, reaction: Reaction) {
        for ev in plan.reference.events.iter() {
            match ev {
                SeqEvent::Replan(result) => self.log_replan(result),
                SeqEvent::SwingStarted(..) => {
                    self.crutch.begin_step();
                }
                SeqEvent::Stopped => {
                    self.crutch.end_step();
                }
                _ => {}
            }
        }
        let crutches = force::CRUTCHES.map(|i| s.forces_n.get(i).copied().unwrap_or(f32::NAN));
        self.crutch.sample(crutches[0], crutches[1], self.cfg.dt_s);
        if self.seq_status.at_rest()
            && self.crutch.current().is_some()
            && reaction >= Reaction::SafeHold
        {
            self.crutch.end_step();
        }
    }
}

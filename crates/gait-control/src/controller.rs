//! The 1 kHz control tick, top to bottom:
//!
//! 1. **sense** — read every encoder, force sensor, button and the e-stop;
//!    decode, calibrate, check (a failed read becomes a status, never a
//!    panic, and the last good angle is kept for control);
//! 2. **plan** — the operator scheme turns button events into requests; the
//!    sequencer advances the gait and yields the reference;
//! 3. **act** — per joint, PID plus the model's inverse-dynamics feed-forward
//!    along the reference (gait-core, f32);
//! 4. **guard** — the supervisor checks every fact and decides a reaction
//!    before anything is written;
//! 5. **write** — motor commands (only after the guard), indicators, the
//!    crutch-load metric.
//!
//! Bounded: fixed numbers of reads, one table interpolation (three lookups
//! for the rates), one inverse-dynamics evaluation, no allocation, no wait.

use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;
use embedded_hal::spi::SpiDevice;
use gait_core::foot::{self, StanceFoot};
use gait_core::kinematics::joint_torques;
use gait_core::model::GRAVITY_M_S2;
use gait_core::{BodyModel, LINKS};

use crate::crutch_load::CrutchLoad;
use crate::drivers::as5048a::{self, As5048a};
use crate::drivers::buttons::Button;
use crate::drivers::mcp3208::{self, ForceCalibration, ForceChannels, ForceFault, Mcp3208};
use crate::drivers::motor::{self, Motor};
use crate::drivers::status::Indicator;
use crate::faults::{FaultSet, Reaction};
use crate::operator::{ControllerStatus, Input, Operator, OperatorConfig, Request};
use crate::position_loop::{JointGains, JointLoop, Setpoint};
use crate::posture::{JOINTS, Side, joint_torques_from_theta_torques, phi_from_joints};
use crate::sequencer::{GaitTables, Phase, Sensed, SeqEvent, Sequencer, SequencerConfig};
use crate::supervisor::{
    EncoderSense, EncoderStatus, ForceSense, ForceStatus, MotorSense, Supervisor, SupervisorInput,
    Verdict,
};

/// Encoders: the four joints (joint order), then left and right ankle.
pub const ENCODERS: usize = JOINTS + 2;
/// Force sensors: left foot, right foot, left crutch, right crutch.
pub const FORCES: usize = 4;
/// Points of each force sensor's calibration table.
pub const FORCE_CAL_POINTS: usize = 4;

/// Everything the controller drives, as embedded-hal 1.0 drivers. The board
/// builds it (one SPI device per chip select, erased pin types).
pub struct Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT> {
    /// Joint encoders (joint order), then left and right ankle.
    pub encoders: [As5048a<ENC>; ENCODERS],
    /// The force-sensor ADC.
    pub adc: Mcp3208<ADC>,
    /// Which ADC channel each force sensor is on.
    pub force_channels: ForceChannels,
    /// Joint motors (joint order).
    pub motors: [Motor<PWM, DIR, EN>; JOINTS],
    /// MODE button.
    pub mode: Button<IN>,
    /// GO button.
    pub go: Button<IN>,
    /// External emergency-stop input.
    pub e_stop: IN,
    /// Gait LED.
    pub gait_led: Indicator<OUT>,
    /// Fault LED.
    pub fault_led: Indicator<OUT>,
    /// Buzzer.
    pub buzzer: Indicator<OUT>,
}

/// The controller's configuration (validated once in [`Controller::new`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControllerConfig {
    /// Tick period, s.
    pub dt_s: f32,
    /// Per-joint loop gains and limits (joint order).
    pub gains: [JointGains; JOINTS],
    /// Gait execution thresholds and timings.
    pub sequencer: SequencerConfig,
    /// Force calibrations: left foot, right foot, left crutch, right crutch.
    pub force_calibration: [ForceCalibration<FORCE_CAL_POINTS>; FORCES],
    /// `true` when the e-stop input reads high while pressed.
    pub e_stop_active_high: bool,
    /// Cut-off of the joint-rate low-pass filter, Hz.
    pub rate_filter_hz: f32,
    /// Largest joint rate that still counts as standing still, rad/s.
    pub still_rate_rad_s: f32,
    /// The model used for the feed-forward.
    pub model: BodyModel<f32>,
}

/// Why a configuration was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// Tick period, filter or thresholds not positive and finite.
    BadTiming,
    /// A joint's gains are invalid.
    BadGains(usize),
}

/// What one tick did (for logs, tests and the simulator's plots).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickReport {
    /// Tick number.
    pub tick: u32,
    /// Measured joint angles (last good), rad.
    pub joints_rad: [f32; JOINTS],
    /// Reference joint angles, rad.
    pub reference_rad: [f32; JOINTS],
    /// Feed-forward torques, N·m.
    pub feedforward_nm: [f32; JOINTS],
    /// Commands written (0 when disabled), N·m.
    pub command_nm: [f32; JOINTS],
    /// Calibrated forces (NaN if faulted): left foot, right foot, left
    /// crutch, right crutch, N.
    pub forces_n: [f32; FORCES],
    /// Sequencer phase after this tick.
    pub phase: Phase,
    /// The supervisor's verdict.
    pub reaction: Reaction,
    /// Latched faults.
    pub faults: FaultSet,
    /// Motors enabled after this tick.
    pub motors_enabled: bool,
}

/// The controller state: everything between two ticks.
pub struct Controller<'t> {
    cfg: ControllerConfig,
    seq: Sequencer<'t>,
    loops: [JointLoop; JOINTS],
    operator: Operator,
    supervisor: Supervisor,
    crutch: CrutchLoad,
    last_raw: [u16; ENCODERS],
    last_angle: [f32; ENCODERS],
    /// What the gait plans for each ankle this tick (left, right), rad:
    /// the shank's lean as a stance shank, NaN where nothing is planned
    /// ([`Controller::plan_ankles`]). With the heel up (toe rocker) the
    /// ankle encoder reads its stop, not the lean: the feed-forward's
    /// static posture then uses the plan ([`Controller::stance_phi1`]), and
    /// the supervisor flags a heel-off the plan does not have (0x0105).
    ankle_plan: [f32; 2],
    rate: [f32; JOINTS],
    motor_sense: [MotorSense; JOINTS],
    motors_enabled: bool,
    primed: bool,
    /// A clinician reset waiting for the supervisor to see cleared motor
    /// flags: (safe posture when asked, ticks still to wait).
    pending_reset: Option<(bool, u8)>,
    /// Integral of the other foot's load error in double support, N.
    other_foot_integral_n: f32,
    tick: u32,
}

impl<'t> Controller<'t> {
    /// Builds the controller. Tables must already be verified
    /// ([`gait_core::tables::GaitTable::parse`]); a gait whose table is
    /// missing cannot be started (and should not be in `operator.allowed`).
    pub fn new(
        cfg: ControllerConfig,
        tables: GaitTables<'t>,
        operator: OperatorConfig,
        supervisor: Supervisor,
    ) -> Result<Self, ConfigError> {
        let timing = [cfg.dt_s, cfg.rate_filter_hz, cfg.still_rate_rad_s];
        if !timing.iter().all(|v| v.is_finite() && *v > 0.0) {
            return Err(ConfigError::BadTiming);
        }
        for (i, g) in cfg.gains.iter().enumerate() {
            if !g.is_valid() {
                return Err(ConfigError::BadGains(i));
            }
        }
        let idle = MotorSense {
            commanded_nm: 0.0,
            applied_nm: 0.0,
            limit_nm: 0.0,
            thermal_fault: false,
            output_fault: false,
        };
        Ok(Self {
            cfg,
            seq: Sequencer::new(cfg.sequencer, tables, [0.0; JOINTS]).with_model(cfg.model),
            loops: [JointLoop::default(); JOINTS],
            operator: Operator::new(operator),
            supervisor,
            crutch: CrutchLoad::new(),
            last_raw: [0; ENCODERS],
            last_angle: [0.0; ENCODERS],
            ankle_plan: [f32::NAN; 2],
            rate: [0.0; JOINTS],
            motor_sense: [idle; JOINTS],
            motors_enabled: false,
            primed: false,
            pending_reset: None,
            other_foot_integral_n: 0.0,
            tick: 0,
        })
    }

    /// The configuration it was built with.
    pub fn config(&self) -> &ControllerConfig {
        &self.cfg
    }

    /// The gait the next start would play: the one being played while a
    /// gait runs, else the clinician's selection.
    pub fn planned_gait(&self) -> crate::operator::Gait {
        if self.seq.walking() {
            self.seq.gait()
        } else {
            self.operator.selected()
        }
    }

    /// The sequencer (phase, reference).
    pub fn sequencer(&self) -> &Sequencer<'t> {
        &self.seq
    }

    /// The supervisor (latched faults, post-mortem log).
    pub fn supervisor(&self) -> &Supervisor {
        &self.supervisor
    }

    /// The crutch-load log.
    pub fn crutch_load(&self) -> &CrutchLoad {
        &self.crutch
    }

    /// One control tick. `deadline_missed`: the previous tick overran its
    /// budget (measured by the board's timer).
    pub fn tick<ENC, ADC, PWM, DIR, EN, IN, OUT, PwmE, PinE>(
        &mut self,
        hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
        deadline_missed: bool,
    ) -> TickReport
    where
        ENC: SpiDevice<u8>,
        ADC: SpiDevice<u8>,
        PWM: SetDutyCycle<Error = PwmE>,
        DIR: OutputPin<Error = PinE>,
        EN: OutputPin<Error = PinE>,
        IN: InputPin,
        OUT: OutputPin,
    {
        let dt = self.cfg.dt_s;
        self.tick = self.tick.wrapping_add(1);

        // 1. sense
        let encoders = self.read_encoders(hw);
        let forces = self.read_forces(hw);
        let mode = hw.mode.tick();
        let go = hw.go.tick();
        let (e_stop_pressed, e_stop_read_error) = match hw.e_stop.is_high() {
            Ok(high) => (high == self.cfg.e_stop_active_high, false),
            Err(_) => (true, true),
        };
        let joints = self.joint_angles();
        let forces_n = forces.map(|f| f.newtons);
        let sensed = Sensed {
            joints_rad: joints,
            feet_n: [forces_n[0], forces_n[1]],
            crutches_n: [forces_n[2], forces_n[3]],
            // This tick's readings (NaN unless the encoder answered well):
            // a held last-good value must not count as "ready".
            ankles_rad: [JOINTS, JOINTS + 1]
                .map(|i| encoders.get(i).map_or(f32::NAN, |e| e.angle_rad)),
        };
        if !self.primed {
            // First tick: hold the posture the device is in.
            self.seq = Sequencer::new(self.cfg.sequencer, *self.seq.tables(), joints)
                .with_model(self.cfg.model);
            self.primed = true;
        }

        // 2. plan
        let status = ControllerStatus {
            walking: self.seq.walking(),
            step_in_progress: self.seq.step_in_progress(),
            safe_posture: self.safe_posture(&sensed),
            faulted: !self.supervisor.latched().is_empty(),
        };
        let op = self.operator.tick(&Input { mode, go, status });
        match op.request {
            Some(Request::Start(gait)) => {
                self.seq.request_start(gait, &sensed);
            }
            Some(Request::StopAfterStep) => self.seq.request_stop(),
            Some(Request::ResetFaults) => {
                // Motor drivers latch their own faults: clear them first and
                // let one supervisor check see the cleared flags, then ask.
                for m in hw.motors.iter_mut() {
                    let _ = m.reset_fault();
                }
                // The cleared flags reach the supervisor's check at the end
                // of the next tick; its reset decision uses the last check.
                self.pending_reset = Some((status.safe_posture, 2));
            }
            None => match self.pending_reset {
                Some((safe, 0)) => {
                    self.pending_reset = None;
                    if safe && status.safe_posture && self.supervisor.request_reset(true).is_ok() {
                        self.seq.reset_after_faults();
                        self.loops.iter_mut().for_each(JointLoop::reset);
                    }
                }
                Some((safe, n)) => self.pending_reset = Some((safe, n - 1)),
                None => {}
            },
        }
        let crutch = &mut self.crutch;
        let plan = self.seq.update(&sensed, dt, &mut |ev| match ev {
            SeqEvent::SwingStarted(..) => {
                crutch.begin_step();
            }
            SeqEvent::Stopped => {
                crutch.end_step();
            }
            _ => {}
        });
        self.crutch.sample(forces_n[2], forces_n[3], dt);

        // 3. act
        self.ankle_plan = self.plan_ankles(plan.stance, plan.swing);
        let stance_ankle = self.stance_phi1(
            self.last_angle
                .get(JOINTS + plan.stance.ankle())
                .copied()
                .unwrap_or(0.0),
            plan.stance,
        );
        // What the other foot may carry: the share the plan gives it (the
        // whole body between steps; along a swing what the table plans for
        // its swing foot, so a table can shift the weight in double support
        // before it lifts the foot). Not from the foot's sensor during a
        // swing: a swing foot brushing the ground then switched the model's
        // load on and off, and the feed-forward bounced the foot. In a safe
        // hold, what the sensor reads (NaN: nothing).
        let weight = self.cfg.model.total_mass_kg() * GRAVITY_M_S2 as f32;
        let other_load = match plan.other_foot_share {
            Some(share) => weight * share.clamp(0.0, 1.0),
            None => {
                let other_foot = forces_n
                    .get(plan.stance.other().foot())
                    .copied()
                    .unwrap_or(f32::NAN);
                if other_foot.is_finite() {
                    other_foot.max(0.0).min(weight)
                } else {
                    0.0
                }
            }
        };
        let planned = self.feedforward(
            &plan.angle_rad,
            plan.swing,
            plan.stance,
            stance_ankle,
            other_load,
        );
        let mut feedforward = planned.torques_nm;
        // The other foot's load in double support: measured against the
        // plan, the difference pushed by the other leg (proportional and
        // integral), so that the share the plan gives it is what it carries.
        // Without it the share is a free internal force of the closed chain
        // that the legs' position loops and the pilot settle between them.
        let other_share = plan.other_foot_share.unwrap_or(0.0).clamp(0.0, 1.0);
        let measured = forces_n
            .get(plan.stance.other().foot())
            .copied()
            .unwrap_or(f32::NAN);
        if other_share > 0.0 && measured.is_finite() && self.motors_enabled {
            let error = planned.other_foot_n - measured;
            let integral = (self.other_foot_integral_n + OTHER_FOOT_KI_PER_S * error * dt)
                .clamp(-OTHER_FOOT_INTEGRAL_N, OTHER_FOOT_INTEGRAL_N);
            let push = |integral: f32| {
                other_share
                    * (OTHER_FOOT_KP * error + integral)
                        .clamp(-OTHER_FOOT_PUSH_N, OTHER_FOOT_PUSH_N)
            };
            // Anti-windup: the integral moves only while the other leg's
            // feed-forward stays inside its loops' limits.
            let within = |push_n: f32| {
                feedforward
                    .iter()
                    .zip(&planned.per_other_foot_newton)
                    .zip(&self.cfg.gains)
                    .enumerate()
                    .all(|(i, ((&f, &per), g))| {
                        !plan.stance.other().has_joint(i)
                            || (f + push_n * per).abs() <= g.torque_limit_nm
                    })
            };
            if within(push(integral)) {
                self.other_foot_integral_n = integral;
            }
            let push_n = push(self.other_foot_integral_n);
            for (i, (f, &per)) in feedforward
                .iter_mut()
                .zip(&planned.per_other_foot_newton)
                .enumerate()
            {
                if plan.stance.other().has_joint(i) {
                    *f += push_n * per;
                }
            }
        } else {
            self.other_foot_integral_n = 0.0;
        }
        let mut command = [0.0f32; JOINTS];
        let mut saturated = [false; JOINTS];
        // In double support the chain is closed: the stance leg and the
        // pilot set the posture, and the other leg's torques set how much
        // of the body its foot carries. Stiff position loops on both legs
        // would fight each other through the ground and decide that share
        // by their tracking errors; the other leg's loop is softened by the
        // share of the body its foot is planned to carry (stiff again as the
        // plan unloads it before a lift-off), so its feed-forward, which
        // plans that load, is what it applies.
        let carried = if other_share > 0.0 && weight > 0.0 {
            (planned.other_foot_n / weight).clamp(0.0, 1.0)
        } else {
            0.0
        };
        for i in 0..JOINTS {
            let (Some(lp), Some(g)) = (self.loops.get_mut(i), self.cfg.gains.get(i)) else {
                continue;
            };
            let softened;
            let g = if plan.stance.other().has_joint(i) && carried > 0.0 {
                softened = g.with_stiffness(1.0 - DOUBLE_SUPPORT_COMPLIANCE * carried);
                &softened
            } else {
                g
            };
            let sp = Setpoint {
                angle_rad: plan.angle_rad.get(i).copied().unwrap_or(f32::NAN),
                rate_rad_s: plan.rate_rad_s.get(i).copied().unwrap_or(0.0),
                feedforward_nm: feedforward.get(i).copied().unwrap_or(0.0),
            };
            let out = lp.update(
                g,
                &sp,
                joints.get(i).copied().unwrap_or(f32::NAN),
                self.rate.get(i).copied().unwrap_or(0.0),
                dt,
            );
            if let Some(c) = command.get_mut(i) {
                *c = out.command_nm;
            }
            if let Some(s) = saturated.get_mut(i) {
                *s = out.saturated;
            }
        }

        // 4. guard
        let mut motors = self.motor_sense;
        for ((m, &c), &g) in motors.iter_mut().zip(&command).zip(&self.cfg.gains) {
            m.commanded_nm = c;
            m.limit_nm = g.torque_limit_nm;
        }
        let ankle_plan_rad = self.ankle_plan;
        let input = SupervisorInput {
            tick: self.tick,
            joints: [0, 1, 2, 3].map(|i| encoders.get(i).copied().unwrap_or(BAD_ENCODER)),
            joint_reference_rad: plan.angle_rad,
            ankles: [4, 5].map(|i| encoders.get(i).copied().unwrap_or(BAD_ENCODER)),
            forces,
            motors,
            e_stop_pressed,
            e_stop_read_error,
            deadline_missed,
            step_in_progress: self.seq.step_in_progress(),
            button_input_fault: mode.input_fault || go.input_fault,
            ankle_plan_rad,
        };
        let verdict: Verdict = self.supervisor.check(&input);
        match verdict.reaction {
            Reaction::None => {}
            Reaction::FinishStepThenHold => self.seq.block_new_steps(),
            Reaction::SafeHold => self.seq.enter_safe_hold(&joints),
            Reaction::DisableMotors => {
                self.seq.follow_measured(&joints);
                self.loops.iter_mut().for_each(JointLoop::reset);
            }
        }
        if matches!(self.seq.phase(), Phase::Standing | Phase::SafeHold { .. })
            && self.crutch.current().is_some()
            && verdict.reaction >= Reaction::SafeHold
        {
            self.crutch.end_step();
        }

        // 5. write
        let enable = verdict.reaction < Reaction::DisableMotors;
        if enable && !self.motors_enabled {
            let mut all_ok = true;
            for m in hw.motors.iter_mut() {
                all_ok &= m.enable().is_ok();
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
            let cmd = if self.motors_enabled {
                command.get(i).copied().unwrap_or(0.0)
            } else {
                0.0
            };
            let sense = self.motor_sense.get_mut(i);
            let result = m.update(cmd);
            if let Some(s) = sense {
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
        let fb = op.feedback;
        let _ = hw.gait_led.update(fb.gait_led, op.tick);
        let _ = hw.fault_led.update(fb.fault_led, op.tick);
        let _ = hw.buzzer.update(fb.buzzer, op.tick);

        TickReport {
            tick: self.tick,
            joints_rad: joints,
            reference_rad: plan.angle_rad,
            feedforward_nm: feedforward,
            command_nm: written,
            forces_n,
            phase: self.seq.phase(),
            reaction: verdict.reaction,
            faults: verdict.latched,
            motors_enabled: self.motors_enabled,
        }
    }

    fn read_encoders<ENC, ADC, PWM, DIR, EN, IN, OUT>(
        &mut self,
        hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
    ) -> [EncoderSense; ENCODERS]
    where
        ENC: SpiDevice<u8>,
    {
        let mut out = [BAD_ENCODER; ENCODERS];
        let dt = self.cfg.dt_s;
        // First-order low-pass on the joint rates: α = dt / (RC + dt).
        let rc = 1.0 / (2.0 * core::f32::consts::PI * self.cfg.rate_filter_hz);
        let alpha = dt / (rc + dt);
        for (i, (enc, o)) in hw.encoders.iter_mut().zip(out.iter_mut()).enumerate() {
            let status = match enc.read_angle() {
                Ok(r) => {
                    if let (Some(last), Some(raw)) =
                        (self.last_angle.get_mut(i), self.last_raw.get_mut(i))
                    {
                        if let Some(rate) = self.rate.get_mut(i) {
                            let raw_rate = if self.primed {
                                (r.angle_rad - *last) / dt
                            } else {
                                0.0
                            };
                            *rate += alpha * (raw_rate - *rate);
                        }
                        *last = r.angle_rad;
                        *raw = r.raw_counts;
                    }
                    EncoderStatus::Ok
                }
                Err(as5048a::Error::Bus(_)) => EncoderStatus::BusError,
                Err(as5048a::Error::Parity) => EncoderStatus::Parity,
                Err(as5048a::Error::ErrorFlag(_)) => EncoderStatus::ErrorFlag,
            };
            *o = EncoderSense {
                status,
                raw_counts: self.last_raw.get(i).copied().unwrap_or(0),
                angle_rad: if status == EncoderStatus::Ok {
                    self.last_angle.get(i).copied().unwrap_or(f32::NAN)
                } else {
                    f32::NAN
                },
            };
        }
        out
    }

    fn read_forces<ENC, ADC, PWM, DIR, EN, IN, OUT>(
        &mut self,
        hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
    ) -> [ForceSense; FORCES]
    where
        ADC: SpiDevice<u8>,
    {
        let ch = hw.force_channels;
        let channels = [ch.left_foot, ch.right_foot, ch.left_crutch, ch.right_crutch];
        let mut out = [ForceSense {
            status: ForceStatus::BusError,
            newtons: f32::NAN,
        }; FORCES];
        for ((o, channel), cal) in out
            .iter_mut()
            .zip(channels)
            .zip(&self.cfg.force_calibration)
        {
            *o = match hw.adc.read_force(channel, cal) {
                Ok(n) => ForceSense {
                    status: ForceStatus::Ok,
                    newtons: n,
                },
                Err(mcp3208::Error::Bus(_)) => ForceSense {
                    status: ForceStatus::BusError,
                    newtons: f32::NAN,
                },
                Err(mcp3208::Error::Sensor(f)) => ForceSense {
                    status: match f {
                        ForceFault::OpenCircuit { .. } => ForceStatus::Open,
                        ForceFault::ShortCircuit { .. } => ForceStatus::Shorted,
                        ForceFault::OutOfRange { .. } => ForceStatus::OutOfRange,
                    },
                    newtons: f32::NAN,
                },
            };
        }
        out
    }

    /// The stance shank's angle φ1 for a static posture: the ankle
    /// encoder's reading, or, when it reads the dorsiflexion stop (within
    /// 0.5°: the heel may be up and φ1 beyond what the encoder can see), the
    /// larger of it and the last planned φ1.
    fn stance_phi1(&self, ankle_reading: f32, stance: Side) -> f32 {
        let stop = StanceFoot::for_model(&self.cfg.model).heel_off_rad;
        let planned = self
            .ankle_plan
            .get(stance.ankle())
            .copied()
            .unwrap_or(f32::NAN);
        crate::posture::stance_phi1_estimate(ankle_reading, stop, planned)
    }

    /// What the gait plans for each ankle now (left, right), as a stance
    /// shank's lean (φ1; past the stop the heel is planned to be up):
    /// - in a swing, the stance ankle follows the table (its last sample
    ///   once it has ended); the swing foot is in the air (NaN);
    /// - standing, waiting or transferring, both feet are down in the
    ///   gait's start posture: the stance ankle at the table's first φ1,
    ///   the other at its last (the trailing leg's lean; periodic tables).
    ///   Standing, the gait is the clinician's selection;
    /// - in a safe hold, what it was when the hold began.
    fn plan_ankles(
        &self,
        stance: Side,
        swing: Option<(crate::operator::Gait, Side, f32)>,
    ) -> [f32; 2] {
        let tables = self.seq.tables();
        let mut out = [f32::NAN; 2];
        let mut set = |side: Side, v: f32| {
            if let Some(p) = out.get_mut(side.ankle()) {
                *p = v;
            }
        };
        let both = |tb: &gait_core::tables::GaitTable<'_>, set: &mut dyn FnMut(Side, f32)| {
            let [first, ..] = tb.first();
            let [last, ..] = tb.last();
            set(stance, first);
            set(stance.other(), last);
        };
        match self.seq.phase() {
            Phase::SafeHold { .. } => return self.ankle_plan,
            Phase::Swing { .. } => {
                let playing = swing.and_then(|(g, s, t)| tables.get(g).map(|tb| (tb, s, t)));
                if let Some((tb, s, t)) = playing {
                    let [phi1, ..] = tb.at_time(t.min(tb.duration_s()));
                    set(s, phi1);
                }
            }
            Phase::Standing => {
                if let Some(tb) = tables.get(self.operator.selected()) {
                    both(tb, &mut set);
                }
            }
            Phase::WaitingReady { .. } | Phase::Transfer { .. } => {
                if let Some(tb) = tables.get(self.seq.gait()) {
                    both(tb, &mut set);
                }
            }
        }
        out
    }

    /// Last good joint angles (joint order).
    fn joint_angles(&self) -> [f32; JOINTS] {
        [0, 1, 2, 3].map(|i| self.last_angle.get(i).copied().unwrap_or(f32::NAN))
    }

    /// Standing still with both crutches loaded: a reset cannot surprise.
    fn safe_posture(&self, sensed: &Sensed) -> bool {
        let still = self
            .rate
            .iter()
            .all(|r| r.abs() <= self.cfg.still_rate_rad_s);
        let standing = matches!(self.seq.phase(), Phase::Standing | Phase::SafeHold { .. });
        let crutches = sensed
            .crutches_n
            .iter()
            .all(|&f| f >= self.cfg.sequencer.crutch_ready_n);
        still && standing && crutches
    }

    /// The model's joint torques along the reference: during a swing from
    /// the table's Φ and its rates (central differences over one table
    /// period; at rest once the table has ended and the reference is held);
    /// otherwise static torques of the reference posture. In both, the
    /// other foot takes up to `other_load_n` of the load where that lowers
    /// the effort ([`share_load`]).
    fn feedforward(
        &self,
        reference: &[f32; JOINTS],
        swing: Option<(crate::operator::Gait, Side, f32)>,
        stance: Side,
        stance_ankle: f32,
        other_load_n: f32,
    ) -> FeedForward {
        let model = &self.cfg.model;
        // Past the table's end (waiting for the landing) the reference holds
        // the last posture: statics, not the table's final rates.
        let playing = swing.and_then(|(g, s, t)| {
            self.seq
                .tables()
                .get(g)
                .filter(|tb| t <= tb.duration_s())
                .map(|tb| (tb, s, t))
        });
        let (phi, dphi, ddphi, side) = match playing {
            Some((tb, s, t)) => {
                let h = tb.period_s();
                // Derivatives from samples inside the table: past either
                // end, at_time clamps, and a central difference across
                // the clamp reads the last rate as a stop within one
                // period (φ1 still moving at 0.14 rad/s at the landing
                // became a 1,200 N·m ankle and 600 N·m knee demand).
                let tc = t.max(h).min(tb.duration_s() - h);
                let (a, c) = (tb.at_time(tc - h), tb.at_time(tc + h));
                let mid = tb.at_time(tc);
                let b = tb.at_time(t);
                let mut d1 = [0.0f32; LINKS];
                let mut d2 = [0.0f32; LINKS];
                for (((o1, o2), (&x0, &x1)), &x2) in d1
                    .iter_mut()
                    .zip(d2.iter_mut())
                    .zip(a.iter().zip(&mid))
                    .zip(&c)
                {
                    *o1 = (x2 - x0) / (2.0 * h);
                    *o2 = (x2 - 2.0 * x1 + x0) / (h * h);
                }
                (b, d1, d2, s)
            }
            None => (
                phi_from_joints(reference, stance_ankle, stance),
                [0.0; LINKS],
                [0.0; LINKS],
                stance,
            ),
        };
        // The stance heel lifts past the ankle's stop (stair descent): the
        // chain then turns about the toe (gait_core::foot).
        let foot = StanceFoot::for_model(model);
        let single = joint_torques(&foot::inverse_dynamics(model, &foot, &phi, &dphi, &ddphi));
        let shared = foot::share_load(model, &foot, &phi, &single, other_load_n);
        let ff = joint_torques_from_theta_torques(&shared.torques, side);
        let (_, per_newton_up) = foot::second_foot_torques(model, &foot, &phi);
        let per_newton = joint_torques_from_theta_torques(&per_newton_up.map(|v| -v), side);
        let clean = |v: f32| if v.is_finite() { v } else { 0.0 };
        FeedForward {
            torques_nm: ff.map(clean),
            other_foot_n: clean(shared.reaction_n[1]),
            per_other_foot_newton: per_newton.map(clean),
        }
    }
}

/// The model's torques along the reference and the load it plans for the
/// other foot.
struct FeedForward {
    /// Joint torques, joint order, N·m.
    torques_nm: [f32; JOINTS],
    /// Vertical force the other foot is planned to carry, N.
    other_foot_n: f32,
    /// Joint torques (joint order) that one more newton pushed down by the
    /// other foot takes, N·m/N.
    per_other_foot_newton: [f32; JOINTS],
}

/// How much of its position feedback the other leg gives up while its foot
/// is planned to carry the whole body (0: none, 1: all of it).
const DOUBLE_SUPPORT_COMPLIANCE: f32 = 0.8;

/// Proportional gain of the other foot's load loop (share of the error
/// pushed at once).
const OTHER_FOOT_KP: f32 = 0.5;
/// Its integral gain, 1/s, and the integral's clamp, N.
const OTHER_FOOT_KI_PER_S: f32 = 5.0;
const OTHER_FOOT_INTEGRAL_N: f32 = 200.0;
/// Largest correction of the other foot's load, N (a sensor reading far
/// from the plan, as right after power-up, must not drive the leg to its
/// limit).
const OTHER_FOOT_PUSH_N: f32 = 200.0;

const BAD_ENCODER: EncoderSense = EncoderSense {
    status: EncoderStatus::BusError,
    raw_counts: 0,
    angle_rad: f32::NAN,
};

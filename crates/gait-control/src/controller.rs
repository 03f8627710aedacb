//! The 1 kHz control tick, in five stages, each a method of its own:
//!
//! 1. **sense** (`controller/sense.rs`) — decode, calibrate and check
//!    what the acquisition read of every encoder and force sensor
//!    ([`crate::acquisition`]: through the drivers at the tick's start, or
//!    by DMA before it), read the buttons and the e-stop (a failed read
//!    becomes a status, never a panic, and the last good angle is kept for
//!    control);
//! 2. **plan** — the operator scheme turns button events into requests; the
//!    sequencer's one update obeys them and the last verdict's orders and
//!    hands over the whole [`Reference`] (one table interpolation);
//! 3. **act** (`controller/act.rs`) — per joint, PID plus the model's
//!    feed-forward: its answer to the last tick's request, and the request
//!    for this tick's reference ([`crate::feedforward`]);
//! 4. **guard** — the supervisor checks every fact and decides a reaction
//!    before anything is written; the reaction becomes the orders of the
//!    next update;
//! 5. **write** (`controller/write.rs`) — motor commands (only after the
//!    guard), indicators, the crutch-load metric.
//!
//! Bounded: fixed numbers of reads, one table interpolation (three lookups
//! for the rates), no allocation, no wait; the inverse dynamics run between
//! ticks (or, without a model task, once a tick for the next one).

mod act;
mod chain;
mod estop;
mod guard;
mod sense;
mod write;

use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::pwm::SetDutyCycle;
use embedded_hal::spi::SpiDevice;
use gait_core::BodyModel;

use crate::acquisition::{self, Frames};
use crate::ahead::Steps;
use crate::crutch_load::CrutchLoad;
use crate::drivers::as5048a::As5048a;
use crate::drivers::buttons::Button;
use crate::drivers::mcp3208::{
    Channel, DriveCurrentCalibration, ForceCalibration, ForceChannels, Mcp3208,
};
use crate::drivers::motor::Motor;
use crate::drivers::status::Indicator;
use crate::faults::{FaultCode, FaultSet, Reaction};
use crate::feedforward::{FeedForward, ModelSlot};
use crate::layout::Side;
use crate::operator::{self, ControllerStatus, Input, Operator, OperatorConfig, Request};
use crate::position_loop::{JointGains, JointLoop};
use crate::posture::JOINTS;
use crate::reference::Reference;
use crate::replan::{ReplanConfig, ReplanSlot};
use crate::sequencer::{
    GaitTables, Orders, Phase, SeqInput, SeqRequest, SeqStatus, Sequencer, SequencerConfig,
};
use crate::supervisor::{Findings, Lent, MotorSense, Supervisor, WindowedChecks};

use sense::Senses;

pub use crate::layout::{ENCODERS, FORCES};
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
    /// Which ADC channel each hip and knee drive's current monitor is on
    /// (joint order).
    pub drive_current_channels: [Channel; JOINTS],
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
    /// The drives' current monitors as joint torque (joint order).
    pub drive_current_calibration: [DriveCurrentCalibration; JOINTS],
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
///
/// `repr(C)`: its fields lie in the order written, which the QEMU replay
/// measured 80 instructions a tick cheaper on the Cortex-M4 than the
/// compiler's own order (more of the inlined stages' loads reach their
/// fields with a short offset). Moving fields changes the tick: measure
/// with `cargo xtask qemu`.
#[repr(C)]
pub struct Controller<'t> {
    cfg: ControllerConfig,
    loops: [JointLoop; JOINTS],
    operator: Operator,
    supervisor: Supervisor<Lent>,
    last_raw: [u16; ENCODERS],
    last_angle: [f32; ENCODERS],
    /// Consecutive frames of each encoder (joints, then ankles) that
    /// control could not take (bad or dropped): from [`BLIND_AFTER_FRAMES`]
    /// on, a joint is blind and runs on its feed-forward alone, and a
    /// stance ankle's lean is estimated instead of read.
    untaken: [u8; ENCODERS],
    rate: [f32; JOINTS],
    /// The rates' first-order low-pass, α = dt / (RC + dt): it depends on
    /// the configuration only, so it is worked out once.
    rate_alpha: f32,
    /// A lost hip's or knee's angle from the closed chain.
    chain: chain::ChainEstimate,
    motor_sense: [MotorSense; JOINTS],
    motors_enabled: bool,
    /// The model task runs the windowed checks.
    checks_in_task: bool,
    /// Joints whose drive the supervisor has disabled, braked
    /// (`FaultCode::brakes_joint`: an output-stage fault, 0x0404 until a
    /// reset; a lost encoder while the closed chain does not give its
    /// angle).
    braked: [bool; JOINTS],
    primed: bool,
    /// A clinician reset waiting for the supervisor.
    pending_reset: Option<PendingReset>,
    /// Integral of the other foot's load error in double support, N.
    other_foot_integral_n: f32,
    /// The model's answer the next tick applies ([`crate::feedforward`]).
    model_ff: FeedForward,
    /// With a model task: the slot it answers through.
    model_slot: Option<&'t ModelSlot>,
    /// The e-stop's stop: whether it has been seen since it last
    /// cleared, and the set-down of a swing it struck in.
    estop: estop::EStopStop,
    /// Where gait execution is after the last tick (its verdict's orders
    /// obeyed).
    seq_status: SeqStatus,
    /// The last verdict's orders, for the next update.
    orders: Orders,
    tick: u32,
    /// Near the end: its per-gait tables are read once a tick at most.
    seq: Sequencer<'t>,
    /// Its log of steps is written once a step.
    crutch: CrutchLoad,
    /// Last, past the fields a tick reads on the board (4 KiB, see
    /// `firmware/src/lib.rs`): without a model task, what the windowed
    /// checks found in the last tick's facts, and their memory.
    findings: Findings,
    windowed: Option<WindowedChecks>,
}

/// Bytes of the controller's state that a tick reads on the board: every
/// field before the host's `findings` (`firmware/src/lib.rs` keeps them
/// under 4 KiB).
pub const TICK_STATE_BYTES: usize = core::mem::offset_of!(Controller<'static>, findings);

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
            enabled: false,
            feedforward_nm: 0.0,
        };
        let (supervisor, windowed) = supervisor.lend();
        Ok(Self {
            cfg,
            windowed: Some(windowed),
            checks_in_task: false,
            findings: Findings::NONE,
            seq: Sequencer::new(cfg.sequencer, tables, [0.0; JOINTS]).with_model(cfg.model),
            loops: [JointLoop::default(); JOINTS],
            operator: Operator::new(operator),
            supervisor,
            crutch: CrutchLoad::new(),
            last_raw: [0; ENCODERS],
            last_angle: [0.0; ENCODERS],
            untaken: [0; ENCODERS],
            rate: [0.0; JOINTS],
            rate_alpha: {
                let rc = 1.0 / (2.0 * core::f32::consts::PI * cfg.rate_filter_hz);
                cfg.dt_s / (rc + cfg.dt_s)
            },
            chain: chain::ChainEstimate::default(),
            motor_sense: [idle; JOINTS],
            motors_enabled: false,
            braked: [false; JOINTS],
            primed: false,
            pending_reset: None,
            other_foot_integral_n: 0.0,
            model_ff: FeedForward::NONE,
            model_slot: None,
            estop: estop::EStopStop::default(),
            seq_status: SeqStatus::STANDING,
            orders: Orders::NONE,
            tick: 0,
        })
    }

    /// Adapts each step to where the pilot's stance ankle is, through the
    /// idle-time re-planner that shares `slot` ([`crate::replan`]).
    pub fn set_replanner(&mut self, slot: &'t ReplanSlot, cfg: ReplanConfig) {
        self.seq = self.seq.with_replanner(slot, cfg);
    }

    /// Leaves the model's feed-forward and the supervisor's windowed
    /// checks to a task that answers through `slot` between ticks
    /// ([`crate::feedforward::ModelTask`]), instead of working them out in
    /// the tick: the same torques and verdicts, off the tick. Returns the
    /// windowed checks' memory, for the task
    /// ([`crate::feedforward::ModelTask::with_checks`]; `None` if already
    /// lent); a task without it leaves every tick's facts unchecked, each
    /// a missed deadline ([`FaultCode::DeadlineMissed`] from the third).
    /// Call before the first tick.
    #[must_use = "the model task runs the windowed checks only when given them"]
    pub fn set_model_task(&mut self, slot: &'t ModelSlot) -> Option<WindowedChecks> {
        self.model_slot = Some(slot);
        self.checks_in_task = true;
        slot.checks().make_room();
        self.windowed.take()
    }

    /// The steps its swings play, for a model task that does their table
    /// work a tick ahead ([`ModelTask::with_steps`]). Call after
    /// [`Controller::set_replanner`], if at all.
    ///
    /// [`ModelTask::with_steps`]: crate::feedforward::ModelTask::with_steps
    pub fn steps(&self) -> Steps<'t> {
        Steps {
            tables: *self.seq.tables(),
            replanned: self.seq.replan_slot(),
        }
    }

    /// The configuration it was built with.
    pub fn config(&self) -> &ControllerConfig {
        &self.cfg
    }

    /// The gait the next start would play: the one being played while a
    /// gait runs, else the clinician's selection.
    pub fn planned_gait(&self) -> crate::operator::Gait {
        if self.seq_status.walking() {
            self.seq_status.gait
        } else {
            self.operator.selected()
        }
    }

    /// The sequencer (phase, reference), for observers: the tick itself
    /// only calls its [`Sequencer::update`].
    pub fn sequencer(&self) -> &Sequencer<'t> {
        &self.seq
    }

    /// The supervisor (latched faults, post-mortem log).
    pub fn supervisor(&self) -> &Supervisor<Lent> {
        &self.supervisor
    }

    /// The supervisor's windowed checks, while the tick runs them itself
    /// (not lent to a model task), for observers.
    pub fn windowed_checks(&self) -> Option<&WindowedChecks> {
        self.windowed.as_ref()
    }

    /// Joints whose drive is disabled and braked on the supervisor's word
    /// (not those the e-stop disables, nor those 0x0404 holds in place).
    pub const fn braked_joints(&self) -> [bool; JOINTS] {
        self.braked
    }

    /// The crutch-load log.
    pub fn crutch_load(&self) -> &CrutchLoad {
        &self.crutch
    }

    /// The board restarted after a panic: start in a hold of the posture the
    /// first tick finds (fault 0x0603, `docs/safety.md`).
    pub fn report_restart_after_panic(&mut self) {
        self.supervisor.report_restart_after_panic();
    }

    /// Latches a fault the board found at boot in its flash data
    /// (`FaultCode::BundleRefused`, `FaultCode::CalibrationRefused`): the
    /// controller holds what it finds (or keeps the motors off) from its
    /// first tick, and no reset clears it. Call before the first tick.
    pub fn report_boot_fault(&mut self, code: FaultCode) {
        self.supervisor.report_boot_fault(code);
    }

    /// One control tick that reads its own sensors first
    /// ([`acquisition::acquire`], through the drivers). `deadline_missed`:
    /// the previous tick overran its budget (measured by the board's
    /// timer).
    // Never inlined: the firmware check of panic paths (`cargo xtask panics`)
    // starts from this symbol, and one call a tick costs nothing measurable.
    #[inline(never)]
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
        let acquired = acquisition::acquire(hw, self.next_drive_joint());
        self.tick_acquired(hw, &acquired, deadline_missed)
    }

    /// One control tick on frames acquired before it (on the motor board,
    /// by the buses' DMA): the tick reads no bus for its sensors. Its
    /// acquisition must read the drive monitor of [`Self::next_drive_joint`]
    /// (another's reading is still checked as that joint's).
    #[inline(never)]
    pub fn tick_acquired<ENC, ADC, PWM, DIR, EN, IN, OUT, PwmE, PinE>(
        &mut self,
        hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
        acquired: &Frames,
        deadline_missed: bool,
    ) -> TickReport
    where
        PWM: SetDutyCycle<Error = PwmE>,
        DIR: OutputPin<Error = PinE>,
        EN: OutputPin<Error = PinE>,
        IN: InputPin,
        OUT: OutputPin,
    {
        self.tick = self.tick.wrapping_add(1);
        let senses = self.sense(hw, acquired);
        let plan = self.plan(hw, &senses);
        let actuation = self.act(&senses, &plan.reference);
        let verdict = self.guard(&senses, &plan.reference, &actuation, deadline_missed);
        self.write(hw, &senses, &plan, &actuation, &verdict)
    }

    /// The drive whose current monitor the next tick's acquisition reads.
    pub const fn next_drive_joint(&self) -> u8 {
        acquisition::drive_joint_of(self.tick.wrapping_add(1))
    }

    /// Stage 2: the operator's requests and the last verdict's orders to
    /// the sequencer, and its reference.
    #[inline(always)]
    fn plan<ENC, ADC, PWM, DIR, EN, IN, OUT, PwmE, PinE>(
        &mut self,
        hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
        s: &Senses,
    ) -> Planned
    where
        PWM: SetDutyCycle<Error = PwmE>,
        DIR: OutputPin<Error = PinE>,
        EN: OutputPin<Error = PinE>,
    {
        // First tick: hold the posture the device is in.
        let restart = !self.primed;
        self.primed = true;
        let status = ControllerStatus {
            walking: self.seq_status.walking(),
            step_in_progress: self.seq_status.step_in_progress(),
            safe_posture: self.safe_posture(&s.sensed),
            faulted: !self.supervisor.latched().is_empty(),
        };
        let operator = self.operator.tick(&Input {
            mode: s.mode,
            go: s.go,
            status,
        });
        let request = match operator.request {
            Some(Request::Start(gait)) => Some(SeqRequest::Start(gait)),
            Some(Request::StopAfterStep) => Some(SeqRequest::StopAfterStep),
            Some(Request::ResetFaults) => {
                // Motor drivers latch their own faults: clear them first.
                for m in hw.motors.iter_mut() {
                    let _ = m.reset_fault();
                }
                self.pending_reset = Some(PendingReset::new(status.safe_posture));
                None
            }
            None => self
                .complete_reset(status.safe_posture)
                .then_some(SeqRequest::ResetAfterFaults),
        };
        Planned {
            reference: self.seq.update(&SeqInput {
                sensed: &s.sensed,
                selected: self.operator.choice(),
                request,
                orders: &self.orders,
                braked: &self.braked,
                hold_joint_at: s.chain_hold,
                restart,
                dt_s: self.cfg.dt_s,
                ahead: self.model_slot.map(ModelSlot::ahead),
            }),
            operator,
        }
    }

    /// The clinician's reset, once the supervisor has seen the motor
    /// drivers' cleared flags: granted only in a safe posture, both when
    /// asked and now. `true` when granted (the sequencer then stands where
    /// it is and allows steps again).
    fn complete_reset(&mut self, safe_now: bool) -> bool {
        let Some(pending) = self.pending_reset else {
            return false;
        };
        if pending.ticks_left > 0 {
            self.pending_reset = Some(PendingReset {
                ticks_left: pending.ticks_left - 1,
                ..pending
            });
            return false;
        }
        self.pending_reset = None;
        let granted =
            pending.safe_when_asked && safe_now && self.supervisor.request_reset(true).is_ok();
        if granted {
            self.loops.iter_mut().for_each(JointLoop::reset);
        }
        granted
    }

    /// The swing leg while its foot is surely in the air: the sequencer's
    /// landing window ([`SeqStatus::airborne_leg`]) and its sensor feeling
    /// no contact (a failed sensor cannot tell: not airborne). For the
    /// supervisor's stuck-ankle check.
    fn airborne_leg(&self, s: &Senses, status: &SeqStatus) -> Option<Side> {
        let contact = self.cfg.sequencer.landing_contact_n;
        status.airborne_leg.filter(|leg| {
            s.forces_n
                .get(leg.foot())
                .is_some_and(|&load| load < contact)
        })
    }

    /// Standing still with both crutches loaded: a reset cannot surprise.
    fn safe_posture(&self, sensed: &crate::sequencer::Sensed) -> bool {
        let still = self
            .rate
            .iter()
            .all(|r| r.abs() <= self.cfg.still_rate_rad_s);
        let standing = self.seq_status.at_rest();
        let crutches = sensed
            .crutches_n
            .iter()
            .all(|&f| f >= self.cfg.sequencer.crutch_ready_n);
        still && standing && crutches
    }
}

/// Consecutive untaken frames after which a joint counts as blind: the
/// supervisor's bad-frame debounce (its fault latches then too).
pub const BLIND_AFTER_FRAMES: u8 = 3;

/// What *plan* decided.
struct Planned {
    /// The sequencer's reference.
    reference: Reference,
    /// The operator scheme's output (indicators, the selection).
    operator: operator::Output,
}

/// A clinician reset waiting for the supervisor to see the motor drivers'
/// cleared flags: they reach its check at the end of the next tick, and
/// its reset decision uses the last check.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PendingReset {
    /// The posture was safe when the reset was asked for.
    safe_when_asked: bool,
    /// Ticks still to wait.
    ticks_left: u8,
}

impl PendingReset {
    fn new(safe_when_asked: bool) -> Self {
        Self {
            safe_when_asked,
            ticks_left: 2,
        }
    }
}

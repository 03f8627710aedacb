//! The real controller (gait-control's `Controller`, the code that runs on
//! the motor board) against the plant, through the simulated peripherals,
//! in lock-step at 1 kHz.
//!
//! The rig is wired like the board: six AS5048A (four joints, two ankles),
//! one MCP3208 for the four force sensors, four motor bridges, MODE/GO
//! buttons, an e-stop, two LEDs and a buzzer. The clinic's calibration is
//! done the way it is on a device: encoder zero offsets and directions are
//! read off the encoder mountings, force calibrations off the sensors'
//! characteristics. Every handle a scenario needs for fault injection is
//! public.

use std::cell::Cell;
use std::rc::Rc;

use embedded_hal::digital::{self, InputPin, OutputPin};
use exogait_device::tick_record::TickRecord;
use exogait_device::{BoardIo, DeviceConfig};
use gait_control::acquisition;
use gait_control::controller::{Controller, Hardware, TickReport};
use gait_control::faults::{FaultSet, Reaction};
use gait_control::operator::Gait;
use gait_control::sequencer::{GaitTables, Phase};
use gait_core::BodyModel;

use crate::as5048a::SimAs5048a;
use crate::inject::{Injector, leaned};
use crate::mcp3208::SimMcp3208;
use crate::motor::{SimBridgePin, SimPwm};
use crate::pins::{PressedLevel, SimButton, SimEStop};
use crate::plant::{Plant, PlantConfig, Side, SimError, TrueState};
use crate::shared::SharedF64;
use crate::wiring::{Wiring, mount_of};

mod pilot_aim;
mod placement;

use pilot_aim::pilot_target;
pub use pilot_aim::{PilotBehaviour, table_stance_shank};

/// The buttons' and the e-stop's pins have one type on the board (erased
/// GPIO); here one enum stands for both.
#[derive(Clone, Debug)]
pub enum SimInput {
    /// A scripted push button.
    Button(SimButton),
    /// The emergency stop.
    EStop(SimEStop),
}

/// Read error of a simulated input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SimInputError;

impl digital::Error for SimInputError {
    fn kind(&self) -> digital::ErrorKind {
        digital::ErrorKind::Other
    }
}

impl digital::ErrorType for SimInput {
    type Error = SimInputError;
}

impl InputPin for SimInput {
    fn is_high(&mut self) -> Result<bool, Self::Error> {
        match self {
            Self::Button(b) => b.is_high().map_err(|_| SimInputError),
            Self::EStop(e) => e.is_high().map_err(|_| SimInputError),
        }
    }

    fn is_low(&mut self) -> Result<bool, Self::Error> {
        self.is_high().map(|h| !h)
    }
}

/// An LED or the buzzer: remembers its level.
#[derive(Clone, Debug, Default)]
pub struct SimLed(Rc<Cell<bool>>);

impl SimLed {
    /// `true` while lit / sounding.
    pub fn is_on(&self) -> bool {
        self.0.get()
    }
}

impl digital::ErrorType for SimLed {
    type Error = core::convert::Infallible;
}

impl OutputPin for SimLed {
    fn set_low(&mut self) -> Result<(), Self::Error> {
        self.0.set(false);
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Self::Error> {
        self.0.set(true);
        Ok(())
    }
}

/// The hardware type the rig drives.
pub type SimHardware =
    Hardware<SimAs5048a, SimMcp3208, SimPwm, SimBridgePin, SimBridgePin, SimInput, SimLed>;

/// Why a rig could not be built.
#[derive(Debug)]
pub enum RigError {
    /// The plant refused its configuration or state.
    Sim(SimError),
    /// A controller, supervisor or driver configuration was refused.
    Config(&'static str),
    /// The device configuration was refused.
    Device(exogait_device::DeviceError),
}

impl core::fmt::Display for RigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Sim(e) => write!(f, "plant: {e:?}"),
            Self::Config(m) => write!(f, "configuration: {m}"),
            Self::Device(e) => write!(f, "device configuration: {e:?}"),
        }
    }
}

impl From<SimError> for RigError {
    fn from(e: SimError) -> Self {
        Self::Sim(e)
    }
}

/// One tick of the closed loop, for metrics and plots.
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// What the controller did.
    pub report: TickReport,
    /// The plant's true state after the tick.
    pub state: TrueState,
    /// Joints the controller had braked after the tick.
    pub braked: [bool; 4],
    /// The supervisor's torque residual of each joint after the tick, N·m
    /// (0x0404; NaN where a model task runs the windowed checks).
    pub residual_nm: [f32; 4],
}

/// The closed loop.
pub struct Rig<'t> {
    /// The plant.
    pub plant: Plant,
    /// Cells and motor bridges.
    pub wiring: Wiring,
    /// Joint encoders (fault injection handles; joint order).
    pub joint_encoders: [SimAs5048a; 4],
    /// Ankle encoders (left, right).
    pub ankle_encoders: [SimAs5048a; 2],
    /// The force ADC.
    pub adc: SimMcp3208,
    /// MODE button script.
    pub mode: SimButton,
    /// GO button script.
    pub go: SimButton,
    /// Emergency stop.
    pub e_stop: SimEStop,
    /// Gait LED, fault LED, buzzer.
    pub indicators: [SimLed; 3],
    ankle_cells: [SharedF64; 2],
    hw: SimHardware,
    /// The controller under test.
    pub controller: Controller<'t>,
    /// Every tick so far.
    pub trace: Vec<Sample>,
    pub(crate) device: DeviceConfig,
    support_ticks: u64,
    pilot: PilotBehaviour,
    transfer_from_phi1: Option<f64>,
    /// The pilot's reaction to a safe hold.
    hold_reaction: pilot_aim::HoldReaction,
    /// The pilot's own lean over the plan.
    habit: pilot_aim::Habit,
    /// The board's idle-time re-planner, when it runs one.
    pub(crate) replanner: Option<crate::replanning::SimReplanner<'t>>,
    pub(crate) faults: Injector,
    /// The tables the controller was built with (a reboot builds it again).
    tables: GaitTables<'t>,
    /// When recording (`record_ticks`): every tick's peripheral state and
    /// the controller's commands, for a replay on the target.
    pub recorded: Option<Vec<TickRecord>>,
    /// Each tick's sensors read frame by frame in the motor board's DMA
    /// order (`acquisition::acquire_in_rounds`, then `tick_acquired`), not
    /// through the drivers at the tick's start: the same frames.
    pub dma_frame_order: bool,
}

/// How a rig starts.
#[derive(Clone, Copy, Debug)]
pub struct RigSetup {
    /// The device (the plant's body model and ankle springs, the drives,
    /// the controller's configuration all come from it).
    pub device: DeviceConfig,
    /// The plant's parameters (terrain, pilot; its model and ankle spring
    /// are replaced by the device's).
    pub plant: PlantConfig,
    /// Initial Φ (rad) and stance leg.
    pub phi: [f64; 5],
    /// The stance leg.
    pub stance: Side,
    /// World position of the stance ankle, m (on the terrain).
    pub stance_foot_m: [f64; 2],
    /// What the pilot does with the stance shank.
    pub pilot: PilotBehaviour,
    /// The gait the clinician's list allows first (selected at power-up).
    pub gait: Gait,
    /// Ticks during which the plant is held still (the pilot supported,
    /// e.g. by a therapist or a hoist) while the motors soft-start.
    pub support_ticks: u64,
    /// The clinician's gait list, when it is not the device's own order
    /// over `tables` (a patient's bundle: `exogait_device::boot`).
    pub operator: Option<gait_control::operator::OperatorConfig>,
}

/// The device's body model: Table III with its joint limits (the
/// heel-rocker ankle, [`gait_core::JointLimits::paper_with_heel_rocker`]);
/// the plant's ankle stop and the supervisor's ankle envelope both use them.
pub fn heel_rocker_model() -> BodyModel<f64> {
    DeviceConfig::exogait().map_or_else(|_| BodyModel::paper_table_iii(), |d| d.body)
}

impl<'t> Rig<'t> {
    /// Builds the plant, the peripherals, the drivers and the controller,
    /// all from `setup.device`.
    pub fn new(setup: &RigSetup, tables: GaitTables<'t>) -> Result<Self, RigError> {
        let device = setup.device;
        let plant_cfg = PlantConfig {
            model: device.body,
            ankle_stiffness_nm_per_rad: device.ankle_spring_nm_per_rad,
            dt_s: f64::from(device.dt_s),
            ..setup.plant
        };
        let mut plant = Plant::with_posture(
            plant_cfg,
            setup.phi,
            [0.0; 5],
            setup.stance,
            setup.stance_foot_m,
        )?;
        let wiring = Wiring::for_device(&device);
        let joint_encoders: [SimAs5048a; 4] = std::array::from_fn(|j| {
            wiring
                .encoder(j)
                .unwrap_or_else(|| SimAs5048a::new(SharedF64::default(), wiring.encoder_mounts[0]))
        });
        let ankle_cells: [SharedF64; 2] = Default::default();
        let ankle_encoders: [SimAs5048a; 2] = std::array::from_fn(|a| {
            SimAs5048a::new(ankle_cells[a].clone(), mount_of(&device.encoders[4 + a]))
        });
        let adc = wiring.force_adc();
        let clock = wiring.clock.clone();
        let pressed = |active_high: bool| {
            if active_high {
                PressedLevel::High
            } else {
                PressedLevel::Low
            }
        };
        let button_level = pressed(matches!(
            device.buttons.active,
            gait_control::drivers::buttons::ActiveLevel::High
        ));
        let mode = SimButton::new(clock.clone(), Vec::new(), button_level);
        let go = SimButton::new(clock, Vec::new(), button_level);
        let e_stop = SimEStop::new(pressed(device.e_stop_active_high));
        let indicators: [SimLed; 3] = Default::default();
        let io = BoardIo {
            encoders: [
                joint_encoders[0].clone(),
                joint_encoders[1].clone(),
                joint_encoders[2].clone(),
                joint_encoders[3].clone(),
                ankle_encoders[0].clone(),
                ankle_encoders[1].clone(),
            ],
            adc: adc.clone(),
            pwm: std::array::from_fn(|j| wiring.motors[j].pwm()),
            dir: std::array::from_fn(|j| wiring.motors[j].direction_pin()),
            enable: std::array::from_fn(|j| wiring.motors[j].enable_pin()),
            mode: SimInput::Button(mode.clone()),
            go: SimInput::Button(go.clone()),
            e_stop: SimInput::EStop(e_stop.clone()),
            gait_led: indicators[0].clone(),
            fault_led: indicators[1].clone(),
            buzzer: indicators[2].clone(),
        };
        let hw = exogait_device::hardware(&device, io).map_err(RigError::Device)?;
        let controller = match setup.operator {
            None => exogait_device::build_controller(&device, tables, setup.gait)
                .map_err(RigError::Device)?,
            Some(op) => gait_control::controller::Controller::new(
                device.controller,
                tables,
                op,
                device.supervisor().map_err(RigError::Device)?,
            )
            .map_err(|e| RigError::Device(exogait_device::DeviceError::Controller(e)))?,
        };
        if controller.sequencer().tables().get(setup.gait).is_none() {
            return Err(RigError::Config("no verified table for the gait"));
        }
        plant.set_pilot(pilot_target(
            &setup.pilot,
            false,
            &Phase::Standing,
            tables.get(setup.gait),
            None,
            0.0,
            0.0,
        ));
        let rig = Self {
            plant,
            wiring,
            joint_encoders,
            ankle_encoders,
            adc,
            mode,
            go,
            e_stop,
            indicators,
            ankle_cells,
            hw,
            controller,
            trace: Vec::new(),
            device,
            support_ticks: setup.support_ticks,
            pilot: setup.pilot,
            transfer_from_phi1: None,
            hold_reaction: pilot_aim::HoldReaction::default(),
            habit: pilot_aim::Habit::default(),
            replanner: None,
            faults: Injector::default(),
            tables,
            recorded: None,
            dma_frame_order: false,
        };
        // Start the ankle readings at their true values (no lag to settle).
        let s = rig.plant.state();
        for (cell, a) in rig.ankle_cells.iter().zip(s.ankle_dorsiflexion_rad) {
            cell.set(a.unwrap_or(0.0));
        }
        rig.publish();
        Ok(rig)
    }

    /// The device configuration the rig was built from.
    pub fn device(&self) -> &DeviceConfig {
        &self.device
    }

    /// The configuration the rig actually runs, read back from the live
    /// controller, supervisor and drivers and from the simulated parts
    /// (drives, encoder mountings, load cells): equal to [`Rig::device`]
    /// when nothing in the simulator departs from the device.
    pub fn running_config(&self) -> DeviceConfig {
        let mut c = self.device;
        c.controller = *self.controller.config();
        c.supervisor = *self.controller.supervisor().config();
        for (m, d) in c.motors.iter_mut().zip(&self.hw.motors) {
            *m = *d.config();
        }
        for (e, h) in c.encoders.iter_mut().zip(&self.hw.encoders) {
            *e = h.calibration();
        }
        c.body = self.plant.config().model;
        c.ankle_spring_nm_per_rad = self.plant.config().ankle_stiffness_nm_per_rad;
        c.force_channels = self.hw.force_channels;
        for (d, m) in c.drives.iter_mut().zip(&self.wiring.motors) {
            if let Some(spec) = m.drive_spec() {
                *d = spec;
            }
        }
        c
    }

    fn publish(&self) {
        let s = self.plant.state();
        self.wiring.publish(&s);
        // The swing ankle in the air is not modelled: its spring holds it
        // near rest (0), and at foot-flat it turns to the stance angle within
        // a few tens of milliseconds. Both ankle readings follow their
        // targets (on the ground: the shank's lean; in the air: rest)
        // through a 30 ms first-order lag, so the swap at landing reads as a
        // fast but physical rotation, not a jump.
        const TAU_S: f64 = 0.03;
        let alpha = (self.plant.config().dt_s / TAU_S).min(1.0);
        for (cell, a) in self.ankle_cells.iter().zip(s.ankle_dorsiflexion_rad) {
            let target = a.unwrap_or(0.0);
            let now = cell.get();
            cell.set(now + alpha * (target - now));
        }
    }

    /// Measurement noise on every encoder (±`encoder_counts` of 16,384 per
    /// turn) and on the force ADC (±`adc_counts` of 4,096), seeded per
    /// device from `seed`.
    pub fn set_sensor_noise(&self, encoder_counts: u16, adc_counts: u16, seed: u64) {
        for (i, e) in self
            .joint_encoders
            .iter()
            .chain(&self.ankle_encoders)
            .enumerate()
        {
            e.set_noise(encoder_counts, seed.wrapping_add(i as u64 * 7919));
        }
        self.adc
            .set_noise(adc_counts, seed.wrapping_mul(31).wrapping_add(17));
    }

    /// The current tick number (= the simulated clock).
    pub fn now(&self) -> u64 {
        self.wiring.clock.now()
    }

    /// Scripts a press of `button` from tick `at` for `ticks`.
    pub fn press(button: &SimButton, at: u64, ticks: u64) {
        button.push(at, true);
        button.push(at + ticks, false);
    }

    /// One controller tick, then one plant step.
    pub fn tick(&mut self) -> Result<&Sample, SimError> {
        self.inject_due();
        let overrun = self.faults.overruns_left > 0;
        self.faults.overruns_left = self.faults.overruns_left.saturating_sub(1);
        let mut record = self
            .recorded
            .is_some()
            .then(|| self.peripheral_state(overrun));
        let report = match self.rebooting()? {
            Some(report) => report,
            None if self.dma_frame_order => {
                let joint = self.controller.next_drive_joint();
                let frames = acquisition::acquire_in_rounds(&mut self.hw, joint);
                self.controller
                    .tick_acquired(&mut self.hw, &frames, overrun)
            }
            None => self.controller.tick(&mut self.hw, overrun),
        };
        if let (Some(log), Some(r)) = (&mut self.recorded, &mut record) {
            r.host_command_nm = report.command_nm;
            log.push(*r);
        }
        match report.phase {
            Phase::Transfer { .. } => {
                if self.transfer_from_phi1.is_none() {
                    self.transfer_from_phi1 = Some(self.plant.state().phi[0]);
                }
            }
            _ => self.transfer_from_phi1 = None,
        }
        let seq = self.controller.sequencer();
        let table = seq.tables().get(self.controller.planned_gait()).copied();
        // The plant may have put the swing foot down a few ticks before the
        // controller counts the landing.
        let swapped = match report.phase {
            Phase::Swing { stance, .. } => {
                let plant_left = self.plant.stance() == Side::Left;
                plant_left != (stance == gait_control::posture::Side::Left)
            }
            _ => false,
        };
        let target = pilot_target(
            &self.pilot,
            swapped,
            &report.phase,
            table.as_ref(),
            self.transfer_from_phi1,
            self.device.controller.sequencer.transfer_s,
            self.plant.time_s(),
        );
        let pilot_cfg = self.plant.config().pilot;
        let plant = &self.plant;
        let target = self.hold_reaction.aim(
            &pilot_cfg,
            matches!(report.phase, Phase::SafeHold { .. }),
            target,
            plant.stance(),
            || plant.state().phi[0],
            plant.time_s(),
        );
        let habit = self
            .habit
            .lean(&pilot_cfg, &report.phase, self.plant.config().dt_s);
        let target = leaned(target, self.faults.pilot_lean_rad + habit);
        if target != self.plant.pilot() {
            self.plant.set_pilot(target);
        }
        self.wiring.record_drive_currents();
        if self.now() >= self.support_ticks {
            self.wiring.drive_plant(&mut self.plant)?;
        }
        self.wiring.integrate_thermal(self.plant.config().dt_s);
        self.publish();
        if let Some(r) = &mut self.replanner {
            r.idle(self.wiring.clock.now(), &self.device, &self.tables);
        }
        self.wiring.clock.tick();
        self.trace.push(Sample {
            report,
            state: self.plant.state(),
            braked: self.controller.braked_joints(),
            residual_nm: self
                .controller
                .windowed_checks()
                .map_or([f32::NAN; 4], |w| w.residuals_nm()),
        });
        self.trace.last().ok_or(SimError::NonFinite)
    }

    /// The board resets after a panic (`Kind::Panic`): every motor is
    /// disabled through its driver now, as the reset's floating enable lines
    /// do, and the controller stops ticking until `now + boot`.
    pub(crate) fn panic_reset(&mut self, now: u64, boot_ms: f64) {
        for m in &mut self.hw.motors {
            let _ = m.disable();
        }
        let boot_ticks = (boot_ms * 1e-3 / f64::from(self.device.dt_s)).ceil() as u64;
        self.faults.reboot_until = Some(now + boot_ticks);
    }

    /// While the board boots after a panic: the report of a board that does
    /// not tick (the last one, motors off). At the end of the boot the
    /// controller is built afresh, as the firmware builds it, told it
    /// restarted after a panic, and `None` lets it tick.
    fn rebooting(&mut self) -> Result<Option<TickReport>, SimError> {
        let Some(until) = self.faults.reboot_until else {
            return Ok(None);
        };
        if self.now() < until {
            let mut report = self
                .trace
                .last()
                .map(|s| s.report)
                .ok_or(SimError::Config("a panic injected before the first tick"))?;
            report.motors_enabled = false;
            report.command_nm = [0.0; 4];
            return Ok(Some(report));
        }
        self.faults.reboot_until = None;
        let gait = self.controller.planned_gait();
        self.controller = exogait_device::build_controller(&self.device, self.tables, gait)
            .map_err(|_| SimError::Config("the rebooted board's controller was refused"))?;
        if let Some(r) = &self.replanner {
            self.controller
                .set_replanner(r.slot(), exogait_device::replan::REPLAN);
        }
        self.controller.report_restart_after_panic();
        Ok(None)
    }

    /// Ticks until `done` says so or `max_ticks` pass; returns the ticks run.
    pub fn run_until(
        &mut self,
        max_ticks: u64,
        mut done: impl FnMut(&Sample) -> bool,
    ) -> Result<u64, SimError> {
        for n in 0..max_ticks {
            let s = self.tick()?;
            if done(s) {
                return Ok(n + 1);
            }
        }
        Ok(max_ticks)
    }

    /// Changes what the simulated pilot does from the next tick on (fault
    /// injection: a pilot who stops following the plan).
    pub fn set_pilot_behaviour(&mut self, behaviour: PilotBehaviour) {
        self.pilot = behaviour;
    }

    /// Latched faults now.
    pub fn faults(&self) -> FaultSet {
        self.controller.supervisor().latched()
    }

    /// The controller's phase now.
    pub fn phase(&self) -> Phase {
        self.controller.sequencer().phase()
    }

    /// The strongest reaction over the trace.
    pub fn worst_reaction(&self) -> Reaction {
        self.trace
            .iter()
            .map(|s| s.report.reaction)
            .max()
            .unwrap_or(Reaction::None)
    }
}

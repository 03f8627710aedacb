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
use gait_control::controller::{
    Controller, ControllerConfig, FORCE_CAL_POINTS, Hardware, TickReport,
};
use gait_control::drivers::as5048a::{As5048a, Calibration, Direction};
use gait_control::drivers::buttons::{Button, ButtonConfig};
use gait_control::drivers::mcp3208::{Channel, ForceCalibration, ForceChannels, Mcp3208};
use gait_control::drivers::motor::{Motor, MotorConfig};
use gait_control::drivers::status::Indicator;
use gait_control::faults::{FaultSet, Reaction};
use gait_control::operator::{AllowedGaits, Gait, OperatorConfig};
use gait_control::position_loop::JointGains;
use gait_control::sequencer::{GaitTables, Phase, SequencerConfig};
use gait_control::supervisor::{Supervisor, SupervisorConfig};
use gait_core::BodyModel;
use gait_core::gait::StanceAnkleProfile;

use crate::as5048a::{EncoderMount, Mounting, SimAs5048a};
use crate::mcp3208::{ForceSensorCal, SimMcp3208};
use crate::motor::{SimBridgePin, SimPwm};
use crate::pilot::PilotTarget;
use crate::pins::{PressedLevel, SimButton, SimEStop};
use crate::plant::{Plant, PlantConfig, Side, SimError, TrueState};
use crate::shared::SharedF64;
use crate::wiring::{ENCODER_MOUNTS, FULL_SCALE_TORQUE_NM, Wiring};

/// Ankle encoder mountings (left, right).
pub const ANKLE_MOUNTS: [EncoderMount; 2] = [
    EncoderMount {
        zero_counts: 3000,
        mounting: Mounting::Positive,
    },
    EncoderMount {
        zero_counts: 12000,
        mounting: Mounting::Negative,
    },
];

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

/// Torque limit of the simulated hip and knee drives, N·m. Sized for stair
/// ascent at the paper's stair: with flat feet the 5-link model lifts the
/// body on the stance knee alone once the trailing foot leaves the floor,
/// 208 N·m static at the 43° start posture and about 320 N·m with the
/// table's accelerations (at 200 N·m the first stair swing faults).
/// Walking needs well under 200 N·m.
pub const DRIVE_TORQUE_LIMIT_NM: f32 = 350.0;

/// The device's tuning for the simulated exoskeleton (also the reference
/// for the board's values): joint gains, sequencer thresholds, force
/// calibrations matching [`ForceSensorCal`], the feed-forward model.
pub fn controller_config(model: BodyModel<f32>) -> Result<ControllerConfig, RigError> {
    let hip = JointGains {
        kp_nm_per_rad: 2000.0,
        ki_nm_per_rad_s: 1000.0,
        kd_nm_s_per_rad: 80.0,
        integral_limit_nm: 25.0,
        torque_limit_nm: DRIVE_TORQUE_LIMIT_NM,
        slew_nm_per_tick: 12.0,
    };
    let knee = JointGains {
        kp_nm_per_rad: 2000.0,
        ki_nm_per_rad_s: 1000.0,
        kd_nm_s_per_rad: 60.0,
        integral_limit_nm: 20.0,
        torque_limit_nm: DRIVE_TORQUE_LIMIT_NM,
        slew_nm_per_tick: 12.0,
    };
    Ok(ControllerConfig {
        dt_s: 0.001,
        gains: [hip, knee, hip, knee],
        // The simulated pilot does not shift weight onto the front foot
        // before a swing (no weight-shift model), so "weight on the stance
        // foot" is a lower bar here than on a device.
        sequencer: SequencerConfig {
            crutch_ready_n: 30.0,
            stance_foot_ready_n: 100.0,
            ..SequencerConfig::DEFAULT
        },
        force_calibration: [
            force_calibration(&ForceSensorCal::FOOT, FOOT_POINTS_N)?,
            force_calibration(&ForceSensorCal::FOOT, FOOT_POINTS_N)?,
            force_calibration(&ForceSensorCal::CRUTCH, CRUTCH_POINTS_N)?,
            force_calibration(&ForceSensorCal::CRUTCH, CRUTCH_POINTS_N)?,
        ],
        e_stop_active_high: true,
        rate_filter_hz: 40.0,
        still_rate_rad_s: 0.2,
        model,
    })
}

/// A calibration table for a sensor, as a clinic would record it: four
/// (counts, newtons) points spread over the sensor's 12-bit range.
fn force_calibration(
    sensor: &ForceSensorCal,
    points_n: [f32; FORCE_CAL_POINTS],
) -> Result<ForceCalibration<FORCE_CAL_POINTS>, RigError> {
    let counts = points_n.map(|n| sensor.counts(f64::from(n)));
    ForceCalibration::new(counts, points_n, 50, 4090, -50.0, 2500.0)
        .map_err(|_| RigError::Config("force calibration refused"))
}

/// Calibration points of the foot sensors (to 2.2 kN) and the crutch
/// sensors (to 550 N), within each sensor's 12-bit range.
const FOOT_POINTS_N: [f32; FORCE_CAL_POINTS] = [0.0, 600.0, 1400.0, 2200.0];
const CRUTCH_POINTS_N: [f32; FORCE_CAL_POINTS] = [0.0, 150.0, 350.0, 550.0];

/// Motor drive settings matching the simulated bridges.
pub fn motor_config() -> MotorConfig {
    MotorConfig {
        torque_limit_nm: DRIVE_TORQUE_LIMIT_NM,
        full_scale_torque_nm: FULL_SCALE_TORQUE_NM as f32,
        torque_constant_nm_per_a: 0.12,
        gear_ratio: 100.0,
        continuous_current_a: 8.0,
        i2t_warning_a2s: 300.0,
        i2t_fault_a2s: 600.0,
        derated_limit_nm: 160.0,
        slew_nm_per_tick: 12.0,
        soft_start_ticks: 40,
        dt_s: 0.001,
    }
}

fn calibration(mount: &EncoderMount) -> Calibration {
    Calibration {
        zero_offset_counts: mount.zero_counts,
        direction: match mount.mounting {
            Mounting::Positive => Direction::Positive,
            Mounting::Negative => Direction::Negative,
        },
    }
}

/// Why a rig could not be built.
#[derive(Debug)]
pub enum RigError {
    /// The plant refused its configuration or state.
    Sim(SimError),
    /// A controller, supervisor or driver configuration was refused.
    Config(&'static str),
}

impl core::fmt::Display for RigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Sim(e) => write!(f, "plant: {e:?}"),
            Self::Config(m) => write!(f, "configuration: {m}"),
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
    support_ticks: u64,
    pilot: PilotBehaviour,
    transfer_from_phi1: Option<f64>,
    transfer_s: f32,
}

/// Where the pilot's stance shank should be, given the controller's phase:
/// the planned profile during a swing; during the weight transfer a smooth
/// move from where the shank was at landing to the profile's start (as the
/// controller's transfer plans it); otherwise held at the profile's start.
fn pilot_target(
    b: &PilotBehaviour,
    phase: &Phase,
    transfer_from: Option<f64>,
    transfer_s: f32,
    now_s: f64,
) -> PilotTarget {
    match *b {
        PilotBehaviour::Fixed(t) => t,
        PilotBehaviour::FollowsPlan(profile) => match *phase {
            Phase::Swing { t_s, .. } => PilotTarget::Profile {
                profile,
                t0_s: now_s - f64::from(t_s),
            },
            Phase::Transfer { t_s, .. } => {
                let to = profile.at(0.0);
                let from = transfer_from.unwrap_or(to);
                let x = if transfer_s > 0.0 {
                    f64::from(t_s / transfer_s).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                let s = x * x * (3.0 - 2.0 * x);
                PilotTarget::Hold {
                    phi1_rad: from + s * (to - from),
                }
            }
            _ => PilotTarget::Hold {
                phi1_rad: profile.at(0.0),
            },
        },
    }
}

/// How a rig starts.
#[derive(Clone, Copy, Debug)]
pub struct RigSetup {
    /// The plant's parameters (terrain, pilot, model).
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
}

/// How the simulated pilot uses the crutches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PilotBehaviour {
    /// A fixed target for the whole run.
    Fixed(PilotTarget),
    /// A pilot who has learnt the gait (the paper's pilots practised 25
    /// cycles first): during each swing the stance shank follows the
    /// profile the gait was planned with, timed from the swing's start as
    /// the controller reports it; between swings the shank is held at the
    /// profile's start angle.
    FollowsPlan(StanceAnkleProfile<f64>),
}

/// Table III with the heel-rocker ankle limits
/// ([`gait_core::JointLimits::paper_with_heel_rocker`]): the plant's ankle
/// stop and the supervisor's ankle envelope both use them, as the board does.
pub fn heel_rocker_model() -> BodyModel<f64> {
    let m = BodyModel::<f64>::paper_table_iii();
    BodyModel::new(*m.links(), gait_core::JointLimits::paper_with_heel_rocker()).unwrap_or(m)
}

impl<'t> Rig<'t> {
    /// Builds the plant, the peripherals, the drivers and the controller.
    pub fn new(setup: &RigSetup, tables: GaitTables<'t>) -> Result<Self, RigError> {
        let mut plant = Plant::with_posture(
            setup.plant,
            setup.phi,
            [0.0; 5],
            setup.stance,
            setup.stance_foot_m,
        )?;
        plant.set_pilot(pilot_target(&setup.pilot, &Phase::Standing, None, 0.0, 0.0));
        let wiring = Wiring::new();
        let joint_encoders: [SimAs5048a; 4] = [0, 1, 2, 3].map(|j| {
            wiring
                .encoder(j)
                .unwrap_or_else(|| SimAs5048a::new(SharedF64::default(), ENCODER_MOUNTS[0]))
        });
        let ankle_cells: [SharedF64; 2] = Default::default();
        let ankle_encoders =
            [0, 1].map(|a| SimAs5048a::new(ankle_cells[a].clone(), ANKLE_MOUNTS[a]));
        let adc = wiring.force_adc();
        let clock = wiring.clock.clone();
        let mode = SimButton::new(clock.clone(), Vec::new(), PressedLevel::Low);
        let go = SimButton::new(clock, Vec::new(), PressedLevel::Low);
        let e_stop = SimEStop::new(PressedLevel::High);
        let indicators: [SimLed; 3] = Default::default();

        let mounts = [
            ENCODER_MOUNTS[0],
            ENCODER_MOUNTS[1],
            ENCODER_MOUNTS[2],
            ENCODER_MOUNTS[3],
            ANKLE_MOUNTS[0],
            ANKLE_MOUNTS[1],
        ];
        let devices = [
            joint_encoders[0].clone(),
            joint_encoders[1].clone(),
            joint_encoders[2].clone(),
            joint_encoders[3].clone(),
            ankle_encoders[0].clone(),
            ankle_encoders[1].clone(),
        ];
        let mut enc_iter = devices.into_iter().zip(mounts);
        let encoders: [As5048a<SimAs5048a>; 6] = std::array::from_fn(|_| {
            let (d, m) = enc_iter.next().unwrap_or_else(|| {
                (
                    SimAs5048a::new(SharedF64::default(), ENCODER_MOUNTS[0]),
                    ENCODER_MOUNTS[0],
                )
            });
            As5048a::new(d, calibration(&m))
        });
        let mut motors_vec = Vec::with_capacity(4);
        for m in &wiring.motors {
            let motor = Motor::new(m.pwm(), m.direction_pin(), m.enable_pin(), motor_config())
                .map_err(|_| RigError::Config("motor configuration refused"))?;
            motors_vec.push(motor);
        }
        let motors: [Motor<SimPwm, SimBridgePin, SimBridgePin>; 4] = motors_vec
            .try_into()
            .map_err(|_| RigError::Config("four motors"))?;
        let hw = Hardware {
            encoders,
            adc: Mcp3208::new(adc.clone()),
            force_channels: ForceChannels {
                left_foot: Channel::Ch0,
                right_foot: Channel::Ch1,
                left_crutch: Channel::Ch2,
                right_crutch: Channel::Ch3,
            },
            motors,
            mode: Button::new(SimInput::Button(mode.clone()), ButtonConfig::DEFAULT_1KHZ),
            go: Button::new(SimInput::Button(go.clone()), ButtonConfig::DEFAULT_1KHZ),
            e_stop: SimInput::EStop(e_stop.clone()),
            gait_led: Indicator::new(indicators[0].clone()),
            fault_led: Indicator::new(indicators[1].clone()),
            buzzer: Indicator::new(indicators[2].clone()),
        };
        let model: BodyModel<f32> = setup.plant.model.cast();
        let transfer_s = controller_config(model)?.sequencer.transfer_s;
        let allowed_list: Vec<Gait> = std::iter::once(setup.gait)
            .chain(
                [Gait::Walk, Gait::StairUp, Gait::StairDown]
                    .into_iter()
                    .filter(|g| *g != setup.gait),
            )
            .filter(|g| tables.get(*g).is_some())
            .collect();
        let allowed = AllowedGaits::new(&allowed_list)
            .map_err(|_| RigError::Config("no gait has a verified table"))?;
        let supervisor = Supervisor::new(SupervisorConfig::default_for(model.limits()))
            .map_err(|_| RigError::Config("supervisor configuration refused"))?;
        let controller = Controller::new(
            controller_config(model)?,
            tables,
            OperatorConfig {
                allowed,
                reset_hold_ticks: 3000,
            },
            supervisor,
        )
        .map_err(|_| RigError::Config("controller configuration refused"))?;
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
            support_ticks: setup.support_ticks,
            pilot: setup.pilot,
            transfer_from_phi1: None,
            transfer_s,
        };
        // Start the ankle readings at their true values (no lag to settle).
        let s = rig.plant.state();
        for (cell, a) in rig.ankle_cells.iter().zip(s.ankle_dorsiflexion_rad) {
            cell.set(a.unwrap_or(0.0));
        }
        rig.publish();
        Ok(rig)
    }

    fn publish(&self) {
        let s = self.plant.state();
        self.wiring.publish(&s);
        // The swing ankle is not modelled: its spring holds it near rest (0)
        // in the air, and at foot-flat it turns to the stance angle within a
        // few tens of milliseconds. Both ankle readings follow their targets
        // (stance: φ1; swing: rest) through a 30 ms first-order lag, so the
        // swap at landing reads as a fast but physical rotation, not a jump.
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
        let report = self.controller.tick(&mut self.hw, false);
        match report.phase {
            Phase::Transfer { .. } => {
                if self.transfer_from_phi1.is_none() {
                    self.transfer_from_phi1 = Some(self.plant.state().phi[0]);
                }
            }
            _ => self.transfer_from_phi1 = None,
        }
        let target = pilot_target(
            &self.pilot,
            &report.phase,
            self.transfer_from_phi1,
            self.transfer_s,
            self.plant.time_s(),
        );
        if target != self.plant.pilot() {
            self.plant.set_pilot(target);
        }
        let torques = self.wiring.motor_torques_nm();
        if self.now() >= self.support_ticks {
            self.plant.step(torques)?;
        }
        self.publish();
        self.wiring.clock.tick();
        self.trace.push(Sample {
            report,
            state: self.plant.state(),
        });
        self.trace.last().ok_or(SimError::NonFinite)
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

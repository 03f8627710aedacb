//! The standard wiring of the simulated exoskeleton: the cells that carry
//! the plant's joint angles and forces to the peripherals and the motor
//! bridges whose torques drive the plant, in one place so every harness
//! connects them the same way.
//!
//! Channel map of the force ADC (MCP3208): 0 left foot, 1 right foot,
//! 2 left crutch, 3 right crutch; on the device's other channels the hip
//! and knee amplifiers' current monitors (`DeviceConfig::drive_current_channels`). Encoder and motor order: left hip, left
//! knee, right hip, right knee ([`crate::plant::joint`]).

use embedded_hal::spi;
use exogait_device::DeviceConfig;
use exogait_device::sensors::LoadCellSpec;
use gait_control::drivers::as5048a::{Calibration, Direction};

use crate::as5048a::{EncoderMount, Mounting, SimAs5048a};
use crate::mcp3208::{ForceSensorCal, SimMcp3208};
use crate::motor::SimMotor;
use crate::plant::{Landing, Plant, SimError, TrueState};
use crate::shared::{SharedF64, SimClock};

/// ADC channel of each force sensor.
pub mod channel {
    /// Left foot.
    pub const LEFT_FOOT: usize = 0;
    /// Right foot.
    pub const RIGHT_FOOT: usize = 1;
    /// Left crutch.
    pub const LEFT_CRUTCH: usize = 2;
    /// Right crutch.
    pub const RIGHT_CRUTCH: usize = 3;
}

/// Default motor bridge: PWM resolution and joint torque at 100 % duty.
pub const MAX_DUTY: u16 = 4200;
/// Joint torque at 100 % duty, N·m.
pub const FULL_SCALE_TORQUE_NM: f64 = 400.0;

/// Encoder mountings used by [`Wiring::new`]: arbitrary offsets and one
/// reversed encoder per leg, so calibration mistakes show up.
pub const ENCODER_MOUNTS: [EncoderMount; 4] = [
    EncoderMount {
        zero_counts: 1234,
        mounting: Mounting::Positive,
    },
    EncoderMount {
        zero_counts: 15000,
        mounting: Mounting::Negative,
    },
    EncoderMount {
        zero_counts: 8191,
        mounting: Mounting::Negative,
    },
    EncoderMount {
        zero_counts: 40,
        mounting: Mounting::Positive,
    },
];

/// Shared cells and motor handles between a plant and its peripherals.
#[derive(Clone, Debug)]
pub struct Wiring {
    /// Anatomical joint angles (flexion positive), rad.
    pub joint_angles: [SharedF64; 4],
    /// Force on each ADC channel 0…3 (see [`channel`]), N.
    pub forces: [SharedF64; 4],
    /// The four motor bridges.
    pub motors: [SimMotor; 4],
    /// The tick counter.
    pub clock: SimClock,
    /// How each joint encoder is mounted (joint order).
    pub encoder_mounts: [EncoderMount; 4],
    /// The sensors on ADC channels 0…3 (see [`channel`]).
    pub force_sensors: [ForceSensorCal; 4],
    /// Each drive's amplifier current as joint torque over the last plant
    /// step, N·m (joint order): what its current monitor reports.
    pub drive_currents: [SharedF64; 4],
    /// The current monitors as counts per joint N·m, and the ADC channel
    /// of each (joint order; `None` on the bench harness: nothing
    /// connected).
    pub current_monitor: Option<(ForceSensorCal, [usize; 4])>,
}

/// The mounting a calibration sheet describes: the encoder reads
/// `zero_offset_counts` at the joint's zero, turning the way `direction`
/// says. Building the simulated device from its own calibration sheet
/// makes the calibration exact, as on a freshly calibrated device.
pub fn mount_of(cal: &Calibration) -> EncoderMount {
    EncoderMount {
        zero_counts: cal.zero_offset_counts,
        mounting: match cal.direction {
            Direction::Positive => Mounting::Positive,
            Direction::Negative => Mounting::Negative,
        },
    }
}

/// A load cell's characteristic as the simulated ADC input.
pub fn sensor_of(cell: &LoadCellSpec) -> ForceSensorCal {
    ForceSensorCal {
        offset_counts: f64::from(cell.zero_counts),
        counts_per_n: f64::from(cell.counts_per_n),
    }
}

impl Default for Wiring {
    fn default() -> Self {
        Self::new()
    }
}

impl Wiring {
    /// A bench harness: cells at zero, ideal torque-source bridges with
    /// [`MAX_DUTY`] and [`FULL_SCALE_TORQUE_NM`], encoders mounted as
    /// [`ENCODER_MOUNTS`], linear foot and crutch sensors
    /// ([`ForceSensorCal::FOOT`], [`ForceSensorCal::CRUTCH`]). The
    /// closed-loop rig uses [`Wiring::for_device`].
    pub fn new() -> Self {
        Self {
            joint_angles: Default::default(),
            forces: Default::default(),
            motors: std::array::from_fn(|_| SimMotor::new(MAX_DUTY, FULL_SCALE_TORQUE_NM)),
            clock: SimClock::new(),
            encoder_mounts: ENCODER_MOUNTS,
            force_sensors: [
                ForceSensorCal::FOOT,
                ForceSensorCal::FOOT,
                ForceSensorCal::CRUTCH,
                ForceSensorCal::CRUTCH,
            ],
            drive_currents: Default::default(),
            current_monitor: None,
        }
    }

    /// The device as shipped: its drives behind the bridges (peak torque,
    /// torque–speed line, I²t derating), encoders mounted as its
    /// calibration sheet says, its load cells on the ADC.
    pub fn for_device(cfg: &DeviceConfig) -> Self {
        let [e0, e1, e2, e3, ..] = cfg.encoders;
        Self {
            joint_angles: Default::default(),
            forces: Default::default(),
            motors: std::array::from_fn(|j| {
                SimMotor::with_drive(MAX_DUTY, cfg.drives[j], cfg.motors[j])
            }),
            clock: SimClock::new(),
            encoder_mounts: [e0, e1, e2, e3].map(|c| mount_of(&c)),
            force_sensors: [
                sensor_of(&cfg.foot_sensor),
                sensor_of(&cfg.foot_sensor),
                sensor_of(&cfg.crutch_sensor),
                sensor_of(&cfg.crutch_sensor),
            ],
            drive_currents: Default::default(),
            // The four drives are alike (`DeviceConfig::drives`).
            current_monitor: cfg.drives.first().map(|d| {
                let m = &cfg.drive_current_monitor;
                let per_amp = d.joint_torque_per_amp();
                let cal = ForceSensorCal {
                    offset_counts: f64::from(m.counts(0.0, per_amp)),
                    counts_per_n: f64::from(m.counts_per_amp() / per_amp),
                };
                (cal, cfg.drive_current_channels.map(|c| c as usize))
            }),
        }
    }

    /// The encoder of joint `j` (order of [`crate::plant::joint`]), mounted
    /// as [`Wiring::encoder_mounts`] says.
    pub fn encoder(&self, j: usize) -> Option<SimAs5048a> {
        let angle = self.joint_angles.get(j)?.clone();
        let mount = *self.encoder_mounts.get(j)?;
        Some(SimAs5048a::new(angle, mount))
    }

    /// The force ADC with the four sensors connected
    /// ([`Wiring::force_sensors`]).
    pub fn force_adc(&self) -> SimMcp3208 {
        let adc = SimMcp3208::new();
        for (ch, (cell, cal)) in self.forces.iter().zip(self.force_sensors).enumerate() {
            adc.connect(ch, cell.clone(), cal);
        }
        if let Some((cal, channels)) = self.current_monitor {
            for (cell, ch) in self.drive_currents.iter().zip(channels) {
                adc.connect(ch, cell.clone(), cal);
            }
        }
        adc
    }

    /// Writes the plant's true state into the cells (call after each
    /// plant step, before the controller's next tick).
    pub fn publish(&self, state: &TrueState) {
        for (cell, &a) in self.joint_angles.iter().zip(&state.joint_angles_rad) {
            cell.set(a);
        }
        let f = [
            state.foot_forces_n[0],
            state.foot_forces_n[1],
            state.crutch_forces_n[0],
            state.crutch_forces_n[1],
        ];
        for (cell, v) in self.forces.iter().zip(f) {
            cell.set(v);
        }
        for (m, &w) in self.motors.iter().zip(&state.joint_rates_rad_s) {
            m.set_joint_speed(w);
        }
    }

    /// One control period of the plant: steps it under the bridges'
    /// torques, publishes the new state to the sensors and advances the
    /// clock. The controller's tick goes between two calls.
    pub fn step(&self, plant: &mut Plant) -> Result<Option<Landing>, SimError> {
        self.record_drive_currents();
        let landing = self.drive_plant(plant)?;
        self.integrate_thermal(plant.config().dt_s);
        self.publish(&plant.state());
        self.clock.tick();
        Ok(landing)
    }

    /// Steps the plant one control period under what the bridges do now:
    /// the torques the enabled ones drive, the brakes of the disabled ones.
    pub fn drive_plant(&self, plant: &mut Plant) -> Result<Option<Landing>, SimError> {
        plant.set_brakes(self.brake_dampings());
        plant.step(self.driven_torques_nm())
    }

    /// Sets what the current monitors report for the plant step about to
    /// be taken (call just before it, with the same bridge state).
    pub fn record_drive_currents(&self) {
        for (cell, m) in self.drive_currents.iter().zip(&self.motors) {
            cell.set(m.amplifier_torque_nm());
        }
    }

    /// Advances every drive's winding model over one plant step.
    pub fn integrate_thermal(&self, dt_s: f64) {
        for m in &self.motors {
            m.integrate_thermal(dt_s);
        }
    }

    /// The torques the motor bridges produce now, N·m: driven, or a
    /// disabled bridge's brake at the joint's last published speed.
    pub fn motor_torques_nm(&self) -> [f64; 4] {
        std::array::from_fn(|j| self.motors.get(j).map_or(0.0, SimMotor::torque_nm))
    }

    /// The torques the power stages drive now (input of
    /// [`crate::plant::Plant::step`]), N·m; the brakes are separate
    /// ([`Wiring::brake_dampings`]).
    pub fn driven_torques_nm(&self) -> [f64; 4] {
        std::array::from_fn(|j| self.motors.get(j).map_or(0.0, SimMotor::driven_torque_nm))
    }

    /// Every joint's dynamic-brake damping now, N·m·s/rad (input of
    /// [`crate::plant::Plant::set_brakes`]).
    pub fn brake_dampings(&self) -> [f64; 4] {
        std::array::from_fn(|j| {
            self.motors
                .get(j)
                .map_or(0.0, SimMotor::brake_damping_nm_s_per_rad)
        })
    }
}

/// A bus error kind for fault injection that no healthy bus produces.
pub const INJECTED_SPI_ERROR: spi::ErrorKind = spi::ErrorKind::ChipSelectFault;

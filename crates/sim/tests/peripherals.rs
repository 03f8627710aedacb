//! Each simulated peripheral against gait-control's real driver: the
//! values come through, and every injected fault arrives as the matching
//! typed error.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::f64::consts::PI;

use embedded_hal::digital::InputPin;
use embedded_hal::spi::{Error as _, ErrorKind, Operation, SpiDevice};
use gait_control::drivers::as5048a::{
    self, As5048a, Calibration, Direction, ErrorRegister, wrapped_delta,
};
use gait_control::drivers::buttons::{ActiveLevel, Button, ButtonConfig, Event};
use gait_control::drivers::mcp3208::{
    self, Channel, ForceCalibration, ForceFault, Mcp3208, decode_reply,
};
use gait_control::drivers::motor::{self, Motor, MotorConfig};
use sim::as5048a::{EncoderMount, Mounting, SimAs5048a, error_bit};
use sim::mcp3208::{ChannelFault, ForceSensorCal, SimMcp3208};
use sim::motor::{BridgePin, SimPinError, SimPwmError};
use sim::pins::{PressedLevel, SimButton, SimEStop};
use sim::plant::STANDING;
use sim::wiring::{self, ENCODER_MOUNTS, INJECTED_SPI_ERROR, Wiring};
use sim::{Plant, PlantConfig, SharedF64, Side, SimClock};

const RAD_PER_COUNT: f64 = 2.0 * PI / 16384.0;

fn calibration_for(mount: EncoderMount) -> Calibration {
    Calibration {
        zero_offset_counts: mount.zero_counts,
        direction: match mount.mounting {
            Mounting::Positive => Direction::Positive,
            Mounting::Negative => Direction::Negative,
        },
    }
}

/// The driver on a simulated encoder of joint `j`, and a handle on the chip.
fn encoder(angle: &SharedF64, j: usize) -> (As5048a<SimAs5048a>, SimAs5048a) {
    let mount = ENCODER_MOUNTS[j];
    let chip = SimAs5048a::new(angle.clone(), mount);
    (As5048a::new(chip.clone(), calibration_for(mount)), chip)
}

#[test]
fn encoder_driver_reads_the_joint_angle_to_14_bits() {
    for j in 0..4 {
        let angle = SharedF64::new(0.0);
        let (mut enc, _) = encoder(&angle, j);
        for k in -40..=40 {
            let a = f64::from(k) * 0.0737; // ±2.95 rad, off the count grid
            angle.set(a);
            let r = enc.read_angle().unwrap();
            let err = f64::from(r.angle_rad) - a;
            assert!(
                err.abs() <= 0.5 * RAD_PER_COUNT + 1e-6,
                "joint {j}, angle {a}: read {} (error {err})",
                r.angle_rad
            );
        }
        let d = enc.read_diagnostics().unwrap();
        assert!(d.is_healthy(), "{d:?}");
        assert!(enc.read_magnitude().unwrap() > 1000);
    }
}

#[test]
fn encoder_driver_sees_each_fault_as_its_typed_error() {
    let angle = SharedF64::new(0.3);
    let (mut enc, chip) = encoder(&angle, 1);

    chip.fail_transactions(1, INJECTED_SPI_ERROR);
    match enc.read_angle() {
        Err(as5048a::Error::Bus(e)) => assert_eq!(e.kind(), ErrorKind::ChipSelectFault),
        other => panic!("{other:?}"),
    }
    assert!(enc.read_angle().is_ok());

    chip.corrupt_answers(1);
    assert_eq!(enc.read_angle(), Err(as5048a::Error::Parity));
    assert!(enc.read_angle().is_ok());

    chip.raise_error(error_bit::FRAMING);
    assert_eq!(
        enc.read_angle(),
        Err(as5048a::Error::ErrorFlag(Some(ErrorRegister {
            framing: true,
            invalid_command: false,
            parity: false,
        })))
    );
    // The driver cleared it.
    assert!(enc.read_angle().is_ok());

    // Frozen: the raw counts stop following the joint.
    let before = enc.read_angle().unwrap().raw_counts;
    chip.freeze(true);
    angle.set(0.5);
    assert_eq!(enc.read_angle().unwrap().raw_counts, before);
    chip.freeze(false);
    let live = enc.read_angle().unwrap();
    assert!((f64::from(live.angle_rad) - 0.5).abs() < RAD_PER_COUNT);

    // Jump by K counts.
    chip.jump(3000);
    let jumped = enc.read_angle().unwrap().raw_counts;
    assert_eq!(wrapped_delta(live.raw_counts, jumped).unsigned_abs(), 3000);

    // A weak magnet shows in the diagnostics.
    chip.set_weak_field(true);
    let d = enc.read_diagnostics().unwrap();
    assert!(d.comp_high && !d.is_healthy());
}

#[test]
fn a_command_with_bad_parity_raises_the_flag_the_driver_reports() {
    let angle = SharedF64::new(0.0);
    let (mut enc, chip) = encoder(&angle, 0);
    // Another master on the bus sends a read of ANGLE with a wrong parity bit.
    let mut raw = chip.clone();
    let mut frame = 0x7FFFu16.to_be_bytes();
    raw.transaction(&mut [Operation::TransferInPlace(&mut frame)])
        .unwrap();
    match enc.read_angle() {
        Err(as5048a::Error::ErrorFlag(Some(reg))) => assert!(reg.parity, "{reg:?}"),
        other => panic!("{other:?}"),
    }
    assert_eq!(chip.error_bits(), 0);
    assert!(enc.read_angle().is_ok());
}

/// The controller-side calibration that inverts a sensor model, from two
/// points (what a bench calibration would measure).
fn force_calibration(cal: ForceSensorCal, max_n: f32) -> ForceCalibration<2> {
    let top = cal.counts(f64::from(max_n));
    ForceCalibration::new(
        [200, top],
        [0.0, cal.newtons(top) as f32],
        50,
        4050,
        -50.0,
        max_n * 1.1,
    )
    .unwrap()
}

const CHANNELS: [Channel; 4] = [Channel::Ch0, Channel::Ch1, Channel::Ch2, Channel::Ch3];

#[test]
fn adc_driver_reads_each_force_within_calibration_error() {
    let w = Wiring::new();
    let adc = w.force_adc();
    let mut drv = Mcp3208::new(adc.clone());
    let cals = [
        force_calibration(ForceSensorCal::FOOT, 1000.0),
        force_calibration(ForceSensorCal::FOOT, 1000.0),
        force_calibration(ForceSensorCal::CRUTCH, 500.0),
        force_calibration(ForceSensorCal::CRUTCH, 500.0),
    ];
    for k in 0..=20 {
        // Different forces on each channel, so a wrong channel shows.
        let f = [
            f64::from(k) * 45.0,
            900.0 - f64::from(k) * 40.0,
            f64::from(k) * 22.0 + 3.0,
            470.0 - f64::from(k) * 21.0,
        ];
        for (cell, v) in w.forces.iter().zip(f) {
            cell.set(v);
        }
        for ch in 0..4 {
            assert_eq!(drv.read_raw(CHANNELS[ch]).unwrap(), adc.counts(ch));
            let n = drv.read_force(CHANNELS[ch], &cals[ch]).unwrap();
            let gain = if ch < 2 {
                ForceSensorCal::FOOT.counts_per_n
            } else {
                ForceSensorCal::CRUTCH.counts_per_n
            };
            // Half a count of quantisation, plus f32 rounding.
            let tol = 0.5 / gain + 1e-3;
            assert!(
                (f64::from(n) - f[ch]).abs() <= tol,
                "channel {ch}: {n} vs {}",
                f[ch]
            );
        }
    }
    // Unconnected channels read 0, and the chip converted once per read.
    assert_eq!(drv.read_raw(Channel::Ch7).unwrap(), 0);
    assert_eq!(adc.conversions(), 21 * 8 + 1);
}

#[test]
fn adc_driver_sees_open_short_and_bus_faults() {
    let w = Wiring::new();
    let adc = w.force_adc();
    let mut drv = Mcp3208::new(adc.clone());
    let cal = force_calibration(ForceSensorCal::FOOT, 1000.0);
    w.forces[wiring::channel::RIGHT_FOOT].set(300.0);
    assert!(drv.read_force(Channel::Ch1, &cal).is_ok());

    adc.set_fault(wiring::channel::RIGHT_FOOT, Some(ChannelFault::Open));
    assert_eq!(
        drv.read_force(Channel::Ch1, &cal),
        Err(mcp3208::Error::Sensor(ForceFault::OpenCircuit {
            counts: 0
        }))
    );
    adc.set_fault(wiring::channel::RIGHT_FOOT, Some(ChannelFault::Short));
    assert_eq!(
        drv.read_force(Channel::Ch1, &cal),
        Err(mcp3208::Error::Sensor(ForceFault::ShortCircuit {
            counts: 4095
        }))
    );
    adc.set_fault(wiring::channel::RIGHT_FOOT, None);
    adc.fail_transactions(2, ErrorKind::Overrun);
    for _ in 0..2 {
        match drv.read_force(Channel::Ch1, &cal) {
            Err(mcp3208::Error::Bus(e)) => assert_eq!(e.kind(), ErrorKind::Overrun),
            other => panic!("{other:?}"),
        }
    }
    assert!(drv.read_force(Channel::Ch1, &cal).is_ok());
    // A force beyond the sensor clamps at full scale: the driver's short
    // check catches it (a saturated sensor is not believed).
    w.forces[wiring::channel::RIGHT_FOOT].set(9000.0);
    assert!(matches!(
        drv.read_force(Channel::Ch1, &cal),
        Err(mcp3208::Error::Sensor(ForceFault::ShortCircuit { .. }))
    ));
}

#[test]
fn adc_reply_decodes_with_the_datasheet_bit_positions() {
    // Independent of the driver's decode: the raw bytes as a driver sends
    // them, decoded by hand from the datasheet (null bit = bit 4 of byte 1).
    let f = SharedF64::new(250.0);
    let mut adc = SimMcp3208::new();
    adc.connect(6, f, ForceSensorCal::CRUTCH);
    let mut b = [0b0000_0111, 0b1000_0000, 0];
    adc.transaction(&mut [Operation::TransferInPlace(&mut b)])
        .unwrap();
    assert_eq!(b[1] & 0x10, 0, "null bit");
    let counts = (u16::from(b[1] & 0x0F) << 8) | u16::from(b[2]);
    assert_eq!(counts, 1950);
    assert_eq!(decode_reply(b), 1950);
    // High-impedance bits before the null bit read as the pull-up.
    assert_eq!(b[0], 0xFF);
    assert_eq!(b[1] & 0xE0, 0xE0);
}

fn motor_config() -> MotorConfig {
    MotorConfig {
        torque_limit_nm: 100.0,
        full_scale_torque_nm: wiring::FULL_SCALE_TORQUE_NM as f32,
        torque_constant_nm_per_a: 0.1,
        gear_ratio: 100.0,
        continuous_current_a: 10.0,
        i2t_warning_a2s: 1e6,
        i2t_fault_a2s: 2e6,
        derated_limit_nm: 90.0,
        slew_nm_per_tick: 5.0,
        soft_start_ticks: 0,
        dt_s: 0.001,
    }
}

type SimDriver = Motor<sim::motor::SimPwm, sim::motor::SimBridgePin, sim::motor::SimBridgePin>;

fn motor_driver(w: &Wiring, j: usize) -> SimDriver {
    let m = &w.motors[j];
    Motor::new(m.pwm(), m.direction_pin(), m.enable_pin(), motor_config()).unwrap()
}

#[test]
fn motor_driver_torque_reaches_the_plant() {
    let w = Wiring::new();
    let mut drivers: Vec<SimDriver> = (0..4).map(|j| motor_driver(&w, j)).collect();
    for d in &mut drivers {
        d.disable().unwrap();
        d.enable().unwrap();
    }
    let mut plant = Plant::with_posture(
        PlantConfig::default(),
        STANDING,
        [0.0; 5],
        Side::Left,
        [0.0, 0.0],
    )
    .unwrap();
    // Right hip (swing) flexion +20 N·m, right knee flexion +6 N·m; the
    // left leg held straight by a stiff servo through its drivers.
    let quantum = wiring::FULL_SCALE_TORQUE_NM / f64::from(wiring::MAX_DUTY);
    for _ in 0..80 {
        let s = plant.state();
        let hold = |q: f64, dq: f64| (-3000.0 * q - 150.0 * dq) as f32;
        let cmd = [
            hold(s.joint_angles_rad[0], s.joint_rates_rad_s[0]),
            hold(s.joint_angles_rad[1], s.joint_rates_rad_s[1]),
            20.0f32,
            6.0,
        ];
        let mut applied = [0.0f64; 4];
        for (j, d) in drivers.iter_mut().enumerate() {
            applied[j] = f64::from(d.update(cmd[j]).unwrap().applied_nm);
        }
        let torques = w.motor_torques_nm();
        for j in 0..4 {
            assert!(
                (torques[j] - applied[j]).abs() <= 0.5 * quantum + 1e-4,
                "joint {j}: bridge {} vs driver {}",
                torques[j],
                applied[j]
            );
        }
        w.step(&mut plant).unwrap();
    }
    assert_eq!(w.clock.now(), 80);
    let s = plant.state();
    assert!((s.motor_torques_nm[2] - 20.0).abs() <= quantum);
    assert!((s.motor_torques_nm[3] - 6.0).abs() <= quantum);
    assert!(
        s.joint_angles_rad[2] > 0.01 && s.joint_angles_rad[3] > 0.01,
        "{:?}",
        s.joint_angles_rad
    );
    // The published angle is what an encoder on that joint reads.
    let (mut enc, _) = encoder(&w.joint_angles[2], 2);
    let r = enc.read_angle().unwrap();
    assert!((f64::from(r.angle_rad) - s.joint_angles_rad[2]).abs() < RAD_PER_COUNT);
    for m in &w.motors {
        assert_eq!(m.reversals_under_duty(), 0);
    }
}

#[test]
fn motor_driver_sees_pwm_and_pin_faults() {
    let w = Wiring::new();
    let mut d = motor_driver(&w, 0);
    d.enable().unwrap();
    d.update(3.0).unwrap(); // the first tick after enable is zero
    assert_eq!(w.motors[0].torque_nm(), 0.0);
    d.update(3.0).unwrap();
    // Within one duty step of the bridge's resolution.
    let step = sim::wiring::FULL_SCALE_TORQUE_NM / f64::from(sim::wiring::MAX_DUTY);
    assert!((w.motors[0].torque_nm() - 3.0).abs() <= step);

    w.motors[0].fail_pwm_writes(1);
    assert_eq!(d.update(4.0), Err(motor::Error::Pwm(SimPwmError::Injected)));
    // The driver disabled the bridge: no torque, fault latched.
    assert_eq!(w.motors[0].torque_nm(), 0.0);
    assert_eq!(d.update(4.0), Err(motor::Error::OutputFault));

    let mut d = motor_driver(&w, 1);
    w.motors[1].fail_pin_writes(BridgePin::Enable, 1);
    assert_eq!(d.enable(), Err(motor::Error::Pin(SimPinError)));
    assert_eq!(w.motors[1].torque_nm(), 0.0);

    let mut d = motor_driver(&w, 2);
    d.enable().unwrap();
    d.update(2.0).unwrap();
    d.update(2.0).unwrap();
    w.motors[2].fail_pin_writes(BridgePin::Direction, 1);
    assert_eq!(d.update(-2.0), Err(motor::Error::Pin(SimPinError)));
    assert_eq!(w.motors[2].torque_nm(), 0.0);
    let (_, _, enabled) = w.motors[2].outputs();
    assert!(!enabled);
}

#[test]
fn button_script_with_bounce_gives_one_press_and_one_release() {
    let clock = SimClock::new();
    let pin = SimButton::new(
        clock.clone(),
        vec![(100, true), (400, false)],
        PressedLevel::Low,
    )
    .with_bounce(7);
    let handle = pin.clone();
    let mut button = Button::new(pin, ButtonConfig::DEFAULT_1KHZ);
    assert_eq!(ButtonConfig::DEFAULT_1KHZ.active, ActiveLevel::Low);
    let mut events = Vec::new();
    for t in 0..700u64 {
        clock.set(t);
        if let Some(e) = button.tick().event {
            events.push((t, e));
        }
    }
    assert_eq!(events.len(), 2, "{events:?}");
    assert!(matches!(events[0], (t, Event::Pressed) if (100..=130).contains(&t)));
    assert!(matches!(events[1], (t, Event::Released { .. }) if (400..=430).contains(&t)));

    handle.fail_reads(1);
    assert!(button.tick().input_fault);
    assert!(!button.tick().input_fault);
}

#[test]
fn estop_reads_and_fails() {
    let stop = SimEStop::default();
    let mut pin = stop.clone();
    assert!(!pin.is_high().unwrap());
    stop.set_pressed(true);
    assert!(pin.is_high().unwrap() && !pin.is_low().unwrap());
    stop.fail_reads(1);
    assert_eq!(pin.is_high(), Err(SimPinError));
    assert!(pin.is_high().unwrap());
}

/// The device's current monitors, end to end: the drive's bridge, the
/// simulated monitor on its ADC channel, gait-control's driver reading it
/// with the device's calibration, give back the torque the bridge puts
/// out (within a count, 0.1 N·m), either sign, and nothing while the drive
/// is disabled (its brake's current is not the amplifier's).
#[test]
fn the_device_s_current_monitors_read_the_bridges_torque_through_its_calibration() {
    let device = exogait_device::DeviceConfig::exogait().unwrap();
    let w = Wiring::for_device(&device);
    let mut adc = Mcp3208::new(w.force_adc());
    let per_count = 1.0 / f64::from(device.drive_current_monitor.counts_per_amp())
        * f64::from(device.drives[0].joint_torque_per_amp());
    for (j, m) in w.motors.iter().enumerate() {
        let mut driver =
            Motor::new(m.pwm(), m.direction_pin(), m.enable_pin(), device.motors[j]).unwrap();
        driver.disable().unwrap();
        driver.enable().unwrap();
        let cal = device.controller.drive_current_calibration[j];
        let channel = device.drive_current_channels[j];
        let asked = if j % 2 == 0 { 120.0f32 } else { -75.0 };
        for _ in 0..60 {
            driver.update(asked).unwrap();
        }
        w.record_drive_currents();
        let read = f64::from(adc.read_drive_torque(channel, &cal).unwrap());
        assert!(
            (read - m.torque_nm()).abs() <= per_count,
            "joint {j}: read {read}, bridge {}",
            m.torque_nm()
        );
        assert!((m.torque_nm() - f64::from(asked)).abs() < 0.1, "joint {j}");
        driver.disable().unwrap();
        // Moving, braked: the brake's torque is large, the amplifier's none.
        m.set_joint_speed(0.5);
        assert!(m.torque_nm().abs() > 50.0, "joint {j}: {}", m.torque_nm());
        w.record_drive_currents();
        let off = f64::from(adc.read_drive_torque(channel, &cal).unwrap());
        assert!(off.abs() <= per_count, "joint {j} disabled: {off}");
    }
}

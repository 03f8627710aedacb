//! MCP3208 driver: frame encoding, mock-bus sequences, force calibration.

use crate::common::{FaultySpi, frame, frames};
use embedded_hal::spi::ErrorKind;
use gait_control::drivers::mcp3208::{
    CalibrationError, Channel, DriveCurrentCalibration, Error, ForceCalibration, ForceFault,
    Mcp3208, decode_reply, encode_request,
};
use proptest::prelude::*;

const ALL: [Channel; 8] = [
    Channel::Ch0,
    Channel::Ch1,
    Channel::Ch2,
    Channel::Ch3,
    Channel::Ch4,
    Channel::Ch5,
    Channel::Ch6,
    Channel::Ch7,
];

/// 0 N at 200 counts, 400 N at 1000, 1000 N at 3000; open below 50,
/// shorted above 4000; rated 0..=1200 N (slightly negative allowed: -20 N).
fn cal() -> ForceCalibration<3> {
    ForceCalibration::new(
        [200, 1000, 3000],
        [0.0, 400.0, 1000.0],
        50,
        4000,
        -20.0,
        1200.0,
    )
    .unwrap()
}

fn new_adc(
    groups: &[[embedded_hal_mock::eh1::spi::Transaction<u8>; 3]],
    fail_at: Option<usize>,
) -> Mcp3208<FaultySpi> {
    Mcp3208::new(FaultySpi::new(&frames(groups), fail_at))
}

fn destroy_adc(adc: Mcp3208<FaultySpi>) {
    adc.destroy().done();
}

/// A reply carrying `counts` with junk in the bits the ADC leaves floating.
fn reply(counts: u16) -> [u8; 3] {
    [0xFF, 0xE0 | (counts >> 8) as u8, (counts & 0xFF) as u8]
}

#[test]
fn request_frames_match_datasheet() {
    assert_eq!(encode_request(Channel::Ch0), [0x06, 0x00, 0x00]);
    assert_eq!(encode_request(Channel::Ch3), [0x06, 0xC0, 0x00]);
    assert_eq!(encode_request(Channel::Ch4), [0x07, 0x00, 0x00]);
    assert_eq!(encode_request(Channel::Ch5), [0x07, 0x40, 0x00]);
    assert_eq!(encode_request(Channel::Ch7), [0x07, 0xC0, 0x00]);
}

#[test]
fn reply_decoding_ignores_null_and_floating_bits() {
    assert_eq!(decode_reply([0xFF, 0xEA, 0xBC]), 0xABC);
    assert_eq!(decode_reply([0x00, 0x10, 0x00]), 0);
    assert_eq!(decode_reply([0x00, 0x0F, 0xFF]), 0xFFF);
}

#[test]
fn read_raw_one_cs_frame() {
    let mut adc = new_adc(&[frame(&[0x07, 0x40, 0x00], &reply(0x5A5))], None);
    assert_eq!(adc.read_raw(Channel::Ch5).unwrap(), 0x5A5);
    destroy_adc(adc);
}

#[test]
fn read_force_calibrated() {
    let mut adc = new_adc(&[frame(&[0x06, 0x40, 0x00], &reply(600))], None);
    let n = adc.read_force(Channel::Ch1, &cal()).unwrap();
    assert!((n - 200.0).abs() < 1e-3, "{n}");
    destroy_adc(adc);
}

#[test]
fn open_circuit_is_a_fault() {
    let mut adc = new_adc(&[frame(&[0x06, 0x00, 0x00], &reply(10))], None);
    assert_eq!(
        adc.read_force(Channel::Ch0, &cal()),
        Err(Error::Sensor(ForceFault::OpenCircuit { counts: 10 }))
    );
    destroy_adc(adc);
}

#[test]
fn short_circuit_is_a_fault() {
    let mut adc = new_adc(&[frame(&[0x06, 0x80, 0x00], &reply(4095))], None);
    assert_eq!(
        adc.read_force(Channel::Ch2, &cal()),
        Err(Error::Sensor(ForceFault::ShortCircuit { counts: 4095 }))
    );
    destroy_adc(adc);
}

#[test]
fn out_of_range_is_reported_unclamped() {
    // 3900 counts extrapolates to 1270 N > 1200 N.
    match cal().convert(3900) {
        Err(ForceFault::OutOfRange {
            counts: 3900,
            newtons,
        }) => {
            assert!((newtons - 1270.0).abs() < 1e-2, "{newtons}");
        }
        other => panic!("{other:?}"),
    }
    // 100 counts extrapolates to -50 N < -20 N.
    assert!(matches!(
        cal().convert(100),
        Err(ForceFault::OutOfRange { .. })
    ));
}

#[test]
fn bus_error_is_reported() {
    let mut adc = new_adc(&[], Some(0));
    assert_eq!(
        adc.read_raw(Channel::Ch0),
        Err(Error::Bus(ErrorKind::Other))
    );
    destroy_adc(adc);
}

#[test]
fn bad_calibrations_are_refused() {
    assert_eq!(
        ForceCalibration::new([200, 200], [0.0, 1.0], 50, 4000, 0.0, 10.0),
        Err(CalibrationError::NotMonotonic)
    );
    assert_eq!(
        ForceCalibration::new([200, 300], [0.0, f32::NAN], 50, 4000, 0.0, 10.0),
        Err(CalibrationError::NotMonotonic)
    );
    assert_eq!(
        ForceCalibration::new([200, 300], [0.0, 1.0], 4000, 50, 0.0, 10.0),
        Err(CalibrationError::BadBounds)
    );
    assert_eq!(
        ForceCalibration::new([200, 300], [0.0, 1.0], 50, 4096, 0.0, 10.0),
        Err(CalibrationError::BadBounds)
    );
    assert_eq!(
        ForceCalibration::new([], [], 50, 4000, 0.0, 10.0),
        Err::<ForceCalibration<0>, _>(CalibrationError::NotMonotonic)
    );
}

proptest! {
    #[test]
    fn request_bits(i in 0usize..8) {
        let ch = ALL[i];
        let f = encode_request(ch);
        // Five leading zeros, start bit, single-ended bit.
        prop_assert_eq!(f[0] & 0xF8, 0);
        prop_assert_eq!(f[0] & 0b110, 0b110);
        let decoded = ((f[0] & 1) << 2) | (f[1] >> 6);
        prop_assert_eq!(decoded as usize, i);
        prop_assert_eq!(f[1] & 0x3F, 0);
        prop_assert_eq!(f[2], 0);
    }

    #[test]
    fn reply_roundtrip(v in 0u16..4096, junk0 in any::<u8>(), junk1 in 0u8..16) {
        let r = [junk0, (junk1 << 4) | (v >> 8) as u8, (v & 0xFF) as u8];
        prop_assert_eq!(decode_reply(r), v);
    }

    #[test]
    fn reply_is_12_bit(r in any::<[u8; 3]>()) {
        prop_assert!(decode_reply(r) <= 0x0FFF);
    }

    #[test]
    fn convert_never_returns_out_of_bounds(counts in any::<u16>()) {
        if let Ok(n) = cal().convert(counts) {
            prop_assert!((-20.0..=1200.0).contains(&n));
            prop_assert!((50..=4000).contains(&counts));
        }
    }
}

/// A drive's current monitor: 2,048 counts at 0 A, 0.1 N·m a count.
fn drive_cal() -> DriveCurrentCalibration {
    DriveCurrentCalibration::new(2048, 0.1, 100, 4000).unwrap()
}

#[test]
fn a_drive_current_reads_as_joint_torque_either_way() {
    let mut adc = new_adc(
        &[
            frame(&[0x07, 0x00, 0x00], &reply(2548)),
            frame(&[0x07, 0xC0, 0x00], &reply(1548)),
        ],
        None,
    );
    let flex = adc.read_drive_torque(Channel::Ch4, &drive_cal()).unwrap();
    let ext = adc.read_drive_torque(Channel::Ch7, &drive_cal()).unwrap();
    assert!((flex - 50.0).abs() < 1e-3, "{flex}");
    assert!((ext + 50.0).abs() < 1e-3, "{ext}");
    destroy_adc(adc);
}

#[test]
fn a_drive_current_monitor_at_a_rail_is_a_fault_not_a_current() {
    let c = drive_cal();
    assert_eq!(c.convert(99), Err(ForceFault::OpenCircuit { counts: 99 }));
    assert_eq!(
        c.convert(4001),
        Err(ForceFault::ShortCircuit { counts: 4001 })
    );
    assert!(c.convert(100).is_ok() && c.convert(4000).is_ok());
}

#[test]
fn a_drive_current_calibration_needs_its_zero_between_the_rails() {
    for (zero, per, open, short) in [
        (50, 0.1, 100, 4000),
        (4050, 0.1, 100, 4000),
        (2048, 0.0, 100, 4000),
        (2048, f32::NAN, 100, 4000),
        (2048, 0.1, 100, 4096),
    ] {
        assert_eq!(
            DriveCurrentCalibration::new(zero, per, open, short),
            Err(CalibrationError::BadBounds),
            "{zero} {per} {open} {short}"
        );
    }
}

//! AS5048A driver: frame encoding, mock-bus sequences, calibration.

use crate::common::{FaultySpi, frame, frames};
use core::f32::consts::PI;
use embedded_hal::spi::ErrorKind;
use gait_control::drivers::as5048a::{
    As5048a, COUNTS_PER_REV, Calibration, Diagnostics, Direction, Error, ErrorRegister, FrameError,
    decode_response, encode_command, reg, wrapped_delta,
};
use proptest::prelude::*;

const CAL: Calibration = Calibration {
    zero_offset_counts: 0x1000,
    direction: Direction::Positive,
};

/// A response frame with even parity and EF clear.
fn response(data: u16) -> u16 {
    encode_command(data, false)
}

fn be(x: u16) -> [u8; 2] {
    x.to_be_bytes()
}

fn new_enc(
    groups: &[[embedded_hal_mock::eh1::spi::Transaction<u8>; 3]],
    fail_at: Option<usize>,
) -> As5048a<FaultySpi> {
    As5048a::new(FaultySpi::new(&frames(groups), fail_at), CAL)
}

fn destroy_enc(enc: As5048a<FaultySpi>) {
    enc.destroy().done();
}

#[test]
fn command_frames_match_datasheet() {
    assert_eq!(encode_command(reg::ANGLE, true), 0xFFFF);
    assert_eq!(encode_command(reg::MAGNITUDE, true), 0x7FFE);
    assert_eq!(encode_command(reg::DIAGNOSTICS_AGC, true), 0x7FFD);
    assert_eq!(encode_command(reg::NOP, true), 0xC000);
    assert_eq!(encode_command(reg::NOP, false), 0x0000);
    assert_eq!(encode_command(reg::CLEAR_ERROR_FLAG, true), 0x4001);
    // Address bits above 13 are dropped, never smuggled into R/W or parity.
    assert_eq!(encode_command(0xFFFF, false), encode_command(0x3FFF, false));
}

#[test]
fn decode_checks_parity_then_error_flag() {
    assert_eq!(decode_response(0x0000), Ok(0));
    assert_eq!(decode_response(0x9234), Ok(0x1234));
    assert_eq!(decode_response(0x1234), Err(FrameError::Parity));
    assert_eq!(decode_response(0xC000), Err(FrameError::ErrorFlag));
    // Bad parity wins over EF: a corrupted frame's EF bit means nothing.
    assert_eq!(decode_response(0x4000), Err(FrameError::Parity));
}

#[test]
fn read_angle_sends_command_then_nop_in_separate_cs_frames() {
    let mut enc = new_enc(
        &[
            frame(&be(0xFFFF), &[0xAA, 0x55]), // reply to an older command: ignored
            frame(&be(0xC000), &be(response(0x1234))),
        ],
        None,
    );
    let r = enc.read_angle().unwrap();
    assert_eq!(r.raw_counts, 0x1234);
    let expected = f32::from(0x234_i16) * 2.0 * PI / 16384.0;
    assert!((r.angle_rad - expected).abs() < 1e-6);
    destroy_enc(enc);
}

#[test]
fn parity_error_is_reported() {
    let mut enc = new_enc(
        &[frame(&be(0xFFFF), &[0, 0]), frame(&be(0xC000), &be(0x1234))],
        None,
    );
    assert_eq!(enc.read_angle(), Err(Error::Parity));
    destroy_enc(enc);
}

#[test]
fn error_flag_triggers_clear_error_read() {
    let mut enc = new_enc(
        &[
            frame(&be(0xFFFF), &[0, 0]),
            frame(&be(0xC000), &be(0xC000)), // EF set, even parity
            frame(&be(0x4001), &[0, 0]),     // Clear Error Flag command
            frame(&be(0xC000), &be(response(0b100))), // parity error bit
        ],
        None,
    );
    assert_eq!(
        enc.read_angle(),
        Err(Error::ErrorFlag(Some(ErrorRegister {
            framing: false,
            invalid_command: false,
            parity: true
        })))
    );
    destroy_enc(enc);
}

#[test]
fn error_flag_with_corrupt_error_register() {
    let mut enc = new_enc(
        &[
            frame(&be(0xFFFF), &[0, 0]),
            frame(&be(0xC000), &be(0xC000)),
            frame(&be(0x4001), &[0, 0]),
            frame(&be(0xC000), &be(0x0001)), // odd parity
        ],
        None,
    );
    assert_eq!(enc.read_angle(), Err(Error::ErrorFlag(None)));
    destroy_enc(enc);
}

#[test]
fn bus_error_on_command_frame() {
    let mut enc = new_enc(&[], Some(0));
    assert_eq!(enc.read_angle(), Err(Error::Bus(ErrorKind::Other)));
    destroy_enc(enc);
}

#[test]
fn bus_error_on_nop_frame() {
    let mut enc = new_enc(&[frame(&be(0xFFFF), &[0, 0])], Some(1));
    assert_eq!(enc.read_angle(), Err(Error::Bus(ErrorKind::Other)));
    destroy_enc(enc);
}

#[test]
fn bus_error_while_clearing_error_flag() {
    let mut enc = new_enc(
        &[
            frame(&be(0xFFFF), &[0, 0]),
            frame(&be(0xC000), &be(0xC000)),
            frame(&be(0x4001), &[0, 0]),
        ],
        Some(3),
    );
    assert_eq!(enc.read_angle(), Err(Error::Bus(ErrorKind::Other)));
    destroy_enc(enc);
}

#[test]
fn diagnostics_and_magnitude() {
    // AGC 0x80, OCF set: healthy.
    let diag = 0x0180;
    let mut enc = new_enc(
        &[
            frame(&be(0x7FFD), &[0, 0]),
            frame(&be(0xC000), &be(response(diag))),
            frame(&be(0x7FFE), &[0, 0]),
            frame(&be(0xC000), &be(response(0x0ABC))),
        ],
        None,
    );
    let d = enc.read_diagnostics().unwrap();
    assert_eq!(d.agc, 0x80);
    assert!(d.offset_compensation_finished && d.is_healthy());
    assert_eq!(enc.read_magnitude().unwrap(), 0x0ABC);
    destroy_enc(enc);

    let weak = Diagnostics::from_bits(0x0100 | (1 << 11));
    assert!(weak.comp_high && !weak.is_healthy());
    assert!(!Diagnostics::from_bits(0x0300).is_healthy());
}

#[test]
fn calibration_range_and_direction() {
    let pos = CAL;
    let neg = Calibration {
        direction: Direction::Negative,
        ..CAL
    };
    assert_eq!(pos.counts_to_rad(0x1000), 0.0);
    // Half a turn is +π exactly, one count more wraps to just above −π.
    assert_eq!(pos.counts_to_rad(0x1000 + 8192), PI);
    assert!(pos.counts_to_rad(0x1000 + 8193) < -PI + 1e-3);
    assert_eq!(neg.signed_counts(0x1000 + 100), -100);
    assert_eq!(pos.signed_counts(0x1000 - 100), -100);
    // Wrap around zero.
    let near_zero = Calibration {
        zero_offset_counts: 10,
        direction: Direction::Positive,
    };
    assert_eq!(near_zero.signed_counts(COUNTS_PER_REV - 10), -20);
}

#[test]
fn wrapped_delta_takes_the_short_way() {
    assert_eq!(wrapped_delta(100, 126), 26);
    assert_eq!(wrapped_delta(16380, 4), 8);
    assert_eq!(wrapped_delta(4, 16380), -8);
    assert_eq!(wrapped_delta(0, 8192), 8192);
    assert_eq!(wrapped_delta(0, 8193), -8191);
    assert_eq!(wrapped_delta(77, 77), 0);
}

proptest! {
    #[test]
    fn encode_always_even_parity(addr in any::<u16>(), read in any::<bool>()) {
        let f = encode_command(addr, read);
        prop_assert_eq!(f.count_ones() % 2, 0);
        prop_assert_eq!(f & 0x3FFF, addr & 0x3FFF);
        prop_assert_eq!(f & 0x4000 != 0, read);
    }

    #[test]
    fn decode_accepts_valid_and_rejects_any_single_bit_flip(data in 0u16..0x4000, bit in 0u32..16) {
        let f = response(data);
        prop_assert_eq!(decode_response(f), Ok(data));
        prop_assert_eq!(decode_response(f ^ (1 << bit)), Err(FrameError::Parity));
    }

    #[test]
    fn decode_is_total(frame in any::<u16>()) {
        if let Ok(d) = decode_response(frame) {
            prop_assert!(d < 0x4000 && frame.count_ones() % 2 == 0);
        }
    }

    #[test]
    fn angle_in_half_open_range(raw in any::<u16>(), zero in any::<u16>(), neg in any::<bool>()) {
        let cal = Calibration {
            zero_offset_counts: zero,
            direction: if neg { Direction::Negative } else { Direction::Positive },
        };
        let a = cal.counts_to_rad(raw);
        prop_assert!(a > -PI && a <= PI, "{a}");
        let c = cal.signed_counts(raw);
        prop_assert!(c > -8192 && c <= 8192);
    }
}

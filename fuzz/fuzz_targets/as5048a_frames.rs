//! AS5048A frames: decoding any 16-bit word is total (no panic), accepts
//! only even-parity frames without the error flag, and round-trips through
//! the command encoder's parity rule; calibration maps any raw value into
//! (−π, π].
#![no_main]

use gait_control::drivers::as5048a::{Calibration, Direction, decode_response, encode_command};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: [u8; 4]| {
    let word = u16::from_be_bytes([data[0], data[1]]);
    if let Ok(value) = decode_response(word) {
        assert!(value < 1 << 14);
        assert_eq!(word.count_ones() % 2, 0, "accepted odd parity");
        assert_eq!(word & 0x4000, 0, "accepted the error flag");
    }
    let cmd = encode_command(word & 0x3FFF, data[2] & 1 == 1);
    assert_eq!(cmd.count_ones() % 2, 0, "command with odd parity");
    let cal = Calibration {
        zero_offset_counts: u16::from_be_bytes([data[2], data[3]]),
        direction: if data[3] & 1 == 0 { Direction::Positive } else { Direction::Negative },
    };
    let a = cal.counts_to_rad(word);
    assert!(a > -core::f32::consts::PI - 1e-6 && a <= core::f32::consts::PI + 1e-6);
});

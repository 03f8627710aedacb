//! MCP3208 replies: decoding any three bytes is total and yields 12 bits;
//! any reply converted through a calibration gives a force in the rated range
//! or a typed fault, never NaN.
#![no_main]

use gait_control::drivers::mcp3208::{Channel, ForceCalibration, decode_reply, encode_request};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: [u8; 4]| {
    let counts = decode_reply([data[0], data[1], data[2]]);
    assert!(counts <= 4095);
    let ch = match data[3] & 7 {
        0 => Channel::Ch0,
        1 => Channel::Ch1,
        2 => Channel::Ch2,
        3 => Channel::Ch3,
        4 => Channel::Ch4,
        5 => Channel::Ch5,
        6 => Channel::Ch6,
        _ => Channel::Ch7,
    };
    let req = encode_request(ch);
    assert_eq!(req[0] & 0b0000_0110, 0b0000_0110, "start and single-ended bits");
    let Ok(cal) = ForceCalibration::new([100, 1000, 2500, 4000], [0.0, 150.0, 600.0, 1500.0], 40, 4080, -50.0, 1600.0) else {
        return;
    };
    if let Ok(n) = cal.convert(counts) {
        assert!(n.is_finite() && (-50.0..=1600.0).contains(&n));
    }
});

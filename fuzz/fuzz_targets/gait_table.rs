//! Gait-table reader: any byte string is either refused with a typed error
//! or yields a table whose every sample and interpolation is finite; a valid
//! image with any single bit flipped is refused.
#![no_main]

use gait_core::ik::IkOptions;
use gait_core::tables::{GaitKind, GaitTable, encode, image_len};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(t) = GaitTable::parse(data) {
        for k in 0..t.len() {
            assert!(t.sample(k).is_some_and(|s| s.iter().all(|v| v.is_finite())));
        }
        for x in [-1.0, 0.0, 0.0037, t.duration_s() * 0.5, t.duration_s(), 1e9, f32::NAN] {
            assert!(t.at_time(x).iter().all(|v| v.is_finite()));
        }
    }
    // Build a valid table from the input's floats, flip one bit, expect refusal.
    if data.len() >= 44 {
        let floats: Vec<f32> = data
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .filter(|v| v.is_finite())
            .collect();
        let samples: Vec<[f32; 5]> = floats.chunks_exact(5).map(|c| [c[0], c[1], c[2], c[3], c[4]]).collect();
        if samples.len() >= 2 && samples.len() <= 64 {
            let mut buf = vec![0u8; image_len(samples.len())];
            if encode(GaitKind::Walk, 10_000, IkOptions::paper(), &samples, &mut buf).is_ok() {
                assert!(GaitTable::parse(&buf).is_ok());
                let bit = usize::from(data[0]) * 8 + usize::from(data[1] & 7);
                let at = bit / 8 % buf.len();
                buf[at] ^= 1 << (bit % 8);
                assert!(GaitTable::parse(&buf).is_err(), "bit flip at byte {at} accepted");
            }
        }
    }
});

//! Board-independent pieces of the firmware: the power-on self-test that both
//! boards run, and the instruction counter used for on-target benchmarks.
//!
//! No control logic lives here (that is gait-control's job); this crate only
//! wires boards to the portable crates.
#![no_std]
#![forbid(unsafe_code)]

pub mod selftest;

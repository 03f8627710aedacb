//! gait-control: the real-time controller, generic over embedded-hal 1.0 so
//! the same code runs on the motor board, under QEMU and in host tests.
//!
//! - [`drivers`]: one module per part (AS5048A encoders, MCP3208 force
//!   ADC), the motor output, buttons and status indicators;
//! - [`operator`]: the clinician's MODE/GO button scheme as a pure state
//!   machine (described for clinicians in `docs/operation.md`).
#![no_std]

pub mod acquisition;
pub mod ahead;
pub mod check_slot;
pub mod controller;
pub mod crutch_load;
pub mod drivers;
pub mod faults;
pub mod feedforward;
mod fingerprint;
pub mod layout;
pub mod operator;
pub mod position_loop;
pub mod posture;
pub mod reference;
pub mod replan;
pub mod ring_log;
pub mod sequencer;
pub mod supervisor;

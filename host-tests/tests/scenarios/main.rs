//! The closed-loop scenarios, in one binary (one link, one lint header):
//! gait-control's real controller drives the simulated device and pilot
//! through simulated peripherals speaking the real wire formats.
// Clippy's allow-*-in-tests covers `#[test]` fns, not the helpers here;
// of the strict lints, host-tests denies only these two (Cargo.toml).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod acquisition;
mod clinical_tables;
mod closed_loop;
mod common;
mod device;
mod documents;
mod fault_injection;
mod ground_search;
mod leaning_pilot;
mod model_task;
mod patient_bundle;
mod replanning;
mod sensing_faults;
mod set_down;

//! gait-control's integration tests, in one binary (one link, one lint
//! header): the drivers on mock buses, the clinician buttons, the ring log,
//! the gait sequencer, the safety supervisor and its fault table.
// Clippy's allow-*-in-tests covers `#[test]` fns, not the helpers here.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

mod as5048a;
mod buttons;
mod common;
mod fault_table;
mod mcp3208;
mod motor;
mod operator;
mod ring_log;
mod sequencer;
mod supervisor;

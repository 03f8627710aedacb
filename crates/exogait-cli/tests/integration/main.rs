//! exogait-cli's integration tests, in one binary (one link, one lint
//! header): each runs the built `exogait` and checks its answers and exit
//! status (`common.rs` runs it).
// Clippy's allow-*-in-tests covers `#[test]` fns, not the helpers here;
// of the strict lints, exogait-cli denies only these two (Cargo.toml).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod cli;
mod clinic;
mod common;
mod compare;
mod faults;
mod input;
mod optimize;
mod safe_gaits;
mod simulate;

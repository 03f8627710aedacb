//! exogait-device's integration tests, in one binary (one link, one lint
//! header): the boot from flash, the drives' figures, the device fitted to
//! a patient, the re-plan.
// Clippy's allow-*-in-tests covers `#[test]` fns, not the helpers here.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    missing_docs
)]

mod boot;
mod drive;
mod fitting;
mod replan;

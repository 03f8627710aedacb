//! gait-core's integration tests, in one binary (one link, one lint
//! header): the model against derivations that share no code with it, the
//! tables, IK and gaits by their properties, the patient bundle's checks.
// Clippy's allow-*-in-tests covers `#[test]` fns, not the helpers here.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::needless_range_loop,
    missing_docs
)]

mod bundle;
mod chain;
mod clamp;
mod constructors;
mod contact;
mod dynamics_independent;
mod flash_table_properties;
mod gait_sampling;
mod ik_properties;
mod periodic_steps;
mod replan;
mod replan_aim;
mod replan_setup;
mod table_ik_options;
mod toe_rocker;

//! Board-independent pieces of the firmware: the configuration both boards
//! run the controller with ([`board_config`]), the motor board's clock tree
//! and timers computed when compiling ([`clock_tree`]), the power-on self-test
//! ([`selftest`]), the idle-time re-planner both boards schedule under the
//! tick ([`idle_replan`]) and the tick's state its interrupt owns
//! ([`tick_state`]), and the in-memory peripherals of the QEMU control-tick
//! benchmark ([`qemu_rig`]), its replay of ticks recorded in the simulator
//! ([`tick_replay`]) and the text it prints ([`text`]).
//!
//! No control logic lives here (that is gait-control's job); this crate only
//! wires boards to the portable crates.
#![no_std]
// `deny`, not `forbid`: `flash_sectors` alone reads the data sectors.
#![deny(unsafe_code)]

pub mod board_config;
pub mod clock_tree;
pub mod flash_sectors;
pub mod idle_replan;
pub mod model_task;
#[cfg(not(feature = "board-stm32f405"))]
pub mod qemu_bundle;
pub mod qemu_rig;
pub mod selftest;
pub mod text;
pub mod tick_replay;
pub mod tick_state;

/// The controller's state a tick reads ends within its first 4 KiB: a field
/// past that offset from its base needs an extra instruction to address on
/// the Cortex-M4 (a 12-bit load offset), paid many times a tick.
const _: () = assert!(gait_control::controller::TICK_STATE_BYTES <= 4096);

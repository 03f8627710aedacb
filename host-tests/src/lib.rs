//! Shared fixtures of the closed-loop scenarios (thin over
//! [`sim::scenario`]): the tables the device carries in flash, and a rig
//! standing in the walk table's start posture with a pilot who knows the
//! gait.

use sim::closed_loop::{Rig, RigError};
use sim::pilot::PilotConfig;
pub use sim::scenario::{flash_tables, strong_pilot};

/// The device standing in the walk table's start posture with its flash
/// tables (see [`sim::scenario::walk_rig`]).
pub fn standing_rig(pilot: PilotConfig) -> Result<Rig<'static>, RigError> {
    sim::scenario::walk_rig(pilot, flash_tables())
}

//! The pilot and board conditions `simulate` and `compare` run under: a
//! pilot whose stance ankle departs from the plan (a habitual lean, a
//! slower shank), and whether the board re-plans each step from the
//! measured ankle in its idle time (`exogait_device::replan`).

use clap::{Args, ValueEnum};
use serde::Serialize;
use sim::closed_loop::Rig;
use sim::pilot::PilotConfig;

/// Off or on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum OnOff {
    /// Off.
    Off,
    /// On.
    On,
}

/// Largest habitual lean taken, degrees.
const MAX_LEAN_DEG: f64 = 10.0;

/// Options shared by `simulate` and `compare`.
#[derive(Debug, Clone, Copy, Args, Serialize)]
pub struct Conditions {
    /// Re-plan each step from the pilot's measured stance ankle in the
    /// board's idle time (`on`), or play the tables as planned (`off`).
    #[arg(long, value_enum, default_value_t = OnOff::Off)]
    pub replan: OnOff,
    /// The simulated pilot's habitual lean over the plan's stance shank,
    /// degrees (forward positive): kept through every step, and brought
    /// towards the plan only while the device keeps the pilot waiting.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub pilot_lean: f64,
    /// The simulated pilot's stiffness at the ankle as a share of the
    /// default (below 1: a slower shank that lags the plan).
    #[arg(long, value_name = "SHARE", default_value_t = 1.0)]
    pub pilot_stiffness: f64,
}

impl Conditions {
    /// Checks the values; the message for the user otherwise.
    pub fn check(&self) -> Result<(), String> {
        if !(self.pilot_lean.is_finite() && self.pilot_lean.abs() <= MAX_LEAN_DEG) {
            return Err(format!(
                "--pilot-lean must be within ±{MAX_LEAN_DEG} degrees"
            ));
        }
        if !(self.pilot_stiffness.is_finite() && (0.2..=2.0).contains(&self.pilot_stiffness)) {
            return Err("--pilot-stiffness must be in [0.2, 2]".into());
        }
        Ok(())
    }

    /// `pilot` standing and stepping as asked.
    #[must_use]
    pub fn pilot(&self, pilot: PilotConfig) -> PilotConfig {
        PilotConfig {
            habit_lean_rad: self.pilot_lean.to_radians(),
            kp_nm_per_rad: pilot.kp_nm_per_rad * self.pilot_stiffness,
            kd_nm_s_per_rad: pilot.kd_nm_s_per_rad * self.pilot_stiffness.sqrt(),
            ..pilot
        }
    }

    /// Sets `rig` up: its board's re-planner on `slot` when on.
    pub fn prepare<'t>(&self, rig: &mut Rig<'t>, slot: &'t gait_control::replan::ReplanSlot) {
        if self.replan == OnOff::On {
            rig.replan_with(slot);
        }
    }
}

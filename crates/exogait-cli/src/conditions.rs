//! The pilot and board conditions `simulate` and `compare` run under: a
//! pilot whose stance ankle departs from the plan (a habitual lean, a
//! slower shank, a stance foot placed off), the sensors' noise, and
//! whether the board re-plans each
//! step from the measured ankle in its idle time
//! (`exogait_device::replan`).

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
/// Farthest a stance foot is placed off, cm.
const MAX_FOOT_OFF_CM: f64 = 5.0;

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
    /// The pilot stands with the stance foot this much further forward
    /// under the body than the gait's start posture puts it (negative:
    /// back), cm: the hip, torso and other leg where planned, the stance
    /// shank leaning back from its plan (forward for a foot placed back).
    #[arg(
        long,
        value_name = "CM",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub stance_foot_off: f64,
    /// Sensor noise: uniform ±ENC counts on every encoder (of 16,384 per
    /// turn) and ±ADC counts on the force ADC (of 4,096), e.g. `3,10`
    /// (the encoder's datasheet noise is 0.06° RMS, 2.7 counts). Without
    /// it a joint the chain holds reads exactly the same counts tick after
    /// tick, which a real encoder never does.
    #[arg(long, value_name = "ENC,ADC", value_parser = parse_noise)]
    pub sensor_noise: Option<(u16, u16)>,
    /// Seed of the sensor noise (`exogait faults` lists each run's, so a
    /// run can be played again here).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 2026,
        requires = "sensor_noise"
    )]
    pub noise_seed: u64,
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
        if !(self.stance_foot_off.is_finite() && self.stance_foot_off.abs() <= MAX_FOOT_OFF_CM) {
            return Err(format!(
                "--stance-foot-off must be within ±{MAX_FOOT_OFF_CM} cm"
            ));
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

    /// Sets `rig` up: the pilot's stance foot, its sensors' noise, its board's
    /// re-planner on `slot` when on.
    ///
    /// # Errors
    ///
    /// The message for the user when the stance leg cannot reach a foot
    /// placed so.
    pub fn prepare<'t>(
        &self,
        rig: &mut Rig<'t>,
        slot: &'t gait_control::replan::ReplanSlot,
    ) -> Result<(), String> {
        if self.stance_foot_off != 0.0 {
            rig.place_stance_foot(self.stance_foot_off / 100.0)
                .map_err(|e| format!("--stance-foot-off {} cm: {e}", self.stance_foot_off))?;
        }
        if let Some((enc, adc)) = self.sensor_noise {
            rig.set_sensor_noise(enc, adc, self.noise_seed);
        }
        if self.replan == OnOff::On {
            rig.replan_with(slot);
        }
        Ok(())
    }
}

/// `ENC,ADC` → counts of noise on the encoders and the ADC (each ≤ 1,000).
fn parse_noise(text: &str) -> Result<(u16, u16), String> {
    let (enc, adc) = text
        .split_once(',')
        .ok_or_else(|| format!("expected ENC,ADC (two counts), got {text:?}"))?;
    let count = |s: &str, what: &str| -> Result<u16, String> {
        let v: u16 = s
            .trim()
            .parse()
            .map_err(|_| format!("{what} noise must be a whole number of counts, got {s:?}"))?;
        if v > 1000 {
            return Err(format!("{what} noise {v} is beyond 1,000 counts"));
        }
        Ok(v)
    };
    Ok((count(enc, "encoder")?, count(adc, "ADC")?))
}

#[cfg(test)]
mod tests {
    use super::parse_noise;

    #[test]
    fn noise_option_parses_and_refuses_clearly() {
        assert_eq!(parse_noise("3,10"), Ok((3, 10)));
        assert_eq!(parse_noise(" 0 , 0 "), Ok((0, 0)));
        for bad in ["3", "a,1", "1,-2", "1,2000", "", "1,2,3"] {
            assert!(parse_noise(bad).is_err(), "{bad:?} accepted");
        }
    }
}

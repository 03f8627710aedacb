//! How far a gait's healthy closed loop takes the supervisor's torque
//! residual (0x0404) at the stance hip of its swings: the figure a table's
//! generator sets the gait's own limit there from
//! (`GaitTable::with_stance_hip_residual_nm`, `docs/safety.md`).
//!
//! A slipping stance hip shows as a residual the position loop cannot
//! hide, 70–95 N·m late in a swing; a brisk gait for a tall patient shows
//! up to 106 N·m healthy, the built-in gaits 34–51 (with a pilot off the
//! plan). The device's one limit (100 N·m) must pass the brisk gaits; a
//! gait's own limit, taken from its healthy runs, catches the slip where
//! the gait leaves room.

use gait_control::sequencer::Phase;
use gait_core::tables::GaitTable;

use crate::closed_loop::Sample;
use crate::compare::{RunLength, play_for};
use crate::pilot::PilotConfig;
use crate::scenario::strong_pilot;
use exogait_device::DeviceConfig;

/// Sensor-noise seeds of the noisy runs. A gait's peak varies with the
/// noise: the 1.75 m patient's 0.15 m descent peaks at 69 N·m over seeds
/// 1–3 and at 80 over 1–10, as over 1–50.
pub const NOISE_SEEDS: [u64; 10] = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10];
/// The encoders' noise of the noisy runs, counts (±; the AS5048A's 0.06°
/// RMS is 2.7).
pub const ENCODER_NOISE_COUNTS: u16 = 3;
/// The force ADC's noise of the noisy runs, counts (±).
pub const ADC_NOISE_COUNTS: u16 = 10;

/// The largest |d̂| of the stance hip in the swings of `trace`, N·m;
/// `None` when no swing tick has it (no swing, or the windowed checks ran
/// in a model task, whose residuals the trace does not see).
pub fn stance_hip_peak_nm(trace: &[Sample]) -> Option<f64> {
    trace
        .iter()
        .filter_map(|s| match s.report.phase {
            Phase::Swing { stance, .. } => s.residual_nm.get(stance.hip()).copied(),
            _ => None,
        })
        .filter(|d| d.is_finite())
        .map(|d| f64::from(d.abs()))
        .reduce(f64::max)
}

/// A pilot off the plan, as `exogait compare` plays one: their lean over
/// the plan (° forward), the stiffness of their shank (a share of the
/// strong pilot's) and where their stance foot stands (m forward).
/// Only such a pilot's runs that latch nothing count: a run the device
/// already holds for the pilot's own departure (an ankle at its stop) is
/// not the gait's healthy loop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Departure {
    /// Habitual lean over the plan, degrees (forward positive).
    pub lean_deg: f64,
    /// Shank stiffness, a share of the strong pilot's.
    pub stiffness: f64,
    /// The stance foot's placement off the plan, m (forward positive).
    pub stance_foot_m: f64,
}

/// The departures a gait's figure is measured over besides the pilot on
/// the plan: leaning 2° either way, half and twice as stiff, the stance
/// foot 1 cm off either way. Off the plan the stance hip carries more:
/// the built-in walk peaks at 31 N·m on the plan, 51 leaning 2° forward.
pub const DEPARTURES: [Departure; 6] = [
    Departure {
        lean_deg: 2.0,
        stiffness: 1.0,
        stance_foot_m: 0.0,
    },
    Departure {
        lean_deg: -2.0,
        stiffness: 1.0,
        stance_foot_m: 0.0,
    },
    Departure {
        lean_deg: 0.0,
        stiffness: 0.5,
        stance_foot_m: 0.0,
    },
    Departure {
        lean_deg: 0.0,
        stiffness: 2.0,
        stance_foot_m: 0.0,
    },
    Departure {
        lean_deg: 0.0,
        stiffness: 1.0,
        stance_foot_m: 0.01,
    },
    Departure {
        lean_deg: 0.0,
        stiffness: 1.0,
        stance_foot_m: -0.01,
    },
];

/// Noise seeds of each departure's runs.
pub const DEPARTURE_SEEDS: [u64; 2] = [1, 2];

impl Departure {
    /// The strong pilot, departing so.
    fn pilot(&self) -> PilotConfig {
        let base = strong_pilot();
        PilotConfig {
            habit_lean_rad: self.lean_deg.to_radians(),
            kp_nm_per_rad: base.kp_nm_per_rad * self.stiffness,
            kd_nm_s_per_rad: base.kd_nm_s_per_rad * self.stiffness.sqrt(),
            ..base
        }
    }
}

/// The stance hip's peak over `steps` steps of `table` on `device`, N·m:
/// played by the strong pilot on the plan without sensor noise and with
/// the device's at each of [`NOISE_SEEDS`], and by each of
/// [`DEPARTURES`] with noise at [`DEPARTURE_SEEDS`]. An error names a run
/// on the plan that faulted or landed short (the gait is not healthy on
/// this device); a departing pilot's run that latches anything is left
/// out ([`Departure`]).
pub fn stance_hip_residual_peak_nm(
    device: &DeviceConfig,
    table: GaitTable<'_>,
    steps: usize,
    max_s: f64,
) -> Result<f64, String> {
    let length = RunLength {
        steps,
        max_s,
        tail_s: 0.5,
    };
    let on_plan = core::iter::once(None).chain(NOISE_SEEDS.map(Some));
    let mut peak = 0.0f64;
    for noise in on_plan {
        let (run, rig) = play_for(device, table, strong_pilot(), length, |rig| {
            if let Some(seed) = noise {
                rig.set_sensor_noise(ENCODER_NOISE_COUNTS, ADC_NOISE_COUNTS, seed);
            }
        })
        .map_err(|e| format!("closed loop: {e}"))?;
        let with = noise.map_or_else(
            || "without sensor noise".to_string(),
            |seed| format!("with sensor noise ±{ENCODER_NOISE_COUNTS}/±{ADC_NOISE_COUNTS} counts, seed {seed}"),
        );
        if let Some((code, name)) = run.faults.first() {
            return Err(format!("closed loop {with}: fault {code} ({name})"));
        }
        if run.landed() < steps {
            return Err(format!(
                "closed loop {with}: {} of {steps} steps landed",
                run.landed()
            ));
        }
        let run_peak = stance_hip_peak_nm(&rig.trace).ok_or_else(|| {
            format!("closed loop {with}: no stance hip's residual measured in a swing")
        })?;
        peak = peak.max(run_peak);
    }
    for d in DEPARTURES {
        for seed in DEPARTURE_SEEDS {
            let played = play_for(device, table, d.pilot(), length, |rig| {
                if d.stance_foot_m != 0.0 {
                    // A foot the leg cannot reach is left as planned.
                    let _ = rig.place_stance_foot(d.stance_foot_m);
                }
                rig.set_sensor_noise(ENCODER_NOISE_COUNTS, ADC_NOISE_COUNTS, seed);
            });
            if let Ok((run, rig)) = played
                && run.faults.is_empty()
            {
                peak = peak.max(stance_hip_peak_nm(&rig.trace).unwrap_or(0.0));
            }
        }
    }
    Ok(peak)
}

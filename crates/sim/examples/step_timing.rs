//! When each step of a closed-loop run touches down against its table, and
//! where the balance part of the crutch impulse is spent: for reading why
//! a pilot off the plan loads the crutches more with one step than with
//! another (`docs/replanning.md`, "Why, so far").
//!
//! `cargo run --release -p sim --example step_timing -- GAIT LEAN_DEG on|off [NOISE_SEED]`
//!
//! GAIT is walk, stair-up or stair-down; LEAN_DEG the pilot's habitual
//! lean (forward positive); `on` re-plans each step on the board's
//! schedule. The sensors carry `compare --sensor-noise 3,10`'s noise
//! (seed 2026 unless given). Per step it prints the swing's length against
//! the table's step time (a foot still in the air at the table's end waits
//! for the ground search), the step's error, and the balance impulse
//! Σ|τ_pilot|Δt/lever split by phase from the swing's start to the next
//! (the last step's to its landing and weight transfer).

use gait_control::operator::Gait;
use gait_control::replan::ReplanSlot;
use gait_control::sequencer::Phase;

fn gait_named(name: &str) -> Option<Gait> {
    match name {
        "walk" => Some(Gait::Walk),
        "stair-up" => Some(Gait::StairUp),
        "stair-down" => Some(Gait::StairDown),
        _ => None,
    }
}

/// The phase's column: swing, transfer, waiting (standing and holds
/// count as waiting: the pilot stands).
fn column(phase: &Phase) -> usize {
    match phase {
        Phase::Swing { .. } => 0,
        Phase::Transfer { .. } => 1,
        _ => 2,
    }
}

fn main() -> std::process::ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: step_timing GAIT LEAN_DEG on|off [NOISE_SEED]";
    let (Some(gait), Some(lean), Some(on)) = (
        args.first().and_then(|g| gait_named(g)),
        args.get(1).and_then(|v| v.parse::<f64>().ok()),
        args.get(2).and_then(|v| match v.as_str() {
            "on" => Some(true),
            "off" => Some(false),
            _ => None,
        }),
    ) else {
        eprintln!("{usage}");
        return std::process::ExitCode::from(2);
    };
    let seed = match args.get(3).map(|v| v.parse::<u64>()) {
        None => 2026,
        Some(Ok(s)) => s,
        Some(Err(_)) => {
            eprintln!("{usage}");
            return std::process::ExitCode::from(2);
        }
    };
    match run(gait, lean, on, seed) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("step_timing: {e}");
            std::process::ExitCode::from(1)
        }
    }
}

fn run(gait: Gait, lean_deg: f64, on: bool, seed: u64) -> Result<(), String> {
    let device = exogait_device::DeviceConfig::exogait().map_err(|e| format!("{e:?}"))?;
    let tables = sim::scenario::flash_tables();
    let table = *tables.get(gait).ok_or("no table for the gait")?;
    let pilot = sim::pilot::PilotConfig {
        habit_lean_rad: lean_deg.to_radians(),
        ..sim::scenario::strong_pilot()
    };
    let slot: &'static ReplanSlot = Box::leak(Box::new(ReplanSlot::new()));
    let (run, rig) = sim::compare::play(&device, table, pilot, 4, 60.0, |rig| {
        rig.set_sensor_noise(3, 10, seed);
        if on {
            rig.replan_with(slot);
        }
    })
    .map_err(|e| e.to_string())?;
    let step_s = f64::from(table.duration_s());
    let dt = f64::from(device.dt_s);
    println!(
        "table step time {step_s:.3} s; balance impulse N·s by phase (swing, transfer, waiting)"
    );
    println!("step  swing s  past table s  step error mm  swing  transfer  waiting  total");
    for (i, step) in run.steps.iter().enumerate() {
        // To the next swing's start; the last step to its landing and
        // transfer.
        let next = run.steps.get(i + 1).map_or(step.end_s, |s| s.start_s);
        let mut by_phase = [0.0; 3];
        for t in rig
            .trace
            .iter()
            .filter(|t| t.state.time_s > step.start_s && t.state.time_s <= next)
        {
            let c = column(&t.report.phase);
            if let Some(v) = by_phase.get_mut(c) {
                *v += t.state.pilot_torque_nm.abs() / pilot.crutch_lever_m * dt;
            }
        }
        let swing_s = step.landing_s.map_or(f64::NAN, |l| l - step.start_s);
        let error = step
            .step_error_m
            .map_or_else(|| "  —".to_string(), |e| format!("{:+5.1}", e * 1e3));
        println!(
            "{:4}  {swing_s:7.3}  {:+12.3}  {error:>13}  {:5.0}  {:8.0}  {:7.0}  {:5.0}",
            i + 1,
            swing_s - step_s,
            by_phase[0],
            by_phase[1],
            by_phase[2],
            by_phase.iter().sum::<f64>()
        );
    }
    Ok(())
}

//! What a change of the hip and knee drives would buy a patient's gait
//! family: for each patient and drive, the walking paces and stairs the
//! device clears (the same search, admission check and closed loop as
//! `exogait tables`), and on stderr why each other gait is left out.
//! `cargo run --release -p gait-opt --example drive_tradeoff` (a few
//! minutes); the figures are in
//! `docs/optimiser.md`, "What the drives allow".
#![allow(missing_docs)]

use std::process::ExitCode;

use exogait_device::DeviceConfig;
use exogait_device::drive::DriveSpec;
use exogait_device::fitting::{Measures, fit};
use exogait_device::parts::JOINT_DRIVE;
use gait_opt::family::{DEFAULT_EVALS, Outcome, design_all, family_plans};

fn main() -> ExitCode {
    let raised_current = DriveSpec {
        // The gearbox's repeated-peak rating (178 N·m) instead of 150 N·m.
        current_limit_a: JOINT_DRIVE.gearbox.repeated_peak_torque_nm
            / JOINT_DRIVE.joint_torque_per_amp(),
        ..JOINT_DRIVE
    };
    let mut higher_bus = raised_current;
    higher_bus.amplifier.supply_v = 60.0;
    let drives = [
        ("as built", JOINT_DRIVE),
        (
            "current limit to the gearbox's repeated peak",
            raised_current,
        ),
        ("that, and a 60 V bus", higher_bus),
    ];
    let patients = [(1.60, 55.0), (1.75, 75.0), (1.90, 95.0)];
    let paces = [0.30, 0.35, 0.40];
    let stairs = [(0.15, 0.28), (0.17, 0.28), (0.18, 0.28)];
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    println!("| patient | drive | peak N·m | no-load rad/s | walks cleared (m/s) | up | down |");
    println!("|---|---|---|---|---|---|---|");
    for (name, drive) in drives {
        let Ok(device) = DeviceConfig::with_drive(drive) else {
            eprintln!("{name}: device refused");
            return ExitCode::FAILURE;
        };
        for (h, m) in patients {
            let measures = Measures {
                height_m: h,
                mass_kg: m,
                thigh_m: None,
                shank_m: None,
                foot_m: None,
            };
            let Ok(fitted) = fit(&device, &measures).and_then(|p| {
                device
                    .fitted(&p.model)
                    .map_err(exogait_device::fitting::FitError::Model)
            }) else {
                eprintln!("{h} m: not fitted");
                return ExitCode::FAILURE;
            };
            let plans = family_plans(&paces, &stairs, &fitted);
            let out = design_all(&plans, &fitted, DEFAULT_EVALS, threads, &|_, _, _| {});
            let mut walks = Vec::new();
            let (mut up, mut down) = (Vec::new(), Vec::new());
            for o in &out {
                if let Outcome::LeftOut { plan, reason } = o {
                    eprintln!("{h:.2} m, {name}: {} left out: {reason}", plan.name);
                }
                if let Outcome::Cleared(g) = o {
                    let rise = g.plan.spacing_m[1];
                    match g.plan.kind {
                        gait_core::tables::GaitKind::Walk => {
                            walks.push(format!("{:.2}", g.info.pace_m_s));
                        }
                        gait_core::tables::GaitKind::StairUp => up.push(format!("{rise:.2}")),
                        gait_core::tables::GaitKind::StairDown => {
                            down.push(format!("{:.2}", -rise));
                        }
                    }
                }
            }
            let show = |v: &[String]| {
                if v.is_empty() {
                    "—".to_string()
                } else {
                    v.join(", ")
                }
            };
            println!(
                "| {h:.2} m, {m:.0} kg | {name} | {:.0} | {:.2} | {} | {} | {} |",
                drive.peak_torque_nm(),
                drive.no_load_speed_rad_s(),
                show(&walks),
                show(&up),
                show(&down)
            );
        }
    }
    ExitCode::SUCCESS
}

//! `exogait compare`: the paper's Table II in the closed loop. The table
//! the firmware ships and the human-data gait at the same step length, rise
//! and step time, played by the same controller on the same simulated
//! device and pilot; per step and as a mean: the crutch impulse F, its
//! balance part, each crutch's peak, the time the pilot's torque was at its
//! limit, the landing error, the faults; then the reductions. No algorithm
//! here: gait-opt builds the human gait, sim plays and measures.
//!
//! The JSON field names carry their units (`F_Ns`, `peak_N`, …), as the
//! issue that asked for them spelt them.
#![allow(non_snake_case)]

use std::path::PathBuf;

use clap::Args;
use exogait_device::DeviceConfig;
use gait_control::replan::ReplanSlot;
use gait_core::tables::{GaitKind, GaitTable};
use gait_opt::clinical::ClinicalCase;
use gait_opt::human::playable_human_gait_in_loop;
use serde::Serialize;
use sim::compare::{GaitRun, play, reduction_pct};

use crate::conditions::Conditions;
use crate::simulate::SimGait;

/// Options of `exogait compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The gait: walk, stair-up or stair-down (the shipped tables), or a
    /// gait's name in the bundle given with `--bundle`.
    #[arg(long, value_name = "NAME")]
    pub gait: String,
    /// A patient's bundle (`exogait tables`): its patient's body and its
    /// gait named by `--gait`.
    #[arg(long, value_name = "FILE.bundle")]
    pub bundle: Option<PathBuf>,
    /// Steps to play each gait for.
    #[arg(long, default_value_t = 4)]
    pub steps: usize,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Write a plot of both runs (.svg or .png).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// The pilot and whether the board re-plans.
    #[command(flatten)]
    pub conditions: Conditions,
}

/// One gait's figures in the JSON answer.
#[derive(Debug, Serialize)]
pub struct RunJson {
    /// Per step: F, N·s.
    #[serde(rename = "F_Ns")]
    pub f_ns: Vec<f64>,
    /// Per step: the balance part of F, N·s.
    #[serde(rename = "F_balance_Ns")]
    pub f_balance_ns: Vec<f64>,
    /// Per step: the higher crutch's peak, N.
    pub peak_N: Vec<f64>,
    /// Per step: time the pilot's torque was at its limit, s.
    pub saturated_s: Vec<f64>,
    /// Per step: landing x less the plan's, m (null: no landing).
    pub landing_error_m: Vec<Option<f64>>,
    /// Per step: its landing less the previous one less the planned step,
    /// m (null: no landing).
    pub step_error_m: Vec<Option<f64>>,
    /// Per step: time the device waited for the pilot before its swing
    /// (readiness, a re-plan's latency), s.
    pub waited_s: Vec<f64>,
    /// Re-plans answered with a re-planned step (the sequencer plays it
    /// unless the ankle has moved since the request).
    pub replanned_answers: usize,
    /// Landings (world x, y), m.
    pub landings: Vec<[f64; 2]>,
    /// Faults latched, code and name.
    pub faults: Vec<FaultJson>,
    /// Means over the landed steps.
    pub mean: MeanJson,
    /// Progression from the first swing's start to the last landing, m/s.
    pub progression_m_s: f64,
    /// Lowest swing-foot clearance over a nosing in the closed loop, m
    /// (the sole taken level under the ankle; null on level ground).
    pub clearance_min_m: Option<f64>,
    /// Why the simulation stopped early, if it did.
    pub ended_by: Option<String>,
}

/// The gait's geometry and timing (both gaits share them).
#[derive(Debug, Serialize)]
pub struct GeometryJson {
    /// Horizontal step length, m.
    pub step_length_m: f64,
    /// Rise per step, m (negative down, 0 on level ground).
    pub rise_m: f64,
    /// Tread, m (0 on level ground).
    pub tread_m: f64,
    /// Step time, s.
    pub step_time_s: f64,
}

/// A fault.
#[derive(Debug, Serialize)]
pub struct FaultJson {
    /// "0x0401".
    pub code: String,
    /// Its name.
    pub name: &'static str,
}

/// Means over the landed steps.
#[derive(Debug, Serialize)]
pub struct MeanJson {
    /// F, N·s.
    #[serde(rename = "F_Ns")]
    pub f_ns: Option<f64>,
    /// Balance part, N·s.
    #[serde(rename = "F_balance_Ns")]
    pub f_balance_ns: Option<f64>,
    /// Highest crutch peak, N.
    pub peak_N: Option<f64>,
}

/// The reductions of the shipped table against the human gait, %.
#[derive(Debug, Serialize)]
pub struct ReductionJson {
    /// Of the mean F.
    #[serde(rename = "F")]
    pub f: Option<f64>,
    /// Of the mean balance part.
    #[serde(rename = "F_balance")]
    pub f_balance: Option<f64>,
    /// Of the highest crutch peak.
    pub peak: Option<f64>,
}

/// The device's figures in the answer.
#[derive(Debug, Serialize)]
pub struct DeviceJson {
    /// The drives' peak torque, N·m.
    pub drive_peak_Nm: f64,
    /// Their continuous torque, N·m.
    pub drive_continuous_Nm: f64,
    /// The device configuration's CRC-32 (the firmware's).
    pub fingerprint: String,
}

/// The answer.
#[derive(Debug, Serialize)]
pub struct CompareJson {
    /// "walk", "stair_up", "stair_down", or the bundle gait's name.
    pub gait: String,
    /// The movement: "walk", "stair_up", "stair_down".
    pub kind: &'static str,
    /// The patient's hash (null: the device's own body, Table III).
    pub patient_hash: Option<String>,
    /// The gait's geometry and timing.
    pub geometry: GeometryJson,
    /// Steps asked for.
    pub steps: usize,
    /// The table the firmware ships.
    pub shipped: RunJson,
    /// The human-data gait.
    pub human: RunJson,
    /// The human gait's torso lean (its one change), rad.
    pub human_torso_lean_rad: f64,
    /// Reductions of the shipped table against the human gait, %.
    pub reduction_pct: ReductionJson,
    /// The device.
    pub device: DeviceJson,
    /// The pilot and whether the board re-planned.
    pub conditions: Conditions,
}

fn run_json(r: &GaitRun, rig: &sim::closed_loop::Rig<'_>) -> RunJson {
    RunJson {
        step_error_m: r.steps.iter().map(|s| s.step_error_m).collect(),
        waited_s: r.steps.iter().map(|s| s.waited_s).collect(),
        replanned_answers: rig
            .replans()
            .iter()
            .filter(|p| p.answer.outcome == gait_control::replan::ReplanOutcome::Replanned)
            .count(),
        progression_m_s: r.progression_m_s(),
        clearance_min_m: sim::compare::nosing_clearance_m(rig),
        f_ns: r.steps.iter().map(|s| s.impulse_ns).collect(),
        f_balance_ns: r.steps.iter().map(|s| s.balance_ns).collect(),
        peak_N: r
            .steps
            .iter()
            .map(|s| s.peak_n[0].max(s.peak_n[1]))
            .collect(),
        saturated_s: r.steps.iter().map(|s| s.saturated_s).collect(),
        landing_error_m: r.steps.iter().map(|s| s.landing_error_m).collect(),
        landings: r.landings_m.clone(),
        faults: r
            .faults
            .iter()
            .map(|(code, name)| FaultJson {
                code: code.clone(),
                name,
            })
            .collect(),
        mean: MeanJson {
            f_ns: r.mean(|s| s.impulse_ns),
            f_balance_ns: r.mean(|s| s.balance_ns),
            peak_N: r.peak_n(),
        },
        ended_by: r.ended_by.clone(),
    }
}

/// The comparison of one shipped gait (also the main job's).
pub fn compare(
    kind: GaitKind,
    steps: usize,
    conditions: &Conditions,
) -> Result<(CompareJson, GaitRun, GaitRun), String> {
    let device = DeviceConfig::exogait().map_err(|e| format!("device: {e:?}"))?;
    let shipped = gait_core::flash_tables::of(kind)
        .map_err(|e| format!("the shipped table is refused: {e}"))?;
    let name = gait_opt::clinical_report::gait_name(kind).to_string();
    compare_table(&device, shipped, name, None, steps, conditions)
}

/// The comparison of `table` on `device` (fitted to a patient, or as
/// built) against the human-data gait at the table's geometry and step
/// time on the same device and pilot.
pub fn compare_table(
    device: &DeviceConfig,
    shipped: GaitTable<'_>,
    name: String,
    patient_hash: Option<u32>,
    steps: usize,
    conditions: &Conditions,
) -> Result<(CompareJson, GaitRun, GaitRun), String> {
    let kind = shipped.kind();
    let geometry = sim::scenario::table_geometry(&shipped, &device.body);
    let mut case = ClinicalCase::for_gait(kind, device);
    case.spacing_m = geometry.landing_m;
    case.step_time_s = f64::from(shipped.duration_s());
    let human = playable_human_gait_in_loop(&case, device, &gait_opt::default_data_dir())
        .map_err(|e| format!("human-data gait: {e}"))?;
    // The human-data gait comes from joint-angle data, not from the IK: its
    // table carries the clinical case's IK options, the ones the shipped
    // table of the gait was made with, so that the weight transfers of both
    // gaits are planned alike.
    let image = gait_opt::tables::table_image(kind, &case.ik, &human.phi)
        .map_err(|e| format!("human-data gait as a table: {e}"))?;
    let human_table = GaitTable::parse(&image).map_err(|e| format!("human table: {e}"))?;
    let pilot = conditions.pilot(sim::scenario::strong_pilot());
    let max_s = 8.0 + (2.0 + case.step_time_s) * steps as f64;
    let (our_slot, their_slot) = (ReplanSlot::new(), ReplanSlot::new());
    let (mut our_setup, mut their_setup) = (Ok(()), Ok(()));
    let (ours, our_rig) = play(device, shipped, pilot, steps, max_s, |rig| {
        our_setup = conditions.prepare(rig, &our_slot);
    })
    .map_err(|e| format!("shipped table: {e}"))?;
    our_setup?;
    let (theirs, their_rig) = play(device, human_table, pilot, steps, max_s, |rig| {
        their_setup = conditions.prepare(rig, &their_slot);
    })
    .map_err(|e| format!("human-data gait: {e}"))?;
    their_setup.map_err(|e| format!("human-data gait: {e}"))?;
    let level = kind == GaitKind::Walk;
    let answer = CompareJson {
        gait: name,
        kind: gait_opt::clinical_report::gait_name(kind),
        patient_hash: patient_hash.map(|h| format!("0x{h:08x}")),
        geometry: GeometryJson {
            step_length_m: geometry.landing_m[0],
            rise_m: if level { 0.0 } else { geometry.landing_m[1] },
            tread_m: if level { 0.0 } else { geometry.landing_m[0] },
            step_time_s: f64::from(shipped.duration_s()),
        },
        steps,
        shipped: run_json(&ours, &our_rig),
        human: run_json(&theirs, &their_rig),
        conditions: *conditions,
        human_torso_lean_rad: human.torso_lean_rad,
        reduction_pct: ReductionJson {
            f: reduction_pct(ours.mean(|s| s.impulse_ns), theirs.mean(|s| s.impulse_ns)),
            f_balance: reduction_pct(ours.mean(|s| s.balance_ns), theirs.mean(|s| s.balance_ns)),
            peak: reduction_pct(ours.peak_n(), theirs.peak_n()),
        },
        device: DeviceJson {
            drive_peak_Nm: f64::from(device.drives[0].peak_torque_nm()),
            drive_continuous_Nm: f64::from(device.drives[0].continuous_torque_nm()),
            fingerprint: format!("0x{:08x}", device.fingerprint()),
        },
    };
    Ok((answer, ours, theirs))
}

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "—".into(), |x| format!("{x:.digits$}"))
}

/// The table printed for one comparison.
pub fn table_text(a: &CompareJson) -> String {
    let mut out = format!(
        "exogait compare: {} — the shipped table against the human-data gait (torso lean {:+.2} rad), \
         {} steps each, same controller, device ({:.0} N·m drives, config 0x{}) and pilot\n",
        a.gait,
        a.human_torso_lean_rad,
        a.steps,
        a.device.drive_peak_Nm,
        a.device.fingerprint.trim_start_matches("0x")
    );
    out += "step  F shipped  F human  balance shipped  balance human  peak shipped  peak human  sat shipped  sat human\n";
    let n = a.shipped.f_ns.len().max(a.human.f_ns.len());
    let at = |v: &Vec<f64>, i: usize, d: usize| opt(v.get(i).copied(), d);
    for i in 0..n {
        out += &format!(
            "{:>4}  {:>9}  {:>7}  {:>15}  {:>13}  {:>12}  {:>10}  {:>11}  {:>9}\n",
            i + 1,
            at(&a.shipped.f_ns, i, 0),
            at(&a.human.f_ns, i, 0),
            at(&a.shipped.f_balance_ns, i, 0),
            at(&a.human.f_balance_ns, i, 0),
            at(&a.shipped.peak_N, i, 0),
            at(&a.human.peak_N, i, 0),
            at(&a.shipped.saturated_s, i, 3),
            at(&a.human.saturated_s, i, 3),
        );
    }
    out += &format!(
        "mean  {:>9}  {:>7}  {:>15}  {:>13}  {:>12}  {:>10}   (landed steps; N·s, N, s)\n",
        opt(a.shipped.mean.f_ns, 0),
        opt(a.human.mean.f_ns, 0),
        opt(a.shipped.mean.f_balance_ns, 0),
        opt(a.human.mean.f_balance_ns, 0),
        opt(a.shipped.mean.peak_N, 0),
        opt(a.human.mean.peak_N, 0),
    );
    let faults = |r: &RunJson| {
        if r.faults.is_empty() {
            "none".to_string()
        } else {
            r.faults
                .iter()
                .map(|f| format!("{} {}", f.code, f.name))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    out += &format!(
        "landed: shipped {}/{}, human {}/{}; faults: shipped {}; human {}\n",
        a.shipped
            .landing_error_m
            .iter()
            .filter(|l| l.is_some())
            .count(),
        a.steps,
        a.human
            .landing_error_m
            .iter()
            .filter(|l| l.is_some())
            .count(),
        a.steps,
        faults(&a.shipped),
        faults(&a.human)
    );
    let per_step = |v: &[Option<f64>], scale: f64| {
        v.iter()
            .map(|e| opt(e.map(|x| x * scale), 1))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let waits = |v: &[f64]| {
        v.iter()
            .map(|w| format!("{w:.2}"))
            .collect::<Vec<_>>()
            .join(" ")
    };
    out += &format!(
        "step error (mm): shipped {}; human {}\nwaited before each swing (s): shipped {}; human {}\n",
        per_step(&a.shipped.step_error_m, 1e3),
        per_step(&a.human.step_error_m, 1e3),
        waits(&a.shipped.waited_s),
        waits(&a.human.waited_s),
    );
    let c = &a.conditions;
    if let Some((enc, adc)) = c.sensor_noise {
        out += &format!(
            "sensor noise: ±{enc} encoder counts, ±{adc} ADC counts (seed {})\n",
            c.noise_seed
        );
    }
    if c.replan == crate::conditions::OnOff::On
        || c.pilot_lean != 0.0
        || c.pilot_stiffness != 1.0
        || c.stance_foot_off != 0.0
    {
        out += &format!(
            "pilot: lean {:+.1}°, stiffness ×{:.2}, stance foot {:+.1} cm off; re-planning {} (re-planned answers: shipped {}, human {})\n",
            c.pilot_lean,
            c.pilot_stiffness,
            c.stance_foot_off,
            if c.replan == crate::conditions::OnOff::On {
                "on"
            } else {
                "off"
            },
            a.shipped.replanned_answers,
            a.human.replanned_answers,
        );
    }
    out += &format!(
        "reduction (shipped against human): F {} %, balance part {} %, highest crutch peak {} %\n",
        opt(a.reduction_pct.f, 1),
        opt(a.reduction_pct.f_balance, 1),
        opt(a.reduction_pct.peak, 1)
    );
    out
}

/// The comparison of the bundle's gait `name` on its patient.
fn compare_bundle(
    path: &std::path::Path,
    name: &str,
    steps: usize,
    conditions: &Conditions,
) -> Result<(CompareJson, GaitRun, GaitRun), String> {
    let file = crate::bundle_file::BundleFile::load(path)?;
    let bundle = file.bundle()?;
    let (_, gait) = bundle.find(name).ok_or_else(|| {
        format!(
            "{}: no gait {name:?} (it holds {})",
            path.display(),
            file.names().join(", ")
        )
    })?;
    let device = file.fitted_device()?;
    compare_table(
        &device,
        gait.table,
        name.to_string(),
        Some(bundle.patient_hash()),
        steps,
        conditions,
    )
}

/// Runs `exogait compare`; exit status 0 when both gaits landed every step
/// without a fault, 1 otherwise, 2 for unusable options or a failed set-up.
pub fn run(args: &CompareArgs) -> u8 {
    if args.steps == 0 || args.steps > 20 {
        eprintln!("exogait compare: --steps must be in 1..=20");
        return 2;
    }
    if let Some(Err(e)) = args.plot.as_deref().map(crate::plot_path::check) {
        eprintln!("exogait compare: {e}");
        return 2;
    }
    if let Err(e) = args.conditions.check() {
        eprintln!("exogait compare: {e}");
        return 2;
    }
    let c = &args.conditions;
    let result = match &args.bundle {
        Some(path) => compare_bundle(path, &args.gait, args.steps, c),
        None => match <SimGait as clap::ValueEnum>::from_str(&args.gait, false) {
            Ok(g) => compare(g.kind(), args.steps, c),
            Err(_) => {
                eprintln!(
                    "exogait compare: --gait {:?}: without --bundle, one of walk, stair-up, stair-down",
                    args.gait
                );
                return 2;
            }
        },
    };
    let (answer, ours, theirs) = match result {
        Ok(x) => x,
        Err(e) => {
            eprintln!("exogait compare: {e}");
            return 2;
        }
    };
    if args.json {
        match serde_json::to_string(&answer) {
            Ok(t) => outln!("{t}"),
            Err(e) => {
                eprintln!("exogait compare: {e}");
                return 2;
            }
        }
    } else {
        out!("{}", table_text(&answer));
    }
    if let Some(path) = &args.plot {
        let title = format!(
            "{}: shipped table against the human-data gait on the same device",
            answer.gait
        );
        if let Err(e) = sim::plot::plot_comparison(&title, &ours, &theirs, path) {
            eprintln!("exogait compare: {}: {e}", path.display());
            return 2;
        }
        if !args.json {
            outln!("plot: {}", path.display());
        }
    }
    let clean = |r: &GaitRun| r.faults.is_empty() && r.landed() >= args.steps;
    if clean(&ours) && clean(&theirs) { 0 } else { 1 }
}

//! `exogait tables`: a patient's gait family as a verified bundle. Every
//! gait is searched on the patient's model, admitted by the device's check
//! and played for four steps in the closed loop (gait-opt's `family`); the
//! ones the device cannot play for this patient are left out, each with
//! the reason in numbers.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use exogait_device::DeviceConfig;
use gait_core::bundle::{GaitSource, bundle_len, encode};
use gait_opt::family::{
    DEFAULT_EVALS, DEFAULT_PACES_M_S, DEFAULT_STAIRS_M, Outcome, design_all_checked, family_plans,
};
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::patient_file;

/// Options of `exogait tables`.
#[derive(Debug, Args)]
pub struct TablesArgs {
    /// The patient file (`exogait fit`).
    #[arg(long, value_name = "FILE.json")]
    pub patient: PathBuf,
    /// Where to write the bundle.
    #[arg(long, value_name = "FILE.bundle")]
    pub out: PathBuf,
    /// Walking paces to design, m/s (default 0.15,0.25,0.35,0.40).
    #[arg(long, value_name = "V,…", value_delimiter = ',')]
    pub paces: Option<Vec<f64>>,
    /// Stairs to design, each up and down: RISE:TREAD in m (default
    /// 0.15:0.28,0.17:0.28,0.18:0.28).
    #[arg(long, value_name = "RISE:TREAD,…", value_delimiter = ',', value_parser = parse_stair)]
    pub stairs: Option<Vec<(f64, f64)>>,
    /// Cost evaluations of each gait's search.
    #[arg(long, default_value_t = DEFAULT_EVALS, value_name = "N")]
    pub evals: usize,
    /// Also play each gait that clears through N runs of the seeded fault
    /// campaign (`exogait faults`, seed 1): one a device fault drops the
    /// pilot from, with no named reason, is tried slower, and left out if
    /// no attempt passes (0 … 10,000; 0: none; about 0.1 s a run on two
    /// cores).
    #[arg(long, default_value_t = 0, value_name = "N")]
    pub campaign: usize,
    /// Print a JSON report instead of the text.
    #[arg(long)]
    pub json: bool,
}

fn parse_stair(text: &str) -> Result<(f64, f64), String> {
    let (r, t) = text
        .split_once(':')
        .ok_or_else(|| format!("expected RISE:TREAD in m, got {text:?}"))?;
    let num = |s: &str, what: &str| -> Result<f64, String> {
        s.trim()
            .parse::<f64>()
            .map_err(|_| format!("{what} {s:?} is not a number"))
    };
    let (rise, tread) = (num(r, "rise")?, num(t, "tread")?);
    if !(0.05..=0.22).contains(&rise) {
        return Err(format!("rise {rise} m is outside 0.05-0.22 m"));
    }
    if !(0.20..=0.40).contains(&tread) {
        return Err(format!("tread {tread} m is outside 0.20-0.40 m"));
    }
    Ok((rise, tread))
}

/// The generator's version as the bundle stores it.
pub fn generator_version() -> u32 {
    let mut parts = env!("CARGO_PKG_VERSION")
        .split('.')
        .map(|p| p.parse::<u32>().unwrap_or(0));
    let mut next = || parts.next().unwrap_or(0).min(255);
    let (major, minor, patch) = (next(), next(), next());
    (major << 16) | (minor << 8) | patch
}

#[derive(Debug, Serialize)]
struct GaitJson {
    name: String,
    kind: &'static str,
    cleared: bool,
    step_length_m: f64,
    rise_m: f64,
    step_time_s: f64,
    pace_m_s: Option<f64>,
    clearance_m: Option<f64>,
    double_support_s: Option<f64>,
    balance_ns: Option<f64>,
    /// The stance hip's torque residual in the healthy swings, highest, N·m.
    stance_hip_residual_peak_nm: Option<f64>,
    /// The limit the gait carries there (0x0404), N·m.
    stance_hip_residual_limit_nm: Option<u8>,
    reason: Option<String>,
}

#[derive(Debug, Serialize)]
struct TablesJson {
    bundle: String,
    patient_hash: String,
    device_fingerprint: String,
    seconds: f64,
    gaits: Vec<GaitJson>,
}

/// Runs `exogait tables`: 0 bundle written, 1 no gait could be cleared
/// (nothing written), 2 unusable input or I/O.
pub fn run(args: &TablesArgs) -> u8 {
    let started = Instant::now();
    let device = match DeviceConfig::exogait() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("exogait tables: device configuration: {e:?}");
            return 2;
        }
    };
    let patient = match patient_file::load(&args.patient, &device) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("exogait tables: {e}");
            return 2;
        }
    };
    let paces = args
        .paces
        .clone()
        .unwrap_or_else(|| DEFAULT_PACES_M_S.to_vec());
    if let Some(v) = paces.iter().find(|v| !(0.05..=0.6).contains(*v)) {
        eprintln!("exogait tables: pace {v} m/s is outside 0.05-0.6 m/s");
        return 2;
    }
    let stairs = args
        .stairs
        .clone()
        .unwrap_or_else(|| DEFAULT_STAIRS_M.to_vec());
    if !(200..=100_000).contains(&args.evals) {
        eprintln!("exogait tables: --evals must be in 200..=100000");
        return 2;
    }
    if args.campaign > 10_000 {
        eprintln!("exogait tables: --campaign must be in 0..=10000");
        return 2;
    }
    let fitted = match device.fitted(&patient.model) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("exogait tables: {e}");
            return 2;
        }
    };
    let plans = family_plans(&paces, &stairs, &fitted);
    if let Some(twice) = plans
        .iter()
        .enumerate()
        .find(|(i, p)| plans.iter().skip(i + 1).any(|q| q.name == p.name))
    {
        eprintln!(
            "exogait tables: gait {} asked twice (each pace and stair once)",
            twice.1.name
        );
        return 2;
    }
    if plans.is_empty() || plans.len() > gait_core::bundle::MAX_GAITS {
        eprintln!(
            "exogait tables: {} gaits asked; a bundle holds 1-{}",
            plans.len(),
            gait_core::bundle::MAX_GAITS
        );
        return 2;
    }
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    let bar = ProgressBar::new(plans.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{elapsed:>4} [{bar:30}] {pos}/{len} gaits  {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let outcomes = design_all_checked(
        &plans,
        &fitted,
        args.evals,
        args.campaign,
        threads,
        &|_, _, name| {
            bar.inc(1);
            bar.set_message(name.to_string());
        },
    );
    bar.finish_and_clear();
    let cleared: Vec<_> = outcomes
        .iter()
        .filter_map(|o| match o {
            Outcome::Cleared(g) => Some(g),
            Outcome::LeftOut { .. } => None,
        })
        .collect();
    let gaits_json: Vec<GaitJson> = outcomes
        .iter()
        .map(|o| match o {
            Outcome::Cleared(g) => GaitJson {
                name: g.plan.name.clone(),
                kind: gait_opt::clinical_report::gait_name(g.plan.kind),
                cleared: true,
                step_length_m: g.plan.spacing_m[0],
                rise_m: g.plan.spacing_m[1],
                step_time_s: g.plan.step_time_s,
                pace_m_s: Some(f64::from(g.info.pace_m_s)),
                clearance_m: Some(f64::from(g.info.clearance_m)),
                double_support_s: Some(g.evaluation.double_support_s),
                balance_ns: Some(g.balance_ns),
                stance_hip_residual_peak_nm: Some(g.stance_hip_residual_peak_nm),
                stance_hip_residual_limit_nm: Some(g.info.stance_hip_residual_nm),
                reason: None,
            },
            Outcome::LeftOut { plan, reason } => GaitJson {
                name: plan.name.clone(),
                kind: gait_opt::clinical_report::gait_name(plan.kind),
                cleared: false,
                step_length_m: plan.spacing_m[0],
                rise_m: plan.spacing_m[1],
                step_time_s: plan.step_time_s,
                pace_m_s: None,
                clearance_m: None,
                double_support_s: None,
                balance_ns: None,
                stance_hip_residual_peak_nm: None,
                stance_hip_residual_limit_nm: None,
                reason: Some(reason.clone()),
            },
        })
        .collect();
    let report = TablesJson {
        bundle: args.out.display().to_string(),
        patient_hash: format!("0x{:08x}", patient.hash()),
        device_fingerprint: format!("0x{:08x}", device.fingerprint()),
        seconds: started.elapsed().as_secs_f64(),
        gaits: gaits_json,
    };
    if args.json {
        match serde_json::to_string_pretty(&report) {
            Ok(t) => outln!("{t}"),
            Err(e) => {
                eprintln!("exogait tables: {e}");
                return 2;
            }
        }
    } else {
        outln!(
            "exogait tables: {} of {} gaits cleared for patient 0x{:08x} ({:.2} m, {:.0} kg) in {:.1} s",
            cleared.len(),
            outcomes.len(),
            patient.hash(),
            patient.height_m,
            patient.mass_kg,
            report.seconds
        );
        for g in &report.gaits {
            if g.cleared {
                outln!(
                    "  cleared   {:<12} step {:.3} m, rise {:+.3} m, {:.2} s ({:.2} s double support): pace {:.3} m/s, clearance {:.3} m, balance part {:.0} N·s, stance hip's residual {:.0} N·m (limit {})",
                    g.name,
                    g.step_length_m,
                    g.rise_m,
                    g.step_time_s,
                    g.double_support_s.unwrap_or(0.0),
                    g.pace_m_s.unwrap_or(0.0),
                    g.clearance_m.unwrap_or(0.0),
                    g.balance_ns.unwrap_or(0.0),
                    g.stance_hip_residual_peak_nm.unwrap_or(0.0),
                    g.stance_hip_residual_limit_nm.unwrap_or(0),
                );
            } else {
                outln!(
                    "  left out  {:<12} {}",
                    g.name,
                    g.reason.as_deref().unwrap_or("")
                );
            }
        }
    }
    if cleared.is_empty() {
        eprintln!("exogait tables: no gait could be cleared for this patient: no bundle written");
        return 1;
    }
    let sources: Vec<GaitSource<'_>> = cleared
        .iter()
        .map(|g| GaitSource {
            info: g.info,
            table: &g.image,
        })
        .collect();
    let mut buf = vec![0u8; bundle_len(&sources)];
    if let Err(e) = encode(
        device.fingerprint(),
        generator_version(),
        &patient,
        &sources,
        &mut buf,
    ) {
        eprintln!("exogait tables: the bundle could not be written: {e}");
        return 2;
    }
    if let Err(e) = std::fs::write(&args.out, &buf) {
        eprintln!("exogait tables: {}: {e}", args.out.display());
        return 2;
    }
    if !args.json {
        outln!("bundle: {} ({} bytes)", args.out.display(), buf.len());
    }
    0
}

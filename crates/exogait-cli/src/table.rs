//! `exogait table`: an `optimize` report (paper or clinical mode) turned
//! into a gait table in the flash format, checked against the device
//! before it is written; and the loading of a report or a table file for
//! `simulate --table`. No algorithm here: gait-opt rebuilds the step,
//! gait-core encodes and verifies, exogait-device checks.

use std::path::{Path, PathBuf};

use clap::Args;
use exogait_device::DeviceConfig;
use gait_core::tables::{GaitKind, GaitTable, MAGIC};
use gait_opt::clinical_report::{ClinicalReport, gait_kind};
use gait_opt::family::check_playable;
use gait_opt::report::step_samples;
use gait_opt::{Report, tables::table_image};

/// Options of `exogait table`.
#[derive(Debug, Args)]
pub struct TableArgs {
    /// The report `exogait optimize` wrote.
    #[arg(value_name = "REPORT.json")]
    pub report: PathBuf,
    /// Where to write the table (the flash format, with its CRC).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Why a table could not be made or loaded (the message names the cause).
#[derive(Debug)]
pub struct TableFailure {
    /// What went wrong.
    pub message: String,
    /// Whether the gait is the problem (refused by the device: exit 1)
    /// rather than the input (exit 2).
    pub refused: bool,
}

impl TableFailure {
    fn input(message: String) -> Self {
        Self {
            message,
            refused: false,
        }
    }
}

/// The table image of a report's step: clinical reports rebuild their step
/// on the device's model; paper-mode reports their control points on the
/// report's problem (the kind from its case label).
pub fn image_of_report(text: &str, device: &DeviceConfig) -> Result<Vec<u8>, TableFailure> {
    if text.contains("\"mode\"") {
        let r = ClinicalReport::from_json(text).map_err(|e| TableFailure::input(e.to_string()))?;
        let kind = gait_kind(&r.gait)
            .ok_or_else(|| TableFailure::input(format!("unknown gait {:?}", r.gait)))?;
        let case = r
            .case(device)
            .map_err(|e| TableFailure::input(e.to_string()))?;
        let (phi, _) = r
            .phi(device)
            .map_err(|e| TableFailure::input(e.to_string()))?;
        return table_image(kind, &case.ik, &phi).map_err(|e| TableFailure::input(e.to_string()));
    }
    let r =
        Report::from_json(text).map_err(|e| TableFailure::input(format!("not a report: {e}")))?;
    let problem = r
        .problem
        .problem()
        .map_err(|e| TableFailure::input(format!("report: {e}")))?;
    let rows = step_samples(&problem, &r.control_points)
        .map_err(|e| TableFailure::input(format!("report: the step cannot be sampled: {e}")))?;
    let phi: Vec<[f64; 5]> = rows.iter().map(|row| row.phi_rad).collect();
    let kind = match r.problem.case.as_str() {
        "walk" => GaitKind::Walk,
        "stair_down" => GaitKind::StairDown,
        _ if problem.case.landing_m[1] < 0.0 => GaitKind::StairDown,
        _ if problem.case.landing_m[1] > 0.0 => GaitKind::StairUp,
        _ => GaitKind::Walk,
    };
    table_image(kind, &problem.case.ik, &phi).map_err(|e| TableFailure::input(e.to_string()))
}

/// A table file (flash format) or a report, as a verified table image that
/// the device can play: refused, naming the sample, the joint and the
/// limit, when it cannot.
pub fn load_playable(path: &Path, device: &DeviceConfig) -> Result<Vec<u8>, TableFailure> {
    let bytes = std::fs::read(path)
        .map_err(|e| TableFailure::input(format!("{}: cannot read: {e}", path.display())))?;
    let image = if bytes.starts_with(&MAGIC) {
        bytes
    } else {
        let text = String::from_utf8(bytes).map_err(|_| {
            TableFailure::input(format!(
                "{}: neither a gait table nor a JSON report",
                path.display()
            ))
        })?;
        image_of_report(&text, device).map_err(|e| TableFailure {
            message: format!("{}: {}", path.display(), e.message),
            ..e
        })?
    };
    admit(&image, device, path)?;
    Ok(image)
}

/// The table of `image` is one the tool may hand a user
/// (`gait_opt::family::check_playable`: admission, clearance, first step
/// in the closed loop); refused with the reason otherwise.
pub fn admit(image: &[u8], device: &DeviceConfig, path: &Path) -> Result<(), TableFailure> {
    let table = GaitTable::parse(image)
        .map_err(|e| TableFailure::input(format!("{}: {e}", path.display())))?;
    check_playable(device, &table).map_err(|e| TableFailure {
        message: format!("{}: the device cannot play it: {e}", path.display()),
        refused: true,
    })?;
    Ok(())
}

/// Runs `exogait table`: 0 written, 1 the device refuses the gait (nothing
/// written), 2 unusable input or output.
pub fn run(args: &TableArgs) -> u8 {
    let device = match DeviceConfig::exogait() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("exogait table: device configuration: {e:?}");
            return 2;
        }
    };
    let text = match std::fs::read_to_string(&args.report) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("exogait table: {}: cannot read: {e}", args.report.display());
            return 2;
        }
    };
    let image = match image_of_report(&text, &device)
        .and_then(|image| admit(&image, &device, &args.report).map(|()| image))
    {
        Ok(i) => i,
        Err(e) => {
            eprintln!("exogait table: {}", e.message);
            return if e.refused { 1 } else { 2 };
        }
    };
    if let Err(e) = std::fs::write(&args.out, &image) {
        eprintln!(
            "exogait table: --out {}: cannot write: {e}",
            args.out.display()
        );
        return 2;
    }
    let table = GaitTable::parse(&image);
    if let Ok(t) = table {
        outln!(
            "table {}: {} samples, {:.2} s, {} bytes: {}",
            gait_opt::clinical_report::gait_name(t.kind()),
            t.len(),
            t.duration_s(),
            image.len(),
            args.out.display()
        );
    }
    0
}

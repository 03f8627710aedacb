//! `exogait bundle`: what a bundle holds, after verifying it for this
//! device.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use crate::bundle_file::BundleFile;

/// Options of `exogait bundle`.
#[derive(Debug, Args)]
pub struct BundleArgs {
    /// The bundle (`exogait tables`).
    #[arg(value_name = "FILE.bundle")]
    pub file: PathBuf,
    /// Print JSON instead of the text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Serialize)]
struct GaitJson {
    name: String,
    kind: &'static str,
    step_length_m: f32,
    rise_m: f32,
    tread_m: f32,
    step_time_s: f32,
    pace_m_s: f32,
    clearance_m: f32,
    /// The stance hip's torque-residual limit in its swings as the board
    /// holds it, N·m (the entry's figure within the supervisor's bounds;
    /// the device's own limit where the entry gives none).
    stance_hip_residual_nm: f32,
    /// Whether the entry gives one.
    stance_hip_residual_own: bool,
}

#[derive(Debug, Serialize)]
struct BundleJson {
    format_version: u16,
    bytes: usize,
    crc: String,
    device_fingerprint: String,
    generator_version: String,
    patient_hash: String,
    height_m: f64,
    mass_kg: f64,
    segments_m: [f64; 3],
    total_mass_kg: f64,
    gaits: Vec<GaitJson>,
}

/// Runs `exogait bundle`: 0 listed, 2 refused or unreadable.
pub fn run(args: &BundleArgs) -> u8 {
    let file = match BundleFile::load(&args.file) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("exogait bundle: {e}");
            return 2;
        }
    };
    let b = match file.bundle() {
        Ok(b) => b,
        Err(e) => {
            eprintln!("exogait bundle: {e}");
            return 2;
        }
    };
    let response = file.device.supervisor.response;
    let v = b.generator_version();
    let p = b.patient();
    let answer = BundleJson {
        format_version: gait_core::bundle::FORMAT_VERSION,
        bytes: b.image_len(),
        crc: format!("0x{:08x}", b.crc()),
        device_fingerprint: format!("0x{:08x}", b.device_fingerprint()),
        generator_version: format!("{}.{}.{}", v >> 16, (v >> 8) & 0xff, v & 0xff),
        patient_hash: format!("0x{:08x}", b.patient_hash()),
        height_m: p.height_m,
        mass_kg: p.mass_kg,
        segments_m: p.segments_m,
        total_mass_kg: p.model.total_mass_kg(),
        gaits: (0..b.len())
            .filter_map(|i| b.gait(i))
            .map(|g| GaitJson {
                name: g.info.name.as_str().to_string(),
                kind: gait_opt::clinical_report::gait_name(g.info.kind),
                step_length_m: g.info.step_length_m,
                rise_m: g.info.rise_m,
                tread_m: g.info.tread_m,
                step_time_s: g.info.step_time_s,
                pace_m_s: g.info.pace_m_s,
                clearance_m: g.info.clearance_m,
                stance_hip_residual_nm: response
                    .stance_hip_limit_nm(f32::from(g.info.stance_hip_residual_nm)),
                stance_hip_residual_own: g.info.stance_hip_residual_nm > 0,
            })
            .collect(),
    };
    if args.json {
        match serde_json::to_string_pretty(&answer) {
            Ok(t) => outln!("{t}"),
            Err(e) => {
                eprintln!("exogait bundle: {e}");
                return 2;
            }
        }
        return 0;
    }
    outln!(
        "{}: bundle v{}, {} bytes, CRC {}, device {}, generator {}",
        args.file.display(),
        answer.format_version,
        answer.bytes,
        answer.crc,
        answer.device_fingerprint,
        answer.generator_version
    );
    outln!(
        "patient {}: {:.2} m, {:.1} kg (with the exoskeleton {:.1} kg); thigh {:.3} m, shank {:.3} m, foot {:.3} m",
        answer.patient_hash,
        p.height_m,
        p.mass_kg,
        answer.total_mass_kg,
        p.segments_m[0],
        p.segments_m[1],
        p.segments_m[2]
    );
    outln!(
        "  #  name          kind        step m  rise m  tread m  time s  pace m/s  clearance m  stance hip N·m"
    );
    for (i, g) in answer.gaits.iter().enumerate() {
        outln!(
            "{:>3}  {:<12}  {:<10}  {:>6.3}  {:>+6.3}  {:>7.3}  {:>6.2}  {:>8.3}  {:>11.3}  {:>14}",
            i + 1,
            g.name,
            g.kind,
            g.step_length_m,
            g.rise_m,
            g.tread_m,
            g.step_time_s,
            g.pace_m_s,
            g.clearance_m,
            if g.stance_hip_residual_own {
                format!("{:.0}", g.stance_hip_residual_nm)
            } else {
                format!("{:.0} (device's)", g.stance_hip_residual_nm)
            }
        );
    }
    0
}

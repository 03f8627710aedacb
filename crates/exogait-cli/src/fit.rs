//! `exogait fit`: a patient's body model from the clinic's measures (the
//! exoskeleton's own segments and joint limits from the device), written
//! as a patient file and printed.

use std::path::PathBuf;

use clap::Args;
use exogait_device::DeviceConfig;
use exogait_device::fitting::{Measures, fit};

use crate::patient_file::PatientFile;

/// Options of `exogait fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// Standing height, m (1.45-2.00).
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub height: f64,
    /// Body mass without the exoskeleton, kg (40-120).
    #[arg(long, value_name = "KG", allow_negative_numbers = true)]
    pub mass: f64,
    /// Measured thigh (greater trochanter to knee joint), m; default:
    /// Winter's 0.245 x height.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub thigh: Option<f64>,
    /// Measured shank (knee joint to lateral malleolus), m; default:
    /// Winter's 0.246 x height.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub shank: Option<f64>,
    /// Measured foot (heel to toe tip), m; default: Winter's 0.152 x
    /// height.
    #[arg(long, value_name = "M", allow_negative_numbers = true)]
    pub foot: Option<f64>,
    /// Where to write the patient file.
    #[arg(long, value_name = "FILE.json")]
    pub out: PathBuf,
}

/// Runs `exogait fit`: 0 written, 2 refused measures or I/O.
pub fn run(args: &FitArgs) -> u8 {
    let device = match DeviceConfig::exogait() {
        Ok(d) => d,
        Err(e) => {
            eprintln!("exogait fit: device configuration: {e:?}");
            return 2;
        }
    };
    let measures = Measures {
        height_m: args.height,
        mass_kg: args.mass,
        thigh_m: args.thigh,
        shank_m: args.shank,
        foot_m: args.foot,
    };
    let patient = match fit(&device, &measures) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("exogait fit: {e}");
            return 2;
        }
    };
    let file = PatientFile::new(&patient, &measures);
    let text = match serde_json::to_string_pretty(&file) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("exogait fit: {e}");
            return 2;
        }
    };
    if let Err(e) = std::fs::write(&args.out, format!("{text}\n")) {
        eprintln!("exogait fit: {}: {e}", args.out.display());
        return 2;
    }
    outln!("{text}");
    0
}

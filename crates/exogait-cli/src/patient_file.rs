//! The patient file `exogait fit` writes and `exogait tables` reads: what
//! the clinic measured and the combined pilot-plus-exoskeleton model built
//! from it (SI units; the joint limits are the device's).
//!
//! ```json
//! {"format": "exogait-patient", "version": 1,
//!  "height_m": 1.75, "mass_kg": 75.0,
//!  "thigh_m": 0.429, "shank_m": 0.431, "foot_m": 0.266,
//!  "measured": ["thigh"],
//!  "total_mass_kg": 92.0, "patient_hash": "0x1234abcd",
//!  "links": [{"name": "stance shank", "length_m": …, "com_m": …, "mass_kg": …, "inertia_kgm2": …}, …×5]}
//! ```
//!
//! On reading, the model is rebuilt from the measures on this device and
//! must equal the file's links: a file edited by hand, or written for
//! another exoskeleton, is refused rather than trusted.

use std::path::Path;

use exogait_device::DeviceConfig;
use exogait_device::fitting::{Measures, fit};
use gait_core::bundle::Patient;
use serde::{Deserialize, Serialize};

/// The format's name in the file.
pub const FORMAT: &str = "exogait-patient";
/// The format's version.
pub const VERSION: u32 = 1;

const LINK_NAMES: [&str; 5] = [
    "stance shank",
    "stance thigh",
    "torso",
    "swing thigh",
    "swing shank",
];

/// One link in the file.
#[derive(Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LinkJson {
    /// Its role in the chain.
    pub name: String,
    /// Joint to joint, m.
    pub length_m: f64,
    /// Proximal joint to centre of mass, m.
    pub com_m: f64,
    /// Mass, kg.
    pub mass_kg: f64,
    /// Inertia about the centre of mass, kg·m².
    pub inertia_kgm2: f64,
}

/// The file.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PatientFile {
    /// [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// Standing height, m.
    pub height_m: f64,
    /// Body mass without the exoskeleton, kg.
    pub mass_kg: f64,
    /// Greater trochanter to knee joint, m.
    pub thigh_m: f64,
    /// Knee joint to lateral malleolus, m.
    pub shank_m: f64,
    /// Heel to toe tip, m.
    pub foot_m: f64,
    /// Which of thigh, shank and foot were measured (the others are
    /// Winter's proportions of the height).
    pub measured: Vec<String>,
    /// Pilot plus exoskeleton, kg.
    pub total_mass_kg: f64,
    /// CRC-32 of the model as the bundle stores it.
    pub patient_hash: String,
    /// The five links.
    pub links: Vec<LinkJson>,
}

impl PatientFile {
    /// The file of a fitted patient.
    pub fn new(p: &Patient, measured: &Measures) -> Self {
        let mut which = Vec::new();
        for (name, m) in [
            ("thigh", measured.thigh_m),
            ("shank", measured.shank_m),
            ("foot", measured.foot_m),
        ] {
            if m.is_some() {
                which.push(name.to_string());
            }
        }
        Self {
            format: FORMAT.into(),
            version: VERSION,
            height_m: p.height_m,
            mass_kg: p.mass_kg,
            thigh_m: p.segments_m[0],
            shank_m: p.segments_m[1],
            foot_m: p.segments_m[2],
            measured: which,
            total_mass_kg: p.model.total_mass_kg(),
            patient_hash: format!("0x{:08x}", p.hash()),
            links: p
                .model
                .links()
                .iter()
                .zip(LINK_NAMES)
                .map(|(l, name)| LinkJson {
                    name: name.into(),
                    length_m: l.length_m,
                    com_m: l.com_m,
                    mass_kg: l.mass_kg,
                    inertia_kgm2: l.inertia_kgm2,
                })
                .collect(),
        }
    }

    /// The measures the file records.
    pub fn measures(&self) -> Measures {
        let given = |name: &str, v: f64| self.measured.iter().any(|m| m == name).then_some(v);
        Measures {
            height_m: self.height_m,
            mass_kg: self.mass_kg,
            thigh_m: given("thigh", self.thigh_m),
            shank_m: given("shank", self.shank_m),
            foot_m: given("foot", self.foot_m),
        }
    }
}

/// Reads and checks a patient file against `device`.
pub fn load(path: &Path, device: &DeviceConfig) -> Result<Patient, String> {
    let where_ = path.display();
    let text = std::fs::read_to_string(path).map_err(|e| format!("{where_}: {e}"))?;
    let file: PatientFile =
        serde_json::from_str(&text).map_err(|e| format!("{where_}: not a patient file: {e}"))?;
    if file.format != FORMAT || file.version != VERSION {
        return Err(format!(
            "{where_}: format {:?} version {} is not {FORMAT:?} version {VERSION}",
            file.format, file.version
        ));
    }
    if let Some(m) = file
        .measured
        .iter()
        .find(|m| !["thigh", "shank", "foot"].contains(&m.as_str()))
    {
        return Err(format!("{where_}: unknown measured segment {m:?}"));
    }
    let patient = fit(device, &file.measures()).map_err(|e| format!("{where_}: {e}"))?;
    let rebuilt = PatientFile::new(&patient, &file.measures());
    let same = rebuilt.links.len() == file.links.len()
        && rebuilt.links.iter().zip(&file.links).all(|(a, b)| {
            let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(1.0);
            a.name == b.name
                && close(a.length_m, b.length_m)
                && close(a.com_m, b.com_m)
                && close(a.mass_kg, b.mass_kg)
                && close(a.inertia_kgm2, b.inertia_kgm2)
        });
    let winter_ok = [
        ("thigh", file.thigh_m, rebuilt.thigh_m),
        ("shank", file.shank_m, rebuilt.shank_m),
        ("foot", file.foot_m, rebuilt.foot_m),
    ]
    .iter()
    .all(|(_, a, b)| (a - b).abs() <= 1e-9);
    if !same || !winter_ok {
        return Err(format!(
            "{where_}: its model is not what its measures give on this device (edited by hand, \
             or fitted for another exoskeleton): fit the patient again with `exogait fit`"
        ));
    }
    Ok(patient)
}

//! The `--model FILE.json` format: explicit links, or a pilot built with
//! gait-core's anthropometry. Everything ends in `BodyModel::new`'s checks.
//!
//! ```json
//! {"links": [{"length_m": 0.441, "com_m": 0.269, "mass_kg": 7.05, "inertia_kgm2": 0.226}, …×5],
//!  "limits": {"hip_flexion_deg": 100}}
//! {"pilot": {"height_m": 1.75, "mass_kg": 76.5},
//!  "exo": {"torso": {"mass_kg": 6.2}, "thigh": {"mass_kg": 3.5}, "shank": {"mass_kg": 1.9}},
//!  "torso_span": "hip_to_vertex"}
//! ```
//!
//! Joint limits are in degrees (as clinicians and Table I state them); each
//! one left out keeps Table I's value.

use std::fmt;
use std::path::{Path, PathBuf};

use gait_core::anthropometry::{self, ExoSegment, ExoSegments, Options, Pilot, TorsoSpan};
use gait_core::{BodyModel, JointLimits, Link};
use serde::Deserialize;

/// A `--model` file that could not be used: which file and why.
#[derive(Debug)]
pub struct ModelFileError {
    path: PathBuf,
    problem: String,
}

impl fmt::Display for ModelFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "--model {}: {}", self.path.display(), self.problem)
    }
}

impl std::error::Error for ModelFileError {}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    links: Option<[LinkJson; 5]>,
    pilot: Option<PilotJson>,
    exo: Option<ExoJson>,
    torso_span: Option<TorsoSpanJson>,
    limits: Option<LimitsJson>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LinkJson {
    length_m: f64,
    com_m: f64,
    mass_kg: f64,
    inertia_kgm2: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PilotJson {
    height_m: f64,
    mass_kg: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExoJson {
    torso: ExoSegmentJson,
    thigh: ExoSegmentJson,
    shank: ExoSegmentJson,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExoSegmentJson {
    mass_kg: f64,
    com_m: Option<f64>,
    inertia_kgm2: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "snake_case")]
enum TorsoSpanJson {
    HipToShoulder,
    HipToVertex,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitsJson {
    hip_flexion_deg: Option<f64>,
    hip_extension_deg: Option<f64>,
    knee_flexion_deg: Option<f64>,
    knee_extension_deg: Option<f64>,
    ankle_dorsiflexion_deg: Option<f64>,
    ankle_plantarflexion_deg: Option<f64>,
}

impl LimitsJson {
    /// Table I with the given values (degrees) replaced.
    fn to_limits(&self) -> JointLimits<f64> {
        let base = JointLimits::<f64>::paper_table_i();
        let pick = |deg: Option<f64>, default: f64| deg.map_or(default, f64::to_radians);
        JointLimits {
            hip_flexion_rad: pick(self.hip_flexion_deg, base.hip_flexion_rad),
            hip_extension_rad: pick(self.hip_extension_deg, base.hip_extension_rad),
            knee_flexion_rad: pick(self.knee_flexion_deg, base.knee_flexion_rad),
            knee_extension_rad: pick(self.knee_extension_deg, base.knee_extension_rad),
            ankle_dorsiflexion_rad: pick(self.ankle_dorsiflexion_deg, base.ankle_dorsiflexion_rad),
            ankle_plantarflexion_rad: pick(
                self.ankle_plantarflexion_deg,
                base.ankle_plantarflexion_rad,
            ),
        }
    }
}

impl From<&ExoSegmentJson> for ExoSegment<f64> {
    fn from(s: &ExoSegmentJson) -> Self {
        Self {
            mass_kg: s.mass_kg,
            com_m: s.com_m,
            inertia_kgm2: s.inertia_kgm2,
        }
    }
}

/// Reads, parses and validates a model file.
pub fn load(path: &Path) -> Result<BodyModel<f64>, ModelFileError> {
    let fail = |problem: String| ModelFileError {
        path: path.to_path_buf(),
        problem,
    };
    let text = std::fs::read_to_string(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    parse(&text).map_err(fail)
}

/// Parses and validates a model file's text.
fn parse(text: &str) -> Result<BodyModel<f64>, String> {
    let file: ModelFile = serde_json::from_str(text).map_err(|e| format!("bad JSON: {e}"))?;
    let limits = file.limits.unwrap_or_default().to_limits();
    match (file.links, file.pilot) {
        (Some(links), None) => {
            if file.exo.is_some() || file.torso_span.is_some() {
                return Err("\"exo\" and \"torso_span\" only go with \"pilot\"".into());
            }
            let links = links.map(|l| Link {
                length_m: l.length_m,
                com_m: l.com_m,
                mass_kg: l.mass_kg,
                inertia_kgm2: l.inertia_kgm2,
            });
            BodyModel::new(links, limits).map_err(|e| format!("invalid model: {e}"))
        }
        (None, Some(p)) => {
            let pilot = Pilot {
                height_m: p.height_m,
                mass_kg: p.mass_kg,
            };
            let exo = file
                .exo
                .map_or_else(ExoSegments::paper_default, |e| ExoSegments {
                    torso: (&e.torso).into(),
                    thigh: (&e.thigh).into(),
                    shank: (&e.shank).into(),
                });
            let torso = match file.torso_span {
                None => TorsoSpan::default(),
                Some(TorsoSpanJson::HipToShoulder) => TorsoSpan::HipToShoulder,
                Some(TorsoSpanJson::HipToVertex) => TorsoSpan::HipToVertex,
            };
            let options = Options { torso, limits };
            anthropometry::body_model_with(&pilot, &exo, &options)
                .map_err(|e| format!("invalid pilot: {e}"))
        }
        (Some(_), Some(_)) => Err("give either \"links\" or \"pilot\", not both".into()),
        (None, None) => Err("needs \"links\" (five links) or \"pilot\"".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_iii_as_links_round_trips() -> Result<(), String> {
        let m = BodyModel::<f64>::paper_table_iii();
        let links: Vec<String> = m
            .links()
            .iter()
            .map(|l| {
                format!(
                    "{{\"length_m\":{},\"com_m\":{},\"mass_kg\":{},\"inertia_kgm2\":{}}}",
                    l.length_m, l.com_m, l.mass_kg, l.inertia_kgm2
                )
            })
            .collect();
        let text = format!("{{\"links\":[{}]}}", links.join(","));
        assert_eq!(parse(&text)?, m);
        Ok(())
    }

    #[test]
    fn limits_in_degrees_override_table_i() -> Result<(), String> {
        let text = "{\"pilot\":{\"height_m\":1.75,\"mass_kg\":76.5},\
                    \"limits\":{\"knee_flexion_deg\":90}}";
        let m = parse(text)?;
        assert!((m.limits().knee_flexion_rad - 90f64.to_radians()).abs() < 1e-15);
        assert_eq!(
            m.limits().hip_flexion_rad,
            JointLimits::<f64>::paper_table_i().hip_flexion_rad
        );
        Ok(())
    }

    #[test]
    fn problems_are_named() {
        let err = |t: &str| parse(t).err().unwrap_or_default();
        assert!(err("{}").contains("needs"));
        assert!(err("{\"pilot\":{\"height_m\":3,\"mass_kg\":70}}").contains("height"));
        assert!(
            err("{\"pilot\":{\"height_m\":1.7,\"mass_kg\":70},\"typo\":1}")
                .contains("unknown field")
        );
        assert!(err("{\"links\":[]}").contains("bad JSON"));
        assert!(
            err(
                "{\"pilot\":{\"height_m\":1.7,\"mass_kg\":70},\"limits\":{\"hip_flexion_deg\":-5}}"
            )
            .contains("joint limits")
        );
    }
}

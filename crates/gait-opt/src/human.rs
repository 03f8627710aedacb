//! The human-data gait a table is compared with (the paper's Table II): the
//! baseline of [`crate::baseline`] built at the table's geometry (step
//! length and rise) and step time, and replayed through the device's own
//! IK, so that the controller plays it on the same device as the tables.
//!
//! The baseline's construction is the paper mode's (swing phase of the
//! data, scaled to the step, end-corrected), with the device's feet (the
//! toe rocker: a stance heel may lift). One change, the smallest that lets
//! the device play it: the data have no trunk angle (the baseline holds the
//! torso upright), and the torso is given the constant lean of smallest
//! magnitude for which no hip or knee needs more than [`HUMAN_DRIVE_USE`]
//! of its drive (a lean moves neither foot), and, where the closed loop
//! still cannot play it ([`playable_human_gait_in_loop`]: a walk whose
//! stance knee gives way as the second step begins), the nearest lean, in
//! [`LOOP_LEAN_STEP_RAD`] steps, that lands every step. What the device then
//! does with it, faults included, is what the comparison reports
//! (`docs/optimiser.md`, "The human-data gait").

use std::path::Path;

use gait_core::BodyModel;
use gait_core::foot::StanceFoot;
use gait_core::gait::StanceAnkleProfile;
use gait_core::ik::IkOptions;
use gait_core::kinematics::Phi;
use gait_core::problem::{PaperProblem, StepCase};
use gait_core::tables::GaitKind;

use exogait_device::DeviceConfig;
use gait_core::tables::GaitTable;

use crate::baseline::{BaselineError, Correction, Source, baseline_window};
use crate::clinical::{ClinicalCase, evaluate_phi};

/// A human-data step and what it was built from.
#[derive(Clone, Debug, PartialEq)]
pub struct HumanGait {
    /// The data set.
    pub source: Source,
    /// Φ at every 10 ms sample, rad.
    pub phi: Vec<Phi<f64>>,
    /// The amplitude factor applied to the data.
    pub amplitude_scale: f64,
    /// The torso's lean, rad (forward positive).
    pub torso_lean_rad: f64,
}

/// The problem whose geometry a human step is built at: from −`spacing`
/// to +`spacing` around the stance foot in `step_time_s`, on `model` with
/// the device's feet.
pub fn human_problem(
    spacing_m: [f64; 2],
    step_time_s: f64,
    model: &BodyModel<f64>,
) -> PaperProblem<f64> {
    let [sx, sy] = spacing_m;
    let case = StepCase {
        start_m: [-sx, -sy],
        landing_m: [sx, sy],
        step_time_s,
        // Not used by a baseline (its stance shank comes from the data).
        stance: StanceAnkleProfile {
            a_rad: 0.0,
            b_rad: 0.0,
            k_per_s: 1.0,
            t_c_s: 0.0,
        },
        r2_start: 0.5,
        phi3_start_rad: 0.0,
        end_posture: None,
        rest_at_ends: false,
        foot: Some(StanceFoot::for_model(model)),
        ik: IkOptions::paper(),
    };
    PaperProblem::new(case, *model)
}

/// The human-data step of `case`'s movement (walk: Fukuchi 2018; stair
/// ascent: Reznick 20°; stair descent: Reznick 20°) at its geometry and
/// timing, from the data in `dir`, with the torso
/// at `lean_rad`.
pub fn human_gait(
    case: &ClinicalCase,
    dir: &Path,
    lean_rad: f64,
) -> Result<HumanGait, BaselineError> {
    let source = Source::for_gait(case.gait);
    let problem = human_problem(case.spacing_m, case.step_time_s, &case.model);
    let b = baseline_window(&problem, source, dir, correction_for(case.gait))?;
    let phi: Vec<Phi<f64>> = b
        .phi
        .iter()
        .map(|p| {
            let mut q = *p;
            q[2] += lean_rad;
            q
        })
        .collect();
    Ok(HumanGait {
        source,
        phi,
        amplitude_scale: b.amplitude_scale,
        torso_lean_rad: lean_rad,
    })
}

/// Which end correction makes the human step playable on the device: the
/// paper mode's (the stance thigh and the swing leg) where it does, the
/// stance shank instead of the thigh where the thigh's correction bends the
/// stance knee past its stop (walking: by 5.4°; descent: by 7°).
pub fn correction_for(gait: GaitKind) -> Correction {
    match gait {
        GaitKind::StairUp => Correction::StanceThighAndSwingLeg,
        GaitKind::Walk | GaitKind::StairDown => Correction::StanceShankAndSwingLeg,
    }
}

/// Largest share of the drive's available torque the replayed human gait
/// may ask of any hip or knee (the rest is the position loop's: the human
/// step loads the stance leg at once when it lifts the foot).
pub const HUMAN_DRIVE_USE: f64 = 0.65;
/// Largest torso lean tried, rad (26°).
const MAX_LEAN_RAD: f64 = 0.45;
/// Step of the lean search, rad.
const LEAN_STEP_RAD: f64 = 0.01;

/// [`human_gait`] with the torso lean of smallest magnitude (forward or
/// back, in 0.01 rad steps up to 0.45 rad) for which no hip or knee needs
/// more than [`HUMAN_DRIVE_USE`] of what its drive gives at its speed, with
/// the device's sharing of the load between the feet; when no lean is
/// enough, the one asking least of the drives.
pub fn playable_human_gait(case: &ClinicalCase, dir: &Path) -> Result<HumanGait, BaselineError> {
    let use_of = |g: &HumanGait| evaluate_phi(case, &g.phi).map_or(f64::INFINITY, |e| e.drive_use);
    let mut best: Option<(f64, HumanGait)> = None;
    let steps = (MAX_LEAN_RAD / LEAN_STEP_RAD).round() as usize;
    for i in 0..=steps {
        for sign in [1.0, -1.0] {
            let lean = sign * LEAN_STEP_RAD * i as f64;
            if let Ok(g) = human_gait(case, dir, lean) {
                let u = use_of(&g);
                if u <= HUMAN_DRIVE_USE {
                    return Ok(g);
                }
                if best.as_ref().is_none_or(|(b, _)| u < *b) {
                    best = Some((u, g));
                }
            }
            if i == 0 {
                break;
            }
        }
    }
    match best {
        Some((_, g)) => Ok(g),
        None => human_gait(case, dir, 0.0),
    }
}

/// Steps the human gait must land, without a fault, for the closed loop to
/// play it.
pub const HUMAN_VERIFY_STEPS: usize = 4;
/// Step of the closed loop's lean search, rad (about 3°).
pub const LOOP_LEAN_STEP_RAD: f64 = 0.05;

/// Whether `device` with the comparison's pilot plays `gait` for
/// [`HUMAN_VERIFY_STEPS`] steps, every one landed and no fault.
fn lands_in_loop(case: &ClinicalCase, device: &DeviceConfig, gait: &HumanGait) -> bool {
    let Ok(image) = crate::tables::table_image(case.gait, &case.ik, &gait.phi) else {
        return false;
    };
    let Ok(table) = GaitTable::parse(&image) else {
        return false;
    };
    let steps = HUMAN_VERIFY_STEPS;
    let max_s = 8.0 + (2.0 + case.step_time_s) * steps as f64;
    sim::compare::play(
        device,
        table,
        sim::scenario::strong_pilot(),
        steps,
        max_s,
        |_| {},
    )
    .is_ok_and(|(run, _)| run.faults.is_empty() && run.landed() >= steps)
}

/// [`playable_human_gait`], played in the closed loop on `device`: when it
/// does not land every step, the lean nearest to it (in
/// [`LOOP_LEAN_STEP_RAD`] steps, forward first, within the drive use of
/// [`HUMAN_DRIVE_USE`]) that does; when none does, [`playable_human_gait`]'s
/// (the comparison then reports the faults).
pub fn playable_human_gait_in_loop(
    case: &ClinicalCase,
    device: &DeviceConfig,
    dir: &Path,
) -> Result<HumanGait, BaselineError> {
    let first = playable_human_gait(case, dir)?;
    if lands_in_loop(case, device, &first) {
        return Ok(first);
    }
    let use_of = |g: &HumanGait| evaluate_phi(case, &g.phi).map_or(f64::INFINITY, |e| e.drive_use);
    let steps = (MAX_LEAN_RAD / LOOP_LEAN_STEP_RAD).round() as usize;
    for i in 1..=steps {
        for sign in [1.0, -1.0] {
            let lean = first.torso_lean_rad + sign * LOOP_LEAN_STEP_RAD * i as f64;
            if lean.abs() > MAX_LEAN_RAD + 1e-9 {
                continue;
            }
            let Ok(g) = human_gait(case, dir, lean) else {
                continue;
            };
            if use_of(&g) <= HUMAN_DRIVE_USE && lands_in_loop(case, device, &g) {
                return Ok(g);
            }
        }
    }
    Ok(first)
}

//! Baselines from human data (the paper's first experiment): a swing step
//! built from reference joint angles, evaluated with the same cost as the
//! optimised gait. The construction is documented step by step in
//! `docs/optimiser.md`; in short:
//!
//! 1. Swing phase: the reference leg from toe-off to its next heel strike;
//!    the stance leg is the same curve half a cycle earlier (symmetric gait).
//!    The phase is mapped linearly onto [0, ts] and sampled at t_k = kΔt.
//! 2. Angles → Φ: thigh inclinations (forward +) come from the data's thigh
//!    segment angle (Reznick) or hip flexion minus pelvic tilt (0 where the
//!    file has none); torso upright, φ3 = 0;
//!    φ2 = −thigh_stance, φ1 = φ2 + knee_stance (the stance shank from the
//!    thigh and knee, so no foot is needed), φ4 = π − thigh_swing,
//!    φ5 = φ4 + knee_swing (signs of `kinematics::anatomical_angles`).
//! 3. Amplitude: each of the four curves is scaled about its mean over the
//!    phase by one factor s, found by bisection so that the swing ankle's
//!    forward travel (FK, before end correction) equals the case's.
//! 4. Ends: a minimum-norm correction of (φ2, φ4, φ5) at t = 0 and at
//!    t = ts (Gauss–Newton on FK) puts the swing ankle exactly on the case's
//!    start and landing points; the correction is blended linearly in time
//!    between the two ends.
//!
//! The Φ sequence is then evaluated by [`crate::phi_cost::cost_from_phi`]
//! with no IK, so the paper IK's 45° cap on stance-knee flexion
//! (φ2 ≥ φ1 − π/4) does not constrain the baseline, while it does
//! constrain the optimised gait.
//!
//! Reading the data files (step 1's input) is in `data.rs`.

use std::path::{Path, PathBuf};

use gait_core::kinematics::{Phi, forward_kinematics};
use gait_core::problem::{Cost, PaperCase, PaperProblem};
use serde::{Deserialize, Serialize};

use crate::phi_cost::{PhiCostError, cost_from_phi};

mod data;

use data::load;

/// A reference data set usable as a baseline.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// Fukuchi et al. 2018 treadmill walking mean (primary for walking).
    Fukuchi2018Walk,
    /// Winter 2009 Table A.4, one stride (hip relative to the trunk).
    WinterWalk,
    /// Vicon Plug-in-Gait normal data (with pelvic tilt).
    ViconWalk,
    /// Reznick et al. 2021 stair ascent mean at 20° (primary for stairs).
    ReznickStairI20,
    /// Riener et al. 2002 stair ascent (digitised).
    RienerStairAscent,
    /// Reznick et al. 2021 stair descent mean at 20° (primary for descent).
    ReznickStairD20,
}

impl Source {
    /// Every source a paper case's baseline can be built from, with that
    /// case (stair descent is not a paper case): the list the baseline
    /// examples and tests go through.
    pub const PAPER_BASELINES: [(PaperCase, Self); 5] = [
        (PaperCase::Walk, Self::Fukuchi2018Walk),
        (PaperCase::Walk, Self::WinterWalk),
        (PaperCase::Walk, Self::ViconWalk),
        (PaperCase::StairUp, Self::ReznickStairI20),
        (PaperCase::StairUp, Self::RienerStairAscent),
    ];

    /// The primary source for a case.
    pub fn primary(case: PaperCase) -> Self {
        match case {
            PaperCase::Walk => Self::Fukuchi2018Walk,
            PaperCase::StairUp => Self::ReznickStairI20,
        }
    }

    /// A one-line description with the file and events used.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Fukuchi2018Walk => {
                "walk_fukuchi2018/fukuchi2018_walk_mean_sd_2pct.csv (Fukuchi et al. 2018, CC BY 4.0): \
                 mean curves, heel strike 0 %, toe-off 62 %, pelvis taken upright"
            }
            Self::WinterWalk => {
                "walk_winter/winter_walk_right_HS_to_HS.csv (Winter 2009, Table A.4): heel strike 0 %, \
                 toe-off 60.9 %, hip relative to the trunk"
            }
            Self::ViconWalk => {
                "walk_vicon_gaitutils/vicon_normal_sagittal_2pct.csv (Vicon normal data): heel strike 0 %, \
                 toe-off 65.48 %, thigh = hip flexion − pelvic tilt"
            }
            Self::ReznickStairI20 => {
                "stair_reznick_cortino/reznick_stair_ascent_mean_150pt.csv, 20° columns (Reznick et al. 2021): \
                 thigh segment angle; file origin shifted: heel strike at 5 % of the file, toe-off 63 % later"
            }
            Self::RienerStairAscent => {
                "stair_riener_cortino/riener_stair_ascent_1000pt.csv (Riener et al. 2002, digitised): \
                 heel strike 0 %, toe-off 63 %, pelvis taken upright"
            }
            Self::ReznickStairD20 => {
                "stair_reznick_cortino/reznick_stair_descent_mean_150pt.csv, 20° columns (Reznick et al. 2021): \
                 thigh segment angle; file origin shifted: foot contact at 24 % of the file (just after \
                 the knee's minimum, SOURCES.md), toe-off 62 % later"
            }
        }
    }

    /// The primary source for a gait table's movement.
    pub fn for_gait(kind: gait_core::tables::GaitKind) -> Self {
        match kind {
            gait_core::tables::GaitKind::Walk => Self::Fukuchi2018Walk,
            gait_core::tables::GaitKind::StairUp => Self::ReznickStairI20,
            gait_core::tables::GaitKind::StairDown => Self::ReznickStairD20,
        }
    }
}

/// A baseline swing step: Φ samples and their cost.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Baseline {
    /// Which data set.
    pub source: Source,
    /// Description of the file and events used.
    pub source_detail: String,
    /// Amplitude factor s of step 3.
    pub amplitude_scale: f64,
    /// End corrections of (φ2, φ4, φ5) at t = 0 and t = ts, rad.
    pub end_correction_rad: [[f64; 3]; 2],
    /// Φ(t_k), k = 0…N, rad.
    pub phi: Vec<Phi<f64>>,
    /// J and its parts (not serialised: rebuild with `cost_from_phi`).
    #[serde(skip)]
    pub cost: Option<Cost<f64>>,
}

/// Why a baseline could not be built.
#[derive(Debug)]
pub enum BaselineError {
    /// The data file could not be read.
    Io(PathBuf, std::io::Error),
    /// The data file is not what we expect (message says what).
    Format(PathBuf, String),
    /// The data set is not for this case.
    WrongCase(Source, PaperCase),
    /// No amplitude factor or end correction reaches the case's points.
    Unreachable(String),
    /// Evaluating the Φ sequence failed.
    Cost(PhiCostError),
}

impl std::fmt::Display for BaselineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Io(p, e) => write!(f, "{}: {e}", p.display()),
            Self::Format(p, m) => write!(f, "{}: {m}", p.display()),
            Self::WrongCase(s, c) => write!(f, "{s:?} is not a data set for {c:?}"),
            Self::Unreachable(m) => write!(f, "baseline construction failed: {m}"),
            Self::Cost(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for BaselineError {}

/// The folder of the shared gait data: `$EXOGAIT_GAIT_DATA` if set, else
/// `shared/data/gait` beside the repository.
pub fn default_data_dir() -> PathBuf {
    if let Some(d) = std::env::var_os("EXOGAIT_GAIT_DATA") {
        return PathBuf::from(d);
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/gait")
}

/// Step 2 of the module doc: (thigh_st, knee_st, thigh_sw, knee_sw) in
/// radians → Φ with the torso upright.
fn phi_from_angles(a: [f64; 4]) -> Phi<f64> {
    let [thigh_st, knee_st, thigh_sw, knee_sw] = a;
    let phi2 = -thigh_st;
    let phi1 = phi2 + knee_st;
    let phi4 = std::f64::consts::PI - thigh_sw;
    [phi1, phi2, 0.0, phi4, phi4 + knee_sw]
}

/// The swing ankle of Φ in the stance foot's flat frame: FK, shifted by the
/// stance ankle's roll onto its toe when the problem has a foot.
fn swing_ankle(problem: &PaperProblem<f64>, phi: &Phi<f64>) -> [f64; 2] {
    match &problem.case.foot {
        Some(f) => gait_core::playback::swing_ankle(&problem.model, f, phi),
        None => forward_kinematics(&problem.model, phi)[4],
    }
}

/// Where the swing ankle of Φ must be for its foot to stand at the flat
/// position `target`: `target` itself, or, for a trailing foot whose shank
/// leans past the ankle's stop (a descent, the problem having a foot),
/// raised onto its toe as the toe rocker puts it.
fn standing_ankle(problem: &PaperProblem<f64>, phi: &Phi<f64>, target: [f64; 2]) -> [f64; 2] {
    match &problem.case.foot {
        Some(f) => {
            let lean = gait_core::kinematics::wrap_pi(phi[4] - std::f64::consts::PI);
            let a = f.ankle(lean).position_m;
            [target[0] + a[0], target[1] + a[1]]
        }
        None => target,
    }
}

/// Puts the first and last samples' swing ankle on the case's start and
/// landing points (the feet standing there) by the least change of
/// (φ_`stance_link`, φ4, φ5) at each end (`stance_link` 1: the stance
/// thigh, 0: the stance shank), blended linearly in time between them;
/// returns the two end changes.
fn correct_ends(
    problem: &PaperProblem<f64>,
    phi: &mut [Phi<f64>],
    stance_link: usize,
) -> Result<[[f64; 3]; 2], BaselineError> {
    let (Some(&first), Some(&last)) = (phi.first(), phi.last()) else {
        return Err(BaselineError::Unreachable("no samples".into()));
    };
    let d0 = end_correction(problem, &first, problem.case.start_m, stance_link)
        .ok_or_else(|| BaselineError::Unreachable("start point out of reach".into()))?;
    let d1 = end_correction(problem, &last, problem.case.landing_m, stance_link)
        .ok_or_else(|| BaselineError::Unreachable("landing point out of reach".into()))?;
    let n = phi.len().saturating_sub(1).max(1);
    for (k, p) in phi.iter_mut().enumerate() {
        let w = k as f64 / n as f64;
        for (j, &i) in [stance_link, 3, 4].iter().enumerate() {
            if let (Some(v), Some(a), Some(b)) = (p.get_mut(i), d0.get(j), d1.get(j)) {
                *v += (1.0 - w) * a + w * b;
            }
        }
    }
    Ok([d0, d1])
}

/// Minimum-norm change of (φ2, φ4, φ5) that puts the swing ankle on
/// `target` (Gauss–Newton with the 2×3 Jacobian's pseudo-inverse); with a
/// foot, the target follows the trailing foot's roll onto its toe.
fn end_correction(
    problem: &PaperProblem<f64>,
    phi: &Phi<f64>,
    target: [f64; 2],
    stance_link: usize,
) -> Option<[f64; 3]> {
    let lengths = problem.model.lengths();
    let [.., l4, l5] = lengths;
    let ls = lengths.get(stance_link).copied().unwrap_or(0.0);
    let mut q = *phi;
    for _ in 0..80 {
        let p5 = swing_ankle(problem, &q);
        let goal = standing_ankle(problem, &q, target);
        let e = [goal[0] - p5[0], goal[1] - p5[1]];
        if e[0].hypot(e[1]) < 1e-11 {
            let ds = q.get(stance_link).copied().unwrap_or(0.0)
                - phi.get(stance_link).copied().unwrap_or(0.0);
            return Some([ds, q[3] - phi[3], q[4] - phi[4]]);
        }
        // ∂p5/∂φ for p = l (sin φ, cos φ): l (cos φ, −sin φ).
        let cols = [(stance_link, ls), (3, l4), (4, l5)].map(|(i, l)| {
            let a = q.get(i).copied().unwrap_or(0.0);
            [l * a.cos(), -l * a.sin()]
        });
        // J Jᵀ (2×2) and its inverse.
        let mut m = [[0.0; 2]; 2];
        for c in &cols {
            m[0][0] += c[0] * c[0];
            m[0][1] += c[0] * c[1];
            m[1][1] += c[1] * c[1];
        }
        m[1][0] = m[0][1];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        if det.abs() < 1e-12 {
            return None;
        }
        let y = [
            (m[1][1] * e[0] - m[0][1] * e[1]) / det,
            (-m[1][0] * e[0] + m[0][0] * e[1]) / det,
        ];
        for (i, c) in [stance_link, 3, 4].iter().zip(&cols) {
            if let Some(v) = q.get_mut(*i) {
                *v += c[0] * y[0] + c[1] * y[1];
            }
        }
    }
    None
}

/// Builds the baseline of `case` from `source` in `dir` (see the module
/// documentation) and evaluates it.
pub fn baseline_from(
    case: PaperCase,
    source: Source,
    dir: &Path,
) -> Result<Baseline, BaselineError> {
    let is_walk = matches!(
        source,
        Source::Fukuchi2018Walk | Source::WinterWalk | Source::ViconWalk
    );
    if is_walk != (case == PaperCase::Walk) {
        return Err(BaselineError::WrongCase(source, case));
    }
    baseline_for_problem(&PaperProblem::<f64>::paper(case), source, dir)
}

/// The baseline from `source` in `dir` at `problem`'s geometry, step time
/// and model (same construction as [`baseline_from`], which is this with
/// paper mode). The caller picks a source that fits the step (walking data
/// for a level step, ascent data for a rising one); a geometry the data
/// cannot be scaled or corrected to gives [`BaselineError::Unreachable`].
pub fn baseline_for_problem(
    problem: &PaperProblem<f64>,
    source: Source,
    dir: &Path,
) -> Result<Baseline, BaselineError> {
    baseline_window(problem, source, dir, Correction::StanceThighAndSwingLeg)
}

/// How the end corrections share the change between the joints.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Correction {
    /// The least change of (φ2, φ4, φ5) (the paper-mode baseline).
    StanceThighAndSwingLeg,
    /// The least change of (φ1, φ4, φ5): the stance shank instead of the
    /// stance thigh (the comparison's human gait). Reaching further with
    /// the thigh straightens the stance knee — the walk's landing
    /// correction bent it 5.4° past its stop —, with the shank it bends it.
    StanceShankAndSwingLeg,
}

/// The baseline of `source` at `problem`'s geometry with the end
/// corrections on `correction`'s joints (see [`baseline_for_problem`] for
/// the construction).
pub fn baseline_window(
    problem: &PaperProblem<f64>,
    source: Source,
    dir: &Path,
    correction: Correction,
) -> Result<Baseline, BaselineError> {
    let curves = load(source, dir)?;
    let problem = *problem;
    let n = problem.sampling.intervals;
    let ts = problem.case.step_time_s;
    let dt = problem.sampling.dt_s;
    let to = curves.toe_off_pct;
    let (sw_start, sw_len) = (to, 100.0 - (to - curves.heel_strike_pct));
    // Raw angles at each sample, radians: [thigh_st, knee_st, thigh_sw, knee_sw].
    let raw: Vec<[f64; 4]> = (0..=n)
        .map(|k| {
            let frac = (k as f64 * dt / ts).min(1.0);
            let sw = sw_start + sw_len * frac;
            let st = sw - 50.0;
            [
                curves.thigh.at(st),
                curves.knee.at(st),
                curves.thigh.at(sw),
                curves.knee.at(sw),
            ]
            .map(f64::to_radians)
        })
        .collect();
    let mut mean = [0.0; 4];
    for r in &raw {
        for (m, v) in mean.iter_mut().zip(r) {
            *m += v / raw.len() as f64;
        }
    }
    let scaled = |s: f64| -> Vec<Phi<f64>> {
        raw.iter()
            .map(|r| {
                let mut a = [0.0; 4];
                for ((o, &v), &m) in a.iter_mut().zip(r).zip(&mean) {
                    *o = m + s * (v - m);
                }
                phi_from_angles(a)
            })
            .collect()
    };
    let travel = |phi: &[Phi<f64>]| -> f64 {
        match (phi.first(), phi.last()) {
            (Some(a), Some(b)) => swing_ankle(&problem, b)[0] - swing_ankle(&problem, a)[0],
            _ => 0.0,
        }
    };
    let want = problem.case.landing_m[0] - problem.case.start_m[0];
    let (mut lo, mut hi) = (0.05, 4.0);
    if (travel(&scaled(lo)) - want) * (travel(&scaled(hi)) - want) > 0.0 {
        return Err(BaselineError::Unreachable(format!(
            "no amplitude factor in [{lo}, {hi}] gives a swing travel of {want} m"
        )));
    }
    let increasing = travel(&scaled(hi)) > travel(&scaled(lo));
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if (travel(&scaled(mid)) < want) == increasing {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let s = 0.5 * (lo + hi);
    let mut phi = scaled(s);
    let stance_link = match correction {
        Correction::StanceThighAndSwingLeg => 1,
        Correction::StanceShankAndSwingLeg => 0,
    };
    let [d0, d1] = correct_ends(&problem, &mut phi, stance_link)?;
    let cost = cost_from_phi(&problem, &phi).map_err(BaselineError::Cost)?;
    Ok(Baseline {
        source,
        source_detail: source.describe().to_string(),
        amplitude_scale: s,
        end_correction_rad: [d0, d1],
        phi,
        cost: Some(cost),
    })
}

/// The baseline of `case` from its primary source in [`default_data_dir`].
pub fn baseline(case: PaperCase) -> Result<Baseline, BaselineError> {
    baseline_from(case, Source::primary(case), &default_data_dir())
}

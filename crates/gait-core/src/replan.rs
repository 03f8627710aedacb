//! The step re-planner: adapts the step about to be played to the stance
//! ankle the pilot actually has at its start, in bounded work, no heap.
//!
//! A table's stance shank path φ1(t) is the plan's assumption about the
//! pilot's ankle. When the measured φ1 at the step's start departs from the
//! table's by δ (the pilot leans a few degrees forward or back), playing
//! the table as it is rotates the whole chain by δ about the stance ankle
//! and the swing foot lands off its foothold (about 16 mm for 3° on a
//! 0.3 m step). The re-planner instead plans a posture sequence that starts
//! where the pilot stands and lands where the table lands.
//!
//! # Design
//!
//! - **Warm start from the table.** Each re-planned sample is the table's
//!   sample with corrections that fade by t_f, a fraction of the step time
//!   well before the landing (`replan/curves.rs`):
//!   - stance shank: φ1' = φ1 + δ·w(t/t_f) + ω_e·t_f·g(t/t_f), w a
//!     degree-5 Bézier [1, 1, w2, w3, p, p] from the measured angle to the
//!     share p of δ the pilot is expected to keep to the landing
//!     ([`Measured::persist`]), g a fixed curve of slope 1 at the start
//!     that brings the plan's initial rate to the measured one (ω_e:
//!     measured rate less the table's);
//!   - torso: φ3' = φ3 + δ3·u(t/t_f), u = [1, 1, u2, u3, 0, 0], δ3 the
//!     start posture's torso less the table's: it starts where it is and
//!     returns to the table's;
//!   - knee choice: r2' = r2 + δ·ρ·b(t/t_f), b a bump [0, 0, 1, 1, 0, 0].
//!
//!   The swing ankle is kept on the table's path in the stance foot's flat
//!   frame ([`crate::playback::swing_ankle`]) through the IK, shifted at
//!   the start to where the start posture ([`Measured::posture`], the
//!   measured joints; else the table's first posture turned by δ) has it,
//!   the shift fading with u. So the first sample is the posture the body
//!   is in, and the swing lands on the planned foothold; from t_f on, the
//!   samples are the table's with p·δ on the stance shank (the table's own
//!   when p = 0). The decision variables are the six numbers (t_f/ts, w2,
//!   w3, u2, u3, ρ); every correction is proportional to the start's
//!   offsets, so with the pilot on the plan every candidate is the table.
//! - **Cost and constraints of the clinical mode** (`replan/cost.rs`): gait-core's
//!   playback of the samples ([`crate::playback::for_each_sample`]) gives
//!   the predicted balance impulse Σ|τ_pilot|Δt/lever plus the clinical
//!   mode's quadratic penalties (drive torque over its share, joint speed
//!   and acceleration, hip and knee range inside a margin, clearance band, sole
//!   over the ground, the last centimetre straight down, weight on the
//!   trailing foot at the start), with the same weights; hard rejects for
//!   a hip or knee torque above what the drive can give at its speed, an
//!   angle outside the envelope, an IK without a posture, and a landing
//!   more than [`LANDING_TOLERANCE_M`] off the table's. Two terms differ:
//!   - the "last centimetre straight down" counts only samples where the
//!     foot comes down (gait-opt's also counts an ascent's rise to the
//!     upper tread, some 0.4 m from the landing, which no candidate can
//!     change);
//!   - the stance ankle has its stop as a hard limit but no soft margin.
//!     The ankle has no drive, so its angle is the pilot's. With the
//!     margin, a pilot leaning back 2° on the walk stood inside it, and
//!     the search bought the margin back by planning φ1 forward, where the
//!     pilot did not go: the landings were right, but the crutch load
//!     rose by a third in the closed loop.
//! - **Baseline** (`table_cost`): the table played from the measured start,
//!   as the device does without re-planning: every sample rotated by δ. Its
//!   cost is the same sum plus the landing penalty
//!   W·max(0, e − [`LANDING_TOLERANCE_M`])² on its landing error e (the
//!   clinical mode's clearance weight; a clinical table lands by
//!   construction). Its balance impulse alone is reported too
//!   ([`Outcome::Replanned`]), so the comparison can be read without it.
//! - **Search** (`replan/search.rs`): a compass (coordinate pattern) search within
//!   bounds, at most [`MAX_EVALS`] evaluations. Why not Nelder–Mead or a
//!   gradient method: the cost is non-smooth (IK branch switches, penalty
//!   kinks, early rejects give +∞), a simplex in six dimensions spends
//!   seven evaluations before its first move, and compass search needs
//!   no storage beyond the current point and one step per variable, is
//!   deterministic, and resumes between any two evaluations.
//! - **Bounded and resumable**: [`Replanner::step`] does at most the
//!   number of evaluations it is given (each one IK pass and one playback
//!   over the table's samples) and returns; the board calls it in the idle
//!   time of its tick and plays the table if it has not finished in time.
//!
//! - **Aim** ([`ReplanSetup::aim_m`]): the candidates' swing ankle
//!   follows the table's path shifted by the aim's x (faded in over the
//!   step) and, in its last centimetre above the landing, pressed down to
//!   the aim's y. The reason is the closed loop, which the open-loop cost
//!   does not see: aimed exactly at the floor at the table's end, a
//!   re-planned foot met it 0.13–0.16 s late (the joints lag, the
//!   pilot's shank leans on) and the ground search held the body on one
//!   foot meanwhile, at some 13 % more crutch load than the table played
//!   turned; touching down sooner lands long by an offset the step's
//!   movement sets (about 8 mm on the walk and the ascent), which the aim's
//!   x takes back (`docs/replanning.md`).
//!
//! The transfer after the landing is not counted: every candidate lands on
//! the table's foothold with the same stance shank (the table's, less p·δ),
//! so it adds nearly the same to each. Nor is the drives' I²t
//! over two steps: a fade of a few degrees changes it little, and the
//! device's I²t monitor guards it.

mod cost;
mod curves;
mod search;

pub use search::Replanner;

use crate::BodyModel;
use crate::foot::StanceFoot;
use crate::scalar::Real;

/// Evaluations a re-plan may use at most (each an IK pass over the fade
/// and a playback over the table: about 0.9 M instructions on the M4F for
/// a 225–229-sample table, estimated from host time; 48 make some 45 M, a
/// quarter of a second at 168 MHz).
pub const MAX_EVALS: u16 = 48;
/// Largest landing aim ([`ReplanSetup::aim_m`]) either way, m.
pub const MAX_AIM_M: f64 = 0.03;
/// The re-planned landing may be this far from the one aimed at, m.
pub const LANDING_TOLERANCE_M: f64 = 0.001;
/// A measured start this close to the table's, with a rate this close,
/// is on the plan: the table is played as it is (rad, rad/s).
pub const ON_PLAN_RAD: f64 = 1.0e-3;
/// See [`ON_PLAN_RAD`], rad/s.
pub const ON_PLAN_RAD_S: f64 = 0.01;
/// Largest start offset the re-planner takes, rad (10°): beyond it the
/// pilot is not standing in the step's start posture at all.
pub const MAX_OFFSET_RAD: f64 = 0.174_532_925;
/// The rate mismatch the plan matches at most, rad/s (a larger measured
/// rate is taken at this magnitude: the shank is still settling).
pub const MAX_RATE_ERROR_RAD_S: f64 = 0.5;

/// The stance ankle as measured at the step's start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Measured<T> {
    /// Stance shank φ1, rad.
    pub phi1_rad: T,
    /// Its rate, rad/s.
    pub rate_rad_s: T,
    /// Share (0 … 1) of the offset from the table the pilot is expected
    /// to keep through the step: 0, a pilot who returns to the plan's
    /// stance shank within the fade; 1, a pilot who leans as they stand
    /// all the way to the landing (the plan then keeps the offset and the
    /// joints carry the swing foot to the foothold around it).
    pub persist: T,
    /// The posture the step starts from, Φ (rad; φ1 is taken from
    /// `phi1_rad`): the measured joints. `None`: the table's first posture
    /// with every link turned by the offset.
    pub posture: Option<[T; 5]>,
}

/// The body and the step's geometry the table was made for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplanSetup<'a, T> {
    /// Pilot plus exoskeleton.
    pub model: &'a BodyModel<T>,
    /// The stance foot's toe rocker.
    pub foot: StanceFoot<T>,
    /// The exoskeleton ankle's passive spring, N·m/rad.
    pub spring_nm_per_rad: T,
    /// The front ankle relative to the back one in double support (tread
    /// or step length, rise), m: where the ground is under the swing foot.
    pub spacing_m: [T; 2],
    /// The pilot's crutch lever, m (turns ankle torque into crutch force;
    /// scales the cost only).
    pub crutch_lever_m: T,
    /// Where the re-planned swing lands, relative to the table's foothold
    /// (m): x along the step, y up. A y below zero takes the approach's
    /// last centimetre that far under the floor, so that the foot meets
    /// the floor by the table's end although the joints lag; x then moves
    /// the foothold aimed at by the offset that earlier touch-down lands
    /// with (module documentation). At most [`MAX_AIM_M`] either way.
    pub aim_m: [T; 2],
}

/// The hip and knee drive's torque at the joint: the peak up to a speed,
/// then falling linearly to nothing at the no-load speed while driving
/// (the supply cannot push the current against the back-EMF); braking,
/// the peak.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveLimit<T> {
    /// Peak joint torque, N·m.
    pub peak_nm: T,
    /// Joint speed up to which the peak is available, rad/s.
    pub full_torque_speed_rad_s: T,
    /// Joint speed at which nothing is left while driving, rad/s.
    pub no_load_speed_rad_s: T,
}

impl<T: Real> DriveLimit<T> {
    /// The largest |torque| the drive gives at `rate_rad_s` in the
    /// direction of `torque_nm`, N·m.
    pub fn available_nm(&self, rate_rad_s: T, torque_nm: T) -> T {
        let w = rate_rad_s.abs();
        let driving = rate_rad_s * torque_nm > T::zero();
        if !driving || w <= self.full_torque_speed_rad_s {
            return self.peak_nm;
        }
        let span = self.no_load_speed_rad_s - self.full_torque_speed_rad_s;
        if w >= self.no_load_speed_rad_s || span <= T::zero() {
            return T::zero();
        }
        self.peak_nm * (self.no_load_speed_rad_s - w) / span
    }
}

/// What the device allows: hard limits (a candidate beyond them is
/// refused) and the clinical mode's soft ones (penalised).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReplanLimits<T> {
    /// Every hip and knee drive.
    pub drive: DriveLimit<T>,
    /// Share of the available torque the plan may use before it is
    /// penalised (the rest is for the position loop).
    pub torque_share: T,
    /// Anatomical hip angle envelope (extension negative), rad.
    pub hip_rad: [T; 2],
    /// Anatomical knee angle envelope, rad.
    pub knee_rad: [T; 2],
    /// Lowest stance-ankle dorsiflexion φ1 (leaning back), rad.
    pub ankle_min_rad: T,
    /// How far inside the envelope the penalty starts, rad.
    pub range_margin_rad: T,
    /// Hip and knee speed above which the penalty grows, rad/s.
    pub joint_speed_rad_s: T,
    /// Hip and knee acceleration above which the penalty grows, rad/s².
    pub joint_accel_rad_s2: T,
    /// Swing-foot clearance band over the floor or the nosing, m.
    pub clearance_m: [T; 2],
    /// Largest share of the weight the trailing foot may carry at the start.
    pub start_trailing_share: T,
}

impl<T: Real> ReplanLimits<T> {
    /// The clinical mode's soft limits (gait-opt's `ClinicalCase`) with the
    /// device's `drive` and envelope.
    pub fn clinical(
        drive: DriveLimit<T>,
        hip_rad: [T; 2],
        knee_rad: [T; 2],
        ankle_min_rad: T,
    ) -> Self {
        Self {
            drive,
            torque_share: T::lit(0.75),
            hip_rad,
            knee_rad,
            ankle_min_rad,
            range_margin_rad: T::lit(5f64.to_radians()),
            joint_speed_rad_s: T::lit(1.8),
            joint_accel_rad_s2: T::lit(20.0),
            clearance_m: [T::lit(0.04), T::lit(0.07)],
            start_trailing_share: T::lit(0.8),
        }
    }

    /// `true` when every value is finite, every range ordered, and the
    /// drive's speeds and peak positive.
    fn valid(&self) -> bool {
        let d = &self.drive;
        let all = [
            d.peak_nm,
            d.full_torque_speed_rad_s,
            d.no_load_speed_rad_s,
            self.torque_share,
            self.hip_rad[0],
            self.hip_rad[1],
            self.knee_rad[0],
            self.knee_rad[1],
            self.ankle_min_rad,
            self.range_margin_rad,
            self.joint_speed_rad_s,
            self.joint_accel_rad_s2,
            self.clearance_m[0],
            self.clearance_m[1],
            self.start_trailing_share,
        ];
        all.iter().all(|v| v.finite())
            && d.peak_nm > T::zero()
            && d.full_torque_speed_rad_s > T::zero()
            && d.no_load_speed_rad_s >= d.full_torque_speed_rad_s
            && self.torque_share > T::zero()
            && self.hip_rad[0] < self.hip_rad[1]
            && self.knee_rad[0] < self.knee_rad[1]
            && self.range_margin_rad >= T::zero()
            && self.clearance_m[0] <= self.clearance_m[1]
    }
}

/// Why a re-plan cannot be set up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReplanError {
    /// The output buffer's length is not the table's.
    BufferLength,
    /// The measured angle or rate is not finite.
    BadMeasurement,
    /// The measured angle is more than [`MAX_OFFSET_RAD`] off the table's.
    OffsetTooLarge,
    /// A limit is not finite or a range is empty ([`ReplanLimits`]).
    BadLimits,
    /// The setup's lever, spring or spacing is not finite, or the lever
    /// not positive.
    BadSetup,
    /// The evaluation budget is 0 or above [`MAX_EVALS`].
    BadBudget,
}

impl core::fmt::Display for ReplanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::BufferLength => "the output buffer must have the table's length",
            Self::BadMeasurement => "the measured ankle angle or rate is not finite",
            Self::OffsetTooLarge => "the measured ankle is more than 10 degrees off the table",
            Self::BadLimits => "a limit is not finite or a range is empty",
            Self::BadSetup => "the lever, spring or spacing is unusable",
            Self::BadBudget => "the evaluation budget must be in 1 ..= MAX_EVALS",
        })
    }
}

/// Which hard limit a candidate (or the baseline) breaks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Violation {
    /// The IK has no posture at this sample.
    Ik(u16),
    /// A sample could not be played (not finite).
    Playback(u16),
    /// A hip or knee (0 stance knee … 3 swing knee) needs more torque than
    /// the drive gives at its speed, at this sample.
    DriveTorque {
        /// Sample index.
        k: u16,
        /// Joint role, 0 … 3.
        joint: u8,
    },
    /// A hip or knee leaves the envelope at this sample.
    JointRange {
        /// Sample index.
        k: u16,
        /// Joint role, 0 … 3.
        joint: u8,
    },
    /// The stance ankle leans back past its stop at this sample.
    AnkleRange(u16),
    /// The swing foot lands more than [`LANDING_TOLERANCE_M`] off.
    Landing,
}

/// Why the table is to be played as it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fallback {
    /// The pilot stands on the plan ([`ON_PLAN_RAD`], [`ON_PLAN_RAD_S`]).
    OnPlan,
    /// No candidate costs less than the baseline.
    NoImprovement,
    /// Every candidate broke a hard limit (the best one's).
    Infeasible(Violation),
}

/// The re-planner's answer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outcome<T> {
    /// The buffer holds the re-planned samples.
    Replanned {
        /// Their cost (balance impulse plus penalties), N·s.
        cost: T,
        /// Their predicted balance impulse alone, N·s.
        balance_ns: T,
        /// The baseline's cost, N·s.
        table_cost: T,
        /// The baseline's balance impulse alone, N·s.
        table_balance_ns: T,
        /// Evaluations used (the baseline's included).
        evals: u16,
    },
    /// The buffer holds the table's samples, unchanged.
    UseTable(Fallback),
}

/// Where a re-plan stands after [`Replanner::step`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress<T> {
    /// More evaluations to do; those used so far.
    Running {
        /// Evaluations used so far.
        evals: u16,
    },
    /// Finished: the buffer is ready to play.
    Done(Outcome<T>),
}

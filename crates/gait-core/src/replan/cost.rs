//! The cost of a sample sequence, as gait-opt's clinical mode scores a
//! table (`crates/gait-opt/src/clinical/evaluate.rs`): the predicted
//! balance impulse Σ|τ_pilot|Δt/lever from gait-core's playback plus the
//! same quadratic penalties with the same weights, and the hard limits
//! the re-planner adds (module documentation of [`super`]).

use crate::clinical::{HEEL_M, ground_level, riser_behind_stance_x};
use crate::kinematics::{Phi, anatomical_angles, theta_from_phi};
use crate::model::{GRAVITY_M_S2, LINKS};
use crate::playback::{self, PlaybackError, PlaybackSample, swing_ankle};
use crate::scalar::Real;

use super::{LANDING_TOLERANCE_M, ReplanLimits, ReplanSetup, Violation};

/// Weights of a squared excess, N·s per unit² (gait-opt's clinical mode).
const W_TORQUE: f64 = 50.0 * 100.0; // per (share of the drive over the allowed)² per sample
const W_SPEED: f64 = 200.0; // per (rad/s)² per sample
const W_ACCEL: f64 = 0.5; // per (rad/s²)² per sample
const W_RANGE: f64 = 2.0e4; // per rad² per sample
const W_CLEARANCE: f64 = 1.0e6; // per m²
const W_START: f64 = 5.0e3; // per (share)²
/// Below this height above the landing point, m …
const LANDING_HEIGHT_M: f64 = 0.01;
/// … the swing ankle is at most this far from it horizontally, m.
const LANDING_TRAVEL_M: f64 = 0.01;
/// The lowest the sole may come over the ground in the air, m (negative:
/// allowed to pass this close below it, as the clinical mode's term).
const SOLE_MARGIN_M: f64 = -0.005;
/// Edges a sole can span (a foot is shorter than two treads).
const MAX_EDGES: usize = 4;

/// Penalty parts: drive torque, speed, acceleration, range, clearance,
/// start share, landing.
const PARTS: usize = 7;
const TORQUE: usize = 0;
const SPEED: usize = 1;
const ACCEL: usize = 2;
const RANGE: usize = 3;
const CLEARANCE: usize = 4;
const START: usize = 5;
const LANDING: usize = 6;

/// What a sample sequence costs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Evaluation<T> {
    /// Balance impulse plus penalties, N·s.
    pub cost: T,
    /// Balance impulse alone, N·s.
    pub balance_ns: T,
    /// The first hard limit broken, if any.
    pub violation: Option<Violation>,
}

/// Why the playback stopped early (the first hard limit, for a candidate).
enum Stop {
    Playback(PlaybackError),
    Hard(Violation),
}

impl From<PlaybackError> for Stop {
    fn from(e: PlaybackError) -> Self {
        Self::Playback(e)
    }
}

/// Scores `len` samples (`sample(k)`) played at `period_s`, landing at
/// `landing_m` against the planned `planned_m` (both in the stance foot's
/// frame). `stop_early`: give up at the first hard limit (a candidate);
/// otherwise score to the end and report the first (the baseline).
/// Bounded: one playback over the samples.
pub(super) fn evaluate<T: Real>(
    setup: &ReplanSetup<'_, T>,
    limits: &ReplanLimits<T>,
    period_s: T,
    len: usize,
    sample: impl Fn(usize) -> Option<Phi<T>>,
    planned_m: [T; 2],
    stop_early: bool,
) -> Evaluation<T> {
    let infeasible = |v| Evaluation {
        cost: T::max_value().unwrap_or(T::one() / T::zero()),
        balance_ns: T::zero(),
        violation: Some(v),
    };
    let Some(last) = len.checked_sub(1).and_then(&sample) else {
        return infeasible(Violation::Playback(0));
    };
    let landing = swing_ankle(setup.model, &setup.foot, &last);
    let err = norm([landing[0] - planned_m[0], landing[1] - planned_m[1]]);
    let mut acc = Accumulator::new(setup, limits, period_s, len, landing);
    if err > T::lit(LANDING_TOLERANCE_M) {
        acc.first = Some(Violation::Landing);
        if stop_early {
            return infeasible(Violation::Landing);
        }
    }
    let run = playback::for_each_sample::<T, Stop>(
        setup.model,
        &setup.foot,
        setup.spring_nm_per_rad,
        len,
        period_s,
        &sample,
        |s| {
            acc.visit(s);
            match acc.first {
                Some(v) if stop_early => Err(Stop::Hard(v)),
                _ => Ok(()),
            }
        },
    );
    match run {
        Err(Stop::Hard(v)) => return infeasible(v),
        Err(Stop::Playback(PlaybackError::BadSample(k))) => {
            return infeasible(Violation::Playback(u16::try_from(k).unwrap_or(u16::MAX)));
        }
        Err(Stop::Playback(PlaybackError::TooShort)) => {
            return infeasible(Violation::Playback(0));
        }
        Ok(()) => {}
    }
    let excess = (err - T::lit(LANDING_TOLERANCE_M)).max(T::zero());
    let landing_penalty = T::lit(W_CLEARANCE) * excess * excess;
    acc.add(LANDING, landing_penalty);
    let parts = acc.finish();
    let penalty = parts.iter().fold(T::zero(), |a, &b| a + b);
    Evaluation {
        cost: acc.balance_ns + penalty,
        balance_ns: acc.balance_ns,
        violation: acc.first,
    }
}

fn norm<T: Real>([x, y]: [T; 2]) -> T {
    (x * x + y * y).sqrt()
}

/// (x − limit)² where x exceeds limit, else 0.
fn sq_excess<T: Real>(x: T, limit: T) -> T {
    let e = (x - limit).max(T::zero());
    e * e
}

/// The running sums of one playback.
struct Accumulator<'s, 'a, T: Real> {
    setup: &'s ReplanSetup<'a, T>,
    limits: &'s ReplanLimits<T>,
    period_s: T,
    len: usize,
    landing: [T; 2],
    weight_n: T,
    balance_ns: T,
    parts: [T; PARTS],
    first: Option<Violation>,
    lifted: bool,
    start_share: T,
    approach_m: T,
    last_y_m: Option<T>,
    sole_margin_m: T,
    peak_lift_m: T,
    crossing_m: Option<T>,
    nosing: Option<(T, T)>,
}

impl<'s, 'a, T: Real> Accumulator<'s, 'a, T> {
    fn new(
        setup: &'s ReplanSetup<'a, T>,
        limits: &'s ReplanLimits<T>,
        period_s: T,
        len: usize,
        landing: [T; 2],
    ) -> Self {
        Self {
            setup,
            limits,
            period_s,
            len,
            landing,
            weight_n: setup.model.total_mass_kg() * T::lit(GRAVITY_M_S2),
            balance_ns: T::zero(),
            parts: [T::zero(); PARTS],
            first: None,
            lifted: false,
            start_share: T::zero(),
            approach_m: T::zero(),
            last_y_m: None,
            sole_margin_m: T::max_value().unwrap_or(T::one() / T::zero()),
            peak_lift_m: T::min_value().unwrap_or(-T::one() / T::zero()),
            crossing_m: None,
            nosing: nosing_crossed(setup),
        }
    }

    fn hard(&mut self, v: Violation) {
        if self.first.is_none() {
            self.first = Some(v);
        }
    }

    fn visit(&mut self, s: &PlaybackSample<T>) {
        let l = self.limits;
        let at = u16::try_from(s.k).unwrap_or(u16::MAX);
        self.balance_ns += s.pilot_nm.abs() * self.period_s / self.setup.crutch_lever_m;
        if s.k == 0 {
            self.start_share = s.reaction_n[1] / self.weight_n;
        }
        let margin = l.range_margin_rad;
        let phi1 = s.phi[0];
        // The stance ankle has no drive: where it is, the pilot put it. Its
        // stop is a hard limit here, with no soft margin (the clinical
        // mode's margin keeps a designed plan off the stop; a re-plan that
        // buys that margin back steers φ1 where the pilot does not follow).
        if phi1 < l.ankle_min_rad {
            self.hard(Violation::AnkleRange(at));
        }
        let zero = theta_from_phi(&[T::zero(); LINKS]);
        let angles = anatomical_angles(&theta_from_phi(&s.phi));
        let rates = theta_from_phi(&s.dphi);
        let accels = theta_from_phi(&s.ddphi);
        // Roles 0 … 3: stance knee, stance hip, swing hip, swing knee.
        let ranges = [l.knee_rad, l.hip_rad, l.hip_rad, l.knee_rad];
        let is_knee = [true, false, false, true];
        for (j, (range, knee)) in ranges.iter().zip(is_knee).enumerate() {
            let i = j + 1;
            let (Some(&q), Some(&r), Some(&a), Some(&z), Some(&torque)) = (
                angles.get(i),
                rates.get(i),
                accels.get(i),
                zero.get(i),
                s.torques.get(i),
            ) else {
                continue;
            };
            let joint = u8::try_from(j).unwrap_or(u8::MAX);
            let (rate, accel) = (r - z, a - z);
            let available = l.drive.available_nm(rate, torque);
            let share = torque.abs() / available.max(T::lit(1e-6));
            self.add(TORQUE, T::lit(W_TORQUE) * sq_excess(share, l.torque_share));
            if share > T::one() {
                self.hard(Violation::DriveTorque { k: at, joint });
            }
            self.add(
                SPEED,
                T::lit(W_SPEED) * sq_excess(rate.abs(), l.joint_speed_rad_s),
            );
            self.add(
                ACCEL,
                T::lit(W_ACCEL) * sq_excess(accel.abs(), l.joint_accel_rad_s2),
            );
            let [lo, hi] = *range;
            // Soft: inside the envelope by the margin (a straight knee, at
            // the envelope's small hyperextension allowance, stays free).
            let soft_lo = if knee { lo.min(T::zero()) } else { lo + margin };
            let out = (soft_lo - q).max(q - (hi - margin)).max(T::zero());
            self.add(RANGE, T::lit(W_RANGE) * out * out);
            if q < lo || q > hi {
                self.hard(Violation::JointRange { k: at, joint });
            }
        }
        if s.other_share > T::zero() && !self.lifted {
            return;
        }
        self.lifted = true;
        if s.other_share <= T::zero() {
            self.clearance(s);
        }
    }

    /// The swing foot over what is under it (the clinical mode's terms).
    fn clearance(&mut self, s: &PlaybackSample<T>) {
        let [x, y] = s.swing_ankle_m;
        let setup = self.setup;
        // The last centimetre down is straight down. Only while the foot
        // comes down: gait-opt's term (any sample in the second half lower
        // than 1 cm over the landing) also counts an ascent's whole rise
        // to the upper tread, which is not an approach.
        let descending = self.last_y_m.is_some_and(|prev| y < prev);
        self.last_y_m = Some(y);
        if descending && y - self.landing[1] < T::lit(LANDING_HEIGHT_M) && s.k > self.len / 2 {
            self.approach_m = self.approach_m.max((x - self.landing[0]).abs());
        }
        let under = ground_under_sole(setup, x);
        self.sole_margin_m = self.sole_margin_m.min(y - under);
        self.peak_lift_m = self
            .peak_lift_m
            .max(y - ground_level(setup.spacing_m, &setup.foot, x));
        if let Some((nx, level)) = self.nosing {
            if x - T::lit(HEEL_M) <= nx && nx <= x + setup.foot.toe_m {
                let c = y - level;
                self.crossing_m = Some(self.crossing_m.map_or(c, |m| m.min(c)));
            }
        }
    }

    fn add(&mut self, part: usize, v: T) {
        if let Some(p) = self.parts.get_mut(part) {
            *p += v;
        }
    }

    /// The penalties, with those that need the whole step.
    fn finish(&mut self) -> [T; PARTS] {
        let l = self.limits;
        let w = T::lit(W_CLEARANCE);
        let mut pen = T::zero();
        if self.lifted {
            let c = match self.nosing {
                Some(_) => self.crossing_m.unwrap_or(-T::one()),
                None => self.peak_lift_m,
            };
            let [lo, hi] = l.clearance_m;
            let out = (lo - c).max(c - hi).max(T::zero());
            pen += w * out * out;
            pen += w * sq_excess(-self.sole_margin_m, T::lit(SOLE_MARGIN_M));
            pen += w * sq_excess(self.approach_m, T::lit(LANDING_TRAVEL_M));
        }
        self.add(CLEARANCE, pen);
        let start = T::lit(W_START) * sq_excess(self.start_share, l.start_trailing_share);
        self.add(START, start);
        self.parts
    }
}

/// The nosing the swing foot crosses on stairs, (x from the stance ankle,
/// its ground level), m; `None` on level ground.
fn nosing_crossed<T: Real>(setup: &ReplanSetup<'_, T>) -> Option<(T, T)> {
    let riser = riser_behind_stance_x(setup.spacing_m, &setup.foot)?;
    let [tread, rise] = setup.spacing_m;
    let level = if rise > T::zero() { rise } else { T::zero() };
    Some((riser + tread, level))
}

/// The highest ground under a sole whose ankle is at `x` (ankle-level
/// convention), m. Bounded: at most [`MAX_EDGES`] edges.
fn ground_under_sole<T: Real>(setup: &ReplanSetup<'_, T>, x: T) -> T {
    let f = |x: T| ground_level(setup.spacing_m, &setup.foot, x);
    let (a, b) = (x - T::lit(HEEL_M), x + setup.foot.toe_m);
    let mut m = f(a).max(f(b));
    if let Some(riser) = riser_behind_stance_x(setup.spacing_m, &setup.foot) {
        let tread = setup.spacing_m[0];
        let mut e = riser + tread * ((a - riser) / tread).ceil();
        for _ in 0..MAX_EDGES {
            if e > b {
                break;
            }
            m = m.max(f(e)).max(f(e - T::lit(1e-9)));
            e += tread;
        }
    }
    m
}

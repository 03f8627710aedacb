//! The candidates: the table's samples with the fading corrections of the
//! decision variables (the module documentation of [`super`] gives the
//! curves), solved by the IK with the swing ankle on the table's path.

use crate::bezier::Bezier;
use crate::foot::StanceFoot;
use crate::ik::{IkSolver, IkTarget};
use crate::kinematics::Phi;
use crate::model::{BodyModel, LINKS};
use crate::playback::swing_ankle;
use crate::scalar::Real;
use crate::tables::GaitTable;

use super::Violation;

/// Decision variables: fade end over the step time, the φ1 fade's two
/// interior values, the torso fade's two, the knee-choice bump per rad of
/// offset.
pub(super) const DIM: usize = 6;
/// The start point: a quintic smoothstep fade of φ1 and torso over half
/// the step, the table's knee choice.
pub(super) const INITIAL: [f64; DIM] = [0.5, 1.0, 0.0, 1.0, 0.0, 0.0];
/// Lower bounds. The fade ends no earlier than 15 % of the step (a faster
/// return asks the pilot's ankle for a jerk) …
pub(super) const LOWER: [f64; DIM] = [0.15, -0.5, -0.5, -1.0, -1.0, -4.0];
/// … and no later than 80 % (the landing stays the table's).
pub(super) const UPPER: [f64; DIM] = [0.8, 1.5, 1.5, 2.0, 2.0, 4.0];
/// The search's first step along each variable.
pub(super) const STEP: [f64; DIM] = [0.15, 0.5, 0.5, 0.5, 0.5, 2.0];

/// The height above the table's landing from which the approach is
/// pressed towards the aim's y, m.
const APPROACH_M: f64 = 0.01;

/// 3x² − 2x³ for x in [0, 1]: an eased move, at rest at both ends.
fn smoothstep<T: Real>(x: T) -> T {
    x * x * (T::lit(3.0) - T::lit(2.0) * x)
}

/// A degree-5 Bézier of s ∈ [0, 1] through these control values.
fn curve<T: Real>(values: [T; 6]) -> Bezier<T, 6> {
    let mut points = [[T::zero(); 2]; 6];
    for (j, (p, v)) in points.iter_mut().zip(values).enumerate() {
        *p = [T::lit(j as f64 / 5.0), v];
    }
    Bezier::new(points)
}

/// The corrections of one candidate, as functions of time.
struct Corrections<T: Real> {
    fade_end_s: T,
    /// The φ1 correction kept after the fade: the share of the offset the
    /// pilot keeps (`Measured::persist`).
    kept: T,
    /// δ·w(s) + ω_e·t_f·g(s), then `kept`.
    phi1: Bezier<T, 6>,
    /// u(s): the share of the start's torso offset and swing-ankle and
    /// knee-choice shift left.
    fade: Bezier<T, 6>,
    /// The torso's offset at the start, rad.
    torso: T,
    /// δ·ρ·b(s).
    r2: Bezier<T, 6>,
}

impl<T: Real> Corrections<T> {
    fn new(x: &[T; DIM], plan: &Plan<'_, T>) -> Self {
        let [fade, w2, w3, u2, u3, rho] = *x;
        let fade_end_s = fade * plan.step_time_s;
        let (d, z, one) = (plan.delta, T::zero(), T::one());
        // g = [0, 1/5, 0, 0, 0, 0] has slope 1 at s = 0, so ω_e·t_f·g
        // gives the plan the rate ω_e at t = 0.
        let g1 = plan.rate_error * fade_end_s / T::lit(5.0);
        let bump = d * rho;
        let kept = d * plan.persist;
        Self {
            fade_end_s,
            kept,
            phi1: curve([d, d + g1, d * w2, d * w3, kept, kept]),
            fade: curve([one, one, u2, u3, z, z]),
            torso: plan.start_torso,
            r2: curve([z, z, bump, bump, z, z]),
        }
    }

    /// (φ1, φ3, r2) corrections at `t_s` and the share of the start's
    /// shift left; `None` once the fade is over and nothing is kept (the
    /// table's own sample).
    fn at(&self, t_s: T) -> Option<([T; 3], T)> {
        let z = T::zero();
        if t_s >= self.fade_end_s || self.fade_end_s <= z {
            return (self.kept != z).then_some(([self.kept, z, z], z));
        }
        let s = t_s / self.fade_end_s;
        let u = self.fade.eval(s)[1];
        Some((
            [self.phi1.eval(s)[1], self.torso * u, self.r2.eval(s)[1]],
            u,
        ))
    }
}

/// One step's re-planning problem: the table, the body, the offset.
pub(super) struct Plan<'a, T: Real> {
    pub model: &'a BodyModel<T>,
    pub foot: StanceFoot<T>,
    pub ik: IkSolver<T>,
    pub table: GaitTable<'a>,
    pub period_s: T,
    pub step_time_s: T,
    /// Measured φ1 less the table's at the start, rad.
    pub delta: T,
    /// Measured φ1 rate less the table's at the start (limited), rad/s.
    pub rate_error: T,
    /// Share of δ the pilot is expected to keep to the landing.
    pub persist: T,
    /// The posture the step starts from: the measured one, or the
    /// table's first with every link turned by δ.
    pub start_phi: Phi<T>,
    /// Where it puts the swing ankle and the knee choice, less where the
    /// table's first posture does ([`Plan::start_shift`]) …
    pub start_shift: ([T; 2], T),
    /// … and its torso less the table's, rad: the first sample is the
    /// posture the body is in.
    pub start_torso: T,
    /// The landing aimed at less the table's, m ([`super::ReplanSetup::aim_m`]).
    pub aim_m: [T; 2],
    /// The table's swing ankle height at its landing (stance foot's
    /// frame), m: where the approach's last centimetre begins above …
    pub landing_y_m: T,
    /// … and from when, s: the last time the table's swing ankle comes
    /// down through that centimetre (an ascent's swing foot starts below
    /// the landing, on the lower tread).
    pub approach_from_s: T,
}

impl<T: Real> Plan<'_, T> {
    /// The table's sample `k`.
    pub fn table_phi(&self, k: usize) -> Option<Phi<T>> {
        self.table
            .sample(k)
            .map(|s| s.map(|v| T::lit(f64::from(v))))
    }

    /// The table's sample `k` played from the measured start: the chain
    /// rotated by δ.
    pub fn rotated_phi(&self, k: usize) -> Option<Phi<T>> {
        self.table_phi(k).map(|p| p.map(|v| v + self.delta))
    }

    /// Writes the candidate `x` into `out` (the table's length).
    pub fn fill(&self, x: &[T; DIM], out: &mut [[T; LINKS]]) -> Result<(), Violation> {
        let c = Corrections::new(x, self);
        for (k, o) in out.iter_mut().enumerate() {
            let at = u16::try_from(k).unwrap_or(u16::MAX);
            let table = self.table_phi(k).ok_or(Violation::Playback(at))?;
            let t = T::lit(k as f64) * self.period_s;
            let aimed = self.aim_m != [T::zero(); 2];
            // After the fade with nothing kept, the table's own sample,
            // unless it is aimed elsewhere.
            let (e, shift) = match c.at(t) {
                None if !aimed => {
                    *o = table;
                    continue;
                }
                None => ([T::zero(); 3], T::zero()),
                Some(correction) => correction,
            };
            *o = self
                .corrected(&table, e, shift, t)
                .ok_or(Violation::Ik(at))?;
        }
        Ok(())
    }

    /// Writes the table's samples into `out`.
    pub fn fill_table(&self, out: &mut [[T; LINKS]]) {
        for (k, o) in out.iter_mut().enumerate() {
            if let Some(p) = self.table_phi(k) {
                *o = p;
            }
        }
    }

    /// The swing ankle (stance foot's flat frame) and the knee choice r2
    /// of `phi`.
    fn ankle_and_knee(&self, phi: &Phi<T>) -> Option<([T; 2], T)> {
        let [phi1, phi2, ..] = *phi;
        let p5 = swing_ankle(self.model, &self.foot, phi);
        let a = self.foot.ankle(phi1).position_m;
        let (lo, hi) = self.ik.phi2_range(p5[0] - a[0], p5[1] - a[1], phi1).ok()?;
        let span = hi - lo;
        let r2 = if span > T::lit(1e-9) {
            (phi2 - lo) / span
        } else {
            T::one()
        };
        Some((p5, r2))
    }

    /// The aim's share at `t_s`, the table's swing ankle at height `y_m`:
    /// x eased in over the step (nothing at the start, where the body
    /// is), y eased in over the approach's last [`APPROACH_M`] above the
    /// table's landing.
    #[inline]
    fn aimed(&self, y_m: T, t_s: T) -> [T; 2] {
        let [ax, ay] = self.aim_m;
        if ax == T::zero() && ay == T::zero() {
            return [T::zero(); 2];
        }
        let along = (t_s / self.step_time_s).max(T::zero()).min(T::one());
        let above = (y_m - self.landing_y_m) / T::lit(APPROACH_M);
        let down = if t_s >= self.approach_from_s {
            (T::one() - above).max(T::zero()).min(T::one())
        } else {
            T::zero()
        };
        [ax * smoothstep(along), ay * smoothstep(down)]
    }

    /// When the table's swing ankle last comes down to [`APPROACH_M`]
    /// above its landing height `landing_y_m`, s (the first sample after
    /// the last one above it). Bounded: one pass over the table.
    pub fn approach_from(&self, landing_y_m: T) -> T {
        let mut from = 0;
        for k in 0..self.table.len() {
            let Some(phi) = self.table_phi(k) else { break };
            if swing_ankle(self.model, &self.foot, &phi)[1] - landing_y_m > T::lit(APPROACH_M) {
                from = k + 1;
            }
        }
        T::lit(from as f64) * self.period_s
    }

    /// Where the start posture ([`Plan::start_phi`]) puts the swing ankle
    /// and the knee choice, less where the table's first does. The
    /// candidates start there and fade back to the table's path with the
    /// torso (u), so the first sample is the posture the body is in.
    pub fn start_shift(&self) -> ([T; 2], T) {
        let z = ([T::zero(); 2], T::zero());
        let Some(table) = self.table_phi(0) else {
            return z;
        };
        match (
            self.ankle_and_knee(&table),
            self.ankle_and_knee(&self.start_phi),
        ) {
            (Some((p, r)), Some((q, s))) => ([q[0] - p[0], q[1] - p[1]], s - r),
            _ => z,
        }
    }

    /// The table's posture with the corrections (φ1, φ3, r2) applied and
    /// the swing ankle where the table has it, in the stance foot's frame,
    /// shifted by `start_shift` times `shift` (1 at the start, fading) and
    /// towards the aim ([`Plan::aimed`]) at `t_s`.
    fn corrected(&self, table: &Phi<T>, [e1, e3, er]: [T; 3], shift: T, t_s: T) -> Option<Phi<T>> {
        let [phi1, _, phi3, ..] = *table;
        let (p5, r2) = self.ankle_and_knee(table)?;
        let ([dx, dy], dr) = self.start_shift;
        let [ax, ay] = self.aimed(p5[1], t_s);
        let p5 = [p5[0] + shift * dx + ax, p5[1] + shift * dy + ay];
        let phi1 = phi1 + e1;
        let a = self.foot.ankle(phi1).position_m;
        let target = IkTarget {
            x5: p5[0] - a[0],
            y5: p5[1] - a[1],
            phi1,
            phi3: phi3 + e3,
            r2: (r2 + shift * dr + er).max(T::zero()).min(T::one()),
        };
        self.ik.solve(&target).ok().map(|s| s.phi)
    }
}

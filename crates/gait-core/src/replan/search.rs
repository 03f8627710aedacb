//! The re-planner as a state machine: the baseline, the start point, then
//! a compass search, one evaluation at a time, so that a caller can spread
//! the work over the idle time of its tick.
//!
//! Compass search (opportunistic coordinate pattern search): try the
//! current point plus and minus the step along each variable in turn,
//! move to the first that costs less; after a sweep without a move halve
//! every step; stop after [`SHRINKS`] halvings or at the budget. It keeps
//! one point, its cost and one step per variable, visits a deterministic
//! sequence (so the same budget spread over any number of calls gives the
//! same result), and treats a refused candidate as +∞ (the cost is not
//! smooth, and a gradient would need DIM evaluations per step besides).

use crate::ik::IkSolver;
use crate::model::LINKS;
use crate::playback::swing_ankle;
use crate::scalar::Real;
use crate::tables::GaitTable;

use super::cost::{Evaluation, evaluate};
use super::curves::{DIM, INITIAL, LOWER, Plan, STEP, UPPER};
use super::{
    Fallback, MAX_AIM_M, MAX_EVALS, MAX_OFFSET_RAD, MAX_RATE_ERROR_RAD_S, Measured, ON_PLAN_RAD,
    ON_PLAN_RAD_S, Outcome, Progress, ReplanError, ReplanLimits, ReplanSetup,
};

/// Halvings of the steps after which the search has converged (the finest
/// step is 1/16 of the first: 0.01 of the step time for the fade's end).
const SHRINKS: u8 = 4;

/// Where the state machine stands.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Stage {
    /// The table from the measured start is to be scored.
    Baseline,
    /// The start point is to be scored.
    Start,
    /// Searching: the next trial is along `coord`, `up` or down.
    Search { coord: usize, up: bool },
}

/// One step's re-plan, in progress or finished (module documentation of
/// [`super`]). Holds the output buffer for its lifetime: it is the
/// candidates' scratch, and holds the answer once done.
pub struct Replanner<'a, T: Real> {
    plan: Plan<'a, T>,
    setup: ReplanSetup<'a, T>,
    limits: ReplanLimits<T>,
    out: &'a mut [[T; LINKS]],
    planned_landing_m: [T; 2],
    max_evals: u16,
    evals: u16,
    stage: Stage,
    table: Option<Evaluation<T>>,
    best_x: [T; DIM],
    best: Option<Evaluation<T>>,
    step: [T; DIM],
    moved: bool,
    shrinks: u8,
    outcome: Option<Outcome<T>>,
}

impl<'a, T: Real> Replanner<'a, T> {
    /// A re-plan of `table` for a pilot measured at `measured`, writing
    /// into `out` (the table's length), with at most `max_evals`
    /// evaluations (1 ..= [`MAX_EVALS`]). Does no evaluation: the work is
    /// done by [`Self::step`].
    pub fn new(
        setup: ReplanSetup<'a, T>,
        limits: ReplanLimits<T>,
        table: GaitTable<'a>,
        measured: Measured<T>,
        out: &'a mut [[T; LINKS]],
        max_evals: u16,
    ) -> Result<Self, ReplanError> {
        if out.len() != table.len() {
            return Err(ReplanError::BufferLength);
        }
        if !(measured.phi1_rad.finite()
            && measured.rate_rad_s.finite()
            && measured.persist.finite())
        {
            return Err(ReplanError::BadMeasurement);
        }
        if !limits.valid() {
            return Err(ReplanError::BadLimits);
        }
        let setup_ok = [setup.spring_nm_per_rad, setup.crutch_lever_m]
            .iter()
            .chain(&setup.spacing_m)
            .chain(&setup.aim_m)
            .all(|v| v.finite())
            && setup.crutch_lever_m > T::zero()
            && setup.aim_m.iter().all(|a| a.abs() <= T::lit(MAX_AIM_M));
        if !setup_ok {
            return Err(ReplanError::BadSetup);
        }
        if max_evals == 0 || max_evals > MAX_EVALS {
            return Err(ReplanError::BadBudget);
        }
        let lit = |v: f32| T::lit(f64::from(v));
        let first = table.first();
        let second = table.sample(1).unwrap_or(first);
        let period_s = lit(table.period_s());
        let [phi1_start, ..] = first;
        let delta = measured.phi1_rad - lit(phi1_start);
        if delta.abs() > T::lit(MAX_OFFSET_RAD) {
            return Err(ReplanError::OffsetTooLarge);
        }
        let table_rate = (lit(second[0]) - lit(phi1_start)) / period_s;
        let max_rate = T::lit(MAX_RATE_ERROR_RAD_S);
        let rate_error = (measured.rate_rad_s - table_rate)
            .max(-max_rate)
            .min(max_rate);
        let mut plan = Plan {
            model: setup.model,
            foot: setup.foot,
            ik: IkSolver::new(setup.model).with_options(table.ik_options().cast()),
            table,
            period_s,
            step_time_s: lit(table.duration_s()),
            delta,
            rate_error,
            persist: measured.persist.max(T::zero()).min(T::one()),
            start_phi: [T::zero(); LINKS],
            start_shift: ([T::zero(); 2], T::zero()),
            start_torso: T::zero(),
            aim_m: setup.aim_m,
            landing_y_m: T::zero(),
            approach_from_s: T::zero(),
        };
        let rotated = plan.rotated_phi(0).unwrap_or(plan.start_phi);
        plan.start_phi = match measured.posture {
            Some(p) if p.iter().all(|v| v.finite()) => {
                let mut p = p;
                // φ1 is the measured angle itself.
                if let Some(phi1) = p.first_mut() {
                    *phi1 = measured.phi1_rad;
                }
                p
            }
            _ => rotated,
        };
        plan.start_shift = plan.start_shift();
        plan.start_torso = plan.start_phi[2] - lit(first[2]);
        let [table_x, table_y] = swing_ankle(setup.model, &setup.foot, &plan.table_phi_last());
        plan.landing_y_m = table_y;
        if setup.aim_m[1] != T::zero() {
            plan.approach_from_s = plan.approach_from(table_y);
        }
        let [aim_x, aim_y] = setup.aim_m;
        let planned_landing_m = [table_x + aim_x, table_y + aim_y];
        let mut me = Self {
            plan,
            setup,
            limits,
            out,
            planned_landing_m,
            max_evals,
            evals: 0,
            stage: Stage::Baseline,
            table: None,
            best_x: INITIAL.map(T::lit),
            best: None,
            step: STEP.map(T::lit),
            moved: false,
            shrinks: 0,
            outcome: None,
        };
        if delta.abs() < T::lit(ON_PLAN_RAD) && rate_error.abs() < T::lit(ON_PLAN_RAD_S) {
            me.finish_with(Outcome::UseTable(Fallback::OnPlan));
        }
        Ok(me)
    }

    /// Does at most `budget_evals` evaluations and says where the re-plan
    /// stands. Once done, it answers the same outcome again at no cost.
    pub fn step(&mut self, budget_evals: u16) -> Progress<T> {
        for _ in 0..budget_evals {
            if self.outcome.is_some() {
                break;
            }
            self.advance();
        }
        match self.outcome {
            Some(o) => Progress::Done(o),
            None => Progress::Running { evals: self.evals },
        }
    }

    /// Evaluations used so far.
    pub fn evals(&self) -> u16 {
        self.evals
    }

    /// The buffer: the candidate last scored while running, the answer
    /// once done.
    pub fn samples(&self) -> &[[T; LINKS]] {
        self.out
    }

    /// The baseline's cost, once scored (N·s).
    pub fn table_cost(&self) -> Option<T> {
        self.table.map(|e| e.cost)
    }

    /// One evaluation, then the answer if that was the last.
    fn advance(&mut self) {
        match self.stage {
            Stage::Baseline => {
                let plan = &self.plan;
                let ev = evaluate(
                    &self.setup,
                    &self.limits,
                    plan.period_s,
                    plan.table.len(),
                    |k| plan.rotated_phi(k),
                    self.planned_landing_m,
                    false,
                );
                self.evals = self.evals.saturating_add(1);
                self.table = Some(ev);
                self.stage = Stage::Start;
            }
            Stage::Start => {
                let x = self.best_x;
                self.best = Some(self.score(&x));
                self.stage = Stage::Search { coord: 0, up: true };
            }
            Stage::Search { coord, up } => self.search(coord, up),
        }
        if self.evals >= self.max_evals && self.outcome.is_none() {
            self.conclude();
        }
    }

    /// The next trial of the compass search: scores it if it differs from
    /// the current point (a trial clamped onto it is skipped), at most one
    /// evaluation.
    fn search(&mut self, mut coord: usize, mut up: bool) {
        // Bounded: each pass either scores a trial or moves to the next
        // direction; after 2·DIM directions the sweep ends.
        for _ in 0..=2 * DIM {
            let Some(trial) = self.trial(coord, up) else {
                (coord, up) = self.next_direction(coord, up);
                if self.outcome.is_some() {
                    return;
                }
                continue;
            };
            let ev = self.score(&trial);
            let better = match self.best {
                Some(b) => ev.violation.is_none() && (b.violation.is_some() || ev.cost < b.cost),
                None => true,
            };
            if better {
                self.best = Some(ev);
                self.best_x = trial;
                self.moved = true;
            }
            // After a move up, down would score the point just left.
            (coord, up) = self.next_direction(coord, up && !better);
            if self.outcome.is_none() {
                self.stage = Stage::Search { coord, up };
            }
            return;
        }
    }

    /// The current point moved by the step along `coord`, within the
    /// bounds; `None` if that is the current point.
    fn trial(&self, coord: usize, up: bool) -> Option<[T; DIM]> {
        let mut x = self.best_x;
        let (v, h) = (x.get_mut(coord)?, *self.step.get(coord)?);
        let lo = T::lit(*LOWER.get(coord)?);
        let hi = T::lit(*UPPER.get(coord)?);
        let moved = if up { *v + h } else { *v - h }.max(lo).min(hi);
        if moved == *v {
            return None;
        }
        *v = moved;
        Some(x)
    }

    /// The direction after (`coord`, `up`); at the end of a sweep without
    /// a move the steps halve, and after [`SHRINKS`] halvings the search
    /// concludes.
    fn next_direction(&mut self, coord: usize, up: bool) -> (usize, bool) {
        if up {
            return (coord, false);
        }
        if coord + 1 < DIM {
            return (coord + 1, true);
        }
        if !self.moved {
            self.shrinks = self.shrinks.saturating_add(1);
            for h in &mut self.step {
                *h *= T::lit(0.5);
            }
            if self.shrinks >= SHRINKS {
                self.conclude();
            }
        }
        self.moved = false;
        (0, true)
    }

    /// Writes candidate `x` into the buffer and scores it.
    fn score(&mut self, x: &[T; DIM]) -> Evaluation<T> {
        self.evals = self.evals.saturating_add(1);
        if let Err(v) = self.plan.fill(x, self.out) {
            return Evaluation {
                cost: T::max_value().unwrap_or(T::one() / T::zero()),
                balance_ns: T::zero(),
                violation: Some(v),
            };
        }
        let out: &[[T; LINKS]] = self.out;
        evaluate(
            &self.setup,
            &self.limits,
            self.plan.period_s,
            out.len(),
            |k| out.get(k).copied(),
            self.planned_landing_m,
            true,
        )
    }

    /// The answer from the best point and the baseline; the buffer is
    /// filled with what is to be played.
    fn conclude(&mut self) {
        let outcome = match (self.best, self.table) {
            (Some(best), Some(table)) => match best.violation {
                Some(v) => Outcome::UseTable(Fallback::Infeasible(v)),
                None if best.cost < table.cost => Outcome::Replanned {
                    cost: best.cost,
                    balance_ns: best.balance_ns,
                    table_cost: table.cost,
                    table_balance_ns: table.balance_ns,
                    evals: self.evals,
                },
                None => Outcome::UseTable(Fallback::NoImprovement),
            },
            _ => Outcome::UseTable(Fallback::NoImprovement),
        };
        self.finish_with(outcome);
    }

    /// Fills the buffer for `outcome` and stores it.
    fn finish_with(&mut self, outcome: Outcome<T>) {
        let outcome = match outcome {
            Outcome::Replanned { .. } => match self.plan.fill(&self.best_x, self.out) {
                Ok(()) => outcome,
                Err(v) => {
                    self.plan.fill_table(self.out);
                    Outcome::UseTable(Fallback::Infeasible(v))
                }
            },
            Outcome::UseTable(_) => {
                self.plan.fill_table(self.out);
                outcome
            }
        };
        self.outcome = Some(outcome);
    }
}

impl<T: Real> Plan<'_, T> {
    /// The table's last sample (landing), zero if unreadable (a verified
    /// table always has it).
    fn table_phi_last(&self) -> [T; LINKS] {
        self.table_phi(self.table.len().saturating_sub(1))
            .unwrap_or([T::zero(); LINKS])
    }
}

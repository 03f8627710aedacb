//! The search over the 22 free entries of P (see `encoding`): exploratory
//! CMA-ES runs from several starts raced by successive halving, then
//! IPOP-CMA-ES from the best point, then a compass-search polish
//! (docs/optimiser.md has the details and the measured figures).
//!
//! Why CMA-ES, and why the `cmaes` crate:
//! - J is discontinuous: the IK's stance-thigh range has kinks (min/max of
//!   eq. (aaa)/(aba)) and jumps (the folded-leg case switch), the contact
//!   indicator c_k switches samples in and out, and the velocity term is a
//!   max. Finite-difference gradients are meaningless there (L-BFGS-B stalls
//!   at 9326 / 2189). CMA-ES only uses the *ranking* of sampled points, so
//!   jumps and kinks do not mislead it, and it learns the strongly coupled,
//!   badly scaled directions (times vs values of one curve) through its
//!   covariance.
//! - `cmaes` (pengowen123) is a maintained, documented implementation with
//!   the standard (Hansen) parameters, seeded sampling (ChaCha) and
//!   evaluation-count termination; it runs fine on one thread. We drive it
//!   generation by generation with [`cmaes::CMAES::next`] so that the
//!   budget, restarts and progress reports are ours. `argmin` has no
//!   CMA-ES (its derivative-free methods are Nelder–Mead, particle swarm
//!   and simulated annealing; none learns a search covariance, and
//!   Nelder–Mead in 22 dimensions stalls on the jumps).
//!
//! Budget is a number of cost evaluations, never wall time, so the result is
//! a pure function of (case, seed, budget).

use std::cell::RefCell;
use std::time::Instant;

use cmaes::{CMAESOptions, DVector};
use gait_core::gait::{ControlPoints, GaitError};
use gait_core::problem::{Cost, Infeasible, PaperCase, PaperProblem};

use crate::compass::compass_search;
use crate::encoding::{DIM, Encoding};

/// What [`optimize`] is asked to do.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptimizeConfig {
    /// Which of the paper's cases.
    pub case: PaperCase,
    /// Seed of the search's random numbers.
    pub seed: u64,
    /// Total number of cost evaluations (CMA-ES and polish together).
    pub max_evals: usize,
    /// Share of `max_evals` kept for the final pattern search, 0–1.
    pub polish_share: f64,
    /// Number of exploratory CMA-ES runs (the first from the initial
    /// guess, the others from random points).
    pub starts: usize,
    /// Share of the CMA-ES budget spent on the exploratory runs.
    pub explore_share: f64,
    /// Initial step size of the exploratory runs (box = unit cube).
    pub sigma0: f64,
    /// Initial step size of the refinement runs.
    pub sigma_refine: f64,
    /// Velocity weight the exploratory runs rank by (a homotopy: a larger
    /// weight than the paper's v_p favours long, slow swings).
    pub explore_velocity_weight: f64,
}

impl OptimizeConfig {
    /// The defaults for a case: 20,000 evaluations (about 1.7 s on one core
    /// in release), 15 % of them for the polish, seed 1.
    ///
    /// The exploration settings differ per case; they were chosen by
    /// running seeds 1–6 at 20,000 evaluations (docs/optimiser.md): level
    /// walking needs random starts and a stronger velocity homotopy to avoid
    /// the "late, fast swing" basin (J ≈ 4,200–4,700); stair ascent does
    /// best from the structured starts alone with the paper's v_p.
    pub fn new(case: PaperCase) -> Self {
        let (starts, explore_share, explore_velocity_weight) = match case {
            PaperCase::Walk => (8, 0.6, 2000.0),
            PaperCase::StairUp => (4, 0.5, 1000.0),
        };
        Self {
            case,
            seed: 1,
            max_evals: 20_000,
            polish_share: 0.15,
            starts,
            explore_share,
            sigma0: 0.3,
            sigma_refine: 0.05,
            explore_velocity_weight,
        }
    }
}

/// The phase the search is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// One CMA-ES run (restart number inside [`Progress`]).
    Cmaes,
    /// The final pattern search.
    Polish,
}

/// A progress report, sent once per CMA-ES generation and per polish sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    /// Phase of the search.
    pub phase: Phase,
    /// CMA-ES run index (0 = first run, then IPOP restarts).
    pub run: usize,
    /// Cost evaluations so far.
    pub evaluations: usize,
    /// Best feasible J so far (infinite before the first feasible point).
    pub best_j: f64,
}

/// What [`optimize`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimizeResult {
    /// The case solved.
    pub case: PaperCase,
    /// The best P found; always passes `check_feasible`.
    pub control_points: ControlPoints<f64>,
    /// J and its parts at `control_points`.
    pub cost: Cost<f64>,
    /// Cost evaluations used in all.
    pub evaluations: usize,
    /// Of which by the CMA-ES runs.
    pub cmaes_evaluations: usize,
    /// Number of CMA-ES runs (1 + restarts).
    pub runs: usize,
    /// Wall-clock time of the search, s (informative only; never used to
    /// stop it).
    pub wall_s: f64,
    /// The seed used.
    pub seed: u64,
}

/// Why [`optimize`] could not return a result.
#[derive(Clone, Debug, PartialEq)]
pub enum OptimizeError {
    /// The configuration is unusable (the message says which field).
    BadConfig(String),
    /// The CMA-ES library refused its options.
    Cmaes(String),
    /// No evaluated point was feasible (should not happen: the initial
    /// guess is feasible).
    NoFeasiblePoint,
}

impl std::fmt::Display for OptimizeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::BadConfig(m) => write!(f, "bad optimiser configuration: {m}"),
            Self::Cmaes(m) => write!(f, "CMA-ES: {m}"),
            Self::NoFeasiblePoint => f.write_str("no feasible point was found"),
        }
    }
}

impl std::error::Error for OptimizeError {}

/// Value given to a P whose IK fails at sample k of N: far above any
/// feasible J (feasible J < 1e6 for every P tried), and lower the later the
/// failure, so that the ranking still leads towards feasibility.
fn infeasible_value(e: &Infeasible, n: usize) -> f64 {
    match e {
        Infeasible::Gait(GaitError::Ik { k, .. }) => {
            1e8 + 1e7 * (n.saturating_sub(*k) as f64) / (n.max(1) as f64)
        }
        _ => 1e9,
    }
}

/// Weight of the squared distance to the search box.
const BOX_PENALTY: f64 = 1e5;

/// Counts evaluations and keeps the best feasible point.
struct Tracker {
    problem: PaperProblem<f64>,
    encoding: Encoding,
    evals: usize,
    best: Option<(f64, [f64; DIM])>,
    /// Velocity weight the search ranks by (the paper's v_p, or a larger
    /// one during exploration); the best point is always kept by true J.
    search_weight: f64,
    /// Best true J seen since the last reset (per exploratory run).
    run_best: f64,
}

impl Tracker {
    fn eval(&mut self, x: &[f64]) -> f64 {
        self.evals += 1;
        let p = self.encoding.decode(x);
        let base = match self.problem.cost(&p) {
            Ok(c) => {
                let j = c.j;
                self.run_best = self.run_best.min(j);
                if self.best.is_none_or(|(b, _)| j < b) {
                    let mut xb = [0.0; DIM];
                    for (o, &v) in xb.iter_mut().zip(x) {
                        *o = v.clamp(0.0, 1.0);
                    }
                    self.best = Some((j, xb));
                }
                c.torque + self.search_weight * c.peak_ankle_speed_m_s
            }
            Err(e) => infeasible_value(&e, self.problem.sampling.intervals),
        };
        base + BOX_PENALTY * Encoding::box_violation(x)
    }

    fn best_j(&self) -> f64 {
        self.best.map_or(f64::INFINITY, |(j, _)| j)
    }
}

/// Minimises J for one case (see the module documentation).
///
/// `progress` is called once per CMA-ES generation and once per polish
/// sweep. Deterministic: the same config gives bitwise the same P.
pub fn optimize(
    config: &OptimizeConfig,
    progress: &mut dyn FnMut(&Progress),
) -> Result<OptimizeResult, OptimizeError> {
    optimize_problem(&PaperProblem::<f64>::paper(config.case), config, progress)
}

/// Minimises J for any problem of the paper's form (another step geometry,
/// step time, body model or velocity weight); `config.case` only labels the
/// result and picks nothing else. [`optimize`] is this with paper mode.
pub fn optimize_problem(
    problem: &PaperProblem<f64>,
    config: &OptimizeConfig,
    progress: &mut dyn FnMut(&Progress),
) -> Result<OptimizeResult, OptimizeError> {
    if config.max_evals < 200 {
        return Err(OptimizeError::BadConfig(
            "max_evals must be at least 200".into(),
        ));
    }
    if !(0.0..=0.9).contains(&config.polish_share) {
        return Err(OptimizeError::BadConfig(
            "polish_share must be in [0, 0.9]".into(),
        ));
    }
    let started = Instant::now();
    let problem = *problem;
    let encoding = Encoding::new(&problem);
    let tracker = RefCell::new(Tracker {
        problem,
        encoding,
        evals: 0,
        best: None,
        search_weight: config.explore_velocity_weight,
        run_best: f64::INFINITY,
    });
    let polish_budget = (config.max_evals as f64 * config.polish_share) as usize;
    let cmaes_budget = config.max_evals - polish_budget;
    let mut rng = SplitMix64(config.seed ^ 0x5EED_0FE0_6A17);
    let guess = encoding.encode(&problem.initial_guess());
    let default_lambda = 4 + (3.0 * (DIM as f64).ln()).floor() as usize;
    let mut run;
    // Phase 1, exploration by successive halving: `starts` CMA-ES runs (the
    // first from the initial guess, the others from random points of the
    // box) advance side by side; after each stage the worse half (by the
    // best true J each run has seen) is dropped, so that the budget goes to
    // the basins that look best without trusting one short run.
    let explore_budget = (cmaes_budget as f64 * config.explore_share) as usize;
    let starts = config.starts.max(1);
    let stages = (usize::BITS - starts.leading_zeros()) as usize; // ⌊log2⌋ + 1
    let stage_budget = explore_budget / stages.max(1);
    let objective = |x: &DVector<f64>| tracker.borrow_mut().eval(x.as_slice());
    let mut alive = Vec::with_capacity(starts);
    for s in 0..starts {
        let mean: Vec<f64> = if s == 0 {
            guess.to_vec()
        } else if let Some(&frac) = LATE_SWING_STARTS.get(s - 1) {
            encoding.encode(&late_swing_guess(&problem, frac)).to_vec()
        } else {
            (0..DIM).map(|_| 0.1 + 0.8 * rng.unit()).collect()
        };
        let cma = CMAESOptions::new(mean, config.sigma0)
            .population_size(default_lambda)
            .seed(run_seed(config.seed, s))
            .tol_fun(1e-6)
            .tol_x(1e-7)
            .build(objective)
            .map_err(|e| OptimizeError::Cmaes(format!("{e:?}")))?;
        alive.push((s, cma, f64::INFINITY, false));
    }
    run = starts;
    while !alive.is_empty() {
        let per_run = stage_budget / alive.len();
        for (id, cma, best, finished) in alive.iter_mut() {
            tracker.borrow_mut().run_best = *best;
            let stop = tracker.borrow().evals + per_run;
            while !*finished && tracker.borrow().evals + default_lambda <= stop {
                *finished = cma.next().is_some();
                let t = tracker.borrow();
                progress(&Progress {
                    phase: Phase::Cmaes,
                    run: *id,
                    evaluations: t.evals,
                    best_j: t.best_j(),
                });
            }
            *best = tracker.borrow().run_best;
        }
        if alive.len() == 1 {
            break;
        }
        alive.sort_by(|a, b| a.2.total_cmp(&b.2));
        alive.truncate(alive.len().div_ceil(2));
    }
    drop(alive);
    // Phase 2, exploitation: IPOP-style CMA-ES runs from the best point,
    // with the paper's v_p and a smaller step, population doubled per run.
    tracker.borrow_mut().search_weight = problem.velocity_weight;
    let mut lambda = default_lambda;
    while tracker.borrow().evals + lambda * 20 < cmaes_budget {
        let mean = tracker.borrow().best.map_or(guess, |(_, x)| x);
        let stop = cmaes_budget;
        cma_run(
            &tracker,
            &mean,
            config.sigma_refine,
            lambda,
            config.seed,
            run,
            stop,
            progress,
        )?;
        run += 1;
        lambda *= 2;
    }
    let cmaes_evaluations = tracker.borrow().evals;
    let mut t = tracker.into_inner();
    polish(&mut t, config.max_evals, progress, run);
    let Some((_, xb)) = t.best else {
        return Err(OptimizeError::NoFeasiblePoint);
    };
    let p = encoding.decode(&xb);
    let cost = problem
        .cost(&p)
        .map_err(|_| OptimizeError::NoFeasiblePoint)?;
    Ok(OptimizeResult {
        case: config.case,
        control_points: p,
        cost,
        evaluations: t.evals,
        cmaes_evaluations,
        runs: run,
        wall_s: started.elapsed().as_secs_f64(),
        seed: config.seed,
    })
}

/// One CMA-ES run from `mean` until its own termination or until the
/// tracker has counted `stop` evaluations; returns the run's best point.
#[allow(clippy::too_many_arguments)]
fn cma_run(
    tracker: &RefCell<Tracker>,
    mean: &[f64; DIM],
    sigma: f64,
    lambda: usize,
    seed: u64,
    run: usize,
    stop: usize,
    progress: &mut dyn FnMut(&Progress),
) -> Result<Option<(f64, [f64; DIM])>, OptimizeError> {
    let left = stop.saturating_sub(tracker.borrow().evals);
    if left < lambda {
        return Ok(None);
    }
    let objective = |x: &DVector<f64>| tracker.borrow_mut().eval(x.as_slice());
    let mut cma = CMAESOptions::new(mean.to_vec(), sigma)
        .population_size(lambda)
        .seed(run_seed(seed, run))
        .max_function_evals(left)
        .tol_fun(1e-6)
        .tol_x(1e-7)
        .build(objective)
        .map_err(|e| OptimizeError::Cmaes(format!("{e:?}")))?;
    loop {
        let done = cma.next();
        let t = tracker.borrow();
        progress(&Progress {
            phase: Phase::Cmaes,
            run,
            evaluations: t.evals,
            best_j: t.best_j(),
        });
        if done.is_some() || t.evals + lambda > stop {
            break;
        }
    }
    Ok(cma.overall_best_individual().map(|ind| {
        let mut x = [0.0; DIM];
        for (o, &v) in x.iter_mut().zip(ind.point.iter()) {
            *o = v.clamp(0.0, 1.0);
        }
        (ind.value, x)
    }))
}

/// Swing-start times (fractions of ts) of the structured start points.
const LATE_SWING_STARTS: [f64; 3] = [0.5, 0.6, 0.7];

/// A structured start point, the shape that long searches converge to in
/// both cases: the foot stays down (z ≈ 0) until `frac`·ts and then swings
/// to the landing by ts along the lowest path the bounds allow; torso
/// leaning forward at the bound; stance knee straightening (r2 from 1 down
/// to 0.15). Why it is a good region: c_k ignores the stance-ankle torque
/// while the swing foot is within 2 mm of its start, so gaits that keep it
/// down until the centre of mass nears the stance ankle and then swing at an
/// even speed pay little torque; the search still decides everything.
fn late_swing_guess(problem: &PaperProblem<f64>, frac: f64) -> ControlPoints<f64> {
    let mut p = problem.initial_guess();
    let ts = problem.case.step_time_s;
    let (lo, _) = problem.bounds();
    let r2 = [1.0, 0.6, 0.3, 0.15];
    for (row, &v) in p.iter_mut().skip(1).take(4).zip(&r2) {
        row[1] = v;
    }
    for row in p.iter_mut().skip(6).take(4) {
        row[1] = std::f64::consts::PI / 12.0;
    }
    for r in [11, 13] {
        if let (Some(row), Some(l)) = (p.get_mut(r), lo.get(r)) {
            row[1] = l[1];
        }
    }
    if let (Some(row), Some(l)) = (p.get_mut(12), lo.get(12)) {
        *row = *l;
    }
    let ta = (frac * ts).clamp(0.0, ts);
    if let Some(r) = p.get_mut(16) {
        *r = [ta, 0.4];
    }
    if let Some(r) = p.get_mut(17) {
        *r = [ta, 0.0];
    }
    p
}

/// The CMA-ES library's seed for run `run` of a search seeded `seed`.
fn run_seed(seed: u64, run: usize) -> u64 {
    seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(run as u64)
}

/// SplitMix64: a tiny, well-known generator for the random start points
/// (the CMA-ES library seeds its own ChaCha generator).
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Compass search ([`compass_search`]) around the best point, ranked as
/// the search ranks; the best point is kept by true J.
fn polish(t: &mut Tracker, max_evals: usize, progress: &mut dyn FnMut(&Progress), run: usize) {
    let Some((fbest, x)) = t.best else {
        return;
    };
    let budget = max_evals.saturating_sub(t.evals);
    compass_search(
        t,
        x,
        fbest,
        1e-6,
        budget,
        |t, y| t.eval(y),
        |t, _| {
            progress(&Progress {
                phase: Phase::Polish,
                run,
                evaluations: t.evals,
                best_j: t.best_j(),
            });
        },
    );
}

//! Solves one or both cases and prints J, evaluations and wall time:
//! `solve [MAX_EVALS [SEED [walk|stair]]]`. For tuning, the environment
//! overrides the defaults: STARTS, EXPLORE, VW (exploration velocity
//! weight), SIGMA0, SIGMAR, POLISH; VERBOSE=1 prints progress and P.
use gait_core::problem::PaperCase;
use gait_opt::{OptimizeConfig, optimize};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let evals: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    let cases = match args.get(3).map(String::as_str) {
        Some("walk") => vec![PaperCase::Walk],
        Some("stair") => vec![PaperCase::StairUp],
        _ => vec![PaperCase::Walk, PaperCase::StairUp],
    };
    let verbose = std::env::var("VERBOSE").is_ok();
    for case in cases {
        let mut cfg = OptimizeConfig::new(case);
        cfg.max_evals = evals;
        cfg.seed = seed;
        let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
        if let Some(v) = env("STARTS") {
            cfg.starts = v as usize;
        }
        if let Some(v) = env("EXPLORE") {
            cfg.explore_share = v;
        }
        if let Some(v) = env("SIGMA0") {
            cfg.sigma0 = v;
        }
        if let Some(v) = env("SIGMAR") {
            cfg.sigma_refine = v;
        }
        if let Some(v) = env("VW") {
            cfg.explore_velocity_weight = v;
        }
        if let Some(v) = env("POLISH") {
            cfg.polish_share = v;
        }
        let mut last = 0usize;
        match optimize(&cfg, &mut |p| {
            if verbose && p.evaluations >= last + 2000 {
                last = p.evaluations;
                eprintln!(
                    "  {:?} run {} evals {} J {:.1}",
                    p.phase, p.run, p.evaluations, p.best_j
                );
            }
        }) {
            Ok(r) => {
                if verbose {
                    for row in &r.control_points {
                        println!("  [{:.4}, {:.4}]", row[0], row[1]);
                    }
                }
                println!(
                    "{case:?}: J = {:.2} (torque {:.2}, velocity {:.2}) evals {} (cmaes {}, runs {}) wall {:.2} s",
                    r.cost.j,
                    r.cost.torque,
                    r.cost.velocity,
                    r.evaluations,
                    r.cmaes_evaluations,
                    r.runs,
                    r.wall_s
                )
            }
            Err(e) => println!("{case:?}: {e}"),
        }
    }
}

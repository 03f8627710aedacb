//! The closed-loop refinement of one clinical table, with its progress:
//! `cargo run --release -p gait-opt --example refine -- stair-up [STEPS EVALS STEP]`
//! (the settings `cargo xtask tables` uses by default).

use std::process::ExitCode;
use std::time::Instant;

use gait_core::tables::GaitKind;
use gait_opt::clinical::ClinicalCase;
use gait_opt::clinical::closed_loop::refine;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let kind = match args.first().map(String::as_str) {
        Some("walk") => GaitKind::Walk,
        Some("stair-down") => GaitKind::StairDown,
        _ => GaitKind::StairUp,
    };
    let Some(mut config) = gait_opt::tables::closed_loop_refinement(kind)
        .or(gait_opt::tables::closed_loop_refinement(GaitKind::StairUp))
    else {
        return ExitCode::FAILURE;
    };
    if let Some(v) = args.get(1).and_then(|a| a.parse().ok()) {
        config.search_steps = v;
    }
    if let Some(v) = args.get(2).and_then(|a| a.parse().ok()) {
        config.max_evals = v;
    }
    if let Some(v) = args.get(3).and_then(|a| a.parse().ok()) {
        config.initial_step = v;
    }
    let Ok(device) = exogait_device::DeviceConfig::exogait() else {
        return ExitCode::FAILURE;
    };
    let case = ClinicalCase::for_gait(kind, &device);
    let t0 = Instant::now();
    let start = match gait_opt::tables::clinical_start(kind, &device) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("refine: {e}");
            return ExitCode::FAILURE;
        }
    };
    eprintln!(
        "{config:?}; CMA-ES stage {:.1} s",
        t0.elapsed().as_secs_f64()
    );
    let t1 = Instant::now();
    let mut progress = |n: usize, v: f64| {
        eprintln!("{:8.1} s  {n:5}  {v:.2}", t1.elapsed().as_secs_f64());
    };
    match refine(&case, &device, &start.x, &config, &mut progress) {
        Ok(r) => {
            println!(
                "evaluations {}, search {:.1} → {:.1} N·s; 4 steps {:.1} N·s ({:?}), peak {:.0} N, \
                 near-peak {:.3} s/step; 20 steps {:.1} N·s; start 4 steps {:.1}; predicted {:.1}; {:.0} s",
                r.evaluations,
                r.search_ns[0],
                r.search_ns[1],
                r.verified[0].mean_balance_ns,
                r.verified[0].balance_ns,
                r.verified[0].crutch_peak_n,
                r.verified[0].near_peak_s_per_step,
                r.verified[1].mean_balance_ns,
                r.start_played.mean_balance_ns,
                r.evaluation.balance_ns,
                t1.elapsed().as_secs_f64()
            );
            println!("x {:?}", r.x);
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("refine: {e}");
            ExitCode::FAILURE
        }
    }
}

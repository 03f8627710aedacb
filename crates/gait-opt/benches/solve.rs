//! One cost evaluation, one Φ-sequence evaluation, and a full solve
//! (default budget, 20,000 evaluations; sample size 10).
//!
//! `CARGO_TARGET_DIR=... cargo bench -p gait-opt`
use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use gait_core::problem::{PaperCase, PaperProblem};
use gait_opt::report::step_samples;
use gait_opt::{OptimizeConfig, cost_from_phi, optimize};

fn cost(c: &mut Criterion) {
    let problem = PaperProblem::<f64>::paper(PaperCase::Walk);
    let p = problem.initial_guess();
    c.bench_function("paper_cost_walk", |b| {
        b.iter(|| problem.cost(black_box(&p)))
    });
    let phi: Vec<_> = step_samples(&problem, &p)
        .map(|rows| rows.iter().map(|s| s.phi_rad).collect())
        .unwrap_or_default();
    c.bench_function("cost_from_phi_walk", |b| {
        b.iter(|| cost_from_phi(&problem, black_box(&phi)))
    });
}

fn solve(c: &mut Criterion) {
    let mut g = c.benchmark_group("solve");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(100))
        .measurement_time(Duration::from_secs(15));
    for case in [PaperCase::Walk, PaperCase::StairUp] {
        let cfg = OptimizeConfig::new(case);
        g.bench_function(format!("{case:?}_20k_evals"), |b| {
            b.iter(|| optimize(black_box(&cfg), &mut |_| {}))
        });
    }
    g.finish();
}

criterion_group!(benches, cost, solve);
criterion_main!(benches);

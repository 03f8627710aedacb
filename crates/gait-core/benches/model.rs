//! Host benchmarks of the per-sample work: IK, inverse dynamics (flat foot
//! and on the toe rocker), both
//! together, and the feed-forward's load sharing between the feet, in f32
//! and f64; and one paper-mode cost evaluation (the optimiser's inner loop).
//! `cargo bench -p gait-core`.
#![allow(missing_docs, clippy::unwrap_used)]

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use gait_core::dynamics::Contact::{FixedAnkle, ToeRocker};
use gait_core::dynamics::{inverse_dynamics, share_load};
use gait_core::ik::{IkSolver, IkTarget};
use gait_core::problem::{PaperCase, PaperProblem};
use gait_core::{BodyModel, Real};

fn per_sample<T: Real>(c: &mut Criterion, name: &str) {
    let m: BodyModel<T> = BodyModel::<f64>::paper_table_iii().cast();
    let ik = IkSolver::new(&m);
    let l = T::lit;
    let target = IkTarget {
        x5: l(-0.12),
        y5: l(0.1),
        phi1: l(0.1),
        phi3: l(0.05),
        r2: l(0.7),
    };
    let w = [0.4, -0.9, 0.2, -2.1, 3.3].map(l);
    let a = [1.5, -2.0, 0.7, 6.0, -9.0].map(l);
    let phi = ik.solve(&target).unwrap().phi;
    c.bench_function(&format!("ik_{name}"), |b| {
        b.iter(|| ik.solve(black_box(&target)))
    });
    c.bench_function(&format!("inverse_dynamics_{name}"), |b| {
        b.iter(|| {
            inverse_dynamics(
                &m,
                &FixedAnkle,
                black_box(&phi),
                black_box(&w),
                black_box(&a),
            )
        })
    });
    // The stance heel up (stair descent): the toe rocker's dynamics.
    let rocker = ToeRocker(gait_core::foot::StanceFoot::for_model(&m));
    let mut on_toe = phi;
    on_toe[0] = l(0.6);
    c.bench_function(&format!("toe_rocker_inverse_dynamics_{name}"), |b| {
        b.iter(|| {
            inverse_dynamics(
                &m,
                &rocker,
                black_box(&on_toe),
                black_box(&w),
                black_box(&a),
            )
        })
    });
    let single = [-208.0, -208.0, 5.0, 5.0, -2.0].map(l);
    c.bench_function(&format!("share_load_{name}"), |b| {
        b.iter(|| {
            share_load(
                &m,
                &FixedAnkle,
                black_box(&phi),
                black_box(&single),
                l(912.0),
            )
        })
    });
    c.bench_function(&format!("ik_plus_inverse_dynamics_{name}"), |b| {
        b.iter(|| {
            let sol = ik.solve(black_box(&target)).unwrap();
            inverse_dynamics(&m, &FixedAnkle, &sol.phi, black_box(&w), black_box(&a))
        })
    });
}

fn benches(c: &mut Criterion) {
    per_sample::<f32>(c, "f32");
    per_sample::<f64>(c, "f64");
    let pb = PaperProblem::<f64>::paper(PaperCase::Walk);
    let p = pb.initial_guess();
    c.bench_function("paper_cost_walk_f64", |b| b.iter(|| pb.cost(black_box(&p))));
    // The descent table's problem: toe rocker, human knee range, joint limits.
    let case = gait_core::problem::StepCase::periodic(
        &gait_core::problem::PeriodicStep::<f64>::stair_down(),
        &BodyModel::paper_table_iii(),
    )
    .unwrap();
    let pb = PaperProblem::new(case, BodyModel::paper_table_iii());
    let p = pb.initial_guess();
    c.bench_function("descent_cost_f64", |b| b.iter(|| pb.cost(black_box(&p))));
}

criterion_group!(model, benches);
criterion_main!(model);

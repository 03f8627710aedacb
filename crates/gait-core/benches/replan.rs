//! Host benchmark of one step re-plan ([`gait_core::replan`]) on each
//! shipped table, the pilot 3° forward of the table's start, in f32 (the
//! board's precision), with the figures of each gait at −3°, 0 and +3°
//! printed first. `cargo bench -p gait-core --bench replan`.
//!
//! The host time is a proxy for the board's: the ratio of one re-plan to
//! one IK plus inverse dynamics (`ik_plus_inverse_dynamics_f32` of the
//! `model` bench, some 1,750 instructions on the M4F) estimates its
//! instruction count.
#![allow(missing_docs, clippy::unwrap_used, clippy::indexing_slicing)]

use std::hint::black_box;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use gait_core::BodyModel;
use gait_core::dynamics::{Contact::FixedAnkle, inverse_dynamics};
use gait_core::flash_tables;
use gait_core::foot::StanceFoot;
use gait_core::ik::{IkSolver, IkTarget};
use gait_core::kinematics::theta_from_phi;
use gait_core::playback::swing_ankle;
use gait_core::replan::{MAX_EVALS, Outcome, Progress, Replanner};
use gait_core::tables::GaitKind;

/// Instructions of one IK plus inverse dynamics on the M4F (issue 39).
const M4F_SAMPLE_INSNS: f64 = 1_750.0;

#[path = "../tests/integration/replan_setup.rs"]
#[allow(dead_code)]
mod replan_setup;
use replan_setup::{limits, measured, setup};

fn replan(m: &BodyModel<f32>, kind: GaitKind, deg: f32, out: &mut [[f32; 5]]) -> Outcome<f32> {
    let table = flash_tables::of(kind).unwrap();
    let mut r = Replanner::new(
        setup(m, kind),
        limits(),
        table,
        measured(&table, deg),
        out,
        MAX_EVALS,
    )
    .unwrap();
    match r.step(MAX_EVALS) {
        Progress::Done(o) => o,
        Progress::Running { .. } => unreachable!("the whole budget was given"),
    }
}

/// Host time of one IK plus inverse dynamics, s (the model bench's case).
fn per_sample_s(m: &BodyModel<f32>) -> f64 {
    let ik = IkSolver::new(m);
    let target = IkTarget {
        x5: -0.12,
        y5: 0.1,
        phi1: 0.1,
        phi3: 0.05,
        r2: 0.7,
    };
    let w = [0.4, -0.9, 0.2, -2.1, 3.3];
    let a = [1.5, -2.0, 0.7, 6.0, -9.0];
    let n = 20_000;
    // The fastest of several runs: the host is shared.
    (0..10)
        .map(|_| {
            let t0 = Instant::now();
            for _ in 0..n {
                let sol = ik.solve(black_box(&target)).unwrap();
                black_box(inverse_dynamics(m, &FixedAnkle, &sol.phi, &w, &a));
            }
            t0.elapsed().as_secs_f64() / f64::from(n)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The figures per gait and offset, printed once.
fn figures(m: &BodyModel<f32>) {
    let sample_s = per_sample_s(m);
    let foot = StanceFoot::for_model(m);
    eprintln!(
        "one IK + inverse dynamics: {:.0} ns on this host",
        sample_s * 1e9
    );
    for kind in [GaitKind::Walk, GaitKind::StairUp, GaitKind::StairDown] {
        let table = flash_tables::of(kind).unwrap();
        let planned = swing_ankle(m, &foot, &table.last());
        let err = |phi: &[f32; 5]| {
            let p = swing_ankle(m, &foot, phi);
            1e3 * (p[0] - planned[0]).hypot(p[1] - planned[1])
        };
        for deg in [-3.0f32, 0.0, 3.0] {
            let mut out = vec![[0.0f32; 5]; table.len()];
            let mut outcome = replan(m, kind, deg, &mut out);
            let mut host_s = f64::INFINITY;
            for _ in 0..20 {
                let t0 = Instant::now();
                outcome = replan(m, kind, deg, &mut out);
                host_s = host_s.min(t0.elapsed().as_secs_f64());
            }
            let rotated = table.last().map(|v| v + deg.to_radians());
            // The first sample's hips and knees against the table's: what
            // the start posture with the trailing foot on its footprint
            // changes.
            let (t_new, t_tab) = (theta_from_phi(&out[0]), theta_from_phi(&table.first()));
            let start_jump = (1..5)
                .map(|j| (t_new[j] - t_tab[j]).abs())
                .fold(0.0f32, f32::max)
                .to_degrees();
            eprintln!(
                "{kind:?} {deg:+}°: landing {:.2} mm (table rotated) -> {:.3} mm; {outcome:?}; \
                 start hips/knees up to {start_jump:.2}° off the table's; host {:.2} ms \
                 ≈ {:.2} M M4F instructions",
                err(&rotated),
                err(out.last().unwrap()),
                host_s * 1e3,
                host_s / sample_s * M4F_SAMPLE_INSNS * 1e-6
            );
        }
    }
}

fn benches(c: &mut Criterion) {
    let m = replan_setup::model();
    figures(&m);
    for kind in [GaitKind::Walk, GaitKind::StairUp, GaitKind::StairDown] {
        let table = flash_tables::of(kind).unwrap();
        let mut out = vec![[0.0f32; 5]; table.len()];
        c.bench_function(&format!("replan_{kind:?}_plus_3deg_f32"), |b| {
            b.iter(|| replan(&m, kind, black_box(3.0), &mut out))
        });
    }
}

criterion_group!(replan_benches, benches);
criterion_main!(replan_benches);

//! The step re-planner on the shipped tables and the device's body model:
//! a pilot measured 3° forward or back of the table's start gets samples
//! that start where they stand, land on the table's foothold, stay inside
//! the joint ranges and the drives, and cost no more than the table played
//! from where they stand; on the plan, the table itself.

use gait_core::foot::StanceFoot;
use gait_core::kinematics::{anatomical_angles, theta_from_phi};
use gait_core::playback::{PlaybackError, for_each_sample, swing_ankle};
use gait_core::replan::{
    DriveLimit, Fallback, MAX_EVALS, Measured, Outcome, Progress, ReplanError, ReplanLimits,
    ReplanSetup, Replanner,
};
use gait_core::tables::GaitKind;
use gait_core::{BodyModel, flash_tables};

use super::replan_setup::{KINDS, limits, measured, model, setup};

/// Runs a re-plan in calls of `per_call` evaluations; the outcome, the
/// samples and the number of calls.
fn run(kind: GaitKind, m: Measured<f32>, per_call: u16) -> (Outcome<f32>, Vec<[f32; 5]>, usize) {
    let body = model();
    let table = flash_tables::of(kind).unwrap();
    let mut out = vec![[0.0f32; 5]; table.len()];
    let mut r =
        Replanner::new(setup(&body, kind), limits(), table, m, &mut out, MAX_EVALS).unwrap();
    let mut calls = 0;
    let outcome = loop {
        calls += 1;
        assert!(calls <= 2 * usize::from(MAX_EVALS) + 2, "{kind:?}: no end");
        if let Progress::Done(o) = r.step(per_call) {
            break o;
        }
    };
    (outcome, out, calls)
}

/// Distance of the swing ankle at the last of `samples` from the table's
/// landing, m.
fn landing_error(kind: GaitKind, samples: &[[f32; 5]]) -> f32 {
    let m = model();
    let foot = StanceFoot::for_model(&m);
    let table = flash_tables::of(kind).unwrap();
    let planned = swing_ankle(&m, &foot, &table.last());
    let got = swing_ankle(&m, &foot, samples.last().unwrap());
    (got[0] - planned[0]).hypot(got[1] - planned[1])
}

/// Every sample inside the envelope and within what the drive gives at
/// its speed, by gait-core's playback (checked here, not by the
/// re-planner's own cost).
fn assert_within_limits(kind: GaitKind, samples: &[[f32; 5]]) {
    let m = model();
    let foot = StanceFoot::for_model(&m);
    let l = limits();
    let zero = theta_from_phi(&[0.0f32; 5]);
    for_each_sample::<f32, PlaybackError>(
        &m,
        &foot,
        30.0,
        samples.len(),
        0.01,
        |k| samples.get(k).copied(),
        |s| {
            assert!(
                s.phi[0] >= l.ankle_min_rad,
                "{kind:?} k {}: ankle {}",
                s.k,
                s.phi[0]
            );
            let q = anatomical_angles(&theta_from_phi(&s.phi));
            let rate = theta_from_phi(&s.dphi);
            for (j, range) in [l.knee_rad, l.hip_rad, l.hip_rad, l.knee_rad]
                .iter()
                .enumerate()
            {
                let i = j + 1;
                assert!(
                    (range[0]..=range[1]).contains(&q[i]),
                    "{kind:?} k {}: joint {i} at {} rad",
                    s.k,
                    q[i]
                );
                let w = rate[i] - zero[i];
                let driving = w * s.torques[i] > 0.0;
                let d = l.drive;
                let available = if !driving || w.abs() <= d.full_torque_speed_rad_s {
                    d.peak_nm
                } else {
                    d.peak_nm
                        * ((d.no_load_speed_rad_s - w.abs())
                            / (d.no_load_speed_rad_s - d.full_torque_speed_rad_s))
                            .max(0.0)
                };
                assert!(
                    s.torques[i].abs() <= available,
                    "{kind:?} k {}: joint {i} needs {} N·m of {available}",
                    s.k,
                    s.torques[i]
                );
            }
            Ok(())
        },
    )
    .unwrap();
}

#[test]
fn on_the_plan_the_table_is_played_as_it_is() {
    for kind in KINDS {
        let table = flash_tables::of(kind).unwrap();
        let (outcome, out, calls) = run(kind, measured(&table, 0.0), MAX_EVALS);
        assert_eq!(outcome, Outcome::UseTable(Fallback::OnPlan), "{kind:?}");
        assert_eq!(calls, 1);
        for (k, s) in out.iter().enumerate() {
            assert_eq!(Some(*s), table.sample(k), "{kind:?} sample {k}");
        }
    }
}

#[test]
fn three_degrees_off_starts_where_the_pilot_stands_and_lands_on_the_foothold() {
    for kind in KINDS {
        let table = flash_tables::of(kind).unwrap();
        for deg in [-3.0f32, 3.0] {
            let m = measured(&table, deg);
            let (outcome, out, _) = run(kind, m, MAX_EVALS);
            let Outcome::Replanned {
                cost,
                table_cost,
                evals,
                ..
            } = outcome
            else {
                panic!("{kind:?} {deg}°: {outcome:?}");
            };
            assert!(evals <= MAX_EVALS);
            assert!(cost <= table_cost, "{kind:?} {deg}°: {cost} > {table_cost}");
            assert!(
                (out[0][0] - m.phi1_rad).abs() < 1e-6,
                "{kind:?} {deg}°: starts at {} for {}",
                out[0][0],
                m.phi1_rad
            );
            // The baseline: the table with the chain rotated by the offset.
            let delta = deg.to_radians();
            let rotated: Vec<[f32; 5]> = (0..table.len())
                .map(|k| table.sample(k).unwrap().map(|v| v + delta))
                .collect();
            let baseline = landing_error(kind, &rotated);
            let replanned = landing_error(kind, &out);
            assert!(
                replanned <= 0.001,
                "{kind:?} {deg}°: lands {replanned} m off"
            );
            assert!(
                replanned <= 0.5 * baseline,
                "{kind:?} {deg}°: {replanned} m vs the table's {baseline} m"
            );
            // The table's 9, 11 and 7 mm today (walk, ascent, descent).
            assert!(baseline > 0.005, "{kind:?} {deg}°: baseline {baseline} m");
            assert_within_limits(kind, &out);
        }
    }
}

#[test]
fn spread_over_many_calls_the_result_is_the_same() {
    for kind in KINDS {
        let table = flash_tables::of(kind).unwrap();
        let m = measured(&table, 3.0);
        let (whole, whole_out, calls) = run(kind, m, MAX_EVALS);
        assert_eq!(calls, 1);
        for per_call in [1, 5] {
            let (spread, spread_out, calls) = run(kind, m, per_call);
            assert_eq!(spread, whole, "{kind:?} by {per_call}");
            assert!(calls > 1);
            assert!(
                spread_out == whole_out,
                "{kind:?} by {per_call}: samples differ"
            );
        }
    }
}

#[test]
fn the_plan_starts_at_the_measured_rate() {
    let table = flash_tables::walk().unwrap();
    let mut m = measured(&table, 2.0);
    m.rate_rad_s += 0.2;
    let (outcome, out, _) = run(GaitKind::Walk, m, MAX_EVALS);
    assert!(matches!(outcome, Outcome::Replanned { .. }), "{outcome:?}");
    let rate = (out[1][0] - out[0][0]) / table.period_s();
    assert!(
        (rate - m.rate_rad_s).abs() < 0.02,
        "{rate} rad/s for {}",
        m.rate_rad_s
    );
}

#[test]
fn with_too_small_a_budget_the_table_is_played() {
    let body = model();
    let table = flash_tables::walk().unwrap();
    let mut out = vec![[0.0f32; 5]; table.len()];
    let s = setup(&body, GaitKind::Walk);
    let m = measured(&table, 3.0);
    let mut r = Replanner::new(s, limits(), table, m, &mut out, 1).unwrap();
    assert_eq!(
        r.step(10),
        Progress::Done(Outcome::UseTable(Fallback::NoImprovement))
    );
    assert_eq!(r.evals(), 1);
    assert_eq!(r.samples().first().copied(), Some(table.first()));
}

#[test]
fn unusable_inputs_are_refused() {
    let body = model();
    let table = flash_tables::walk().unwrap();
    let s = setup(&body, GaitKind::Walk);
    let m = measured(&table, 3.0);
    let mut short = vec![[0.0f32; 5]; table.len() - 1];
    let err = |r: Result<Replanner<'_, f32>, ReplanError>| r.err();
    assert_eq!(
        err(Replanner::new(s, limits(), table, m, &mut short, 8)),
        Some(ReplanError::BufferLength)
    );
    let mut out = vec![[0.0f32; 5]; table.len()];
    let far = measured(&table, 12.0);
    assert_eq!(
        err(Replanner::new(s, limits(), table, far, &mut out, 8)),
        Some(ReplanError::OffsetTooLarge)
    );
    let nan = Measured {
        phi1_rad: f32::NAN,
        rate_rad_s: 0.0,
        persist: 0.0,
        posture: None,
    };
    assert_eq!(
        err(Replanner::new(s, limits(), table, nan, &mut out, 8)),
        Some(ReplanError::BadMeasurement)
    );
    assert_eq!(
        err(Replanner::new(
            s,
            limits(),
            table,
            m,
            &mut out,
            MAX_EVALS + 1
        )),
        Some(ReplanError::BadBudget)
    );
    let mut bad = limits();
    bad.hip_rad = [1.0, -1.0];
    assert_eq!(
        err(Replanner::new(s, bad, table, m, &mut out, 8)),
        Some(ReplanError::BadLimits)
    );
}

/// The same code in f64 (the host's precision) gives the f32 answer's
/// outcome kind and landing.
#[test]
fn generic_over_the_scalar() {
    let body: BodyModel<f64> = model().cast();
    let table = flash_tables::stair_down().unwrap();
    let mut out = vec![[0.0f64; 5]; table.len()];
    let s = ReplanSetup {
        model: &body,
        foot: StanceFoot::for_model(&body),
        spring_nm_per_rad: 30.0,
        spacing_m: [0.275, -0.0935],
        crutch_lever_m: 0.45,
        aim_m: [0.0, 0.0],
    };
    let l32 = limits();
    let d = l32.drive;
    let l = ReplanLimits::clinical(
        DriveLimit {
            peak_nm: f64::from(d.peak_nm),
            full_torque_speed_rad_s: f64::from(d.full_torque_speed_rad_s),
            no_load_speed_rad_s: f64::from(d.no_load_speed_rad_s),
        },
        l32.hip_rad.map(f64::from),
        l32.knee_rad.map(f64::from),
        f64::from(l32.ankle_min_rad),
    );
    let m32 = measured(&table, -3.0);
    let m = Measured {
        phi1_rad: f64::from(m32.phi1_rad),
        rate_rad_s: f64::from(m32.rate_rad_s),
        persist: f64::from(m32.persist),
        posture: None,
    };
    let mut r = Replanner::new(s, l, table, m, &mut out, MAX_EVALS).unwrap();
    let p = r.step(MAX_EVALS);
    assert!(
        matches!(p, Progress::Done(Outcome::Replanned { .. })),
        "{p:?}"
    );
    let planned = swing_ankle(&body, &s.foot, &table.last().map(f64::from));
    let got = swing_ankle(&body, &s.foot, r.samples().last().unwrap());
    assert!((got[0] - planned[0]).hypot(got[1] - planned[1]) < 1e-3);
}

#[test]
fn a_measured_posture_is_the_first_sample_and_a_kept_offset_still_lands_on_the_foothold() {
    for kind in KINDS {
        let table = flash_tables::of(kind).unwrap();
        let first = table.first();
        // The joints held where the table starts, the shank 3° forward:
        // every link but the shank's turned with it, the trailing knee
        // given 2° by the closed chain.
        let lean = 3.0f32.to_radians();
        let mut posture = first.map(|v| v + lean);
        posture[4] += 2.0f32.to_radians();
        for persist in [0.0f32, 1.0] {
            let m = Measured {
                persist,
                posture: Some(posture),
                ..measured(&table, 3.0)
            };
            let (outcome, out, _) = run(kind, m, MAX_EVALS);
            assert!(
                matches!(outcome, Outcome::Replanned { .. }),
                "{kind:?} persist {persist}: {outcome:?}"
            );
            for (a, b) in out[0].iter().zip(&posture) {
                assert!((a - b).abs() < 1e-4, "{kind:?}: starts at {:?}", out[0]);
            }
            assert!(
                landing_error(kind, &out) < 1e-3,
                "{kind:?} persist {persist}"
            );
            assert_within_limits(kind, &out);
            // Kept: the stance shank lands 3° ahead of the table's.
            let kept = out.last().unwrap()[0] - table.last()[0];
            assert!((kept - persist * lean).abs() < 1e-4, "{kind:?}: {kept}");
        }
    }
}

//! Report JSON: round trip, independent recomputation, and errors that name
//! what is wrong.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use gait_core::problem::PaperCase;
use gait_opt::{OptimizeConfig, Report, baseline, optimize};

fn report(case: PaperCase) -> Report {
    let mut cfg = OptimizeConfig::new(case);
    cfg.max_evals = 300;
    let r = optimize(&cfg, &mut |_| {}).unwrap();
    Report::new(&r, Some(&baseline(case).unwrap())).unwrap()
}

#[test]
fn round_trip_and_recompute() {
    for case in [PaperCase::Walk, PaperCase::StairUp] {
        let rep = report(case);
        let text = rep.to_json().unwrap();
        let back = Report::from_json(&text).unwrap();
        assert_eq!(back, rep);
        let c = back.recompute_cost().unwrap();
        assert_eq!(c.j.to_bits(), rep.j.j.to_bits());
        assert_eq!(rep.samples.len(), rep.problem.intervals + 1);
        assert!(rep.samples[0].tau_nm.is_none() && rep.samples[2].tau_nm.is_some());
        let red = rep.reduction_pct.unwrap();
        let b = rep.baseline.as_ref().unwrap();
        assert!((red.torque_part - 100.0 * (b.j.torque - rep.j.torque) / b.j.torque).abs() < 1e-9);
        let v: serde_json::Value = serde_json::from_str(&text).unwrap();
        for key in [
            "problem",
            "control_points",
            "J",
            "tau_rms_Nm",
            "tau_peak_Nm",
            "baseline",
            "reduction_pct",
            "solver",
            "samples",
        ] {
            assert!(v.get(key).is_some(), "missing {key}");
        }
    }
}

#[test]
fn bad_files_name_what_is_wrong() {
    let rep = report(PaperCase::Walk);
    // A control point outside eq. (cons).
    let mut r = rep.clone();
    r.control_points[12][1] = 5.0;
    let e = r.recompute_cost().unwrap_err().to_string();
    assert!(e.contains("P[12][1]"), "{e}");
    // A negative mass.
    let mut r = rep.clone();
    r.problem.links[2].mass_kg = -1.0;
    let e = r.recompute_cost().unwrap_err().to_string();
    assert!(e.contains("problem.links"), "{e}");
    // Bounds that do not follow from the case.
    let mut r = rep.clone();
    r.problem.upper_bound[11][1] = 0.9;
    let e = r.recompute_cost().unwrap_err().to_string();
    assert!(e.contains("problem.upper_bound[11][1]"), "{e}");
    // Unknown differences scheme.
    let mut r = rep.clone();
    r.problem.differences = "forward".into();
    let e = r.recompute_cost().unwrap_err().to_string();
    assert!(e.contains("problem.differences"), "{e}");
    // A missing field and an unknown field: serde names them.
    let mut v: serde_json::Value = serde_json::from_str(&rep.to_json().unwrap()).unwrap();
    v["problem"].as_object_mut().unwrap().remove("dt_s");
    let e = Report::from_json(&v.to_string()).unwrap_err().to_string();
    assert!(e.contains("dt_s"), "{e}");
    let mut v: serde_json::Value = serde_json::from_str(&rep.to_json().unwrap()).unwrap();
    v["problem"]["dtt"] = serde_json::json!(1);
    let e = Report::from_json(&v.to_string()).unwrap_err().to_string();
    assert!(e.contains("dtt"), "{e}");
    assert!(Report::from_json("not json").is_err());
}

#[cfg(feature = "plot")]
#[test]
fn plots_svg_and_png() {
    let rep = report(PaperCase::StairUp);
    let dir = std::env::temp_dir().join(format!("gait-opt-plot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("r.svg");
    let png = dir.join("r.png");
    gait_opt::plot_report(&rep, &svg).unwrap();
    gait_opt::plot_report(&rep, &png).unwrap();
    let s = std::fs::read_to_string(&svg).unwrap();
    assert!(s.contains("<svg") && s.contains("stance-ankle torque"));
    let p = std::fs::read(&png).unwrap();
    assert!(
        p.starts_with(b"\x89PNG") && p.len() > 10_000,
        "{} bytes",
        p.len()
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn one_call_for_the_cli() {
    let mut cfg = OptimizeConfig::new(PaperCase::Walk);
    cfg.max_evals = 300;
    let rep = gait_opt::optimise_and_report(&cfg, &mut |_| {}).unwrap();
    assert_eq!(rep.problem.case, "walk");
    assert!(rep.baseline.is_some());
    assert_eq!(
        rep.solver.evaluations,
        optimize(&cfg, &mut |_| {}).unwrap().evaluations
    );
}

/// The descent table's problem (toe rocker, human knee range, joint
/// limits) survives the JSON round trip: its fields are written, read back,
/// and the cost recomputed from the file is the same, bit for bit; the
/// cost from the sampled Φ (`cost_from_phi`) agrees with it too.
#[test]
fn descent_problem_round_trips_with_its_new_fields() {
    use gait_core::problem::PeriodicStep;
    let problem = gait_opt::tables::table_problem(&PeriodicStep::stair_down(), None).unwrap();
    let mut cfg = OptimizeConfig::new(PaperCase::StairUp);
    cfg.max_evals = 300;
    let r = gait_opt::solver::optimize_problem(&problem, &cfg, &mut |_| {}).unwrap();
    let rep = Report::for_problem("stair_down", &problem, &r, None).unwrap();
    let text = rep.to_json().unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for key in [
        "foot",
        "stance_knee_max_rad",
        "knee_range_human",
        "joint_range_limit",
    ] {
        assert!(v["problem"].get(key).is_some(), "missing problem.{key}");
    }
    let back = Report::from_json(&text).unwrap();
    assert_eq!(back, rep);
    let again = back.problem.problem().unwrap();
    assert_eq!(again.case.foot, problem.case.foot);
    assert_eq!(again.case.ik, problem.case.ik);
    assert_eq!(again.joint_range_limit, problem.joint_range_limit);
    let c = back.recompute_cost().unwrap();
    assert_eq!(c.j.to_bits(), r.cost.j.to_bits());
    // Corrupt values are refused by name.
    for (key, value) in [
        ("foot", serde_json::json!([0.0, 0.07, 0.35])),
        ("foot", serde_json::json!([-0.1, 0.07, 0.35])),
        ("stance_knee_max_rad", serde_json::json!(4.0)),
        ("joint_range_limit", serde_json::json!([-0.1, 1e5])),
    ] {
        let mut w = v.clone();
        w["problem"][key] = value;
        let parsed = Report::from_json(&w.to_string()).unwrap();
        let e = parsed.problem.problem().unwrap_err().to_string();
        assert!(e.contains(key), "{key}: {e}");
    }
    let phi = gait_opt::tables::step_phi(&problem, &r.control_points).unwrap();
    let from_phi = gait_opt::cost_from_phi(&problem, &phi).unwrap();
    assert!(
        (from_phi.j - r.cost.j).abs() < 1e-6 * r.cost.j,
        "{} vs {}",
        from_phi.j,
        r.cost.j
    );
}

//! Runs the built `exogait optimize` and `exogait cost` and checks the
//! report, the recomputed J and the refusals. Small budgets (--evals) keep
//! each search under a second.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use serde_json::Value;

use crate::common::{Run, exogait, s};

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("exogait-opt-test-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// One paper-mode walk search (2,000 evaluations) with its report and
/// plot, shared by the tests that read them.
fn walk_report() -> &'static (PathBuf, PathBuf, Run) {
    static RUN: OnceLock<(PathBuf, PathBuf, Run)> = OnceLock::new();
    RUN.get_or_init(|| {
        let out = dir().join("walk.json");
        let plot = dir().join("walk.svg");
        let run = exogait(&[
            "optimize",
            "--case",
            "walk",
            "--evals",
            "2000",
            "--out",
            s(&out),
            "--plot",
            s(&plot),
        ]);
        (out, plot, run)
    })
}

fn read_json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

#[test]
fn walk_paper_mode_writes_a_report_that_cost_agrees_with() {
    let (out, _, run) = walk_report();
    assert_eq!(run.status, 0, "{}", run.stderr);
    assert!(run.stdout.contains("paper mode"), "{}", run.stdout);
    assert!(run.stdout.contains("record J = 3361.9"), "{}", run.stdout);
    let r = read_json(out);
    assert_eq!(r["problem"]["case"], "walk");
    assert_eq!(r["problem"]["start_m"][0], -0.3);
    let p = r["control_points"].as_array().unwrap();
    assert_eq!(p.len(), 19);
    assert!(p.iter().all(|row| row.as_array().unwrap().len() == 2));
    for key in ["J", "torque", "velocity"] {
        assert!(r["J"][key].is_f64(), "J.{key}");
    }
    assert!(r["tau_rms_Nm"].is_f64() && r["tau_peak_Nm"].is_f64());
    assert_eq!(r["baseline"]["source"], "fukuchi2018_walk");
    assert!(r["baseline"]["J"]["J"].is_f64());
    for key in ["torque_part", "tau_rms", "tau_peak"] {
        assert!(r["reduction_pct"][key].is_f64(), "reduction_pct.{key}");
    }
    assert!(r["solver"]["evaluations"].as_u64().unwrap() <= 2000);
    assert!(r["solver"]["wall_s"].is_f64() && r["solver"]["name"].is_string());
    let samples = r["samples"].as_array().unwrap();
    assert_eq!(samples.len(), 225);
    assert!(samples[10]["tau_Nm"].as_array().unwrap().len() == 5);
    assert!(samples[10]["phi_rad"].is_array() && samples[10]["theta_rad"].is_array());

    let c = exogait(&["cost", s(out)]);
    assert_eq!(c.status, 0, "{}", c.stderr);
    let answer: Value = serde_json::from_str(c.stdout.trim()).unwrap();
    assert_eq!(answer["agrees"], true);
    assert!(answer["relative_difference"].as_f64().unwrap() <= 1e-9);
    assert_eq!(answer["J"], r["J"]["J"]);
    assert!(answer["torque"].is_f64() && answer["velocity"].is_f64());
}

#[test]
fn plot_is_a_non_empty_svg() {
    let (_, plot, run) = walk_report();
    assert_eq!(run.status, 0, "{}", run.stderr);
    let svg = std::fs::read_to_string(plot).unwrap();
    assert!(svg.len() > 1000 && svg.contains("<svg"));
}

#[test]
fn paper_mode_with_a_geometry_override_is_refused() {
    let out = dir().join("refused.json");
    let run = exogait(&[
        "optimize",
        "--case",
        "walk",
        "--mode",
        "paper",
        "--stride",
        "0.5",
        "--out",
        s(&out),
    ]);
    assert_eq!(run.status, 2);
    assert!(run.stderr.contains("--mode paper") && run.stderr.contains("--stride"));
    assert!(!out.exists());
    let run = exogait(&[
        "optimize",
        "--case",
        "stair-down",
        "--mode",
        "paper",
        "--out",
        s(&out),
    ]);
    assert_eq!(run.status, 2);
    assert!(run.stderr.contains("no paper mode"), "{}", run.stderr);
}

#[test]
fn stair_down_with_defaults_writes_a_report() {
    let out = dir().join("stair_down.json");
    let run = exogait(&[
        "optimize",
        "--case",
        "stair-down",
        "--evals",
        "2000",
        "--out",
        s(&out),
    ]);
    assert_eq!(run.status, 0, "{}", run.stderr);
    let r = read_json(&out);
    assert_eq!(r["problem"]["case"], "stair_down");
    assert_eq!(r["problem"]["start_m"][1], 0.0935);
    assert_eq!(r["problem"]["landing_m"][1], -0.0935);
    assert_eq!(r["problem"]["step_time_s"], 2.28);
    assert!(r["baseline"].is_null());
    assert!(r["baseline_note"].as_str().unwrap().contains("descent"));
    let c = exogait(&["cost", s(&out)]);
    assert_eq!(c.status, 0, "{}", c.stderr);
}

/// The walk report with `edit` applied to its JSON value.
fn corrupted(name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let (out, _, run) = walk_report();
    assert_eq!(run.status, 0, "{}", run.stderr);
    let mut v = read_json(out);
    edit(&mut v);
    let p = dir().join(name);
    std::fs::write(&p, serde_json::to_string(&v).unwrap()).unwrap();
    p
}

#[test]
fn cost_names_what_is_wrong_with_a_bad_file() {
    let (out, _, _) = walk_report();
    // Not JSON: the report cut in half.
    let text = std::fs::read_to_string(out).unwrap();
    let cut = dir().join("cut.json");
    std::fs::write(&cut, &text[..text.len() / 2]).unwrap();
    let run = exogait(&["cost", s(&cut)]);
    assert_eq!(run.status, 2);
    assert!(
        run.stderr.contains("cut.json") && run.stderr.contains("not a valid report"),
        "{}",
        run.stderr
    );

    // A control point moved out of its bounds (r2's time control point).
    let moved = corrupted("moved.json", |v| v["control_points"][1][0] = (-1.0).into());
    let run = exogait(&["cost", s(&moved)]);
    assert_eq!(run.status, 2);
    assert!(
        run.stderr.contains("moved.json") && run.stderr.contains("P[1][0] is outside its bounds"),
        "{}",
        run.stderr
    );

    // A missing field.
    let missing = corrupted("missing.json", |v| {
        v.as_object_mut().unwrap().remove("control_points");
    });
    let run = exogait(&["cost", s(&missing)]);
    assert_eq!(run.status, 2);
    assert!(
        run.stderr.contains("missing.json")
            && run.stderr.contains("missing field `control_points`"),
        "{}",
        run.stderr
    );

    // An inconsistent problem: a bound that is not eq. (cons) for the case.
    let bound = corrupted("bound.json", |v| {
        v["problem"]["upper_bound"][11][1] = 0.7.into();
    });
    let run = exogait(&["cost", s(&bound)]);
    assert_eq!(run.status, 2);
    assert!(
        run.stderr.contains("problem.upper_bound[11][1]"),
        "{}",
        run.stderr
    );

    // Unreadable.
    let run = exogait(&["cost", s(&dir().join("absent.json"))]);
    assert_eq!(run.status, 2);
    assert!(run.stderr.contains("absent.json") && run.stderr.contains("cannot read"));
}

#[test]
fn cost_exits_1_when_the_stored_j_disagrees() {
    let off = corrupted("off.json", |v| {
        let j = v["J"]["J"].as_f64().unwrap();
        v["J"]["J"] = (j * (1.0 + 1e-6)).into();
    });
    let run = exogait(&["cost", s(&off)]);
    assert_eq!(run.status, 1, "{}", run.stderr);
    let answer: Value = serde_json::from_str(run.stdout.trim()).unwrap();
    assert_eq!(answer["agrees"], false);
    assert!(run.stderr.contains("off.json"));
}

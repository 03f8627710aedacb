//! `exogait compare`: the paper's Table II in the closed loop, as JSON, and
//! the reductions the shipped tables hold against the human-data gait on
//! the same device (targets and margins in docs/optimiser.md).

use std::process::Command;

/// Runs `exogait` with `args` (and a path, when given, appended).
fn exogait(args: &[&str], path: &[&std::path::Path]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args(args)
        .args(path)
        .output()
        .unwrap()
}

fn compare(gait: &str) -> (serde_json::Value, i32) {
    let out = exogait(&["compare", "--gait", gait, "--steps", "4", "--json"], &[]);
    let text = String::from_utf8(out.stdout).unwrap();
    let v: serde_json::Value =
        serde_json::from_str(text.trim()).unwrap_or_else(|e| panic!("{e}: {text}"));
    (v, out.status.code().unwrap_or(-1))
}

fn f(v: &serde_json::Value, path: &[&str]) -> f64 {
    let mut x = v;
    for p in path {
        x = &x[*p];
    }
    x.as_f64().unwrap_or_else(|| panic!("{path:?}: {x}"))
}

/// The shape of the answer, and that the shipped table landed every step
/// without a fault.
fn check_shape(v: &serde_json::Value, gait: &str) {
    assert_eq!(v["gait"], gait);
    assert_eq!(v["steps"], 4);
    for who in ["shipped", "human"] {
        for key in [
            "F_Ns",
            "F_balance_Ns",
            "peak_N",
            "saturated_s",
            "landings",
            "faults",
        ] {
            assert!(v[who][key].is_array(), "{who}.{key}");
        }
    }
    assert_eq!(v["shipped"]["F_Ns"].as_array().unwrap().len(), 4);
    assert!(
        v["shipped"]["faults"].as_array().unwrap().is_empty(),
        "{}",
        v["shipped"]["faults"]
    );
    assert!(v["shipped"]["landings"].as_array().unwrap().len() >= 4);
    for key in ["F", "F_balance", "peak"] {
        assert!(v["reduction_pct"][key].is_number(), "reduction_pct.{key}");
    }
    assert!((f(v, &["device", "drive_peak_Nm"]) - 150.0).abs() < 1e-3);
    // The balance part is F less the pilot's constant lean: smaller.
    for (a, b) in v["shipped"]["F_Ns"]
        .as_array()
        .unwrap()
        .iter()
        .zip(v["shipped"]["F_balance_Ns"].as_array().unwrap())
    {
        assert!(b.as_f64().unwrap() < a.as_f64().unwrap());
    }
}

/// The balance part of the crutch load falls by at least `min_pct`, and the
/// highest crutch peak does not rise.
fn check_reductions(v: &serde_json::Value, min_pct: f64) {
    let r = &v["reduction_pct"];
    assert!(f(v, &["reduction_pct", "F_balance"]) >= min_pct, "{r}");
    assert!(f(v, &["reduction_pct", "peak"]) >= 0.0, "{r}");
}

#[test]
fn walking_lightens_the_arms_by_more_than_the_papers_quarter() {
    let (v, code) = compare("walk");
    check_shape(&v, "walk");
    // The human walk leans forward until the closed loop plays it: every
    // step lands, so the reduction is over four steps of each.
    assert_eq!(code, 0, "both gaits land every step without a fault");
    assert!(f(&v, &["human_torso_lean_rad"]) > 0.0);
    // Target 25 % (the paper's 25.1 %); measured 80.2 %.
    check_reductions(&v, 60.0);
}

#[test]
fn compare_reports_pace_clearance_and_geometry() {
    let (v, _) = compare("stair-up");
    let g = &v["geometry"];
    assert!((f(g, &["step_length_m"]) - 0.275).abs() < 0.01, "{g}");
    assert!((f(g, &["rise_m"]) - 0.0935).abs() < 0.005, "{g}");
    assert_eq!(f(g, &["tread_m"]), f(g, &["step_length_m"]));
    assert!((f(g, &["step_time_s"]) - 2.28).abs() < 0.01, "{g}");
    for who in ["shipped", "human"] {
        let pace = f(&v, &[who, "progression_m_s"]);
        assert!((0.08..0.13).contains(&pace), "{who}: {pace}");
        // Over a nosing on stairs: a finite number (a level walk's is null).
        assert!(v[who]["clearance_min_m"].is_number(), "{who}");
    }
    let (w, _) = compare("walk");
    assert!(w["shipped"]["clearance_min_m"].is_null());
    assert_eq!(f(&w, &["geometry", "rise_m"]), 0.0);
    assert_eq!(w["kind"], "walk");
    assert!(w["patient_hash"].is_null());
}

#[test]
fn stair_ascent_lightens_the_arms_by_three_quarters() {
    let (v, code) = compare("stair-up");
    check_shape(&v, "stair_up");
    assert_eq!(code, 0, "both gaits land every step without a fault");
    // Target 75 % (the paper's 74.7 %); the table refined in the closed
    // loop gives 78.3 % (docs/optimiser.md, "Where the targets stand").
    check_reductions(&v, 75.0);
}

#[test]
fn stair_descent_lightens_the_arms_by_more_than_half() {
    let (v, code) = compare("stair-down");
    check_shape(&v, "stair_down");
    assert_eq!(code, 0, "both gaits land every step without a fault");
    // Target: below the human gait, aim 50 %; measured 76.4 %.
    check_reductions(&v, 50.0);
}

#[test]
fn a_gait_the_device_cannot_play_is_refused_before_the_run() {
    let dir = std::env::temp_dir().join(format!("exogait-refuse-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let report = dir.join("paper.json");
    let out = exogait(
        &["optimize", "--case", "walk", "--evals", "2000", "--out"],
        &[&report],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The paper-mode optimum swings too fast for the device.
    let table = dir.join("paper.bin");
    let out = exogait(&["table", "--out"], &[&table, &report]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("sample ") && err.contains("limit"), "{err}");
    assert!(!table.exists(), "nothing written");
    let out = exogait(&["simulate", "--table"], &[&report]);
    assert_eq!(out.status.code(), Some(2));
    // A clinical report becomes a table the device plays.
    let clinical = dir.join("clinical.json");
    let out = exogait(
        &[
            "optimize", "--case", "walk", "--mode", "clinical", "--evals", "3000", "--out",
        ],
        &[&clinical],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = exogait(&["table", "--out"], &[&table, &clinical]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = exogait(&["simulate", "--steps", "2", "--table"], &[&table]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

//! `exogait simulate` end to end: the built binary runs the closed loop,
//! prints its metrics, writes the plot, and says by its exit status whether
//! the step landed on the plan.

use std::process::Command;

#[test]
fn simulate_prints_metrics_and_writes_the_plot() {
    let plot = std::env::temp_dir().join(format!("exogait-sim-{}.svg", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args(["simulate", "--plot"])
        .arg(&plot)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for needle in ["landed", "crutch load F", "tracking RMS", "faults latched"] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
    let svg = std::fs::read_to_string(&plot).unwrap();
    let _ = std::fs::remove_file(&plot);
    assert!(svg.starts_with("<svg"));
}

#[test]
fn simulate_refuses_bad_options() {
    let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args(["simulate", "--seconds=-1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--seconds"));
}

#[test]
fn a_pilot_out_of_range_or_a_bad_replan_value_is_refused_before_the_run() {
    for (cmd, args, says) in [
        ("simulate", ["--pilot-lean", "30"], "--pilot-lean"),
        ("simulate", ["--pilot-stiffness", "0"], "--pilot-stiffness"),
        ("compare", ["--pilot-lean", "-11"], "--pilot-lean"),
        ("simulate", ["--replan", "maybe"], "--replan"),
    ] {
        let mut all = vec![cmd, "--gait", "walk"];
        all.extend(args);
        let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
            .args(&all)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{all:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{all:?}: {err}");
        assert!(out.stdout.is_empty(), "{all:?}: nothing run");
    }
}

fn simulate_json(args: &[&str]) -> (serde_json::Value, Option<i32>) {
    let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .arg("simulate")
        .args(args)
        .arg("--json")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let v = serde_json::from_str(text.trim())
        .unwrap_or_else(|e| panic!("{e}: {text}\n{}", String::from_utf8_lossy(&out.stderr)));
    (v, out.status.code())
}

/// The fault of `code` in a `--json` answer.
fn fault<'a>(v: &'a serde_json::Value, code: &str) -> &'a serde_json::Value {
    v["faults"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["code"] == code)
        .unwrap_or_else(|| panic!("no {code} in {v:#}"))
}

#[test]
fn a_healthy_run_reports_no_fault_and_exits_0() {
    let (v, code) = simulate_json(&["--steps", "2"]);
    assert_eq!(code, Some(0), "{v:#}");
    assert!(v["landings"].as_u64().unwrap() >= 2);
    assert_eq!(v["faults"].as_array().unwrap().len(), 0);
    assert_eq!(v["fell"], false);
    assert!(v["worst_limit_margin_rad"].as_f64().unwrap() > 0.0);
    for j in 0..4 {
        let rms = v["tracking_rms_rad"][j].as_f64().unwrap();
        let peak = v["tracking_peak_rad"][j].as_f64().unwrap();
        assert!(
            rms > 0.0 && rms <= peak && peak < 0.1,
            "joint {j}: {rms} {peak}"
        );
    }
}

#[test]
fn an_injected_estop_is_detected_in_its_tick_and_disables_the_motors_once_the_foot_is_down() {
    let (v, code) = simulate_json(&["--steps", "2", "--inject", "estop@3"]);
    assert_eq!(code, Some(1), "a faulted run must not exit 0: {v:#}");
    assert_eq!(v["injected"][0]["fault"], "estop@3");
    let f = fault(&v, "0x0501");
    assert_eq!(f["latency_ticks"], 0);
    assert_eq!(f["reaction"], "motors-disabled");
    assert!((f["injected_s"].as_f64().unwrap() - 3.0).abs() < 1e-3);
    // In the swing (1.36–3.54 s) the swing foot is set down first, for
    // 0.8 s at most (docs/safety.md, "The e-stop in a swing").
    let stopped = f["safe_state_s"].as_f64().unwrap() - f["detected_s"].as_f64().unwrap();
    assert!((0.05..=0.802).contains(&stopped), "{stopped}");
}

#[test]
fn an_injected_parity_fault_is_detected_within_its_debounce_and_holds() {
    let (v, code) = simulate_json(&["--inject", "encoder-parity:left-knee@2.5", "--steps", "2"]);
    assert_eq!(code, Some(1));
    let f = fault(&v, "0x0202");
    // docs/safety.md: the bad-frame debounce (3 of the last ticks).
    assert!(f["latency_ticks"].as_u64().unwrap() <= 3, "{f}");
    assert_eq!(f["reaction"], "safe-hold");
    // In the swing (1.36–3.54 s) a lost encoder holds at once
    // (docs/safety.md, "Reactions"): the hold's 0.3 s ramp.
    let held = f["safe_state_s"].as_f64().unwrap() - f["detected_s"].as_f64().unwrap();
    assert!((0.0..=0.31).contains(&held), "{held}");
}

#[test]
fn bad_injections_are_refused_with_exit_2_and_say_why() {
    for (inj, says) in [
        ("warp-drive@2", "unknown kind"),
        ("encoder-parity@2", "needs a target"),
        ("motor-weak=2:left-knee@2", "fraction"),
        ("estop@30", "after the run"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
            .args(["simulate", "--inject", inj])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{inj}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{inj}: {err}");
    }
}

#[test]
fn faults_runs_a_seeded_campaign_and_tallies_it() {
    let run = |seed: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
            .args([
                "faults",
                "--runs",
                "6",
                "--healthy",
                "1",
                "--seed",
                seed,
                "--json",
            ])
            .output()
            .unwrap();
        let v: serde_json::Value =
            serde_json::from_str(String::from_utf8_lossy(&out.stdout).trim()).unwrap();
        (v, out.status.code())
    };
    let (v, code) = run("3");
    assert_eq!(v["all"]["runs"], 6);
    let by_kind: u64 = v["by_kind"]
        .as_array()
        .unwrap()
        .iter()
        .map(|k| k[1]["runs"].as_u64().unwrap())
        .sum();
    assert_eq!(by_kind, 6);
    // One healthy run of each gait beside them.
    assert_eq!(v["healthy"]["all"]["runs"], 3);
    assert_eq!(v["healthy"]["by_gait"].as_array().unwrap().len(), 3);
    // Exit 0 only when the campaign's goal (falls and stops crossed but
    // the named cases) and the healthy runs' are met.
    let bad = [
        "unnamed_falls",
        "unnamed_past_a_stop",
        "missed",
        "false_trips",
        "errors",
    ]
    .iter()
    .map(|k| v["all"][*k].as_u64().unwrap())
    .sum::<u64>()
        + ["falls", "past_a_stop", "false_trips", "short", "errors"]
            .iter()
            .map(|k| v["healthy"]["all"][*k].as_u64().unwrap())
            .sum::<u64>();
    assert_eq!(code, Some(if bad == 0 { 0 } else { 1 }), "{v:#}");
    // The same seed, the same campaign.
    assert_eq!(run("3").0, v);
    for args in [
        ["--runs", "0", "--healthy", "0"],
        ["--runs", "100001", "--healthy", "0"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
            .arg("faults")
            .args(args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
    }
}

#[test]
fn the_plot_marks_phases_and_faults_in_degrees_with_references_apart() {
    let plot = std::env::temp_dir().join(format!("exogait-marks-{}.svg", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args([
            "simulate",
            "--steps",
            "2",
            "--inject",
            "encoder-jump=300:right-knee@2.4",
            "--plot",
        ])
        .arg(&plot)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "the jump's hold is a fault");
    let svg = std::fs::read_to_string(&plot).unwrap();
    let _ = std::fs::remove_file(&plot);
    // The phases' shading (swing, transfer or hold colours), the fault's
    // label, degrees on the joint panels, the references' own colours.
    for needle in [
        "#FFF4CC", "#FAD2D2", "0x0205", "degrees", "#FF9600", "#00A0A0",
    ] {
        assert!(
            svg.to_ascii_uppercase()
                .contains(&needle.to_ascii_uppercase()),
            "missing {needle}"
        );
    }
}

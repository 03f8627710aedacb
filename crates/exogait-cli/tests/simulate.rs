//! `exogait simulate` end to end: the built binary runs the closed loop,
//! prints its metrics, writes the plot, and says by its exit status whether
//! the step landed on the plan.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

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

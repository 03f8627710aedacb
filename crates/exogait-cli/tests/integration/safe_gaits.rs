//! The tool never hands a user a gait the device cannot play: an
//! infeasible search exits 1 and says why, `table` and `simulate --table`
//! refuse a table whose first step does not land, and a short run says
//! why; the default run time fits the steps asked.

use std::path::PathBuf;
use std::process::Command;

fn exogait(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("safe-gaits");
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn a_search_that_finds_no_playable_step_exits_1_and_says_why() {
    let report = dir().join("up17.json");
    let r = report.to_str().unwrap();
    let (code, _, err) = exogait(&[
        "optimize", "--case", "stair-up", "--rise", "0.17", "--tread", "0.28", "--mode",
        "clinical", "--evals", "2000", "--out", r,
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("no playable step"), "{err}");
    // The report stays for inspection, and `table` refuses it too.
    assert!(report.exists());
    let bin = dir().join("up17.bin");
    let (code, _, err) = exogait(&["table", r, "--out", bin.to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("cannot play"), "{err}");
    assert!(!bin.exists(), "nothing written");
    let (code, _, err) = exogait(&["simulate", "--table", r]);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn the_default_run_time_fits_the_steps_and_a_short_run_says_why() {
    let (code, out, err) = exogait(&["simulate", "--steps", "8"]);
    assert_eq!(code, 0, "{out}{err}");
    let (code, _, err) = exogait(&["simulate", "--steps", "8", "--seconds", "10"]);
    assert_eq!(code, 1);
    assert!(err.contains("of 8 steps landed within 10 s"), "{err}");
}

#[test]
fn cost_recomputes_a_clinical_report_and_catches_an_edit() {
    let report = dir().join("walk-clinical.json");
    let r = report.to_str().unwrap();
    let (code, _, err) = exogait(&[
        "optimize", "--case", "walk", "--mode", "clinical", "--evals", "1500", "--out", r,
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = exogait(&["cost", r]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["mode"], "clinical");
    assert_eq!(v["agrees"], true);
    // A stored J that is not the step's: exit 1.
    let text = std::fs::read_to_string(&report).unwrap();
    let mut j: serde_json::Value = serde_json::from_str(&text).unwrap();
    j["j"] = serde_json::json!(j["j"].as_f64().unwrap() * 1.01);
    let edited = dir().join("walk-edited.json");
    std::fs::write(&edited, j.to_string()).unwrap();
    let (code, _, _) = exogait(&["cost", edited.to_str().unwrap()]);
    assert_eq!(code, 1);
}

#[test]
fn help_states_each_commands_exit_status_as_it_behaves() {
    let (_, top, _) = exogait(&["--help"]);
    let line = |cmd: &str| {
        top.lines()
            .find(|l| l.trim_start().starts_with(cmd))
            .unwrap_or_else(|| panic!("{cmd} not in the help"))
            .to_string()
    };
    assert!(line("simulate").contains("exit 0 when every step"), "{top}");
    assert!(line("compare").contains("exit 0 when both land"), "{top}");
    assert!(line("faults").contains("named case"), "{top}");
    assert!(
        line("tables").contains("exit 1 if none is cleared"),
        "{top}"
    );
    // What compare's help promises, it does: the walk's comparison lands
    // every step of both gaits and exits 0.
    let (code, _, err) = exogait(&["compare", "--gait", "walk", "--steps", "2"]);
    assert_eq!(code, 0, "{err}");
}

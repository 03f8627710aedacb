//! Runs the built `exogait` binary with stdin and checks its answers and
//! exit status.

use std::f64::consts::PI;
use std::path::PathBuf;
use std::process::Command;

use gait_core::BodyModel;
use gait_core::anthropometry::{ExoSegments, Pilot, body_model_for};
use gait_core::dynamics::{Contact, inverse_dynamics};
use gait_core::kinematics::{forward_kinematics, joint_torques};
use serde_json::Value;

use crate::common::run_piped;

struct Run {
    status: i32,
    stdout: Vec<Value>,
    stderr: String,
}

fn exogait(args: &[&str], stdin: &str) -> Run {
    let out = run_piped(args, stdin.as_bytes());
    let text = String::from_utf8(out.stdout).expect("utf-8 stdout");
    Run {
        status: out.status.code().expect("exit code"),
        stdout: text
            .lines()
            .map(|l| serde_json::from_str(l).expect("every output line is JSON"))
            .collect(),
        stderr: String::from_utf8(out.stderr).expect("utf-8 stderr"),
    }
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// A file in the test's own temporary directory.
fn temp_file(name: &str, contents: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("exogait-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

#[test]
fn good_and_bad_lines_are_both_answered() {
    let input = "{\"phi\":[0,0,0,3.14,3.14]}\n\
                 \n\
                 {\"phi\":[0,0,0]}\n\
                 {\"phi\":[0,0,0,3.14,3.14],\"ph\":1}\n\
                 {\"phi\":[0,0,0,3.14,1e400]}\n\
                 {\"phi\":[0.1,0,0,3.14,3.14]}\n";
    let r = exogait(&["fk"], input);
    assert_eq!(r.status, 1, "{}", r.stderr);
    assert_eq!(r.stdout.len(), 5);
    assert!(r.stdout[0].get("p").is_some());
    for (i, line) in [(1, 3), (2, 4), (3, 5)] {
        assert_eq!(r.stdout[i]["line"], line, "{:?}", r.stdout[i]);
        assert!(r.stdout[i]["error"].is_string());
    }
    assert!(r.stdout[1]["error"].as_str().unwrap().contains("length 5"));
    assert!(
        r.stdout[2]["error"]
            .as_str()
            .unwrap()
            .contains("unknown field")
    );
    assert!(r.stdout[4].get("p").is_some());
    assert!(r.stderr.contains("3 of 5 lines failed"));
}

#[test]
fn all_good_exits_zero() {
    let r = exogait(&["fk"], "{\"phi\":[0,0,0,3,3]}\n{\"phi\":[0,0,0,3,3]}\n");
    assert_eq!(r.status, 0);
    assert_eq!(r.stdout.len(), 2);
}

#[test]
fn fk_standing_posture() {
    let r = exogait(&["fk"], &format!("{{\"phi\":[0,0,0,{PI},{PI}]}}\n"));
    assert_eq!(r.status, 0);
    let p = r.stdout[0]["p"].as_array().unwrap();
    let hip = floats(&p[1]);
    let ankle = floats(&p[4]);
    assert!(hip[0].abs() < 1e-12 && (hip[1] - 0.836).abs() < 1e-12);
    assert!(ankle[0].abs() < 1e-12 && ankle[1].abs() < 1e-12);
    // Equal to the library's answer.
    let lib = forward_kinematics(
        &BodyModel::<f64>::paper_table_iii(),
        &[0.0, 0.0, 0.0, PI, PI],
    );
    for (got, want) in p.iter().zip(lib) {
        assert_eq!(floats(got), want.to_vec());
    }
}

#[test]
fn dynamics_equals_library_call() {
    let phi = [0.1, -0.2, 0.05, 2.9, 3.3];
    let dphi = [0.5, -0.3, 0.1, 1.2, -0.8];
    let ddphi = [1.0, 2.0, -0.5, 3.0, -2.0];
    let line = serde_json::json!({"phi": phi, "dphi": dphi, "ddphi": ddphi}).to_string();
    let r = exogait(&["dynamics"], &format!("{line}\n"));
    assert_eq!(r.status, 0, "{}", r.stderr);
    let model = BodyModel::<f64>::paper_table_iii();
    let t_phi = inverse_dynamics(&model, &Contact::FixedAnkle, &phi, &dphi, &ddphi);
    let t_theta = joint_torques(&t_phi);
    assert_eq!(floats(&r.stdout[0]["t_phi"]), t_phi.to_vec());
    assert_eq!(floats(&r.stdout[0]["t_theta"]), t_theta.to_vec());
}

#[test]
fn ik_answers_and_reports_unreachable_targets() {
    let input = "{\"x5\":0.3,\"y5\":0.0,\"phi1\":0.2,\"phi3\":0.0,\"r2\":0.5}\n\
                 {\"x5\":3.0,\"y5\":0.0,\"phi1\":0.0,\"phi3\":0.0,\"r2\":0.5}\n";
    let r = exogait(&["ik"], input);
    assert_eq!(r.status, 1);
    let phi = floats(&r.stdout[0]["phi"]);
    assert_eq!(floats(&r.stdout[0]["theta"]).len(), 5);
    // The posture puts the swing ankle on the target.
    let p = forward_kinematics(
        &BodyModel::<f64>::paper_table_iii(),
        &phi.clone().try_into().unwrap(),
    );
    assert!((p[4][0] - 0.3).abs() < 1e-9 && p[4][1].abs() < 1e-9);
    assert_eq!(r.stdout[1]["line"], 2);
    assert!(r.stdout[1]["error"].as_str().unwrap().contains("reach"));
}

#[test]
fn bad_model_file_exits_2_naming_file_and_problem() {
    let path = temp_file("bad.json", "{\"pilot\":{\"height_m\":3.0,\"mass_kg\":70}}");
    let r = exogait(&["fk", "--model", path.to_str().unwrap()], "");
    assert_eq!(r.status, 2);
    assert!(r.stderr.contains("bad.json"), "{}", r.stderr);
    assert!(r.stderr.contains("height"), "{}", r.stderr);

    let path = temp_file("typo.json", "{\"links\":[], \"limts\":{}}");
    let r = exogait(&["dynamics", "--model", path.to_str().unwrap()], "");
    assert_eq!(r.status, 2);
    assert!(r.stderr.contains("typo.json") && r.stderr.contains("bad JSON"));

    // `--model` belongs to the model commands only: the others do not
    // list it, and refuse it as an unknown option.
    let help = |cmd: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
            .args([cmd, "--help"])
            .output()
            .expect("help");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    for cmd in [
        "simulate", "compare", "table", "faults", "fit", "tables", "bundle", "cost",
    ] {
        assert!(!help(cmd).contains("--model"), "{cmd} lists --model");
    }
    for cmd in ["fk", "ik", "dynamics", "optimize"] {
        assert!(help(cmd).contains("--model"), "{cmd} does not list --model");
    }
    let r = exogait(&["simulate", "--model", path.to_str().unwrap()], "");
    assert_eq!(r.status, 2);

    let r = exogait(&["fk", "--model", "/nonexistent/model.json"], "");
    assert_eq!(r.status, 2);
    assert!(r.stderr.contains("/nonexistent/model.json") && r.stderr.contains("cannot read"));
}

#[test]
fn model_from_pilot() {
    let path = temp_file(
        "pilot.json",
        "{\"pilot\":{\"height_m\":1.75,\"mass_kg\":76.5}}",
    );
    let r = exogait(
        &["fk", "--model", path.to_str().unwrap()],
        &format!("{{\"phi\":[0,0,0,{PI},{PI}]}}\n"),
    );
    assert_eq!(r.status, 0, "{}", r.stderr);
    let model = body_model_for(&Pilot::<f64>::paper(), &ExoSegments::paper_default()).unwrap();
    let [l1, l2, ..] = model.lengths();
    let hip = floats(&r.stdout[0]["p"][1]);
    // 0.491 H = 0.85925 m, not Table III's 0.836 m.
    assert!((hip[1] - (l1 + l2)).abs() < 1e-12);
    assert!((hip[1] - 0.491 * 1.75).abs() < 1e-12);
}

/// A reader that has gone (`exogait simulate --json | head -0`) lets the
/// command finish with its own status and no message, not a panic.
#[test]
fn a_closed_stdout_lets_the_command_finish_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args(["simulate", "--gait", "walk", "--json"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn exogait");
    // Closed before the run (a quarter of a second at least) prints.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&out.stderr);
    // The walk lands every step: 0, as with its output read.
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
}

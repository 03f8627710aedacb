//! `exogait faults` end to end: the built binary plays a short seeded
//! campaign, says by its exit status whether the goal held, and its JSON
//! tells each bad run's braked joints.

use std::process::Command;

const JOINTS: [&str; 4] = ["left-hip", "left-knee", "right-hip", "right-knee"];

#[test]
fn a_short_campaign_lists_each_bad_run_s_braked_joints() {
    let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args([
            "faults",
            "--runs",
            "60",
            "--seed",
            "18",
            "--healthy",
            "0",
            "--json",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let v: serde_json::Value =
        serde_json::from_str(text.trim()).unwrap_or_else(|e| panic!("{e}: {text}"));
    let all = &v["all"];
    assert_eq!(all["runs"], 60);
    // Exit 0 only when no fall and no stop crossed is the device's.
    let goal_met = all["unnamed_falls"] == 0
        && all["unnamed_past_a_stop"] == 0
        && all["missed"] == 0
        && all["false_trips"] == 0
        && all["errors"] == 0;
    assert_eq!(out.status.code(), Some(if goal_met { 0 } else { 1 }));
    let bad = v["bad_runs"].as_array().unwrap();
    assert!(!bad.is_empty(), "seed 18's first 60 runs include bad ones");
    let mut own_joint_runs = 0;
    let mut estop_runs = 0;
    for run in bad {
        let braked: Vec<&str> = run["braked_joints"]
            .as_array()
            .unwrap_or_else(|| panic!("no braked_joints in {run}"))
            .iter()
            .map(|j| j.as_str().unwrap())
            .collect();
        // Known names, each once, in joint order.
        let order: Vec<usize> = braked
            .iter()
            .map(|j| JOINTS.iter().position(|n| n == j).unwrap())
            .collect();
        assert!(order.windows(2).all(|w| w[0] < w[1]), "{run}");
        let fault = run["fault"].as_str().unwrap();
        // The e-stop disables every drive without a joint's fault: none
        // is listed.
        if fault.starts_with("estop") {
            estop_runs += 1;
            assert!(braked.is_empty(), "{run}");
        }
        // A lost hip or knee encoder, or a drive whose PWM or direction
        // output failed, brakes its own joint.
        let lost = [
            "encoder-bus:",
            "encoder-parity:",
            "encoder-error-flag:",
            "pwm-fail:",
            "dir-fail:",
        ]
        .iter()
        .find_map(|kind| fault.strip_prefix(kind))
        .and_then(|rest| rest.split('@').next())
        .filter(|target| JOINTS.contains(target));
        if let Some(target) = lost {
            assert!(braked.contains(&target), "{run}");
        }
        // Any fault on a joint that lists that joint braked: the names
        // come out in the right place.
        let target = fault.split(':').nth(1).and_then(|t| t.split('@').next());
        if target.is_some_and(|t| braked.contains(&t)) {
            own_joint_runs += 1;
        }
    }
    // With the campaign's pilot, who meets a hold 0.15 s late, no e-stop
    // run (824 in seed 1's 10,000) and no lost encoder or output stage is
    // a bad one: each is checked above when one is. Seed 18's first 60
    // hold a stair ascent's slipping hip gear braked at its own hip (the
    // torso tips on the braked stance hip, a named case).
    eprintln!("{estop_runs} e-stop runs among the bad ones");
    assert!(
        own_joint_runs > 0,
        "a bad run lists its own joint braked: {text}"
    );
}

//! Bad input gets a clear error and loses nothing: a line that is not
//! UTF-8 is answered and the lines after it still are; a negative number
//! reaches the range check; a plot that cannot be written is refused
//! before the run; the text report holds no Rust debug text.

use crate::common::run_piped;

fn exogait(args: &[&str], stdin: &[u8]) -> (i32, String, String) {
    let out = run_piped(args, stdin);
    (
        out.status.code().unwrap(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_line_that_is_not_utf8_is_answered_and_the_rest_still_are() {
    let line = b"{\"phi\":[0,0,0,3.14,3.14]}\n";
    let mut input = line.to_vec();
    input.extend_from_slice(b"\xff\xfe\n");
    input.extend_from_slice(line);
    let (code, out, _) = exogait(&["fk"], &input);
    assert_eq!(code, 1);
    let answers: Vec<&str> = out.lines().collect();
    assert_eq!(answers.len(), 3, "{out}");
    assert!(answers[0].starts_with("{\"p\""));
    assert!(answers[1].contains("not UTF-8") && answers[1].contains("\"line\":2"));
    assert!(answers[2].starts_with("{\"p\""));
}

#[test]
fn negative_numbers_reach_the_range_check() {
    let (code, _, err) = exogait(&["simulate", "--seconds", "-1"], b"");
    assert_eq!(code, 2);
    assert!(err.contains("--seconds must be in"), "{err}");
    for cmd in ["simulate", "compare"] {
        let (code, _, err) = exogait(&[cmd, "--gait", "walk", "--stance-foot-off", "-6"], b"");
        assert_eq!(code, 2, "{cmd}");
        assert!(
            err.contains("--stance-foot-off must be within"),
            "{cmd}: {err}"
        );
    }
    let (code, _, err) = exogait(
        &[
            "optimize",
            "--case",
            "walk",
            "--mode",
            "clinical",
            "--step-time",
            "-2",
            "--out",
            "/tmp/x.json",
        ],
        b"",
    );
    assert_eq!(code, 2);
    assert!(err.contains("step-time"), "{err}");
}

#[test]
fn a_plot_that_cannot_be_written_is_refused_before_the_run() {
    for (cmd, plot) in [
        (vec!["simulate"], "/tmp/out.pdf"),
        (vec!["compare", "--gait", "walk"], "/no/such/folder/out.svg"),
    ] {
        let mut args = cmd.clone();
        args.extend(["--plot", plot]);
        let t = std::time::Instant::now();
        let (code, _, err) = exogait(&args, b"");
        assert_eq!(code, 2, "{args:?}");
        assert!(err.contains("--plot"), "{err}");
        assert!(t.elapsed().as_secs_f64() < 2.0, "refused only after a run");
    }
}

#[test]
fn the_text_report_reads_as_text() {
    let (code, out, _) = exogait(&["simulate", "--steps", "1"], b"");
    assert_eq!(code, 0);
    assert!(!out.contains(" {") && !out.contains("t_s:"), "{out}");
    assert!(out.contains("final phase"), "{out}");
    assert!(out.contains("faults latched           none"), "{out}");
}

#[test]
fn a_noisy_run_is_played_again_from_its_seed() {
    let rms = |seed: &str| {
        let (code, out, err) = exogait(
            &[
                "simulate",
                "--steps",
                "1",
                "--sensor-noise",
                "3,10",
                "--noise-seed",
                seed,
                "--json",
            ],
            b"",
        );
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        v["tracking_rms_rad"].to_string()
    };
    assert_eq!(rms("5"), rms("5"));
    assert_ne!(rms("5"), rms("6"));
}

#[test]
fn the_campaign_reports_progress_and_time_when_piped() {
    let (_, _, err) = exogait(&["faults", "--runs", "10", "--healthy", "0"], b"");
    assert!(err.contains("10/10 runs"), "{err}");
    assert!(err.contains("runs in "), "{err}");
}

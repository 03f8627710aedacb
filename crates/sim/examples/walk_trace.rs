//! Prints a coarse trace of the closed-loop walk (every 50 ms): phase, the
//! true Φ, the reference and measured joints, commands, pilot torque, foot
//! and crutch forces. For diagnosing the closed loop:
//! `cargo run --release -p sim --example walk_trace -- [STEPS] [SECONDS] [EVERY_MS] [walk|stair-up|stair-down]`.

fn main() {
    let mut args = std::env::args().skip(1);
    let steps: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(2);
    let secs: f64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let every: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(50);
    let gait = match args.next().as_deref() {
        Some("stair-up") => gait_control::operator::Gait::StairUp,
        Some("stair-down") => gait_control::operator::Gait::StairDown,
        _ => gait_control::operator::Gait::Walk,
    };
    // EXO_NOISE="ENC,ADC": sensor noise in counts.
    let noise: Option<(u16, u16)> = std::env::var("EXO_NOISE").ok().and_then(|v| {
        let (a, b) = v.split_once(',')?;
        Some((a.parse().ok()?, b.parse().ok()?))
    });
    let run = match sim::scenario::run_gait_with(gait, secs, steps, |rig| {
        if let Some((e, a)) = noise {
            rig.set_sensor_noise(e, a, 2026);
        }
    }) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("walk_trace: {e}");
            return;
        }
    };
    println!("{}", run.summary);
    println!(
        "t phase | phi(5) | ref-meas(4) | cmd(feed-forward)(4) | pilot | feet | crutches | ankles"
    );
    for (k, s) in run.rig.trace.iter().enumerate() {
        if k % every != 0 {
            continue;
        }
        let r = &s.report;
        let st = &s.state;
        let err: Vec<String> = r
            .reference_rad
            .iter()
            .zip(&r.joints_rad)
            .map(|(a, b)| format!("{:+.3}", a - b))
            .collect();
        let phase = format!("{:?}", r.phase);
        println!(
            "{:.3} {:<34} | {} | {} | {} | {:+6.1} | {:5.0} {:5.0} | {:4.0} {:4.0} | {:?}",
            st.time_s,
            &phase[..phase.len().min(34)],
            st.phi
                .iter()
                .map(|v| format!("{v:+.3}"))
                .collect::<Vec<_>>()
                .join(" "),
            err.join(" "),
            r.command_nm
                .iter()
                .zip(&r.feedforward_nm)
                .map(|(v, f)| format!("{v:+6.1}({f:+6.1})"))
                .collect::<Vec<_>>()
                .join(" "),
            st.pilot_torque_nm,
            st.foot_forces_n[0],
            st.foot_forces_n[1],
            st.crutch_forces_n[0],
            st.crutch_forces_n[1],
            st.ankle_dorsiflexion_rad
                .map(|a| a.map(|v| (v * 1000.0).round() / 1000.0)),
        );
    }
    if let Some(e) = run.ended_by {
        println!("ended early: {e:?}");
    }
}

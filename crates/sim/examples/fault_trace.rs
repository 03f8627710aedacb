//! Prints a coarse trace of one campaign run (every EVERY ms): phase, hip
//! height, the true joints, reference − true, commands, motor torques, foot
//! and crutch forces, faults. For diagnosing a run `exogait faults --json`
//! lists: `cargo run --release -p sim --example fault_trace -- GAIT FAULT NOISE_SEED [EVERY_MS]`.
//! Feet and crutches are [left, right]; `FULL=1` prints the phase whole
//! (its time into a swing, to time a landing), `PILOT=1` the plant's stance, its five link angles φ and the
//! pilot's torque, `POINTS=1` adds the
//! body's points and the feet, m; `PLACE=M` stands the stance foot M metres
//! further forward first (`Rig::place_stance_foot`).

use std::str::FromStr;

fn main() {
    let mut args = std::env::args().skip(1);
    let gait = match args.next().as_deref() {
        Some("stair-up") => gait_control::operator::Gait::StairUp,
        Some("stair-down") => gait_control::operator::Gait::StairDown,
        _ => gait_control::operator::Gait::Walk,
    };
    let Some(Ok(fault)) = args.next().map(|s| sim::inject::Injection::from_str(&s)) else {
        eprintln!("fault_trace: GAIT FAULT NOISE_SEED [EVERY_MS]");
        return;
    };
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(1);
    let every: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(50);
    let Ok(device) = exogait_device::DeviceConfig::exogait() else {
        return;
    };
    let run = sim::campaign::CampaignRun {
        gait,
        slot: sim::campaign::built_in_slot(gait),
        fault,
        noise_seed: seed,
    };
    let played = sim::scenario::run_tables_with(
        &device,
        sim::scenario::flash_tables(),
        gait,
        sim::scenario::strong_pilot(),
        fault.at_s + 4.0,
        2,
        |rig| {
            if let Some(m) = std::env::var("PLACE").ok().and_then(|v| v.parse().ok()) {
                if let Err(e) = rig.place_stance_foot(m) {
                    eprintln!("fault_trace: PLACE={m}: {e}");
                }
            }
            rig.set_sensor_noise(3, 10, seed);
            rig.schedule(fault);
        },
    );
    let r = match played {
        Ok(r) => r,
        Err(e) => {
            eprintln!("fault_trace: {e}");
            return;
        }
    };
    println!("{:?}", run);
    println!(
        "t phase | hipY | joints(4) | ref-true(4) | cmd(4) | motor(4) | feet | crutches | ankles | faults"
    );
    for (k, s) in r.rig.trace.iter().enumerate() {
        if k % every != 0 {
            continue;
        }
        let rep = &s.report;
        let st = &s.state;
        let f4 = |v: [f64; 4]| {
            v.iter()
                .map(|x| format!("{x:+.3}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        let phase = format!("{:?}", rep.phase);
        println!(
            "{:.3} {:<28} | {:.3} | {} | {} | {} | {} | {:5.0} {:5.0} | {:4.0} {:4.0} | {:+.3} {:+.3} | {:?} {:?} en={}",
            st.time_s,
            &phase[..phase.len().min(std::env::var("FULL").map_or(28, |_| 60))],
            st.points_m[1][1],
            f4(st.joint_angles_rad),
            f4(core::array::from_fn(
                |j| f64::from(rep.reference_rad[j]) - st.joint_angles_rad[j]
            )),
            rep.command_nm
                .iter()
                .map(|v| format!("{v:+6.1}"))
                .collect::<Vec<_>>()
                .join(" "),
            st.motor_torques_nm
                .iter()
                .map(|v| format!("{v:+6.1}"))
                .collect::<Vec<_>>()
                .join(" "),
            st.foot_forces_n[0],
            st.foot_forces_n[1],
            st.crutch_forces_n[0],
            st.crutch_forces_n[1],
            st.ankle_dorsiflexion_rad[0].unwrap_or(f64::NAN),
            st.ankle_dorsiflexion_rad[1].unwrap_or(f64::NAN),
            rep.reaction,
            rep.faults,
            rep.motors_enabled,
        );
        if std::env::var("PILOT").is_ok() {
            println!(
                "      pilot stance {:?} phi {} torque {:+.1} spring {:+.1}",
                st.stance,
                st.phi
                    .iter()
                    .map(|x| format!("{x:+.3}"))
                    .collect::<Vec<_>>()
                    .join(" "),
                st.pilot_torque_nm,
                st.spring_torque_nm
            );
        }
        if std::env::var("POINTS").is_ok() {
            let p = |v: [f64; 2]| format!("({:+.3},{:+.3})", v[0], v[1]);
            let points: Vec<String> = st.points_m.iter().map(|&v| p(v)).collect();
            println!(
                "      points {} feet {} {}",
                points.join(" "),
                p(st.feet_m[0]),
                p(st.feet_m[1])
            );
        }
    }
    let o = sim::outcome::outcome(&r.rig, r.ended_by.as_ref());
    println!(
        "fell: {:?}; margin {:.3} (joint {})",
        o.fell, o.worst_limit_margin_rad, o.worst_limit_joint
    );
    for f in &o.faults {
        println!("{f:?}");
    }
    for rec in r.rig.controller.supervisor().log() {
        println!(
            "log: tick {} {:?} channel {} value {}",
            rec.tick, rec.code, rec.channel, rec.value
        );
    }
}

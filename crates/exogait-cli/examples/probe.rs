#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    missing_docs
)]
use exogait_device::DeviceConfig;
use gait_control::operator::Gait;
use gait_control::sequencer::{GaitTables, Phase};
use gait_core::tables::{GaitKind, GaitTable};
use gait_opt::clinical::*;

fn table_bytes(kind: GaitKind, phi: &[[f64; 5]]) -> Vec<u8> {
    gait_opt::tables::table_image(kind, phi).unwrap()
}

fn play(device: &DeviceConfig, kind: GaitKind, image: &[u8], steps: usize) {
    let table = GaitTable::parse(image).unwrap();
    let gait = match kind {
        GaitKind::Walk => Gait::Walk,
        GaitKind::StairUp => Gait::StairUp,
        GaitKind::StairDown => Gait::StairDown,
    };
    let mut tables = GaitTables::default();
    match gait {
        Gait::Walk => tables.walk = Some(table),
        Gait::StairUp => tables.stair_up = Some(table),
        Gait::StairDown => tables.stair_down = Some(table),
    }
    let run = sim::scenario::run_tables_with(
        device,
        tables,
        gait,
        sim::scenario::strong_pilot(),
        40.0,
        steps,
        |_| {},
    )
    .unwrap();
    let tr = &run.rig.trace;
    let transfer = device.controller.sequencer.transfer_s as f64;
    let lever = 0.45;
    // per step windows
    let mut starts = vec![];
    for w in tr.windows(2) {
        if matches!(w[1].report.phase, Phase::Swing { .. })
            && !matches!(w[0].report.phase, Phase::Swing { .. })
        {
            starts.push(w[1].state.time_s);
        }
    }
    let lands: Vec<f64> = run.rig.plant.landings().iter().map(|l| l.time_s).collect();
    for (i, &t0) in starts.iter().enumerate() {
        let Some(&t1) = lands.get(i) else { break };
        let t1 = t1 + transfer;
        let (mut f, mut bal, mut pk, mut sat) = (0.0, 0.0, 0.0f64, 0.0);
        for s in tr
            .iter()
            .filter(|s| s.state.time_s > t0 && s.state.time_s <= t1)
        {
            f += (s.state.crutch_forces_n[0] + s.state.crutch_forces_n[1]) * 0.001;
            bal += s.state.pilot_torque_nm.abs() / lever * 0.001;
            pk = pk.max(s.state.crutch_forces_n[0]);
            if s.state.pilot_torque_nm.abs() >= 299.9 {
                sat += 0.001;
            }
        }
        println!(
            "  step {i}: F {f:.0} N·s balance {bal:.0} N·s peak {pk:.0} N sat {sat:.3} s ({:.2}..{:.2})",
            t0, t1
        );
    }
    println!(
        "  {}",
        run.summary
            .to_string()
            .lines()
            .filter(|l| l.starts_with("landings")
                || l.starts_with("faults")
                || l.starts_with("steps")
                || l.starts_with("first")
                || l.starts_with("foot"))
            .collect::<Vec<_>>()
            .join("\n  ")
    );
    if let Some(e) = run.ended_by {
        println!("  ended by {e:?}");
    }
    let peak_cmd = tr
        .iter()
        .flat_map(|s| s.report.command_nm)
        .fold(0.0f32, |a, b| a.max(b.abs()));
    let i2t = run
        .rig
        .wiring
        .motors
        .iter()
        .map(|m| m.i2t_a2s())
        .fold(0.0, f64::max);
    println!("  peak command {peak_cmd:.0} N·m, i2t max {i2t:.0} A²s");
}

fn main() {
    let mut device = DeviceConfig::exogait().unwrap();
    if let Some(peak) = std::env::var("PEAK")
        .ok()
        .and_then(|v| v.parse::<f32>().ok())
    {
        for d in device.drives.iter_mut() {
            d.gearbox.repeated_peak_torque_nm = d.gearbox.repeated_peak_torque_nm.max(peak);
            d.current_limit_a = peak / d.joint_torque_per_amp();
            d.amplifier.peak_current_a = d.amplifier.peak_current_a.max(d.current_limit_a);
        }
        for (m, d) in device.motors.iter_mut().zip(device.drives) {
            *m = d.motor_config(0.001, 15.0, 40);
        }
        for g in device.controller.gains.iter_mut() {
            g.torque_limit_nm = peak;
        }
    }
    let which = std::env::args().nth(1).unwrap_or("walk".into());
    if std::env::var("SHIPPED").is_ok() {
        shipped_figures();
        return;
    }
    if std::env::var("SAT").is_ok() {
        sat20(match which.as_str() {
            "walk" => GaitKind::Walk,
            "up" => GaitKind::StairUp,
            _ => GaitKind::StairDown,
        });
        return;
    }
    let evals: usize = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(6000);
    let kind = match which.as_str() {
        "walk" => GaitKind::Walk,
        "up" => GaitKind::StairUp,
        _ => GaitKind::StairDown,
    };
    let case = ClinicalCase::for_gait(kind, &device);
    // human baseline at periodic geometry
    if std::env::var("LEAN").is_ok() {
        let h = gait_opt::human::human_gait(&case, &gait_opt::default_data_dir(), 0.0).unwrap();
        for i in 0..13 {
            let c = -0.3 + 0.075 * i as f64;
            let phi: Vec<[f64; 5]> = h
                .phi
                .iter()
                .map(|p| {
                    let mut q = *p;
                    q[2] += c;
                    q
                })
                .collect();
            let ev = evaluate_phi(&case, &phi).unwrap();
            println!(
                "lean {c:.2}: balance {:.0} pilot {:.0} joints {:?} start share {:.2}",
                ev.balance_ns,
                ev.pilot_peak_nm,
                ev.joint_peak_nm.map(|v| v.round()),
                ev.start_trailing_share
            );
        }
        return;
    }
    if std::env::var("HUMAN").is_ok() {
        let h = gait_opt::human::playable_human_gait(&case, &gait_opt::default_data_dir()).unwrap();
        let lean = h.torso_lean_rad;
        let ev = evaluate_phi(&case, &h.phi).unwrap();
        println!(
            "HUMAN {which}: lean {lean:.2} use {:.2} scale",
            ev.drive_use
        );
        println!(
            "x {:.2} balance {:.0} pilot peak {:.0} ankle peak {:.0} joints {:?} speeds {:?} i2t {:?} clearance {:.3} sole {:.3} start share {:.2} pen {:.0}",
            h.amplitude_scale,
            ev.balance_ns,
            ev.pilot_peak_nm,
            ev.ankle_peak_nm,
            ev.joint_peak_nm.map(|v| v.round()),
            ev.joint_speed_peak_rad_s
                .map(|v| (v * 100.0).round() / 100.0),
            ev.i2t_ratio,
            ev.clearance_m,
            ev.sole_margin_m,
            ev.start_trailing_share,
            ev.penalty
        );
        let mins = h
            .phi
            .iter()
            .map(|p| {
                gait_core::kinematics::anatomical_angles(&gait_core::kinematics::theta_from_phi(p))
            })
            .fold([9.0f64; 5], |m, a| {
                [
                    m[0].min(a[0]),
                    m[1].min(a[1]),
                    m[2].min(a[2]),
                    m[3].min(a[3]),
                    m[4].min(a[4]),
                ]
            });
        println!(
            "min anatomical (ankle, st knee, st hip, sw hip, sw knee) deg {:?}",
            mins.map(|v| (v.to_degrees() * 10.0).round() / 10.0)
        );
        let img = table_bytes(kind, &h.phi);
        geom(&img);
        play(&device, kind, &img, 4);
        if std::env::var("DUMP").is_ok() {
            trace_dump(&device, kind, &img, &case);
        }
        return;
    }
    let t = std::time::Instant::now();
    let r = optimize_clinical(
        &case,
        &ClinicalConfig {
            seed: std::env::var("SEED")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(1),
            max_evals: evals,
        },
        &mut |_, _| {},
    )
    .unwrap();
    println!(
        "{which}: {:.1} s, {} evals",
        t.elapsed().as_secs_f64(),
        r.evaluations
    );
    println!("{:#?}", r.evaluation);
    println!("start {:?} lift {:.3}", r.step.start, r.step.lift_fraction);
    let img = table_bytes(kind, &r.phi);
    std::fs::write(format!("/tmp/clin_{which}.bin"), &img).unwrap();
    play(&device, kind, &img, 4);
    if std::env::var("DUMP").is_ok() {
        trace_dump(&device, kind, &img, &case);
    }
    let t = GaitTable::parse(&img).unwrap();
    let (run20, rig) =
        sim::compare::play(&device, t, sim::scenario::strong_pilot(), 20, 90.0, |_| {}).unwrap();
    let hi = rig
        .trace
        .iter()
        .filter(|s| s.report.command_nm.iter().any(|c| c.abs() > 145.0))
        .count();
    println!(
        "  20 steps: landings {} faults {:?} ticks>145 {hi} mean balance {:?}",
        rig.plant.landings().len(),
        run20.faults,
        run20.mean(|s| s.balance_ns)
    );
}

#[allow(dead_code)]
pub fn trace_dump(device: &DeviceConfig, kind: GaitKind, image: &[u8], case: &ClinicalCase) {
    let table = GaitTable::parse(image).unwrap();
    let phi: Vec<[f64; 5]> = (0..table.len())
        .map(|k| table.sample(k).unwrap().map(f64::from))
        .collect();
    let mut pred = vec![];
    gait_core::playback::for_each_sample::<f64, gait_core::playback::PlaybackError>(
        &case.model,
        &case.foot,
        30.0,
        phi.len(),
        0.01,
        |k| phi.get(k).copied(),
        |s| {
            pred.push(*s);
            Ok(())
        },
    )
    .unwrap();
    let gait = match kind {
        GaitKind::Walk => Gait::Walk,
        GaitKind::StairUp => Gait::StairUp,
        GaitKind::StairDown => Gait::StairDown,
    };
    let mut tables = GaitTables::default();
    match gait {
        Gait::Walk => tables.walk = Some(table),
        Gait::StairUp => tables.stair_up = Some(table),
        Gait::StairDown => tables.stair_down = Some(table),
    }
    let run = sim::scenario::run_tables_with(
        device,
        tables,
        gait,
        sim::scenario::strong_pilot(),
        12.0,
        3,
        |_| {},
    )
    .unwrap();
    let from: f64 = std::env::var("FROM")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.0);
    let every: usize = std::env::var("EVERY")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(50);
    for s in run
        .rig
        .trace
        .iter()
        .filter(|s| s.state.time_s >= from)
        .step_by(every)
    {
        let (tt, ph) = match s.report.phase {
            Phase::Swing { t_s, .. } => (t_s as f64, "swing"),
            Phase::Transfer { .. } => (-1.0, "xfer"),
            Phase::WaitingReady { .. } => (-1.0, "wait"),
            Phase::Standing => (-1.0, "stand"),
            _ => (-1.0, "hold"),
        };
        let p = if tt >= 0.0 {
            pred.get((tt / 0.01) as usize)
                .map(|p| (p.pilot_nm, p.other_share, p.reaction_n[1], p.torques))
        } else {
            None
        };
        println!(
            "{:.3} {ph:5} pilot {:7.1} pred {:?} feet {:?} ff {:?} cmd {:?} err {:?} phi1 {:.4} rfoot {:?}",
            s.state.time_s,
            s.state.pilot_torque_nm,
            p.map(|p| (
                p.0.round(),
                (p.1 * 100.0).round() / 100.0,
                p.2.round(),
                p.3.map(|v| v.round())
            )),
            s.state.foot_forces_n.map(|v| v.round()),
            s.report.feedforward_nm.map(|v| v.round()),
            s.report.command_nm.map(|v| v.round()),
            (0..4)
                .map(
                    |j| ((s.state.joint_angles_rad[j] - s.report.reference_rad[j] as f64) * 1000.0)
                        .round()
                )
                .collect::<Vec<_>>(),
            s.state.phi[0],
            (
                s.state.feet_m[1].map(|v| (v * 1000.0).round()),
                s.state.swing_lifted,
                s.state.stance
            )
        );
    }
}
#[allow(dead_code)]
pub fn geom(img: &[u8]) {
    let t = GaitTable::parse(img).unwrap();
    let d = DeviceConfig::exogait().unwrap();
    println!("GEOM {:?}", sim::scenario::table_geometry(&t, &d.body));
}
#[allow(dead_code)]
pub fn sat20(kind: GaitKind) {
    let device = DeviceConfig::exogait().unwrap();
    let t = match kind {
        GaitKind::Walk => gait_core::flash_tables::walk(),
        GaitKind::StairUp => gait_core::flash_tables::stair_up(),
        GaitKind::StairDown => gait_core::flash_tables::stair_down(),
    }
    .unwrap();
    let (run, rig) =
        sim::compare::play(&device, t, sim::scenario::strong_pilot(), 20, 90.0, |_| {}).unwrap();
    println!(
        "faults {:?} landings {}",
        run.faults,
        rig.plant.landings().len()
    );
    for s in rig.trace.iter() {
        if s.report.command_nm.iter().any(|c| c.abs() > 140.0) {
            println!(
                "{:.3} {:?} cmd {:?} ff {:?}",
                s.state.time_s, s.report.phase, s.report.command_nm, s.report.feedforward_nm
            );
        }
    }
    let lens: Vec<String> = rig
        .plant
        .landings()
        .iter()
        .map(|l| format!("{:.3}", l.step_length_m))
        .collect();
    println!("step lengths {}", lens.join(" "));
    let i2t: Vec<f64> = rig.wiring.motors.iter().map(|m| m.i2t_a2s()).collect();
    println!("i2t {:?}", i2t);
}
#[allow(dead_code)]
pub fn shipped_figures() {
    let device = DeviceConfig::exogait().unwrap();
    for kind in [GaitKind::Walk, GaitKind::StairUp, GaitKind::StairDown] {
        let t = match kind {
            GaitKind::Walk => gait_core::flash_tables::walk(),
            GaitKind::StairUp => gait_core::flash_tables::stair_up(),
            GaitKind::StairDown => gait_core::flash_tables::stair_down(),
        }
        .unwrap();
        let phi: Vec<[f64; 5]> = (0..t.len())
            .map(|k| t.sample(k).unwrap().map(f64::from))
            .collect();
        let case = ClinicalCase::for_gait(kind, &device);
        let e = evaluate_phi(&case, &phi).unwrap();
        let d = exogait_device::admission::check_table(&device, &t).unwrap();
        println!(
            "{kind:?}: balance {:.0} pilot peak {:.0} ankle {:.0} joints {:?} speeds {:?} accel {:.1} clearance {:.3} sole {:.3} ds {:.2} i2t {:?} drive_use {:.2} admission {:?}",
            e.balance_ns,
            e.pilot_peak_nm,
            e.ankle_peak_nm,
            e.joint_peak_nm.map(|v| v.round()),
            e.joint_speed_peak_rad_s
                .map(|v| (v * 100.0).round() / 100.0),
            e.joint_accel_peak_rad_s2,
            e.clearance_m,
            e.sole_margin_m,
            e.double_support_s,
            e.i2t_ratio.map(|v| (v * 100.0).round() / 100.0),
            e.drive_use,
            d
        );
    }
}

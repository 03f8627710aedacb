//! Plays the runs of campaign SEED (RUNS runs) whose fault's name starts
//! with one of the given prefixes, on every core, and prints each fall
//! and stop crossed with the faults the run latched, each missed
//! detection, and the tally: for trying a reaction on the kinds it is for.
//! `cargo run --release -p sim --example campaign_subset -- SEED RUNS PREFIX...`
//! (`EXO_SET_DOWN=SECONDS,METRES` tries another set-down,
//! `EXO_SET_DOWN_SPEED=RAD_PER_S` another cap on its joints,
//! `EXO_LANDS_AFTER=WALK,UP,DOWN` other points of each swing from which a
//! hold lands first, `EXO_PILOT_REACTION=SECONDS,SECONDS` a pilot who
//! reacts to a hold at another time and speed, `EXO_RESIDUAL=N_M` another
//! limit of every joint's torque residual (0x0404; the gaits' own
//! stance-hip limits overridden), `EXO_GAIT=stair-down` one
//! gait's runs alone, `EXO_ALL=1` every run played with the phase its fault
//! struck in, not only the falls), or the runs
//! listed in a file, one `GAIT FAULT NOISE_SEED` a line (as `fault_trace`
//! takes them): `... campaign_subset -- file PATH`.

use std::str::FromStr;

/// The gait named as `--gait` takes it.
fn gait_named(name: &str) -> Option<gait_control::operator::Gait> {
    match name {
        "walk" => Some(gait_control::operator::Gait::Walk),
        "stair-up" => Some(gait_control::operator::Gait::StairUp),
        "stair-down" => Some(gait_control::operator::Gait::StairDown),
        _ => None,
    }
}

/// The runs listed in `path`, one `GAIT FAULT NOISE_SEED` a line (blank
/// lines skipped); a line that does not read is an error naming it.
fn listed(path: &str) -> Result<Vec<sim::campaign::CampaignRun>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut runs = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let bad = |why: &str| format!("{path}:{}: {why}: {line:?}", n + 1);
        let [gait, fault, seed] = words.as_slice() else {
            if words.is_empty() {
                continue;
            }
            return Err(bad("want GAIT FAULT NOISE_SEED"));
        };
        let gait = gait_named(gait).ok_or_else(|| bad("gait is walk, stair-up or stair-down"))?;
        let fault = sim::inject::Injection::from_str(fault).map_err(|e| bad(&e.to_string()))?;
        let noise_seed = seed
            .parse()
            .map_err(|_| bad("noise seed is a whole number"))?;
        runs.push(sim::campaign::CampaignRun {
            gait,
            slot: sim::campaign::built_in_slot(gait),
            fault,
            noise_seed,
        });
    }
    Ok(runs)
}

/// The faults a run latched, as `CODE@CHANNEL/SECONDS`.
fn latched(r: &sim::campaign::RunResult) -> String {
    let codes: Vec<String> = r
        .outcome
        .faults
        .iter()
        .map(|f| format!("{:04x}@{:?}/{:.3}", f.code.code(), f.channel, f.detected_s))
        .collect();
    codes.join(" ")
}

fn main() {
    let mut args = std::env::args().skip(1);
    let first = args.next();
    let file = if first.as_deref() == Some("file") {
        args.next()
    } else {
        None
    };
    let seed: u64 = first.and_then(|s| s.parse().ok()).unwrap_or(3);
    let runs: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(2000);
    let prefixes: Vec<String> = args.collect();
    let Ok(mut device) = exogait_device::DeviceConfig::exogait() else {
        return;
    };
    // EXO_SET_DOWN="SECONDS,METRES": try another set-down.
    if let Some((s, m)) = std::env::var("EXO_SET_DOWN").ok().and_then(|v| {
        let (a, b) = v.split_once(',')?;
        Some((a.parse::<f32>().ok()?, b.parse::<f32>().ok()?))
    }) {
        device.controller.sequencer.set_down_s = s;
        device.controller.sequencer.set_down_depth_m = m;
    }
    // EXO_SET_DOWN_SPEED=RAD_PER_S: another cap on the set-down's joints.
    if let Some(w) = std::env::var("EXO_SET_DOWN_SPEED")
        .ok()
        .and_then(|v| v.parse::<f32>().ok())
    {
        device.controller.sequencer.set_down_joint_speed_rad_s = w;
    }
    // EXO_LANDS_AFTER=WALK,UP,DOWN: other points of each gait's swing
    // from which a hold plays the step on.
    if let Some(f) = std::env::var("EXO_LANDS_AFTER").ok().and_then(|v| {
        let f: Vec<f32> = v.split(',').filter_map(|x| x.parse().ok()).collect();
        <[f32; 3]>::try_from(f).ok()
    }) {
        device.controller.sequencer.lands_after = f;
    }
    // EXO_RESIDUAL=N_M: another limit of the joints' torque residual.
    if let Some(l) = std::env::var("EXO_RESIDUAL")
        .ok()
        .and_then(|v| v.parse::<f32>().ok())
    {
        device.supervisor.response.limit_nm = l;
        device.supervisor.response.stance_hip_min_nm = l;
    }
    // EXO_GAIT=walk|stair-up|stair-down: that gait's runs alone.
    let gait = std::env::var("EXO_GAIT").ok().and_then(|g| gait_named(&g));
    let plan: Vec<_> = match &file {
        Some(path) => match listed(path) {
            Ok(runs) => runs,
            Err(e) => {
                eprintln!("campaign_subset: {e}");
                std::process::exit(2);
            }
        },
        None => sim::campaign::plan(seed, runs)
            .into_iter()
            .filter(|r| gait.is_none_or(|g| r.gait == g))
            .filter(|r| {
                let name = r.fault.to_string();
                prefixes.iter().any(|p| name.starts_with(p.as_str()))
            })
            .collect(),
    };
    // EXO_PILOT_REACTION="SECONDS,SECONDS": a pilot who acts on a hold
    // after that reaction time, and moves the shank to its aim over the
    // second (`PilotConfig::hold_reaction_s`, `hold_recovery_s`).
    let mut pilot = sim::scenario::strong_pilot();
    if let Some((r, v)) = std::env::var("EXO_PILOT_REACTION").ok().and_then(|v| {
        let (a, b) = v.split_once(',')?;
        Some((a.parse::<f64>().ok()?, b.parse::<f64>().ok()?))
    }) {
        pilot.hold_reaction_s = r;
        pilot.hold_recovery_s = v;
    }
    let results = sim::campaign::play_all_with_pilot(&plan, &device, pilot, &|| {});
    let mut falls = 0;
    let mut past = 0;
    let mut missed = 0;
    let mut unnamed = 0;
    let mut unnamed_past = 0;
    // EXO_ALL=1: the runs that did not fall too.
    let every_run = std::env::var_os("EXO_ALL").is_some();
    for r in &results {
        unnamed_past += usize::from(r.unnamed_stop());
        if r.outcome.worst_limit_margin_rad < 0.0 {
            past += 1;
            println!(
                "past {:?} {} {} joint {} {} {:.2} deg{} [{}]",
                r.run.gait,
                r.run.fault,
                r.run.noise_seed,
                r.outcome.worst_limit_joint,
                if r.outcome.limit_margins[r.outcome.worst_limit_joint].1 {
                    "flexion"
                } else {
                    "extension"
                },
                r.outcome.worst_limit_margin_rad.to_degrees(),
                if r.outcome.fell.is_some() {
                    " fell"
                } else {
                    ""
                },
                r.named_stop().map_or("device", |c| c.name())
            );
            println!("  faults {}", latched(r));
        }
        if r.missed() {
            missed += 1;
            println!(
                "missed {:?} {} {} in {:?}",
                r.run.gait, r.run.fault, r.run.noise_seed, r.struck_in
            );
        }
        if every_run && r.outcome.fell.is_none() {
            println!(
                "ok {:?} {} {} in {:?}",
                r.run.gait, r.run.fault, r.run.noise_seed, r.struck_in
            );
        }
        if let Some(f) = &r.outcome.fell {
            falls += 1;
            unnamed += usize::from(r.unnamed_fall());
            let named = r.named_fall().map_or("device", |c| c.name());
            println!(
                "{:?} {} {} {f} [{named}] in {:?}",
                r.run.gait, r.run.fault, r.run.noise_seed, r.struck_in
            );
            println!("  faults {}", latched(r));
        }
    }
    println!(
        "{} runs: {falls} falls ({unnamed} outside the named cases), {past} past a stop ({unnamed_past} outside), {missed} missed",
        results.len()
    );
}

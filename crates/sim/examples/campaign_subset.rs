//! Plays the runs of campaign SEED (RUNS runs) whose fault's name starts
//! with one of the given prefixes, on every core, and prints each device
//! fall and the tally: for trying a reaction on the kinds it is for.
//! `cargo run --release -p sim --example campaign_subset -- SEED RUNS PREFIX...`
//! (`EXO_SET_DOWN=SECONDS,METRES` tries another set-down), or the runs
//! listed in a file, one `GAIT FAULT NOISE_SEED` a line (as `fault_trace`
//! takes them): `... campaign_subset -- file PATH`.

use std::str::FromStr;

/// The runs listed in `path`, one `GAIT FAULT NOISE_SEED` a line.
fn listed(path: &str) -> Vec<sim::campaign::CampaignRun> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    text.lines()
        .filter_map(|line| {
            let mut w = line.split_whitespace();
            let gait = match w.next()? {
                "stair-up" => gait_control::operator::Gait::StairUp,
                "stair-down" => gait_control::operator::Gait::StairDown,
                _ => gait_control::operator::Gait::Walk,
            };
            let fault = sim::inject::Injection::from_str(w.next()?).ok()?;
            let noise_seed = w.next()?.parse().ok()?;
            Some(sim::campaign::CampaignRun {
                gait,
                fault,
                noise_seed,
            })
        })
        .collect()
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
    let plan: Vec<_> = match &file {
        Some(path) => listed(path),
        None => sim::campaign::plan(seed, runs)
            .into_iter()
            .filter(|r| {
                let name = r.fault.to_string();
                prefixes.iter().any(|p| name.starts_with(p.as_str()))
            })
            .collect(),
    };
    let results = sim::campaign::play_all(&plan, &device, &|| {});
    let mut falls = 0;
    let mut past = 0;
    let mut missed = 0;
    let mut unnamed = 0;
    for r in &results {
        if r.outcome.worst_limit_margin_rad < 0.0 {
            past += 1;
        }
        if r.missed() {
            missed += 1;
        }
        if let Some(f) = &r.outcome.fell {
            falls += 1;
            unnamed += usize::from(r.unnamed_fall());
            let named = r.named_fall().map_or("device", |c| c.name());
            println!(
                "{:?} {} {} {f} [{named}]",
                r.run.gait, r.run.fault, r.run.noise_seed
            );
        }
    }
    println!(
        "{} runs: {falls} falls ({unnamed} outside the named cases), {past} past a stop, {missed} missed",
        results.len()
    );
}

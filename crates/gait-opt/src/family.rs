//! A patient's gait family: clinical-mode tables for walking at several
//! paces and for stairs of several geometries, each searched on the
//! patient's model, admitted by the device's check and played for four
//! steps in the closed loop before it is cleared; a gait the device cannot
//! play for this patient is left out with the reason, in numbers.
//!
//! The gaits are independent searches, so they run on every core at once
//! (one scoped thread per core taking gaits from a shared queue); each is
//! deterministic, so the family is the same however the threads interleave.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use exogait_device::DeviceConfig;
use exogait_device::admission::check_table;
use gait_core::bundle::{GaitInfo, GaitName};
use gait_core::tables::{GaitKind, GaitTable};
use sim::campaign::{CampaignGait, CampaignGaits, plan_over, play_all_on};
use sim::compare::{RunLength, play_for};
use sim::scenario::strong_pilot;

use crate::clinical::{ClinicalCase, ClinicalConfig, Evaluation, optimize_clinical};
use crate::tables::table_image;

/// Default walking paces of a family, m/s (closed-loop progression aimed
/// at).
pub const DEFAULT_PACES_M_S: [f64; 4] = [0.15, 0.25, 0.35, 0.40];
/// Default stairs of a family, (rise, tread), m: building stairs.
pub const DEFAULT_STAIRS_M: [(f64, f64); 3] = [(0.15, 0.28), (0.17, 0.28), (0.18, 0.28)];
/// Lowest swing-foot clearance over the nosing a stair gait is cleared
/// with, m.
pub const STAIR_CLEARANCE_M: f64 = 0.05;
/// Lowest swing-foot clearance over level floor a walking gait is cleared
/// with, m.
pub const WALK_CLEARANCE_M: f64 = 0.03;
/// Steps a gait is played in the closed loop before it is cleared.
pub const VERIFY_STEPS: usize = 4;

/// How far inside Table I's stops every hip and knee must stay while a
/// gait is verified in the closed loop, rad (0.5°). The pilot's joints must
/// not be driven past a stop; the verifying run is noise-free, and this
/// margin covers the scatter of noisy runs about it (0.1–0.2° in the
/// healthy runs of `exogait faults --bundle`).
pub const STOP_MARGIN_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// Evaluations of each gait's clinical search.
pub const DEFAULT_EVALS: usize = 6_000;

/// One gait to design.
#[derive(Clone, Debug, PartialEq)]
pub struct GaitPlan {
    /// Its name in the bundle.
    pub name: String,
    /// Which movement.
    pub kind: GaitKind,
    /// Front ankle relative to the back one, m (tread and signed rise on
    /// stairs).
    pub spacing_m: [f64; 2],
    /// Step time, s.
    pub step_time_s: f64,
}

/// Walking: step length and step time aimed at `pace_m_s` for a leg of
/// `leg_m` (thigh + shank). Longer steps at a higher pace, as people walk
/// (about 0.36 leg lengths at 0.12 m/s, one more leg length per m/s); the
/// step time is what is left of each step's share of the time once the
/// controller's hand-over between steps (`transfer_s` of weight transfer,
/// of which the closed loop measures about 0.25 s beyond the table) is
/// taken out, and never under 0.9 s.
pub fn walk_plan(pace_m_s: f64, leg_m: f64, handover_s: f64) -> GaitPlan {
    let step = leg_m * (0.36 + (pace_m_s - 0.12).max(0.0));
    let step_time_s = (step / pace_m_s - handover_s).max(0.9);
    GaitPlan {
        name: format!("walk-{pace_m_s:.2}"),
        kind: GaitKind::Walk,
        spacing_m: [(step * 1000.0).round() / 1000.0, 0.0],
        step_time_s: (step_time_s * 100.0).round() / 100.0,
    }
}

/// What each step adds to a walking table's time in the closed loop, s
/// (measured: 1.45 s a step for a 1.2 s table, 1.26 s for 1.0 s).
pub const WALK_HANDOVER_S: f64 = 0.25;

/// Stairs of `rise_m` on `tread_m`, up or down, one step per stair; the
/// step time grows with the rise (the swing knee lifts further).
pub fn stair_plan(kind: GaitKind, rise_m: f64, tread_m: f64) -> GaitPlan {
    let (sign, word) = match kind {
        GaitKind::StairDown => (-1.0, "down"),
        _ => (1.0, "up"),
    };
    GaitPlan {
        name: format!("{word}-{rise_m:.3}"),
        kind,
        spacing_m: [tread_m, sign * rise_m],
        step_time_s: 2.3 + 4.0 * (rise_m - 0.09).max(0.0),
    }
}

/// The plans of a family: each pace, then each stair up, then each down.
pub fn family_plans(
    paces_m_s: &[f64],
    stairs_m: &[(f64, f64)],
    device: &DeviceConfig,
) -> Vec<GaitPlan> {
    let links = device.body.links();
    let leg = links[0].length_m + links[1].length_m;
    let walks = paces_m_s
        .iter()
        .map(|&v| walk_plan(v, leg, WALK_HANDOVER_S));
    let ups = stairs_m
        .iter()
        .map(|&(r, t)| stair_plan(GaitKind::StairUp, r, t));
    let downs = stairs_m
        .iter()
        .map(|&(r, t)| stair_plan(GaitKind::StairDown, r, t));
    walks.chain(ups).chain(downs).collect()
}

/// A gait the device can play for this patient.
#[derive(Clone, Debug, PartialEq)]
pub struct ClearedGait {
    /// What was asked.
    pub plan: GaitPlan,
    /// The bundle's description (closed-loop pace and clearance).
    pub info: GaitInfo,
    /// The table image.
    pub image: Vec<u8>,
    /// The clinical search's evaluation of the table.
    pub evaluation: Evaluation,
    /// Mean crutch impulse over the verified steps, N·s.
    pub impulse_ns: f64,
    /// Mean balance part of it, N·s.
    pub balance_ns: f64,
    /// The stance hip's torque residual, highest over the healthy runs
    /// with and without sensor noise, N·m ([`crate::residual_limit`]).
    pub stance_hip_residual_peak_nm: f64,
}

/// What became of one plan.
#[derive(Clone, Debug, PartialEq)]
pub enum Outcome {
    /// Cleared for the bundle.
    Cleared(Box<ClearedGait>),
    /// Left out, and why (with the numbers).
    LeftOut {
        /// What was asked.
        plan: GaitPlan,
        /// Why the device cannot play it for this patient.
        reason: String,
    },
}

/// The attempts of a gait, (extra step time s, torque share): the plan
/// as asked with the clinical search's share of the drive (0.75), then
/// slower and leaving the position loop more of the drive, for a patient
/// whose closed loop saturates a drive or lags behind the plan.
pub const ATTEMPTS: [(f64, f64); 3] = [(0.0, 0.75), (0.4, 0.65), (0.8, 0.55)];

/// Designs and verifies one gait on the fitted `device`: each of
/// [`ATTEMPTS`] in turn until one is cleared; the reason given for a gait
/// left out is its first attempt's (the plan as asked).
pub fn design(plan: &GaitPlan, device: &DeviceConfig, max_evals: usize) -> Outcome {
    design_checked(plan, device, max_evals, 0)
}

/// [`design`], each attempt that clears also played through
/// `campaign_runs` runs of the fault campaign ([`campaign_check`]; 0:
/// none): one a device fault drops the pilot from goes on to the next,
/// slower attempt. A gait left out so gives the first such attempt's step
/// time and campaign.
pub fn design_checked(
    plan: &GaitPlan,
    device: &DeviceConfig,
    max_evals: usize,
    campaign_runs: usize,
) -> Outcome {
    let mut first_reason = None;
    let mut campaign_reason = None;
    for (extra_s, share) in ATTEMPTS {
        let mut p = plan.clone();
        p.step_time_s = ((plan.step_time_s + extra_s) * 100.0).round() / 100.0;
        match attempt(&p, device, max_evals, share) {
            Ok(g) if campaign_runs == 0 => return Outcome::Cleared(g),
            Ok(g) => match campaign_check(&g, device, campaign_runs, 1) {
                Ok(()) => return Outcome::Cleared(g),
                Err(reason) => {
                    campaign_reason.get_or_insert(format!("{:.2} s: {reason}", p.step_time_s));
                }
            },
            Err(reason) => {
                first_reason.get_or_insert(reason);
            }
        }
    }
    // An attempt the closed loop played but the campaign refused says more
    // than the first attempt's reason.
    Outcome::LeftOut {
        plan: plan.clone(),
        reason: campaign_reason.or(first_reason).unwrap_or_default(),
    }
}

fn attempt(
    plan: &GaitPlan,
    device: &DeviceConfig,
    max_evals: usize,
    torque_share: f64,
) -> Result<Box<ClearedGait>, String> {
    let mut case = ClinicalCase::for_gait(plan.kind, device);
    case.spacing_m = plan.spacing_m;
    case.step_time_s = plan.step_time_s;
    case.limits.torque_share = torque_share;
    if plan.kind != GaitKind::Walk {
        // Aimed well above the bar: tracking lag takes some of it.
        case.limits.clearance_m = (STAIR_CLEARANCE_M + 0.02, STAIR_CLEARANCE_M + 0.05);
        // Higher stairs fold the stance knee further at the start.
        case.ik.stance_knee_max_rad = case.ik.stance_knee_max_rad.max(80f64.to_radians());
    }
    let config = ClinicalConfig { seed: 1, max_evals };
    let r = optimize_clinical(&case, &config, &mut |_, _| {})
        .map_err(|e| format!("no step found: {e}"))?;
    let e = r.evaluation.clone();
    let image = table_image(plan.kind, &case.ik, &r.phi).map_err(|err| format!("table: {err}"))?;
    let table =
        GaitTable::parse(&image).map_err(|_| "table refused by its own reader".to_string())?;
    let drive = &device.drives[1];
    let peak = f64::from(drive.peak_torque_nm());
    let joints = format!(
        "joint peaks {:.0}/{:.0}/{:.0}/{:.0} N·m (stance knee, stance hip, swing hip, swing knee) \
         of the drive's {peak:.0} N·m, speeds up to {:.2} rad/s of its {:.2} rad/s no-load",
        e.joint_peak_nm[0],
        e.joint_peak_nm[1],
        e.joint_peak_nm[2],
        e.joint_peak_nm[3],
        e.joint_speed_peak_rad_s.iter().copied().fold(0.0, f64::max),
        drive.no_load_speed_rad_s(),
    );
    check_table(device, &table).map_err(|refusal| {
        format!("the device's admission check refuses it: {refusal}; {joints}")
    })?;
    let min_clearance = if plan.kind == GaitKind::Walk {
        WALK_CLEARANCE_M
    } else {
        STAIR_CLEARANCE_M
    };
    if e.clearance_m < min_clearance {
        return Err(format!(
            "swing-foot clearance {:.3} m is below {min_clearance} m within the drives; {joints}",
            e.clearance_m
        ));
    }
    let max_s = 4.0 + VERIFY_STEPS as f64 * (plan.step_time_s + 3.0);
    let (run, rig) = play_for(
        device,
        table,
        strong_pilot(),
        RunLength {
            steps: VERIFY_STEPS,
            max_s,
            tail_s: 1.5,
        },
        |_| {},
    )
    .map_err(|err| format!("closed loop: {err}"))?;
    if let Some((code, name)) = run.faults.first() {
        return Err(format!(
            "closed loop: fault {code} ({name}) after {} of {VERIFY_STEPS} steps; planned {joints}",
            run.landed()
        ));
    }
    if run.landed() < VERIFY_STEPS {
        return Err(format!(
            "closed loop: {} of {VERIFY_STEPS} steps landed{}",
            run.landed(),
            run.ended_by
                .as_deref()
                .map(|w| format!(" ({w})"))
                .unwrap_or_default()
        ));
    }
    let o = sim::outcome::outcome(&rig, None);
    if o.worst_limit_margin_rad < STOP_MARGIN_RAD {
        let side = ["left hip", "left knee", "right hip", "right knee"];
        let stop = match o.limit_margins.get(o.worst_limit_joint) {
            Some((_, true)) => "flexion",
            _ => "extension",
        };
        return Err(format!(
            "closed loop: the {} comes {:.2}° from its {stop} stop (Table I; {:.1}° asked); planned {joints}",
            side.get(o.worst_limit_joint).copied().unwrap_or("?"),
            o.worst_limit_margin_rad.to_degrees(),
            STOP_MARGIN_RAD.to_degrees(),
        ));
    }
    // The table's clearance is the one the bundle records and the gate
    // holds (gait-core models the foot's toe rocker); the closed loop's
    // (`sim::compare::nosing_clearance_m`, the sole taken level) is
    // reported beside it by `exogait compare`.
    let (residual_peak, residual_limit) =
        crate::residual_limit::measure(device, table, VERIFY_STEPS, max_s)?;
    let clearance = e.clearance_m;
    let name = GaitName::new(&plan.name)
        .ok_or_else(|| format!("name {:?} is not 1-16 printable ASCII", plan.name))?;
    let level = plan.kind == GaitKind::Walk;
    let info = GaitInfo {
        name,
        kind: plan.kind,
        step_length_m: plan.spacing_m[0] as f32,
        rise_m: if level { 0.0 } else { plan.spacing_m[1] as f32 },
        tread_m: if level { 0.0 } else { plan.spacing_m[0] as f32 },
        step_time_s: plan.step_time_s as f32,
        pace_m_s: run.progression_m_s() as f32,
        clearance_m: clearance as f32,
        stance_hip_residual_nm: residual_limit,
    };
    Ok(Box::new(ClearedGait {
        plan: plan.clone(),
        info,
        image,
        evaluation: e,
        impulse_ns: run.mean(|s| s.impulse_ns).unwrap_or(f64::NAN),
        balance_ns: run.mean(|s| s.balance_ns).unwrap_or(f64::NAN),
        stance_hip_residual_peak_nm: residual_peak,
    }))
}

/// Designs every plan on `threads` threads (at least one); `progress` is
/// called after each gait with (done, total, its name). Outcomes are in
/// the plans' order.
pub fn design_all(
    plans: &[GaitPlan],
    device: &DeviceConfig,
    max_evals: usize,
    threads: usize,
    progress: &(dyn Fn(usize, usize, &str) + Sync),
) -> Vec<Outcome> {
    design_all_checked(plans, device, max_evals, 0, threads, progress)
}

/// [`design_all`] with each gait [`design_checked`] by `campaign_runs`
/// runs of the fault campaign.
pub fn design_all_checked(
    plans: &[GaitPlan],
    device: &DeviceConfig,
    max_evals: usize,
    campaign_runs: usize,
    threads: usize,
    progress: &(dyn Fn(usize, usize, &str) + Sync),
) -> Vec<Outcome> {
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Outcome>>> = Mutex::new(vec![None; plans.len()]);
    std::thread::scope(|s| {
        for _ in 0..threads.max(1).min(plans.len().max(1)) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(plan) = plans.get(i) else { break };
                    let outcome = design_checked(plan, device, max_evals, campaign_runs);
                    if let Ok(mut r) = results.lock() {
                        if let Some(slot) = r.get_mut(i) {
                            *slot = Some(outcome);
                        }
                    }
                    let n = done.fetch_add(1, Ordering::Relaxed) + 1;
                    progress(n, plans.len(), &plan.name);
                }
            });
        }
    });
    let results = results.into_inner().unwrap_or_default();
    plans
        .iter()
        .zip(results)
        .map(|(plan, r)| {
            r.unwrap_or_else(|| Outcome::LeftOut {
                plan: plan.clone(),
                reason: "not designed (a worker thread failed)".into(),
            })
        })
        .collect()
}

/// The checks every table the tool hands a user passes, in this order:
/// the device's admission check; a swing foot that stays above the floor
/// or the nosing it crosses (the table's own clearance at its geometry,
/// gait-core's model of the foot); and its first step landing, without a
/// fault, in the closed loop (the comparison's pilot). `Err` says which
/// failed, with its numbers.
pub fn check_playable(device: &DeviceConfig, table: &GaitTable<'_>) -> Result<(), String> {
    check_table(device, table)
        .map_err(|r| format!("the device's admission check refuses it: {r}"))?;
    let geometry = sim::scenario::table_geometry(table, &device.body);
    let mut case = ClinicalCase::for_gait(table.kind(), device);
    case.spacing_m = geometry.landing_m;
    case.step_time_s = f64::from(table.duration_s());
    let phi: Vec<gait_core::kinematics::Phi<f64>> = (0..table.len())
        .filter_map(|k| table.sample(k))
        .map(|p| p.map(f64::from))
        .collect();
    let e = crate::clinical::evaluate_phi(&case, &phi)
        .map_err(|err| format!("its step cannot be evaluated: {err:?}"))?;
    if e.clearance_m < 0.0 {
        return Err(format!(
            "its swing foot passes {:.3} m below the {} it crosses",
            -e.clearance_m,
            if table.kind() == GaitKind::Walk {
                "floor"
            } else {
                "nosing"
            }
        ));
    }
    let max_s = 8.0 + f64::from(table.duration_s()) + 3.0;
    let (run, _) = play_for(
        device,
        *table,
        strong_pilot(),
        RunLength {
            steps: 1,
            max_s,
            tail_s: 0.5,
        },
        |_| {},
    )
    .map_err(|err| format!("closed loop: {err}"))?;
    if let Some((code, name)) = run.faults.first() {
        return Err(format!(
            "its first step faults in the closed loop: {code} {name}"
        ));
    }
    if run.landed() < 1 {
        return Err("its first step does not land in the closed loop".into());
    }
    Ok(())
}

/// Plays `runs` runs of the seeded fault campaign (`sim::campaign`, seed
/// `seed`) on a cleared gait of the fitted `device`. `Err` says how many
/// dropped the pilot through the device (a fall no named case explains)
/// and after which faults: such a gait is not for this patient.
pub fn campaign_check(
    gait: &ClearedGait,
    device: &DeviceConfig,
    runs: usize,
    seed: u64,
) -> Result<(), String> {
    let table = GaitTable::parse(&gait.image)
        .map_err(|_| "table refused by its own reader".to_string())?
        .with_stance_hip_residual_nm(gait.info.stance_hip_residual_nm);
    let gaits = CampaignGaits::of(vec![CampaignGait {
        name: gait.plan.name.clone(),
        gait: sim::compare::gait_of(table.kind()),
        tables: sim::compare::tables_of(table),
    }]);
    let plan = plan_over(seed, runs, &gaits);
    let results = play_all_on(&plan, device, strong_pilot(), &gaits, &|| {});
    let unnamed: Vec<String> = results
        .iter()
        .filter(|r| r.unnamed_fall())
        .map(|r| r.run.fault.to_string())
        .collect();
    if unnamed.is_empty() {
        return Ok(());
    }
    let kinds: Vec<&str> = results
        .iter()
        .filter(|r| r.unnamed_fall())
        .map(|r| r.run.fault.kind.name())
        .fold(Vec::new(), |mut v, k| {
            if !v.contains(&k) {
                v.push(k);
            }
            v
        });
    Err(format!(
        "fault campaign: {} of {} runs drop the pilot with no named reason (after {}; first: {})",
        unnamed.len(),
        results.len(),
        kinds.join(", "),
        unnamed.first().map_or("", String::as_str),
    ))
}

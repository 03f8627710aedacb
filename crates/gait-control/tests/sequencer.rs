//! Gait execution rules, step by step: start only from the planned posture
//! with a verified table, swing only when the pilot is ready, landing only
//! by the foot sensor inside the landing window, alternate legs, stop at the
//! end of the step, safe hold.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::indexing_slicing,
    clippy::needless_range_loop,
    missing_docs
)]

use gait_control::faults::InSwing;
use gait_control::operator::Gait;
use gait_control::posture::{JOINTS, Side, joints_from_phi};
use gait_control::sequencer::{
    GaitTables, Measured, Order, Orders, Phase, Reference, RefuseReason, Sensed, SeqEvent,
    SeqInput, SeqRequest, Sequencer, SequencerConfig,
};
use gait_core::gait::GaitError;
use gait_core::ik::IkOptions;
use gait_core::problem::{PaperCase, PaperProblem};
use gait_core::tables::{GaitKind, GaitTable, encode, image_len};

const DT: f32 = 0.001;

/// A walk table from the paper problem's simple feasible gait.
fn walk_image() -> Vec<u8> {
    walk_image_with(IkOptions::paper())
}

/// The same samples (made with the paper's IK) with `label` as the IK
/// options in the header.
fn walk_image_with(label: IkOptions<f32>) -> Vec<u8> {
    let pb = PaperProblem::<f64>::paper(PaperCase::Walk);
    let step = pb.step(&pb.initial_guess());
    let mut phis = Vec::new();
    // Φ per sample through the IK, as the table generator does.
    let ik = gait_core::ik::IkSolver::new(&pb.model);
    step.for_each_sample::<GaitError>(|s| {
        phis.push(s.solve(&ik)?.phi.map(|v| v as f32));
        Ok(())
    })
    .unwrap();
    let mut buf = vec![0u8; image_len(phis.len())];
    encode(GaitKind::Walk, 10_000, label, &phis, &mut buf).unwrap();
    buf
}

/// The walk table's stance-shank angle at the start (the paper profile's
/// φ1(0)): both ankles read it unless a test says otherwise.
const START_ANKLE: f32 = -0.0932;

fn sensed(joints: [f32; JOINTS], feet: [f32; 2], crutches: [f32; 2]) -> Sensed {
    Sensed {
        joints_rad: joints,
        feet_n: feet,
        crutches_n: crutches,
        ankles_rad: [START_ANKLE; 2],
    }
}

/// A sequencer ticked as the controller ticks it: one `update` a tick,
/// the orders and requests given between two ticks taking effect in the
/// next.
struct Rig<'t> {
    seq: Sequencer<'t>,
    table: GaitTable<'t>,
    events: Vec<SeqEvent>,
    orders: Orders,
    request: Option<SeqRequest<Gait>>,
}

impl<'t> Rig<'t> {
    fn new(image: &'t [u8]) -> Self {
        Self::with_config(image, SequencerConfig::DEFAULT)
    }

    fn with_config(image: &'t [u8], cfg: SequencerConfig) -> Self {
        let table = GaitTable::parse(image).unwrap();
        let tables = match table.kind() {
            GaitKind::Walk => GaitTables::by_kind(Some(table), None, None),
            GaitKind::StairUp => GaitTables::by_kind(None, Some(table), None),
            GaitKind::StairDown => GaitTables::by_kind(None, None, Some(table)),
        };
        let start = joints_from_phi(&table.first(), Side::Left);
        Self {
            seq: Sequencer::new(cfg, tables, start),
            table,
            events: Vec::new(),
            orders: Orders::NONE,
            request: None,
        }
    }

    /// One tick with the orders and request given since the last.
    fn tick(&mut self, s: &Sensed) -> Reference {
        let orders = std::mem::replace(&mut self.orders, Orders::NONE);
        let r = self.seq.update(&SeqInput {
            sensed: s,
            selected: Gait::Walk,
            request: self.request.take(),
            orders: &orders,
            braked: &[false; JOINTS],
            hold_joint_at: None,
            restart: false,
            dt_s: DT,
        });
        self.events.extend(r.events.iter());
        r
    }

    fn step(&mut self, s: &Sensed) -> [f32; JOINTS] {
        self.tick(s).angle_rad
    }

    /// Asks for a start of `gait` from `s`'s posture, in a tick whose
    /// crutches are unloaded (the pilot is not ready yet: the swing waits);
    /// the answer.
    fn start(&mut self, gait: Gait, s: &Sensed) -> SeqEvent {
        self.request = Some(SeqRequest::Start(gait));
        let mut unready = *s;
        unready.crutches_n = [0.0; 2];
        let r = self.tick(&unready);
        r.events.iter().next().unwrap()
    }

    /// The verdict's `order`, with `measured` the posture of its tick, for
    /// the next tick.
    fn order(&mut self, order: Order, measured: [f32; JOINTS]) {
        self.orders.order = order;
        self.orders.measured = Measured {
            joints_rad: measured,
            ..Measured::UNKNOWN
        };
    }

    /// A safe hold of `measured`, for the next tick.
    fn hold(&mut self, measured: [f32; JOINTS], in_swing: InSwing) {
        self.order(Order::SafeHold(in_swing), measured);
    }

    /// Joint `i` to be held at `measured` (the verdict's re-hold), for the
    /// next tick.
    fn rehold(&mut self, i: usize, measured: f32) {
        self.orders.rehold[i] = true;
        self.orders.measured.joints_rad[i] = measured;
    }

    fn start_pose(&self, stance: Side) -> [f32; JOINTS] {
        joints_from_phi(&self.table.first(), stance)
    }
}

const READY_FEET: [f32; 2] = [500.0, 0.0];
const READY_CRUTCHES: [f32; 2] = [100.0, 100.0];

#[test]
fn start_needs_a_table_and_the_start_posture() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    assert_eq!(
        rig.start(Gait::StairUp, &s),
        SeqEvent::StartRefused(RefuseReason::NoTable)
    );
    let mut off = pose;
    off[1] += 0.3;
    assert_eq!(
        rig.start(Gait::Walk, &sensed(off, READY_FEET, READY_CRUTCHES)),
        SeqEvent::StartRefused(RefuseReason::NotInStartPosture)
    );
    assert_eq!(
        rig.start(Gait::Walk, &s),
        SeqEvent::StartAccepted(Gait::Walk, Side::Left)
    );
    // The mirrored posture starts with the other leg as stance.
    let mut rig = Rig::new(&img);
    let s = sensed(rig.start_pose(Side::Right), [0.0, 500.0], READY_CRUTCHES);
    assert_eq!(
        rig.start(Gait::Walk, &s),
        SeqEvent::StartAccepted(Gait::Walk, Side::Right)
    );
}

#[test]
fn swing_waits_for_the_stance_shank_at_the_planned_angle() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    rig.start(Gait::Walk, &sensed(pose, READY_FEET, READY_CRUTCHES));
    let tol = SequencerConfig::DEFAULT.start_ankle_tolerance_rad;
    // Forces ready, but the body is ahead of the planned start (stance
    // ankle dorsiflexed 0.1 rad more), or its ankle reading is NaN: wait.
    for ankle in [START_ANKLE + 0.1, START_ANKLE - 1.5 * tol, f32::NAN] {
        for _ in 0..200 {
            let mut s = sensed(pose, READY_FEET, READY_CRUTCHES);
            s.ankles_rad[Side::Left.ankle()] = ankle;
            rig.step(&s);
        }
        assert!(
            matches!(rig.seq.phase(), Phase::WaitingReady { .. }),
            "{ankle}"
        );
    }
    // The swing ankle's reading does not matter; the stance one within
    // tolerance starts the swing.
    let mut s = sensed(pose, READY_FEET, READY_CRUTCHES);
    s.ankles_rad[Side::Left.ankle()] = START_ANKLE + 0.8 * tol;
    s.ankles_rad[Side::Right.ankle()] = f32::NAN;
    rig.step(&s);
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
}

#[test]
fn swing_waits_for_crutches_and_the_feet() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    rig.start(Gait::Walk, &sensed(pose, READY_FEET, READY_CRUTCHES));
    // One crutch unloaded: keep waiting, however long.
    for _ in 0..2000 {
        rig.step(&sensed(pose, READY_FEET, [100.0, 10.0]));
    }
    assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
    // The feet together carry too little (the device is not standing on
    // them): keep waiting. Which foot carries how much is the table's plan.
    for _ in 0..100 {
        rig.step(&sensed(pose, [50.0, 100.0], READY_CRUTCHES));
    }
    assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
    // NaN forces (a faulted sensor) never count as ready.
    rig.step(&sensed(pose, [f32::NAN, 0.0], [f32::NAN, 100.0]));
    assert!(matches!(rig.seq.phase(), Phase::WaitingReady { .. }));
    rig.step(&sensed(pose, READY_FEET, READY_CRUTCHES));
    assert!(matches!(
        rig.seq.phase(),
        Phase::Swing {
            stance: Side::Left,
            ..
        }
    ));
    assert!(
        rig.events
            .contains(&SeqEvent::SwingStarted(Gait::Walk, Side::Left))
    );
}

/// Runs a swing to its landing; returns the reference trace.
fn swing_and_land(
    rig: &mut Rig<'_>,
    stance: Side,
    early_contact_at: Option<f32>,
) -> Vec<[f32; JOINTS]> {
    let pose = rig.start_pose(stance);
    let swing_foot = stance.other().foot();
    let mut trace = Vec::new();
    let duration = rig.table.duration_s();
    let mut t = 0.0;
    loop {
        let mut feet = [0.0; 2];
        feet[stance.foot()] = 500.0;
        let contact = t >= duration || early_contact_at.is_some_and(|e| (t - e).abs() < 0.05);
        if contact {
            feet[swing_foot] = 200.0;
        }
        let r = rig.step(&sensed(pose, feet, READY_CRUTCHES));
        trace.push(r);
        t += DT;
        if !matches!(
            rig.seq.phase(),
            Phase::Swing { .. } | Phase::WaitingReady { .. }
        ) || t > duration + 2.0
        {
            break;
        }
    }
    trace
}

#[test]
fn swing_plays_the_table_and_lands_on_the_foot_sensor() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    rig.start(Gait::Walk, &sensed(pose, READY_FEET, READY_CRUTCHES));
    // An early scuff at 20 % of the step is not a landing.
    let scuff = 0.2 * rig.table.duration_s();
    let trace = swing_and_land(&mut rig, Side::Left, Some(scuff));
    assert!(rig.events.contains(&SeqEvent::Landed));
    let n = trace.len() as f32 * DT;
    assert!(n >= rig.table.duration_s() - 0.01, "landed after {n} s");
    // Mid-swing the reference is the table, mapped with the left leg standing.
    let mid = trace[trace.len() / 2];
    let t_mid = (trace.len() / 2) as f32 * DT;
    let want = joints_from_phi(&rig.table.at_time(t_mid - DT), Side::Left);
    for i in 0..JOINTS {
        assert!(
            (mid[i] - want[i]).abs() < 2e-3,
            "joint {i}: {} vs {}",
            mid[i],
            want[i]
        );
    }
    // After landing the legs swap: transfer with the right leg standing, then
    // wait at the next start posture.
    assert!(matches!(
        rig.seq.phase(),
        Phase::Transfer {
            stance: Side::Right,
            ..
        }
    ));
    let right_pose = rig.start_pose(Side::Right);
    for _ in 0..1000 {
        rig.step(&sensed(right_pose, [0.0, 500.0], [10.0, 10.0]));
    }
    assert!(matches!(
        rig.seq.phase(),
        Phase::WaitingReady {
            stance: Side::Right
        }
    ));
    let r = rig.seq.reference();
    for i in 0..JOINTS {
        assert!((r[i] - right_pose[i]).abs() < 1e-5);
    }
}

#[test]
fn stop_request_ends_at_the_landing_and_no_gait_change_mid_step() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.start(Gait::Walk, &s);
    rig.step(&s);
    assert!(rig.seq.status().step_in_progress());
    assert_eq!(
        rig.start(Gait::Walk, &s),
        SeqEvent::StartRefused(RefuseReason::Busy)
    );
    rig.request = Some(SeqRequest::StopAfterStep);
    swing_and_land(&mut rig, Side::Left, None);
    assert_eq!(rig.seq.phase(), Phase::Standing);
    assert!(rig.events.contains(&SeqEvent::Stopped));
    // It holds the landing posture.
    let held = rig.seq.reference();
    for _ in 0..500 {
        let r = rig.step(&s);
        assert_eq!(r, held);
    }
}

#[test]
fn landing_timeout_holds_the_posture() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.start(Gait::Walk, &s);
    let steps =
        ((rig.table.duration_s() + SequencerConfig::DEFAULT.landing_timeout_s + 0.2) / DT) as usize;
    for _ in 0..steps {
        rig.step(&s); // the swing foot never reports contact
    }
    assert!(rig.events.contains(&SeqEvent::LandingTimeout));
    assert_eq!(rig.seq.phase(), Phase::Standing);
}

#[test]
fn a_blind_swing_foot_lands_once_it_has_had_time_to_follow_the_table() {
    // The swing foot's sensor is lost (NaN) from mid-swing: the step counts
    // as landed `blind_landing_settle_s` after the table's end, not at the
    // end itself (the foot lags its reference and was still above a stair's
    // tread), holding the table's last posture in between.
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.start(Gait::Walk, &s);
    let mut blind = s;
    blind.feet_n[Side::Right.foot()] = f32::NAN;
    let duration = rig.table.duration_s();
    let settle = SequencerConfig::DEFAULT.blind_landing_settle_s;
    assert!(settle > 0.1, "{settle}");
    // The ground search has not begun: the table's last posture is held.
    assert!(SequencerConfig::DEFAULT.ground_search_after_s > settle);
    let last = joints_from_phi(&rig.table.at_time(duration), Side::Left);
    let mut landed_at = None;
    let mut n = 0usize;
    while landed_at.is_none() && n < 5000 {
        let sensed_now = if n < 1000 { s } else { blind };
        let r = rig.step(&sensed_now);
        n += 1;
        let t = n as f32 * DT;
        if matches!(rig.seq.phase(), Phase::Swing { .. }) && t > duration + 0.01 {
            for i in 0..JOINTS {
                assert!((r[i] - last[i]).abs() < 1e-4, "at {t} s joint {i}");
            }
        }
        if rig.events.contains(&SeqEvent::Landed) {
            landed_at = Some(t);
        }
    }
    let t = landed_at.expect("never landed");
    assert!(
        (t - (duration + settle)).abs() <= 2.5 * DT,
        "landed at {t} s, the table ends at {duration} s"
    );
    assert!(matches!(rig.seq.phase(), Phase::Transfer { .. }));
}

/// A walk started from its start posture and played 0.7 s into its first
/// swing; the sensed readings it was started with.
fn walking_in_a_swing(img: &[u8]) -> (Rig<'_>, Sensed) {
    let mut rig = Rig::new(img);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.start(Gait::Walk, &s);
    for _ in 0..700 {
        rig.step(&s);
    }
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
    (rig, s)
}

#[test]
fn safe_hold_ramps_to_the_measured_posture_and_blocks_starts() {
    let img = walk_image();
    let (mut rig, s) = walking_in_a_swing(&img);
    let measured = [0.3, 0.2, 0.1, 0.4];
    let before = rig.seq.reference();
    // The controller asks for the hold every tick while the fault is
    // latched. In a swing the step lands first, then the hold begins.
    let mut last = before;
    let mut max_step = 0.0f32;
    let mut phases = Vec::new();
    // The swing plays on, times out its landing (no contact here), stands,
    // then holds.
    let ticks =
        ((rig.table.duration_s() + SequencerConfig::DEFAULT.landing_timeout_s) / DT) as usize;
    for _ in 0..ticks {
        rig.hold(measured, InSwing::LandFirst);
        let r = rig.step(&sensed(measured, READY_FEET, READY_CRUTCHES));
        for i in 0..JOINTS {
            max_step = max_step.max((r[i] - last[i]).abs());
        }
        last = r;
        let kind = std::mem::discriminant(&rig.seq.phase());
        if phases.last() != Some(&kind) {
            phases.push(kind);
        }
    }
    let swing = std::mem::discriminant(&Phase::Swing {
        stance: Side::Left,
        t_s: 0.0,
    });
    let hold = std::mem::discriminant(&Phase::SafeHold { t_s: 0.0 });
    assert_eq!(phases.first(), Some(&swing), "the swing went on");
    assert_eq!(phases.last(), Some(&hold), "then held");
    assert!(
        !phases.contains(&std::mem::discriminant(&Phase::Transfer {
            stance: Side::Left,
            t_s: 0.0
        })),
        "no weight transfer after the landing: {phases:?}"
    );
    for i in 0..JOINTS {
        assert!((last[i] - measured[i]).abs() < 1e-6);
    }
    // Ramped: no jump bigger than the smoothstep's steepest tick.
    assert!(
        max_step < 0.02,
        "reference jumped {max_step} rad in one tick"
    );
    assert_eq!(
        rig.start(Gait::Walk, &s),
        SeqEvent::StartRefused(RefuseReason::Busy)
    );
    rig.request = Some(SeqRequest::ResetAfterFaults);
    rig.step(&s);
    assert_eq!(rig.seq.phase(), Phase::Standing);
}

#[test]
fn a_safe_hold_for_a_motor_fault_holds_a_swing_at_once() {
    let img = walk_image();
    let (mut rig, s) = walking_in_a_swing(&img);
    rig.hold([0.3, 0.2, 0.1, 0.4], InSwing::HoldNow);
    rig.step(&s);
    assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
}

#[test]
fn late_in_a_swing_a_hold_lands_the_step_while_the_stance_knee_works() {
    // From `lands_after` of the swing on (here 0.6 of the walk's), a hold
    // that would stop the swing plays it on to its landing, unless the
    // stance knee is braked: it is what lowers the body onto the foot.
    let img = walk_image();
    let mut cfg = SequencerConfig::DEFAULT;
    cfg.lands_after = [0.6, 1.0, 1.0];
    let mut rig = Rig::with_config(&img, cfg);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.start(Gait::Walk, &s);
    let none = [false; JOINTS];
    let mut stance_knee = [false; JOINTS];
    stance_knee[Side::Left.hip() + 1] = true;
    let mut swing_knee = [false; JOINTS];
    swing_knee[Side::Right.hip() + 1] = true;
    assert_eq!(
        rig.seq.status().in_swing_now(InSwing::HoldNow, &none),
        InSwing::HoldNow
    );
    let duration = rig.table.duration_s();
    let mut seen = (false, false);
    for _ in 0..(3.0 / DT) as usize {
        rig.step(&s);
        let Phase::Swing { t_s, .. } = rig.seq.phase() else {
            continue;
        };
        let now = rig.seq.status().in_swing_now(InSwing::HoldNow, &none);
        if t_s < 0.59 * duration {
            assert_eq!(now, InSwing::HoldNow, "{t_s} s");
            seen.0 = true;
        } else if t_s > 0.61 * duration {
            assert_eq!(now, InSwing::LandFirst, "{t_s} s");
            assert_eq!(
                rig.seq
                    .status()
                    .in_swing_now(InSwing::HoldInAir, &swing_knee),
                InSwing::LandFirst
            );
            assert_eq!(
                rig.seq
                    .status()
                    .in_swing_now(InSwing::HoldNow, &stance_knee),
                InSwing::HoldNow
            );
            seen.1 = true;
        }
    }
    assert_eq!(seen, (true, true), "the swing was seen early and late");
    // The shipped configuration's walk never lands first this way.
    let (rig, _) = walking_in_a_swing(&img);
    assert_eq!(
        rig.seq.status().in_swing_now(InSwing::HoldNow, &none),
        InSwing::HoldNow
    );
}

#[test]
fn non_fatal_block_finishes_the_step_then_refuses_new_ones() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.start(Gait::Walk, &s);
    rig.step(&s);
    rig.order(Order::FinishStepThenHold, pose);
    assert!(rig.seq.status().step_in_progress(), "the step goes on");
    swing_and_land(&mut rig, Side::Left, None);
    assert_eq!(rig.seq.phase(), Phase::Standing);
    let s2 = sensed(rig.start_pose(Side::Right), [0.0, 500.0], READY_CRUTCHES);
    assert_eq!(
        rig.start(Gait::Walk, &s2),
        SeqEvent::StartRefused(RefuseReason::Busy)
    );
}

#[test]
fn weight_transfer_keeps_the_trailing_foot_planted() {
    // With the model, the transfer after landing is planned in double
    // support: reconstructing the reference posture with the planned stance
    // shank, the trailing foot stays where it is while the posture moves to
    // the next start posture; the reference never jumps.
    use gait_control::posture::phi_from_joints;
    use gait_core::BodyModel;
    use gait_core::kinematics::forward_kinematics;
    let img = walk_image();
    let (mut rig, pose) = landed_with_the_model(&img);
    let model: BodyModel<f32> = BodyModel::<f64>::paper_table_iii().cast();
    assert!(matches!(
        rig.seq.phase(),
        Phase::Transfer {
            stance: Side::Right,
            ..
        }
    ));
    // The planned stance shank: from the landing posture seen from the new
    // stance foot (φ5 − π of the table's last sample) to the start's φ1.
    let last = rig.table.last();
    let phi1_from = last[4] - core::f32::consts::PI;
    let phi1_to = rig.table.first()[0];
    let cfg = SequencerConfig::DEFAULT;
    let mut feet = Vec::new();
    let mut prev = rig.seq.reference();
    let mut worst_step = 0.0f32;
    let mut t = 0.0f32;
    while matches!(rig.seq.phase(), Phase::Transfer { .. }) {
        let r = rig.step(&sensed(pose, [0.0, 500.0], READY_CRUTCHES));
        t += DT;
        let x = (t / cfg.transfer_s).clamp(0.0, 1.0);
        let s = x * x * (3.0 - 2.0 * x);
        let phi = phi_from_joints(&r, phi1_from + s * (phi1_to - phi1_from), Side::Right);
        feet.push(forward_kinematics(&model, &phi)[4]);
        for i in 0..JOINTS {
            worst_step = worst_step.max((r[i] - prev[i]).abs());
        }
        prev = r;
    }
    let first = feet[0];
    let drift = feet
        .iter()
        .map(|p| ((p[0] - first[0]).powi(2) + (p[1] - first[1]).powi(2)).sqrt())
        .fold(0.0f32, f32::max);
    // Planned: the foot stays within 0.1 mm (f32 IK). A joint-angle blend
    // drifts it by 1.4 mm even on this gentle table, tens of mm on the
    // optimised one.
    assert!(
        drift < 1e-4,
        "trailing foot moved {drift} m during the transfer"
    );
    assert!(worst_step < 0.02, "reference jumped {worst_step} rad");
    let start = rig.start_pose(Side::Right);
    for i in 0..JOINTS {
        assert!((rig.seq.reference()[i] - start[i]).abs() < 1e-4);
    }
}

/// A walk with the model (the transfer planned by the IK) started from its
/// start posture and played to its first landing; that start posture.
fn landed_with_the_model(image: &[u8]) -> (Rig<'_>, [f32; JOINTS]) {
    let mut rig = Rig::new(image);
    let model: gait_core::BodyModel<f32> = gait_core::BodyModel::<f64>::paper_table_iii().cast();
    rig.seq = rig.seq.with_model(model);
    let pose = rig.start_pose(Side::Left);
    rig.start(Gait::Walk, &sensed(pose, READY_FEET, READY_CRUTCHES));
    swing_and_land(&mut rig, Side::Left, None);
    (rig, pose)
}

/// The reference through the weight transfer after the first landing, with
/// the model (the transfer planned by the IK).
fn transfer_trace(image: &[u8]) -> Vec<[f32; JOINTS]> {
    let (mut rig, pose) = landed_with_the_model(image);
    let mut trace = Vec::new();
    while matches!(rig.seq.phase(), Phase::Transfer { .. }) {
        trace.push(rig.step(&sensed(pose, [0.0, 500.0], READY_CRUTCHES)));
    }
    trace
}

#[test]
fn the_transfer_is_planned_with_the_ik_options_the_table_carries() {
    use gait_core::ik::KneeRange;
    // The same samples, made with the paper's IK, once labelled with it and
    // once with the descent's options: the sequencer plans the transfer
    // with the label (the knee choice r2 is measured in another range), so
    // the two references part mid-transfer; both end at the start posture.
    let paper = walk_image();
    let human =
        walk_image_with(IkOptions::new(core::f32::consts::FRAC_PI_2, KneeRange::Human).unwrap());
    assert_eq!(
        GaitTable::parse(&human).unwrap().ik_options().knee_range,
        KneeRange::Human
    );
    let a = transfer_trace(&paper);
    let b = transfer_trace(&human);
    assert_eq!(a.len(), b.len());
    let apart = a
        .iter()
        .zip(&b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0f32, f32::max);
    // 0.45 mrad today; f32 rounding alone would be ~1e-6 rad.
    assert!(apart > 1e-4, "the transfers differ by {apart} rad only");
    let start = joints_from_phi(&GaitTable::parse(&paper).unwrap().first(), Side::Right);
    for trace in [&a, &b] {
        let end = trace.last().unwrap();
        for i in 0..JOINTS {
            assert!(
                (end[i] - start[i]).abs() < 1e-3,
                "joint {i}: {} vs {}",
                end[i],
                start[i]
            );
        }
    }
}

/// The swing ankle's height above the stance ankle for joint angles `j`
/// (stance left, the table's stance shank `phi1`), m.
fn swing_ankle_height(model: &gait_core::BodyModel<f32>, j: &[f32; JOINTS], phi1: f32) -> f32 {
    swing_ankle(model, j, phi1)[1]
}

/// The swing ankle's position in the stance foot's frame for joint angles
/// `j` (stance left, the stance shank `phi1`), m.
fn swing_ankle(model: &gait_core::BodyModel<f32>, j: &[f32; JOINTS], phi1: f32) -> [f32; 2] {
    let phi = gait_control::posture::phi_from_joints(j, phi1, Side::Left);
    gait_core::kinematics::forward_kinematics(model, &phi)[4]
}

/// A sequencer with the paper's body model, asked to start walking from
/// its start posture: the rig, the model, what it senses, the posture.
fn started_with_a_model(img: &[u8]) -> (Rig<'_>, gait_core::BodyModel<f32>, Sensed, [f32; JOINTS]) {
    let mut rig = Rig::new(img);
    let model: gait_core::BodyModel<f32> = gait_core::BodyModel::<f64>::paper_table_iii().cast();
    rig.seq = rig.seq.with_model(model);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.start(Gait::Walk, &s);
    (rig, model, s, pose)
}

#[test]
fn a_swing_that_ends_without_contact_lowers_the_foot_until_it_lands() {
    let img = walk_image();
    let (mut rig, model, s, pose) = started_with_a_model(&img);
    let end_phi1 = rig.table.at_time(rig.table.duration_s())[0];
    let cfg = SequencerConfig::DEFAULT;
    // Play to the table's end with no contact: the table's last posture.
    let mut at_end = None;
    let mut heights = Vec::new();
    for _ in 0..20_000 {
        let r = rig.step(&s);
        if let Phase::Swing { t_s, .. } = rig.seq.phase() {
            if t_s <= rig.table.duration_s() {
                at_end = Some(r);
            } else {
                heights.push(swing_ankle_height(&model, &r, end_phi1));
            }
            if t_s > rig.table.duration_s() + cfg.ground_search_after_s + cfg.ground_search_s + 0.1
            {
                break;
            }
        }
    }
    let end = swing_ankle_height(&model, &at_end.unwrap(), end_phi1);
    // Down, never up, smoothly, by the configured depth at most.
    let lowest = heights.iter().copied().fold(f32::INFINITY, f32::min);
    assert!(heights.windows(2).all(|w| w[1] <= w[0] + 1e-6));
    assert!(
        heights
            .windows(2)
            .all(|w| (w[0] - w[1]) / DT <= 1.6 * cfg.ground_search_depth_m / cfg.ground_search_s),
        "faster than the search's eased speed"
    );
    // As deep as configured, or until the swing knee (right) is nearly
    // straight (this table lands with its knee nearly straight).
    let depth = end - lowest;
    let knee = rig.seq.reference()[3];
    assert!(
        depth > 0.005 && depth <= cfg.ground_search_depth_m + 1e-4,
        "{depth}"
    );
    assert!(
        depth >= cfg.ground_search_depth_m - 1e-4 || (knee - 0.1).abs() < 0.005,
        "stopped at {depth} m with the knee at {knee} rad"
    );
    assert!(rig.events.iter().all(|e| *e != SeqEvent::LandingTimeout));
    // The ground felt, and held for the landing's confirmation: the step
    // lands where the foot has got to.
    let before = rig.events.len();
    let confirm_ticks = (cfg.landing_confirm_s / DT).round() as usize;
    for tick in 1..=confirm_ticks {
        rig.step(&sensed(pose, [500.0, 200.0], READY_CRUTCHES));
        assert_eq!(
            rig.events[before..].contains(&SeqEvent::Landed),
            tick == confirm_ticks,
            "tick {tick} of {confirm_ticks}: {:?}",
            rig.events
        );
    }
    assert!(matches!(rig.seq.phase(), Phase::Transfer { .. }));
}

#[test]
fn a_force_spike_late_in_the_swing_is_not_a_landing() {
    let img = walk_image();
    let (mut rig, _model, s, pose) = started_with_a_model(&img);
    let cfg = SequencerConfig::DEFAULT;
    let confirm_ticks = (cfg.landing_confirm_s / DT).round() as usize;
    assert!(confirm_ticks > 3, "the campaign's spikes last 3 ms");
    // Into the landing window: 90 % of the table.
    for _ in 0..20_000 {
        if matches!(rig.seq.phase(), Phase::Swing { t_s, .. } if t_s > 0.9 * rig.table.duration_s())
        {
            break;
        }
        rig.step(&s);
    }
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
    // The swing foot's sensor (right) reads 400 N for 3 ticks, and again
    // for one tick short of the confirmation after a gap of one tick.
    let spike = sensed(pose, [500.0, 400.0], READY_CRUTCHES);
    for n in [3, confirm_ticks - 1] {
        for _ in 0..n {
            rig.step(&spike);
        }
        rig.step(&s);
    }
    assert!(!rig.events.contains(&SeqEvent::Landed), "{:?}", rig.events);
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
    // Held contact lands.
    for _ in 0..confirm_ticks {
        rig.step(&spike);
    }
    assert!(rig.events.contains(&SeqEvent::Landed), "{:?}", rig.events);
}

#[test]
fn without_a_model_a_swing_holds_the_tables_end_until_the_timeout() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.start(Gait::Walk, &s);
    let end = joints_from_phi(&rig.table.at_time(rig.table.duration_s()), Side::Left);
    for _ in 0..20_000 {
        let r = rig.step(&s);
        if let Phase::Swing { t_s, .. } = rig.seq.phase() {
            if t_s > rig.table.duration_s() + 0.5 {
                assert_eq!(r, end);
                break;
            }
        }
    }
}

#[test]
fn a_safe_hold_in_a_swing_sets_the_foot_down_until_it_feels_the_ground() {
    let img = walk_image();
    let (mut rig, model, s, pose) = started_with_a_model(&img);
    // Into the middle of the swing.
    let mut held = pose;
    let mut phi1 = f32::NAN;
    for _ in 0..20_000 {
        held = rig.step(&s);
        if let Phase::Swing { t_s, .. } = rig.seq.phase() {
            if t_s >= 0.5 * rig.table.duration_s() {
                phi1 = rig.table.at_time(t_s)[0];
                break;
            }
        }
    }
    assert!(phi1.is_finite());
    rig.hold(held, InSwing::HoldNow);
    let in_air = sensed(held, READY_FEET, READY_CRUTCHES);
    rig.step(&in_air);
    assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
    assert_eq!(
        rig.seq.status().swing_leg,
        Some(Side::Right),
        "moved as a swing leg"
    );
    let cfg = SequencerConfig::DEFAULT;
    let start = swing_ankle(&model, &held, phi1);
    let mut heights = Vec::new();
    for _ in 0..(0.5 * cfg.set_down_s / DT) as usize {
        let last = rig.step(&in_air);
        let a = swing_ankle(&model, &last, phi1);
        // Straight down while the leg reaches.
        assert!((a[0] - start[0]).abs() < 1e-4, "{a:?} from {start:?}");
        heights.push(a[1]);
        // The stance leg holds what was measured.
        assert!((last[0] - held[0]).abs() < 1e-5 && (last[1] - held[1]).abs() < 1e-5);
    }
    assert!(
        heights.windows(2).all(|w| w[1] <= w[0] + 1e-6),
        "down, never up"
    );
    let speed = heights
        .windows(2)
        .map(|w| (w[0] - w[1]) / DT)
        .fold(0.0, f32::max);
    assert!(
        speed <= 1.5 * cfg.set_down_depth_m / cfg.set_down_s + 1e-3,
        "{speed} m/s"
    );
    let depth = start[1] - heights.last().copied().unwrap_or(start[1]);
    assert!(depth > 0.03, "went down {depth} m");
    // The ground felt: the foot stays where it is, a stance leg's again.
    let contact = sensed(held, [500.0, 150.0], READY_CRUTCHES);
    let at_contact = rig.step(&contact);
    assert_eq!(rig.seq.status().swing_leg, None);
    for _ in 0..2_000 {
        assert_eq!(rig.step(&contact), at_contact);
        // Lifting off again does not restart it.
        assert_eq!(rig.step(&in_air), at_contact);
    }
    assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
}

/// The fastest the set-down moved the swing hip or knee reference, rad/s,
/// with `cfg`, from the middle of the walk's swing, the foot never finding
/// the ground.
fn set_down_joint_speed(img: &[u8], cfg: SequencerConfig) -> f32 {
    let (mut rig, model, s, pose) = started_with_a_model(img);
    rig.seq = Rig::with_config(img, cfg).seq.with_model(model);
    rig.start(Gait::Walk, &s);
    let mut held = pose;
    for _ in 0..20_000 {
        held = rig.step(&s);
        if matches!(rig.seq.phase(), Phase::Swing { t_s, .. } if t_s >= 0.5 * rig.table.duration_s())
        {
            break;
        }
    }
    rig.hold(held, InSwing::HoldNow);
    let in_air = sensed(held, READY_FEET, READY_CRUTCHES);
    let mut last = rig.step(&in_air);
    let mut fastest = 0.0f32;
    for _ in 0..(1.5 * cfg.set_down_s / DT) as usize {
        let now = rig.step(&in_air);
        for j in [Side::Right.hip(), Side::Right.hip() + 1] {
            fastest = fastest.max((now[j] - last[j]).abs() / DT);
        }
        last = now;
    }
    fastest
}

#[test]
fn the_set_down_moves_the_swing_leg_no_faster_than_its_joint_speed() {
    // Asked to go 60 cm down in 0.4 s, the ankle's target leaves the leg's
    // reach: near a straight knee the IK's answer races; the references
    // move at the set-down's joint speed at most.
    let img = walk_image();
    let mut cfg = SequencerConfig::DEFAULT;
    cfg.set_down_depth_m = 0.6;
    cfg.set_down_s = 0.4;
    let capped = set_down_joint_speed(&img, cfg);
    assert!(
        capped <= cfg.set_down_joint_speed_rad_s * 1.001 && capped > 0.5,
        "{capped} rad/s"
    );
    cfg.set_down_joint_speed_rad_s = f32::INFINITY;
    let free = set_down_joint_speed(&img, cfg);
    assert!(free > 2.0 * capped, "without the cap: {free} rad/s");
}

#[test]
fn a_safe_hold_standing_or_without_a_model_moves_no_foot() {
    let img = walk_image();
    // Without a model: the swing's joints hold what was measured.
    let (mut rig, s) = walking_in_a_swing(&img);
    let measured = rig.seq.reference();
    rig.hold(measured, InSwing::HoldNow);
    assert_eq!(rig.step(&s), measured);
    assert_eq!(rig.seq.status().swing_leg, None);
    for _ in 0..2_000 {
        assert_eq!(rig.step(&s), measured);
    }
    // Standing, with a model: nothing to set down.
    let mut rig = Rig::new(&img);
    let model: gait_core::BodyModel<f32> = gait_core::BodyModel::<f64>::paper_table_iii().cast();
    rig.seq = rig.seq.with_model(model);
    let pose = rig.start_pose(Side::Left);
    rig.hold(pose, InSwing::HoldNow);
    for _ in 0..2_000 {
        assert_eq!(rig.step(&sensed(pose, READY_FEET, READY_CRUTCHES)), pose);
    }
}

/// A joint the supervisor holds in place (`Verdict::rehold_joints`) is
/// held where it was measured from then on, the others as before; outside
/// a hold, or for a non-finite angle, nothing changes.
#[test]
fn a_joint_held_in_place_keeps_its_measured_angle_in_the_hold() {
    let img = walk_image();
    let mut rig = Rig::new(&img);
    let pose = rig.start_pose(Side::Left);
    let s = sensed(pose, READY_FEET, READY_CRUTCHES);
    rig.rehold(1, 0.9);
    assert_eq!(rig.step(&s), pose, "standing: not a hold, nothing moves");
    rig.hold(pose, InSwing::HoldNow);
    for _ in 0..50 {
        rig.step(&s);
    }
    rig.rehold(1, 0.9);
    rig.rehold(2, f32::NAN);
    let mut want = pose;
    want[1] = 0.9;
    for _ in 0..2_000 {
        assert_eq!(rig.step(&s), want);
    }
}

#[test]
fn after_a_restart_the_foot_found_unloaded_is_set_down() {
    let img = walk_image();
    let model: gait_core::BodyModel<f32> = gait_core::BodyModel::<f64>::paper_table_iii().cast();
    let found = [0.4, 0.3, 0.1, 0.6];
    let cases = [
        // Right foot carrying, left unloaded: the left is set down.
        ([0.0, 600.0], Some(Side::Left)),
        ([600.0, 10.0], Some(Side::Right)),
        // Both carrying, or a foot that cannot tell: a plain hold.
        ([400.0, 300.0], None),
        ([f32::NAN, 600.0], None),
        ([0.0, 0.0], None),
    ];
    for (feet, lifted) in cases {
        let mut rig = Rig::new(&img);
        rig.seq = rig.seq.with_model(model).restarted_at(found);
        let s = Sensed {
            joints_rad: found,
            feet_n: feet,
            crutches_n: READY_CRUTCHES,
            ankles_rad: [0.05, 0.05],
        };
        rig.orders.order = Order::HoldWhereFound;
        rig.orders.measured = Measured::of(&s);
        rig.step(&s);
        assert!(matches!(rig.seq.phase(), Phase::SafeHold { .. }));
        assert_eq!(rig.seq.status().swing_leg, lifted, "{feet:?}");
        let mut last = found;
        let mut stance_fed_forward = Side::Left;
        for _ in 0..300 {
            let r = rig.tick(&s);
            last = r.angle_rad;
            stance_fed_forward = r.stance;
        }
        match lifted {
            Some(leg) => {
                let stance = leg.other();
                assert_eq!(stance_fed_forward, stance, "{feet:?}");
                // The stance leg holds; the lifted leg's joints have moved.
                let (sh, lh) = (stance.hip(), leg.hip());
                assert_eq!(&last[sh..sh + 2], &found[sh..sh + 2], "{feet:?}");
                assert!(
                    (last[lh + 1] - found[lh + 1]).abs() > 0.01,
                    "{feet:?}: {last:?}"
                );
            }
            None => assert_eq!(last, found, "{feet:?}"),
        }
    }
}

#[test]
fn a_hold_for_a_saturated_drive_leaves_the_foot_in_the_air() {
    let img = walk_image();
    let (mut rig, _, s, _) = started_with_a_model(&img);
    let mut held = [0.0; JOINTS];
    while !matches!(rig.seq.phase(), Phase::Swing { t_s, .. } if t_s > 0.3) {
        held = rig.step(&s);
    }
    rig.hold(held, InSwing::HoldInAir);
    assert_eq!(rig.step(&s), held);
    assert_eq!(rig.seq.status().swing_leg, None);
    for _ in 0..2_000 {
        assert_eq!(rig.step(&s), held);
    }
}

#[test]
fn the_swing_foot_is_surely_in_the_air_only_in_its_landing_window() {
    // Early in a swing the trailing toe may still hold the ground (and its
    // ankle on the stop); from the landing window on the table has the
    // foot well up: only then the supervisor's stuck-ankle check runs.
    let img = walk_image();
    let (mut rig, _model, s, _pose) = started_with_a_model(&img);
    let window = SequencerConfig::DEFAULT.landing_window_fraction * rig.table.duration_s();
    let (mut early, mut late) = (0, 0);
    for _ in 0..20_000 {
        rig.step(&s);
        match rig.seq.phase() {
            Phase::Swing { t_s, .. } if t_s < window => {
                assert_eq!(rig.seq.status().swing_leg, Some(Side::Right));
                assert_eq!(rig.seq.status().airborne_leg, None, "{t_s} s");
                early += 1;
            }
            Phase::Swing { t_s, .. } => {
                if rig.seq.status().airborne_leg.is_some() {
                    assert_eq!(rig.seq.status().airborne_leg, Some(Side::Right), "{t_s} s");
                    late += 1;
                }
            }
            _ if early > 0 => break,
            _ => assert_eq!(rig.seq.status().airborne_leg, None),
        }
    }
    assert!(
        early > 100 && late > 100,
        "{early} early, {late} late ticks"
    );
    rig.hold(rig.seq.reference(), InSwing::HoldNow);
    rig.step(&s);
    assert_eq!(rig.seq.status().airborne_leg, None, "a hold plays no table");
}

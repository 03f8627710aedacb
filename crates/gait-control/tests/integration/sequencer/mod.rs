//! Gait execution rules, step by step, through the sequencer's one entry
//! `Sequencer::update`: start only from the planned posture with a verified
//! table (`start.rs`), swing only when the pilot is ready, landing only by
//! the foot sensor inside the landing window, stop at the end of the step
//! (`swing.rs`), alternate legs (`transfer.rs`), safe hold (`hold.rs`).
//! Here: the `Rig` that ticks it as the controller does, and the walks the
//! tests start from.
#![allow(clippy::needless_range_loop)]

mod hold;
mod replan;
mod start;
mod swing;
mod transfer;

use gait_control::faults::InSwing;
use gait_control::operator::Gait;
use gait_control::posture::{JOINTS, Side, joints_from_phi};
use gait_control::sequencer::{
    GaitTables, Measured, Order, Orders, Phase, Reference, RefuseReason, Sensed, SeqEvent,
    SeqInput, SeqRequest, Sequencer, SequencerConfig,
};
use gait_core::BodyModel;
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

/// The paper's body model (Table III), as the sequencer takes it.
fn paper_model() -> BodyModel<f32> {
    BodyModel::<f64>::paper_table_iii().cast()
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
        Self::with_table(GaitTable::parse(image).unwrap(), cfg)
    }

    fn with_table(table: GaitTable<'t>, cfg: SequencerConfig) -> Self {
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

    /// The same rig, its sequencer given `model` (the transfer and the
    /// set-down planned by the IK).
    fn with_model(mut self, model: BodyModel<f32>) -> Self {
        self.seq = self.seq.with_model(model);
        self
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
            ahead: None,
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

    /// A walk asked to start from the left-stance start posture, the feet
    /// and crutches loaded as when the pilot is ready: the rig, that
    /// posture, and what it senses there.
    fn walking(mut self) -> (Self, [f32; JOINTS], Sensed) {
        let (pose, s) = self.ready();
        self.start(Gait::Walk, &s);
        (self, pose, s)
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

    /// The left-stance start posture, and what is sensed there when the
    /// pilot is ready (feet and crutches loaded).
    fn ready(&self) -> ([f32; JOINTS], Sensed) {
        let pose = self.start_pose(Side::Left);
        (pose, sensed(pose, READY_FEET, READY_CRUTCHES))
    }
}

const READY_FEET: [f32; 2] = [500.0, 0.0];
const READY_CRUTCHES: [f32; 2] = [100.0, 100.0];

/// A walk on `img` (no model) asked to start from its start posture
/// (`Rig::walking`): the rig, the posture, what it senses.
fn started(img: &[u8]) -> (Rig<'_>, [f32; JOINTS], Sensed) {
    Rig::new(img).walking()
}

/// A sequencer with the paper's body model, asked to start walking from
/// its start posture: the rig, the model, what it senses, the posture.
fn started_with_a_model(img: &[u8]) -> (Rig<'_>, BodyModel<f32>, Sensed, [f32; JOINTS]) {
    let model = paper_model();
    let (rig, pose, s) = Rig::new(img).with_model(model).walking();
    (rig, model, s, pose)
}

/// A walk started from its start posture and played 0.7 s into its first
/// swing; the sensed readings it was started with.
fn walking_in_a_swing(img: &[u8]) -> (Rig<'_>, Sensed) {
    let (mut rig, _, s) = started(img);
    for _ in 0..700 {
        rig.step(&s);
    }
    assert!(matches!(rig.seq.phase(), Phase::Swing { .. }));
    (rig, s)
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

/// The swing ankle's position in the stance foot's frame for joint angles
/// `j` (stance left, the stance shank `phi1`), m.
fn swing_ankle(model: &BodyModel<f32>, j: &[f32; JOINTS], phi1: f32) -> [f32; 2] {
    let phi = gait_control::posture::phi_from_joints(j, phi1, Side::Left);
    gait_core::kinematics::forward_kinematics(model, &phi)[4]
}

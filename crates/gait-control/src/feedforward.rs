//! The model's feed-forward, worked out between two ticks.
//!
//! The joint torques the model gives for the reference (inverse dynamics
//! along a table, statics of a held posture, the load shared with the
//! other foot in double support) change over tens of milliseconds, and
//! they are the largest single piece of a tick's work. So the tick does not
//! work them out: it applies the answer to the request it made one tick
//! before, and makes the next request ([`ModelRequest`]). The feed-forward
//! a tick applies is therefore the model's torques for the previous tick's
//! reference, on the board and in the simulator alike.
//!
//! On the board a lower-priority interrupt answers between two ticks
//! ([`ModelTask`], through a [`ModelSlot`] of atomics: the tick never waits
//! for it and takes no lock). Without a slot (the host's simulation,
//! tests) the controller answers its last request itself at the start of
//! the next tick: the same arithmetic on the same inputs, so both give the
//! same commands bit for bit.
//!
//! ```text
//!   tick n:   apply answer(n − 1) ─► reference(n) ─► request(n) ─► write
//!   between:                               model task: answer(n)
//!   tick n+1: apply answer(n) …
//! ```

use core::sync::atomic::{AtomicU32, Ordering};

use gait_core::LINKS;
use gait_core::dynamics::{self, Contact, DoubleSupportStatics};
use gait_core::foot::StanceFoot;
use gait_core::kinematics::{Phi, Posture, joint_torques};
use gait_core::model::BodyModel;

use crate::ahead::{AheadSlot, Steps};
use crate::check_slot::CheckSlot;
use crate::posture::{JOINTS, Side, joint_torques_from_theta_torques};
use crate::supervisor::WindowedChecks;

/// What a tick asks of the model: its reference in the stance leg's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelRequest {
    /// Φ of the reference, rad.
    pub phi: Phi<f32>,
    /// While a table plays: Φ̇ (rad/s) and Φ̈ (rad/s²); `None` for a held
    /// or blended posture, whose statics are asked.
    pub motion: Option<(Phi<f32>, Phi<f32>)>,
    /// The vertical load the other foot may take, N (0: single support).
    pub other_load_n: f32,
    /// The stance leg.
    pub stance: Side,
}

/// The model's answer: joint torques along the reference and the load it
/// plans for the other foot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedForward {
    /// Joint torques, joint order, N·m.
    pub torques_nm: [f32; JOINTS],
    /// Vertical force the other foot is planned to carry, N.
    pub other_foot_n: f32,
    /// Joint torques (joint order) that one more newton pushed down by the
    /// other foot takes, N·m/N.
    pub per_other_foot_newton: [f32; JOINTS],
}

impl FeedForward {
    /// No torque: before the first answer.
    pub const NONE: Self = Self {
        torques_nm: [0.0; JOINTS],
        other_foot_n: 0.0,
        per_other_foot_newton: [0.0; JOINTS],
    };
}

/// The model's torques for `req`: inverse dynamics while a table plays,
/// statics otherwise, the stance foot rolling onto its toe past the ankle's
/// stop (`gait_core::foot`); the other foot takes up to `other_load_n`
/// where that lowers the effort (`dynamics::share_load`). Non-finite
/// values (a posture the model cannot describe) come out as 0.
#[must_use]
pub fn feedforward(model: &BodyModel<f32>, req: &ModelRequest) -> FeedForward {
    let contact = Contact::ToeRocker(StanceFoot::for_model(model));
    let posture = Posture::new(&req.phi);
    let single = joint_torques(&match &req.motion {
        Some((dphi, ddphi)) => {
            dynamics::inverse_dynamics_at(model, &contact, &posture, dphi, ddphi)
        }
        None => dynamics::static_torques_at(model, &contact, &posture),
    });
    // In single support nothing is shared: the answer is the
    // single-support torques and no reaction.
    let shared = if req.other_load_n > 0.0 {
        dynamics::share_load_at(model, &contact, &posture, &single, req.other_load_n)
    } else {
        DoubleSupportStatics {
            reaction_n: [0.0; 2],
            torques: single,
            per_newton: ([0.0; LINKS], [0.0; LINKS]),
        }
    };
    let ff = joint_torques_from_theta_torques(&shared.torques, req.stance);
    let (_, per_newton_up) = shared.per_newton;
    let per_newton = joint_torques_from_theta_torques(&per_newton_up.map(|v| -v), req.stance);
    let clean = |v: f32| if v.is_finite() { v } else { 0.0 };
    FeedForward {
        torques_nm: ff.map(clean),
        other_foot_n: clean(shared.reaction_n[1]),
        per_other_foot_newton: per_newton.map(clean),
    }
}

/// Flag bits of a request.
const MOVING: u32 = 1;
const RIGHT_STANCE: u32 = 2;

/// Five f32 as atomic words.
type Words5 = [AtomicU32; LINKS];
/// Four f32 as atomic words.
type Words4 = [AtomicU32; JOINTS];

fn store<const N: usize>(words: &[AtomicU32; N], values: &[f32; N]) {
    for (w, v) in words.iter().zip(values) {
        w.store(v.to_bits(), Ordering::Relaxed);
    }
}

fn load<const N: usize>(words: &[AtomicU32; N]) -> [f32; N] {
    let mut out = [0.0; N];
    for (o, w) in out.iter_mut().zip(words) {
        *o = f32::from_bits(w.load(Ordering::Relaxed));
    }
    out
}

/// The hand-off between the tick and the model task: every word an atomic,
/// one writer each way. The tick writes a request (it is never interrupted
/// by the task, so the task sees a whole one or, if the tick came while it
/// read, a changed sequence number and reads again); the task writes the
/// answer with an odd sequence number while it writes, so a tick that
/// interrupted it keeps the answer it had.
pub struct ModelSlot {
    /// Requests made so far.
    request_seq: AtomicU32,
    phi: Words5,
    dphi: Words5,
    ddphi: Words5,
    other_load_n: AtomicU32,
    flags: AtomicU32,
    /// Twice the answers begun, plus one while one is being written.
    answer_seq: AtomicU32,
    /// The request the answer is for.
    answered: AtomicU32,
    torques_nm: Words4,
    other_foot_n: AtomicU32,
    per_other_foot_newton: Words4,
    /// The work asked a tick ahead (the transfer's IK, the swing's table
    /// work).
    ahead: AheadSlot,
    /// The supervisor's windowed checks of the last tick's facts.
    checks: CheckSlot,
}

impl Default for ModelSlot {
    fn default() -> Self {
        Self::new()
    }
}

impl ModelSlot {
    /// Empty: no request, no answer.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            request_seq: AtomicU32::new(0),
            phi: [const { AtomicU32::new(0) }; LINKS],
            dphi: [const { AtomicU32::new(0) }; LINKS],
            ddphi: [const { AtomicU32::new(0) }; LINKS],
            other_load_n: AtomicU32::new(0),
            flags: AtomicU32::new(0),
            answer_seq: AtomicU32::new(0),
            answered: AtomicU32::new(0),
            torques_nm: [const { AtomicU32::new(0) }; JOINTS],
            other_foot_n: AtomicU32::new(0),
            per_other_foot_newton: [const { AtomicU32::new(0) }; JOINTS],
            ahead: AheadSlot::new(),
            checks: CheckSlot::new(),
        }
    }

    /// The hand-off of the work a tick ahead ([`crate::ahead`]).
    pub const fn ahead(&self) -> &AheadSlot {
        &self.ahead
    }

    /// The hand-off of the supervisor's windowed checks
    /// ([`crate::check_slot`]).
    pub const fn checks(&self) -> &CheckSlot {
        &self.checks
    }

    /// The tick: makes `req` the request; returns its number.
    pub fn request(&self, req: &ModelRequest) -> u32 {
        store(&self.phi, &req.phi);
        let mut flags = if req.stance == Side::Right {
            RIGHT_STANCE
        } else {
            0
        };
        if let Some((dphi, ddphi)) = &req.motion {
            store(&self.dphi, dphi);
            store(&self.ddphi, ddphi);
            flags |= MOVING;
        }
        self.other_load_n
            .store(req.other_load_n.to_bits(), Ordering::Relaxed);
        self.flags.store(flags, Ordering::Relaxed);
        let n = self.request_seq.load(Ordering::Relaxed).wrapping_add(1);
        self.request_seq.store(n, Ordering::Release);
        n
    }

    /// The tick: the newest whole answer and the request it is for; `None`
    /// before the first or while the task is writing one.
    pub fn answer(&self) -> Option<(u32, FeedForward)> {
        let seq = self.answer_seq.load(Ordering::Acquire);
        if seq == 0 || seq % 2 == 1 {
            return None;
        }
        Some((
            self.answered.load(Ordering::Relaxed),
            FeedForward {
                torques_nm: load(&self.torques_nm),
                other_foot_n: f32::from_bits(self.other_foot_n.load(Ordering::Relaxed)),
                per_other_foot_newton: load(&self.per_other_foot_newton),
            },
        ))
    }

    /// The tick: the answer to its last request, if the task has given it
    /// whole (else the tick keeps the one it applied before).
    pub fn answer_to_last_request(&self) -> Option<FeedForward> {
        let (n, ff) = self.answer()?;
        (n == self.request_seq.load(Ordering::Relaxed)).then_some(ff)
    }

    /// The task (and observers): the newest request and its number, read
    /// whole (a tick that came while it was read made a newer one: read
    /// again, at most a few times); `None` before the first request.
    pub fn newest_request(&self) -> Option<(u32, ModelRequest)> {
        for _ in 0..4 {
            let before = self.request_seq.load(Ordering::Acquire);
            if before == 0 {
                return None;
            }
            let flags = self.flags.load(Ordering::Relaxed);
            let req = ModelRequest {
                phi: load(&self.phi),
                motion: (flags & MOVING != 0).then(|| (load(&self.dphi), load(&self.ddphi))),
                other_load_n: f32::from_bits(self.other_load_n.load(Ordering::Relaxed)),
                stance: if flags & RIGHT_STANCE != 0 {
                    Side::Right
                } else {
                    Side::Left
                },
            };
            if self.request_seq.load(Ordering::Acquire) == before {
                return Some((before, req));
            }
        }
        None
    }

    /// The task: publishes `ff` as the answer to request `n`.
    fn publish(&self, n: u32, ff: &FeedForward) {
        let writing = self.answer_seq.load(Ordering::Relaxed).wrapping_add(1) | 1;
        self.answer_seq.store(writing, Ordering::Release);
        store(&self.torques_nm, &ff.torques_nm);
        self.other_foot_n
            .store(ff.other_foot_n.to_bits(), Ordering::Relaxed);
        store(&self.per_other_foot_newton, &ff.per_other_foot_newton);
        self.answered.store(n, Ordering::Relaxed);
        // Even again (never 0: 0 means no answer yet).
        self.answer_seq
            .store(writing.wrapping_add(1).max(2), Ordering::Release);
    }
}

/// The model's side of a [`ModelSlot`]: answers the tick's newest request.
/// Run it between two ticks, at a priority the tick preempts.
pub struct ModelTask<'t> {
    model: BodyModel<f32>,
    slot: &'t ModelSlot,
    checks: Option<WindowedChecks>,
    steps: Option<Steps<'t>>,
}

impl<'t> ModelTask<'t> {
    /// The task for the controller built with `model`, sharing `slot`.
    #[must_use]
    pub const fn new(model: BodyModel<f32>, slot: &'t ModelSlot) -> Self {
        Self {
            model,
            slot,
            checks: None,
            steps: None,
        }
    }

    /// The task that also runs the supervisor's windowed checks, with the
    /// memory the controller lent when it was given the slot
    /// ([`crate::controller::Controller::set_model_task`]).
    #[must_use]
    pub fn with_checks(self, checks: Option<WindowedChecks>) -> Self {
        Self { checks, ..self }
    }

    /// The task that also does a swing's table work a tick ahead
    /// ([`crate::ahead::Steps`], the controller's:
    /// [`crate::controller::Controller::steps`]); without them the tick
    /// does it itself.
    #[must_use]
    pub fn with_steps(self, steps: Steps<'t>) -> Self {
        Self {
            steps: Some(steps),
            ..self
        }
    }

    /// Runs the windowed checks of the newest tick's facts if they have not
    /// been run (its tick when they were), the newest ask of the work a
    /// tick ahead ([`crate::ahead`]), and answers the newest request for
    /// the feed-forward if it has no answer yet (its number when it did).
    pub fn serve(&mut self) -> Option<u32> {
        if let Some(c) = self.checks.as_mut() {
            self.slot.checks.serve(c);
        }
        self.slot.ahead.serve(&self.model, self.steps.as_ref());
        let (n, req) = self.slot.newest_request()?;
        if self.slot.answer().is_some_and(|(a, _)| a == n) {
            return None;
        }
        let ff = feedforward(&self.model, &req);
        self.slot.publish(n, &ff);
        Some(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(load: f32, moving: bool, stance: Side) -> ModelRequest {
        ModelRequest {
            phi: [0.05, -0.1, 0.12, 0.3, -0.2],
            motion: moving.then_some(([0.3, -0.5, 0.1, 1.2, -2.0], [1.0, 2.0, -3.0, 4.0, 5.0])),
            other_load_n: load,
            stance,
        }
    }

    #[test]
    fn the_task_answers_each_request_once_with_the_models_torques() {
        let model = BodyModel::<f32>::paper_table_iii();
        let slot = ModelSlot::new();
        let mut task = ModelTask::new(model, &slot);
        assert_eq!(task.serve(), None, "nothing asked yet");
        assert_eq!(slot.answer(), None);
        for req in [
            request(0.0, true, Side::Left),
            request(300.0, false, Side::Right),
            request(150.0, true, Side::Right),
        ] {
            let n = slot.request(&req);
            assert_eq!(task.serve(), Some(n));
            assert_eq!(task.serve(), None, "answered once");
            let (for_n, ff) = slot.answer().unwrap();
            assert_eq!(for_n, n);
            assert_eq!(ff, feedforward(&model, &req));
        }
    }

    #[test]
    fn a_request_crosses_the_slot_unchanged() {
        let slot = ModelSlot::new();
        for req in [
            request(0.0, true, Side::Left),
            request(812.5, false, Side::Right),
        ] {
            let n = slot.request(&req);
            assert_eq!(slot.newest_request(), Some((n, req)));
        }
    }

    #[test]
    fn an_answer_being_written_is_not_read() {
        let model = BodyModel::<f32>::paper_table_iii();
        let slot = ModelSlot::new();
        let mut task = ModelTask::new(model, &slot);
        slot.request(&request(0.0, true, Side::Left));
        task.serve();
        let before = slot.answer().unwrap();
        // A tick interrupting the task between its first and last word.
        slot.answer_seq.fetch_add(1, Ordering::Release);
        assert_eq!(slot.answer(), None);
        slot.answer_seq.fetch_add(1, Ordering::Release);
        assert_eq!(slot.answer(), Some(before));
    }

    #[test]
    fn the_model_shares_the_load_only_in_double_support() {
        let model = BodyModel::<f32>::paper_table_iii();
        let single = feedforward(&model, &request(0.0, false, Side::Left));
        assert_eq!(single.other_foot_n, 0.0);
        assert_eq!(single.per_other_foot_newton, [0.0; JOINTS]);
        let shared = feedforward(&model, &request(400.0, false, Side::Left));
        assert!(shared.other_foot_n > 0.0 && shared.other_foot_n <= 400.0);
        assert_ne!(shared.torques_nm, single.torques_nm);
        // Mirrored stance: the same torques on the other leg's joints.
        let mirrored = feedforward(&model, &request(400.0, false, Side::Right));
        let mut swapped = mirrored.torques_nm;
        swapped.swap(0, 2);
        swapped.swap(1, 3);
        assert_eq!(swapped, shared.torques_nm);
    }
}

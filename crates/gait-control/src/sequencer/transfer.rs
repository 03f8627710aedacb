//! The weight transfer between two steps, planned in double support: both
//! feet stay where they are while the stance shank, the torso and the knee
//! choice move from the landing posture to the next step's start posture,
//! and the IK keeps the trailing foot planted (blending joint angles
//! instead would make the legs fight each other through the ground).

use gait_core::BodyModel;
use gait_core::LINKS;
use gait_core::ik::{IkOptions, IkSolver};
use gait_core::kinematics::{Phi, forward_kinematics, swap_legs};

use crate::ahead::{AheadAsk, AheadJob, AheadSlot};
use crate::operator::{Gait, MAX_GAITS};
use crate::posture::{JOINTS, Side, joints_from_phi};

use super::{Phase, SeqEvent, SeqEvents, Sequencer, smoothstep};

/// A weight transfer in double support: both feet stay where they are, the
/// stance shank, torso and knee choice move from the landing posture to the
/// next step's start posture, and the IK keeps the trailing foot planted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct TransferPlan {
    /// The landing posture seen from the new stance foot (the links swap
    /// roles).
    landing_phi: Phi<f32>,
    /// (x5, y5, φ1, φ3, r2) at the landing (the end's are the slot's
    /// [`transfer_targets`]): worked out in the transfer's first tick, not
    /// in the landing's, which already plays the swing.
    from: Option<[f32; 5]>,
    /// Joint-angle offset at the landing between the reference and the IK's
    /// reconstruction of it (it decays to zero over the transfer, so the
    /// reference is continuous even where the landing posture lies outside
    /// the IK's human range). Solved in the transfer's second tick: each
    /// tick holds at most one IK solve (the tick's budget,
    /// `docs/safety.md`). The first two ticks hold the landing reference
    /// (the smoothstep has moved it by some 1e-6 of the way by then).
    offset: Option<[f32; JOINTS]>,
}

/// (x5, y5, φ1, φ3, r2) of posture `phi`: the swing ankle, the stance shank
/// and torso, and where φ2 sits in the IK's range for them.
pub(crate) fn transfer_params(
    model: &BodyModel<f32>,
    ik: &IkSolver<f32>,
    phi: &Phi<f32>,
) -> Option<[f32; 5]> {
    let [x5, y5] = forward_kinematics(model, phi).get(LINKS - 1).copied()?;
    let (lo, hi) = ik.phi2_range(x5, y5, phi[0]).ok()?;
    let r2 = if hi - lo > 1e-4 {
        ((phi[1] - lo) / (hi - lo)).clamp(0.0, 1.0)
    } else {
        0.5
    };
    Some([x5, y5, phi[0], phi[2], r2])
}

/// The transfer's end for each slot's table: the parameters of its first
/// posture, fixed with the tables, so a landing need not compute them.
pub(super) fn transfer_targets(
    model: &BodyModel<f32>,
    tables: &crate::sequencer::GaitTables<'_>,
) -> [Option<[f32; 5]>; MAX_GAITS] {
    let mut out = [None; MAX_GAITS];
    for (i, o) in out.iter_mut().enumerate() {
        *o = tables.slot(i).and_then(|table| {
            let ik = IkSolver::new(model).with_options(table.ik_options());
            transfer_params(model, &ik, &table.first())
        });
    }
    out
}

/// `gait`'s index in per-movement arrays (`SequencerConfig::lands_after`).
pub(super) const fn kind_index(gait: Gait) -> usize {
    match gait {
        Gait::Walk => 0,
        Gait::StairUp => 1,
        Gait::StairDown => 2,
    }
}

impl Sequencer<'_> {
    /// A tick of the weight transfer `t_s + dt_s` after the landing: on to
    /// the next step's start posture, then waiting for the pilot (or
    /// standing, when a stop was asked for). With `ahead`, the next tick's
    /// IK is asked of the model task ([`crate::ahead`]).
    pub(super) fn transfer_tick(
        &mut self,
        stance: Side,
        t_s: f32,
        dt_s: f32,
        ahead: Option<&AheadSlot>,
        events: &mut SeqEvents,
    ) -> [f32; JOINTS] {
        let cfg = self.cfg;
        let t = t_s + dt_s;
        let fraction_at = |t: f32| {
            if cfg.transfer_s > 0.0 {
                t / cfg.transfer_s
            } else {
                1.0
            }
        };
        let frac = fraction_at(t);
        if frac >= 1.0 {
            if self.stop_requested {
                self.phase = Phase::Standing;
                events.push(SeqEvent::Stopped);
            } else {
                self.phase = Phase::WaitingReady { stance };
            }
            self.blend_from = self.blend_to;
            self.blend_to
        } else {
            self.phase = Phase::Transfer { stance, t_s: t };
            let reference = self.transfer_reference(frac, stance, ahead);
            if let Some(slot) = ahead {
                self.ask_transfer_ik(slot, fraction_at(t + dt_s));
            }
            reference
        }
    }

    /// Asks the model task for what the transfer's next tick (at
    /// `next_fraction`) will solve: the landing offset's IK after the first
    /// tick, the path's after that.
    fn ask_transfer_ik(&self, slot: &AheadSlot, next_fraction: f32) {
        let (Some(plan), Some(options)) = (self.transfer, self.transfer_ik_options()) else {
            return;
        };
        let job = match (plan.from, plan.offset) {
            (Some(from), None) => AheadJob::Solve(from),
            (Some(from), Some(_)) if next_fraction < 1.0 => {
                let Some(to) = self.transfer_targets.get(self.slot).copied().flatten() else {
                    return;
                };
                AheadJob::Solve(transfer_point(&from, &to, next_fraction))
            }
            _ => return,
        };
        slot.request(&AheadAsk { job, options });
    }

    /// Asks the model task for the transfer's first tick: the landing
    /// posture's IK parameters.
    pub(super) fn ask_transfer_start(&self, slot: &AheadSlot) {
        if let (Some(plan), Some(options)) = (self.transfer, self.transfer_ik_options()) {
            slot.request(&AheadAsk {
                job: AheadJob::Params(plan.landing_phi),
                options,
            });
        }
    }

    /// The IK options of the gait's table; `None` without one.
    fn transfer_ik_options(&self) -> Option<IkOptions<f32>> {
        Some(self.table.as_ref()?.ik_options())
    }

    /// The double-support plan from the reference Φ at landing (old stance
    /// frame) to the next table's first posture (its parameters computed
    /// with the tables: [`transfer_targets`]); `None` without a model, a
    /// table or the slot's target (the transfer then blends joint angles).
    pub(super) fn plan_transfer(&self, landing_phi: &Phi<f32>) -> Option<TransferPlan> {
        self.model.as_ref()?;
        self.table.as_ref()?;
        self.transfer_targets.get(self.slot).copied().flatten()?;
        Some(TransferPlan {
            landing_phi: swap_legs(landing_phi),
            from: None,
            offset: None,
        })
    }

    /// `ask`'s answer: the model task's when it gave it, else worked out
    /// now (the same computation).
    fn ik_answer(
        model: &BodyModel<f32>,
        ahead: Option<&AheadSlot>,
        ask: &AheadAsk,
    ) -> Option<[f32; 5]> {
        match ahead.and_then(|slot| slot.answer_to(ask)) {
            Some(answer) => answer,
            None => ask.work(model),
        }
    }

    /// The transfer reference at `fraction` (smoothstepped), or the joint
    /// blend when there is no plan or the IK fails. The first call of a
    /// transfer finds the landing's parameters and the second its offset;
    /// both hold the landing reference.
    fn transfer_reference(
        &mut self,
        fraction: f32,
        stance: Side,
        ahead: Option<&AheadSlot>,
    ) -> [f32; JOINTS] {
        let planned = self.transfer.and_then(|plan| {
            let model = self.model.as_ref()?;
            let options = self.transfer_ik_options()?;
            let landing = joints_from_phi(&plan.landing_phi, stance);
            let answer = |job| Self::ik_answer(model, ahead, &AheadAsk { job, options });
            let Some(from) = plan.from else {
                let from = answer(AheadJob::Params(plan.landing_phi))?;
                return Some((landing, Solved::From(from)));
            };
            let Some(offset) = plan.offset else {
                let at_landing = joints_from_phi(&answer(AheadJob::Solve(from))?, stance);
                let mut offset = [0.0; JOINTS];
                for ((o, r), a) in offset.iter_mut().zip(&landing).zip(&at_landing) {
                    *o = r - a;
                }
                return Some((landing, Solved::Offset(offset)));
            };
            let to = self.transfer_targets.get(self.slot).copied().flatten()?;
            let s = smoothstep(fraction);
            let p = transfer_point(&from, &to, fraction);
            let mut joints = joints_from_phi(&answer(AheadJob::Solve(p))?, stance);
            for (j, &o) in joints.iter_mut().zip(&offset) {
                *j += (1.0 - s) * o;
            }
            Some((joints, Solved::Nothing))
        });
        match planned {
            Some((joints, solved)) => {
                if let Some(plan) = self.transfer.as_mut() {
                    match solved {
                        Solved::From(from) => plan.from = Some(from),
                        Solved::Offset(offset) => plan.offset = Some(offset),
                        Solved::Nothing => {}
                    }
                }
                joints
            }
            None => self.blended(fraction),
        }
    }
}

/// The transfer path's IK parameters at `fraction` (smoothstepped) of the
/// way from `from` to `to`.
fn transfer_point(from: &[f32; 5], to: &[f32; 5], fraction: f32) -> [f32; 5] {
    let s = smoothstep(fraction);
    let mut p = *from;
    for (v, &b) in p.iter_mut().zip(to) {
        *v += s * (b - *v);
    }
    p
}

/// What a transfer tick worked out for the ticks after it.
enum Solved {
    /// The landing's parameters (the first tick).
    From([f32; 5]),
    /// The landing's offset (the second).
    Offset([f32; JOINTS]),
    /// Nothing more: the plan is complete.
    Nothing,
}

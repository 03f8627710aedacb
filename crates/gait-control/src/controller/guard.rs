//! *guard*: the supervisor's verdict on everything sensed and commanded,
//! and the orders it gives the sequencer's next update. The windowed
//! checks (`supervisor/windowed.rs`) see this tick's facts after it: the
//! model task between this tick and the next, written into its slot in
//! place (a copy of them would cost the tick some 300 instructions), or
//! the controller itself at the end of this stage.

use crate::check_slot::Answer;
use crate::faults::Reaction;
use crate::feedforward::ModelSlot;
use crate::layout::Side;
use crate::position_loop::{JointGains, JointLoop};
use crate::posture::JOINTS;
use crate::reference::Reference;
use crate::sequencer::Orders;
use crate::supervisor::{
    Findings, Lent, MotorSense, Supervisor, Verdict, WindowedChecks, WindowedJob,
};

use super::Controller;
use super::act::Actuation;
use super::sense::Senses;

impl Controller<'_> {
    /// Stage 4: the supervisor's verdict on everything sensed and
    /// commanded, and the orders it gives the sequencer's next update.
    #[inline(always)]
    pub(super) fn guard(
        &mut self,
        s: &Senses,
        r: &Reference,
        a: &Actuation,
        deadline_missed: bool,
    ) -> Verdict {
        let status = &r.status;
        let airborne_leg = self.airborne_leg(s, status);
        let facts = Facts {
            tick: self.tick,
            s,
            r,
            a,
            deadline_missed,
            motors: &self.motor_sense,
            gains: &self.cfg.gains,
            airborne_leg,
            stance_hip_residual_nm: self.seq.stance_hip_residual_nm(),
        };
        let task = self.model_slot.filter(|_| self.checks_in_task);
        let mut verdict = check(
            &mut self.supervisor,
            task,
            (&mut self.windowed, &mut self.findings),
            &facts,
        );
        let estop_hold = self.stop_for_estop(&mut verdict, status);
        if verdict.reaction == Reaction::None && !estop_hold {
            // Nothing to order (most ticks): no fault latched re-holds a
            // joint either.
            self.orders = Orders::NONE;
            self.seq_status = *status;
        } else {
            self.orders = Orders::from_verdict(&verdict, estop_hold, &s.sensed);
            self.seq_status =
                status.obeying(&self.orders, &verdict.braked_joints, &self.cfg.sequencer);
        }
        if verdict.reaction == Reaction::DisableMotors {
            self.loops.iter_mut().for_each(JointLoop::reset);
        }
        verdict
    }
}

/// The supervisor's verdict: what the windowed checks found in the last
/// tick's facts and this tick's own checks; this tick's facts then go to
/// the windowed checks: the model task's (`task`, written in place in its
/// slot), or run here (`findings`, for the next tick).
#[inline(always)]
fn check(
    sup: &mut Supervisor<Lent>,
    task: Option<&ModelSlot>,
    (windowed, findings): (&mut Option<WindowedChecks>, &mut Findings),
    facts: &Facts<'_>,
) -> Verdict {
    let Some(slot) = task else {
        let mut job = WindowedJob::default();
        facts.write(&mut job);
        let verdict = sup.check_after(&job.input, &job.frames, findings, false);
        sup.mark(&mut job);
        // Lent only with a task: always here without one.
        if let Some(w) = windowed.as_mut() {
            *findings = w.run(&job);
        }
        return verdict;
    };
    slot.checks().exchange(|answer, job| {
        facts.write(job);
        let (found, late) = match answer {
            Answer::Found(f) => (f, false),
            Answer::NoneAsked => (&Findings::NONE, false),
            Answer::Late(_) => (&Findings::NONE, true),
        };
        let verdict = sup.check_after(&job.input, &job.frames, found, late);
        sup.mark(job);
        verdict
    })
}

/// This tick's facts for the supervisor.
struct Facts<'a> {
    tick: u32,
    s: &'a Senses,
    r: &'a Reference,
    a: &'a Actuation,
    deadline_missed: bool,
    /// The drivers' reports of the last write.
    motors: &'a [MotorSense; JOINTS],
    gains: &'a [JointGains; JOINTS],
    airborne_leg: Option<Side>,
    /// The playing gait's limit on the stance hip of its swings, N·m.
    stance_hip_residual_nm: f32,
}

impl Facts<'_> {
    /// Writes them into `job`, field by field (in place: on the board the
    /// job is the model task's slot).
    #[inline(always)]
    fn write(&self, job: &mut WindowedJob) {
        let (s, r, a) = (self.s, self.r, self.a);
        let input = &mut job.input;
        // Joints, then ankles (`layout::encoder`).
        let [j0, j1, j2, j3, left_ankle, right_ankle] = s.encoders;
        input.tick = self.tick;
        input.joints = [j0, j1, j2, j3];
        input.joint_reference_rad = r.angle_rad;
        input.ankles = [left_ankle, right_ankle];
        input.forces = s.forces;
        // Each motor's report with this tick's commands, built where it
        // goes (not the reports copied whole, then patched).
        for ((((m, last), &c), &f), g) in input
            .motors
            .iter_mut()
            .zip(self.motors)
            .zip(&a.command_nm)
            .zip(&a.feedforward_nm)
            .zip(self.gains)
        {
            *m = MotorSense {
                commanded_nm: c,
                feedforward_nm: f,
                limit_nm: g.torque_limit_nm,
                ..*last
            };
        }
        input.e_stop_pressed = s.e_stop_pressed;
        input.e_stop_read_error = s.e_stop_read_error;
        input.deadline_missed = self.deadline_missed;
        input.step_in_progress = r.status.step_in_progress();
        input.button_input_fault = s.mode.input_fault || s.go.input_fault;
        input.ankle_plan_rad = r.ankle_plan_rad;
        input.swing_leg = r.status.swing_leg;
        input.stance_hip_residual_nm = self.stance_hip_residual_nm;
        input.airborne_leg = self.airborne_leg;
        input.chain_closed = s.chain_closed;
        input.drive_current = Some(s.drive_current);
        job.frames = s.frames;
    }
}

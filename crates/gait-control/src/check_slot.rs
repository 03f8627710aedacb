//! The hand-off of the windowed checks (`supervisor/windowed.rs`) between
//! the tick and the model task: each tick leaves its facts
//! ([`WindowedJob`]), the task checks them before the next tick and leaves
//! its [`Findings`], which the next tick's guard applies.
//!
//! The two are too large for the model slot's atomic words (some 90 and
//! 140 words), so each sits in a critical section's cell. The tick runs
//! above the task and is never interrupted by it: its critical sections
//! never find a cell borrowed. The task's hold the tick off for one copy of
//! a job or of findings (about a microsecond at 168 MHz); the tick never
//! waits for the task's work.
//!
//! **A late task.** After a tick that overran, the next one comes before
//! the task has run: it finds no findings for the facts it handed over
//! ([`Answer::Late`]; the supervisor counts it as a missed deadline,
//! 0x0601) and replaces the
//! untaken job with its own (that tick's facts go unchecked by the windowed
//! rules, whose windows count it as not seen). A task the tick preempted
//! in the middle of a job finishes it and, its findings not yet taken, adds
//! the next job's to them: no finding is lost, they come a tick later.
//! Only a task two or more jobs behind fills the findings' room
//! ([`Findings::overflowed`]: 0x0608 at once).

use core::cell::RefCell;

use critical_section::Mutex;

#[cfg(test)]
use crate::supervisor::MAX_RAISES;
use crate::supervisor::{Findings, WindowedChecks, WindowedJob};

/// The last job, whether the tick has handed one over and whether the
/// task has still to take it. The job's room is made before the first
/// tick ([`CheckSlot::make_room`]), so no tick pays for making it.
struct JobCell {
    pending: bool,
    asked: bool,
    job: Option<WindowedJob>,
}

/// Findings and whether the tick has still to take them.
struct FoundCell {
    fresh: bool,
    found: Findings,
}

/// What the tick finds of the facts it handed over last.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Answer<'a> {
    /// Nothing handed over yet (the first tick).
    NoneAsked,
    /// The task's findings (of those facts, and of any before them it
    /// had not left yet).
    Found(&'a Findings),
    /// The task has not checked the facts of this tick yet.
    Late(u32),
}

/// The windowed checks' hand-off (one job and one answer in flight).
pub struct CheckSlot {
    job: Mutex<RefCell<JobCell>>,
    found: Mutex<RefCell<FoundCell>>,
}

impl Default for CheckSlot {
    fn default() -> Self {
        Self::new()
    }
}

impl CheckSlot {
    /// Empty: no job, no findings.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            job: Mutex::new(RefCell::new(JobCell {
                pending: false,
                asked: false,
                job: None,
            })),
            found: Mutex::new(RefCell::new(FoundCell {
                fresh: false,
                found: Findings::NONE,
            })),
        }
    }

    /// The tick: `f` on the answer to the facts it handed over last (the
    /// findings taken, once) and on the job it fills with this tick's
    /// facts for the task, in place (replacing any the task has not taken).
    #[inline(always)]
    pub fn exchange<R>(&self, f: impl FnOnce(Answer<'_>, &mut WindowedJob) -> R) -> R {
        critical_section::with(|cs| {
            // Never borrowed while the tick runs (the task borrows only in
            // its own critical sections); the job goes nowhere otherwise.
            let mut job = self.job.borrow(cs).try_borrow_mut().ok();
            let asked = job
                .as_ref()
                .filter(|c| c.asked)
                .and_then(|c| c.job.as_ref())
                .map(WindowedJob::tick);
            let mut found = self.found.borrow(cs).try_borrow_mut().ok();
            let answer = match asked {
                None => Answer::NoneAsked,
                Some(tick) => found
                    .as_deref_mut()
                    .filter(|c| c.fresh && c.found.tick() == tick)
                    .map_or(Answer::Late(tick), |c| {
                        c.fresh = false;
                        Answer::Found(&c.found)
                    }),
            };
            let Some(cell) = job.as_deref_mut() else {
                return f(answer, &mut WindowedJob::default());
            };
            let out = f(answer, cell.job.get_or_insert_with(WindowedJob::default));
            cell.pending = true;
            cell.asked = true;
            out
        })
    }

    /// Makes the job's room (a job's worth of zeros written once), before
    /// the first tick: [`crate::controller::Controller::set_model_task`].
    pub fn make_room(&self) {
        critical_section::with(|cs| {
            if let Ok(mut cell) = self.job.borrow(cs).try_borrow_mut() {
                cell.job.get_or_insert_with(WindowedJob::default);
            }
        });
    }

    /// The task: checks the newest job with `checks` and leaves the
    /// findings (added to those the tick has not taken yet); the job's
    /// tick, or `None` if there was none to take.
    pub fn serve(&self, checks: &mut WindowedChecks) -> Option<u32> {
        let job = self.take_job()?;
        self.leave(&checks.run(&job));
        Some(job.tick())
    }

    /// The task: the job the tick left, if it has not been taken.
    fn take_job(&self) -> Option<WindowedJob> {
        critical_section::with(|cs| {
            let mut cell = self.job.borrow(cs).try_borrow_mut().ok()?;
            if !cell.pending {
                return None;
            }
            cell.pending = false;
            cell.job
        })
    }

    /// The task: leaves `found`, added to findings the tick has not taken.
    fn leave(&self, found: &Findings) {
        critical_section::with(|cs| {
            if let Ok(mut cell) = self.found.borrow(cs).try_borrow_mut() {
                if cell.fresh {
                    cell.found.merge(found);
                } else {
                    cell.found = *found;
                    cell.fresh = true;
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::faults::FaultCode;
    use crate::supervisor::{ForceSense, ForceStatus, Supervisor, SupervisorConfig};

    fn checks() -> WindowedChecks {
        let (_, checks) = Supervisor::new(SupervisorConfig::paper()).unwrap().lend();
        checks
    }

    /// Tick `tick`'s facts into `job`: a force sensor that reads Ok but not
    /// finite when `bad` (0x0304 at once), else all in order.
    fn fill(job: &mut WindowedJob, tick: u32, bad: bool) {
        *job = WindowedJob::default();
        job.input.tick = tick;
        job.input.forces = [ForceSense {
            status: ForceStatus::Ok,
            newtons: 100.0,
        }; crate::layout::FORCES];
        if bad {
            job.input.forces[0].newtons = f32::NAN;
        }
    }

    /// One tick: the answer it found (the findings' tick and whether they
    /// hold 0x0304, or late), its facts handed over.
    fn tick(slot: &CheckSlot, tick: u32, bad: bool) -> Result<Option<(u32, usize)>, u32> {
        slot.exchange(|answer, job| {
            fill(job, tick, bad);
            match answer {
                Answer::NoneAsked => Ok(None),
                Answer::Found(f) => {
                    let n = f
                        .raises()
                        .iter()
                        .filter(|r| r.code() == FaultCode::ForceOutOfRange)
                        .count();
                    Ok(Some((f.tick(), n)))
                }
                Answer::Late(t) => Err(t),
            }
        })
    }

    #[test]
    fn room_made_before_the_first_tick_is_no_job_handed_over() {
        let slot = CheckSlot::new();
        slot.make_room();
        assert_eq!(slot.serve(&mut checks()), None, "no job for the task");
        assert_eq!(tick(&slot, 1, false), Ok(None), "nothing asked yet");
        assert_eq!(slot.serve(&mut checks()), Some(1));
        assert_eq!(tick(&slot, 2, false), Ok(Some((1, 0))));
    }

    #[test]
    fn each_ticks_facts_are_answered_by_the_next_tick_once() {
        let slot = CheckSlot::new();
        let mut c = checks();
        assert_eq!(tick(&slot, 1, true), Ok(None), "nothing asked yet");
        assert_eq!(slot.serve(&mut c), Some(1));
        assert_eq!(slot.serve(&mut c), None, "taken once");
        assert_eq!(tick(&slot, 2, false), Ok(Some((1, 1))));
        slot.serve(&mut c);
        assert_eq!(tick(&slot, 3, false), Ok(Some((2, 0))));
    }

    #[test]
    fn a_tick_that_left_the_task_no_time_finds_the_answer_late_and_replaces_the_job() {
        let slot = CheckSlot::new();
        let mut c = checks();
        tick(&slot, 1, false).unwrap();
        // Tick 1 overran: tick 2 comes before the task.
        assert_eq!(tick(&slot, 2, true), Err(1));
        assert_eq!(slot.serve(&mut c), Some(2), "tick 1's facts replaced");
        assert_eq!(tick(&slot, 3, false), Ok(Some((2, 1))));
    }

    #[test]
    fn a_task_preempted_in_a_job_adds_its_findings_to_the_next_and_loses_none() {
        let slot = CheckSlot::new();
        let mut c = checks();
        tick(&slot, 1, true).unwrap();
        // The task takes tick 1's job; tick 2 preempts it before it leaves
        // its findings.
        let job = slot.take_job().unwrap();
        assert_eq!(tick(&slot, 2, true), Err(1));
        slot.leave(&c.run(&job));
        // PendSV, pended again by tick 2, checks its facts.
        assert_eq!(slot.serve(&mut c), Some(2));
        assert_eq!(
            tick(&slot, 3, false),
            Ok(Some((2, 2))),
            "both ticks' 0x0304"
        );
    }

    #[test]
    fn findings_the_tick_never_takes_overflow_and_say_so() {
        let slot = CheckSlot::new();
        let mut c = checks();
        let mut job = WindowedJob::default();
        fill(&mut job, 1, true);
        let one = c.run(&job);
        assert!(!one.overflowed());
        let overflowed =
            || critical_section::with(|cs| slot.found.borrow(cs).borrow().found.overflowed());
        // One raise each: the room holds MAX_RAISES of them.
        for _ in 0..MAX_RAISES {
            slot.leave(&one);
        }
        assert!(!overflowed());
        slot.leave(&one);
        assert!(overflowed());
    }
}

//! The hand-off of the windowed checks (`supervisor/windowed.rs`) between
//! the tick and the model task: each tick leaves its facts
//! ([`WindowedJob`]), the task checks them before the next tick and leaves
//! its [`Findings`], which the next tick's guard applies.
//!
//! The two are too large for the model slot's atomic words (some 90 and
//! 130 words), so each sits in a critical section's cell. The tick runs
//! above the task and is never interrupted by it: its critical sections
//! never find a cell borrowed and cost it a few instructions. The task's
//! hold the tick off for one copy of a job or of findings (about a
//! microsecond at 168 MHz); the tick never waits for the task's work.

use core::cell::RefCell;

use critical_section::Mutex;

use crate::supervisor::{Findings, WindowedChecks, WindowedJob};

/// A job and whether the task has still to take it.
struct JobCell {
    pending: bool,
    job: Option<WindowedJob>,
}

/// Findings and whether the tick has still to take them.
struct FoundCell {
    fresh: bool,
    found: Findings,
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
                job: None,
            })),
            found: Mutex::new(RefCell::new(FoundCell {
                fresh: false,
                found: Findings::NONE,
            })),
        }
    }

    /// The tick: `f` on the findings for the facts of tick `tick` if the
    /// task has left them (each is taken once; else `None`) and on the job
    /// it fills with this tick's facts for the task, in place (replacing
    /// any the task has not taken).
    #[inline(always)]
    pub fn exchange<R>(
        &self,
        tick: u32,
        f: impl FnOnce(Option<&Findings>, &mut WindowedJob) -> R,
    ) -> R {
        critical_section::with(|cs| {
            let mut found = self.found.borrow(cs).try_borrow_mut().ok();
            let found = found
                .as_deref_mut()
                .filter(|c| c.fresh && c.found.tick() == tick)
                .map(|c| {
                    c.fresh = false;
                    &c.found
                });
            // Never borrowed while the tick runs (the task borrows only in
            // its own critical sections); the job goes nowhere otherwise.
            let Ok(mut cell) = self.job.borrow(cs).try_borrow_mut() else {
                return f(found, &mut WindowedJob::default());
            };
            let out = f(found, cell.job.get_or_insert_with(WindowedJob::default));
            cell.pending = true;
            out
        })
    }

    /// The task: checks the newest job with `checks` and leaves the
    /// findings; the job's tick, or `None` if there was none to take.
    pub fn serve(&self, checks: &mut WindowedChecks) -> Option<u32> {
        let job = critical_section::with(|cs| {
            let mut cell = self.job.borrow(cs).try_borrow_mut().ok()?;
            if !cell.pending {
                return None;
            }
            cell.pending = false;
            cell.job
        })?;
        let found = checks.run(&job);
        critical_section::with(|cs| {
            if let Ok(mut cell) = self.found.borrow(cs).try_borrow_mut() {
                cell.found = found;
                cell.fresh = true;
            }
        });
        Some(job.tick())
    }
}

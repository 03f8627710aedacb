//! Work a tick ahead, by the model task ([`crate::feedforward::ModelTask`]):
//! the weight transfer's inverse kinematics and the swing foot's planned
//! share.
//!
//! Between two steps the reference follows a path in the IK's parameters
//! (`sequencer/transfer.rs`): each tick solves the IK once, the largest
//! piece of a transfer tick. In a swing each tick works out where the
//! table puts the swing foot's toe, for the share of the body it may carry
//! (the landing window and the load sharing). Both are known a tick ahead
//! (the transfer's path once the foot has landed, the table's next
//! posture), so the tick asks for the next one and the model task answers
//! between the two ticks; the next tick takes the answer if it is for
//! exactly what it needs (the same job, bit for bit) and works it out
//! itself otherwise. The answer is the very computation the tick would
//! make, so the reference is the same either way.

use core::sync::atomic::{AtomicU32, Ordering};

use gait_core::BodyModel;
use gait_core::foot::StanceFoot;
use gait_core::ik::{IkOptions, IkSolver, KneeRange};
use gait_core::kinematics::{Phi, Posture};
use gait_core::playback::{other_foot_share, swing_toe_at};

use crate::sequencer::transfer_params;

/// One piece of work a tick needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AheadJob {
    /// The IK's parameters (x5, y5, φ1, φ3, r2) of a posture Φ: where the
    /// transfer starts.
    Params(Phi<f32>),
    /// The posture Φ at parameters (x5, y5, φ1, φ3, r2).
    Solve([f32; 5]),
    /// The share of the body's weight a swing foot may carry at a table's
    /// posture Φ, its toe having started at (x, y) (the stance foot's flat
    /// frame; `gait_core::playback::other_foot_share`): the first value.
    SwingShare(Phi<f32>, [f32; 2]),
}

/// A job with the IK options of the table it is for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AheadAsk {
    /// What to work out.
    pub job: AheadJob,
    /// The IK the table was made with.
    pub options: IkOptions<f32>,
}

impl AheadAsk {
    /// The answer: five values, or `None` where the IK has none.
    #[must_use]
    pub fn work(&self, model: &BodyModel<f32>) -> Option<[f32; 5]> {
        let ik = || IkSolver::new(model).with_options(self.options);
        match &self.job {
            AheadJob::Params(phi) => transfer_params(model, &ik(), phi),
            AheadJob::SwingShare(phi, start) => {
                let foot = StanceFoot::for_model(model);
                let toe = swing_toe_at(model, &foot, &Posture::new(phi));
                Some([other_foot_share(toe, *start), 0.0, 0.0, 0.0, 0.0])
            }
            AheadJob::Solve([x5, y5, phi1, phi3, r2]) => ik()
                .solve(&gait_core::ik::IkTarget {
                    x5: *x5,
                    y5: *y5,
                    phi1: *phi1,
                    phi3: *phi3,
                    r2: *r2,
                })
                .ok()
                .map(|s| s.phi),
        }
    }

    /// Its words: the kind and the knee range as flags, the cap, the input.
    fn words(&self) -> (u32, u32, [u32; 7]) {
        let (kind, input, [x, y]) = match &self.job {
            AheadJob::Params(phi) => (0, *phi, [0.0; 2]),
            AheadJob::Solve(p) => (SOLVE, *p, [0.0; 2]),
            AheadJob::SwingShare(phi, start) => (SHARE, *phi, *start),
        };
        let [a, b, c, d, e] = input.map(f32::to_bits);
        let range = match self.options.knee_range {
            KneeRange::Reach => 0,
            KneeRange::Human => HUMAN_RANGE,
        };
        (
            kind | range,
            self.options.stance_knee_max_rad.to_bits(),
            [a, b, c, d, e, x.to_bits(), y.to_bits()],
        )
    }
}

/// Flag bits of an ask.
const SOLVE: u32 = 1;
const HUMAN_RANGE: u32 = 2;
const SHARE: u32 = 4;
/// [`AheadSlot::at`] of an ask that is not a swing's share (a NaN's bits:
/// no time's).
const NOT_AT: u32 = 0x7FC0_0000;
/// Flag bit of an answer: the IK found one.
const FOUND: u32 = 1;

/// The hand-off of the work a tick ahead, one writer each way, as the
/// feed-forward's
/// ([`crate::feedforward::ModelSlot`]).
#[derive(Debug)]
pub struct AheadSlot {
    request_seq: AtomicU32,
    flags: AtomicU32,
    cap: AtomicU32,
    input: [AtomicU32; 7],
    /// The time the tick asked a swing's share for (its bits; NaN's for
    /// other asks): [`AheadSlot::asked_posture`].
    at: AtomicU32,
    answer_seq: AtomicU32,
    answered: AtomicU32,
    found: AtomicU32,
    output: [AtomicU32; 5],
}

impl Default for AheadSlot {
    fn default() -> Self {
        Self::new()
    }
}

impl AheadSlot {
    /// Nothing asked.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            request_seq: AtomicU32::new(0),
            flags: AtomicU32::new(0),
            cap: AtomicU32::new(0),
            input: [const { AtomicU32::new(0) }; 7],
            at: AtomicU32::new(NOT_AT),
            answer_seq: AtomicU32::new(0),
            answered: AtomicU32::new(0),
            found: AtomicU32::new(0),
            output: [const { AtomicU32::new(0) }; 5],
        }
    }

    /// Asks made so far (for observers).
    pub fn asked(&self) -> u32 {
        self.request_seq.load(Ordering::Relaxed)
    }

    /// The tick: asks for `ask`'s answer by the next tick.
    pub fn request(&self, ask: &AheadAsk) {
        self.request_at(ask, NOT_AT);
    }

    /// The tick: asks for a swing's share at its posture `at_s` into the
    /// swing ([`AheadJob::SwingShare`]); the next tick reads the posture
    /// back ([`AheadSlot::asked_posture`]).
    pub fn request_swing_share(&self, ask: &AheadAsk, at_s: f32) {
        self.request_at(ask, at_s.to_bits());
    }

    /// The tick: the table posture it asked the share for at `at_s` into
    /// the swing whose toe started at `start` (the table's interpolation
    /// there, bit for bit), if that was its last ask.
    pub fn asked_posture(&self, at_s: f32, start: [f32; 2]) -> Option<Phi<f32>> {
        let [a, b, c, d, e, x, y] = self.input.each_ref().map(|w| w.load(Ordering::Relaxed));
        let asked = self.flags.load(Ordering::Relaxed) & SHARE != 0
            && self.at.load(Ordering::Relaxed) == at_s.to_bits()
            && [x, y] == start.map(f32::to_bits);
        asked.then(|| [a, b, c, d, e].map(f32::from_bits))
    }

    fn request_at(&self, ask: &AheadAsk, at: u32) {
        self.at.store(at, Ordering::Relaxed);
        let (flags, cap, input) = ask.words();
        self.flags.store(flags, Ordering::Relaxed);
        self.cap.store(cap, Ordering::Relaxed);
        for (w, v) in self.input.iter().zip(input) {
            w.store(v, Ordering::Relaxed);
        }
        let n = self.request_seq.load(Ordering::Relaxed).wrapping_add(1);
        self.request_seq.store(n, Ordering::Release);
    }

    /// The tick: the answer to `ask` if its last request was `ask`, bit for
    /// bit, and the task has answered it whole (`Some(None)`: the IK has
    /// none); `None` otherwise (the tick works it out).
    pub fn answer_to(&self, ask: &AheadAsk) -> Option<Option<[f32; 5]>> {
        let seq = self.answer_seq.load(Ordering::Acquire);
        let last = self.request_seq.load(Ordering::Relaxed);
        if seq == 0 || seq % 2 == 1 || self.answered.load(Ordering::Relaxed) != last {
            return None;
        }
        let (flags, cap, input) = ask.words();
        let same = self.flags.load(Ordering::Relaxed) == flags
            && self.cap.load(Ordering::Relaxed) == cap
            && self
                .input
                .iter()
                .zip(input)
                .all(|(w, v)| w.load(Ordering::Relaxed) == v);
        if !same {
            return None;
        }
        let found = self.found.load(Ordering::Relaxed) & FOUND != 0;
        let out = self
            .output
            .each_ref()
            .map(|w| f32::from_bits(w.load(Ordering::Relaxed)));
        Some(found.then_some(out))
    }

    /// The task: the newest ask and its number, read whole; `None` before
    /// the first, or if ticks kept replacing it while it was read.
    fn newest(&self) -> Option<(u32, AheadAsk)> {
        for _ in 0..4 {
            let before = self.request_seq.load(Ordering::Acquire);
            if before == 0 {
                return None;
            }
            let flags = self.flags.load(Ordering::Relaxed);
            let cap = f32::from_bits(self.cap.load(Ordering::Relaxed));
            let [a, b, c, d, e, x, y] = self
                .input
                .each_ref()
                .map(|w| f32::from_bits(w.load(Ordering::Relaxed)));
            if self.request_seq.load(Ordering::Acquire) != before {
                continue;
            }
            let input = [a, b, c, d, e];
            let job = if flags & SHARE != 0 {
                AheadJob::SwingShare(input, [x, y])
            } else if flags & SOLVE != 0 {
                AheadJob::Solve(input)
            } else {
                AheadJob::Params(input)
            };
            let knee_range = if flags & HUMAN_RANGE != 0 {
                KneeRange::Human
            } else {
                KneeRange::Reach
            };
            return Some((
                before,
                AheadAsk {
                    job,
                    options: IkOptions {
                        stance_knee_max_rad: cap,
                        knee_range,
                    },
                },
            ));
        }
        None
    }

    /// The task: answers the newest ask if it has no answer yet; its
    /// number when it did.
    pub(crate) fn serve(&self, model: &BodyModel<f32>) -> Option<u32> {
        let (n, ask) = self.newest()?;
        let seq = self.answer_seq.load(Ordering::Relaxed);
        if seq != 0 && seq & 1 == 0 && self.answered.load(Ordering::Relaxed) == n {
            return None;
        }
        let out = ask.work(model);
        let writing = seq.wrapping_add(1) | 1;
        self.answer_seq.store(writing, Ordering::Release);
        for (w, v) in self.output.iter().zip(out.unwrap_or([0.0; 5])) {
            w.store(v.to_bits(), Ordering::Relaxed);
        }
        self.found
            .store(if out.is_some() { FOUND } else { 0 }, Ordering::Relaxed);
        self.answered.store(n, Ordering::Relaxed);
        self.answer_seq
            .store(writing.wrapping_add(1).max(2), Ordering::Release);
        Some(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gait_core::kinematics::forward_kinematics;

    fn model() -> BodyModel<f32> {
        BodyModel::<f32>::paper_table_iii()
    }

    #[test]
    fn an_answer_serves_only_the_ask_it_was_made_for() {
        let m = model();
        let slot = AheadSlot::new();
        let phi = [0.1, 0.35, 0.05, 2.9, 3.3];
        let params = AheadAsk {
            job: AheadJob::Params(phi),
            options: IkOptions::paper(),
        };
        assert_eq!(slot.answer_to(&params), None, "nothing asked");
        slot.request(&params);
        assert_eq!(slot.answer_to(&params), None, "not answered yet");
        assert!(slot.serve(&m).is_some());
        assert!(slot.serve(&m).is_none(), "answered once");
        let answer = slot.answer_to(&params).unwrap();
        assert_eq!(answer, params.work(&m));
        let p = answer.unwrap();
        // The same posture's ankle: the parameters are its own.
        let ankle = forward_kinematics(&m, &phi)[4];
        assert_eq!([p[0], p[1]], ankle);
        // Another job, or the same with other options, is not answered.
        let solve = AheadAsk {
            job: AheadJob::Solve(p),
            options: IkOptions::paper(),
        };
        assert_eq!(slot.answer_to(&solve), None);
        let human = AheadAsk {
            options: IkOptions {
                knee_range: KneeRange::Human,
                ..IkOptions::paper()
            },
            ..params
        };
        assert_eq!(slot.answer_to(&human), None);
        // Asked, the solve comes back as the tick would work it out.
        slot.request(&solve);
        assert_eq!(slot.answer_to(&params), None, "a newer ask replaced it");
        slot.serve(&m);
        assert_eq!(slot.answer_to(&solve), Some(solve.work(&m)));
    }

    #[test]
    fn a_swing_foot_carries_the_body_only_near_where_its_toe_started() {
        let m = model();
        let phi = [0.1, 0.35, 0.05, 2.9, 3.3];
        let toe = swing_toe_at(&m, &StanceFoot::for_model(&m), &Posture::new(&phi));
        let share = |start: [f32; 2]| {
            AheadAsk {
                job: AheadJob::SwingShare(phi, start),
                options: IkOptions::paper(),
            }
            .work(&m)
            .map(|[s, ..]| s)
        };
        assert_eq!(share(toe), Some(1.0), "still where it started");
        assert_eq!(share([toe[0] - 0.05, toe[1]]), Some(0.0), "5 cm on");
        let half = share([toe[0] - 0.007, toe[1]]).unwrap();
        assert!(
            (half - 0.5).abs() < 1e-3,
            "halfway between 2 and 12 mm: {half}"
        );
    }

    #[test]
    fn the_posture_asked_with_a_share_is_read_back_for_its_time_and_swing_only() {
        let slot = AheadSlot::new();
        let phi = [0.1, 0.35, 0.05, 2.9, 3.3];
        let start = [-0.3, 0.0];
        let share = AheadAsk {
            job: AheadJob::SwingShare(phi, start),
            options: IkOptions::paper(),
        };
        slot.request_swing_share(&share, 0.125);
        assert_eq!(slot.asked_posture(0.125, start), Some(phi));
        assert_eq!(slot.asked_posture(0.126, start), None, "another time");
        assert_eq!(
            slot.asked_posture(0.125, [-0.2, 0.0]),
            None,
            "another swing"
        );
        // Any other ask replaces it.
        slot.request(&AheadAsk {
            job: AheadJob::Params(phi),
            options: IkOptions::paper(),
        });
        assert_eq!(slot.asked_posture(0.125, start), None);
        slot.request(&share);
        assert_eq!(
            slot.asked_posture(0.125, start),
            None,
            "asked without its time"
        );
    }

    #[test]
    fn an_answer_being_written_is_not_read_and_no_solution_is_an_answer() {
        let m = model();
        let slot = AheadSlot::new();
        let far = AheadAsk {
            job: AheadJob::Solve([5.0, 0.0, 0.0, 0.0, 0.5]),
            options: IkOptions::paper(),
        };
        slot.request(&far);
        slot.serve(&m);
        assert_eq!(slot.answer_to(&far), Some(None), "out of reach");
        slot.answer_seq.fetch_add(1, Ordering::Release);
        assert_eq!(slot.answer_to(&far), None, "being written");
    }
}

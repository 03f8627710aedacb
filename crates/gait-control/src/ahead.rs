//! Work a tick ahead, by the model task ([`crate::feedforward::ModelTask`]):
//! the weight transfer's inverse kinematics and the swing's table work.
//!
//! Between two steps the reference follows a path in the IK's parameters
//! (`sequencer/transfer.rs`): each tick solves the IK once, the largest
//! piece of a transfer tick. In a swing each tick reads the step's table
//! three times (its posture, and the two samples of its central
//! differences: [`crate::reference::table_motion`]) and works out where
//! the table puts the swing foot's toe, for the share of the body it may
//! carry (the landing window and the load sharing). Both are known a tick
//! ahead (the transfer's path once the foot has landed, the step's next
//! time), so the tick asks for the next one and the model task answers
//! between the two ticks; the next tick takes the answer if it is for
//! exactly what it needs (the same job, bit for bit) and works it out
//! itself otherwise. The answer is the very computation the tick would
//! make, so the reference is the same either way.

use core::sync::atomic::{AtomicU32, Ordering};

use gait_core::BodyModel;
use gait_core::ik::{IkOptions, IkSolver, KneeRange};
use gait_core::kinematics::Phi;
use gait_core::reach::place_swing_ankle_from;

use crate::sequencer::{SEARCH_MIN_KNEE_FLEXION_RAD, transfer_params};

mod swing;
pub use swing::{Steps, SwingAnswer, SwingKey};

/// Words of an answer: a swing's Φ, Φ̇, Φ̈, start and share; the IK's five.
const OUTPUT_WORDS: usize = 18;

/// One piece of work a tick needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AheadJob {
    /// The IK's parameters (x5, y5, φ1, φ3, r2) of a posture Φ: where the
    /// transfer starts.
    Params(Phi<f32>),
    /// The posture Φ at parameters (x5, y5, φ1, φ3, r2).
    Solve([f32; 5]),
    /// A swing tick's table work ([`SwingAnswer`]).
    Swing(SwingKey),
    /// A safe hold's set-down from the posture held: the posture with the
    /// swing ankle placed at a target from the hip (both beside the ask:
    /// [`AheadSlot::request_place`]; `gait_core::reach::place_swing_ankle_from`).
    Place(Phi<f32>),
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
    /// The answer's words and flags: the IK's five values, or a swing's
    /// ([`SwingAnswer`]); `None` where the IK has none, or the step is not
    /// among `steps`.
    fn answer(
        &self,
        model: &BodyModel<f32>,
        steps: Option<&Steps<'_>>,
        [hx, hy, tx, ty]: [f32; 4],
    ) -> Option<([f32; OUTPUT_WORDS], u32)> {
        let five = match &self.job {
            AheadJob::Swing(key) => return steps?.swing(model, key).map(|a| a.words()),
            AheadJob::Place(from) => {
                place_swing_ankle_from(model, from, [hx, hy], [tx, ty], SEARCH_MIN_KNEE_FLEXION_RAD)
            }
            _ => self.work(model)?,
        };
        let mut out = [0.0; OUTPUT_WORDS];
        for (o, x) in out.iter_mut().zip(five) {
            *o = x;
        }
        Some((out, FOUND))
    }

    /// An IK job's answer: five values, or `None` where the IK has none
    /// (and for a swing's, which needs the steps: [`Steps::swing`]).
    #[must_use]
    pub fn work(&self, model: &BodyModel<f32>) -> Option<[f32; 5]> {
        let ik = || IkSolver::new(model).with_options(self.options);
        match &self.job {
            AheadJob::Params(phi) => transfer_params(model, &ik(), phi),
            AheadJob::Swing(_) | AheadJob::Place(_) => None,
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
    #[inline(always)]
    fn words(&self) -> (u32, u32, [u32; 5]) {
        let (kind, input) = match &self.job {
            AheadJob::Params(phi) => (0, phi.map(f32::to_bits)),
            AheadJob::Solve(p) => (SOLVE, p.map(f32::to_bits)),
            AheadJob::Swing(k) => (SWING, [k.slot, k.replanned_len, k.t_s.to_bits(), 0, 0]),
            AheadJob::Place(from) => (PLACE, from.map(f32::to_bits)),
        };
        let range = match self.options.knee_range {
            KneeRange::Reach => 0,
            KneeRange::Human => HUMAN_RANGE,
        };
        (
            kind | range,
            self.options.stance_knee_max_rad.to_bits(),
            input,
        )
    }
}

/// A set-down's ask (its hip and target beside it in the slot).
fn place_ask(from: &Phi<f32>) -> AheadAsk {
    AheadAsk {
        job: AheadJob::Place(*from),
        options: IkOptions::paper(),
    }
}

/// Flag bits of an ask.
const SOLVE: u32 = 1;
const HUMAN_RANGE: u32 = 2;
const SWING: u32 = 4;
const PLACE: u32 = 8;
/// Flag bits of an answer: there is one (the IK found one, the step was
/// found); a swing's has the table's motion.
const FOUND: u32 = 1;
const MOTION: u32 = 2;

/// The hand-off of the work a tick ahead, one writer each way, as the
/// feed-forward's
/// ([`crate::feedforward::ModelSlot`]).
#[derive(Debug)]
pub struct AheadSlot {
    request_seq: AtomicU32,
    flags: AtomicU32,
    cap: AtomicU32,
    input: [AtomicU32; 5],
    /// A set-down's hip and target, m ([`AheadJob::Place`]).
    place: [AtomicU32; 4],
    answer_seq: AtomicU32,
    answered: AtomicU32,
    found: AtomicU32,
    output: [AtomicU32; OUTPUT_WORDS],
    /// Swing answers the tick took (for observers).
    taken: AtomicU32,
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
            input: [const { AtomicU32::new(0) }; 5],
            place: [const { AtomicU32::new(0) }; 4],
            answer_seq: AtomicU32::new(0),
            answered: AtomicU32::new(0),
            found: AtomicU32::new(0),
            output: [const { AtomicU32::new(0) }; OUTPUT_WORDS],
            taken: AtomicU32::new(0),
        }
    }

    /// Asks made so far (for observers).
    pub fn asked(&self) -> u32 {
        self.request_seq.load(Ordering::Relaxed)
    }

    /// Swing answers the tick has taken so far (for observers: the table
    /// work a swing tick did not do itself).
    pub fn taken(&self) -> u32 {
        self.taken.load(Ordering::Relaxed)
    }

    /// The tick: asks for `ask`'s answer by the next tick (inlined: each
    /// caller's kind of ask then folds to its own words).
    #[inline(always)]
    pub fn request(&self, ask: &AheadAsk) {
        let (flags, cap, input) = ask.words();
        self.flags.store(flags, Ordering::Relaxed);
        self.cap.store(cap, Ordering::Relaxed);
        for (w, v) in self.input.iter().zip(input) {
            w.store(v, Ordering::Relaxed);
        }
        let n = self.request_seq.load(Ordering::Relaxed).wrapping_add(1);
        self.request_seq.store(n, Ordering::Release);
    }

    /// The tick: asks for the set-down's posture from `from` with the
    /// swing ankle placed at `target_m` from the hip at `hip_m` (the stance
    /// foot's frame, m).
    pub fn request_place(&self, from: &Phi<f32>, hip_m: [f32; 2], target_m: [f32; 2]) {
        let [a, b] = hip_m;
        let [c, d] = target_m;
        for (w, v) in self.place.iter().zip([a, b, c, d]) {
            w.store(v.to_bits(), Ordering::Relaxed);
        }
        self.request(&place_ask(from));
    }

    /// The tick: the set-down's posture if its last request was for
    /// exactly these, and the task has answered it.
    pub fn placed(&self, from: &Phi<f32>, hip_m: [f32; 2], target_m: [f32; 2]) -> Option<Phi<f32>> {
        let (out, found) = self.answered_words(&place_ask(from))?;
        let [a, b] = hip_m;
        let [c, d] = target_m;
        let same = self
            .place
            .iter()
            .zip([a, b, c, d])
            .all(|(w, v)| w.load(Ordering::Relaxed) == v.to_bits());
        let [a, b, c, d, e, ..] = out;
        (same && found & FOUND != 0).then_some([a, b, c, d, e])
    }

    /// The answer's words and flags if the last request was `ask`, bit for
    /// bit, and the task has answered it whole (flags 0: no answer).
    #[inline(always)]
    fn answered_words(&self, ask: &AheadAsk) -> Option<([f32; OUTPUT_WORDS], u32)> {
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
        let found = self.found.load(Ordering::Relaxed);
        let out = self
            .output
            .each_ref()
            .map(|w| f32::from_bits(w.load(Ordering::Relaxed)));
        Some((out, found))
    }

    /// The tick: the answer to `ask` (an IK job) if its last request was
    /// `ask`, bit for bit, and the task has answered it whole
    /// (`Some(None)`: the IK has none); `None` otherwise (the tick works
    /// it out).
    pub fn answer_to(&self, ask: &AheadAsk) -> Option<Option<[f32; 5]>> {
        let (out, found) = self.answered_words(ask)?;
        Some(
            (found & FOUND != 0)
                .then(|| core::array::from_fn(|i| out.get(i).copied().unwrap_or(0.0))),
        )
    }

    /// The tick: the work of the swing tick `key` (the step's IK options
    /// `options`) if it was the last ask and the task found the step;
    /// `None` otherwise (the tick works it out).
    pub fn swing_answer(&self, key: SwingKey, options: IkOptions<f32>) -> Option<SwingAnswer> {
        let ask = AheadAsk {
            job: AheadJob::Swing(key),
            options,
        };
        let (out, found) = self.answered_words(&ask)?;
        if found & FOUND == 0 {
            return None;
        }
        // The tick is the one writer.
        let n = self.taken.load(Ordering::Relaxed).wrapping_add(1);
        self.taken.store(n, Ordering::Relaxed);
        Some(SwingAnswer::from_words(&out, found))
    }

    /// The task: the newest ask and its number, read whole; `None` before
    /// the first, or if ticks kept replacing it while it was read.
    fn newest(&self) -> Option<(u32, AheadAsk, [f32; 4])> {
        for _ in 0..4 {
            let before = self.request_seq.load(Ordering::Acquire);
            if before == 0 {
                return None;
            }
            let flags = self.flags.load(Ordering::Relaxed);
            let cap = f32::from_bits(self.cap.load(Ordering::Relaxed));
            let words = self.input.each_ref().map(|w| w.load(Ordering::Relaxed));
            let place = self
                .place
                .each_ref()
                .map(|w| f32::from_bits(w.load(Ordering::Relaxed)));
            if self.request_seq.load(Ordering::Acquire) != before {
                continue;
            }
            let input = words.map(f32::from_bits);
            let job = if flags & PLACE != 0 {
                AheadJob::Place(input)
            } else if flags & SWING != 0 {
                let [slot, replanned_len, t, ..] = words;
                AheadJob::Swing(SwingKey {
                    slot,
                    replanned_len,
                    t_s: f32::from_bits(t),
                })
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
                place,
            ));
        }
        None
    }

    /// The task: answers the newest ask if it has no answer yet; its
    /// number when it did.
    pub(crate) fn serve(&self, model: &BodyModel<f32>, steps: Option<&Steps<'_>>) -> Option<u32> {
        let (n, ask, place) = self.newest()?;
        let seq = self.answer_seq.load(Ordering::Relaxed);
        if seq != 0 && seq & 1 == 0 && self.answered.load(Ordering::Relaxed) == n {
            return None;
        }
        let (out, found) = ask
            .answer(model, steps, place)
            .unwrap_or(([0.0; OUTPUT_WORDS], 0));
        let writing = seq.wrapping_add(1) | 1;
        self.answer_seq.store(writing, Ordering::Release);
        for (w, v) in self.output.iter().zip(out) {
            w.store(v.to_bits(), Ordering::Relaxed);
        }
        self.found.store(found, Ordering::Relaxed);
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
        assert!(slot.serve(&m, None).is_some());
        assert!(slot.serve(&m, None).is_none(), "answered once");
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
        slot.serve(&m, None);
        assert_eq!(slot.answer_to(&solve), Some(solve.work(&m)));
    }

    #[test]
    fn a_set_down_is_answered_for_its_posture_hip_and_target_only() {
        let m = model();
        let slot = AheadSlot::new();
        let from = [0.1, 0.35, 0.05, 2.9, 3.3];
        let p = forward_kinematics(&m, &from);
        let (hip, ankle) = (p[1], p[4]);
        let target = [ankle[0], ankle[1] - 0.02];
        slot.request_place(&from, hip, target);
        assert_eq!(slot.placed(&from, hip, target), None, "not yet");
        slot.serve(&m, None);
        let placed = slot.placed(&from, hip, target).unwrap();
        let own = place_swing_ankle_from(&m, &from, hip, target, SEARCH_MIN_KNEE_FLEXION_RAD);
        assert_eq!(placed, own, "the tick's own IK, bit for bit");
        assert_ne!(placed, from, "the swing leg moved");
        assert_eq!(
            slot.placed(&from, hip, [target[0], target[1] - 0.001]),
            None
        );
        assert_eq!(slot.placed(&from, [hip[0] + 0.001, hip[1]], target), None);
        // Another ask with the same posture is not a set-down.
        slot.request(&AheadAsk {
            job: AheadJob::Params(from),
            options: IkOptions::paper(),
        });
        slot.serve(&m, None);
        assert_eq!(slot.placed(&from, hip, target), None);
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
        slot.serve(&m, None);
        assert_eq!(slot.answer_to(&far), Some(None), "out of reach");
        slot.answer_seq.fetch_add(1, Ordering::Release);
        assert_eq!(slot.answer_to(&far), None, "being written");
    }
}

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
use gait_core::foot::StanceFoot;
use gait_core::ik::{IkOptions, IkSolver, KneeRange};
use gait_core::kinematics::{Phi, Posture};
use gait_core::playback::{other_foot_share, swing_toe_at};

use crate::reference::{TableMotion, table_motion};
use crate::replan::ReplanSlot;
use crate::sequencer::{GaitTables, StepTable, transfer_params};

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
}

/// Which swing tick: the step (its table's slot, and a re-planned step's
/// length, 0 for the table's own) and its time. An answer is taken only
/// for the tick's newest ask, so a later swing of the same step asks
/// again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwingKey {
    /// The table's slot in the controller's tables.
    pub slot: u32,
    /// Samples of the re-planned step played; 0: the table as planned.
    pub replanned_len: u32,
    /// Time into the swing, s.
    pub t_s: f32,
}

/// A swing tick's table work, as the tick would do it: the table's
/// posture, its motion ([`table_motion`], `None` past the table's end),
/// where the step's first posture puts the swing toe (the stance foot's
/// flat frame, m), and the share of the body's weight the swing foot may
/// carry at the posture, its toe having started there
/// (`gait_core::playback::other_foot_share`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SwingAnswer {
    /// Φ at the key's time, rad.
    pub phi: Phi<f32>,
    /// Its motion.
    pub motion: Option<TableMotion>,
    /// The swing toe at the step's start, m.
    pub start_m: [f32; 2],
    /// The swing foot's share.
    pub share: f32,
}

/// The steps a swing plays, as the model task finds them from a
/// [`SwingKey`]: the controller's tables and its re-planner's slot
/// ([`crate::controller::Controller::steps`]).
#[derive(Clone, Copy, Debug)]
pub struct Steps<'t> {
    /// The controller's tables.
    pub tables: GaitTables<'t>,
    /// Where a re-planned step's samples are.
    pub replanned: Option<&'t ReplanSlot>,
}

impl SwingAnswer {
    /// Its words (Φ, Φ̇, Φ̈, the start, the share) and flags.
    fn words(&self) -> ([f32; OUTPUT_WORDS], u32) {
        let mut out = [0.0; OUTPUT_WORDS];
        let (dphi, ddphi, flags) = self.motion.map_or(([0.0; 5], [0.0; 5], FOUND), |m| {
            (m.dphi, m.ddphi, FOUND | MOTION)
        });
        let words = self
            .phi
            .iter()
            .chain(&dphi)
            .chain(&ddphi)
            .chain(&self.start_m)
            .chain([&self.share]);
        for (o, &v) in out.iter_mut().zip(words) {
            *o = v;
        }
        (out, flags)
    }

    /// Read back from `words` and `flags`.
    fn from_words(w: &[f32; OUTPUT_WORDS], flags: u32) -> Self {
        let five = |k: usize| core::array::from_fn(|i| w.get(k + i).copied().unwrap_or(0.0));
        let phi = five(0);
        Self {
            phi,
            motion: (flags & MOTION != 0).then(|| TableMotion {
                phi,
                dphi: five(5),
                ddphi: five(10),
            }),
            start_m: [15, 16].map(|k| w.get(k).copied().unwrap_or(0.0)),
            share: w.get(17).copied().unwrap_or(0.0),
        }
    }
}

impl<'t> Steps<'t> {
    /// The step `key` names.
    #[must_use]
    pub fn step(&self, key: &SwingKey) -> Option<StepTable<'t>> {
        let table = *self.tables.slot(key.slot as usize)?;
        match key.replanned_len {
            0 => Some(StepTable::Planned(table)),
            len => Some(StepTable::Replanned {
                slot: self.replanned?,
                len: len as usize,
                table,
            }),
        }
    }

    /// The work of the swing tick `key` on `model`.
    #[must_use]
    pub fn swing(&self, model: &BodyModel<f32>, key: &SwingKey) -> Option<SwingAnswer> {
        let step = self.step(key)?;
        let phi = step.at_time(key.t_s);
        let foot = StanceFoot::for_model(model);
        let toe = |p: &Phi<f32>| swing_toe_at(model, &foot, &Posture::new(p));
        let start_m = toe(&step.at_time(0.0));
        Some(SwingAnswer {
            phi,
            motion: table_motion(&step, key.t_s, phi),
            start_m,
            share: other_foot_share(toe(&phi), start_m),
        })
    }
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
    ) -> Option<([f32; OUTPUT_WORDS], u32)> {
        if let AheadJob::Swing(key) = &self.job {
            return steps?.swing(model, key).map(|a| a.words());
        }
        let five = self.work(model)?;
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
            AheadJob::Swing(_) => None,
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
    fn words(&self) -> (u32, u32, [u32; 5]) {
        let (kind, input) = match &self.job {
            AheadJob::Params(phi) => (0, phi.map(f32::to_bits)),
            AheadJob::Solve(p) => (SOLVE, p.map(f32::to_bits)),
            AheadJob::Swing(k) => (SWING, [k.slot, k.replanned_len, k.t_s.to_bits(), 0, 0]),
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

/// Flag bits of an ask.
const SOLVE: u32 = 1;
const HUMAN_RANGE: u32 = 2;
const SWING: u32 = 4;
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

    /// The tick: asks for `ask`'s answer by the next tick.
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

    /// The answer's words and flags if the last request was `ask`, bit for
    /// bit, and the task has answered it whole (flags 0: no answer).
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
    fn newest(&self) -> Option<(u32, AheadAsk)> {
        for _ in 0..4 {
            let before = self.request_seq.load(Ordering::Acquire);
            if before == 0 {
                return None;
            }
            let flags = self.flags.load(Ordering::Relaxed);
            let cap = f32::from_bits(self.cap.load(Ordering::Relaxed));
            let words = self.input.each_ref().map(|w| w.load(Ordering::Relaxed));
            if self.request_seq.load(Ordering::Acquire) != before {
                continue;
            }
            let input = words.map(f32::from_bits);
            let job = if flags & SWING != 0 {
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
            ));
        }
        None
    }

    /// The task: answers the newest ask if it has no answer yet; its
    /// number when it did.
    pub(crate) fn serve(&self, model: &BodyModel<f32>, steps: Option<&Steps<'_>>) -> Option<u32> {
        let (n, ask) = self.newest()?;
        let seq = self.answer_seq.load(Ordering::Relaxed);
        if seq != 0 && seq & 1 == 0 && self.answered.load(Ordering::Relaxed) == n {
            return None;
        }
        let (out, found) = ask.answer(model, steps).unwrap_or(([0.0; OUTPUT_WORDS], 0));
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

    /// Samples of the test table.
    const N: usize = 20;

    /// A table of [`N`] samples 10 ms apart, moving from a standing walk
    /// posture at 0.5 rad/s on every link.
    fn table_image() -> [u8; gait_core::tables::image_len(N)] {
        use gait_core::tables::{GaitKind, encode};
        let phis: [[f32; 5]; N] =
            core::array::from_fn(|k| [0.1, 0.35, 0.05, 2.9, 3.3].map(|p| p + 0.005 * k as f32));
        let mut buf = [0u8; gait_core::tables::image_len(N)];
        encode(GaitKind::Walk, 10_000, IkOptions::paper(), &phis, &mut buf).unwrap();
        buf
    }

    fn steps(image: &[u8]) -> Steps<'_> {
        let table = gait_core::tables::GaitTable::parse(image).unwrap();
        Steps {
            tables: GaitTables::by_kind(Some(table), None, None),
            replanned: None,
        }
    }

    fn key(t_s: f32) -> SwingKey {
        SwingKey {
            slot: 0,
            replanned_len: 0,
            t_s,
        }
    }

    #[test]
    fn a_swing_foot_carries_the_body_only_near_where_its_toe_started() {
        let m = model();
        let image = table_image();
        let steps = steps(&image);
        let step = steps.step(&key(0.0)).unwrap();
        let foot = StanceFoot::for_model(&m);
        let toe = |t: f32| swing_toe_at(&m, &foot, &Posture::new(&step.at_time(t)));
        let answer = |t: f32| steps.swing(&m, &key(t)).unwrap();
        assert_eq!(answer(0.1).start_m, toe(0.0), "the step's first posture's");
        assert_eq!(answer(0.0).share, 1.0, "still where it started");
        // The test table moves the toe on: the share is gone once it is
        // 12 mm from where it started.
        let moved = |t: f32| {
            let ([x, y], [x0, y0]) = (toe(t), toe(0.0));
            libm::sqrtf((x - x0) * (x - x0) + (y - y0) * (y - y0))
        };
        let far = (1..N)
            .map(|k| 0.01 * k as f32)
            .find(|&t| moved(t) > 0.012)
            .expect("the table moves the toe 12 mm");
        assert_eq!(answer(far).share, 0.0, "{far} s: {} m", moved(far));
    }

    #[test]
    fn a_swing_answer_is_the_ticks_own_table_work_for_its_step_and_time_only() {
        let m = model();
        let image = table_image();
        let steps = steps(&image);
        let step = steps.step(&key(0.0)).unwrap();
        let slot = AheadSlot::new();
        let opts = IkOptions::paper();
        let ask = |k: SwingKey| AheadAsk {
            job: AheadJob::Swing(k),
            options: opts,
        };
        // Asked, answered between two ticks: what the tick would work out.
        slot.request(&ask(key(0.125)));
        assert_eq!(slot.swing_answer(key(0.125), opts), None, "not yet");
        assert!(slot.serve(&m, Some(&steps)).is_some());
        let a = slot.swing_answer(key(0.125), opts).unwrap();
        let phi = step.at_time(0.125);
        assert_eq!(a.phi, phi);
        assert_eq!(a.motion, table_motion(&step, 0.125, phi));
        assert!(a.motion.is_some_and(|mo| (mo.dphi[0] - 0.5).abs() < 1e-3));
        assert_eq!(Some(a), steps.swing(&m, &key(0.125)));
        // Only for that time, that step and those options.
        assert_eq!(slot.swing_answer(key(0.126), opts), None);
        let replanned = SwingKey {
            replanned_len: 20,
            ..key(0.125)
        };
        assert_eq!(slot.swing_answer(replanned, opts), None);
        let human = IkOptions {
            knee_range: KneeRange::Human,
            ..opts
        };
        assert_eq!(slot.swing_answer(key(0.125), human), None);
        // Past the table's end: its last posture and no motion.
        slot.request(&ask(key(0.5)));
        slot.serve(&m, Some(&steps));
        let past = slot.swing_answer(key(0.5), opts).unwrap();
        assert_eq!(past.phi, step.at_time(0.19));
        assert_eq!(past.motion, None);
        // A task without the steps, or a step it does not hold, answers
        // nothing the tick takes.
        slot.request(&ask(key(0.13)));
        slot.serve(&m, None);
        assert_eq!(slot.swing_answer(key(0.13), opts), None);
        slot.request(&ask(replanned));
        slot.serve(&m, Some(&steps));
        assert_eq!(slot.swing_answer(replanned, opts), None, "no re-planner");
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

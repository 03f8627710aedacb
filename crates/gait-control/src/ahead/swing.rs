//! A swing tick's table work done a tick ahead: which step and time it is
//! for ([`SwingKey`]), what the model task works out ([`SwingAnswer`]),
//! and where it finds the step ([`Steps`]).

use gait_core::BodyModel;
use gait_core::foot::StanceFoot;
use gait_core::kinematics::{Phi, Posture};
use gait_core::playback::{other_foot_share, swing_toe_at};

use crate::reference::{TableMotion, table_motion};
use crate::replan::ReplanSlot;
use crate::sequencer::{GaitTables, StepTable};

use super::{FOUND, MOTION, OUTPUT_WORDS};

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
    pub(super) fn words(&self) -> ([f32; OUTPUT_WORDS], u32) {
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
    pub(super) fn from_words(w: &[f32; OUTPUT_WORDS], flags: u32) -> Self {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ahead::{AheadAsk, AheadJob, AheadSlot};
    use gait_core::ik::{IkOptions, KneeRange};

    fn model() -> BodyModel<f32> {
        BodyModel::<f32>::paper_table_iii()
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
}

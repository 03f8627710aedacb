//! The swing: the table plays, the landing is the swing foot's sensor
//! feeling the ground inside the landing window (or, a blind sensor, the
//! table's own timing); a swing whose table has ended without a landing
//! goes on lowering the foot (the ground search,
//! [`SequencerConfig::ground_search_depth_m`](super::SequencerConfig))
//! until the foot's sensor feels the ground or the landing times out.

use gait_core::kinematics::{Phi, Posture};

use crate::ahead::{AheadAsk, AheadJob, AheadSlot, SwingKey};
use crate::posture::{Side, joints_from_phi};
use crate::reference::TableMotion;

use super::{
    JOINTS, Phase, Sensed, SeqEvent, SeqEvents, Sequencer, StepTable, smoothstep, transfer,
};

/// The ground search stops where the swing knee would straighten past this
/// flexion, rad (6°): a leg locked straight takes the landing on its stop.
pub(crate) const SEARCH_MIN_KNEE_FLEXION_RAD: f32 = 0.1;

/// The table's posture at the swing's time while it plays: (stance, t, Φ,
/// and its motion when the model task worked it out ahead: `Some(None)`
/// past the table's end).
pub(super) type Playing = (Side, f32, Option<Phi<f32>>, Option<Option<TableMotion>>);

/// The present swing's landing detection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct SwingState {
    /// The swing foot's toe at the start of the table being played (stance
    /// foot's flat frame), m.
    start_m: [f32; 2],
    /// When the table's swing foot was planned fully lifted in the present
    /// swing, s (landing is looked for only after that).
    lifted_at_s: Option<f32>,
    /// How long the swing foot has felt the ground in the landing window
    /// without a break, s (`SequencerConfig::landing_confirm_s`).
    contact_s: f32,
    /// The present swing has reached its landing window (set each swing
    /// tick; a swing starts without it).
    pub(super) in_landing_window: bool,
    /// The stance-shank angle φ1 of the step's posture last sent in the
    /// present swing, rad (its first sample's on the tick the swing
    /// begins; NaN before any swing): a hold's set-down builds its frame
    /// on it.
    pub(super) phi1: f32,
    /// From when in this swing a hold lands the step first, s
    /// ([`Sequencer::lands_first_from_s`], fixed for the swing).
    pub(super) lands_first_from_s: f32,
}

impl SwingState {
    /// Before any swing.
    pub(super) const START: Self = Self {
        start_m: [0.0; 2],
        lifted_at_s: None,
        contact_s: 0.0,
        in_landing_window: false,
        phi1: f32::NAN,
        lands_first_from_s: f32::INFINITY,
    };

    /// A swing begins from the step's first sample, its stance shank at
    /// `phi1`; its swing toe's start is worked out at its first tick.
    pub(super) fn begin(&mut self, lands_first_from_s: f32, phi1: f32) {
        self.start_m = [f32::NAN; 2];
        self.phi1 = phi1;
        self.lands_first_from_s = lands_first_from_s;
        self.lifted_at_s = None;
        self.in_landing_window = false;
        self.contact_s = 0.0;
    }
}

/// Whether `a` and `b` are the same posture bit for bit (compared word by
/// word: an array's `==` calls `memcmp`, some 120 instructions on the M4).
fn same_bits(a: &Phi<f32>, b: &Phi<f32>) -> bool {
    a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// What a swing tick reads of [`super::SequencerConfig`].
#[derive(Clone, Copy)]
struct LandingSettings {
    landing_window_fraction: f32,
    blind_landing_settle_s: f32,
    landing_timeout_s: f32,
    landing_contact_n: f32,
    landing_confirm_s: f32,
}

impl LandingSettings {
    fn of(c: &super::SequencerConfig) -> Self {
        Self {
            landing_window_fraction: c.landing_window_fraction,
            blind_landing_settle_s: c.blind_landing_settle_s,
            landing_timeout_s: c.landing_timeout_s,
            landing_contact_n: c.landing_contact_n,
            landing_confirm_s: c.landing_confirm_s,
        }
    }
}

impl Sequencer<'_> {
    /// A swing tick `t_s + dt_s` into the swing: the reference, the table's
    /// posture while the swing goes on, and the other foot's share.
    pub(super) fn swing_tick(
        &mut self,
        sensed: &Sensed,
        stance: Side,
        t_s: f32,
        dt_s: f32,
        ahead: Option<&AheadSlot>,
        events: &mut SeqEvents,
    ) -> ([f32; JOINTS], Option<Playing>, f32) {
        // The settings this tick reads, not the whole configuration (a copy
        // of some 20 words a swing tick).
        let cfg = LandingSettings::of(&self.cfg);
        let t = t_s + dt_s;
        let step = self.step.as_ref();
        let duration = step.map_or(0.0, |tb| tb.duration_s());
        let swing_foot = sensed
            .feet_n
            .get(stance.other().foot())
            .copied()
            .unwrap_or(f32::NAN);
        // The table's work (its posture, its motion, the swing toe's start
        // and the swing foot's share): asked ahead last tick (the same
        // arithmetic on the same step and time, bit for bit), else done
        // now. Past the
        // table's end without a landing, the foot goes on down looking for
        // the ground.
        let answer = ahead.filter(|_| self.model.is_some()).and_then(|slot| {
            let options = self.table.as_ref()?.ik_options();
            slot.swing_answer(self.swing_key(t)?, options)
        });
        // The swing toe's start, at the swing's first tick: the answer's,
        // or worked out now.
        if self.swing.start_m[0].is_nan() {
            self.swing.start_m = match (answer, step) {
                (Some(a), _) => a.start_m,
                (None, Some(tb)) => self
                    .planned_swing_toe(Some(&Posture::new(&tb.at_time(0.0))))
                    .unwrap_or([0.0; 2]),
                (None, None) => [0.0; 2],
            };
        }
        let phi_t = step.map(|tb| {
            let table = answer.map_or_else(|| tb.at_time(t), |a| a.phi);
            self.searching_for_ground(&table, t - duration)
        });
        self.swing.phi1 = phi_t.map_or(f32::NAN, |p| p[0]);
        // The answer is for the table's posture: taken where the ground
        // search has not moved it.
        let taken = match (phi_t, answer) {
            (Some(p), Some(a)) if same_bits(&p, &a.phi) => Some(a),
            _ => None,
        };
        let share = match (phi_t, taken) {
            (_, Some(a)) => a.share,
            (Some(p), None) => self.swing_share(&p),
            (None, None) => 0.0,
        };
        if self.swing.lifted_at_s.is_none() && share <= 0.0 {
            self.swing.lifted_at_s = Some(t);
        }
        // Contact counts as the landing only once the table has lifted the
        // foot and played the given fraction of its time in the air
        // (earlier contact is a scuff).
        let in_window = self
            .swing
            .lifted_at_s
            .is_some_and(|lift| t >= lift + cfg.landing_window_fraction * (duration - lift));
        self.swing.in_landing_window = in_window;
        // A foot whose sensor has failed (NaN) cannot report the contact:
        // the step ends on the table's own timing, where the table has put
        // the foot down, once the foot has had the time to follow it there.
        let blind = !swing_foot.is_finite();
        // Never past the landing timeout (a NaN setting is the timeout).
        let settle = cfg.blind_landing_settle_s.min(cfg.landing_timeout_s);
        let blind_landed = blind && t >= duration + settle;
        // Contact counts once it has held `landing_confirm_s`: a spike of
        // a few ticks is not the ground.
        self.swing.contact_s = if in_window && swing_foot >= cfg.landing_contact_n {
            self.swing.contact_s + dt_s
        } else {
            0.0
        };
        let contact_s = self.swing.contact_s;
        let touched = contact_s > 0.0 && contact_s >= cfg.landing_confirm_s - 0.5 * dt_s;
        let landed = in_window && (touched || blind_landed);
        let reference = phi_t.map_or(self.reference, |p| joints_from_phi(&p, stance));
        let mut playing = None;
        if landed {
            self.release_played();
            events.push(SeqEvent::Landed);
            if self.stop_requested {
                self.blend_from = reference;
                self.blend_to = reference;
                self.phase = Phase::Standing;
                self.stance = stance.other();
                events.push(SeqEvent::Stopped);
            } else {
                let new_stance = stance.other();
                self.stance = new_stance;
                self.blend_from = reference;
                let table = self.table.as_ref().copied();
                self.blend_to =
                    table.map_or(reference, |tb| joints_from_phi(&tb.first(), new_stance));
                self.transfer = phi_t.and_then(|p| self.plan_transfer(&p));
                self.phase = Phase::Transfer {
                    stance: new_stance,
                    t_s: 0.0,
                };
            }
        } else if t > duration + cfg.landing_timeout_s {
            self.release_played();
            events.push(SeqEvent::LandingTimeout);
            self.blend_from = reference;
            self.blend_to = reference;
            self.phase = Phase::Standing;
            events.push(SeqEvent::Stopped);
        } else {
            self.phase = Phase::Swing { stance, t_s: t };
            playing = Some((stance, t, phi_t, taken.map(|a| a.motion)));
            if let Some(slot) = ahead {
                self.ask_swing(slot, t + dt_s);
            }
        }
        (reference, playing, share)
    }

    /// The present swing's tick `t_s` into it, as the model task finds it
    /// ([`SwingKey`]); `None` without a step.
    fn swing_key(&self, t_s: f32) -> Option<SwingKey> {
        let replanned_len = match self.step.as_ref()? {
            StepTable::Planned(_) => 0,
            StepTable::Replanned { len, .. } => u32::try_from(*len).ok()?,
        };
        Some(SwingKey {
            slot: u32::try_from(self.slot).ok()?,
            replanned_len,
            t_s,
        })
    }

    /// Asks the model task for the table's work at the swing's next tick,
    /// `t_s` into it, while the table plays (the ground search past its
    /// end works its posture out only then).
    pub(super) fn ask_swing(&self, slot: &AheadSlot, t_s: f32) {
        let (Some(step), Some(table), Some(key)) =
            (self.step.as_ref(), self.table.as_ref(), self.swing_key(t_s))
        else {
            return;
        };
        let searching = t_s - step.duration_s() - self.cfg.ground_search_after_s;
        if searching.is_finite() && searching > 0.0 {
            return;
        }
        slot.request(&AheadAsk {
            job: AheadJob::Swing(key),
            options: table.ik_options(),
        });
    }

    /// From when in the present swing a safe hold lands the step first, s
    /// ([`SeqStatus::in_swing_now`](super::SeqStatus::in_swing_now));
    /// infinite outside a swing or without a table.
    pub(super) fn lands_first_from_s(&self) -> f32 {
        let duration = self.step.as_ref().map_or(0.0, |tb| tb.duration_s());
        let slot = transfer::kind_index(self.gait);
        let after = self.cfg.lands_after.get(slot).copied().unwrap_or(1.0);
        if duration > 0.0 {
            after * duration
        } else {
            f32::INFINITY
        }
    }

    /// The swing foot's toe at the table's posture (stance foot's flat
    /// frame), m; `None` without a model or table.
    pub(super) fn planned_swing_toe(&self, posture: Option<&Posture<f32>>) -> Option<[f32; 2]> {
        let model = self.model.as_ref()?;
        let posture = posture?;
        let foot = gait_core::foot::StanceFoot::for_model(model);
        Some(gait_core::playback::swing_toe_at(model, &foot, posture))
    }

    /// The ground search: `phi` (the table's last posture) with the swing
    /// ankle lowered by how far the search has gone `since_end_s` after the
    /// table's end (from `ground_search_after_s` on, eased in and out over
    /// `ground_search_s` to the full `ground_search_depth_m`); `phi` itself
    /// before then or without a model. A tread a few millimetres lower
    /// than planned, or a foot tracking a little high, would otherwise
    /// leave the foot hovering until the landing timed out, the step
    /// standing on one leg.
    fn searching_for_ground(
        &self,
        phi: &[f32; gait_core::LINKS],
        since_end_s: f32,
    ) -> [f32; gait_core::LINKS] {
        let Some(model) = self.model.as_ref() else {
            return *phi;
        };
        let c = &self.cfg;
        let searching_s = since_end_s - c.ground_search_after_s;
        if !(searching_s.is_finite() && searching_s > 0.0) {
            return *phi;
        }
        let frac = if c.ground_search_s > 0.0 {
            searching_s / c.ground_search_s
        } else {
            1.0
        };
        let depth = c.ground_search_depth_m * smoothstep(frac);
        gait_core::reach::lower_swing_ankle(model, phi, depth, SEARCH_MIN_KNEE_FLEXION_RAD)
    }

    /// The other foot's share at the table's posture `phi` in the present
    /// swing (0 without a model: the foot is taken as lifted from the
    /// start, and the landing window counts from the swing's start).
    fn swing_share(&self, phi: &Phi<f32>) -> f32 {
        self.planned_swing_toe(Some(&Posture::new(phi)))
            .map_or(0.0, |p| {
                gait_core::playback::other_foot_share(p, self.swing.start_m)
            })
    }

    /// The step has ended: a re-planned one's samples go back to the
    /// re-planner (the next request may overwrite them).
    fn release_played(&mut self) {
        if let Some(StepTable::Replanned { slot, .. }) = self.step {
            slot.release();
            self.step = None;
        }
    }
}

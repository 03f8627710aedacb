//! The hand-off between the tick and the step re-planner that runs in the
//! tick's idle time (issue: the pilot's ankle is not where the table's
//! step was planned from).
//!
//! The tick never waits for the re-planner and never shares a lock with
//! it. A [`ReplanSlot`] is memory both sides reach through a shared
//! reference, each word an atomic, and its `state` says who owns the
//! samples:
//!
//! ```text
//!   tick: request ──► Requested ──► idle: take ──► Working ──► idle: publish
//!                                                                  │
//!   tick: take at the fixed latency ◄── Replanned / Declined / Refused
//!          │
//!          └─► Playing (the tick reads the samples; the idle side writes
//!              only in Working, which only a new request leads to)
//! ```
//!
//! Each request is a new generation of the state word: the idle side's
//! [`Ticket`] names the one it works on, and an answer for a request the
//! tick has since withdrawn or replaced is never published.
//!
//! The tick takes the result exactly [`crate::sequencer::SequencerConfig`]'s
//! `replan_latency_ticks` after its request, never earlier: the step then
//! starts at the same tick whether the re-planner needed a tenth or all of
//! that time, so the host's simulation and the board play the same step.
//! A result not there by then is late: the table is played (the fault
//! table's notice rows).

use core::sync::atomic::{AtomicU32, Ordering};

use gait_core::LINKS;

use crate::posture::{JOINTS, Side};

/// Most samples a re-planned step holds (5.1 s at the tables' 10 ms).
pub const REPLAN_CAPACITY: usize = 512;

/// What the tick asks the re-planner: the step of table `slot` with
/// `stance` as stance leg, from where the pilot's stance ankle will be.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReplanRequest {
    /// The table's slot ([`crate::sequencer::GaitTables`]).
    pub slot: u8,
    /// The stance leg.
    pub stance: Side,
    /// The stance shank's angle φ1 the step will start from (measured at
    /// the request), rad.
    pub phi1_rad: f32,
    /// The joints then (joint order), rad: with φ1, the posture the step
    /// starts from.
    pub joints_rad: [f32; JOINTS],
    /// The share (0 … 1) of its offset from the table the pilot is
    /// expected to keep to the landing ([`ReplanConfig::persist`]).
    pub persist: f32,
}

/// How the sequencer uses the re-planner.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ReplanConfig {
    /// A stance ankle this close to the table's start plays the table at
    /// once, rad (no re-plan, no wait) …
    pub min_offset_rad: f32,
    /// … a step is re-planned for a stance ankle up to this far from the
    /// table's start (φ1(0)), rad; further, the pilot is asked to lean
    /// (the step waits), as without re-planning.
    pub ankle_tolerance_rad: f32,
    /// The answer is taken this many ticks after the request, never
    /// earlier (what the re-planner has by then; see the module docs).
    pub latency_ticks: u16,
    /// A re-planned step is played only if the stance ankle is still within
    /// this of where it was asked for, rad; else it is asked again.
    pub ankle_drift_rad: f32,
    /// The share of the start's offset the pilot is expected to keep to
    /// the landing.
    pub persist: f32,
    /// Where a re-planned step lands relative to its table's foothold, m
    /// (x along the step, y up), for the walk, the ascent and the descent
    /// ([`gait_core::replan::ReplanSetup::aim_m`]).
    pub landing_aim_m: [[f32; 2]; 3],
}

impl ReplanConfig {
    /// Re-planned from 0.01 rad (0.6°) up to 0.07 rad (4.0°) from the
    /// table's start (from 0.08–0.12 rad, a pilot leaning 4° forward
    /// steps sooner but the walk and the ascent latch safe holds; an
    /// ankle further off comes within it before the table's 0.05 rad),
    /// the answer taken 200 ms after the request (some 21 evaluations of
    /// a 225-sample table in the idle time of a 168 MHz M4F; at 120 ms or
    /// less, walkers leaning forward trip 0x0404, and a request made
    /// before the pilot is ready, from the ankle predicted for then,
    /// raises the crutch load), played if the ankle has moved by less
    /// than 0.02 rad meanwhile;
    /// 0.6 of the offset expected to be kept to the landing (what the
    /// simulated pilot keeps: leaning back 2° on the walk, 0.031 rad at
    /// the start, 0.018–0.024 rad at the landing; kept whole, a
    /// forward-leaning pilot's swing foot ended above the ground and
    /// waited for the ground search; dropped, the steps landed as far off
    /// as the table's). On the walk and the ascent the approach is pressed
    /// 3 mm under the floor, so the foot meets it by the table's end, and
    /// aimed 8 mm short, the offset that earlier touch-down lands with on
    /// the simulated device; the descent is not aimed (pressed, a pilot
    /// leaning back crossed the ankle's stop). `docs/replanning.md`; to be
    /// measured again on the device.
    pub const DEFAULT: Self = Self {
        min_offset_rad: 0.01,
        ankle_tolerance_rad: 0.07,
        latency_ticks: 200,
        ankle_drift_rad: 0.02,
        persist: 0.6,
        landing_aim_m: [[-0.008, -0.003], [-0.008, -0.003], [0.0, 0.0]],
    };

    /// The landing aim of a step of `kind` ([`ReplanConfig::landing_aim_m`]).
    #[must_use]
    pub fn landing_aim_for(&self, kind: gait_core::tables::GaitKind) -> [f32; 2] {
        use gait_core::tables::GaitKind;
        let [walk, up, down] = self.landing_aim_m;
        match kind {
            GaitKind::Walk => walk,
            GaitKind::StairUp => up,
            GaitKind::StairDown => down,
        }
    }
}

/// What came of the re-plan of a step, as the sequencer reports it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReplanResult {
    /// The re-planner's answer at the latency.
    Answered(ReplanOutcome),
    /// No answer at the latency: the table is played.
    Late,
}

/// What the re-planner made of a request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ReplanOutcome {
    /// A better step than the table from there, admitted by the device's
    /// check: its samples are in the slot.
    Replanned,
    /// Nothing better than the table found (or the ankle needs none).
    Declined,
    /// A step was found, but the device's admission check refused it.
    Refused,
}

/// The slot's states (one byte, so each side reads it in one load).
mod state {
    pub const IDLE: u32 = 0;
    pub const REQUESTED: u32 = 1;
    pub const WORKING: u32 = 2;
    pub const REPLANNED: u32 = 3;
    pub const DECLINED: u32 = 4;
    pub const REFUSED: u32 = 5;
    pub const PLAYING: u32 = 6;
    /// The state's bits; the generation is above them.
    pub const MASK: u32 = 0xFF;

    /// `state` in the generation of `word`.
    pub const fn with(word: u32, state: u32) -> u32 {
        (word & !MASK) | state
    }
}

/// Which request an answer is for (the idle side's receipt from
/// [`ReplanSlot::take_request`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ticket(u32);

/// Where a request stands, as the tick sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SlotView {
    /// No request, or the re-planner is still at it.
    Pending,
    /// The re-planner's answer.
    Done(ReplanOutcome),
}

/// Shared memory between the tick (the sequencer) and the idle-time
/// re-planner: a request, then the re-planned samples. Lives as long as
/// both (a `static` on the board, the simulation's run on the host).
pub struct ReplanSlot {
    /// The request's generation (bits 8…) and the state (bits 0–7): an
    /// answer is published only for the generation it was worked on.
    state: AtomicU32,
    /// Request: slot and stance (bit 8: right), then φ1, the joints and
    /// the share kept (f32 bits).
    request: [AtomicU32; 3 + JOINTS],
    /// Samples published, and each sample's Φ (f32 bits).
    len: AtomicU32,
    samples: [[AtomicU32; LINKS]; REPLAN_CAPACITY],
}

impl core::fmt::Debug for ReplanSlot {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("ReplanSlot")
            .field("state", &self.state.load(Ordering::Relaxed))
            .field("len", &self.len.load(Ordering::Relaxed))
            .finish_non_exhaustive()
    }
}

/// One slot is itself: the sequencer compares by where it points.
impl PartialEq for ReplanSlot {
    fn eq(&self, other: &Self) -> bool {
        core::ptr::eq(self, other)
    }
}

impl Default for ReplanSlot {
    fn default() -> Self {
        Self::new()
    }
}

impl ReplanSlot {
    /// An empty slot (`const`: a `static` on the board).
    #[must_use]
    pub const fn new() -> Self {
        Self {
            state: AtomicU32::new(state::IDLE),
            request: [const { AtomicU32::new(0) }; 3 + JOINTS],
            len: AtomicU32::new(0),
            samples: [const { [const { AtomicU32::new(0) }; LINKS] }; REPLAN_CAPACITY],
        }
    }

    // --- The tick's side -------------------------------------------------

    /// Asks for a re-plan (replacing any request or result not played).
    pub fn request(&self, r: &ReplanRequest) {
        let who = u32::from(r.slot) | (u32::from(matches!(r.stance, Side::Right)) << 8);
        let values = core::iter::once(r.phi1_rad)
            .chain(r.joints_rad)
            .chain(core::iter::once(r.persist));
        if let Some((first, rest)) = self.request.split_first() {
            first.store(who, Ordering::Relaxed);
            for (w, v) in rest.iter().zip(values) {
                w.store(v.to_bits(), Ordering::Relaxed);
            }
        }
        let next = self.state.load(Ordering::Relaxed).wrapping_add(1 << 8);
        self.state
            .store(state::with(next, state::REQUESTED), Ordering::Release);
    }

    /// The answer to the last request, if there is one.
    #[must_use]
    pub fn view(&self) -> SlotView {
        match self.state.load(Ordering::Acquire) & state::MASK {
            state::REPLANNED => SlotView::Done(ReplanOutcome::Replanned),
            state::DECLINED => SlotView::Done(ReplanOutcome::Declined),
            state::REFUSED => SlotView::Done(ReplanOutcome::Refused),
            _ => SlotView::Pending,
        }
    }

    /// Takes a [`ReplanOutcome::Replanned`] result for playing: the
    /// re-planner leaves the samples alone until [`ReplanSlot::release`]
    /// or the next request. `None` if there is no such result.
    #[must_use]
    pub fn take(&self) -> Option<usize> {
        let now = self.state.load(Ordering::Acquire);
        if now & state::MASK != state::REPLANNED {
            return None;
        }
        self.state
            .compare_exchange(
                now,
                state::with(now, state::PLAYING),
                Ordering::AcqRel,
                Ordering::Relaxed,
            )
            .ok()
            .map(|_| (self.len.load(Ordering::Relaxed) as usize).min(REPLAN_CAPACITY))
    }

    /// Withdraws the request or result (a step that was not started, or
    /// one that has been played): a re-planner still working discards its
    /// answer.
    pub fn release(&self) {
        let now = self.state.load(Ordering::Relaxed);
        self.state
            .store(state::with(now, state::IDLE), Ordering::Release);
    }

    /// Sample `k` of the taken step.
    #[inline]
    #[must_use]
    pub fn sample(&self, k: usize) -> Option<[f32; LINKS]> {
        let s = self.samples.get(k)?;
        Some(core::array::from_fn(|i| {
            s.get(i)
                .map_or(f32::NAN, |v| f32::from_bits(v.load(Ordering::Relaxed)))
        }))
    }

    // --- The re-planner's side -------------------------------------------

    /// Takes the pending request for working on it, with the ticket its
    /// answer is published with.
    #[must_use]
    pub fn take_request(&self) -> Option<(ReplanRequest, Ticket)> {
        let now = self.state.load(Ordering::Acquire);
        if now & state::MASK != state::REQUESTED {
            return None;
        }
        let working = state::with(now, state::WORKING);
        self.state
            .compare_exchange(now, working, Ordering::AcqRel, Ordering::Relaxed)
            .ok()?;
        let word = |i: usize| self.request.get(i).map_or(0, |w| w.load(Ordering::Relaxed));
        let value = |i: usize| f32::from_bits(word(i));
        let who = word(0);
        let request = ReplanRequest {
            slot: (who & 0xFF) as u8,
            stance: if who & 0x100 != 0 {
                Side::Right
            } else {
                Side::Left
            },
            phi1_rad: value(1),
            joints_rad: core::array::from_fn(|j| value(2 + j)),
            persist: value(2 + JOINTS),
        };
        // A new request written while these words were read (the tick
        // preempts) is a new generation: this one is not worked on.
        let ticket = Ticket(working);
        self.still_wanted(ticket).then_some((request, ticket))
    }

    /// Whether the request `ticket` is for still stands (the tick has not
    /// withdrawn or replaced it): a re-planner may stop early when not.
    #[must_use]
    pub fn still_wanted(&self, ticket: Ticket) -> bool {
        self.state.load(Ordering::Acquire) == ticket.0
    }

    /// Publishes the answer to the request `ticket` is for: `samples` (at
    /// most [`REPLAN_CAPACITY`]) with [`ReplanOutcome::Replanned`], none
    /// otherwise. Returns `false`, publishing nothing, if the tick has
    /// withdrawn or replaced the request meanwhile.
    pub fn publish(
        &self,
        ticket: Ticket,
        outcome: ReplanOutcome,
        samples: &[[f32; LINKS]],
    ) -> bool {
        if !self.still_wanted(ticket) {
            return false;
        }
        // A step longer than the slot is not played cut short.
        let outcome = if samples.len() > REPLAN_CAPACITY || samples.len() < 2 {
            match outcome {
                ReplanOutcome::Replanned => ReplanOutcome::Declined,
                other => other,
            }
        } else {
            outcome
        };
        let n = if outcome == ReplanOutcome::Replanned {
            for (slot, s) in self.samples.iter().zip(samples) {
                for (w, v) in slot.iter().zip(s) {
                    w.store(v.to_bits(), Ordering::Relaxed);
                }
            }
            samples.len().min(REPLAN_CAPACITY)
        } else {
            0
        };
        self.len.store(n as u32, Ordering::Relaxed);
        let done = match outcome {
            ReplanOutcome::Replanned => state::REPLANNED,
            ReplanOutcome::Declined => state::DECLINED,
            ReplanOutcome::Refused => state::REFUSED,
        };
        self.state
            .compare_exchange(
                ticket.0,
                state::with(ticket.0, done),
                Ordering::AcqRel,
                Ordering::Relaxed,
            )
            .is_ok()
    }
}

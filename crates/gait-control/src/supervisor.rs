//! The safety supervisor: checked once per 1 kHz tick, after the controller
//! has sensed and computed its commands and before any output is written.
//!
//! It only receives facts ([`SupervisorInput`]), decides ([`Verdict`]) and
//! never waits: no allocation, no panics, a fixed amount of work per call
//! (loops only over the fixed-size joint, ankle, sensor and fault arrays).
//! The fault table, the detection bounds, the reactions and the reset rules
//! are in `docs/safety.md`; the tests in `tests/integration/supervisor/` check one
//! row each.
//!
//! # Time
//!
//! Every window and debounce counts calls of [`Supervisor::check`] (one per
//! tick), not `input.tick`, which is only copied into the log, so a
//! controller that repeats or skips a tick number cannot stretch a window.
//!
//! # NaN
//!
//! Every comparison is written so that NaN fails it (`!(x <= limit)` rather
//! than `x > limit`): a NaN value can only trip a fault, never pass a check.

use crate::ring_log::RingLog;

use crate::drivers::as5048a::{DATA_MASK, wrapped_delta};
use crate::faults::{FaultCode, FaultSet, Reaction};

pub use crate::layout::{ANKLES, ENCODERS, FORCES, JOINTS, Side};

mod balance;
mod checks;
mod config;
mod crutch_idle;
mod drive_current;
mod facts;
mod findings;
mod frames;
mod latch;
mod response;
mod tracks;
mod windowed;

pub use balance::{BalanceCheck, ErrorBounds};
pub use config::{
    AngleRange, ConfigError, Debounce, EnvelopeMargins, ResetRefused, SupervisorConfig,
};
pub use crutch_idle::CrutchIdleCheck;
pub use drive_current::{DriveCurrentCheck, DriveCurrentSense};
pub use facts::{
    EncoderSense, EncoderStatus, ForceSense, ForceStatus, MotorSense, SupervisorInput,
};
pub use findings::{Findings, MAX_RAISES, Marks, Raise};
pub use frames::EncoderFrame;
use latch::Latch;
pub use response::ResponseCheck;
use tracks::{Class, EncoderTrack, JointTrack};
pub use windowed::{WindowedChecks, WindowedJob};
/// Records kept in the post-mortem log (the newest ones).
pub const LOG_LEN: usize = 32;
/// Channel of a [`FaultRecord`] for faults that belong to no channel.
pub const NO_CHANNEL: u8 = 0xFF;
/// Longest debounce window for encoder and force samples, ticks.
pub const MAX_SAMPLE_WINDOW_TICKS: u8 = 128;
/// Largest number of deadline misses the deadline rule can count.
pub const MAX_DEADLINE_MISSES: u8 = 8;

/// Largest |angle| an AS5048A reading can give after calibration, rad
/// (the driver's range is (−π, π]; a little slack for rounding).
const MAX_ENCODER_ANGLE_RAD: f32 = core::f32::consts::PI + 1e-3;

/// The supervisor's decision for one tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Verdict {
    /// The most severe reaction over all latched faults.
    pub reaction: Reaction,
    /// Every latched fault.
    pub latched: FaultSet,
    /// Faults latched by this call (not latched before it).
    pub new: FaultSet,
    /// Joints whose drive must be disabled, braked: a drive that does not
    /// give the torque commanded (0x0403, 0x0404 latched on it) is worse
    /// than its brake, until a reset; a joint whose encoder is lost
    /// (0x0201–0x0204) while the closed chain does not give its angle
    /// (`SupervisorInput::chain_closed`).
    pub braked_joints: [bool; JOINTS],
    /// Joints whose drive 0x0404 found not following while another joint
    /// was already braked, this tick, for the first time: most likely
    /// dragged by the braked one, not faulty (its current follows its
    /// command, or 0x0405 would have braked it). Held where they are now
    /// with their drive, not braked: braked, a loaded joint sinks, and
    /// held at the hold's old reference its drive pushes the body. A
    /// second trip on the same joint brakes it.
    pub rehold_joints: [bool; JOINTS],
}

/// One post-mortem record: written when a fault latches, and again when
/// the same fault appears on another channel while latched.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FaultRecord {
    /// `input.tick` of the check that raised it.
    pub tick: u32,
    /// The fault.
    pub code: FaultCode,
    /// Joint, ankle, force sensor or motor index; [`NO_CHANNEL`] for none.
    pub channel: u8,
    /// The offending value: angle or error (rad), velocity (rad/s), raw
    /// count change, force (N), command (N·m), or a count (bad samples,
    /// ticks, misses), as listed in `docs/safety.md`.
    pub value: f32,
}

/// The safety supervisor. See the module docs and `docs/safety.md`.
///
/// `W`: where its windowed checks' memory is. [`WindowedChecks`] (made by
/// [`Supervisor::new`]): here, and [`Supervisor::check`] runs them;
/// [`Lent`] ([`Supervisor::lend`]): elsewhere (the controller's, or its
/// model task's), and the tick's state keeps only what the tick reads.
#[derive(Debug, Clone)]
pub struct Supervisor<W = WindowedChecks> {
    cfg: SupervisorConfig,
    /// Calls of `check` so far (the supervisor's own clock).
    calls: u32,
    /// Faults whose condition held at the last check.
    present: FaultSet,
    /// What latched, and its log.
    latch: Latch,
    joints: [JointTrack; JOINTS],
    ankles: [EncoderTrack; ANKLES],
    /// An ankle found stuck: control takes none of its frames until its
    /// counts move again.
    ankle_stuck: [bool; ANKLES],
    /// `calls` at the latest deadline misses (ring, filled from its start:
    /// the first `deadline_misses_total` slots hold one).
    misses: [u32; MAX_DEADLINE_MISSES as usize],
    miss_next: u8,
    deadline_misses_total: u32,
    /// Some encoder's persistent jump is taken out of its frames
    /// ([`Supervisor::encoder_offsets`]).
    encoder_offsets: bool,
    /// Faults found at boot in flash data ([`Supervisor::report_boot_fault`]):
    /// present at every check.
    boot_faults: FaultSet,
    /// Each ankle's error from its plan, for 0x0701 and 0x0702: checked
    /// in the tick, so that a pilot losing balance is held without the
    /// windowed checks' lag.
    balance: [balance::BalanceTrack; ANKLES],
    windowed: W,
}

/// A supervisor's windowed checks run elsewhere ([`Supervisor::lend`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct Lent;

/// Collects what one check raised.
struct Tick {
    tick: u32,
    present: FaultSet,
    new: FaultSet,
}

impl Supervisor {
    /// Checks `cfg` and starts with nothing latched.
    pub fn new(cfg: SupervisorConfig) -> Result<Self, ConfigError> {
        cfg.validate()?;
        Ok(Self {
            windowed: WindowedChecks::new(&cfg),
            cfg,
            balance: [balance::BalanceTrack::default(); ANKLES],
            calls: 0,
            present: FaultSet::EMPTY,
            boot_faults: FaultSet::EMPTY,
            latch: Latch {
                latched: FaultSet::EMPTY,
                logged_channels: [0; FaultCode::COUNT],
                logged_none: FaultSet::EMPTY,
                log: RingLog::new(),
                braked: [false; JOINTS],
                angle_lost: [false; JOINTS],
                held_in_place_once: [false; JOINTS],
                hold_in_place: [false; JOINTS],
            },
            joints: [JointTrack::default(); JOINTS],
            ankles: [EncoderTrack::default(); ANKLES],
            ankle_stuck: [false; ANKLES],
            misses: [0; MAX_DEADLINE_MISSES as usize],
            miss_next: 0,
            deadline_misses_total: 0,
            encoder_offsets: false,
        })
    }

    /// The tick's part, and the windowed checks' memory for whoever runs
    /// them in its stead ([`Supervisor::check_after`]).
    pub fn lend(self) -> (Supervisor<Lent>, WindowedChecks) {
        let Self {
            cfg,
            calls,
            present,
            latch,
            joints,
            ankles,
            ankle_stuck,
            misses,
            miss_next,
            deadline_misses_total,
            encoder_offsets,
            boot_faults,
            balance,
            windowed,
        } = self;
        let tick = Supervisor {
            cfg,
            calls,
            present,
            latch,
            joints,
            ankles,
            ankle_stuck,
            misses,
            miss_next,
            deadline_misses_total,
            encoder_offsets,
            boot_faults,
            balance,
            windowed: Lent,
        };
        (tick, windowed)
    }

    /// The windowed checks of `job` on the supervisor's own memory of them
    /// (for [`Supervisor::check_after`] at the next check).
    pub fn run_windowed(&mut self, job: &WindowedJob) -> Findings {
        self.windowed.run(job)
    }

    /// The per-tick check: updates every detector with `input`, latches
    /// what tripped, and returns the reaction over all latched faults.
    pub fn check(&mut self, input: &SupervisorInput) -> Verdict {
        let [j0, j1, j2, j3] = &input.joints;
        let [left, right] = &input.ankles;
        let frames = [j0, j1, j2, j3, left, right];
        let mut n = 0;
        let frames = frames.map(|sense| {
            n += 1;
            self.take_encoder(n - 1, sense)
        });
        self.check_frames(input, &frames)
    }

    /// [`Supervisor::check`] with this tick's encoder frames already
    /// taken ([`Supervisor::take_encoder`], joints then ankles, from the
    /// senses in `input`): the tick's own checks, then the windowed checks
    /// on the same facts.
    pub fn check_frames(
        &mut self,
        input: &SupervisorInput,
        frames: &[EncoderFrame; ENCODERS],
    ) -> Verdict {
        let mut t = self.begin(input);
        self.check_tick(input, frames, false, &mut t);
        let found = self.windowed.run(&self.windowed_job(input, frames));
        self.apply(&found, &mut t);
        self.end(input, t)
    }
}

impl<W> Supervisor<W> {
    /// The configuration in use.
    pub const fn config(&self) -> &SupervisorConfig {
        &self.cfg
    }

    /// Every latched fault.
    pub const fn latched(&self) -> FaultSet {
        self.latch.latched
    }

    /// Faults whose condition held at the last check (always a subset of
    /// [`Supervisor::latched`]).
    pub const fn present(&self) -> FaultSet {
        self.present
    }

    /// Deadline misses seen since start (single misses do not latch).
    pub const fn deadline_misses(&self) -> u32 {
        self.deadline_misses_total
    }

    /// Joints whose encoder a latched fault has lost
    /// ([`FaultCode::loses_angle`]): control must not take their angle from
    /// their encoder (a frozen one still sends valid frames).
    pub const fn angle_lost_joints(&self) -> [bool; JOINTS] {
        self.latch.angle_lost
    }

    /// Joints braked this tick: the drive faults' until a reset, a lost
    /// encoder's while the chain does not give its angle.
    fn braked_joints(&self, chain_closed: &[bool; JOINTS]) -> [bool; JOINTS] {
        let mut out = self.latch.braked;
        if self.latch.angle_lost == [false; JOINTS] {
            return out;
        }
        for ((o, &lost), &closed) in out.iter_mut().zip(&self.latch.angle_lost).zip(chain_closed) {
            *o |= lost && !closed;
        }
        out
    }

    /// The post-mortem log, oldest record first (the newest [`LOG_LEN`]).
    pub fn log(&self) -> impl Iterator<Item = &FaultRecord> {
        self.latch.log.iter()
    }

    /// Clinician reset (MODE + GO held 3 s, `docs/operation.md`). Honoured
    /// only in a safe posture and only if no latched fault's condition was
    /// present at the last check; then every latched fault is cleared at
    /// once (the log is kept). Refused otherwise, and nothing changes.
    pub fn request_reset(&mut self, safe_posture: bool) -> Result<(), ResetRefused> {
        if !safe_posture {
            return Err(ResetRefused::NotSafePosture);
        }
        let still = self.present.intersection(self.latch.latched);
        if !still.is_empty() {
            return Err(ResetRefused::ConditionPresent(still));
        }
        self.latch.latched = FaultSet::EMPTY;
        self.latch.logged_channels = [0; FaultCode::COUNT];
        self.latch.logged_none = FaultSet::EMPTY;
        self.latch.braked = [false; JOINTS];
        self.latch.angle_lost = [false; JOINTS];
        self.latch.held_in_place_once = [false; JOINTS];
        Ok(())
    }

    /// Latches [`FaultCode::RestartedAfterPanic`]: the board came back from
    /// a panic (`firmware`'s panic handler), so the controller must hold the
    /// posture it finds instead of starting afresh. Call before the first
    /// tick; a clinician reset clears it like any fault.
    pub fn report_restart_after_panic(&mut self) {
        let mut t = Tick {
            tick: 0,
            present: FaultSet::EMPTY,
            new: FaultSet::EMPTY,
        };
        self.latch
            .raise(&mut t, FaultCode::RestartedAfterPanic, NO_CHANNEL, 0.0);
    }

    /// Latches a fault found at boot in the data the board loads from
    /// flash ([`FaultCode::BundleRefused`], [`FaultCode::CalibrationRefused`]):
    /// its condition stays present for as long as the board runs, so no
    /// reset clears it. Call before the first tick.
    pub fn report_boot_fault(&mut self, code: FaultCode) {
        let mut t = Tick {
            tick: 0,
            present: FaultSet::EMPTY,
            new: FaultSet::EMPTY,
        };
        self.boot_faults.insert(code);
        self.present.insert(code);
        self.latch.raise(&mut t, code, NO_CHANNEL, 0.0);
    }

    /// Logs a fault whose reaction the sequencer has already carried out in
    /// the tick that found it ([`Reaction::PlayTable`]: the re-planner's
    /// 0x0606 and 0x0607). It is not latched: it orders nothing, blocks no
    /// step and needs no reset. Its first occurrence since power-up or a
    /// reset is one post-mortem record, as a latched fault's is (a run of
    /// late answers must not push older records out of the log). A code of
    /// any other reaction is latched as a found fault.
    pub fn log_played_table(&mut self, tick: u32, code: FaultCode) {
        if code.reaction() == Reaction::PlayTable {
            if !self.latch.logged_none.contains(code) {
                self.latch.logged_none.insert(code);
                self.latch.log.push(FaultRecord {
                    tick,
                    code,
                    channel: NO_CHANNEL,
                    value: 0.0,
                });
            }
        } else {
            let mut t = Tick {
                tick,
                present: FaultSet::EMPTY,
                new: FaultSet::EMPTY,
            };
            self.latch.raise(&mut t, code, NO_CHANNEL, 0.0);
        }
    }

    /// The controller's check of one tick: the windowed checks' `found` in
    /// the last tick's facts, then this tick's own checks
    /// (`supervisor/windowed.rs`). `late`: the windowed checks had not
    /// answered the last tick's facts (a task the last tick left no time):
    /// counted as a missed deadline (0x0601), once with this tick's own
    /// miss. Hand this tick's facts ([`Supervisor::windowed_job`]) to the
    /// windowed checks next.
    #[inline(always)]
    pub fn check_after(
        &mut self,
        input: &SupervisorInput,
        frames: &[EncoderFrame; ENCODERS],
        found: &Findings,
        late: bool,
    ) -> Verdict {
        let mut t = self.begin(input);
        self.apply(found, &mut t);
        self.check_tick(input, frames, late, &mut t);
        self.end(input, t)
    }

    /// The facts of the tick just checked, for the windowed checks, with
    /// the latch's marks as they stand.
    #[inline(always)]
    pub fn windowed_job(
        &self,
        input: &SupervisorInput,
        frames: &[EncoderFrame; ENCODERS],
    ) -> WindowedJob {
        let mut job = WindowedJob {
            input: *input,
            frames: *frames,
            marks: Marks::default(),
        };
        self.mark(&mut job);
        job
    }

    /// Writes the latch's marks as they stand into `job`, whose facts were
    /// just checked: the windowed checks go on from them.
    #[inline(always)]
    pub fn mark(&self, job: &mut WindowedJob) {
        job.marks = Marks {
            braked: self.latch.braked,
            angle_lost: self.latch.angle_lost,
            held_once: self.latch.held_in_place_once,
        };
    }

    #[inline(always)]
    fn begin(&mut self, input: &SupervisorInput) -> Tick {
        self.calls = self.calls.wrapping_add(1);
        Tick {
            tick: input.tick,
            present: FaultSet::EMPTY,
            new: FaultSet::EMPTY,
        }
    }

    /// The tick's own checks; `late`: see [`Supervisor::check_after`].
    #[inline(always)]
    fn check_tick(
        &mut self,
        input: &SupervisorInput,
        frames: &[EncoderFrame; ENCODERS],
        late: bool,
        t: &mut Tick,
    ) {
        self.check_operator_inputs(input, t);
        self.check_deadline(input.deadline_missed || late, t);
        self.check_motors(input, t);
        self.check_joints(input, frames, t);
        self.check_ankles(input, frames, t);
    }

    /// Latches what the windowed checks found, as found in their tick.
    #[inline(always)]
    fn apply(&mut self, found: &Findings, t: &mut Tick) {
        for (stuck, change) in self.ankle_stuck.iter_mut().zip(found.ankle_stuck) {
            if let Some(s) = change {
                *stuck = s;
            }
        }
        let raises = found.raises();
        if raises.is_empty() && !found.overflowed() {
            return;
        }
        let now = core::mem::replace(&mut t.tick, found.tick);
        for r in raises {
            // Held in place only if the latch still holds the reason (a
            // reset since the facts may have released the other joint).
            let hold = r.hold && self.latch.holds_in_place(r.code, usize::from(r.channel));
            if hold {
                let j = usize::from(r.channel);
                if let (Some(once), Some(now)) = (
                    self.latch.held_in_place_once.get_mut(j),
                    self.latch.hold_in_place.get_mut(j),
                ) {
                    *once = true;
                    *now = true;
                }
            }
            self.latch
                .raise_marking(t, r.code, r.channel, r.value, !hold);
        }
        if found.overflowed() {
            self.latch
                .raise(t, FaultCode::ChecksLate, NO_CHANNEL, found.tick as f32);
        }
        t.tick = now;
    }

    #[inline(always)]
    fn end(&mut self, input: &SupervisorInput, t: Tick) -> Verdict {
        self.present = t.present.union(self.boot_faults);
        Verdict {
            reaction: self.latch.latched.reaction(),
            latched: self.latch.latched,
            new: t.new,
            braked_joints: self.braked_joints(&input.chain_closed),
            rehold_joints: core::mem::take(&mut self.latch.hold_in_place),
        }
    }
}

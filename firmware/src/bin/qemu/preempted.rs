//! The re-planner in the tick's idle time, scheduled as on the motor board
//! (`firmware::idle_replan`): the 1 kHz control tick in a timer interrupt,
//! which preempts everything else, and the re-planner in thread mode, which
//! runs whenever the tick does not and sleeps (WFI) when nothing is asked.
//! The two share only the [`ReplanSlot`] (atomics): the tick never waits
//! and takes no lock.
//!
//! The run replayed is a stair descent of a pilot leaning 2° forward,
//! recorded on the host with the simulator's model of this re-planner
//! (`sim::replay::record_replanning`). The timer's period is one tick of
//! the 168 MHz core, 168,000 instructions (4,200 counts of the 25 MHz
//! clock under `-icount shift=0`), so the re-planner gets the idle time
//! the board would give it. The target's commands equal the host's only if
//! each answer reached the sequencer within its latency, as on the host.
//!
//! Prints per re-plan `replan: tick=<asked> insns=<n> evals=<k>
//! ticks=<to the answer> used=<replanned|table>` (its own instructions, the
//! ticks' taken out), per phase `tick: replanning phase=<name> avg=<n>
//! worst=<n> ticks=<n>`, and `tick: replanning replayed ticks=<n>
//! max_command_diff_nm=<d> differing_ticks=<n> overruns=<n>`; xtask checks
//! them. Fails when a re-plan takes more than 0.5 s of the core, a tick
//! overruns its period, or a command differs from the host's.

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use cortex_m::peripheral::scb::SystemHandler;
use cortex_m::peripheral::{NVIC, SCB, SYST};
use cortex_m_rt::exception;
use exogait_device::replan::REPLAN;
use exogait_device::tick_record::{RECORD_LEN, Segment, TickRecord, segments};
use exogait_device::{DeviceConfig, build_controller};
use firmware::idle_replan::IdleReplanner;
use firmware::qemu_rig::RigHardware;
use firmware::tick_replay::{REPLANNING_RECORDS, Replay};
use firmware::tick_state::TickState;
use firmware::{board_config, model_task, qemu_rig};
use gait_control::controller::Controller;
use gait_control::feedforward::ModelTask;
use gait_control::replan::{ReplanOutcome, ReplanSlot};
use gait_control::supervisor::WindowedChecks;

use crate::recorded::print_phases;
use crate::{INSTR_PER_TICK, Out, SYST_MAX, checked, line};

/// One tick of the 168 MHz core in counts of the 25 MHz timer clock under
/// `-icount shift=0` (1 ns an instruction): 168,000 instructions.
const PERIOD_COUNTS: u32 = 168_000 / INSTR_PER_TICK;
/// 0.5 s of the 168 MHz core.
const MAX_REPLAN_INSTRUCTIONS: u32 = 84_000_000;
/// Re-plans reported (a recording of a few steps asks fewer).
const MAX_REPLANS: usize = 8;

/// The slot the tick's sequencer and the idle-time re-planner share.
static SLOT: ReplanSlot = ReplanSlot::new();
/// What the tick works on; the interrupt takes it, and the thread only
/// before the timer starts and after it stops.
static TICKING: TickState<Ticking> = TickState::new();
/// Timer interrupts so far.
static TICKS: AtomicU32 = AtomicU32::new(0);
/// Instructions spent in the timer interrupt so far (taken out of the
/// re-planner's count).
static TICK_INSTRUCTIONS: AtomicU32 = AtomicU32::new(0);
/// The model task's answers so far, their instructions, and the most one
/// took (taken out of the re-planner's count, as the tick's are).
static MODEL_ANSWERS: AtomicU32 = AtomicU32::new(0);
static MODEL_INSTRUCTIONS: AtomicU32 = AtomicU32::new(0);
static MODEL_WORST: AtomicU32 = AtomicU32::new(0);
/// The recording has been replayed to its end.
static DONE: AtomicBool = AtomicBool::new(false);

/// The tick's state: the board's controller with its re-planner, its
/// drivers over the rig, and the recording.
struct Ticking {
    device: DeviceConfig,
    controller: Controller<'static>,
    hw: RigHardware,
    records: &'static [u8],
    next: u32,
    replay: Replay,
    overruns: u32,
}

impl Ticking {
    /// One control tick on the next recorded inputs; `false` at the end.
    fn tick(&mut self) -> bool {
        let at = self.next as usize * RECORD_LEN;
        let Some(record) = self
            .records
            .get(at..at + RECORD_LEN)
            .and_then(TickRecord::decode)
        else {
            return false;
        };
        qemu_rig::replay(&self.device, &record);
        // The board's DMA reads the sensors before the tick: not the
        // tick's work (it is the interrupt's, out of the re-planner's
        // count all the same).
        let frames = qemu_rig::acquire(&mut self.hw, &self.controller);
        let start = SYST::get_current();
        let report = self
            .controller
            .tick_acquired(&mut self.hw, &frames, record.deadline_missed);
        let instr = since(start);
        self.replay
            .account(self.next, instr, &report, &record.host_command_nm);
        self.next += 1;
        true
    }
}

/// The ticks so far, the instructions of the ticks and the model task so
/// far, and SysTick, read together (no interrupt between them).
fn clocks() -> (u32, u32, u32) {
    cortex_m::interrupt::free(|_| {
        (
            TICKS.load(Ordering::Acquire),
            TICK_INSTRUCTIONS
                .load(Ordering::Acquire)
                .wrapping_add(MODEL_INSTRUCTIONS.load(Ordering::Acquire)),
            SYST::get_current(),
        )
    })
}

/// Instructions since SysTick read `start` (it counts down, free-running).
fn since(start: u32) -> u32 {
    let ticks = start.wrapping_sub(SYST::get_current()) & SYST_MAX;
    ticks.saturating_mul(INSTR_PER_TICK)
}

/// The mps2-an386's CMSDK APB timer 0 (ARM DDI 0479C §4.3; QEMU's
/// `hw/arm/mps2.c` puts it at 0x4000_0000 on IRQ 8, clocked at 25 MHz).
mod timer0 {
    const BASE: usize = 0x4000_0000;
    const CTRL: *mut u32 = BASE as *mut u32;
    const VALUE: *mut u32 = (BASE + 0x04) as *mut u32;
    const RELOAD: *mut u32 = (BASE + 0x08) as *mut u32;
    /// INTSTATUS when read, INTCLEAR when written.
    const INT: *mut u32 = (BASE + 0x0C) as *mut u32;
    const ENABLE: u32 = 1 << 0;
    const IRQ_ENABLE: u32 = 1 << 3;

    /// Its interrupt's number.
    #[derive(Clone, Copy)]
    pub struct Irq;

    // SAFETY: 8 is timer 0's interrupt on the mps2-an386.
    unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
        fn number(self) -> u16 {
            8
        }
    }

    /// Interrupts every `period` counts (it counts RELOAD down to 0, so
    /// RELOAD + 1 counts a period).
    pub fn start(period: u32) {
        let reload = period.saturating_sub(1);
        // SAFETY: the timer's own registers, which nothing else in this
        // image touches; 32-bit aligned MMIO.
        unsafe {
            CTRL.write_volatile(0);
            RELOAD.write_volatile(reload);
            VALUE.write_volatile(reload);
            INT.write_volatile(1);
            CTRL.write_volatile(ENABLE | IRQ_ENABLE);
        }
    }

    /// Stopped, its interrupt cleared.
    pub fn stop() {
        // SAFETY: as in `start`.
        unsafe {
            CTRL.write_volatile(0);
            INT.write_volatile(1);
        }
    }

    /// Clears the interrupt.
    pub fn clear() {
        // SAFETY: as in `start`.
        unsafe { INT.write_volatile(1) }
    }

    /// The period ended again since the last `clear`.
    pub fn pending() -> bool {
        // SAFETY: as in `start`.
        unsafe { INT.read_volatile() & 1 != 0 }
    }
}

/// Every interrupt without a handler of its own comes here (cortex-m-rt's
/// default vector table); only timer 0's is enabled.
#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == 8 {
        on_tick();
    }
}

/// The model task, below the tick (`firmware::model_task`).
#[exception]
fn PendSV() {
    static mut TASK: Option<ModelTask<'static>> = None;
    let start = SYST::get_current();
    model_task::serve(TASK);
    let instr = since(start);
    MODEL_ANSWERS.fetch_add(1, Ordering::AcqRel);
    MODEL_INSTRUCTIONS.fetch_add(instr, Ordering::AcqRel);
    MODEL_WORST.fetch_max(instr, Ordering::AcqRel);
}

/// The timer's interrupt: one control tick.
fn on_tick() {
    let start = SYST::get_current();
    timer0::clear();
    let _ = TICKING.with(|t| {
        if !t.tick() {
            DONE.store(true, Ordering::Release);
        }
        // The next period ended before this tick did.
        if timer0::pending() {
            t.overruns += 1;
        }
    });
    TICKS.fetch_add(1, Ordering::AcqRel);
    TICK_INSTRUCTIONS.fetch_add(since(start), Ordering::AcqRel);
    model_task::pend();
}

/// One re-plan as thread mode ran it.
#[derive(Clone, Copy)]
struct Seen {
    asked_tick: u32,
    instructions: u32,
    evals: u16,
    ticks: u32,
    outcome: ReplanOutcome,
}

/// Replays the recording with the tick in the timer's interrupt and the
/// re-planner in thread mode; prints what they did. Returns the number of
/// failures.
pub(crate) fn check(out: &mut Out, scb: &mut SCB) -> usize {
    let Some(segment) = segments(REPLANNING_RECORDS).ok().and_then(|mut s| s.next()) else {
        out.put(&mut line(
            "tick: replanning: no recording built in (cargo xtask qemu records one)",
        ));
        return 0;
    };
    let Ok(device) = board_config::device() else {
        out.put(&mut line("FAIL replanning: device configuration refused"));
        return 1;
    };
    let tables = board_config::flash_tables();
    let Some((ticking, checks)) = ticking(&device, &segment) else {
        out.put(&mut line(
            "FAIL replanning: the controller or its drivers were refused",
        ));
        return 1;
    };
    // SAFETY: PendSV has not run yet; lowering its priority breaks no
    // critical section (nothing relies on PendSV being masked).
    unsafe { scb.set_priority(SystemHandler::PendSV, model_task::PRIORITY) };
    let model = ModelTask::new(ticking.controller.config().model, &model_task::SLOT)
        .with_checks(checks)
        .with_steps(ticking.controller.steps());
    if !model_task::install(model) {
        out.put(&mut line("FAIL replanning: the model task is in use"));
        return 1;
    }
    if !TICKING.place(ticking) {
        out.put(&mut line("FAIL replanning: the tick's state is in use"));
        return 1;
    }
    timer0::start(PERIOD_COUNTS);
    // SAFETY: its handler shares state with thread mode only through
    // atomics and the `TICKING` mutex.
    unsafe { NVIC::unmask(timer0::Irq) };

    let mut replanner = IdleReplanner::new(&SLOT, device, tables);
    let mut seen: [Option<Seen>; MAX_REPLANS] = [None; MAX_REPLANS];
    let mut count = 0;
    while !DONE.load(Ordering::Acquire) {
        let (asked_tick, in_ticks, start) = clocks();
        let Some(answer) = replanner.serve() else {
            // An interrupt between the check and here ends the sleep at
            // the next tick at the latest.
            cortex_m::asm::wfi();
            continue;
        };
        let (now_tick, out_ticks, end) = clocks();
        let elapsed = (start.wrapping_sub(end) & SYST_MAX).saturating_mul(INSTR_PER_TICK);
        let ticked = out_ticks.wrapping_sub(in_ticks);
        if let Some(s) = seen.get_mut(count) {
            *s = Some(Seen {
                asked_tick,
                instructions: elapsed.saturating_sub(ticked),
                evals: answer.evals,
                ticks: now_tick.wrapping_sub(asked_tick),
                outcome: answer.outcome,
            });
        }
        count += 1;
    }
    NVIC::mask(timer0::Irq);
    timer0::stop();
    let Some(done) = TICKING.take() else {
        out.put(&mut line("FAIL replanning: the tick's state is gone"));
        return 1;
    };
    report(out, &done, seen.iter().flatten())
}

/// The controller the board builds for the recorded gait, its re-planner
/// on; its drivers over the rig.
fn ticking(
    device: &DeviceConfig,
    segment: &Segment<'static>,
) -> Option<(Ticking, Option<WindowedChecks>)> {
    let mut controller =
        build_controller(device, board_config::flash_tables(), segment.gait).ok()?;
    controller.set_replanner(&SLOT, REPLAN);
    let checks = controller.set_model_task(&model_task::SLOT);
    let hw = board_config::hardware(device, qemu_rig::peripherals()).ok()?;
    let ticking = Ticking {
        device: *device,
        controller,
        hw,
        records: segment.records,
        next: 0,
        replay: Replay {
            segments: 1,
            ..Replay::default()
        },
        overruns: 0,
    };
    Some((ticking, checks))
}

/// Prints the re-plans and the ticks; the number of failures.
fn report<'a>(out: &mut Out, done: &Ticking, seen: impl Iterator<Item = &'a Seen>) -> usize {
    let mut failed = 0;
    for s in seen {
        let in_time = s.ticks < u32::from(REPLAN.latency_ticks);
        let used = if s.outcome == ReplanOutcome::Replanned && in_time {
            "replanned"
        } else {
            "table"
        };
        let over = s.instructions > MAX_REPLAN_INSTRUCTIONS;
        failed += usize::from(over);
        out.put(
            checked(over, "replan: tick=")
                .u32(s.asked_tick)
                .str(" insns=")
                .u32(s.instructions)
                .str(" evals=")
                .u32(u32::from(s.evals))
                .str(" ticks=")
                .u32(s.ticks)
                .str(" used=")
                .str(used),
        );
    }
    let r = &done.replay;
    print_phases(out, "tick: replanning phase=", r);
    let answers = MODEL_ANSWERS.load(Ordering::Acquire);
    out.put(
        line("model: replanning avg=")
            .u32(MODEL_INSTRUCTIONS.load(Ordering::Acquire) / answers.max(1))
            .str(" worst=")
            .u32(MODEL_WORST.load(Ordering::Acquire))
            .str(" answers=")
            .u32(answers),
    );
    let bad = r.differing_ticks > 0 || done.overruns > 0;
    failed += usize::from(bad);
    out.put(
        checked(bad, "tick: replanning replayed ticks=")
            .u32(r.ticks)
            .str(" max_command_diff_nm=")
            .exp(r.max_command_diff_nm)
            .str(" differing_ticks=")
            .u32(r.differing_ticks)
            .str(" overruns=")
            .u32(done.overruns),
    );
    failed
}

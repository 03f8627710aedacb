//! The motor board's three priorities: TIM2's update interrupt runs the
//! control tick every 1 ms on the sensor frames the DMA read before it
//! (`acquire`, started by TIM2's compare and carried by the DMA streams'
//! interrupts, at the tick's priority); PendSV, which the tick pends as it ends, runs
//! the supervisor's windowed checks of the tick's facts and works out the
//! model's feed-forward for the next tick (`firmware::model_task`); thread
//! mode runs the step re-planner when the sequencer asked for one (with
//! `board_config::REPLANNING`, `firmware::idle_replan`), else sleeps (WFI).
//! Each preempts the ones below it; they share only the slots (atomics, and
//! the check slot's short critical sections), so the tick never waits for
//! either's work.
//!
//! The watchdog is fed by the tick: a tick that stops coming resets the
//! board, whatever thread mode is doing.

use cortex_m::peripheral::{DWT, NVIC};
use cortex_m_rt::exception;
use firmware::board_config::{self, TICK_HZ};
use firmware::idle_replan::IdleReplanner;
use firmware::model_task;
use firmware::tick_state::TickState;
use gait_control::acquisition;
use gait_control::controller::{Controller, TickReport};
use gait_control::faults::{FaultCode, FaultSet, Reaction};
use gait_control::feedforward::ModelTask;
use gait_control::replan::ReplanSlot;
use stm32f4xx_hal::pac;
use stm32f4xx_hal::watchdog::IndependentWatchdog;

use crate::acquire;
use crate::tick::{self, Tick};
use crate::{BoardHardware, CYCLES_PER_TICK};

/// The tick's deadline in core cycles: the next acquisition's start,
/// `acquire::LEAD_US` before the period ends.
const DEADLINE_CYCLES: u32 =
    CYCLES_PER_TICK / tick::US_PER_TICK * (tick::US_PER_TICK - acquire::LEAD_US);

/// The slot the sequencer and the idle-time re-planner share.
pub static SLOT: ReplanSlot = ReplanSlot::new();

/// What the tick's interrupt works on: placed once by [`run`], before the
/// interrupt is unmasked; thread mode never touches it again.
static BOARD: TickState<Board> = TickState::new();

/// The controller, its drivers, the tick's timer and watchdog, the log.
pub struct Board {
    controller: Controller<'static>,
    hw: BoardHardware,
    tick: Tick,
    dog: IndependentWatchdog,
    log: LoopLog,
    /// The last tick ran past its deadline, the next acquisition's start
    /// (750 µs in): this one tells the supervisor.
    overran: bool,
    /// Periods begun (TIM2 updates): stamps each acquisition with the
    /// tick it is for.
    period: u32,
}

impl Board {
    pub fn new(
        controller: Controller<'static>,
        hw: BoardHardware,
        tick: Tick,
        dog: IndependentWatchdog,
    ) -> Self {
        Self {
            controller,
            hw,
            tick,
            dog,
            log: LoopLog::new(),
            overran: false,
            period: 0,
        }
    }

    /// TIM2's interrupt: the compare starts the next tick's acquisition,
    /// the update runs the tick (both when a late tick left both flags
    /// up: the acquisition then misses this tick, which reads its sensors
    /// itself).
    fn on_timer(&mut self) {
        if self.tick.compare_elapsed() {
            acquire::start(self.period);
        }
        if self.tick.elapsed() {
            self.period = self.period.wrapping_add(1);
            self.tick();
        }
    }

    /// One control tick, in the timer's interrupt. The DWT cycle counter
    /// measures its work for the log.
    fn tick(&mut self) {
        let start = DWT::cycle_count();
        let frames = match acquire::take(self.period.wrapping_sub(1)) {
            Some(frames) => frames,
            // None of its own (late or stalled): the tick reads the
            // sensors itself, the acquisition stopped (about 235 µs, both
            // buses in turn).
            None => {
                acquire::stop();
                acquisition::acquire(&mut self.hw, self.controller.next_drive_joint())
            }
        };
        let report = self
            .controller
            .tick_acquired(&mut self.hw, &frames, self.overran);
        acquire::set_next_drive_joint(self.controller.next_drive_joint());
        model_task::pend();
        self.dog.feed();
        let cycles = DWT::cycle_count().wrapping_sub(start);
        self.log
            .after_tick(&report, &self.controller, cycles, self.overran);
        // The next acquisition's start (or the next period's update)
        // already here: this tick (and its log) ran past its deadline, and
        // the next tick's sensors come late or not at all. The supervisor
        // decides what a run of them means.
        self.overran = self.tick.compare_pending() || self.tick.pending();
    }
}

/// The model task, below the tick.
#[exception]
fn PendSV() {
    static mut TASK: Option<ModelTask<'static>> = None;
    model_task::serve(TASK);
}

/// Every interrupt without a handler of its own comes here (cortex-m-rt's
/// vector table without a device crate); only TIM2's and the two DMA
/// streams' (`acquire::install`) are unmasked.
#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    const TIM2: i16 = pac::Interrupt::TIM2 as i16;
    const ENCODER_FRAME: i16 = pac::Interrupt::DMA2_STREAM0 as i16;
    const CONVERSION: i16 = pac::Interrupt::DMA1_STREAM3 as i16;
    match irqn {
        // No state to tick with (unreachable: `run` places it before
        // unmasking): no more ticks, so the watchdog, fed only by the
        // tick, resets the board into its safe boot.
        TIM2 => {
            if BOARD.with(Board::on_timer).is_none() {
                NVIC::mask(pac::Interrupt::TIM2);
            }
        }
        ENCODER_FRAME => acquire::on_encoder_frame(),
        CONVERSION => acquire::on_conversion(),
        _ => {}
    }
}

/// Hands `board` to the tick's interrupt and unmasks it; then runs the
/// re-planner (if any) whenever a request waits, and sleeps otherwise.
pub fn run(board: Board, mut replanner: Option<IdleReplanner<'static>>) -> ! {
    if !BOARD.place(board) {
        crate::halt("the tick's state is in use: motors stay disabled");
    }
    // SAFETY: the handler shares state with thread mode only through the
    // `BOARD` mutex (no longer used here) and the slot's atomics.
    unsafe { NVIC::unmask(pac::Interrupt::TIM2) };
    loop {
        let served =
            board_config::REPLANNING && replanner.as_mut().is_some_and(|r| r.serve().is_some());
        if !served {
            // A request made between the check and here waits for the next
            // tick's interrupt to end the sleep: 1 ms of the 200 ms latency.
            cortex_m::asm::wfi();
        }
    }
}

/// What the tick reports over defmt: new faults and reactions at once,
/// each finished step's crutch load, and once a second a status line with
/// the forces and the worst tick.
struct LoopLog {
    faults: FaultSet,
    reaction: Reaction,
    worst_cycles: u32,
    overruns: u32,
    last_step: Option<u32>,
    /// The newest post-mortem record reported.
    last_record: Option<(u32, FaultCode)>,
}

impl LoopLog {
    fn new() -> Self {
        Self {
            faults: FaultSet::EMPTY,
            reaction: Reaction::None,
            worst_cycles: 0,
            overruns: 0,
            last_step: None,
            last_record: None,
        }
    }

    fn after_tick(
        &mut self,
        r: &TickReport,
        controller: &Controller<'_>,
        cycles: u32,
        overran: bool,
    ) {
        self.worst_cycles = self.worst_cycles.max(cycles);
        self.overruns = self.overruns.saturating_add(u32::from(overran));
        if r.faults != self.faults {
            for code in r.faults.iter() {
                if !self.faults.contains(code) {
                    defmt::error!(
                        "tick {=u32}: fault {=u16} {=str}",
                        r.tick,
                        code.code(),
                        code.name()
                    );
                }
            }
            self.faults = r.faults;
        }
        if r.reaction != self.reaction {
            defmt::warn!(
                "tick {=u32}: reaction {} (motors enabled {=bool})",
                r.tick,
                r.reaction,
                r.motors_enabled
            );
            self.reaction = r.reaction;
        }
        // 0x0606/0x0607 never latch: reported from the post-mortem log,
        // which records the first of each since a reset.
        let newest = controller
            .supervisor()
            .log()
            .last()
            .map(|rec| (rec.tick, rec.code));
        if newest != self.last_record {
            if let Some((tick, code)) = newest
                && code.reaction() == Reaction::PlayTable
            {
                defmt::warn!(
                    "tick {=u32}: fault {=u16} {=str}: the step plays its table",
                    tick,
                    code.code(),
                    code.name()
                );
            }
            self.last_record = newest;
        }
        for step in controller.crutch_load().log() {
            if self.last_step.is_none_or(|s| step.step > s) {
                defmt::info!(
                    "step {=u32}: crutch impulse {=f32} N·s, peaks L {=f32} R {=f32} N, {=f32} s",
                    step.step,
                    step.impulse_ns,
                    step.left_peak_n,
                    step.right_peak_n,
                    step.duration_s
                );
                self.last_step = Some(step.step);
            }
        }
        if r.tick.is_multiple_of(TICK_HZ) {
            let [left_foot, right_foot, left_crutch, right_crutch] = r.forces_n;
            defmt::info!(
                "t {=u32} s: {} feet {=f32} {=f32} N, crutches {=f32} {=f32} N, worst tick {=u32}/{=u32} cycles, overruns {=u32}, acquisitions missed {=u32}",
                r.tick / TICK_HZ,
                r.phase,
                left_foot,
                right_foot,
                left_crutch,
                right_crutch,
                self.worst_cycles,
                DEADLINE_CYCLES,
                self.overruns,
                acquire::missed()
            );
            self.worst_cycles = 0;
        }
    }
}

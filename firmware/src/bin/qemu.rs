//! QEMU `mps2-an386` (Cortex-M4F) image: runs the power-on self-test and the
//! on-target benchmarks, prints them over semihosting and reports the result
//! through QEMU's exit status (0 = every check passed).
//!
//! The control-tick benchmark builds the controller and its hardware through
//! `firmware::board_config` exactly as the motor board does, over the
//! in-memory peripherals of `firmware::qemu_rig` (a pilot standing still),
//! runs [`CONTROL_TICKS`] ticks and fails the run if the controller reports
//! any fault or does not enable its motors.
//!
//! Instruction counts: run QEMU with `-icount shift=0,sleep=off` so every
//! instruction advances the virtual clock by 1 ns (and a `WFI` skips to the
//! next timer event); SysTick on the core clock (25 MHz on this machine)
//! then ticks once per 40 instructions.
//!
//! Output: semihosting writes of lines built with `firmware::text::Line`,
//! not `core::fmt` (whose float and `Debug` formatting carry panic paths and
//! indirect calls; `cargo xtask panics` accepts none in the image).
#![no_std]
#![no_main]
// cortex-m-rt's `#[entry]`/`#[exception]` expand to `#[export_name]`, which
// the unsafe_code lint counts; this file contains no unsafe block of its own.
#![allow(unsafe_code)]

#[path = "qemu/bundle.rs"]
mod bundle;
#[path = "qemu/calibration.rs"]
mod calibration;
#[path = "qemu/preempted.rs"]
mod preempted;
#[path = "qemu/recorded.rs"]
mod recorded;
#[path = "qemu/replan.rs"]
mod replan;

use core::hint::black_box;

use cortex_m::peripheral::{SYST, syst::SystClkSource};
use cortex_m_rt::entry;
use cortex_m_semihosting::debug;
use cortex_m_semihosting::hio::{self, HostStream};
use exogait_device::DeviceError;
use firmware::text::Line;
use firmware::{board_config, qemu_rig, selftest, tick_replay};
use gait_control::faults::{FaultSet, Reaction};
use gait_control::feedforward::{ModelSlot, ModelTask};
use gait_core::BodyModel;
use gait_core::dynamics::Contact::{FixedAnkle, ToeRocker};
use gait_core::dynamics::{inverse_dynamics, share_load};
use gait_core::ik::{IkSolver, IkTarget};
use gait_core::scalar::sin_cos_f32;

/// Instructions per core-clock SysTick tick under `-icount shift=0`
/// (1 ns per instruction, 25 MHz core clock).
const INSTR_PER_TICK: u32 = 40;
const SYST_MAX: u32 = 0x00FF_FFFF;
/// Control ticks run by the control-tick benchmark (1 s at 1 kHz).
const CONTROL_TICKS: u32 = 1_000;
/// Ticks after which the standing rig's motors must be enabled.
const ENABLE_WITHIN_TICKS: u32 = 5;

/// The host's standard output over semihosting (nothing is printed if QEMU
/// refuses to open it).
struct Out(Option<HostStream>);

impl Out {
    fn open() -> Self {
        Self(hio::hstdout().ok())
    }

    /// Prints `line` and a newline.
    fn put(&mut self, line: &mut Line) {
        line.str("\n");
        if let Some(stream) = &mut self.0 {
            let _ = stream.write_all(line.as_bytes());
        }
    }
}

/// A new line starting with `s`.
fn line(s: &str) -> Line {
    let mut l = Line::new();
    l.str(s);
    l
}

/// A new line starting with `s`, marked `FAIL ` first when `failed`
/// (xtask looks for the mark).
fn checked(failed: bool, s: &str) -> Line {
    let mut l = line(if failed { "FAIL " } else { "" });
    l.str(s);
    l
}

/// What a configuration error is, by name (the index where it has one).
fn device_error(l: &mut Line, e: &DeviceError) {
    let (name, index) = match e {
        DeviceError::ForceCalibration(i, _) => ("force calibration", Some(*i)),
        DeviceError::DriveCurrentCalibration(i, _) => ("drive current calibration", Some(*i)),
        DeviceError::Motor(i, _) => ("motor", Some(*i)),
        DeviceError::MotorDisable(i) => ("motor disable", Some(*i)),
        DeviceError::Operator(_) => ("operator", None),
        DeviceError::Supervisor(_) => ("supervisor", None),
        DeviceError::Controller(_) => ("controller", None),
        DeviceError::Patient(_) => ("patient model", None),
    };
    l.str(name);
    if let Some(i) = index {
        l.str(" ").usize(i);
    }
}

/// A reaction by its name.
const fn reaction_name(r: Reaction) -> &'static str {
    match r {
        Reaction::None => "None",
        Reaction::PlayTable => "PlayTable",
        Reaction::FinishStepThenHold => "FinishStepThenHold",
        Reaction::SafeHold => "SafeHold",
        Reaction::DisableMotors => "DisableMotors",
    }
}

/// A fault set as `[0x0205 name, …]`.
fn fault_list(l: &mut Line, faults: &FaultSet) {
    l.str("[");
    for (i, code) in faults.iter().enumerate() {
        if i > 0 {
            l.str(", ");
        }
        l.str("0x")
            .hex(u32::from(code.code()), 4)
            .str(" ")
            .str(code.name());
    }
    l.str("]");
}

/// A phase by the name the replay prints it with.
fn phase_name(phase: &gait_control::sequencer::Phase) -> &'static str {
    tick_replay::PHASES
        .get(tick_replay::phase_index(phase))
        .copied()
        .unwrap_or("?")
}

/// Counts instructions with SysTick; intervals must stay below 2^24 ticks.
struct InstrCounter {
    syst: SYST,
}

impl InstrCounter {
    fn new(mut syst: SYST) -> Self {
        syst.disable_counter();
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(SYST_MAX);
        syst.clear_current();
        syst.enable_counter();
        Self { syst }
    }

    /// Average instructions per call of `f` over `n` calls (loop included).
    fn per_call(&mut self, n: u32, mut f: impl FnMut(u32)) -> u32 {
        self.syst.clear_current();
        let start = SYST::get_current();
        for i in 0..n {
            f(black_box(i));
        }
        let end = SYST::get_current();
        let ticks = start.wrapping_sub(end) & SYST_MAX;
        ticks.saturating_mul(INSTR_PER_TICK) / n.max(1)
    }

    /// Instructions of one call of `f` (resolution: one SysTick tick, 40
    /// instructions) and its result.
    fn once<T>(&mut self, f: impl FnOnce() -> T) -> (u32, T) {
        self.syst.clear_current();
        let start = SYST::get_current();
        let out = f();
        let end = SYST::get_current();
        let ticks = start.wrapping_sub(end) & SYST_MAX;
        (ticks.saturating_mul(INSTR_PER_TICK), out)
    }
}

#[entry]
fn main() -> ! {
    let failed = run();
    debug::exit(if failed == 0 {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}

fn run() -> usize {
    let out = &mut Out::open();
    out.put(&mut line("exogait self-test (mps2-an386, Cortex-M4F)"));
    let checks = selftest::run();
    let mut failed = 0;
    for c in &checks {
        let verdict = if c.passed() { "ok  " } else { "FAIL" };
        if !c.passed() {
            failed += 1;
        }
        out.put(
            line("  ")
                .str(verdict)
                .str(" ")
                .str_padded(c.name, 28)
                .str(" ")
                .sci(c.value, 3)
                .str(" (bound ")
                .sci(c.bound, 1)
                .str(")"),
        );
    }
    out.put(
        line("selftest: ")
            .usize(checks.len().saturating_sub(failed))
            .str(" passed, ")
            .usize(failed)
            .str(" failed"),
    );

    match cortex_m::Peripherals::take() {
        Some(mut p) => {
            let mut ctr = InstrCounter::new(p.SYST);
            bench(out, &mut ctr);
            failed += control_tick_bench(out, &mut ctr);
            // Before the replay: `cargo xtask profile` counts from the
            // replay's start on.
            failed += replan::check(out, &mut ctr);
            failed += preempted::check(out, &mut p.SCB);
            failed += recorded::check(out, &mut ctr);
            failed += calibration::check(out);
            failed += bundle::check(out, &mut ctr);
        }
        None => {
            out.put(&mut line("bench: SysTick unavailable"));
            failed += 1;
        }
    }
    failed
}

/// On-target instruction counts (see README, "Performance").
fn bench(out: &mut Out, ctr: &mut InstrCounter) {
    let base = ctr.per_call(1000, |i| {
        black_box(i);
    });
    let sinf = ctr.per_call(1000, |i| {
        black_box(libm::sinf(i as f32 * 0.01));
    });
    let fast = ctr.per_call(1000, |i| {
        black_box(sin_cos_f32(i as f32 * 0.01));
    });
    let m: BodyModel<f32> = BodyModel::<f64>::paper_table_iii().cast();
    let id = ctr.per_call(1000, |i| {
        let a = i as f32 * 1e-3;
        let phi = [0.2 + a, -0.1, 0.05, 2.7 - a, 3.5];
        black_box(inverse_dynamics(&m, &FixedAnkle, &phi, &BENCH_W, &BENCH_DD));
    });
    let ik = IkSolver::new(&m);
    let ik_only = ctr.per_call(1000, |i| {
        black_box(ik.solve(&bench_ik_target(i)).ok());
    });
    let ik_id = ctr.per_call(1000, |i| {
        if let Ok(sol) = ik.solve(&bench_ik_target(i)) {
            black_box(inverse_dynamics(
                &m,
                &FixedAnkle,
                &sol.phi,
                &BENCH_W,
                &BENCH_DD,
            ));
        }
    });
    let share = ctr.per_call(1000, |i| {
        let a = i as f32 * 1e-4;
        let phi = [0.0 + a, -0.74, 0.0, 2.98, 3.30];
        let single = [-208.0, -208.0, 5.0, 5.0, -2.0];
        black_box(share_load(&m, &FixedAnkle, &phi, &single, 912.0));
    });
    // The stance heel up (stair descent): the toe rocker's extra terms.
    let rocker = ToeRocker(gait_core::foot::StanceFoot::for_model(&m));
    let toe_id = ctr.per_call(1000, |i| {
        let a = i as f32 * 1e-3;
        let phi = [0.6 + a, -0.3, 0.05, 2.7 - a, 3.5];
        black_box(inverse_dynamics(&m, &rocker, &phi, &BENCH_W, &BENCH_DD));
    });
    out.put(line("bench: loop_overhead instr=").u32(base));
    for (name, instr) in [
        ("toe_rocker_inverse_dynamics_f32", toe_id),
        ("share_load_f32", share),
        ("ik_f32", ik_only),
        ("ik_plus_inverse_dynamics_f32", ik_id),
        ("libm_sinf", sinf),
        ("sin_cos_f32", fast),
        ("inverse_dynamics_f32", id),
    ] {
        out.put(
            line("bench: ")
                .str(name)
                .str(" instr=")
                .u32(instr.saturating_sub(base)),
        );
    }
}

/// The inverse-dynamics benchmarks' joint rates (rad/s) and accelerations
/// (rad/s²).
const BENCH_W: [f32; 5] = [0.4, -0.9, 0.2, -2.1, 3.3];
const BENCH_DD: [f32; 5] = [1.5, -2.0, 0.7, 6.0, -9.0];

/// The IK benchmarks' target at call `i`: the swing ankle moving forward.
#[inline(always)]
fn bench_ik_target(i: u32) -> IkTarget<f32> {
    IkTarget {
        x5: -0.2 + i as f32 * 1e-4,
        y5: 0.1,
        phi1: 0.1,
        phi3: 0.05,
        r2: 0.7,
    }
}

/// Runs the board's controller on the standing rig: instructions per tick
/// (average and worst) and a health check. Returns the number of failures.
fn control_tick_bench(out: &mut Out, ctr: &mut InstrCounter) -> usize {
    let device = match board_config::device() {
        Ok(d) => d,
        Err(e) => {
            let mut l = line("FAIL control: device configuration refused: ");
            device_error(&mut l, &e);
            out.put(&mut l);
            return 1;
        }
    };
    // xtask compares this with the host's (the simulator's) configuration.
    out.put(line("device: fingerprint=0x").hex(device.fingerprint(), 8));
    let controller = match board_config::build_controller() {
        Ok(c) => c,
        Err(e) => {
            let mut l = line("FAIL control: configuration refused: ");
            device_error(&mut l, &e);
            out.put(&mut l);
            return 1;
        }
    };
    let mut hw = match board_config::hardware(&device, qemu_rig::standing(&device)) {
        Ok(h) => h,
        Err(e) => {
            let mut l = line("FAIL control: hardware refused: ");
            device_error(&mut l, &e);
            out.put(&mut l);
            return 1;
        }
    };
    // Every driver must start disabled (`hardware` disables each one).
    let mut failed = 0;
    if hw.motors.iter().any(|m| m.is_enabled()) {
        out.put(&mut line("FAIL control: a motor is enabled after boot"));
        failed += 1;
    }
    out.put(
        line("control: state ")
            .usize(core::mem::size_of_val(&controller) + core::mem::size_of_val(&hw))
            .str(" bytes (controller ")
            .usize(core::mem::size_of_val(&controller))
            .str(", hardware ")
            .usize(core::mem::size_of_val(&hw))
            .str(")"),
    );
    // The model task answers between the ticks, as PendSV does on the board.
    let slot = ModelSlot::new();
    let mut controller: gait_control::controller::Controller<'_> = controller;
    let checks = controller.set_model_task(&slot);
    let mut task = ModelTask::new(controller.config().model, &slot)
        .with_checks(checks)
        .with_steps(controller.steps());
    let base = ctr.once(|| black_box(0u32)).0;
    let mut total: u64 = 0;
    let mut worst = 0u32;
    let mut worst_at = 0u32;
    let mut first_bad = None;
    let mut last = None;
    for i in 0..CONTROL_TICKS {
        let frames = qemu_rig::acquire(&mut hw, &controller);
        let (instr, report) = ctr.once(|| controller.tick_acquired(&mut hw, &frames, false));
        task.serve();
        let instr = instr.saturating_sub(base);
        total += u64::from(instr);
        if instr > worst {
            worst = instr;
            worst_at = report.tick;
        }
        let healthy = report.reaction == Reaction::None
            && report.faults.is_empty()
            && report.command_nm.iter().all(|c| c.is_finite())
            && (i < ENABLE_WITHIN_TICKS || report.motors_enabled);
        if !healthy && first_bad.is_none() {
            first_bad = Some(report);
        }
        last = Some(report);
    }
    let avg = total / u64::from(CONTROL_TICKS.max(1));
    out.put(line("bench: control_tick instr=").u64(avg));
    out.put(
        line("bench: control_tick_worst instr=")
            .u32(worst)
            .str(" (tick ")
            .u32(worst_at)
            .str(")"),
    );
    if let Some(r) = last {
        out.put(
            line("control: standing rig, ")
                .u32(r.tick)
                .str(" ticks: phase ")
                .str(phase_name(&r.phase))
                .str(", motors enabled ")
                .str(if r.motors_enabled { "true" } else { "false" })
                .str(", joints ")
                .fixed_list(&r.joints_rad, 4)
                .str(" rad, forces ")
                .fixed_list(&r.forces_n, 1)
                .str(" N, commands ")
                .fixed_list(&r.command_nm, 3)
                .str(" N·m"),
        );
    }
    if let Some(r) = first_bad {
        let mut l = line("FAIL control: unhealthy while standing at tick ");
        l.u32(r.tick)
            .str(": reaction ")
            .str(reaction_name(r.reaction))
            .str(", faults ");
        fault_list(&mut l, &r.faults);
        l.str(", motors enabled ")
            .str(if r.motors_enabled { "true" } else { "false" });
        out.put(&mut l);
        for rec in controller.supervisor().log() {
            out.put(
                line("  fault log: tick ")
                    .u32(rec.tick)
                    .str(" 0x")
                    .hex(u32::from(rec.code.code()), 4)
                    .str(" ")
                    .str(rec.code.name())
                    .str(" channel ")
                    .u32(u32::from(rec.channel))
                    .str(" value ")
                    .exp(rec.value),
            );
        }
        failed += 1;
    } else {
        out.put(&mut line(
            "control: ok (no fault, motors enabled, commands finite)",
        ));
    }
    // The acquisition must have spoken the parts' protocols: two 16-bit frames
    // per encoder read, one conversion per force sensor and one drive's
    // current monitor, every tick.
    let frames = hw.encoders.map(|e| e.destroy().frames);
    let conversions = hw.adc.destroy().conversions;
    if frames.iter().any(|&f| f != 2 * CONTROL_TICKS) || conversions != 5 * CONTROL_TICKS {
        let mut l = line("FAIL control: bus traffic: encoder frames [");
        for (i, f) in frames.iter().enumerate() {
            if i > 0 {
                l.str(", ");
            }
            l.u32(*f);
        }
        l.str("], ADC conversions ")
            .u32(conversions)
            .str(" over ")
            .u32(CONTROL_TICKS)
            .str(" ticks");
        out.put(&mut l);
        failed += 1;
    }
    failed
}

/// None is reachable (`cargo xtask panics`); if one happens anyway, the run
/// fails with where it came from (no message: printing it needs `core::fmt`).
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    let mut l = line("panic");
    if let Some(at) = info.location() {
        l.str(" at ").str(at.file()).str(":").u32(at.line());
    }
    Out::open().put(&mut l);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}

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
//! Instruction counts: run QEMU with `-icount shift=0` so every instruction
//! advances the virtual clock by 1 ns; SysTick on the core clock (25 MHz on
//! this machine) then ticks once per 40 instructions.
#![no_std]
#![no_main]
// cortex-m-rt's `#[entry]`/`#[exception]` expand to `#[export_name]`, which
// the unsafe_code lint counts; this file contains no unsafe block of its own.
#![allow(unsafe_code)]

use core::hint::black_box;

use cortex_m::peripheral::{SYST, syst::SystClkSource};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use firmware::{board_config, qemu_rig, selftest, tick_replay};
use gait_control::faults::Reaction;
use gait_core::BodyModel;
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
    hprintln!("exogait self-test (mps2-an386, Cortex-M4F)");
    let checks = selftest::run();
    let mut failed = 0;
    for c in &checks {
        let verdict = if c.passed() { "ok  " } else { "FAIL" };
        if !c.passed() {
            failed += 1;
        }
        hprintln!(
            "  {} {:<28} {:.3e} (bound {:.1e})",
            verdict,
            c.name,
            c.value,
            c.bound
        );
    }
    hprintln!(
        "selftest: {} passed, {} failed",
        checks.len() - failed,
        failed
    );

    match cortex_m::Peripherals::take() {
        Some(p) => {
            let mut ctr = InstrCounter::new(p.SYST);
            bench(&mut ctr);
            failed += control_tick_bench(&mut ctr);
            failed += replay_bench(&mut ctr);
        }
        None => {
            hprintln!("bench: SysTick unavailable");
            failed += 1;
        }
    }
    failed
}

/// On-target instruction counts (see README, "Performance").
fn bench(ctr: &mut InstrCounter) {
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
        let w = [0.4, -0.9, 0.2, -2.1, 3.3];
        let dd = [1.5, -2.0, 0.7, 6.0, -9.0];
        black_box(inverse_dynamics(&m, &phi, &w, &dd));
    });
    let ik = IkSolver::new(&m);
    let ik_only = ctr.per_call(1000, |i| {
        let a = i as f32 * 1e-4;
        let t = IkTarget {
            x5: -0.2 + a,
            y5: 0.1,
            phi1: 0.1,
            phi3: 0.05,
            r2: 0.7,
        };
        black_box(ik.solve(&t).ok());
    });
    let ik_id = ctr.per_call(1000, |i| {
        let a = i as f32 * 1e-4;
        let t = IkTarget {
            x5: -0.2 + a,
            y5: 0.1,
            phi1: 0.1,
            phi3: 0.05,
            r2: 0.7,
        };
        if let Ok(sol) = ik.solve(&t) {
            let w = [0.4, -0.9, 0.2, -2.1, 3.3];
            let dd = [1.5, -2.0, 0.7, 6.0, -9.0];
            black_box(inverse_dynamics(&m, &sol.phi, &w, &dd));
        }
    });
    let share = ctr.per_call(1000, |i| {
        let a = i as f32 * 1e-4;
        let phi = [0.0 + a, -0.74, 0.0, 2.98, 3.30];
        let single = [-208.0, -208.0, 5.0, 5.0, -2.0];
        black_box(share_load(&m, &phi, &single, 912.0));
    });
    // The stance heel up (stair descent): the toe rocker's extra terms.
    let foot = gait_core::foot::StanceFoot::for_model(&m);
    let toe_id = ctr.per_call(1000, |i| {
        let a = i as f32 * 1e-3;
        let phi = [0.6 + a, -0.3, 0.05, 2.7 - a, 3.5];
        let w = [0.4, -0.9, 0.2, -2.1, 3.3];
        let dd = [1.5, -2.0, 0.7, 6.0, -9.0];
        black_box(gait_core::foot::inverse_dynamics(&m, &foot, &phi, &w, &dd));
    });
    hprintln!("bench: loop_overhead instr={}", base);
    hprintln!(
        "bench: toe_rocker_inverse_dynamics_f32 instr={}",
        toe_id.saturating_sub(base)
    );
    hprintln!("bench: share_load_f32 instr={}", share.saturating_sub(base));
    hprintln!("bench: ik_f32 instr={}", ik_only.saturating_sub(base));
    hprintln!(
        "bench: ik_plus_inverse_dynamics_f32 instr={}",
        ik_id.saturating_sub(base)
    );
    hprintln!("bench: libm_sinf instr={}", sinf.saturating_sub(base));
    hprintln!("bench: sin_cos_f32 instr={}", fast.saturating_sub(base));
    hprintln!(
        "bench: inverse_dynamics_f32 instr={}",
        id.saturating_sub(base)
    );
}

/// Runs the board's controller on the standing rig: instructions per tick
/// (average and worst) and a health check. Returns the number of failures.
fn control_tick_bench(ctr: &mut InstrCounter) -> usize {
    let device = match board_config::device() {
        Ok(d) => d,
        Err(e) => {
            hprintln!("FAIL control: device configuration refused: {:?}", e);
            return 1;
        }
    };
    // xtask compares this with the host's (the simulator's) configuration.
    hprintln!("device: fingerprint=0x{:08x}", device.fingerprint());
    let mut controller = match board_config::build_controller() {
        Ok(c) => c,
        Err(e) => {
            hprintln!("FAIL control: configuration refused: {:?}", e);
            return 1;
        }
    };
    let mut hw = match board_config::hardware(&device, qemu_rig::standing(&device)) {
        Ok(h) => h,
        Err(e) => {
            hprintln!("FAIL control: hardware refused: {:?}", e);
            return 1;
        }
    };
    // Every driver must start disabled (`hardware` disables each one).
    let mut failed = 0;
    if hw.motors.iter().any(|m| m.is_enabled()) {
        hprintln!("FAIL control: a motor is enabled after boot");
        failed += 1;
    }
    hprintln!(
        "control: state {} bytes (controller {}, hardware {})",
        core::mem::size_of_val(&controller) + core::mem::size_of_val(&hw),
        core::mem::size_of_val(&controller),
        core::mem::size_of_val(&hw)
    );
    let base = ctr.once(|| black_box(0u32)).0;
    let mut total: u64 = 0;
    let mut worst = 0u32;
    let mut worst_at = 0u32;
    let mut first_bad = None;
    let mut last = None;
    for i in 0..CONTROL_TICKS {
        let (instr, report) = ctr.once(|| controller.tick(&mut hw, false));
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
    hprintln!("bench: control_tick instr={}", avg);
    hprintln!(
        "bench: control_tick_worst instr={} (tick {})",
        worst,
        worst_at
    );
    if let Some(r) = last {
        hprintln!(
            "control: standing rig, {} ticks: phase {:?}, motors enabled {}, joints {:?} rad, forces {:?} N, commands {:?} N·m",
            r.tick,
            r.phase,
            r.motors_enabled,
            r.joints_rad,
            r.forces_n,
            r.command_nm
        );
    }
    if let Some(r) = first_bad {
        hprintln!(
            "FAIL control: unhealthy while standing at tick {}: reaction {:?}, faults {:?}, motors enabled {}",
            r.tick,
            r.reaction,
            r.faults,
            r.motors_enabled
        );
        for rec in controller.supervisor().log() {
            hprintln!(
                "  fault log: tick {} {:?} channel {} value {}",
                rec.tick,
                rec.code,
                rec.channel,
                rec.value
            );
        }
        failed += 1;
    } else {
        hprintln!("control: ok (no fault, motors enabled, commands finite)");
    }
    // The drivers must have spoken the parts' protocols: two 16-bit frames
    // per encoder read, one conversion per force sensor, every tick.
    let frames = hw.encoders.map(|e| e.destroy().frames);
    let conversions = hw.adc.destroy().conversions;
    if frames.iter().any(|&f| f != 2 * CONTROL_TICKS) || conversions != 4 * CONTROL_TICKS {
        hprintln!(
            "FAIL control: bus traffic: encoder frames {:?}, ADC conversions {} over {} ticks",
            frames,
            conversions,
            CONTROL_TICKS
        );
        failed += 1;
    }
    failed
}

/// Replays the ticks recorded in the simulator (`firmware::tick_replay`)
/// and prints, per phase, `tick: phase=<name> avg=<instructions>
/// worst=<instructions> ticks=<n>`, then how far the target's motor
/// commands are from the host's. xtask checks the budget and the bound.
fn replay_bench(ctr: &mut InstrCounter) -> usize {
    let device = match board_config::device() {
        Ok(d) => d,
        Err(e) => {
            hprintln!("FAIL replay: device configuration refused: {:?}", e);
            return 1;
        }
    };
    let base = ctr.once(|| black_box(0u32)).0;
    let result = tick_replay::replay(&device, |tick| {
        let (instr, report) = ctr.once(tick);
        (instr.saturating_sub(base), report)
    });
    match result {
        Ok(r) if r.segments == 0 => {
            hprintln!("tick: no recording built in (cargo xtask qemu records one)");
            0
        }
        Ok(r) => {
            for (name, p) in tick_replay::PHASES.iter().zip(r.phases) {
                if p.ticks > 0 {
                    hprintln!(
                        "tick: phase={} avg={} worst={} ticks={}",
                        name,
                        p.average(),
                        p.worst,
                        p.ticks
                    );
                }
            }
            hprintln!(
                "tick: replayed runs={} ticks={} max_command_diff_nm={:e} differing_ticks={}",
                r.segments,
                r.ticks,
                r.max_command_diff_nm,
                r.differing_ticks
            );
            0
        }
        Err(e) => {
            hprintln!("FAIL replay: {:?}", e);
            1
        }
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}

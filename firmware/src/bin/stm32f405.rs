//! Motor board image (STM32F405RG, 168 MHz): board wiring only. The
//! controller (sense → plan → act → guard → write) is gait-control's; its
//! configuration is `firmware::board_config`, shared with the QEMU image.
//!
//! Boot order puts safety first: the four motor-driver enable lines are
//! driven low before anything else, the power-on self-test must pass before
//! the control loop may start, every driver is built and every motor
//! disabled through the drivers, and only then do the independent watchdog
//! and the 1 kHz tick start. The tick runs in TIM2's interrupt and thread
//! mode re-plans steps in its idle time (`schedule`). A panic resets the
//! board into a hold of the posture it finds (fault 0x0603, see `panic`).
//!
//! # Pin map (motor board rev A, LQFP64)
//!
//! | signal | pin | notes |
//! |---|---|---|
//! | encoder SPI1 SCK / MISO / MOSI | PA5 / PA6 / PA7 | AF5, mode 1, 5.25 MHz |
//! | encoder CS: left hip, left knee | PA4, PC4 | active low |
//! | encoder CS: right hip, right knee | PC5, PB0 | active low |
//! | encoder CS: left ankle, right ankle | PB1, PC6 | active low |
//! | force ADC SPI2 SCK / MISO / MOSI | PB10 / PC2 / PC3 | AF5, mode 0, 656 kHz |
//! | force ADC CS (MCP3208) | PC7 | active low |
//! | PWM TIM1 CH1–CH4: left hip, left knee, right hip, right knee | PA8, PA9, PA10, PA11 | AF1, 20 kHz |
//! | motor direction, same order | PC8, PC9, PC10, PC11 | high = positive torque |
//! | motor enable, same order | PB12, PB13, PB14, PB15 | active high |
//! | MODE / GO buttons | PC0 / PC1 | pull-up, pressed = low |
//! | e-stop | PA0 | pull-up, NC contact to GND: high = stop (or cut cable) |
//! | gait LED / fault LED / buzzer | PC13 / PB8 / PB9 | active high |
//! | SWD | PA13 / PA14 | probe-rs, defmt over RTT |
//! | HSE 8 MHz crystal | PH0 / PH1 | |
//!
//! MCP3208 inputs: CH0 left foot, CH1 right foot, CH2 left crutch, CH3
//! right crutch (`board_config::FORCE_CHANNELS`).
#![no_std]
#![no_main]
// Unsafe, each block with its reason: the panic mark and `disable_motors`
// (the motor-enable lines reached whatever owns GPIOB), the register words
// the PAC takes as raw bits (`clocks`), the PAC's TIM1/SPI register blocks
// after the peripheral was handed over (`pwm`, `spi`), the DMA, SPI and
// GPIO BSRR registers the sensors' acquisition drives (`acquire`), and the RTT control
// block the probe shares (`rtt_log`); cortex-m-rt's attributes also expand
// to `#[export_name]`, which this lint counts.
#![allow(unsafe_code)]

#[path = "stm32f405/acquire.rs"]
mod acquire;
#[path = "stm32f405/calibrate.rs"]
mod calibrate;
#[path = "stm32f405/clocks.rs"]
mod clocks;
#[path = "stm32f405/pwm.rs"]
mod pwm;
#[path = "stm32f405/rtt_log.rs"]
mod rtt_log;
#[path = "stm32f405/schedule.rs"]
mod schedule;
#[path = "stm32f405/spi.rs"]
mod spi;
#[path = "stm32f405/tick.rs"]
mod tick;

use core::convert::Infallible;
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;

use cortex_m::peripheral::DWT;
use cortex_m::peripheral::scb::SystemHandler;
use cortex_m_rt::entry;
use embedded_hal::delay::DelayNs;
use embedded_hal::digital::{ErrorType, OutputPin};
use embedded_hal::spi::{Mode, Phase, Polarity};
use embedded_hal_bus::spi::{AtomicDevice, ExclusiveDevice};
use embedded_hal_bus::util::AtomicCell;
use exogait_device::boot::{self, Gaits, TableSlots};
use exogait_device::replan::REPLAN;
use firmware::board_config::{self, BoardIo, TICK_HZ};
use firmware::clock_tree::{ADC_SPI_BR, ENCODER_SPI_BR};
use firmware::idle_replan::IdleReplanner;
use firmware::{flash_sectors, model_task, selftest};
use gait_control::feedforward::ModelTask;
use stm32f4xx_hal::gpio::{ErasedPin, Input, Output};
use stm32f4xx_hal::{pac, prelude::*, watchdog::IndependentWatchdog};

/// Motor-enable pins on GPIOB (see the pin map above).
const MOTOR_ENABLE_PINS_B: [u8; 4] = [12, 13, 14, 15];
/// Core clock, Hz (`firmware::clock_tree`).
const SYSCLK_HZ: u32 = firmware::clock_tree::SYSCLK_HZ;
/// Core cycles in one control period.
const CYCLES_PER_TICK: u32 = SYSCLK_HZ / TICK_HZ;
/// Watchdog window: a stalled loop resets the board (motors disabled by reset).
const WATCHDOG_MS: u32 = 20;
/// AS5048A: CSn low to first clock edge, and CSn high time between frames,
/// at least 350 ns each (datasheet, SPI timing tL and tCSn): 64 cycles at
/// 168 MHz is 381 ns.
pub(crate) const ENCODER_CS_CYCLES: u32 = 64;
/// MCP3208: CS high at least 500 ns between conversions (tCSH): 96 cycles
/// is 571 ns.
pub(crate) const ADC_CS_CYCLES: u32 = 96;

/// A chip-select line that holds its new level for the part's set-up /
/// hold time after every change (busy-wait of `CYCLES` core cycles), so two
/// frames in a row always keep CS high long enough in between.
struct ChipSelect<const CYCLES: u32>(ErasedPin<Output>);

impl<const CYCLES: u32> ErrorType for ChipSelect<CYCLES> {
    type Error = Infallible;
}

impl<const CYCLES: u32> OutputPin for ChipSelect<CYCLES> {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.0.set_low();
        cortex_m::asm::delay(CYCLES);
        Ok(())
    }

    fn set_high(&mut self) -> Result<(), Infallible> {
        self.0.set_high();
        cortex_m::asm::delay(CYCLES);
        Ok(())
    }
}

/// A busy-wait delay in core cycles for the SPI devices' `DelayNs`
/// operations. The drivers use none; embedded-hal-bus's `NoDelay` would
/// panic on one, and that branch stayed in the image where the optimiser
/// could not prove it dead.
struct CycleDelay;

impl DelayNs for CycleDelay {
    fn delay_ns(&mut self, ns: u32) {
        // 168 cycles per µs = 21 / 125 per ns, rounded up.
        let cycles = u64::from(ns) * u64::from(SYSCLK_HZ / 8_000_000) / 125 + 1;
        cortex_m::asm::delay(u32::try_from(cycles).unwrap_or(u32::MAX));
    }
}

#[entry]
fn main() -> ! {
    let Some(dp) = pac::Peripherals::take() else {
        halt("peripherals already taken");
    };
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        halt("core peripherals already taken");
    };
    let restarted_after_panic = take_panic_mark();
    // 1. Motors off before anything else.
    let gpiob = dp.GPIOB.split();
    let mut en = [
        gpiob.pb12.into_push_pull_output().erase(),
        gpiob.pb13.into_push_pull_output().erase(),
        gpiob.pb14.into_push_pull_output().erase(),
        gpiob.pb15.into_push_pull_output().erase(),
    ];
    en.iter_mut().for_each(|p| p.set_low());
    let gpioa = dp.GPIOA.split();
    let gpioc = dp.GPIOC.split();

    // 2. Clocks: 8 MHz crystal → 168 MHz (APB1 42 MHz, APB2 84 MHz),
    //    register values computed when compiling (`firmware::clock_tree`).
    let clocks = match clocks::setup(&dp.RCC, &dp.FLASH, &dp.PWR) {
        Ok(c) => c,
        Err(e) => {
            defmt::error!("clock set-up failed: {}", e);
            halt("no clock: motors stay disabled");
        }
    };
    defmt::info!("exogait motor board up, sysclk {} Hz", clocks.sysclk_hz());

    // 3. Self-test: the model code in this image must agree with itself.
    let checks = selftest::run();
    let mut failed = 0u32;
    for c in &checks {
        if c.passed() {
            defmt::info!("selftest ok   {=str} {=f64}", c.name, c.value);
        } else {
            failed += 1;
            defmt::error!(
                "selftest FAIL {=str} {=f64} > {=f64}",
                c.name,
                c.value,
                c.bound
            );
        }
    }
    if failed > 0 {
        halt("self-test failed: motors stay disabled");
    }

    // 4. Peripherals → drivers (board_config's calibrations and limits);
    //    `hardware` disables every motor through its driver.
    let mode_1 = Mode {
        polarity: Polarity::IdleLow,
        phase: Phase::CaptureOnSecondTransition,
    };
    let mode_0 = Mode {
        polarity: Polarity::IdleLow,
        phase: Phase::CaptureOnFirstTransition,
    };
    let _encoder_bus_pins = (
        gpioa.pa5.into_alternate::<5>(),
        gpioa.pa6.into_alternate::<5>(),
        gpioa.pa7.into_alternate::<5>(),
    );
    // 'static, as everything the tick's interrupt holds.
    let encoder_bus: Option<&'static mut AtomicCell<spi::Bus>> = cortex_m::singleton!(
        : AtomicCell<spi::Bus> =
            AtomicCell::new(spi::Bus::spi1(dp.SPI1, &dp.RCC, mode_1, ENCODER_SPI_BR))
    );
    let Some(encoder_bus) = encoder_bus else {
        halt("encoder bus already taken");
    };
    let encoder_bus: &'static AtomicCell<spi::Bus> = encoder_bus;
    let _adc_bus_pins = (
        gpiob.pb10.into_alternate::<5>(),
        gpioc.pc2.into_alternate::<5>(),
        gpioc.pc3.into_alternate::<5>(),
    );
    let adc_bus = spi::Bus::spi2(dp.SPI2, &dp.RCC, mode_0, ADC_SPI_BR);
    let cs = |pin: ErasedPin<Output>| ChipSelect::<ENCODER_CS_CYCLES>(pin);
    let encoder = |pin| match AtomicDevice::new(encoder_bus, cs(pin), CycleDelay) {
        Ok(d) => d,
        Err(e) => match e {},
    };
    let encoder_cs = [
        gpioa.pa4.into_push_pull_output().erase(),
        gpioc.pc4.into_push_pull_output().erase(),
        gpioc.pc5.into_push_pull_output().erase(),
        gpiob.pb0.into_push_pull_output().erase(),
        gpiob.pb1.into_push_pull_output().erase(),
        gpioc.pc6.into_push_pull_output().erase(),
    ];
    // The same lines for the DMA acquisition, once the drivers are done
    // with the buses (`acquire`).
    let encoder_lines = encoder_cs.each_ref().map(acquire::Line::of);
    let encoders = encoder_cs.map(encoder);
    let adc_cs_pin = gpioc.pc7.into_push_pull_output().erase();
    let adc_line = acquire::Line::of(&adc_cs_pin);
    let adc_cs = ChipSelect::<ADC_CS_CYCLES>(adc_cs_pin);
    let adc = match ExclusiveDevice::new(adc_bus, adc_cs, CycleDelay) {
        Ok(d) => d,
        Err(e) => match e {},
    };
    // TIM1 CH1–CH4 at 20 kHz, every duty 0 (`pwm::setup`).
    let _pwm_pins = (
        gpioa.pa8.into_alternate::<1>(),
        gpioa.pa9.into_alternate::<1>(),
        gpioa.pa10.into_alternate::<1>(),
        gpioa.pa11.into_alternate::<1>(),
    );
    let pwm = pwm::setup(dp.TIM1, &dp.RCC);
    let dir = [
        gpioc.pc8.into_push_pull_output().erase(),
        gpioc.pc9.into_push_pull_output().erase(),
        gpioc.pc10.into_push_pull_output().erase(),
        gpioc.pc11.into_push_pull_output().erase(),
    ];
    let mode = gpioc.pc0.into_pull_up_input().erase();
    let go = gpioc.pc1.into_pull_up_input().erase();
    // MODE and GO held at power-up (active low): the calibration procedure.
    let calibrating = mode.is_low() && go.is_low();
    let io = BoardIo {
        encoders,
        adc,
        pwm,
        dir,
        enable: en,
        mode,
        go,
        e_stop: gpioa.pa0.into_pull_up_input().erase(),
        gait_led: gpioc.pc13.into_push_pull_output().erase(),
        fault_led: gpiob.pb8.into_push_pull_output().erase(),
        buzzer: gpiob.pb9.into_push_pull_output().erase(),
    };
    // 5. The device's calibration from its own sector (or, MODE and GO
    //    held at power-up, recorded now), and the gaits: the patient's
    //    bundle from its own sector, verified (`exogait_device::boot`); the
    //    built-in tables when it is erased.
    let device = match board_config::device() {
        Ok(d) => d,
        Err(e) => {
            defmt::error!("device configuration refused: {}", e);
            halt("bad device configuration: motors stay disabled");
        }
    };
    if calibrating {
        let mut flash = dp.FLASH;
        let recorded = board_config::hardware(&device, io)
            .map_err(|_| calibrate::Failure::ReadBack)
            .and_then(|mut hw| calibrate::record(&device, &mut hw, &mut flash));
        match recorded {
            Ok(r) => {
                defmt::info!(
                    "calibration recorded: encoder zeros {}, load cells unloaded {}",
                    r.encoder_zero_counts,
                    r.force_zero_counts
                );
                halt("calibration recorded: restart the board");
            }
            Err(calibrate::Failure::Refused(e)) => {
                defmt::error!("calibration refused ({=str}): nothing written", e.reason());
                halt("calibration refused: check the jig and the posture, then try again");
            }
            Err(_) => halt("calibration could not be written to flash"),
        }
    }
    let calibration = boot::calibration_in(&device, flash_sectors::calibration());
    if let Err(e) = &calibration {
        defmt::error!(
            "calibration refused ({=str}): motors stay off (fault 0x0605); record it on the jig",
            e.reason()
        );
    }
    let gaits = boot::gaits_in(&device, flash_sectors::bundle());
    match &gaits {
        Gaits::BuiltIn => defmt::info!("no patient bundle: the device's built-in gaits"),
        Gaits::Patient(b) => defmt::info!(
            "patient bundle verified: {=usize} gaits, crc {=u32:#010x}, patient {=u32:#010x}",
            b.len(),
            b.crc(),
            b.patient_hash()
        ),
        Gaits::Refused(e) => defmt::error!(
            "patient bundle refused ({=str}): holding, GO does nothing (fault 0x0604)",
            e.reason()
        ),
    }
    let slots: Option<&'static mut TableSlots<'static>> =
        cortex_m::singleton!(: TableSlots<'static> = [None; gait_core::bundle::MAX_GAITS]);
    let Some(slots) = slots else {
        halt("table slots already taken");
    };
    let (cfg, mut controller) = match boot::build(
        &device,
        &gaits,
        &calibration,
        board_config::flash_tables(),
        slots,
    ) {
        Ok(x) => x,
        Err(e) => {
            defmt::error!("controller configuration refused: {}", e);
            halt("bad controller configuration: motors stay disabled");
        }
    };
    let hw = match board_config::hardware(&cfg, io) {
        Ok(hw) => hw,
        Err(e) => {
            defmt::error!("board configuration refused: {}", e);
            halt("bad board configuration: motors stay disabled");
        }
    };

    if restarted_after_panic {
        defmt::error!("restarted after a panic: holding the posture found (fault 0x0603)");
        controller.report_restart_after_panic();
    }

    // 6. The re-planner, when the board re-plans, over the controller's
    //    own tables (a request names one by its slot).
    let tables = *controller.sequencer().tables();
    let replanner = board_config::REPLANNING.then(|| {
        controller.set_replanner(&schedule::SLOT, REPLAN);
        IdleReplanner::new(&schedule::SLOT, cfg, tables)
    });

    // 7. The model's feed-forward in PendSV, below the tick
    //    (`firmware::model_task`).
    let checks = controller.set_model_task(&model_task::SLOT);
    // SAFETY: PendSV has not run yet; lowering its priority breaks no
    // critical section (nothing relies on PendSV being masked).
    unsafe {
        cp.SCB
            .set_priority(SystemHandler::PendSV, model_task::PRIORITY);
    }
    let model = ModelTask::new(controller.config().model, &model_task::SLOT)
        .with_checks(checks)
        .with_steps(controller.steps());
    if !model_task::install(model) {
        halt("the model task's state is in use: motors stay disabled");
    }

    // 8. The sensors by DMA before each tick; the blocking buses serve
    //    only a tick that finds no acquisition of its own (`acquire`).
    acquire::install(
        &dp.RCC,
        encoder_lines,
        adc_line,
        cfg.force_channels,
        cfg.drive_current_channels,
    );

    // 9. The 1 kHz tick in TIM2's interrupt under an independent watchdog;
    //    the re-planner in thread mode.
    cp.DCB.enable_trace();
    cp.DWT.enable_cycle_counter();
    let mut dog = IndependentWatchdog::new(dp.IWDG);
    dog.start(WATCHDOG_MS.millis());
    let tick = tick::Tick::start(dp.TIM2, &dp.RCC);
    schedule::run(schedule::Board::new(controller, hw, tick, dog), replanner)
}

/// The controller's drivers over this board's peripherals.
type BoardHardware = gait_control::controller::Hardware<
    AtomicDevice<'static, spi::Bus, ChipSelect<ENCODER_CS_CYCLES>, CycleDelay>,
    ExclusiveDevice<spi::Bus, ChipSelect<ADC_CS_CYCLES>, CycleDelay>,
    pwm::Channel,
    ErasedPin<Output>,
    ErasedPin<Output>,
    ErasedPin<Input>,
    ErasedPin<Output>,
>;

/// Stops for good with the motors disabled; the watchdog is not fed, so if it
/// was started the board resets into the same safe boot.
fn halt(why: &'static str) -> ! {
    defmt::error!("halt: {=str}", why);
    disable_motors();
    loop {
        cortex_m::asm::wfi();
    }
}

/// Drives every motor-enable line low through the GPIOB set/reset register.
fn disable_motors() {
    // SAFETY: BSRR writes are atomic, touch only the bits written, and only
    // reset the four enable pins; this may run while the HAL believes it owns
    // GPIOB (in a panic), which is exactly when the motors must stop.
    let gpiob = unsafe { &*pac::GPIOB::ptr() };
    let mask = MOTOR_ENABLE_PINS_B
        .iter()
        .fold(0u32, |m, &p| m | (1u32 << (16 + u32::from(p))));
    gpiob.bsrr().write(|w| unsafe { w.bits(mask) });
}

/// Marks a restart after a panic (the fault code 0x0603 in the top half).
const PANIC_MARK_MAGIC: u32 = 0x0603_5AFE;

/// Left by the panic handler for the next boot. `.uninit` RAM is neither
/// zeroed nor initialised by cortex-m-rt, and a system reset keeps SRAM.
#[unsafe(link_section = ".uninit.exogait_panic_mark")]
static mut PANIC_MARK: MaybeUninit<u32> = MaybeUninit::uninit();

/// Whether the last reset came from the panic handler; clears the mark.
fn take_panic_mark() -> bool {
    // SAFETY: runs once at boot, before any interrupt is enabled, so
    // nothing else touches the word; the volatile accesses keep the compiler
    // from assuming anything about RAM that survived a reset (at power-on
    // it holds noise, which matches the 32-bit magic with odds 2^-32).
    unsafe {
        let mark = addr_of_mut!(PANIC_MARK).cast::<u32>();
        let found = mark.read_volatile() == PANIC_MARK_MAGIC;
        mark.write_volatile(0);
        found
    }
}

/// A panic — none is reachable from the control tick or our crates, `cargo
/// xtask panics` proves it on every CI run — leaves a mark in RAM and resets
/// the board at once. The reset drives the enable lines low for the boot
/// (the drives' dynamic brakes close; a few ms to the first tick); the
/// controller then starts with fault 0x0603 latched, whose reaction is the
/// one the fault table keeps for an internal error: SAFE HOLD of the
/// posture it finds, motors powered. Never a limp exoskeleton waiting for
/// a clinician. Nothing is logged here: the
/// log itself may be what panicked; the next boot logs the restart.
#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    // SAFETY: a single aligned word write; whatever else was running is
    // abandoned by the reset that follows.
    unsafe {
        addr_of_mut!(PANIC_MARK)
            .cast::<u32>()
            .write_volatile(PANIC_MARK_MAGIC)
    };
    cortex_m::peripheral::SCB::sys_reset()
}

// Timestamps are core cycles (wrap every 25.6 s at 168 MHz).
defmt::timestamp!("{=u32}", DWT::cycle_count());

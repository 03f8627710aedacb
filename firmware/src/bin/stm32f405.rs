//! Motor board image (STM32F405, 168 MHz): board wiring only.
//!
//! Boot order puts safety first: the four motor-driver enable lines are
//! driven low before anything else, the power-on self-test must pass before
//! the control loop may start, and the independent watchdog resets the board
//! if a 1 kHz tick is ever missed by more than its window. Control logic
//! itself lives in gait-control and is wired in here as it lands.
//!
//! Pin map (motor board rev A): motor enables PB12 left hip, PB13 left knee,
//! PB14 right hip, PB15 right knee (active high); status LED PC13.
#![no_std]
#![no_main]
// Unsafe is confined to the panic handler, which must reach the motor-enable
// lines after the HAL's ownership of them is gone (see `panic`); cortex-m-rt's
// attributes also expand to `#[export_name]`, which this lint counts.
#![allow(unsafe_code)]

use cortex_m_rt::entry;
use defmt_rtt as _;
use firmware::selftest;
use stm32f4xx_hal::{pac, prelude::*, watchdog::IndependentWatchdog};

/// Motor-enable pins on GPIOB (see the pin map above).
const MOTOR_ENABLE_PINS_B: [u8; 4] = [12, 13, 14, 15];
/// Control-loop rate.
const TICK_HZ: u32 = 1_000;
/// Watchdog window: a stalled loop resets the board (motors disabled by reset).
const WATCHDOG_MS: u32 = 20;

#[entry]
fn main() -> ! {
    let Some(dp) = pac::Peripherals::take() else {
        halt("peripherals already taken");
    };
    // 1. Motors off before anything else.
    let gpiob = dp.GPIOB.split();
    let mut en = (
        gpiob.pb12.into_push_pull_output(),
        gpiob.pb13.into_push_pull_output(),
        gpiob.pb14.into_push_pull_output(),
        gpiob.pb15.into_push_pull_output(),
    );
    en.0.set_low();
    en.1.set_low();
    en.2.set_low();
    en.3.set_low();
    let gpioc = dp.GPIOC.split();
    let mut led = gpioc.pc13.into_push_pull_output();

    // 2. Clocks: 8 MHz crystal → 168 MHz.
    let rcc = dp.RCC.constrain();
    let clocks = rcc.cfgr.use_hse(8.MHz()).sysclk(168.MHz()).freeze();
    defmt::info!(
        "exogait motor board up, sysclk {} Hz",
        clocks.sysclk().raw()
    );

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

    // 4. The 1 kHz loop under an independent watchdog.
    let mut tick = dp.TIM2.counter_hz(&clocks);
    if tick.start(TICK_HZ.Hz()).is_err() {
        halt("cannot start the tick timer");
    }
    let mut dog = IndependentWatchdog::new(dp.IWDG);
    dog.start(WATCHDOG_MS.millis());
    let mut ticks: u32 = 0;
    loop {
        // Busy-wait for the timer: nothing else runs on this core.
        while tick.wait().is_err() {}
        dog.feed();
        ticks = ticks.wrapping_add(1);
        if ticks.is_multiple_of(TICK_HZ) {
            led.toggle();
            defmt::debug!("alive, {} s", ticks / TICK_HZ);
        }
    }
}

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

/// A panic leaves the motors disabled (a limp exoskeleton with a reset pending
/// is safer than a running one whose software state is unknown).
#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    disable_motors();
    defmt::error!("panic: motors disabled");
    cortex_m::asm::udf()
}

defmt::timestamp!("{=u32}", 0);

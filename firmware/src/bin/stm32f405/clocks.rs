//! The clock tree through the PAC: 8 MHz HSE → PLL → 168 MHz, APB1 42 MHz,
//! APB2 84 MHz, with the register values `firmware::clock_tree` computes
//! when compiling (the ones stm32f4xx-hal's `CFGR::freeze` computed at run
//! time, with its PLL search and its asserts). Every wait is bounded and
//! ends in a typed error instead of spinning forever.

use firmware::clock_tree::{ClockTree, MOTOR_BOARD};
use stm32f4xx_hal::pac::{FLASH, PWR, RCC};

/// Why the clocks could not be set up (the board then halts with its
/// motors disabled; the watchdog is not running yet).
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum ClockError {
    /// The crystal did not start (HSERDY, RM0090 §7.3.1).
    HseNotReady,
    /// The PLL did not lock (PLLRDY).
    PllNotLocked,
    /// The switch of SYSCLK to the PLL did not take (SWS, RM0090 §7.3.3).
    SwitchNotTaken,
}

/// Polls of a ready flag before giving up. Each poll is a volatile load, a
/// test and a branch: at least 4 cycles of the 16 MHz HSI the chip boots
/// on, so 400,000 polls wait at least 100 ms, 50 times the HSE's typical
/// start-up (2 ms, STM32F405 datasheet, "HSE 4-26 MHz oscillator
/// characteristics") and far more than the PLL's lock time (100 µs max).
const READY_POLLS: u32 = 400_000;

/// Polls `ready` up to [`READY_POLLS`] times.
fn wait_for(ready: impl Fn() -> bool) -> bool {
    (0..READY_POLLS).any(|_| ready())
}

/// Sets the clocks to [`MOTOR_BOARD`] (RM0090 §7.2, "Clocks"): voltage
/// scale 1 (§5.4.1, PWR_CR VOS, its reset value on the F405, written while
/// the PLL is off), 5 flash wait states with prefetch and caches (§3.5.1 and
/// §3.9.1, FLASH_ACR) before the clock rises, the HSE on (§7.3.1, RCC_CR),
/// the PLL's M/N/P/Q from HSE (§7.3.2, RCC_PLLCFGR) and locked, the AHB /
/// APB prescalers (§7.3.3, RCC_CFGR PPRE2/PPRE1/HPRE), then SYSCLK switched
/// to the PLL (SW) and the switch checked (SWS).
pub fn setup(rcc: &RCC, flash: &FLASH, pwr: &PWR) -> Result<ClockTree, ClockError> {
    const TREE: ClockTree = MOTOR_BOARD;
    // Voltage scale 1 (the reset value, written so the 168 MHz never rests
    // on a default); the PWR clock only for that write.
    rcc.apb1enr().modify(|_, w| w.pwren().set_bit());
    let _ = rcc.apb1enr().read();
    pwr.cr().modify(|_, w| w.vos().scale1());
    rcc.apb1enr().modify(|_, w| w.pwren().clear_bit());

    flash.acr().modify(|_, w| {
        w.latency().set(TREE.flash_latency as u8);
        w.prften().set_bit();
        w.icen().set_bit();
        w.dcen().set_bit()
    });

    rcc.cr().modify(|_, w| w.hseon().set_bit());
    if !wait_for(|| rcc.cr().read().hserdy().bit_is_set()) {
        return Err(ClockError::HseNotReady);
    }

    // SAFETY: every field of the word is in its range (`clock_tree`'s
    // constant assertions), reserved bit 29 at its reset value.
    rcc.pllcfgr().write(|w| unsafe { w.bits(TREE.pllcfgr()) });
    rcc.cr().modify(|_, w| w.pllon().set_bit());
    if !wait_for(|| rcc.cr().read().pllrdy().bit_is_set()) {
        return Err(ClockError::PllNotLocked);
    }

    // SAFETY: only the three prescaler fields change, to codes RM0090
    // defines (`ClockTree::cfgr_prescalers`).
    rcc.cfgr().modify(|r, w| unsafe {
        w.bits(r.bits() & !ClockTree::CFGR_PRESCALER_MASK | TREE.cfgr_prescalers())
    });
    // "The clocks are divided with the new prescaler factor from 1 to 16
    // AHB cycles after write" (RM0090 §7.3.3).
    cortex_m::asm::delay(16);
    rcc.cfgr().modify(|_, w| w.sw().pll());
    if !wait_for(|| rcc.cfgr().read().sws().is_pll()) {
        return Err(ClockError::SwitchNotTaken);
    }
    Ok(TREE)
}

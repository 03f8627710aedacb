//! The 1 kHz control tick on TIM2 through the PAC, as stm32f4xx-hal's
//! `CounterHz::start(1 kHz)` set it (without its run-time prescaler search):
//! PSC and ARR from `firmware::clock_tree::TICK_TIMER`, computed when
//! compiling. Its update interrupt (TIM2, IRQ 28) runs the tick; its
//! compare channel 1, [`crate::acquire::LEAD_US`] before each update,
//! starts the sensors' acquisition (same interrupt).

use crate::acquire::LEAD_US;
use firmware::board_config::TICK_HZ;

/// One control period, µs.
pub const US_PER_TICK: u32 = 1_000_000 / TICK_HZ;
const _: () = assert!(LEAD_US < US_PER_TICK && 1_000_000 % TICK_HZ == 0);

use firmware::clock_tree::TICK_TIMER;
use stm32f4xx_hal::pac::{RCC, TIM2};

/// TIM2 counting control periods.
pub struct Tick {
    tim: TIM2,
}

impl Tick {
    /// Clock on and the timer reset (RM0090 §7.3.13 / §7.3.5); PSC and ARR
    /// (§18.4.11–12, "General-purpose timers (TIM2 to TIM5)"), loaded by an
    /// update event with URS set so that it raises no update flag (§18.4.1,
    /// §18.4.6); the update interrupt enabled (DIER UIE, §18.4.4); the
    /// counter started (CEN).
    pub fn start(tim: TIM2, rcc: &RCC) -> Self {
        rcc.apb1enr().modify(|_, w| w.tim2en().set_bit());
        let _ = rcc.apb1enr().read();
        rcc.apb1rstr().modify(|_, w| w.tim2rst().set_bit());
        rcc.apb1rstr().modify(|_, w| w.tim2rst().clear_bit());
        tim.psc().write(|w| w.psc().set(TICK_TIMER.psc));
        tim.arr().write(|w| w.arr().set(u32::from(TICK_TIMER.arr)));
        tim.cr1().modify(|_, w| w.urs().set_bit());
        tim.egr().write(|w| w.ug().set_bit());
        tim.cr1().modify(|_, w| w.urs().clear_bit());
        // CC1 in frozen output-compare mode (CCMR1 reset value): only its
        // flag, LEAD_US before the update (§18.4.14, §18.3.8).
        let period = u32::from(TICK_TIMER.arr) + 1;
        let lead = period / US_PER_TICK * LEAD_US;
        tim.ccr1().write(|w| w.ccr().set(period - lead));
        tim.sr().write(|w| w.uif().clear_bit().cc1if().clear_bit());
        tim.dier()
            .modify(|_, w| w.uie().set_bit().cc1ie().set_bit());
        tim.cr1().modify(|_, w| w.cen().set_bit());
        Self { tim }
    }

    /// Whether the compare came since the last call (SR CC1IF), clearing
    /// it.
    pub fn compare_elapsed(&mut self) -> bool {
        if self.tim.sr().read().cc1if().bit_is_set() {
            // rc_w0: the write clears only it.
            self.tim.sr().write(|w| w.cc1if().clear_bit());
            true
        } else {
            false
        }
    }

    /// Whether the compare came and was not yet served (SR CC1IF).
    pub fn compare_pending(&self) -> bool {
        self.tim.sr().read().cc1if().bit_is_set()
    }

    /// Whether a period ended since the last [`Tick::elapsed`] (SR UIF),
    /// leaving the flag as it is.
    pub fn pending(&self) -> bool {
        self.tim.sr().read().uif().bit_is_set()
    }

    /// Whether a period ended since the last call (the update flag, SR
    /// UIF, §18.4.5), clearing it.
    pub fn elapsed(&mut self) -> bool {
        if self.tim.sr().read().uif().bit_is_set() {
            // UIF is rc_w0: the write clears only it.
            self.tim.sr().write(|w| w.uif().clear_bit());
            true
        } else {
            false
        }
    }
}

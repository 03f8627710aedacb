//! TIM1's four H-bridge PWM channels through the PAC, as stm32f4xx-hal's
//! `Timer::pwm_hz(20 kHz)` set them up (without its run-time prescaler
//! search and `unwrap`): edge-aligned up-counting, PWM mode 1 with preload,
//! active high, no dead time (one output per bridge, no complementary
//! outputs), main outputs on. The values come from
//! `firmware::clock_tree::MOTOR_PWM`, computed when compiling.

use core::convert::Infallible;

use embedded_hal::pwm::{ErrorType, SetDutyCycle};
use firmware::clock_tree::MOTOR_PWM;
use stm32f4xx_hal::pac::{RCC, TIM1};

/// One TIM1 output channel, 0…3 for CH1…CH4 (a duty written to any other
/// number goes nowhere).
pub struct Channel(u8);

impl ErrorType for Channel {
    type Error = Infallible;
}

impl SetDutyCycle for Channel {
    fn max_duty_cycle(&self) -> u16 {
        MOTOR_PWM.max_duty()
    }

    /// Writes TIMx_CCRy (RM0090 §17.4.14–17), taken at the next update
    /// event (preload on).
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        // SAFETY: TIM1 is owned by `setup`'s caller (consumed there); each
        // channel writes only its own compare register, a single store.
        let tim = unsafe { &*TIM1::ptr() };
        let ccr = match self.0 {
            0 => tim.ccr1(),
            1 => tim.ccr2(),
            2 => tim.ccr3(),
            3 => tim.ccr4(),
            _ => return Ok(()),
        };
        ccr.write(|w| w.ccr().set(duty));
        Ok(())
    }
}

/// Starts TIM1 (RM0090 §17, "Advanced-control timers (TIM1&TIM8)"):
/// clock on and the timer reset (§7.3.14 / §7.3.6, RCC_APB2ENR / RSTR);
/// auto-reload preload (§17.4.1, CR1 ARPE); PSC and ARR for 20 kHz on the
/// 168 MHz timer clock (§17.4.11–12); an update event to load them with
/// URS set, so no update interrupt or DMA request comes of it (§17.4.6,
/// EGR UG); per channel PWM mode 1 with CCR preload (§17.4.7–8, CCMRx
/// OCxM = 110, OCxPE; §17.3.10, "PWM mode"), duty 0 and the output enabled,
/// active high (§17.4.9, CCER CCxE, CCxP = 0); no dead time and the main
/// outputs on (§17.4.18, BDTR DTG = 0, MOE, and AOE as the HAL set it, which
/// would set MOE again at an update event); then the counter (CEN).
pub fn setup(tim: TIM1, rcc: &RCC) -> [Channel; 4] {
    rcc.apb2enr().modify(|_, w| w.tim1en().set_bit());
    let _ = rcc.apb2enr().read();
    rcc.apb2rstr().modify(|_, w| w.tim1rst().set_bit());
    rcc.apb2rstr().modify(|_, w| w.tim1rst().clear_bit());

    tim.cr1().modify(|_, w| w.arpe().set_bit());
    tim.psc().write(|w| w.psc().set(MOTOR_PWM.psc));
    tim.arr().write(|w| w.arr().set(MOTOR_PWM.arr));
    tim.cr1().modify(|_, w| w.urs().set_bit());
    tim.egr().write(|w| w.ug().set_bit());
    tim.cr1().modify(|_, w| w.urs().clear_bit());

    tim.ccmr1_output().modify(|_, w| {
        w.oc1pe().set_bit();
        w.oc1m().pwm_mode1();
        w.oc2pe().set_bit();
        w.oc2m().pwm_mode1()
    });
    tim.ccmr2_output().modify(|_, w| {
        w.oc3pe().set_bit();
        w.oc3m().pwm_mode1();
        w.oc4pe().set_bit();
        w.oc4m().pwm_mode1()
    });
    let mut channels = [Channel(0), Channel(1), Channel(2), Channel(3)];
    for ch in &mut channels {
        let Ok(()) = ch.set_duty_cycle(0);
    }
    tim.ccer().modify(|_, w| {
        w.cc1e().set_bit();
        w.cc1p().clear_bit();
        w.cc2e().set_bit();
        w.cc2p().clear_bit();
        w.cc3e().set_bit();
        w.cc3p().clear_bit();
        w.cc4e().set_bit();
        w.cc4p().clear_bit()
    });
    tim.bdtr().modify(|_, w| {
        w.dtg().set(0);
        w.aoe().set_bit();
        w.moe().set_bit()
    });
    tim.cr1().modify(|_, w| w.cen().set_bit());
    channels
}

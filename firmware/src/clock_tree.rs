//! The STM32F405 motor board's clock tree, timers and SPI baud rates,
//! computed when compiling: the register values the board writes through
//! the PAC (`stm32f405` image, its `clocks`, `pwm`, `tick` and `spi`
//! modules), so that no PLL search, divider choice or `assert!` is left in
//! the image to panic.
//!
//! The values are the ones stm32f4xx-hal 0.22 computed at run time for
//! `use_hse(8 MHz).sysclk(168 MHz).pclk1(42 MHz).pclk2(84 MHz)` and
//! `TIM1.pwm_hz(20 kHz)`, TIM2's 1 kHz tick and the two SPI buses:
//! [`ClockTree::like_hal`], [`TimerTiming::like_hal`] and [`spi_br_like_hal`]
//! are that crate's algorithms (`rcc::pll::MainPll::fast_setup`,
//! `rcc::CFGR::freeze_internal`, `timer::compute_arr_presc`,
//! `spi::Spi::pre_init`) written as const fns, and the constant assertions
//! below pin the results against the frequencies asked for, the limits of
//! RM0090 and the register words worked out by hand. Pure arithmetic,
//! evaluated by the compiler: none of these functions is called on the
//! board.

/// The crystal on the motor board, Hz.
pub const HSE_HZ: u32 = 8_000_000;
/// Core clock asked for, Hz.
pub const SYSCLK_HZ: u32 = 168_000_000;
/// APB1 clock asked for, Hz (its maximum on the F405).
pub const PCLK1_HZ: u32 = 42_000_000;
/// APB2 clock asked for, Hz (its maximum on the F405).
pub const PCLK2_HZ: u32 = 84_000_000;
/// H-bridge PWM frequency, Hz (above hearing).
pub const PWM_HZ: u32 = 20_000;
/// The control tick, Hz.
pub const TICK_HZ: u32 = crate::board_config::TICK_HZ;

/// One clock configuration: the dividers, as numbers (not register codes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ClockTree {
    /// PLL source (the HSE crystal), Hz.
    pub source_hz: u32,
    /// PLLM: VCO input = source / M (RM0090 §7.3.2, 2…63).
    pub pllm: u32,
    /// PLLN: VCO output = VCO input × N (50…432).
    pub plln: u32,
    /// PLLP: SYSCLK = VCO output / P (2, 4, 6 or 8).
    pub pllp: u32,
    /// PLLQ: 48 MHz domain = VCO output / Q (2…15).
    pub pllq: u32,
    /// AHB prescaler (1, 2, 4, …, 512).
    pub hpre: u32,
    /// APB1 prescaler (1, 2, 4, 8, 16).
    pub ppre1: u32,
    /// APB2 prescaler (1, 2, 4, 8, 16).
    pub ppre2: u32,
    /// Flash wait states (RM0090 §3.5.1, Table 10).
    pub flash_latency: u32,
}

/// The HAL's divider choice for an APB prescaler: `ceil(from / to)` rounded
/// up to the next divider the register can hold.
const fn hal_apb_div(hclk: u32, pclk: u32) -> u32 {
    match hclk.div_ceil(pclk) {
        1 => 1,
        2 => 2,
        3..=5 => 4,
        6..=11 => 8,
        _ => 16,
    }
}

/// The HAL's divider choice for the AHB prescaler.
const fn hal_ahb_div(sysclk: u32, hclk: u32) -> u32 {
    match sysclk.div_ceil(hclk) {
        1 => 1,
        2 => 2,
        3..=5 => 4,
        6..=11 => 8,
        12..=39 => 16,
        40..=95 => 64,
        96..=191 => 128,
        192..=383 => 256,
        _ => 512,
    }
}

/// The register code of an APB divider (PPRE1/PPRE2, RM0090 §7.3.3).
const fn ppre_bits(div: u32) -> u32 {
    match div {
        1 => 0b000,
        2 => 0b100,
        4 => 0b101,
        8 => 0b110,
        _ => 0b111,
    }
}

/// The register code of the AHB divider (HPRE, RM0090 §7.3.3).
const fn hpre_bits(div: u32) -> u32 {
    match div {
        1 => 0b0000,
        2 => 0b1000,
        4 => 0b1001,
        8 => 0b1010,
        16 => 0b1011,
        64 => 0b1100,
        128 => 0b1101,
        256 => 0b1110,
        _ => 0b1111,
    }
}

impl ClockTree {
    /// What stm32f4xx-hal 0.22's `CFGR::freeze` picks for a PLL fed by
    /// `source_hz` (HSE) and the frequencies asked for, without the USB
    /// clock (`require_pll48clk`) or I2S: `MainPll::fast_setup`'s search for
    /// the lowest M that hits `sysclk × P` exactly, P the smallest even
    /// divider keeping the VCO at or below 432 MHz, Q the smallest keeping
    /// the 48 MHz domain at or below 48 MHz; the prescalers round the
    /// division up; the flash gets one wait state per 30 MHz.
    #[must_use]
    pub const fn like_hal(source_hz: u32, sysclk: u32, hclk: u32, pclk1: u32, pclk2: u32) -> Self {
        let pllm_min = source_hz.div_ceil(2_000_000);
        let pllm_max = source_hz / 1_000_000;
        let sysclk_div = {
            let d = (432_000_000 / sysclk) & !1;
            if d < 8 { d } else { 8 }
        };
        let target = sysclk * sysclk_div;
        // `min_by_key` keeps the first of equal minima: strict `<`.
        let mut pllm = pllm_min;
        let mut best = u32::MAX;
        let mut m = pllm_min;
        while m <= pllm_max {
            let vco_in = source_hz / m;
            let err = target - vco_in * (target / vco_in);
            if err < best {
                best = err;
                pllm = m;
            }
            m += 1;
        }
        let vco_in = source_hz / pllm;
        let plln = target / vco_in;
        let pllq = (vco_in * plln).div_ceil(48_000_000);
        let real_sysclk = vco_in * plln / sysclk_div;
        let hpre = hal_ahb_div(real_sysclk, hclk);
        let real_hclk = real_sysclk / hpre;
        Self {
            source_hz,
            pllm,
            plln,
            pllp: sysclk_div,
            pllq,
            hpre,
            ppre1: hal_apb_div(real_hclk, pclk1),
            ppre2: hal_apb_div(real_hclk, pclk2),
            flash_latency: (real_sysclk - 1) / 30_000_000,
        }
    }

    /// VCO input, Hz (RM0090 §7.2.3: 1…2 MHz, 2 MHz recommended for jitter).
    #[must_use]
    pub const fn vco_in_hz(&self) -> u32 {
        self.source_hz / self.pllm
    }

    /// VCO output, Hz (100…432 MHz).
    #[must_use]
    pub const fn vco_hz(&self) -> u32 {
        self.vco_in_hz() * self.plln
    }

    /// SYSCLK, Hz.
    #[must_use]
    pub const fn sysclk_hz(&self) -> u32 {
        self.vco_hz() / self.pllp
    }

    /// HCLK (AHB, core), Hz.
    #[must_use]
    pub const fn hclk_hz(&self) -> u32 {
        self.sysclk_hz() / self.hpre
    }

    /// PCLK1 (APB1), Hz.
    #[must_use]
    pub const fn pclk1_hz(&self) -> u32 {
        self.hclk_hz() / self.ppre1
    }

    /// PCLK2 (APB2), Hz.
    #[must_use]
    pub const fn pclk2_hz(&self) -> u32 {
        self.hclk_hz() / self.ppre2
    }

    /// The APB2 timers' clock (TIM1), Hz: ×2 when APB2 is divided
    /// (RM0090 §7.2, "timer clock frequencies").
    #[must_use]
    pub const fn apb2_timer_hz(&self) -> u32 {
        if self.ppre2 == 1 {
            self.pclk2_hz()
        } else {
            2 * self.pclk2_hz()
        }
    }

    /// The APB1 timers' clock (TIM2), Hz: ×2 when APB1 is divided.
    #[must_use]
    pub const fn apb1_timer_hz(&self) -> u32 {
        if self.ppre1 == 1 {
            self.pclk1_hz()
        } else {
            2 * self.pclk1_hz()
        }
    }

    /// The 48 MHz domain (USB OTG FS, SDIO, RNG; unused here), Hz.
    #[must_use]
    pub const fn pll48_hz(&self) -> u32 {
        self.vco_hz() / self.pllq
    }

    /// RCC_PLLCFGR (RM0090 §7.3.2): PLLM [5:0], PLLN [14:6], PLLP [17:16]
    /// (P/2 − 1), PLLSRC [22] = HSE, PLLQ [27:24]; reserved bit 29 kept at
    /// its reset value 1 (reset value 0x2400_3010), as svd2rust's `write`
    /// through the HAL left it.
    #[must_use]
    pub const fn pllcfgr(&self) -> u32 {
        (1 << 29)
            | (self.pllq << 24)
            | (1 << 22)
            | ((self.pllp / 2 - 1) << 16)
            | (self.plln << 6)
            | self.pllm
    }

    /// RCC_CFGR's prescaler fields (RM0090 §7.3.3): PPRE2 [15:13], PPRE1
    /// [12:10], HPRE [7:4]; everything else 0 (SW is written after).
    #[must_use]
    pub const fn cfgr_prescalers(&self) -> u32 {
        (ppre_bits(self.ppre2) << 13) | (ppre_bits(self.ppre1) << 10) | (hpre_bits(self.hpre) << 4)
    }

    /// The mask of [`Self::cfgr_prescalers`]' fields in RCC_CFGR.
    pub const CFGR_PRESCALER_MASK: u32 = (0b111 << 13) | (0b111 << 10) | (0b1111 << 4);
}

/// The motor board's clocks: 8 MHz HSE → PLL → 168 MHz SYSCLK and HCLK,
/// APB1 42 MHz, APB2 84 MHz (timers 84 / 168 MHz).
pub const MOTOR_BOARD: ClockTree =
    ClockTree::like_hal(HSE_HZ, SYSCLK_HZ, SYSCLK_HZ, PCLK1_HZ, PCLK2_HZ);

// The HAL's choice, worked out by hand from its algorithm: M from 4 (8 MHz /
// 2 MHz) to 8; P = 2 (432 / 168 = 2.57, even); target VCO 336 MHz; M = 4
// (2 MHz in, N = 168) is the first with no error; Q = ceil(336 / 48) = 7;
// AHB /1, APB1 ceil(168 / 42) = 4, APB2 ceil(168 / 84) = 2; 5 wait states.
const _: () = assert!(
    MOTOR_BOARD.pllm == 4
        && MOTOR_BOARD.plln == 168
        && MOTOR_BOARD.pllp == 2
        && MOTOR_BOARD.pllq == 7
        && MOTOR_BOARD.hpre == 1
        && MOTOR_BOARD.ppre1 == 4
        && MOTOR_BOARD.ppre2 == 2
        && MOTOR_BOARD.flash_latency == 5
);
// The frequencies asked for, exactly.
const _: () = assert!(
    MOTOR_BOARD.sysclk_hz() == SYSCLK_HZ
        && MOTOR_BOARD.hclk_hz() == SYSCLK_HZ
        && MOTOR_BOARD.pclk1_hz() == PCLK1_HZ
        && MOTOR_BOARD.pclk2_hz() == PCLK2_HZ
        && MOTOR_BOARD.apb2_timer_hz() == SYSCLK_HZ
);
// RM0090 limits: VCO input 1–2 MHz and output 100–432 MHz (§7.2.3), the
// 48 MHz domain not above 48 MHz, SYSCLK ≤ 168 MHz, APB1 ≤ 42 MHz, APB2 ≤
// 84 MHz (§7.2), and 5 wait states for 150–168 MHz at 2.7–3.6 V (§3.5.1,
// Table 10).
const _: () = assert!(
    MOTOR_BOARD.vco_in_hz() >= 1_000_000
        && MOTOR_BOARD.vco_in_hz() <= 2_000_000
        && MOTOR_BOARD.vco_hz() >= 100_000_000
        && MOTOR_BOARD.vco_hz() <= 432_000_000
        && MOTOR_BOARD.pll48_hz() <= 48_000_000
        && MOTOR_BOARD.sysclk_hz() <= 168_000_000
        && MOTOR_BOARD.pclk1_hz() <= 42_000_000
        && MOTOR_BOARD.pclk2_hz() <= 84_000_000
        && MOTOR_BOARD.flash_latency == MOTOR_BOARD.hclk_hz().div_ceil(30_000_000) - 1
);
// The register words, by hand: Q 7 << 24 | HSE 1 << 22 | P 0 << 16 | N 168
// << 6 | M 4, with reserved bit 29; PPRE2 /2 = 0b100, PPRE1 /4 = 0b101.
const _: () = assert!(MOTOR_BOARD.pllcfgr() == 0x2740_2A04);
const _: () = assert!(MOTOR_BOARD.cfgr_prescalers() == 0x9400);

/// A timer's time base (TIM1's PWM period, TIM2's control tick).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TimerTiming {
    /// TIMx_PSC: the counter runs at timer clock / (PSC + 1).
    pub psc: u16,
    /// TIMx_ARR: the period is ARR + 1 counts.
    pub arr: u16,
}

impl TimerTiming {
    /// stm32f4xx-hal 0.22's `compute_arr_presc`, as `Timer::pwm_hz` and
    /// `CounterHz::start` used it: the smallest prescaler that fits the
    /// period into 16 bits.
    #[must_use]
    pub const fn like_hal(timer_hz: u32, pwm_hz: u32) -> Self {
        let ticks = timer_hz / pwm_hz;
        let psc = (ticks - 1) / (1 << 16);
        let arr = ticks / (psc + 1) - 1;
        assert!(psc <= 0xFFFF && arr > 0 && arr <= 0xFFFF);
        Self {
            psc: psc as u16,
            arr: arr as u16,
        }
    }

    /// The duty cycle's full scale (`SetDutyCycle::max_duty_cycle`): ARR + 1.
    #[must_use]
    pub const fn max_duty(&self) -> u16 {
        self.arr.wrapping_add(1)
    }

    /// The update frequency this gives at `timer_hz`, Hz.
    #[must_use]
    pub const fn frequency_hz(&self, timer_hz: u32) -> u32 {
        timer_hz / ((self.psc as u32 + 1) * (self.arr as u32 + 1))
    }
}

/// The motor board's PWM: TIM1 on APB2's 168 MHz timer clock, 20 kHz.
pub const MOTOR_PWM: TimerTiming = TimerTiming::like_hal(MOTOR_BOARD.apb2_timer_hz(), PWM_HZ);

// 168 MHz / 20 kHz = 8,400 counts: no prescaler, ARR 8,399, exactly 20 kHz.
const _: () =
    assert!(MOTOR_PWM.psc == 0 && MOTOR_PWM.arr == 8_399 && MOTOR_PWM.max_duty() == 8_400);
const _: () = assert!(MOTOR_PWM.frequency_hz(MOTOR_BOARD.apb2_timer_hz()) == PWM_HZ);

/// The control tick's timer: TIM2 on APB1's 84 MHz timer clock, 1 kHz.
pub const TICK_TIMER: TimerTiming = TimerTiming::like_hal(MOTOR_BOARD.apb1_timer_hz(), TICK_HZ);

// 84 MHz / 1 kHz = 84,000 counts, over 16 bits: PSC 1 (÷2), ARR 41,999.
const _: () = assert!(TICK_TIMER.psc == 1 && TICK_TIMER.arr == 41_999);
const _: () = assert!(TICK_TIMER.frequency_hz(MOTOR_BOARD.apb1_timer_hz()) == TICK_HZ);

/// stm32f4xx-hal 0.22's SPI baud-rate choice (`Spi::pre_init`): the
/// register code BR (RM0090 §28.5.1, SPI_CR1 BR[2:0], f_PCLK / 2^(BR+1)) for
/// the bus clock `freq_hz` asked for on a peripheral clocked at `pclk_hz`.
#[must_use]
pub const fn spi_br_like_hal(pclk_hz: u32, freq_hz: u32) -> u8 {
    match pclk_hz / freq_hz {
        0..=2 => 0b000,
        3..=5 => 0b001,
        6..=11 => 0b010,
        12..=23 => 0b011,
        24..=47 => 0b100,
        48..=95 => 0b101,
        96..=191 => 0b110,
        _ => 0b111,
    }
}

/// The SPI clock a BR code gives on a peripheral clocked at `pclk_hz`, Hz.
#[must_use]
pub const fn spi_hz(pclk_hz: u32, br: u8) -> u32 {
    pclk_hz >> (br as u32 + 1)
}

/// Encoder bus (SPI1 on APB2) clock asked for, Hz: the fastest of APB2's
/// 84 MHz not above 2× this, /16 = 5.25 MHz (/8 would be 10.5 MHz, above
/// the AS5048A's 10 MHz).
pub const ENCODER_SPI_HZ: u32 = 5_250_000;
/// ADC bus (SPI2 on APB1) clock asked for, Hz: 42 MHz / 64 = 656 kHz (the
/// MCP3208 is rated 1 MHz at 2.7 V; /32 would be 1.31 MHz).
pub const ADC_SPI_HZ: u32 = 656_250;
/// SPI1's BR code for the encoders.
pub const ENCODER_SPI_BR: u8 = spi_br_like_hal(MOTOR_BOARD.pclk2_hz(), ENCODER_SPI_HZ);
/// SPI2's BR code for the force ADC.
pub const ADC_SPI_BR: u8 = spi_br_like_hal(MOTOR_BOARD.pclk1_hz(), ADC_SPI_HZ);

const _: () =
    assert!(ENCODER_SPI_BR == 0b011 && spi_hz(MOTOR_BOARD.pclk2_hz(), ENCODER_SPI_BR) == 5_250_000);
const _: () = assert!(ADC_SPI_BR == 0b101 && spi_hz(MOTOR_BOARD.pclk1_hz(), ADC_SPI_BR) == 656_250);

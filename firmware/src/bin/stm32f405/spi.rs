//! The encoder and force-ADC SPI buses through the PAC: master, 8-bit
//! frames, MSB first, software NSS (chip selects are GPIO), as
//! stm32f4xx-hal's `Spi::new` set them up (its constructor needs the HAL's
//! `Clocks`, which only its clock set-up with the PLL search can make).
//! Every wait for the hardware is bounded: a bus that stops answering gives
//! a typed error (the drivers report a bus fault), not a hang.

use embedded_hal::spi::{ErrorKind, ErrorType, Mode, Phase, Polarity, SpiBus};
use stm32f4xx_hal::pac::{self, RCC, spi1::RegisterBlock};

/// What went wrong on the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error {
    /// A received byte was overwritten before it was read (SR OVR).
    Overrun,
    /// Another master pulled NSS (SR MODF).
    ModeFault,
    /// CRC mismatch (SR CRCERR; CRC is off, so never expected).
    Crc,
    /// TXE or RXNE did not come within [`POLLS`] polls.
    Timeout,
}

impl embedded_hal::spi::Error for Error {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Overrun => ErrorKind::Overrun,
            Self::ModeFault => ErrorKind::ModeFault,
            Self::Crc | Self::Timeout => ErrorKind::Other,
        }
    }
}

/// Polls of SR for one flag before [`Error::Timeout`]. A poll is at least 4
/// core cycles (a load over the APB bridge, a test, a branch), so 2,000 polls
/// wait at least 8,000 cycles (48 µs at 168 MHz), almost 4 byte times on the
/// slower bus (656 kHz: 12.2 µs a byte); a healthy bus sets TXE at once and
/// RXNE one byte time after the write.
const POLLS: u32 = 2_000;

/// One SPI master bus.
pub struct Bus {
    regs: &'static RegisterBlock,
}

// SAFETY: a bus is its peripheral's only user (the PAC's SPI1 or SPI2,
// which are `Send`, was handed over to build it): moving it to the tick's
// interrupt moves that sole access with it.
unsafe impl Send for Bus {}

impl Bus {
    /// SPI1 (APB2), the encoders' bus: clock on and the peripheral reset
    /// (RM0090 §7.3.14 / §7.3.6), then [`Bus::start`].
    pub fn spi1(_spi: pac::SPI1, rcc: &RCC, mode: Mode, br: u8) -> Self {
        rcc.apb2enr().modify(|_, w| w.spi1en().set_bit());
        let _ = rcc.apb2enr().read();
        rcc.apb2rstr().modify(|_, w| w.spi1rst().set_bit());
        rcc.apb2rstr().modify(|_, w| w.spi1rst().clear_bit());
        // SAFETY: the peripheral was handed over (`_spi`); this is its only
        // user from here on.
        Self::start(unsafe { &*pac::SPI1::ptr() }, mode, br)
    }

    /// SPI2 (APB1), the force ADC's bus (RM0090 §7.3.13 / §7.3.5).
    pub fn spi2(_spi: pac::SPI2, rcc: &RCC, mode: Mode, br: u8) -> Self {
        rcc.apb1enr().modify(|_, w| w.spi2en().set_bit());
        let _ = rcc.apb1enr().read();
        rcc.apb1rstr().modify(|_, w| w.spi2rst().set_bit());
        rcc.apb1rstr().modify(|_, w| w.spi2rst().clear_bit());
        // SAFETY: as for SPI1.
        Self::start(unsafe { &*pac::SPI2::ptr() }, mode, br)
    }

    /// RM0090 §28.3.3, "Configuring the SPI in master mode", and §28.5.1–2
    /// (SPI_CR1, SPI_CR2): SS output off; CPHA/CPOL from `mode`, master,
    /// baud rate f_PCLK / 2^(BR+1), MSB first, software slave management
    /// with SSI high, full duplex, 8-bit frames; then SPE.
    fn start(regs: &'static RegisterBlock, mode: Mode, br: u8) -> Self {
        regs.cr2().write(|w| w.ssoe().clear_bit());
        regs.cr1().write(|w| {
            w.cpha().bit(mode.phase == Phase::CaptureOnSecondTransition);
            w.cpol().bit(mode.polarity == Polarity::IdleHigh);
            w.mstr().set_bit();
            w.br().set(br);
            w.lsbfirst().clear_bit();
            w.ssm().set_bit();
            w.ssi().set_bit();
            w.rxonly().clear_bit();
            w.dff().clear_bit()
        });
        regs.cr1().modify(|_, w| {
            w.bidimode().clear_bit();
            w.bidioe().clear_bit();
            w.dff().clear_bit();
            w.spe().set_bit()
        });
        Self { regs }
    }

    /// The error flags, as the HAL checked them (clearing each as RM0090
    /// §28.4.8 says: OVR by reading DR then SR, MODF by a write to CR1).
    fn check(&self) -> Result<(), Error> {
        let sr = self.regs.sr().read();
        if sr.ovr().bit_is_set() {
            let _ = self.regs.dr8().read();
            let _ = self.regs.sr().read();
            Err(Error::Overrun)
        } else if sr.modf().bit_is_set() {
            self.regs.cr1().modify(|_, w| w);
            Err(Error::ModeFault)
        } else if sr.crcerr().bit_is_set() {
            self.regs.sr().modify(|_, w| w.crcerr().clear_bit());
            Err(Error::Crc)
        } else {
            Ok(())
        }
    }

    /// Sends one byte and returns the one received with it.
    fn exchange(&mut self, out: u8) -> Result<u8, Error> {
        let mut sent = false;
        for _ in 0..POLLS {
            self.check()?;
            if self.regs.sr().read().txe().bit_is_set() {
                self.regs.dr8().write(|w| w.dr().set(out));
                sent = true;
                break;
            }
        }
        if !sent {
            return Err(Error::Timeout);
        }
        for _ in 0..POLLS {
            self.check()?;
            if self.regs.sr().read().rxne().bit_is_set() {
                return Ok(self.regs.dr8().read().dr().bits());
            }
        }
        Err(Error::Timeout)
    }
}

impl ErrorType for Bus {
    type Error = Error;
}

impl SpiBus<u8> for Bus {
    fn read(&mut self, words: &mut [u8]) -> Result<(), Error> {
        for w in words {
            *w = self.exchange(0)?;
        }
        Ok(())
    }

    fn write(&mut self, words: &[u8]) -> Result<(), Error> {
        for &w in words {
            self.exchange(w)?;
        }
        Ok(())
    }

    fn transfer(&mut self, read: &mut [u8], write: &[u8]) -> Result<(), Error> {
        let mut reads = read.iter_mut();
        let mut writes = write.iter();
        loop {
            match (reads.next(), writes.next()) {
                (Some(r), Some(&w)) => *r = self.exchange(w)?,
                (Some(r), None) => *r = self.exchange(0)?,
                (None, Some(&w)) => {
                    self.exchange(w)?;
                }
                (None, None) => return Ok(()),
            }
        }
    }

    fn transfer_in_place(&mut self, words: &mut [u8]) -> Result<(), Error> {
        for w in words {
            *w = self.exchange(*w)?;
        }
        Ok(())
    }

    /// Every byte's answer has been read, so nothing is left in flight.
    fn flush(&mut self) -> Result<(), Error> {
        Ok(())
    }
}

//! Mock SPI, PWM and pins shared by the driver tests.

use core::cell::RefCell;
use core::convert::Infallible;
use std::rc::Rc;

use embedded_hal::digital::{ErrorType as PinErrorType, OutputPin};
use embedded_hal::pwm::{ErrorType as PwmErrorType, SetDutyCycle};
use embedded_hal::spi::{ErrorKind, ErrorType as SpiErrorType, Operation, SpiDevice};
use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as SpiTransaction};

/// embedded-hal-mock 0.11's SPI mock has no `with_error`, so bus errors are
/// injected by this wrapper: transaction number `fail_at` (0-based) returns
/// `ErrorKind::Other` without reaching the mock (so it needs no
/// expectation); every other transaction goes to the mock.
pub struct FaultySpi {
    pub mock: SpiMock<u8>,
    pub fail_at: Option<usize>,
    pub count: usize,
}

impl FaultySpi {
    pub fn new(expectations: &[SpiTransaction<u8>], fail_at: Option<usize>) -> Self {
        Self {
            mock: SpiMock::new(expectations),
            fail_at,
            count: 0,
        }
    }

    /// Checks that every expectation was used.
    pub fn done(mut self) {
        self.mock.done();
    }
}

impl SpiErrorType for FaultySpi {
    type Error = ErrorKind;
}

impl SpiDevice<u8> for FaultySpi {
    fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), ErrorKind> {
        let n = self.count;
        self.count += 1;
        if Some(n) == self.fail_at {
            return Err(ErrorKind::Other);
        }
        self.mock.transaction(operations)
    }
}

/// One SPI transaction of a single in-place transfer, with its CS frame.
pub fn frame(tx: &[u8], rx: &[u8]) -> [SpiTransaction<u8>; 3] {
    [
        SpiTransaction::transaction_start(),
        SpiTransaction::transfer_in_place(tx.to_vec(), rx.to_vec()),
        SpiTransaction::transaction_end(),
    ]
}

/// Flattens groups of frames into one expectation list.
pub fn frames<const N: usize>(groups: &[[SpiTransaction<u8>; N]]) -> Vec<SpiTransaction<u8>> {
    groups.iter().flat_map(|g| g.iter().cloned()).collect()
}

/// A PWM that records every duty written (for long or random runs where
/// listing mock expectations is impractical).
#[derive(Clone)]
pub struct RecordingPwm {
    pub max: u16,
    pub log: Rc<RefCell<Vec<u16>>>,
}

impl RecordingPwm {
    pub fn new(max: u16) -> Self {
        Self {
            max,
            log: Rc::new(RefCell::new(Vec::new())),
        }
    }
}

impl PwmErrorType for RecordingPwm {
    type Error = Infallible;
}

impl SetDutyCycle for RecordingPwm {
    fn max_duty_cycle(&self) -> u16 {
        self.max
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        assert!(duty <= self.max, "duty {duty} above max {}", self.max);
        self.log.borrow_mut().push(duty);
        Ok(())
    }
}

/// An output pin that remembers its level.
#[derive(Clone, Default)]
pub struct RecordingPin {
    pub high: Rc<RefCell<bool>>,
}

impl PinErrorType for RecordingPin {
    type Error = Infallible;
}

impl OutputPin for RecordingPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        *self.high.borrow_mut() = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        *self.high.borrow_mut() = true;
        Ok(())
    }
}

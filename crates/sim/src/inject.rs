//! Fault injection by name: what `exogait simulate --inject` and the fault
//! campaigns ask of the rig. An [`Injection`] is a kind, a target where the
//! kind needs one, and a time; written `KIND[=VALUE][:TARGET]@SECONDS`,
//! e.g. `encoder-jump=200:right-hip@3.1`, `motor-weak=0.5:left-knee@2`,
//! `estop@5`. The rig applies it at that time through the simulated
//! peripherals, the motor bridges or the pilot
//! ([`crate::closed_loop::Rig::schedule`]); one-frame and short faults undo
//! themselves.

use core::fmt;
use core::str::FromStr;

mod apply;

pub(crate) use apply::{Injector, leaned};

/// A fault the simulated peripherals, bridges or pilot can produce.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    /// Every transaction with the encoder fails on the bus.
    EncoderBus,
    /// Every answer of the encoder fails its parity check.
    EncoderParity,
    /// The encoder raises its error flag with every frame (the driver's
    /// clearing read does not help: the chip keeps seeing bad frames).
    EncoderErrorFlag,
    /// The encoder's reading sticks where it is.
    EncoderStuck,
    /// The reading jumps by this many counts and stays there.
    EncoderJump(i32),
    /// The reading is off by this many counts for one frame.
    EncoderGlitch(i32),
    /// The force sensor's cable opens (0 counts).
    FsrOpen,
    /// The force sensor shorts to the reference (full scale).
    FsrShort,
    /// The force sensor reads a quarter above its rated maximum.
    FsrOverRange,
    /// The force sensor reads this many newtons more for 3 ms.
    FsrSpike(f64),
    /// Every transaction with the force ADC fails on the bus.
    AdcBus,
    /// The drive's amplifier gives only this share of the current asked
    /// (its current monitor sees it).
    MotorWeak(f64),
    /// The gearbox passes only this share of the motor's torque (the
    /// current, and its monitor, stay what was asked).
    GearSlip(f64),
    /// The bridge's output sticks at its present torque.
    MotorStuck,
    /// Every PWM write to the bridge fails.
    PwmFail,
    /// Every write to the bridge's direction pin fails.
    DirFail,
    /// The drive's current-monitor line opens (its ADC channel reads 0).
    CurrentOpen,
    /// The drive's current-monitor line shorts to the reference (full
    /// scale).
    CurrentShort,
    /// The emergency stop is pressed.
    EStop,
    /// The emergency-stop input cannot be read.
    EStopRead,
    /// The MODE and GO inputs cannot be read.
    ButtonRead,
    /// This many consecutive ticks overrun their deadline.
    Overrun(u32),
    /// The pilot leans the stance shank this much further forward, rad.
    PilotLean(f64),
    /// The pilot stops balancing on the crutches.
    PilotStopsBalancing,
    /// The board's re-planner gives no answer to its next request in time
    /// (with re-planning on).
    ReplanTimeout,
    /// The device's admission check refuses the re-planner's next answer
    /// (with re-planning on).
    ReplanRefused,
    /// The firmware panics: the panic handler resets the board, the motors
    /// are off (limp) for the boot, this many milliseconds, and the new
    /// controller starts with fault 0x0603 (`docs/safety.md`).
    Panic(f64),
}

/// The motor board's boot after a reset, ms, until its first control tick:
/// the 8 MHz crystal's start-up (≤ 2 ms, STM32F405 datasheet), the PLL lock
/// and the power-on self-test (measured under QEMU, `cargo xtask qemu`:
/// "selftest" line), rounded up.
pub const DEFAULT_BOOT_MS: f64 = 5.0;

/// Where a fault strikes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// A joint (hip or knee; joint order, gait-control's layout).
    Joint(usize),
    /// An ankle encoder (0 left, 1 right).
    Ankle(usize),
    /// A force sensor (gait-control's layout: feet, then crutches).
    Force(usize),
}

/// What a kind may strike.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Needs {
    Encoder,
    Force,
    Motor,
    Nothing,
}

const TARGETS: [(&str, Target); 10] = [
    ("left-hip", Target::Joint(0)),
    ("left-knee", Target::Joint(1)),
    ("right-hip", Target::Joint(2)),
    ("right-knee", Target::Joint(3)),
    ("left-ankle", Target::Ankle(0)),
    ("right-ankle", Target::Ankle(1)),
    ("left-foot", Target::Force(0)),
    ("right-foot", Target::Force(1)),
    ("left-crutch", Target::Force(2)),
    ("right-crutch", Target::Force(3)),
];

impl Target {
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        TARGETS
            .iter()
            .find(|(_, t)| *t == self)
            .map_or("?", |(n, _)| n)
    }
}

impl Kind {
    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::EncoderBus => "encoder-bus",
            Self::EncoderParity => "encoder-parity",
            Self::EncoderErrorFlag => "encoder-error-flag",
            Self::EncoderStuck => "encoder-stuck",
            Self::EncoderJump(_) => "encoder-jump",
            Self::EncoderGlitch(_) => "encoder-glitch",
            Self::FsrOpen => "fsr-open",
            Self::FsrShort => "fsr-short",
            Self::FsrOverRange => "fsr-over-range",
            Self::FsrSpike(_) => "fsr-spike",
            Self::AdcBus => "adc-bus",
            Self::MotorWeak(_) => "motor-weak",
            Self::GearSlip(_) => "gear-slip",
            Self::MotorStuck => "motor-stuck",
            Self::PwmFail => "pwm-fail",
            Self::DirFail => "dir-fail",
            Self::CurrentOpen => "current-open",
            Self::CurrentShort => "current-short",
            Self::EStop => "estop",
            Self::EStopRead => "estop-read",
            Self::ButtonRead => "button-read",
            Self::Overrun(_) => "overrun",
            Self::PilotLean(_) => "pilot-lean",
            Self::PilotStopsBalancing => "pilot-stops-balancing",
            Self::ReplanTimeout => "replan-timeout",
            Self::ReplanRefused => "replan-refused",
            Self::Panic(_) => "panic",
        }
    }

    fn needs(self) -> Needs {
        match self {
            Self::EncoderBus
            | Self::EncoderParity
            | Self::EncoderErrorFlag
            | Self::EncoderStuck
            | Self::EncoderJump(_)
            | Self::EncoderGlitch(_) => Needs::Encoder,
            Self::FsrOpen | Self::FsrShort | Self::FsrOverRange | Self::FsrSpike(_) => Needs::Force,
            Self::MotorWeak(_)
            | Self::GearSlip(_)
            | Self::MotorStuck
            | Self::PwmFail
            | Self::DirFail
            | Self::CurrentOpen
            | Self::CurrentShort => Needs::Motor,
            Self::AdcBus
            | Self::EStop
            | Self::EStopRead
            | Self::ButtonRead
            | Self::Overrun(_)
            | Self::PilotLean(_)
            | Self::PilotStopsBalancing
            | Self::ReplanTimeout
            | Self::ReplanRefused
            | Self::Panic(_) => Needs::Nothing,
        }
    }

    /// Every kind's name, for help texts and errors.
    pub const NAMES: [&'static str; 27] = [
        "encoder-bus",
        "encoder-parity",
        "encoder-error-flag",
        "encoder-stuck",
        "encoder-jump=<counts>",
        "encoder-glitch=<counts>",
        "fsr-open",
        "fsr-short",
        "fsr-over-range",
        "fsr-spike=<newtons>",
        "adc-bus",
        "motor-weak=<fraction>",
        "gear-slip=<fraction>",
        "motor-stuck",
        "pwm-fail",
        "dir-fail",
        "current-open",
        "current-short",
        "estop",
        "estop-read",
        "button-read",
        "overrun=<count>",
        "pilot-lean=<rad>",
        "pilot-stops-balancing",
        "replan-timeout",
        "replan-refused",
        "panic=<boot ms>",
    ];
}

/// One fault to inject.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Injection {
    /// What.
    pub kind: Kind,
    /// Where (`None` for kinds that strike no channel).
    pub target: Option<Target>,
    /// When, simulated seconds from the start.
    pub at_s: f64,
}

impl fmt::Display for Injection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.kind.name())?;
        match self.kind {
            Kind::EncoderJump(c) | Kind::EncoderGlitch(c) => write!(f, "={c}")?,
            Kind::FsrSpike(v)
            | Kind::MotorWeak(v)
            | Kind::GearSlip(v)
            | Kind::PilotLean(v)
            | Kind::Panic(v) => {
                write!(f, "={v}")?;
            }
            Kind::Overrun(n) => write!(f, "={n}")?,
            _ => {}
        }
        if let Some(t) = self.target {
            write!(f, ":{}", t.name())?;
        }
        write!(f, "@{}", self.at_s)
    }
}

/// Why an injection was refused (the message says what would be accepted).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError(pub String);

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ParseError {}

fn err<T>(text: &str, why: impl fmt::Display) -> Result<T, ParseError> {
    Err(ParseError(format!("--inject {text:?}: {why}")))
}

impl FromStr for Injection {
    type Err = ParseError;

    fn from_str(text: &str) -> Result<Self, ParseError> {
        let Some((what, at)) = text.rsplit_once('@') else {
            return err(
                text,
                "expected KIND[=VALUE][:TARGET]@SECONDS, e.g. encoder-parity:left-knee@2.5",
            );
        };
        let at_s: f64 = match at.trim().parse() {
            Ok(v) if (0.0..=600.0).contains(&v) => v,
            _ => return err(text, "the time must be a number of seconds in [0, 600]"),
        };
        let (head, target) = match what.split_once(':') {
            Some((h, t)) => (h, Some(t.trim())),
            None => (what, None),
        };
        let (name, value) = match head.split_once('=') {
            Some((n, v)) => (n.trim(), Some(v.trim())),
            None => (head.trim(), None),
        };
        let kind = parse_kind(text, name, value)?;
        let target = match (kind.needs(), target) {
            (Needs::Nothing, None) => None,
            (Needs::Nothing, Some(_)) => {
                return err(text, format!("{} takes no target", kind.name()));
            }
            (needs, None) => {
                return err(
                    text,
                    format!("{} needs a target: {}", kind.name(), allowed(needs)),
                );
            }
            (needs, Some(t)) => {
                let found = TARGETS.iter().find(|(n, _)| *n == t).map(|(_, t)| *t);
                match (needs, found) {
                    (Needs::Encoder, Some(t @ (Target::Joint(_) | Target::Ankle(_))))
                    | (Needs::Force, Some(t @ Target::Force(_)))
                    | (Needs::Motor, Some(t @ Target::Joint(_))) => Some(t),
                    _ => {
                        return err(
                            text,
                            format!("{} cannot strike {t:?}: {}", kind.name(), allowed(needs)),
                        );
                    }
                }
            }
        };
        Ok(Self { kind, target, at_s })
    }
}

fn allowed(needs: Needs) -> &'static str {
    match needs {
        Needs::Encoder => "left-hip, left-knee, right-hip, right-knee, left-ankle or right-ankle",
        Needs::Force => "left-foot, right-foot, left-crutch or right-crutch",
        Needs::Motor => "left-hip, left-knee, right-hip or right-knee",
        Needs::Nothing => "none",
    }
}

fn parse_kind(text: &str, name: &str, value: Option<&str>) -> Result<Kind, ParseError> {
    let number = |lo: f64, hi: f64, unit: &str| -> Result<f64, ParseError> {
        let Some(v) = value else {
            return err(text, format!("{name} needs a value: {name}=<{unit}>"));
        };
        match v.parse::<f64>() {
            Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
            _ => err(
                text,
                format!("{name}'s value must be {unit} in [{lo}, {hi}]"),
            ),
        }
    };
    let counts = || -> Result<i32, ParseError> {
        let x = number(-16_383.0, 16_383.0, "counts")?;
        if x.fract() != 0.0 || x == 0.0 {
            return err(
                text,
                format!("{name}'s value must be a non-zero whole number of counts"),
            );
        }
        Ok(x as i32)
    };
    let kind = match name {
        "encoder-bus" => Kind::EncoderBus,
        "encoder-parity" => Kind::EncoderParity,
        "encoder-error-flag" => Kind::EncoderErrorFlag,
        "encoder-stuck" => Kind::EncoderStuck,
        "encoder-jump" => Kind::EncoderJump(counts()?),
        "encoder-glitch" => Kind::EncoderGlitch(counts()?),
        "fsr-open" => Kind::FsrOpen,
        "fsr-short" => Kind::FsrShort,
        "fsr-over-range" => Kind::FsrOverRange,
        "fsr-spike" => Kind::FsrSpike(number(-5_000.0, 5_000.0, "newtons")?),
        "adc-bus" => Kind::AdcBus,
        "motor-weak" => Kind::MotorWeak(number(0.0, 1.0, "a fraction")?),
        "gear-slip" => Kind::GearSlip(number(0.0, 1.0, "a fraction")?),
        "motor-stuck" => Kind::MotorStuck,
        "pwm-fail" => Kind::PwmFail,
        "dir-fail" => Kind::DirFail,
        "current-open" => Kind::CurrentOpen,
        "current-short" => Kind::CurrentShort,
        "estop" => Kind::EStop,
        "estop-read" => Kind::EStopRead,
        "button-read" => Kind::ButtonRead,
        "overrun" => {
            let n = number(1.0, 1_000.0, "a tick count")?;
            if n.fract() != 0.0 {
                return err(text, "overrun's value must be a whole number of ticks");
            }
            Kind::Overrun(n as u32)
        }
        "pilot-lean" => Kind::PilotLean(number(-0.5, 0.5, "radians")?),
        "pilot-stops-balancing" => Kind::PilotStopsBalancing,
        "replan-timeout" => Kind::ReplanTimeout,
        "replan-refused" => Kind::ReplanRefused,
        "panic" => Kind::Panic(match value {
            Some(_) => number(0.0, 1_000.0, "milliseconds")?,
            None => DEFAULT_BOOT_MS,
        }),
        _ => {
            return err(
                text,
                format!("unknown kind {name:?}; kinds: {}", Kind::NAMES.join(", ")),
            );
        }
    };
    let takes_value = matches!(
        kind,
        Kind::EncoderJump(_)
            | Kind::EncoderGlitch(_)
            | Kind::FsrSpike(_)
            | Kind::MotorWeak(_)
            | Kind::GearSlip(_)
            | Kind::Overrun(_)
            | Kind::PilotLean(_)
            | Kind::Panic(_)
    );
    if value.is_some() && !takes_value {
        return err(text, format!("{name} takes no value"));
    }
    Ok(kind)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_examples_and_prints_them_back() {
        for text in [
            "encoder-parity:left-knee@2.5",
            "encoder-jump=200:right-hip@3.1",
            "motor-weak=0.5:left-knee@2",
            "estop@5",
            "overrun=5@4",
            "fsr-spike=300:right-foot@1.25",
            "encoder-glitch=-2000:left-ankle@0.5",
            "pilot-stops-balancing@3",
            "current-open:right-knee@1.5",
            "gear-slip=0.3:left-hip@2.25",
        ] {
            let i: Injection = text.parse().unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(i.to_string(), text);
        }
        let i: Injection = "encoder-jump=200:right-hip@3.1".parse().unwrap();
        assert_eq!(i.kind, Kind::EncoderJump(200));
        assert_eq!(i.target, Some(Target::Joint(2)));
        assert_eq!(i.at_s, 3.1);
    }

    #[test]
    fn refuses_bad_input_naming_what_is_wrong() {
        for (text, says) in [
            ("encoder-parity:left-knee", "KIND[=VALUE][:TARGET]@SECONDS"),
            ("encoder-parity@2", "needs a target"),
            ("estop:left-knee@2", "takes no target"),
            ("fsr-open:left-knee@2", "cannot strike"),
            ("motor-stuck:left-ankle@2", "cannot strike"),
            ("current-short:left-foot@2", "cannot strike"),
            ("motor-weak=1.5:left-knee@2", "fraction in [0, 1]"),
            ("encoder-jump:left-knee@2", "needs a value"),
            ("encoder-jump=2.5:left-knee@2", "whole number"),
            ("estop=3@2", "takes no value"),
            ("warp-drive@2", "unknown kind"),
            ("estop@-1", "seconds in [0, 600]"),
        ] {
            match text.parse::<Injection>() {
                Ok(i) => panic!("{text} accepted as {i:?}"),
                Err(e) => assert!(e.0.contains(says), "{text}: {e}"),
            }
        }
    }
}

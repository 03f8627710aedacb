//! Applying injections to the rig: the faults wait for their time, strike
//! through the simulated peripherals, bridges or pilot, and the short ones
//! undo themselves.

use super::{Injection, Kind, Target};
use crate::as5048a::SimAs5048a;
use crate::closed_loop::{PilotBehaviour, Rig};
use crate::mcp3208::ChannelFault;
use crate::motor::BridgePin;
use crate::pilot::PilotTarget;

/// The rig's injected faults: those waiting for their time, those applied
/// (with the time they struck), what undoes the short ones and when, and
/// what lasts across ticks (overruns, the pilot's lean).
#[derive(Debug, Default)]
pub(crate) struct Injector {
    pending: Vec<Injection>,
    applied: Vec<(Injection, f64)>,
    undo: Vec<(u64, Undo)>,
    /// Encoders that raise their error flag with every frame.
    flagging: Vec<Target>,
    pub(crate) overruns_left: u32,
    pub(crate) pilot_lean_rad: f64,
    /// After an injected panic: the tick the rebooted board ticks again.
    pub(crate) reboot_until: Option<u64>,
}

/// What ends a one-frame or short fault.
#[derive(Clone, Copy, Debug)]
enum Undo {
    /// Move encoder `Target` back by these counts.
    Jump(Target, i32),
    /// Repair force channel.
    Force(usize),
}

impl Rig<'_> {
    /// Injects `fault` when the simulated clock reaches its time (at once
    /// if it has passed).
    pub fn schedule(&mut self, fault: Injection) {
        self.faults.pending.push(fault);
    }

    /// The faults injected so far, with the simulated time each struck, s.
    pub fn injected(&self) -> &[(Injection, f64)] {
        &self.faults.applied
    }

    /// Applies the faults whose time has come and undoes the short ones
    /// whose time is over.
    pub(crate) fn inject_due(&mut self) {
        let now = self.now();
        let dt = f64::from(self.device.dt_s);
        // The plant's clock: the time base of the trace.
        let t = self.plant.time_s();
        let mut undo = core::mem::take(&mut self.faults.undo);
        undo.retain(|&(at, u)| {
            if at > now {
                return true;
            }
            match u {
                Undo::Jump(target, counts) => {
                    if let Some(e) = self.encoder(target) {
                        e.jump(-counts);
                    }
                }
                Undo::Force(ch) => self.adc.set_fault(ch, None),
            }
            false
        });
        self.faults.undo = undo;
        for &target in &self.faults.flagging {
            if let Some(e) = self.encoder(target) {
                e.raise_error(crate::as5048a::error_bit::FRAMING);
            }
        }
        let (due, later): (Vec<_>, Vec<_>) = core::mem::take(&mut self.faults.pending)
            .into_iter()
            .partition(|f| f.at_s <= t + 0.5 * dt);
        self.faults.pending = later;
        for f in due {
            self.apply(f, now);
            self.faults.applied.push((f, t));
        }
    }

    fn encoder(&self, target: Target) -> Option<&SimAs5048a> {
        match target {
            Target::Joint(j) => self.joint_encoders.get(j),
            Target::Ankle(a) => self.ankle_encoders.get(a),
            Target::Force(_) => None,
        }
    }

    /// Makes `f` happen now (tick `now`).
    fn apply(&mut self, f: Injection, now: u64) {
        let target = f.target;
        let encoder = target.and_then(|t| self.encoder(t)).cloned();
        let force = match target {
            Some(Target::Force(k)) => Some(k),
            _ => None,
        };
        let motor = match target {
            Some(Target::Joint(j)) => self.wiring.motors.get(j).cloned(),
            _ => None,
        };
        match f.kind {
            Kind::EncoderBus => {
                if let Some(e) = &encoder {
                    e.fail_transactions(u32::MAX, embedded_hal::spi::ErrorKind::Other);
                }
            }
            Kind::EncoderParity => {
                if let Some(e) = &encoder {
                    e.corrupt_answers(u32::MAX);
                }
            }
            Kind::EncoderErrorFlag => {
                if let (Some(e), Some(t)) = (&encoder, target) {
                    e.raise_error(crate::as5048a::error_bit::FRAMING);
                    self.faults.flagging.push(t);
                }
            }
            Kind::EncoderStuck => {
                if let Some(e) = &encoder {
                    e.freeze(true);
                }
            }
            Kind::EncoderJump(c) => {
                if let Some(e) = &encoder {
                    e.jump(c);
                }
            }
            Kind::EncoderGlitch(c) => {
                if let (Some(e), Some(t)) = (&encoder, target) {
                    e.jump(c);
                    self.faults.undo.push((now + 1, Undo::Jump(t, c)));
                }
            }
            Kind::FsrOpen | Kind::FsrShort | Kind::FsrOverRange | Kind::FsrSpike(_) => {
                if let Some(k) = force {
                    let spec = if k < 2 {
                        self.device.foot_sensor
                    } else {
                        self.device.crutch_sensor
                    };
                    let fault = match f.kind {
                        Kind::FsrOpen => ChannelFault::Open,
                        Kind::FsrShort => ChannelFault::Short,
                        Kind::FsrSpike(n) => {
                            self.faults.undo.push((now + SPIKE_TICKS, Undo::Force(k)));
                            ChannelFault::Adds(n)
                        }
                        // Halfway between the rated maximum and the count the
                        // driver takes for a short.
                        _ => {
                            let short_n = (f64::from(exogait_device::sensors::SHORT_ABOVE_COUNTS)
                                - f64::from(spec.zero_counts))
                                / f64::from(spec.counts_per_n);
                            let max = f64::from(spec.rated_max_n);
                            ChannelFault::Reads(max + 0.5 * (short_n - max))
                        }
                    };
                    self.adc.set_fault(k, Some(fault));
                }
            }
            Kind::AdcBus => self
                .adc
                .fail_transactions(u32::MAX, embedded_hal::spi::ErrorKind::Other),
            Kind::MotorWeak(share) => {
                if let Some(m) = &motor {
                    m.weaken(share);
                }
            }
            Kind::GearSlip(share) => {
                if let Some(m) = &motor {
                    m.slip_gear(share);
                }
            }
            Kind::MotorStuck => {
                if let Some(m) = &motor {
                    m.stick();
                }
            }
            Kind::PwmFail => {
                if let Some(m) = &motor {
                    m.fail_pwm_writes(u32::MAX);
                }
            }
            Kind::DirFail => {
                if let Some(m) = &motor {
                    m.fail_pin_writes(BridgePin::Direction, u32::MAX);
                }
            }
            Kind::CurrentOpen | Kind::CurrentShort => {
                let channel = match (self.wiring.current_monitor, target) {
                    (Some((_, channels)), Some(Target::Joint(j))) => channels.get(j).copied(),
                    _ => None,
                };
                if let Some(ch) = channel {
                    let fault = if f.kind == Kind::CurrentOpen {
                        ChannelFault::Open
                    } else {
                        ChannelFault::Short
                    };
                    self.adc.set_fault(ch, Some(fault));
                }
            }
            Kind::EStop => self.e_stop.set_pressed(true),
            Kind::EStopRead => self.e_stop.fail_reads(u32::MAX),
            Kind::ButtonRead => {
                self.mode.fail_reads(u32::MAX);
                self.go.fail_reads(u32::MAX);
            }
            Kind::Overrun(n) => self.faults.overruns_left = n,
            Kind::PilotLean(rad) => self.faults.pilot_lean_rad += rad,
            Kind::PilotStopsBalancing => {
                self.set_pilot_behaviour(PilotBehaviour::Fixed(PilotTarget::Off));
            }
            Kind::Panic(boot_ms) => self.panic_reset(now, boot_ms),
            Kind::ReplanTimeout | Kind::ReplanRefused => {
                if let Some(r) = &mut self.replanner {
                    r.sabotage = Some(f.kind);
                }
            }
        }
    }
}

/// How long an injected force spike lasts, ticks.
const SPIKE_TICKS: u64 = 3;

/// The pilot's target with the stance shank `lean` further forward (an
/// injected lean; profiles the pilot times itself are left as they are).
pub(crate) fn leaned(target: PilotTarget, lean: f64) -> PilotTarget {
    if lean == 0.0 {
        return target;
    }
    match target {
        PilotTarget::Hold { phi1_rad } => PilotTarget::Hold {
            phi1_rad: phi1_rad + lean,
        },
        PilotTarget::Track {
            phi1_rad,
            rate_rad_s,
            t0_s,
        } => PilotTarget::Track {
            phi1_rad: phi1_rad + lean,
            rate_rad_s,
            t0_s,
        },
        other => other,
    }
}

//! *sense*: decode, calibrate and check what the acquisition read of every
//! encoder, force sensor and one drive's current monitor
//! ([`crate::acquisition`]); read the buttons and the e-stop. A failed
//! read becomes a status, never a panic, and the last good angle is kept
//! for control.

use embedded_hal::digital::InputPin;

use crate::acquisition::Frames;
use crate::drivers::as5048a;
use crate::drivers::buttons::Sample;
use crate::layout::{encoder, force};
use crate::posture::JOINTS;
use crate::sequencer::Sensed;
use crate::supervisor::{
    DriveCurrentSense, EncoderFrame, EncoderSense, EncoderStatus, ForceSense, ForceStatus,
};

use super::{Controller, ENCODERS, FORCES, Hardware};

/// What *sense* read this tick.
pub(super) struct Senses {
    /// Each encoder's frame as the supervisor checks it.
    pub encoders: [EncoderSense; ENCODERS],
    /// The supervisor's classification of each (its check goes on from it).
    pub frames: [EncoderFrame; ENCODERS],
    /// Each force sensor's sample as the supervisor checks it.
    pub forces: [ForceSense; FORCES],
    /// This tick's drive-current sample.
    pub drive_current: DriveCurrentSense,
    /// Debounced MODE and GO.
    pub mode: Sample,
    pub go: Sample,
    /// E-stop pressed (also when it could not be read), and whether the
    /// read failed.
    pub e_stop_pressed: bool,
    pub e_stop_read_error: bool,
    /// Joints whose angle (and rate) comes from the closed chain this
    /// tick ([`Controller::close_chain`]).
    pub chain_closed: [bool; JOINTS],
    /// The joint (and angle) whose chain estimate settled this tick.
    pub chain_hold: Option<(usize, f32)>,
    /// Joints whose encoder the supervisor has found lost.
    pub lost: [bool; JOINTS],
    /// Calibrated forces (NaN if faulted), N.
    pub forces_n: [f32; FORCES],
    /// What the sequencer needs of it. Its joints are the last good
    /// angles (joint order, rad), a lost encoder's from the closed chain
    /// when it gives it: what control and the holds use.
    pub sensed: Sensed,
}

pub(super) const BAD_ENCODER: EncoderSense = EncoderSense {
    status: EncoderStatus::BusError,
    raw_counts: 0,
    angle_rad: f32::NAN,
};

impl Controller<'_> {
    /// Stage 1.
    #[inline(always)]
    pub(super) fn sense<ENC, ADC, PWM, DIR, EN, IN, OUT>(
        &mut self,
        hw: &mut Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
        acquired: &Frames,
    ) -> Senses
    where
        IN: InputPin,
    {
        let lost = self.supervisor.angle_lost_joints();
        let alpha = self.rate_alpha;
        let (encoders, frames) = self.read_encoders(hw, acquired, &lost, alpha);
        let forces = self.read_forces(acquired);
        let drive_current = self.read_drive_current(acquired);
        let forces_n = forces.map(|f| f.newtons);
        let (chain_closed, chain_hold) = self.close_chain(&forces_n, &lost, alpha);
        let mode = hw.mode.tick();
        let go = hw.go.tick();
        let (e_stop_pressed, e_stop_read_error) = match hw.e_stop.is_high() {
            Ok(high) => (high == self.cfg.e_stop_active_high, false),
            Err(_) => (true, true),
        };
        let joints = self.joint_angles();
        let sensed = Sensed {
            joints_rad: joints,
            feet_n: force::FEET.map(|i| forces_n.get(i).copied().unwrap_or(f32::NAN)),
            crutches_n: force::CRUTCHES.map(|i| forces_n.get(i).copied().unwrap_or(f32::NAN)),
            // This tick's readings (NaN unless the frame was taken): a held
            // last-good value must not count as "ready".
            ankles_rad: encoder::OF_ANKLES.map(|i| match (self.last_angle.get(i), frames.get(i)) {
                (Some(&a), Some(f)) if f.usable() => a,
                _ => f32::NAN,
            }),
        };
        Senses {
            encoders,
            frames,
            forces,
            drive_current,
            mode,
            go,
            e_stop_pressed,
            e_stop_read_error,
            chain_closed,
            chain_hold,
            lost,
            forces_n,
            sensed,
        }
    }

    /// Each encoder's frame as the supervisor will check it, and whether
    /// control takes it: only the frames the supervisor takes
    /// ([`crate::supervisor::Supervisor::take_encoder`]) move the
    /// angles and rates control uses; otherwise the last taken one holds.
    /// Nor do those of an encoder the supervisor has found `lost` (a
    /// frozen one's frames are valid). `alpha` is the rates' low-pass
    /// (`rate_alpha`).
    fn read_encoders<ENC, ADC, PWM, DIR, EN, IN, OUT>(
        &mut self,
        hw: &Hardware<ENC, ADC, PWM, DIR, EN, IN, OUT>,
        acquired: &Frames,
        lost: &[bool; JOINTS],
        alpha: f32,
    ) -> ([EncoderSense; ENCODERS], [EncoderFrame; ENCODERS]) {
        let mut out = [BAD_ENCODER; ENCODERS];
        let mut frames = [EncoderFrame::NONE; ENCODERS];
        let dt = self.cfg.dt_s;
        let offsets = self.supervisor.encoder_offsets();
        for (i, (o, frame)) in out.iter_mut().zip(frames.iter_mut()).enumerate() {
            let reply = acquired.encoders.get(i).copied().flatten();
            let result = match (reply, hw.encoders.get(i)) {
                (Some(reply), Some(enc)) => as5048a::decode_angle(reply, enc.calibration()),
                _ => Err(EncoderStatus::BusError),
            };
            *o = match &result {
                Ok(r) => EncoderSense {
                    status: EncoderStatus::Ok,
                    raw_counts: r.raw_counts,
                    angle_rad: r.angle_rad,
                },
                Err(status) => EncoderSense {
                    status: *status,
                    raw_counts: self.last_raw.get(i).copied().unwrap_or(0),
                    angle_rad: f32::NAN,
                },
            };
            *frame = self.supervisor.take_encoder(i, o);
            let took = frame.usable();
            if let Some(n) = self.untaken.get_mut(i) {
                *n = if took { 0 } else { n.saturating_add(1) };
            }
            let trusted = !lost.get(i).copied().unwrap_or(false);
            if let (Ok(r), true) = (&result, took && trusted) {
                let angle = if offsets {
                    self.supervisor.encoder_angle(i, r.angle_rad)
                } else {
                    r.angle_rad
                };
                if let (Some(last), Some(raw)) =
                    (self.last_angle.get_mut(i), self.last_raw.get_mut(i))
                {
                    if let Some(rate) = self.rate.get_mut(i) {
                        let raw_rate = if self.primed {
                            (angle - *last) / dt
                        } else {
                            0.0
                        };
                        *rate += alpha * (raw_rate - *rate);
                    }
                    *last = angle;
                    *raw = r.raw_counts;
                }
            }
        }
        (out, frames)
    }

    /// Each force sensor's acquired counts, calibrated and checked.
    fn read_forces(&self, acquired: &Frames) -> [ForceSense; FORCES] {
        let mut out = [ForceSense {
            status: ForceStatus::BusError,
            newtons: f32::NAN,
        }; FORCES];
        for ((o, counts), cal) in out
            .iter_mut()
            .zip(acquired.forces)
            .zip(&self.cfg.force_calibration)
        {
            if let Some(counts) = counts {
                *o = match cal.convert(counts) {
                    Ok(newtons) => ForceSense {
                        status: ForceStatus::Ok,
                        newtons,
                    },
                    Err(f) => ForceSense {
                        status: f.status(),
                        newtons: f32::NAN,
                    },
                };
            }
        }
        out
    }

    /// The drive current monitor the acquisition read: one a tick, in turn
    /// (each every [`JOINTS`] ticks: one ADC conversion, not four, in an
    /// acquisition).
    fn read_drive_current(&self, acquired: &Frames) -> DriveCurrentSense {
        let joint = acquired.drive_joint;
        let Some(cal) = self.cfg.drive_current_calibration.get(usize::from(joint)) else {
            return DriveCurrentSense::default();
        };
        let (status, torque_nm) = match acquired.drive_current.map(|c| cal.convert(c)) {
            Some(Ok(nm)) => (ForceStatus::Ok, nm),
            Some(Err(f)) => (f.status(), f32::NAN),
            None => (ForceStatus::BusError, f32::NAN),
        };
        DriveCurrentSense {
            joint,
            status,
            torque_nm,
        }
    }

    /// Last good joint angles (joint order).
    fn joint_angles(&self) -> [f32; JOINTS] {
        encoder::OF_JOINTS.map(|i| self.last_angle.get(i).copied().unwrap_or(f32::NAN))
    }
}

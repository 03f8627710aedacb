//! Each hip and knee drive's current against its command (0x0405), and
//! the current monitors themselves (0x0406).
//!
//! The servo amplifier reports the current it drives on an analog output,
//! read on the force ADC's spare channels, one drive a tick in turn. A
//! drive stuck on an old set value, or one that gives only a share of the
//! current asked (a failing power stage, a lost phase, a current limit
//! set wrong), shows it in its own current within a few samples, at its
//! own joint. The torque residual (0x0404) sees the same faults only
//! through the motion, after tens to hundreds of milliseconds, and often
//! first at a joint the faulted one dragged (`docs/safety.md`). What the
//! monitor cannot see — a gearbox that slips, an amplifier whose own
//! current sensing is wrong — is still 0x0404's.
//!
//! The sample is compared with the torque the drive was given at the last
//! tick (what it was executing when the ADC sampled it). A drive gives
//! less than asked, legitimately, where its supply cannot push the current
//! against the motor's back-EMF: moving fast in the direction of its
//! torque. Under-delivery there is not counted.

use super::findings::Findings;
use super::tracks::SampleWindow;
use super::windowed::WindowedChecks;
use super::*;

/// Settings of the drive-current check.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriveCurrentCheck {
    /// Mismatch allowed whatever the command, N·m (the monitor's noise and
    /// offset, the current loop's lag behind a slewing set value).
    pub band_nm: f32,
    /// Mismatch allowed as a share of |command| (the tolerances of the
    /// amplifier's set-value and monitor gains).
    pub band_share: f32,
    /// Consecutive mismatching samples of one drive that make 0x0405.
    pub samples: u8,
    /// Joint speed up to which the drive gives its full torque, rad/s: the
    /// torque–speed line's corner (`DriveSpec::full_torque_speed_rad_s`).
    pub full_torque_speed_rad_s: f32,
    /// Share of that speed above which, moving in the torque's direction,
    /// under-delivery is not counted (the supervisor's velocity lags the
    /// joint's by a few milliseconds).
    pub back_emf_speed_share: f32,
    /// Bad samples (bus, open, short) of one monitor that make 0x0406,
    /// counted over that monitor's own samples (a value reported Ok but
    /// not finite makes it at once).
    pub debounce: Debounce,
}

impl DriveCurrentCheck {
    /// 10 N·m and 10 %, three samples in a row (9–12 ticks at one drive
    /// every 4 ticks). The command and the monitor both scale through the
    /// same amplifier, so the motor's torque constant cancels: what is left
    /// is the monitor's offset and gain (about 2 % of its ±12 A, 3 N·m),
    /// the ADC's noise (±10 counts, 0.9 N·m) and the current loop's lag
    /// behind a 15 N·m slew (a fraction of a tick). In the simulator even
    /// 4 N·m and 3 % never trip in 90 noisy healthy runs. Full torque to
    /// 2.2 rad/s (the device's drive), under-delivery counted below 70 %
    /// of it; a broken monitor after 3 bad samples among its last 25 (100
    /// ticks).
    pub const DEFAULT: Self = Self {
        band_nm: 10.0,
        band_share: 0.10,
        samples: 3,
        full_torque_speed_rad_s: 2.2,
        back_emf_speed_share: 0.7,
        debounce: Debounce {
            count: 3,
            window_ticks: 25,
        },
    };

    /// Whether every value is finite and in range.
    pub(super) fn is_valid(&self) -> bool {
        let positive = [self.band_nm, self.full_torque_speed_rad_s];
        let shares = [self.band_share, self.back_emf_speed_share];
        positive.iter().all(|v| v.is_finite() && *v > 0.0)
            && shares.iter().all(|v| (0.0..=1.0).contains(v))
            && self.samples > 0
    }
}

/// One drive's current-monitor sample this tick (one drive a tick, in
/// turn), as joint torque.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DriveCurrentSense {
    /// The joint whose drive was sampled (joint order).
    pub joint: u8,
    /// What the driver reported.
    pub status: ForceStatus,
    /// The drive's current as joint torque, N·m (flexion positive);
    /// ignored unless `status` is `Ok`.
    pub torque_nm: f32,
}

/// What the supervisor remembers of one drive's monitor.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct DriveCurrentTrack {
    window: SampleWindow,
    /// Consecutive samples whose current did not match the command.
    mismatches: u8,
}

impl WindowedChecks {
    pub(super) fn check_drive_current(&mut self, input: &SupervisorInput, f: &mut Findings) {
        let Some(s) = input.drive_current else {
            return;
        };
        let i = usize::from(s.joint);
        let c = &self.cfg.drive_current;
        let (Some(track), Some(motor), Some(joint)) = (
            self.drive_currents.get_mut(i),
            input.motors.get(i),
            self.joints.get(i),
        ) else {
            return;
        };
        // A value reported Ok that is not finite is no reading at all: at
        // once, like a force sensor's.
        let not_finite = s.status == ForceStatus::Ok && !s.torque_nm.is_finite();
        let bad = s.status != ForceStatus::Ok || not_finite;
        track.window.push(bad, c.debounce.window_ticks);
        let n = track.window.count();
        if not_finite {
            f.raise(FaultCode::DriveCurrentMonitor, s.joint, s.torque_nm);
        } else if n >= u32::from(c.debounce.count) {
            f.raise(FaultCode::DriveCurrentMonitor, s.joint, n as f32);
        }
        // A disabled drive's amplifier gives no current (its brake's flows
        // through the contactor): nothing to compare.
        if bad || !motor.enabled {
            track.mismatches = 0;
            return;
        }
        let asked = motor.applied_nm;
        let along = if asked < 0.0 { -1.0 } else { 1.0 };
        // The current along the torque asked, against its magnitude.
        let got = s.torque_nm * along;
        let band = c.band_nm + c.band_share * asked.abs();
        let speed = if joint.velocity_valid {
            joint.velocity_rad_s * along
        } else {
            0.0
        };
        let short =
            got < asked.abs() - band && speed < c.back_emf_speed_share * c.full_torque_speed_rad_s;
        let over = got > asked.abs() + band;
        track.mismatches = if short || over {
            track.mismatches.saturating_add(1)
        } else {
            0
        };
        if track.mismatches >= c.samples {
            f.raise(
                FaultCode::DriveCurrentMismatch,
                s.joint,
                s.torque_nm - asked,
            );
        }
    }
}

//! Whether the device can play a gait table: every sample inside the
//! supervisor's envelope, every hip and knee slower than the supervisor's
//! limit and than the drive can turn, and the torque the controller's
//! feed-forward plans for it (gait-core's playback: the motion's inverse
//! dynamics with the other foot's planned share of the load) within what
//! the drive gives at that speed. A table that fails is refused before it
//! is played, naming the sample, the joint and the limit.

use gait_core::foot::StanceFoot;
use gait_core::kinematics::{anatomical_angles, theta_from_phi};
use gait_core::playback::{self, PlaybackError};
use gait_core::tables::GaitTable;

use crate::DeviceConfig;

/// A hip or knee by its role in the step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RoleJoint {
    /// The stance leg's knee.
    StanceKnee,
    /// The stance leg's hip.
    StanceHip,
    /// The swing leg's hip.
    SwingHip,
    /// The swing leg's knee.
    SwingKnee,
    /// The stance ankle.
    StanceAnkle,
}

impl RoleJoint {
    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Self::StanceKnee => "stance knee",
            Self::StanceHip => "stance hip",
            Self::SwingHip => "swing hip",
            Self::SwingKnee => "swing knee",
            Self::StanceAnkle => "stance ankle",
        }
    }
}

/// Which limit a sample breaks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Limit {
    /// The angle leaves the supervisor's envelope [min, max], rad.
    Angle {
        /// Lowest allowed, rad.
        min_rad: f32,
        /// Highest allowed, rad.
        max_rad: f32,
    },
    /// The speed is above the supervisor's limit or the drive's no-load
    /// speed, rad/s.
    Speed {
        /// Highest allowed, rad/s.
        max_rad_s: f32,
    },
    /// The planned torque is above what the drive gives at that speed, N·m.
    Torque {
        /// What the drive gives, N·m.
        max_nm: f32,
    },
}

/// Why a table is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Refusal {
    /// Sample `sample` (at `time_s`) breaks `limit` at `joint` with `value`.
    Breaks {
        /// Sample index.
        sample: usize,
        /// Time since the table's start, s.
        time_s: f32,
        /// The joint.
        joint: RoleJoint,
        /// The value (rad, rad/s or N·m).
        value: f32,
        /// The limit it breaks.
        limit: Limit,
    },
    /// The table cannot be played through the model at all.
    Playback(PlaybackError),
}

impl From<PlaybackError> for Refusal {
    fn from(e: PlaybackError) -> Self {
        Self::Playback(e)
    }
}

impl core::fmt::Display for Refusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Breaks {
                sample,
                time_s,
                joint,
                value,
                limit,
            } => {
                write!(f, "sample {sample} ({time_s:.2} s): {} ", joint.name())?;
                match limit {
                    Limit::Angle { min_rad, max_rad } => write!(
                        f,
                        "at {:.1}°, outside the supervisor's envelope [{:.1}°, {:.1}°]",
                        value.to_degrees(),
                        min_rad.to_degrees(),
                        max_rad.to_degrees()
                    ),
                    Limit::Speed { max_rad_s } => write!(
                        f,
                        "turning at {value:.2} rad/s, above the limit of {max_rad_s:.2} rad/s"
                    ),
                    Limit::Torque { max_nm } => write!(
                        f,
                        "needs {value:.1} N·m, above the {max_nm:.1} N·m its drive gives at that speed"
                    ),
                }
            }
            Self::Playback(e) => write!(f, "the table cannot be played: {e:?}"),
        }
    }
}

/// What the table asks of the device at its most demanding samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Demand {
    /// Largest planned |torque| of stance knee, stance hip, swing hip,
    /// swing knee, N·m.
    pub peak_torque_nm: [f32; 4],
    /// Largest |speed| of the same, rad/s.
    pub peak_speed_rad_s: [f32; 4],
    /// Largest share of the available torque any of them uses.
    pub drive_use: f32,
}

/// Checks `table` against `cfg` (see the module documentation). Bounded:
/// one pass over the table's samples.
pub fn check_table(cfg: &DeviceConfig, table: &GaitTable<'_>) -> Result<Demand, Refusal> {
    check_samples(cfg, table.len(), table.period_s(), |k| table.sample(k))
}

/// [`check_table`] for the samples `sample(0 … len − 1)` taken every
/// `period_s` wherever they are kept (a step re-planned on the board is
/// checked by the same rule before it is played).
pub fn check_samples(
    cfg: &DeviceConfig,
    len: usize,
    period_s: f32,
    sample: impl Fn(usize) -> Option<[f32; 5]>,
) -> Result<Demand, Refusal> {
    let model = cfg.controller.model;
    let foot = StanceFoot::for_model(&model);
    let sv = &cfg.supervisor;
    let [hip, knee, ..] = sv.joint_range;
    let [ankle, _] = sv.ankle_range;
    let drive = &cfg.drives[1];
    let no_load = drive.no_load_speed_rad_s();
    let zero = theta_from_phi(&[0.0f32; 5]);
    let mut demand = Demand {
        peak_torque_nm: [0.0; 4],
        peak_speed_rad_s: [0.0; 4],
        drive_use: 0.0,
    };
    let roles = [
        (RoleJoint::StanceKnee, knee, 1usize),
        (RoleJoint::StanceHip, hip, 0),
        (RoleJoint::SwingHip, hip, 2),
        (RoleJoint::SwingKnee, knee, 3),
    ];
    playback::for_each_sample::<f32, Refusal>(
        &model,
        &foot,
        cfg.ankle_spring_nm_per_rad as f32,
        len,
        period_s,
        sample,
        |s| {
            let breaks = |joint, value, limit| Refusal::Breaks {
                sample: s.k,
                time_s: s.t_s,
                joint,
                value,
                limit,
            };
            let angles = anatomical_angles(&theta_from_phi(&s.phi));
            let rates = theta_from_phi(&s.dphi);
            // The stance ankle reads φ1 up to its stop (the heel lifts
            // beyond it): only its plantarflexion side can leave.
            let [phi1, ..] = s.phi;
            if phi1 < ankle.min_rad {
                return Err(breaks(
                    RoleJoint::StanceAnkle,
                    phi1,
                    Limit::Angle {
                        min_rad: ankle.min_rad,
                        max_rad: ankle.max_rad,
                    },
                ));
            }
            for (j, &(joint, range, limit_index)) in roles.iter().enumerate() {
                let i = j + 1;
                let (Some(&q), Some(&r), Some(&z), Some(&t)) =
                    (angles.get(i), rates.get(i), zero.get(i), s.torques.get(i))
                else {
                    continue;
                };
                if q < range.min_rad || q > range.max_rad {
                    return Err(breaks(
                        joint,
                        q,
                        Limit::Angle {
                            min_rad: range.min_rad,
                            max_rad: range.max_rad,
                        },
                    ));
                }
                let rate = r - z;
                let max_speed = sv
                    .velocity_limit_rad_s
                    .get(limit_index)
                    .copied()
                    .unwrap_or(0.0)
                    .min(no_load);
                if rate.abs() > max_speed {
                    return Err(breaks(
                        joint,
                        rate.abs(),
                        Limit::Speed {
                            max_rad_s: max_speed,
                        },
                    ));
                }
                let sign = if t >= 0.0 { 1.0 } else { -1.0 };
                let available = drive.available_torque_nm(rate, sign);
                if t.abs() > available {
                    return Err(breaks(joint, t.abs(), Limit::Torque { max_nm: available }));
                }
                if let (Some(pt), Some(ps)) = (
                    demand.peak_torque_nm.get_mut(j),
                    demand.peak_speed_rad_s.get_mut(j),
                ) {
                    *pt = pt.max(t.abs());
                    *ps = ps.max(rate.abs());
                }
                if available > 0.0 {
                    demand.drive_use = demand.drive_use.max(t.abs() / available);
                }
            }
            Ok(())
        },
    )?;
    Ok(demand)
}

//! What playing a gait table asks of the device and of the pilot, sample by
//! sample: the one model of "the other foot's share of the load" and of "the
//! pilot's ankle torque" that the controller's feed-forward, the table
//! generator's crutch-load cost, the admission check of a table and the
//! open-loop figures of `exogait compare` all use.
//!
//! - **The other foot's share.** A table's swing foot carries load while it
//!   is planned on the ground: while its toe ([`swing_toe`]; a planted
//!   trailing foot may roll on it) is within [`FOOT_DOWN_M`] of where it
//!   started (the paper's 2 mm contact threshold), all of it may be used;
//!   the cap falls smoothly to nothing at [`FOOT_LIFTED_M`]. A table that
//!   keeps the swing foot down for a while plans a weight shift in double
//!   support before the lift-off.
//! - **Sharing.** The inverse dynamics of the table's motion on the stance
//!   foot, then the least-effort ground force on the other foot within its
//!   cap ([`crate::dynamics::share_load`], ankle weighted as the pilot's).
//! - **The pilot.** What remains at the stance ankle, less the passive
//!   ankle spring's torque, is the pilot's: pushed through the crutches.
//!
//! Rates are central differences over one table period (the controller's
//! feed-forward uses the same), zero at the first and last sample (tables
//! start and end at rest).

use crate::dynamics::{self, Contact};
use crate::foot::StanceFoot;
use crate::kinematics::{Phi, Posture, joint_torques};
use crate::model::{BodyModel, GRAVITY_M_S2, LINKS};
use crate::scalar::Real;

/// The swing foot is down, and may carry the whole body, while its ankle is
/// within this of its start point, m (the paper's contact threshold).
pub const FOOT_DOWN_M: f64 = 0.002;
/// It carries nothing once it is this far from it, m.
pub const FOOT_LIFTED_M: f64 = 0.012;

/// Share (0 … 1) of the body's weight the swing foot may carry with its
/// toe ([`swing_toe`]) at `toe` and where it started at `toe_start` (both
/// in the stance foot's flat frame): 1 within [`FOOT_DOWN_M`], 0 beyond
/// [`FOOT_LIFTED_M`], a smoothstep between.
pub fn other_foot_share<T: Real>(toe: [T; 2], toe_start: [T; 2]) -> T {
    let dx = toe[0] - toe_start[0];
    let dy = toe[1] - toe_start[1];
    let d = (dx * dx + dy * dy).sqrt();
    let (down, lifted) = (T::lit(FOOT_DOWN_M), T::lit(FOOT_LIFTED_M));
    if !d.finite() {
        return T::zero();
    }
    let x = ((d - down) / (lifted - down)).max(T::zero()).min(T::one());
    T::one() - x * x * (T::lit(3.0) - T::lit(2.0) * x)
}

/// The swing ankle in the stance foot's flat frame (the stance ankle may
/// have rolled onto its toe), m.
pub fn swing_ankle<T: Real>(model: &BodyModel<T>, foot: &StanceFoot<T>, phi: &Phi<T>) -> [T; 2] {
    let [.., p5] = foot.points(model, phi);
    p5
}

/// The ball of the swing foot (its toe pivot) in the stance foot's flat
/// frame, m: ahead of and below the ankle while the foot is flat; where the
/// foot stands when its shank leans past the ankle's stop (a trailing foot
/// on its toe, [`crate::foot`]). A planted trailing foot keeps this point
/// still while its ankle rolls about it.
pub fn swing_toe<T: Real>(model: &BodyModel<T>, foot: &StanceFoot<T>, phi: &Phi<T>) -> [T; 2] {
    swing_toe_at(model, foot, &Posture::new(phi))
}

/// [`swing_toe`] at a posture whose sines are known.
pub fn swing_toe_at<T: Real>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    posture: &Posture<T>,
) -> [T; 2] {
    let [.., phi5] = posture.phi;
    let lean = crate::kinematics::wrap_pi(phi5 - T::pi());
    let [.., p5] = foot.points_at(model, posture);
    let toe = foot.toe();
    let a = foot.ankle(lean).position_m;
    [p5[0] + toe[0] - a[0], p5[1] + toe[1] - a[1]]
}

/// The pilot's torque on the stance ankle (dorsiflexion positive, N·m)
/// when the chain needs the joint torques `t_theta` (T_Θ, after sharing):
/// the ankle needs T_θ1 = −(pilot + spring), and while the foot is flat the
/// exoskeleton's passive spring (`spring_nm_per_rad`, relaxed at 0) gives
/// −k φ1; on the toe it acts inside the foot and gives nothing.
pub fn pilot_torque<T: Real>(
    foot: &StanceFoot<T>,
    phi1: T,
    t_theta: &[T; LINKS],
    spring_nm_per_rad: T,
) -> T {
    let spring = if foot.on_toe(phi1) {
        T::zero()
    } else {
        -spring_nm_per_rad * phi1
    };
    let [ankle, ..] = *t_theta;
    -ankle - spring
}

/// One sample of a table as the device plays it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlaybackSample<T> {
    /// Sample index.
    pub k: usize,
    /// Time since the table's start, s.
    pub t_s: T,
    /// Φ, rad.
    pub phi: Phi<T>,
    /// Φ̇, rad/s.
    pub dphi: Phi<T>,
    /// Φ̈, rad/s².
    pub ddphi: Phi<T>,
    /// The other foot's share of the body's weight it may carry, 0 … 1.
    pub other_share: T,
    /// Ground force on the other foot, (x, y), N.
    pub reaction_n: [T; 2],
    /// Joint torques T_Θ after sharing, N·m (`[0]` the stance pivot).
    pub torques: [T; LINKS],
    /// The pilot's ankle torque, N·m (dorsiflexion positive).
    pub pilot_nm: T,
    /// The swing ankle in the stance foot's flat frame, m.
    pub swing_ankle_m: [T; 2],
}

/// Why a table could not be played through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlaybackError {
    /// Fewer than two samples, or a non-positive period.
    TooShort,
    /// A sample is missing or not finite (its index).
    BadSample(usize),
}

/// Plays the table `sample(0) … sample(len − 1)` at `period_s` on
/// `model` with `foot` and a passive ankle spring, and hands every sample
/// to `visit` (see the module documentation). Bounded: `len` samples, one
/// inverse dynamics and one sharing each.
pub fn for_each_sample<T: Real, E>(
    model: &BodyModel<T>,
    foot: &StanceFoot<T>,
    spring_nm_per_rad: T,
    len: usize,
    period_s: T,
    sample: impl Fn(usize) -> Option<Phi<T>>,
    mut visit: impl FnMut(&PlaybackSample<T>) -> Result<(), E>,
) -> Result<(), E>
where
    E: From<PlaybackError>,
{
    if len < 2 || !(period_s.finite() && period_s > T::zero()) {
        return Err(PlaybackError::TooShort.into());
    }
    let get = |k: usize| {
        sample(k)
            .filter(|p| p.iter().all(|v| v.finite()))
            .ok_or(PlaybackError::BadSample(k))
    };
    let start = swing_toe(model, foot, &get(0)?);
    let weight = model.total_mass_kg() * T::lit(GRAVITY_M_S2);
    let h = period_s;
    for k in 0..len {
        let phi = get(k)?;
        let (dphi, ddphi) = if k == 0 || k + 1 == len {
            ([T::zero(); LINKS], [T::zero(); LINKS])
        } else {
            let (a, c) = (get(k - 1)?, get(k + 1)?);
            let mut d1 = [T::zero(); LINKS];
            let mut d2 = [T::zero(); LINKS];
            for ((((o1, o2), &x0), &x1), &x2) in
                d1.iter_mut().zip(d2.iter_mut()).zip(&a).zip(&phi).zip(&c)
            {
                *o1 = (x2 - x0) / (T::lit(2.0) * h);
                *o2 = (x2 - T::lit(2.0) * x1 + x0) / (h * h);
            }
            (d1, d2)
        };
        let p5 = swing_ankle(model, foot, &phi);
        let share = other_foot_share(swing_toe(model, foot, &phi), start);
        let contact = Contact::ToeRocker(*foot);
        let single = joint_torques(&dynamics::inverse_dynamics(
            model, &contact, &phi, &dphi, &ddphi,
        ));
        let shared = dynamics::share_load(model, &contact, &phi, &single, share * weight);
        let pilot = pilot_torque(foot, phi[0], &shared.torques, spring_nm_per_rad);
        visit(&PlaybackSample {
            k,
            t_s: T::lit(k as f64) * h,
            phi,
            dphi,
            ddphi,
            other_share: share,
            reaction_n: shared.reaction_n,
            torques: shared.torques,
            pilot_nm: pilot,
            swing_ankle_m: p5,
        })?;
    }
    Ok(())
}

//! Power-on self-test: checks that the model code linked into this image
//! computes what the host-verified model computes.
//!
//! Each check compares two independent computations on the target itself
//! (f32 against f64, fast trigonometry against libm, forward against inverse
//! dynamics), so a miscompiled or mislinked image fails here rather than in a
//! pilot's step.

use gait_core::dynamics::Contact::FixedAnkle;
use gait_core::dynamics::{energy, forward_dynamics, inverse_dynamics, rk4_step};
use gait_core::kinematics::{forward_kinematics, phi_from_theta, theta_from_phi};
use gait_core::scalar::sin_cos_f32;
use gait_core::{BodyModel, LINKS};

/// The outcome of one self-test check.
#[derive(Clone, Copy, Debug)]
pub struct Check {
    /// Short name, printed.
    pub name: &'static str,
    /// Measured error (units per check).
    pub value: f64,
    /// Largest accepted error.
    pub bound: f64,
}

impl Check {
    /// `true` when the measured error is finite and within the bound.
    pub fn passed(&self) -> bool {
        self.value.is_finite() && self.value <= self.bound
    }
}

/// Number of checks [`run`] performs.
pub const CHECKS: usize = 7;

/// A swing-phase state away from any symmetry (angles in rad, rates in rad/s).
const PHI: [f64; LINKS] = [0.21, -0.18, 0.07, 2.71, 3.52];
const DPHI: [f64; LINKS] = [0.4, -0.9, 0.2, -2.1, 3.3];
const DDPHI: [f64; LINKS] = [1.5, -2.0, 0.7, 6.0, -9.0];

/// Runs every check and returns the results (none may panic).
pub fn run() -> [Check; CHECKS] {
    let m64 = BodyModel::<f64>::paper_table_iii();
    let m32: BodyModel<f32> = m64.cast();
    let f32s = |a: [f64; LINKS]| a.map(|x| x as f32);

    // 1. Model: Table III standing hip height is l1 + l2.
    let standing = [0.0, 0.0, 0.0, core::f64::consts::PI, core::f64::consts::PI];
    let p = forward_kinematics(&m64, &standing);
    let hip_err = (p[1][1] - (0.441 + 0.395)).abs() + p[1][0].abs();

    // 2. Angle systems: Θ → Φ → Θ.
    let th = theta_from_phi(&PHI);
    let back = phi_from_theta(&th);
    let angle_err = max_abs_diff(&back, &PHI);

    // 3. Fast f32 sine/cosine against libm's f64 over ±10 rad.
    let mut trig_err = 0.0_f64;
    let mut x = -10.0_f32;
    while x <= 10.0 {
        let (s, c) = sin_cos_f32(x);
        let xd = f64::from(x);
        trig_err = trig_err
            .max((f64::from(s) - libm::sin(xd)).abs())
            .max((f64::from(c) - libm::cos(xd)).abs());
        x += 0.01;
    }

    // 4. Inverse dynamics: f32 against f64, relative to the largest torque.
    let t64 = inverse_dynamics(&m64, &FixedAnkle, &PHI, &DPHI, &DDPHI);
    let t32 = inverse_dynamics(&m32, &FixedAnkle, &f32s(PHI), &f32s(DPHI), &f32s(DDPHI));
    let scale = t64.iter().fold(1.0_f64, |a, &t| a.max(t.abs()));
    let t32d = t32.map(f64::from);
    let id_err = max_abs_diff(&t32d, &t64) / scale;

    // 5. Forward dynamics inverts inverse dynamics (f64).
    let dd = forward_dynamics(&m64, &FixedAnkle, &PHI, &DPHI, &t64).unwrap_or([f64::NAN; LINKS]);
    let fd_err = max_abs_diff(&dd, &DDPHI);

    // 6. Energy of the free chain over 0.2 s of RK4 in f32 (relative drift).
    let drift = free_energy_drift_f32(&m32, f32s(PHI), f32s(DPHI));

    // 7. The gait tables in flash pass their CRC and format checks here.
    let bad_tables = [
        gait_core::flash_tables::walk().is_err(),
        gait_core::flash_tables::stair_up().is_err(),
    ]
    .iter()
    .filter(|&&bad| bad)
    .count() as f64;

    [
        Check {
            name: "fk_standing_hip_m",
            value: hip_err,
            bound: 1e-12,
        },
        Check {
            name: "theta_phi_round_trip_rad",
            value: angle_err,
            bound: 1e-12,
        },
        Check {
            name: "sin_cos_f32_abs",
            value: trig_err,
            bound: 3e-7,
        },
        Check {
            name: "inverse_dynamics_f32_rel",
            value: id_err,
            bound: 1e-4,
        },
        Check {
            name: "forward_dynamics_rad_s2",
            value: fd_err,
            bound: 1e-9,
        },
        Check {
            name: "energy_drift_f32_rel",
            value: drift,
            bound: 1e-3,
        },
        Check {
            name: "flash_tables_failing",
            value: bad_tables,
            bound: 0.0,
        },
    ]
}

fn max_abs_diff(a: &[f64; LINKS], b: &[f64; LINKS]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| {
        if (x - y).abs() > m || x.is_nan() {
            (x - y).abs()
        } else {
            m
        }
    })
}

/// RK4 of the unforced chain; returns |E_end − E_0| / |E_0|.
fn free_energy_drift_f32(m: &BodyModel<f32>, mut q: [f32; LINKS], mut w: [f32; LINKS]) -> f64 {
    let zero = [0.0_f32; LINKS];
    let e0 = f64::from(energy(m, &FixedAnkle, &q, &w));
    for _ in 0..200 {
        match rk4_step(m, &FixedAnkle, &q, &w, &zero, 0.001) {
            Ok((q1, w1)) => (q, w) = (q1, w1),
            Err(_) => return f64::NAN,
        }
    }
    let e1 = f64::from(energy(m, &FixedAnkle, &q, &w));
    ((e1 - e0) / e0).abs()
}

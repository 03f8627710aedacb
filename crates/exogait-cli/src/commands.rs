//! One request and one response type per subcommand, and the call into
//! gait-core between them. Inputs and outputs are checked to be finite
//! (JSON cannot carry NaN or infinity, and serde_json would print them as
//! `null`).

use gait_core::BodyModel;
use gait_core::dynamics::{Contact, inverse_dynamics};
use gait_core::ik::{IkSolver, IkTarget};
use gait_core::kinematics::{forward_kinematics, joint_torques};
use serde::{Deserialize, Serialize};

/// Five values, one per link.
type Five = [f64; 5];

/// `exogait dynamics` input.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DynamicsRequest {
    phi: Five,
    dphi: Five,
    ddphi: Five,
}

/// `exogait dynamics` output.
#[derive(Debug, Serialize)]
pub struct DynamicsResponse {
    t_phi: Five,
    t_theta: Five,
}

/// `exogait fk` input.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FkRequest {
    phi: Five,
}

/// `exogait fk` output.
#[derive(Debug, Serialize)]
pub struct FkResponse {
    p: [[f64; 2]; 5],
}

/// `exogait ik` input.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IkRequest {
    x5: f64,
    y5: f64,
    phi1: f64,
    phi3: f64,
    r2: f64,
}

/// `exogait ik` output.
#[derive(Debug, Serialize)]
pub struct IkResponse {
    phi: Five,
    theta: Five,
}

/// `Err` naming the first field that is not finite.
fn check_finite<'a>(fields: impl IntoIterator<Item = (&'a str, &'a [f64])>) -> Result<(), String> {
    for (name, values) in fields {
        if values.iter().any(|v| !v.is_finite()) {
            return Err(format!("{name}: not a finite number"));
        }
    }
    Ok(())
}

/// Inverse dynamics T_Φ and the joint torques T_Θ = Aᵀ T_Φ.
pub fn dynamics(model: &BodyModel<f64>, r: DynamicsRequest) -> Result<DynamicsResponse, String> {
    check_finite([("phi", &r.phi[..]), ("dphi", &r.dphi), ("ddphi", &r.ddphi)])?;
    let t_phi = inverse_dynamics(model, &Contact::FixedAnkle, &r.phi, &r.dphi, &r.ddphi);
    let t_theta = joint_torques(&t_phi);
    check_finite([("t_phi", &t_phi[..]), ("t_theta", &t_theta)])
        .map_err(|e| format!("result overflowed: {e}"))?;
    Ok(DynamicsResponse { t_phi, t_theta })
}

/// Forward kinematics: joint points p1…p5.
pub fn fk(model: &BodyModel<f64>, r: FkRequest) -> Result<FkResponse, String> {
    check_finite([("phi", &r.phi[..])])?;
    let p = forward_kinematics(model, &r.phi);
    check_finite([("p", p.as_flattened())]).map_err(|e| format!("result overflowed: {e}"))?;
    Ok(FkResponse { p })
}

/// Inverse kinematics of the paper's section III-B.
pub fn ik(solver: &IkSolver<f64>, r: IkRequest) -> Result<IkResponse, String> {
    check_finite([
        ("x5", &[r.x5][..]),
        ("y5", &[r.y5]),
        ("phi1", &[r.phi1]),
        ("phi3", &[r.phi3]),
        ("r2", &[r.r2]),
    ])?;
    let target = IkTarget {
        x5: r.x5,
        y5: r.y5,
        phi1: r.phi1,
        phi3: r.phi3,
        r2: r.r2,
    };
    let sol = solver.solve(&target).map_err(|e| e.to_string())?;
    Ok(IkResponse {
        phi: sol.phi,
        theta: sol.theta,
    })
}

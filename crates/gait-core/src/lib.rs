//! gait-core: the exoskeleton's sagittal 5-link model and everything computed
//! from it — angle systems, forward and inverse kinematics, Lagrangian
//! dynamics, Bézier gait description and the paper's ankle-torque cost.
//!
//! Source: Wong et al., "Upper Extremity Load Reduction for Lower Limb
//! Exoskeleton Trajectory Generation Using Ankle Torque Minimization"
//! (`shared/paper/ankle-torque-minimization.tex`). Each function that
//! implements a paper equation names it; where the printed equation is wrong
//! or ambiguous, the choice made is in `docs/model.md` and tested.
//!
//! `no_std`, no heap, no panics: every fallible operation returns a typed
//! error. One scalar type parameter ([`Real`]) runs the same code in `f32` on
//! the Cortex-M4F and in `f64` on the host.
#![no_std]
#![cfg_attr(test, allow(clippy::needless_range_loop, clippy::approx_constant))]

pub mod anthropometry;
pub mod bezier;
pub mod bundle;
pub mod clinical;
pub mod dynamics;
pub mod fingerprint;
pub mod flash_tables;
pub mod foot;
pub mod gait;
pub mod ik;
pub mod kinematics;
pub mod model;
pub mod playback;
pub mod problem;
pub mod reach;
pub mod replan;
pub mod scalar;
pub mod tables;

pub use model::{BodyModel, JointLimits, LINKS, Link, ModelError};
pub use scalar::Real;

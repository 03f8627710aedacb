//! Fault-table rows of the force sensors, the e-stop and buttons, the
//! tick's deadline and the control values.

use crate::supervisor::support::*;

fn bad_force(status: ForceStatus, code: FaultCode) {
    let (_, v) = inject(10, |_, input| input.forces[2].status = status);
    assert_row(&v, code, Reaction::FinishStepThenHold, 3);
}

#[test]
fn row_force_bus_error() {
    bad_force(ForceStatus::BusError, FaultCode::ForceBusError);
}

#[test]
fn row_force_open() {
    bad_force(ForceStatus::Open, FaultCode::ForceOpen);
}

#[test]
fn row_force_shorted() {
    bad_force(ForceStatus::Shorted, FaultCode::ForceShorted);
}

#[test]
fn row_force_out_of_range() {
    bad_force(ForceStatus::OutOfRange, FaultCode::ForceOutOfRange);
    // Reported Ok but outside the configured rated range.
    let (_, v) = inject(10, |_, input| input.forces[0].newtons = 5000.0);
    assert_row(
        &v,
        FaultCode::ForceOutOfRange,
        Reaction::FinishStepThenHold,
        3,
    );
    // Not finite: at once.
    let (_, v) = inject(10, |_, input| input.forces[0].newtons = f32::NAN);
    assert_row(
        &v,
        FaultCode::ForceOutOfRange,
        Reaction::FinishStepThenHold,
        1,
    );
}

#[test]
fn row_e_stop_pressed() {
    let (_, v) = inject(3, |_, input| input.e_stop_pressed = true);
    assert_row(&v, FaultCode::EStopPressed, Reaction::DisableMotors, 1);
}

#[test]
fn row_e_stop_input_fault() {
    let (_, v) = inject(3, |_, input| input.e_stop_read_error = true);
    assert_row(&v, FaultCode::EStopInputFault, Reaction::DisableMotors, 1);
}

#[test]
fn row_button_input_fault() {
    let (_, v) = inject(3, |_, input| input.button_input_fault = true);
    assert_row(
        &v,
        FaultCode::ButtonInputFault,
        Reaction::FinishStepThenHold,
        1,
    );
}

#[test]
fn row_deadline_missed() {
    // Third miss within 1000 ticks trips.
    let (sup, v) = inject(600, |k, input| {
        input.deadline_missed = [1, 2, 500].contains(&k);
    });
    assert_row(&v, FaultCode::DeadlineMissed, Reaction::SafeHold, 500);
    assert_eq!(sup.deadline_misses(), 3);
}

#[test]
fn sparse_deadline_misses_only_count() {
    let (sup, v) = inject(3000, |k, input| input.deadline_missed = k % 600 == 1);
    assert!(v.iter().all(|v| v.latched.is_empty()));
    assert_eq!(sup.deadline_misses(), 5);
}

#[test]
fn row_control_value_invalid() {
    let (_, v) = inject(3, |_, input| input.motors[1].commanded_nm = f32::NAN);
    assert_row(&v, FaultCode::ControlValueInvalid, Reaction::SafeHold, 1);
    let (_, v) = inject(3, |_, input| input.joint_reference_rad[0] = f32::NAN);
    assert_eq!(detected_at(&v, FaultCode::ControlValueInvalid), Some(1));
    let (_, v) = inject(3, |_, input| input.motors[2].limit_nm = 0.0);
    assert_eq!(detected_at(&v, FaultCode::ControlValueInvalid), Some(1));
}

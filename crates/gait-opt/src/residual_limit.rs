//! The stance hip's torque-residual limit a generated gait carries
//! (0x0404, `GaitTable::with_stance_hip_residual_nm`): the peak its healthy
//! closed loop shows there (`sim::residual`), with a margin, held within
//! the device's bounds (`ResponseCheck::stance_hip_min_nm` to
//! `ResponseCheck::limit_nm`). A gait that leaves room below the device's
//! limit has a slipping stance hip caught sooner; a brisk one keeps the
//! device's limit.

use exogait_device::DeviceConfig;
use gait_control::supervisor::ResponseCheck;
use gait_core::tables::GaitTable;

/// The margin over the healthy peak, N·m: over the 10 noise seeds
/// (`sim::residual::NOISE_SEEDS`) a gait's peak is within a few N·m of
/// what 50 seeds give, and a slipping gear's deficit comes to 70–95 N·m.
pub const MARGIN_NM: f64 = 20.0;

/// The limit for a gait whose healthy stance hip peaks at `peak_nm`, N·m.
/// The device's own bounds are the supervisor's
/// ([`ResponseCheck::stance_hip_limit_nm`]), so the board plays the figure
/// as it is written.
pub fn limit_for(peak_nm: f64, check: &ResponseCheck) -> u8 {
    let asked = (peak_nm + MARGIN_NM).ceil() as f32;
    // Whole N·m within the device's bounds (100): exact in a byte.
    check.stance_hip_limit_nm(asked).clamp(1.0, 255.0) as u8
}

/// A gait's stance hip, measured on `device` (its healthy peak, N·m, and
/// the limit it carries): `table` played for `steps` steps within `max_s`
/// without sensor noise and with the device's (`sim::residual`). An error
/// names a run that faulted or landed short, or a healthy peak at or over
/// the device's own limit: shorter than the 10 ticks that latch there, it
/// is one noise seed away from a healthy run held for a drive fault.
pub fn measure(
    device: &DeviceConfig,
    table: GaitTable<'_>,
    steps: usize,
    max_s: f64,
) -> Result<(f64, u8), String> {
    let peak = sim::residual::stance_hip_residual_peak_nm(device, table, steps, max_s)?;
    let check = &device.supervisor.response;
    if peak >= f64::from(check.limit_nm) {
        return Err(format!(
            "closed loop: the stance hip's torque residual reaches {peak:.0} N·m in a healthy \
             swing, at or over the {:.0} N·m the device takes for a drive fault (0x0404)",
            check.limit_nm
        ));
    }
    Ok((peak, limit_for(peak, check)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quiet_gait_gets_the_floor_and_a_brisk_one_the_device_limit() {
        let check = ResponseCheck::DEFAULT;
        assert_eq!(limit_for(35.0, &check), 70);
        assert_eq!(limit_for(55.2, &check), 76);
        assert_eq!(limit_for(86.0, &check), 100);
        assert_eq!(limit_for(106.0, &check), 100);
    }
}

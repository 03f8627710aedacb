//! A joint drive from its parts' datasheet figures: brushless motor,
//! strain-wave gearbox and servo amplifier. The joint-level figures every
//! other part of the project uses (peak and continuous torque, the
//! torque–speed line, the I²t budget) are derived here, once, so that the
//! firmware's limits, the simulator's drive model and the table generator's
//! constraints cannot drift apart.
//!
//! Units are SI at the joint unless a field says otherwise; the datasheet
//! figures are kept in the units the datasheets print (mN·m, rpm/V, g·cm²)
//! so they can be checked against the sheet line by line.

use gait_control::drivers::motor::MotorConfig;

/// A brushless motor's datasheet figures (values at nominal voltage).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotorSpec {
    /// Maker and product, with part number.
    pub name: &'static str,
    /// Nominal voltage of the winding, V.
    pub nominal_voltage_v: f32,
    /// Nominal (maximum continuous) torque, mN·m.
    pub nominal_torque_mnm: f32,
    /// Nominal (maximum continuous) current, A.
    pub nominal_current_a: f32,
    /// Torque constant, mN·m/A.
    pub torque_constant_mnm_per_a: f32,
    /// Speed constant, rpm/V.
    pub speed_constant_rpm_per_v: f32,
    /// Terminal resistance phase to phase, Ω.
    pub terminal_resistance_ohm: f32,
    /// Rotor inertia, g·cm².
    pub rotor_inertia_gcm2: f32,
    /// Thermal time constant of the winding, s.
    pub winding_time_constant_s: f32,
}

/// A strain-wave gear component set's datasheet figures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GearboxSpec {
    /// Maker and product.
    pub name: &'static str,
    /// Reduction ratio (motor turns per joint turn).
    pub ratio: f32,
    /// Rated torque at 2,000 rpm input, N·m.
    pub rated_torque_nm: f32,
    /// Limit for average torque, N·m.
    pub average_torque_nm: f32,
    /// Limit for repeated peak torque, N·m.
    pub repeated_peak_torque_nm: f32,
    /// Limit for momentary torque, N·m.
    pub momentary_torque_nm: f32,
    /// Efficiency at the input speeds of gait (≈ 500–1,000 rpm), 0–1.
    pub efficiency: f32,
}

/// The servo amplifier (current-controlled) and its supply.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmplifierSpec {
    /// Maker and product.
    pub name: &'static str,
    /// Supply (bus) voltage, V.
    pub supply_v: f32,
    /// Largest continuous output current, A.
    pub continuous_current_a: f32,
    /// Largest peak output current, A.
    pub peak_current_a: f32,
}

/// The drive's dynamic brake: a normally-closed contactor across the
/// motor's phases, held open by the bridge-enable line. Whenever the
/// motors are disabled (e-stop, an output-stage fault, a reset, a power
/// loss) it closes and the motor's back-EMF drives a current through the
/// winding and the braking resistor: the joint is damped, not limp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicBrake {
    /// The part.
    pub name: &'static str,
    /// Resistance in series with the shorted winding, Ω (it bounds the
    /// braking current at speed).
    pub resistance_ohm: f32,
}

/// One joint drive: the parts, and the current limit the amplifier is set
/// to (which sets the joint's peak torque).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriveSpec {
    /// The motor.
    pub motor: MotorSpec,
    /// The gearbox.
    pub gearbox: GearboxSpec,
    /// The amplifier.
    pub amplifier: AmplifierSpec,
    /// The amplifier's current limit as configured, A (at most its peak
    /// current).
    pub current_limit_a: f32,
    /// Share of the winding's I²t budget (τ_w · I_nom²) at which the torque
    /// limit starts to fall, 0–1.
    pub i2t_warning_share: f32,
    /// Share of the budget at which the output is disabled, 0–1.
    pub i2t_fault_share: f32,
    /// What holds the joint while the bridge is disabled (`None`: nothing,
    /// the joint is limp).
    pub brake: Option<DynamicBrake>,
}

const RPM_TO_RAD_S: f32 = core::f32::consts::PI / 30.0;

/// The derated torque limit over the continuous torque.
pub const DERATED_OVER_CONTINUOUS: f32 = 1.15;

impl DriveSpec {
    /// Joint torque per ampere of motor current, N·m/A: k_t · ratio ·
    /// efficiency.
    pub fn joint_torque_per_amp(&self) -> f32 {
        self.motor.torque_constant_mnm_per_a * 1e-3 * self.gearbox.ratio * self.gearbox.efficiency
    }

    /// Peak joint torque, N·m: the amplifier's current limit through motor
    /// and gear, never above the gearbox's repeated-peak rating.
    pub fn peak_torque_nm(&self) -> f32 {
        (self.current_limit_a * self.joint_torque_per_amp())
            .min(self.gearbox.repeated_peak_torque_nm)
    }

    /// Continuous joint torque, N·m: the motor's nominal current, or the
    /// gearbox's average-torque rating if that is lower.
    pub fn continuous_torque_nm(&self) -> f32 {
        (self.motor.nominal_current_a * self.joint_torque_per_amp())
            .min(self.gearbox.average_torque_nm)
    }

    /// The motor current that gives the continuous joint torque, A.
    pub fn continuous_current_a(&self) -> f32 {
        self.continuous_torque_nm() / self.joint_torque_per_amp()
    }

    /// Joint damping while braked, N·m per (rad/s): the back-EMF k_e·N·ω
    /// drives I = k_e·N·ω / (R + R_brake) through the shorted winding, whose
    /// torque k_t·I·N·η opposes the motion: b = η·N²·k_t·k_e / (R + R_brake).
    /// Zero without a brake. (The winding's inductance is left out: at the
    /// joint speeds of a braked sink, under 1 rad/s, its reactance is a
    /// tenth of the resistance.)
    pub fn brake_damping_nm_s_per_rad(&self) -> f32 {
        let Some(brake) = self.brake else {
            return 0.0;
        };
        let n = self.gearbox.ratio;
        let kt = self.motor.torque_constant_mnm_per_a * 1e-3;
        let r = self.motor.terminal_resistance_ohm + brake.resistance_ohm;
        if r > 0.0 {
            self.gearbox.efficiency * n * n * kt * self.back_emf_v_per_rad_s() / r
        } else {
            0.0
        }
    }

    /// Back-EMF constant, V per (rad/s) of the motor.
    fn back_emf_v_per_rad_s(&self) -> f32 {
        1.0 / (self.motor.speed_constant_rpm_per_v * RPM_TO_RAD_S)
    }

    /// No-load joint speed at the supply voltage, rad/s.
    pub fn no_load_speed_rad_s(&self) -> f32 {
        self.amplifier.supply_v / self.back_emf_v_per_rad_s() / self.gearbox.ratio
    }

    /// Joint speed up to which the full peak torque is available while
    /// driving (the supply still pushes the current limit through the
    /// winding against the back-EMF), rad/s.
    pub fn full_torque_speed_rad_s(&self) -> f32 {
        let headroom =
            self.amplifier.supply_v - self.current_limit_a * self.motor.terminal_resistance_ohm;
        (headroom / self.back_emf_v_per_rad_s() / self.gearbox.ratio).max(0.0)
    }

    /// Largest torque magnitude the drive can put out at `joint_speed_rad_s`
    /// in the direction `sign` (+1 or −1 torque), N·m: the peak torque, less
    /// where the supply cannot push the current against the back-EMF
    /// (I ≤ (V − k_e ω_m)/R when torque and motion agree; braking, the
    /// back-EMF helps and the current limit alone applies).
    pub fn available_torque_nm(&self, joint_speed_rad_s: f32, sign: f32) -> f32 {
        let peak = self.peak_torque_nm();
        let omega_motor = joint_speed_rad_s * self.gearbox.ratio;
        let driving = omega_motor * sign > 0.0;
        if !driving {
            return peak;
        }
        let emf = self.back_emf_v_per_rad_s() * omega_motor.abs();
        let current =
            ((self.amplifier.supply_v - emf) / self.motor.terminal_resistance_ohm).max(0.0);
        (current * self.joint_torque_per_amp()).min(peak)
    }

    /// The drive's I²t budget, A²·s: τ_w · I_c², with I_c the continuous
    /// current. A cold winding reaches its limit temperature after about
    /// this much ∫(I² − I_c²) dt under a large current (first-order thermal
    /// model, I ≫ I_c).
    pub fn i2t_budget_a2s(&self) -> f32 {
        let c = self.continuous_current_a();
        self.motor.winding_time_constant_s * c * c
    }

    /// The motor driver's configuration (gait-control) for this drive at a
    /// tick of `dt_s`: limit = peak torque, 100 % duty = the current limit,
    /// the I²t levels from [`DriveSpec::i2t_budget_a2s`], derated to
    /// [`DERATED_OVER_CONTINUOUS`]× the continuous torque (above it, so that
    /// sustained overload still reaches the fault). The driver's torque constant is the effective
    /// one at the joint side of the gear (k_t · efficiency), so its current
    /// estimate is the motor's.
    pub fn motor_config(
        &self,
        dt_s: f32,
        slew_nm_per_tick: f32,
        soft_start_ticks: u32,
    ) -> MotorConfig {
        let peak = self.peak_torque_nm();
        MotorConfig {
            torque_limit_nm: peak,
            full_scale_torque_nm: self.current_limit_a * self.joint_torque_per_amp(),
            torque_constant_nm_per_a: self.motor.torque_constant_mnm_per_a
                * 1e-3
                * self.gearbox.efficiency,
            gear_ratio: self.gearbox.ratio,
            continuous_current_a: self.continuous_current_a(),
            i2t_warning_a2s: self.i2t_warning_share * self.i2t_budget_a2s(),
            i2t_fault_a2s: self.i2t_fault_share * self.i2t_budget_a2s(),
            derated_limit_nm: (DERATED_OVER_CONTINUOUS * self.continuous_torque_nm()).min(peak),
            slew_nm_per_tick,
            soft_start_ticks,
            dt_s,
        }
    }
}

//! Prints every baseline's J and parts.
use gait_opt::{Source, baseline_from, default_data_dir};

fn main() {
    let dir = default_data_dir();
    for (case, src) in Source::PAPER_BASELINES {
        match baseline_from(case, src, &dir) {
            Ok(b) => {
                let c = b.cost.unwrap_or_else(|| unreachable!());
                println!(
                    "{case:?} {src:?}: J = {:.1} (torque {:.1}, velocity {:.1}, speed {:.3} m/s) tau rms {:.1} peak {:.1} swing {} | s = {:.3} corr {:?}",
                    c.j,
                    c.torque,
                    c.velocity,
                    c.peak_ankle_speed_m_s,
                    c.tau_rms_nm,
                    c.tau_peak_nm,
                    c.swing_samples,
                    b.amplitude_scale,
                    b.end_correction_rad
                        .map(|d| d.map(|x| (x.to_degrees() * 10.0).round() / 10.0))
                );
            }
            Err(e) => println!("{case:?} {src:?}: {e}"),
        }
    }
}

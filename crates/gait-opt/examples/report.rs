//! Optimises both cases, builds their reports with baselines, writes
//! `target/report-<case>.json` (or the folder given as the first argument),
//! and prints the figures quoted in docs/optimiser.md.
use gait_core::problem::{PaperCase, PaperProblem};
use gait_opt::report::step_samples;
use gait_opt::{OptimizeConfig, Report, baseline, cost_from_phi, optimize};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "target".into());
    for case in [PaperCase::Walk, PaperCase::StairUp] {
        let cfg = OptimizeConfig::new(case);
        let r = optimize(&cfg, &mut |_| {})?;
        let b = baseline(case)?;
        let rep = Report::new(&r, Some(&b))?;
        let path = format!("{dir}/report-{case:?}.json").to_lowercase();
        std::fs::write(&path, rep.to_json()?)?;
        let back = Report::from_json(&std::fs::read_to_string(&path)?)?;
        let again = back.recompute_cost()?;
        let pr = PaperProblem::<f64>::paper(case);
        let phi: Vec<_> = step_samples(&pr, &r.control_points)?
            .iter()
            .map(|s| s.phi_rad)
            .collect();
        let via_phi = cost_from_phi(&pr, &phi)?;
        println!(
            "{case:?}: J {:.2} (torque {:.2} velocity {:.2}, speed {:.3} m/s) tau rms {:.2} peak {:.2}; evals {} (cmaes {}, runs {}), wall {:.2} s",
            r.cost.j,
            r.cost.torque,
            r.cost.velocity,
            r.cost.peak_ankle_speed_m_s,
            r.cost.tau_rms_nm,
            r.cost.tau_peak_nm,
            r.evaluations,
            r.cmaes_evaluations,
            r.runs,
            r.wall_s
        );
        println!(
            "  recomputed from JSON: {:.6} (rel diff {:.1e}); via Phi: rel diff {:.1e}",
            again.j,
            (again.j - r.cost.j).abs() / r.cost.j,
            (via_phi.j - r.cost.j).abs() / r.cost.j
        );
        if let (Some(bf), Some(red)) = (&rep.baseline, &rep.reduction_pct) {
            println!(
                "  baseline {:?}: J {:.1} (torque {:.1} velocity {:.1}) tau rms {:.1} peak {:.1}; scale {:.3}",
                bf.source,
                bf.j.j,
                bf.j.torque,
                bf.j.velocity,
                bf.j.tau_rms_nm,
                bf.j.tau_peak_nm,
                bf.amplitude_scale
            );
            println!(
                "  reductions: torque part {:.1} %, tau rms {:.1} %, tau peak {:.1} %, J {:.1} %",
                red.torque_part, red.tau_rms, red.tau_peak, red.j
            );
        }
        println!("  wrote {path}");
        for ext in ["svg", "png"] {
            let plot = path.replace(".json", &format!(".{ext}"));
            gait_opt::plot_report(&rep, std::path::Path::new(&plot))?;
            println!("  wrote {plot}");
        }
    }
    Ok(())
}

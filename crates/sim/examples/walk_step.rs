//! One closed-loop walking step (the main job without the CLI):
//! `cargo run --release -p sim --example walk_step -- OUT.svg|png`.

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "walk.svg".into());
    match sim::scenario::walk_step(8.0) {
        Ok(run) => {
            println!("{}", run.summary);
            if let Some(e) = run.ended_by {
                println!("simulation ended early: {e:?}");
            }
            match sim::plot::plot_run(&run.rig.trace, &run.summary, std::path::Path::new(&out)) {
                Ok(()) => println!("plot: {out}"),
                Err(e) => eprintln!("plot failed: {e}"),
            }
        }
        Err(e) => eprintln!("walk_step: {e}"),
    }
}

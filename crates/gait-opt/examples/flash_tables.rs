//! Writes the generated gait-table module the firmware links into flash:
//! `cargo run --release -p gait-opt --example flash_tables -- PATH`
//! (normally through `cargo xtask tables`).

use std::process::ExitCode;

fn main() -> ExitCode {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: flash_tables OUT.rs");
        return ExitCode::from(2);
    };
    match gait_opt::tables::flash_module_source() {
        Ok(src) => match std::fs::write(&path, src) {
            Ok(()) => {
                println!("wrote {path}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("flash_tables: cannot write {path}: {e}");
                ExitCode::FAILURE
            }
        },
        Err(e) => {
            eprintln!("flash_tables: {e}");
            ExitCode::FAILURE
        }
    }
}

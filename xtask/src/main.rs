//! `cargo xtask`: every build, test and run step of the project in one place,
//! so that "if `cargo xtask ci` passes locally, CI is green".
//!
//! Cross-building: when rustup has the `thumbv7em-none-eabihf` target (a
//! workstation with internet) it is used as is. Otherwise the route in
//! `shared/notes/cross-build.md` is taken: Debian's `rustc-web` and
//! `rust-web-src` build `core` from source (`-Zbuild-std=core`), linked by
//! rustup's `rust-lld` (or `arm-none-eabi-ld`). Missing Debian packages are
//! installed with apt-get (as root, or through sudo).

mod panic_paths;
mod profile;
mod qemu;
mod sectors;
mod tick_replay;

use std::env;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::time::Instant;

const TARGET: &str = "thumbv7em-none-eabihf";
/// Firmware builds get their own target dir: host builds (rustup's compiler)
/// and target builds (possibly Debian's) would otherwise invalidate each
/// other's caches.
const FW_TARGET_DIR: &str = "../target/fw";
const QEMU_TIMEOUT_S: u64 = 300;

/// A firmware board: its Cargo feature, binary name and how to run it.
#[derive(Clone, Copy)]
struct Board {
    name: &'static str,
    feature: &'static str,
    bin: &'static str,
}

const BOARDS: [Board; 2] = [
    Board {
        name: "stm32f405",
        feature: "board-stm32f405",
        bin: "exogait-stm32f405",
    },
    Board {
        name: "qemu",
        feature: "qemu",
        bin: "exogait-qemu",
    },
];

pub(crate) type Result<T = ()> = std::result::Result<T, String>;

fn main() -> ExitCode {
    let args: Vec<String> = env::args().skip(1).collect();
    let cmd = args.first().map(String::as_str).unwrap_or("help");
    let rest = args.get(1..).unwrap_or(&[]);
    let started = Instant::now();
    let res = match cmd {
        "ci" => ci(),
        "run" => run_main_job(rest),
        "setup" => Toolchain::detect().map(|_| ()),
        "firmware" => Toolchain::detect().and_then(|tc| {
            for b in BOARDS {
                build_firmware(&tc, b)?;
            }
            Ok(())
        }),
        "qemu" => Toolchain::detect().and_then(|tc| match rest {
            [flag, file] if flag == "--bundle" => {
                sectors::qemu_with_bundle(&tc, Path::new(file)).map(|_| ())
            }
            [] => qemu::self_test(&tc),
            _ => Err("usage: cargo xtask qemu [--bundle FILE]".into()),
        }),
        "flash-bundle" => match rest {
            [file] => sectors::flash_bundle(Path::new(file)),
            _ => Err("usage: cargo xtask flash-bundle FILE".into()),
        },
        "profile" => Toolchain::detect().and_then(|tc| {
            let board = BOARDS
                .iter()
                .find(|b| b.name == "qemu")
                .copied()
                .ok_or("no qemu board")?;
            profile::profile(&build_firmware(&tc, board)?)
        }),
        "size" => Toolchain::detect().and_then(|tc| size_all(&tc)),
        "panics" => Toolchain::detect().and_then(|tc| panic_paths_all(&tc)),
        "clippy" => Toolchain::detect().and_then(|tc| clippy(&tc)),
        "tables" => regenerate_tables(rest),
        "faults" => fault_campaign(rest),
        "help" | "--help" | "-h" => {
            println!("{}", HELP);
            Ok(())
        }
        other => Err(format!("unknown task `{other}`\n\n{HELP}")),
    };
    match res {
        Ok(()) => {
            eprintln!(
                "xtask {cmd}: ok in {:.0} s",
                started.elapsed().as_secs_f64()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("xtask {cmd}: FAILED: {e}");
            ExitCode::FAILURE
        }
    }
}

const HELP: &str = "\
usage: cargo xtask <task>

  ci        everything CI checks: fmt, clippy (host and both boards, warnings
            denied), host tests, firmware builds, QEMU self-test, size report
  run       the main job: the shipped tables against the human-data gait, in the
            closed loop, walking and stairs (the paper's Table II; plot)
  firmware  build the firmware for every board (release)
  qemu      build the QEMU image and run its self-test and benchmarks;
            `--bundle FILE`: with a patient's bundle in its sector (and,
            when it verifies, its first step recorded on the host)
  flash-bundle FILE
            write a patient's bundle to the motor board's bundle sector
            (probe-rs; the image and the calibration are left as they are)
  profile   where the replayed ticks' instructions go on the target, per
            source file and the costliest lines, then each phase's
            costliest tick by file (QEMU's execution log; about 3-5 minutes)
  size      flash/RAM use per board
  panics    proves both release images hold no panic: none reachable from the
            vector table's handlers, no panic code left at all (no allow-list)
  clippy    clippy with warnings denied, host and firmware
  faults    the randomised fault campaign in the closed loop: `cargo xtask faults
            --runs N [--healthy M] [--seed S] [--json]` (progress bar; tally per
            fault kind; then M healthy runs of each gait, default 100)
  tables    regenerate the flash gait tables (crates/gait-core/src/flash_tables.rs)
            from the optimiser (deterministic; minutes: the stair-ascent table's
            closed-loop refinement); `--check`: regenerate in memory and compare
            with the committed file (CI's test checks all but the refinement's
            search)
  setup     install missing system packages for cross-building";

pub(crate) fn root() -> PathBuf {
    // xtask lives in <root>/xtask.
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.parent().map(Path::to_path_buf).unwrap_or(here)
}

fn ci() -> Result {
    step("cargo fmt --check", || {
        run(cargo().args(["fmt", "--all", "--", "--check"]))?;
        run(cargo_in_firmware("cargo").args(["fmt", "--all", "--", "--check"]))
    })?;
    let tc = Toolchain::detect()?;
    step("clippy (host + firmware, -D warnings)", || clippy(&tc))?;
    step("host tests", || run(cargo().args(["test", "--workspace"])))?;
    for b in BOARDS {
        step(&format!("firmware build: {}", b.name), || {
            build_firmware(&tc, b).map(|_| ())
        })?;
    }
    step("panic paths (both release images)", || panic_paths_all(&tc))?;
    step("QEMU self-test", || qemu::self_test(&tc))?;
    step(
        "QEMU boot with a patient's bundle, good and corrupted",
        || sectors::ci_bundle_boot(&tc),
    )?;
    step("QEMU boot without a calibration", || {
        sectors::ci_uncalibrated_boot(&tc)
    })?;
    step("size report", || size_all(&tc))?;
    Ok(())
}

/// `cargo xtask faults --runs N [--healthy M] [--seed S] [--json]`:
/// `exogait faults`,
/// built in release. Its exit status 1 (the campaign's goal not met) is
/// reported, not an error of the task; 2 is.
fn fault_campaign(args: &[String]) -> Result {
    run(cargo().args(["build", "--quiet", "--release", "-p", "exogait-cli"]))?;
    let exe = root().join("target/release/exogait");
    let status = Command::new(&exe)
        .current_dir(root())
        .arg("faults")
        .args(args)
        .status()
        .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
    match status.code() {
        Some(0) => Ok(()),
        Some(1) => {
            eprintln!(
                "xtask faults: the campaign's goal (no fall and no stop crossed but the named cases, no missed detection, no false trip; every healthy run clean) is not met"
            );
            Ok(())
        }
        _ => Err("exogait faults could not run the campaign".into()),
    }
}

/// `cargo xtask tables`: regenerates the flash tables (the stair-ascent
/// refinement searches in the closed loop for minutes). `--check`: instead,
/// regenerates them in memory, search included, and compares with the
/// committed file (the `#[ignore]`d full test; CI runs the fast one).
fn regenerate_tables(args: &[String]) -> Result {
    if args.iter().any(|a| a == "--check") {
        return run(cargo().args([
            "test",
            "--release",
            "-p",
            "gait-opt",
            "--test",
            "flash_tables",
            "--",
            "--ignored",
            "--nocapture",
        ]));
    }
    run(cargo().args([
        "run",
        "--release",
        "-p",
        "gait-opt",
        "--example",
        "flash_tables",
        "--",
        "crates/gait-core/src/flash_tables.rs",
    ]))
}

/// The main job: the paper's Table II in the closed loop — for walking,
/// stair ascent and stair descent, the table the firmware ships against the
/// human-data gait, four steps each on the simulated device and pilot —
/// printed as a table, with a plot of the walk's comparison in
/// `target/sim/walk-compare.svg` (or the path given).
fn run_main_job(args: &[String]) -> Result {
    let plot = args
        .first()
        .cloned()
        .unwrap_or_else(|| "target/sim/walk-compare.svg".into());
    if let Some(dir) = Path::new(&plot).parent() {
        std::fs::create_dir_all(root().join(dir))
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    run(cargo().args(["build", "--quiet", "--release", "-p", "exogait-cli"]))?;
    let exe = root().join("target/release/exogait");
    let mut failed = Vec::new();
    for gait in ["walk", "stair-up", "stair-down"] {
        let mut cmd = Command::new(&exe);
        cmd.current_dir(root()).args(["compare", "--gait", gait]);
        if gait == "walk" {
            cmd.args(["--plot", &plot]);
        }
        let status = cmd
            .status()
            .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
        // 1: a gait faulted or fell short (reported in the table); 2: the
        // comparison could not run at all.
        if status.code() == Some(2) || status.code().is_none() {
            failed.push(gait);
        }
        println!();
    }
    if failed.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "the comparison could not run for {}",
            failed.join(", ")
        ))
    }
}

fn step(name: &str, f: impl FnOnce() -> Result) -> Result {
    eprintln!("\n=== {name}");
    let t = Instant::now();
    let r = f();
    eprintln!(
        "=== {name}: {} ({:.0} s)",
        if r.is_ok() { "ok" } else { "FAILED" },
        t.elapsed().as_secs_f64()
    );
    r.map_err(|e| format!("{name}: {e}"))
}

pub(crate) fn cargo() -> Command {
    let mut c = Command::new(env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

/// A cargo command run inside the firmware's own workspace.
fn cargo_in_firmware(program: &str) -> Command {
    let mut c = Command::new(program);
    c.current_dir(root().join("firmware"));
    c
}

pub(crate) fn run(cmd: &mut Command) -> Result {
    let shown = format!("{cmd:?}");
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start {shown}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{shown} exited with {status}"))
    }
}

pub(crate) fn output(cmd: &mut Command) -> Result<String> {
    let shown = format!("{cmd:?}");
    let out = cmd
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot start {shown}: {e}"))?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).into_owned())
    } else {
        Err(format!("{shown} exited with {}", out.status))
    }
}

fn have(program: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {program} >/dev/null 2>&1")])
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// How this machine cross-builds for the Cortex-M4F.
pub(crate) enum Toolchain {
    /// rustup has the target's prebuilt `core`.
    Rustup,
    /// Debian's rustc-web builds `core` from rust-web-src.
    DebianBuildStd { linker: PathBuf },
}

impl Toolchain {
    fn detect() -> Result<Self> {
        let rustup_has_target = Command::new("rustup")
            .args(["target", "list", "--installed"])
            .output()
            .map(|o| {
                String::from_utf8_lossy(&o.stdout)
                    .lines()
                    .any(|l| l.trim() == TARGET)
            })
            .unwrap_or(false);
        let mut pkgs: Vec<&str> = Vec::new();
        // Plot text (plotters renders it from a TTF file).
        if !Path::new("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf").exists() {
            pkgs.push("fonts-dejavu-core");
        }
        if !have("qemu-system-arm") {
            pkgs.push("qemu-system-arm");
        }
        if !have("arm-none-eabi-size") {
            pkgs.push("binutils-arm-none-eabi");
        }
        if rustup_has_target {
            apt_install(&pkgs)?;
            return Ok(Self::Rustup);
        }
        if !debian_rustc_ok() {
            pkgs.push("rustc-web");
        }
        if !Path::new("/usr/lib/rustlib/src/rust/library/core/Cargo.toml").exists() {
            pkgs.push("rust-web-src");
        }
        if !Path::new("/usr/bin/clippy-driver").exists() {
            pkgs.push("rust-web-clippy");
        }
        apt_install(&pkgs)?;
        if !debian_rustc_ok() {
            return Err("/usr/bin/rustc is not rustc-web >= 1.85 after installing it".into());
        }
        Ok(Self::DebianBuildStd {
            linker: find_linker()?,
        })
    }

    /// A cargo command for the target, with the environment this route needs.
    fn cargo(&self, subcommand: &str) -> Command {
        let cargo_bin = env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let mut c = match self {
            Self::Rustup => cargo_in_firmware(&cargo_bin),
            Self::DebianBuildStd { linker } => {
                let mut c = if subcommand == "clippy" {
                    // Debian's cargo-clippy drives its own clippy-driver,
                    // which matches /usr/bin/rustc's version.
                    cargo_in_firmware("/usr/bin/cargo-clippy")
                } else {
                    cargo_in_firmware(&cargo_bin)
                };
                c.env("RUSTC", "/usr/bin/rustc")
                    .env("RUSTC_BOOTSTRAP", "1")
                    .env("CARGO_TARGET_THUMBV7EM_NONE_EABIHF_LINKER", linker)
                    .env_remove("RUSTC_WORKSPACE_WRAPPER")
                    .env_remove("RUSTFLAGS");
                c
            }
        };
        c.arg(subcommand);
        if let Self::DebianBuildStd { .. } = self {
            c.arg("-Zbuild-std=core");
        }
        c.args(["--target", TARGET, "--target-dir", FW_TARGET_DIR]);
        c
    }
}

fn debian_rustc_ok() -> bool {
    let Ok(out) = Command::new("/usr/bin/rustc").arg("--version").output() else {
        return false;
    };
    let v = String::from_utf8_lossy(&out.stdout);
    // "rustc 1.96.0 (...)"
    let minor = v
        .split_whitespace()
        .nth(1)
        .and_then(|ver| ver.split('.').nth(1))
        .and_then(|m| m.parse::<u32>().ok());
    matches!(minor, Some(m) if m >= 85)
}

fn find_linker() -> Result<PathBuf> {
    // rustup's own rust-lld, found through the host compiler's sysroot.
    if let Ok(sysroot) = output(Command::new("rustc").args(["--print", "sysroot"])) {
        let host = output(Command::new("rustc").arg("-vV"))
            .ok()
            .and_then(|v| {
                v.lines()
                    .find_map(|l| l.strip_prefix("host: ").map(str::to_owned))
            })
            .unwrap_or_else(|| "x86_64-unknown-linux-gnu".into());
        let lld = Path::new(sysroot.trim())
            .join("lib/rustlib")
            .join(host)
            .join("bin/rust-lld");
        if lld.exists() {
            return Ok(lld);
        }
    }
    if have("arm-none-eabi-ld") {
        return Ok(PathBuf::from("arm-none-eabi-ld"));
    }
    Err("no linker: neither rustup's rust-lld nor arm-none-eabi-ld was found".into())
}

fn apt_install(pkgs: &[&str]) -> Result {
    if pkgs.is_empty() {
        return Ok(());
    }
    eprintln!("installing missing system packages: {}", pkgs.join(" "));
    let is_root = output(Command::new("id").arg("-u"))
        .map(|s| s.trim() == "0")
        .unwrap_or(false);
    let apt = |args: &[&str]| -> Command {
        let mut c = if is_root {
            Command::new("apt-get")
        } else {
            let mut c = Command::new("sudo");
            c.arg("apt-get");
            c
        };
        c.args(args).env("DEBIAN_FRONTEND", "noninteractive");
        c
    };
    run(&mut apt(&["update", "-qq"]))?;
    let mut install = apt(&["install", "-y", "-qq", "--no-install-recommends"]);
    install.args(pkgs);
    run(&mut install)
}

fn build_firmware(tc: &Toolchain, board: Board) -> Result<PathBuf> {
    let mut build = tc.cargo("build");
    build.args(["--release", "--features", board.feature, "--bin", board.bin]);
    if board.name == "qemu" {
        let files = tick_replay::recording()?;
        build
            .env("EXOGAIT_TICK_RECORDS", files.ticks)
            .env("EXOGAIT_REPLANNING_RECORDS", files.replanning);
    }
    run(&mut build)?;
    let elf = root()
        .join("target/fw")
        .join(TARGET)
        .join("release")
        .join(board.bin);
    if elf.exists() {
        Ok(elf)
    } else {
        Err(format!("build succeeded but {} is missing", elf.display()))
    }
}

fn clippy(tc: &Toolchain) -> Result {
    run(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ]))?;
    for b in BOARDS {
        run(tc.cargo("clippy").args([
            "--features",
            b.feature,
            "--bins",
            "--lib",
            "--",
            "-D",
            "warnings",
        ]))?;
    }
    Ok(())
}

fn panic_paths_all(tc: &Toolchain) -> Result {
    for b in BOARDS {
        let elf = build_firmware(tc, b)?;
        panic_paths::check(&elf)?;
    }
    Ok(())
}

fn size_all(tc: &Toolchain) -> Result {
    let mut report = String::new();
    for b in BOARDS {
        let elf = build_firmware(tc, b)?;
        let out = output(Command::new("arm-none-eabi-size").arg(&elf))?;
        // Berkeley format: header line, then "text data bss dec hex filename".
        let nums: Vec<u64> = out
            .lines()
            .nth(1)
            .unwrap_or_default()
            .split_whitespace()
            .take(3)
            .filter_map(|s| s.parse().ok())
            .collect();
        let [text, data, bss] = nums[..] else {
            return Err(format!("cannot parse arm-none-eabi-size output: {out}"));
        };
        let _ = writeln!(
            report,
            "size: board={} text={text} data={data} bss={bss}",
            b.name
        );
    }
    print!("{report}");
    Ok(())
}

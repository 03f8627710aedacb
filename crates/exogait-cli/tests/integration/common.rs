//! Running the built `exogait`, shared by the tests.

use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// Runs the built `exogait` with `args`, `stdin` piped in, to its exit.
pub fn run_piped(args: &[&str], stdin: &[u8]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn exogait");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(stdin)
        .expect("write stdin");
    child.wait_with_output().expect("wait")
}

/// What a run without input answered: its exit status and its output,
/// which must be UTF-8.
pub struct Run {
    pub status: i32,
    pub stdout: String,
    pub stderr: String,
}

/// Runs the built `exogait` with `args` and no input.
pub fn exogait(args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_exogait"))
        .args(args)
        .output()
        .expect("run exogait");
    Run {
        status: out.status.code().expect("exit code"),
        stdout: String::from_utf8(out.stdout).expect("utf-8 stdout"),
        stderr: String::from_utf8(out.stderr).expect("utf-8 stderr"),
    }
}

/// A path as the command line takes it.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

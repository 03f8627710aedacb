//! Standard output for every command. `println!` panics when the reader
//! has gone (`exogait tables … | head`), and the panic lost the work not
//! yet written (a family's bundle); these let the command finish instead,
//! its output dropped, with its own exit status.

use std::fmt;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, Ordering};

/// Standard output has failed once: nothing more is written to it.
static GONE: AtomicBool = AtomicBool::new(false);

/// Writes `args` (and a newline with `newline`) to stdout. A closed pipe
/// (the reader chose to stop) drops this and every later output quietly;
/// any other write error is said once on stderr.
pub fn write(args: fmt::Arguments<'_>, newline: bool) {
    if GONE.load(Ordering::Relaxed) {
        return;
    }
    let mut out = io::stdout().lock();
    let written = out
        .write_fmt(args)
        .and_then(|()| {
            if newline {
                out.write_all(b"\n")
            } else {
                Ok(())
            }
        })
        .and_then(|()| out.flush());
    if let Err(e) = written {
        GONE.store(true, Ordering::Relaxed);
        if e.kind() != io::ErrorKind::BrokenPipe {
            eprintln!("exogait: writing the output: {e}");
        }
    }
}

/// `println!` to stdout through [`write`].
macro_rules! outln {
    () => {
        $crate::out::write(format_args!(""), true)
    };
    ($($arg:tt)*) => {
        $crate::out::write(format_args!($($arg)*), true)
    };
}

/// `print!` to stdout through [`write`].
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::out::write(format_args!($($arg)*), false)
    };
}

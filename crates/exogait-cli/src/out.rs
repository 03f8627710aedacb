//! Standard output for every command. `outln!` panics when the reader
//! has gone (`exogait faults --json | head`); these end the command
//! quietly instead, as `cat` or `git log` do, with the I/O status 2.

use std::fmt;
use std::io::{self, Write};

/// Writes `args` (and a newline with `newline`) to stdout. A closed pipe
/// ends the process at once with status 2 and no message (the reader
/// chose to stop); any other write error is said on stderr, status 2.
pub fn write(args: fmt::Arguments<'_>, newline: bool) {
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
        if e.kind() != io::ErrorKind::BrokenPipe {
            eprintln!("exogait: writing the output: {e}");
        }
        std::process::exit(i32::from(crate::EXIT_FATAL));
    }
}

/// `outln!` to stdout through [`write`].
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

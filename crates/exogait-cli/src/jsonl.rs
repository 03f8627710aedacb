//! The JSON-lines loop shared by every subcommand.
//!
//! Each non-blank input line is parsed as one request and answered with one
//! output line, in order: the handler's response, or
//! `{"error":"…","line":N}` (N 1-based) when the line is malformed or the
//! handler refuses it. A bad line never stops the loop.

use std::io::{self, BufRead, Write};

use serde::Serialize;
use serde::de::DeserializeOwned;

/// How a run went.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Lines answered (blank lines are skipped and not counted).
    pub answered: usize,
    /// Lines answered with an error.
    pub failed: usize,
}

/// The error answer for one line.
#[derive(Debug, Serialize)]
struct LineError<'a> {
    error: &'a str,
    line: usize,
}

/// serde_json's message, without its "line 1" (every request is one line;
/// the answer carries the input's line number).
fn parse_error(e: &serde_json::Error) -> String {
    e.to_string().replace(" at line 1 column ", " at column ")
}

/// Reads requests line by line from `input`, answers each on `output`.
///
/// `handle` gets the parsed request and returns the response or a message.
/// Only I/O failures end the loop early.
pub fn run<Req, Resp, R, W, F>(input: R, mut output: W, mut handle: F) -> io::Result<Summary>
where
    Req: DeserializeOwned,
    Resp: Serialize,
    R: BufRead,
    W: Write,
    F: FnMut(Req) -> Result<Resp, String>,
{
    let mut summary = Summary::default();
    // Lines as bytes: a line that is not UTF-8 is answered with an error
    // like any bad line, and the lines after it still are.
    for (index, bytes) in input.split(b'\n').enumerate() {
        let bytes = bytes?;
        let text = std::str::from_utf8(&bytes);
        if text.is_ok_and(|l| l.trim().is_empty()) {
            continue;
        }
        summary.answered += 1;
        let answer = text
            .map_err(|_| "the line is not UTF-8 text".to_string())
            .and_then(|line| serde_json::from_str::<Req>(line).map_err(|e| parse_error(&e)))
            .and_then(&mut handle)
            .and_then(|resp| serde_json::to_string(&resp).map_err(|e| e.to_string()));
        match answer {
            Ok(text) => writeln!(output, "{text}")?,
            Err(message) => {
                summary.failed += 1;
                let err = LineError {
                    error: &message,
                    line: index + 1,
                };
                let text = serde_json::to_string(&err).map_err(io::Error::other)?;
                writeln!(output, "{text}")?;
            }
        }
    }
    output.flush()?;
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Req {
        x: f64,
    }

    #[derive(Serialize)]
    struct Resp {
        y: f64,
    }

    fn half(r: Req) -> Result<Resp, String> {
        if r.x < 0.0 {
            Err("x must be >= 0".into())
        } else {
            Ok(Resp { y: r.x / 2.0 })
        }
    }

    #[test]
    fn answers_every_line_in_order() -> io::Result<()> {
        let input = "{\"x\":2}\n\n{\"x\":-1}\nnot json\n{\"x\":1,\"z\":0}\n   \n{\"x\":4}\n";
        let mut out = Vec::new();
        let s = run(input.as_bytes(), &mut out, half)?;
        assert_eq!(
            s,
            Summary {
                answered: 5,
                failed: 3
            }
        );
        let text = String::from_utf8(out).map_err(io::Error::other)?;
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 5);
        assert_eq!(lines.first(), Some(&"{\"y\":1.0}"));
        assert_eq!(
            lines.get(1),
            Some(&"{\"error\":\"x must be >= 0\",\"line\":3}")
        );
        assert!(lines.get(2).is_some_and(|l| l.ends_with("\"line\":4}")));
        assert!(
            lines
                .get(3)
                .is_some_and(|l| l.contains("unknown field") && l.ends_with("\"line\":5}"))
        );
        assert_eq!(lines.get(4), Some(&"{\"y\":2.0}"));
        Ok(())
    }
}

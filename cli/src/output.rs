//! The one place the command line writes: the JSON document on stdout, warnings, progress and errors on
//! stderr (docs/command-line.md). Nothing here panics: output into a closed pipe ends the program quietly, as Unix
//! tools do, and a closed stderr never stops the work.

use serde::Serialize;
use std::io::{BufWriter, ErrorKind, Write};
use std::process::ExitCode;

/// Exit status of an error (docs/command-line.md: non-zero, below 128).
pub const FAILURE: u8 = 1;

/// Exit status of a bug caught at the last line of defence (EX_SOFTWARE of sysexits.h).
pub const INTERNAL_ERROR: u8 = 70;

/// Writes a line to stderr; a failure to write is ignored (stderr is for people, not for the result).
pub fn note(text: &str) {
    let mut err = std::io::stderr().lock();
    let _ = err.write_all(text.as_bytes());
    let _ = err.write_all(b"\n");
}

/// Writes the result to stdout and says how the program ends: quietly with success where the reader
/// closed the pipe early (`embedyn info M | head -c 10`), with an error message for any other failure
/// (a full disk).
pub fn document(text: &str) -> ExitCode {
    let mut out = std::io::stdout().lock();
    ending(out.write_all(text.as_bytes()).and_then(|()| out.flush()))
}

/// Writes `value` as one line of compact JSON to stdout, serialized as it is written (a million samples'
/// results are never held as text), ending as [`document`] does.
pub fn json_document<T: Serialize>(value: &T) -> ExitCode {
    let mut out = BufWriter::new(std::io::stdout().lock());
    let written = serde_json::to_writer(&mut out, value)
        .map_err(|e| match e.io_error_kind() {
            Some(kind) => std::io::Error::new(kind, e),
            None => std::io::Error::other(e),
        })
        .and_then(|()| out.write_all(b"\n"))
        .and_then(|()| out.flush());
    ending(written)
}

fn ending(written: std::io::Result<()>) -> ExitCode {
    match written {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.kind() == ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            note(&format!("error: cannot write the output: {e}"));
            ExitCode::from(FAILURE)
        }
    }
}

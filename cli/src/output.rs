//! The one place the command line writes: the JSON document on stdout, warnings, progress and errors on
//! stderr (docs/command-line.md). Nothing here panics: output into a closed pipe ends the program quietly, as Unix
//! tools do, and a closed stderr never stops the work.

use embedyn_codegen::Printable;
use serde::Serialize;
use std::io::{BufWriter, ErrorKind, Write};
use std::process::ExitCode;

/// Exit status of an error (docs/command-line.md: non-zero, below 128).
pub const FAILURE: u8 = 1;

/// Exit status of a bug caught at the last line of defence (EX_SOFTWARE of sysexits.h).
pub const INTERNAL_ERROR: u8 = 70;

/// The most characters a line of stderr shows; the rest is cut (a name of megabytes from a model file
/// or an input document does not become megabytes of stderr).
pub const MAX_NOTE_LINE_CHARS: usize = 4096;

/// Writes a line to stderr; a failure to write is ignored (stderr is for people, not for the result).
/// Every line of `text` goes through the loader's [`Printable`] (control characters and the invisible
/// Unicode format characters that reorder or hide text shown as escapes, whatever message carries them)
/// and is cut at [`MAX_NOTE_LINE_CHARS`].
pub fn note(text: &str) {
    let mut err = std::io::stderr().lock();
    let _ = err.write_all(printable_lines(text).as_bytes());
    let _ = err.write_all(b"\n");
}

/// `text` as [`note`] writes it (without the final line break).
pub fn printable_lines(text: &str) -> String {
    let mut out = String::with_capacity(text.len().min(1 << 16));
    for (k, line) in text.split('\n').enumerate() {
        if k > 0 {
            out.push('\n');
        }
        match line.char_indices().nth(MAX_NOTE_LINE_CHARS) {
            None => out += &Printable(line).to_string(),
            Some((end, _)) => {
                out += &format!("{}… ({} bytes)", Printable(&line[..end]), line.len());
            }
        }
    }
    out
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn note_lines_are_escaped_and_cut_line_by_line() {
        assert_eq!(
            printable_lines("error: a\u{202E}b\u{1b}[2J\nsecond \u{2029} line"),
            "error: a\\u{202e}b\\u{1b}[2J\nsecond \\u{2029} line"
        );
        // Escaping twice changes nothing (the loader's messages are escaped already).
        let once = printable_lines("x\u{FEFF}\u{7}");
        assert_eq!(printable_lines(&once), once);
        let long = format!("{}\nshort", "é".repeat(1_000_000));
        let out = printable_lines(&long);
        assert!(out.len() < 3 * MAX_NOTE_LINE_CHARS, "{}", out.len());
        assert!(
            out.ends_with("… (2000000 bytes)\nshort"),
            "{}",
            &out[out.len() - 40..]
        );
    }
}

//! Reading a whole file or stream with a size limit: a model path or `--input` that names `/dev/zero`, a
//! FIFO or a runaway file must end with a clear error, not read until memory runs out.

use std::io::Read;

/// Largest model file read (the largest public URDFs are a few MB; a 50 MB file of 50,000 links loads in
/// seconds).
pub const MAX_MODEL_BYTES: u64 = 256 << 20;

/// Largest JSON input read by the command line (about a million samples of a 30-DoF robot).
pub const MAX_INPUT_BYTES: u64 = 512 << 20;

/// Reads `reader` to the end as UTF-8, failing once more than `limit` bytes arrive.
pub fn read_to_string_limited(reader: impl Read, limit: u64) -> Result<String, String> {
    let mut bytes = Vec::new();
    reader
        .take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(format!(
            "larger than {} MiB, the most embedyn reads",
            limit >> 20
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        )
    })
}

/// [`read_to_string_limited`] of a file.
pub fn read_file_limited(path: &std::path::Path, limit: u64) -> Result<String, String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    read_to_string_limited(file, limit)
}

/// A model file's text: a regular file (or a link to one) of at most [`MAX_MODEL_BYTES`]. A device
/// (`/dev/zero`) or a FIFO is refused before it is opened: opening a FIFO waits for a writer, which would
/// hang a build that expands `robot!`.
pub fn read_model_file(path: &std::path::Path) -> Result<String, String> {
    let meta = std::fs::metadata(path).map_err(|e| e.to_string())?;
    if !meta.is_file() {
        return Err("not a regular file".into());
    }
    read_file_limited(path, MAX_MODEL_BYTES)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endless_and_binary_streams_end_with_an_error() {
        let endless = std::io::repeat(b'x');
        let e = read_to_string_limited(endless, 1 << 20).unwrap_err();
        assert!(e.contains("larger than 1 MiB"), "{e}");
        let e = read_to_string_limited(&[b'a', 0xff, b'b'][..], 10).unwrap_err();
        assert!(e.contains("not UTF-8") && e.contains("offset 1"), "{e}");
        assert_eq!(read_to_string_limited(&b"abc"[..], 3).unwrap(), "abc");
    }

    #[cfg(unix)]
    #[test]
    fn a_model_file_must_be_a_regular_file() {
        let e = read_model_file("/dev/zero".as_ref()).unwrap_err();
        assert_eq!(e, "not a regular file");
        let e = read_model_file("/".as_ref()).unwrap_err();
        assert_eq!(e, "not a regular file");
    }
}

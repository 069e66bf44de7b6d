//! Reading a whole file or stream with a size limit: a model path or `--input` that names `/dev/zero`, a
//! FIFO or a runaway file must end with a clear error, not read until memory runs out.

use crate::error::Shared;
use std::io::Read;

/// Largest model file read (the largest public URDFs are a few MB; a 50 MB file of 50,000 links loads in
/// seconds).
pub const MAX_MODEL_BYTES: u64 = 256 << 20;

/// Largest JSON input read by the command line (about a million samples of a 30-DoF robot).
pub const MAX_INPUT_BYTES: u64 = 512 << 20;

/// Why a file or stream was not read.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ReadError {
    /// The system refused (no such file, no permission, …).
    #[error("{0}")]
    Io(#[source] Shared<std::io::Error>),
    /// A model path that names a device, a FIFO or a folder.
    #[error("not a regular file")]
    NotARegularFile,
    /// More than `limit` bytes.
    #[error("larger than {} MiB, the most embedyn reads", .limit >> 20)]
    TooLarge {
        /// The most bytes read.
        limit: u64,
    },
    /// Bytes that are not UTF-8.
    #[error("not UTF-8 text (invalid byte at offset {offset})")]
    NotUtf8 {
        /// The offset of the first invalid byte.
        offset: usize,
    },
}

impl From<std::io::Error> for ReadError {
    fn from(error: std::io::Error) -> Self {
        ReadError::Io(error.into())
    }
}

/// Reads `reader` to the end as UTF-8, failing once more than `limit` bytes arrive.
pub fn read_to_string_limited(reader: impl Read, limit: u64) -> Result<String, ReadError> {
    let mut bytes = Vec::new();
    reader.take(limit + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(ReadError::TooLarge { limit });
    }
    String::from_utf8(bytes).map_err(|e| ReadError::NotUtf8 {
        offset: e.utf8_error().valid_up_to(),
    })
}

/// [`read_to_string_limited`] of a file.
pub fn read_file_limited(path: &std::path::Path, limit: u64) -> Result<String, ReadError> {
    let file = std::fs::File::open(path)?;
    read_to_string_limited(file, limit)
}

/// A model file's text: a regular file (or a link to one) of at most [`MAX_MODEL_BYTES`]. A device
/// (`/dev/zero`) or a FIFO is refused before it is opened: opening a FIFO waits for a writer, which would
/// hang a build that expands `robot!`.
pub fn read_model_file(path: &std::path::Path) -> Result<String, ReadError> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(ReadError::NotARegularFile);
    }
    read_file_limited(path, MAX_MODEL_BYTES)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endless_and_binary_streams_end_with_an_error() {
        let endless = std::io::repeat(b'x');
        let e = read_to_string_limited(endless, 1 << 20)
            .unwrap_err()
            .to_string();
        assert!(e.contains("larger than 1 MiB"), "{e}");
        let e = read_to_string_limited(&[b'a', 0xff, b'b'][..], 10)
            .unwrap_err()
            .to_string();
        assert!(e.contains("not UTF-8") && e.contains("offset 1"), "{e}");
        assert_eq!(read_to_string_limited(&b"abc"[..], 3).unwrap(), "abc");
    }

    #[test]
    fn read_errors_carry_their_data() {
        let e = read_to_string_limited(std::io::repeat(b'x'), 1 << 20).unwrap_err();
        assert_eq!(e, ReadError::TooLarge { limit: 1 << 20 });
        let e = read_to_string_limited(&[b'a', b'b', 0xff][..], 10).unwrap_err();
        assert_eq!(e, ReadError::NotUtf8 { offset: 2 });
        let e = read_model_file("/no/such/model.urdf".as_ref()).unwrap_err();
        assert!(
            matches!(&e, ReadError::Io(io) if io.get().kind() == std::io::ErrorKind::NotFound),
            "{e:?}"
        );
    }

    #[cfg(unix)]
    #[test]
    fn a_model_file_must_be_a_regular_file() {
        let e = read_model_file("/dev/zero".as_ref())
            .unwrap_err()
            .to_string();
        assert_eq!(e, "not a regular file");
        let e = read_model_file("/".as_ref()).unwrap_err().to_string();
        assert_eq!(e, "not a regular file");
    }
}

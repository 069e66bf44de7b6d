//! Errors and warnings of model loading, each pointing at the file, the element and the line.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a model file something is: the file, the element (`joint "knee"`) and its line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The model file.
    pub file: PathBuf,
    /// 1-based line, when known.
    pub line: Option<u32>,
    /// The element, e.g. `joint "knee"` or `link "thigh" <inertial>`.
    pub element: String,
}

impl Location {
    /// A location in `file` at `line` (1-based, when known) naming `element`.
    pub fn new(file: &Path, line: Option<u32>, element: impl Into<String>) -> Self {
        Location {
            file: file.to_path_buf(),
            line,
            element: element.into(),
        }
    }
}

/// Text for a terminal: control characters (from a file name, or a name written with `&#10;` or `&#27;`
/// in the XML) shown as escapes, so that a message cannot move the cursor, recolour or clear the screen
/// of whoever reads it, nor forge a line of its own.
pub(crate) struct Printable<'a>(pub &'a str);

impl fmt::Display for Printable<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for c in self.0.chars() {
            if c.is_control() {
                write!(f, "{}", c.escape_default())?;
            } else {
                write!(f, "{c}")?;
            }
        }
        Ok(())
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", Printable(&self.file.to_string_lossy()))?;
        if let Some(l) = self.line {
            write!(f, ":{l}")?;
        }
        if !self.element.is_empty() {
            write!(f, ": {}", Printable(&self.element))?;
        }
        Ok(())
    }
}

/// A model that cannot be loaded. The message names the file, the element and, where possible, the line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadError {
    /// Where in the model file.
    pub location: Location,
    /// What is wrong.
    pub message: String,
}

impl LoadError {
    /// An error at `location` saying `message`.
    pub fn new(location: Location, message: impl Into<String>) -> Self {
        LoadError {
            location,
            message: message.into(),
        }
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.location, Printable(&self.message))
    }
}

impl std::error::Error for LoadError {}

/// Unusual but valid data (a massless body with rotational inertia, an inertia violating the triangle
/// inequality): the model loads and the warning is reported.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// Where in the model file.
    pub location: Location,
    /// What is unusual.
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "warning: {}: {}",
            self.location,
            Printable(&self.message)
        )
    }
}

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

/// A model that cannot be loaded, or code that cannot be generated or written from it. The message names
/// the file, the element and, where possible, the line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadError {
    /// Where in the model file.
    pub location: Location,
    /// What is wrong.
    pub kind: LoadErrorKind,
}

/// What went wrong, with its data; displayed as the message after the location.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LoadErrorKind {
    /// The model file cannot be read.
    #[error("cannot read the model file: {problem}")]
    Unreadable {
        /// What is wrong with it.
        problem: String,
    },
    /// Elements nested deeper than `limit`, refused before parsing.
    #[error("elements are nested more than {limit} deep here; a URDF needs a handful of levels, so this is not a model file (refused before parsing, which would exhaust the stack)")]
    NestedTooDeep {
        /// The deepest nesting read.
        limit: usize,
    },
    /// The text is not well-formed XML.
    #[error("malformed XML: {problem}")]
    MalformedXml {
        /// What is wrong with it.
        problem: String,
    },
    /// A required attribute is absent.
    #[error("missing attribute `{attribute}`")]
    MissingAttribute {
        /// The attribute.
        attribute: String,
    },
    /// A required child element is absent.
    #[error("missing <{tag}>")]
    MissingElement {
        /// The element.
        tag: String,
    },
    /// An attribute that must be a number is not one.
    #[error("`{attribute}=\"{text}\"` is not a number")]
    NotANumber {
        /// The attribute.
        attribute: String,
        /// Its text.
        text: String,
    },
    /// An attribute that must be a finite number is infinite or NaN.
    #[error("`{attribute}=\"{text}\"` is not a finite number")]
    NotFinite {
        /// The attribute.
        attribute: String,
        /// Its text.
        text: String,
    },
    /// A second `<link>` or `<joint>` (`what`) of a name already used.
    #[error("a {what} of this name is already defined")]
    DuplicateName {
        /// `link` or `joint`.
        what: &'static str,
    },
    /// Every link is some joint's child.
    #[error("the joints form a cycle: every link is some joint's child, so there is no root link")]
    NoRootLink,
    /// A cycle of joints through `link`, apart from the tree of `root`.
    #[error("the joints form a cycle through link \"{link}\", which is not connected to the root link \"{root}\"")]
    Cycle {
        /// A link on the cycle.
        link: String,
        /// The root link.
        root: String,
    },
    /// Any other problem of the model (an unknown link, a cycle, a duplicate name, …), described.
    #[error("{0}")]
    Model(String),
    /// A constant of the model does not fit f32 when f32 functions are generated.
    #[error("{inner} (generated f32 code cannot hold it; generate the f64 functions only)")]
    NotForF32 {
        /// What does not fit.
        inner: Box<LoadErrorKind>,
    },
    /// Code cannot be generated from the model (too large to compile, a constant that is not a number).
    #[error("{0}")]
    Generate(String),
    /// A generated file cannot be written.
    #[error("{0}")]
    Write(String),
}

impl LoadError {
    /// A problem of the model, described by `message`.
    pub fn new(location: Location, message: impl Into<String>) -> Self {
        LoadError::at(location, LoadErrorKind::Model(message.into()))
    }

    /// An error at `location` of `kind`.
    pub fn at(location: Location, kind: LoadErrorKind) -> Self {
        LoadError { location, kind }
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {}",
            self.location,
            Printable(&self.kind.to_string())
        )
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

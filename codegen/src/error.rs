//! Errors and warnings of model loading, each pointing at the file, the element and the line.
//!
//! Every problem is a variant with its data ([`LoadErrorKind`], [`WarningKind`]); the message is made
//! from the data by `thiserror`, so a caller can match on what went wrong and read the names and numbers
//! instead of parsing text.

use crate::algorithm::Algorithm;
use crate::bounded_read::ReadError;
use embedyn_runtime::{DynamicsError, ModelError};
use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
    ///
    /// A name in `element` longer than [`MAX_SHOWN_CHARS`] is kept shortened (see [`shortened`]): the
    /// element is for messages, and a problem must not copy a name of megabytes (one joint's name in
    /// each of its two thousand `<mimic>` problems).
    pub fn new(file: &Path, line: Option<u32>, element: impl Into<String>) -> Self {
        let mut element = element.into();
        shorten_element(&mut element);
        Location {
            file: file.to_path_buf(),
            line,
            element,
        }
    }
}

/// The most characters of a name or a value that messages show; a longer one is cut (see
/// [`shortened`]), so that a name of 20 MB does not become 20 MB of message.
pub const MAX_SHOWN_CHARS: usize = 80;

/// `text`, or its first [`MAX_SHOWN_CHARS`] characters and `… (N bytes)` when it is longer (by more
/// than the 32 characters that note could take, so that a shortened text is never shortened again): what
/// messages show of a name or a value from a model file.
///
/// Line breaks in it are shown as `\n`, `\r` (and U+2028, U+2029 as `\u{2028}`, `\u{2029}`): a name
/// never starts a new line of a message, so a hostile link name cannot forge an `error:` line.
pub fn shortened(text: &str) -> std::borrow::Cow<'_, str> {
    let breaks = |c: char| matches!(c, '\n' | '\r' | '\u{2028}' | '\u{2029}');
    let escaped: std::borrow::Cow<'_, str> = if text.contains(breaks) {
        std::borrow::Cow::Owned(
            text.chars()
                .map(|c| match c {
                    c if breaks(c) => c.escape_default().to_string(),
                    c => c.to_string(),
                })
                .collect(),
        )
    } else {
        std::borrow::Cow::Borrowed(text)
    };
    if escaped.char_indices().nth(MAX_SHOWN_CHARS + 32).is_none() {
        return escaped;
    }
    match escaped.char_indices().nth(MAX_SHOWN_CHARS) {
        None => escaped,
        Some((end, _)) => {
            std::borrow::Cow::Owned(format!("{}… ({} bytes)", &escaped[..end], text.len()))
        }
    }
}

/// Shortens `text` in place where [`shortened`] would.
pub(crate) fn shorten(text: &mut String) {
    if let std::borrow::Cow::Owned(short) = shortened(text) {
        *text = short;
    }
}

/// Shortens each quoted name of an element (`joint "…" <mimic>`), and the whole where it is still long
/// (a name made of quotes).
fn shorten_element(element: &mut String) {
    // (Fast path: a short element has no long name.)
    if element.len() <= MAX_SHOWN_CHARS + 32 {
        return;
    }
    let parts: Vec<std::borrow::Cow<'_, str>> = element.split('"').map(shortened).collect();
    let mut short = parts.join("\"");
    if short.chars().count() > 4 * MAX_SHOWN_CHARS {
        shorten(&mut short);
    }
    *element = short;
}

/// Text for a terminal: control characters (from a file name, or a name written with `&#10;` or `&#27;`
/// in the XML) shown as escapes, so that a message cannot move the cursor, recolour or clear the screen
/// of whoever reads it, nor forge a line of its own; and so are the invisible Unicode format characters
/// that reorder or hide text (bidirectional overrides and isolates, zero-width characters, the line and
/// paragraph separators; see [`is_hidden_format`]), so that what a message shows is what it says.
pub struct Printable<'a>(pub &'a str);

/// Unicode format characters that reorder, join or hide text, or break a line, without being control
/// characters: U+00AD, U+061C, U+180E, U+200B–U+200F, U+2028, U+2029, U+202A–U+202E, U+2060–U+2064,
/// U+2066–U+206F, U+FEFF, U+FFF9–U+FFFB.
pub fn is_hidden_format(c: char) -> bool {
    matches!(
        c,
        '\u{00AD}'
            | '\u{061C}'
            | '\u{180E}'
            | '\u{200B}'..='\u{200F}'
            | '\u{2028}'
            | '\u{2029}'
            | '\u{202A}'..='\u{202E}'
            | '\u{2060}'..='\u{2064}'
            | '\u{2066}'..='\u{206F}'
            | '\u{FEFF}'
            | '\u{FFF9}'..='\u{FFFB}'
    )
}

impl fmt::Display for Printable<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for c in self.0.chars() {
            if c.is_control() || is_hidden_format(c) {
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
///
/// The URDF reader does not stop at the first problem of an element (a missing attribute, a number that
/// is not one, an unknown joint type, …): it reads on and reports every such problem of the file at once,
/// so that a file with five mistakes takes one round of fixing, not five. The first problem is this
/// error's `location` and `kind`, the others are in [`also`](Self::also). They stay inside the one
/// `LoadError` (rather than a list type of their own) so that `Result<_, LoadError>` remains the API of
/// every function that loads or generates, and a caller that looks only at the first problem keeps
/// working unchanged.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadError {
    /// Where in the model file. Boxed so that a `Result<_, LoadError>` stays small (clippy's
    /// `result_large_err`) while the kind holds the runtime's errors inline, where they can be matched.
    pub location: Box<Location>,
    /// What is wrong.
    pub kind: LoadErrorKind,
    /// Further problems found in the same pass over the file, in the order they were found (each with an
    /// empty `also`). Empty for a problem that ends the reading (malformed XML, elements nested too
    /// deep) and for problems found after reading (building the model, generating code).
    pub also: Vec<LoadError>,
    /// Further problems of the same pass that were counted but not kept: a pass keeps at most
    /// [`MAX_KEPT_ERRORS`] (the earliest in the file), so that a file of a million mistakes costs no more
    /// memory than its text. The message counts them with the unlisted ones of `also`.
    pub omitted: usize,
}

/// The most problems [`LoadError`]'s message lists one by one; the rest are counted.
pub const MAX_LISTED_ERRORS: usize = 20;

/// The most problems one pass over a file keeps in a [`LoadError`] (the first and [`LoadError::also`]);
/// the rest are counted in [`LoadError::omitted`].
pub const MAX_KEPT_ERRORS: usize = 100;

/// An error of another library inside a [`LoadErrorKind`], which is `Clone` and `PartialEq` (tests
/// compare kinds) while I/O and parser errors are neither: shared rather than copied, and equal when their
/// messages are.
#[derive(Debug)]
pub struct Shared<E>(pub Arc<E>);

impl<E> Shared<E> {
    /// The error held.
    pub fn get(&self) -> &E {
        &self.0
    }
}

impl<E> Clone for Shared<E> {
    fn clone(&self) -> Self {
        Shared(Arc::clone(&self.0))
    }
}

impl<E: fmt::Display> PartialEq for Shared<E> {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0) || self.0.to_string() == other.0.to_string()
    }
}

impl<E> From<E> for Shared<E> {
    fn from(error: E) -> Self {
        Shared(Arc::new(error))
    }
}

impl<E: fmt::Display> fmt::Display for Shared<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl<E: std::error::Error> std::error::Error for Shared<E> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

/// Which element's axis a [`LoadErrorKind::ZeroAxis`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisOf {
    /// A `<joint>`'s.
    Joint,
    /// A URDF+ `<loop>`'s.
    Loop,
}

impl fmt::Display for AxisOf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            AxisOf::Joint => "joint",
            AxisOf::Loop => "loop",
        })
    }
}

/// The kinds of constraint a name can belong to, as [`LoadErrorKind::ConstraintNameTaken`] names them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConstraintElement {
    /// A URDF+ `<loop>`.
    Loop,
    /// A URDF+ `<coupling>`.
    Coupling,
    /// A joint's `<mimic>` (the constraint takes the joint's name).
    Mimic,
}

impl fmt::Display for ConstraintElement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ConstraintElement::Loop => "loop",
            ConstraintElement::Coupling => "coupling",
            ConstraintElement::Mimic => "the <mimic> of joint",
        })
    }
}

/// How a traced algorithm disagrees with its descriptor ([`LoadErrorKind::DescriptorMismatch`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DescriptorMismatch {
    /// It returns or writes other outputs than described.
    #[error("the outputs are not those described")]
    Outputs,
    /// An output has another number of values than its described shape.
    #[error("`{output}` has {values} values, described {rows}×{cols}")]
    OutputLength {
        /// The output's name.
        output: &'static str,
        /// The values traced.
        values: usize,
        /// The described rows.
        rows: usize,
        /// The described columns.
        cols: usize,
    },
}

/// What went wrong, with its data; displayed as the message after the location.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LoadErrorKind {
    // Reading the file.
    /// The model file cannot be read.
    #[error("cannot read the model file: {error}")]
    Unreadable {
        /// Why.
        #[source]
        error: ReadError,
    },
    /// Elements nested deeper than `limit`, refused before parsing.
    #[error("elements are nested more than {limit} deep here; a URDF needs a handful of levels, so this is not a model file (refused before parsing, which would exhaust the stack)")]
    NestedTooDeep {
        /// The deepest nesting read.
        limit: usize,
    },
    /// An element with more than `limit` attributes, refused before parsing.
    #[error("an element has more than {limit} attributes here; a URDF element has a handful, so this is not a model file (refused before parsing, whose duplicate check is quadratic in an element's attributes)")]
    TooManyAttributes {
        /// The most attributes an element may have.
        limit: usize,
    },
    /// The text is not well-formed XML.
    #[error("malformed XML: {error}")]
    MalformedXml {
        /// The XML parser's error.
        #[source]
        error: roxmltree::Error,
    },
    /// The document's root element is not `<robot>`.
    #[error("the root element must be <robot>")]
    RootNotRobot,

    // One element.
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
    /// An attribute that must not be negative is (an armature, a rotor inertia).
    #[error("`{attribute}` is {value:e}; it must be ≥ 0")]
    Negative {
        /// The attribute.
        attribute: String,
        /// Its value.
        value: f64,
    },
    /// An element whose text must be a number (`<mechanicalReduction>50</mechanicalReduction>`) holds
    /// something else.
    #[error("<{element}> holds \"{text}\", which is not a finite number")]
    TextNotANumber {
        /// The element.
        element: String,
        /// Its text.
        text: String,
    },
    /// A transmission with a rotor inertia names a joint the model does not have (or none).
    #[error(
        "its rotor inertia would add armature to joint \"{joint}\", which the model does not have"
    )]
    UnknownTransmissionJoint {
        /// The joint named (empty when the transmission names none).
        joint: String,
    },
    /// An attribute that must be a finite number is infinite or NaN.
    #[error("`{attribute}=\"{text}\"` is not a finite number")]
    NotFinite {
        /// The attribute.
        attribute: String,
        /// Its text.
        text: String,
    },
    /// A joint's `<limit lower upper>` with lower above upper.
    #[error("`lower` ({lower}) is above `upper` ({upper}): the joint could take no position")]
    LimitsReversed {
        /// The lower limit.
        lower: f64,
        /// The upper limit.
        upper: f64,
    },
    /// An attribute that must be three numbers (`xyz`, `rpy`) has another count of words.
    #[error("`{attribute}=\"{text}\"` must be three numbers")]
    NotThreeNumbers {
        /// The attribute.
        attribute: String,
        /// Its text.
        text: String,
    },
    /// One of an attribute's three numbers is not a number.
    #[error("`{attribute}=\"{text}\"`: \"{entry}\" is not a number")]
    EntryNotANumber {
        /// The attribute.
        attribute: String,
        /// Its text.
        text: String,
        /// The word that is not a number.
        entry: String,
    },
    /// One of an attribute's three numbers is infinite or NaN.
    #[error("`{attribute}=\"{text}\"` contains a number that is not finite")]
    EntryNotFinite {
        /// The attribute.
        attribute: String,
        /// Its text.
        text: String,
    },
    /// An attribute that must be `true` or `false` is neither.
    #[error("attribute `{attribute}` must be \"true\" or \"false\", not \"{text}\"")]
    NotABoolean {
        /// The attribute.
        attribute: String,
        /// Its text.
        text: String,
    },
    /// A `<mass>` below zero.
    #[error("negative mass {mass}")]
    NegativeMass {
        /// The mass given.
        mass: f64,
    },
    /// A `<joint type="planar">`, which embedyn does not support.
    #[error("joint type \"planar\" is not supported (model it as two prismatic joints and a revolute joint)")]
    PlanarJoint,
    /// A joint type URDF does not have.
    #[error("unknown joint type \"{joint_type}\" (expected revolute, continuous, prismatic, fixed or floating)")]
    UnknownJointType {
        /// The type given.
        joint_type: String,
    },
    /// A `<loop type="planar">`, which embedyn does not support.
    #[error("loop type \"planar\" is not supported")]
    PlanarLoop,
    /// A loop type URDF+ does not have.
    #[error("unknown loop type \"{loop_type}\" (expected revolute, continuous, prismatic, spherical or fixed)")]
    UnknownLoopType {
        /// The type given.
        loop_type: String,
    },
    /// A `<parent>`, `<child>`, `<predecessor>` or `<successor>` names a link the file does not define.
    #[error("names link \"{link}\", which does not exist")]
    UnknownLink {
        /// The name given.
        link: String,
    },
    /// A joint or loop that moves along or about its axis has a zero axis.
    #[error("the {of} axis is zero")]
    ZeroAxis {
        /// Whose axis.
        of: AxisOf,
    },

    // The file as a whole.
    /// A second `<link>` or `<joint>` (`what`) of a name already used.
    #[error("a {what} of this name is already defined")]
    DuplicateName {
        /// `link` or `joint`.
        what: &'static str,
    },
    /// A link is the child of a second joint.
    #[error("link \"{link}\" is already the child of joint \"{joint}\"; a link has at most one parent (close loops with URDF+ <loop>)")]
    TwoParents {
        /// The link.
        link: String,
        /// The joint it is already the child of.
        joint: String,
    },
    /// A joint whose parent is its child.
    #[error("parent and child are the same link")]
    SelfParent,
    /// A loop or coupling between a link and itself.
    #[error("predecessor and successor are the same link")]
    SameEnds,
    /// A `<robot>` without links.
    #[error("the model has no <link>")]
    NoLinks,
    /// More than one link is no joint's child.
    #[error("the model has {} root links ({}); a URDF tree has exactly one", .roots.len(), listed_up_to(.roots.iter().cloned(), MAX_LISTED_ERRORS))]
    SeveralRoots {
        /// The root links, in file order.
        roots: Vec<String>,
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
    /// A `<mimic>` names a joint the file does not define.
    #[error("<mimic> names joint \"{joint}\", which does not exist")]
    UnknownMimicTarget {
        /// The name given.
        joint: String,
    },
    /// A loop or coupling named like another constraint.
    #[error("{other} \"{name}\"{} already has this name; loops, couplings and mimic joints are constraints that messages and `info` name, so each needs its own name", at_line(*.other_line))]
    ConstraintNameTaken {
        /// The name.
        name: String,
        /// What the constraint of that name is.
        other: ConstraintElement,
        /// Where it is written.
        other_line: Option<u32>,
    },

    // Building the model.
    /// `--floating` for a file that has a floating joint already.
    #[error("--floating makes the root free, but the file already has a floating joint")]
    AlreadyFloating,
    /// `--floating` for a file that has a joint named like the one it adds.
    #[error("--floating adds the root's joint \"{}\", but the file already has a joint of that name; rename it", crate::assemble::ROOT_JOINT)]
    RootJointNameTaken,
    /// `--lock` names a joint the model does not have.
    #[error("there is no joint \"{}\" to lock", crate::names::shown(.joint))]
    LockUnknownJoint {
        /// The name given.
        joint: String,
    },
    /// `--wrenches` or `--frames` names a link the model does not have.
    #[error("there is no link \"{}\"{hint}", crate::names::shown(.link))]
    UnknownLinkNamed {
        /// The name given.
        link: String,
        /// The closest link names, as ` (did you mean "lf_foot"?)`.
        hint: String,
    },
    /// `--lock` on a joint that has not exactly one coordinate.
    #[error("only a joint of one coordinate (revolute, continuous or prismatic) can be locked, and this joint is {kind}")]
    LockNotOneDof {
        /// The joint's type.
        kind: &'static str,
    },
    /// `--lock` gives one joint two values.
    #[error("the joint is locked twice ({first} and {second}); give one value")]
    LockedTwice {
        /// The first value given.
        first: f64,
        /// The second.
        second: f64,
    },
    /// A `--lock` value that is infinite or NaN.
    #[error("the value to lock the joint at, {value}, is not a finite number")]
    LockValueNotFinite {
        /// The value given.
        value: f64,
    },
    /// `--lock` on a `<mimic>` joint: the joints it follows are the ones to lock (it is fixed with them).
    #[error("{}", locked_mimic_joint(.drivers, *.already_locked))]
    LockedMimicJoint {
        /// The joints at the top of its chains of `<mimic>`s (those that follow no other joint), or, in a
        /// cycle of mimics, the joints it follows itself.
        drivers: Vec<String>,
        /// Whether all of them are locked: then it is fixed already.
        already_locked: bool,
    },
    /// The offset of a `<mimic>` once a locked joint's term joins it.
    #[error("the offset of its <mimic> becomes {value}, not a finite number")]
    MimicOffsetNotFinite {
        /// The offset.
        value: f64,
    },
    /// A joint that mimics a locked joint, where the lock cannot be carried into its `<mimic>`.
    #[error("locking joint \"{}\" makes the term of it in this joint's <mimic> a constant, but {reason}", crate::names::shown(.driver))]
    LockFixesMimicJoint {
        /// The joint locked.
        driver: String,
        /// Why this joint cannot be fixed.
        reason: Box<LoadErrorKind>,
    },
    /// `--lock` on a joint whose coordinate a loop or coupling relates to others.
    #[error("the joint cannot be locked: {what} \"{}\" relates its coordinate to others (locking it would change the constraint; lock joints outside loops and couplings, or fix the joint in the file)", crate::names::shown(.name))]
    LockedJointInConstraint {
        /// What the constraint is.
        what: ConstraintElement,
        /// Its name.
        name: String,
    },
    /// `--rotors reflected`: ratio² × the rotor's axial inertia overflows f64.
    #[error("--rotors reflected would put ratio² × rotor inertia on the driving joints, and with ratio {ratio:e} and axial inertia {axial_inertia:e} kg·m² that overflows f64; model this coupling exactly")]
    ReflectedInertiaOverflow {
        /// The coupling's ratio.
        ratio: f64,
        /// The rotor's axial inertia (kg·m²).
        axial_inertia: f64,
    },
    /// A transmission's gear ratio of zero.
    #[error("a gear ratio of 0 would make the rotor's inertia vanish from the joint; the ratio is the rotor's speed over the joint's (e.g. 50)")]
    ZeroGearRatio,
    /// A floating joint below the root.
    #[error("a floating joint must connect the root (a link fixed to the world) to the rest of the tree")]
    FloatingNotAtRoot,
    /// A link's inertia about its body frame is not finite in f64.
    #[error("the link's inertia about its body frame overflows f64 (mass {mass:e} kg, centre of mass {com_distance:e} m from the frame, rotational inertia up to {largest_moment:e} kg·m²): the numbers are too large to combine")]
    InertiaOverflow {
        /// The link's mass (kg).
        mass: f64,
        /// Its centre of mass's distance from the body frame (m).
        com_distance: f64,
        /// The largest entry of its rotational inertia (kg·m²).
        largest_moment: f64,
    },
    /// Adding a link's inertia to the body it is fixed to overflows f64.
    #[error("adding this link's inertia to the body it is fixed to (link \"{body_link}\") overflows f64: the numbers are too large to combine")]
    MergedInertiaOverflow {
        /// The body's own link.
        body_link: String,
    },
    /// Both frames of a loop are on one rigid body.
    #[error("both frames are on the same rigid body (the links are joined by fixed joints): the loop constrains nothing or can never close")]
    LoopWithinOneBody,
    /// No moving joint lies between a coupling's links.
    #[error("no moving joint lies between the two links: the coupling relates nothing")]
    CouplingRelatesNothing,
    /// A `<mimic>` on a fixed joint that is still a constraint (on a fixed joint it is ignored with a warning).
    #[error("a fixed joint cannot mimic another joint")]
    FixedJointMimics,
    /// A `<mimic>` whose driving joint is fixed.
    #[error("the driving joint \"{joint}\" is fixed")]
    FixedDriver {
        /// The driving joint.
        joint: String,
    },
    /// A joint that mimics itself (or a joint on its own body).
    #[error("a joint cannot mimic itself")]
    MimicSelf,
    /// The subtree a joint moves has no inertia about its axis, in the scalar type `scalar`.
    #[error("the links this joint moves have no inertia about its axis beyond rounding{} (D = {d:e}), so its acceleration is undetermined; give the child link an <inertial> or make the joint fixed", precision_of(.scalar))]
    UndeterminedAcceleration {
        /// The articulated inertia about the axis.
        d: f64,
        /// The scalar type (`"f64"`, `"f32"`).
        scalar: &'static str,
    },
    /// The runtime refused the model (a loop that never closes, a constant that does not fit, …).
    #[error("{0}")]
    Model(#[from] ModelError),
    /// A constant of the model does not fit f32 when f32 functions are generated.
    #[error("{inner} (generated f32 code cannot hold it; generate the f64 functions only)")]
    NotForF32 {
        /// What does not fit.
        inner: Box<LoadErrorKind>,
    },

    // Generating code.
    /// A function that exists only for models with constraints, asked for a tree.
    #[error("`{}` exists only for a model with loops, couplings or mimic joints; this one is a tree", .function.name())]
    NeedsConstraints {
        /// The function.
        function: Algorithm,
    },
    /// A lane count the scalar has no lane type of.
    #[error("`lanes = {lanes}` / `--lanes {lanes}` has no lane type for {scalar} (lanes: 2 or 4 for f64, 4 or 8 for f32; `f64_only` or `f32_only` in robot!, `--scalar f64|f32` for embedyn generate, picks one scalar)")]
    NoLaneType {
        /// The scalar.
        scalar: &'static str,
        /// The lanes asked for.
        lanes: usize,
    },
    /// A function generated for links named at generation time, asked for without any.
    #[error("`{}` is generated for links named at generation time, and none is named: {}", .function.name(), links_option(*.function))]
    NeedsLinks {
        /// The function.
        function: Algorithm,
    },
    /// A link named twice in `wrenches(…)` or `frames(…)`.
    #[error("the link \"{}\" is named twice in {option} (each link once: {per_link})", crate::names::shown(.link))]
    LinkNamedTwice {
        /// The link.
        link: String,
        /// The option (`--wrenches / wrenches(…)`, …).
        option: &'static str,
        /// What each link named there gets (`one row of \`f_ext\` per link`, …).
        per_link: &'static str,
    },
    /// Links named for functions that `only(…)` leaves out: they would be silently ignored.
    #[error("{option} names links, but no function generated takes them: add {functions} to `only(…)` / `--only`, or drop the links")]
    LinksUnused {
        /// The option (`--wrenches / wrenches(…)`, …).
        option: &'static str,
        /// The functions that would take them.
        functions: &'static str,
    },
    /// A constant folded from the model's numbers is beyond f32's range.
    #[error("`{}`: the constant {constant:e}, folded from the model's numbers, is beyond the range of the scalar type f32 (largest {:e}); generated f32 code cannot hold it, generate the f64 functions only", .function.name(), f32::MAX)]
    ConstantBeyondF32 {
        /// The function.
        function: Algorithm,
        /// The constant.
        constant: f64,
    },
    /// The generated code would need more memory to compile than allowed.
    #[error("{0}")]
    TooLargeToCompile(Box<crate::size::TooLargeToCompile>),
    /// Tracing an algorithm on the model failed.
    #[error("tracing {}: {error}", .function.name())]
    Trace {
        /// The algorithm.
        function: Algorithm,
        /// Its error.
        #[source]
        error: DynamicsError,
    },
    /// A traced algorithm disagrees with its descriptor (a bug of embedyn).
    #[error("tracing {}: {problem} (the algorithm's descriptor and its implementation disagree; a bug)", .function.name())]
    DescriptorMismatch {
        /// The algorithm.
        function: Algorithm,
        /// How.
        problem: DescriptorMismatch,
    },
    /// A value the generated code would write as a literal is not a number.
    #[error("{0}")]
    Emit(#[from] crate::emit::EmitError),
    /// Generated code is not Rust tokens (a bug of embedyn).
    #[error("generated code does not tokenize: {error}")]
    Tokenize {
        /// The lexer's error.
        #[source]
        error: Shared<syn::Error>,
    },
    /// Generated code does not parse as a Rust file (a bug of embedyn).
    #[error("{0}")]
    Unparsable(#[from] crate::generate::UnparsableCode),
    /// A generated `Cargo.toml` cannot be written as TOML.
    #[cfg(feature = "standalone")]
    #[error("{0}")]
    Manifest(#[from] crate::standalone::ManifestError),
    /// A model path that cannot be passed to cargo's build-script protocol.
    #[error("a model path with a line break cannot be given to cargo (cargo:rerun-if-changed)")]
    PathWithLineBreak,

    // Writing files.
    /// A generated file cannot be written to `path`.
    #[error("cannot write {}: {error}", .path.display())]
    CannotWriteTo {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        error: Shared<std::io::Error>,
    },
    /// `embedyn generate` would replace a file it did not write (the location names it).
    #[error("exists and was not written by embedyn: `generate` replaces only its own files (a Cargo.toml, README.md or src/lib.rs whose first line is its \"Generated by embedyn\" marker), never a link or a crate of yours; choose a new or empty folder, or remove the file")]
    WouldReplace,
    /// `--out` names something that is not a folder (the location names it).
    #[error(
        "is not a folder: `--out` names the folder the crate is written into (created if needed)"
    )]
    OutNotAFolder,
    /// With lanes, one frame function's batch form would take another frame function's name.
    #[error("with lanes, the batch form of `{function}` (the frame function of link {}) would be named `{function}_batch`, the frame function of link {}: name the frames of one of the two links in a crate or module without lanes (or rename the link)", crate::names::code_span(.of_link), crate::names::code_span(.link))]
    BatchNameTaken {
        /// The frame function whose batch form clashes.
        function: String,
        /// The link whose frame function has the batch form's name.
        link: String,
        /// The link of `function`.
        of_link: String,
    },
    /// `embedyn generate --name` gives no usable crate name.
    #[error("--name {message}")]
    BadCrateName {
        /// What is wrong with it, naming it (`names::check_crate_name`).
        message: String,
    },
    /// A file or folder cannot be written (the location names it).
    #[error("cannot write: {error}")]
    CannotWrite {
        /// Why.
        #[source]
        error: Shared<std::io::Error>,
    },
}

/// ` at line 7`, or nothing when the line is unknown.
fn at_line(line: Option<u32>) -> String {
    line.map_or(String::new(), |l| format!(" at line {l}"))
}

/// ` at the precision of f32`, or nothing for f64 (where rounding is the reader's assumption).
fn precision_of(scalar: &str) -> String {
    if scalar == <f64 as embedyn_runtime::Real>::NAME {
        String::new()
    } else {
        format!(" at the precision of {scalar}")
    }
}

impl LoadError {
    /// An error at `location` of `kind`.
    ///
    /// Names and texts in `kind` longer than [`MAX_SHOWN_CHARS`] are kept shortened ([`shortened`]), as
    /// [`Location::new`] keeps the element's.
    pub fn at(location: Location, mut kind: LoadErrorKind) -> Self {
        kind.shorten_texts();
        LoadError {
            location: Box::new(location),
            kind,
            also: Vec::new(),
            omitted: 0,
        }
    }

    /// This error's first problem and those in [`also`](Self::also), in file order.
    pub fn problems(&self) -> impl Iterator<Item = &LoadError> {
        std::iter::once(self).chain(&self.also)
    }

    /// The errors of one pass as one `LoadError`: the first, holding the others; `None` when there are
    /// none. `omitted` more were counted and not kept.
    pub(crate) fn collected(errors: Vec<LoadError>, omitted: usize) -> Option<LoadError> {
        let mut omitted = omitted;
        let mut errors = errors.into_iter().flat_map(|mut e| {
            let also = std::mem::take(&mut e.also);
            omitted += std::mem::take(&mut e.omitted);
            std::iter::once(e).chain(also)
        });
        let mut first = errors.next()?;
        first.also = errors.collect();
        first.omitted = omitted;
        Some(first)
    }
}

/// The message of [`LoadErrorKind::LockedMimicJoint`].
fn locked_mimic_joint(drivers: &[String], already_locked: bool) -> String {
    let names: Vec<String> = drivers
        .iter()
        .map(|d| format!("\"{}\"", crate::names::shown(d)))
        .collect();
    let (joints, list) = match names.as_slice() {
        [one] => ("joint", one.clone()),
        [rest @ .., last] => ("joints", format!("{} and {last}", rest.join(", "))),
        [] => ("joints", String::new()),
    };
    if already_locked {
        format!("the joint is fixed already: it follows {joints} {list} through <mimic>, locked; leave its own lock out")
    } else {
        let them = if names.len() == 1 {
            list.as_str()
        } else {
            "them"
        };
        format!("the joint cannot be locked: it follows {joints} {list} through <mimic>; lock {them} instead, and the joints that follow are fixed with {}", if names.len() == 1 { "it" } else { "them" })
    }
}

impl LoadErrorKind {
    /// Shortens every name and text from the model file ([`shorten`]).
    fn shorten_texts(&mut self) {
        use LoadErrorKind as K;
        match self {
            K::MissingAttribute { attribute: a }
            | K::MissingElement { tag: a }
            | K::UnknownJointType { joint_type: a }
            | K::UnknownLoopType { loop_type: a }
            | K::UnknownLink { link: a }
            | K::UnknownMimicTarget { joint: a }
            | K::FixedDriver { joint: a }
            | K::LockUnknownJoint { joint: a }
            | K::UnknownLinkNamed { link: a, .. }
            | K::LockedJointInConstraint { name: a, .. }
            | K::ConstraintNameTaken { name: a, .. }
            | K::MergedInertiaOverflow { body_link: a } => shorten(a),
            K::NotANumber { attribute, text }
            | K::NotFinite { attribute, text }
            | K::NotThreeNumbers { attribute, text }
            | K::EntryNotFinite { attribute, text }
            | K::NotABoolean { attribute, text } => {
                shorten(attribute);
                shorten(text);
            }
            K::EntryNotANumber {
                attribute,
                text,
                entry,
            } => {
                shorten(attribute);
                shorten(text);
                shorten(entry);
            }
            K::TwoParents { link, joint } => {
                shorten(link);
                shorten(joint);
            }
            K::Cycle { link, root } => {
                shorten(link);
                shorten(root);
            }
            K::SeveralRoots { roots } => roots.iter_mut().for_each(shorten),
            K::NotForF32 { inner } => inner.shorten_texts(),
            K::LockedMimicJoint { drivers, .. } => drivers.iter_mut().for_each(shorten),
            K::LockFixesMimicJoint { driver, reason } => {
                shorten(driver);
                reason.shorten_texts();
            }
            _ => {}
        }
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {}",
            self.location,
            Printable(&self.kind.to_string())
        )?;
        // The first line is the message a single problem has always had; each further problem is a line
        // of its own, in the same form, so that editors and `grep` find every `file:line:`.
        let listed = self.also.len().min(MAX_LISTED_ERRORS - 1);
        for e in &self.also[..listed] {
            write!(f, "\n{}: {}", e.location, Printable(&e.kind.to_string()))?;
        }
        let more = self.also.len() - listed + self.omitted;
        if more > 0 {
            write!(f, "\nand {more} more errors")?;
        }
        Ok(())
    }
}

impl std::error::Error for LoadError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        std::error::Error::source(&self.kind)
    }
}

/// Unusual but valid data (a massless body with rotational inertia, an inertia violating the triangle
/// inequality): the model loads and the warning is reported.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    /// Where in the model file (the first element, when the same warning is folded for several).
    pub location: Location,
    /// What is unusual.
    pub kind: WarningKind,
    /// The other elements with the same warning (talos_reduced's twelve `<mimic>` leftovers on fixed
    /// joints), or with a warning of the same kind that differs only in its numbers (an inertia that is
    /// not positive): one warning names them all, since a screen of near-identical lines hides what
    /// differs.
    pub same_for: Vec<String>,
    /// Whether some warning folded into this one had other numbers than `kind`'s (which are then the
    /// first element's, an example): the message says "also for" rather than "the same for".
    pub numbers_differ: bool,
}

/// What is unusual, with its data; displayed as the warning's message after the location.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum WarningKind {
    /// An inertia tensor with a negative eigenvalue (beyond rounding).
    #[error("the inertia tensor is not positive semi-definite (ixx={ixx}, iyy={iyy}, izz={izz}, ixy={ixy}, ixz={ixz}, iyz={iyz}; smallest eigenvalue {smallest_eigenvalue:.3e}): no rigid body has it; loaded as given")]
    InertiaNotPositive {
        /// `ixx` as given.
        ixx: f64,
        /// `iyy` as given.
        iyy: f64,
        /// `izz` as given.
        izz: f64,
        /// `ixy` as given.
        ixy: f64,
        /// `ixz` as given.
        ixz: f64,
        /// `iyz` as given.
        iyz: f64,
        /// The tensor's smallest eigenvalue.
        smallest_eigenvalue: f64,
    },
    /// Principal moments that violate the triangle inequality.
    #[error("the principal moments of inertia violate the triangle inequality (no rigid body has them); loaded as given")]
    TriangleInequality,
    /// Zero mass with rotational inertia.
    #[error("zero mass with a non-zero rotational inertia (a massless rotor); loaded as given")]
    MasslessRotor,
    /// An element URDF has once given several times: the first is read.
    #[error("<{element}> is given {count} times; the first is read (as urdfdom, and so Pinocchio, reads it), the others are ignored")]
    RepeatedElement {
        /// The element's tag.
        element: String,
        /// How many times it is given.
        count: usize,
    },
    /// A `<mimic>` on a fixed joint, ignored.
    #[error("<mimic> on a fixed joint has nothing to drive; ignored")]
    MimicOnFixedJoint,
    /// A namespace prefix used without a declaration, read as if declared.
    #[error("the namespace prefix `{prefix}` is used without a declaration; read as declared (add xmlns:{prefix}=\"…\" to <robot>, e.g. xmlns:drake=\"http://drake.mit.edu\")")]
    UndeclaredNamespace {
        /// The prefix.
        prefix: String,
    },
    /// A transmission's rotor inertia on a joint that does not move.
    #[error("a rotor inertia on the fixed joint \"{joint}\" moves nothing; ignored")]
    RotorOnFixedJoint {
        /// The joint.
        joint: String,
    },
    /// A transmission of several joints with a rotor inertia: how it maps to the joints is not read.
    #[error("a transmission of {joints} joints: embedyn reads the rotor inertia of transmissions of one joint (SimpleTransmission) only; its rotors add no armature (give each joint <dynamics armature>)")]
    MultiJointTransmission {
        /// How many joints it names.
        joints: usize,
    },
    /// A file without a floating joint that has one inside a comment (example-robot-data's G1: "uncomment
    /// when convert to mujoco"): read as written, its root is fixed to the world, which a user of a
    /// legged robot rarely means. Tools that know the scene's options drop it where the root is made free.
    #[error("a joint of type \"floating\" is written only inside a comment, so the root link `{root}` is fixed to the world as the file stands; for a free-floating base pass --floating (`floating` in robot! and ModelOptions)")]
    FloatingJointInComment {
        /// The root link of the file's tree.
        root: String,
    },
    /// Joint damping or friction, which the dynamics does not model.
    #[error("<dynamics damping/friction> of {} joint(s) ({}) ignored: embedyn computes the dynamics of ideal joints (as Pinocchio's algorithms do); add the losses to tau", .joints.len(), listed(.joints.iter().map(|j| format!("\"{j}\""))))]
    JointDynamicsIgnored {
        /// The joints with non-zero damping or friction, in file order.
        joints: Vec<String>,
    },
}

/// What [`WarningKind::fold_key`] folds by: warnings of equal keys are reported as one.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) enum WarningFoldKey {
    /// A kind whose warnings fold whatever their numbers (a tensor that is not positive, at any
    /// values): its discriminant.
    Kind(std::mem::Discriminant<WarningKind>),
    /// A kind whose warnings fold only when equal: its message.
    Message(String),
}

impl WarningKind {
    /// What warnings fold by: kinds that differ only in their numbers fold into one line (the numbers
    /// are the first element's, an example), kinds with names fold only when equal.
    pub(crate) fn fold_key(&self) -> WarningFoldKey {
        match self {
            WarningKind::JointDynamicsIgnored { .. }
            | WarningKind::UndeclaredNamespace { .. }
            | WarningKind::RotorOnFixedJoint { .. }
            | WarningKind::RepeatedElement { .. } => WarningFoldKey::Message(self.to_string()),
            _ => WarningFoldKey::Kind(std::mem::discriminant(self)),
        }
    }
}

/// The most names a warning lists one by one; the rest are counted.
const LISTED_NAMES: usize = 5;

/// `a, b, c, d, e and 3 more`.
fn listed(names: impl ExactSizeIterator<Item = String>) -> String {
    listed_up_to(names, LISTED_NAMES)
}

/// The first `most` of `names`, then how many more.
fn listed_up_to(names: impl ExactSizeIterator<Item = String>, most: usize) -> String {
    let count = names.len();
    let mut list = names
        .take(most)
        .map(|n| shortened(&n).into_owned())
        .collect::<Vec<_>>()
        .join(", ");
    if count > most {
        list += &format!(" and {} more", count - most);
    }
    list
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut message = self.kind.to_string();
        if !self.same_for.is_empty() {
            let names = listed(self.same_for.iter().cloned());
            if self.numbers_differ {
                message += &format!(" (also for {names}, with numbers of their own)");
            } else {
                message += &format!(" (the same for {names})");
            }
        }
        write!(f, "warning: {}: {}", self.location, Printable(&message))
    }
}

/// How the links of `function` are named (for [`LoadErrorKind::NeedsLinks`]).
fn links_option(function: Algorithm) -> &'static str {
    match function.spec().parameter {
        crate::algorithm::Parameter::Frame => {
            "name them with `frames(link, …)` (robot!) or `--frames LINK,…` (embedyn generate)"
        }
        _ => "name the links that take wrenches with `wrenches(link, …)` (robot!) or `--wrenches LINK,…` (embedyn generate)",
    }
}

#[cfg(test)]
mod shortened_tests {
    use super::shortened;

    /// A name in a message never starts a new line (attacker trial, issue 11: a link named
    /// `new\nline` printed across two lines, and so could forge an `error:` line), and a shortened name
    /// is never shortened again.
    #[test]
    fn names_in_messages_never_break_lines() {
        assert_eq!(shortened("new\nline"), "new\\nline");
        assert_eq!(shortened("a\r\u{2028}b"), "a\\r\\u{2028}b");
        assert_eq!(shortened("plain"), "plain");
        let long = "x\n".repeat(200);
        let once = shortened(&long).into_owned();
        assert!(
            !once.contains('\n') && once.ends_with("(400 bytes)"),
            "{once}"
        );
        assert_eq!(shortened(&once), once);
    }
}

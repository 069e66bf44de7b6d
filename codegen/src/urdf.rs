//! Reads URDF into the model IR with `roxmltree`, keeping line numbers for messages.
//!
//! `urdf-rs` is not used: it drops URDF+ elements, keeps no source positions and rejects a joint with two
//! `<mimic>` children (a differential).

use crate::bounded_read::read_model_file;
use crate::error::{
    shortened, AxisOf, ConstraintElement, LoadError, LoadErrorKind, Location, Warning,
    WarningFoldKey, WarningKind, MAX_KEPT_ERRORS,
};
use crate::ir::{
    Coupling, Inertial, Joint, JointKind, Limits, Link, Loop, LoopFrame, LoopKind, Mimic, Origin,
    Robot,
};
use crate::xml_text::{beyond_limits, Beyond, LineIndex, MAX_ATTRIBUTES, MAX_NESTING};
use embedyn_runtime::nalgebra::Matrix3;
use roxmltree::{Document, Node};
use std::cell::{Cell, RefCell};
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// A parsed model and the warnings its data raised.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The model as the file describes it.
    pub robot: Robot,
    /// Unusual but valid data, each at its element.
    pub warnings: Vec<Warning>,
}

/// Warnings of one kind at several elements (talos_reduced's twelve `<mimic>` leftovers on fixed
/// joints, a CAD export's hundred inertias that are not positive) become one, at the first, naming the
/// others: a screen of near-identical lines hides what differs. Warnings that differ only in their
/// numbers fold too ([`WarningKind::fold_key`]): one line says the kind of problem and where, the first
/// element's numbers show an example. Linear: a hash map from the kind's key to its folded warning.
fn fold_repeated_warnings(warnings: &mut Vec<Warning>) {
    let mut folded: Vec<Warning> = Vec::new();
    let mut first_of: HashMap<WarningFoldKey, usize> = HashMap::new();
    for w in warnings.drain(..) {
        match first_of.get(&w.kind.fold_key()) {
            Some(&i) => {
                let first = &mut folded[i];
                first.numbers_differ |= first.kind != w.kind;
                first.same_for.push(w.location.element);
            }
            None => {
                first_of.insert(w.kind.fold_key(), folded.len());
                folded.push(w);
            }
        }
    }
    *warnings = folded;
}

/// Reads and checks a URDF file.
pub fn load_urdf(path: &Path) -> Result<Loaded, LoadError> {
    let text = read_model_file(path).map_err(|error| {
        LoadError::at(
            Location::new(path, None, ""),
            LoadErrorKind::Unreadable { error },
        )
    })?;
    parse_urdf(&text, path)
}

/// Parses URDF text; `path` is used in messages only.
///
/// A problem of an element (a missing attribute, a number that is not one, an unknown joint type or
/// link, a zero axis, …) does not end the reading: every such problem of the file is reported in one
/// [`LoadError`] (the first as the error, the others in [`LoadError::also`]). What makes the rest
/// meaningless ends it at once: malformed XML, nesting too deep, a root element that is not `<robot>`,
/// and the tree's own shape (no link, several roots, a cycle), which is judged only once every link and
/// joint was read without a problem.
pub fn parse_urdf(text: &str, path: &Path) -> Result<Loaded, LoadError> {
    let lines = LineIndex::new(text);
    if let Some(beyond) = beyond_limits(text, MAX_NESTING, MAX_ATTRIBUTES) {
        let (offset, kind) = match beyond {
            Beyond::Nesting { offset, .. } => {
                (offset, LoadErrorKind::NestedTooDeep { limit: MAX_NESTING })
            }
            Beyond::Attributes { offset, .. } => (
                offset,
                LoadErrorKind::TooManyAttributes {
                    limit: MAX_ATTRIBUTES,
                },
            ),
        };
        return Err(LoadError::at(
            Location::new(path, Some(lines.line(offset)), "XML"),
            kind,
        ));
    }
    // Namespace prefixes used without a declaration (`<drake:rotor_inertia>` in a `<robot>` that never
    // declares `xmlns:drake`, as files Pinocchio reads do) are declared on the root and reported; the
    // declaration goes on the root's own line, so every line number stays.
    let mut patched = std::borrow::Cow::Borrowed(text);
    let mut undeclared: Vec<(String, u32)> = Vec::new();
    let doc = loop {
        match Document::parse(&patched) {
            Err(roxmltree::Error::UnknownNamespace(prefix, pos))
                if undeclared.len() < MAX_UNDECLARED_PREFIXES
                    && !undeclared.iter().any(|(p, _)| *p == prefix) =>
            {
                let Some(at) = root_tag_end(&patched) else {
                    break Document::parse(&patched);
                };
                let mut owned = patched.into_owned();
                owned.insert_str(
                    at,
                    &format!(" xmlns:{prefix}=\"urn:embedyn:undeclared:{prefix}\""),
                );
                patched = std::borrow::Cow::Owned(owned);
                undeclared.push((prefix, pos.row));
            }
            other => break other,
        }
    }
    .map_err(|error| {
        let pos = error.pos();
        LoadError::at(
            Location::new(path, Some(pos.row), "XML"),
            LoadErrorKind::MalformedXml { error },
        )
    })?;
    let mut p = Parser {
        doc: &doc,
        lines,
        path,
        warnings: Vec::new(),
        errors: RefCell::new(Vec::new()),
        omitted: Cell::new(0),
    };
    for (prefix, line) in undeclared {
        p.warnings.push(Warning {
            location: Location::new(path, Some(line), "XML"),
            kind: WarningKind::UndeclaredNamespace { prefix },
            same_for: Vec::new(),
            numbers_differ: false,
        });
    }
    let robot = p.robot()?;
    Ok(Loaded {
        robot,
        warnings: p.warnings,
    })
}

/// The most undeclared namespace prefixes declared on the reader's behalf (each costs a parse).
const MAX_UNDECLARED_PREFIXES: usize = 8;

/// Where the root element's name ends in `text` (after `<robot`), to declare a namespace there; `None`
/// when the root is not `<robot` (the reader then reports that).
fn root_tag_end(text: &str) -> Option<usize> {
    let mut rest = 0;
    while let Some(k) = text[rest..].find('<') {
        let at = rest + k;
        let tail = &text[at + 1..];
        if tail.starts_with('?') || tail.starts_with('!') {
            // A declaration, comment or doctype: skip past its end.
            let end = if tail.starts_with("!--") { "-->" } else { ">" };
            rest = at + 1 + tail.find(end)? + end.len();
            continue;
        }
        let name_end = tail
            .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
            .unwrap_or(tail.len());
        return (&tail[..name_end] == "robot").then_some(at + 1 + name_end);
    }
    None
}

/// The problem of an element has been recorded in [`Parser::errors`]; what depends on the element is
/// skipped (a joint with an unknown type is not added to the tree), the reading goes on.
#[derive(Debug)]
struct Reported;

/// What an element's reader returns: the element, or [`Reported`].
type Parsed<T> = Result<T, Reported>;

struct Parser<'a, 'input> {
    doc: &'a Document<'input>,
    lines: LineIndex,
    path: &'a Path,
    warnings: Vec<Warning>,
    /// The problems found so far, in the order found (serde_derive's `Ctxt`: errors collected where they
    /// are found, through `&self`, and turned into one `LoadError`, in line order, once the pass is over).
    /// A `RefCell`, so that the readers, which borrow the parser immutably (and the closures inside them),
    /// can record. At most 2 × [`MAX_KEPT_ERRORS`]: past that the earliest in the file are kept and the
    /// rest counted in `omitted`, so that the memory stays bounded by the file's.
    errors: RefCell<Vec<LoadError>>,
    /// Problems found and not kept.
    omitted: Cell<usize>,
}

/// Sorts problems by line (stably: the problems of one line stay in the order found), those without a
/// line last, and keeps the first `keep`; returns how many it dropped.
fn earliest_problems(errors: &mut Vec<LoadError>, keep: usize) -> usize {
    errors.sort_by_key(|e| e.location.line.unwrap_or(u32::MAX));
    let dropped = errors.len().saturating_sub(keep);
    errors.truncate(keep);
    dropped
}

impl<'a, 'input> Parser<'a, 'input> {
    fn line(&self, node: Node) -> Option<u32> {
        Some(self.lines.line(node.range().start))
    }

    fn loc(&self, node: Node, element: impl Into<String>) -> Location {
        Location::new(self.path, self.line(node), element)
    }

    /// Records a problem at `location`; the reading goes on.
    fn record(&self, location: Location, kind: LoadErrorKind) {
        let mut errors = self.errors.borrow_mut();
        errors.push(LoadError::at(location, kind));
        if errors.len() >= 2 * MAX_KEPT_ERRORS {
            let dropped = earliest_problems(&mut errors, MAX_KEPT_ERRORS);
            self.omitted.set(self.omitted.get() + dropped);
        }
    }

    /// Records a problem of `element` at `node`, and returns that the element is [`Reported`].
    fn fail<T>(&self, node: Node, element: impl Into<String>, kind: LoadErrorKind) -> Parsed<T> {
        self.record(self.loc(node, element), kind);
        Err(Reported)
    }

    /// Whether a problem has been recorded.
    fn has_errors(&self) -> bool {
        !self.errors.borrow().is_empty()
    }

    /// The problems recorded, as one error, in line order (the reader's passes go links, joints, mimics,
    /// loops, but the first problem reported is the earliest in the file); `Ok` when there are none.
    fn finish(&self) -> Result<(), LoadError> {
        let mut errors = self.errors.take();
        let omitted = self.omitted.take() + earliest_problems(&mut errors, MAX_KEPT_ERRORS);
        match LoadError::collected(errors, omitted) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }

    fn warn(&mut self, node: Node, element: impl Into<String>, kind: WarningKind) {
        let w = Warning {
            location: self.loc(node, element),
            kind,
            same_for: Vec::new(),
            numbers_differ: false,
        };
        self.warnings.push(w);
    }

    fn robot(&mut self) -> Result<Robot, LoadError> {
        let root = self.doc.root_element();
        if root.tag_name().name() != "robot" {
            return Err(LoadError::at(
                self.loc(root, format!("<{}>", root.tag_name().name())),
                LoadErrorKind::RootNotRobot,
            ));
        }
        let name = root.attribute("name").unwrap_or("robot").to_string();
        let mut links = Vec::new();
        let mut link_index: HashMap<String, usize> = HashMap::new();
        for node in root.children().filter(|n| n.has_tag_name("link")) {
            let Ok(link) = self.link(node) else { continue };
            if link_index.contains_key(&link.name) {
                self.record(
                    self.loc(node, format!("link \"{}\"", link.name)),
                    LoadErrorKind::DuplicateName { what: "link" },
                );
                continue;
            }
            link_index.insert(link.name.clone(), links.len());
            links.push(link);
        }
        let mut joints: Vec<Joint> = Vec::new();
        let mut joint_names: HashSet<String> = HashSet::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
        for node in root.children().filter(|n| n.has_tag_name("joint")) {
            let Ok(joint) = self.joint(node, &link_index) else {
                continue;
            };
            let what = format!("joint \"{}\"", joint.name);
            if !joint_names.insert(joint.name.clone()) {
                self.record(
                    self.loc(node, what),
                    LoadErrorKind::DuplicateName { what: "joint" },
                );
                continue;
            }
            if let Some(other) = parent_joint[joint.child] {
                let kind = LoadErrorKind::TwoParents {
                    link: links[joint.child].name.clone(),
                    joint: joints[other].name.clone(),
                };
                self.record(self.loc(node, what), kind);
                continue;
            }
            if joint.parent == joint.child {
                self.record(self.loc(node, what), LoadErrorKind::SelfParent);
                continue;
            }
            parent_joint[joint.child] = Some(joints.len());
            joints.push(joint);
        }
        // The tree's shape is judged only from a complete tree: with a joint left out (its type unknown,
        // say) its child would be another root, which is no news to the reader. Its problem is, and so
        // are those of the loops and mimics below.
        let mut root_link = 0;
        if !self.has_errors() {
            root_link = self.tree_root(root, &name, &links, &joints, &parent_joint)?;
        }
        // Mimic targets must exist (a joint the reader left out counts as existing: its own problem
        // is reported) and be another joint: a file error whatever the scene options (a lock of the joint
        // would otherwise be refused first and hide it).
        let written_joints: HashSet<&str> = root
            .children()
            .filter(|n| n.has_tag_name("joint"))
            .filter_map(|n| n.attribute("name"))
            .collect();
        for joint in &joints {
            // (Shortened once per joint, not once per <mimic>: a joint's name may be megabytes long.)
            let element = format!("joint \"{}\" <mimic>", shortened(&joint.name));
            for m in &joint.mimics {
                if m.joint == joint.name {
                    self.record(
                        Location::new(self.path, m.line, element.clone()),
                        LoadErrorKind::MimicSelf,
                    );
                } else if !written_joints.contains(m.joint.as_str()) {
                    self.record(
                        Location::new(self.path, m.line, element.clone()),
                        LoadErrorKind::UnknownMimicTarget {
                            joint: m.joint.clone(),
                        },
                    );
                }
            }
        }
        let mut loops = Vec::new();
        let mut couplings = Vec::new();
        // Every constraint has a name that messages and `info` use to point at it: a loop's or a
        // coupling's own, a mimic joint's is its joint's. The names must tell them apart.
        let mut constraint_names: HashMap<String, (ConstraintElement, Option<u32>)> = joints
            .iter()
            .filter(|j| !j.mimics.is_empty())
            .map(|j| (j.name.clone(), (ConstraintElement::Mimic, j.line)))
            .collect();
        for node in root
            .children()
            .filter(|n| n.has_tag_name("loop") || n.has_tag_name("coupling"))
        {
            let (tag, name, line) = if node.has_tag_name("loop") {
                let Ok(l) = self.loop_element(node, &link_index) else {
                    continue;
                };
                let named = (ConstraintElement::Loop, l.name.clone(), l.line);
                loops.push(l);
                named
            } else {
                let Ok(c) = self.coupling(node, &link_index) else {
                    continue;
                };
                let named = (ConstraintElement::Coupling, c.name.clone(), c.line);
                couplings.push(c);
                named
            };
            if let Some(&(other, other_line)) = constraint_names.get(&name) {
                self.record(
                    self.loc(node, format!("{tag} \"{name}\"")),
                    LoadErrorKind::ConstraintNameTaken {
                        name: name.clone(),
                        other,
                        other_line,
                    },
                );
                continue;
            }
            constraint_names.insert(name, (tag, line));
        }
        // Before `finish`: a transmission's problems are collected with the others.
        self.transmissions(root, &mut joints, &written_joints);
        self.finish()?;
        self.warn_ignored_joint_dynamics(root);
        self.warn_repeated_elements(root);
        let root_name = links
            .get(root_link)
            .map_or("", |l| l.name.as_str())
            .to_string();
        self.warn_floating_joint_in_comment(root, &joints, &root_name);
        fold_repeated_warnings(&mut self.warnings);
        Ok(Robot {
            name,
            source: self.path.to_path_buf(),
            links,
            joints,
            root: root_link,
            loops,
            couplings,
        })
    }

    /// The root link of a tree read without problems: exactly one link is no joint's child, and every
    /// link is reachable from it (otherwise the joints form a cycle). A problem here ends the reading.
    fn tree_root(
        &self,
        robot: Node,
        name: &str,
        links: &[Link],
        joints: &[Joint],
        parent_joint: &[Option<usize>],
    ) -> Result<usize, LoadError> {
        if links.is_empty() {
            return Err(LoadError::at(
                self.loc(robot, format!("robot \"{name}\"")),
                LoadErrorKind::NoLinks,
            ));
        }
        let roots: Vec<usize> = (0..links.len())
            .filter(|&l| parent_joint[l].is_none())
            .collect();
        let root_link = match roots.as_slice() {
            [r] => *r,
            [] => {
                let j = &joints[0];
                return Err(LoadError::at(
                    Location::new(self.path, j.line, format!("joint \"{}\"", j.name)),
                    LoadErrorKind::NoRootLink,
                ));
            }
            [_, second, ..] => {
                let l = &links[*second];
                return Err(LoadError::at(
                    Location::new(self.path, l.line, format!("link \"{}\"", l.name)),
                    LoadErrorKind::SeveralRoots {
                        roots: roots.iter().map(|&r| links[r].name.clone()).collect(),
                    },
                ));
            }
        };
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); links.len()];
        for (j, joint) in joints.iter().enumerate() {
            children[joint.parent].push(j);
        }
        let mut seen = vec![false; links.len()];
        let mut stack = vec![root_link];
        while let Some(l) = stack.pop() {
            seen[l] = true;
            stack.extend(children[l].iter().map(|&j| joints[j].child));
        }
        if let Some(l) = seen.iter().position(|s| !s) {
            let j = &joints[parent_joint[l].expect("a link other than the root has a parent")];
            return Err(LoadError::at(
                Location::new(self.path, j.line, format!("joint \"{}\"", j.name)),
                LoadErrorKind::Cycle {
                    link: links[l].name.clone(),
                    root: links[root_link].name.clone(),
                },
            ));
        }
        Ok(root_link)
    }

    /// A `<link>`. A problem of its `<inertial>` is recorded, and the link is still defined (without
    /// inertia), so that the joints naming it are read as they would be.
    fn link(&mut self, node: Node) -> Parsed<Link> {
        let Some(name) = node.attribute("name") else {
            return self.fail(
                node,
                "<link>",
                LoadErrorKind::MissingAttribute {
                    attribute: "name".into(),
                },
            );
        };
        let what = format!("link \"{name}\"");
        let inertial = match node.children().find(|n| n.has_tag_name("inertial")) {
            None => None,
            Some(inode) => self.inertial(inode, &what).ok(),
        };
        Ok(Link {
            name: name.to_string(),
            inertial,
            line: self.line(node),
        })
    }

    fn inertial(&mut self, node: Node, link: &str) -> Parsed<Inertial> {
        let what = format!("{link} <inertial>");
        let origin = self.origin(node, &what);
        let mass = match node.children().find(|n| n.has_tag_name("mass")) {
            None => self.fail(
                node,
                what.clone(),
                LoadErrorKind::MissingElement { tag: "mass".into() },
            ),
            Some(mnode) => {
                let mw = format!("{what} <mass>");
                match self.number(mnode, "value", None, &mw) {
                    Ok(mass) if mass < 0.0 => {
                        self.fail(mnode, mw, LoadErrorKind::NegativeMass { mass })
                    }
                    mass => mass.map(|m| (m, mnode)),
                }
            }
        };
        let Some(inode) = node.children().find(|n| n.has_tag_name("inertia")) else {
            return self.fail(
                node,
                what,
                LoadErrorKind::MissingElement {
                    tag: "inertia".into(),
                },
            );
        };
        let iw = format!("{what} <inertia>");
        let mut inertia = Ok([0.0; 6]);
        for (k, a) in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
            .iter()
            .enumerate()
        {
            match (self.number(inode, a, None, &iw), &mut inertia) {
                (Ok(x), Ok(inertia)) => inertia[k] = x,
                (Ok(_), Err(_)) => {}
                (Err(e), _) => inertia = Err(e),
            }
        }
        let (origin, (mass, mnode), inertia) = (origin?, mass?, inertia?);
        let [ixx, ixy, ixz, iyy, iyz, izz] = inertia;
        let m = Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz);
        let scale = inertia_rounding_scale(&m, mass, &origin);
        if below_rounding(min_eigenvalue(&m), scale) {
            self.warn(
                inode,
                iw.clone(),
                WarningKind::InertiaNotPositive {
                    ixx,
                    iyy,
                    izz,
                    ixy,
                    ixz,
                    iyz,
                    smallest_eigenvalue: min_eigenvalue(&m),
                },
            );
        } else {
            // The principal moments of a physical body satisfy the triangle inequality, equivalently
            // ½ tr(I) 1 − I (the body's second moment of mass) is positive semi-definite.
            let second_moment = Matrix3::identity() * (0.5 * m.trace()) - m;
            if below_rounding(min_eigenvalue(&second_moment), scale) {
                self.warn(inode, iw.clone(), WarningKind::TriangleInequality);
            }
        }
        if mass == 0.0 && m.iter().any(|&x| x != 0.0) {
            self.warn(mnode, iw, WarningKind::MasslessRotor);
        }
        Ok(Inertial {
            origin,
            mass,
            inertia,
        })
    }

    /// A `<joint>`: every attribute and child is read, so that each of its problems is recorded.
    fn joint(&mut self, node: Node, links: &HashMap<String, usize>) -> Parsed<Joint> {
        let Some(name) = node.attribute("name") else {
            return self.fail(
                node,
                "<joint>",
                LoadErrorKind::MissingAttribute {
                    attribute: "name".into(),
                },
            );
        };
        let what = format!("joint \"{name}\"");
        let kind = match node.attribute("type") {
            Some("revolute") => Ok(JointKind::Revolute),
            Some("continuous") => Ok(JointKind::Continuous),
            Some("prismatic") => Ok(JointKind::Prismatic),
            Some("fixed") => Ok(JointKind::Fixed),
            Some("floating") => Ok(JointKind::Floating),
            Some("planar") => self.fail(node, what.clone(), LoadErrorKind::PlanarJoint),
            Some(t) => self.fail(
                node,
                what.clone(),
                LoadErrorKind::UnknownJointType {
                    joint_type: t.into(),
                },
            ),
            None => self.fail(
                node,
                what.clone(),
                LoadErrorKind::MissingAttribute {
                    attribute: "type".into(),
                },
            ),
        };
        let link_of = |tag: &str| -> Parsed<usize> {
            let Some(n) = node.children().find(|n| n.has_tag_name(tag)) else {
                return self.fail(
                    node,
                    what.clone(),
                    LoadErrorKind::MissingElement { tag: tag.into() },
                );
            };
            let Some(l) = n.attribute("link") else {
                return self.fail(
                    n,
                    format!("{what} <{tag}>"),
                    LoadErrorKind::MissingAttribute {
                        attribute: "link".into(),
                    },
                );
            };
            match links.get(l) {
                Some(&i) => Ok(i),
                None => self.fail(
                    n,
                    format!("{what} <{tag}>"),
                    LoadErrorKind::UnknownLink { link: l.into() },
                ),
            }
        };
        let parent = link_of("parent");
        let child = link_of("child");
        let origin = self.origin(node, &what);
        let axis_node = node.children().find(|n| n.has_tag_name("axis"));
        let mut axis = match axis_node {
            None => Ok([1.0, 0.0, 0.0]),
            Some(a) => self.vec3(a, "xyz", Some([1.0, 0.0, 0.0]), &format!("{what} <axis>")),
        };
        if let (Ok(kind), Ok(xyz)) = (&kind, &axis) {
            if matches!(
                kind,
                JointKind::Revolute | JointKind::Continuous | JointKind::Prismatic
            ) && xyz.iter().all(|&x| x == 0.0)
            {
                axis = self.fail(
                    axis_node.unwrap_or(node),
                    format!("{what} <axis>"),
                    LoadErrorKind::ZeroAxis { of: AxisOf::Joint },
                );
            }
        }
        let mut mimics = Ok(Vec::new());
        for m in node.children().filter(|n| n.has_tag_name("mimic")) {
            let mw = format!("{what} <mimic>");
            let target = match m.attribute("joint") {
                Some(target) => Ok(target),
                None => self.fail(
                    m,
                    mw.clone(),
                    LoadErrorKind::MissingAttribute {
                        attribute: "joint".into(),
                    },
                ),
            };
            let multiplier = self.number(m, "multiplier", Some(1.0), &mw);
            let offset = self.number(m, "offset", Some(0.0), &mw);
            match (target, multiplier, offset, &mut mimics) {
                (Ok(target), Ok(multiplier), Ok(offset), Ok(mimics)) => mimics.push(Mimic {
                    joint: target.to_string(),
                    multiplier,
                    offset,
                    line: self.line(m),
                }),
                _ => mimics = Err(Reported),
            }
        }
        if matches!(kind, Ok(JointKind::Fixed)) && mimics.as_ref().is_ok_and(|m| !m.is_empty()) {
            // A fixed joint has no coordinate to drive (talos_reduced.urdf has such gripper leftovers):
            // Pinocchio ignores these too.
            self.warn(node, what.clone(), WarningKind::MimicOnFixedJoint);
            mimics = Ok(Vec::new());
        }
        let armature = match node.children().find(|d| d.has_tag_name("dynamics")) {
            None => Ok(0.0),
            Some(d) => self.non_negative(d, "armature", &format!("{what} <dynamics>")),
        };
        let limits = match (node.children().find(|l| l.has_tag_name("limit")), &kind) {
            (Some(l), Ok(k)) if k.is_one_dof() => self.limits(l, *k, &what),
            _ => Ok(Limits::default()),
        };
        let independent = match node.attribute("independent") {
            None => Ok(None),
            Some("true") => Ok(Some(true)),
            Some("false") => Ok(Some(false)),
            Some(x) => self.fail(
                node,
                what,
                LoadErrorKind::NotABoolean {
                    attribute: "independent".into(),
                    text: x.into(),
                },
            ),
        };
        Ok(Joint {
            armature: armature?,
            limits: limits?,
            locked: None,
            name: name.to_string(),
            kind: kind?,
            parent: parent?,
            child: child?,
            origin: origin?,
            axis: axis?,
            mimics: mimics?,
            independent: independent?,
            line: self.line(node),
        })
    }

    /// `<limit lower upper velocity effort>` of a one-coordinate joint: each attribute optional (absent,
    /// not 0, where missing), finite; velocity and effort ≥ 0; lower ≤ upper. A continuous joint has no
    /// position limits (as in Pinocchio): its `lower` and `upper` are not read.
    fn limits(&self, node: Node, kind: JointKind, what: &str) -> Parsed<Limits> {
        let what = format!("{what} <limit>");
        let read = |attr: &str| -> Parsed<Option<f64>> {
            if node.attribute(attr).is_none() {
                return Ok(None);
            }
            self.number(node, attr, None, &what).map(Some)
        };
        let magnitude = |attr: &str| -> Parsed<Option<f64>> {
            match read(attr)? {
                Some(x) if x < 0.0 => self.fail(
                    node,
                    what.as_str(),
                    LoadErrorKind::Negative {
                        attribute: attr.into(),
                        value: x,
                    },
                ),
                x => Ok(x),
            }
        };
        let positioned = kind != JointKind::Continuous;
        let lower = if positioned { read("lower") } else { Ok(None) };
        let upper = if positioned { read("upper") } else { Ok(None) };
        let velocity = magnitude("velocity");
        let effort = magnitude("effort");
        let (lower, upper, velocity, effort) = (lower?, upper?, velocity?, effort?);
        if let (Some(l), Some(u)) = (lower, upper) {
            if l > u {
                return self.fail(
                    node,
                    what,
                    LoadErrorKind::LimitsReversed { lower: l, upper: u },
                );
            }
        }
        Ok(Limits {
            lower,
            upper,
            velocity,
            effort,
        })
    }

    /// `<predecessor link>` or `<successor link>` of a loop or coupling.
    fn named_link(
        &self,
        node: Node<'a, 'input>,
        tag: &str,
        what: &str,
        links: &HashMap<String, usize>,
    ) -> Parsed<(usize, Node<'a, 'input>)> {
        let Some(n) = node.children().find(|n| n.has_tag_name(tag)) else {
            return self.fail(
                node,
                what,
                LoadErrorKind::MissingElement { tag: tag.into() },
            );
        };
        let Some(l) = n.attribute("link") else {
            return self.fail(
                n,
                format!("{what} <{tag}>"),
                LoadErrorKind::MissingAttribute {
                    attribute: "link".into(),
                },
            );
        };
        match links.get(l) {
            Some(&i) => Ok((i, n)),
            None => self.fail(
                n,
                format!("{what} <{tag}>"),
                LoadErrorKind::UnknownLink { link: l.into() },
            ),
        }
    }

    /// `<loop name>` or `<coupling name>`: required, as GRBDA's reader requires it (it refuses an
    /// unnamed constraint), so that every message can point at the element.
    fn constraint_name(&self, node: Node, tag: &str) -> Parsed<String> {
        match node.attribute("name") {
            Some(name) => Ok(name.to_string()),
            None => self.fail(
                node,
                format!("<{tag}>"),
                LoadErrorKind::MissingAttribute {
                    attribute: "name".into(),
                },
            ),
        }
    }

    /// `<dynamics damping friction>` describe joint losses that embedyn's ideal rigid bodies do not
    /// model (nor do Pinocchio's algorithms): one warning per file that names the joints concerned.
    /// A value of zero changes nothing and is passed over silently.
    fn warn_ignored_joint_dynamics(&mut self, root: Node) {
        let mut first = None;
        let mut names = Vec::new();
        for joint in root.children().filter(|n| n.has_tag_name("joint")) {
            let name = joint.attribute("name").unwrap_or("?");
            let lossy = joint.children().find(|d| {
                d.has_tag_name("dynamics")
                    && [d.attribute("damping"), d.attribute("friction")]
                        .into_iter()
                        .flatten()
                        .any(|v| v.trim().parse::<f64>() != Ok(0.0))
            });
            if let Some(dynamics) = lossy {
                first.get_or_insert((name, dynamics));
                names.push(name.to_string());
            }
        }
        let Some((joint, dynamics)) = first else {
            return;
        };
        self.warn(
            dynamics,
            format!("joint \"{joint}\" <dynamics>"),
            WarningKind::JointDynamicsIgnored { joints: names },
        );
    }

    /// Elements that URDF has once per parent (a joint's `<axis>`, `<origin>`, `<limit>`, …, a link's
    /// `<inertial>` and its `<mass>`, `<inertia>`, `<origin>`) given more than once: the reader takes the
    /// first, as urdfdom (and so Pinocchio) does, and says so, since which one a file meant is a guess.
    /// `<mimic>` may repeat (several drivers add up: docs/model-format.md), `<visual>` and `<collision>`
    /// too.
    /// [`WarningKind::FloatingJointInComment`]: no joint of the file is floating, and a comment among
    /// `<robot>`'s children holds a `<joint` with `type="floating"` (either quote).
    fn warn_floating_joint_in_comment(&mut self, root: Node, joints: &[Joint], root_link: &str) {
        if joints.iter().any(|j| j.kind == JointKind::Floating) {
            return;
        }
        let commented = root.children().filter(|n| n.is_comment()).find(|n| {
            let text = n.text().unwrap_or("");
            text.contains("<joint")
                && (text.contains("type=\"floating\"") || text.contains("type='floating'"))
        });
        if let Some(comment) = commented {
            let kind = WarningKind::FloatingJointInComment {
                root: root_link.to_string(),
            };
            self.warn(comment, "comment", kind);
        }
    }

    fn warn_repeated_elements(&mut self, root: Node) {
        const JOINT_ONCE: [&str; 8] = [
            "origin",
            "parent",
            "child",
            "axis",
            "calibration",
            "dynamics",
            "limit",
            "safety_controller",
        ];
        let mut found = Vec::new();
        let mut check =
            |parent, what: &str, tags: &[&str]| repeated(parent, what, tags, &mut found);
        for node in root.children().filter(|n| n.is_element()) {
            let name = node.attribute("name").unwrap_or("?");
            match node.tag_name().name() {
                "joint" => check(node, &format!("joint \"{name}\""), &JOINT_ONCE),
                "link" => {
                    let what = format!("link \"{name}\"");
                    check(node, &what, &["inertial"]);
                    if let Some(inertial) = node.children().find(|n| n.has_tag_name("inertial")) {
                        check(
                            inertial,
                            &format!("{what} <inertial>"),
                            &["origin", "mass", "inertia"],
                        );
                    }
                }
                _ => {}
            }
        }
        for (node, what, element, count) in found {
            self.warn(node, what, WarningKind::RepeatedElement { element, count });
        }
    }

    /// ROS `<transmission>` blocks: each `<actuator>` with a rotor inertia I (Drake's
    /// `<drake:rotor_inertia value>`) adds r² · I to the armature of the transmission's joint, with r its
    /// `<drake:gear_ratio value>`, else its `<mechanicalReduction>` (in the actuator or, in the older
    /// form, the transmission), else 1. A transmission without a rotor inertia adds nothing, whatever it
    /// names (ROS files carry many for controllers only).
    ///
    /// A transmission naming a joint of the file that the reader left out (for a problem of its own,
    /// reported) adds nothing and is no further problem, as for mimic targets.
    fn transmissions(&mut self, root: Node, joints: &mut [Joint], written_joints: &HashSet<&str>) {
        let local = |n: &Node, tag: &str| n.is_element() && n.tag_name().name() == tag;
        // By name, once: a file of many transmissions and joints stays linear to read.
        let index: HashMap<String, usize> = joints
            .iter()
            .enumerate()
            .map(|(i, j)| (j.name.clone(), i))
            .collect();
        for t in root.children().filter(|n| n.has_tag_name("transmission")) {
            let what = format!("transmission \"{}\"", t.attribute("name").unwrap_or(""));
            let joint_elements: Vec<Node> =
                t.children().filter(|n| n.has_tag_name("joint")).collect();
            let joint = joint_elements.first().and_then(|n| n.attribute("name"));
            let mut actuators = t
                .children()
                .filter(|n| n.has_tag_name("actuator"))
                .filter(|a| a.children().any(|n| local(&n, "rotor_inertia")))
                .peekable();
            if actuators.peek().is_none() {
                continue;
            }
            if joint_elements.len() > 1 {
                // A differential or four-bar transmission: which rotor reflects onto which joint, and with
                // which cross terms, is not in the rotor inertia alone.
                self.warn(
                    t,
                    what.clone(),
                    WarningKind::MultiJointTransmission {
                        joints: joint_elements.len(),
                    },
                );
                continue;
            }
            for actuator in actuators {
                let inertia = actuator
                    .children()
                    .find(|n| local(n, "rotor_inertia"))
                    .expect("filtered above");
                let element = |n: Node| format!("{what} <actuator> <{}>", n.tag_name().name());
                let Ok(rotor) = self.required_non_negative(inertia, "value", &element(inertia))
                else {
                    continue;
                };
                let ratio = if let Some(g) = actuator.children().find(|n| local(n, "gear_ratio")) {
                    self.number(g, "value", None, &element(g)).map(|r| (r, g))
                } else if let Some(m) = actuator
                    .children()
                    .chain(t.children())
                    .find(|n| local(n, "mechanicalReduction"))
                {
                    self.element_number(m, &element(m)).map(|r| (r, m))
                } else {
                    Ok((1.0, actuator))
                };
                let Ok((ratio, ratio_node)) = ratio else {
                    continue;
                };
                if ratio == 0.0 {
                    self.record(
                        self.loc(ratio_node, element(ratio_node)),
                        LoadErrorKind::ZeroGearRatio,
                    );
                    continue;
                }
                match joint.and_then(|name| index.get(name)) {
                    Some(&j) if !joints[j].kind.is_moving() => self.warn(
                        t,
                        what.clone(),
                        WarningKind::RotorOnFixedJoint {
                            joint: joints[j].name.clone(),
                        },
                    ),
                    Some(&j) => joints[j].armature += ratio * ratio * rotor,
                    None if joint.is_some_and(|name| written_joints.contains(name)) => {}
                    None => self.record(
                        self.loc(t, what.clone()),
                        LoadErrorKind::UnknownTransmissionJoint {
                            joint: joint.unwrap_or("").to_string(),
                        },
                    ),
                }
            }
        }
    }

    /// A finite number ≥ 0 in attribute `attr`, which must be present.
    fn required_non_negative(&self, node: Node, attr: &str, what: &str) -> Parsed<f64> {
        let x = self.number(node, attr, None, what)?;
        if x < 0.0 {
            return self.fail(
                node,
                what,
                LoadErrorKind::Negative {
                    attribute: attr.into(),
                    value: x,
                },
            );
        }
        Ok(x)
    }

    /// A finite number ≥ 0 in attribute `attr` (0 when absent).
    fn non_negative(&self, node: Node, attr: &str, what: &str) -> Parsed<f64> {
        let x = self.number(node, attr, Some(0.0), what)?;
        if x < 0.0 {
            return self.fail(
                node,
                what,
                LoadErrorKind::Negative {
                    attribute: attr.into(),
                    value: x,
                },
            );
        }
        Ok(x)
    }

    /// The text of an element such as `<mechanicalReduction>50</mechanicalReduction>`, a finite number.
    fn element_number(&self, node: Node, what: &str) -> Parsed<f64> {
        let text = node.text().unwrap_or("").trim();
        match text.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => self.fail(
                node,
                what,
                LoadErrorKind::TextNotANumber {
                    element: node.tag_name().name().into(),
                    text: text.into(),
                },
            ),
        }
    }

    fn loop_element(&self, node: Node, links: &HashMap<String, usize>) -> Parsed<Loop> {
        let name = self.constraint_name(node, "loop")?;
        let what = format!("loop \"{name}\"");
        let kind = match node.attribute("type") {
            Some("revolute") | Some("continuous") => Ok(LoopKind::Revolute),
            Some("prismatic") => Ok(LoopKind::Prismatic),
            Some("spherical") => Ok(LoopKind::Spherical),
            Some("fixed") => Ok(LoopKind::Fixed),
            Some("planar") => self.fail(node, what.clone(), LoadErrorKind::PlanarLoop),
            Some(t) => self.fail(
                node,
                what.clone(),
                LoadErrorKind::UnknownLoopType {
                    loop_type: t.into(),
                },
            ),
            None => self.fail(
                node,
                what.clone(),
                LoadErrorKind::MissingAttribute {
                    attribute: "type".into(),
                },
            ),
        };
        let predecessor = self.named_link(node, "predecessor", &what, links);
        let successor = self.named_link(node, "successor", &what, links);
        let frame = |end: &Parsed<(usize, Node)>, tag: &str| -> Parsed<LoopFrame> {
            let &(link, n) = end.as_ref().map_err(|_| Reported)?;
            Ok(LoopFrame {
                link,
                origin: self.origin(n, &format!("{what} <{tag}>"))?,
            })
        };
        let (predecessor_frame, successor_frame) = (
            frame(&predecessor, "predecessor"),
            frame(&successor, "successor"),
        );
        let axis = match node.children().find(|n| n.has_tag_name("axis")) {
            None => Ok([1.0, 0.0, 0.0]),
            Some(a) => {
                let aw = format!("{what} <axis>");
                match self.vec3(a, "xyz", Some([1.0, 0.0, 0.0]), &aw) {
                    Ok(axis)
                        if matches!(kind, Ok(LoopKind::Revolute | LoopKind::Prismatic))
                            && axis.iter().all(|&x| x == 0.0) =>
                    {
                        self.fail(a, aw, LoadErrorKind::ZeroAxis { of: AxisOf::Loop })
                    }
                    axis => axis,
                }
            }
        };
        if let (Ok((pl, _)), Ok((sl, _))) = (&predecessor, &successor) {
            if pl == sl {
                return self.fail(node, what, LoadErrorKind::SameEnds);
            }
        }
        Ok(Loop {
            name,
            kind: kind?,
            predecessor: predecessor_frame?,
            successor: successor_frame?,
            axis: axis?,
            line: self.line(node),
        })
    }

    fn coupling(&self, node: Node, links: &HashMap<String, usize>) -> Parsed<Coupling> {
        let name = self.constraint_name(node, "coupling")?;
        let what = format!("coupling \"{name}\"");
        let predecessor = self.named_link(node, "predecessor", &what, links);
        let successor = self.named_link(node, "successor", &what, links);
        let ratio = match node.children().find(|n| n.has_tag_name("ratio")) {
            None => Ok(1.0),
            Some(r) => self.number(r, "value", Some(1.0), &format!("{what} <ratio>")),
        };
        let ((predecessor, _), (successor, _)) = (predecessor?, successor?);
        if predecessor == successor {
            return self.fail(node, what, LoadErrorKind::SameEnds);
        }
        Ok(Coupling {
            name,
            predecessor,
            successor,
            ratio: ratio?,
            line: self.line(node),
        })
    }

    fn origin(&self, parent: Node, what: &str) -> Parsed<Origin> {
        match parent.children().find(|n| n.has_tag_name("origin")) {
            None => Ok(Origin::default()),
            Some(o) => {
                let w = format!("{what} <origin>");
                let xyz = self.vec3(o, "xyz", Some([0.0; 3]), &w);
                let rpy = self.vec3(o, "rpy", Some([0.0; 3]), &w);
                Ok(Origin {
                    xyz: xyz?,
                    rpy: rpy?,
                })
            }
        }
    }

    fn number(&self, node: Node, attr: &str, default: Option<f64>, what: &str) -> Parsed<f64> {
        match node.attribute(attr) {
            None => match default {
                Some(d) => Ok(d),
                None => self.fail(
                    node,
                    what,
                    LoadErrorKind::MissingAttribute {
                        attribute: attr.into(),
                    },
                ),
            },
            Some(s) => match s.trim().parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(x),
                Ok(_) => self.fail(
                    node,
                    what,
                    LoadErrorKind::NotFinite {
                        attribute: attr.into(),
                        text: s.into(),
                    },
                ),
                Err(_) => self.fail(
                    node,
                    what,
                    LoadErrorKind::NotANumber {
                        attribute: attr.into(),
                        text: s.into(),
                    },
                ),
            },
        }
    }

    fn vec3(
        &self,
        node: Node,
        attr: &str,
        default: Option<[f64; 3]>,
        what: &str,
    ) -> Parsed<[f64; 3]> {
        let Some(s) = node.attribute(attr) else {
            return match default {
                Some(d) => Ok(d),
                None => self.fail(
                    node,
                    what,
                    LoadErrorKind::MissingAttribute {
                        attribute: attr.into(),
                    },
                ),
            };
        };
        let parts: Vec<&str> = s.split_whitespace().collect();
        if parts.len() != 3 {
            return self.fail(
                node,
                what,
                LoadErrorKind::NotThreeNumbers {
                    attribute: attr.into(),
                    text: s.into(),
                },
            );
        }
        let mut out = [0.0; 3];
        for (k, p) in parts.iter().enumerate() {
            out[k] = match p.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                Ok(_) => {
                    return self.fail(
                        node,
                        what,
                        LoadErrorKind::EntryNotFinite {
                            attribute: attr.into(),
                            text: s.into(),
                        },
                    )
                }
                Err(_) => {
                    return self.fail(
                        node,
                        what,
                        LoadErrorKind::EntryNotANumber {
                            attribute: attr.into(),
                            text: s.into(),
                            entry: (*p).into(),
                        },
                    )
                }
            };
        }
        Ok(out)
    }
}

/// The magnitude against which rounding in an `<inertial>`'s tensor is judged.
///
/// Not the tensor alone: what the dynamics uses is the link's inertia about its frame,
/// I_c + m(|c|²1 − c cᵀ), and CAD exporters obtain I_c by subtracting that parallel-axis term from an
/// inertia about a part frame, so the rounding left in I_c is relative to the larger of the two. A
/// nearly point-like link then carries rounding residue that is tiny next to m|c|² but as large as
/// I_c itself (icub's head: I_c = 2.4e-35 off the diagonal and zeros on it, m|c|² = 1.7e-2 kg·m²).
/// Judged against I_c alone that residue would be "not positive semi-definite"; against the link's
/// inertia it is, correctly, rounding. No absolute constant enters: a milligram link is judged at
/// its own scale.
fn inertia_rounding_scale(tensor: &Matrix3<f64>, mass: f64, origin: &Origin) -> f64 {
    let [x, y, z] = origin.xyz;
    let own = tensor.iter().fold(0.0f64, |a, &v| a.max(v.abs()));
    own.max(mass * (x * x + y * y + z * z))
}

/// Whether an eigenvalue is negative beyond rounding at `scale`: more than 1e-12 · scale below zero.
/// 1e-12 is some 4500 units of f64 roundoff, room for the arithmetic that produced the file's
/// numbers; inertias that are wrong, not rounded, are off by 1e-4 … 1 relative (example-robot-data's
/// tiago antennas −0.58, romeo_laas_small's body −0.15, against at most 3e-16 for rounding residue).
fn below_rounding(eigenvalue: f64, scale: f64) -> bool {
    eigenvalue < -1e-12 * scale
}

/// The smallest eigenvalue of a symmetric 3×3 matrix.
fn min_eigenvalue(m: &Matrix3<f64>) -> f64 {
    m.symmetric_eigenvalues().min()
}

/// `parent`'s children named in `tags` that are given more than once: (the second, where, tag, count).
fn repeated<'a, 'i>(
    parent: Node<'a, 'i>,
    what: &str,
    tags: &[&str],
    found: &mut Vec<(Node<'a, 'i>, String, String, usize)>,
) {
    for &tag in tags {
        let mut same = parent
            .children()
            .filter(|n| n.is_element() && n.tag_name().name() == tag);
        if let (Some(_), Some(second)) = (same.next(), same.next()) {
            let count = 2 + same.count();
            found.push((second, format!("{what} <{tag}>"), tag.to_string(), count));
        }
    }
}

#[cfg(test)]
mod kind_tests {
    use super::*;
    use crate::error::{MAX_LISTED_ERRORS, MAX_SHOWN_CHARS};

    fn error_of(text: &str) -> LoadError {
        match parse_urdf(text, Path::new("m.urdf")) {
            Ok(_) => panic!("{text} loaded"),
            Err(e) => e,
        }
    }

    #[test]
    fn load_errors_carry_what_went_wrong_as_data_and_keep_their_messages() {
        let e = error_of("<robot name=\"r\">\n<link/>\n</robot>");
        assert_eq!(
            e.kind,
            LoadErrorKind::MissingAttribute {
                attribute: "name".into()
            }
        );
        assert_eq!(e.location.line, Some(2));
        assert_eq!(e.to_string(), "m.urdf:2: <link>: missing attribute `name`");

        let e = error_of("<robot name=\"r\"><link name=\"a\"><inertial><mass value=\"x\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link></robot>");
        assert_eq!(
            e.kind,
            LoadErrorKind::NotANumber {
                attribute: "value".into(),
                text: "x".into()
            },
            "{e}"
        );
        assert!(
            e.to_string().ends_with("`value=\"x\"` is not a number"),
            "{e}"
        );

        let e = error_of("<robot name=\"r\"><link name=\"a\"/><link name=\"a\"/></robot>");
        assert_eq!(e.kind, LoadErrorKind::DuplicateName { what: "link" });
        assert!(
            e.to_string()
                .ends_with("link \"a\": a link of this name is already defined"),
            "{e}"
        );

        let e = error_of("<robot");
        assert!(matches!(e.kind, LoadErrorKind::MalformedXml { .. }), "{e}");
        assert!(e.to_string().contains(": XML: malformed XML: "), "{e}");
    }

    /// The file `m.urdf` with `body` inside `<robot>`, the first line being line 2.
    fn robot_of(body: &str) -> String {
        format!("<robot name=\"r\">\n{body}\n</robot>")
    }

    const INERTIA: &str = r#"<inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>"#;

    #[test]
    fn problems_of_several_elements_are_reported_together() {
        let text = robot_of(&format!(
            r#"<link name="a"/>
<link name="b"><inertial><mass value="-1"/>{INERTIA}</inertial></link>
<joint name="j1" type="hinge"><parent link="a"/><child link="b"/></joint>
<joint name="j2" type="fixed"><parent link="a"/><child link="c"/></joint>"#
        ));
        let e = error_of(&text);
        let found: Vec<(Option<u32>, &LoadErrorKind)> =
            e.problems().map(|p| (p.location.line, &p.kind)).collect();
        assert_eq!(
            found,
            [
                (Some(3), &LoadErrorKind::NegativeMass { mass: -1.0 }),
                (
                    Some(4),
                    &LoadErrorKind::UnknownJointType {
                        joint_type: "hinge".into()
                    }
                ),
                (Some(5), &LoadErrorKind::UnknownLink { link: "c".into() }),
            ],
            "{e}"
        );
        // The first line is the message of the first problem alone; each other is a line of its own.
        let message = e.to_string();
        let lines: Vec<&str> = message.lines().collect();
        assert_eq!(lines.len(), 3, "{message}");
        assert_eq!(
            lines[0],
            "m.urdf:3: link \"b\" <inertial> <mass>: negative mass -1"
        );
        assert!(lines[1].starts_with("m.urdf:4: joint \"j1\": unknown joint type \"hinge\""));
        assert_eq!(
            lines[2],
            "m.urdf:5: joint \"j2\" <child>: names link \"c\", which does not exist"
        );
    }

    #[test]
    fn every_problem_of_one_element_is_reported() {
        let text = robot_of(
            r#"<link name="a"/><link name="b"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="1 2" rpy="0 x 0"/></joint>"#,
        );
        let e = error_of(&text);
        let kinds: Vec<&LoadErrorKind> = e.problems().map(|p| &p.kind).collect();
        assert_eq!(
            kinds,
            [
                &LoadErrorKind::NotThreeNumbers {
                    attribute: "xyz".into(),
                    text: "1 2".into()
                },
                &LoadErrorKind::EntryNotANumber {
                    attribute: "rpy".into(),
                    text: "0 x 0".into(),
                    entry: "x".into()
                },
            ],
            "{e}"
        );
        // An axis is judged zero only when the joint's type is known and its axis read.
        let text = robot_of(
            r#"<link name="a"/><link name="b"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 0"/></joint>"#,
        );
        let e = error_of(&text);
        assert_eq!(e.kind, LoadErrorKind::ZeroAxis { of: AxisOf::Joint });
        assert!(e.also.is_empty(), "{e}");
    }

    #[test]
    fn a_joint_left_out_raises_no_problems_of_the_tree() {
        // Without `j1` (its type unknown), `b` would be a second root and `j2`'s mimic would name a
        // joint that is not there: neither is news, so only `j1`'s own problem is reported.
        let text = robot_of(
            r#"<link name="a"/><link name="b"/><link name="c"/>
<joint name="j1" type="hinge"><parent link="a"/><child link="b"/></joint>
<joint name="j2" type="revolute"><parent link="a"/><child link="c"/><mimic joint="j1"/></joint>"#,
        );
        let e = error_of(&text);
        assert_eq!(
            e.kind,
            LoadErrorKind::UnknownJointType {
                joint_type: "hinge".into()
            }
        );
        assert!(e.also.is_empty(), "{e}");
    }

    #[test]
    fn a_problem_that_ends_the_reading_is_reported_alone() {
        let e = error_of("<robot name=\"r\">\n<link name=\"a\"><mass value=\"x\"/>\n</robot");
        assert!(matches!(e.kind, LoadErrorKind::MalformedXml { .. }), "{e}");
        assert!(e.also.is_empty());
        // The tree's shape is judged once its elements are read without problems: two roots.
        let e = error_of(&robot_of(r#"<link name="a"/><link name="b"/>"#));
        assert_eq!(
            e.kind,
            LoadErrorKind::SeveralRoots {
                roots: vec!["a".into(), "b".into()]
            }
        );
        assert!(e.also.is_empty());
    }

    #[test]
    fn a_long_list_of_problems_is_cut_short() {
        let links: Vec<String> = (0..25)
            .map(|k| format!(r#"<link name="l{k}"><inertial><mass value="-{k}.5"/>{INERTIA}</inertial></link>"#))
            .collect();
        let e = error_of(&robot_of(&links.join("\n")));
        assert_eq!(e.problems().count(), 25);
        let message = e.to_string();
        let lines: Vec<&str> = message.lines().collect();
        assert_eq!(lines.len(), MAX_LISTED_ERRORS + 1, "{message}");
        assert!(lines[MAX_LISTED_ERRORS - 1].starts_with("m.urdf:21: link \"l19\""));
        assert_eq!(lines[MAX_LISTED_ERRORS], "and 5 more errors");
    }

    #[test]
    fn warnings_carry_their_kind_and_fold_repeats() {
        let joint = |k: u32| {
            format!(
                r#"<joint name="g{k}" type="fixed"><parent link="a"/><child link="b{k}"/><mimic joint="j"/></joint>"#
            )
        };
        let text = robot_of(&format!(
            r#"<link name="a"/><link name="b0"/><link name="b1"/><link name="b2"/><link name="c"/>
<joint name="j" type="revolute"><parent link="a"/><child link="c"/></joint>
{}
{}
{}"#,
            joint(0),
            joint(1),
            joint(2)
        ));
        let loaded = parse_urdf(&text, Path::new("m.urdf")).unwrap();
        assert_eq!(loaded.warnings.len(), 1);
        let w = &loaded.warnings[0];
        assert_eq!(w.kind, WarningKind::MimicOnFixedJoint);
        assert_eq!(w.location.line, Some(4));
        assert_eq!(w.same_for, ["joint \"g1\"", "joint \"g2\""]);
        assert_eq!(
            w.to_string(),
            "warning: m.urdf:4: joint \"g0\": <mimic> on a fixed joint has nothing to drive; ignored (the same for joint \"g1\", joint \"g2\")"
        );
    }

    /// A floating joint left in a comment (example-robot-data's G1: "uncomment when convert to mujoco")
    /// is warned of at the comment, naming the root that stays fixed; not when the file has a floating
    /// joint of its own, nor for a comment that only mentions the word.
    #[test]
    fn a_floating_joint_in_a_comment_is_warned_of() {
        let commented = robot_of(
            r#"<!-- uncomment for a free base: <link name="world"/>
  <joint name="base" type="floating"><parent link="world"/><child link="pelvis"/></joint> -->
<link name="pelvis"/><link name="thigh"/>
<joint name="hip" type="revolute"><parent link="pelvis"/><child link="thigh"/><axis xyz="0 1 0"/></joint>"#,
        );
        let loaded = parse_urdf(&commented, Path::new("g1.urdf")).unwrap();
        let kinds: Vec<&WarningKind> = loaded.warnings.iter().map(|w| &w.kind).collect();
        assert_eq!(
            kinds,
            [&WarningKind::FloatingJointInComment {
                root: "pelvis".into()
            }]
        );
        assert_eq!(loaded.warnings[0].location.line, Some(2));
        assert!(
            loaded.warnings[0].to_string().contains("pass --floating"),
            "{}",
            loaded.warnings[0]
        );
        // Single quotes count too.
        let single = commented.replace(r#"type="floating""#, "type='floating'");
        assert_eq!(
            parse_urdf(&single, Path::new("g1.urdf"))
                .unwrap()
                .warnings
                .len(),
            1
        );
        // A floating joint of its own: the comment is an alternative, not a missing base.
        let own = robot_of(
            r#"<!-- <joint name="old" type="floating"/> -->
<link name="world"/><link name="pelvis"/>
<joint name="base" type="floating"><parent link="world"/><child link="pelvis"/></joint>"#,
        );
        assert!(parse_urdf(&own, Path::new("m.urdf"))
            .unwrap()
            .warnings
            .is_empty());
        // A comment that names no joint of that type.
        let prose = robot_of(
            r#"<!-- the base is floating in simulation; <joint> elements below are revolute -->
<link name="a"/><link name="b"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>"#,
        );
        assert!(parse_urdf(&prose, Path::new("m.urdf"))
            .unwrap()
            .warnings
            .is_empty());
    }

    /// An element URDF has once, given twice (the attacker's joint with two `<axis>`): the first is read,
    /// as urdfdom reads it, and a warning at the second says so; several `<mimic>` are no repetition.
    #[test]
    fn an_element_given_twice_is_read_once_with_a_warning() {
        let text = robot_of(
            r#"<link name="a"/><link name="c"><inertial><mass value="1"/><mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
<joint name="j" type="revolute"><parent link="a"/><child link="c"/><axis xyz="0 0 1"/>
<axis xyz="1 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>"#,
        );
        let loaded = parse_urdf(&text, Path::new("m.urdf")).unwrap();
        let model = loaded.model::<f64>(&Default::default()).unwrap();
        assert_eq!(
            model.joints[0].axis,
            embedyn_runtime::nalgebra::Vector3::z()
        );
        assert_eq!(model.bodies[0].inertia.mass, 1.0);
        let shown: Vec<String> = loaded.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(shown.len(), 2, "{shown:?}");
        assert!(
            shown.iter().any(|w| w.starts_with(
                "warning: m.urdf:4: joint \"j\" <axis>: <axis> is given 3 times; the first is read"
            )),
            "{shown:?}"
        );
        assert!(
            shown
                .iter()
                .any(|w| w.contains("link \"c\" <inertial> <mass>: <mass> is given 2 times")),
            "{shown:?}"
        );
    }

    /// The bytes a problem holds (its element and its kind's message, which shows every text it keeps).
    fn held_bytes(e: &LoadError) -> usize {
        e.problems()
            .map(|p| p.location.element.len() + p.kind.to_string().len())
            .sum()
    }

    /// Trial 9: one joint of a 1 MB name with 2000 bad `<mimic>` children peaked at 3.9 GB (the name
    /// copied into every problem). The problems kept are bounded in count and in size, the others are
    /// counted, and the message is bounded too.
    #[test]
    fn many_problems_of_a_long_name_cost_memory_bounded_by_the_file() {
        let name = "n".repeat(100_000);
        let mimics = r#"<mimic joint="ghost"/>"#.repeat(500);
        let text = robot_of(&format!(
            r#"<link name="a"/><link name="b"/>
<joint name="{name}" type="revolute"><parent link="a"/><child link="b"/>{mimics}</joint>"#
        ));
        let e = error_of(&text);
        assert_eq!(e.problems().count(), MAX_KEPT_ERRORS);
        assert_eq!(e.omitted, 500 - MAX_KEPT_ERRORS);
        assert!(held_bytes(&e) < text.len(), "{} bytes held", held_bytes(&e));
        let message = e.to_string();
        assert!(message.len() < 20_000, "{} bytes of message", message.len());
        assert!(
            message.ends_with(&format!("\nand {} more errors", 500 - MAX_LISTED_ERRORS)),
            "{}",
            &message[message.len() - 200..]
        );
        assert!(
            message.contains(&format!(
                "joint \"{}… (100000 bytes)\" <mimic>",
                &name[..80]
            )),
            "{}",
            &message[..300]
        );
    }

    /// A name or a value of megabytes is shown by its first characters and its length.
    #[test]
    fn long_names_and_values_are_shortened_in_messages() {
        let long = "x".repeat(1_000_000);
        let e = error_of(&robot_of(&format!(
            r#"<link name="a"><inertial><mass value="{long}"/>{INERTIA}</inertial></link>"#
        )));
        let message = e.to_string();
        assert!(message.len() < 400, "{}", message.len());
        assert!(
            message.ends_with(&format!(
                "`value=\"{}… (1000000 bytes)\"` is not a number",
                &long[..80]
            )),
            "{message}"
        );
        let e = error_of(&robot_of(&format!(
            r#"<link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="{long}"/></joint>"#
        )));
        assert!(e.to_string().len() < 400, "{}", e.to_string().len());
        // Names of up to MAX_SHOWN_CHARS characters are shown whole (and kept whole).
        let ok = "é".repeat(MAX_SHOWN_CHARS);
        let e = error_of(&robot_of(&format!(
            r#"<link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="{ok}"/></joint>"#
        )));
        assert_eq!(e.kind, LoadErrorKind::UnknownLink { link: ok.clone() });
    }

    /// Trial 9 (order.urdf): the reader's passes (links, joints, mimics, loops) listed lines 6, 2, 8, 7.
    /// Problems are reported in line order, the first the earliest in the file.
    #[test]
    fn problems_are_reported_in_line_order() {
        let text = format!(
            r#"<robot name="order">
  <joint name="j1" type="revolutee">
    <parent link="base"/><child link="l1"/>
  </joint>
  <link name="base"/>
  <link name="l1"><inertial><mass value="-1"/>{INERTIA}</inertial></link>
  <loop name="c" type="revolute"><predecessor link="nope"/><successor link="l1"/></loop>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><mimic joint="ghost"/></joint>
  <link name="l2"/>
</robot>"#
        );
        let e = error_of(&text);
        let lines: Vec<Option<u32>> = e.problems().map(|p| p.location.line).collect();
        assert_eq!(lines, [Some(2), Some(6), Some(7), Some(8)], "{e}");
    }

    /// Past the problems kept, the earliest in the file are the ones kept.
    #[test]
    fn the_earliest_problems_are_kept() {
        // Joint problems (read second) on early lines, link problems (read first) on later ones.
        let joints: String = (0..150)
            .map(|k| format!("<joint name=\"j{k}\" type=\"hinge\"><parent link=\"a\"/><child link=\"a\"/></joint>\n"))
            .collect();
        let links: String = (0..150)
            .map(|k| format!("<link name=\"l{k}\"><inertial><mass value=\"-1\"/>{INERTIA}</inertial></link>\n"))
            .collect();
        let e = error_of(&robot_of(&format!("<link name=\"a\"/>\n{joints}{links}")));
        let lines: Vec<u32> = e.problems().map(|p| p.location.line.unwrap()).collect();
        assert_eq!(lines, (3..3 + MAX_KEPT_ERRORS as u32).collect::<Vec<_>>());
        assert_eq!(e.omitted, 300 - MAX_KEPT_ERRORS);
    }

    /// Trial 9: U+202E and the other invisible format characters were printed raw, so a name could
    /// reorder the rest of its line on a terminal. They are escaped as control characters are.
    #[test]
    fn format_characters_that_reorder_or_hide_text_are_escaped() {
        for c in [
            '\u{AD}', '\u{61C}', '\u{180E}', '\u{200B}', '\u{200F}', '\u{2028}', '\u{2029}',
            '\u{202A}', '\u{202E}', '\u{2060}', '\u{2064}', '\u{2066}', '\u{206F}', '\u{FEFF}',
            '\u{FFF9}', '\u{FFFB}',
        ] {
            let e = error_of(&robot_of(&format!(
                r#"<link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="b{c}c"/></joint>"#
            )));
            let message = e.to_string();
            assert!(!message.contains(c), "U+{:04X}: {message:?}", c as u32);
            assert!(
                message.contains(&format!("b\\u{{{:x}}}c", c as u32)),
                "U+{:04X}: {message:?}",
                c as u32
            );
        }
        // Ordinary non-ASCII text is shown as it is.
        let e = error_of(&robot_of(
            r#"<link name="a"/><joint name="j" type="fixed"><parent link="a"/><child link="Gelenk-ä-関節"/></joint>"#,
        ));
        assert!(e.to_string().contains("\"Gelenk-ä-関節\""), "{e}");
    }

    /// Trial 9: 80k warnings took 18 s to fold (a linear search per warning, and inertias with other
    /// numbers never folded). Warnings that differ only in their numbers fold into one line.
    #[test]
    fn warnings_that_differ_only_in_their_numbers_fold() {
        let links: String = (0..2000)
            .map(|k| {
                format!(
                    r#"<link name="l{k}"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="{}" ixz="0" iyz="0"/></inertial></link>
"#,
                    2 + k
                )
            })
            .collect();
        let joints: String = (0..2000)
            .map(|k| format!(r#"<joint name="j{k}" type="fixed"><parent link="a"/><child link="l{k}"/></joint>"#))
            .collect();
        let text = robot_of(&format!("<link name=\"a\"/>\n{links}{joints}"));
        let loaded = parse_urdf(&text, Path::new("m.urdf")).unwrap();
        assert_eq!(loaded.warnings.len(), 1, "{:?}", &loaded.warnings[..2]);
        let w = &loaded.warnings[0];
        assert!(matches!(w.kind, WarningKind::InertiaNotPositive { ixy, .. } if ixy == 2.0));
        assert_eq!(w.same_for.len(), 1999);
        assert!(w.numbers_differ);
        assert_eq!(w.same_for[0], "link \"l1\" <inertial> <inertia>");
        assert!(
            w.to_string().ends_with("(also for link \"l1\" <inertial> <inertia>, link \"l2\" <inertial> <inertia>, link \"l3\" <inertial> <inertia>, link \"l4\" <inertial> <inertia>, link \"l5\" <inertial> <inertia> and 1994 more, with numbers of their own)"),
            "{w}"
        );
    }
}

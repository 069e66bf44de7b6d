//! Reads URDF into the model IR with `roxmltree`, keeping line numbers for messages.
//!
//! `urdf-rs` is not used: it drops URDF+ elements, keeps no source positions and rejects a joint with two
//! `<mimic>` children (a differential).

use crate::bounded_read::read_model_file;
use crate::error::{LoadError, LoadErrorKind, Location, Warning};
use crate::ir::{
    Coupling, Inertial, Joint, JointKind, Link, Loop, LoopFrame, LoopKind, Mimic, Origin, Robot,
};
use crate::xml_text::{nesting_too_deep, LineIndex, MAX_NESTING};
use embedyn_runtime::nalgebra::Matrix3;
use roxmltree::{Document, Node};
use std::collections::HashMap;
use std::path::Path;

/// A parsed model and the warnings its data raised.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The model as the file describes it.
    pub robot: Robot,
    /// Unusual but valid data, each at its element.
    pub warnings: Vec<Warning>,
}

/// Warnings of one message at several elements (talos_reduced's twelve `<mimic>` leftovers on fixed
/// joints) become one, at the first, naming the others: a screen of identical lines hides what differs.
fn fold_repeated_warnings(warnings: &mut Vec<Warning>) {
    const LISTED: usize = 5;
    let mut folded: Vec<(Warning, Vec<String>)> = Vec::new();
    for w in warnings.drain(..) {
        match folded
            .iter_mut()
            .find(|(first, _)| first.message == w.message)
        {
            Some((_, others)) => others.push(w.location.element),
            None => folded.push((w, Vec::new())),
        }
    }
    for (mut w, others) in folded {
        if !others.is_empty() {
            let mut list = others[..others.len().min(LISTED)].join(", ");
            if others.len() > LISTED {
                list += &format!(" and {} more", others.len() - LISTED);
            }
            w.message += &format!(" (the same for {list})");
        }
        warnings.push(w);
    }
}

/// Reads and checks a URDF file.
pub fn load_urdf(path: &Path) -> Result<Loaded, LoadError> {
    let text = read_model_file(path).map_err(|e| {
        LoadError::at(
            Location::new(path, None, ""),
            LoadErrorKind::Unreadable {
                problem: e.to_string(),
            },
        )
    })?;
    parse_urdf(&text, path)
}

/// Parses URDF text; `path` is used in messages only.
pub fn parse_urdf(text: &str, path: &Path) -> Result<Loaded, LoadError> {
    let lines = LineIndex::new(text);
    if let Some(deep) = nesting_too_deep(text, MAX_NESTING) {
        return Err(LoadError::at(
            Location::new(path, Some(lines.line(deep.offset)), "XML"),
            LoadErrorKind::NestedTooDeep { limit: MAX_NESTING },
        ));
    }
    let doc = Document::parse(text).map_err(|e| {
        let pos = e.pos();
        LoadError::at(
            Location::new(path, Some(pos.row), "XML"),
            LoadErrorKind::MalformedXml {
                problem: e.to_string(),
            },
        )
    })?;
    let mut p = Parser {
        doc: &doc,
        lines,
        path,
        warnings: Vec::new(),
    };
    let robot = p.robot()?;
    Ok(Loaded {
        robot,
        warnings: p.warnings,
    })
}

struct Parser<'a, 'input> {
    doc: &'a Document<'input>,
    lines: LineIndex,
    path: &'a Path,
    warnings: Vec<Warning>,
}

impl<'a, 'input> Parser<'a, 'input> {
    fn line(&self, node: Node) -> Option<u32> {
        Some(self.lines.line(node.range().start))
    }

    fn loc(&self, node: Node, element: impl Into<String>) -> Location {
        Location::new(self.path, self.line(node), element)
    }

    fn err<T>(
        &self,
        node: Node,
        element: impl Into<String>,
        msg: impl Into<String>,
    ) -> Result<T, LoadError> {
        self.fail(node, element, LoadErrorKind::Model(msg.into()))
    }

    fn fail<T>(
        &self,
        node: Node,
        element: impl Into<String>,
        kind: LoadErrorKind,
    ) -> Result<T, LoadError> {
        Err(LoadError::at(self.loc(node, element), kind))
    }

    fn warn(&mut self, node: Node, element: impl Into<String>, msg: impl Into<String>) {
        let w = Warning {
            location: self.loc(node, element),
            message: msg.into(),
        };
        self.warnings.push(w);
    }

    fn robot(&mut self) -> Result<Robot, LoadError> {
        let root = self.doc.root_element();
        if root.tag_name().name() != "robot" {
            return self.err(
                root,
                format!("<{}>", root.tag_name().name()),
                "the root element must be <robot>",
            );
        }
        let name = root.attribute("name").unwrap_or("robot").to_string();
        let mut links = Vec::new();
        let mut link_index: HashMap<String, usize> = HashMap::new();
        for node in root.children().filter(|n| n.has_tag_name("link")) {
            let link = self.link(node)?;
            if link_index.insert(link.name.clone(), links.len()).is_some() {
                return self.fail(
                    node,
                    format!("link \"{}\"", link.name),
                    LoadErrorKind::DuplicateName { what: "link" },
                );
            }
            links.push(link);
        }
        let mut joints: Vec<Joint> = Vec::new();
        let mut joint_names: HashMap<String, usize> = HashMap::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; links.len()];
        for node in root.children().filter(|n| n.has_tag_name("joint")) {
            let joint = self.joint(node, &link_index)?;
            let what = format!("joint \"{}\"", joint.name);
            if joint_names
                .insert(joint.name.clone(), joints.len())
                .is_some()
            {
                return self.fail(node, what, LoadErrorKind::DuplicateName { what: "joint" });
            }
            if let Some(other) = parent_joint[joint.child] {
                return self.err(
                    node,
                    what,
                    format!(
                        "link \"{}\" is already the child of joint \"{}\"; a link has at most one parent (close loops with URDF+ <loop>)",
                        links[joint.child].name, joints[other].name
                    ),
                );
            }
            if joint.parent == joint.child {
                return self.err(node, what, "parent and child are the same link");
            }
            parent_joint[joint.child] = Some(joints.len());
            joints.push(joint);
        }
        if links.is_empty() {
            return self.err(root, format!("robot \"{name}\""), "the model has no <link>");
        }
        // Exactly one root; every link reachable from it (otherwise the joints form a cycle).
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
                let names: Vec<&str> = roots.iter().map(|&r| links[r].name.as_str()).collect();
                let l = &links[*second];
                return Err(LoadError::new(
                    Location::new(self.path, l.line, format!("link \"{}\"", l.name)),
                    format!(
                        "the model has {} root links ({}); a URDF tree has exactly one",
                        roots.len(),
                        names.join(", ")
                    ),
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
            let j = &joints[parent_joint[l].unwrap()];
            return Err(LoadError::at(
                Location::new(self.path, j.line, format!("joint \"{}\"", j.name)),
                LoadErrorKind::Cycle {
                    link: links[l].name.clone(),
                    root: links[root_link].name.clone(),
                },
            ));
        }
        // Mimic targets must exist.
        for joint in &joints {
            for m in &joint.mimics {
                if !joint_names.contains_key(&m.joint) {
                    return Err(LoadError::new(
                        Location::new(
                            self.path,
                            m.line,
                            format!("joint \"{}\" <mimic>", joint.name),
                        ),
                        format!("<mimic> names joint \"{}\", which does not exist", m.joint),
                    ));
                }
            }
        }
        let mut loops = Vec::new();
        let mut couplings = Vec::new();
        // Every constraint has a name that messages and `info` use to point at it: a loop's or a
        // coupling's own, a mimic joint's is its joint's. The names must tell them apart.
        let mut constraint_names: HashMap<String, (&str, Option<u32>)> = joints
            .iter()
            .filter(|j| !j.mimics.is_empty())
            .map(|j| (j.name.clone(), ("the <mimic> of joint", j.line)))
            .collect();
        for node in root
            .children()
            .filter(|n| n.has_tag_name("loop") || n.has_tag_name("coupling"))
        {
            let (tag, name, line) = if node.has_tag_name("loop") {
                let l = self.loop_element(node, &link_index)?;
                let named = ("loop", l.name.clone(), l.line);
                loops.push(l);
                named
            } else {
                let c = self.coupling(node, &link_index)?;
                let named = ("coupling", c.name.clone(), c.line);
                couplings.push(c);
                named
            };
            if let Some((other, other_line)) = constraint_names.get(&name) {
                let at = other_line.map_or(String::new(), |l| format!(" at line {l}"));
                return self.err(
                    node,
                    format!("{tag} \"{name}\""),
                    format!(
                        "{other} \"{name}\"{at} already has this name; loops, couplings and mimic joints are constraints that messages and `info` name, so each needs its own name"
                    ),
                );
            }
            constraint_names.insert(name, (tag, line));
        }
        self.warn_ignored_joint_dynamics(root);
        self.warn_ignored_armature(root);
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

    fn link(&mut self, node: Node) -> Result<Link, LoadError> {
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
            Some(inode) => Some(self.inertial(inode, &what)?),
        };
        Ok(Link {
            name: name.to_string(),
            inertial,
            line: self.line(node),
        })
    }

    fn inertial(&mut self, node: Node, link: &str) -> Result<Inertial, LoadError> {
        let what = format!("{link} <inertial>");
        let origin = self.origin(node, &what)?;
        let Some(mnode) = node.children().find(|n| n.has_tag_name("mass")) else {
            return self.fail(
                node,
                what,
                LoadErrorKind::MissingElement { tag: "mass".into() },
            );
        };
        let mass = self.number(mnode, "value", None, &format!("{what} <mass>"))?;
        if mass < 0.0 {
            return self.err(
                mnode,
                format!("{what} <mass>"),
                format!("negative mass {mass}"),
            );
        }
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
        let mut inertia = [0.0; 6];
        for (k, a) in ["ixx", "ixy", "ixz", "iyy", "iyz", "izz"]
            .iter()
            .enumerate()
        {
            inertia[k] = self.number(inode, a, None, &iw)?;
        }
        let [ixx, ixy, ixz, iyy, iyz, izz] = inertia;
        let m = Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz);
        let scale = inertia_rounding_scale(&m, mass, &origin);
        if below_rounding(min_eigenvalue(&m), scale) {
            self.warn(
                inode,
                iw.clone(),
                format!(
                    "the inertia tensor is not positive semi-definite (ixx={ixx}, iyy={iyy}, izz={izz}, ixy={ixy}, ixz={ixz}, iyz={iyz}; smallest eigenvalue {:.3e}): no rigid body has it; loaded as given",
                    min_eigenvalue(&m)
                ),
            );
        } else {
            // The principal moments of a physical body satisfy the triangle inequality, equivalently
            // ½ tr(I) 1 − I (the body's second moment of mass) is positive semi-definite.
            let second_moment = Matrix3::identity() * (0.5 * m.trace()) - m;
            if below_rounding(min_eigenvalue(&second_moment), scale) {
                self.warn(inode, iw.clone(), "the principal moments of inertia violate the triangle inequality (no rigid body has them); loaded as given");
            }
        }
        if mass == 0.0 && m.iter().any(|&x| x != 0.0) {
            self.warn(
                mnode,
                iw,
                "zero mass with a non-zero rotational inertia (a massless rotor); loaded as given",
            );
        }
        Ok(Inertial {
            origin,
            mass,
            inertia,
        })
    }

    fn joint(&mut self, node: Node, links: &HashMap<String, usize>) -> Result<Joint, LoadError> {
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
            Some("revolute") => JointKind::Revolute,
            Some("continuous") => JointKind::Continuous,
            Some("prismatic") => JointKind::Prismatic,
            Some("fixed") => JointKind::Fixed,
            Some("floating") => JointKind::Floating,
            Some("planar") => {
                return self.err(node, what, "joint type \"planar\" is not supported (model it as two prismatic joints and a revolute joint)")
            }
            Some(t) => {
                return self.err(node, what, format!("unknown joint type \"{t}\" (expected revolute, continuous, prismatic, fixed or floating)"))
            }
            None => return self.fail(node, what, LoadErrorKind::MissingAttribute { attribute: "type".into() }),
        };
        let link_of = |tag: &str| -> Result<usize, LoadError> {
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
                None => self.err(
                    n,
                    format!("{what} <{tag}>"),
                    format!("names link \"{l}\", which does not exist"),
                ),
            }
        };
        let parent = link_of("parent")?;
        let child = link_of("child")?;
        let origin = self.origin(node, &what)?;
        let axis = match node.children().find(|n| n.has_tag_name("axis")) {
            None => [1.0, 0.0, 0.0],
            Some(a) => self.vec3(a, "xyz", Some([1.0, 0.0, 0.0]), &format!("{what} <axis>"))?,
        };
        if matches!(
            kind,
            JointKind::Revolute | JointKind::Continuous | JointKind::Prismatic
        ) && axis.iter().all(|&x| x == 0.0)
        {
            let a = node
                .children()
                .find(|n| n.has_tag_name("axis"))
                .unwrap_or(node);
            return self.err(a, format!("{what} <axis>"), "the joint axis is zero");
        }
        let mut mimics = Vec::new();
        for m in node.children().filter(|n| n.has_tag_name("mimic")) {
            let mw = format!("{what} <mimic>");
            let Some(target) = m.attribute("joint") else {
                return self.fail(
                    m,
                    mw,
                    LoadErrorKind::MissingAttribute {
                        attribute: "joint".into(),
                    },
                );
            };
            mimics.push(Mimic {
                joint: target.to_string(),
                multiplier: self.number(m, "multiplier", Some(1.0), &mw)?,
                offset: self.number(m, "offset", Some(0.0), &mw)?,
                line: self.line(m),
            });
        }
        if kind == JointKind::Fixed && !mimics.is_empty() {
            // A fixed joint has no coordinate to drive (talos_reduced.urdf has such gripper leftovers):
            // Pinocchio ignores these too.
            self.warn(
                node,
                what.clone(),
                "<mimic> on a fixed joint has nothing to drive; ignored",
            );
            mimics.clear();
        }
        let independent = match node.attribute("independent") {
            None => None,
            Some("true") => Some(true),
            Some("false") => Some(false),
            Some(x) => {
                return self.err(
                    node,
                    what,
                    format!("attribute `independent` must be \"true\" or \"false\", not \"{x}\""),
                )
            }
        };
        Ok(Joint {
            name: name.to_string(),
            kind,
            parent,
            child,
            origin,
            axis,
            mimics,
            independent,
            line: self.line(node),
        })
    }

    /// `<predecessor link>` or `<successor link>` of a loop or coupling.
    fn named_link(
        &self,
        node: Node<'a, 'input>,
        tag: &str,
        what: &str,
        links: &HashMap<String, usize>,
    ) -> Result<(usize, Node<'a, 'input>), LoadError> {
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
            None => self.err(
                n,
                format!("{what} <{tag}>"),
                format!("names link \"{l}\", which does not exist"),
            ),
        }
    }

    /// `<loop name>` or `<coupling name>`: required, as GRBDA's reader requires it (it refuses an
    /// unnamed constraint), so that every message can point at the element.
    fn constraint_name(&self, node: Node, tag: &str) -> Result<String, LoadError> {
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
                names.push(name);
            }
        }
        let Some(first) = first else { return };
        const LISTED: usize = 5;
        let mut list = names[..names.len().min(LISTED)]
            .iter()
            .map(|n| format!("\"{n}\""))
            .collect::<Vec<_>>()
            .join(", ");
        if names.len() > LISTED {
            list += &format!(" and {} more", names.len() - LISTED);
        }
        let message = format!(
            "<dynamics damping/friction> of {} joint(s) ({list}) ignored: embedyn computes the dynamics of ideal joints (as Pinocchio's algorithms do); add the losses to tau",
            names.len()
        );
        let (joint, dynamics) = first;
        self.warn(dynamics, format!("joint \"{joint}\" <dynamics>"), message);
    }

    /// A motor's armature (`<dynamics armature>`, or a transmission's `<drake:rotor_inertia>`) is not
    /// read yet: it would add to M's diagonal, so ignoring it changes the numbers. One warning per file, at
    /// the first element that has a non-zero one, until armature is supported.
    fn warn_ignored_armature(&mut self, root: Node) {
        let nonzero = |v: Option<&str>| v.is_some_and(|v| v.trim().parse::<f64>() != Ok(0.0));
        let armature = root
            .descendants()
            .filter(|d| d.has_tag_name("dynamics") && nonzero(d.attribute("armature")))
            .chain(root.descendants().filter(|d| {
                d.tag_name().name() == "rotor_inertia" && nonzero(d.attribute("value"))
            }))
            .min_by_key(|d| d.range().start);
        if let Some(node) = armature {
            let what = format!("<{}>", node.tag_name().name());
            self.warn(
                node,
                what,
                "armature (a motor's reflected rotor inertia) is not supported yet and is ignored: the dynamics computed are those without it",
            );
        }
    }

    fn loop_element(&self, node: Node, links: &HashMap<String, usize>) -> Result<Loop, LoadError> {
        let name = self.constraint_name(node, "loop")?;
        let what = format!("loop \"{name}\"");
        let kind = match node.attribute("type") {
            Some("revolute") | Some("continuous") => LoopKind::Revolute,
            Some("prismatic") => LoopKind::Prismatic,
            Some("spherical") => LoopKind::Spherical,
            Some("fixed") => LoopKind::Fixed,
            Some("planar") => return self.err(node, what, "loop type \"planar\" is not supported"),
            Some(t) => return self.err(node, what, format!("unknown loop type \"{t}\" (expected revolute, continuous, prismatic, spherical or fixed)")),
            None => return self.fail(node, what, LoadErrorKind::MissingAttribute { attribute: "type".into() }),
        };
        let (pl, pn) = self.named_link(node, "predecessor", &what, links)?;
        let (sl, sn) = self.named_link(node, "successor", &what, links)?;
        let predecessor = LoopFrame {
            link: pl,
            origin: self.origin(pn, &format!("{what} <predecessor>"))?,
        };
        let successor = LoopFrame {
            link: sl,
            origin: self.origin(sn, &format!("{what} <successor>"))?,
        };
        let axis = match node.children().find(|n| n.has_tag_name("axis")) {
            None => [1.0, 0.0, 0.0],
            Some(a) => {
                let axis = self.vec3(a, "xyz", Some([1.0, 0.0, 0.0]), &format!("{what} <axis>"))?;
                if matches!(kind, LoopKind::Revolute | LoopKind::Prismatic)
                    && axis.iter().all(|&x| x == 0.0)
                {
                    return self.err(a, format!("{what} <axis>"), "the loop axis is zero");
                }
                axis
            }
        };
        if pl == sl {
            return self.err(node, what, "predecessor and successor are the same link");
        }
        Ok(Loop {
            name,
            kind,
            predecessor,
            successor,
            axis,
            line: self.line(node),
        })
    }

    fn coupling(&self, node: Node, links: &HashMap<String, usize>) -> Result<Coupling, LoadError> {
        let name = self.constraint_name(node, "coupling")?;
        let what = format!("coupling \"{name}\"");
        let (predecessor, _) = self.named_link(node, "predecessor", &what, links)?;
        let (successor, _) = self.named_link(node, "successor", &what, links)?;
        let ratio = match node.children().find(|n| n.has_tag_name("ratio")) {
            None => 1.0,
            Some(r) => self.number(r, "value", Some(1.0), &format!("{what} <ratio>"))?,
        };
        if predecessor == successor {
            return self.err(node, what, "predecessor and successor are the same link");
        }
        Ok(Coupling {
            name,
            predecessor,
            successor,
            ratio,
            line: self.line(node),
        })
    }

    fn origin(&self, parent: Node, what: &str) -> Result<Origin, LoadError> {
        match parent.children().find(|n| n.has_tag_name("origin")) {
            None => Ok(Origin::default()),
            Some(o) => {
                let w = format!("{what} <origin>");
                Ok(Origin {
                    xyz: self.vec3(o, "xyz", Some([0.0; 3]), &w)?,
                    rpy: self.vec3(o, "rpy", Some([0.0; 3]), &w)?,
                })
            }
        }
    }

    fn number(
        &self,
        node: Node,
        attr: &str,
        default: Option<f64>,
        what: &str,
    ) -> Result<f64, LoadError> {
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
    ) -> Result<[f64; 3], LoadError> {
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
            return self.err(
                node,
                what,
                format!("`{attr}=\"{s}\"` must be three numbers"),
            );
        }
        let mut out = [0.0; 3];
        for (k, p) in parts.iter().enumerate() {
            out[k] = match p.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                Ok(_) => {
                    return self.err(
                        node,
                        what,
                        format!("`{attr}=\"{s}\"` contains a number that is not finite"),
                    )
                }
                Err(_) => {
                    return self.err(
                        node,
                        what,
                        format!("`{attr}=\"{s}\"`: \"{p}\" is not a number"),
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

#[cfg(test)]
mod kind_tests {
    use super::*;

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
}

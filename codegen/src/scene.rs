//! Scene options that change the model as read before it is assembled: locked joints (`--lock`) and the
//! reflected-inertia approximation of geared rotors (`--rotors reflected`).
//!
//! Both turn moving joints into fixed ones in the IR ([`Joint::locked`]); the assembly then merges such a
//! joint's child into its parent exactly as it merges any fixed joint, so that every output (the
//! interpreted model, generated code, `info`) sees one and the same reduced model, and the generator folds
//! whatever depended on the removed coordinate.

use crate::assemble::{inertial_about_link, origin_transform, ModelOptions, ROOT_JOINT};
use crate::error::{ConstraintElement, LoadError, LoadErrorKind, Location};
use crate::ir::{Joint, JointKind, Robot};
use embedyn_runtime::nalgebra::Vector3;
use embedyn_runtime::{SpatialInertia, Transform};
use std::borrow::Cow;
use std::collections::HashMap;

/// How geared rotors are modelled (`--rotors`, the macro's `rotors = …`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Rotors {
    /// Each rotor is a body of its own, coupled to the joints that drive it (the aggregate link of
    /// constraint embedding: exact, gyroscopic coupling included).
    #[default]
    Exact,
    /// Each geared rotor is removed as a body: its mass and inertia join its carrier at rotor angle 0, and
    /// gain² × its axial inertia becomes armature on each joint that drives it (docs/model-format.md says
    /// what this drops).
    Reflected,
}

impl Rotors {
    /// Both choices, `exact` first.
    pub const ALL: [Rotors; 2] = [Rotors::Exact, Rotors::Reflected];

    /// `exact` or `reflected`, as the command line and the macro write it.
    pub fn as_str(self) -> &'static str {
        match self {
            Rotors::Exact => "exact",
            Rotors::Reflected => "reflected",
        }
    }

    /// The choice written `text` (`exact` or `reflected`).
    pub fn parse(text: &str) -> Option<Rotors> {
        Rotors::ALL.into_iter().find(|r| r.as_str() == text)
    }
}

/// One `--lock JOINT=VALUE`: the joint is fixed at `value` (rad or m) and its coordinate leaves q and v.
#[derive(Clone, Debug, PartialEq)]
pub struct LockedJoint {
    /// The joint's name.
    pub joint: String,
    /// Its coordinate, rad (revolute, continuous) or m (prismatic).
    pub value: f64,
}

/// A geared rotor, as `--rotors reflected` sees it: the faster side of a `<coupling>` (the successor when
/// |ratio| > 1, the predecessor when |ratio| < 1, the side declared `independent="false"` at |ratio| = 1)
/// when that side is one moving joint whose child carries no moving joint and no loop, and which takes
/// part in no other constraint. Its coordinate is `Σ gain · q_driver` over the joints on the coupling's
/// other side.
#[derive(Clone, Debug, PartialEq)]
pub struct GearedRotor {
    /// Index of the coupling into [`Robot::couplings`].
    pub coupling: usize,
    /// Index of the rotor's joint into [`Robot::joints`].
    pub joint: usize,
    /// The driving joints (indices into [`Robot::joints`]) and their gains.
    pub drivers: Vec<(usize, f64)>,
    /// The rotor's inertia about its joint axis (kg·m²; its mass, kg, for a prismatic joint), the
    /// armature of its joint included.
    pub axial_inertia: f64,
}

/// The pose of a joint's child link in its parent link: the joint's origin, and for a locked joint the
/// joint's motion at the locked coordinate too.
pub(crate) fn fixed_placement(joint: &Joint) -> Transform<f64> {
    let origin = origin_transform(&joint.origin);
    let Some(value) = joint.locked else {
        return origin;
    };
    let axis = Vector3::from(joint.axis);
    let axis = axis / axis.norm();
    let motion = match joint.kind {
        JointKind::Prismatic => Transform::translation_along(&axis, value),
        _ => Transform::rotation_about(&axis, value),
    };
    origin.compose(&motion)
}

/// The model as the scene options change it: borrowed unchanged when they change nothing.
pub(crate) fn apply<'r>(
    robot: &'r Robot,
    options: &ModelOptions,
) -> Result<Cow<'r, Robot>, LoadError> {
    if options.locks.is_empty() && options.rotors == Rotors::Exact {
        return Ok(Cow::Borrowed(robot));
    }
    let mut scene = robot.clone();
    // Rotors first: a joint that drives only reflected rotors is then outside every constraint and may
    // be locked (its armature goes with it), and a reflected rotor may be locked at another angle.
    if options.rotors == Rotors::Reflected {
        reflect_rotors(&mut scene)?;
    }
    lock_joints(&mut scene, &options.locks, options.floating)?;
    Ok(Cow::Owned(scene))
}

/// The link tree: each link's parent joint and child joints.
struct LinkTree {
    parent_joint: Vec<Option<usize>>,
    child_joints: Vec<Vec<usize>>,
}

impl LinkTree {
    fn new(robot: &Robot) -> Self {
        let mut parent_joint = vec![None; robot.links.len()];
        let mut child_joints = vec![Vec::new(); robot.links.len()];
        for (j, joint) in robot.joints.iter().enumerate() {
            parent_joint[joint.child] = Some(j);
            child_joints[joint.parent].push(j);
        }
        LinkTree {
            parent_joint,
            child_joints,
        }
    }

    /// `link` and its ancestors up to the root.
    fn ancestors(&self, robot: &Robot, mut link: usize) -> Vec<usize> {
        let mut out = vec![link];
        while let Some(j) = self.parent_joint[link] {
            link = robot.joints[j].parent;
            out.push(link);
        }
        out
    }

    /// The moving joints between `a` and `b`, each side from the link up to their common ancestor:
    /// `(joints above a, joints above b)`.
    fn paths(&self, robot: &Robot, a: usize, b: usize) -> (Vec<usize>, Vec<usize>) {
        let above_a = self.ancestors(robot, a);
        let above_b = self.ancestors(robot, b);
        let common = *above_a
            .iter()
            .find(|l| above_b.contains(l))
            .expect("one tree has one root");
        let joints_to = |chain: &[usize]| -> Vec<usize> {
            chain
                .iter()
                .take_while(|&&l| l != common)
                .filter_map(|&l| self.parent_joint[l])
                .filter(|&j| robot.joints[j].moves())
                .collect()
        };
        (joints_to(&above_a), joints_to(&above_b))
    }
}

/// For each joint, the first constraint (kind and name) whose coordinates it takes part in, and how many.
/// Loops and couplings come before mimics, so a joint whose first is a mimic is in no loop or coupling.
fn constraint_uses(
    robot: &Robot,
    tree: &LinkTree,
) -> Vec<(usize, Option<(ConstraintElement, String)>)> {
    let mut uses: Vec<(usize, Option<(ConstraintElement, String)>)> =
        vec![(0, None); robot.joints.len()];
    let mut mark = |j: usize, what: ConstraintElement, name: &str| {
        let entry = &mut uses[j];
        entry.0 += 1;
        entry.1.get_or_insert_with(|| (what, name.to_string()));
    };
    for l in &robot.loops {
        let (a, b) = tree.paths(robot, l.predecessor.link, l.successor.link);
        for j in a.into_iter().chain(b) {
            mark(j, ConstraintElement::Loop, &l.name);
        }
    }
    for c in &robot.couplings {
        let (a, b) = tree.paths(robot, c.predecessor, c.successor);
        for j in a.into_iter().chain(b) {
            mark(j, ConstraintElement::Coupling, &c.name);
        }
    }
    // By a name index: a lookup by scanning the joints per <mimic> took 14.5 s on a 60,000-joint chain.
    let index = joint_index(robot);
    for (j, joint) in robot.joints.iter().enumerate() {
        for m in &joint.mimics {
            mark(j, ConstraintElement::Mimic, &joint.name);
            if let Some(&d) = index.get(m.joint.as_str()) {
                mark(d, ConstraintElement::Mimic, &joint.name);
            }
        }
    }
    uses
}

/// Each joint's index by its name.
fn joint_index(robot: &Robot) -> HashMap<&str, usize> {
    robot
        .joints
        .iter()
        .enumerate()
        .map(|(j, joint)| (joint.name.as_str(), j))
        .collect()
}

/// The joints `j`'s `<mimic>`s lead to at the top of their chains (those that follow no other joint), in
/// the order met; in a cycle of mimics with no such joint, the joints `j` follows itself.
fn mimic_roots(robot: &Robot, index: &HashMap<&str, usize>, j: usize) -> Vec<usize> {
    let direct = || -> Vec<usize> {
        robot.joints[j]
            .mimics
            .iter()
            .filter_map(|m| index.get(m.joint.as_str()).copied())
            .collect()
    };
    let (mut roots, mut seen, mut stack) = (Vec::new(), vec![false; robot.joints.len()], direct());
    stack.reverse();
    seen[j] = true;
    while let Some(d) = stack.pop() {
        if std::mem::replace(&mut seen[d], true) {
            continue;
        }
        let above = &robot.joints[d].mimics;
        if above.is_empty() {
            roots.push(d);
        }
        stack.extend(
            above
                .iter()
                .rev()
                .filter_map(|m| index.get(m.joint.as_str()).copied()),
        );
    }
    if roots.is_empty() {
        roots = direct();
        roots.dedup();
    }
    roots
}

fn lock_joints(robot: &mut Robot, locks: &[LockedJoint], floating: bool) -> Result<(), LoadError> {
    if locks.is_empty() {
        return Ok(());
    }
    let tree = LinkTree::new(robot);
    let uses = constraint_uses(robot, &tree);
    // The value each joint was locked at by an earlier `--lock` (not by a reflected rotor).
    let mut locked_by_user: Vec<Option<f64>> = vec![None; robot.joints.len()];
    let at_joint = |robot: &Robot, j: usize| {
        let joint = &robot.joints[j];
        Location::new(
            &robot.source,
            joint.line,
            format!("joint \"{}\"", joint.name),
        )
    };
    for lock in locks {
        let Some(j) = robot.joints.iter().position(|j| j.name == lock.joint) else {
            let at = Location::new(&robot.source, None, "--lock / lock(…)");
            if floating && lock.joint == ROOT_JOINT {
                return Err(LoadError::at(
                    at,
                    LoadErrorKind::LockNotOneDof { kind: "floating" },
                ));
            }
            return Err(LoadError::at(
                at,
                LoadErrorKind::LockUnknownJoint {
                    joint: lock.joint.clone(),
                },
            ));
        };
        let joint = &robot.joints[j];
        let kind = if joint.kind.is_one_dof() {
            None
        } else {
            Some(LoadErrorKind::LockNotOneDof {
                kind: joint.kind.as_str(),
            })
        };
        let kind = kind
            .or_else(|| {
                locked_by_user[j].map(|first| LoadErrorKind::LockedTwice {
                    first,
                    second: lock.value,
                })
            })
            .or_else(|| {
                (!lock.value.is_finite())
                    .then_some(LoadErrorKind::LockValueNotFinite { value: lock.value })
            })
            .or_else(|| match &uses[j].1 {
                // A joint that only drives mimic joints may be locked: they are fixed with it (below). A
                // mimic joint itself may not: the joints it follows would have to move with it. The
                // refusal names those at the top of its chains, the ones to lock.
                Some((ConstraintElement::Mimic, _)) if !joint.mimics.is_empty() => {
                    let index = joint_index(robot);
                    let roots = mimic_roots(robot, &index, j);
                    Some(LoadErrorKind::LockedMimicJoint {
                        already_locked: roots
                            .iter()
                            .all(|&d| locks.iter().any(|l| l.joint == robot.joints[d].name)),
                        drivers: roots
                            .iter()
                            .map(|&d| robot.joints[d].name.clone())
                            .collect(),
                    })
                }
                Some((ConstraintElement::Mimic, _)) => None,
                Some((what, name)) => Some(LoadErrorKind::LockedJointInConstraint {
                    what: *what,
                    name: name.clone(),
                }),
                None => None,
            });
        if let Some(kind) = kind {
            return Err(LoadError::at(at_joint(robot, j), kind));
        }
        robot.joints[j].locked = Some(lock.value);
        locked_by_user[j] = Some(lock.value);
    }
    fix_followers_of_locked_joints(robot, &uses)
}

/// Each `<mimic>` term whose driver is locked becomes a constant: `q = Σ mₖ q_dₖ + oₖ` keeps its other
/// terms (the constant joins their offset), and a mimic joint whose drivers are all locked is locked
/// itself at `Σ mₖ x_dₖ + oₖ`, which may fix the joints that follow it in turn. Why: the constraint holds
/// at every instant, so with its drivers fixed the joint is fixed too, and a gripper's fingers lock with
/// the joint they follow (a parallel gripper's `finger1_joint`, models/loops/parallel_gripper.urdf).
/// Where a joint cannot be fixed so (on a loop's path, not of one coordinate, a value that overflows),
/// the error is at that joint and names the locked joint that fixes it.
fn fix_followers_of_locked_joints(
    robot: &mut Robot,
    uses: &[(usize, Option<(ConstraintElement, String)>)],
) -> Result<(), LoadError> {
    let index: HashMap<String, usize> = joint_index(robot)
        .into_iter()
        .map(|(name, j)| (name.to_string(), j))
        .collect();
    let mut followers = vec![Vec::new(); robot.joints.len()];
    for (f, joint) in robot.joints.iter().enumerate() {
        for m in &joint.mimics {
            if let Some(&d) = index.get(&m.joint) {
                followers[d].push(f);
            }
        }
    }
    // A worklist of locked joints, not passes until nothing changes: a chain of n mimics written leaf
    // first would take n passes over every joint.
    let mut locked: Vec<usize> = (0..robot.joints.len())
        .filter(|&j| robot.joints[j].locked.is_some())
        .collect();
    // The locked joint each one was fixed by, for messages (itself where locked directly).
    let mut fixed_by: Vec<usize> = (0..robot.joints.len()).collect();
    while let Some(d) = locked.pop() {
        for &f in &followers[d] {
            if robot.joints[f].locked.is_some() {
                continue;
            }
            let mut constant = 0.0;
            let mut kept = Vec::new();
            for m in std::mem::take(&mut robot.joints[f].mimics) {
                match index.get(&m.joint).and_then(|&d| robot.joints[d].locked) {
                    Some(value) => constant += m.multiplier * value + m.offset,
                    None => kept.push(m),
                }
            }
            let joint = &mut robot.joints[f];
            let fixed = kept.is_empty();
            if let Some(first) = kept.first_mut() {
                first.offset += constant;
                constant = first.offset;
            }
            joint.mimics = kept;
            let reason = if fixed && !joint.kind.is_one_dof() {
                Some(LoadErrorKind::LockNotOneDof {
                    kind: joint.kind.as_str(),
                })
            } else if !constant.is_finite() {
                Some(if fixed {
                    LoadErrorKind::LockValueNotFinite { value: constant }
                } else {
                    LoadErrorKind::MimicOffsetNotFinite { value: constant }
                })
            } else if !fixed {
                None
            } else {
                match &uses[f].1 {
                    Some((ConstraintElement::Mimic, _)) | None => None,
                    Some((what, name)) => Some(LoadErrorKind::LockedJointInConstraint {
                        what: *what,
                        name: name.clone(),
                    }),
                }
            };
            if let Some(reason) = reason {
                let at = Location::new(
                    &robot.source,
                    joint.line,
                    format!("joint \"{}\"", joint.name),
                );
                let kind = LoadErrorKind::LockFixesMimicJoint {
                    driver: robot.joints[fixed_by[d]].name.clone(),
                    reason: Box::new(reason),
                };
                return Err(LoadError::at(at, kind));
            }
            if fixed {
                joint.locked = Some(constant);
                fixed_by[f] = fixed_by[d];
                locked.push(f);
            }
        }
    }
    Ok(())
}

/// The geared rotors of `robot` (see [`GearedRotor`]), in the order of their couplings. A coupling whose
/// sides are both more than one joint, or carry further bodies, is no rotor and stays exact.
pub fn geared_rotors(robot: &Robot) -> Vec<GearedRotor> {
    let tree = LinkTree::new(robot);
    let uses = constraint_uses(robot, &tree);
    let loop_links: Vec<usize> = robot
        .loops
        .iter()
        .flat_map(|l| [l.predecessor.link, l.successor.link])
        .collect();
    let mut rotors = Vec::new();
    for (c, coupling) in robot.couplings.iter().enumerate() {
        let (predecessor, successor) = tree.paths(robot, coupling.predecessor, coupling.successor);
        // ratio · Σ q_predecessor = Σ q_successor.
        let rotor = |rotor_side: &[usize], drivers: &[usize], gain: f64| {
            let [r] = rotor_side else { return None };
            let joint = &robot.joints[*r];
            if drivers.is_empty()
                || uses[*r].0 != 1
                || !joint.kind.is_one_dof()
                || !gain.is_finite()
            {
                return None;
            }
            let inertia = rigid_subtree_inertia(robot, &tree, joint.child, &loop_links)?;
            let axis = Vector3::from(joint.axis);
            let axis = axis / axis.norm();
            let axial = match joint.kind {
                JointKind::Prismatic => inertia.mass,
                _ => (axis.transpose() * inertia.rotational * axis)[0],
            };
            Some(GearedRotor {
                coupling: c,
                joint: *r,
                drivers: drivers.iter().map(|&d| (d, gain)).collect(),
                axial_inertia: axial + joint.armature,
            })
        };
        // The rotor is the side that turns faster: the successor when |ratio| > 1 (GRBDA's files write
        // link, rotor, ratio 6), the predecessor when |ratio| < 1; at |ratio| = 1 the side declared
        // dependent. Only that side is tried: the driven link is never taken for a rotor.
        let declared_dependent =
            |side: &[usize]| matches!(side, [j] if robot.joints[*j].independent == Some(false));
        let successor_is_rotor = if coupling.ratio.abs() != 1.0 {
            coupling.ratio.abs() > 1.0
        } else {
            declared_dependent(&successor) && !declared_dependent(&predecessor)
        };
        let found = if successor_is_rotor {
            rotor(&successor, &predecessor, coupling.ratio)
        } else if coupling.ratio.abs() != 1.0 || declared_dependent(&predecessor) {
            rotor(&predecessor, &successor, 1.0 / coupling.ratio)
        } else {
            None
        };
        rotors.extend(found);
    }
    rotors
}

/// The inertia of `link` and every link fixed to it, about `link`'s frame; `None` when a moving joint or
/// a loop hangs below it.
fn rigid_subtree_inertia(
    robot: &Robot,
    tree: &LinkTree,
    link: usize,
    loop_links: &[usize],
) -> Option<SpatialInertia<f64>> {
    let mut total = SpatialInertia::zero();
    let mut stack = vec![(link, Transform::identity())];
    while let Some((l, pose)) = stack.pop() {
        if loop_links.contains(&l) {
            return None;
        }
        if let Some(inertial) = &robot.links[l].inertial {
            total = total + inertial_about_link::<f64>(inertial).act(&pose);
        }
        for &j in &tree.child_joints[l] {
            let joint = &robot.joints[j];
            if joint.moves() {
                return None;
            }
            stack.push((joint.child, pose.compose(&fixed_placement(joint))));
        }
    }
    Some(total)
}

/// `--rotors reflected`: each geared rotor's joint is fixed at angle 0 (its inertia joins its carrier),
/// its coupling removed, and gain² × its axial inertia added to each driving joint's armature.
fn reflect_rotors(robot: &mut Robot) -> Result<(), LoadError> {
    let rotors = geared_rotors(robot);
    for rotor in &rotors {
        for &(d, gain) in &rotor.drivers {
            let armature = robot.joints[d].armature + gain * gain * rotor.axial_inertia;
            if !armature.is_finite() {
                let coupling = &robot.couplings[rotor.coupling];
                return Err(LoadError::at(
                    Location::new(
                        &robot.source,
                        coupling.line,
                        format!("coupling \"{}\"", coupling.name),
                    ),
                    LoadErrorKind::ReflectedInertiaOverflow {
                        ratio: coupling.ratio,
                        axial_inertia: rotor.axial_inertia,
                    },
                ));
            }
            robot.joints[d].armature = armature;
        }
        let joint = &mut robot.joints[rotor.joint];
        joint.locked = Some(0.0);
        joint.armature = 0.0;
    }
    let mut c = 0;
    robot.couplings.retain(|_| {
        c += 1;
        !rotors.iter().any(|r| r.coupling == c - 1)
    });
    Ok(())
}

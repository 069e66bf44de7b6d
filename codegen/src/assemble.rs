//! From the IR to the runtime's [`Model`]: depth-first numbering, fixed joints merged into their parent
//! body (inertias combined exactly), the optional free-flyer root.
//!
//! The model is built and validated in f64, whatever scalar is asked for, and then converted: the
//! structure (redundant loop equations, independent coordinates, which joints determine their
//! accelerations) is decided once, in f64, so that every scalar type gets the same model, and a
//! constant that does not fit the narrower type is an error rather than another model.

use crate::error::{LoadError, LoadErrorKind, Location};
use crate::ir::{Inertial, JointKind, LoopKind, Origin, Robot};
use crate::scene::{self, LockedJoint, Rotors};
use embedyn_runtime::constraints::GroupLabel;
use embedyn_runtime::nalgebra::{Matrix3, Vector3};
use embedyn_runtime::{
    JointType, Model, ModelElement, ModelError, Real, SpatialInertia, Transform,
};

/// Choices made when turning a file into a model.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelOptions {
    /// Make the URDF root free with a floating joint named `root_joint` (`--floating`).
    pub floating: bool,
    /// Gravity in the world frame (m/s²).
    pub gravity: [f64; 3],
    /// Joints fixed at a coordinate (`--lock`), in the order given.
    pub locks: Vec<LockedJoint>,
    /// How geared rotors are modelled (`--rotors`).
    pub rotors: Rotors,
}

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            floating: false,
            gravity: [0.0, 0.0, -9.81],
            locks: Vec::new(),
            rotors: Rotors::Exact,
        }
    }
}

/// The name of the joint `--floating` adds.
pub const ROOT_JOINT: &str = "root_joint";

pub(crate) fn origin_transform<T: Real>(o: &Origin) -> Transform<T> {
    Transform::from_xyz_rpy(o.xyz, o.rpy)
}

/// The spatial inertia of a URDF `<inertial>` about its link frame.
pub fn inertial_about_link<T: Real>(i: &Inertial) -> SpatialInertia<T> {
    let f = T::from_f64;
    let [ixx, ixy, ixz, iyy, iyz, izz] = i.inertia;
    let ic = Matrix3::new(
        f(ixx),
        f(ixy),
        f(ixz),
        f(ixy),
        f(iyy),
        f(iyz),
        f(ixz),
        f(iyz),
        f(izz),
    );
    let frame: Transform<T> = origin_transform(&i.origin);
    let ic_link = frame.rotation * ic * frame.rotation.transpose();
    SpatialInertia::from_com(f(i.mass), frame.translation, ic_link)
}

fn is_finite(i: &SpatialInertia<f64>) -> bool {
    i.mass.is_finite()
        && i.first_moment.iter().all(|x| x.is_finite())
        && i.rotational.iter().all(|x| x.is_finite())
}

/// Builds the model in scalar `T`: built and validated in f64, then converted by [`Model::try_cast`].
pub fn build_model<T: Real>(robot: &Robot, options: &ModelOptions) -> Result<Model<T>, LoadError> {
    convert_model(robot, &build_model_f64(robot, options)?)
}

/// The f64 model converted to `U`, or an error naming the element whose constant does not fit `U` or
/// the joint whose acceleration `U` cannot resolve.
pub(crate) fn convert_model<U: Real>(
    robot: &Robot,
    model: &Model<f64>,
) -> Result<Model<U>, LoadError> {
    model
        .try_cast::<U>()
        .map_err(|e| model_build_error(robot, e, U::NAME))
}

fn build_model_f64(robot: &Robot, options: &ModelOptions) -> Result<Model<f64>, LoadError> {
    let robot = &*scene::apply(robot, options)?;
    let path = &robot.source;
    let joint_loc = |j: usize| {
        let joint = &robot.joints[j];
        Location::new(path, joint.line, format!("joint \"{}\"", joint.name))
    };
    let has_floating = robot
        .joints
        .iter()
        .position(|j| j.kind == JointKind::Floating);
    if options.floating {
        if let Some(j) = has_floating {
            return Err(LoadError::at(joint_loc(j), LoadErrorKind::AlreadyFloating));
        }
        // Coordinates are matched to joints by name: two joints of one name would be ambiguous.
        if let Some(j) = robot.joints.iter().position(|j| j.name == ROOT_JOINT) {
            return Err(LoadError::at(
                joint_loc(j),
                LoadErrorKind::RootJointNameTaken,
            ));
        }
    }
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); robot.links.len()];
    for (j, joint) in robot.joints.iter().enumerate() {
        children[joint.parent].push(j);
    }

    // Depth-first walk over links. Each link gets a body (None: fixed to the world) and its pose in that
    // body's frame.
    struct Pending {
        parent: Option<usize>,
        joint: Option<usize>, // None: the --floating root joint
        placement: Transform<f64>,
        link: usize,
        inertia: SpatialInertia<f64>,
        links: Vec<(String, Transform<f64>)>,
    }
    let mut bodies: Vec<Pending> = Vec::new();
    let mut link_body: Vec<Option<(Option<usize>, Transform<f64>)>> = vec![None; robot.links.len()];
    let root_body = if options.floating {
        bodies.push(Pending {
            parent: None,
            joint: None,
            placement: Transform::identity(),
            link: robot.root,
            inertia: SpatialInertia::zero(),
            links: vec![],
        });
        Some(0)
    } else {
        None
    };
    link_body[robot.root] = Some((root_body, Transform::identity()));
    // Explicit stack so that very deep chains (1000+ bodies) do not overflow the call stack;
    // children are pushed in reverse to visit them in file order.
    let mut stack: Vec<usize> = children[robot.root].iter().rev().copied().collect();
    while let Some(j) = stack.pop() {
        let joint = &robot.joints[j];
        let (parent_body, parent_pose) = link_body[joint.parent].expect("parent visited first");
        if joint.moves() {
            let pose = parent_pose.compose(&origin_transform(&joint.origin));
            if joint.kind == JointKind::Floating && parent_body.is_some() {
                return Err(LoadError::at(
                    joint_loc(j),
                    LoadErrorKind::FloatingNotAtRoot,
                ));
            }
            bodies.push(Pending {
                parent: parent_body,
                joint: Some(j),
                placement: pose,
                link: joint.child,
                inertia: SpatialInertia::zero(),
                links: vec![],
            });
            link_body[joint.child] = Some((Some(bodies.len() - 1), Transform::identity()));
        } else {
            // A fixed joint, or one a scene locked: the child link is merged into the parent body.
            let pose = parent_pose.compose(&scene::fixed_placement(joint));
            link_body[joint.child] = Some((parent_body, pose));
        }
        stack.extend(children[joint.child].iter().rev());
    }
    // Merge every link's inertia into its body; links fixed to the world carry none that matters.
    let mut world_links: Vec<(String, Transform<f64>)> = Vec::new();
    for (l, link) in robot.links.iter().enumerate() {
        let (body, pose) = link_body[l].expect("every link is reachable from the root");
        if body.is_none() {
            world_links.push((link.name.clone(), pose));
        }
        if let Some(b) = body {
            bodies[b].links.push((link.name.clone(), pose));
            if let Some(inertial) = &link.inertial {
                let i = inertial_about_link::<f64>(inertial).act(&pose);
                let at = Location::new(
                    path,
                    link.line,
                    format!("link \"{}\" <inertial>", link.name),
                );
                if !is_finite(&i) {
                    return Err(LoadError::at(
                        at,
                        LoadErrorKind::InertiaOverflow {
                            mass: inertial.mass,
                            com_distance: scaled_norm(
                                &pose.act_point(&Vector3::from(inertial.origin.xyz)),
                            ),
                            largest_moment: inertial
                                .inertia
                                .iter()
                                .fold(0.0f64, |m, x| m.max(x.abs())),
                        },
                    ));
                }
                let merged = bodies[b].inertia + i;
                if !is_finite(&merged) {
                    let body_link = &robot.links[bodies[b].link].name;
                    return Err(LoadError::at(
                        at,
                        LoadErrorKind::MergedInertiaOverflow {
                            body_link: body_link.clone(),
                        },
                    ));
                }
                bodies[b].inertia = merged;
            }
        }
    }

    let g = options.gravity;
    let mut builder =
        Model::<f64>::builder(robot.name.clone()).gravity(Vector3::new(g[0], g[1], g[2]));
    let (names, placements) = world_links.into_iter().unzip();
    builder.set_world_links(names, placements);
    for (b, pending) in bodies.iter().enumerate() {
        let (name, jtype, axis) = match pending.joint {
            None => (ROOT_JOINT.to_string(), JointType::Floating, [0.0; 3]),
            Some(j) => {
                let joint = &robot.joints[j];
                let t = match joint.kind {
                    JointKind::Revolute => JointType::Revolute,
                    JointKind::Continuous => JointType::Continuous,
                    JointKind::Prismatic => JointType::Prismatic,
                    JointKind::Floating => JointType::Floating,
                    JointKind::Fixed => unreachable!("fixed joints were merged"),
                };
                (joint.name.clone(), t, joint.axis)
            }
        };
        let axis = Vector3::new(axis[0], axis[1], axis[2]);
        let index = builder
            .add_body(
                pending.parent,
                name,
                jtype,
                axis,
                pending.placement,
                robot.links[pending.link].name.clone(),
                pending.inertia,
            )
            .map_err(|e| {
                LoadError::at(joint_location(robot, bodies_joint(&bodies, b)), e.into())
            })?;
        if let Some(j) = pending.joint {
            let limits = robot.joints[j].limits;
            if limits != Default::default() {
                builder
                    .set_limits(index, limits)
                    .map_err(|e| LoadError::at(joint_location(robot, Some(j)), e.into()))?;
            }
            let armature = robot.joints[j].armature;
            if armature != 0.0 {
                builder
                    .set_armature(index, armature)
                    .map_err(|e| LoadError::at(joint_location(robot, Some(j)), e.into()))?;
            }
        }
        let mut links = pending.links.clone();
        // The body's own link first.
        if let Some(k) = links
            .iter()
            .position(|(n, _)| *n == robot.links[pending.link].name)
        {
            links.swap(0, k);
        }
        let (names, placements) = links.into_iter().unzip();
        builder.set_merged_links(index, names, placements);
    }
    fn bodies_joint(bodies: &[Pending], b: usize) -> Option<usize> {
        bodies[b].joint
    }
    let mut joint_body = vec![None; robot.joints.len()];
    let mut body_parent = Vec::with_capacity(bodies.len());
    for (b, p) in bodies.iter().enumerate() {
        if let Some(j) = p.joint {
            joint_body[j] = Some(b);
        }
        body_parent.push(p.parent);
    }
    let link_frames: Vec<(Option<usize>, Transform<f64>)> =
        link_body.iter().map(|x| x.expect("reachable")).collect();
    add_constraints(robot, &link_frames, &joint_body, &body_parent, &mut builder)?;
    builder
        .build()
        .map_err(|e| model_build_error(robot, e, f64::NAME))
}

/// A [`ModelError`] of building or converting the model, located at the element it names.
fn model_build_error(robot: &Robot, e: ModelError, scalar: &'static str) -> LoadError {
    let joint_named = |name: &str| robot.joints.iter().position(|j| j.name == name);
    let joint = match &e {
        ModelError::LoopNeverCloses { group, .. }
        | ModelError::DependentMismatch { group, .. }
        | ModelError::SingularDependentChoice { group, .. } => {
            return LoadError::at(group_location(robot, group), e.into());
        }
        ModelError::EmptyConstraint { constraint } => {
            return LoadError::at(constraint_location(robot, constraint), e.into());
        }
        ModelError::ConstantDoesNotFit { element, .. } => {
            let location = match element {
                ModelElement::Body(link) => link_location(robot, link),
                ModelElement::Joint(name) => joint_location(robot, joint_named(name)),
                ModelElement::Constraint(name) => constraint_location(robot, name),
                ModelElement::Gravity => Location::new(&robot.source, None, "gravity"),
            };
            return LoadError::at(location, e.into());
        }
        ModelError::InertiaOverflow { body, .. } => {
            return LoadError::at(link_location(robot, body), e.into());
        }
        ModelError::NoInertiaAboutAxis { joint, .. }
        | ModelError::FloatingInGroup { joint }
        | ModelError::BadAxis { joint }
        | ModelError::FloatingNotRoot { joint }
        | ModelError::BadArmature { joint, .. }
        | ModelError::BadLimit { joint, .. }
        | ModelError::ParentNotYetAdded { joint, .. } => joint_named(joint),
        ModelError::UnknownBody { .. } => None,
    };
    let kind = match e {
        // The runtime's message speaks of bodies; the file's reader knows links and what to change.
        ModelError::NoInertiaAboutAxis { d, .. } => {
            LoadErrorKind::UndeterminedAcceleration { d, scalar }
        }
        other => other.into(),
    };
    LoadError::at(joint_location(robot, joint), kind)
}

/// Where link `name` is written.
fn link_location(robot: &Robot, name: &str) -> Location {
    let line = robot
        .links
        .iter()
        .find(|l| l.name == name)
        .and_then(|l| l.line);
    Location::new(&robot.source, line, format!("link \"{name}\""))
}

/// Where a group is written: at its first constraint.
fn group_location(robot: &Robot, group: &GroupLabel) -> Location {
    match group.constraints.first() {
        Some(first) => constraint_location(robot, first),
        None => Location::new(&robot.source, None, format!("constraints {group}")),
    }
}

/// Where the constraint `name` is written.
fn constraint_location(robot: &Robot, name: &str) -> Location {
    if let Some(l) = robot.loops.iter().find(|l| l.name == name) {
        return Location::new(&robot.source, l.line, format!("loop \"{}\"", l.name));
    }
    if let Some(c) = robot.couplings.iter().find(|c| c.name == name) {
        return Location::new(&robot.source, c.line, format!("coupling \"{}\"", c.name));
    }
    if let Some(j) = robot.joints.iter().find(|j| j.name == name) {
        return Location::new(
            &robot.source,
            j.line,
            format!("joint \"{}\" <mimic>", j.name),
        );
    }
    Location::new(&robot.source, None, format!("constraints {name}"))
}

/// URDF+ loops and couplings and URDF mimic joints, as runtime constraints (docs/model-format.md).
fn add_constraints(
    robot: &Robot,
    link_frames: &[(Option<usize>, Transform<f64>)],
    joint_body: &[Option<usize>],
    body_parent: &[Option<usize>],
    builder: &mut embedyn_runtime::ModelBuilder<f64>,
) -> Result<(), LoadError> {
    use embedyn_runtime::constraints::{Constraint, ConstraintKind, LoopClosure, LoopType};
    use embedyn_runtime::tree;
    let path_of = &robot.source;
    for l in &robot.loops {
        let (pb, ppose) = link_frames[l.predecessor.link];
        let (sb, spose) = link_frames[l.successor.link];
        if pb == sb {
            return Err(LoadError::at(
                Location::new(path_of, l.line, format!("loop \"{}\"", l.name)),
                LoadErrorKind::LoopWithinOneBody,
            ));
        }
        let kind = match l.kind {
            LoopKind::Revolute => LoopType::Revolute,
            LoopKind::Prismatic => LoopType::Prismatic,
            LoopKind::Spherical => LoopType::Spherical,
            LoopKind::Fixed => LoopType::Fixed,
        };
        let axis = Vector3::new(l.axis[0], l.axis[1], l.axis[2]);
        let closure = LoopClosure::new(
            kind,
            pb,
            ppose.compose(&origin_transform(&l.predecessor.origin)),
            sb,
            spose.compose(&origin_transform(&l.successor.origin)),
            axis,
        );
        builder.add_constraint(Constraint {
            name: l.name.clone(),
            kind: ConstraintKind::Loop(closure),
        });
    }
    for c in &robot.couplings {
        let pb = link_frames[c.predecessor].0;
        let sb = link_frames[c.successor].0;
        let parent = |body: usize| body_parent[body];
        let top = tree::common_ancestor(parent, pb, sb);
        let mut predecessor_path = Vec::new();
        tree::path_to_ancestor(parent, pb, top, &mut predecessor_path);
        let mut successor_path = Vec::new();
        tree::path_to_ancestor(parent, sb, top, &mut successor_path);
        let mut terms: Vec<(usize, f64)> = Vec::new();
        for b in predecessor_path {
            terms.push((b, c.ratio));
        }
        for b in successor_path {
            terms.push((b, -1.0));
        }
        if terms.is_empty() {
            return Err(LoadError::at(
                Location::new(path_of, c.line, format!("coupling \"{}\"", c.name)),
                LoadErrorKind::CouplingRelatesNothing,
            ));
        }
        builder.add_constraint(Constraint {
            name: c.name.clone(),
            kind: ConstraintKind::Linear { terms, offset: 0.0 },
        });
    }
    for (j, joint) in robot.joints.iter().enumerate() {
        if joint.mimics.is_empty() {
            continue;
        }
        let loc = |line| Location::new(path_of, line, format!("joint \"{}\" <mimic>", joint.name));
        let Some(body) = joint_body[j] else {
            return Err(LoadError::at(
                loc(joint.line),
                LoadErrorKind::FixedJointMimics,
            ));
        };
        let mut terms = vec![(body, 1.0)];
        let mut offset = 0.0;
        for m in &joint.mimics {
            let driver = robot
                .joints
                .iter()
                .position(|d| d.name == m.joint)
                .expect("checked at parse time");
            let Some(db) = joint_body[driver] else {
                return Err(LoadError::at(
                    loc(m.line),
                    LoadErrorKind::FixedDriver {
                        joint: m.joint.clone(),
                    },
                ));
            };
            if db == body {
                return Err(LoadError::at(loc(m.line), LoadErrorKind::MimicSelf));
            }
            terms.push((db, -m.multiplier));
            offset -= m.offset;
        }
        builder.add_constraint(Constraint {
            name: joint.name.clone(),
            kind: ConstraintKind::Linear { terms, offset },
        });
        builder.declare_dependent(body);
    }
    for (j, joint) in robot.joints.iter().enumerate() {
        if joint.independent == Some(false) {
            if let Some(b) = joint_body[j] {
                builder.declare_dependent(b);
            }
        }
    }
    Ok(())
}

fn joint_location(robot: &Robot, joint: Option<usize>) -> Location {
    match joint {
        Some(j) => {
            let joint = &robot.joints[j];
            Location::new(
                &robot.source,
                joint.line,
                format!("joint \"{}\"", joint.name),
            )
        }
        None => Location::new(&robot.source, None, format!("joint \"{ROOT_JOINT}\"")),
    }
}

/// `|v|` without overflow in its squares (a centre of mass 1e200 m away is 1e200 m, not infinite).
fn scaled_norm(v: &Vector3<f64>) -> f64 {
    let scale = v.amax();
    if scale > 0.0 && scale.is_finite() {
        scale * (v / scale).norm()
    } else {
        scale
    }
}

#[cfg(test)]
mod kind_tests {
    use super::*;
    use crate::{generate_tokens, load, Algorithm, GenerateOptions, LoadErrorKind};
    use std::path::PathBuf;

    fn fixture(name: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../tests/data")
            .join(name)
    }

    fn model_error(name: &str, options: &ModelOptions) -> LoadError {
        let loaded = load(&fixture(name)).unwrap();
        build_model::<f64>(&loaded.robot, options).unwrap_err()
    }

    #[test]
    fn model_errors_carry_their_kind() {
        let e = model_error("bad/floating_not_root.urdf", &ModelOptions::default());
        assert_eq!(e.kind, LoadErrorKind::FloatingNotAtRoot);
        assert_eq!(e.location.element, "joint \"joint2\"");

        // The runtime's error itself, not its text, and the source of the LoadError.
        let e = model_error("bad/loop_never_meets.urdf", &ModelOptions::default());
        match &e.kind {
            LoadErrorKind::Model(ModelError::LoopNeverCloses { group, gap }) => {
                assert_eq!(group.constraints, ["loop1"]);
                assert!(*gap > 1.0, "{gap}");
            }
            other => panic!("{other:?}"),
        }
        let source = std::error::Error::source(&e).expect("the runtime's error is the source");
        assert!(source.to_string().contains("never meet"), "{source}");

        let e = model_error("bad/massless_leaf.urdf", &ModelOptions::default());
        assert!(
            matches!(
                e.kind,
                LoadErrorKind::UndeterminedAcceleration { d, scalar: "f64" } if d == 0.0
            ),
            "{e:?}"
        );
    }

    #[test]
    fn generation_errors_carry_their_kind() {
        let loaded = load(&fixture("unit_slider.urdf")).unwrap();
        let options =
            GenerateOptions::default().with_requested(Some(vec![Algorithm::Complete]), &[]);
        let e = generate_tokens(&loaded, &options).unwrap_err();
        assert_eq!(
            e.kind,
            LoadErrorKind::NeedsConstraints {
                function: Algorithm::Complete
            }
        );
        assert!(e.to_string().ends_with(
            "`complete` exists only for a model with loops, couplings or mimic joints; this one is a tree"
        ));
    }
}

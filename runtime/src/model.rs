//! The kinematic tree the algorithms run on.
//!
//! Bodies are numbered so that a parent precedes its children and every subtree occupies a contiguous
//! range of indices (depth-first order). Body `i` is moved by joint `i`. A URDF's fixed joints are already
//! merged away: every joint here moves. Coordinates follow docs/conventions.md.
//!
//! Design note: the algorithms walk the tree node by node, and each step touches only the node's parent.
//! Constraint embedding replaces a group of bodies by one *aggregate link* with a configuration-dependent
//! joint map; that enters as a new node kind with its own forward and backward step, not as a change to
//! the recursions.

#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::constraints::{Constraint, ConstraintKind, Group, GroupLabel};
use crate::spatial::{Motion, SpatialInertia, Transform};
use crate::Real;
use nalgebra::Vector3;

/// The kind of a moving joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JointType {
    /// One angle about `axis` (rad).
    Revolute,
    /// A revolute joint without limits; still one plain angle.
    Continuous,
    /// One displacement along `axis` (m).
    Prismatic,
    /// Six DoF: `q = [x y z qx qy qz qw]`, `v = [v_lin; ω]` in the body frame (Pinocchio's free-flyer).
    Floating,
}

impl JointType {
    /// Length of this joint's part of `q` (7 for floating: position and unit quaternion, else 1).
    pub fn nq(self) -> usize {
        match self {
            JointType::Floating => 7,
            _ => 1,
        }
    }
    /// Length of this joint's part of `v` (6 for floating, else 1).
    pub fn nv(self) -> usize {
        match self {
            JointType::Floating => 6,
            _ => 1,
        }
    }
    /// The name used in the CLI's JSON (`"revolute"`, `"continuous"`, `"prismatic"`, `"floating"`).
    pub fn as_str(self) -> &'static str {
        match self {
            JointType::Revolute => "revolute",
            JointType::Continuous => "continuous",
            JointType::Prismatic => "prismatic",
            JointType::Floating => "floating",
        }
    }
}

/// A joint's limits, as URDF's `<limit lower upper velocity effort>` gives them (Pinocchio's
/// `lowerPositionLimit`, `upperPositionLimit`, `velocityLimit`, `effortLimit`): `None` where the model
/// gives none. Position limits are in rad or m (revolute and prismatic joints only: a continuous or
/// floating joint has none); velocity (rad/s or m/s) and effort (N·m or N) are magnitudes, ≥ 0. The
/// solver does not enforce them: they are carried for reports and generated constants.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointLimits<T> {
    /// Lowest coordinate.
    pub lower: Option<T>,
    /// Highest coordinate.
    pub upper: Option<T>,
    /// Largest speed.
    pub velocity: Option<T>,
    /// Largest force or torque.
    pub effort: Option<T>,
}

impl<T: Copy> JointLimits<T> {
    /// No limits at all.
    pub fn none() -> Self {
        JointLimits {
            lower: None,
            upper: None,
            velocity: None,
            effort: None,
        }
    }

    /// The same limits with each value converted by `f`.
    pub fn map<U>(&self, mut f: impl FnMut(T) -> U) -> JointLimits<U> {
        JointLimits {
            lower: self.lower.map(&mut f),
            upper: self.upper.map(&mut f),
            velocity: self.velocity.map(&mut f),
            effort: self.effort.map(&mut f),
        }
    }
}

/// A moving joint: connects body `parent` (or the world) to the body of the same index.
#[derive(Clone, Debug)]
pub struct Joint<T: Real> {
    /// The joint's name, as in the model file.
    pub name: String,
    /// What the joint lets move.
    pub joint_type: JointType,
    /// Unit axis in the joint frame (unused by floating joints).
    pub axis: Vector3<T>,
    /// Parent body, `None` for a joint attached to the world.
    pub parent: Option<usize>,
    /// Pose of the joint frame in the parent body frame; at zero displacement the child body frame is
    /// the joint frame.
    pub placement: Transform<T>,
    /// Index of this joint's first coordinate in `q`.
    pub q_index: usize,
    /// Index of this joint's first entry in `v`, `tau` and `qdd`.
    pub v_index: usize,
    /// Armature (kg·m² for a revolute joint, kg for a prismatic one): inertia felt only along the joint's
    /// own coordinates, added to each of its diagonal entries of `M(q)` — a geared motor's rotor inertia
    /// times the gear ratio squared, as Pinocchio's `model.armature`. Zero by default; finite and ≥ 0
    /// ([`ModelBuilder::set_armature`] checks it).
    pub armature: T,
    /// Position, velocity and effort limits (see [`JointLimits`]); none by default
    /// ([`ModelBuilder::set_limits`] sets and checks them).
    pub limits: JointLimits<T>,
}

impl<T: Real> Joint<T> {
    /// Whether the joint has armature, known when the model is built (a constant in traced code too):
    /// where it has none, the algorithms take the steps of a plain joint and generated code is unchanged.
    #[inline(always)]
    pub fn has_armature(&self) -> bool {
        self.armature.value().is_none_or(|a| a != 0.0)
    }

    /// Length of this joint's part of `q`.
    pub fn nq(&self) -> usize {
        self.joint_type.nq()
    }
    /// Length of this joint's part of `v`.
    pub fn nv(&self) -> usize {
        self.joint_type.nv()
    }
    /// This joint's indices in `v`: `v_index..v_index + nv`.
    pub fn v_range(&self) -> core::ops::Range<usize> {
        self.v_index..self.v_index + self.nv()
    }

    /// `X_J(q)`: the pose of the child body frame in the joint frame.
    #[inline(always)]
    pub fn joint_transform(&self, q: &[T]) -> Transform<T> {
        match self.joint_type {
            JointType::Revolute | JointType::Continuous => {
                Transform::rotation_about(&self.axis, q[self.q_index])
            }
            JointType::Prismatic => Transform::translation_along(&self.axis, q[self.q_index]),
            JointType::Floating => {
                let s = &q[self.q_index..self.q_index + 7];
                Transform::new(
                    quaternion_to_rotation([s[3], s[4], s[5], s[6]]),
                    Vector3::new(s[0], s[1], s[2]),
                )
            }
        }
    }

    /// `S q̇`: the joint's relative velocity in the child body frame.
    #[inline(always)]
    pub fn joint_motion(&self, v: &[T]) -> Motion<T> {
        let i = self.v_index;
        match self.joint_type {
            JointType::Revolute | JointType::Continuous => {
                Motion::new(self.axis * v[i], Vector3::zeros())
            }
            JointType::Prismatic => Motion::new(Vector3::zeros(), self.axis * v[i]),
            JointType::Floating => Motion::new(
                Vector3::new(v[i + 3], v[i + 4], v[i + 5]),
                Vector3::new(v[i], v[i + 1], v[i + 2]),
            ),
        }
    }

    /// For a 1-DoF joint whose axis is ±x, ±y or ±z exactly: (whether it is angular, the axis index).
    pub fn coordinate_axis(&self) -> Option<(bool, usize)> {
        let angular = match self.joint_type {
            JointType::Revolute | JointType::Continuous => true,
            JointType::Prismatic => false,
            JointType::Floating => return None,
        };
        let (o, z) = (T::one(), T::zero());
        let a = &self.axis;
        (0..3)
            .find(|&k| (a[k] == o || a[k] == -o) && (0..3).all(|m| m == k || a[m] == z))
            .map(|k| (angular, k))
    }

    /// Column `k` of the motion subspace `S` (the paper's `H*(k)`), in the child body frame.
    #[inline(always)]
    pub fn subspace_column(&self, k: usize) -> Motion<T> {
        match self.joint_type {
            JointType::Revolute | JointType::Continuous => Motion::new(self.axis, Vector3::zeros()),
            JointType::Prismatic => Motion::new(Vector3::zeros(), self.axis),
            JointType::Floating => {
                let mut m = [T::zero(); 6];
                // v = [v_lin; ω] while motions are [ω; v_lin].
                m[(k + 3) % 6] = T::one();
                Motion::from_array(m)
            }
        }
    }
}

/// A rigid body: one moving joint's child link with every link fixed to it merged in.
#[derive(Clone, Debug)]
pub struct Body<T: Real> {
    /// Name of the URDF link that carries the body frame.
    pub name: String,
    /// Inertia about the body frame, fixed-joint children included.
    pub inertia: SpatialInertia<T>,
    /// Names of the URDF links merged into this body (the first is `name`).
    pub links: Vec<String>,
    /// Pose of each of `links` in the body frame (the first, the body's own link, is the identity).
    pub link_placements: Vec<Transform<T>>,
}

/// A kinematic tree ready for the algorithms. Build it with [`Model::builder`].
#[derive(Clone, Debug)]
pub struct Model<T: Real> {
    /// The robot's name (URDF `<robot name>`).
    pub name: String,
    /// The joints, one per body: `joints[i]` moves `bodies[i]`; parents come before children.
    pub joints: Vec<Joint<T>>,
    /// The bodies, in depth-first order (each subtree is a contiguous range).
    pub bodies: Vec<Body<T>>,
    /// Gravity in the world frame, (0, 0, −9.81) m/s² by default.
    pub gravity: Vector3<T>,
    nq: usize,
    nv: usize,
    /// `subtree_end[i]`: one past the last body of the subtree rooted at body `i`.
    subtree_end: Vec<usize>,
    /// Loops, couplings and mimic joints, in the order they were added.
    pub constraints: Vec<Constraint<T>>,
    /// The aggregate links (empty for a tree).
    pub groups: Vec<Group>,
    /// For each body, the group it belongs to.
    group_of: Vec<Option<usize>>,
    /// The URDF links fixed to the world (not on any moving body): frames whose pose never changes.
    pub world_links: Vec<String>,
    /// Pose of each of `world_links` in the world.
    pub world_link_placements: Vec<Transform<T>>,
}

/// A frame of the model: a URDF link, on a moving body or fixed to the world (docs/conventions.md: a frame's
/// placement is its link frame). Find one by name with [`Model::frame`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FrameId {
    /// The body the link rides on (`None`: fixed to the world).
    pub body: Option<usize>,
    /// The link's index in that body's [`Body::links`] (or in [`Model::world_links`]).
    pub link: usize,
}

/// Errors in the structure of a model given to [`ModelBuilder`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A joint names a parent body that was not added before it.
    #[error("joint `{joint}`: parent body {parent} must be added before its children")]
    ParentNotYetAdded {
        /// The joint.
        joint: String,
        /// The parent body's index.
        parent: usize,
    },
    /// A joint's axis is zero or not finite.
    #[error("joint `{joint}`: the axis must be a non-zero finite vector")]
    BadAxis {
        /// The joint.
        joint: String,
    },
    /// [`ModelBuilder::set_armature`] names a body that was not added.
    #[error("body {body} was not added, so its joint has no armature to set")]
    UnknownBody {
        /// The body's index.
        body: usize,
    },
    /// A joint's armature is negative or not finite.
    #[error("joint `{joint}`: armature {armature:e} must be a finite number ≥ 0")]
    BadArmature {
        /// The joint.
        joint: String,
        /// The armature given.
        armature: f64,
    },
    /// A joint's limit is not finite, a velocity or effort limit is negative, its lower position limit
    /// is above its upper one, or it has position limits without being revolute or prismatic.
    #[error("joint `{joint}`: {limit} limit {value:e} {problem}")]
    BadLimit {
        /// The joint.
        joint: String,
        /// Which limit: `lower`, `upper`, `velocity` or `effort`.
        limit: &'static str,
        /// Its value.
        value: f64,
        /// What is wrong with it.
        problem: &'static str,
    },
    /// A floating joint has a parent body.
    #[error("joint `{joint}`: a floating joint must connect a body to the world")]
    FloatingNotRoot {
        /// The joint.
        joint: String,
    },
    /// A joint's subtree has no inertia about its axis, so the mass matrix is singular.
    #[error("joint `{joint}`: the bodies of the subtree it moves have no inertia about its axis (D = {d:e}), so its acceleration is undetermined")]
    NoInertiaAboutAxis {
        /// The joint.
        joint: String,
        /// The articulated inertia about its axis.
        d: f64,
    },
    /// A loop's frames cannot be brought together by any configuration.
    #[error("{group}: the loop's two frames never meet: no configuration closes it (smallest residual found {gap:.3e}; check the <origin> of its predecessor and successor)")]
    LoopNeverCloses {
        /// The group, by the names of its constraints.
        group: GroupLabel,
        /// The smallest residual found.
        gap: f64,
    },
    /// A constraint involves no moving joint.
    #[error("constraint `{constraint}` involves no moving joint")]
    EmptyConstraint {
        /// The constraint's name.
        constraint: String,
    },
    /// A floating joint is part of a loop or coupling.
    #[error("joint `{joint}`: a floating joint cannot be part of a loop or coupling")]
    FloatingInGroup {
        /// The joint.
        joint: String,
    },
    /// A group declares a different number of dependent joints than its constraints remove.
    #[error("{group}: {declared} joint(s) are declared dependent (independent=\"false\" or <mimic>), but the constraints remove {needed} degree(s) of freedom")]
    DependentMismatch {
        /// The group, by the names of its constraints.
        group: GroupLabel,
        /// How many joints the file declares dependent.
        declared: usize,
        /// How many degrees of freedom the constraints remove.
        needed: usize,
    },
    /// The declared dependent joints cannot be solved from the independent ones.
    #[error("{group}: the dependent joints cannot be solved from the independent ones (cond(Y1) = {condition:e} at a generic assembled configuration); declare other joints independent=\"false\"")]
    SingularDependentChoice {
        /// The group, by the names of its constraints.
        group: GroupLabel,
        /// The condition number of the dependent part of the constraint Jacobian.
        condition: f64,
    },
    /// A model constant does not fit the scalar type.
    #[error("{element}: its {what} {value:e} {}", fit_problem(.too_large, .value, .scalar))]
    ConstantDoesNotFit {
        /// What the constant belongs to.
        element: ModelElement,
        /// Which constant it is (`"mass"`, …).
        what: &'static str,
        /// Its value (f64).
        value: f64,
        /// The scalar type's name (`"f32"`).
        scalar: &'static str,
        /// Whether it is too large (else: too small to keep its precision).
        too_large: bool,
    },
    /// Combining the inertias of a joint's subtree overflows the scalar type.
    #[error("joint `{joint}`: the inertias of the bodies it moves overflow when the dynamics combines them (the largest is body `{body}`'s, {magnitude:e}); the model's numbers are too large for this scalar type")]
    InertiaOverflow {
        /// The joint whose subtree overflows.
        joint: String,
        /// The body with the largest inertia.
        body: String,
        /// The magnitude of that inertia.
        magnitude: f64,
    },
}

fn fit_problem(too_large: &bool, value: &f64, scalar: &str) -> String {
    if !value.is_finite() {
        "is not a finite number".to_string()
    } else if *too_large {
        format!("is too large for {scalar}: a constant that does not fit the scalar type would make another model")
    } else {
        format!("is too small for {scalar} to keep its precision (it would become zero or subnormal), yet it matters at the model's scale")
    }
}

/// What a model constant belongs to, for messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ModelElement {
    /// A body, or one of the links merged into it, by link name.
    Body(String),
    /// A joint, by name.
    Joint(String),
    /// A loop, coupling or mimic relation, by name.
    Constraint(String),
    /// The gravity vector.
    Gravity,
}

impl core::fmt::Display for ModelElement {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ModelElement::Body(n) => write!(f, "body `{n}`"),
            ModelElement::Joint(n) => write!(f, "joint `{n}`"),
            ModelElement::Constraint(n) => write!(f, "constraint `{n}`"),
            ModelElement::Gravity => write!(f, "gravity"),
        }
    }
}

/// Adds bodies one at a time, each after its parent; [`ModelBuilder::build`] renumbers them depth-first.
#[derive(Clone, Debug)]
pub struct ModelBuilder<T: Real> {
    name: String,
    joints: Vec<Joint<T>>,
    bodies: Vec<Body<T>>,
    gravity: Vector3<T>,
    nq: usize,
    nv: usize,
    constraints: Vec<Constraint<T>>,
    declared_dependent: Vec<bool>,
    world_links: Vec<String>,
    world_link_placements: Vec<Transform<T>>,
}

impl<T: Real> Model<T> {
    /// Starts a model named `name` with gravity (0, 0, −9.81) m/s²; add bodies, then [`ModelBuilder::build`].
    pub fn builder(name: impl Into<String>) -> ModelBuilder<T> {
        ModelBuilder {
            name: name.into(),
            joints: Vec::new(),
            bodies: Vec::new(),
            gravity: Vector3::new(T::zero(), T::zero(), T::from_f64(-9.81)),
            nq: 0,
            nv: 0,
            constraints: Vec::new(),
            declared_dependent: Vec::new(),
            world_links: Vec::new(),
            world_link_placements: Vec::new(),
        }
    }

    /// Length of `q`.
    pub fn nq(&self) -> usize {
        self.nq
    }
    /// Length of `v`, `tau` and `qdd`.
    pub fn nv(&self) -> usize {
        self.nv
    }
    /// Number of bodies (= number of joints).
    pub fn nbodies(&self) -> usize {
        self.bodies.len()
    }
    /// One past the last body of the subtree of body `i` (subtrees are contiguous).
    pub fn subtree_end(&self, i: usize) -> usize {
        self.subtree_end[i]
    }
    /// The bodies body `i` hangs from, its parent first, up to its root (`i` itself not included).
    pub fn ancestors(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        core::iter::successors(self.joints[i].parent, move |&j| self.joints[j].parent)
    }
    /// Velocity indices `[v_index(i), end)` of the subtree rooted at body `i`.
    pub fn subtree_v_range(&self, i: usize) -> core::ops::Range<usize> {
        let start = self.joints[i].v_index;
        let end = self
            .joints
            .get(self.subtree_end[i])
            .map_or(self.nv, |j| j.v_index);
        start..end
    }

    /// The frame of the link named `name` (on a moving body or fixed to the world).
    pub fn frame(&self, name: &str) -> Option<FrameId> {
        for (b, body) in self.bodies.iter().enumerate() {
            if let Some(link) = body.links.iter().position(|l| l == name) {
                return Some(FrameId {
                    body: Some(b),
                    link,
                });
            }
        }
        self.world_links
            .iter()
            .position(|l| l == name)
            .map(|link| FrameId { body: None, link })
    }

    /// The link name of a frame; `None` if `frame` is not one of this model's.
    pub fn frame_name(&self, frame: FrameId) -> Option<&str> {
        match frame.body {
            Some(b) => self.bodies.get(b)?.links.get(frame.link),
            None => self.world_links.get(frame.link),
        }
        .map(String::as_str)
    }

    /// The pose of a frame in its body's frame (in the world for a link fixed to the world); `None` if
    /// `frame` is not one of this model's.
    pub fn frame_in_body(&self, frame: FrameId) -> Option<&Transform<T>> {
        match frame.body {
            Some(b) => self.bodies.get(b)?.link_placements.get(frame.link),
            None => self.world_link_placements.get(frame.link),
        }
    }

    /// Every frame: each body's links in body order, then the links fixed to the world.
    pub fn frames(&self) -> impl Iterator<Item = FrameId> + '_ {
        self.bodies
            .iter()
            .enumerate()
            .flat_map(|(b, body)| {
                (0..body.links.len()).map(move |link| FrameId {
                    body: Some(b),
                    link,
                })
            })
            .chain((0..self.world_links.len()).map(|link| FrameId { body: None, link }))
    }

    /// Index of the joint (and of its body) named `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// The neutral configuration: zero angles and displacements, identity quaternions.
    pub fn neutral_configuration(&self) -> Vec<T> {
        let mut q = vec![T::zero(); self.nq];
        for j in &self.joints {
            if j.joint_type == JointType::Floating {
                q[j.q_index + 6] = T::one();
            }
        }
        q
    }

    /// `q̇` from `v` (the floating base's quaternion and position rates), for integrating in time.
    ///
    /// # Panics
    /// If `q` or `qdot` is shorter than [`Model::nq`] or `v` than [`Model::nv`] (it checks nothing else:
    /// non-finite entries give non-finite rates).
    pub fn configuration_rate(&self, q: &[T], v: &[T], qdot: &mut [T]) {
        let half = T::from_f64(0.5);
        for j in &self.joints {
            let (iq, iv) = (j.q_index, j.v_index);
            match j.joint_type {
                JointType::Floating => {
                    let x = j.joint_transform(q);
                    let pdot = x.rotation * Vector3::new(v[iv], v[iv + 1], v[iv + 2]);
                    // d/dt quat = ½ quat ⊗ (ω, 0), ω in the body frame.
                    let (x, y, z, w) = (q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6]);
                    let (wx, wy, wz) = (v[iv + 3], v[iv + 4], v[iv + 5]);
                    qdot[iq] = pdot.x;
                    qdot[iq + 1] = pdot.y;
                    qdot[iq + 2] = pdot.z;
                    qdot[iq + 3] = (w * wx + y * wz - z * wy) * half;
                    qdot[iq + 4] = (w * wy + z * wx - x * wz) * half;
                    qdot[iq + 5] = (w * wz + x * wy - y * wx) * half;
                    qdot[iq + 6] = -(x * wx + y * wy + z * wz) * half;
                }
                _ => qdot[iq] = v[iv],
            }
        }
    }

    /// Rescales every floating joint's quaternion to unit length.
    ///
    /// # Panics
    /// If `q` is shorter than [`Model::nq`]. (A zero quaternion becomes NaN: [`crate::aba`] and the other
    /// algorithms refuse it.)
    pub fn normalize_configuration(&self, q: &mut [T]) {
        for j in &self.joints {
            if j.joint_type == JointType::Floating {
                let s = &mut q[j.q_index + 3..j.q_index + 7];
                let n = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + s[3] * s[3]).sqrt();
                for x in s.iter_mut() {
                    *x /= n;
                }
            }
        }
    }

    /// Converts the model to another scalar type (rounding every constant once).
    pub fn cast<U: Real>(&self) -> Model<U> {
        let c = |x: T| U::from_f64(x.to_f64());
        Model {
            name: self.name.clone(),
            joints: self
                .joints
                .iter()
                .map(|j| Joint {
                    name: j.name.clone(),
                    joint_type: j.joint_type,
                    axis: j.axis.map(c),
                    parent: j.parent,
                    placement: j.placement.cast(),
                    q_index: j.q_index,
                    v_index: j.v_index,
                    armature: c(j.armature),
                    limits: j.limits.map(c),
                })
                .collect(),
            bodies: self
                .bodies
                .iter()
                .map(|b| Body {
                    name: b.name.clone(),
                    inertia: b.inertia.cast(),
                    links: b.links.clone(),
                    link_placements: b.link_placements.iter().map(|x| x.cast()).collect(),
                })
                .collect(),
            gravity: self.gravity.map(c),
            nq: self.nq,
            nv: self.nv,
            subtree_end: self.subtree_end.clone(),
            constraints: self.constraints.iter().map(|c| c.cast()).collect(),
            groups: self.groups.clone(),
            group_of: self.group_of.clone(),
            world_links: self.world_links.clone(),
            world_link_placements: self
                .world_link_placements
                .iter()
                .map(|x| x.cast())
                .collect(),
        }
    }

    /// Converts the model to another scalar type, keeping its structure (the groups, the redundant
    /// equations and the independent coordinates decided when it was built), after checking that every
    /// constant fits `U` and that `U` still determines every joint's acceleration (the articulated-inertia
    /// check of [`ModelBuilder::build`], in `U`'s precision). Build in f64 and convert, so that every scalar
    /// type gets the structure decided once, in f64.
    pub fn try_cast<U: Real>(&self) -> Result<Model<U>, ModelError> {
        crate::check::check_constants_fit::<T, U>(self)?;
        let model = self.cast::<U>();
        crate::check::check_converted(&model)?;
        Ok(model)
    }

    /// Whether the model has loops, couplings or mimic joints.
    pub fn has_constraints(&self) -> bool {
        !self.constraints.is_empty()
    }

    /// The group (aggregate link) body `b` belongs to.
    pub fn group_of(&self, b: usize) -> Option<usize> {
        self.group_of[b]
    }

    /// Total number of constraint equations before redundant ones are removed.
    pub fn constraint_raw_rows(&self) -> usize {
        self.constraints.iter().map(|c| c.raw_rows()).sum()
    }

    /// First raw row of each constraint.
    pub fn constraint_row_offsets(&self) -> Vec<usize> {
        let mut off = Vec::with_capacity(self.constraints.len());
        let mut row = 0;
        for c in &self.constraints {
            off.push(row);
            row += c.raw_rows();
        }
        off
    }

    /// Whether the coordinate of joint `j` is independent (joints outside every group are).
    pub fn is_independent(&self, j: usize) -> bool {
        match self.group_of[j] {
            None => true,
            Some(g) => !self.groups[g].dependent.contains(&j),
        }
    }

    /// The independent joints in joint order (the order of `qdd_independent` and of the reduced `M`).
    pub fn independent_joints(&self) -> Vec<usize> {
        (0..self.joints.len())
            .filter(|&j| self.is_independent(j))
            .collect()
    }

    /// The `v` indices of the independent coordinates, in joint order (`v_independent[k] =
    /// v[independent_coordinates()[k]]` for a `v` on the velocity constraints). Never allocates.
    pub fn independent_coordinates(&self) -> impl Iterator<Item = usize> + '_ {
        self.joints
            .iter()
            .enumerate()
            .filter(|&(j, _)| self.is_independent(j))
            .flat_map(|(_, joint)| joint.v_range())
    }

    /// Number of independent velocity coordinates.
    pub fn independent_nv(&self) -> usize {
        (0..self.joints.len())
            .filter(|&j| self.is_independent(j))
            .map(|j| self.joints[j].nv())
            .sum()
    }
}

impl<T: Real> ModelBuilder<T> {
    /// Sets gravity in the world frame (m/s²).
    pub fn gravity(mut self, g: Vector3<T>) -> Self {
        self.gravity = g;
        self
    }

    /// Adds a body moved by a joint. `placement` is the joint frame in the parent body frame, `inertia`
    /// the body's inertia about its own frame. Returns the index to name this body as a parent in later
    /// calls (the built model numbers bodies depth-first, which may differ).
    #[allow(clippy::too_many_arguments)]
    pub fn add_body(
        &mut self,
        parent: Option<usize>,
        joint_name: impl Into<String>,
        joint_type: JointType,
        axis: Vector3<T>,
        placement: Transform<T>,
        body_name: impl Into<String>,
        inertia: SpatialInertia<T>,
    ) -> Result<usize, ModelError> {
        let joint_name = joint_name.into();
        if let Some(p) = parent {
            if p >= self.bodies.len() {
                return Err(ModelError::ParentNotYetAdded {
                    joint: joint_name,
                    parent: p,
                });
            }
        }
        let axis = match joint_type {
            JointType::Floating => {
                if parent.is_some() {
                    return Err(ModelError::FloatingNotRoot { joint: joint_name });
                }
                Vector3::zeros()
            }
            _ => match crate::spatial::unit_vector(&axis) {
                Some(unit) => unit,
                None => return Err(ModelError::BadAxis { joint: joint_name }),
            },
        };
        let body_name = body_name.into();
        self.joints.push(Joint {
            name: joint_name,
            joint_type,
            axis,
            parent,
            placement,
            q_index: self.nq,
            v_index: self.nv,
            armature: T::zero(),
            limits: JointLimits::none(),
        });
        self.nq += joint_type.nq();
        self.nv += joint_type.nv();
        self.bodies.push(Body {
            links: vec![body_name.clone()],
            link_placements: vec![Transform::identity()],
            name: body_name,
            inertia,
        });
        Ok(self.bodies.len() - 1)
    }

    /// Sets the armature of body `body`'s joint (see [`Joint::armature`]): finite and not negative.
    pub fn set_armature(&mut self, body: usize, armature: T) -> Result<(), ModelError> {
        let Some(joint) = self.joints.get_mut(body) else {
            return Err(ModelError::UnknownBody { body });
        };
        let a = armature.to_f64();
        if !(a.is_finite() && a >= 0.0) {
            return Err(ModelError::BadArmature {
                joint: joint.name.clone(),
                armature: a,
            });
        }
        joint.armature = armature;
        Ok(())
    }

    /// Sets the limits of body `body`'s joint (see [`JointLimits`]): every value finite, velocity and effort
    /// ≥ 0, lower ≤ upper, and position limits only on a revolute or prismatic joint.
    pub fn set_limits(&mut self, body: usize, limits: JointLimits<T>) -> Result<(), ModelError> {
        let Some(joint) = self.joints.get_mut(body) else {
            return Err(ModelError::UnknownBody { body });
        };
        let bad = |limit, value: f64, problem| ModelError::BadLimit {
            joint: joint.name.clone(),
            limit,
            value,
            problem,
        };
        let f = limits.map(|x| x.to_f64());
        for (limit, value) in [
            ("lower", f.lower),
            ("upper", f.upper),
            ("velocity", f.velocity),
            ("effort", f.effort),
        ] {
            let Some(x) = value else { continue };
            if !x.is_finite() {
                return Err(bad(limit, x, "is not a finite number"));
            }
            if matches!(limit, "velocity" | "effort") && x < 0.0 {
                return Err(bad(limit, x, "must be ≥ 0"));
            }
            if matches!(limit, "lower" | "upper")
                && !matches!(joint.joint_type, JointType::Revolute | JointType::Prismatic)
            {
                return Err(bad(limit, x, "is for revolute and prismatic joints only"));
            }
        }
        if let (Some(lower), Some(upper)) = (f.lower, f.upper) {
            if lower > upper {
                return Err(bad("lower", lower, "is above the upper limit"));
            }
        }
        joint.limits = limits;
        Ok(())
    }

    /// Adds a loop, coupling or mimic relation. Body and joint indices are those returned by
    /// [`ModelBuilder::add_body`].
    pub fn add_constraint(&mut self, constraint: Constraint<T>) {
        self.constraints.push(constraint);
    }

    /// Declares the coordinate of body `body`'s joint dependent inside its group (URDF+
    /// `independent="false"`; mimic joints). Ignored for joints outside every group.
    pub fn declare_dependent(&mut self, body: usize) {
        if self.declared_dependent.len() <= body {
            self.declared_dependent.resize(body + 1, false);
        }
        self.declared_dependent[body] = true;
    }

    /// Records the URDF links merged into a body with their poses in the body frame (for reports and
    /// link-frame kinematics).
    ///
    /// # Panics
    /// If the two lists differ in length.
    pub fn set_merged_links(
        &mut self,
        body: usize,
        links: Vec<String>,
        placements: Vec<Transform<T>>,
    ) {
        assert_eq!(
            links.len(),
            placements.len(),
            "one placement per merged link"
        );
        self.bodies[body].links = links;
        self.bodies[body].link_placements = placements;
    }

    /// Records the URDF links fixed to the world (frames that never move) with their poses in the world.
    ///
    /// # Panics
    /// If the two lists differ in length.
    pub fn set_world_links(&mut self, links: Vec<String>, placements: Vec<Transform<T>>) {
        assert_eq!(
            links.len(),
            placements.len(),
            "one placement per world link"
        );
        self.world_links = links;
        self.world_link_placements = placements;
    }

    /// Numbers the bodies depth-first (siblings in the order they were added; docs/conventions.md), assigns
    /// the coordinate indices, and checks that every joint's acceleration is determined: `D(k) > 0` at
    /// two unrelated configurations (a joint singular at both is singular everywhere but on a null set).
    pub fn build(self) -> Result<Model<T>, ModelError> {
        let n = self.bodies.len();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut roots = Vec::new();
        for (i, j) in self.joints.iter().enumerate() {
            match j.parent {
                Some(p) => children[p].push(i),
                None => roots.push(i),
            }
        }
        // Depth-first order with an explicit stack (chains of thousands of bodies are fine).
        let mut order = Vec::with_capacity(n);
        let mut stack: Vec<usize> = roots.into_iter().rev().collect();
        while let Some(i) = stack.pop() {
            order.push(i);
            stack.extend(children[i].iter().rev());
        }
        let mut new_index = vec![0; n];
        for (k, &i) in order.iter().enumerate() {
            new_index[i] = k;
        }
        let (mut nq, mut nv) = (0, 0);
        let mut joints = Vec::with_capacity(n);
        let mut bodies = Vec::with_capacity(n);
        for &i in &order {
            let mut j = self.joints[i].clone();
            j.parent = j.parent.map(|p| new_index[p]);
            j.q_index = nq;
            j.v_index = nv;
            nq += j.nq();
            nv += j.nv();
            joints.push(j);
            bodies.push(self.bodies[i].clone());
        }
        let mut subtree_end: Vec<usize> = (0..n).map(|i| i + 1).collect();
        for i in (0..n).rev() {
            if let Some(p) = joints[i].parent {
                subtree_end[p] = subtree_end[p].max(subtree_end[i]);
            }
        }
        let remap = |b: Option<usize>| b.map(|b| new_index[b]);
        let constraints: Vec<Constraint<T>> = self
            .constraints
            .into_iter()
            .map(|mut c| {
                match &mut c.kind {
                    ConstraintKind::Linear { terms, .. } => {
                        for t in terms.iter_mut() {
                            t.0 = new_index[t.0];
                        }
                    }
                    ConstraintKind::Loop(l) => {
                        l.predecessor = remap(l.predecessor);
                        l.successor = remap(l.successor);
                    }
                }
                c
            })
            .collect();
        let mut declared = vec![false; n];
        for (b, &d) in self.declared_dependent.iter().enumerate() {
            if d && b < n {
                declared[new_index[b]] = true;
            }
        }
        let mut model = Model {
            name: self.name,
            joints,
            bodies,
            gravity: self.gravity,
            nq,
            nv,
            subtree_end,
            constraints,
            groups: Vec::new(),
            group_of: vec![None; n],
            world_links: self.world_links,
            world_link_placements: self.world_link_placements,
        };
        if !model.constraints.is_empty() {
            model.groups = crate::constraints::build_groups(&model, &declared)?;
            for (g, group) in model.groups.iter().enumerate() {
                for &b in &group.bodies {
                    model.group_of[b] = Some(g);
                }
            }
        }
        // After the groups: which joints are dependent decides what the inertia check asks of them.
        crate::check::check_built(&model)?;
        Ok(model)
    }
}

/// Rotation matrix of a quaternion `[x, y, z, w]` (scalar last), normalized on the way so that a
/// quaternion that drifted off unit length by integration still gives a rotation.
#[inline(always)]
pub(crate) fn quaternion_to_rotation<T: Real>(q: [T; 4]) -> nalgebra::Matrix3<T> {
    let [x, y, z, w] = q;
    let n2 = w * w + x * x + y * y + z * z;
    let s = T::from_f64(2.0) / n2;
    let one = T::one();
    nalgebra::Matrix3::new(
        one - s * (y * y + z * z),
        s * (x * y - w * z),
        s * (x * z + w * y),
        s * (x * y + w * z),
        one - s * (x * x + z * z),
        s * (y * z - w * x),
        s * (x * z - w * y),
        s * (y * z + w * x),
        one - s * (x * x + y * y),
    )
}

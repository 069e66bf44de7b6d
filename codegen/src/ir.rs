//! The model IR: what a model file says, checked and in SI units, before any choice of scalar type.
//!
//! Every output (the interpreted model, generated code, `embedyn info`) is made from this one structure.
//! Numbers stay as the file wrote them (`f64`); the model is assembled and validated from them in f64 and
//! then converted to the scalar in use (see `assemble.rs`), so every scalar gets one structure.

use std::path::PathBuf;

/// `<origin xyz rpy>`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Origin {
    /// Translation (m).
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (rad), applied about fixed x, y, z.
    pub rpy: [f64; 3],
}

impl Origin {
    /// Whether this is the identity pose (both `xyz` and `rpy` zero).
    pub fn is_identity(&self) -> bool {
        self.xyz == [0.0; 3] && self.rpy == [0.0; 3]
    }
}

/// `<inertial>`: mass, centre-of-mass frame, inertia about the centre of mass in that frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertial {
    /// The centre-of-mass frame in the link frame.
    pub origin: Origin,
    /// Mass (kg).
    pub mass: f64,
    /// `[ixx, ixy, ixz, iyy, iyz, izz]`.
    pub inertia: [f64; 6],
}

/// A URDF `<link>`: a rigid body (inertia optional).
#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    /// The link's name.
    pub name: String,
    /// Its `<inertial>`, `None` for a massless link.
    pub inertial: Option<Inertial>,
    /// Line of the element in the model file, for messages.
    pub line: Option<u32>,
}

/// A URDF joint's `type`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JointKind {
    /// One angle, with limits.
    Revolute,
    /// One angle, without limits.
    Continuous,
    /// One displacement along the axis.
    Prismatic,
    /// No motion: the child link is merged into the parent body.
    Fixed,
    /// Six degrees of freedom.
    Floating,
}

impl JointKind {
    /// Whether the joint has coordinates (every kind but `Fixed`).
    pub fn is_moving(self) -> bool {
        self != JointKind::Fixed
    }

    /// Whether the joint has exactly one coordinate (revolute, continuous, prismatic).
    pub fn is_one_dof(self) -> bool {
        matches!(
            self,
            JointKind::Revolute | JointKind::Continuous | JointKind::Prismatic
        )
    }

    /// The name URDF gives the kind (`revolute`, …).
    pub fn as_str(self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
            JointKind::Fixed => "fixed",
            JointKind::Floating => "floating",
        }
    }
}

impl Joint {
    /// Whether the joint has coordinates in the assembled model: a moving kind, not locked.
    pub fn moves(&self) -> bool {
        self.kind.is_moving() && self.locked.is_none()
    }
}

/// `<mimic joint multiplier offset>`: this joint's coordinate = multiplier · q_joint + offset.
#[derive(Clone, Debug, PartialEq)]
pub struct Mimic {
    /// The joint followed.
    pub joint: String,
    /// Factor on the followed joint's coordinate.
    pub multiplier: f64,
    /// Added to the product.
    pub offset: f64,
    /// Line of the element in the model file, for messages.
    pub line: Option<u32>,
}

/// A joint's `<limit>` as read (see [`Joint::limits`]).
pub type Limits = embedyn_runtime::JointLimits<f64>;

/// A URDF `<joint>`.
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// The joint's name.
    pub name: String,
    /// Its `type`.
    pub kind: JointKind,
    /// Index into [`Robot::links`].
    pub parent: usize,
    /// Index into [`Robot::links`].
    pub child: usize,
    /// Pose of the joint frame in the parent link frame.
    pub origin: Origin,
    /// As written (not normalized); `[1, 0, 0]` when absent, as URDF specifies.
    pub axis: [f64; 3],
    /// The `<mimic>` elements of this joint.
    pub mimics: Vec<Mimic>,
    /// URDF+'s `independent` attribute, if given.
    pub independent: Option<bool>,
    /// Armature (kg·m² or kg): `<dynamics armature>` plus r² · I of each transmission's rotor on it.
    pub armature: f64,
    /// `<limit lower upper velocity effort>`, each `None` where absent: position limits of revolute and
    /// prismatic joints only (a continuous, fixed or floating joint has none), velocity and effort of every
    /// one-coordinate joint. Checked when read: finite, velocity and effort ≥ 0, lower ≤ upper.
    pub limits: Limits,
    /// `Some(value)` when a scene fixes the joint at that coordinate (`--lock`, or a geared rotor reflected
    /// at angle 0): it is then assembled as a fixed joint whose pose includes that motion. `None` as read.
    pub locked: Option<f64>,
    /// Line of the element in the model file, for messages.
    pub line: Option<u32>,
}

/// URDF+ `<loop type>`: what the cut joint keeps (docs/model-format.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LoopKind {
    /// Origins coincide, axes stay aligned (`revolute` and `continuous`).
    Revolute,
    /// Frames stay aligned, origins differ only along the axis.
    Prismatic,
    /// Origins coincide (an embedyn addition).
    Spherical,
    /// Frames coincide.
    Fixed,
}

/// One side of a loop: a frame fixed to a link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoopFrame {
    /// Index into [`Robot::links`].
    pub link: usize,
    /// The frame in the link frame.
    pub origin: Origin,
}

/// URDF+ `<loop>`: a cut joint between two link frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Loop {
    /// The loop's name.
    pub name: String,
    /// What the cut joint keeps.
    pub kind: LoopKind,
    /// The frame on the predecessor side.
    pub predecessor: LoopFrame,
    /// The frame on the successor side.
    pub successor: LoopFrame,
    /// In the predecessor frame; `[1, 0, 0]` when absent.
    pub axis: [f64; 3],
    /// Line of the element in the model file, for messages.
    pub line: Option<u32>,
}

/// URDF+ `<coupling>`: ratio × (coordinates from the common ancestor to `predecessor`) = (coordinates
/// from the common ancestor to `successor`).
#[derive(Clone, Debug, PartialEq)]
pub struct Coupling {
    /// The coupling's name.
    pub name: String,
    /// Link indices.
    pub predecessor: usize,
    /// Link index.
    pub successor: usize,
    /// The gear ratio.
    pub ratio: f64,
    /// Line of the element in the model file, for messages.
    pub line: Option<u32>,
}

/// A robot as read from URDF: links, joints, the root link, and URDF+ loops and couplings.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    /// The robot's name (`<robot name>`).
    pub name: String,
    /// The file it was read from.
    pub source: PathBuf,
    /// The links, in file order.
    pub links: Vec<Link>,
    /// The joints, in file order.
    pub joints: Vec<Joint>,
    /// Index of the root link (the one that is no joint's child).
    pub root: usize,
    /// URDF+ `<loop>` elements.
    pub loops: Vec<Loop>,
    /// URDF+ `<coupling>` elements.
    pub couplings: Vec<Coupling>,
}

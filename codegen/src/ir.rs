//! The model IR: what a model file says, checked and in SI units, before any choice of scalar type.
//!
//! Every output (the interpreted model, generated code, `embedyn info`) is made from this one structure.
//! Numbers stay as the file wrote them (`f64`); the model is assembled and validated from them in f64 and
//! then converted to the scalar in use (see `assemble.rs`), so every scalar gets one structure.

use std::path::PathBuf;

/// `<origin xyz rpy>`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Origin {
    pub xyz: [f64; 3],
    pub rpy: [f64; 3],
}

impl Origin {
    pub fn is_identity(&self) -> bool {
        self.xyz == [0.0; 3] && self.rpy == [0.0; 3]
    }
}

/// `<inertial>`: mass, centre-of-mass frame, inertia about the centre of mass in that frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertial {
    pub origin: Origin,
    pub mass: f64,
    /// `[ixx, ixy, ixz, iyy, iyz, izz]`.
    pub inertia: [f64; 6],
}

#[derive(Clone, Debug, PartialEq)]
pub struct Link {
    pub name: String,
    pub inertial: Option<Inertial>,
    pub line: Option<u32>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JointKind {
    Revolute,
    Continuous,
    Prismatic,
    Fixed,
    Floating,
}

impl JointKind {
    pub fn is_moving(self) -> bool {
        self != JointKind::Fixed
    }
}

/// `<mimic joint multiplier offset>`: this joint's coordinate = multiplier · q_joint + offset.
#[derive(Clone, Debug, PartialEq)]
pub struct Mimic {
    pub joint: String,
    pub multiplier: f64,
    pub offset: f64,
    pub line: Option<u32>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    pub name: String,
    pub kind: JointKind,
    /// Index into [`Robot::links`].
    pub parent: usize,
    pub child: usize,
    pub origin: Origin,
    /// As written (not normalized); `[1, 0, 0]` when absent, as URDF specifies.
    pub axis: [f64; 3],
    pub mimics: Vec<Mimic>,
    /// URDF+'s `independent` attribute, if given.
    pub independent: Option<bool>,
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
    pub origin: Origin,
}

/// URDF+ `<loop>`: a cut joint between two link frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Loop {
    pub name: String,
    pub kind: LoopKind,
    pub predecessor: LoopFrame,
    pub successor: LoopFrame,
    /// In the predecessor frame; `[1, 0, 0]` when absent.
    pub axis: [f64; 3],
    pub line: Option<u32>,
}

/// URDF+ `<coupling>`: ratio × (coordinates from the common ancestor to `predecessor`) = (coordinates
/// from the common ancestor to `successor`).
#[derive(Clone, Debug, PartialEq)]
pub struct Coupling {
    pub name: String,
    /// Link indices.
    pub predecessor: usize,
    pub successor: usize,
    pub ratio: f64,
    pub line: Option<u32>,
}

/// A robot as read from URDF: links, joints, the root link, and URDF+ loops and couplings.
#[derive(Clone, Debug, PartialEq)]
pub struct Robot {
    pub name: String,
    pub source: PathBuf,
    pub links: Vec<Link>,
    pub joints: Vec<Joint>,
    /// Index of the root link (the one that is no joint's child).
    pub root: usize,
    /// URDF+ `<loop>` elements.
    pub loops: Vec<Loop>,
    /// URDF+ `<coupling>` elements.
    pub couplings: Vec<Coupling>,
}

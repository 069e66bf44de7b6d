use super::DynamicsError;
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::constraints::GroupWorkspace;
use crate::model::Model;
use crate::spatial::{ArticulatedInertia, Force, Motion, SpatialInertia, Transform};
use crate::Real;
use nalgebra::DMatrix;

/// The kinematics of the last pass, borrowed from a [`Workspace`]: what constraint rows are computed
/// from. Per-body entries are indexed like `model.bodies`.
#[derive(Clone, Copy, Debug)]
pub struct Kinematics<'w, T: Real> {
    /// Pose of each body frame in the world.
    pub world_placement: &'w [Transform<T>],
    /// Spatial velocity of each body, in its own frame.
    pub velocity: &'w [Motion<T>],
    /// Spatial acceleration of each body, in its own frame (after [`crate::constraint_kinematics`]: the
    /// velocity-product accelerations at q̈ = 0, without gravity).
    pub acceleration: &'w [Motion<T>],
}

/// Which kinematics a [`Workspace`] holds: what the last call that wrote them left valid, each level with
/// everything of the levels before it. Every algorithm that writes the workspace's placements, velocities
/// or accelerations records what it leaves ([`Workspace::sweep`]); the readers of frames, the centre of
/// mass and the centroidal momentum check it and fail with [`DynamicsError::KinematicsNotComputed`]
/// (naming the call to make first) rather than return numbers of another state.
///
/// A plain enum, not a scalar: code generation traces the same sequence of calls, so the checks pass
/// while tracing as they do at run time and add nothing to generated code.
///
/// | Call | Leaves |
/// |---|---|
/// | [`crate::forward_kinematics`]`(q, v)` | `Velocities` |
/// | [`crate::forward_kinematics_acceleration`]`(q, v, qdd)`; [`crate::constraint_kinematics`]`(q, v)` (at `qdd = 0`) | `Accelerations` |
/// | [`crate::kkt_forward_dynamics`], [`crate::constraints::constraint_violation`] | `Velocities` |
/// | [`crate::embedding_map_in`], [`crate::constraints::complete_velocity`], [`crate::constraints::y1_condition`] | `Placements` |
/// | [`crate::aba`], [`crate::rnea`], [`crate::nle`], [`crate::gravity`] and their `_ext` / `_with_gravity` forms, [`crate::crba`], [`crate::reduced_mass_matrix_in`], [`crate::mass_matrix_inverse`], [`crate::constraints::complete_configuration`], [`crate::constraints::completion_step`] | `None` |
///
/// [`crate::kinetic_energy`], [`crate::potential_energy`], [`crate::link_poses`] and the building blocks
/// of [`crate::constraints`] read the workspace without checking; writes to its public fields by hand are
/// not recorded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Sweep {
    /// No world placements: a fresh workspace, or the last call left only parent placements (`crba`,
    /// `mass_matrix_inverse`) or accelerations with gravity (`aba`, `rnea`, `nle`, `gravity`).
    #[default]
    None,
    /// Each body's placement in its parent and in the world at the call's `q`; the velocities and
    /// accelerations are not those of a `v` the caller gave (position-level constraint work zeroes them).
    Placements,
    /// Also each body's spatial velocity at the call's `v`.
    Velocities,
    /// Also each body's spatial acceleration without gravity at the call's `qdd` (`qdd = 0` for
    /// [`crate::constraint_kinematics`]: the velocity-product accelerations).
    Accelerations,
}

impl Sweep {
    /// The call that leaves (at least) this state.
    pub fn call(self) -> &'static str {
        match self {
            Sweep::None => "nothing",
            Sweep::Placements | Sweep::Velocities => "forward_kinematics(q, v)",
            Sweep::Accelerations => "forward_kinematics_acceleration(q, v, qdd)",
        }
    }
}

impl core::fmt::Display for Sweep {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Sweep::None => "no world placements (it is new, or the last call was aba, rnea, nle, gravity, crba, mass_matrix_inverse, reduced_mass_matrix or a configuration completion)",
            Sweep::Placements => "world placements but no velocities (the last call was position-level: embedding_map, complete_velocity, y1_condition)",
            Sweep::Velocities => "placements and velocities but no accelerations without gravity (the last call was forward_kinematics, kkt_forward_dynamics or constraint_violation)",
            Sweep::Accelerations => "placements, velocities and accelerations without gravity",
        })
    }
}

/// Scratch of the aggregate links: per group, its embedding maps and articulated-body quantities; for
/// position completion, every constraint row's residual and the magnitude it is relative to.
#[derive(Clone, Debug)]
pub(crate) struct ConstraintScratch<T: Real> {
    /// Per aggregate link, indexed like `model.groups`.
    pub(crate) groups: Vec<GroupWorkspace<T>>,
    /// Residuals of every constraint row.
    pub(crate) residual: Vec<T>,
    /// The magnitude each residual is computed from (see [`crate::constraints::residuals_scaled`]).
    pub(crate) scale: Vec<T>,
}

/// Scratch memory for the algorithms of one model, allocated once by [`Workspace::new`] and reused by
/// every call, so that no algorithm call touches the heap (what a real-time loop needs).
///
/// Per-body entries are indexed like `model.bodies`. Results of the last call stay readable here.
#[derive(Clone, Debug)]
pub struct Workspace<T: Real> {
    /// Pose of each body frame in its parent body frame (`ᵖX_i` as a placement).
    pub parent_placement: Vec<Transform<T>>,
    /// Pose of each body frame in the world, filled by [`crate::forward_kinematics`].
    pub world_placement: Vec<Transform<T>>,
    /// Spatial velocity of each body, in its own frame.
    pub velocity: Vec<Motion<T>>,
    /// Spatial acceleration of each body (RNEA, ABA), in its own frame, with gravity's −g added at the root.
    pub acceleration: Vec<Motion<T>>,
    /// Velocity-product acceleration `a(k) = V(k) ×ₘ H*(k) θ̇(k)` (the paper's Coriolis term).
    pub(crate) coriolis: Vec<Motion<T>>,
    /// RNEA: joint forces `f(k)`; ABA: the articulated bias force `𝔷(k)`.
    pub force: Vec<Force<T>>,
    /// Articulated (ABA) or composite (CRBA) inertia `P(k)`.
    pub inertia: Vec<ArticulatedInertia<T>>,
    /// CRBA: composite rigid-body inertia of each subtree, in its body frame.
    pub(crate) composite: Vec<SpatialInertia<T>>,
    // Per-joint data of the articulated-body sweeps, sized by each joint's velocity dimension (as
    // Pinocchio's per-joint data), so that a 1-DoF joint and a 6-DoF floating joint take one code path and
    // no two joints share storage.
    /// `U = P(k) H*(k)`: one force column per velocity coordinate (indexed like `v`).
    pub(crate) u: Vec<Force<T>>,
    /// `ε(k) = 𝒯(k) − H(k) 𝔷(k)`, per velocity coordinate.
    pub(crate) epsilon: Vec<T>,
    /// The LDLᵀ factor of each joint's `D(k) = H P H*` (`nv_j × nv_j`, from `d_offset[joint]`; diagonal
    /// holds `1 / D_kk`, see [`crate::linalg::cholesky_in_place`]).
    pub(crate) d_factor: Vec<T>,
    pub(crate) d_offset: Vec<usize>,
    /// Smallest pivot of each joint's last `D` factorization (`D` itself for a 1-DoF joint).
    pub(crate) d_pivot: Vec<T>,
    /// Output of `aba`.
    pub qdd: Vec<T>,
    /// Output of `rnea`.
    pub tau: Vec<T>,
    /// Output of `crba`.
    pub mass_matrix: DMatrix<T>,
    /// Output of `mass_matrix_inverse` (allocated on first use, see [`Workspace::reserve_inverse`]).
    pub inverse_mass_matrix: DMatrix<T>,
    /// Per body, `6 × nv` force columns and acceleration columns for the operator inverse of Eq. 6.
    pub(crate) minv_force: Vec<[T; 6]>,
    pub(crate) minv_accel: Vec<[T; 6]>,
    /// The aggregate links' own scratch, a field of its own so that an algorithm can hold one group's
    /// scratch and the bodies' kinematics at once (see [`Workspace::split_constraints`]).
    pub(crate) constraints: ConstraintScratch<T>,
    /// Output of [`crate::embedding_map_in`]: `X`, nv × independent nv.
    pub embedding: DMatrix<T>,
    /// Output of [`crate::reduced_mass_matrix_in`]: `Xᵀ M X`.
    pub reduced_mass_matrix: DMatrix<T>,
    /// `M X` (scratch of the reduced mass matrix).
    pub(crate) mass_times_x: DMatrix<T>,
    /// Which of `parent_placement`, `world_placement`, `velocity` and `acceleration` are valid, and for
    /// which call (see [`Sweep`]).
    pub(crate) sweep: Sweep,
}

impl<T: Real> Workspace<T> {
    /// Allocates the O(N) scratch every algorithm needs for `model`.
    ///
    /// Outputs that grow faster than the model — the mass matrix (nv²), the operator inverse's column
    /// buffers (12 · N · nv scalars), the embedding map (nv · ni) — are allocated by the algorithm that
    /// needs them on its first call, so a long chain that only runs `aba` never pays for an nv × nv matrix.
    /// A real-time loop that must not allocate at all calls [`Workspace::reserve_all`] (or the `reserve_*`
    /// of the algorithms it uses) once beforehand.
    pub fn new(model: &Model<T>) -> Self {
        let n = model.nbodies();
        let nv = model.nv();
        let mut d_offset = Vec::with_capacity(n);
        let mut d_len = 0;
        for joint in &model.joints {
            d_offset.push(d_len);
            d_len += joint.nv() * joint.nv();
        }
        Workspace {
            parent_placement: vec![Transform::identity(); n],
            world_placement: vec![Transform::identity(); n],
            velocity: vec![Motion::zero(); n],
            acceleration: vec![Motion::zero(); n],
            coriolis: vec![Motion::zero(); n],
            force: vec![Force::zero(); n],
            inertia: vec![ArticulatedInertia::zero(); n],
            composite: vec![SpatialInertia::zero(); n],
            u: vec![Force::zero(); nv],
            epsilon: vec![T::zero(); nv],
            d_factor: vec![T::zero(); d_len],
            d_offset,
            d_pivot: vec![T::one(); n],
            qdd: vec![T::zero(); nv],
            tau: vec![T::zero(); nv],
            mass_matrix: DMatrix::zeros(0, 0),
            inverse_mass_matrix: DMatrix::zeros(0, 0),
            minv_force: Vec::new(),
            minv_accel: Vec::new(),
            constraints: ConstraintScratch {
                groups: model
                    .groups
                    .iter()
                    .map(|g| GroupWorkspace::new(model, g))
                    .collect(),
                residual: vec![T::zero(); model.constraint_raw_rows()],
                scale: vec![T::zero(); model.constraint_raw_rows()],
            },
            embedding: DMatrix::zeros(0, 0),
            reduced_mass_matrix: DMatrix::zeros(0, 0),
            mass_times_x: DMatrix::zeros(0, 0),
            sweep: Sweep::None,
        }
    }

    /// The kinematics of the last [`crate::forward_kinematics`] (or [`crate::constraint_kinematics`]) call.
    pub fn kinematics(&self) -> Kinematics<'_, T> {
        Kinematics {
            world_placement: &self.world_placement,
            velocity: &self.velocity,
            acceleration: &self.acceleration,
        }
    }

    /// Which kinematics the workspace holds (see [`Sweep`]).
    pub fn sweep(&self) -> Sweep {
        self.sweep
    }

    /// Fails unless the workspace holds at least `needs`: `reader` is the function asking, named in the
    /// error with the call to make first.
    pub(crate) fn require(&self, reader: &'static str, needs: Sweep) -> Result<(), DynamicsError> {
        if self.sweep >= needs {
            Ok(())
        } else {
            Err(DynamicsError::KinematicsNotComputed {
                reader,
                needs,
                holds: self.sweep,
            })
        }
    }

    /// The kinematics, read-only, beside the aggregate links' scratch, writable: two disjoint parts of
    /// the workspace borrowed at once, so that no algorithm moves a group's scratch out and back.
    pub(crate) fn split_constraints(&mut self) -> (Kinematics<'_, T>, &mut ConstraintScratch<T>) {
        (
            Kinematics {
                world_placement: &self.world_placement,
                velocity: &self.velocity,
                acceleration: &self.acceleration,
            },
            &mut self.constraints,
        )
    }

    /// Allocates every output buffer of every algorithm, so that no later call allocates (O(nv²) memory:
    /// the mass matrix, its inverse and, for a model with constraints, the embedding map).
    pub fn reserve_all(&mut self, model: &Model<T>) {
        self.reserve_mass_matrix(model);
        self.reserve_inverse(model);
        if model.has_constraints() {
            self.reserve_embedding(model);
        }
    }

    /// Allocates the output of [`crate::crba`] (done on its first call).
    pub fn reserve_mass_matrix(&mut self, model: &Model<T>) {
        let nv = model.nv();
        if self.mass_matrix.shape() != (nv, nv) {
            self.mass_matrix = DMatrix::zeros(nv, nv);
        }
    }

    /// Allocates the outputs of [`crate::embedding_map_in`] and [`crate::reduced_mass_matrix_in`] (done on
    /// their first call).
    pub fn reserve_embedding(&mut self, model: &Model<T>) {
        let (nv, ni) = (model.nv(), model.independent_nv());
        if self.embedding.shape() != (nv, ni) {
            self.embedding = DMatrix::zeros(nv, ni);
            self.reduced_mass_matrix = DMatrix::zeros(ni, ni);
            self.mass_times_x = DMatrix::zeros(nv, ni);
        }
    }

    /// Allocates the buffers of [`crate::mass_matrix_inverse`] (done automatically on its first call; call
    /// this beforehand to keep that first call allocation-free too).
    pub fn reserve_inverse(&mut self, model: &Model<T>) {
        let len = model.nbodies() * model.nv();
        if self.minv_force.len() != len {
            self.minv_force = vec![[T::zero(); 6]; len];
            self.minv_accel = vec![[T::zero(); 6]; len];
            self.inverse_mass_matrix = DMatrix::zeros(model.nv(), model.nv());
        }
    }
}

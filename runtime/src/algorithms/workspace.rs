use crate::model::Model;
use crate::spatial::{ArticulatedInertia, Force, Motion, SpatialInertia, Transform};
use crate::Real;
use nalgebra::{DMatrix, Matrix6};

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
    /// `P(k) H*(k)` for 1-DoF joints.
    pub(crate) u: Vec<Force<T>>,
    /// `D(k)⁻¹` for 1-DoF joints.
    pub(crate) d_inv: Vec<T>,
    /// `ε(k) = 𝒯(k) − H(k) 𝔷(k)` for 1-DoF joints.
    pub(crate) epsilon: Vec<T>,
    /// `D` of a floating root (6×6, in the order of `v`), factored in place.
    pub(crate) floating_d: Matrix6<T>,
    pub(crate) floating_eps: [T; 6],
    /// Smallest pivot of the last `floating_d` factorization.
    pub(crate) floating_pivot: T,
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
    /// Per aggregate link: the embedding maps and its articulated-body scratch.
    pub(crate) groups: Vec<crate::constraints::GroupWorkspace<T>>,
    pub(crate) minv_accel: Vec<[T; 6]>,
    /// `nv` zeros (the velocity of position-level constraint kinematics); never written.
    pub(crate) zero_velocity: Vec<T>,
    /// Residuals of every constraint row (position completion).
    pub(crate) constraint_residual: Vec<T>,
    /// Output of [`crate::embedding_map_in`]: `X`, nv × independent nv.
    pub embedding: DMatrix<T>,
    /// Output of [`crate::reduced_mass_matrix_in`]: `Xᵀ M X`.
    pub reduced_mass_matrix: DMatrix<T>,
    /// `M X` (scratch of the reduced mass matrix).
    pub(crate) mass_times_x: DMatrix<T>,
}

impl<T: Real> Workspace<T> {
    /// Allocates everything the algorithms need for `model`.
    ///
    /// Memory is O(N) except for the mass matrix (nv²) and the operator inverse's column buffers
    /// (12 · N · nv scalars), which are allocated on first use by [`Workspace::reserve_inverse`].
    pub fn new(model: &Model<T>) -> Self {
        let n = model.nbodies();
        let nv = model.nv();
        let mut ws = Workspace {
            parent_placement: vec![Transform::identity(); n],
            world_placement: vec![Transform::identity(); n],
            velocity: vec![Motion::zero(); n],
            acceleration: vec![Motion::zero(); n],
            coriolis: vec![Motion::zero(); n],
            force: vec![Force::zero(); n],
            inertia: vec![ArticulatedInertia::zero(); n],
            composite: vec![SpatialInertia::zero(); n],
            u: vec![Force::zero(); n],
            d_inv: vec![T::zero(); n],
            epsilon: vec![T::zero(); n],
            floating_d: Matrix6::zeros(),
            floating_eps: [T::zero(); 6],
            floating_pivot: T::one(),
            qdd: vec![T::zero(); nv],
            tau: vec![T::zero(); nv],
            mass_matrix: DMatrix::zeros(nv, nv),
            inverse_mass_matrix: DMatrix::zeros(0, 0),
            minv_force: Vec::new(),
            groups: model
                .groups
                .iter()
                .map(|g| crate::constraints::GroupWorkspace::new(model, g))
                .collect(),
            minv_accel: Vec::new(),
            zero_velocity: vec![T::zero(); nv],
            constraint_residual: vec![T::zero(); model.constraint_raw_rows()],
            embedding: DMatrix::zeros(0, 0),
            reduced_mass_matrix: DMatrix::zeros(0, 0),
            mass_times_x: DMatrix::zeros(0, 0),
        };
        if model.has_constraints() {
            ws.reserve_embedding(model);
        }
        ws
    }

    /// Allocates the outputs of [`crate::embedding_map_in`] and [`crate::reduced_mass_matrix_in`] (done
    /// by [`Workspace::new`] for a model with constraints and on first use otherwise).
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

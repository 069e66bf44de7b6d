//! # embedyn-runtime
//!
//! Spatial algebra generic over the scalar, the robot model, and the interpreted dynamics algorithms of
//! embedyn: forward kinematics, RNEA, CRBA, the O(N) articulated-body forward dynamics (A. Jain,
//! DETC2009-87663, Eq. 9) and the operator inverse of the mass matrix (Eq. 6).
//!
//! These are the oracle every generated function is tested against. Every algorithm works on a
//! [`Workspace`] allocated once per model, so calls never allocate.
//!
//! Conventions (see CONTRACT.md §2): spatial vectors are `[angular; linear]`, SI units, gravity
//! (0, 0, −9.81) m/s² by default; a floating base uses Pinocchio's free-flyer layout.

mod algorithms;
pub mod constraints;
mod double_double;
pub mod linalg;
mod model;
mod model_constants;
mod scalar;
pub mod spatial;

pub use algorithms::{
    aba, constraint_kinematics, crba, embedding_map, embedding_map_in, forward_kinematics,
    kinetic_energy, kkt_forward_dynamics, link_poses, mass_matrix_inverse, potential_energy,
    reduced_mass_matrix, reduced_mass_matrix_in, rnea, rnea_with_gravity, DynamicsError, Workspace,
};
pub use model::{Body, Joint, JointType, Model, ModelBuilder, ModelElement, ModelError};
pub use scalar::{DoubleDouble, Real};
pub use spatial::{ArticulatedInertia, Force, Motion, SpatialInertia, Transform};

/// Re-exported so that users of the model API need not depend on nalgebra themselves.
pub use nalgebra;

/// "Relative error" as CONTRACT §2 defines it: `max|a − b| / max(1, max|b|)`.
pub fn relative_error<T: Real>(a: &[T], b: &[T]) -> f64 {
    assert_eq!(
        a.len(),
        b.len(),
        "relative_error of vectors of different lengths"
    );
    let mut diff = 0.0f64;
    let mut scale = 1.0f64;
    for (x, y) in a.iter().zip(b) {
        diff = diff.max((x.to_f64() - y.to_f64()).abs());
        scale = scale.max(y.to_f64().abs());
    }
    diff / scale
}

/// Helpers of the code `embedyn::robot!` and `embedyn_codegen` generate (not for direct use; the
/// standalone crates of `embedyn generate` carry the same source inline).
#[doc(hidden)]
pub mod codegen_support {
    include!("codegen_support.rs");
}

//! # embedyn-runtime
//!
//! Spatial algebra generic over the scalar, the robot model, and the interpreted dynamics algorithms of
//! embedyn: forward kinematics, RNEA, CRBA, the O(N) articulated-body forward dynamics (A. Jain,
//! DETC2009-87663, Eq. 9) and the operator inverse of the mass matrix (Eq. 6).
//!
//! These are the oracle every generated function is tested against. Every algorithm works on a
//! [`Workspace`] allocated once per model, so calls never allocate.
//!
//! Conventions (docs/conventions.md): spatial vectors are `[angular; linear]`, SI units, gravity
//! (0, 0, −9.81) m/s² by default; a floating base uses Pinocchio's free-flyer layout.

#![warn(missing_docs)]
#![no_std]

#[cfg(feature = "alloc")]
extern crate alloc;
// Tests print their measured errors.
#[cfg(any(feature = "std", test))]
#[macro_use]
extern crate std;

/// What `std`'s prelude would bring, for the modules that allocate.
#[cfg(feature = "alloc")]
#[allow(unused_imports)]
mod alloc_prelude {
    pub use alloc::borrow::ToOwned;
    pub use alloc::format;
    pub use alloc::string::{String, ToString};
    pub use alloc::vec;
    pub use alloc::vec::Vec;
}

#[cfg(feature = "alloc")]
mod algorithms;
#[cfg(feature = "alloc")]
mod check;
#[cfg(feature = "alloc")]
pub mod configuration;
#[cfg(feature = "alloc")]
pub mod constraints;
// Fused multiply-add and exact rounding come from the platform's libm.
#[cfg(feature = "std")]
mod double_double;
pub mod dual;
#[cfg(feature = "alloc")]
mod joint_axis_origins;
#[cfg(feature = "alloc")]
pub mod linalg;
#[cfg(feature = "alloc")]
mod model;
pub mod random;
mod scalar;
pub mod spatial;
#[cfg(feature = "alloc")]
pub mod tree;

#[cfg(feature = "alloc")]
pub use algorithms::{
    aba, aba_derivative_factors, aba_derivatives, aba_derivatives_independent, aba_ext,
    center_of_mass, centroidal_momentum, centroidal_momentum_matrix, centroidal_momentum_rate,
    com_jacobian, constraint_kinematics, crba, derivative_singularity_threshold, embedding_map,
    embedding_map_in, forward_kinematics, forward_kinematics_acceleration,
    frame_classical_acceleration, frame_jacobian, frame_placement, frame_velocity, gravity,
    kinetic_energy, kkt_forward_dynamics, link_poses, mass_matrix_inverse, nle, nle_ext,
    potential_energy, reduced_mass_matrix, reduced_mass_matrix_in, rnea, rnea_derivatives,
    rnea_ext, rnea_with_gravity, step, step_derivatives, AbaDerivativeFactors, AbaDerivatives,
    CenterOfMass, DerivativeMethod, DerivativeWorkspace, DynamicsError, Kinematics, LinkWrench,
    ManifoldDerivatives, Reference, RneaDerivatives, StepDerivatives, Sweep, Workspace,
};
#[cfg(feature = "alloc")]
pub use configuration::{
    difference, integrate, random_configuration, random_configuration_within_limits,
};
#[cfg(feature = "alloc")]
pub use model::{
    Body, FrameId, Joint, JointLimits, JointType, Model, ModelBuilder, ModelElement, ModelError,
};
/// The generator `random_configuration` draws from (also `random::SplitMix64`).
pub use random::SplitMix64;
#[cfg(feature = "std")]
pub use scalar::DoubleDouble;
pub use scalar::Real;
pub use spatial::{ArticulatedInertia, Force, Motion, SpatialInertia, Transform};

/// Re-exported so that users of the model API need not depend on nalgebra themselves.
pub use nalgebra;

/// "Relative error" as docs/conventions.md defines it: `max|a − b| / max(1, max|b|)`. A NaN on one side
/// only is an infinite error (`f64::max` would skip it: a NaN the other engine does not give must fail a
/// comparison, not pass it); equal entries, a NaN on both sides included, differ by 0.
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::relative_error;
/// assert_eq!(relative_error(&[3.0, 1.0], &[2.0, 1.0]), 0.5); // |3 − 2| / max(1, 2)
/// assert_eq!(relative_error(&[f64::NAN, 1.0], &[2.0, 1.0]), f64::INFINITY);
/// assert_eq!(relative_error(&[f64::NAN], &[f64::NAN]), 0.0);
/// ```
pub fn relative_error<T: Real>(a: &[T], b: &[T]) -> f64 {
    assert_eq!(
        a.len(),
        b.len(),
        "relative_error of vectors of different lengths"
    );
    let mut diff = 0.0f64;
    let mut scale = 1.0f64;
    for (x, y) in a.iter().zip(b) {
        let (x, y) = (x.to_f64(), y.to_f64());
        let d = if x == y || (x.is_nan() && y.is_nan()) {
            0.0
        } else {
            let d = (x - y).abs();
            if d.is_nan() {
                f64::INFINITY
            } else {
                d
            }
        };
        diff = diff.max(d);
        scale = scale.max(y.abs());
    }
    diff / scale
}

/// Helpers of the code `embedyn::robot!` and `embedyn_codegen` generate (not for direct use; the
/// standalone crates of `embedyn generate` carry the same source inline).
#[doc(hidden)]
pub mod codegen_support {
    include!("codegen_support.rs");
    include!("codegen_lanes.rs");
}

/// The lane types of generated lane modules (`robot!(…, lanes = 4)`: module `f64x4`, …): `N` numbers in
/// one SIMD value, one per state. Pack states with `F64x4::new([…])`, read them with `to_array()`.
pub mod lanes {
    pub use crate::codegen_support::{F32x4, F32x8, F64x2, F64x4};
}

/// The source text of [`codegen_support`], which `embedyn generate` copies into every standalone crate so
/// that it depends on nothing (and computes bit-identically to the macro and build.rs routes).
#[doc(hidden)]
pub const CODEGEN_SUPPORT_SOURCE: &str = include_str!("codegen_support.rs");

/// The source text of the lane types, which `embedyn generate` copies beside [`CODEGEN_SUPPORT_SOURCE`]
/// into a standalone crate generated with lanes (which then depends on `wide`).
#[doc(hidden)]
pub const CODEGEN_LANES_SOURCE: &str = include_str!("codegen_lanes.rs");

//! The interpreted algorithms: each a forward and/or backward sweep over the tree, one small step per
//! joint (as in the paper's Eqs. 1, 9 and 6). They are the oracle the generated code is tested against.

#[allow(unused_imports)]
use crate::alloc_prelude::*;
pub(crate) mod aba;
mod analytical_derivatives;
mod centroidal;
mod crba;
mod derivatives;
mod embedded;
mod frames;
mod kinematics;
mod minv;
mod rnea;
mod workspace;
mod wrenches;

pub use aba::aba;
pub use centroidal::{
    center_of_mass, centroidal_momentum, centroidal_momentum_matrix, centroidal_momentum_rate,
    com_jacobian, CenterOfMass,
};
pub use crba::crba;
pub use derivatives::{
    aba_derivative_factors, aba_derivatives, aba_derivatives_independent,
    derivative_singularity_threshold, rnea_derivatives, step, step_derivatives,
    AbaDerivativeFactors, AbaDerivatives, DerivativeMethod, DerivativeWorkspace,
    ManifoldDerivatives, RneaDerivatives, StepDerivatives,
};
pub(crate) use embedded::position_kinematics;
pub use embedded::{
    constraint_kinematics, embedding_map, embedding_map_in, kkt_forward_dynamics,
    reduced_mass_matrix, reduced_mass_matrix_in,
};
pub use frames::{
    forward_kinematics_acceleration, frame_classical_acceleration, frame_jacobian, frame_placement,
    frame_velocity, Reference,
};
pub use kinematics::{forward_kinematics, kinetic_energy, link_poses, potential_energy};
pub use minv::mass_matrix_inverse;
pub use rnea::{gravity, nle, rnea, rnea_with_gravity};
pub use workspace::{Kinematics, Sweep, Workspace};
pub use wrenches::{aba_ext, nle_ext, rnea_ext, LinkWrench};

use crate::constraints::{ConstraintSet, GroupLabel};
use crate::model::{JointType, Model};
use crate::spatial::{Motion, Transform};
use crate::Real;

/// Errors of an algorithm call.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// An input slice has the wrong length.
    #[error("`{name}` has length {got}, the model needs {expected}")]
    WrongLength {
        /// The argument (`"q"`, `"v"`, …).
        name: &'static str,
        /// Its length.
        got: usize,
        /// The length the model needs.
        expected: usize,
    },
    /// An input entry is NaN or infinite.
    #[error("`{name}`[{index}] is not a finite number ({value})")]
    NonFiniteInput {
        /// The argument.
        name: &'static str,
        /// The entry's index.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// A scalar input (a time step) is NaN or infinite.
    #[error("`{name}` is not a finite number ({value})")]
    NonFiniteScalar {
        /// The argument.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A floating joint's quaternion is zero or not finite.
    #[error("joint `{joint}`: its quaternion `q`[{start}..{end}] has norm {norm:e}; it must be a non-zero, finite [qx qy qz qw] (it is normalized before use)")]
    InvalidQuaternion {
        /// The floating joint.
        joint: String,
        /// Index of the quaternion's first entry in `q`.
        start: usize,
        /// One past its last entry.
        end: usize,
        /// Its norm.
        norm: f64,
    },
    /// A joint's articulated inertia about its axis is not positive at this configuration.
    #[error("joint `{joint}`: the articulated inertia about its axis is not positive (D = {d:e})")]
    SingularJoint {
        /// The joint.
        joint: String,
        /// The articulated inertia about its axis.
        d: f64,
    },
    /// A loop is at or too near a singular configuration.
    #[error("{group}: the loop is at or too near a singular configuration: cond(Y1) = {condition:.3e} ≥ {threshold:.1e}, the limit in this scalar type (at a singular configuration the dependent joints are not determined by the independent ones; derivatives, whose rounding grows as cond², are refused from the square root of the values' limit)")]
    SingularConstraint {
        /// The group, by the names of its constraints (or the whole KKT system).
        group: ConstraintSet,
        /// cond₁(Y1) at this configuration.
        condition: f64,
        /// The limit in this scalar type.
        threshold: f64,
    },
    /// A frame given to an algorithm is not one of the model's (a [`crate::FrameId`] of another model).
    #[error("frame {index} of the call ({frame:?}) is not a frame of this model")]
    UnknownFrame {
        /// Its position among the frames or wrenches of the call.
        index: usize,
        /// The frame.
        frame: crate::FrameId,
    },
    /// A reader of frames, the centre of mass or the centroidal momentum was called on a workspace that
    /// does not hold the kinematics it reads (see [`Sweep`]): a call is missing before it, and the numbers
    /// in the workspace are another state's.
    #[error("{reader} needs {} first; the workspace holds {holds}", .needs.call())]
    KinematicsNotComputed {
        /// The function called.
        reader: &'static str,
        /// What it reads.
        needs: Sweep,
        /// What the workspace holds.
        holds: Sweep,
    },
    /// An aggregate link's reduced inertia is not positive definite.
    #[error("{group}: the reduced inertia of the aggregate link is not positive definite")]
    SingularGroup {
        /// The group, by the names of its constraints.
        group: GroupLabel,
    },
    /// A function defined on trees only was called on a model with loops, couplings or mimic joints.
    #[error("`{function}` is defined for models without loops, couplings or mimic joints")]
    TreeOnly {
        /// The function.
        function: &'static str,
    },
}

pub(crate) fn check_len(
    name: &'static str,
    got: usize,
    expected: usize,
) -> Result<(), DynamicsError> {
    if got == expected {
        Ok(())
    } else {
        Err(DynamicsError::WrongLength {
            name,
            got,
            expected,
        })
    }
}

/// `x` has the model's length and only finite entries (a NaN in the input is named as such, not reported
/// later as whatever singularity it causes). Values unknown at generation time pass.
pub(crate) fn check_input<T: Real>(
    name: &'static str,
    x: &[T],
    expected: usize,
) -> Result<(), DynamicsError> {
    check_len(name, x.len(), expected)?;
    for (index, v) in x.iter().enumerate() {
        if let Some(value) = v.value() {
            if !value.is_finite() {
                return Err(DynamicsError::NonFiniteInput { name, index, value });
            }
        }
    }
    Ok(())
}

/// [`check_input`] for a configuration, and every floating joint's quaternion non-zero (any other norm is
/// normalized away; a zero quaternion is no rotation at all).
pub(crate) fn check_configuration<T: Real>(model: &Model<T>, q: &[T]) -> Result<(), DynamicsError> {
    check_input("q", q, model.nq())?;
    for j in model
        .joints
        .iter()
        .filter(|j| j.joint_type == JointType::Floating)
    {
        let s = &q[j.q_index + 3..j.q_index + 7];
        let norm2 = s.iter().fold(T::zero(), |acc, &x| acc + x * x);
        if let Some(n2) = norm2.value() {
            // (Components so small that their squares underflow are as unusable as zeros.)
            if !(n2 > 0.0 && n2.is_finite()) {
                return Err(DynamicsError::InvalidQuaternion {
                    joint: j.name.clone(),
                    start: j.q_index + 3,
                    end: j.q_index + 7,
                    norm: n2.sqrt(),
                });
            }
        }
    }
    Ok(())
}

/// The first forward sweep shared by RNEA and ABA: `ᵖX_i(q)`, `V(k)`, and `a(k) = V(k) ×ₘ H*θ̇(k)`.
#[inline(always)]
pub(crate) fn velocity_sweep<T: Real>(model: &Model<T>, ws: &mut Workspace<T>, q: &[T], v: &[T]) {
    // New parent placements without world placements (a caller that adds them says so).
    ws.sweep = Sweep::None;
    for (i, (joint, body)) in model.joints.iter().zip(&model.bodies).enumerate() {
        let x = parent_placement(joint, q);
        let vj = joint.joint_motion(v);
        let vel = match joint.parent {
            Some(p) => x.inv_act_motion(&ws.velocity[p]) + vj,
            None => vj,
        };
        ws.coriolis[i] = vel.cross_motion(&vj);
        ws.parent_placement[i] = x;
        ws.velocity[i] = vel.named(&body.name, "v");
    }
}

/// `ᵖX_i(q)`: the pose of a joint's child body frame in its parent body frame (named for generated code).
#[inline(always)]
pub(crate) fn parent_placement<T: Real>(joint: &crate::model::Joint<T>, q: &[T]) -> Transform<T> {
    joint
        .placement
        .compose(&joint.joint_transform(q))
        .named(&joint.name, "x")
}

/// The name of a joint quantity with one entry per velocity coordinate, for generated code
/// ([`Real::named`]): `names[0]` for a joint with one coordinate, `names[k + 1]` for coordinate `k` of
/// a joint with `n` of them.
#[inline(always)]
pub(crate) fn per_coordinate(names: &[&'static str; 7], n: usize, k: usize) -> &'static str {
    if n == 1 {
        names[0]
    } else {
        names[(k + 1).min(6)]
    }
}

/// The acceleration of the world frame that stands in for gravity, `−g`, expressed in `x`'s child frame.
#[inline(always)]
pub(crate) fn gravity_in<T: Real>(gravity: &nalgebra::Vector3<T>, x: &Transform<T>) -> Motion<T> {
    Motion::new(nalgebra::Vector3::zeros(), -x.rotation.tr_mul(gravity))
}

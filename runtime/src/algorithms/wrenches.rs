//! External wrenches: forces the environment applies to links (contacts, a tool's load, a push), as
//! [`aba_ext`], [`rnea_ext`] and [`nle_ext`] take them.
//!
//! A wrench is given where a controller knows it: on a link (a foot, a tool flange — also a link merged
//! into its parent body by a fixed joint), in that link's own frame, about its origin (docs/conventions.md). The
//! algorithms move it once into the frame of the body the link rides on and subtract it from that body's
//! bias force; nothing else changes, so the call costs a few operations per wrench over the plain one,
//! and in generated code a link without a wrench costs nothing.

use super::{DynamicsError, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::model::{FrameId, Model};
use crate::spatial::Force;
use crate::Real;
use nalgebra::Vector3;

/// A wrench the environment applies to one link, in that link's frame, about its origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkWrench<T: Real> {
    /// The link (see [`Model::frame`]).
    pub frame: FrameId,
    /// Force on the link (N), in the link's frame.
    pub force: Vector3<T>,
    /// Torque on the link about its origin (N·m), in the link's frame.
    pub torque: Vector3<T>,
}

impl<T: Real> LinkWrench<T> {
    /// A wrench on `frame` from its force and torque in the link's frame.
    pub fn new(frame: FrameId, force: Vector3<T>, torque: Vector3<T>) -> Self {
        LinkWrench {
            frame,
            force,
            torque,
        }
    }
}

/// Each wrench names one of the model's frames and holds only finite numbers.
pub(crate) fn check_wrenches<T: Real>(
    model: &Model<T>,
    f_ext: &[LinkWrench<T>],
) -> Result<(), DynamicsError> {
    for (k, w) in f_ext.iter().enumerate() {
        if model.frame_name(w.frame).is_none() {
            return Err(DynamicsError::UnknownFrame {
                index: k,
                frame: w.frame,
            });
        }
        let entries = w.force.iter().chain(w.torque.iter());
        for (c, x) in entries.enumerate() {
            if let Some(value) = x.value() {
                if !value.is_finite() {
                    return Err(DynamicsError::NonFiniteInput {
                        name: "f_ext",
                        index: 6 * k + c,
                        value,
                    });
                }
            }
        }
    }
    Ok(())
}

/// Subtracts each wrench, moved into its body's frame, from that body's entry of `ws.force` (the
/// bias force of ABA, the net force of RNEA): the environment supplies part of what the joints would.
/// Wrenches on links fixed to the world act on nothing that moves and are dropped.
pub(crate) fn subtract_wrenches<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    f_ext: &[LinkWrench<T>],
) {
    for w in f_ext {
        if let Some((b, f)) = wrench_in_body(model, w) {
            ws.force[b] -= f;
        }
    }
}

/// A wrench's body and the wrench in that body's frame, about its origin; `None` for a link fixed to the
/// world (it acts on nothing that moves).
pub(crate) fn wrench_in_body<T: Real>(
    model: &Model<T>,
    w: &LinkWrench<T>,
) -> Option<(usize, Force<T>)> {
    let b = w.frame.body?;
    let x = &model.bodies[b].link_placements[w.frame.link];
    Some((b, x.act_force(&Force::new(w.torque, w.force))))
}

/// Forward dynamics with external wrenches: `qdd = M⁻¹ (τ + Σ Jᵀ f − C(q, v) − g(q))`, each `f` a
/// [`LinkWrench`] (Pinocchio's `aba` with `fext`). For a model with loops, couplings or mimic joints the
/// wrenches act on the spanning tree's links and only their projection onto the independent coordinates
/// moves the robot, as for `tau`. The result is also left in `ws.qdd`.
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::nalgebra::{Matrix3, Vector3};
/// use embedyn::{aba_ext, JointType, LinkWrench, Model, SpatialInertia, Transform, Workspace};
/// // A 1 kg point-like pendulum, 0.5 m below a horizontal pivot about x.
/// let mut b = Model::<f64>::builder("pendulum");
/// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
/// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), Transform::identity(), "bob", inertia)
///     .unwrap();
/// let model = b.build().unwrap();
/// let mut ws = Workspace::new(&model);
/// // Hanging straight down, a hand pushes the bob (0.5 m below the link's origin, the pivot) along y with
/// // 2 N: about the link origin that is 2 N and a moment r × f = (0, 0, −0.5) × (0, 2, 0) = (1, 0, 0) N·m.
/// let bob = model.frame("bob").unwrap();
/// let push = LinkWrench::new(bob, Vector3::new(0.0, 2.0, 0.0), Vector3::new(1.0, 0.0, 0.0));
/// let qdd = aba_ext(&model, &mut ws, &[0.0], &[0.0], &[0.0], &[push]).unwrap();
/// assert!((qdd[0] - 1.0 / (0.25 + 1e-3)).abs() < 1e-12);
/// ```
pub fn aba_ext<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    f_ext: &[LinkWrench<T>],
) -> Result<&'w [T], DynamicsError> {
    super::aba::forward_dynamics(model, ws, q, v, tau, f_ext)
}

/// Inverse dynamics with external wrenches: `τ = M qdd + C(q, v) + g(q) − Σ Jᵀ f` (Pinocchio's `rnea`
/// with `fext`): the joint forces that give `qdd` while the environment applies `f_ext`. Left in `ws.tau`.
pub fn rnea_ext<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    qdd: &[T],
    f_ext: &[LinkWrench<T>],
) -> Result<&'w [T], DynamicsError> {
    super::rnea::inverse_dynamics(model, ws, q, v, Some(qdd), true, f_ext)
}

/// The nonlinear effects with external wrenches, `C(q, v) v + g(q) − Σ Jᵀ f` ([`rnea_ext`] at `qdd = 0`).
/// Left in `ws.tau`.
pub fn nle_ext<'w, T: Real>(
    model: &Model<T>,
    ws: &'w mut Workspace<T>,
    q: &[T],
    v: &[T],
    f_ext: &[LinkWrench<T>],
) -> Result<&'w [T], DynamicsError> {
    super::rnea::inverse_dynamics(model, ws, q, v, None, true, f_ext)
}

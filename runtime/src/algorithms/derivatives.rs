//! Derivatives of forward and inverse dynamics (CONTRACT §3 `aba_derivatives`, `rnea_derivatives`): on a
//! tree by the analytical recursion of [`super::analytical_derivatives`] (the default), and by
//! forward-mode dual numbers through the algorithms themselves on models with loops, couplings or mimic
//! joints (and on trees when asked for, [`DerivativeMethod::DualNumbers`], as a second opinion).
//!
//! A pass runs [`aba_ext`](super::aba_ext) or [`rnea_ext`](super::rnea_ext) on [`Dual`] numbers whose
//! tangents are seeded with up to [`DIRECTIONS`] input directions, and reads the outputs' tangents: the
//! derivatives along those directions, exact to rounding (no step size). Derivatives with respect to `q`
//! are in the tangent space, as Pinocchio defines them: column `k` is the derivative along
//! `integrate(q, ε eₖ)`, which the pass obtains by running [`integrate`](crate::integrate) itself on the
//! dual numbers (a free flyer's quaternion moves by its body-frame rotation).
//!
//! On a model with loops, couplings or mimic joints the spanning-tree derivatives differentiate the
//! embedded dynamics as a function of all spanning coordinates; [`aba_derivatives_independent`] moves
//! along the constraint manifold instead: the configuration along `X eₖ` (the manifold's tangent), the
//! dependent velocities following the independent ones through the velocity constraints at the moved
//! configuration ([`crate::constraints::complete_velocity`] on dual numbers, the implicit-function
//! theorem in one linear solve).
//!
//! The value pass runs on the scalar `T` first, so every input check and every error (a singular loop,
//! an inconsistent state) is that of [`crate::aba`] or [`crate::rnea`]; the dual passes then repeat the
//! arithmetic with the tangents.

use super::analytical_derivatives::{
    forward_factors_by_mass_matrix, forward_partials, rnea_partials, AnalyticalScratch,
    InverseDynamicsPartials,
};
use super::{check_len, DynamicsError, LinkWrench, Workspace};
#[allow(unused_imports)]
use crate::alloc_prelude::*;
use crate::dual::Dual;
use crate::model::Model;
use crate::Real;
use nalgebra::{DMatrix, DVector};

/// Directions per dual pass: the derivatives with respect to `q`, `v` and `τ` of an `nv`-coordinate model
/// take `⌈3 nv / DIRECTIONS⌉` passes.
pub const DIRECTIONS: usize = 8;

type D<T> = Dual<T, DIRECTIONS>;

/// How [`aba_derivatives`] and [`rnea_derivatives`] differentiate a model without loops, couplings or
/// mimic joints (a model with them always takes dual numbers).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DerivativeMethod {
    /// The recursion over related pairs of coordinates, in each root body's frame (`O(nv · depth)`), and
    /// `∂q̈ = −M⁻¹ ∂τ` for forward dynamics.
    #[default]
    Analytical,
    /// Forward-mode dual numbers through `aba` and `rnea` (`O(nv²)` tangent work): the other method,
    /// exact to rounding as well, for cross-checks.
    DualNumbers,
    /// The recursion of [`DerivativeMethod::Analytical`], but forward dynamics takes `q̈` and
    /// `M⁻¹` from the mass matrix's sparse factorization `M = Lᵀ D L` (from the recursion's composite
    /// inertias) instead of `aba` and the inverse's sweeps: fewer operations on small trees, digits lost
    /// as `cond(M) ε` (which grows as the cube of a chain's length). Generated code takes it where it
    /// runs fewer statements; inverse dynamics' derivatives are the same as `Analytical`'s.
    MassMatrixFactorization,
}

/// What the derivatives need besides the model: the model and a workspace on dual numbers, the dual
/// inputs and a workspace on `T` for the value pass. Made once per model ([`DerivativeWorkspace::new`]);
/// the calls then do not allocate.
pub struct DerivativeWorkspace<T: Real> {
    plain: Workspace<T>,
    model: Model<D<T>>,
    ws: Workspace<D<T>>,
    q0: Vec<D<T>>,
    q: Vec<D<T>>,
    v: Vec<D<T>>,
    u: Vec<D<T>>,
    step: Vec<D<T>>,
    wrenches: Vec<LinkWrench<D<T>>>,
    x: DMatrix<T>,
    /// [`step`]'s configurations (the undisturbed next one as constants, the disturbed one) and output.
    next0: Vec<D<T>>,
    next: Vec<D<T>>,
    out: Vec<D<T>>,
    method: DerivativeMethod,
    /// The analytical recursion's root-frame quantities, and `∂τ` on the way to `∂q̈`.
    analytical: AnalyticalScratch<T>,
    dtau_dq: DMatrix<T>,
    dtau_dv: DMatrix<T>,
    /// `q̈` of the analytical forward derivatives, and [`step_derivatives`]' configuration's part of the
    /// step: `∂q'/∂q` at a fixed step and `∂q'/∂s` for the step `s = dt v'` (block diagonal, one block
    /// per joint).
    qdd: DVector<T>,
    next_dq: DMatrix<T>,
    next_ds: DMatrix<T>,
}

impl<T: Real> DerivativeWorkspace<T> {
    /// That this workspace was made for a model of `model`'s sizes (a workspace of another model is an
    /// error, not an out-of-bounds index).
    fn check_for(&self, model: &Model<T>) -> Result<(), DynamicsError> {
        const OTHER: &str = "DerivativeWorkspace (made for another model)";
        check_len(OTHER, self.q0.len(), model.nq())?;
        check_len(OTHER, self.v.len(), model.nv())?;
        check_len(OTHER, self.x.ncols(), model.independent_nv())?;
        check_len(OTHER, self.model.nbodies(), model.nbodies())?;
        // Same sizes are not the same model (another gravity, a locked joint, other inertias): the
        // numbers the dual passes run on are compared too (O(N), beside passes of O(N²)).
        let same = |a: T, b: D<T>| a.to_f64() == b.re.to_f64();
        let same3 = |a: &nalgebra::Vector3<T>, b: &nalgebra::Vector3<D<T>>| {
            a.iter().zip(b.iter()).all(|(&x, &y)| same(x, y))
        };
        let bodies = model.bodies.iter().zip(&self.model.bodies).all(|(a, b)| {
            same(a.inertia.mass, b.inertia.mass)
                && same3(&a.inertia.first_moment, &b.inertia.first_moment)
                && a.inertia
                    .rotational
                    .iter()
                    .zip(b.inertia.rotational.iter())
                    .all(|(&x, &y)| same(x, y))
        });
        let same_placement = |a: &crate::Transform<T>, b: &crate::Transform<D<T>>| {
            same3(&a.translation, &b.translation)
                && a.rotation
                    .iter()
                    .zip(b.rotation.iter())
                    .all(|(&x, &y)| same(x, y))
        };
        // Everything the dual passes read from the model (an attacker's trial: another armature or a
        // turned placement went through and dual numbers differentiated the old model).
        let joints = model.joints.iter().zip(&self.model.joints).all(|(a, b)| {
            a.joint_type == b.joint_type
                && a.parent == b.parent
                && same3(&a.axis, &b.axis)
                && same_placement(&a.placement, &b.placement)
                && same(a.armature, b.armature)
        });
        let links = model.bodies.iter().zip(&self.model.bodies).all(|(a, b)| {
            a.link_placements.len() == b.link_placements.len()
                && a.link_placements
                    .iter()
                    .zip(&b.link_placements)
                    .all(|(x, y)| same_placement(x, y))
        });
        if bodies && joints && links && same3(&model.gravity, &self.model.gravity) {
            Ok(())
        } else {
            Err(DynamicsError::WrongLength {
                name: OTHER,
                got: self.model.nbodies(),
                expected: model.nbodies(),
            })
        }
    }

    /// The workspace of the last call's value pass (the plain algorithm at the inputs): on a model with
    /// constraints, [`crate::constraints::constraint_condition`] of it is the singularity measure the
    /// derivatives were checked against (generated code returns it instead of refusing).
    pub fn value_workspace(&self) -> &Workspace<T> {
        &self.plain
    }

    /// The method of the calls that follow on a model without constraints (default
    /// [`DerivativeMethod::Analytical`]).
    pub fn set_method(&mut self, method: DerivativeMethod) {
        self.method = method;
    }

    /// `∂q̈/∂q`, `∂q̈/∂v` and `∂q̈/∂τ = M⁻¹` by the analytical recursion into `[dq, dv, dtau]`
    /// (`−M⁻¹ ∂τ` at `q̈ = aba(q, v, τ)`), `q̈` into `self.qdd`.
    fn forward_by_recursion(
        &mut self,
        model: &Model<T>,
        inputs: (&[T], &[T], &[T]),
        f_ext: &[LinkWrench<T>],
        [dq, dv, minv]: [&mut DMatrix<T>; 3],
    ) -> Result<(), DynamicsError> {
        let factors = (
            &mut self.qdd,
            &mut self.dtau_dq,
            &mut self.dtau_dv,
            &mut *minv,
        );
        factors_into(
            model,
            &mut self.plain,
            &mut self.analytical,
            self.method,
            inputs,
            f_ext,
            factors,
        )?;
        forward_partials(model, minv, &self.dtau_dq, dq);
        forward_partials(model, minv, &self.dtau_dv, dv);
        Ok(())
    }

    /// Whether the calls on `model` take the analytical recursion.
    fn analytical(&self, model: &Model<T>) -> bool {
        self.method != DerivativeMethod::DualNumbers && !model.has_constraints()
    }

    /// A workspace for `model`'s derivatives.
    pub fn new(model: &Model<T>) -> Self {
        let dual: Model<D<T>> = model.cast();
        // Everything the calls may need, so that they never allocate.
        let mut ws = Workspace::new(&dual);
        ws.reserve_all(&dual);
        let mut plain = Workspace::new(model);
        plain.reserve_all(model);
        let zero = Dual::constant(T::zero());
        DerivativeWorkspace {
            plain,
            ws,
            q0: vec![zero; model.nq()],
            q: vec![zero; model.nq()],
            v: vec![zero; model.nv()],
            u: vec![zero; model.nv()],
            step: vec![zero; model.nv()],
            wrenches: Vec::with_capacity(model.frames().count()),
            x: DMatrix::zeros(model.nv(), model.independent_nv()),
            next0: vec![zero; model.nq()],
            next: vec![zero; model.nq()],
            out: vec![zero; 2 * model.nv()],
            method: DerivativeMethod::default(),
            analytical: AnalyticalScratch::new(model),
            dtau_dq: DMatrix::zeros(model.nv(), model.nv()),
            dtau_dv: DMatrix::zeros(model.nv(), model.nv()),
            qdd: DVector::zeros(model.nv()),
            next_dq: DMatrix::zeros(model.nv(), model.nv()),
            next_ds: DMatrix::zeros(model.nv(), model.nv()),
            model: dual,
        }
    }
}

/// `aba`'s result and its derivatives (each `nv × nv`; row `i` is `q̈ᵢ`, column `k` a direction in `v`
/// order).
#[derive(Clone, Debug, PartialEq)]
pub struct AbaDerivatives<T: Real> {
    /// `q̈ = aba(q, v, τ)`.
    pub qdd: DVector<T>,
    /// `∂q̈/∂q` (tangent space: column `k` along `integrate(q, ε eₖ)`).
    pub dqdd_dq: DMatrix<T>,
    /// `∂q̈/∂v`.
    pub dqdd_dv: DMatrix<T>,
    /// `∂q̈/∂τ` (`M⁻¹` for a tree).
    pub dqdd_dtau: DMatrix<T>,
}

impl<T: Real> AbaDerivatives<T> {
    /// Zeros of `model`'s sizes.
    pub fn new(model: &Model<T>) -> Self {
        let nv = model.nv();
        AbaDerivatives {
            qdd: DVector::zeros(nv),
            dqdd_dq: DMatrix::zeros(nv, nv),
            dqdd_dv: DMatrix::zeros(nv, nv),
            dqdd_dtau: DMatrix::zeros(nv, nv),
        }
    }
}

/// `rnea`'s result and its derivatives (each `nv × nv`; row `i` is `τᵢ`, column `k` a direction in `v`
/// order).
#[derive(Clone, Debug, PartialEq)]
pub struct RneaDerivatives<T: Real> {
    /// `τ = rnea(q, v, q̈)`.
    pub tau: DVector<T>,
    /// `∂τ/∂q` (tangent space).
    pub dtau_dq: DMatrix<T>,
    /// `∂τ/∂v`.
    pub dtau_dv: DMatrix<T>,
    /// `∂τ/∂q̈`: the mass matrix `M`.
    pub dtau_dqdd: DMatrix<T>,
}

impl<T: Real> RneaDerivatives<T> {
    /// Zeros of `model`'s sizes.
    pub fn new(model: &Model<T>) -> Self {
        let nv = model.nv();
        RneaDerivatives {
            tau: DVector::zeros(nv),
            dtau_dq: DMatrix::zeros(nv, nv),
            dtau_dv: DMatrix::zeros(nv, nv),
            dtau_dqdd: DMatrix::zeros(nv, nv),
        }
    }
}

/// The derivatives of the independent accelerations along the constraint manifold of a model with
/// loops, couplings or mimic joints (`ni` independent coordinates, in the order of
/// [`Model::independent_coordinates`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ManifoldDerivatives<T: Real> {
    /// `q̈_I`, the independent accelerations.
    pub qdd_independent: DVector<T>,
    /// `∂q̈_I/∂q_I` (`ni × ni`): the configuration moving along the manifold, the independent velocities
    /// held and the dependent ones following them.
    pub dqdd_dq: DMatrix<T>,
    /// `∂q̈_I/∂v_I` (`ni × ni`), the dependent velocities following.
    pub dqdd_dv: DMatrix<T>,
    /// `∂q̈_I/∂τ` (`ni × nv`, over the spanning tree's generalized forces).
    pub dqdd_dtau: DMatrix<T>,
}

impl<T: Real> ManifoldDerivatives<T> {
    /// Zeros of `model`'s sizes.
    pub fn new(model: &Model<T>) -> Self {
        let (nv, ni) = (model.nv(), model.independent_nv());
        ManifoldDerivatives {
            qdd_independent: DVector::zeros(ni),
            dqdd_dq: DMatrix::zeros(ni, ni),
            dqdd_dv: DMatrix::zeros(ni, ni),
            dqdd_dtau: DMatrix::zeros(ni, nv),
        }
    }
}

/// Which input a direction moves, and along what (a vector in `v` order).
#[derive(Clone, Copy)]
enum Seed {
    /// The configuration along `integrate(q, ε eₖ)`.
    Configuration(usize),
    /// The velocity along `eₖ`.
    Velocity(usize),
    /// `τ` (or `q̈`) along `eₖ`.
    Input(usize),
    /// The configuration along column `k` of the embedding map (the manifold's tangent).
    ManifoldConfiguration(usize),
    /// The velocity along column `k` of the embedding map.
    ManifoldVelocity(usize),
}

/// Which algorithm a pass differentiates.
#[derive(Clone, Copy, PartialEq)]
enum Pass<T: Real> {
    ForwardDynamics,
    InverseDynamics,
    /// [`step`] with this time step: the output is `[q' ⊖ q'₀; v']` (the configuration's change in the
    /// tangent space at the undisturbed `q'₀`, then the velocity).
    Step(T),
}

/// The derivatives of forward dynamics, `aba(q, v, τ)` with the wrenches `f_ext` held fixed, over the
/// spanning tree's coordinates, into `out`.
///
/// ```
/// # use embedyn_runtime as embedyn; // the facade `embedyn` re-exports this crate
/// use embedyn::nalgebra::{Matrix3, Vector3};
/// use embedyn::{aba_derivatives, AbaDerivatives, DerivativeWorkspace, JointType, Model, SpatialInertia, Transform};
/// // A 1 kg pendulum 0.5 m below its pivot: θ̈ = −m g l sin θ / (m l² + I) + τ / (m l² + I).
/// let mut b = Model::<f64>::builder("pendulum");
/// let inertia = SpatialInertia::from_com(1.0, Vector3::new(0.0, 0.0, -0.5), Matrix3::identity() * 1e-3);
/// b.add_body(None, "pivot", JointType::Revolute, Vector3::x(), Transform::identity(), "bob", inertia)
///     .unwrap();
/// let model = b.build().unwrap();
/// let mut dws = DerivativeWorkspace::new(&model);
/// let mut d = AbaDerivatives::new(&model);
/// aba_derivatives(&model, &mut dws, &[0.3], &[0.0], &[0.0], &[], &mut d).unwrap();
/// let inertia_about_pivot = 0.25 + 1e-3;
/// assert!((d.dqdd_dq[(0, 0)] + 9.81 * 0.5 * 0.3f64.cos() / inertia_about_pivot).abs() < 1e-12);
/// assert!((d.dqdd_dtau[(0, 0)] - 1.0 / inertia_about_pivot).abs() < 1e-12);
/// ```
///
/// # Errors
/// Those of [`crate::aba_ext`] at `(q, v, τ)`.
pub fn aba_derivatives<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    f_ext: &[LinkWrench<T>],
    out: &mut AbaDerivatives<T>,
) -> Result<(), DynamicsError> {
    dws.check_for(model)?;
    check_out(
        model,
        out.qdd.len(),
        &[&out.dqdd_dq, &out.dqdd_dv, &out.dqdd_dtau],
        "AbaDerivatives",
    )?;
    if dws.analytical(model) {
        let derivatives = [&mut out.dqdd_dq, &mut out.dqdd_dv, &mut out.dqdd_dtau];
        dws.forward_by_recursion(model, (q, v, tau), f_ext, derivatives)?;
        out.qdd.copy_from(&dws.qdd);
        return Ok(());
    }
    let qdd = super::aba_ext(model, &mut dws.plain, q, v, tau, f_ext)?;
    out.qdd.copy_from_slice(qdd);
    check_derivative_condition(model, &dws.plain)?;
    let outputs = [&mut out.dqdd_dq, &mut out.dqdd_dv, &mut out.dqdd_dtau];
    spanning_passes(
        model,
        dws,
        Pass::ForwardDynamics,
        (q, v, tau),
        f_ext,
        outputs,
    )
}

/// The factors of [`aba_derivatives`] on a model without loops, couplings or mimic joints: `q̈ = aba(q, v,
/// τ)`, the inverse-dynamics derivatives `∂τ/∂q`, `∂τ/∂v` at that `q̈`, and `M⁻¹`, from which
/// `∂q̈/∂q = −M⁻¹ ∂τ/∂q`, `∂q̈/∂v = −M⁻¹ ∂τ/∂v` and `∂q̈/∂τ = M⁻¹`. Generated code for large trees
/// computes these unrolled and multiplies them in a loop (an unrolled product of a 38-DoF humanoid is
/// 100k operations of straight-line code).
#[derive(Clone, Debug, PartialEq)]
pub struct AbaDerivativeFactors<T: Real> {
    /// `q̈ = aba(q, v, τ)`.
    pub qdd: DVector<T>,
    /// `∂τ/∂q` at `(q, v, q̈)` (tangent space).
    pub dtau_dq: DMatrix<T>,
    /// `∂τ/∂v` at `(q, v, q̈)`.
    pub dtau_dv: DMatrix<T>,
    /// `M⁻¹`.
    pub minv: DMatrix<T>,
}

impl<T: Real> AbaDerivativeFactors<T> {
    /// Zeros of `model`'s sizes.
    pub fn new(model: &Model<T>) -> Self {
        let nv = model.nv();
        AbaDerivativeFactors {
            qdd: DVector::zeros(nv),
            dtau_dq: DMatrix::zeros(nv, nv),
            dtau_dv: DMatrix::zeros(nv, nv),
            minv: DMatrix::zeros(nv, nv),
        }
    }
}

/// [`AbaDerivativeFactors`] at `(q, v, τ)` with the wrenches `f_ext` held fixed.
///
/// # Errors
/// Those of [`crate::aba_ext`] at `(q, v, τ)`; [`DynamicsError::TreeOnly`] on a model
/// with loops, couplings or mimic joints (whose derivatives are not a product of these).
pub fn aba_derivative_factors<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    f_ext: &[LinkWrench<T>],
    out: &mut AbaDerivativeFactors<T>,
) -> Result<(), DynamicsError> {
    dws.check_for(model)?;
    check_out(
        model,
        out.qdd.len(),
        &[&out.dtau_dq, &out.dtau_dv, &out.minv],
        "AbaDerivativeFactors",
    )?;
    if model.has_constraints() {
        return Err(DynamicsError::TreeOnly {
            function: "aba_derivative_factors",
        });
    }
    let factors = (
        &mut out.qdd,
        &mut out.dtau_dq,
        &mut out.dtau_dv,
        &mut out.minv,
    );
    factors_into(
        model,
        &mut dws.plain,
        &mut dws.analytical,
        dws.method,
        (q, v, tau),
        f_ext,
        factors,
    )
}

/// `q̈ = aba(q, v, τ)`, `∂τ/∂q` and `∂τ/∂v` at `q̈`, and `M⁻¹`, into `(qdd, dtau_dq, dtau_dv, minv)`.
#[allow(clippy::type_complexity)]
fn factors_into<T: Real>(
    model: &Model<T>,
    plain: &mut Workspace<T>,
    analytical: &mut AnalyticalScratch<T>,
    method: DerivativeMethod,
    (q, v, tau): (&[T], &[T], &[T]),
    f_ext: &[LinkWrench<T>],
    (qdd, dtau_dq, dtau_dv, minv): (
        &mut DVector<T>,
        &mut DMatrix<T>,
        &mut DMatrix<T>,
        &mut DMatrix<T>,
    ),
) -> Result<(), DynamicsError> {
    if method == DerivativeMethod::MassMatrixFactorization {
        return forward_factors_by_mass_matrix(
            model,
            plain,
            analytical,
            (q, v, tau),
            f_ext,
            (qdd, dtau_dq, dtau_dv, minv),
        );
    }
    qdd.copy_from_slice(super::aba_ext(model, plain, q, v, tau, f_ext)?);
    let partials = InverseDynamicsPartials {
        dtau_dq,
        dtau_dv,
        mass_matrix: None,
    };
    rnea_partials(
        model,
        plain,
        analytical,
        (q, v, qdd.as_slice()),
        f_ext,
        partials,
    )?;
    minv.copy_from(super::mass_matrix_inverse(model, plain, q)?);
    Ok(())
}

/// The derivatives of inverse dynamics, `rnea(q, v, q̈)` with the wrenches `f_ext` held fixed, into
/// `out` (`∂τ/∂q̈` is the mass matrix).
///
/// # Errors
/// Those of [`crate::rnea_ext`] at `(q, v, q̈)`.
pub fn rnea_derivatives<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    q: &[T],
    v: &[T],
    qdd: &[T],
    f_ext: &[LinkWrench<T>],
    out: &mut RneaDerivatives<T>,
) -> Result<(), DynamicsError> {
    dws.check_for(model)?;
    check_out(
        model,
        out.tau.len(),
        &[&out.dtau_dq, &out.dtau_dv, &out.dtau_dqdd],
        "RneaDerivatives",
    )?;
    if dws.analytical(model) {
        let partials = InverseDynamicsPartials {
            dtau_dq: &mut out.dtau_dq,
            dtau_dv: &mut out.dtau_dv,
            mass_matrix: Some(&mut out.dtau_dqdd),
        };
        rnea_partials(
            model,
            &mut dws.plain,
            &mut dws.analytical,
            (q, v, qdd),
            f_ext,
            partials,
        )?;
        out.tau.copy_from_slice(&dws.plain.tau);
        return Ok(());
    }
    let tau = super::rnea_ext(model, &mut dws.plain, q, v, qdd, f_ext)?;
    out.tau.copy_from_slice(tau);
    let outputs = [&mut out.dtau_dq, &mut out.dtau_dv, &mut out.dtau_dqdd];
    spanning_passes(
        model,
        dws,
        Pass::InverseDynamics,
        (q, v, qdd),
        f_ext,
        outputs,
    )
}

/// The derivatives of the independent accelerations along the constraint manifold (see
/// [`ManifoldDerivatives`]); `q` and `v` must satisfy the constraints, as for [`crate::aba`]. On a model
/// without constraints they are [`aba_derivatives`]' matrices.
///
/// # Errors
/// Those of [`crate::aba_ext`] at `(q, v, τ)`, and [`DynamicsError::SingularConstraint`] from the
/// embedding map.
pub fn aba_derivatives_independent<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    f_ext: &[LinkWrench<T>],
    out: &mut ManifoldDerivatives<T>,
) -> Result<(), DynamicsError> {
    dws.check_for(model)?;
    let (nv, ni) = (model.nv(), model.independent_nv());
    // Every block's shape, so that one mis-sized block is an error rather than an index panic.
    const NAME: &str = "ManifoldDerivatives";
    check_len(NAME, out.qdd_independent.len(), ni)?;
    for (m, cols) in [(&out.dqdd_dq, ni), (&out.dqdd_dv, ni), (&out.dqdd_dtau, nv)] {
        check_len(NAME, m.nrows(), ni)?;
        check_len(NAME, m.ncols(), cols)?;
    }
    let qdd = super::aba_ext(model, &mut dws.plain, q, v, tau, f_ext)?;
    for (r, i) in model.independent_coordinates().enumerate() {
        out.qdd_independent[r] = qdd[i];
    }
    check_derivative_condition(model, &dws.plain)?;
    let x = super::embedding_map_in(model, &mut dws.plain, q)?;
    dws.x.copy_from(x);
    let seed = |c: usize| {
        if c < ni {
            Seed::ManifoldConfiguration(c)
        } else if c < 2 * ni {
            Seed::ManifoldVelocity(c - ni)
        } else {
            Seed::Input(c - 2 * ni)
        }
    };
    passes(
        model,
        dws,
        Pass::ForwardDynamics,
        (q, v, tau),
        f_ext,
        2 * ni + nv,
        seed,
        |c, result, lane| {
            let (matrix, col) = if c < ni {
                (&mut out.dqdd_dq, c)
            } else if c < 2 * ni {
                (&mut out.dqdd_dv, c - ni)
            } else {
                (&mut out.dqdd_dtau, c - 2 * ni)
            };
            for (r, i) in model.independent_coordinates().enumerate() {
                matrix[(r, col)] = result[i].eps[lane];
            }
        },
    )
}

/// One step of semi-implicit (symplectic) Euler: `v' = v + dt · aba(q, v, τ)`, then `q' = q ⊕ dt · v'`
/// ([`integrate`](crate::integrate)), the wrenches `f_ext` held over the step. Leaves `dt · v'` in
/// `ws.qdd`. On a model with constraints it steps the spanning tree's coordinates (the next state satisfies
/// the constraints to first order in `dt`; `complete` projects it back).
///
/// # Errors
/// Those of [`crate::aba_ext`] at `(q, v, τ)`; [`DynamicsError::NonFiniteScalar`] for a `dt` that is NaN or
/// infinite, [`DynamicsError::NonFiniteInput`] naming `dt · v_next` where the step overflows (a huge `dt`);
/// [`DynamicsError::WrongLength`] for a `q_next` or `v_next` of the wrong length.
#[allow(clippy::too_many_arguments)]
pub fn step<T: Real>(
    model: &Model<T>,
    ws: &mut Workspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    dt: T,
    f_ext: &[LinkWrench<T>],
    q_next: &mut [T],
    v_next: &mut [T],
) -> Result<(), DynamicsError> {
    check_step(model, dt, q_next, v_next)?;
    super::aba_ext(model, ws, q, v, tau, f_ext)?;
    advance(model, (q, v), &mut ws.qdd, dt, q_next, v_next)
}

/// [`step`]'s checks of what is not an input of the dynamics: `dt` and the outputs' lengths.
fn check_step<T: Real>(
    model: &Model<T>,
    dt: T,
    q_next: &[T],
    v_next: &[T],
) -> Result<(), DynamicsError> {
    if let Some(value) = dt.value().filter(|x| !x.is_finite()) {
        return Err(DynamicsError::NonFiniteScalar { name: "dt", value });
    }
    check_len("q_next", q_next.len(), model.nq())?;
    check_len("v_next", v_next.len(), model.nv())
}

/// The step from `q̈`: `v' = v + dt q̈`, `q' = q ⊕ dt v'`; `qdd` is left holding `dt v'`.
fn advance<T: Real>(
    model: &Model<T>,
    (q, v): (&[T], &[T]),
    qdd: &mut [T],
    dt: T,
    q_next: &mut [T],
    v_next: &mut [T],
) -> Result<(), DynamicsError> {
    for i in 0..model.nv() {
        v_next[i] = v[i] + dt * qdd[i];
        qdd[i] = dt * v_next[i];
        // A finite state can overflow in the step (a huge dt): name the step, not the input `v` that
        // `integrate` would see.
        if let Some(value) = qdd[i].value().filter(|x| !x.is_finite()) {
            return Err(DynamicsError::NonFiniteInput {
                name: "dt · v_next",
                index: i,
                value,
            });
        }
    }
    crate::configuration::integrate(model, q, qdd, q_next)
}

/// [`step`]'s next state and its Jacobian with respect to `(q, v, τ)` (each block `nv × nv`; row and
/// column perturbations of a configuration are in the tangent space: column `k` of a `∂/∂q` along
/// `integrate(q, ε eₖ)`, row `i` of a `∂q'` the `i`-th entry of `difference(q'₀, q'(ε))`) — the block a
/// multiple-shooting solver linearizes each knot with.
#[derive(Clone, Debug, PartialEq)]
pub struct StepDerivatives<T: Real> {
    /// `q'`.
    pub q_next: DVector<T>,
    /// `v'`.
    pub v_next: DVector<T>,
    /// `∂q'/∂q`.
    pub dq_next_dq: DMatrix<T>,
    /// `∂q'/∂v`.
    pub dq_next_dv: DMatrix<T>,
    /// `∂q'/∂τ`.
    pub dq_next_dtau: DMatrix<T>,
    /// `∂v'/∂q`.
    pub dv_next_dq: DMatrix<T>,
    /// `∂v'/∂v`.
    pub dv_next_dv: DMatrix<T>,
    /// `∂v'/∂τ` (`dt · M⁻¹` for a tree).
    pub dv_next_dtau: DMatrix<T>,
}

impl<T: Real> StepDerivatives<T> {
    /// Zeros of `model`'s sizes.
    pub fn new(model: &Model<T>) -> Self {
        let (nq, nv) = (model.nq(), model.nv());
        let zero = || DMatrix::zeros(nv, nv);
        StepDerivatives {
            q_next: DVector::zeros(nq),
            v_next: DVector::zeros(nv),
            dq_next_dq: zero(),
            dq_next_dv: zero(),
            dq_next_dtau: zero(),
            dv_next_dq: zero(),
            dv_next_dv: zero(),
            dv_next_dtau: zero(),
        }
    }
}

/// [`step`] and its Jacobian (see [`StepDerivatives`]), by dual numbers through the step itself: the
/// forward dynamics, the velocity update, `integrate`, and `difference` against the undisturbed next
/// configuration.
///
/// # Errors
/// Those of [`step`].
#[allow(clippy::too_many_arguments)]
pub fn step_derivatives<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    q: &[T],
    v: &[T],
    tau: &[T],
    dt: T,
    f_ext: &[LinkWrench<T>],
    out: &mut StepDerivatives<T>,
) -> Result<(), DynamicsError> {
    dws.check_for(model)?;
    let nv = model.nv();
    check_len("StepDerivatives q_next", out.q_next.len(), model.nq())?;
    check_out(
        model,
        out.v_next.len(),
        &[
            &out.dq_next_dq,
            &out.dq_next_dv,
            &out.dq_next_dtau,
            &out.dv_next_dq,
            &out.dv_next_dv,
            &out.dv_next_dtau,
        ],
        "StepDerivatives",
    )?;
    if dws.analytical(model) {
        return step_by_chain_rule(model, dws, (q, v, tau), dt, f_ext, out);
    }
    step(
        model,
        &mut dws.plain,
        q,
        v,
        tau,
        dt,
        f_ext,
        out.q_next.as_mut_slice(),
        out.v_next.as_mut_slice(),
    )?;
    check_derivative_condition(model, &dws.plain)?;
    for (d, &x) in dws.next0.iter_mut().zip(out.q_next.iter()) {
        *d = Dual::constant(x);
    }
    let StepDerivatives {
        dq_next_dq,
        dq_next_dv,
        dq_next_dtau,
        dv_next_dq,
        dv_next_dv,
        dv_next_dtau,
        ..
    } = out;
    passes(
        model,
        dws,
        Pass::Step(dt),
        (q, v, tau),
        f_ext,
        3 * nv,
        |c| spanning_seed(c, nv),
        |c, result, lane| {
            let (dq, dv) = match c / nv {
                0 => (&mut *dq_next_dq, &mut *dv_next_dq),
                1 => (&mut *dq_next_dv, &mut *dv_next_dv),
                _ => (&mut *dq_next_dtau, &mut *dv_next_dtau),
            };
            for r in 0..nv {
                dq[(r, c % nv)] = result[r].eps[lane];
                dv[(r, c % nv)] = result[nv + r].eps[lane];
            }
        },
    )
}

/// [`step_derivatives`] on a tree by the chain rule through `v' = v + dt q̈` and `q' = integrate(q, s)`
/// (the step's `q̈` is the recursion's, so `aba` runs once),
/// `s = dt v'`: `∂q̈` by the analytical recursion, and the configuration's part, `∂q'/∂q` at a fixed `s`
/// and `∂q'/∂s` (block diagonal: a joint's coordinates move only its own; the identity but for a free
/// flyer), by dual numbers through `integrate` and `difference` alone. Then
/// `∂v'/∂x = ∂v/∂x + dt ∂q̈/∂x` and `∂q'/∂x = ∂q'/∂q · ∂q/∂x + ∂q'/∂s · dt ∂v'/∂x`.
fn step_by_chain_rule<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    (q, v, tau): (&[T], &[T], &[T]),
    dt: T,
    f_ext: &[LinkWrench<T>],
    out: &mut StepDerivatives<T>,
) -> Result<(), DynamicsError> {
    let nv = model.nv();
    check_step(model, dt, out.q_next.as_slice(), out.v_next.as_slice())?;
    // ∂q̈/∂q, ∂q̈/∂v and M⁻¹ into the ∂v' blocks, then v' = v + dt q̈.
    let derivatives = [
        &mut out.dv_next_dq,
        &mut out.dv_next_dv,
        &mut out.dv_next_dtau,
    ];
    dws.forward_by_recursion(model, (q, v, tau), f_ext, derivatives)?;
    // The step itself from the recursion's q̈ (the same `aba_ext`'s): `step` would run `aba` again.
    advance(
        model,
        (q, v),
        dws.qdd.as_mut_slice(),
        dt,
        out.q_next.as_mut_slice(),
        out.v_next.as_mut_slice(),
    )?;
    for (d, &x) in dws.next0.iter_mut().zip(out.q_next.iter()) {
        *d = Dual::constant(x);
    }
    for m in [
        &mut out.dv_next_dq,
        &mut out.dv_next_dv,
        &mut out.dv_next_dtau,
    ] {
        for x in m.iter_mut() {
            *x = dt * *x;
        }
    }
    for i in 0..nv {
        out.dv_next_dv[(i, i)] += T::one();
    }
    configuration_step_partials(model, dws, q, out.v_next.as_slice(), dt)?;
    // ∂q'/∂x, joint by joint (the blocks of ∂q'/∂q and ∂q'/∂s are the joint's own).
    for joint in &model.joints {
        let rows = joint.v_range();
        for r in rows.clone() {
            for c in 0..nv {
                let through = |m: &DMatrix<T>| {
                    let mut sum = T::zero();
                    for k in rows.clone() {
                        sum += dws.next_ds[(r, k)] * (dt * m[(k, c)]);
                    }
                    sum
                };
                let mut dq = through(&out.dv_next_dq);
                if rows.contains(&c) {
                    dq += dws.next_dq[(r, c)];
                }
                out.dq_next_dq[(r, c)] = dq;
                out.dq_next_dv[(r, c)] = through(&out.dv_next_dv);
                out.dq_next_dtau[(r, c)] = through(&out.dv_next_dtau);
            }
        }
    }
    Ok(())
}

/// The blocks of `∂(q' ⊖ q'₀)/∂q` at a fixed step and of `∂(q' ⊖ q'₀)/∂s`, `q' = integrate(q, s)` at
/// `s = dt v'`, into `dws.next_dq` and `dws.next_ds` (`dws.next0` holds the undisturbed `q'₀`): dual
/// numbers through `integrate` and `difference`, [`DIRECTIONS`] at a time.
fn configuration_step_partials<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    q: &[T],
    v_next: &[T],
    dt: T,
) -> Result<(), DynamicsError> {
    let nv = model.nv();
    for (d, &x) in dws.q0.iter_mut().zip(q) {
        *d = Dual::constant(x);
    }
    dws.next_dq.fill(T::zero());
    dws.next_ds.fill(T::zero());
    let mut start = 0;
    while start < 2 * nv {
        let n = DIRECTIONS.min(2 * nv - start);
        for ((step, s), &v) in dws.step.iter_mut().zip(dws.v.iter_mut()).zip(v_next) {
            *step = Dual::constant(T::zero());
            *s = Dual::constant(dt * v);
        }
        for lane in 0..n {
            let c = start + lane;
            if c < nv {
                dws.step[c].eps[lane] = T::one();
            } else {
                dws.v[c - nv].eps[lane] = T::one();
            }
        }
        crate::configuration::integrate(&dws.model, &dws.q0, &dws.step, &mut dws.q)?;
        crate::configuration::integrate(&dws.model, &dws.q, &dws.v, &mut dws.next)?;
        let (displacement, _) = dws.out.split_at_mut(nv);
        crate::configuration::difference(&dws.model, &dws.next0, &dws.next, displacement)?;
        for lane in 0..n {
            let c = start + lane;
            let (matrix, col) = if c < nv {
                (&mut dws.next_dq, c)
            } else {
                (&mut dws.next_ds, c - nv)
            };
            // Only the column's own joint moves.
            let joint = model
                .joints
                .iter()
                .find(|j| j.v_range().contains(&col))
                .expect("every velocity coordinate has a joint");
            for r in joint.v_range() {
                matrix[(r, col)] = dws.out[r].eps[lane];
            }
        }
        start += n;
    }
    Ok(())
}

fn check_out<T: Real>(
    model: &Model<T>,
    len: usize,
    matrices: &[&DMatrix<T>],
    name: &'static str,
) -> Result<(), DynamicsError> {
    check_len(name, len, model.nv())?;
    for m in matrices {
        check_len(name, m.nrows(), model.nv())?;
        check_len(name, m.ncols(), model.nv())?;
    }
    Ok(())
}

/// On a model with constraints the derivatives differentiate through `Y1⁻¹`, whose derivative
/// `−Y1⁻¹ dY1 Y1⁻¹` amplifies rounding by cond₁(Y1)²: they are refused from the square root of the values'
/// singularity threshold (1e5 in f64, about 92 in f32), where about three digits are left, rather than
/// returned quietly wrong near a toggle. Reads the condition of the last value pass on `plain`.
fn check_derivative_condition<T: Real>(
    model: &Model<T>,
    plain: &Workspace<T>,
) -> Result<(), DynamicsError> {
    let threshold = derivative_singularity_threshold::<T>();
    for (g, gw) in model.groups.iter().zip(&plain.constraints.groups) {
        if let Some(c) = gw.condition.value() {
            if c.is_nan() || c >= threshold {
                return Err(DynamicsError::SingularConstraint {
                    group: crate::constraints::ConstraintSet::Group(g.label.clone()),
                    condition: c,
                    threshold,
                });
            }
        }
    }
    Ok(())
}

/// cond₁(Y1) at or above which the derivatives on a model with constraints are refused in the scalar
/// type `T`: the square root of [`crate::constraints::singularity_threshold`] (1e5 in f64, about 92 in
/// f32), because the derivatives' rounding grows as cond₁(Y1)² where the values' grows as cond₁(Y1).
pub fn derivative_singularity_threshold<T: Real>() -> f64 {
    crate::constraints::singularity_threshold::<T>().sqrt()
}

/// Spanning direction `c` of `3 nv`: the configuration's, the velocity's, then τ's (or q̈'s) coordinates.
fn spanning_seed(c: usize, nv: usize) -> Seed {
    match c / nv {
        0 => Seed::Configuration(c % nv),
        1 => Seed::Velocity(c % nv),
        _ => Seed::Input(c % nv),
    }
}

/// The `3 nv` spanning directions (configuration, velocity, then τ or q̈), each output tangent written as
/// a column of `outputs[0..3]`.
fn spanning_passes<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    pass: Pass<T>,
    inputs: (&[T], &[T], &[T]),
    f_ext: &[LinkWrench<T>],
    outputs: [&mut DMatrix<T>; 3],
) -> Result<(), DynamicsError> {
    let nv = model.nv();
    let [dq, dv, du] = outputs;
    passes(
        model,
        dws,
        pass,
        inputs,
        f_ext,
        3 * nv,
        |c| spanning_seed(c, nv),
        |c, result, lane| {
            let matrix = match c / nv {
                0 => &mut *dq,
                1 => &mut *dv,
                _ => &mut *du,
            };
            for (r, x) in result.iter().enumerate() {
                matrix[(r, c % nv)] = x.eps[lane];
            }
        },
    )
}

/// Directions `0..total` (`seed(c)` says what direction `c` moves) in passes of [`DIRECTIONS`]; after
/// each pass `write(c, output, lane)` for each of its directions.
#[allow(clippy::too_many_arguments)]
fn passes<T: Real>(
    model: &Model<T>,
    dws: &mut DerivativeWorkspace<T>,
    pass: Pass<T>,
    (q, v, u): (&[T], &[T], &[T]),
    f_ext: &[LinkWrench<T>],
    total: usize,
    seed: impl Fn(usize) -> Seed,
    mut write: impl FnMut(usize, &[D<T>], usize),
) -> Result<(), DynamicsError> {
    let mut seeds = [Seed::Input(0); DIRECTIONS];
    let mut start = 0;
    while start < total {
        let n = DIRECTIONS.min(total - start);
        for (lane, s) in seeds.iter_mut().take(n).enumerate() {
            *s = seed(start + lane);
        }
        let result = dual_pass(model, dws, pass, q, v, u, f_ext, &seeds[..n])?;
        for lane in 0..n {
            write(start + lane, result, lane);
        }
        start += n;
    }
    Ok(())
}

/// One pass on dual numbers: the inputs seeded along `seeds` (one lane each), the algorithm run, its
/// output returned (`q̈` or `τ` over the spanning tree, tangents in the lanes).
#[allow(clippy::too_many_arguments)]
fn dual_pass<'w, T: Real>(
    model: &Model<T>,
    dws: &'w mut DerivativeWorkspace<T>,
    pass: Pass<T>,
    q: &[T],
    v: &[T],
    u: &[T],
    f_ext: &[LinkWrench<T>],
    seeds: &[Seed],
) -> Result<&'w [D<T>], DynamicsError> {
    let nv = model.nv();
    for (d, &x) in dws.q0.iter_mut().zip(q) {
        *d = Dual::constant(x);
    }
    for i in 0..nv {
        dws.step[i] = Dual::constant(T::zero());
        dws.v[i] = Dual::constant(v[i]);
        dws.u[i] = Dual::constant(u[i]);
    }
    let mut follow_velocity = false;
    for (lane, seed) in seeds.iter().enumerate() {
        match *seed {
            Seed::Configuration(k) => dws.step[k].eps[lane] = T::one(),
            Seed::Velocity(k) => dws.v[k].eps[lane] = T::one(),
            Seed::Input(k) => dws.u[k].eps[lane] = T::one(),
            Seed::ManifoldConfiguration(k) => {
                for i in 0..nv {
                    dws.step[i].eps[lane] = dws.x[(i, k)];
                }
                follow_velocity = true;
            }
            Seed::ManifoldVelocity(k) => {
                for i in 0..nv {
                    dws.v[i].eps[lane] = dws.x[(i, k)];
                }
                follow_velocity = true;
            }
        }
    }
    crate::configuration::integrate(&dws.model, &dws.q0, &dws.step, &mut dws.q)?;
    if follow_velocity {
        // The dependent velocities at the moved configuration: X(q(ε)) v_I, whose tangent holds ∂X v_I.
        crate::constraints::complete_velocity(&dws.model, &mut dws.ws, &dws.q, &mut dws.v)?;
    }
    dws.wrenches.clear();
    dws.wrenches.extend(f_ext.iter().map(|w| LinkWrench {
        frame: w.frame,
        force: w.force.map(Dual::constant),
        torque: w.torque.map(Dual::constant),
    }));
    match pass {
        Pass::ForwardDynamics => super::aba_ext(
            &dws.model,
            &mut dws.ws,
            &dws.q,
            &dws.v,
            &dws.u,
            &dws.wrenches,
        ),
        Pass::InverseDynamics => super::rnea_ext(
            &dws.model,
            &mut dws.ws,
            &dws.q,
            &dws.v,
            &dws.u,
            &dws.wrenches,
        ),
        Pass::Step(dt) => {
            let dt = Dual::constant(dt);
            let qdd = super::aba_ext(
                &dws.model,
                &mut dws.ws,
                &dws.q,
                &dws.v,
                &dws.u,
                &dws.wrenches,
            )?;
            for (i, &a) in qdd.iter().enumerate() {
                let v_next = dws.v[i] + dt * a;
                dws.out[nv + i] = v_next;
                dws.step[i] = dt * v_next;
            }
            crate::configuration::integrate(&dws.model, &dws.q, &dws.step, &mut dws.next)?;
            let (displacement, _) = dws.out.split_at_mut(nv);
            crate::configuration::difference(&dws.model, &dws.next0, &dws.next, displacement)?;
            Ok(&dws.out)
        }
    }
}

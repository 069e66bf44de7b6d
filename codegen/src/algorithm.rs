//! What an algorithm is, in one place: its name, arguments, outputs, documentation, when it is generated,
//! what it returns, how it is traced and whether the command line offers it. Everything that lists or
//! describes algorithms — the generator, the `robot!` macro's options, build.rs, the standalone crate's
//! README, the `embedyn` command line (`--algo`, `--only`, the cached runner, `bench`) and the docs table
//! (checked in a test) — reads [`ALGORITHMS`]. Adding an algorithm is its runtime implementation and one
//! entry here.

use crate::trace::Sym;
use embedyn_runtime::constraints::{completion_step, constraint_condition};
use embedyn_runtime::nalgebra::{Matrix3xX, Matrix6xX, Vector3};
use embedyn_runtime::{
    aba, aba_derivative_factors, aba_derivatives, aba_derivatives_independent, aba_ext,
    center_of_mass, centroidal_momentum_matrix, centroidal_momentum_rate, com_jacobian, crba,
    difference, embedding_map_in, forward_kinematics, forward_kinematics_acceleration,
    frame_classical_acceleration, frame_jacobian, frame_placement, gravity, integrate, link_poses,
    mass_matrix_inverse, nle, nle_ext, reduced_mass_matrix_in, rnea, rnea_derivatives, rnea_ext,
    step, step_derivatives, AbaDerivativeFactors, AbaDerivatives, DerivativeMethod,
    DerivativeWorkspace, DynamicsError, FrameId, LinkWrench, ManifoldDerivatives, Model, Real,
    Reference, RneaDerivatives, StepDerivatives, Workspace,
};

/// The algorithms code can be generated for; [`Algorithm::spec`] describes each.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Algorithm {
    /// `kinematics`: the world pose of every link on a moving body.
    Kinematics,
    /// `aba`: forward dynamics.
    Aba,
    /// `rnea`: inverse dynamics.
    Rnea,
    /// `gravity`: the generalized gravity `g(q)`.
    Gravity,
    /// `nle`: the nonlinear effects `C(q, v) v + g(q)`.
    Nle,
    /// `crba`: the mass matrix.
    Crba,
    /// `minv`: the inverse mass matrix.
    Minv,
    /// `complete`: position completion (models with constraints).
    Complete,
    /// `embedding`: the embedding map `X` (models with constraints).
    Embedding,
    /// `crba_independent`: `Xᵀ M X` (models with constraints).
    CrbaIndependent,
    /// `integrate`: `q ⊕ v` on the configuration space.
    Integrate,
    /// `difference`: `q1 ⊖ q`, the velocity that `integrate` takes from `q` to `q1`.
    Difference,
    /// `aba_ext`: forward dynamics with the wrenches of the links named at generation time.
    AbaExt,
    /// `rnea_ext`: inverse dynamics with the wrenches of the links named at generation time.
    RneaExt,
    /// `nle_ext`: the nonlinear effects with the wrenches of the links named at generation time.
    NleExt,
    /// `frame_<link>`: pose, Jacobian and bias of one link named at generation time.
    Frame,
    /// `com`: centre of mass, its velocity and Jacobian.
    Com,
    /// `centroidal`: centroidal momentum and its matrix (`h_g`, `A_g`).
    Centroidal,
    /// `centroidal_bias`: `Ȧ_g v`.
    CentroidalBias,
    /// `aba_derivatives`: forward dynamics and its derivatives with respect to `q`, `v` and `τ`.
    AbaDerivatives,
    /// `rnea_derivatives`: inverse dynamics and its derivatives with respect to `q`, `v` and `q̈`.
    RneaDerivatives,
    /// `step`: one semi-implicit Euler step.
    Step,
    /// `step_derivatives`: one semi-implicit Euler step and its Jacobian.
    StepDerivatives,
    /// `aba_derivatives_independent`: the independent accelerations' derivatives along the constraint
    /// manifold (models with constraints).
    AbaDerivativesIndependent,
    /// `aba_derivatives_ext`: `aba_derivatives` with the wrenches of the links named at generation time.
    AbaDerivativesExt,
    /// `rnea_derivatives_ext`: `rnea_derivatives` with the wrenches of the links named at generation
    /// time.
    RneaDerivativesExt,
}

/// A length of an argument or an output, in the model's terms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dim {
    /// `NQ`, the number of position coordinates.
    Nq,
    /// `NV`, the number of velocity coordinates.
    Nv,
    /// `NI`, the number of independent velocity coordinates.
    Ni,
    /// `FRAMES.len()`, the links on moving bodies.
    Frames,
    /// `WRENCH_LINKS.len()`, the links named at generation time to take external wrenches.
    WrenchLinks,
    /// A fixed length.
    Fixed(usize),
    /// A single number passed by value (`dt: S`), not an array.
    Scalar,
}

/// The sizes of one model that [`Dim`]s resolve to.
#[derive(Clone, Copy, Debug)]
pub struct Dims {
    /// Length of `q`.
    pub nq: usize,
    /// Length of `v`.
    pub nv: usize,
    /// Number of independent velocities.
    pub ni: usize,
    /// Number of links on moving bodies.
    pub frames: usize,
    /// Number of links named to take external wrenches (0 unless the generator sets it).
    pub wrench_links: usize,
}

impl Dims {
    /// The sizes of `model`.
    pub fn of<T: embedyn_runtime::Real>(model: &Model<T>) -> Dims {
        Dims {
            nq: model.nq(),
            nv: model.nv(),
            ni: model.independent_nv(),
            frames: model.bodies.iter().map(|b| b.links.len()).sum(),
            wrench_links: 0,
        }
    }
}

impl Dim {
    /// The length on a model of these sizes.
    pub fn len(self, dims: &Dims) -> usize {
        match self {
            Dim::Nq => dims.nq,
            Dim::Nv => dims.nv,
            Dim::Ni => dims.ni,
            Dim::Frames => dims.frames,
            Dim::WrenchLinks => dims.wrench_links,
            Dim::Fixed(n) => n,
            Dim::Scalar => 1,
        }
    }

    /// The length as generated code spells it (`NV`, `FRAMES.len()`, `12`).
    pub fn code(self) -> String {
        match self {
            Dim::Nq => "NQ".into(),
            Dim::Nv => "NV".into(),
            Dim::Ni => "NI".into(),
            Dim::Frames => "FRAMES.len()".into(),
            Dim::WrenchLinks => "WRENCH_LINKS.len()".into(),
            Dim::Fixed(n) => n.to_string(),
            Dim::Scalar => "1".into(),
        }
    }
}

/// One argument of a generated function: `name: &[S; len]`, or `name: &[[S; columns]; len]`.
#[derive(Clone, Copy, Debug)]
pub struct InputSpec {
    /// The argument's name.
    pub name: &'static str,
    /// Its length (its number of rows when it has `columns`).
    pub len: Dim,
    /// The length of each row of a matrix argument (`f_ext`: 6); `None` for a vector.
    pub columns: Option<usize>,
    /// Physical units of the entries.
    pub unit: &'static str,
}

/// The shape of an output.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// `&mut [S; n]`.
    Vector(Dim),
    /// `&mut [[S; cols]; rows]`, written row-major.
    Matrix(Dim, Dim),
}

/// One output argument of a generated function.
#[derive(Clone, Copy, Debug)]
pub struct OutputSpec {
    /// The argument's name.
    pub name: &'static str,
    /// Its shape.
    pub shape: Shape,
    /// Physical units of the entries.
    pub unit: &'static str,
}

/// The scalar a generated function returns (`-> S`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Returns {
    /// Nothing.
    Nothing,
    /// For a model with constraints, the singularity measure cond₁(Y1), to be compared with the scalar
    /// module's `SINGULARITY_THRESHOLD`; nothing for a tree.
    SingularityMeasure,
    /// The largest relative residual of the constraint equations.
    Residual,
}

/// When a function is generated without `only(…)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WhenGenerated {
    /// Always.
    ByDefault,
    /// For a model with loops, couplings or mimic joints.
    WithConstraints,
    /// When asked for by name (its own option of the macro and of `embedyn generate`, `--minv`).
    OnRequest,
    /// When the links its [`Parameter`] reads are named (`wrenches(…)`: `aba_ext`, `rnea_ext`;
    /// `frames(…)`: one `frame_<link>` per link).
    WithLinks,
}

/// What a function is generated for beyond the model: links named at generation time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parameter {
    /// Nothing: one function per model, named as the algorithm.
    None,
    /// The links that take external wrenches (macro `wrenches(…)`, `embedyn generate --wrenches`), in the
    /// order named (`WRENCH_LINKS`): the input `f_ext` has one row `[fx, fy, fz, tx, ty, tz]` per link, in
    /// that link's frame about its origin. Other links take none and cost nothing.
    WrenchLinks,
    /// One link (macro `frames(…)`, `--frames`): one function per link named, `frame_<link>` (the link's
    /// name through the sanitizer, as the index constants spell it, in snake_case), in the reference
    /// chosen (`reference = …`, `--reference`; default `local_world_aligned`).
    Frame,
}

/// The links a function is generated for, found on the model (see [`Parameter`]).
#[derive(Clone, Copy, Debug)]
pub struct Links<'a> {
    /// The frames whose wrenches `f_ext` holds, in its row order.
    pub wrenches: &'a [FrameId],
    /// The frame of a `frame_<link>` function.
    pub frame: Option<FrameId>,
    /// Where a frame function expresses its Jacobian and bias.
    pub reference: Reference,
}

impl Links<'_> {
    /// No links: what a function of [`Parameter::None`] is traced with.
    pub const NONE: Links<'static> = Links {
        wrenches: &[],
        frame: None,
        reference: Reference::LocalWorldAligned,
    };
}

/// How fast a function's code grows with the model (for the size guard's advice).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Growth {
    /// With the number of degrees of freedom.
    Linear,
    /// With the square of the number of degrees of freedom.
    Quadratic,
}

/// The model's numbers the size guard predicts a function's operations from (see `size.rs`).
#[derive(Clone, Copy, Debug)]
pub struct SizeCounts {
    /// Degrees of freedom.
    pub nv: f64,
    /// Independent degrees of freedom.
    pub ni: f64,
    /// Links on moving bodies.
    pub links: f64,
    /// Operations of `crba`: 24 per pair of degrees of freedom on one branch, 30 per degree of freedom.
    pub crba: f64,
}

/// What tracing an algorithm gives: each output's values (row-major) in the order of
/// [`AlgorithmSpec::outputs`], and the returned scalar.
pub struct Traced {
    /// Each output's values, row-major.
    pub outputs: Vec<Vec<Sym>>,
    /// The returned scalar, if the function returns one.
    pub returned: Option<Sym>,
}

/// The `embedyn` command line's view of an algorithm.
#[derive(Clone, Copy, Debug)]
pub struct CliSpec {
    /// The help of the `--algo` value.
    pub help: &'static str,
    /// The function that computes what the command reports for a model with constraints, when that is
    /// not this one (`crba` reports `Xᵀ M X`, `crba_independent`).
    pub with_constraints: Option<Algorithm>,
    /// Whether `embedyn bench` times it (on its random states `(q, v, x)`).
    pub timed: bool,
}

/// Runs an algorithm on the traced scalar (inputs in the order of [`AlgorithmSpec::inputs`], matrices
/// row-major) for the links of its [`Parameter`].
pub type TraceFn =
    fn(&Model<Sym>, &mut Workspace<Sym>, &[Vec<Sym>], &Links) -> Result<Traced, DynamicsError>;

/// Runs the interpreted solver's algorithm in f64 (inputs in the order of [`AlgorithmSpec::inputs`],
/// matrices row-major) for the links of its [`Parameter`].
pub type InterpretedFn =
    fn(&Model<f64>, &mut Workspace<f64>, &[&[f64]], &Links) -> Result<(), DynamicsError>;

/// Everything about one algorithm.
pub struct AlgorithmSpec {
    /// Which algorithm this describes.
    pub algorithm: Algorithm,
    /// The generated function's name, also the name in `only(…)`, `--only` and `--algo`.
    pub name: &'static str,
    /// The name of the traced function when it differs (`complete` iterates `complete_step`).
    pub traced_name: &'static str,
    /// The items written after the traced function, which call it (`complete`'s Newton iteration).
    pub wrapper: Option<fn() -> proc_macro2::TokenStream>,
    /// One line: what it computes (docs/generated-code.md's table).
    pub summary: &'static str,
    /// The generated function's documentation.
    pub doc: &'static str,
    /// The documentation for a model with constraints, when it differs.
    pub doc_with_constraints: Option<&'static str>,
    /// The inputs, in argument order.
    pub inputs: &'static [InputSpec],
    /// The outputs, in argument order after the inputs.
    pub outputs: &'static [OutputSpec],
    /// The scalar the generated function returns.
    pub returns: Returns,
    /// Exists only for a model with loops, couplings or mimic joints.
    pub needs_constraints: bool,
    /// When it is generated without `only(…)`.
    pub generated: WhenGenerated,
    /// The links named at generation time it is generated for.
    pub parameter: Parameter,
    /// The standalone crate's README: the note after the signature, for a tree and, when it differs, for
    /// a model with constraints.
    pub readme_note: &'static str,
    /// The README note for a model with constraints, when it differs from `readme_note`.
    pub readme_note_with_constraints: Option<&'static str>,
    /// Whether `embedyn eval --algo` (and `bench`) offers it.
    pub cli: Option<CliSpec>,
    /// How its code grows with the model.
    pub growth: Growth,
    /// The size guard's prediction of the traced operations (an upper bound; see `size.rs`).
    pub predicted_operations: fn(&SizeCounts) -> f64,
    /// Runs the algorithm on the traced scalar (inputs in the order of `inputs`).
    pub trace: TraceFn,
    /// Runs the interpreted solver's algorithm in f64 (inputs in the order of `inputs`), for timing.
    pub interpreted: InterpretedFn,
}

const Q: InputSpec = InputSpec {
    name: "q",
    len: Dim::Nq,
    columns: None,
    unit: "rad or m; a floating joint's [x y z qx qy qz qw]",
};
const V: InputSpec = InputSpec {
    name: "v",
    len: Dim::Nv,
    columns: None,
    unit: "rad/s or m/s",
};
const TAU: InputSpec = InputSpec {
    name: "tau",
    len: Dim::Nv,
    columns: None,
    unit: "N·m or N",
};
const QDD: InputSpec = InputSpec {
    name: "qdd",
    len: Dim::Nv,
    columns: None,
    unit: "rad/s² or m/s²",
};
const DT: InputSpec = InputSpec {
    name: "dt",
    len: Dim::Scalar,
    columns: None,
    unit: "s",
};
const Q1: InputSpec = InputSpec {
    name: "q1",
    len: Dim::Nq,
    columns: None,
    unit: "rad or m; a floating joint's [x y z qx qy qz qw]",
};
const F_EXT: InputSpec = InputSpec {
    name: "f_ext",
    len: Dim::WrenchLinks,
    columns: Some(6),
    unit: "N (force), N·m (torque); each row in its link's frame, about its origin",
};
const MASS_UNIT: &str = "kg·m², kg·m or kg";

/// Every algorithm, in the order generated code lists them (the order of [`Algorithm`]'s variants).
pub const ALGORITHMS: &[AlgorithmSpec] = &[
    AlgorithmSpec {
        algorithm: Algorithm::Kinematics,
        name: "kinematics",
        traced_name: "kinematics",
        wrapper: None,
        summary: "world pose of every link in `FRAMES`: `[R row-major, origin]`",
        doc: "Forward kinematics: the world pose of every link on a moving body, in the order of `FRAMES`, as `[r00, r01, r02, r10, r11, r12, r20, r21, r22, x, y, z]` (the rotation row-major: its columns are the link's axes in world coordinates; then the link origin in the world).",
        doc_with_constraints: None,
        inputs: &[Q],
        outputs: &[OutputSpec {
            name: "frames",
            shape: Shape::Matrix(Dim::Frames, Dim::Fixed(12)),
            unit: "1 (rotation), m (origin)",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::ByDefault,
        parameter: Parameter::None,
        readme_note: " — the world pose of each link in `FRAMES`: rotation row-major, then the origin",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 40.0 * (c.nv + c.links),
        trace: |model, ws, inputs, _| {
            let zeros = vec![Sym::Const(0.0); model.nv()];
            forward_kinematics(model, ws, &inputs[0], &zeros)?;
            let mut values = Vec::new();
            for (_, x) in link_poses(model, ws) {
                for r in 0..3 {
                    for c in 0..3 {
                        values.push(x.rotation[(r, c)]);
                    }
                }
                values.extend(x.translation.iter().copied());
            }
            Ok(Traced {
                outputs: vec![values],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| {
            forward_kinematics(model, ws, inputs[0], &vec![0.0; model.nv()])
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Aba,
        name: "aba",
        traced_name: "aba",
        wrapper: None,
        summary: "forward dynamics (O(N) articulated-body algorithm)",
        doc: "Forward dynamics: `qdd = M(q)⁻¹ (τ − C(q, v) − g(q))` (the O(N) articulated-body algorithm, unrolled).",
        doc_with_constraints: Some("Forward dynamics with constraint embedding: `qdd` over all spanning coordinates (the O(N) articulated-body algorithm with each aggregate link inline, unrolled); only `Xᵀ τ` acts. Returns the singularity measure, the largest condition number cond₁(Y1) over the loops: where it is not below `SINGULARITY_THRESHOLD` (`!(cond < SINGULARITY_THRESHOLD)`, which also catches NaN) the configuration is at or too near a singular one (a toggle) and `qdd` is meaningless — the interpreted solver refuses there."),
        inputs: &[Q, V, TAU],
        outputs: &[OutputSpec {
            name: "qdd",
            shape: Shape::Vector(Dim::Nv),
            unit: "rad/s² or m/s²",
        }],
        returns: Returns::SingularityMeasure,
        needs_constraints: false,
        generated: WhenGenerated::ByDefault,
        parameter: Parameter::None,
        readme_note: "",
        readme_note_with_constraints: Some(" — returns the singularity measure cond₁(Y1): where it is not below `SINGULARITY_THRESHOLD` (or is NaN) the configuration is at or too near a singular one and `qdd` is meaningless (the interpreted solver refuses there)"),
        cli: Some(CliSpec {
            help: "Forward dynamics (articulated-body algorithm)",
            with_constraints: None,
            timed: true,
        }),
        growth: Growth::Linear,
        predicted_operations: |c| 440.0 * c.nv,
        trace: |model, ws, inputs, _| {
            let qdd = aba(model, ws, &inputs[0], &inputs[1], &inputs[2])?.to_vec();
            Ok(Traced {
                outputs: vec![qdd],
                returned: model.has_constraints().then(|| constraint_condition(ws)),
            })
        },
        interpreted: |model, ws, inputs, _| {
            aba(model, ws, inputs[0], inputs[1], inputs[2]).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Rnea,
        name: "rnea",
        traced_name: "rnea",
        wrapper: None,
        summary: "inverse dynamics (recursive Newton–Euler)",
        doc: "Inverse dynamics: `τ = M(q) qdd + C(q, v) + g(q)` (recursive Newton–Euler, unrolled).",
        doc_with_constraints: None,
        inputs: &[Q, V, QDD],
        outputs: &[OutputSpec {
            name: "tau",
            shape: Shape::Vector(Dim::Nv),
            unit: "N·m or N",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::ByDefault,
        parameter: Parameter::None,
        readme_note: "",
        readme_note_with_constraints: None,
        cli: Some(CliSpec {
            help: "Inverse dynamics (recursive Newton–Euler)",
            with_constraints: None,
            timed: true,
        }),
        growth: Growth::Linear,
        predicted_operations: |c| 215.0 * c.nv,
        trace: |model, ws, inputs, _| {
            let tau = rnea(model, ws, &inputs[0], &inputs[1], &inputs[2])?.to_vec();
            Ok(Traced {
                outputs: vec![tau],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| {
            rnea(model, ws, inputs[0], inputs[1], inputs[2]).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Gravity,
        name: "gravity",
        traced_name: "gravity",
        wrapper: None,
        summary: "generalized gravity `g(q)` (`rnea` at `v = 0`, `qdd = 0`; only when asked for)",
        doc: "Generalized gravity: `τ = g(q)`, the joint forces that hold the robot still at `q` (Newton–Euler at `v = 0`, `qdd = 0`, unrolled: gravity carried down the tree, each subtree's mass and first moment carried up; no velocity terms, no armature).",
        doc_with_constraints: Some("Generalized gravity: `τ = g(q)` on the spanning tree's joints (Newton–Euler at `v = 0`, `qdd = 0`, unrolled: gravity carried down the tree, each subtree's mass and first moment carried up; no velocity terms, no armature); only its projection `Xᵀ τ` (`embedding`) acts on the independent coordinates."),
        inputs: &[Q],
        outputs: &[OutputSpec {
            name: "tau",
            shape: Shape::Vector(Dim::Nv),
            unit: "N·m or N",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — the generalized gravity `g(q)`",
        readme_note_with_constraints: Some(" — the generalized gravity `g(q)` on the spanning tree's joints; `Xᵀ τ` acts on the independent coordinates"),
        cli: Some(CliSpec {
            help: "Generalized gravity g(q) (Newton–Euler at rest)",
            with_constraints: None,
            timed: true,
        }),
        growth: Growth::Linear,
        predicted_operations: |c| 100.0 * c.nv,
        trace: |model, ws, inputs, _| {
            let tau = gravity(model, ws, &inputs[0])?.to_vec();
            Ok(Traced {
                outputs: vec![tau],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| gravity(model, ws, inputs[0]).map(|_| ()),
    },
    AlgorithmSpec {
        algorithm: Algorithm::Nle,
        name: "nle",
        traced_name: "nle",
        wrapper: None,
        summary: "nonlinear effects `C(q, v) v + g(q)` (`rnea` at `qdd = 0`; only when asked for)",
        doc: "Nonlinear effects: `τ = C(q, v) v + g(q)`, Coriolis, centrifugal and gravity forces (recursive Newton–Euler at `qdd = 0`, unrolled: no armature).",
        doc_with_constraints: Some("Nonlinear effects: `τ = C(q, v) v + g(q)` on the spanning tree's joints (recursive Newton–Euler at `qdd = 0`, unrolled: no armature), for a `v` that satisfies the velocity constraints; only its projection `Xᵀ τ` (`embedding`) acts on the independent coordinates."),
        inputs: &[Q, V],
        outputs: &[OutputSpec {
            name: "tau",
            shape: Shape::Vector(Dim::Nv),
            unit: "N·m or N",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — the nonlinear effects `C(q, v) v + g(q)`",
        readme_note_with_constraints: Some(" — the nonlinear effects `C(q, v) v + g(q)` on the spanning tree's joints, for a `v` on the velocity constraints; `Xᵀ τ` acts on the independent coordinates"),
        cli: Some(CliSpec {
            help: "Nonlinear effects C(q, v) v + g(q) (Newton–Euler at qdd = 0)",
            with_constraints: None,
            timed: true,
        }),
        growth: Growth::Linear,
        predicted_operations: |c| 215.0 * c.nv,
        trace: |model, ws, inputs, _| {
            let tau = nle(model, ws, &inputs[0], &inputs[1])?.to_vec();
            Ok(Traced {
                outputs: vec![tau],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| nle(model, ws, inputs[0], inputs[1]).map(|_| ()),
    },
    AlgorithmSpec {
        algorithm: Algorithm::Crba,
        name: "crba",
        traced_name: "crba",
        wrapper: None,
        summary: "the spanning tree's mass matrix",
        doc: "The joint-space mass matrix `M(q)` (composite-rigid-body algorithm, unrolled).",
        doc_with_constraints: None,
        inputs: &[Q],
        outputs: &[OutputSpec {
            name: "m",
            shape: Shape::Matrix(Dim::Nv, Dim::Nv),
            unit: MASS_UNIT,
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::ByDefault,
        parameter: Parameter::None,
        readme_note: "",
        readme_note_with_constraints: None,
        cli: Some(CliSpec {
            help: "Mass matrix (composite-rigid-body algorithm)",
            with_constraints: Some(Algorithm::CrbaIndependent),
            timed: true,
        }),
        growth: Growth::Quadratic,
        predicted_operations: |c| c.crba,
        trace: |model, ws, inputs, _| {
            let m = crba(model, ws, &inputs[0])?;
            Ok(Traced {
                outputs: vec![row_major(m)],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| crba(model, ws, inputs[0]).map(|_| ()),
    },
    AlgorithmSpec {
        algorithm: Algorithm::Minv,
        name: "minv",
        traced_name: "minv",
        wrapper: None,
        summary: "`M⁻¹` by the operator factorization (O(N²) output; only when asked for)",
        doc: "The inverse mass matrix `M(q)⁻¹` by the operator factorization of Eq. 6, unrolled.",
        doc_with_constraints: None,
        inputs: &[Q],
        outputs: &[OutputSpec {
            name: "m_inv",
            shape: Shape::Matrix(Dim::Nv, Dim::Nv),
            unit: "1/kg, 1/(kg·m) or 1/(kg·m²)",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: "",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Quadratic,
        predicted_operations: |c| 38.0 * c.nv * c.nv + 170.0 * c.nv,
        trace: |model, ws, inputs, _| {
            let m_inv = mass_matrix_inverse(model, ws, &inputs[0])?;
            Ok(Traced {
                outputs: vec![row_major(m_inv)],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| mass_matrix_inverse(model, ws, inputs[0]).map(|_| ()),
    },
    AlgorithmSpec {
        algorithm: Algorithm::Complete,
        name: "complete",
        traced_name: "complete_step",
        wrapper: Some(crate::generate::complete_loop),
        summary: "dependent coordinates solved from the independent ones by Newton's method from `q`'s dependent entries, until the relative residual is below 64 ε or for at most `COMPLETION_MAX_STEPS` steps; returns the residual — check it",
        doc: "One Newton step of the position completion: `q_out` is `q` with its dependent coordinates moved towards the solution of the loop, gear and mimic equations (loop coordinates by at most 0.5 rad or m). Returns the largest residual at `q`, relative to the magnitudes in each equation (`complete` iterates this).",
        doc_with_constraints: None,
        inputs: &[Q],
        outputs: &[OutputSpec {
            name: "q_out",
            shape: Shape::Vector(Dim::Nq),
            unit: "rad or m",
        }],
        returns: Returns::Residual,
        needs_constraints: true,
        generated: WhenGenerated::WithConstraints,
        parameter: Parameter::None,
        readme_note: "",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 100.0 * c.nv,
        trace: |model, ws, inputs, _| {
            let mut q_out = inputs[0].clone();
            let residual = completion_step(model, ws, &mut q_out)?;
            Ok(Traced {
                outputs: vec![q_out],
                returned: Some(residual),
            })
        },
        interpreted: |model, ws, inputs, _| {
            completion_step(model, ws, &mut inputs[0].to_vec()).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Embedding,
        name: "embedding",
        traced_name: "embedding",
        wrapper: None,
        summary: "the map `X` (`NV × NI`), `v = X v_independent`",
        doc: "The embedding map `X` (rows: all velocity coordinates, columns: independent ones): `v = X v_independent`. Returns the singularity measure cond₁(Y1) (as `aba` does).",
        doc_with_constraints: None,
        inputs: &[Q],
        outputs: &[OutputSpec {
            name: "x",
            shape: Shape::Matrix(Dim::Nv, Dim::Ni),
            unit: "1 (velocity ratios)",
        }],
        returns: Returns::SingularityMeasure,
        needs_constraints: true,
        generated: WhenGenerated::WithConstraints,
        parameter: Parameter::None,
        readme_note: " — `v = X v_independent`; returns the singularity measure, as `aba` does",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 50.0 * c.nv + 2.0 * c.nv * c.ni,
        trace: |model, ws, inputs, _| {
            let x = row_major(embedding_map_in(model, ws, &inputs[0])?);
            Ok(Traced {
                outputs: vec![x],
                returned: Some(constraint_condition(ws)),
            })
        },
        interpreted: |model, ws, inputs, _| embedding_map_in(model, ws, inputs[0]).map(|_| ()),
    },
    AlgorithmSpec {
        algorithm: Algorithm::CrbaIndependent,
        name: "crba_independent",
        traced_name: "crba_independent",
        wrapper: None,
        summary: "`Xᵀ M X` over the independent coordinates",
        doc: "The mass matrix over the independent coordinates, `Xᵀ M(q) X` (the spanning tree's `M` is `crba`). Returns the singularity measure cond₁(Y1) (as `aba` does).",
        doc_with_constraints: None,
        inputs: &[Q],
        outputs: &[OutputSpec {
            name: "m",
            shape: Shape::Matrix(Dim::Ni, Dim::Ni),
            unit: MASS_UNIT,
        }],
        returns: Returns::SingularityMeasure,
        needs_constraints: true,
        generated: WhenGenerated::WithConstraints,
        parameter: Parameter::None,
        readme_note: " — the mass matrix over the independent coordinates, `Xᵀ M X`",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Quadratic,
        predicted_operations: |c| 1.25 * c.crba + 2.0 * c.nv * c.ni,
        trace: |model, ws, inputs, _| {
            let m = row_major(reduced_mass_matrix_in(model, ws, &inputs[0])?);
            Ok(Traced {
                outputs: vec![m],
                returned: Some(constraint_condition(ws)),
            })
        },
        interpreted: |model, ws, inputs, _| {
            reduced_mass_matrix_in(model, ws, inputs[0]).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Integrate,
        name: "integrate",
        traced_name: "integrate",
        wrapper: None,
        summary: "`q ⊕ v`: joint coordinates plus `v`, a floating joint moved by the SE(3) exponential of its body-frame twist (only when asked for)",
        doc: "The configuration reached from `q` along `v` in unit time, `q_out = q ⊕ v` (Pinocchio's `integrate`): every revolute, continuous and prismatic coordinate plus its velocity; a floating joint's pose `M` moved to `M · exp(v)`, the SE(3) exponential of its body-frame twist `[v_lin ω]`. The quaternions of `q_out` have unit norm and the sign nearer `q`'s (Pinocchio's). A time step is `integrate(q, dt · v)`. Small angles through series, selected without branches.",
        doc_with_constraints: None,
        inputs: &[Q, V],
        outputs: &[OutputSpec {
            name: "q_out",
            shape: Shape::Vector(Dim::Nq),
            unit: "rad or m; a floating joint's [x y z qx qy qz qw]",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — `q ⊕ v`: a floating joint moves by the SE(3) exponential of its body-frame twist",
        readme_note_with_constraints: None,
        cli: Some(CliSpec {
            help: "q ⊕ v (a floating joint by the SE(3) exponential of its body twist)",
            with_constraints: None,
            timed: false,
        }),
        growth: Growth::Linear,
        predicted_operations: |c| 20.0 * c.nv + 200.0,
        trace: |model, _ws, inputs, _| {
            let mut q_out = vec![Sym::Const(0.0); model.nq()];
            integrate(model, &inputs[0], &inputs[1], &mut q_out)?;
            Ok(Traced {
                outputs: vec![q_out],
                returned: None,
            })
        },
        interpreted: |model, _ws, inputs, _| {
            integrate(model, inputs[0], inputs[1], &mut vec![0.0; model.nq()])
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Difference,
        name: "difference",
        traced_name: "difference",
        wrapper: None,
        summary: "`q1 ⊖ q`: the `v` that `integrate` takes from `q` to `q1`, of least rotation (only when asked for)",
        doc: "The velocity that `integrate` takes from `q` to `q1` in unit time, `v = q1 ⊖ q` (Pinocchio's `difference`): every revolute, continuous and prismatic coordinate `q1 − q` (angles not wrapped); a floating joint's body-frame twist `log(M⁻¹ M1)`, the least rotation (angle ≤ π, whatever the signs of the quaternions). Small angles and the shorter rotation are selected without branches.",
        doc_with_constraints: None,
        inputs: &[Q, Q1],
        outputs: &[OutputSpec {
            name: "v",
            shape: Shape::Vector(Dim::Nv),
            unit: "rad or m (a velocity over unit time)",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — `q1 ⊖ q`, the `v` of least rotation with `integrate(q, v) = q1`",
        readme_note_with_constraints: None,
        cli: Some(CliSpec {
            help: "q1 ⊖ q (a floating joint by the SE(3) logarithm, least rotation)",
            with_constraints: None,
            timed: false,
        }),
        growth: Growth::Linear,
        predicted_operations: |c| 20.0 * c.nv + 300.0,
        trace: |model, _ws, inputs, _| {
            let mut v = vec![Sym::Const(0.0); model.nv()];
            difference(model, &inputs[0], &inputs[1], &mut v)?;
            Ok(Traced {
                outputs: vec![v],
                returned: None,
            })
        },
        interpreted: |model, _ws, inputs, _| {
            difference(model, inputs[0], inputs[1], &mut vec![0.0; model.nv()])
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::AbaExt,
        name: "aba_ext",
        traced_name: "aba_ext",
        wrapper: None,
        summary: "`aba` with the wrenches `f_ext` of the links named at generation time (`wrenches(…)`, `--wrenches`)",
        doc: "Forward dynamics with external wrenches: `qdd = M(q)⁻¹ (τ + Σ Jᵀ f − C(q, v) − g(q))` (the articulated-body algorithm, unrolled). Row `k` of `f_ext` is the wrench `[fx, fy, fz, tx, ty, tz]` (N, N·m) the environment applies to link `WRENCH_LINKS[k]` (index constants in `wrench`), in that link's own frame, about its origin; links not in `WRENCH_LINKS` take none and cost nothing.",
        doc_with_constraints: Some("Forward dynamics with external wrenches and constraint embedding: `qdd` over all spanning coordinates (the articulated-body algorithm with each aggregate link inline, unrolled). Row `k` of `f_ext` is the wrench `[fx, fy, fz, tx, ty, tz]` (N, N·m) the environment applies to link `WRENCH_LINKS[k]` (index constants in `wrench`), in that link's own frame, about its origin; like `tau`, only the wrenches' projection onto the independent coordinates acts. Returns the singularity measure, the largest condition number cond₁(Y1) over the loops: where it is not below `SINGULARITY_THRESHOLD` (`!(cond < SINGULARITY_THRESHOLD)`, which also catches NaN) the configuration is at or too near a singular one (a toggle) and `qdd` is meaningless — the interpreted solver refuses there."),
        inputs: &[Q, V, TAU, F_EXT],
        outputs: &[OutputSpec {
            name: "qdd",
            shape: Shape::Vector(Dim::Nv),
            unit: "rad/s² or m/s²",
        }],
        returns: Returns::SingularityMeasure,
        needs_constraints: false,
        generated: WhenGenerated::WithLinks,
        parameter: Parameter::WrenchLinks,
        readme_note: " — `aba` with row `k` of `f_ext` the wrench `[fx, fy, fz, tx, ty, tz]` on link `WRENCH_LINKS[k]`, in its frame about its origin",
        readme_note_with_constraints: Some(" — `aba` with row `k` of `f_ext` the wrench `[fx, fy, fz, tx, ty, tz]` on link `WRENCH_LINKS[k]`, in its frame about its origin; returns the singularity measure, as `aba` does"),
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 440.0 * c.nv + 40.0 * c.links,
        trace: |model, ws, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, &inputs[3]);
            let qdd = aba_ext(model, ws, &inputs[0], &inputs[1], &inputs[2], &f_ext)?.to_vec();
            Ok(Traced {
                outputs: vec![qdd],
                returned: model.has_constraints().then(|| constraint_condition(ws)),
            })
        },
        interpreted: |model, ws, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, inputs[3]);
            aba_ext(model, ws, inputs[0], inputs[1], inputs[2], &f_ext).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::RneaExt,
        name: "rnea_ext",
        traced_name: "rnea_ext",
        wrapper: None,
        summary: "`rnea` with the wrenches `f_ext` of the links named at generation time",
        doc: "Inverse dynamics with external wrenches: `τ = M(q) qdd + C(q, v) + g(q) − Σ Jᵀ f` (recursive Newton–Euler, unrolled): the joint forces that give `qdd` while the environment applies `f_ext`. Row `k` of `f_ext` is the wrench `[fx, fy, fz, tx, ty, tz]` (N, N·m) on link `WRENCH_LINKS[k]` (index constants in `wrench`), in that link's own frame, about its origin.",
        doc_with_constraints: None,
        inputs: &[Q, V, QDD, F_EXT],
        outputs: &[OutputSpec {
            name: "tau",
            shape: Shape::Vector(Dim::Nv),
            unit: "N·m or N",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::WithLinks,
        parameter: Parameter::WrenchLinks,
        readme_note: " — `rnea` less the joint forces of the wrenches `f_ext` (rows as in `aba_ext`)",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 215.0 * c.nv + 40.0 * c.links,
        trace: |model, ws, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, &inputs[3]);
            let tau = rnea_ext(model, ws, &inputs[0], &inputs[1], &inputs[2], &f_ext)?.to_vec();
            Ok(Traced {
                outputs: vec![tau],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, inputs[3]);
            rnea_ext(model, ws, inputs[0], inputs[1], inputs[2], &f_ext).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::NleExt,
        name: "nle_ext",
        traced_name: "nle_ext",
        wrapper: None,
        summary: "`nle` with the wrenches `f_ext` of the links named at generation time (only when asked for)",
        doc: "Nonlinear effects with external wrenches: `τ = C(q, v) v + g(q) − Σ Jᵀ f` (recursive Newton–Euler at `qdd = 0`, unrolled: no armature). Row `k` of `f_ext` is the wrench `[fx, fy, fz, tx, ty, tz]` (N, N·m) on link `WRENCH_LINKS[k]` (index constants in `wrench`), in that link's own frame, about its origin.",
        doc_with_constraints: None,
        inputs: &[Q, V, F_EXT],
        outputs: &[OutputSpec {
            name: "tau",
            shape: Shape::Vector(Dim::Nv),
            unit: "N·m or N",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::WrenchLinks,
        readme_note: " — `nle` less the joint forces of the wrenches `f_ext` (rows as in `aba_ext`)",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 215.0 * c.nv + 40.0 * c.links,
        trace: |model, ws, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, &inputs[2]);
            let tau = nle_ext(model, ws, &inputs[0], &inputs[1], &f_ext)?.to_vec();
            Ok(Traced {
                outputs: vec![tau],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, inputs[2]);
            nle_ext(model, ws, inputs[0], inputs[1], &f_ext).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Frame,
        name: "frame",
        traced_name: "frame",
        wrapper: None,
        summary: "one per link named at generation time (`frames(…)`, `--frames`): its world pose, 6 × `NV` Jacobian and bias `J̇ v` (classical acceleration at `qdd = 0`) in the chosen reference",
        doc: "Kinematics of one link: `pose` its world pose `[r00, r01, r02, r10, r11, r12, r20, r21, r22, x, y, z]` (as `kinematics` writes it: the rotation row-major, then the origin); `jacobian` its 6 × `NV` Jacobian, rows linear then angular (the frame's velocity is `jacobian · v`); `bias` its classical acceleration at `qdd = 0`, `[linear; angular]`, without gravity (the acceleration is `jacobian · qdd + bias`; Pinocchio's `getFrameClassicalAcceleration`). Jacobian and bias are in the reference below (Pinocchio's: `local` the link's axes and origin; `local_world_aligned` the world's axes at the link's origin, where `bias = J̇ v`; `world` the world's axes and origin).",
        doc_with_constraints: Some("Kinematics of one link: `pose` its world pose `[r00, r01, r02, r10, r11, r12, r20, r21, r22, x, y, z]` (as `kinematics` writes it: the rotation row-major, then the origin); `jacobian` its 6 × `NV` Jacobian over the spanning tree's coordinates, rows linear then angular (`jacobian · X`, with `X` from `embedding`, is the Jacobian over the independent ones); `bias` its classical acceleration at `qdd = 0`, `[linear; angular]`, without gravity, for a `v` on the velocity constraints. Jacobian and bias are in the reference below (Pinocchio's: `local` the link's axes and origin; `local_world_aligned` the world's axes at the link's origin, where `bias = J̇ v`; `world` the world's axes and origin)."),
        inputs: &[Q, V],
        outputs: &[
            OutputSpec {
                name: "pose",
                shape: Shape::Vector(Dim::Fixed(12)),
                unit: "1 (rotation), m (origin)",
            },
            OutputSpec {
                name: "jacobian",
                shape: Shape::Matrix(Dim::Fixed(6), Dim::Nv),
                unit: "m/rad or 1 (linear rows), rad/rad or rad/m (angular rows)",
            },
            OutputSpec {
                name: "bias",
                shape: Shape::Vector(Dim::Fixed(6)),
                unit: "m/s², rad/s²",
            },
        ],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::WithLinks,
        parameter: Parameter::Frame,
        readme_note: " — one per link named at generation time: world pose (as `kinematics`), 6 × `NV` Jacobian (rows linear then angular) and bias `[linear; angular]` (classical acceleration at `qdd = 0`) in the reference each function's doc names",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 150.0 * c.nv + 200.0,
        trace: |model, ws, inputs, links| {
            let nv = model.nv();
            let frame = the_frame(links)?;
            forward_kinematics_acceleration(
                model,
                ws,
                &inputs[0],
                &inputs[1],
                &vec![Sym::Const(0.0); nv],
            )?;
            let x = frame_placement(model, ws, frame)?;
            let mut pose = Vec::with_capacity(12);
            for r in 0..3 {
                for c in 0..3 {
                    pose.push(x.rotation[(r, c)]);
                }
            }
            pose.extend(x.translation.iter().copied());
            let mut jacobian = Matrix6xX::from_element(nv, Sym::Const(0.0));
            frame_jacobian(model, ws, frame, links.reference, &mut jacobian)?;
            let bias = frame_classical_acceleration(model, ws, frame, links.reference)?;
            Ok(Traced {
                outputs: vec![
                    pose,
                    row_major6(&jacobian),
                    linear_angular(&bias.linear, &bias.angular),
                ],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, links| {
            let frame = the_frame(links)?;
            let zeros = vec![0.0; model.nv()];
            forward_kinematics_acceleration(model, ws, inputs[0], inputs[1], &zeros)?;
            frame_placement(model, ws, frame)?;
            let mut jacobian = Matrix6xX::zeros(model.nv());
            frame_jacobian(model, ws, frame, links.reference, &mut jacobian)?;
            frame_classical_acceleration(model, ws, frame, links.reference).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Com,
        name: "com",
        traced_name: "com",
        wrapper: None,
        summary: "centre of mass, its velocity and its 3 × `NV` Jacobian (only when asked for)",
        doc: "The centre of mass of the bodies that joints move (links fixed to the world are left out, as in Pinocchio) in the world, `com`; its velocity `vcom`; and its 3 × `NV` Jacobian `j_com` (`vcom = j_com · v`; Pinocchio's `jacobianCenterOfMass`).",
        doc_with_constraints: Some("The centre of mass of the bodies that joints move (links fixed to the world are left out, as in Pinocchio) in the world, `com`; its velocity `vcom` (for a `v` on the velocity constraints); and its 3 × `NV` Jacobian `j_com` over the spanning tree's coordinates (`vcom = j_com · v`; `j_com · X` over the independent ones)."),
        inputs: &[Q, V],
        outputs: &[
            OutputSpec {
                name: "com",
                shape: Shape::Vector(Dim::Fixed(3)),
                unit: "m",
            },
            OutputSpec {
                name: "vcom",
                shape: Shape::Vector(Dim::Fixed(3)),
                unit: "m/s",
            },
            OutputSpec {
                name: "j_com",
                shape: Shape::Matrix(Dim::Fixed(3), Dim::Nv),
                unit: "m/rad or 1",
            },
        ],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — centre of mass in the world, its velocity and its 3 × `NV` Jacobian",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 200.0 * c.nv + 20.0 * c.links,
        trace: |model, ws, inputs, _| {
            forward_kinematics(model, ws, &inputs[0], &inputs[1])?;
            let c = center_of_mass(model, ws)?;
            let mut j_com = Matrix3xX::from_element(model.nv(), Sym::Const(0.0));
            com_jacobian(model, ws, &mut j_com)?;
            let j_com = (0..3)
                .flat_map(|r| (0..model.nv()).map(move |k| (r, k)))
                .map(|(r, k)| j_com[(r, k)])
                .collect();
            Ok(Traced {
                outputs: vec![
                    c.com.iter().copied().collect(),
                    c.vcom.iter().copied().collect(),
                    j_com,
                ],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| {
            forward_kinematics(model, ws, inputs[0], inputs[1])?;
            center_of_mass(model, ws)?;
            com_jacobian(model, ws, &mut Matrix3xX::zeros(model.nv())).map(|_| ())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Centroidal,
        name: "centroidal",
        traced_name: "centroidal",
        wrapper: None,
        summary: "centroidal momentum `h_g` and its matrix `A_g` (6 × `NV`), rows linear then angular (only when asked for)",
        doc: "Centroidal momentum (Orin and Goswami; Pinocchio's `ccrba`): `h_g = A_g v`, the linear momentum and the angular momentum about the centre of mass in world axes, `[linear; angular]`, and the centroidal momentum matrix `a_g` (6 × `NV`, rows linear then angular). Positions only, then one product with `v`: `centroidal_bias` gives `Ȧ_g v`.",
        doc_with_constraints: Some("Centroidal momentum (Orin and Goswami; Pinocchio's `ccrba`): `h_g = A_g v`, the linear momentum and the angular momentum about the centre of mass in world axes, `[linear; angular]`, for a `v` on the velocity constraints, and the centroidal momentum matrix `a_g` (6 × `NV` over the spanning tree's coordinates, rows linear then angular; `a_g · X` over the independent ones)."),
        inputs: &[Q, V],
        outputs: &[
            OutputSpec {
                name: "h_g",
                shape: Shape::Vector(Dim::Fixed(6)),
                unit: "kg·m/s (linear), kg·m²/s (angular)",
            },
            OutputSpec {
                name: "a_g",
                shape: Shape::Matrix(Dim::Fixed(6), Dim::Nv),
                unit: "kg·m or kg (linear rows), kg·m² or kg·m (angular rows)",
            },
        ],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — centroidal momentum `h_g` and the matrix `A_g`, rows linear then angular (world axes, about the centre of mass)",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 300.0 * c.nv + 40.0 * c.links,
        trace: |model, ws, inputs, _| {
            let nv = model.nv();
            forward_kinematics(model, ws, &inputs[0], &vec![Sym::Const(0.0); nv])?;
            let mut a_g = Matrix6xX::from_element(nv, Sym::Const(0.0));
            centroidal_momentum_matrix(model, ws, &mut a_g)?;
            // h_g = A_g v: six dot products, no velocity sweep, summed subtree by subtree (leaves
            // first), so that isomorphic branches' sums are alike and pair (codegen/src/pairing.rs).
            let mut partial: Vec<Vec<Sym>> = vec![vec![Sym::Const(0.0); 6]; model.joints.len()];
            let mut h = vec![Sym::Const(0.0); 6];
            for (i, joint) in model.joints.iter().enumerate().rev() {
                for k in joint.v_range() {
                    for r in 0..6 {
                        partial[i][r] += a_g[(r, k)] * inputs[1][k];
                    }
                }
                let sum = std::mem::take(&mut partial[i]);
                let into = match joint.parent {
                    Some(p) => &mut partial[p],
                    None => &mut h,
                };
                for r in 0..6 {
                    into[r] += sum[r];
                }
            }
            Ok(Traced {
                outputs: vec![h, row_major6(&a_g)],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| {
            forward_kinematics(model, ws, inputs[0], &vec![0.0; model.nv()])?;
            let mut a_g = Matrix6xX::zeros(model.nv());
            centroidal_momentum_matrix(model, ws, &mut a_g)?;
            let _h = &a_g * embedyn_runtime::nalgebra::DVector::from_column_slice(inputs[1]);
            Ok(())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::CentroidalBias,
        name: "centroidal_bias",
        traced_name: "centroidal_bias",
        wrapper: None,
        summary: "`Ȧ_g v`, the rate of the centroidal momentum at `qdd = 0`, `[linear; angular]` (only when asked for)",
        doc: "The centroidal momentum's bias `dh_g = Ȧ_g v` (Pinocchio's `dccrba` times `v`): the rate of `h_g` at `qdd = 0`, without gravity (`ḣ_g = A_g qdd + Ȧ_g v`), `[linear; angular]`, world axes, about the centre of mass — what centroidal MPC adds to `A_g qdd`.",
        doc_with_constraints: Some("The centroidal momentum's bias `dh_g = Ȧ_g v` (Pinocchio's `dccrba` times `v`) over the spanning tree's coordinates, for a `v` on the velocity constraints: the rate of `h_g` at `qdd = 0`, without gravity, `[linear; angular]`, world axes, about the centre of mass."),
        inputs: &[Q, V],
        outputs: &[OutputSpec {
            name: "dh_g",
            shape: Shape::Vector(Dim::Fixed(6)),
            unit: "N (linear), N·m (angular)",
        }],
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — `Ȧ_g v`, the centroidal momentum's rate at `qdd = 0`, `[linear; angular]`",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 250.0 * c.nv + 40.0 * c.links,
        trace: |model, ws, inputs, _| {
            let nv = model.nv();
            forward_kinematics_acceleration(
                model,
                ws,
                &inputs[0],
                &inputs[1],
                &vec![Sym::Const(0.0); nv],
            )?;
            let dh = centroidal_momentum_rate(model, ws)?;
            Ok(Traced {
                outputs: vec![linear_angular(&dh.linear, &dh.angular)],
                returned: None,
            })
        },
        interpreted: |model, ws, inputs, _| {
            let zeros = vec![0.0; model.nv()];
            forward_kinematics_acceleration(model, ws, inputs[0], inputs[1], &zeros)?;
            centroidal_momentum_rate(model, ws)?;
            Ok(())
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::AbaDerivatives,
        name: "aba_derivatives",
        traced_name: "aba_derivatives",
        wrapper: None,
        summary: "`q̈` and its derivatives `∂q̈/∂q`, `∂q̈/∂v`, `∂q̈/∂τ` (only when asked for)",
        doc: "Forward dynamics `qdd = aba(q, v, tau)` and its derivatives (`nv × nv`, row `i` is `qdd[i]`, column `k` a direction in `v` order): `dqdd_dq` in the tangent space (column `k` along `integrate(q, ε e_k)`, Pinocchio's convention), `dqdd_dv` and `dqdd_dtau` (`M⁻¹`). Unrolled: the analytical recursion (`−M⁻¹ ∂τ` after it, in a loop on large trees; where no `f32` code is generated, `qdd` and `M⁻¹` may come from the factorized mass matrix instead of `aba`, rounding as cond(M) ε) or forward-mode dual numbers, whichever runs fewer statements.",
        doc_with_constraints: Some("Forward dynamics `qdd = aba(q, v, tau)` over the spanning tree and its derivatives as a function of every spanning coordinate (`nv × nv`, tangent space); for a `q`, `v` on the constraints (`aba_derivatives_independent` moves along the constraint manifold instead). Returns the singularity measure cond₁(Y1): where it is not below `DERIVATIVE_SINGULARITY_THRESHOLD` (`!(cond < DERIVATIVE_SINGULARITY_THRESHOLD)`) the derivatives have lost their digits (their rounding grows as cond²) and the interpreted solver refuses."),
        inputs: &[Q, V, TAU],
        outputs: ABA_DERIVATIVE_OUTPUTS,
        returns: Returns::SingularityMeasure,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — forward dynamics and its derivatives `∂q̈/∂q`, `∂q̈/∂v`, `∂q̈/∂τ` (tangent space)",
        readme_note_with_constraints: Some(" — forward dynamics and its derivatives over every spanning coordinate (tangent space); returns the singularity measure, to compare with `DERIVATIVE_SINGULARITY_THRESHOLD`"),
        cli: None,
        growth: Growth::Quadratic,
        predicted_operations: predicted_forward_derivatives,
        trace: |model, _, inputs, _| {
            traced_aba_derivatives(model, inputs, &[])
        },
        interpreted: |model, _, inputs, _| {
            let mut dws = DerivativeWorkspace::new(model);
            let mut d = AbaDerivatives::new(model);
            aba_derivatives(model, &mut dws, inputs[0], inputs[1], inputs[2], &[], &mut d)
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::RneaDerivatives,
        name: "rnea_derivatives",
        traced_name: "rnea_derivatives",
        wrapper: None,
        summary: "`τ` and its derivatives `∂τ/∂q`, `∂τ/∂v`, `∂τ/∂q̈ = M` (only when asked for)",
        doc: "Inverse dynamics `tau = rnea(q, v, qdd)` and its derivatives (`nv × nv`, row `i` is `tau[i]`, column `k` a direction in `v` order): `dtau_dq` in the tangent space (column `k` along `integrate(q, ε e_k)`), `dtau_dv` and `dtau_dqdd` (the mass matrix). Unrolled: the analytical recursion or forward-mode dual numbers, whichever runs fewer statements.",
        doc_with_constraints: None,
        inputs: &[Q, V, QDD],
        outputs: RNEA_DERIVATIVE_OUTPUTS,
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — inverse dynamics and its derivatives `∂τ/∂q`, `∂τ/∂v`, `∂τ/∂q̈ = M` (tangent space)",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Quadratic,
        predicted_operations: predicted_inverse_derivatives,
        trace: |model, _, inputs, _| {
            traced_rnea_derivatives(model, inputs, &[])
        },
        interpreted: |model, _, inputs, _| {
            let mut dws = DerivativeWorkspace::new(model);
            let mut d = RneaDerivatives::new(model);
            rnea_derivatives(model, &mut dws, inputs[0], inputs[1], inputs[2], &[], &mut d)
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::Step,
        name: "step",
        traced_name: "step",
        wrapper: None,
        summary: "one semi-implicit Euler step `(q', v')` (only when asked for)",
        doc: "One step of semi-implicit (symplectic) Euler: `v_next = v + dt · aba(q, v, tau)`, then `q_next = integrate(q, dt · v_next)` — a rollout's step; `step_derivatives` adds its Jacobian.",
        doc_with_constraints: Some("One step of semi-implicit Euler over the spanning tree's coordinates (`q_next` satisfies the constraints to first order in `dt`; `complete` projects it back). Returns the singularity measure cond₁(Y1) of the step's `aba`, to compare with `SINGULARITY_THRESHOLD` as `aba`'s."),
        inputs: &[Q, V, TAU, DT],
        outputs: &[
            OutputSpec {
                name: "q_next",
                shape: Shape::Vector(Dim::Nq),
                unit: "rad or m; a floating joint's [x y z qx qy qz qw]",
            },
            OutputSpec {
                name: "v_next",
                shape: Shape::Vector(Dim::Nv),
                unit: "rad/s or m/s",
            },
        ],
        returns: Returns::SingularityMeasure,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — one semi-implicit Euler step (a rollout's step)",
        readme_note_with_constraints: Some(" — one semi-implicit Euler step over the spanning coordinates; returns the singularity measure, as `aba` does"),
        cli: None,
        growth: Growth::Linear,
        predicted_operations: |c| 500.0 * c.nv,
        trace: |model, ws, inputs, _| {
            let (mut q_next, mut v_next) =
                (vec![Sym::Const(0.0); model.nq()], vec![Sym::Const(0.0); model.nv()]);
            let dt = inputs[3][0];
            step(model, ws, &inputs[0], &inputs[1], &inputs[2], dt, &[], &mut q_next, &mut v_next)?;
            Ok(Traced {
                outputs: vec![q_next, v_next],
                returned: model.has_constraints().then(|| constraint_condition(ws)),
            })
        },
        interpreted: |model, ws, inputs, _| {
            let (mut q_next, mut v_next) = (vec![0.0; model.nq()], vec![0.0; model.nv()]);
            step(model, ws, inputs[0], inputs[1], inputs[2], inputs[3][0], &[], &mut q_next, &mut v_next)
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::StepDerivatives,
        name: "step_derivatives",
        traced_name: "step_derivatives",
        wrapper: None,
        summary: "one semi-implicit Euler step `(q', v')` and its Jacobian with respect to `(q, v, τ)` (only when asked for)",
        doc: "One step of semi-implicit Euler, `v_next = v + dt · aba(q, v, tau)` and `q_next = integrate(q, dt · v_next)`, and its Jacobian in blocks (`nv × nv`, tangent space: a column of `∂/∂q` is along `integrate(q, ε e_k)`, a row of `∂q_next` is an entry of `difference(q_next, ·)`): the linearization a multiple-shooting solver takes at each knot.",
        doc_with_constraints: Some("One step of semi-implicit Euler over the spanning tree's coordinates (`q_next` satisfies the constraints to first order in `dt`), and its Jacobian in blocks (`nv × nv`, tangent space). Returns the singularity measure cond₁(Y1), to compare with `DERIVATIVE_SINGULARITY_THRESHOLD` as `aba_derivatives`'."),
        inputs: &[Q, V, TAU, DT],
        outputs: &[
            OutputSpec {
                name: "q_next",
                shape: Shape::Vector(Dim::Nq),
                unit: "rad or m; a floating joint's [x y z qx qy qz qw]",
            },
            OutputSpec {
                name: "v_next",
                shape: Shape::Vector(Dim::Nv),
                unit: "rad/s or m/s",
            },
            OutputSpec {
                name: "dq_next_dq",
                shape: Shape::Matrix(Dim::Nv, Dim::Nv),
                unit: "per unit of the input",
            },
            OutputSpec {
                name: "dq_next_dv",
                shape: Shape::Matrix(Dim::Nv, Dim::Nv),
                unit: "per unit of the input",
            },
            OutputSpec {
                name: "dq_next_dtau",
                shape: Shape::Matrix(Dim::Nv, Dim::Nv),
                unit: "per unit of the input",
            },
            OutputSpec {
                name: "dv_next_dq",
                shape: Shape::Matrix(Dim::Nv, Dim::Nv),
                unit: "per unit of the input",
            },
            OutputSpec {
                name: "dv_next_dv",
                shape: Shape::Matrix(Dim::Nv, Dim::Nv),
                unit: "per unit of the input",
            },
            OutputSpec {
                name: "dv_next_dtau",
                shape: Shape::Matrix(Dim::Nv, Dim::Nv),
                unit: "per unit of the input",
            },
        ],
        returns: Returns::SingularityMeasure,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — one semi-implicit Euler step and its Jacobian with respect to `(q, v, tau)` (tangent space)",
        readme_note_with_constraints: Some(" — one semi-implicit Euler step and its Jacobian over the spanning coordinates; returns the singularity measure, to compare with `DERIVATIVE_SINGULARITY_THRESHOLD`"),
        cli: None,
        growth: Growth::Quadratic,
        predicted_operations: predicted_step_derivatives,
        trace: |model, _, inputs, _| {
            let mut dws = derivative_workspace(model);
            let mut d = StepDerivatives::new(model);
            let dt = inputs[3][0];
            step_derivatives(model, &mut dws, &inputs[0], &inputs[1], &inputs[2], dt, &[], &mut d)?;
            Ok(Traced {
                outputs: vec![
                    d.q_next.iter().copied().collect(),
                    d.v_next.iter().copied().collect(),
                    row_major(&d.dq_next_dq),
                    row_major(&d.dq_next_dv),
                    row_major(&d.dq_next_dtau),
                    row_major(&d.dv_next_dq),
                    row_major(&d.dv_next_dv),
                    row_major(&d.dv_next_dtau),
                ],
                returned: model
                    .has_constraints()
                    .then(|| constraint_condition(dws.value_workspace())),
            })
        },
        interpreted: |model, _, inputs, _| {
            let mut dws = DerivativeWorkspace::new(model);
            let mut d = StepDerivatives::new(model);
            step_derivatives(model, &mut dws, inputs[0], inputs[1], inputs[2], inputs[3][0], &[], &mut d)
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::AbaDerivativesIndependent,
        name: "aba_derivatives_independent",
        traced_name: "aba_derivatives_independent",
        wrapper: None,
        summary: "`q̈_I` and its derivatives along the constraint manifold (models with constraints, only when asked for)",
        doc: "The independent accelerations `qdd_i` (of `aba`) and their derivatives along the constraint manifold: `dqdd_dq` (`ni × ni`) with the configuration moving along column `k` of the embedding map `X` (the dependent coordinates follow the independent ones), `dqdd_dv` (`ni × ni`) with the dependent velocities following the independent ones through the velocity constraints, and `dqdd_dtau` (`ni × nv`, over the spanning tree's `tau`). `q` and `v` must satisfy the constraints (`complete`). Returns the singularity measure cond₁(Y1): where it is not below `DERIVATIVE_SINGULARITY_THRESHOLD` (`!(cond < DERIVATIVE_SINGULARITY_THRESHOLD)`) the derivatives have lost their digits and the interpreted solver refuses.",
        doc_with_constraints: None,
        inputs: &[Q, V, TAU],
        outputs: &[
            OutputSpec {
                name: "qdd_i",
                shape: Shape::Vector(Dim::Ni),
                unit: "rad/s² or m/s²",
            },
            OutputSpec {
                name: "dqdd_dq",
                shape: Shape::Matrix(Dim::Ni, Dim::Ni),
                unit: "1/s² or m/s² per rad",
            },
            OutputSpec {
                name: "dqdd_dv",
                shape: Shape::Matrix(Dim::Ni, Dim::Ni),
                unit: "1/s",
            },
            OutputSpec {
                name: "dqdd_dtau",
                shape: Shape::Matrix(Dim::Ni, Dim::Nv),
                unit: "1/kg, 1/(kg·m) or 1/(kg·m²)",
            },
        ],
        returns: Returns::SingularityMeasure,
        needs_constraints: true,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::None,
        readme_note: " — the independent accelerations' derivatives along the constraint manifold; returns the singularity measure, to compare with `DERIVATIVE_SINGULARITY_THRESHOLD`",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Quadratic,
        predicted_operations: |c| 600.0 * c.nv * c.nv,
        trace: |model, _, inputs, _| {
            let mut dws = DerivativeWorkspace::new(model);
            let mut d = ManifoldDerivatives::new(model);
            aba_derivatives_independent(model, &mut dws, &inputs[0], &inputs[1], &inputs[2], &[], &mut d)?;
            Ok(Traced {
                outputs: vec![
                    d.qdd_independent.iter().copied().collect(),
                    row_major(&d.dqdd_dq),
                    row_major(&d.dqdd_dv),
                    row_major(&d.dqdd_dtau),
                ],
                returned: Some(constraint_condition(dws.value_workspace())),
            })
        },
        interpreted: |model, _, inputs, _| {
            let mut dws = DerivativeWorkspace::new(model);
            let mut d = ManifoldDerivatives::new(model);
            aba_derivatives_independent(model, &mut dws, inputs[0], inputs[1], inputs[2], &[], &mut d)
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::AbaDerivativesExt,
        name: "aba_derivatives_ext",
        traced_name: "aba_derivatives_ext",
        wrapper: None,
        summary: "`aba_derivatives` with the wrenches `f_ext` of the links named at generation time, held fixed (only when asked for)",
        doc: "Forward dynamics with external wrenches, `qdd = aba_ext(q, v, tau, f_ext)`, and its derivatives with the wrenches held fixed (`nv × nv`, as `aba_derivatives`: `dqdd_dq` in the tangent space, `dqdd_dv`, `dqdd_dtau = M⁻¹`). Row `k` of `f_ext` is the wrench `[fx, fy, fz, tx, ty, tz]` (N, N·m) on link `WRENCH_LINKS[k]`, in that link's own frame, about its origin: a wrench fixed in the link's frame turns with the link, which `dqdd_dq` includes.",
        doc_with_constraints: Some("Forward dynamics with external wrenches over the spanning tree and its derivatives with the wrenches held fixed in their links' frames, as a function of every spanning coordinate (`nv × nv`, tangent space); rows of `f_ext` as in `aba_ext`. Returns the singularity measure cond₁(Y1), to compare with `DERIVATIVE_SINGULARITY_THRESHOLD` as `aba_derivatives`'."),
        inputs: &[Q, V, TAU, F_EXT],
        outputs: ABA_DERIVATIVE_OUTPUTS,
        returns: Returns::SingularityMeasure,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::WrenchLinks,
        readme_note: " — `aba_derivatives` with the wrenches `f_ext` (rows as in `aba_ext`) held fixed in their links' frames",
        readme_note_with_constraints: Some(" — `aba_derivatives` with the wrenches `f_ext` (rows as in `aba_ext`) held fixed in their links' frames; returns the singularity measure, to compare with `DERIVATIVE_SINGULARITY_THRESHOLD`"),
        cli: None,
        growth: Growth::Quadratic,
        predicted_operations: |c| predicted_forward_derivatives(c) + 50.0 * c.nv * c.links,
        trace: |model, _, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, &inputs[3]);
            traced_aba_derivatives(model, inputs, &f_ext)
        },
        interpreted: |model, _, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, inputs[3]);
            let mut dws = DerivativeWorkspace::new(model);
            let mut d = AbaDerivatives::new(model);
            aba_derivatives(model, &mut dws, inputs[0], inputs[1], inputs[2], &f_ext, &mut d)
        },
    },
    AlgorithmSpec {
        algorithm: Algorithm::RneaDerivativesExt,
        name: "rnea_derivatives_ext",
        traced_name: "rnea_derivatives_ext",
        wrapper: None,
        summary: "`rnea_derivatives` with the wrenches `f_ext` of the links named at generation time, held fixed (only when asked for)",
        doc: "Inverse dynamics with external wrenches, `tau = rnea_ext(q, v, qdd, f_ext)`, and its derivatives with the wrenches held fixed (`nv × nv`, as `rnea_derivatives`: `dtau_dq` in the tangent space, `dtau_dv`, `dtau_dqdd = M`). Row `k` of `f_ext` is the wrench `[fx, fy, fz, tx, ty, tz]` (N, N·m) on link `WRENCH_LINKS[k]`, in that link's own frame, about its origin: a wrench fixed in the link's frame turns with the link, which `dtau_dq` includes.",
        doc_with_constraints: None,
        inputs: &[Q, V, QDD, F_EXT],
        outputs: RNEA_DERIVATIVE_OUTPUTS,
        returns: Returns::Nothing,
        needs_constraints: false,
        generated: WhenGenerated::OnRequest,
        parameter: Parameter::WrenchLinks,
        readme_note: " — `rnea_derivatives` with the wrenches `f_ext` (rows as in `aba_ext`) held fixed in their links' frames",
        readme_note_with_constraints: None,
        cli: None,
        growth: Growth::Quadratic,
        predicted_operations: |c| predicted_inverse_derivatives(c) + 20.0 * c.nv * c.links,
        trace: |model, _, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, &inputs[3]);
            traced_rnea_derivatives(model, inputs, &f_ext)
        },
        interpreted: |model, _, inputs, links| {
            let f_ext = link_wrenches(links.wrenches, inputs[3]);
            let mut dws = DerivativeWorkspace::new(model);
            let mut d = RneaDerivatives::new(model);
            rnea_derivatives(model, &mut dws, inputs[0], inputs[1], inputs[2], &f_ext, &mut d)
        },
    },
];

/// `aba_derivatives`' outputs (also those of `aba_derivatives_ext`).
const ABA_DERIVATIVE_OUTPUTS: &[OutputSpec] = &[
    OutputSpec {
        name: "qdd",
        shape: Shape::Vector(Dim::Nv),
        unit: "rad/s² or m/s²",
    },
    OutputSpec {
        name: "dqdd_dq",
        shape: Shape::Matrix(Dim::Nv, Dim::Nv),
        unit: "1/s² or m/s² per rad",
    },
    OutputSpec {
        name: "dqdd_dv",
        shape: Shape::Matrix(Dim::Nv, Dim::Nv),
        unit: "1/s",
    },
    OutputSpec {
        name: "dqdd_dtau",
        shape: Shape::Matrix(Dim::Nv, Dim::Nv),
        unit: "1/kg, 1/(kg·m) or 1/(kg·m²)",
    },
];

/// `rnea_derivatives`' outputs (also those of `rnea_derivatives_ext`).
const RNEA_DERIVATIVE_OUTPUTS: &[OutputSpec] = &[
    OutputSpec {
        name: "tau",
        shape: Shape::Vector(Dim::Nv),
        unit: "N·m or N",
    },
    OutputSpec {
        name: "dtau_dq",
        shape: Shape::Matrix(Dim::Nv, Dim::Nv),
        unit: "N·m/rad, N/rad, N·m/m or N/m",
    },
    OutputSpec {
        name: "dtau_dv",
        shape: Shape::Matrix(Dim::Nv, Dim::Nv),
        unit: "N·m·s/rad or N·s/m",
    },
    OutputSpec {
        name: "dtau_dqdd",
        shape: Shape::Matrix(Dim::Nv, Dim::Nv),
        unit: MASS_UNIT,
    },
];

/// Predicted operations of `rnea_derivatives`: on a tree (`ni = nv`) the analytical recursion, about 60 per
/// pair of coordinates on one branch (`c.crba` counts 24 each, with 30 per coordinate) and 1,100 per
/// coordinate (measured 2026-12-03: the Z1 7.2k against 9.3k predicted, the floating ANYmal B 20k traced
/// against 32k, the floating TALOS 34k against 74k); with constraints, dual numbers (`300 nv²`).
fn predicted_inverse_derivatives(c: &SizeCounts) -> f64 {
    if c.ni < c.nv {
        return 300.0 * c.nv * c.nv;
    }
    3.0 * c.crba + 1200.0 * c.nv
}

/// Predicted operations of `aba_derivatives`: on a tree its factors (`aba`, `minv`'s `38 nv² + 170 nv`,
/// the recursion), an upper bound of the way kept (the Z1 11k against 14k, the ANYmal B 16k against 55k,
/// the TALOS 88k against 152k); with constraints, dual numbers (`600 nv²`).
fn predicted_forward_derivatives(c: &SizeCounts) -> f64 {
    if c.ni < c.nv {
        return 600.0 * c.nv * c.nv;
    }
    440.0 * c.nv + 38.0 * c.nv * c.nv + 170.0 * c.nv + predicted_inverse_derivatives(c)
}

/// Predicted operations of `step_derivatives`: on a tree the factors, the product `−M⁻¹ ∂τ` unrolled (4 per
/// row of `M⁻¹` and nonzero of `∂τ`, at most twice the branch pairs) and the chain rule (the Z1 11k
/// against 16k, the ANYmal B 48k against 78k, the TALOS 203k against 286k); with constraints, dual
/// numbers (`700 nv²`).
fn predicted_step_derivatives(c: &SizeCounts) -> f64 {
    if c.ni < c.nv {
        return 700.0 * c.nv * c.nv;
    }
    let branch_pairs = (c.crba - 30.0 * c.nv) / 24.0;
    predicted_forward_derivatives(c) + 8.0 * c.nv * branch_pairs + 10.0 * c.nv * c.nv
}

/// How a traced function differentiates, for the functions of [`Algorithm::has_derivative_methods`] on a
/// tree; the generator traces each way and keeps the shortest code (`generate_algorithm`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DerivativeTrace {
    /// The runtime's method, unrolled whole (for forward dynamics, `−M⁻¹ ∂τ` too).
    Method(DerivativeMethod),
    /// Forward dynamics' factors unrolled (`q̈`, `∂τ/∂q`, `∂τ/∂v`, `M⁻¹` in the places of `q̈`,
    /// `∂q̈/∂q`, `∂q̈/∂v`, `∂q̈/∂τ`) by the runtime's method, the product `−M⁻¹ ∂τ` left to a loop after
    /// them.
    Factors(DerivativeMethod),
}

std::thread_local! {
    /// The way the traces of derivatives take ([`with_derivative_trace`]).
    static DERIVATIVE_TRACE: std::cell::Cell<DerivativeTrace> =
        const { std::cell::Cell::new(DerivativeTrace::Method(DerivativeMethod::Analytical)) };
}

/// Runs `f` (a trace) with the derivatives traced `way`; the way before is back afterwards, also when
/// `f` panics (a proc-macro server runs many expansions on one thread).
pub(crate) fn with_derivative_trace<R>(way: DerivativeTrace, f: impl FnOnce() -> R) -> R {
    struct Restore(DerivativeTrace);
    impl Drop for Restore {
        fn drop(&mut self) {
            DERIVATIVE_TRACE.with(|m| m.set(self.0));
        }
    }
    let _restore = Restore(DERIVATIVE_TRACE.with(|m| m.replace(way)));
    f()
}

fn derivative_workspace(model: &Model<Sym>) -> DerivativeWorkspace<Sym> {
    let mut dws = DerivativeWorkspace::new(model);
    let (DerivativeTrace::Method(method) | DerivativeTrace::Factors(method)) =
        DERIVATIVE_TRACE.with(std::cell::Cell::get);
    dws.set_method(method);
    dws
}

/// The traced `aba_derivatives` (and `_ext` with `f_ext`), the way of [`with_derivative_trace`].
fn traced_aba_derivatives(
    model: &Model<Sym>,
    inputs: &[Vec<Sym>],
    f_ext: &[LinkWrench<Sym>],
) -> Result<Traced, DynamicsError> {
    let mut dws = derivative_workspace(model);
    let (q, v, tau) = (&inputs[0], &inputs[1], &inputs[2]);
    if let DerivativeTrace::Factors(_) = DERIVATIVE_TRACE.with(std::cell::Cell::get) {
        let mut f = AbaDerivativeFactors::new(model);
        aba_derivative_factors(model, &mut dws, q, v, tau, f_ext, &mut f)?;
        return Ok(Traced {
            outputs: vec![
                f.qdd.iter().copied().collect(),
                row_major(&f.dtau_dq),
                row_major(&f.dtau_dv),
                row_major(&f.minv),
            ],
            returned: None,
        });
    }
    let mut d = AbaDerivatives::new(model);
    aba_derivatives(model, &mut dws, q, v, tau, f_ext, &mut d)?;
    Ok(aba_derivatives_traced(model, &dws, &d))
}

/// The traced `rnea_derivatives` (and `_ext` with `f_ext`), by the method of [`with_derivative_method`].
fn traced_rnea_derivatives(
    model: &Model<Sym>,
    inputs: &[Vec<Sym>],
    f_ext: &[LinkWrench<Sym>],
) -> Result<Traced, DynamicsError> {
    let mut dws = derivative_workspace(model);
    let mut d = RneaDerivatives::new(model);
    rnea_derivatives(
        model, &mut dws, &inputs[0], &inputs[1], &inputs[2], f_ext, &mut d,
    )?;
    Ok(rnea_derivatives_traced(&d))
}

/// The traced outputs of `aba_derivatives` (and `_ext`), with the singularity measure of its value pass
/// on a model with constraints.
fn aba_derivatives_traced(
    model: &Model<Sym>,
    dws: &DerivativeWorkspace<Sym>,
    d: &AbaDerivatives<Sym>,
) -> Traced {
    Traced {
        outputs: vec![
            d.qdd.iter().copied().collect(),
            row_major(&d.dqdd_dq),
            row_major(&d.dqdd_dv),
            row_major(&d.dqdd_dtau),
        ],
        returned: model
            .has_constraints()
            .then(|| constraint_condition(dws.value_workspace())),
    }
}

/// The traced outputs of `rnea_derivatives` (and `_ext`).
fn rnea_derivatives_traced(d: &RneaDerivatives<Sym>) -> Traced {
    Traced {
        outputs: vec![
            d.tau.iter().copied().collect(),
            row_major(&d.dtau_dq),
            row_major(&d.dtau_dv),
            row_major(&d.dtau_dqdd),
        ],
        returned: None,
    }
}

/// The wrenches of `f_ext`'s rows (`[fx, fy, fz, tx, ty, tz]`, row-major) on `frames`, in order.
fn link_wrenches<T: Real>(frames: &[FrameId], f_ext: &[T]) -> Vec<LinkWrench<T>> {
    frames
        .iter()
        .zip(f_ext.chunks_exact(6))
        .map(|(&frame, w)| {
            LinkWrench::new(
                frame,
                Vector3::new(w[0], w[1], w[2]),
                Vector3::new(w[3], w[4], w[5]),
            )
        })
        .collect()
}

/// The frame a frame function is generated for (the generator always gives one).
fn the_frame(links: &Links) -> Result<FrameId, DynamicsError> {
    links.frame.ok_or(DynamicsError::UnknownFrame {
        index: 0,
        frame: FrameId {
            body: None,
            link: usize::MAX,
        },
    })
}

/// A 6-row matrix's entries row-major.
fn row_major6(m: &Matrix6xX<Sym>) -> Vec<Sym> {
    (0..6)
        .flat_map(|r| (0..m.ncols()).map(move |c| m[(r, c)]))
        .collect()
}

/// `[linear; angular]`.
fn linear_angular(linear: &Vector3<Sym>, angular: &Vector3<Sym>) -> Vec<Sym> {
    linear.iter().chain(angular.iter()).copied().collect()
}

/// A matrix's entries row-major.
fn row_major(m: &embedyn_runtime::nalgebra::DMatrix<Sym>) -> Vec<Sym> {
    let (rows, cols) = m.shape();
    (0..rows * cols).map(|k| m[(k / cols, k % cols)]).collect()
}

// The table lists every algorithm once, in the order of the enum's variants (`spec` indexes it).
const _: () = {
    let mut i = 0;
    while i < ALGORITHMS.len() {
        assert!(ALGORITHMS[i].algorithm as usize == i);
        i += 1;
    }
    assert!(Algorithm::RneaDerivativesExt as usize + 1 == ALGORITHMS.len());
};

impl Algorithm {
    /// Whether the function is traced on
    /// [`Model::with_origins_on_joint_axes`](embedyn_runtime::Model::with_origins_on_joint_axes): the same
    /// dynamics in body frames whose translations have more zeros. Only functions whose inputs and outputs
    /// are joint-space quantities may be (poses, Jacobians, wrenches and the centre of mass are in body
    /// frames), and of these the ones that carry inertias or columns of `M` across the joints, where the
    /// zeros pay: `rnea`, `gravity` and `nle` carry only vectors (the G1's `rnea` lost 0.5 % of its
    /// operations and ran 1.09× the time, its second part spilling twice as much; 2026-12-03).
    pub(crate) fn traced_on_moved_origins(self) -> bool {
        matches!(
            self,
            Algorithm::Aba
                | Algorithm::Crba
                | Algorithm::Minv
                | Algorithm::AbaDerivatives
                | Algorithm::RneaDerivatives
                | Algorithm::Step
                | Algorithm::StepDerivatives
        )
    }

    /// Whether the function is derivatives that two methods compute on a tree (analytical recursion,
    /// dual numbers; [`DerivativeTrace`]).
    pub(crate) fn has_derivative_methods(self) -> bool {
        matches!(
            self,
            Algorithm::AbaDerivatives
                | Algorithm::RneaDerivatives
                | Algorithm::AbaDerivativesExt
                | Algorithm::RneaDerivativesExt
                | Algorithm::StepDerivatives
        )
    }

    /// Whether the function is forward dynamics' derivatives, which [`DerivativeTrace::Factors`] can
    /// trace as factors.
    pub(crate) fn has_derivative_factors(self) -> bool {
        matches!(
            self,
            Algorithm::AbaDerivatives | Algorithm::AbaDerivativesExt
        )
    }

    /// Every algorithm, in the order generated code lists them.
    pub const ALL: [Algorithm; ALGORITHMS.len()] = {
        let mut all = [Algorithm::Kinematics; ALGORITHMS.len()];
        let mut i = 0;
        while i < ALGORITHMS.len() {
            all[i] = ALGORITHMS[i].algorithm;
            i += 1;
        }
        all
    };

    /// Its descriptor.
    pub fn spec(self) -> &'static AlgorithmSpec {
        &ALGORITHMS[self as usize]
    }

    /// The generated function's name (`"aba"`, `"crba_independent"`, …).
    pub fn name(self) -> &'static str {
        self.spec().name
    }

    /// Whether the algorithm exists only for models with loops, couplings or mimic joints.
    pub fn needs_constraints(self) -> bool {
        self.spec().needs_constraints
    }

    /// The algorithm with this generated function name (`"aba"`, `"crba_independent"`, …); the error
    /// lists the names there are.
    pub fn from_name(name: &str) -> Result<Algorithm, UnknownAlgorithm> {
        Algorithm::ALL
            .into_iter()
            .find(|a| a.name() == name)
            .ok_or_else(|| UnknownAlgorithm {
                name: name.to_string(),
            })
    }

    /// The algorithms generated when `generated` says so, in table order.
    pub fn generated(generated: WhenGenerated) -> impl Iterator<Item = Algorithm> {
        ALGORITHMS
            .iter()
            .filter(move |s| s.generated == generated)
            .map(|s| s.algorithm)
    }

    /// The algorithms `embedyn eval --algo` and `bench` offer, in table order.
    pub fn offered_by_cli() -> impl Iterator<Item = Algorithm> {
        ALGORITHMS
            .iter()
            .filter(|s| s.cli.is_some())
            .map(|s| s.algorithm)
    }

    /// The algorithms `embedyn bench` times, in table order.
    pub fn timed_by_bench() -> impl Iterator<Item = Algorithm> {
        ALGORITHMS
            .iter()
            .filter(|s| s.cli.is_some_and(|c| c.timed))
            .map(|s| s.algorithm)
    }

    /// The function that computes what the command line reports for this algorithm on a model with
    /// or without constraints (`crba` on a model with constraints: `crba_independent`).
    pub fn reported_by(self, constrained: bool) -> Algorithm {
        match self.spec().cli {
            Some(CliSpec {
                with_constraints: Some(other),
                ..
            }) if constrained => other,
            _ => self,
        }
    }
}

impl AlgorithmSpec {
    /// Whether the generated function returns a scalar on a model with or without constraints.
    pub fn returns_value(&self, constrained: bool) -> bool {
        match self.returns {
            Returns::Nothing => false,
            Returns::SingularityMeasure => constrained,
            Returns::Residual => true,
        }
    }

    /// The documentation of the generated function.
    pub fn doc(&self, constrained: bool) -> &'static str {
        match self.doc_with_constraints {
            Some(doc) if constrained => doc,
            _ => self.doc,
        }
    }

    /// The signature as the standalone crate's README shows it, with its note:
    /// `aba(q: &[S; NQ], v: &[S; NV], tau: &[S; NV], qdd: &mut [S; NV])`.
    pub fn readme_line(&self, constrained: bool) -> String {
        let inputs = self.inputs.iter().map(|i| match i.columns {
            None if i.len == Dim::Scalar => format!("{}: S", i.name),
            None => format!("{}: &[S; {}]", i.name, i.len.code()),
            Some(c) => format!("{}: &[[S; {c}]; {}]", i.name, i.len.code()),
        });
        let outputs = self.outputs.iter().map(|o| match o.shape {
            Shape::Vector(n) => format!("{}: &mut [S; {}]", o.name, n.code()),
            Shape::Matrix(rows, cols) => {
                format!("{}: &mut [[S; {}]; {}]", o.name, cols.code(), rows.code())
            }
        });
        let arguments: Vec<String> = inputs.chain(outputs).collect();
        let returned = if self.returns_value(constrained) {
            " -> S"
        } else {
            ""
        };
        let note = match self.readme_note_with_constraints {
            Some(note) if constrained => note,
            _ => self.readme_note,
        };
        format!(
            "- `{}({}){returned}`{note}\n",
            self.shown_name(),
            arguments.join(", ")
        )
    }

    /// The function's name as documentation shows it: the name, or for a function generated per link
    /// `frame_<link>`.
    pub fn shown_name(&self) -> String {
        match self.parameter {
            Parameter::Frame => format!("{}_<link>", self.name),
            Parameter::None | Parameter::WrenchLinks => self.name.to_string(),
        }
    }
}

/// A function name that no algorithm has (`--only`, `only(…)` in `robot!`); the message lists the names
/// there are.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown function `{name}` (expected {})", known_names())]
pub struct UnknownAlgorithm {
    /// The name given.
    pub name: String,
}

fn known_names() -> String {
    let known: Vec<&str> = Algorithm::ALL.iter().map(|a| a.name()).collect();
    known.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trace that panics leaves the derivative way as it found it: the next expansion on the thread
    /// (a proc-macro server's) must not trace factors it did not ask for.
    #[test]
    fn the_derivative_way_is_restored_after_a_panic() {
        let way = || DERIVATIVE_TRACE.with(std::cell::Cell::get);
        let before = way();
        let panicked = std::panic::catch_unwind(|| {
            with_derivative_trace(
                DerivativeTrace::Factors(DerivativeMethod::Analytical),
                || panic!("a trace failed"),
            )
        });
        assert!(panicked.is_err());
        assert_eq!(way(), before);
        assert_eq!(
            with_derivative_trace(DerivativeTrace::Factors(DerivativeMethod::Analytical), way),
            DerivativeTrace::Factors(DerivativeMethod::Analytical)
        );
        assert_eq!(way(), before);
    }

    /// A row of the function tables of docs/generated-code.md.
    #[derive(Debug, PartialEq)]
    struct Row {
        signature: String,
        what: String,
        /// In the table of functions a model with constraints also has.
        constrained: bool,
    }

    /// The rows of the markdown tables of docs/generated-code.md's "What a module holds".
    fn documented_functions() -> Vec<Row> {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/generated-code.md");
        let text =
            std::fs::read_to_string(path).expect("docs/generated-code.md is in the repository");
        let section = text
            .split("## What a module holds")
            .nth(1)
            .and_then(|s| s.split("\n## ").next())
            .expect("the section \"What a module holds\"");
        let mut constrained = false;
        let mut rows = Vec::new();
        for line in section.lines() {
            if line.contains("loops, couplings or mimic joints also has") {
                constrained = true;
            }
            let Some(cell) = line.strip_prefix("| `") else {
                continue;
            };
            if let Some((signature, what)) = cell.split_once("` | ") {
                rows.push(Row {
                    signature: signature.to_string(),
                    what: what.trim_end_matches(" |").to_string(),
                    constrained,
                });
            }
        }
        rows
    }

    /// `name(q, v, tau, qdd)` (and ` -> S` when it always returns a scalar), as the docs' table writes it.
    fn documented_signature(name: &str, spec: &AlgorithmSpec) -> String {
        let arguments: Vec<&str> = spec
            .inputs
            .iter()
            .map(|i| i.name)
            .chain(spec.outputs.iter().map(|o| o.name))
            .collect();
        // The docs show ` -> S` where the function always returns a scalar (`aba`'s measure for a model
        // with constraints is in the prose).
        let returned = spec.returns_value(spec.needs_constraints);
        format!(
            "{name}({}){}",
            arguments.join(", "),
            if returned { " -> S" } else { "" }
        )
    }

    #[test]
    fn the_docs_table_lists_every_algorithm_as_described() {
        let rows = documented_functions();
        let mut described = Vec::new();
        for spec in ALGORITHMS {
            let signature = documented_signature(&spec.shown_name(), spec);
            let row = rows.iter().find(|r| r.signature == signature);
            assert_eq!(
                row,
                Some(&Row {
                    signature,
                    what: spec.summary.to_string(),
                    constrained: spec.needs_constraints
                }),
                "docs/generated-code.md's row of `{}` differs from its descriptor",
                spec.name
            );
            described.push(row);
            if spec.traced_name != spec.name {
                // The traced step of an iterated algorithm is a function of its own.
                let step = documented_signature(spec.traced_name, spec);
                let row = rows.iter().find(|r| r.signature == step);
                assert!(
                    row.is_some_and(|r| r.constrained == spec.needs_constraints),
                    "docs/generated-code.md does not list `{step}` with `{}`",
                    spec.name
                );
                described.push(row);
            }
        }
        for row in &rows {
            assert!(
                described.contains(&Some(row)),
                "docs/generated-code.md lists {row:?}, which no descriptor describes"
            );
        }
    }

    #[test]
    fn the_descriptors_agree_with_each_other() {
        for spec in ALGORITHMS {
            // Generated with constraints only for a model that has them; an iterated algorithm names its
            // step.
            if spec.generated == WhenGenerated::WithConstraints {
                assert!(spec.needs_constraints, "{}", spec.name);
            }
            assert_eq!(
                spec.wrapper.is_some(),
                spec.traced_name != spec.name,
                "{}",
                spec.name
            );
            // What the command line reports with constraints is computed by a function that exists then.
            if let Some(CliSpec {
                with_constraints: Some(other),
                ..
            }) = spec.cli
            {
                assert!(
                    other.needs_constraints() && other.spec().cli.is_none(),
                    "{}",
                    spec.name
                );
            }
            // A singularity measure is what a function for a model with constraints returns; a tree's
            // functions return nothing but a residual.
            if spec.needs_constraints {
                assert!(spec.returns_value(true), "{}", spec.name);
            }
            assert_eq!(
                spec.inputs.first().map(|i| i.len),
                Some(Dim::Nq),
                "{}",
                spec.name
            );
            // A function of wrenches reads `f_ext` (and only those do); one generated with links
            // has links to be generated for.
            assert_eq!(
                spec.parameter == Parameter::WrenchLinks,
                spec.inputs.iter().any(|i| i.len == Dim::WrenchLinks),
                "{}",
                spec.name
            );
            if spec.generated == WhenGenerated::WithLinks {
                assert_ne!(spec.parameter, Parameter::None, "{}", spec.name);
            }
        }
    }

    #[test]
    fn every_algorithm_is_found_by_its_name() {
        for a in Algorithm::ALL {
            assert_eq!(Algorithm::from_name(a.name()), Ok(a));
            assert_eq!(a.spec().algorithm, a);
        }
        assert_eq!(
            Algorithm::from_name("abba"),
            Err(UnknownAlgorithm {
                name: "abba".into()
            })
        );
        let e = Algorithm::from_name("abba").unwrap_err().to_string();
        assert_eq!(
            e,
            "unknown function `abba` (expected kinematics, aba, rnea, gravity, nle, crba, minv, complete, embedding, crba_independent, integrate, difference, aba_ext, rnea_ext, nle_ext, frame, com, centroidal, centroidal_bias, aba_derivatives, rnea_derivatives, step, step_derivatives, aba_derivatives_independent, aba_derivatives_ext, rnea_derivatives_ext)"
        );
    }

    #[test]
    fn the_command_line_reports_crba_independent_for_crba_with_constraints() {
        let offered: Vec<&str> = Algorithm::offered_by_cli().map(Algorithm::name).collect();
        assert_eq!(
            offered,
            [
                "aba",
                "rnea",
                "gravity",
                "nle",
                "crba",
                "integrate",
                "difference"
            ]
        );
        let timed: Vec<&str> = Algorithm::timed_by_bench().map(Algorithm::name).collect();
        assert_eq!(timed, ["aba", "rnea", "gravity", "nle", "crba"]);
        assert_eq!(
            Algorithm::Crba.reported_by(true),
            Algorithm::CrbaIndependent
        );
        assert_eq!(Algorithm::Crba.reported_by(false), Algorithm::Crba);
        assert_eq!(Algorithm::Aba.reported_by(true), Algorithm::Aba);
    }
}

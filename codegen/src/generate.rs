//! Code generation: the one entry point the `robot!` macro, `build.rs` and `embedyn generate` share.
//!
//! The interpreted algorithms run on the traced scalar ([`crate::trace::Sym`]) over the model built from
//! the IR, which unrolls them for this model and folds its constants; the tape becomes straight-line Rust,
//! once per scalar type.

pub use crate::algorithm::Algorithm;
use crate::algorithm::{Dims, Links, Parameter, Shape, WhenGenerated};
use crate::emit::{function, Arg, Code, Emitted, Output};
use crate::error::{DescriptorMismatch, Shared};
use crate::names::{code_span, shown};
use crate::size;
use crate::trace::{input, record_within, snap, Sym};
use crate::value_names::Owners;
use crate::{build_model, LoadError, LoadErrorKind, Loaded, Location, ModelOptions};
use embedyn_runtime::constraints::{singularity_threshold, COMPLETION_MAX_STEPS};
use embedyn_runtime::derivative_singularity_threshold;
use embedyn_runtime::{FrameId, Model, Real, Reference, Workspace};

use proc_macro2::TokenStream;
use quote::{format_ident, quote};

/// What to generate.
#[derive(Clone, Debug)]
pub struct GenerateOptions {
    /// How the model is assembled from the file (floating root, …).
    pub model: ModelOptions,
    /// Default: `kinematics`, `aba`, `rnea`, `crba` (the O(N²) inverse only when asked for).
    pub algorithms: Vec<Algorithm>,
    /// Emit the `f64` module.
    pub f64: bool,
    /// Emit the `f32` module.
    pub f32: bool,
    /// Path of the helper module the code calls (`sincos`, `sqrt`); `::embedyn::codegen_support` for
    /// the macro, `crate::helpers` for a standalone crate.
    pub helpers: TokenStream,
    /// Generate exactly `algorithms` (the user chose them: firmware that needs only `aba` pays only for
    /// `aba`). When false, a model with constraints also gets `complete`, `embedding` and
    /// `crba_independent`.
    pub exact: bool,
    /// Refuse to generate code that rustc is estimated to need more than this many MB of memory to
    /// compile (checked before tracing from the model and after tracing from the code, always before
    /// anything is formatted or written; see `size.rs`). `None`: no limit.
    pub max_compile_memory_mb: Option<u64>,
    /// Links named at generation time: those whose wrenches `aba_ext`, `rnea_ext` and `nle_ext` take,
    /// and those that get a frame function each.
    pub links: LinkOptions,
    /// Lanes of the lane modules (`f64x4`, `f32x4` for 4: every function evaluating that many states
    /// at once, one per lane); 0 for none (the default). Macro `lanes = 4`, `embedyn generate --lanes 4`.
    pub lanes: usize,
    /// Which `f64` functions get an AVX twin that runs where the CPU has AVX (x86-64 builds without AVX
    /// enabled; `src/dispatch.rs`, docs/generated-code.md). Default: the large ones; macro
    /// `avx_twins = none|large|all`, `embedyn generate --avx-twins none|large|all`.
    pub avx_twins: crate::AvxTwins,
    /// The standalone crate's package name (`embedyn generate --name`; checked by
    /// [`crate::names::check_crate_name`]). `None`: the robot's name as an identifier, then `_dynamics`.
    /// Only the standalone crate has one.
    pub crate_name: Option<String>,
}

/// Links named at generation time, by name (macro `wrenches(…)`, `frames(…)`, `reference = …`;
/// `embedyn generate --wrenches`, `--frames`, `--reference`). A name the model has no link of is an
/// error naming it and the closest link names; a name given twice counts once.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinkOptions {
    /// The links that take external wrenches, in the order of `f_ext`'s rows (`WRENCH_LINKS`): without
    /// `only(…)`, naming any generates `aba_ext` and `rnea_ext`.
    pub wrenches: Vec<String>,
    /// The links that get a function `frame_<link>` each (pose, Jacobian, bias).
    pub frames: Vec<String>,
    /// Where the frame functions express their Jacobian and bias (default `local_world_aligned`).
    pub reference: Reference,
}

impl LinkOptions {
    /// Whether the links `parameter` reads are named.
    fn named(&self, parameter: Parameter) -> bool {
        match parameter {
            Parameter::None => true,
            Parameter::WrenchLinks => !self.wrenches.is_empty(),
            Parameter::Frame => !self.frames.is_empty(),
        }
    }
}

impl Default for GenerateOptions {
    fn default() -> Self {
        GenerateOptions {
            model: ModelOptions::default(),
            algorithms: Algorithm::generated(WhenGenerated::ByDefault).collect(),
            f64: true,
            f32: true,
            helpers: quote!(::embedyn::codegen_support),
            exact: false,
            max_compile_memory_mb: Some(crate::size::DEFAULT_COMPILE_MEMORY_MB),
            links: LinkOptions::default(),
            lanes: 0,
            avx_twins: crate::AvxTwins::Large,
            crate_name: None,
        }
    }
}

impl GenerateOptions {
    /// The scalar modules asked for, in order (`f64`, `f32`).
    pub fn scalars(&self) -> Vec<&'static str> {
        [(self.f64, "f64"), (self.f32, "f32")]
            .into_iter()
            .filter_map(|(enabled, scalar)| enabled.then_some(scalar))
            .collect()
    }

    /// The functions a user asked for, read the same way by the `robot!` macro and `embedyn generate`:
    /// exactly `only` (each once, in the order given) when given, else the default ones; and `also`
    /// (the functions generated on request, `minv`) added when missing.
    pub fn with_requested(mut self, only: Option<Vec<Algorithm>>, also: &[Algorithm]) -> Self {
        if let Some(only) = only {
            self.algorithms = Vec::new();
            for algo in only {
                if !self.algorithms.contains(&algo) {
                    self.algorithms.push(algo);
                }
            }
            self.exact = true;
        }
        for &algo in also {
            if !self.algorithms.contains(&algo) {
                self.algorithms.push(algo);
            }
        }
        self
    }

    /// The functions generated for a model with or without constraints: `algorithms`; unless `exact`,
    /// also those of the links named (`aba_ext` and `rnea_ext` for wrenches, the frame functions for
    /// frames) and for a model with constraints those generated with constraints (`complete`, …).
    pub fn generated_algorithms(&self, constrained: bool) -> Vec<Algorithm> {
        let mut algorithms = self.algorithms.clone();
        if !self.exact {
            for extra in Algorithm::generated(WhenGenerated::WithLinks) {
                if self.links.named(extra.spec().parameter) && !algorithms.contains(&extra) {
                    algorithms.push(extra);
                }
            }
        }
        if constrained && !self.exact {
            for extra in Algorithm::generated(WhenGenerated::WithConstraints) {
                if !algorithms.contains(&extra) {
                    algorithms.push(extra);
                }
            }
        }
        algorithms
    }
}

/// Version of the generator, part of every cache key: generated code from another version is never reused.
pub const GENERATOR_VERSION: &str = concat!(env!("CARGO_PKG_VERSION"), "-g4");

/// The model the generator traces: rotations and axes within 1e-14 of 0 or ±1 made exact, so that the
/// zero structure of axis-aligned joints and right-angle frames folds away.
fn snapped(model: &Model<f64>) -> Model<f64> {
    let mut m = model.clone();
    for j in &mut m.joints {
        j.axis = j.axis.map(snap);
        j.placement.rotation = j.placement.rotation.map(snap);
    }
    m
}

/// An error about the whole robot, at its source file.
fn located_at_robot(loaded: &Loaded, kind: LoadErrorKind) -> LoadError {
    LoadError::at(
        Location::new(
            &loaded.robot.source,
            None,
            format!("robot \"{}\"", shown(&loaded.robot.name)),
        ),
        kind,
    )
}

/// One generated function: an algorithm, and for a frame function its link.
struct Instance<'a> {
    algorithm: Algorithm,
    /// The generated function's name (`aba`, `complete_step`, `frame_lf_foot`).
    name: String,
    /// The link of a frame function, as the model names it.
    link: Option<&'a str>,
    /// Its frame.
    frame: Option<FrameId>,
}

/// The index constant of every link of `model`, by link name: one spelling per link for the `frames::` and
/// `wrench::` constants and the `frame_<link>` functions, so that `wrench::FOOT` and `frame_foot` are the
/// link `frames::FOOT` is, whatever links a user names and in whatever order ([`crate::names::constants`]
/// over the bodies' links in coordinate order, then the links fixed to the world).
pub fn link_constants<T: Real>(model: &Model<T>) -> std::collections::HashMap<String, String> {
    let names: Vec<&str> = model.frames().filter_map(|f| model.frame_name(f)).collect();
    names
        .iter()
        .map(|n| n.to_string())
        .zip(crate::names::constants(&names, "link"))
        .collect()
}

/// The generated frame functions' names for `links` of `model` (`frame_` and the link's constant in lower
/// case: `frame_lf_foot` for `frames::LF_FOOT`), in the order given.
pub fn frame_function_names<T: Real>(model: &Model<T>, links: &[&str]) -> Vec<String> {
    let constants = link_constants(model);
    links
        .iter()
        .map(|l| {
            let c = constants
                .get(*l)
                .cloned()
                .unwrap_or_else(|| crate::names::identifier(l, "link").to_ascii_uppercase());
            format!("frame_{}", c.to_ascii_lowercase())
        })
        .collect()
}

/// The frames of the links `names`, in order; a name of no link of the model is an error at `option`
/// naming it and the closest link names, and so is a link named twice (`per_link` says why once).
fn resolve_links(
    loaded: &Loaded,
    model: &Model<f64>,
    names: &[String],
    option: &'static str,
    per_link: &'static str,
) -> Result<Vec<(String, FrameId)>, LoadError> {
    let mut links: Vec<(String, FrameId)> = Vec::new();
    for name in names {
        if links.iter().any(|(n, _)| n == name) {
            return Err(LoadError::at(
                Location::new(&loaded.robot.source, None, option),
                LoadErrorKind::LinkNamedTwice {
                    link: name.clone(),
                    option,
                    per_link,
                },
            ));
        }
        let Some(frame) = model.frame(name) else {
            let known: Vec<&str> = model.frames().filter_map(|f| model.frame_name(f)).collect();
            let closest = crate::names::closest(name, known.iter().copied());
            return Err(LoadError::at(
                Location::new(&loaded.robot.source, None, option),
                LoadErrorKind::UnknownLinkNamed {
                    link: name.clone(),
                    hint: link_hint(&closest),
                },
            ));
        };
        links.push((name.clone(), frame));
    }
    Ok(links)
}

/// ` (did you mean "lf_foot"?)`, or where no link name is close, where the names are listed.
fn link_hint(closest: &[&str]) -> String {
    let quoted: Vec<String> = closest
        .iter()
        .map(|n| format!("\"{}\"", shown(n)))
        .collect();
    match quoted.split_last() {
        None => " (`embedyn info` lists the model's links as `frames`)".to_string(),
        Some((last, [])) => format!(" (did you mean {last}?)"),
        Some((last, rest)) => format!(" (did you mean {} or {last}?)", rest.join(", ")),
    }
}

/// The generated items before they are joined into a file or a token stream: the constants at the top
/// and the functions of the scalar modules (the same code for `f64` and `f32`: only `S` differs, so
/// each algorithm is traced and emitted once).
struct Generated {
    header: TokenStream,
    scalars: Vec<&'static str>,
    functions: Vec<Emitted>,
    /// For each of `functions`, its code with an AVX twin where it has one: the `f64` module's copy
    /// (src/dispatch.rs).
    f64_twins: Vec<Option<Code>>,
    /// The same functions for the lane modules (those without a hand-written wrapper), when asked for.
    lane_functions: Vec<Emitted>,
    /// For each of `lane_functions`, its code with an AVX twin where it has one: the copy of the lane
    /// module of 256-bit values (src/dispatch.rs, `lanes_of_256_bits`).
    lane_twins: Vec<Option<Code>>,
    /// Lanes per lane module (0: none).
    lanes: usize,
    /// The helper module's path (for the lane modules' scalar type).
    helpers: TokenStream,
    /// Whether the model has loops, couplings or mimic joints (then each scalar module has its
    /// `SINGULARITY_THRESHOLD`).
    constrained: bool,
    /// The limits of each coordinate, for the scalar modules' `LOWER`, `UPPER`, `VELOCITY`, `EFFORT`.
    limits: LimitTables,
}

impl Generated {
    /// The scalar modules' functions, each written by `render` (as tokens or as text): the plain code,
    /// and for the `f64` module a function's code with its AVX twin where it has one (src/dispatch.rs).
    fn scalar_functions<T: Clone, E>(
        &self,
        render: impl Fn(&Code) -> Result<T, E>,
    ) -> Result<Rendered<T>, E> {
        Rendered::of_functions(&self.functions, &self.f64_twins, render)
    }

    /// The lane modules' functions, each written by `render`: for the lane module of 256-bit values a
    /// function's code with its AVX twin where it has one.
    fn lane_functions<T: Clone, E>(
        &self,
        render: impl Fn(&Code) -> Result<T, E>,
    ) -> Result<Rendered<T>, E> {
        Rendered::of_functions(&self.lane_functions, &self.lane_twins, render)
    }
}

/// Functions as written for a module: without twins, and with them where they have one.
struct Rendered<T> {
    /// Every function as traced.
    plain: Vec<T>,
    /// Every function with its AVX twin where it has one (the `f64` module's, the 256-bit lane module's).
    twinned: Vec<T>,
}

impl<T: Clone> Rendered<T> {
    /// `functions` and their `twins` (one per function) written by `render`.
    fn of_functions<E>(
        functions: &[Emitted],
        twins: &[Option<Code>],
        render: impl Fn(&Code) -> Result<T, E>,
    ) -> Result<Rendered<T>, E> {
        let plain = functions
            .iter()
            .map(|f| render(&f.code))
            .collect::<Result<Vec<T>, E>>()?;
        let twinned = plain
            .iter()
            .zip(twins)
            .map(|(plain, twin)| twin.as_ref().map_or_else(|| Ok(plain.clone()), &render))
            .collect::<Result<Vec<T>, E>>()?;
        Ok(Rendered { plain, twinned })
    }

    /// The functions of a module with twins (`true`) or without.
    fn of(&self, with_twins: bool) -> &[T] {
        if with_twins {
            &self.twinned
        } else {
            &self.plain
        }
    }
}

/// Each coordinate's limits (`None` where the model gives none): position limits per entry of `q`,
/// velocity and effort limits per entry of `v`.
struct LimitTables {
    lower: Vec<Option<f64>>,
    upper: Vec<Option<f64>>,
    velocity: Vec<Option<f64>>,
    effort: Vec<Option<f64>>,
}

impl LimitTables {
    fn of(model: &Model<f64>) -> Self {
        let mut t = LimitTables {
            lower: Vec::with_capacity(model.nq()),
            upper: Vec::with_capacity(model.nq()),
            velocity: Vec::with_capacity(model.nv()),
            effort: Vec::with_capacity(model.nv()),
        };
        for j in &model.joints {
            for _ in 0..j.nq() {
                t.lower.push(j.limits.lower);
                t.upper.push(j.limits.upper);
            }
            for _ in 0..j.nv() {
                t.velocity.push(j.limits.velocity);
                t.effort.push(j.limits.effort);
            }
        }
        t
    }

    /// `LOWER`, `UPPER`, `VELOCITY` and `EFFORT` in `scalar`: each value as the interpreted model in that
    /// scalar holds it (rounded once from f64), an absent bound (or one beyond f32's range) as ±infinity.
    fn constants(&self, scalar: &str) -> TokenStream {
        let value = |x: Option<f64>, absent: TokenStream| -> TokenStream {
            let Some(x) = x else { return absent };
            let (negative, literal) = if scalar == "f32" {
                let y = x as f32;
                if y.is_infinite() {
                    return if y > 0.0 {
                        quote!(S::INFINITY)
                    } else {
                        quote!(-S::INFINITY)
                    };
                }
                (
                    y.is_sign_negative(),
                    proc_macro2::Literal::f32_unsuffixed(y.abs()),
                )
            } else {
                (
                    x.is_sign_negative(),
                    proc_macro2::Literal::f64_unsuffixed(x.abs()),
                )
            };
            if negative {
                quote!(-#literal)
            } else {
                quote!(#literal)
            }
        };
        let row = |values: &[Option<f64>], absent: TokenStream| -> Vec<TokenStream> {
            values.iter().map(|&x| value(x, absent.clone())).collect()
        };
        let lower = row(&self.lower, quote!(-S::INFINITY));
        let upper = row(&self.upper, quote!(S::INFINITY));
        let velocity = row(&self.velocity, quote!(S::INFINITY));
        let effort = row(&self.effort, quote!(S::INFINITY));
        quote! {
            /// Lower position limit of each coordinate of `q` (rad or m; `<limit lower>`): `-INFINITY`
            /// where the model gives none (continuous and floating joints, a missing attribute).
            pub const LOWER: [S; super::NQ] = [#(#lower),*];
            /// Upper position limit of each coordinate of `q` (rad or m; `<limit upper>`): `INFINITY`
            /// where the model gives none.
            pub const UPPER: [S; super::NQ] = [#(#upper),*];
            /// Velocity limit of each entry of `v` (rad/s or m/s, a magnitude; `<limit velocity>`):
            /// `INFINITY` where the model gives none (floating joints, a missing attribute).
            pub const VELOCITY: [S; super::NV] = [#(#velocity),*];
            /// Effort limit of each entry of `tau` (N·m or N, a magnitude; `<limit effort>`): `INFINITY`
            /// where the model gives none.
            pub const EFFORT: [S; super::NV] = [#(#effort),*];
        }
    }
}

/// `pub mod #module { pub const NAME: usize = index; … }`: one constant per name (see
/// [`crate::names::constants`]), each documented with the name it stands for.
fn index_module(
    module: &str,
    doc: &str,
    names: &[&str],
    prefix: &str,
    value: impl Fn(usize) -> usize,
    what: &str,
) -> TokenStream {
    let constants = crate::names::constants(names, prefix);
    index_module_spelled(module, doc, names, &constants, value, what)
}

/// [`index_module`] with the constants' spelling given (`constants[i]` for `names[i]`).
fn index_module_spelled(
    module: &str,
    doc: &str,
    names: &[&str],
    constants: &[String],
    value: impl Fn(usize) -> usize,
    what: &str,
) -> TokenStream {
    let module = format_ident!("{}", module);
    let items = constants
        .iter()
        .zip(names)
        .enumerate()
        .map(|(i, (c, name))| {
            let ident = format_ident!("{}", c);
            let doc = format!(" {what} {}.", code_span(name));
            let index = proc_macro2::Literal::usize_unsuffixed(value(i));
            quote! {
                #[doc = #doc]
                pub const #ident: usize = #index;
            }
        });
    let doc = format!(" {doc}");
    quote! {
        #[doc = #doc]
        #[allow(dead_code)]
        pub mod #module {
            #(#items)*
        }
    }
}

fn generate_items(loaded: &Loaded, options: &GenerateOptions) -> Result<Generated, LoadError> {
    let model64 = loaded.model::<f64>(&options.model)?;
    if options.f32 {
        // The f32 functions fold the same constants as f32 literals: each must fit f32.
        crate::assemble::convert_model::<f32>(&loaded.robot, &model64).map_err(|e| LoadError {
            kind: LoadErrorKind::NotForF32 {
                inner: Box::new(e.kind),
            },
            ..e
        })?;
    }
    if let Some(a) = options
        .algorithms
        .iter()
        .find(|a| a.needs_constraints() && !model64.has_constraints())
    {
        return Err(located_at_robot(
            loaded,
            LoadErrorKind::NeedsConstraints { function: *a },
        ));
    }
    let wrench_links = resolve_links(
        loaded,
        &model64,
        &options.links.wrenches,
        "--wrenches / wrenches(…)",
        "one row of `f_ext` per link",
    )?;
    let frame_links = resolve_links(
        loaded,
        &model64,
        &options.links.frames,
        "--frames / frames(…)",
        "one frame function per link",
    )?;
    let algorithms = options.generated_algorithms(model64.has_constraints());
    if let Some(a) = algorithms
        .iter()
        .find(|a| !options.links.named(a.spec().parameter))
    {
        return Err(located_at_robot(
            loaded,
            LoadErrorKind::NeedsLinks { function: *a },
        ));
    }
    // Links named for functions that are not generated would be silently ignored.
    for (named, parameter, option, functions) in [
        (
            !wrench_links.is_empty(),
            Parameter::WrenchLinks,
            "--wrenches / wrenches(…)",
            "`aba_ext`, `rnea_ext`, `nle_ext`, `aba_derivatives_ext` or `rnea_derivatives_ext`",
        ),
        (
            !frame_links.is_empty(),
            Parameter::Frame,
            "--frames / frames(…)",
            "`frame`",
        ),
    ] {
        if named && !algorithms.iter().any(|a| a.spec().parameter == parameter) {
            return Err(located_at_robot(
                loaded,
                LoadErrorKind::LinksUnused { option, functions },
            ));
        }
    }
    if options.lanes > 0 {
        for scalar in &options.scalars() {
            if lane_type(scalar, options.lanes).is_none() {
                return Err(located_at_robot(
                    loaded,
                    LoadErrorKind::NoLaneType {
                        scalar,
                        lanes: options.lanes,
                    },
                ));
            }
        }
    }
    let model: Model<Sym> = snapped(&model64).cast();
    let (nq, nv) = (model.nq(), model.nv());
    let names: Vec<&str> = model.joints.iter().map(|j| j.name.as_str()).collect();
    let scalars = options.scalars();
    // One function per algorithm, and per link named for a frame function.
    let frame_names: Vec<&str> = frame_links.iter().map(|(name, _)| name.as_str()).collect();
    let frame_functions = frame_function_names(&model64, &frame_names);
    // A lane module's batch form of `frame_foo` is `frame_foo_batch`, which is also the frame function of
    // a link `foo_batch` (attacker's trial: E0428 in the lane module).
    if options.lanes > 0 {
        for (k, function) in frame_functions.iter().enumerate() {
            if let Some(j) = frame_functions
                .iter()
                .position(|other| *other == format!("{function}_batch"))
            {
                return Err(located_at_robot(
                    loaded,
                    LoadErrorKind::BatchNameTaken {
                        function: function.clone(),
                        link: frame_names[j].to_string(),
                        of_link: frame_names[k].to_string(),
                    },
                ));
            }
        }
    }
    let mut instances = Vec::new();
    for &algo in &algorithms {
        match algo.spec().parameter {
            Parameter::Frame => {
                for ((link, frame), ident) in frame_links.iter().zip(&frame_functions) {
                    instances.push(Instance {
                        algorithm: algo,
                        name: ident.clone(),
                        link: Some(link.as_str()),
                        frame: Some(*frame),
                    });
                }
            }
            Parameter::None | Parameter::WrenchLinks => instances.push(Instance {
                algorithm: algo,
                name: algo.spec().traced_name.to_string(),
                link: None,
                frame: None,
            }),
        }
    }
    // Every name at the module's level: the public functions (and wrappers' names, every algorithm's
    // name), which the parts of long functions must not take.
    let mut taken: std::collections::HashSet<String> = instances
        .iter()
        .map(|i| i.name.clone())
        .chain(Algorithm::ALL.iter().map(|a| a.name().to_string()))
        .chain(
            Algorithm::ALL
                .iter()
                .map(|a| a.spec().traced_name.to_string()),
        )
        // The lane modules' batch forms (`aba_batch`, `frame_foot_batch`) and their items.
        .chain(instances.iter().map(|i| format!("{}_batch", i.name)))
        .chain(["S", "E", "LANES"].map(String::from))
        .collect();
    let wrench_frames: Vec<FrameId> = wrench_links.iter().map(|(_, f)| *f).collect();
    let wrench_names: Vec<&str> = wrench_links.iter().map(|(n, _)| n.as_str()).collect();
    let mut functions = Vec::new();
    let mut f64_twins = Vec::new();
    let mut lane_functions = Vec::new();
    let mut lane_twins = Vec::new();
    // The AVX lane type of the lane module of 256-bit values, if one is generated.
    let avx_type = scalars
        .iter()
        .find_map(|s| crate::dispatch::avx_lane_type(s, options.lanes));
    if !scalars.is_empty() {
        let instance_algorithms: Vec<(Algorithm, &str)> = instances
            .iter()
            .map(|i| (i.algorithm, i.name.as_str()))
            .collect();
        let mut sizes =
            check_size_before_tracing(loaded, &model64, &instance_algorithms, &scalars, options)?;
        // The model some joint-space functions are traced on (fewer operations, the same dynamics;
        // runtime/src/joint_axis_origins.rs), found once for all of them.
        let moved_model = model.with_origins_on_joint_axes();
        for (k, instance) in instances.iter().enumerate() {
            let algo = instance.algorithm;
            let links = Links {
                wrenches: &wrench_frames,
                frame: instance.frame,
                reference: options.links.reference,
            };
            let limit = options.max_compile_memory_mb;
            let budget = size::tape_budget(limit, scalars.len());
            let request = FunctionRequest {
                loaded,
                model: &model,
                moved_model: &moved_model,
                instance,
                links: &links,
                wrench_names: &wrench_names,
                single_precision: options.f32,
            };
            let (function, lane_function) = match generate_algorithm(
                &request,
                &mut taken,
                Emission {
                    helpers: &options.helpers,
                    lanes: options.lanes,
                    budget,
                },
            )? {
                TracedFunction::Emitted(function, lane_function) => (function, lane_function),
                // Refused on what was counted: no function that long fits the limit.
                TracedFunction::Stopped(full) => {
                    let name = sizes[k].name.take();
                    sizes[k] = size::FunctionSize {
                        name,
                        ..size::FunctionSize::stopped(algo, full)
                    };
                    return Err(size::refuse(loaded, &sizes, &scalars, limit.unwrap_or(0)));
                }
            };
            // Whether the f64 module's copy gets an AVX twin by its size (f64 only: the twin doubles the
            // function's compile time, src/dispatch.rs); the twins are written once all are chosen, below.
            // Asked for (`avx_twins = all`), the twin counts here and a limit it passes refuses the code;
            // by default (`large`) it is a speed-up like the budget twins, added below where it fits.
            let twinned = options.f64 && options.avx_twins == crate::AvxTwins::All;
            // The lane function's copy with an AVX twin, for the lane module of 256-bit values.
            let lane_twin = lane_function.as_ref().and_then(|lane| {
                let avx_type =
                    avx_type.filter(|_| options.avx_twins.twins_lanes(lane.statements))?;
                Some(crate::dispatch::with_avx_twin(
                    &lane.code,
                    &instance.name,
                    &options.helpers,
                    crate::dispatch::TwinOf::Lanes { avx_type },
                ))
            });
            // Constants are folded in f64; the f32 module writes them as f32 literals.
            if options.f32 && function.largest_constant > f64::from(f32::MAX) {
                return Err(located_at_robot(
                    loaded,
                    LoadErrorKind::ConstantBeyondF32 {
                        function: algo,
                        constant: function.largest_constant,
                    },
                ));
            }
            sizes[k] = size::FunctionSize {
                algorithm: algo,
                operations: function.operations,
                // The lane module's copy is compiled beside each scalar's, at several times the cost.
                compile_bytes: function.compile_bytes
                    // The twin is one more copy, in the f64 module (this is per scalar module).
                    + if twinned {
                        function.compile_bytes / scalars.len() as f64
                    } else {
                        0.0
                    }
                    + lane_function.as_ref().map_or(0.0, |f| {
                        // The lane twins (AVX and AVX-512): each part of one more lane copy, in the
                        // 256-bit lane module.
                        let twin = if lane_twin.is_some() {
                            2.0 * size::LANE_TWIN_MEMORY_SHARE / scalars.len() as f64
                        } else {
                            0.0
                        };
                        size::LANE_MEMORY_FACTOR * f.compile_bytes * (1.0 + twin)
                    }),
                traced: true,
                tracing_stopped: false,
                twinned,
                name: sizes[k].name.take(),
            };
            // Exact for what is traced: refused as soon as that alone is too large.
            size::check(loaded, &sizes[..=k], &sizes, &scalars, limit, 1.0)?;
            functions.push(function);
            if lane_function.is_some() {
                lane_twins.push(lane_twin);
            }
            lane_functions.extend(lane_function);
        }
        // One more copy of function `k` in the f64 module, if the estimate of the compiler's memory
        // stays within the limit: counted in `sizes` then.
        let add_copy = |sizes: &mut Vec<size::FunctionSize>, k: usize| -> bool {
            let bytes = functions[k].compile_bytes / scalars.len() as f64;
            if let Some(limit) = options.max_compile_memory_mb {
                let mut with = sizes.clone();
                with[k].compile_bytes += bytes;
                if size::compile_memory_mb(&with, scalars.len()) > limit as f64 {
                    return false;
                }
            }
            sizes[k].compile_bytes += bytes;
            true
        };
        let mut avx512 = vec![false; functions.len()];
        if options.f64 {
            // The default's twins by size, in the order of the functions, each where the estimate of the
            // compiler's memory stays within the limit (a new user's trial: GRBDA's jvrc1 humanoid, whose
            // five functions fit 2 GB without the twins of `aba` and `rnea`, was refused by `embedyn bench`).
            let by_size = |k: &usize| {
                options.avx_twins == crate::AvxTwins::Large
                    && options.avx_twins.twins(functions[*k].statements)
            };
            for k in (0..functions.len()).filter(by_size) {
                if add_copy(&mut sizes, k) {
                    sizes[k].twinned = true;
                }
            }
            let statements: Vec<usize> = functions.iter().map(|f| f.statements).collect();
            // Smaller functions' twins, under the module's budget (src/dispatch.rs): decided once every
            // function is traced, as the budget is shared. They are a speed-up, not a request: one that
            // would take the estimate of the compiler's memory over the limit is left out (smallest
            // first, so the rest are too).
            let twinned: Vec<bool> = sizes.iter().map(|f| f.twinned).collect();
            for k in options.avx_twins.small_twins(&statements, &twinned) {
                if !add_copy(&mut sizes, k) {
                    break;
                }
                sizes[k].twinned = true;
            }
            // AVX-512 twins beside some AVX ones (src/dispatch.rs), again within the compiler's memory.
            let twinned: Vec<bool> = sizes.iter().map(|f| f.twinned).collect();
            for k in options
                .avx_twins
                .avx512_twins(model64.nv(), &statements, &twinned)
            {
                avx512[k] = add_copy(&mut sizes, k);
            }
        }
        // The chosen twins' code.
        f64_twins = functions
            .iter()
            .zip(&sizes)
            .zip(&instances)
            .zip(&avx512)
            .map(|(((function, size), instance), &avx512)| {
                size.twinned.then(|| {
                    crate::dispatch::with_avx_twin(
                        &function.code,
                        &instance.name,
                        &options.helpers,
                        crate::dispatch::TwinOf::Scalar { avx512 },
                    )
                })
            })
            .collect();
    }
    let independent: Vec<bool> = (0..model64.joints.len())
        .map(|j| model64.is_independent(j))
        .collect();
    let nj = names.len();
    let frames: Vec<&str> = model64
        .bodies
        .iter()
        .flat_map(|b| b.links.iter().map(String::as_str))
        .collect();
    let nf = frames.len();
    let ni = model64.independent_nv();
    // Names reach the docs as escaped code spans (docs/model-format.md, "Names are data"); `JOINTS` and
    // `FRAMES` below hold them exactly, as string literals that `quote` escapes.
    let shown: Vec<String> = names.iter().map(|n| code_span(n)).collect();
    let doc = format!(
        "Dynamics of {} generated by embedyn {} from {}: nq = {nq}, nv = {nv}; joints in coordinate order: {}.",
        code_span(&model64.name),
        GENERATOR_VERSION,
        code_span(&loaded.robot.source.file_name().map_or_else(String::new, |f| f.to_string_lossy().into_owned())),
        shown.join(", ")
    );
    let doc = format!(" {doc}");
    let [nq, nv, ni, nj, nf] = [nq, nv, ni, nj, nf].map(proc_macro2::Literal::usize_unsuffixed);
    let header = quote! {
        #[doc = #doc]
        #[allow(dead_code)]
        pub const NQ: usize = #nq;
        /// Length of `v`, `tau` and `qdd`.
        #[allow(dead_code)]
        pub const NV: usize = #nv;
        /// Number of independent velocity coordinates (`NV` for a tree).
        #[allow(dead_code)]
        pub const NI: usize = #ni;
        /// Joint names in coordinate order (embedyn's docs/conventions.md).
        #[allow(dead_code)]
        pub const JOINTS: [&str; #nj] = [#(#names),*];
        /// Whether each joint's coordinate is independent (false for gear- or mimic-driven joints).
        #[allow(dead_code)]
        pub const INDEPENDENT: [bool; #nj] = [#(#independent),*];
        /// The links whose poses `kinematics` returns, in its order (every link on a moving body; links
        /// fixed to the world are constant and not listed).
        #[allow(dead_code)]
        pub const FRAMES: [&str; #nf] = [#(#frames),*];
    };
    // Links are spelled alike in `frames`, `wrench` and the frame functions' names.
    let link_constants = link_constants(&model64);
    let spelled = |names: &[&str]| -> Vec<String> {
        names
            .iter()
            .map(|n| link_constants.get(*n).cloned().unwrap_or_default())
            .collect()
    };
    let q_index: Vec<usize> = model64.joints.iter().map(|j| j.q_index).collect();
    let v_index: Vec<usize> = model64.joints.iter().map(|j| j.v_index).collect();
    let indices = [
        index_module(
            "joints",
            "Index in `JOINTS` (and `INDEPENDENT`) of each joint, by name: `JOINTS[joints::KNEE]` is the joint `knee`. Names are the joint names in SCREAMING_SNAKE_CASE (embedyn's docs/generated-code.md says how other names are spelled).",
            &names,
            "joint",
            |i| i,
            "Index in `JOINTS` of joint",
        ),
        index_module(
            "q_index",
            "Index in `q` (and `LOWER`, `UPPER`) of each joint's first coordinate, by name (as in `joints`).",
            &names,
            "joint",
            |i| q_index[i],
            "Index in `q` of the first coordinate of joint",
        ),
        index_module(
            "v_index",
            "Index in `v`, `qdd` and `tau` (and `VELOCITY`, `EFFORT`) of each joint's first entry, by name (as in `joints`).",
            &names,
            "joint",
            |i| v_index[i],
            "Index in `v` of the first entry of joint",
        ),
        index_module_spelled(
            "frames",
            "Index in `FRAMES` (and in the output of `kinematics`) of each link, by name: `FRAMES[frames::LF_FOOT]` is the link `lf_foot`.",
            &frames,
            &spelled(&frames),
            |i| i,
            "Index in `FRAMES` of link",
        ),
    ];
    let wrench_items = if wrench_names.is_empty() {
        quote!()
    } else {
        let k = proc_macro2::Literal::usize_unsuffixed(wrench_names.len());
        let index = index_module_spelled(
            "wrench",
            "Row in `f_ext` (of `aba_ext`, `rnea_ext`, `nle_ext`) and index in `WRENCH_LINKS` of each link named to take an external wrench, by name (spelled as in `frames`: `wrench::FOOT` is the link `frames::FOOT` is).",
            &wrench_names,
            &spelled(&wrench_names),
            |i| i,
            "Row in `f_ext` of the wrench on link",
        );
        quote! {
            /// The links whose external wrenches `f_ext` holds (`aba_ext`, `rnea_ext`, `nle_ext`), in the
            /// order of its rows: row `k` is `[fx, fy, fz, tx, ty, tz]` (N, N·m) on link `WRENCH_LINKS[k]`,
            /// in that link's frame, about its origin.
            #[allow(dead_code)]
            pub const WRENCH_LINKS: [&str; #k] = [#(#wrench_names),*];
            #index
        }
    };
    let header = quote! {
        #header
        #(#indices)*
        #wrench_items
    };
    Ok(Generated {
        header,
        scalars,
        functions,
        f64_twins,
        lane_functions,
        lane_twins,
        lanes: options.lanes,
        helpers: options.helpers.clone(),
        constrained: model64.has_constraints(),
        limits: LimitTables::of(&model64),
    })
}

/// The size guard's first step: the functions' sizes predicted from the model, refused before any
/// tracing when far beyond the limit (see `size.rs`).
fn check_size_before_tracing(
    loaded: &Loaded,
    model: &Model<f64>,
    algorithms: &[(Algorithm, &str)],
    scalars: &[&'static str],
    options: &GenerateOptions,
) -> Result<Vec<size::FunctionSize>, LoadError> {
    // With lanes, each function also has a lane module's copy (not `complete`'s wrapper alone, a detail).
    let lane_weight = if options.lanes > 0 {
        1.0 + size::LANE_MEMORY_FACTOR
    } else {
        1.0
    };
    let predicted: Vec<size::FunctionSize> = algorithms
        .iter()
        .map(|&(a, name)| {
            let mut f = size::predicted(model, a);
            f.compile_bytes *= lane_weight;
            f.name = (name != a.name()).then(|| name.to_string());
            f
        })
        .collect();
    let limit = options.max_compile_memory_mb;
    size::check(
        loaded,
        &predicted,
        &predicted,
        scalars,
        limit,
        size::PREDICTION_SLACK,
    )?;
    Ok(predicted)
}

/// The scalar module `pub mod f64 { type S = f64; … }` around `functions`; for a model with constraints
/// it also holds the scalar's singularity threshold.
fn scalar_module(
    scalar: &str,
    constrained: bool,
    limits: &LimitTables,
    functions: &[TokenStream],
) -> TokenStream {
    let module = format_ident!("{}", scalar);
    let doc = format!(" The generated dynamics in `{scalar}`.");
    let threshold = if constrained {
        let value = proc_macro2::Literal::f64_unsuffixed(match scalar {
            "f32" => singularity_threshold::<f32>(),
            _ => singularity_threshold::<f64>(),
        });
        let derivative_value = proc_macro2::Literal::f64_unsuffixed(match scalar {
            "f32" => derivative_singularity_threshold::<f32>(),
            _ => derivative_singularity_threshold::<f64>(),
        });
        quote! {
            /// cond₁(Y1) at or above which a configuration counts as singular in this scalar type,
            /// `min(1e10, 10⁻³ / ε)`: where the condition number returned by `aba`, `embedding` or
            /// `crba_independent` is not below it (`cond.is_nan() || cond >= SINGULARITY_THRESHOLD`), the
            /// results are meaningless and the interpreted solver refuses.
            pub const SINGULARITY_THRESHOLD: S = #value;
            /// cond₁(Y1) at or above which the derivatives (`aba_derivatives`, `step_derivatives`,
            /// `aba_derivatives_independent`, …) have lost their digits in this scalar type: the square
            /// root of `SINGULARITY_THRESHOLD`, because their rounding grows as cond₁(Y1)² where the
            /// values' grows as cond₁(Y1). The interpreted solver refuses derivatives from it.
            pub const DERIVATIVE_SINGULARITY_THRESHOLD: S = #derivative_value;
        }
    } else {
        quote!()
    };
    let limits = limits.constants(scalar);
    quote! {
        #[doc = #doc]
        // A program uses some of the functions generated for it; the others are not dead code to fix.
        #[allow(clippy::all, clippy::pedantic, unused_parens, non_snake_case, dead_code)]
        pub mod #module {
            type S = #module;
            // The model's sizes by the path a function one module deeper names them (`super::NQ`): a
            // function's AVX twin (codegen/src/dispatch.rs) holds a copy of `complete`.
            #[allow(unused_imports)]
            use super::{NQ, NV};
            #threshold
            #limits
            #(#functions)*
        }
    }
}

/// The helper module's lane type of `lanes` lanes of `scalar` (`F64x4`), if it has one.
fn lane_type(scalar: &str, lanes: usize) -> Option<&'static str> {
    embedyn_runtime::codegen_support::LANE_TYPES
        .iter()
        .find(|(s, n, _)| *s == scalar && *n == lanes)
        .map(|(_, _, name)| *name)
}

/// The lane module `pub mod f64x4 { type S = F64x4; … }` of `scalar` around `functions`.
fn lane_module(
    scalar: &str,
    lanes: usize,
    constrained: bool,
    helpers: &TokenStream,
    functions: &[TokenStream],
) -> TokenStream {
    let module = format_ident!("{}x{}", scalar, lanes);
    let lane_type = format_ident!("{}", lane_type(scalar, lanes).unwrap_or("F64x4"));
    let scalar_ident = format_ident!("{}", scalar);
    let n = proc_macro2::Literal::usize_unsuffixed(lanes);
    // The thresholds the returned measures (one per lane) are compared with, lane by lane.
    let thresholds = if constrained {
        quote! {
            /// The scalar module's `SINGULARITY_THRESHOLD`: compare each lane of a returned measure with it.
            pub const SINGULARITY_THRESHOLD: E = super::#scalar_ident::SINGULARITY_THRESHOLD;
            /// The scalar module's `DERIVATIVE_SINGULARITY_THRESHOLD`, for the derivatives' measures.
            pub const DERIVATIVE_SINGULARITY_THRESHOLD: E =
                super::#scalar_ident::DERIVATIVE_SINGULARITY_THRESHOLD;
        }
    } else {
        quote!()
    };
    let doc = format!(
        " The generated dynamics in `{scalar}`, {lanes} states per call: the scalar `S` is `{lane_type}` (one SIMD value, one state per lane), the functions are the `{scalar}` module's (less `complete` and `complete_step`), lane by lane bit-identical to them. Pack states with `S::new([…])` per entry, read lane `k` with `to_array()[k]`, or pass slices of states to the `_batch` forms. A lane value of 256 bits (`F64x4`, `F32x8`) takes one instruction per operation where the CPU has AVX: in a build with AVX (`-C target-cpu=native`), and on x86-64 builds without it through the functions' AVX twins, chosen at run time (`avx_twins`, docs/generated-code.md)."
    );
    quote! {
        #[doc = #doc]
        #[allow(clippy::all, clippy::pedantic, unused_parens, non_snake_case, dead_code)]
        pub mod #module {
            /// One number per state.
            pub type S = #helpers::#lane_type;
            /// The number of one state (the scalar of the `_batch` functions' slices).
            pub type E = #scalar_ident;
            /// States per lane call.
            pub const LANES: usize = #n;
            /// Whether the `_batch` form of a function whose scalar form computes mirrored branches as
            /// pairs calls that scalar function state by state instead of the lane function. True only in
            /// a module of four f64 lanes built without AVX: there an `F64x4` is two SSE2 registers, and
            /// the paired scalar code already fills one (a floating Go2's `aba`: 323 ns per call, 690 per
            /// state through the lanes, 2026-12-03). Where the CPU has AVX the batch runs in the function's
            /// AVX twin, whose own constant is false (codegen/src/dispatch.rs). The results are the same
            /// bits either way (but for the sign of a NaN).
            const PAIRED_BATCH_PER_STATE: bool = cfg!(not(target_feature = "avx"))
                && LANES == 4
                && ::core::mem::size_of::<E>() == 8;
            #[allow(unused_imports)]
            use super::#scalar_ident as scalar_module;
            #thresholds
            #(#functions)*
        }
    }
}

/// Generates the items for a model: `NQ`, `NV`, `JOINTS`, and modules `f64`/`f32` with one function per
/// algorithm.
pub fn generate_tokens(
    loaded: &Loaded,
    options: &GenerateOptions,
) -> Result<TokenStream, LoadError> {
    let generated = generate_items(loaded, options)?;
    let lex = |code: &Code| match code {
        Code::Tokens(t) => Ok(t.clone()),
        // Lexed by syn, whose error (unlike proc_macro2's) may cross threads with the LoadError.
        Code::Text(text) => syn::parse_str::<TokenStream>(text)
            .map_err(|e| located_at_robot(loaded, LoadErrorKind::Tokenize { error: e.into() })),
    };
    let functions = generated.scalar_functions(lex)?;
    let modules = generated.scalars.iter().map(|scalar| {
        scalar_module(
            scalar,
            generated.constrained,
            &generated.limits,
            functions.of(*scalar == "f64"),
        )
    });
    let lane_functions = generated.lane_functions(lex)?;
    let lane_modules: Vec<TokenStream> = match generated.lanes {
        0 => Vec::new(),
        n => generated
            .scalars
            .iter()
            .map(|scalar| {
                lane_module(
                    scalar,
                    n,
                    generated.constrained,
                    &generated.helpers,
                    lane_functions.of(crate::dispatch::lanes_of_256_bits(scalar, n)),
                )
            })
            .collect(),
    };
    let header = generated.header;
    Ok(quote! {
        #header
        #(#modules)*
        #(#lane_modules)*
    })
}

/// Generates the model's code as formatted source text: the same items as [`generate_tokens`], with
/// the small functions formatted by `prettyplease` and the long ones written formatted by the emitter
/// (pretty-printing millions of tokens would cost more time and memory than generating them).
pub fn generate_source(loaded: &Loaded, options: &GenerateOptions) -> Result<String, LoadError> {
    let generated = generate_items(loaded, options)?;
    let fail = |e: UnparsableCode| located_at_robot(loaded, e.into());
    let mut text = format_tokens(&generated.header).map_err(fail)?;
    // Each function formatted on its own inside a module, so that it is indented (and its lines
    // broken) exactly as inside the scalar module.
    let text_of = |code: &Code| match code {
        Code::Tokens(t) => {
            let wrapped = format_tokens(&quote!(mod m { #t })).map_err(fail)?;
            Ok(module_body(&wrapped).to_string())
        }
        Code::Text(body) => Ok(body.clone()),
    };
    let functions = generated.scalar_functions(text_of)?;
    let lane_functions = generated.lane_functions(text_of)?;
    let mut modules = Vec::new();
    for scalar in &generated.scalars {
        let empty = scalar_module(scalar, generated.constrained, &generated.limits, &[]);
        modules.push((empty, functions.of(*scalar == "f64")));
    }
    if generated.lanes > 0 {
        for scalar in &generated.scalars {
            let empty = lane_module(
                scalar,
                generated.lanes,
                generated.constrained,
                &generated.helpers,
                &[],
            );
            modules.push((
                empty,
                lane_functions.of(crate::dispatch::lanes_of_256_bits(scalar, generated.lanes)),
            ));
        }
    }
    for (empty, functions) in modules {
        let empty = format_tokens(&empty).map_err(fail)?;
        text.push_str(empty.strip_suffix("}\n").unwrap_or(&empty));
        for f in functions {
            text.push_str(f);
        }
        text.push_str("}\n");
    }
    Ok(text)
}

/// The lines between `mod m {` and the closing `}` of a formatted module.
fn module_body(formatted: &str) -> &str {
    let start = formatted.find('\n').map_or(0, |i| i + 1);
    formatted[start..]
        .strip_suffix("}\n")
        .unwrap_or(&formatted[start..])
}

/// `complete`: `complete_step` iterated until the relative residual is below 64 ε (or NaN) or the step
/// budget is spent. The iteration is over Newton steps, not over bodies: the step itself is unrolled.
pub(crate) fn complete_loop() -> TokenStream {
    let max_steps = proc_macro2::Literal::usize_unsuffixed(COMPLETION_MAX_STEPS);
    let must_use = crate::emit::MUST_USE;
    quote! {
        /// Position completion: `q_out` is `q` with its dependent coordinates solved from the independent
        /// ones by Newton's method from `q`'s dependent entries as the guess (it converges to the assembly
        /// branch nearest the guess), iterated until the largest residual, relative to the magnitudes in
        /// each equation, is below 64 ε or for at most `COMPLETION_MAX_STEPS` steps. Returns that residual:
        /// check it — a guess outside the mechanism's range does not converge (or gives NaN).
        #[must_use = #must_use]
        pub fn complete(q: &[S; super::NQ], q_out: &mut [S; super::NQ]) -> S {
            let tolerance: S = 64.0 * S::EPSILON;
            *q_out = *q;
            let mut next = *q;
            for _ in 0..COMPLETION_MAX_STEPS {
                let residual = complete_step(q_out, &mut next);
                if !(residual > tolerance) {
                    return residual;
                }
                *q_out = next;
            }
            complete_step(q_out, &mut next)
        }
        /// Newton steps `complete` takes at most.
        pub const COMPLETION_MAX_STEPS: usize = #max_steps;
    }
}

/// Components of a joint's coordinates in the names of generated code (a floating joint has 7).
const COORDINATE: [&str; 7] = ["0", "1", "2", "3", "4", "5", "6"];

/// Names of the entries of a wrench row, for the names of `f_ext`'s values (`lf_foot_f_ext_fx`).
const WRENCH_COMPONENT: [&str; 6] = ["fx", "fy", "fz", "tx", "ty", "tz"];

/// How one function is traced and written: the helpers' path, the lanes of its lane module (0: none)
/// and the tape's budget ([`size::tape_budget`]).
#[derive(Clone, Copy)]
struct Emission<'a> {
    helpers: &'a TokenStream,
    lanes: usize,
    budget: Option<usize>,
}

/// What tracing one function gave: its code (and its lane module's), or the stop at the tape's budget.
enum TracedFunction {
    Emitted(Emitted, Option<Emitted>),
    Stopped(crate::trace::TapeFull),
}

/// One function traced and written ([`generate_one_way`]); derivatives on a tree each way they can be
/// traced, the code that runs fewer statements kept (a pair's operation counting once, a loop's product
/// at half). No way wins everywhere: the analytical recursion is `O(nv · depth)` but forward dynamics
/// then pays `M⁻¹ ∂τ`, unrolled or (factors) in a loop; dual numbers are `O(nv²)`, and on a quadruped
/// their passes pair leg with leg. Measured (f64 statements) for `aba_derivatives`: the Z1 arm 11.3k
/// unrolled recursion against 16.3k dual numbers; the floating ANYmal B 16.2k factors + 6.8k loop
/// against 32.1k paired dual numbers and 40.9k unrolled; the floating TALOS 89.5k factors + 48.9k loop
/// against 187k unrolled and 254k dual numbers.
fn generate_algorithm(
    request: &FunctionRequest,
    taken: &mut std::collections::HashSet<String>,
    emission: Emission,
) -> Result<TracedFunction, LoadError> {
    use crate::algorithm::DerivativeTrace;
    use embedyn_runtime::DerivativeMethod;
    let (model, algorithm) = (request.model, request.instance.algorithm);
    if !algorithm.has_derivative_methods() || model.has_constraints() {
        return generate_one_way(request, taken, emission, None);
    }
    // The likely winner first, so that the others can stop early: a way whose tape grows past three times
    // the best code so far (plus a margin) cannot run fewer statements, and its trace stops there (a
    // 120-joint chain traced its cubic unrolled product and 600 nv² of dual numbers in full: 66 s, 3 GB).
    let product = FactorProduct::structural_operations(model);
    let factors = algorithm.has_derivative_factors() && product > FACTOR_PRODUCT_MIN;
    let mut ways = Vec::new();
    // Forward dynamics' q̈ and M⁻¹ from the factorized mass matrix instead of ABA and the inverse's sweeps
    // (inverse dynamics' derivatives are the same either way), only where no f32 code is written from the
    // same trace: the factorization's rounding grows as cond(M) ε, which f32 cannot spare (attacker's
    // trial, 2026-12-04, generated f32 against interpreted f64: the Z1's q̈ 2.1e-7 by `aba`, 6.0e-5 by the
    // factorization, M⁻¹ 1.2e-7 against 4.1e-5; a 20-link chain's q̈ 7.2e-6 against 1.6e-4; in f64 the Z1's
    // q̈ 3.3e-16 against 1.5e-13).
    let factorized = !request.single_precision
        && (algorithm.has_derivative_factors() || algorithm == Algorithm::StepDerivatives);
    if factors {
        ways.push(DerivativeTrace::Factors(DerivativeMethod::Analytical));
        if factorized {
            ways.push(DerivativeTrace::Factors(
                DerivativeMethod::MassMatrixFactorization,
            ));
        }
    }
    if !factors || product <= UNROLLED_PRODUCT_MAX {
        ways.push(DerivativeTrace::Method(DerivativeMethod::Analytical));
        if factorized {
            ways.push(DerivativeTrace::Method(
                DerivativeMethod::MassMatrixFactorization,
            ));
        }
    }
    ways.push(DerivativeTrace::Method(DerivativeMethod::DualNumbers));
    let mut best: Option<(TracedFunction, usize, std::collections::HashSet<String>)> = None;
    for way in ways {
        let budget = match &best {
            Some((_, cost, _)) if *cost < usize::MAX => {
                let beaten = cost.saturating_mul(3).saturating_add(20_000);
                Some(emission.budget.map_or(beaten, |b| b.min(beaten)))
            }
            _ => emission.budget,
        };
        let mut names = taken.clone();
        let traced = generate_one_way(
            request,
            &mut names,
            Emission { budget, ..emission },
            Some(way),
        )?;
        let cost = match &traced {
            TracedFunction::Emitted(e, _) => e.statements,
            TracedFunction::Stopped(_) => usize::MAX,
        };
        if best.as_ref().is_none_or(|(_, kept, _)| cost < *kept) {
            best = Some((traced, cost, names));
        }
    }
    let (traced, _, names) = best.expect("two ways were tried");
    *taken = names;
    Ok(traced)
}

/// Forward dynamics' derivatives are traced as factors with the product in a loop
/// ([`crate::algorithm::DerivativeTrace::Factors`]) only where the product is at least this many
/// operations: a short product unrolled folds and schedules better than a loop (the Z1 arm's, 864).
const FACTOR_PRODUCT_MIN: usize = 8_000;

/// Where forward dynamics' derivatives can be traced as factors, the recursion is also traced with its
/// product unrolled only up to this many operations of product (the floating ANYmal B's 15.5k; the TALOS's
/// 98k unrolled ran at 0.65 ns per operation against the loop's 0.14, and a chain's grows as nv² · depth).
const UNROLLED_PRODUCT_MAX: usize = 50_000;

/// The product `−M⁻¹ ∂τ` of forward dynamics' derivatives from their factors: for each column of
/// `∂τ/∂q` and of `∂τ/∂v`, the rows the trace did not fold to zero (at most a joint's ancestors' and its
/// subtree's coordinates; none in a free flyer's translation columns of `∂τ/∂q`).
struct FactorProduct {
    /// Rows and column starts of `∂τ/∂q`, then of `∂τ/∂v`.
    rows: [Vec<u32>; 2],
    starts: [Vec<u32>; 2],
    nv: usize,
}

impl FactorProduct {
    /// Operations of both products before tracing, from the tree alone (each column's ancestors and
    /// subtree): whether tracing the factors may pay.
    fn structural_operations(model: &Model<Sym>) -> usize {
        let mut nonzero = 0;
        for (k, joint) in model.joints.iter().enumerate() {
            let ancestors: usize = model.ancestors(k).map(|j| model.joints[j].nv()).sum();
            nonzero += joint.nv() * (ancestors + model.subtree_v_range(k).len());
        }
        2 * 2 * model.nv() * nonzero
    }

    /// From the traced factors (`qdd`, `dtau_dq`, `dtau_dv`, `minv`).
    fn of(outputs: &[Output]) -> FactorProduct {
        let mut product = FactorProduct {
            rows: [Vec::new(), Vec::new()],
            starts: [vec![0], vec![0]],
            nv: 0,
        };
        for (k, output) in outputs[1..3].iter().enumerate() {
            let Output::Matrix {
                rows, cols, values, ..
            } = output
            else {
                unreachable!("∂τ is a matrix")
            };
            product.nv = *cols;
            for c in 0..*cols {
                for r in 0..*rows {
                    if !matches!(values[r * cols + c], Sym::Const(x) if x == 0.0) {
                        product.rows[k].push(r as u32);
                    }
                }
                product.starts[k].push(product.rows[k].len() as u32);
            }
        }
        product
    }

    /// Multiplications and additions of both products (`∂q̈/∂q`, `∂q̈/∂v`).
    fn operations(&self) -> usize {
        2 * self.nv * (self.rows[0].len() + self.rows[1].len())
    }

    /// `pub fn name(args, outputs)`: `name_factors`, then both products in place.
    fn wrapper(
        &self,
        name: &str,
        doc: &str,
        args: &[Arg],
        outputs: &[Output],
        helpers: &TokenStream,
    ) -> TokenStream {
        let fname = quote::format_ident!("{}", name);
        let factors = quote::format_ident!("{}_factors", name);
        let mut params = Vec::new();
        let mut call = Vec::new();
        for a in args {
            let id = quote::format_ident!("{}", a.name);
            params.push(a.tokens());
            call.push(quote!(#id));
        }
        for o in outputs {
            // Forward dynamics' derivatives on a tree return nothing: every output is a parameter.
            let name = o.name().expect("forward dynamics' outputs are named");
            let id = quote::format_ident!("{}", name);
            params.extend(o.param());
            call.push(quote!(#id));
        }
        let table =
            |t: &[u32]| -> Vec<_> { t.iter().map(|&r| crate::emit::num(r as usize)).collect() };
        let (rows_q, rows_v) = (table(&self.rows[0]), table(&self.rows[1]));
        let (starts_q, starts_v) = (table(&self.starts[0]), table(&self.starts[1]));
        let (nq, nv) = (
            crate::emit::num(self.rows[0].len()),
            crate::emit::num(self.rows[1].len()),
        );
        let n = crate::emit::num(self.nv + 1);
        let doc_lines = doc.lines();
        quote! {
            #(#[doc = #doc_lines])*
            pub fn #fname(#(#params),*) {
                // The rows of each column of ∂τ/∂q and ∂τ/∂v that are not zero.
                const ROWS_Q: [u32; #nq] = [#(#rows_q),*];
                const STARTS_Q: [u32; #n] = [#(#starts_q),*];
                const ROWS_V: [u32; #nv] = [#(#rows_v),*];
                const STARTS_V: [u32; #n] = [#(#starts_v),*];
                #factors(#(#call),*);
                #helpers::minus_symmetric_times_sparse(dqdd_dtau, dqdd_dq, &ROWS_Q, &STARTS_Q);
                #helpers::minus_symmetric_times_sparse(dqdd_dtau, dqdd_dv, &ROWS_V, &STARTS_V);
            }
        }
    }
}

/// What one generated function is of: the model (as loaded, and traced), the function, the links of
/// its frame and wrenches.
struct FunctionRequest<'a> {
    loaded: &'a Loaded,
    model: &'a Model<Sym>,
    /// `model` with its body origins on the joint axes, which the functions of
    /// `Algorithm::traced_on_moved_origins` are traced on (the same joints and bodies).
    moved_model: &'a Model<Sym>,
    instance: &'a Instance<'a>,
    links: &'a Links<'a>,
    wrench_names: &'a [&'a str],
    /// Whether an `f32` module (or lane module) is written from the same traced code: forward dynamics'
    /// derivatives then keep `aba`'s `q̈` and `M⁻¹` (see `generate_algorithm`).
    single_precision: bool,
}

/// One function traced (derivatives `way`, where they have ways) and written.
fn generate_one_way(
    request: &FunctionRequest,
    taken: &mut std::collections::HashSet<String>,
    emission: Emission,
    way: Option<crate::algorithm::DerivativeTrace>,
) -> Result<TracedFunction, LoadError> {
    use crate::algorithm::DerivativeTrace;
    match way {
        None => generate_traced(request, taken, emission, false),
        Some(way) => crate::algorithm::with_derivative_trace(way, || {
            generate_traced(
                request,
                taken,
                emission,
                matches!(way, DerivativeTrace::Factors(_)),
            )
        }),
    }
}

/// [`generate_one_way`]'s work: `factors` for forward dynamics' derivatives traced as factors, written
/// as `name_factors` with `name` after it multiplying them ([`FactorProduct`]).
fn generate_traced(
    request: &FunctionRequest,
    taken: &mut std::collections::HashSet<String>,
    emission: Emission,
    factors: bool,
) -> Result<TracedFunction, LoadError> {
    let FunctionRequest {
        loaded,
        model,
        moved_model,
        instance,
        links,
        wrench_names,
        single_precision: _,
    } = *request;
    let Emission {
        helpers,
        lanes,
        budget,
    } = emission;
    let algo = instance.algorithm;
    let spec = algo.spec();
    let dims = Dims {
        wrench_links: links.wrenches.len(),
        ..Dims::of(model)
    };
    let constrained = model.has_constraints();
    // Inputs are named after their joints: `knee_q`, `knee_v`, `base_q_3` (a joint with several
    // coordinates), so that generated code reads `let knee_q = q[2];`.
    let named_input = |arg: u8, spec_input: &crate::algorithm::InputSpec, i: usize| -> Sym {
        let value = input(arg, i);
        if spec_input.len == crate::algorithm::Dim::Scalar {
            return value;
        }
        if spec_input.len == crate::algorithm::Dim::WrenchLinks {
            return match wrench_names.get(i / 6) {
                Some(link) => value.named(link, spec_input.name, WRENCH_COMPONENT[i % 6]),
                None => value,
            };
        }
        let positions = spec_input.len == crate::algorithm::Dim::Nq;
        let range = |j: &embedyn_runtime::Joint<Sym>| {
            if positions {
                (j.q_index, j.nq())
            } else {
                (j.v_index, j.nv())
            }
        };
        let owner = model.joints.iter().find(|j| {
            let (start, len) = range(j);
            (start..start + len).contains(&i)
        });
        match owner {
            Some(j) if range(j).1 == 1 => value.named(&j.name, spec_input.name, ""),
            Some(j) => value.named(
                &j.name,
                spec_input.name,
                COORDINATE[(i - range(j).0).min(6)],
            ),
            None => value,
        }
    };
    let fail = |error: embedyn_runtime::DynamicsError| {
        located_at_robot(
            loaded,
            LoadErrorKind::Trace {
                function: algo,
                error,
            },
        )
    };
    // Names and owners below come from `model`: the two models have the same joints and bodies.
    let traced_model = if spec.algorithm.traced_on_moved_origins() {
        moved_model
    } else {
        model
    };
    let recorded = record_within(budget, || {
        let mut ws = Workspace::new(traced_model);
        let inputs: Vec<Vec<Sym>> = (0u8..)
            .zip(spec.inputs)
            .map(|(arg, i)| {
                (0..i.len.len(&dims) * i.columns.unwrap_or(1))
                    .map(|k| named_input(arg, i, k))
                    .collect()
            })
            .collect();
        (spec.trace)(traced_model, &mut ws, &inputs, links)
    });
    let (traced, tape) = match recorded {
        Ok(recorded) => recorded,
        Err(full) => return Ok(TracedFunction::Stopped(full)),
    };
    let traced = traced.map_err(fail)?;
    let bodies: Vec<&str> = model.bodies.iter().map(|b| b.name.as_str()).collect();
    let owners = Owners::new(
        model.joints.iter().map(|j| j.name.as_str()),
        bodies.iter().copied(),
    )
    .with_links(
        model.frames().filter_map(|f| {
            let b = f.body?;
            Some((model.frame_name(f)?, b))
        }),
        &bodies,
    );
    // The descriptor and the traced algorithm must agree on what the function returns and writes.
    let mismatch = |problem: DescriptorMismatch| {
        located_at_robot(
            loaded,
            LoadErrorKind::DescriptorMismatch {
                function: algo,
                problem,
            },
        )
    };
    if traced.returned.is_some() != spec.returns_value(constrained)
        || traced.outputs.len() != spec.outputs.len()
    {
        return Err(mismatch(DescriptorMismatch::Outputs));
    }
    let mut outputs = Vec::with_capacity(spec.outputs.len() + 1);
    for (o, values) in spec.outputs.iter().zip(traced.outputs) {
        let (rows, cols) = match o.shape {
            Shape::Vector(n) => (n.len(&dims), 1),
            Shape::Matrix(rows, cols) => (rows.len(&dims), cols.len(&dims)),
        };
        if values.len() != rows * cols {
            return Err(mismatch(DescriptorMismatch::OutputLength {
                output: o.name,
                values: values.len(),
                rows,
                cols,
            }));
        }
        outputs.push(match o.shape {
            Shape::Vector(_) => Output::Vector {
                name: o.name,
                values,
            },
            Shape::Matrix(..) => Output::Matrix {
                name: o.name,
                rows,
                cols,
                values,
            },
        });
    }
    outputs.extend(traced.returned.map(Output::Return));
    let args: Vec<Arg> = spec
        .inputs
        .iter()
        .map(|i| Arg {
            name: i.name,
            len: i.len.len(&dims),
            columns: i.columns,
            scalar: i.len == crate::algorithm::Dim::Scalar,
        })
        .collect();
    let doc = match instance.link {
        Some(link) => format!(
            "{}\n\nLink {}; reference `{}`.",
            spec.doc(constrained),
            code_span(link),
            links.reference.as_str()
        ),
        None => spec.doc(constrained).to_string(),
    };
    // The lane module's copy takes the same part names: its module-level names are the scalar module's
    // (the same functions, emitted alike), so the names free there before this function are free here.
    let mut lane_taken = taken.clone();
    // Traced as factors: the traced function is `name_factors`, and `name` multiplies its results.
    let (traced_name, traced_doc, product) = if factors {
        let name = format!("{}_factors", instance.name);
        taken.insert(name.clone());
        lane_taken.insert(name.clone());
        let doc = format!(
            "The factors of `{0}`: `qdd`, and in place of its derivatives the inverse-dynamics derivatives `dtau_dq`, `dtau_dv` at that `qdd` and `M⁻¹`; `{0}` multiplies them (`dqdd_dq = −M⁻¹ dtau_dq`, `dqdd_dv = −M⁻¹ dtau_dv`) in a loop.",
            instance.name
        );
        (name, doc, Some(FactorProduct::of(&outputs)))
    } else {
        (instance.name.clone(), doc.clone(), None)
    };
    let mut emitted = function(
        &traced_name,
        &traced_doc,
        &args,
        &outputs,
        &tape,
        &mut crate::emit::ModuleContext {
            helpers,
            owners: &owners,
            taken,
            lanes: false,
            pairs: Some(&crate::pairing::BranchPairs::of(model)),
        },
    )
    .map_err(|e| located_at_robot(loaded, e.into()))?;
    // The lane module's copy: the same tape, emitted with lane constants and selects. Functions with a
    // hand-written wrapper (`complete`'s Newton loop branches on the residual) have none.
    let lane_function = match lanes {
        0 => None,
        _ if spec.wrapper.is_some() => None,
        n => {
            let lane_doc = format!(
                "{doc}\n\n{n} states at once, one per lane: every argument's entry holds that entry of each state (`q[i].0[k]` is `q[i]` of state `k`), and lane `k` of every result is bit-identical to the scalar function's result for state `k`."
            );
            let lane_traced_doc = match product {
                Some(_) => traced_doc.clone(),
                None => lane_doc.clone(),
            };
            let mut lane = function(
                &traced_name,
                &lane_traced_doc,
                &args,
                &outputs,
                &tape,
                &mut crate::emit::ModuleContext {
                    helpers,
                    owners: &owners,
                    taken: &mut lane_taken,
                    lanes: true,
                    pairs: None,
                },
            )
            .map_err(|e| located_at_robot(loaded, e.into()))?;
            let mut items =
                crate::emit::batch_wrapper(&instance.name, &args, &outputs, emitted.paired, n);
            if let Some(product) = &product {
                let wrapper = product.wrapper(&instance.name, &lane_doc, &args, &outputs, helpers);
                items = quote!(#wrapper #items);
            }
            lane.code =
                followed_by(lane.code, &items).map_err(|e| located_at_robot(loaded, e.into()))?;
            Some(lane)
        }
    };
    if let Some(wrapper) = spec.wrapper {
        emitted.code = followed_by(emitted.code, &wrapper())
            .map_err(|e| located_at_robot(loaded, e.into()))?;
    }
    if let Some(product) = &product {
        // What runs: the loop's product counts half (its inner loop takes two numbers per SSE2
        // instruction), for choosing between the ways of tracing.
        emitted.statements += product.operations() / 2;
        let wrapper = product.wrapper(&instance.name, &doc, &args, &outputs, helpers);
        emitted.code =
            followed_by(emitted.code, &wrapper).map_err(|e| located_at_robot(loaded, e.into()))?;
    }
    Ok(TracedFunction::Emitted(emitted, lane_function))
}

/// `code` with `items` after it (a wrapper, a batch form), in `code`'s form: tokens appended, or the
/// items formatted as inside a module and appended to the text.
fn followed_by(code: Code, items: &TokenStream) -> Result<Code, UnparsableCode> {
    Ok(match code {
        Code::Tokens(t) => Code::Tokens(quote! { #t #items }),
        Code::Text(text) => {
            let formatted = format_tokens(&quote!(mod m { #items }))?;
            Code::Text(text + module_body(&formatted))
        }
    })
}

/// Generated items that are not a Rust file (a bug of the generator): `syn`'s error.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("generated code does not parse: {0}")]
pub struct UnparsableCode(#[source] pub Shared<syn::Error>);

/// Formats generated items as a source file with `prettyplease`.
pub fn format_tokens(tokens: &TokenStream) -> Result<String, UnparsableCode> {
    let file: syn::File = syn::parse2(tokens.clone()).map_err(|e| UnparsableCode(e.into()))?;
    Ok(prettyplease::unparse(&file))
}

/// For `build.rs`: generates the model's code as a formatted Rust source file (include it with
/// `include!(concat!(env!("OUT_DIR"), "/robot.rs"))` inside a module). Prints the `cargo:rerun-if-changed`
/// line for the model file.
///
/// Add `embedyn-codegen` under `[build-dependencies]` (or `embedyn`, and call
/// `embedyn::codegen::generate_file`). Report an error with `panic!("{e}")`: its `Display` lists every
/// problem of the model file with its file:line, where `.unwrap()` would print the `Debug` form.
///
/// ```no_run
/// // in build.rs's main():
/// let out = std::path::Path::new(&std::env::var("OUT_DIR").unwrap()).join("arm.rs");
/// if let Err(e) = embedyn_codegen::generate_file("models/arm7.urdf".as_ref(), &Default::default(), &out) {
///     panic!("{e}");
/// }
/// ```
pub fn generate_file(
    model_path: &std::path::Path,
    options: &GenerateOptions,
    out: &std::path::Path,
) -> Result<(), LoadError> {
    // The path goes into cargo's line-based build-script protocol: a line break in it would add a
    // directive of its own.
    let shown_path = model_path.display().to_string();
    if shown_path.contains(['\n', '\r']) {
        return Err(LoadError::at(
            Location::new(model_path, None, ""),
            LoadErrorKind::PathWithLineBreak,
        ));
    }
    println!("cargo:rerun-if-changed={shown_path}");
    let loaded = crate::load(model_path)?;
    let text = generate_source(&loaded, options)?;
    std::fs::write(out, text).map_err(|e| {
        located_at_robot(
            &loaded,
            LoadErrorKind::CannotWriteTo {
                path: out.to_path_buf(),
                error: e.into(),
            },
        )
    })
}

/// Builds the f64 model the way generated code sees it (for comparisons in tests).
pub fn generation_model(loaded: &Loaded, options: &ModelOptions) -> Result<Model<f64>, LoadError> {
    Ok(snapped(&build_model::<f64>(&loaded.robot, options)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A batch of 24 angles or more is padded with zeros to a multiple of 8 (`SINCOS_PAD_MIN`,
    /// `SINCOS_PAD`); a shorter one, and a lane function's, is left as it is.
    #[test]
    fn long_sine_batches_are_padded_to_whole_vectors() {
        // The entries of every batch (`sincos_batch([a, b, …])`) and how many of them are `0.0` padding.
        fn batches(text: &str) -> Vec<(usize, usize)> {
            text.match_indices("sincos_batch([")
                .map(|(at, m)| {
                    let rest = &text[at + m.len()..];
                    let entries: Vec<&str> = rest[..rest.find(']').unwrap()]
                        .split(',')
                        .map(str::trim)
                        .filter(|e| !e.is_empty())
                        .collect();
                    let zeros = entries.iter().rev().take_while(|e| **e == "0.0").count();
                    (entries.len(), zeros)
                })
                .collect()
        }
        let models = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/");
        // 29 joint angles: padded to 32.
        let humanoid = crate::load(format!("{models}humanoid34.urdf").as_ref()).unwrap();
        let found = batches(&f64_source(&humanoid, Algorithm::Crba));
        assert!(!found.is_empty());
        assert!(found.iter().all(|&b| b == (32, 3)), "{found:?}");
        // Fewer than 24: as they are.
        let z1 = crate::load(format!("{models}peers/z1.urdf").as_ref()).unwrap();
        let found = batches(&f64_source(&z1, Algorithm::Crba));
        assert!(
            !found.is_empty() && found.iter().all(|&(n, zeros)| n < 24 && zeros == 0),
            "{found:?}"
        );
        // Lane functions: their angles are vectors already.
        let options = GenerateOptions {
            f32: false,
            lanes: 4,
            ..GenerateOptions::default()
        }
        .with_requested(Some(vec![Algorithm::Crba]), &[]);
        let text = generate_source(&humanoid, &options).unwrap();
        let lanes = &text[text.find("pub mod f64x4").unwrap()..];
        let found = batches(lanes);
        assert!(
            !found.is_empty() && found.iter().all(|&b| b == (29, 0)),
            "{found:?}"
        );
    }

    /// The scratch stores of each part of a long unpaired function (`SPACED_SLOTS_MIN_OPERATIONS`) go to
    /// slots of one parity (the part's own), so that none are adjacent; a short one's parts
    /// store to adjacent slots, numbered without gaps.
    #[test]
    fn long_functions_parts_store_to_slots_of_their_own_parity() {
        // The parity of the slots each part stores to (`s.K = …`), per part, in order.
        fn parities(text: &str) -> (Vec<Vec<usize>>, usize) {
            let mut parts: Vec<Vec<usize>> = Vec::new();
            let mut most = 0;
            for line in text.lines().map(str::trim_start) {
                if line.starts_with("pub(super) fn ") || line.starts_with("pub(crate) fn ") {
                    parts.push(Vec::new());
                } else if let Some(rest) = line.strip_prefix("s.") {
                    let k: usize = rest.split(' ').next().unwrap().parse().unwrap();
                    most = most.max(k);
                    parts.last_mut().unwrap().push(k % 2);
                }
            }
            parts.retain(|p| !p.is_empty());
            (parts, most)
        }
        let models = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/");
        let chain = crate::load(format!("{models}loops/rotor_chain_10.urdf").as_ref()).unwrap();
        let (parts, _) = parities(&f64_source(&chain, Algorithm::AbaDerivatives));
        assert!(parts.len() >= 4, "{}", parts.len());
        for (c, p) in parts.iter().enumerate() {
            assert!(p.iter().all(|&parity| parity == p[0]), "part {c}: {p:?}");
        }
        assert!(parts.iter().any(|p| p[0] == 0) && parts.iter().any(|p| p[0] == 1));
        let z1 = crate::load(format!("{models}peers/z1.urdf").as_ref()).unwrap();
        let text = f64_source(&z1, Algorithm::AbaDerivatives);
        let (parts, most) = parities(&text);
        assert!(parts.iter().any(|p| p.contains(&0) && p.contains(&1)));
        let slots = text
            .lines()
            .find(|l| {
                l.trim_start()
                    .starts_with("type aba_derivatives_scratch = (")
            })
            .unwrap()
            .matches('S')
            .count();
        assert_eq!(most + 1, slots, "slots without gaps");
    }

    /// A paired body longer than `PAIRED_PART` statements (the twin arms' `crba`, 8,849) is cut into parts
    /// that pass scalars and pairs, spread over modules.
    #[test]
    fn long_paired_bodies_are_cut_into_parts_in_modules() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../tests/data/scale/twin_arms.urdf"
        );
        let text = f64_source(&crate::load(path.as_ref()).unwrap(), Algorithm::Crba);
        assert!(text.contains("type P = "), "not paired");
        assert!(text.contains("sp: &mut ["), "no scratch array of pairs");
        assert!(
            text.contains("mod crba_parts_1"),
            "not cut into parts in modules"
        );
        assert!(text.contains("use self::crba_parts_0::"));
        assert!(most_lets(&text).0 <= 2_400);

        // With debug info, LLVM recurses once per nested `let` scope: paired `kinematics` of two 50-link
        // arms, 2,000 statements and 2,922 `let`s (the pairs taken out to scalars add them), overflowed
        // rustc's stack in a debug build (attacker's trial). Parts are cut by `let`s now.
        let mut urdf = String::from("<robot name=\"twin50\"><link name=\"base\"/>");
        for (side, y) in [("l", 0.2f64), ("r", -0.2)] {
            let mut parent = "base".to_string();
            for i in 1..=50 {
                let axis = ["0 0 1", "0 1 0", "1 0 0"][i % 3];
                let mass = 1.0 + 0.3 * ((i * 7) % 5) as f64;
                let offset = if i == 1 { y } else { 0.004 * -y.signum() };
                urdf += &format!(
                    "<link name=\"{side}{i}\"><inertial><origin xyz=\"0.003 0 0.08\"/><mass \
                     value=\"{mass}\"/><inertia ixx=\"4.5e-3\" ixy=\"0\" ixz=\"-7.3e-6\" \
                     iyy=\"3.8e-3\" iyz=\"0\" izz=\"1.1e-3\"/></inertial></link><joint \
                     name=\"{side}_joint{i}\" type=\"continuous\"><parent link=\"{parent}\"/><child \
                     link=\"{side}{i}\"/><origin xyz=\"0.02 {offset} 0.17\"/><axis xyz=\"{axis}\"/></joint>"
                );
                parent = format!("{side}{i}");
            }
        }
        urdf += "</robot>";
        let dir = std::env::temp_dir().join(format!("embedyn-twin50-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("twin50.urdf");
        std::fs::write(&file, urdf).unwrap();
        let loaded = crate::load(&file).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        let text = f64_source(&loaded, Algorithm::Kinematics);
        assert!(text.contains("type P = "), "not paired");
        let (lets, function) = most_lets(&text);
        assert!(lets > 1000 && lets <= 2_400, "{lets} lets in `{function}`");
    }

    /// A floating quadruped's `aba_derivatives` is traced as factors (the product `−M⁻¹ ∂τ`, 10k
    /// operations, in a loop after them), which are under the pairing limit and paired, and every
    /// computed entry of its outputs is written by the part that computes it: the function of the
    /// factors reads no scratch slot into an output.
    #[test]
    fn a_quadrupeds_derivatives_are_paired_and_written_where_computed() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../tests/data/pinocchio/solo12.urdf"
        );
        let options = GenerateOptions {
            f32: false,
            model: ModelOptions {
                floating: true,
                ..ModelOptions::default()
            },
            // (without the AVX twin, which repeats the function in a module of its own)
            avx_twins: crate::AvxTwins::None,
            ..GenerateOptions::default()
        }
        .with_requested(Some(vec![Algorithm::AbaDerivatives]), &[]);
        let text = generate_source(&crate::load(path.as_ref()).unwrap(), &options).unwrap();
        assert!(text.contains("type P = "), "not paired");
        assert!(
            text.contains("mod aba_derivatives_factors_parts_0"),
            "not in parts"
        );
        let factors = &text[text.find("pub fn aba_derivatives_factors(").unwrap()..];
        let factors = &factors[..factors.find("pub fn aba_derivatives(").unwrap()];
        assert!(
            !factors.contains("= s["),
            "an output read from the scratch array"
        );
        assert!(text.contains("dqdd_dq[0][0] = "));
        let public = &text[text.find("pub fn aba_derivatives(").unwrap()..];
        assert_eq!(public.matches("minus_symmetric_times_sparse").count(), 2);
    }

    /// A paired function's `_batch` form goes state by state through the scalar function where the lane
    /// module says so (four f64 lanes without AVX); an unpaired one's always through the lanes.
    #[test]
    fn batch_forms_of_paired_functions_can_go_state_by_state() {
        let source = |file: &str, floating: bool| {
            let options = GenerateOptions {
                f32: false,
                lanes: 4,
                model: ModelOptions {
                    floating,
                    ..ModelOptions::default()
                },
                ..GenerateOptions::default()
            }
            .with_requested(Some(vec![Algorithm::Aba]), &[]);
            let path = format!("{}/../{file}", env!("CARGO_MANIFEST_DIR"));
            generate_source(&crate::load(path.as_ref()).unwrap(), &options).unwrap()
        };
        let batch = |text: &str| -> String {
            let at = text.find("pub fn aba_batch(").expect("a batch form");
            text[at..at + text[at..].find("\n    }\n").unwrap()].to_string()
        };
        let paired = source("tests/data/pinocchio/solo12.urdf", true);
        assert!(paired.contains("type P = "), "not paired");
        let b = batch(&paired);
        assert!(b.contains("if PAIRED_BATCH_PER_STATE"), "{b}");
        assert!(
            b.contains("scalar_module::aba(&q[s], &v[s], &tau[s], &mut qdd[s]);"),
            "{b}"
        );
        assert!(paired.contains("const PAIRED_BATCH_PER_STATE: bool"));
        let unpaired = source("models/peers/z1.urdf", false);
        assert!(!unpaired.contains("type P = "), "paired");
        assert!(!batch(&unpaired).contains("PAIRED_BATCH_PER_STATE"));
    }

    /// A function of at least `TWIN_MIN_STATEMENTS` statements gets an AVX twin in the f64 module only
    /// (src/dispatch.rs), in both the source text and the macro's tokens, and one below it where the
    /// module's budget allows; with `avx_twins` off, none does.
    #[test]
    fn large_functions_get_an_avx_twin_in_the_f64_module() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/peers/z1.urdf");
        let loaded = crate::load(path.as_ref()).unwrap();
        let options = |algorithm, twins: bool| {
            GenerateOptions {
                avx_twins: if twins {
                    crate::AvxTwins::Large
                } else {
                    crate::AvxTwins::None
                },
                ..GenerateOptions::default()
            }
            .with_requested(Some(vec![algorithm]), &[])
        };
        // The Z1's `aba_derivatives`: 11k statements.
        let text = generate_source(&loaded, &options(Algorithm::AbaDerivatives, true)).unwrap();
        let f32_start = text.find("pub mod f32 {").unwrap();
        let (f64_module, f32_module) = text.split_at(f32_start);
        assert_eq!(f64_module.matches("mod aba_derivatives_avx {").count(), 1);
        assert_eq!(f64_module.matches("dispatch::avx()").count(), 1);
        assert!(f64_module.contains("aba_derivatives_avx::aba_derivatives("));
        assert!(!f32_module.contains("_avx"), "the f32 module has no twins");
        // Every function of the twin has AVX, and only those: as many attributes as twin functions.
        let twin = &f64_module[f64_module.find("mod aba_derivatives_avx {").unwrap()..];
        let functions = twin
            .lines()
            .filter(|l| {
                l.trim_start().starts_with("pub(super) fn ")
                    || l.trim_start().starts_with("pub fn ")
            })
            .count();
        assert!(functions > 1);
        assert_eq!(
            twin.matches("#[target_feature(enable = \"avx\")]").count(),
            functions
        );
        let tokens = generate_tokens(&loaded, &options(Algorithm::AbaDerivatives, true))
            .unwrap()
            .to_string();
        assert_eq!(tokens.matches("mod aba_derivatives_avx").count(), 1);

        // The standalone crate's README names it.
        #[cfg(feature = "standalone")]
        {
            let readme = standalone_readme(&loaded, &options(Algorithm::AbaDerivatives, true));
            assert!(
                readme.contains("function `aba_derivatives` is also compiled with AVX"),
                "{readme}"
            );
        }
        let without = generate_source(&loaded, &options(Algorithm::AbaDerivatives, false)).unwrap();
        assert!(!without.contains("_avx"));
        // Its `aba` (1.7k statements) alone gets one under the module's budget
        // (`dispatch::TWIN_BUDGET_STATEMENTS`), but not beside `aba_derivatives` and `step_derivatives`
        // (twinned by size), which leave too little of it.
        let small = generate_source(&loaded, &options(Algorithm::Aba, true)).unwrap();
        assert_eq!(small.matches("mod aba_avx {").count(), 1);
        let three = GenerateOptions {
            avx_twins: crate::AvxTwins::Large,
            ..GenerateOptions::default()
        }
        .with_requested(
            Some(vec![
                Algorithm::Aba,
                Algorithm::AbaDerivatives,
                Algorithm::StepDerivatives,
            ]),
            &[],
        );
        let three = generate_source(&loaded, &three).unwrap();
        assert_eq!(three.matches("mod aba_derivatives_avx {").count(), 1);
        assert_eq!(three.matches("mod step_derivatives_avx {").count(), 1);
        assert!(!three.contains("mod aba_avx {"));
    }

    /// A wide tree's smallest twinned functions also get an AVX-512 twin (src/dispatch.rs,
    /// `AVX512_MIN_NV`): the bundled 34-joint humanoid's `kinematics` and `crba` under the default
    /// budget, not its larger `rnea` and `aba`; a floating quadruped (nv = 18) gets none, and
    /// `avx_twins = all` gives one to every function.
    #[test]
    fn a_wide_trees_small_functions_get_an_avx512_twin() {
        let load = |path: &str| {
            crate::load(format!("{}/../{path}", env!("CARGO_MANIFEST_DIR")).as_ref()).unwrap()
        };
        let options = |floating: bool, avx_twins: crate::AvxTwins| GenerateOptions {
            model: ModelOptions {
                floating,
                ..ModelOptions::default()
            },
            avx_twins,
            f32: false,
            ..GenerateOptions::default()
        };
        let wide = |text: &str| -> Vec<&str> {
            ["kinematics", "aba", "rnea", "crba"]
                .into_iter()
                .filter(|f| text.contains(&format!("mod {f}_avx512 {{")))
                .collect()
        };
        let humanoid = load("models/humanoid34.urdf");
        let text = generate_source(&humanoid, &options(false, crate::AvxTwins::Large)).unwrap();
        assert_eq!(wide(&text), ["kinematics", "crba"]);
        // Each asks for its AVX-512 twin first, then for its AVX one.
        let crba = &text[text.find("pub fn crba(").unwrap()..];
        let (avx512, avx) = (
            crba.find("dispatch::avx512()").unwrap(),
            crba.find("dispatch::avx()").unwrap(),
        );
        assert!(avx512 < avx);
        // The standalone crate's README names them.
        #[cfg(feature = "standalone")]
        {
            let readme = standalone_readme(&humanoid, &options(false, crate::AvxTwins::Large));
            assert!(
                readme.contains(
                    "The `f64` module's functions `kinematics`, `crba` are also compiled with AVX-512"
                ),
                "{readme}"
            );
        }
        let all = generate_source(&humanoid, &options(false, crate::AvxTwins::All)).unwrap();
        assert_eq!(wide(&all), ["kinematics", "aba", "rnea", "crba"]);
        let quadruped = load("models/peers/anymal_b.urdf");
        let text = generate_source(&quadruped, &options(true, crate::AvxTwins::Large)).unwrap();
        assert!(text.contains("mod crba_avx {"));
        assert!(wide(&text).is_empty());
    }

    /// The smaller functions' twins are a speed-up, not a request: under a memory limit that the code
    /// fits only without them they are left out, where generation used to be refused (a new user's trial:
    /// the floating ANYmal B's default functions refused at 200 MB, which fit before the budget twins).
    #[test]
    fn budget_twins_give_way_to_the_memory_limit() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/peers/anymal_b.urdf");
        let loaded = crate::load(path.as_ref()).unwrap();
        let options = |limit: Option<u64>| GenerateOptions {
            model: ModelOptions {
                floating: true,
                ..ModelOptions::default()
            },
            max_compile_memory_mb: limit,
            ..GenerateOptions::default()
        };
        let twins = |text: &str| {
            ["kinematics", "aba", "rnea", "crba"]
                .iter()
                .filter(|f| text.contains(&format!("mod {f}_avx {{")))
                .count()
        };
        let unlimited = generate_source(&loaded, &options(None)).unwrap();
        let roomy = twins(&unlimited);
        assert!(roomy >= 3, "{roomy} twins without a limit");
        // The smallest limit without any twin (measured: 191 MB) fits; the small twins do not.
        let tight = generate_source(&loaded, &options(Some(200))).unwrap();
        assert!(twins(&tight) < roomy, "{} of {roomy}", twins(&tight));
        // Every function is still there, in both scalar modules.
        for f in ["kinematics", "aba", "rnea", "crba"] {
            assert!(tight.matches(&format!("pub fn {f}(")).count() >= 2, "{f}");
        }
    }

    /// The twins by size are a speed-up too under the default (`large`): where the code fits the limit only
    /// without a large function's twin, the twin is left out; asked for (`all`) it still refuses. Measured
    /// for the humanoid34's `aba` in f64 (a twin by size): it fits 150 MB without its twin, 170 MB with it.
    #[test]
    fn large_twins_give_way_to_the_memory_limit_by_default() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/humanoid34.urdf");
        let loaded = crate::load(path.as_ref()).unwrap();
        let options = |twins: crate::AvxTwins, limit: Option<u64>| {
            GenerateOptions {
                f32: false,
                avx_twins: twins,
                max_compile_memory_mb: limit,
                ..GenerateOptions::default()
            }
            .with_requested(Some(vec![Algorithm::Aba]), &[])
        };
        let twinned = |text: &str| text.contains("mod aba_avx {");
        let roomy = generate_source(&loaded, &options(crate::AvxTwins::Large, None)).unwrap();
        assert!(twinned(&roomy));
        let tight = generate_source(&loaded, &options(crate::AvxTwins::Large, Some(160))).unwrap();
        assert!(!twinned(&tight));
        assert!(tight.contains("pub fn aba("));
        let refusal = generate_source(&loaded, &options(crate::AvxTwins::All, Some(160)))
            .unwrap_err()
            .to_string();
        assert!(refusal.contains("--avx-twins none"), "{refusal}");
    }

    /// A refusal for size names each frame function by its own name, not the algorithm's `frame` (a new
    /// user's trial: two feet were listed as `frame` twice).
    #[test]
    fn a_refusal_names_frame_functions_by_their_links() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/peers/anymal_b.urdf");
        let loaded = crate::load(path.as_ref()).unwrap();
        let options = GenerateOptions {
            model: ModelOptions {
                floating: true,
                ..ModelOptions::default()
            },
            links: LinkOptions {
                frames: vec!["LF_FOOT".to_string(), "RF_FOOT".to_string()],
                ..LinkOptions::default()
            },
            max_compile_memory_mb: Some(120),
            ..GenerateOptions::default()
        }
        .with_requested(Some(vec![Algorithm::Aba, Algorithm::Frame]), &[]);
        let refusal = generate_source(&loaded, &options).unwrap_err().to_string();
        assert!(refusal.contains("`frame_lf_foot` "), "{refusal}");
        assert!(refusal.contains("`frame_rf_foot` "), "{refusal}");
        assert!(refusal.contains("`aba` "), "{refusal}");
    }

    /// Every function of a lane module of 256-bit values (`f64x4`, `f32x8`) gets an AVX twin, however
    /// small, whose batch form goes through the lanes; the 128-bit lane modules (`f32x4`) get none, and
    /// `avx_twins = none` leaves them all out. The standalone README names the twinned lane functions.
    #[test]
    fn lane_modules_of_256_bits_get_an_avx_twin() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/peers/z1.urdf");
        let loaded = crate::load(path.as_ref()).unwrap();
        let options = |lanes: usize, twins: crate::AvxTwins| {
            GenerateOptions {
                lanes,
                avx_twins: twins,
                ..GenerateOptions::default()
            }
            .with_requested(Some(vec![Algorithm::Aba]), &[])
        };
        let module = |text: &str, name: &str| -> String {
            let start = text.find(&format!("pub mod {name} {{")).unwrap();
            let end = text[start + 1..]
                .find("\npub mod ")
                .map_or(text.len(), |e| start + 1 + e);
            text[start..end].to_string()
        };
        // The Z1's `aba` (1.8k statements: in the f64 module an AVX twin only, under the module's budget).
        let text = generate_source(&loaded, &options(4, crate::AvxTwins::Large)).unwrap();
        assert_eq!(module(&text, "f64").matches("mod aba_avx {").count(), 1);
        assert!(!module(&text, "f64").contains("_avx512"));
        let f64x4 = module(&text, "f64x4");
        // Two twins: AVX-512 (F and VL), then AVX.
        assert_eq!(f64x4.matches("mod aba_avx {").count(), 1);
        assert_eq!(f64x4.matches("mod aba_avx512 {").count(), 1);
        // `aba` and `aba_batch` dispatch, AVX-512 asked first; the twins' batch goes through the lanes.
        assert_eq!(f64x4.matches("dispatch::avx()").count(), 2, "{f64x4}");
        assert_eq!(f64x4.matches("dispatch::avx512()").count(), 2, "{f64x4}");
        let public = &f64x4[..f64x4.find("mod aba_avx").unwrap()];
        let first = public.find("dispatch::avx512()").unwrap();
        assert!(first < public.find("dispatch::avx()").unwrap(), "{public}");
        assert!(f64x4.contains("aba_avx::aba_batch("));
        assert!(f64x4.contains("aba_avx512::aba_batch("));
        for (twin, features) in [("aba_avx", "avx"), ("aba_avx512", "avx512f,avx512vl")] {
            let start = f64x4.find(&format!("mod {twin} {{")).unwrap();
            let end = f64x4[start + 1..]
                .find("    mod aba_avx")
                .map_or(f64x4.len(), |e| start + 1 + e);
            let twin = &f64x4[start..end];
            assert!(twin.contains("const PAIRED_BATCH_PER_STATE: bool = false;"));
            assert!(twin.contains("::AvxF64x4;"), "{twin}");
            // Every function of the twin compiled for its level, and none dispatches again.
            let attribute = format!("#[target_feature(enable = \"{features}\")]");
            assert_eq!(
                twin.matches("#[target_feature(").count(),
                twin.matches(&attribute).count()
            );
            assert!(twin.matches(&attribute).count() >= 2, "{twin}");
            assert!(!twin.contains("dispatch::avx"), "{twin}");
        }
        // Arguments and results handed over to the twins' lane type.
        assert_eq!(
            f64x4.matches("dispatch::recast(").count(),
            2 * 2 * (1 + 4),
            "{f64x4}"
        );
        assert!(!module(&text, "f32x4").contains("_avx"), "128-bit lanes");
        let eight = GenerateOptions {
            f64: false,
            ..options(8, crate::AvxTwins::Large)
        };
        let eight = generate_source(&loaded, &eight).unwrap();
        assert_eq!(module(&eight, "f32x8").matches("mod aba_avx {").count(), 1);
        assert_eq!(
            module(&eight, "f32x8").matches("mod aba_avx512 {").count(),
            1
        );
        let tokens = generate_tokens(&loaded, &options(4, crate::AvxTwins::Large))
            .unwrap()
            .to_string();
        // The f64 module's twin and the f64x4 module's.
        assert_eq!(tokens.matches("mod aba_avx ").count(), 2);
        assert_eq!(tokens.matches("mod aba_avx512 ").count(), 1);
        let none = generate_source(&loaded, &options(4, crate::AvxTwins::None)).unwrap();
        assert!(!none.contains("_avx"));
        #[cfg(feature = "standalone")]
        {
            let readme = standalone_readme(&loaded, &options(4, crate::AvxTwins::Large));
            assert!(
                readme.contains("the `f64x4` module's function `aba` is also compiled with AVX"),
                "{readme}"
            );
            assert!(
                readme.contains("the `f64` module's function `aba` is also compiled with AVX"),
                "{readme}"
            );
        }
    }

    /// With lanes, frames on links `foo` and `foo_batch` would give two functions `frame_foo_batch` in the
    /// lane module (the batch form of one, the other itself): refused, naming both links; without lanes
    /// both are generated.
    #[test]
    fn a_frame_function_named_like_another_ones_batch_form_is_refused_with_lanes() {
        let urdf = "<robot name=\"clash\"><link name=\"base\"/><link name=\"foo\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" iyy=\"0.1\" izz=\"0.1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link><link name=\"foo_batch\"><inertial><mass value=\"1\"/><inertia ixx=\"0.1\" iyy=\"0.1\" izz=\"0.1\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link><joint name=\"a\" type=\"revolute\"><parent link=\"base\"/><child link=\"foo\"/><axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint><joint name=\"b\" type=\"revolute\"><parent link=\"foo\"/><child link=\"foo_batch\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint></robot>";
        let dir = std::env::temp_dir().join(format!("embedyn-clash-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("clash.urdf");
        std::fs::write(&file, urdf).unwrap();
        let loaded = crate::load(&file).unwrap();
        let options = |lanes: usize| {
            GenerateOptions {
                lanes,
                f32: false,
                links: LinkOptions {
                    frames: vec!["foo".into(), "foo_batch".into()],
                    ..LinkOptions::default()
                },
                ..GenerateOptions::default()
            }
            .with_requested(Some(vec![Algorithm::Frame]), &[])
        };
        let error = generate_source(&loaded, &options(4))
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("frame_foo_batch")
                && error.contains("`foo`")
                && error.contains("`foo_batch`"),
            "{error}"
        );
        let text = generate_source(&loaded, &options(0)).unwrap();
        assert!(text.contains("pub fn frame_foo(") && text.contains("pub fn frame_foo_batch("));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The README of the standalone crate of `loaded` with `options`.
    #[cfg(feature = "standalone")]
    fn standalone_readme(loaded: &Loaded, options: &GenerateOptions) -> String {
        let files = crate::standalone::crate_files(loaded, options).unwrap();
        files
            .into_iter()
            .find(|(p, _)| p.ends_with("README.md"))
            .unwrap()
            .1
    }

    /// The generated source of `algorithm` alone, f64 only.
    fn f64_source(loaded: &Loaded, algorithm: Algorithm) -> String {
        let options = GenerateOptions {
            f32: false,
            ..GenerateOptions::default()
        }
        .with_requested(Some(vec![algorithm]), &[]);
        generate_source(loaded, &options).unwrap()
    }

    /// The most `let` statements of one generated function (or part) in `text`, and its name.
    fn most_lets(text: &str) -> (usize, String) {
        let mut most = (0, String::new());
        let mut current: Option<(usize, String)> = None;
        for line in text.lines() {
            let line = line.trim_start();
            let header = line
                .strip_prefix("pub fn ")
                .or_else(|| line.strip_prefix("pub(super) fn "))
                .or_else(|| line.strip_prefix("pub(crate) fn "));
            if let Some(rest) = header {
                most = most.max(current.take().unwrap_or_default());
                current = Some((0, rest.split('(').next().unwrap().to_string()));
            } else if line.starts_with("let ") {
                if let Some((n, _)) = current.as_mut() {
                    *n += 1;
                }
            }
        }
        most.max(current.unwrap_or_default())
    }

    fn quadruped() -> Loaded {
        crate::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/quadruped.urdf").as_ref())
            .unwrap()
    }

    /// A link is spelled alike in `frames::`, `wrench::` and `frame_<link>`, whatever links are named and
    /// in whatever order (attacker trial, issue 11: `wrench::FOOT` was the link `foot` while
    /// `frames::FOOT` was `Foot`).
    #[test]
    fn links_are_spelled_alike_in_frames_wrench_and_frame_functions() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../tests/data/case_names.urdf");
        let loaded = crate::load(path.as_ref()).unwrap();
        let model = loaded.model::<f64>(&Default::default()).unwrap();
        let spelling = link_constants(&model);
        for order in [["foot", "Foot", "foot_2"], ["foot_2", "Foot", "foot"]] {
            let options = GenerateOptions {
                f32: false,
                links: LinkOptions {
                    wrenches: order.map(String::from).to_vec(),
                    frames: order.map(String::from).to_vec(),
                    ..Default::default()
                },
                ..GenerateOptions::default()
            };
            let text = generate_source(&loaded, &options).unwrap();
            let module = |name: &str| -> String {
                let start = text.find(&format!("pub mod {name} {{")).unwrap();
                text[start..start + text[start..].find("\n}").unwrap()].to_string()
            };
            let (frames, wrench) = (module("frames"), module("wrench"));
            for (k, link) in order.iter().enumerate() {
                let c = &spelling[*link];
                let frame_index = model
                    .frames()
                    .position(|f| model.frame_name(f) == Some(link));
                assert!(
                    frames.contains(&format!("pub const {c}: usize = {};", frame_index.unwrap()))
                );
                assert!(
                    wrench.contains(&format!("pub const {c}: usize = {k};")),
                    "{wrench}"
                );
                assert!(text.contains(&format!("pub fn frame_{}(", c.to_ascii_lowercase())));
            }
        }
    }

    /// The size guard weighs a lane module's copies (attacker trial, issue 13: `--lanes 4` on the
    /// quadruped's `aba_derivatives` passed a 340 MB limit and took 1.31 GB to compile): a limit the
    /// scalar module alone fits is refused with lanes, before and after tracing.
    #[test]
    fn the_size_guard_counts_lane_modules() {
        let loaded =
            crate::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/quadruped.urdf").as_ref())
                .unwrap();
        let options = |lanes: usize| {
            GenerateOptions {
                f32: false,
                max_compile_memory_mb: Some(340),
                lanes,
                ..GenerateOptions::default()
            }
            .with_requested(Some(vec![Algorithm::AbaDerivatives]), &[])
        };
        assert!(generate_source(&loaded, &options(0)).is_ok());
        let e = generate_source(&loaded, &options(4))
            .unwrap_err()
            .to_string();
        assert!(e.contains("340"), "{e}");
    }

    /// Long functions are split into parts named after their bodies; a body named `ext` (or
    /// `independent`, `bias`, `step`) must not give a part the name of a public function (`aba` + `ext` =
    /// `aba_ext`), on a chain long enough to be split (attacker trial, issue 11: rustc's E0428 on this
    /// very chain). With lanes, a body named `batch` must not give a lane module's part the name of a batch
    /// form (`aba` + `batch`).
    #[test]
    fn parts_of_long_functions_never_take_a_public_function_name() {
        for (last, lanes) in [("ext", 0), ("batch", 4)] {
            parts_never_take_a_public_name(last, lanes);
        }
    }

    fn parts_never_take_a_public_name(last: &str, lanes: usize) {
        let dir = std::env::temp_dir().join(format!("embedyn-parts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let inertial = r#"<inertial><origin xyz="0.05 0.01 0.02"/><mass value="0.5"/><inertia ixx="0.001" ixy="1e-05" ixz="0" iyy="0.0015" iyz="0" izz="0.00125"/></inertial>"#;
        let mut urdf = String::from(r#"<robot name="chain"><link name="base"/>"#);
        let mut parent = "base".to_string();
        // The attacker's chain: 24 links, the last named `ext` (its own part of `aba`).
        for i in 0..24 {
            let link = match i {
                23 => last.to_string(),
                _ => format!("b{i}"),
            };
            let axis = ["1 0 0", "0 1 0", "0 0 1"][i % 3];
            urdf += &format!(
                r#"<link name="{link}">{inertial}</link><joint name="{link}" type="revolute"><parent link="{parent}"/><child link="{link}"/><origin xyz="0.1 0.02 0.03" rpy="0.1 0.2 0.3"/><axis xyz="{axis}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>"#
            );
            parent = link;
        }
        urdf += "</robot>";
        let path = dir.join("chain.urdf");
        std::fs::write(&path, urdf).unwrap();
        let loaded = crate::load(&path).unwrap();
        let options = GenerateOptions {
            f32: false,
            links: LinkOptions {
                wrenches: vec![last.into(), "b4".into()],
                frames: vec![last.into()],
                ..Default::default()
            },
            lanes,
            // (the AVX twins repeat the names in modules of their own)
            avx_twins: crate::AvxTwins::None,
            ..GenerateOptions::default()
        }
        .with_requested(None, &[Algorithm::CentroidalBias, Algorithm::Centroidal]);
        let text = generate_source(&loaded, &options).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        // Names are unique per module (the lane module repeats the scalar module's functions).
        let mut seen = std::collections::HashSet::new();
        let mut modules = 0;
        for line in text.lines() {
            let line = line.trim_start();
            if line.starts_with("pub mod f64") || line.starts_with("pub mod f32") {
                modules += 1;
                seen.clear();
                continue;
            }
            let Some(rest) = line
                .strip_prefix("pub fn ")
                .or_else(|| line.strip_prefix("pub(super) fn "))
                .or_else(|| line.strip_prefix("fn "))
            else {
                continue;
            };
            let name = rest.split(['(', '<']).next().unwrap();
            assert!(seen.insert(name.to_string()), "`{name}` is defined twice");
        }
        assert!(
            seen.iter().any(|n| n.starts_with("aba_") && n != "aba_ext"),
            "aba was not split: {seen:?}"
        );
        assert!(seen.contains("aba_ext") && seen.contains("centroidal_bias"));
        assert_eq!(modules, if lanes > 0 { 2 } else { 1 });
        if lanes > 0 {
            assert!(seen.contains("aba_batch"), "{seen:?}");
        }
    }

    #[test]
    fn links_named_at_generation_time_are_checked_and_generate_their_functions() {
        let loaded = quadruped();
        let with_links = |wrenches: &[&str], frames: &[&str], only: Option<Vec<Algorithm>>| {
            GenerateOptions {
                f32: false,
                links: LinkOptions {
                    wrenches: wrenches.iter().map(|s| s.to_string()).collect(),
                    frames: frames.iter().map(|s| s.to_string()).collect(),
                    reference: Reference::World,
                },
                ..GenerateOptions::default()
            }
            .with_requested(only, &[])
        };
        // An unknown link: named, with the closest names.
        let e = generate_source(&loaded, &with_links(&["FL_fot"], &[], None))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(
                "--wrenches / wrenches(…): there is no link \"FL_fot\" (did you mean \"FL_foot\"?)"
            ),
            "{e}"
        );
        let e = generate_source(&loaded, &with_links(&[], &["elbow"], None))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("there is no link \"elbow\" (`embedyn info` lists"),
            "{e}"
        );
        // A function of links asked for without links.
        let e = generate_source(
            &loaded,
            &with_links(&[], &[], Some(vec![Algorithm::NleExt])),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains(
                "`nle_ext` is generated for links named at generation time, and none is named"
            ),
            "{e}"
        );
        // A link named twice is an error (one row of f_ext, one frame function per link).
        let e = generate_source(
            &loaded,
            &with_links(&["FL_foot", "imu", "FL_foot"], &[], None),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("the link \"FL_foot\" is named twice"), "{e}");
        assert!(e.contains("one row of `f_ext` per link"), "{e}");
        // In frames(…) the reason is the frame function (an attacker's trial: it said `f_ext`).
        let e = generate_source(&loaded, &with_links(&[], &["trunk", "trunk"], None))
            .unwrap_err()
            .to_string();
        assert!(e.contains("the link \"trunk\" is named twice"), "{e}");
        assert!(
            e.contains("one frame function per link") && !e.contains("f_ext"),
            "{e}"
        );
        // Links for functions `only(…)` leaves out are an error, not silently ignored.
        for (wrenches, frames, missing) in [
            (
                &["FL_foot"][..],
                &[][..],
                "`aba_ext`, `rnea_ext`, `nle_ext`, `aba_derivatives_ext` or `rnea_derivatives_ext`",
            ),
            (&[][..], &["trunk"][..], "`frame`"),
        ] {
            let e = generate_source(
                &loaded,
                &with_links(wrenches, frames, Some(vec![Algorithm::Aba])),
            )
            .unwrap_err()
            .to_string();
            assert!(e.contains(&format!("add {missing} to `only(…)`")), "{e}");
        }
        // Without `only`: aba_ext, rnea_ext and one frame function per link.
        let text = generate_source(
            &loaded,
            &with_links(&["FL_foot", "imu"], &["trunk", "FL_foot"], None),
        )
        .unwrap();
        for f in [
            "pub fn aba(",
            "pub fn aba_ext(",
            "pub fn rnea_ext(",
            "pub fn frame_trunk(",
            "pub fn frame_fl_foot(",
            "f_ext: &[[S; 6]; 2]",
            "pub const WRENCH_LINKS: [&str; 2] = [\"FL_foot\", \"imu\"];",
            "pub const IMU: usize = 1;",
            "reference `world`",
        ] {
            assert!(text.contains(f), "{f}");
        }
        assert!(!text.contains("pub fn nle_ext("));
        // Without links nothing of them is generated: `aba` as before.
        let plain = generate_source(&loaded, &with_links(&[], &[], None)).unwrap();
        assert!(!plain.contains("WRENCH_LINKS") && !plain.contains("f_ext"));
    }

    #[test]
    fn requested_functions_are_merged_alike_for_the_macro_and_the_command_line() {
        // `only(aba, aba, crba)` with `minv`: exactly those, each once, in the order given.
        let only = GenerateOptions::default().with_requested(
            Some(vec![Algorithm::Aba, Algorithm::Aba, Algorithm::Crba]),
            &[Algorithm::Minv],
        );
        assert_eq!(
            only.algorithms,
            [Algorithm::Aba, Algorithm::Crba, Algorithm::Minv]
        );
        assert!(only.exact);
        assert_eq!(only.generated_algorithms(true), only.algorithms);
        // Without `only`: the default functions, `minv` once, and for a model with constraints the
        // functions it also gets.
        let default =
            GenerateOptions::default().with_requested(None, &[Algorithm::Minv, Algorithm::Minv]);
        assert!(!default.exact);
        let names =
            |list: Vec<Algorithm>| list.into_iter().map(Algorithm::name).collect::<Vec<_>>();
        assert_eq!(
            names(default.generated_algorithms(false)),
            ["kinematics", "aba", "rnea", "crba", "minv"]
        );
        assert_eq!(
            names(default.generated_algorithms(true)),
            [
                "kinematics",
                "aba",
                "rnea",
                "crba",
                "minv",
                "complete",
                "embedding",
                "crba_independent"
            ]
        );
    }
}

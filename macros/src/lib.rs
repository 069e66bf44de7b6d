//! The `robot!` proc-macro: a thin shell over `embedyn-codegen`, which does all the work (the same
//! function serves `build.rs` and `embedyn generate`).

#![warn(missing_docs)]

use proc_macro::TokenStream;
use quote::quote;
use syn::parse::{Parse, ParseStream};
use syn::{Ident, LitStr, Path, Token};

/// `robot!("model.urdf")` or `robot!("model.urdf", floating, minv, nle, only(aba, kinematics), crate = ::my_facade)`
/// (and `max_compile_memory = 4096` to raise the limit on rustc's estimated memory, MB; `gravity = [0.0,
/// 0.0, -1.62]` for another gravity than (0, 0, −9.81) m/s², folded into the code; `lock(knee = 0.3, …)` to fix
/// joints; `rotors = reflected` for the reflected-inertia approximation of geared rotors; `wrenches(lf_foot, …)`
/// for `aba_ext` and `rnea_ext` with those links' wrenches; `frames(lf_foot, …)` and `reference = world` for a
/// function `frame_<link>` per link: pose, Jacobian, bias).
struct Args {
    path: LitStr,
    floating: bool,
    /// Functions generated on request, each asked for by its name as an option (`minv`, `gravity`, `nle`).
    requested: Vec<embedyn_codegen::Algorithm>,
    f64: bool,
    f32: bool,
    krate: Option<Path>,
    /// `only(aba, kinematics, …)`: exactly these functions.
    only: Option<Vec<embedyn_codegen::Algorithm>>,
    /// `max_compile_memory = MB`.
    max_compile_memory: u64,
    /// `lanes = N`: lane modules (`f64xN`, …) of `N` states per call; 0 for none.
    lanes: usize,
    /// `avx_twins = none|large|all` (`GenerateOptions::avx_twins`).
    avx_twins: embedyn_codegen::AvxTwins,
    /// `gravity = [x, y, z]` (m/s², world frame).
    gravity: Option<[f64; 3]>,
    /// `lock(joint = value, …)`.
    locks: Vec<embedyn_codegen::LockedJoint>,
    /// `rotors = exact | reflected`.
    rotors: embedyn_codegen::Rotors,
    /// `wrenches(link, …)`, `frames(link, …)`, `reference = …`.
    links: embedyn_codegen::LinkOptions,
}

/// A number literal, optionally negated.
fn parse_number(input: ParseStream) -> syn::Result<f64> {
    let negative = input.parse::<Option<Token![-]>>()?.is_some();
    let value = if input.peek(syn::LitFloat) {
        input.parse::<syn::LitFloat>()?.base10_parse::<f64>()?
    } else if input.peek(syn::LitInt) {
        input.parse::<syn::LitInt>()?.base10_parse::<f64>()?
    } else {
        return Err(input.error(
            "expected a number literal such as 0.3 or -1 (the macro reads the model at compile time: constants and expressions are not evaluated)",
        ));
    };
    Ok(if negative { -value } else { value })
}

/// `(knee = 0.3, "left-knee" = -0.1)`: joint names (identifiers or string literals) and finite values.
fn parse_locks(input: ParseStream) -> syn::Result<Vec<embedyn_codegen::LockedJoint>> {
    let content;
    syn::parenthesized!(content in input);
    let mut locks = Vec::new();
    while !content.is_empty() {
        let (joint, span) = if content.peek(LitStr) {
            let name: LitStr = content.parse()?;
            (name.value(), name.span())
        } else {
            // Any identifier, keywords too (`type = 0.1`, `r#type = 0.1`), by its name without `r#`.
            let name = content.call(<Ident as syn::ext::IdentExt>::parse_any)?;
            (syn::ext::IdentExt::unraw(&name).to_string(), name.span())
        };
        content.parse::<Token![=]>()?;
        let value = parse_number(&content)?;
        if !value.is_finite() {
            return Err(syn::Error::new(
                span,
                "lock(joint = value): the value must be a finite number (rad or m)",
            ));
        }
        locks.push(embedyn_codegen::LockedJoint { joint, value });
        if !content.is_empty() {
            content.parse::<Token![,]>()?;
        }
    }
    Ok(locks)
}

/// `(lf_foot, r#type, "LF-foot")`: link names as identifiers (keywords too, raw or not) or string
/// literals.
fn parse_names(input: ParseStream) -> syn::Result<Vec<String>> {
    let content;
    syn::parenthesized!(content in input);
    let mut names = Vec::new();
    while !content.is_empty() {
        if content.peek(LitStr) {
            names.push(content.parse::<LitStr>()?.value());
        } else {
            let name = content.call(<Ident as syn::ext::IdentExt>::parse_any)?;
            names.push(syn::ext::IdentExt::unraw(&name).to_string());
        }
        if !content.is_empty() {
            content.parse::<Token![,]>()?;
        }
    }
    Ok(names)
}

/// `[x, y, z]`: three number literals, each optionally negated.
fn parse_gravity(input: ParseStream) -> syn::Result<[f64; 3]> {
    let content;
    let brackets = syn::bracketed!(content in input);
    let mut values = Vec::new();
    while !content.is_empty() {
        values.push(parse_number(&content)?);
        if !content.is_empty() {
            content.parse::<Token![,]>()?;
        }
    }
    match values[..] {
        [x, y, z] if values.iter().all(|v| v.is_finite()) => Ok([x, y, z]),
        _ => Err(syn::Error::new(
            brackets.span.join(),
            "gravity = [x, y, z]: three finite numbers in m/s² (e.g. [0.0, 0.0, -9.81])",
        )),
    }
}

/// The functions generated only when asked for, each an option of its own (`minv`, `gravity`, `nle`).
fn on_request() -> impl Iterator<Item = embedyn_codegen::Algorithm> {
    embedyn_codegen::Algorithm::generated(embedyn_codegen::algorithm::WhenGenerated::OnRequest)
}

impl Parse for Args {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let path: LitStr = input.parse()?;
        let mut args = Args {
            path,
            floating: false,
            requested: Vec::new(),
            f64: true,
            f32: true,
            krate: None,
            only: None,
            max_compile_memory: embedyn_codegen::DEFAULT_COMPILE_MEMORY_MB,
            lanes: 0,
            avx_twins: embedyn_codegen::AvxTwins::Large,
            gravity: None,
            locks: Vec::new(),
            rotors: embedyn_codegen::Rotors::Exact,
            links: embedyn_codegen::LinkOptions::default(),
        };
        // Options that set one value may appear once: a second `lanes = 8` would silently win over the
        // first (lists such as `lock(…)`, `wrenches(…)` and function names accumulate instead).
        let mut seen: Vec<String> = Vec::new();
        let mut once = |key: &str, span: proc_macro2::Span| -> syn::Result<()> {
            if seen.iter().any(|k| k == key) {
                return Err(syn::Error::new(
                    span,
                    format!("option `{key}` given twice (give it once)"),
                ));
            }
            seen.push(key.to_string());
            Ok(())
        };
        while !input.is_empty() {
            input.parse::<Token![,]>()?;
            if input.is_empty() {
                break;
            }
            if input.peek(Token![crate]) {
                once("crate", input.span())?;
                input.parse::<Token![crate]>()?;
                input.parse::<Token![=]>()?;
                args.krate = Some(input.parse()?);
                continue;
            }
            let key: Ident = input.parse()?;
            let single = [
                "floating",
                "f64_only",
                "f32_only",
                "reference",
                "rotors",
                "max_compile_memory",
                "lanes",
                "avx_twins",
            ];
            let name = key.to_string();
            if single.contains(&name.as_str()) || (name == "gravity" && input.peek(Token![=])) {
                once(&name, key.span())?;
            }
            match name.as_str() {
                "floating" => args.floating = true,
                "avx_twins" => {
                    const VALUES: &str =
                        "avx_twins = none|large|all (which f64 functions and 256-bit lane functions get an AVX copy; default large)";
                    if !input.peek(Token![=]) {
                        return Err(syn::Error::new(key.span(), VALUES));
                    }
                    input.parse::<Token![=]>()?;
                    let value = input
                        .parse::<Ident>()
                        .map_err(|e| syn::Error::new(e.span(), VALUES))?;
                    args.avx_twins = embedyn_codegen::AvxTwins::from_name(&value.to_string())
                        .ok_or_else(|| {
                            syn::Error::new(
                                value.span(),
                                format!("unknown value `{value}`: {VALUES}"),
                            )
                        })?;
                }
                // (`gravity` alone asks for the function, `gravity = [x, y, z]` sets the vector.)
                name if on_request().any(|a| a.name() == name) && !input.peek(Token![=]) => args
                    .requested
                    .extend(on_request().filter(|a| a.name() == name)),
                "f64_only" | "f32_only" if !(args.f64 && args.f32) => {
                    return Err(syn::Error::new(
                        key.span(),
                        "`f64_only` and `f32_only` together leave no scalar module: give one of them (or neither, for both)",
                    ));
                }
                "f64_only" => args.f32 = false,
                "f32_only" => args.f64 = false,
                "gravity" => {
                    input.parse::<Token![=]>()?;
                    args.gravity = Some(parse_gravity(input)?);
                }
                "lock" => args.locks.extend(parse_locks(input)?),
                "wrenches" => args.links.wrenches.extend(parse_names(input)?),
                "frames" => args.links.frames.extend(parse_names(input)?),
                "reference" => {
                    input.parse::<Token![=]>()?;
                    let choice: Ident = input.parse()?;
                    args.links.reference = embedyn_codegen::Reference::from_name(
                        &choice.to_string(),
                    )
                    .ok_or_else(|| {
                        syn::Error::new(
                            choice.span(),
                            "reference = local, reference = local_world_aligned or reference = world",
                        )
                    })?;
                }
                "rotors" => {
                    input.parse::<Token![=]>()?;
                    let choice: Ident = input.parse()?;
                    args.rotors =
                        embedyn_codegen::Rotors::parse(&choice.to_string()).ok_or_else(|| {
                            syn::Error::new(choice.span(), "rotors = exact or rotors = reflected")
                        })?;
                }
                "max_compile_memory" => {
                    input.parse::<Token![=]>()?;
                    args.max_compile_memory = input.parse::<syn::LitInt>()?.base10_parse()?;
                }
                "lanes" => {
                    input.parse::<Token![=]>()?;
                    let n: syn::LitInt = input.parse()?;
                    args.lanes = n.base10_parse()?;
                    if args.lanes == 0 {
                        return Err(syn::Error::new(
                            n.span(),
                            "lanes = N: 2 or 4 for f64, 4 or 8 for f32",
                        ));
                    }
                }
                "only" => {
                    let content;
                    syn::parenthesized!(content in input);
                    let names = content.parse_terminated(Ident::parse, Token![,])?;
                    if names.is_empty() {
                        return Err(syn::Error::new(
                            key.span(),
                            "only(…) names no function: list the functions to generate, e.g. only(aba, rnea)",
                        ));
                    }
                    let list = names
                        .iter()
                        .map(|name| {
                            embedyn_codegen::Algorithm::from_name(&name.to_string())
                                .map_err(|e| syn::Error::new(name.span(), e))
                        })
                        .collect::<syn::Result<Vec<_>>>()?;
                    // Repeated `only(…)` lists add up, as repeated `--only` does on the command line.
                    args.only.get_or_insert_with(Vec::new).extend(list);
                }
                // `minv = 3`: a function's name with a value.
                name if on_request().any(|a| a.name() == name) => {
                    return Err(syn::Error::new(
                        key.span(),
                        format!("`{name}` asks for the function of that name and takes no value: write `{name}` alone"),
                    ));
                }
                other => {
                    let requested: Vec<&str> = on_request().map(|a| a.name()).collect();
                    return Err(syn::Error::new(
                        key.span(),
                        format!(
                            "unknown option `{other}` (expected floating, {}, f64_only, f32_only, only(…), gravity = [x, y, z], lock(joint = value, …), rotors = exact|reflected, wrenches(link, …), frames(link, …), reference = local|local_world_aligned|world, max_compile_memory = MB, lanes = N, avx_twins = none|large|all or crate = path)",
                            requested.join(", ")
                        ),
                    ));
                }
            }
        }
        Ok(args)
    }
}

/// Generates straight-line dynamics for a URDF/URDF+ model at compile time.
///
/// The path is relative to the calling crate's `Cargo.toml` (or to `$EMBEDYN_MODEL_DIR` when set). Expands to `NQ`, `NV`, `JOINTS`,
/// `INDEPENDENT`, `FRAMES` and modules `f64`/`f32` with `kinematics`, `aba`, `rnea`, `crba` (and `minv`, `gravity`,
/// `nle` each with the option of its name; `only(aba, crba, …)` generates exactly the functions named, nothing else;
/// `f64_only`/`f32_only` one scalar module). Code that rustc is estimated to need more than 2 GB of
/// memory to compile is a compile error naming the estimate and what shrinks it (fewer functions, one
/// scalar type); `max_compile_memory = 4096` raises the limit (MB).
/// Invoke it inside a module of its own (`mod arm { embedyn::robot!("arm.urdf"); }`): the modules are
/// named after the scalar types. Errors in the model are compile errors that name the element.
#[proc_macro]
pub fn robot(input: TokenStream) -> TokenStream {
    let args = syn::parse_macro_input!(input as Args);
    match expand(&args) {
        Ok(ts) => ts.into(),
        Err(e) => syn::Error::new(args.path.span(), e)
            .to_compile_error()
            .into(),
    }
}

/// Why `robot!` cannot expand: a compile error at the model path.
#[derive(Debug, thiserror::Error)]
enum ExpandError {
    /// The model file cannot be read.
    #[error("embedyn: cannot read the model file `{given}`{}: {error}", looked_in(.given, .full, .base))]
    Unreadable {
        /// The path as the user wrote it.
        given: String,
        /// The path read.
        full: std::path::PathBuf,
        /// What a relative path is relative to.
        base: Base,
        #[source]
        error: embedyn_codegen::ReadError,
    },
    /// The model cannot be loaded or its code generated.
    #[error("embedyn: {0}")]
    Load(#[from] embedyn_codegen::LoadError),
}

/// What a relative model path is relative to (named when the file cannot be read, so that a user who
/// wrote `models/arm7.urdf` sees which folder it was looked for in).
#[derive(Debug, Clone, Copy)]
enum Base {
    /// `$EMBEDYN_MODEL_DIR`.
    ModelDir,
    /// The calling crate's manifest folder (`$CARGO_MANIFEST_DIR`).
    ManifestDir,
    /// The current folder (neither variable set).
    Current,
}

/// ` (looked for `/abs/models/arm7.urdf`: relative paths are from the crate's manifest folder)`, or
/// nothing for an absolute path.
fn looked_in(given: &str, full: &std::path::Path, base: &Base) -> String {
    if std::path::Path::new(given).is_absolute() {
        return String::new();
    }
    let from = match base {
        Base::ModelDir => "EMBEDYN_MODEL_DIR, which is set",
        Base::ManifestDir => "the calling crate's manifest folder, or EMBEDYN_MODEL_DIR when set",
        Base::Current => {
            "the current folder (neither CARGO_MANIFEST_DIR nor EMBEDYN_MODEL_DIR is set)"
        }
    };
    format!(
        " (looked for `{}`: relative paths are from {from})",
        embedyn_codegen::Printable(&full.to_string_lossy())
    )
}

fn expand(args: &Args) -> Result<proc_macro2::TokenStream, ExpandError> {
    let given = args.path.value();
    // Relative paths resolve against `EMBEDYN_MODEL_DIR` when set (build systems that compile outside the
    // crate's folder, UI tests), else against the calling crate's manifest folder.
    let (base_dir, base) = match std::env::var("EMBEDYN_MODEL_DIR") {
        Ok(dir) => (dir, Base::ModelDir),
        Err(_) => match std::env::var("CARGO_MANIFEST_DIR") {
            Ok(dir) => (dir, Base::ManifestDir),
            Err(_) => (".".into(), Base::Current),
        },
    };
    let full = std::path::Path::new(&base_dir).join(&given);
    let text = embedyn_codegen::bounded_read::read_model_file(&full).map_err(|error| {
        ExpandError::Unreadable {
            given: given.clone(),
            full: full.clone(),
            base,
            error,
        }
    })?;
    // Messages name the file as the user wrote it, not the absolute path.
    let loaded = embedyn_codegen::parse_urdf(&text, given.as_ref())?;
    let krate = args
        .krate
        .clone()
        .map_or_else(|| quote!(::embedyn), |p| quote!(#p));
    let options = embedyn_codegen::GenerateOptions {
        model: embedyn_codegen::ModelOptions {
            floating: args.floating,
            gravity: args
                .gravity
                .unwrap_or(embedyn_codegen::ModelOptions::default().gravity),
            locks: args.locks.clone(),
            rotors: args.rotors,
        },
        f64: args.f64,
        f32: args.f32,
        helpers: quote!(#krate::codegen_support),
        max_compile_memory_mb: Some(args.max_compile_memory),
        links: args.links.clone(),
        lanes: args.lanes,
        avx_twins: args.avx_twins,
        ..Default::default()
    }
    .with_requested(args.only.clone(), &args.requested);
    let items = embedyn_codegen::generate_tokens(&loaded, &options)?;
    let abs = full
        .canonicalize()
        .unwrap_or(full)
        .to_string_lossy()
        .into_owned();
    Ok(quote! {
        // Rebuilds when the model file changes.
        const _: &[u8] = include_bytes!(#abs);
        #items
    })
}

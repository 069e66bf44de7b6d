//! AVX twins: a large function's code compiled a second time with AVX enabled, in a module of its own,
//! and its public functions calling that copy where the CPU has AVX.
//!
//! Why: on x86-64 the baseline target is SSE2, whose arithmetic instructions overwrite one of their two
//! operands, so every value the code reads twice costs a register copy first; long unrolled functions
//! are made of such values. The same code compiled with AVX (three-operand encoding) needs none of those
//! copies: the floating TALOS's `aba` took 0.53× the time, its `rnea` 0.85×, the floating ANYmal B's
//! `aba_derivatives` 0.66× (2026-12-03, docs/generated-code.md). Only AVX is enabled, not FMA: the AVX
//! copy performs the same IEEE operations in the same order, so both copies give the same bits (but for
//! the sign and payload of a NaN: x86 passes on the first operand's NaN, and the two copies may order a
//! commutative operation's operands differently), and a user need not know which one ran.
//!
//! The choice is made at run time (`helpers::dispatch::avx()`: `cpuid` once, then one atomic load), so
//! the generated crate still runs on any x86-64 CPU and needs no build flag; a build that enables AVX
//! itself (`-C target-cpu=native`) compiles the twin out. Other architectures never see it. The twin's
//! functions that call no other share their bodies with the baseline code (src/shared_bodies.rs), so
//! rustc checks them once, but LLVM still optimizes them twice: the twin costs compile time, so functions
//! of at least `TWIN_MIN_STATEMENTS`
//! statements get one, and smaller ones only under a budget shared by the module
//! (`TWIN_BUDGET_STATEMENTS`, smallest first): their gain depends on the CPU (nil for the Z1's `aba`,
//! 1.8k operations, on one Xeon; 0.67× the time for the floating ANYmal B's, 2.3k, on an AMD EPYC).
//!
//! A lane module of 256-bit values gives its functions two twins (`TwinOf::Lanes`, [`AVX512`] then
//! [`AVX`]): the one compiled with AVX-512 F and VL runs where the CPU has them, the AVX one elsewhere.
//! So do a wide tree's smallest twinned scalar functions (`AVX512_MIN_NV`), whose AVX twins still spill
//! for want of registers.

use crate::emit::Code;
use proc_macro2::TokenStream;
use quote::{format_ident, quote};

/// Statements (a pair's operation counting once, [`crate::emit::Emitted::statements`]) from which a
/// function gets an AVX twin. Measured with and without AVX (2026-12-03, baseline x86-64 against
/// `-C target-feature=+avx`, one binary each): the Z1's `aba` (1,757 operations) and `rnea` the same
/// time; the floating ANYmal B's `crba` 0.85×, `rnea` 0.91×, `aba` 0.97–1.0×; the Z1's
/// `aba_derivatives` (11k) 0.78×; the floating G1's and TALOS's `aba` (6k) 0.53–0.56×.
pub const TWIN_MIN_STATEMENTS: usize = 4_000;

/// Statements up to which a function gets an AVX twin: beyond, the twin's compile time outweighs it
/// (the floating TALOS's `aba_derivatives`, 135k statements, takes 10 s to compile alone; issue 12's
/// target for the humanoid's derivatives is 20 s), and a chain of a thousand bodies would double the
/// compiler's memory, already near the default limit.
pub const TWIN_MAX_STATEMENTS: usize = 25_000;

/// Statements of the twins a module's functions below `TWIN_MIN_STATEMENTS` may share under
/// `AvxTwins::Large` ([`AvxTwins::small_twins`]): such functions gain from a twin too (2026-12-04, an AMD
/// EPYC host, the same code with and without its twin in one binary: the floating ANYmal B's `aba`, 2.3k
/// statements, 0.67× the time, `rnea` 0.78×, `crba` 0.80×; the Z1's `aba` 0.94×, `crba` 0.88×; the
/// floating G1's `crba` 0.82× and `rnea` 0.76×), but each twin costs compile time. A robot with a few
/// thousand statements per function gets every function twinned at about a second's compile time; a
/// humanoid, beside its twinned 6.3k `aba`, its default `kinematics` (0.7k–0.8k), `crba` (2.2k–2.4k) and
/// `rnea` (3.4k–3.8k), 12.9k–13.2k in all, and its five dynamics functions (`aba`, `rnea`, `crba`,
/// `gravity`, `nle`: those `embedyn bench` times) too. The budget was 10,000 (no `rnea`) until a rerun
/// measured the humanoids' `rnea` twin at 0.73–0.75× the time (TALOS 1,153 → 840 ns, G1 854 → 637) for
/// 0.6–1.6 s of rustc's time: default crates, three interleaved rounds on 2 cores (2026-12-04, AMD EPYC),
/// G1 6.3–6.6 → 7.1–7.7 s and TALOS 6.8–7.6 → 7.7–7.9 s, in a busier hour 6.8–7.1 → 7.8–8.5 s and
/// 7.5–7.7 → 8.0–8.3 s, within issue 13's 10 s (one earlier round of TALOS with this twin took 10.5 s).
/// At 14,000 a crate of the five functions twinned `nle` (smaller) and not `rnea`; at 17,000 all five,
/// TALOS's such crate then compiling in 9.4–11.2 s. Smallest first: the most functions the budget
/// holds (per statement the smallest paid the most: TALOS's `kinematics` 0.18 ns saved per statement,
/// `rnea` 0.08, `crba` 0.06).
pub const TWIN_BUDGET_STATEMENTS: usize = 17_000;

/// Statements from which a function below `TWIN_MIN_STATEMENTS` may get a twin under the budget: the
/// smallest measured gain was the Z1's `crba` (466 statements, 0.88× the time); below, a function of a few
/// operations (`integrate`, a frame function of a fixed link) would only add the dispatch's check, and take
/// budget that a larger function would use better (a new user's trial).
pub const TWIN_SMALL_MIN_STATEMENTS: usize = 400;

/// Degrees of freedom (`nv`) from which a model's twinned `f64` functions may also get an AVX-512 twin
/// ([`AvxTwins::avx512_twins`]). With AVX-512 F and VL the same scalar code has 32 vector registers
/// instead of 16: where a function keeps more values live than 16 registers hold, it spills half as much
/// (the floating G1's `crba` twin: 612 instructions touching the stack with AVX, 303 with AVX-512).
/// Measured (2026-12-04, an AMD EPYC of the Zen 4 kind, the AVX twin against the AVX-512 one in one
/// binary, two runs): the humanoids gained in every function, the floating G1 (nv = 35) `crba` 0.91–0.93×
/// the time, `kinematics` 0.89–0.90×, `rnea` 0.88×, `aba` 0.94×; TALOS (nv = 44) `crba` 0.87–0.91×,
/// `kinematics` 0.92×, `aba` 0.92×, `rnea` 0.95–0.96×; the floating ANYmal B (nv = 18) lost: `crba`
/// 1.18–1.19×, `rnea` 1.10×, `kinematics` 1.05×, `aba` 1.0×. A small function pays for what LLVM does
/// with 512-bit registers at its start (the batch of sines and cosines stored in 512-bit pieces, then
/// read one by one), and gains little from the registers.
pub const AVX512_MIN_NV: usize = 24;

/// Statements of the AVX-512 twins a module may have under `AvxTwins::Large`, smallest function first
/// ([`AvxTwins::avx512_twins`]): each is one more copy to compile. A humanoid's `kinematics` and `crba`
/// (0.7k–0.8k and 2.2k–2.4k statements) fit; its `rnea` and `aba` (3.4k–3.8k, 6.3k–6.4k: less gain per
/// statement, 0.88–0.96×) do not.
pub const AVX512_TWIN_BUDGET_STATEMENTS: usize = 4_000;

/// Which generated functions get an AVX twin (macro `avx_twins = none|large|all`, `embedyn generate
/// --avx-twins none|large|all`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AvxTwins {
    /// None: one copy of every function, half the compile time of the large ones.
    None,
    /// The `f64` functions of `TWIN_MIN_STATEMENTS` to `TWIN_MAX_STATEMENTS` statements, and smaller
    /// ones, smallest first, while the module's twins total at most `TWIN_BUDGET_STATEMENTS` (the
    /// default; [`AvxTwins::small_twins`]).
    #[default]
    Large,
    /// Every `f64` function (each costs about twice its compile time more; the gain below
    /// `TWIN_MIN_STATEMENTS` was small or nil where measured), and in a model of `AVX512_MIN_NV` or
    /// more degrees of freedom an AVX-512 twin of each besides.
    All,
}

impl AvxTwins {
    /// The option's value by name (`none`, `large`, `all`).
    pub fn from_name(name: &str) -> Option<AvxTwins> {
        match name {
            "none" => Some(AvxTwins::None),
            "large" => Some(AvxTwins::Large),
            "all" => Some(AvxTwins::All),
            _ => None,
        }
    }

    /// Whether a function of `statements` statements gets a twin.
    pub fn twins(self, statements: usize) -> bool {
        match self {
            AvxTwins::None => false,
            AvxTwins::Large => (TWIN_MIN_STATEMENTS..=TWIN_MAX_STATEMENTS).contains(&statements),
            AvxTwins::All => true,
        }
    }

    /// The functions below `TWIN_MIN_STATEMENTS` that also get a twin (`Large` only), by index: given
    /// every f64 function's `statements` and whether it has a twin by [`AvxTwins::twins`], the others
    /// smallest first, while the module's twins (the large ones included) stay within
    /// `TWIN_BUDGET_STATEMENTS`: as many functions as the budget holds.
    pub fn small_twins(self, statements: &[usize], twinned: &[bool]) -> Vec<usize> {
        if self != AvxTwins::Large {
            return Vec::new();
        }
        let mut total: usize = statements
            .iter()
            .zip(twinned)
            .filter(|(_, &t)| t)
            .map(|(&s, _)| s)
            .sum();
        let candidates: Vec<usize> = (0..statements.len())
            .filter(|&k| {
                !twinned[k]
                    && (TWIN_SMALL_MIN_STATEMENTS..TWIN_MIN_STATEMENTS).contains(&statements[k])
            })
            .collect();
        smallest_first_within(candidates, statements, &mut total, TWIN_BUDGET_STATEMENTS)
    }

    /// The twinned `f64` functions (`twinned`, by index, of `statements` statements each) that also get
    /// an AVX-512 twin in a model of `nv` degrees of freedom: none below `AVX512_MIN_NV` (there they
    /// ran slower than the AVX twin: an attacker's trial of `all` on the floating ANYmal B, `crba`
    /// 1.18–1.20×); from it, under `Large` the smallest first while they total at most
    /// `AVX512_TWIN_BUDGET_STATEMENTS`, under `All` every twinned one.
    pub fn avx512_twins(self, nv: usize, statements: &[usize], twinned: &[bool]) -> Vec<usize> {
        let candidates = (0..statements.len()).filter(|&k| twinned[k]);
        match self {
            AvxTwins::None => Vec::new(),
            _ if nv < AVX512_MIN_NV => Vec::new(),
            AvxTwins::All => candidates.collect(),
            AvxTwins::Large => smallest_first_within(
                candidates.collect(),
                statements,
                &mut 0,
                AVX512_TWIN_BUDGET_STATEMENTS,
            ),
        }
    }

    /// Whether a lane function of `statements` statements gets a twin in a lane module of 256-bit values
    /// (`lanes_of_256_bits`). There the twin computes a lane value in one AVX instruction where the
    /// baseline code takes two SSE2 ones, a gain at any size (2026-12-03, 4 f64 lanes, ns per state, the
    /// same bits: the Z1's `aba` 108 against 147; the floating ANYmal B's `aba` 251 against 824, `rnea`
    /// 168 against 494, `crba` 99 against 131), so `Large` twins every lane function up to
    /// `TWIN_MAX_STATEMENTS`.
    pub fn twins_lanes(self, statements: usize) -> bool {
        match self {
            AvxTwins::None => false,
            AvxTwins::Large => statements <= TWIN_MAX_STATEMENTS,
            AvxTwins::All => true,
        }
    }
}

/// Of the `candidates` (indices into `statements`), as many as fit a budget: smallest first (equal sizes
/// in the module's order), each taken while `total` plus its statements stays within `budget`; in the
/// module's order.
fn smallest_first_within(
    mut candidates: Vec<usize>,
    statements: &[usize],
    total: &mut usize,
    budget: usize,
) -> Vec<usize> {
    candidates.sort_by_key(|&k| (statements[k], k));
    let mut chosen = Vec::new();
    for k in candidates {
        if *total + statements[k] <= budget {
            *total += statements[k];
            chosen.push(k);
        }
    }
    chosen.sort_unstable();
    chosen
}

/// Whether the lane module of `lanes` lanes of `scalar` holds 256-bit values (`F64x4`, `F32x8`), which
/// its functions' AVX twins compute in one instruction each (`TwinOf::Lanes`). The 128-bit ones (`F64x2`,
/// `F32x4`) are two numbers per SSE2 instruction already: a twin would only re-encode them, as it does
/// scalar code, which paid only in large functions.
pub fn lanes_of_256_bits(scalar: &str, lanes: usize) -> bool {
    avx_lane_type(scalar, lanes).is_some()
}

/// The AVX twins' lane type of the lane module of `lanes` lanes of `scalar`, if it holds 256-bit values
/// (runtime/src/codegen_lanes.rs).
pub fn avx_lane_type(scalar: &str, lanes: usize) -> Option<&'static str> {
    match (scalar, lanes) {
        ("f64", 4) => Some("AvxF64x4"),
        ("f32", 8) => Some("AvxF32x8"),
        _ => None,
    }
}

/// What a twin copies: a scalar module's function, or a lane module's.
#[derive(Clone, Copy, Debug)]
pub enum TwinOf<'a> {
    /// A function of a scalar module: the twin is the same code compiled with AVX, and where `avx512`
    /// a second one compiled with AVX-512 F and VL, which runs first where the CPU has them
    /// ([`AvxTwins::avx512_twins`]).
    Scalar { avx512: bool },
    /// A function of a lane module of 256-bit values: the twins are the same code over `avx_type`
    /// (`AvxF64x4`: the lane type's layout, AVX instructions), one compiled with AVX-512 (F and VL) and
    /// one with AVX; the public functions hand their arguments and results over with `dispatch::recast`.
    /// `wide`'s lane types pick their instructions when the crate is compiled, so the same code over them
    /// kept two SSE2 halves per value.
    Lanes { avx_type: &'a str },
}

/// An instruction-set level a twin is compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Level {
    /// The twin module's suffix (`aba_avx`, `aba_avx512`), also the name of the `helpers::dispatch`
    /// function that says whether the CPU has the level.
    pub name: &'static str,
    /// The `target_feature` list every function of the twin is compiled with.
    pub features: &'static str,
}

/// AVX: three-operand encoding, 256-bit values, 16 vector registers.
pub const AVX: Level = Level {
    name: "avx",
    features: "avx",
};

/// AVX-512 F and VL: the same 256-bit instructions with 32 vector registers, which long lane functions
/// use to spill less. Measured (2026-12-03, 4 f64 lanes, one binary each, ns per call of 4 states): the
/// Z1's `aba` 313 with AVX, 258 with AVX-512; `rnea` 178 against 164, `crba` 117 against 109; the floating
/// ANYmal B's `aba` 843 against 826, `crba` 340 against 298. Neither the scalar functions (the same time)
/// nor AVX2 and FMA (the ANYmal B's `rnea` 1.1× slower, the Z1's `aba` between the two) paid as well.
/// (The scalar functions on another host, an AMD EPYC of the Zen 4 kind, 2026-12-04: the floating G1's
/// twins compiled for AVX-512 F and VL instead of AVX took 0.90–0.92× the time, `crba` 546–554 → 489–499
/// ns, `aba` 1,218–1,227 → 1,120–1,126, `rnea` 597–608 → 548–553, two runs of one binary each. A
/// scalar function gets this twin beside its AVX one, for the CPUs with AVX but not AVX-512, only in a
/// wide tree and under a budget of its own, `AVX512_MIN_NV`, as each costs compile time.)
/// The lane values stay 256 bits wide, but LLVM is free to use 512-bit instructions where it finds
/// them (an attacker's trial found some, in array copies and the batch of sines and cosines): on CPUs
/// that lower their clock for those (Skylake-SP-class Xeons), `dispatch::use_avx512(false)` is the way
/// to compare.
pub const AVX512: Level = Level {
    name: "avx512",
    features: "avx512f,avx512vl",
};

impl TwinOf<'_> {
    /// The levels this function gets a twin for, the one to prefer first.
    pub fn levels(self) -> &'static [Level] {
        match self {
            TwinOf::Scalar { avx512: false } => &[AVX],
            TwinOf::Scalar { avx512: true } => &[AVX512, AVX],
            TwinOf::Lanes { .. } => &[AVX512, AVX],
        }
    }
}

/// The cfg predicate under which twins exist: an x86-64 build with SSE2 that does not enable AVX
/// itself. (Not a soft-float target such as `x86_64-unknown-none`, for kernels and firmware: its code
/// must not touch vector registers, and LLVM could not compile the lane twins' 256-bit values there.)
/// The runtime's helpers (runtime/src/codegen_support.rs, codegen_lanes.rs) repeat it in their own
/// `#[cfg]`s, where a constant cannot go.
const TWIN_CFG: &str =
    r#"all(target_arch = "x86_64", target_feature = "sse2", not(target_feature = "avx"))"#;

/// [`TWIN_CFG`] as an attribute.
fn twin_cfg() -> TokenStream {
    let predicate: TokenStream = TWIN_CFG.parse().expect("the twin cfg parses");
    quote!(#[cfg(#predicate)])
}

/// `code` (the items of function `function`: its public functions and part modules) with AVX twins:
/// the items as they are, each public function first calling a twin where the CPU has its level, and
/// the items again in module `{function}_{level}` per level (`aba_avx`), every function in it compiled
/// for that level. (The modules are in the type namespace, where the scalar module holds only the part
/// modules, `aba_parts_0`, and CamelCase types besides.)
pub fn with_avx_twin(code: &Code, function: &str, helpers: &TokenStream, of: TwinOf) -> Code {
    let twin = Twin {
        function,
        helpers,
        of,
    };
    // A scalar twin's leaves call the bodies the baseline code calls (src/shared_bodies.rs); a lane
    // twin's `S` is another type, so it is a copy.
    let shared = match of {
        TwinOf::Scalar { .. } => crate::shared_bodies::share(code, function),
        TwinOf::Lanes { .. } => None,
    };
    match shared {
        Some((calls, shared)) => match (code_with_twin(&calls, &twin), shared) {
            (Code::Tokens(mut out), Code::Tokens(shared)) => {
                out.extend(shared);
                Code::Tokens(out)
            }
            (Code::Text(mut out), Code::Text(shared)) => {
                out.push_str(&shared);
                Code::Text(out)
            }
            _ => unreachable!("the shared module is written in the code's own form"),
        },
        None => code_with_twin(code, &twin),
    }
}

/// `code` as it is with its twins, in the same form.
fn code_with_twin(code: &Code, twin: &Twin) -> Code {
    match code {
        Code::Tokens(tokens) => Code::Tokens(tokens_with_twin(tokens.clone(), twin)),
        Code::Text(text) => Code::Text(text_with_twin(text, twin)),
    }
}

/// How a function's code gets its twins.
struct Twin<'a> {
    /// The function's name (its twin modules are `{function}_{level}`).
    function: &'a str,
    /// The helper module's path.
    helpers: &'a TokenStream,
    /// What the twins copy.
    of: TwinOf<'a>,
}

impl Twin<'_> {
    /// Whether arguments and results are handed over with `dispatch::recast` (a lane twin's `S` differs).
    fn recast(&self) -> bool {
        matches!(self.of, TwinOf::Lanes { .. })
    }

    /// The levels, the one to prefer first.
    fn levels(&self) -> &'static [Level] {
        self.of.levels()
    }

    /// The twin module of `level`.
    fn module(&self, level: Level) -> String {
        format!("{}_{}", self.function, level.name)
    }

    /// The items of a twin's module besides the copy, shadowing the enclosing module's names.
    fn items(&self) -> TokenStream {
        twin_items(self.of, self.helpers)
    }
}

/// The items of a twin's module besides the copy. A lane twin's `S` is the AVX lane type, and its batch
/// forms (`aba_batch`) go through the lanes: the lane module's own constant of that name sends a batch of
/// 4 f64 lanes of a paired function through the scalar function state by state when the crate is built
/// without AVX (lane_module in generate.rs), since then an `F64x4` is two SSE2 registers, as full as the
/// paired scalar code's one; in the twin it is one register.
fn twin_items(of: TwinOf, helpers: &TokenStream) -> TokenStream {
    match of {
        TwinOf::Scalar { .. } => quote!(),
        TwinOf::Lanes { avx_type } => {
            let avx_type = format_ident!("{}", avx_type);
            quote! {
                /// The lane type with AVX instructions (this module runs where the CPU has AVX).
                pub type S = #helpers::#avx_type;
                /// Batches through the lanes (see the module's lane type).
                const PAIRED_BATCH_PER_STATE: bool = false;
            }
        }
    }
}

/// The statements a public function starts with: per level, the best first, `return` its twin's
/// result where the CPU has that level.
fn dispatch_statement(signature: &syn::Signature, twin: &Twin) -> TokenStream {
    let helpers = twin.helpers;
    let name = &signature.ident;
    let arguments: Vec<TokenStream> = signature
        .inputs
        .iter()
        .map(|input| match input {
            syn::FnArg::Typed(typed) => {
                let pattern = &typed.pat;
                if twin.recast() {
                    quote!(#helpers::dispatch::recast(#pattern))
                } else {
                    quote!(#pattern)
                }
            }
            syn::FnArg::Receiver(_) => unreachable!("generated functions are free functions"),
        })
        .collect();
    let cfg = twin_cfg();
    let statements = twin.levels().iter().map(|&level| {
        let module = format_ident!("{}", twin.module(level));
        let has = format_ident!("{}", level.name);
        let call = quote!(#module::#name(#(#arguments),*));
        let call = if twin.recast() {
            quote!(#helpers::dispatch::recast(#call))
        } else {
            call
        };
        quote! {
            #cfg
            if #helpers::dispatch::#has() {
                // SAFETY (not in the output: `quote` drops comments): the CPU has the level, the one
                // requirement of the twin; a lane twin's type has the layout of the lane module's
                // (`recast`).
                return unsafe { #call };
            }
        }
    });
    quote!(#(#statements)*)
}

/// The attribute every function of `level`'s twin carries.
fn level_attribute(level: Level) -> syn::Attribute {
    let features = level.features;
    syn::parse_quote!(#[target_feature(enable = #features)])
}

/// Adds `attribute` to every function among `items`, in nested modules too.
fn add_to_functions(items: &mut [syn::Item], attribute: &syn::Attribute) {
    for item in items {
        match item {
            syn::Item::Fn(function) => function.attrs.push(attribute.clone()),
            syn::Item::Mod(module) => {
                if let Some((_, inner)) = &mut module.content {
                    add_to_functions(inner, attribute);
                }
            }
            _ => {}
        }
    }
}

fn tokens_with_twin(tokens: TokenStream, twin: &Twin) -> TokenStream {
    let file: syn::File = syn::parse2(tokens).expect("generated code parses as items");
    let cfg = twin_cfg();
    let twin_items = twin.items();
    let modules: Vec<TokenStream> = twin
        .levels()
        .iter()
        .map(|&level| {
            let mut copy = file.items.clone();
            add_to_functions(&mut copy, &level_attribute(level));
            let module = format_ident!("{}", twin.module(level));
            let doc = format!(
                " The functions above compiled for `{}` (see `helpers::dispatch`).",
                level.features
            );
            quote! {
                #cfg
                #[doc = #doc]
                mod #module {
                    #[allow(unused_imports)]
                    use super::*;
                    #twin_items
                    #(#copy)*
                }
            }
        })
        .collect();
    let mut items = file.items;
    for item in &mut items {
        if let syn::Item::Fn(function) = item {
            if matches!(function.vis, syn::Visibility::Public(_)) {
                let statement = dispatch_statement(&function.sig, twin);
                let block: syn::Block =
                    syn::parse2(quote!({ #statement })).expect("the dispatch statements parse");
                function.block.stmts.splice(0..0, block.stmts);
            }
        }
    }
    quote! {
        #(#items)*
        #(#modules)*
    }
}

/// Whether a trimmed line starts a function item (`fn`, `pub fn`, `pub(super) fn`): the emitters write
/// no other line that way (bodies are `let` statements and assignments, docs start with `///`).
pub(crate) fn starts_function(trimmed: &str) -> bool {
    ["fn ", "pub fn ", "pub(super) fn ", "pub(crate) fn "]
        .iter()
        .any(|p| trimmed.starts_with(p))
}

/// The same for text written by [`crate::emit_large`] (items indented by four spaces, each function's
/// signature ending on the first line at its indentation that ends with `{`).
fn text_with_twin(text: &str, twin_spec: &Twin) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let mut portable = String::with_capacity(text.len() + 1024);
    // The twin's text cut where a function starts: each piece is followed by that function's
    // attribute at the indentation given (the last piece by none), the same for every level.
    let mut pieces: Vec<(String, String)> = Vec::new();
    let mut twin = String::with_capacity(text.len() + 65_536);
    let twin_items = twin_spec.items();
    if !twin_items.is_empty() {
        let items = crate::generate::format_tokens(&twin_items).expect("the twin's items format");
        for l in items.lines() {
            // Indented as the twin's other items (two levels: lane module, twin module).
            push_line(
                &mut twin,
                &if l.is_empty() {
                    String::new()
                } else {
                    format!("    {l}")
                },
            );
        }
    }
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let trimmed = line.trim_start();
        let indent = &line[..line.len() - trimmed.len()];
        if starts_function(trimmed) {
            pieces.push((std::mem::take(&mut twin), format!("    {indent}")));
        }
        if trimmed.starts_with("pub fn ") && indent.len() == 4 {
            // A public function: its whole signature, then the dispatch as its first statements.
            let start = i;
            while !(lines[i].starts_with("    ") && lines[i].trim_end().ends_with('{')) {
                i += 1;
            }
            let mut signature = String::new();
            for l in &lines[start..=i] {
                portable.push_str(l);
                portable.push('\n');
                push_line(&mut twin, l);
                signature.push_str(l.trim());
                signature.push(' ');
            }
            // The signature without `pub` and the opening brace.
            let signature = signature.trim_end().trim_end_matches('{');
            let signature = signature.strip_prefix("pub ").unwrap_or(signature);
            let signature: syn::Signature =
                syn::parse_str(signature).expect("a generated signature parses");
            let statement = dispatch_statement(&signature, twin_spec);
            let wrapped = crate::generate::format_tokens(&quote!(fn f() { #statement }))
                .expect("the dispatch statement formats");
            // The body of the formatted `fn f() { … }`, indented once more for the function's body.
            for l in wrapped.lines().filter(|l| l.starts_with("    ")) {
                portable.push_str("    ");
                portable.push_str(l);
                portable.push('\n');
            }
            i += 1;
            continue;
        }
        portable.push_str(line);
        portable.push('\n');
        push_line(&mut twin, line);
        i += 1;
    }
    let mut out = portable;
    for &level in twin_spec.levels() {
        let module = twin_spec.module(level);
        let features = level.features;
        out.push_str(&format!(
            "    #[cfg({TWIN_CFG})]\n    /// The functions above compiled for `{features}` (see `helpers::dispatch`).\n    mod {module} {{\n        #[allow(unused_imports)]\n        use super::*;\n"
        ));
        for (piece, indent) in &pieces {
            out.push_str(piece);
            out.push_str(&format!(
                "{indent}#[target_feature(enable = \"{features}\")]\n"
            ));
        }
        out.push_str(&twin);
        out.push_str("    }\n");
    }
    out
}

/// A line of the twin, indented once more (it sits in the twin's module).
fn push_line(twin: &mut String, line: &str) {
    if !line.is_empty() {
        twin.push_str("    ");
    }
    twin.push_str(line);
    twin.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;

    fn helpers() -> TokenStream {
        quote!(crate::helpers)
    }

    /// Below `TWIN_MIN_STATEMENTS`, twins go to the smallest functions first while the module's twins
    /// (the large ones counted) fit the budget; only `Large` gives them.
    #[test]
    fn small_functions_share_a_budget_of_twins_smallest_first() {
        assert_eq!(TWIN_BUDGET_STATEMENTS, 17_000);
        // A quadruped with 400, 2.3k, 1.3k and 600 statements: all of them.
        let quadruped = [400, 2_300, 1_300, 600];
        assert_eq!(
            AvxTwins::Large.small_twins(&quadruped, &[false; 4]),
            vec![0, 1, 2, 3]
        );
        assert!(AvxTwins::None
            .small_twins(&quadruped, &[false; 4])
            .is_empty());
        assert!(AvxTwins::All
            .small_twins(&quadruped, &[false; 4])
            .is_empty());
        // A humanoid: beside a twinned `aba` of 6.3k, `kinematics` (800), `crba` (2.4k), a function of 3k
        // and `rnea` (3.4k) fit (15.9k); a sixth of 3.9k no longer does.
        let humanoid = [800, 6_300, 3_400, 2_400, 3_000, 3_900];
        assert_eq!(
            AvxTwins::Large.small_twins(&humanoid, &[false, true, false, false, false, false]),
            vec![0, 2, 3, 4]
        );
        // Equal sizes in the module's order: of four 3.9k functions after 500 and 3k, the first three fit.
        assert_eq!(
            AvxTwins::Large.small_twins(&[3_900, 3_900, 3_900, 3_900, 3_000, 500], &[false; 6]),
            vec![0, 1, 2, 4, 5]
        );
        // Below `TWIN_SMALL_MIN_STATEMENTS` (a few operations: `integrate`, a fixed link's frame), none.
        assert_eq!(TWIN_SMALL_MIN_STATEMENTS, 400);
        assert_eq!(
            AvxTwins::Large.small_twins(&[7, 0, 399, 400, 1_000], &[false; 5]),
            vec![3, 4]
        );
        // A large function alone over the budget leaves nothing; one twinned by size is not chosen again.
        assert!(AvxTwins::Large
            .small_twins(&[TWIN_BUDGET_STATEMENTS + 1, 500], &[true, false])
            .is_empty());
        assert_eq!(
            AvxTwins::Large.small_twins(&[TWIN_MIN_STATEMENTS + 1, 500], &[true, false]),
            vec![1]
        );
    }

    /// AVX-512 twins: none below `AVX512_MIN_NV` (`All` included) or under `None`; from it, among the
    /// twinned functions only, smallest first within the budget (a humanoid's `kinematics` and `crba`,
    /// not its `rnea` and `aba`); every twinned one under `All`.
    #[test]
    fn avx512_twins_go_to_a_wide_trees_smallest_twinned_functions() {
        assert_eq!(AVX512_MIN_NV, 24);
        assert_eq!(AVX512_TWIN_BUDGET_STATEMENTS, 4_000);
        // The floating G1's default functions: kinematics, aba, rnea, crba.
        let g1 = [802, 6_328, 3_354, 2_369];
        let twinned = [true; 4];
        assert_eq!(AvxTwins::Large.avx512_twins(35, &g1, &twinned), vec![0, 3]);
        assert!(AvxTwins::Large.avx512_twins(23, &g1, &twinned).is_empty());
        assert!(AvxTwins::None.avx512_twins(35, &g1, &twinned).is_empty());
        assert_eq!(
            AvxTwins::All.avx512_twins(35, &g1, &twinned),
            vec![0, 1, 2, 3]
        );
        assert!(AvxTwins::All.avx512_twins(23, &g1, &twinned).is_empty());
        // Not twinned, not chosen, however small; equal sizes in the module's order.
        assert_eq!(
            AvxTwins::Large.avx512_twins(35, &g1, &[false, true, true, true]),
            vec![3]
        );
        assert_eq!(
            AvxTwins::Large.avx512_twins(30, &[2_000, 2_000, 2_000], &[true; 3]),
            vec![0, 1]
        );
        // A function over the budget alone leaves room for a smaller one after it.
        assert_eq!(
            AvxTwins::Large.avx512_twins(30, &[4_001, 3_000, 1_500], &[true; 3]),
            vec![2]
        );
    }

    /// A scalar function with an AVX-512 twin asks for it first, then for the AVX one, each module's
    /// functions carrying their level's attribute; the arguments pass as they are (no recast).
    #[test]
    fn a_scalar_function_can_get_an_avx512_twin_before_its_avx_one() {
        let code = quote! {
            pub fn f(q: &[S; 2], out: &mut [S; 1]) { out[0] = q[0]; }
        };
        let Code::Tokens(out) = with_avx_twin(
            &Code::Tokens(code),
            "f",
            &helpers(),
            TwinOf::Scalar { avx512: true },
        ) else {
            panic!("tokens stay tokens")
        };
        let text = crate::generate::format_tokens(&quote!(mod m { #out })).unwrap();
        let avx512 = text
            .find("if crate::helpers::dispatch::avx512() {")
            .expect(&text);
        let avx = text
            .find("if crate::helpers::dispatch::avx() {")
            .expect(&text);
        assert!(avx512 < avx, "{text}");
        assert!(
            text.contains("return unsafe { f_avx512::f(q, out) };"),
            "{text}"
        );
        assert!(
            text.contains("return unsafe { f_avx::f(q, out) };"),
            "{text}"
        );
        assert_eq!(
            text.matches("#[target_feature(enable = \"avx512f,avx512vl\")]")
                .count(),
            1,
            "{text}"
        );
        assert_eq!(
            text.matches("#[target_feature(enable = \"avx\")]").count(),
            1,
            "{text}"
        );
        assert!(!text.contains("recast"), "{text}");
    }

    #[test]
    fn tokens_get_a_dispatch_and_a_twin_with_avx_everywhere() {
        let code = quote! {
            mod f_parts_0 {
                use super::*;
                pub(super) fn f_part(q: &[S; 2], s: &mut [S; 1]) { s[0] = q[0]; }
            }
            use self::f_parts_0::f_part;
            pub fn f(q: &[S; 2], out: &mut [S; 1]) -> S { let mut s = [0.0; 1]; f_part(q, &mut s); out[0] = s[0]; s[0] }
        };
        let Code::Tokens(out) = with_avx_twin(
            &Code::Tokens(code),
            "f",
            &helpers(),
            TwinOf::Scalar { avx512: false },
        ) else {
            panic!("tokens stay tokens")
        };
        let text = crate::generate::format_tokens(&quote!(mod m { #out })).unwrap();
        assert_eq!(
            text.matches("#[target_feature(enable = \"avx\")]").count(),
            2,
            "{text}"
        );
        assert!(
            text.contains("if crate::helpers::dispatch::avx() {"),
            "{text}"
        );
        assert!(
            text.contains("return unsafe { f_avx::f(q, out) };"),
            "{text}"
        );
        assert_eq!(
            text.matches("dispatch::avx").count(),
            1,
            "the twin must not dispatch: {text}"
        );
        assert!(text.contains("mod f_avx {"), "{text}");
    }

    #[test]
    fn text_gets_a_dispatch_and_a_twin_with_avx_everywhere() {
        let text = "    mod g_parts_0 {\n        #[allow(unused_imports)]\n        use super::*;\n        #[inline(never)]\n        pub(super) fn g_part(q: &[S; 2], s: &mut [S; 1]) {\n            s[0] = q[0];\n        }\n    }\n    use self::g_parts_0::g_part;\n    /// Doc.\n    pub fn g(\n        q: &[S; 2],\n        out: &mut [[S; 1]; 1],\n    ) {\n        let mut s: [S; 1] = [0.0; 1];\n        g_part(q, &mut s);\n        out[0][0] = s[0];\n    }\n";
        let Code::Text(out) = with_avx_twin(
            &Code::Text(text.to_string()),
            "g",
            &helpers(),
            TwinOf::Scalar { avx512: false },
        ) else {
            panic!("text stays text")
        };
        assert_eq!(
            out.matches("#[target_feature(enable = \"avx\")]").count(),
            2,
            "{out}"
        );
        assert_eq!(out.matches("dispatch::avx()").count(), 1, "{out}");
        assert!(out.contains("return unsafe { g_avx::g(q, out) };"), "{out}");
        // Both copies parse as items.
        syn::parse_str::<syn::File>(&out).unwrap();
    }

    /// A lane function gets two twins, AVX-512 asked first, each with its level's attribute on every
    /// function and the AVX lane type as its `S`; the arguments and result are recast for each.
    #[test]
    fn lane_functions_get_an_avx512_twin_then_an_avx_one() {
        let text = "    mod h_parts_0 {\n        #[allow(unused_imports)]\n        use super::*;\n        #[inline(never)]\n        pub(super) fn h_part(q: &[S; 2], s: &mut [S; 1]) {\n            s[0] = q[0];\n        }\n    }\n    use self::h_parts_0::h_part;\n    /// Doc.\n    pub fn h(q: &[S; 2], out: &mut [S; 1]) {\n        h_part(q, out);\n    }\n";
        let of = TwinOf::Lanes {
            avx_type: "AvxF64x4",
        };
        let Code::Text(out) = with_avx_twin(&Code::Text(text.to_string()), "h", &helpers(), of)
        else {
            panic!("text stays text")
        };
        let tokens = quote! {
            pub fn h(q: &[S; 2], out: &mut [S; 1]) { out[0] = q[0]; }
        };
        let Code::Tokens(from_tokens) = with_avx_twin(&Code::Tokens(tokens), "h", &helpers(), of)
        else {
            panic!("tokens stay tokens")
        };
        let from_tokens = crate::generate::format_tokens(&from_tokens).unwrap();
        for (out, functions) in [(&out, 2), (&from_tokens, 1)] {
            syn::parse_str::<syn::File>(out).unwrap();
            let avx512 = out.find("if crate::helpers::dispatch::avx512() {").unwrap();
            let avx = out.find("if crate::helpers::dispatch::avx() {").unwrap();
            assert!(avx512 < avx, "{out}");
            // Arguments (2) and result recast for each twin.
            assert_eq!(out.matches("dispatch::recast(").count(), 2 * 3, "{out}");
            // The twins follow the portable code, AVX-512 first.
            let twin512 = out.find("mod h_avx512 {").unwrap();
            let twin = out.find("mod h_avx {").unwrap();
            assert!(avx < twin512 && twin512 < twin, "{out}");
            for (module, features) in [
                (&out[twin512..twin], "avx512f,avx512vl"),
                (&out[twin..], "avx"),
            ] {
                assert!(module.contains("pub type S = crate::helpers::AvxF64x4;"));
                let attribute = format!("#[target_feature(enable = \"{features}\")]");
                assert_eq!(module.matches(&attribute).count(), functions, "{module}");
                assert_eq!(module.matches("#[target_feature(").count(), functions);
                assert!(!module.contains("dispatch::"), "{module}");
            }
        }
    }
}

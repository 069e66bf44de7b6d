//! From a traced tape to Rust: liveness, chunking into small functions (rustc's optimizer is superlinear
//! in function size), and emission with `quote`; functions too long to schedule are written as text by
//! [`crate::emit_large`].

use crate::trace::{Op, Sym, Tape};
use crate::value_names::{body_list, part_names, Owners, ValueNames};
use crate::zero_stores::{self, ZeroWrites};
use proc_macro2::{Ident, Literal, TokenStream};
use quote::{format_ident, quote};
use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap, HashSet};

/// One argument of a generated function: `name: &[S; len]`, or with `columns` a matrix
/// `name: &[[S; columns]; len]` whose entries are numbered row-major.
pub struct Arg {
    pub name: &'static str,
    pub len: usize,
    pub columns: Option<usize>,
    /// A single number passed by value (`dt: S`).
    pub scalar: bool,
}

impl Arg {
    /// The parameter's type: `&[S; 7]` or `&[[S; 6]; 4]`.
    pub(crate) fn type_text(&self) -> String {
        if self.scalar {
            return "S".into();
        }
        match self.columns {
            None => format!("&[S; {}]", self.len),
            Some(c) => format!("&[[S; {c}]; {}]", self.len),
        }
    }

    /// Reading entry `index` (row-major for a matrix): `q[3]`, `f_ext[1][2]`.
    pub(crate) fn entry_text(&self, index: u32) -> String {
        if self.scalar {
            return self.name.to_string();
        }
        let i = index as usize;
        match self.columns {
            None => format!("{}[{i}]", self.name),
            Some(c) => format!("{}[{}][{}]", self.name, i / c, i % c),
        }
    }

    pub(crate) fn tokens(&self) -> TokenStream {
        let id = format_ident!("{}", self.name);
        if self.scalar {
            return quote!(#id: S);
        }
        let len = num(self.len);
        match self.columns {
            None => quote!(#id: &[S; #len]),
            Some(c) => {
                let c = num(c);
                quote!(#id: &[[S; #c]; #len])
            }
        }
    }

    fn entry(&self, index: u32) -> TokenStream {
        let id = format_ident!("{}", self.name);
        if self.scalar {
            return quote!(#id);
        }
        let i = index as usize;
        match self.columns {
            None => {
                let i = num(i);
                quote!(#id[#i])
            }
            Some(c) => {
                let (r, c) = (num(i / c), num(i % c));
                quote!(#id[#r][#c])
            }
        }
    }
}

/// The outputs of a generated function: a vector `&mut [S; n]` or a matrix `&mut [[S; cols]; rows]`
/// (values row-major).
pub enum Output {
    Vector {
        name: &'static str,
        values: Vec<Sym>,
    },
    Matrix {
        name: &'static str,
        rows: usize,
        cols: usize,
        values: Vec<Sym>,
    },
    /// The function's return value (`-> S`).
    Return(Sym),
}

impl Output {
    /// The parameter name of an output (none for the return value).
    pub(crate) fn name(&self) -> Option<&'static str> {
        match self {
            Output::Vector { name, .. } | Output::Matrix { name, .. } => Some(name),
            Output::Return(_) => None,
        }
    }

    /// The output parameter of a generated function (`qdd: &mut [S; 18]`, `m: &mut [[S; 18]; 18]`);
    /// none for the return value.
    pub(crate) fn param(&self) -> Option<TokenStream> {
        let id = format_ident!("{}", self.name()?);
        Some(match self {
            Output::Vector { values, .. } => {
                let n = num(values.len());
                quote!(#id: &mut [S; #n])
            }
            Output::Matrix { rows, cols, .. } => {
                let (cols, rows) = (num(*cols), num(*rows));
                quote!(#id: &mut [[S; #cols]; #rows])
            }
            Output::Return(_) => unreachable!("the return value has no name"),
        })
    }
}

/// The doc of a generated function with its header: the bodies whose values it computes (in the
/// model's order) and its parts (each documented with the bodies it covers).
pub(crate) fn function_doc(doc: &str, bodies: &[&str], parts: &[String]) -> String {
    let mut text = doc.to_string();
    if !bodies.is_empty() {
        text += &format!(
            "\n\nBodies it computes, in the model's order: {}.",
            body_list(bodies)
        );
    }
    if parts.len() > 1 {
        let parts: Vec<String> = parts.iter().map(|p| format!("`{p}`")).collect();
        text += &format!("\n\nComputed in parts, in order: {}.", parts.join(", "));
    }
    text
}

/// The doc of part `index` (of `count`) of function `function`, which covers `bodies` (in the model's
/// order).
pub(crate) fn part_doc(function: &str, index: usize, count: usize, bodies: &[&str]) -> String {
    let mut text = format!("Part {} of {count} of `{function}`", index + 1);
    if !bodies.is_empty() {
        text += &format!(": values of the bodies {}", body_list(bodies));
    }
    text + "."
}

/// The parts of one function are spread over at most this many modules. rustc cuts its code-generation
/// units along modules, so the parts of a long function written in one module were optimized by one
/// thread: measured on the floating TALOS's `aba_derivatives` (121 parts, release, 2 cores), 34 s with
/// the parts in one module, 17 s in 16 (BENCHMARKS.md, "Derivatives").
pub(crate) const PART_MODULES: usize = 16;

/// The parts each module holds, of `count` parts: contiguous runs, at most [`PART_MODULES`] of them.
pub(crate) fn part_module_ranges(count: usize) -> impl Iterator<Item = std::ops::Range<usize>> {
    let per = count.div_ceil(PART_MODULES).max(1);
    (0..count)
        .step_by(per)
        .map(move |start| start..(start + per).min(count))
}

/// The name of the `g`-th module of `function`'s parts: in the type namespace, beside the scalar
/// module's other modules (none) and types (CamelCase), and unique because the index is all digits.
pub(crate) fn part_module_name(function: &str, g: usize) -> String {
    format!("{function}_parts_{g}")
}

/// Part functions (each `pub(super)`) grouped into modules of contiguous parts, each module importing
/// its parent's names, and the parent importing the parts back by name.
fn part_modules(function: &str, parts: Vec<TokenStream>, part_names: &[String]) -> TokenStream {
    let wrapped = part_module_ranges(parts.len())
        .enumerate()
        .map(|(g, range)| {
            let fns = &parts[range.clone()];
            let names: Vec<Ident> = part_names[range]
                .iter()
                .map(|n| format_ident!("{}", n))
                .collect();
            let module = format_ident!("{}", part_module_name(function, g));
            // One name without braces (`unused_import_braces`, a lint users may deny).
            let import = match names.as_slice() {
                [one] => quote!(use self::#module::#one;),
                _ => quote!(use self::#module::{#(#names),*};),
            };
            quote! {
                mod #module {
                    #[allow(unused_imports)]
                    use super::*;
                    #(#fns)*
                }
                #import
            }
        });
    quote!(#(#wrapped)*)
}

/// The most `let`s in one part of a paired body, or in a paired function written whole (see
/// `paired_parts`).
pub(crate) const PAIRED_PART: usize = CHUNK;

/// The statements (`let`s, mostly) a paired body writes: a statement of a pair adds one per lane taken
/// out of it.
fn paired_lets(statements: &[crate::pairing::Statement]) -> usize {
    statements.iter().map(|s| s.tokens.len()).sum()
}

/// Statements per chunk function. At ~2000 statements rustc -O compiles each in about a second, and the
/// call boundaries cost a few loads and stores of live values.
pub const CHUNK: usize = 2000;

fn lit(x: f64) -> TokenStream {
    if x < 0.0 || (x == 0.0 && x.is_sign_negative()) {
        let l = Literal::f64_unsuffixed(-x);
        quote!((-#l))
    } else {
        let l = Literal::f64_unsuffixed(x);
        quote!(#l)
    }
}

/// The reason of `#[must_use]` on a generated function that returns a value: the singularity measure
/// (`aba` of a model with constraints, `embedding`, `crba_independent`) or the residual (`complete`)
/// is what says whether the outputs can be used.
pub(crate) const MUST_USE: &str =
    "the returned measure says whether the outputs can be used (see the function's documentation)";

/// Doc-comment lines as `#[doc]` attributes carry them: each with the space that `/// ` puts after
/// the slashes (without it, the formatted code reads `///Dynamics`).
pub(crate) fn doc_lines(doc: &str) -> Vec<String> {
    doc.lines()
        .map(|line| {
            if line.is_empty() {
                String::new()
            } else {
                format!(" {line}")
            }
        })
        .collect()
}

/// The identifier of value `n` ([`ValueNames`]).
fn node_ident(names: &ValueNames, n: u32) -> Ident {
    format_ident!("{}", names.name(n))
}

/// A length or an index as generated code writes it: `4`, not `4usize`.
pub(crate) fn num(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

/// A generated function (its parts and the public function), ready for a scalar module whose `S` is
/// the scalar type, with what it costs to compile.
pub struct Emitted {
    /// Operations of the traced computation that reach the code.
    pub operations: usize,
    /// The largest magnitude of a constant the code contains. Constants are folded in `f64` and written
    /// as literals of the module's type: one beyond that type's range (a product of model numbers that
    /// each fit, a coupling ratio squared) would not compile, so each scalar module checks it.
    pub largest_constant: f64,
    /// rustc's estimated memory for this function in one scalar module, in bytes
    /// ([`TOKEN_BYTES_PER_OPERATION`], [`crate::emit_large::compile_bytes`]).
    pub compile_bytes: f64,
    /// Whether the code computes mirrored branches side by side as pairs (docs/generated-code.md).
    pub paired: bool,
    /// Arithmetic statements of the code, a pair's operation counting once: what runs, for choosing
    /// between two traces of the same function.
    pub statements: usize,
    pub code: Code,
}

/// The code of an [`Emitted`] function.
pub enum Code {
    /// A function of up to [`SCHEDULE_LIMIT`] statements, as tokens (formatted by `prettyplease`).
    Tokens(TokenStream),
    /// A longer one, as formatted module-body text (items indented by four spaces).
    Text(String),
}

/// rustc's memory per operation of a function emitted as tokens: one `let` per operation, values
/// crossing chunks through an array. Measured: 3.6 KB (a 130,000-operation function in this form
/// needed 541 MB with one scalar module, 70 MB of which the compiler needs for any crate).
pub const TOKEN_BYTES_PER_OPERATION: f64 = 3600.0;

/// Errors of emission: a value the generated code would have to write as a literal is not a number.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EmitError {
    /// An output of `function` folded, at generation time, to a non-finite constant.
    #[error("`{function}`: an output folded to the non-finite constant {value}")]
    NonFiniteOutput {
        /// The generated function.
        function: String,
        /// The constant.
        value: f64,
    },
    /// An intermediate value of `function` folded to a non-finite constant.
    #[error("`{function}`: a constant folded to {value}")]
    NonFiniteConstant {
        /// The generated function.
        function: String,
        /// The constant.
        value: f64,
    },
}

/// What every function of one generated module is emitted against.
pub struct ModuleContext<'a> {
    /// The path of the helper module (`sincos`, `sqrt`).
    pub helpers: &'a TokenStream,
    /// The joints and bodies that named values belong to.
    pub owners: &'a Owners,
    /// The names at the module's level so far (public functions, parts of long functions), which a
    /// function's parts must not take and join.
    pub taken: &'a mut HashSet<String>,
    /// A lane module (`f64x4`, …): constants as `S::splat(…)`, comparisons through `select_gt`.
    pub lanes: bool,
    /// The model's isomorphic branches, whose values a scalar function computes side by side
    /// ([`crate::pairing`]); `None` keeps every value scalar.
    pub pairs: Option<&'a crate::pairing::BranchPairs>,
}

/// Emits `pub fn name(args…, outputs…)` for one scalar module.
pub fn function(
    name: &str,
    doc: &str,
    args: &[Arg],
    outputs: &[Output],
    tape: &Tape,
    module: &mut ModuleContext,
) -> Result<Emitted, EmitError> {
    let (helpers, owners) = (module.helpers, module.owners);
    let nodes = &tape.nodes;
    // Liveness from the outputs.
    let mut live = vec![false; nodes.len()];
    let mut stack: Vec<u32> = Vec::new();
    let mut largest_constant = 0.0_f64;
    let mut out_syms: Vec<Sym> = Vec::new();
    for o in outputs {
        match o {
            Output::Vector { values, .. } | Output::Matrix { values, .. } => {
                out_syms.extend(values.iter().copied())
            }
            Output::Return(v) => out_syms.push(*v),
        }
    }
    for s in &out_syms {
        match s {
            Sym::Node(n) => stack.push(*n),
            Sym::Const(c) if !c.is_finite() => {
                return Err(EmitError::NonFiniteOutput {
                    function: name.to_string(),
                    value: *c,
                })
            }
            Sym::Const(c) => largest_constant = largest_constant.max(c.abs()),
        }
    }
    while let Some(n) = stack.pop() {
        if live[n as usize] {
            continue;
        }
        live[n as usize] = true;
        for operand in operands(&nodes[n as usize]) {
            match operand {
                Sym::Node(m) => stack.push(m),
                Sym::Const(c) if !c.is_finite() => {
                    return Err(EmitError::NonFiniteConstant {
                        function: name.to_string(),
                        value: c,
                    })
                }
                Sym::Const(c) => largest_constant = largest_constant.max(c.abs()),
            }
        }
    }
    // Sine and cosine of one angle come from one helper call.
    let mut sin_of: HashMap<Sym, u32> = HashMap::new();
    let mut cos_of: HashMap<Sym, u32> = HashMap::new();
    for (i, op) in nodes.iter().enumerate() {
        if !live[i] {
            continue;
        }
        match op {
            Op::Sin(a) => {
                sin_of.insert(*a, i as u32);
            }
            Op::Cos(a) => {
                cos_of.insert(*a, i as u32);
            }
            _ => {}
        }
    }
    let order: Vec<u32> = (0..nodes.len() as u32)
        .filter(|&i| live[i as usize] && !matches!(nodes[i as usize], Op::Input { .. }))
        .collect();
    let live_nodes: Vec<u32> = (0..nodes.len() as u32)
        .filter(|&i| live[i as usize])
        .collect();
    // Isomorphic branches side by side, in scalar functions of up to PAIRING_LIMIT operations.
    let pairing = match module.pairs {
        Some(pairs) if !module.lanes && order.len() <= crate::pairing::PAIRING_LIMIT => {
            let arg_lens: Vec<Option<usize>> = args
                .iter()
                .map(|a| (!a.scalar && a.columns.is_none()).then_some(a.len))
                .collect();
            let found = crate::pairing::find(nodes, &live, &pairs.seeds(nodes, &arg_lens));
            (found.computed(nodes) >= crate::pairing::MIN_PAIRS).then_some(found)
        }
        _ => None,
    };
    let mut firsts: Vec<u32> = pairing
        .as_ref()
        .map(|p| p.second.keys().copied().collect())
        .unwrap_or_default();
    firsts.sort_unstable();
    let pair_name_text: Vec<String> = (0..firsts.len()).map(|k| format!("p{k}")).collect();
    let mut reserved: Vec<&str> = vec!["s", "sin_batch", "cos_batch", "P"];
    reserved.extend(pair_name_text.iter().map(String::as_str));
    reserved.extend(args.iter().map(|a| -> &str { a.name }));
    reserved.extend(outputs.iter().filter_map(|o| -> Option<&str> { o.name() }));
    let names = ValueNames::new(tape, &live_nodes, &reserved, owners);
    let pair_names: HashMap<u32, Ident> = firsts
        .iter()
        .zip(&pair_name_text)
        .map(|(&a, name)| (a, format_ident!("{}", name)))
        .collect();
    // The paired body, in trace order; None where the pairs could not be ordered.
    let paired = pairing.as_ref().and_then(|p| {
        // Trace order, not `schedule`'s: see there.
        let (order, batch) = batch_angles(nodes, order.clone(), &sin_of, &cos_of);
        let angles = batch_args(nodes, &batch, module.lanes);
        let writer = Writer {
            nodes,
            names: &names,
            helpers,
            lanes: false,
            batch: &batch,
            angles: &angles,
            sin_of: &sin_of,
            cos_of: &cos_of,
        };
        let statements = crate::pairing::statements(&writer, &order, p, &out_syms, &pair_names)?;
        Some((order, batch, statements))
    });
    // A long function pairs only where that saves much: its paired parts cost rustc more per operation than
    // the unpaired form of `emit_large` (measured: the 38-joint TALOS, 77 % as many statements as
    // operations, gained 10–15 % for 3 s more compile time; the 29-joint G1, 56 %, gained 30 %).
    let paired = paired.filter(|(order, _, statements)| {
        order.len() <= SCHEDULE_LIMIT || statements.len() * 100 <= order.len() * LONG_PAIRED_PERCENT
    });
    if let Some((order, batch, statements)) = &paired {
        if paired_lets(statements) > PAIRED_PART {
            return Ok(paired_parts(
                name,
                doc,
                args,
                outputs,
                nodes,
                order,
                batch,
                statements,
                &names,
                &pair_names,
                module,
                largest_constant,
            ));
        }
    }
    if order.len() > SCHEDULE_LIMIT && paired.is_none() {
        let (order, batch) = batch_angles(nodes, order, &sin_of, &cos_of);
        let angles = batch_args(nodes, &batch, module.lanes);
        let helpers = helpers.to_string().replace(' ', "");
        let operations = order.len();
        let text = crate::emit_large::function_text(
            name,
            doc,
            args,
            outputs,
            nodes,
            order,
            &batch,
            &angles,
            &sin_of,
            &cos_of,
            &helpers,
            &names,
            module.taken,
            module.lanes,
        );
        return Ok(Emitted {
            operations,
            largest_constant,
            compile_bytes: crate::emit_large::compile_bytes(operations, &text),
            paired: false,
            statements: operations,
            code: Code::Text(text),
        });
    }
    let places = output_places(outputs, nodes);
    let zero_writes = ZeroWrites::of(outputs, order.len());
    let is_paired = paired.is_some();
    let statement_count = paired
        .as_ref()
        .map_or(order.len(), |(_, _, statements)| statements.len());
    let (order, batch, mut paired_body) = match paired {
        Some((order, batch, statements)) => (
            order,
            batch,
            Some(
                statements
                    .into_iter()
                    .flat_map(|st| {
                        let mut tokens = st.tokens;
                        for &m in &st.scalars {
                            write_places(&places, &names, m, &mut tokens);
                        }
                        tokens
                    })
                    .collect::<Vec<_>>(),
            ),
        ),
        None => {
            let (order, batch) = batch_angles(nodes, schedule(nodes, order), &sin_of, &cos_of);
            (order, batch, None)
        }
    };
    let angles = batch_args(nodes, &batch, module.lanes);
    // A paired body short enough for one function is one function.
    let chunks: Vec<&[u32]> = if order.is_empty() || paired_body.is_some() {
        vec![&order[..]]
    } else {
        order.chunks(CHUNK).collect()
    };
    let chunk_of: HashMap<u32, usize> = chunks
        .iter()
        .enumerate()
        .flat_map(|(c, ns)| ns.iter().map(move |&n| (n, c)))
        .collect();
    // Values that cross a chunk boundary (or reach the outputs from a split body) live in a scratch array.
    let split = chunks.len() > 1;
    let mut slot: HashMap<u32, usize> = HashMap::new();
    if split {
        // The last chunk that reads each value (outputs count as after every chunk).
        let mut last_use: HashMap<u32, usize> = HashMap::new();
        for &m in &order {
            for o in operands(&nodes[m as usize]) {
                if let Sym::Node(x) = o {
                    let e = last_use.entry(x).or_insert(0);
                    *e = (*e).max(chunk_of[&m]);
                }
            }
        }
        // The returned value (the other outputs are written by the chunk that computes them).
        for o in outputs {
            if let Output::Return(Sym::Node(x)) = o {
                last_use.insert(*x, usize::MAX);
            }
        }
        for &n in &order {
            if last_use.get(&n).is_some_and(|&c| c > chunk_of[&n]) {
                let k = slot.len();
                slot.insert(n, k);
            }
        }
    }
    let scalar_args: Vec<TokenStream> = args.iter().map(Arg::tokens).collect();
    let arg_names: Vec<Ident> = args.iter().map(|a| format_ident!("{}", a.name)).collect();
    let nslots = num(slot.len().max(1));

    let writer = Writer {
        nodes,
        names: &names,
        helpers,
        lanes: module.lanes,
        batch: &batch,
        angles: &angles,
        sin_of: &sin_of,
        cos_of: &cos_of,
    };
    let operand = |s: &Sym| writer.operand(s);
    let pair_type = if paired_body.is_some() {
        quote!(type P = <S as #helpers::Float>::Pair;)
    } else {
        quote!()
    };
    // Outputs: the parameters, which the parts take too, and the writes of what no statement computes.
    let OutputTokens {
        params: out_params,
        fill: fill_stmts,
        writes: out_stmts,
        ret_type,
        ret_value,
    } = output_tokens(outputs, &zero_writes, split, &slot, &operand, nodes, args);
    let out_names = output_names(outputs);
    let chunk_bodies: Vec<Vec<&str>> = chunks.iter().map(|ns| names.bodies(ns.iter())).collect();
    let chunk_names = part_names(name, &chunk_bodies, module.taken);
    let mut chunk_stmts = Vec::new();
    for (c, ns) in chunks.iter().enumerate() {
        let mut stmts = Vec::new();
        let mut defined: HashSet<u32> = HashSet::new();
        // Inputs and earlier chunks' values this chunk reads.
        let mut needed: Vec<u32> = Vec::new();
        for &n in ns.iter() {
            for o in operands(&nodes[n as usize]) {
                if let Sym::Node(m) = o {
                    if chunk_of.get(&m) != Some(&c) {
                        needed.push(m);
                    }
                }
            }
        }
        needed.sort_unstable();
        needed.dedup();
        for m in needed {
            let id = node_ident(&names, m);
            match nodes[m as usize] {
                Op::Input { arg, index } => {
                    let entry = args[arg as usize].entry(index);
                    stmts.push(quote!(let #id: S = #entry;));
                }
                _ => {
                    let k = num(slot[&m]);
                    stmts.push(quote!(let #id: S = s[#k];));
                }
            }
            defined.insert(m);
        }
        match paired_body.take() {
            Some(paired) => stmts.extend(paired),
            None => {
                for &n in ns.iter() {
                    writer.scalar(n, &mut stmts, &mut defined);
                    write_places(&places, &names, n, &mut stmts);
                }
            }
        }
        if split {
            for &n in ns.iter() {
                if let Some(&k) = slot.get(&n) {
                    let k = num(k);
                    let id = node_ident(&names, n);
                    stmts.push(quote!(s[#k] = #id;));
                }
            }
        }
        chunk_stmts.push(stmts);
    }
    let chunk_stmts = zero_stores::spread(chunk_stmts, zero_run_tokens(&zero_writes, &operand));
    let mut chunk_fns = Vec::new();
    let mut bodies = Vec::new();
    for (c, stmts) in chunk_stmts.into_iter().enumerate() {
        if split {
            let fname = format_ident!("{}", chunk_names[c]);
            let part_lines = doc_lines(&part_doc(name, c, chunks.len(), &chunk_bodies[c]));
            chunk_fns.push(quote! {
                #(#[doc = #part_lines])*
                #[inline(never)]
                #[allow(unused_variables, clippy::all)]
                pub(super) fn #fname(#(#scalar_args,)* #(#out_params,)* s: &mut [S; #nslots]) {
                    #(#stmts)*
                }
            });
        } else {
            bodies.push(stmts);
        }
    }
    let fname = format_ident!("{}", name);
    let zero = operand(&Sym::Const(0.0));
    let body = if split {
        let calls: Vec<TokenStream> = chunk_names
            .iter()
            .map(|c| {
                let f = format_ident!("{}", c);
                quote!(#f(#(#arg_names,)* #(#out_names,)* &mut s);)
            })
            .collect();
        quote! {
            #(#fill_stmts)*
            let mut s: [S; #nslots] = [#zero; #nslots];
            #(#calls)*
            #(#out_stmts)*
            #ret_value
        }
    } else {
        let stmts = bodies.pop().unwrap_or_default();
        quote! {
            #pair_type
            #(#fill_stmts)*
            #(#stmts)*
            #(#out_stmts)*
            #ret_value
        }
    };
    let chunk_modules = part_modules(name, chunk_fns, &chunk_names);
    let operations = order.len();
    let doc_lines = doc_lines(&function_doc(
        doc,
        &names.bodies(order.iter()),
        &chunk_names,
    ));
    let must_use = if ret_value.is_empty() {
        quote!()
    } else {
        quote!(#[must_use = #MUST_USE])
    };
    Ok(Emitted {
        operations,
        largest_constant,
        compile_bytes: TOKEN_BYTES_PER_OPERATION * operations as f64,
        paired: is_paired,
        statements: statement_count,
        code: Code::Tokens(quote! {
            #chunk_modules
            #(#[doc = #doc_lines])*
            #must_use
            #[allow(unused_variables, clippy::all)]
            pub fn #fname(#(#scalar_args,)* #(#out_params),*) #ret_type {
                #body
            }
        }),
    })
}

/// The statements writing the structural zeros by runs ([`zero_stores`]), `operand` writing the zero:
/// [`zero_stores::ZeroRun::text`]'s statements, the one form of a run the text emission writes too.
fn zero_run_tokens(
    zero_writes: &ZeroWrites,
    operand: &dyn Fn(&Sym) -> TokenStream,
) -> Vec<TokenStream> {
    let zero = operand(&Sym::Const(0.0)).to_string();
    zero_writes
        .runs()
        .iter()
        .map(|run| {
            run.text(&zero)
                .parse()
                .expect("a run is statements of an output's name, indices and the zero")
        })
        .collect()
}

/// Where each computed value goes in the output arrays (`m[3][4]`, `qdd[2]`; a symmetric matrix's
/// entry in two places). The statement that defines a value is followed by its writes, in whichever part
/// computes it: a value then never crosses to the public function through the scratch arrays only to be
/// stored (for the floating TALOS's `crba`, 674 of M's entries went through `s`, a store, a load and a
/// store each), and it leaves the registers as soon as it is known instead of living to the end.
fn output_places(outputs: &[Output], nodes: &[Op]) -> HashMap<u32, Vec<TokenStream>> {
    let mut places: HashMap<u32, Vec<TokenStream>> = HashMap::new();
    let computed = |v: &Sym| computed_value(v, nodes);
    for o in outputs {
        match o {
            Output::Vector { name, values } => {
                let id = format_ident!("{}", name);
                for (i, v) in values.iter().enumerate() {
                    if let Some(n) = computed(v) {
                        let i = num(i);
                        places.entry(n).or_default().push(quote!(#id[#i]));
                    }
                }
            }
            Output::Matrix {
                name, cols, values, ..
            } => {
                let id = format_ident!("{}", name);
                for (k, v) in values.iter().enumerate() {
                    if let Some(n) = computed(v) {
                        let (r, c) = (num(k / cols), num(k % cols));
                        places.entry(n).or_default().push(quote!(#id[#r][#c]));
                    }
                }
            }
            Output::Return(_) => {}
        }
    }
    places
}

/// The value an output entry `v` takes from a statement: a computed node, not a constant or an input passed
/// through (those the public function writes itself, [`output_tokens`]).
fn computed_value(v: &Sym, nodes: &[Op]) -> Option<u32> {
    match v {
        Sym::Node(n) if !matches!(nodes[*n as usize], Op::Input { .. }) => Some(*n),
        _ => None,
    }
}

/// The output parameters' names, which the public function passes on to its parts.
fn output_names(outputs: &[Output]) -> Vec<Ident> {
    outputs
        .iter()
        .filter_map(|o| o.name().map(|n| format_ident!("{}", n)))
        .collect()
}

/// The writes of value `n` to its output places, after the statement that defines it.
fn write_places(
    places: &HashMap<u32, Vec<TokenStream>>,
    names: &ValueNames,
    n: u32,
    stmts: &mut Vec<TokenStream>,
) {
    if let Some(places) = places.get(&n) {
        let id = node_ident(names, n);
        stmts.extend(places.iter().map(|place| quote!(#place = #id;)));
    }
}

/// The output parameters (`qdd: &mut [S; 18]`), the statements that write the outputs no statement
/// computes (constants, inputs passed through: computed values are written where they are defined,
/// [`output_places`]), and the return type and value of a generated function (from the scratch array
/// `s` when `split`).
fn output_tokens(
    outputs: &[Output],
    zero_writes: &ZeroWrites,
    split: bool,
    slot: &HashMap<u32, usize>,
    operand: &dyn Fn(&Sym) -> TokenStream,
    nodes: &[Op],
    args: &[Arg],
) -> OutputTokens {
    let computed = |v: &Sym| computed_value(v, nodes).is_some();
    let mut out_params = Vec::new();
    let mut out_stmts = Vec::new();
    let mut fill_stmts = Vec::new();
    let mut ret_type = quote!();
    let mut ret_value = quote!();
    for o in outputs {
        match o {
            Output::Return(v) => {
                ret_type = quote!(-> S);
                ret_value = value_tokens(v, split, slot, operand, nodes, args);
            }
            Output::Vector {
                name: oname,
                values,
            } => {
                let id = format_ident!("{}", oname);
                out_params.extend(o.param());
                for (i, v) in values.iter().enumerate().filter(|(_, v)| !computed(v)) {
                    let i = num(i);
                    let val = value_tokens(v, split, slot, operand, nodes, args);
                    out_stmts.push(quote!(#id[#i] = #val;));
                }
            }
            Output::Matrix {
                name: oname,
                rows,
                cols,
                values,
            } => {
                let id = format_ident!("{}", oname);
                out_params.extend(o.param());
                // Zeroed whole first, or by runs spread through the body (`zero_stores`): either
                // way its structural zeros are not written one by one.
                let filled = zero_filled(values);
                if zero_writes.filled().contains(oname) {
                    let (zero, r, c) = (operand(&Sym::Const(0.0)), num(*rows), num(*cols));
                    fill_stmts.push(quote!(*#id = [[#zero; #c]; #r];));
                }
                for r in 0..*rows {
                    for c in 0..*cols {
                        let v = &values[r * cols + c];
                        if computed(v) || (filled && is_positive_zero(v)) {
                            continue;
                        }
                        let val = value_tokens(v, split, slot, operand, nodes, args);
                        let (r, c) = (num(r), num(c));
                        out_stmts.push(quote!(#id[#r][#c] = #val;));
                    }
                }
            }
        }
    }
    OutputTokens {
        params: out_params,
        fill: fill_stmts,
        writes: out_stmts,
        ret_type,
        ret_value,
    }
}

/// What [`output_tokens`] gives a public function.
struct OutputTokens {
    /// The output parameters.
    params: Vec<TokenStream>,
    /// The statements that zero whole matrices first (those [`ZeroWrites`] does not write by runs).
    fill: Vec<TokenStream>,
    /// The writes of the entries no statement computes.
    writes: Vec<TokenStream>,
    ret_type: TokenStream,
    ret_value: TokenStream,
}

/// Constant `+0.0` entries of an output matrix from which its structural zeros are not written one by
/// one but zeroed together: by runs spread through the body or whole first ([`crate::zero_stores`]).
/// The floating TALOS's M has 762 such entries of 1,444 (joints on different branches): one store
/// instruction each (8 KB of code) took its `crba` 1.1× the time of a whole fill (2026-12-03, one
/// binary).
pub(crate) const ZERO_FILL_MIN: usize = 16;

/// Whether the structural zeros of an output matrix of these values are zeroed together
/// ([`ZERO_FILL_MIN`]).
pub(crate) fn zero_filled(values: &[Sym]) -> bool {
    values.iter().filter(|v| is_positive_zero(v)).count() >= ZERO_FILL_MIN
}

/// The constant `+0.0` (not `-0.0`, which a fill with `0.0` would not write).
pub(crate) fn is_positive_zero(v: &Sym) -> bool {
    matches!(v, Sym::Const(c) if c.to_bits() == 0)
}

fn value_tokens(
    v: &Sym,
    split: bool,
    slot: &HashMap<u32, usize>,
    operand: &dyn Fn(&Sym) -> TokenStream,
    nodes: &[Op],
    args: &[Arg],
) -> TokenStream {
    match v {
        // An input passed straight through to an output.
        Sym::Node(n) if matches!(nodes[*n as usize], Op::Input { .. }) => {
            let Op::Input { arg, index } = nodes[*n as usize] else {
                unreachable!()
            };
            args[arg as usize].entry(index)
        }
        Sym::Node(n) if split => {
            let k = num(slot[n]);
            quote!(s[#k])
        }
        _ => operand(v),
    }
}

pub(crate) fn operands(op: &Op) -> Vec<Sym> {
    match *op {
        Op::Input { .. } => vec![],
        Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) => vec![a, b],
        Op::Neg(a) | Op::Sqrt(a) | Op::Sin(a) | Op::Cos(a) | Op::Abs(a) => vec![a],
        Op::Select {
            lhs,
            rhs,
            then,
            otherwise,
        } => vec![lhs, rhs, then, otherwise],
    }
}

/// Latency, in rough cycles, of one operation (for ordering only).
fn latency(op: &Op) -> u32 {
    match op {
        Op::Input { .. } => 0,
        Op::Add(..) | Op::Sub(..) | Op::Neg(..) | Op::Abs(..) | Op::Select { .. } => 3,
        Op::Mul(..) => 4,
        Op::Div(..) => 14,
        Op::Sqrt(..) => 20,
        Op::Sin(..) | Op::Cos(..) => 40,
    }
}

/// A function longer than [`SCHEDULE_LIMIT`] operations is paired only if its statements, a pair counting
/// once, are at most this percentage of its operations.
const LONG_PAIRED_PERCENT: usize = 65;

/// Functions up to this many statements are reordered by [`schedule`]; longer ones keep the trace order.
pub const SCHEDULE_LIMIT: usize = 2 * CHUNK;

/// Orders the statements of an unpaired function for an out-of-order core. The code is latency-bound,
/// so the statements on the longest remaining dependency chain go first (list scheduling by height, ties
/// in trace order) and independent branches (legs, arms) interleave instead of running one after the
/// other. Measured on the 7–12-joint robots this took 10–30% off `aba`, `rnea` and `crba`. Long
/// functions keep the trace order: there the hardware window sees only a small part of the function
/// anyway, and a global order would keep more values live across chunk boundaries and registers.
///
/// Paired functions keep the trace order too, whatever their length. A pair already computes two
/// branches at once, and starting every long chain early keeps more pairs live than the 16 vector
/// registers hold: the floating TALOS's paired `crba` spent a third of its instructions on spills.
/// Measured in one binary (bit-identical results, medians of 9 interleaved rounds, 3–4 runs each,
/// 2026-12-03), trace order against this schedule: `aba` 0.81–0.84× the time on TALOS, 0.85× on G1,
/// 0.78–0.83× on ANYmal B; `crba` 0.84×, 0.73×, 0.92–1.00×; `rnea` 0.93–0.96×, 0.93×, 0.95–1.03×
/// (BENCHMARKS.md, "Floating bases").
fn schedule(nodes: &[Op], order: Vec<u32>) -> Vec<u32> {
    let k = order.len();
    if k > SCHEDULE_LIMIT {
        return order;
    }
    let pos: HashMap<u32, usize> = order.iter().enumerate().map(|(i, &n)| (n, i)).collect();
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); k];
    let mut pending = vec![0usize; k];
    for (i, &n) in order.iter().enumerate() {
        for o in operands(&nodes[n as usize]) {
            if let Sym::Node(m) = o {
                if let Some(&j) = pos.get(&m) {
                    users[j].push(i);
                    pending[i] += 1;
                }
            }
        }
    }
    let mut height = vec![0u32; k];
    for i in (0..k).rev() {
        let below = users[i].iter().map(|&u| height[u]).max().unwrap_or(0);
        height[i] = below + latency(&nodes[order[i] as usize]);
    }
    let mut ready: BinaryHeap<(u32, Reverse<usize>)> = (0..k)
        .filter(|&i| pending[i] == 0)
        .map(|i| (height[i], Reverse(i)))
        .collect();
    let mut out = Vec::with_capacity(k);
    while let Some((_, Reverse(i))) = ready.pop() {
        out.push(order[i]);
        for &u in &users[i] {
            pending[u] -= 1;
            if pending[u] == 0 {
                ready.push((height[u], Reverse(u)));
            }
        }
    }
    out
}

/// A batch of this many angles or more is padded with zeros to a whole number of [`SINCOS_PAD`]: from 24
/// angles the batch runs 4 angles to an AVX instruction (the runtime's `sincos_batch_f64`), 8 in an
/// AVX-512 twin, and angles left over run one at a time, branches and all. The floating G1's 29 angles
/// padded to 32 took its `crba` 0.90× the time in its AVX-512 twin (445 against 494 ns), 0.965× in its
/// AVX twin, 1.02× with no AVX at all (2026-12-05, one binary, the same bits); `aba` and `rnea` 0.97–1.01×.
/// Shorter batches gain nothing (the Z1's 7 angles padded to 8: 0.99–1.01×), and lane functions, whose
/// angles are vectors already, are not padded.
const SINCOS_PAD_MIN: usize = 24;

/// See [`SINCOS_PAD_MIN`].
const SINCOS_PAD: usize = 8;

/// The angles of the batched sine/cosine call, in order of first appearance (then the padding of
/// [`SINCOS_PAD_MIN`]).
fn batch_args(nodes: &[Op], batch: &[u32], lanes: bool) -> Vec<Sym> {
    let mut args: Vec<Sym> = Vec::new();
    for &n in batch {
        if let Op::Sin(a) | Op::Cos(a) = nodes[n as usize] {
            if !args.contains(&a) {
                args.push(a);
            }
        }
    }
    if !lanes && args.len() >= SINCOS_PAD_MIN {
        args.resize(args.len().next_multiple_of(SINCOS_PAD), Sym::Const(0.0));
    }
    args
}

/// Moves every sine and cosine whose angle depends on the inputs alone (a joint angle, a mimic
/// joint's scaled angle) to the front, after the few operations that form the angles, so that one
/// batched helper call computes them all while nothing else is live. Returns the new order and the
/// batched nodes (empty when there are none or too many to fit the first chunk).
fn batch_angles(
    nodes: &[Op],
    order: Vec<u32>,
    sin_of: &HashMap<Sym, u32>,
    cos_of: &HashMap<Sym, u32>,
) -> (Vec<u32>, Vec<u32>) {
    // Whether a value is formed from inputs by arithmetic only (no sine, cosine, root or division).
    let mut pure = vec![false; nodes.len()];
    for (i, op) in nodes.iter().enumerate() {
        let ok = |s: &Sym| match s {
            Sym::Const(_) => true,
            Sym::Node(m) => pure[*m as usize],
        };
        pure[i] = match op {
            Op::Input { .. } => true,
            Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) => ok(a) && ok(b),
            Op::Neg(a) | Op::Abs(a) => ok(a),
            _ => false,
        };
    }
    let is_batched = |n: u32| match nodes[n as usize] {
        Op::Sin(Sym::Node(a)) | Op::Cos(Sym::Node(a)) => pure[a as usize],
        _ => false,
    };
    let mut front: HashSet<u32> = HashSet::new();
    let mut batch: Vec<u32> = Vec::new();
    for &n in &order {
        if is_batched(n) {
            batch.push(n);
            front.insert(n);
            let (Op::Sin(a) | Op::Cos(a)) = nodes[n as usize] else {
                unreachable!()
            };
            // The pair's partner rides along even if it came later.
            for partner in [sin_of.get(&a), cos_of.get(&a)].into_iter().flatten() {
                front.insert(*partner);
            }
            let mut stack = vec![a];
            while let Some(Sym::Node(m)) = stack.pop() {
                if !matches!(nodes[m as usize], Op::Input { .. }) && front.insert(m) {
                    stack.extend(operands(&nodes[m as usize]));
                }
            }
        }
    }
    if batch.is_empty() || front.len() > CHUNK / 2 {
        return (order, Vec::new());
    }
    batch.sort_unstable();
    batch.dedup();
    let (mut first, rest): (Vec<u32>, Vec<u32>) =
        order.into_iter().partition(|n| front.contains(n));
    // Angle arithmetic before the batch, the batched sines and cosines after it.
    first.sort_by_key(|&n| (is_batched(n), n));
    first.extend(rest);
    (first, batch)
}

/// The batch form of a lane function `name` (in a lane module, beside it): `{name}_batch` over any number
/// of states, given as slices of per-state arrays of the lane's scalar `E`, in chunks of `LANES` through
/// the lane function; a last partial chunk is padded with its first state (a valid state: no NaN from
/// padding) and only the real states are written. A returned measure is written per state into `measure`.
/// Returns `false`, computing nothing, where the slices' lengths differ. (A loop over states, not over
/// bodies: the lane function it calls is straight-line.)
///
/// For a function whose scalar form is `paired`, the batch form calls the scalar module's function state by
/// state where the lane module's `PAIRED_BATCH_PER_STATE` says so (four f64 lanes without AVX: see there).
pub(crate) fn batch_wrapper(
    name: &str,
    args: &[Arg],
    outputs: &[Output],
    paired: bool,
    lanes: usize,
) -> TokenStream {
    // Each lane value's lanes go to their states by literal lane indices: an index that varies at run
    // time reads the value back through memory, a store-forwarding stall per entry where the value is one
    // 256-bit register (an AVX twin): a floating Go2's `crba_batch` took 300 ns per state against 128 for
    // the scalar calls, of which its lane `crba` about 30 (2026-12-03, new user's trial).
    let lane_index: Vec<proc_macro2::Literal> = (0..lanes).map(num).collect();
    // Called as `self::name`: an output may share the function's name (`com`'s output `com`).
    let fname = format_ident!("{}", name);
    let batch = format_ident!("{}_batch", name);
    // A paired function with a matrix output goes state by state through the scalar function wherever
    // it runs: the transposition of its many outputs out of the lanes costs more than the lanes save (a
    // floating Go2's `crba_batch` through the AVX twin's lanes 161 ns per state, the scalar calls 130; its
    // `aba_batch` 240 against 360, `rnea_batch` 158 against 184; 2026-12-03).
    let always_per_state = paired && outputs.iter().any(|o| matches!(o, Output::Matrix { .. }));
    let how = if always_per_state {
        format!(
            "It calls the scalar module's `{name}` state by state, which computes mirrored branches side by \
             side: moving its matrix out of the lanes would cost more than the lanes save"
        )
    } else if paired {
        format!(
            "Where `PAIRED_BATCH_PER_STATE` is true (four f64 lanes without AVX) it calls the scalar module's \
             `{name}` state by state, which computes mirrored branches side by side and is faster there; else \
             it runs chunks of `LANES` states through the lane function `{name}` (a last partial chunk padded \
             with its first state, whose results are dropped)"
        )
    } else {
        format!(
            "Runs chunks of `LANES` states through the lane function `{name}` (a last partial chunk padded with \
             its first state, whose results are dropped)"
        )
    };
    let doc = format!(
        " `{name}` over any number of states: entry `s` of every slice is state `s` (`q[s]` its `q`). {how}; \
         every state's results are bit-identical to the scalar function's. Returns `false`, computing nothing, \
         when the slices' lengths differ. Split a large batch across threads with `embedyn::parallel::par_batch` \
         (or `rayon`'s `par_chunks`), each thread calling this on its piece."
    );
    let mut params = Vec::new();
    let mut lane_args = Vec::new();
    let mut call_args = Vec::new();
    let mut lengths = Vec::new();
    for a in args {
        let id = format_ident!("{}", a.name);
        let lane_id = format_ident!("{}_lanes", a.name);
        let len = num(a.len);
        if a.scalar {
            params.push(quote!(#id: E));
            lane_args.push(quote!(let #lane_id = S::splat(#id);));
            call_args.push(quote!(#lane_id));
            continue;
        }
        lengths.push(quote!(#id.len()));
        match a.columns {
            None => {
                params.push(quote!(#id: &[[E; #len]]));
                lane_args.push(quote!(
                    let #lane_id: [S; #len] = ::core::array::from_fn(|i| {
                        S::new(::core::array::from_fn(|k| #id[at(k)][i]))
                    });
                ));
            }
            Some(c) => {
                let c = num(c);
                params.push(quote!(#id: &[[[E; #c]; #len]]));
                lane_args.push(quote!(
                    let #lane_id: [[S; #c]; #len] = ::core::array::from_fn(|r| {
                        ::core::array::from_fn(|c| S::new(::core::array::from_fn(|k| #id[at(k)][r][c])))
                    });
                ));
            }
        }
        call_args.push(quote!(&#lane_id));
    }
    let mut out_lanes = Vec::new();
    let mut stores = Vec::new();
    let mut returns = false;
    for o in outputs {
        match o {
            Output::Vector { name, values } => {
                let id = format_ident!("{}", name);
                let lane_id = format_ident!("{}_lanes", name);
                let n = num(values.len());
                params.push(quote!(#id: &mut [[E; #n]]));
                lengths.push(quote!(#id.len()));
                out_lanes.push(quote!(let mut #lane_id = [S::splat(0.0); #n];));
                call_args.push(quote!(&mut #lane_id));
                stores.push(quote!(
                    for i in 0..#n {
                        let lanes = #lane_id[i].to_array();
                        #(if start + #lane_index < n {
                            #id[start + #lane_index][i] = lanes[#lane_index];
                        })*
                    }
                ));
            }
            Output::Matrix {
                name, rows, cols, ..
            } => {
                let id = format_ident!("{}", name);
                let lane_id = format_ident!("{}_lanes", name);
                let (r, c) = (num(*rows), num(*cols));
                params.push(quote!(#id: &mut [[[E; #c]; #r]]));
                lengths.push(quote!(#id.len()));
                out_lanes.push(quote!(let mut #lane_id = [[S::splat(0.0); #c]; #r];));
                call_args.push(quote!(&mut #lane_id));
                stores.push(quote!(
                    for r in 0..#r {
                        for c in 0..#c {
                            let lanes = #lane_id[r][c].to_array();
                            #(if start + #lane_index < n {
                                #id[start + #lane_index][r][c] = lanes[#lane_index];
                            })*
                        }
                    }
                ));
            }
            Output::Return(_) => returns = true,
        }
    }
    let (call, store_measure) = if returns {
        params.push(quote!(measure: &mut [E]));
        lengths.push(quote!(measure.len()));
        (
            quote!(let returned = self::#fname(#(#call_args),*);),
            quote! {
                let lanes = returned.to_array();
                #(if start + #lane_index < n {
                    measure[start + #lane_index] = lanes[#lane_index];
                })*
            },
        )
    } else {
        (quote!(self::#fname(#(#call_args),*);), quote!())
    };
    let first = lengths.first().cloned().unwrap_or_else(|| quote!(0));
    let must_use = "false where the slices' lengths differ (nothing is computed then)";
    // State by state through the scalar module's paired function: the same bits (lanes never change the
    // arithmetic), in the form that is faster there.
    let per_state = paired.then(|| {
        let scalar_args: Vec<TokenStream> = args
            .iter()
            .map(|a| {
                let id = format_ident!("{}", a.name);
                if a.scalar {
                    quote!(#id)
                } else {
                    quote!(&#id[s])
                }
            })
            .chain(
                output_names(outputs)
                    .into_iter()
                    .map(|id| quote!(&mut #id[s])),
            )
            .collect();
        let call = if returns {
            quote!(measure[s] = scalar_module::#fname(#(#scalar_args),*);)
        } else {
            quote!(scalar_module::#fname(#(#scalar_args),*);)
        };
        quote! {
            for s in 0..n {
                #call
            }
        }
    });
    // Chunks of `LANES` states through the lane function.
    let through_lanes = quote! {
        let mut start = 0;
        while start < n {
            let at = |k: usize| if start + k < n { start + k } else { start };
            #(#lane_args)*
            #(#out_lanes)*
            #call
            #(#stores)*
            #store_measure
            start += LANES;
        }
    };
    let body = match per_state {
        Some(per_state) if always_per_state => per_state,
        Some(per_state) => quote! {
            if PAIRED_BATCH_PER_STATE {
                #per_state
                return true;
            }
            #through_lanes
        },
        None => through_lanes,
    };
    quote! {
        #[doc = #doc]
        #[must_use = #must_use]
        #[allow(unused_variables, clippy::all)]
        pub fn #batch(#(#params),*) -> bool {
            let n = #first;
            if #(#lengths != n)||* {
                return false;
            }
            #body
            true
        }
    }
}

/// Writes one function's scalar statements.
pub(crate) struct Writer<'a> {
    pub nodes: &'a [Op],
    pub names: &'a ValueNames,
    pub helpers: &'a TokenStream,
    /// A lane module: constants as `S::splat(…)`, comparisons through `select_gt`.
    pub lanes: bool,
    /// The sines and cosines of the batched helper call, and its angles.
    pub batch: &'a [u32],
    pub angles: &'a [Sym],
    pub sin_of: &'a HashMap<Sym, u32>,
    pub cos_of: &'a HashMap<Sym, u32>,
}

impl Writer<'_> {
    /// A scalar operand: a literal (splat in a lane module) or the value's name.
    pub(crate) fn operand(&self, s: &Sym) -> TokenStream {
        match s {
            Sym::Const(c) if self.lanes => {
                let c = lit(*c);
                quote!(S::splat(#c))
            }
            Sym::Const(c) => lit(*c),
            Sym::Node(n) => {
                let id = node_ident(self.names, *n);
                quote!(#id)
            }
        }
    }

    /// The statement (or, for a sine or cosine, the helper call) that defines scalar value `n`, unless
    /// `defined` has it already; records what it defines.
    pub(crate) fn scalar(&self, n: u32, stmts: &mut Vec<TokenStream>, defined: &mut HashSet<u32>) {
        let (nodes, names, helpers, lanes) = (self.nodes, self.names, self.helpers, self.lanes);
        let (batch, angles, sin_of, cos_of) = (self.batch, self.angles, self.sin_of, self.cos_of);
        let operand = |s: &Sym| self.operand(s);
        if defined.contains(&n) {
            return;
        }
        let id = node_ident(names, n);
        let expr = match &nodes[n as usize] {
            Op::Input { .. } => unreachable!("inputs are read, not computed"),
            Op::Add(a, b) => {
                let (a, b) = (operand(a), operand(b));
                quote!(#a + #b)
            }
            Op::Sub(a, b) => {
                let (a, b) = (operand(a), operand(b));
                quote!(#a - #b)
            }
            Op::Mul(a, b) => {
                let (a, b) = (operand(a), operand(b));
                quote!(#a * #b)
            }
            Op::Div(a, b) => {
                let (a, b) = (operand(a), operand(b));
                quote!(#a / #b)
            }
            Op::Neg(a) => {
                let a = operand(a);
                quote!(-#a)
            }
            Op::Sqrt(a) => {
                let a = operand(a);
                quote!(#helpers::sqrt(#a))
            }
            Op::Abs(a) => {
                let a = operand(a);
                quote!(#helpers::abs(#a))
            }
            Op::Select {
                lhs,
                rhs,
                then,
                otherwise,
            } => {
                let (l, r, t, o) = (
                    operand(lhs),
                    operand(rhs),
                    operand(then),
                    operand(otherwise),
                );
                if lanes {
                    quote!(#helpers::select_gt(#l, #r, #t, #o))
                } else {
                    quote!(if #l > #r { #t } else { #o })
                }
            }
            Op::Sin(_) | Op::Cos(_) if batch.contains(&n) => {
                // All angles that depend on the inputs alone, in one helper call.
                let args: Vec<TokenStream> = angles.iter().map(&operand).collect();
                stmts.push(quote!(
                    let (sin_batch, cos_batch) = #helpers::sincos_batch([#(#args),*]);
                ));
                for (k, a) in angles.iter().enumerate() {
                    let k = num(k);
                    if let Some(&si) = sin_of.get(a) {
                        let id = node_ident(names, si);
                        stmts.push(quote!(let #id: S = sin_batch[#k];));
                        defined.insert(si);
                    }
                    if let Some(&ci) = cos_of.get(a) {
                        let id = node_ident(names, ci);
                        stmts.push(quote!(let #id: S = cos_batch[#k];));
                        defined.insert(ci);
                    }
                }
                return;
            }
            Op::Sin(a) | Op::Cos(a) => {
                let (s_id, c_id) = (sin_of.get(a).copied(), cos_of.get(a).copied());
                let x = operand(a);
                let s_tok = s_id.map_or_else(|| format_ident!("_"), |x| node_ident(names, x));
                let c_tok = c_id.map_or_else(|| format_ident!("_"), |x| node_ident(names, x));
                stmts.push(quote!(let (#s_tok, #c_tok): (S, S) = #helpers::sincos(#x);));
                if let Some(si) = s_id {
                    defined.insert(si);
                }
                if let Some(ci) = c_id {
                    defined.insert(ci);
                }
                return;
            }
        };
        stmts.push(quote!(let #id: S = #expr;));
        defined.insert(n);
    }
}

/// A paired body longer than one chunk, as parts of up to [`CHUNK`] statements each (a pair counting
/// once; half that for the longest functions): values that cross parts go through two scratch arrays, `s` of scalars and `sp` of pairs.
#[allow(clippy::too_many_arguments)]
fn paired_parts(
    name: &str,
    doc: &str,
    args: &[Arg],
    outputs: &[Output],
    nodes: &[Op],
    order: &[u32],
    batch: &[u32],
    statements: &[crate::pairing::Statement],
    names: &ValueNames,
    pair_names: &HashMap<u32, Ident>,
    module: &mut ModuleContext,
    largest_constant: f64,
) -> Emitted {
    let helpers = module.helpers;
    // Fewer parts run faster (fewer values cross through the scratch arrays): measured on the floating
    // G1 in one binary (bit-identical results), `aba` in parts of 1,000 / 2,000 / 4,000 statements / whole
    // took 2,077 / 1,900 / 1,800 / 1,669 ns, `rnea` 1,130 / 1,030 / 936 / 922, `crba` 1,173 / 1,118 /
    // 1,043 / 1,057, and their crate compiled in 3.1 / 3.2 / 3.3 / 3.5 s, the parts' modules optimized in
    // parallel (release, no debug info). With debug info, though, every `let` opens a lexical scope
    // inside the previous one and LLVM's DWARF writer recurses once per scope: parts of 4,000 paired
    // statements overflowed rustc's stack in the test build (SIGSEGV in
    // `DwarfCompileUnit::createAndAddScopeChildren`). So parts are cut evenly by `let`s, at most
    // PAIRED_PART of them, not by statements: a pair taken out to scalars adds a `let` per lane (paired
    // `kinematics` of two 50-link arms had 1.65 per statement, and its 2,000 statements overflowed rustc's
    // stack in a debug build: attacker's trial). The former half-size parts above 8,000 operations, a
    // compile-time measure, are no longer needed now that the parts' modules compile in parallel.
    let total_lets = paired_lets(statements);
    let part_count = total_lets.div_ceil(PAIRED_PART).max(1);
    let per_part = total_lets.div_ceil(part_count).max(1);
    let mut chunks: Vec<&[crate::pairing::Statement]> = Vec::new();
    let (mut start, mut lets) = (0, 0);
    for (i, st) in statements.iter().enumerate() {
        if lets > 0 && lets + st.tokens.len() > per_part {
            chunks.push(&statements[start..i]);
            (start, lets) = (i, 0);
        }
        lets += st.tokens.len();
    }
    chunks.push(&statements[start..]);
    let mut scalar_chunk: HashMap<u32, usize> = HashMap::new();
    let mut pair_chunk: HashMap<u32, usize> = HashMap::new();
    for (c, part) in chunks.iter().enumerate() {
        for st in part.iter() {
            scalar_chunk.extend(st.scalars.iter().map(|&m| (m, c)));
            pair_chunk.extend(st.pair.map(|a| (a, c)));
        }
    }
    // The last part that reads each value (outputs: after every part).
    let mut scalar_last: HashMap<u32, usize> = HashMap::new();
    let mut pair_last: HashMap<u32, usize> = HashMap::new();
    for (c, part) in chunks.iter().enumerate() {
        for st in part.iter() {
            for &m in &st.reads_scalars {
                let e = scalar_last.entry(m).or_insert(c);
                *e = (*e).max(c);
            }
            for &a in &st.reads_pairs {
                let e = pair_last.entry(a).or_insert(c);
                *e = (*e).max(c);
            }
        }
    }
    // The returned value (the other outputs are written by the part that computes them).
    for o in outputs {
        if let Output::Return(Sym::Node(m)) = o {
            scalar_last.insert(*m, usize::MAX);
        }
    }
    let slots = |chunk_of: &HashMap<u32, usize>, last: &HashMap<u32, usize>| {
        let mut crossing: Vec<u32> = chunk_of
            .iter()
            .filter(|(m, &c)| last.get(m).is_some_and(|&l| l > c))
            .map(|(&m, _)| m)
            .collect();
        crossing.sort_unstable();
        crossing
            .into_iter()
            .enumerate()
            .map(|(k, m)| (m, k))
            .collect::<HashMap<u32, usize>>()
    };
    let places = output_places(outputs, nodes);
    let slot = slots(&scalar_chunk, &scalar_last);
    let pair_slot = slots(&pair_chunk, &pair_last);
    let (nslots, npair_slots) = (num(slot.len().max(1)), num(pair_slot.len().max(1)));
    let pair_type = quote!(<S as #helpers::Float>::Pair);
    let scalar_args: Vec<TokenStream> = args.iter().map(Arg::tokens).collect();
    let arg_names: Vec<Ident> = args.iter().map(|a| format_ident!("{}", a.name)).collect();
    let writer = Writer {
        nodes,
        names,
        helpers,
        lanes: false,
        batch,
        angles: &[],
        sin_of: &HashMap::new(),
        cos_of: &HashMap::new(),
    };
    let chunk_defined: Vec<Vec<u32>> = chunks
        .iter()
        .map(|part| {
            part.iter()
                .flat_map(|st| st.scalars.iter().copied())
                .collect()
        })
        .collect();
    let chunk_bodies: Vec<Vec<&str>> = chunk_defined
        .iter()
        .map(|d| names.bodies(d.iter()))
        .collect();
    let chunk_names = part_names(name, &chunk_bodies, module.taken);
    let operand = |v: &Sym| writer.operand(v);
    let zero_writes = ZeroWrites::of(outputs, order.len());
    let OutputTokens {
        params: out_params,
        fill: fill_stmts,
        writes: out_stmts,
        ret_type,
        ret_value,
    } = output_tokens(outputs, &zero_writes, true, &slot, &operand, nodes, args);
    let out_names = output_names(outputs);
    let mut chunk_stmts = Vec::new();
    for (c, part) in chunks.iter().enumerate() {
        let mut stmts: Vec<TokenStream> = Vec::new();
        let mut scalar_reads: Vec<u32> = part
            .iter()
            .flat_map(|st| st.reads_scalars.iter().copied())
            .filter(|m| scalar_chunk.get(m) != Some(&c))
            .collect();
        scalar_reads.sort_unstable();
        scalar_reads.dedup();
        for m in scalar_reads {
            let id = node_ident(names, m);
            match nodes[m as usize] {
                Op::Input { arg, index } => {
                    let entry = args[arg as usize].entry(index);
                    stmts.push(quote!(let #id: S = #entry;));
                }
                _ => {
                    let k = num(slot[&m]);
                    stmts.push(quote!(let #id: S = s[#k];));
                }
            }
        }
        let mut pair_reads: Vec<u32> = part
            .iter()
            .flat_map(|st| st.reads_pairs.iter().copied())
            .filter(|a| pair_chunk.get(a) != Some(&c))
            .collect();
        pair_reads.sort_unstable();
        pair_reads.dedup();
        for a in pair_reads {
            let id = &pair_names[&a];
            let k = num(pair_slot[&a]);
            stmts.push(quote!(let #id: P = sp[#k];));
        }
        for st in part.iter() {
            stmts.extend(st.tokens.iter().cloned());
            for &m in &st.scalars {
                write_places(&places, names, m, &mut stmts);
            }
        }
        for st in part.iter() {
            for m in &st.scalars {
                if let Some(&k) = slot.get(m) {
                    let (id, k) = (node_ident(names, *m), num(k));
                    stmts.push(quote!(s[#k] = #id;));
                }
            }
            if let Some(a) = st.pair {
                if let Some(&k) = pair_slot.get(&a) {
                    let (id, k) = (&pair_names[&a], num(k));
                    stmts.push(quote!(sp[#k] = #id;));
                }
            }
        }
        chunk_stmts.push(stmts);
    }
    let chunk_stmts = zero_stores::spread(chunk_stmts, zero_run_tokens(&zero_writes, &operand));
    let mut chunk_fns = Vec::new();
    for (c, stmts) in chunk_stmts.into_iter().enumerate() {
        let fname = format_ident!("{}", chunk_names[c]);
        let part_lines = doc_lines(&part_doc(name, c, chunks.len(), &chunk_bodies[c]));
        chunk_fns.push(quote! {
            #(#[doc = #part_lines])*
            #[inline(never)]
            #[allow(unused_variables, clippy::all)]
            pub(super) fn #fname(#(#scalar_args,)* #(#out_params,)* s: &mut [S; #nslots], sp: &mut [#pair_type; #npair_slots]) {
                type P = #pair_type;
                #(#stmts)*
            }
        });
    }
    let zero = operand(&Sym::Const(0.0));
    let calls: Vec<TokenStream> = chunk_names
        .iter()
        .map(|c| {
            let f = format_ident!("{}", c);
            quote!(#f(#(#arg_names,)* #(#out_names,)* &mut s, &mut sp);)
        })
        .collect();
    let fname = format_ident!("{}", name);
    let doc_lines = doc_lines(&function_doc(
        doc,
        &names.bodies(order.iter()),
        &chunk_names,
    ));
    let must_use = if ret_value.is_empty() {
        quote!()
    } else {
        quote!(#[must_use = #MUST_USE])
    };
    let chunk_modules = part_modules(name, chunk_fns, &chunk_names);
    let operations = order.len();
    Emitted {
        operations,
        largest_constant,
        compile_bytes: TOKEN_BYTES_PER_OPERATION * operations as f64,
        paired: true,
        statements: statements.len(),
        code: Code::Tokens(quote! {
            #chunk_modules
            #(#[doc = #doc_lines])*
            #must_use
            #[allow(unused_variables, clippy::all)]
            pub fn #fname(#(#scalar_args,)* #(#out_params),*) #ret_type {
                #(#fill_stmts)*
                let mut s: [S; #nslots] = [#zero; #nslots];
                let mut sp: [#pair_type; #npair_slots] = [#helpers::splat::<S>(#zero); #npair_slots];
                #(#calls)*
                #(#out_stmts)*
                #ret_value
            }
        }),
    }
}

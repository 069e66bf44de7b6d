//! Emission of functions too long to schedule (more than [`SCHEDULE_LIMIT`](crate::emit::SCHEDULE_LIMIT) statements: long chains,
//! whole humanoids, the O(N²) matrices), written as formatted text.
//!
//! rustc's memory is what limits the size of a generated function: it grows linearly with the code,
//! but at about 2.5 KB per operation written one `let` per operation (the whole crate's HIR and MIR are
//! held at once; a 1000-body chain's `aba`, 430 operations per body in f64 and f32, needed 3.5 GB).
//! Measured on generated chains, a `let` binding costs rustc about 1.3 KB on top of its operation, an
//! array element `s[k]` about 2 KB (the bounds check is MIR of its own), a tuple field `s.k` 0.8 KB. So
//! this form spends as few bindings and indexings as the computation allows:
//!
//! - a value used once, by an operation in the same part, is written into its user's expression
//!   (`let t9 = (t3 * 0.5 - t4) * t8;`) instead of being bound to a name; an input or a value of an
//!   earlier part read once is read in place (`q[3]`, `s.17`). Evaluation order and
//!   rounding are those of separate statements: every operation keeps its operands, Rust neither
//!   reassociates nor contracts floating-point arithmetic, and parentheses keep every grouping;
//! - the parts are cut near every [`CHUNK`] operations where the fewest values cross (between bodies
//!   rather than inside one; rustc's optimizer is superlinear in function size, so the parts stay
//!   small), values cross through the scratch tuple `s`, whose slots are reused once their last
//!   reader has run, and each part writes the results it computes straight into the output arrays.
//!
//! The text is formatted as it is written (one statement per line, four spaces per level): the
//! standalone crate needs no pretty-printing pass over millions of tokens.

use crate::emit::{
    doc_lines, function_doc, operands, part_doc, part_module_name, part_module_ranges, Arg, Output,
    CHUNK, MUST_USE,
};
use crate::trace::{Op, Sym};
use crate::value_names::{part_names, ValueNames};
use crate::zero_stores::ZeroWrites;
use std::collections::HashMap;
use std::fmt::Write;

/// Operations written into one expression at most; longer single-use chains get a name. Keeps lines
/// readable and the compiler's recursion shallow.
const MAX_EXPRESSION: u32 = 12;

/// rustc's memory per construct of this text, per scalar module, in bytes: a `let` (a named local with
/// its scope, debug entry and storage markers) and a scratch field (a place projection and its copy)
/// as measured by comparing emitted forms of the same function; a traced operation (its result and
/// operand temporaries in MIR) and an indexing (`q[3]`, `m[2][5]`: each index a bounds check with a
/// block of its own in MIR) fitted by least squares to 14 measured compiles of generated chains'
/// `aba`, `rnea`, `kinematics`, `crba`, `minv` with one and two scalar modules, within 11 %
/// (BENCHMARKS.md, "Scale of generation").
pub(crate) const PER_OPERATION: f64 = 1300.0;
const PER_LET: f64 = 1300.0;
const PER_INDEXING: f64 = 4150.0;
const PER_FIELD: f64 = 800.0;

/// rustc's estimated memory, in bytes, for a function written by [`function_text`] with `operations`
/// traced operations: the constructs of `text` counted and weighted by what the compiler builds for
/// each.
pub(crate) fn compile_bytes(operations: usize, text: &str) -> f64 {
    let (lets, indexings, fields) = constructs(text);
    PER_OPERATION * operations as f64
        + PER_LET * lets as f64
        + PER_INDEXING * indexings as f64
        + PER_FIELD * fields as f64
}

/// The `let` statements, the indexings (`x[`, `][`) and the scratch fields (`s.k`) of emitted text.
fn constructs(text: &str) -> (usize, usize, usize) {
    let (mut lets, mut indexings, mut fields) = (0, 0, 0);
    for line in text.lines() {
        let statement = line.trim_start();
        if statement.starts_with("let ") {
            lets += 1;
        }
        if statement.starts_with("#[")
            || statement.starts_with("///")
            || statement.starts_with("fn ")
            || statement.starts_with("pub fn ")
            || statement.starts_with("type ")
        {
            continue;
        }
        let bytes = statement.as_bytes();
        for (i, &b) in bytes.iter().enumerate() {
            let after_name = i > 0
                && (bytes[i - 1].is_ascii_alphanumeric()
                    || bytes[i - 1] == b'_'
                    || bytes[i - 1] == b']');
            if b == b'[' && after_name {
                indexings += 1;
            }
            let starts_field = b == b's'
                && bytes.get(i + 1) == Some(&b'.')
                && bytes.get(i + 2).is_some_and(u8::is_ascii_digit)
                && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'));
            if starts_field {
                fields += 1;
            }
        }
    }
    (lets, indexings, fields)
}

/// Operations from which a function's parts write the scratch tuple's slots of their own parity only
/// (even parts the even slots), so that no two stores of a part to the scratch are adjacent. LLVM's SLP
/// vectorizer tries every chain of adjacent stores as a seed of vector code, and on long functions that
/// search was a quarter of the optimizer's time, mostly in vain: the floating TALOS's `aba_derivatives`
/// and `rnea_derivatives` in f64 and f32 took 19.8–20.9 s to compile, 17.9 s with the slots spaced
/// (2026-12-05, AMD EPYC, 2 cores, interleaved rounds; 21 % more slots, 2,931 → 3,539). The run time of
/// the long functions stayed the same (in one binary, the same bits: the floating ANYmal B's
/// `aba_derivatives` 0.99–1.0×, TALOS's 0.99×), but short ones lost what SLP found: the Z1's
/// `aba_derivatives` (5.9k statements) took 1.06× the time (1.04× in its baseline copy), so they keep
/// their slots adjacent.
pub(crate) const SPACED_SLOTS_MIN_OPERATIONS: usize = 10_000;

/// Slot `k` of the scratch tuple `s`.
fn slot_text(k: usize) -> String {
    format!("s.{k}")
}

/// The scratch tuple's type name: `aba` → `aba_scratch`. The function's name as it is, for it is unique in
/// the module and a CamelCase form would not be: `frame_x1` and `frame_x_1` were both `FrameX1Scratch`
/// (an attacker's trial: E0428). No module of the code ends in `_scratch` (`_parts_k`, `_avx`, `_avx512`,
/// `_shared`).
fn scratch_type(name: &str) -> String {
    format!("{name}_scratch")
}

/// A float literal as `Literal::f64_unsuffixed` writes it (so both forms of emission print the same
/// constants): the shortest decimal that reads back exactly, with a `.0` when it has no point.
/// A constant as the function's scalar takes it: the literal, or `S::splat(literal)` in a lane function.
pub(crate) fn constant_text(x: f64, lanes: bool) -> String {
    if lanes {
        format!("S::splat({})", float_text(x))
    } else {
        float_text(x)
    }
}

pub(crate) fn float_text(x: f64) -> String {
    let mut s = x.abs().to_string();
    if !s.contains('.') {
        s.push_str(".0");
    }
    if x < 0.0 || (x == 0.0 && x.is_sign_negative()) {
        s.insert(0, '-');
    }
    s
}

/// Where a value is written besides (or instead of) a local name.
#[derive(Clone, Copy)]
enum Destination {
    /// Output `o` (index into the function's outputs), vector element `i` or matrix element `(r, c)`.
    Vector(usize, usize),
    Matrix(usize, usize, usize),
}

/// How an operand is referred to inside a part.
#[derive(Clone, Copy, PartialEq)]
enum Reference {
    /// A `let` name `tN`.
    Name,
    /// Written in place: the operation's own expression (single use in this part).
    Inline,
    /// Read in place: `q[i]`, `s.k` or `sin_batch[k]` (single use in this part).
    Access,
}

/// Binding strength of an expression, for the parentheses around operands.
const ATOM: u8 = 4;
const UNARY: u8 = 3;
const PRODUCT: u8 = 2;
const SUM: u8 = 1;
const CONDITIONAL: u8 = 0;

/// The emitted function: parts `name_part0 …` and the public `name`, as text for the module body
/// (items indented by four spaces).
#[allow(clippy::too_many_arguments)]
pub(crate) fn function_text(
    name: &str,
    doc: &str,
    args: &[Arg],
    outputs: &[Output],
    nodes: &[Op],
    order: Vec<u32>,
    batch: &[u32],
    angles: &[Sym],
    sin_of: &HashMap<Sym, u32>,
    cos_of: &HashMap<Sym, u32>,
    helpers: &str,
    names: &ValueNames,
    taken: &mut std::collections::HashSet<String>,
    lanes: bool,
) -> String {
    let order = pair_sines_with_cosines(nodes, order, sin_of, cos_of, batch);
    let position: HashMap<u32, usize> = order.iter().enumerate().map(|(i, &n)| (n, i)).collect();
    // Every reader of every value, by position (inputs included).
    let mut last_reader: HashMap<u32, usize> = HashMap::new();
    for (i, &n) in order.iter().enumerate() {
        for o in operands(&nodes[n as usize]) {
            if let Sym::Node(m) = o {
                let e = last_reader.entry(m).or_insert(i);
                *e = (*e).max(i);
            }
        }
    }
    // Outputs each computed value is written to; the returned value lives to the end.
    let mut destinations: HashMap<u32, Vec<Destination>> = HashMap::new();
    let mut returned: Option<u32> = None;
    for (o, out) in outputs.iter().enumerate() {
        match out {
            Output::Vector { values, .. } => {
                for (i, v) in values.iter().enumerate() {
                    if let Sym::Node(n) = v {
                        if position.contains_key(n) {
                            destinations
                                .entry(*n)
                                .or_default()
                                .push(Destination::Vector(o, i));
                        }
                    }
                }
            }
            Output::Matrix { cols, values, .. } => {
                for (k, v) in values.iter().enumerate() {
                    if let Sym::Node(n) = v {
                        if position.contains_key(n) {
                            destinations
                                .entry(*n)
                                .or_default()
                                .push(Destination::Matrix(o, k / cols, k % cols));
                        }
                    }
                }
            }
            Output::Return(Sym::Node(n)) if position.contains_key(n) => returned = Some(*n),
            Output::Return(_) => {}
        }
    }
    let parts = cut_into_parts(&order, &last_reader);
    let part_of_position = |i: usize| parts.partition_point(|&start| start <= i) - 1;
    let part_of: HashMap<u32, usize> = order
        .iter()
        .enumerate()
        .map(|(i, &n)| (n, part_of_position(i)))
        .collect();
    // Slots: a value read in a later part than its own occupies a slot from its part to its last
    // reader's part (the returned value to the end); a slot is free again from the part after that.
    // In a long function ([`SPACED_SLOTS_MIN_OPERATIONS`]) each part writes only slots of its own
    // parity (even parts even slots).
    // Slot k belongs to pool k % pools, and part c takes its slots from pool c % pools.
    let pools = if order.len() >= SPACED_SLOTS_MIN_OPERATIONS {
        2
    } else {
        1
    };
    let mut slot: HashMap<u32, usize> = HashMap::new();
    let mut nslots = 0usize;
    {
        let mut free: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
        let mut used = [0usize; 2];
        let mut release_at: Vec<Vec<usize>> = vec![Vec::new(); parts.len() + 1];
        for (c, range) in part_ranges(&parts, order.len()).enumerate() {
            for k in release_at[c].drain(..).rev() {
                free[k % pools].push(k);
            }
            let pool = c % pools;
            for &n in &order[range] {
                let last = if returned == Some(n) {
                    usize::MAX
                } else {
                    match last_reader.get(&n) {
                        Some(&i) if part_of_position(i) > c => part_of_position(i),
                        _ => continue,
                    }
                };
                let k = free[pool].pop().unwrap_or_else(|| {
                    used[pool] += 1;
                    let k = pools * (used[pool] - 1) + pool;
                    nslots = nslots.max(k + 1);
                    k
                });
                slot.insert(n, k);
                if last != usize::MAX {
                    release_at[last + 1].push(k);
                }
            }
        }
    }
    let arg_names: Vec<&str> = args.iter().map(|a| a.name).collect();
    let mut params: Vec<String> = args
        .iter()
        .map(|a| format!("{}: {}", a.name, a.type_text()))
        .collect();
    let mut call_args: Vec<String> = arg_names.iter().map(|a| a.to_string()).collect();
    for out in outputs {
        match out {
            Output::Vector { name, values } => {
                params.push(format!("{name}: &mut [S; {}]", values.len()));
                call_args.push(name.to_string());
            }
            Output::Matrix {
                name, rows, cols, ..
            } => {
                params.push(format!("{name}: &mut [[S; {cols}]; {rows}]"));
                call_args.push(name.to_string());
            }
            Output::Return(_) => {}
        }
    }
    let public_params = params.join(", ");
    if nslots > 0 {
        params.push(format!("s: &mut {}", scratch_type(name)));
        call_args.push("&mut s".to_string());
    }
    let part_params = params.join(", ");
    let part_call_args = call_args.join(", ");

    let mut text = String::new();
    if nslots > 0 {
        writeln!(
            text,
            "    #[allow(non_camel_case_types)]\n    type {} = ({});",
            scratch_type(name),
            "S, ".repeat(nslots).trim_end()
        )
        .unwrap();
    }
    let batched: std::collections::HashSet<u32> = batch.iter().copied().collect();
    let ranges: Vec<_> = part_ranges(&parts, order.len()).collect();
    let part_bodies: Vec<Vec<&str>> = ranges
        .iter()
        .map(|range| names.bodies(order[range.clone()].iter()))
        .collect();
    let part_functions = part_names(name, &part_bodies, taken);
    // Contiguous parts share a module (see `PART_MODULES`), which the parent imports them from. Part
    // text is written one level out and indented as the module's.
    // The parts' statements, one a line, with the runs of structural zeros spread among them.
    let zero_writes = ZeroWrites::of(outputs, order.len());
    let mut bodies: Vec<Vec<String>> = Vec::new();
    for c in 0..ranges.len() {
        let part = Part {
            nodes,
            order: &order[ranges[c].clone()],
            part_of: &part_of,
            index: c,
            slot: &slot,
            destinations: &destinations,
            outputs,
            args,
            batched: &batched,
            angles,
            sin_of,
            cos_of,
            helpers,
            names,
            lanes,
        };
        let mut body = String::new();
        part.write_body(&mut body);
        bodies.push(body.lines().map(str::to_string).collect());
    }
    let zero = constant_text(0.0, lanes);
    let runs = zero_writes
        .runs()
        .iter()
        .map(|run| format!("        {}", run.text(&zero)))
        .collect();
    let mut bodies = crate::zero_stores::spread(bodies, runs).into_iter();
    for (module, members) in part_module_ranges(ranges.len()).enumerate() {
        let module_name = part_module_name(name, module);
        writeln!(text, "    mod {module_name} {{").unwrap();
        writeln!(text, "        #[allow(unused_imports)]").unwrap();
        writeln!(text, "        use super::*;").unwrap();
        for c in members.clone() {
            let mut part_text = String::new();
            write_doc(
                &mut part_text,
                &part_doc(name, c, ranges.len(), &part_bodies[c]),
            );
            writeln!(part_text, "    #[inline(never)]").unwrap();
            writeln!(part_text, "    #[allow(unused_variables, clippy::all)]").unwrap();
            let part_function = &part_functions[c];
            writeln!(
                part_text,
                "    pub(super) fn {part_function}({part_params}) {{"
            )
            .unwrap();
            for line in bodies.next().expect("a body per part") {
                part_text.push_str(&line);
                part_text.push('\n');
            }
            writeln!(part_text, "    }}").unwrap();
            for line in part_text.lines() {
                text.push_str("    ");
                text.push_str(line);
                text.push('\n');
            }
        }
        writeln!(text, "    }}").unwrap();
        // One name without braces (`unused_import_braces`, a lint users may deny).
        match &part_functions[members] {
            [one] => writeln!(text, "    use self::{module_name}::{one};").unwrap(),
            several => {
                let several = several.join(", ");
                writeln!(text, "    use self::{module_name}::{{{several}}};").unwrap()
            }
        }
    }
    // The public function: the parts in order, then the outputs no part computes (constants and
    // inputs passed through), then the returned value.
    let doc = function_doc(doc, &names.bodies(order.iter()), &part_functions);
    write_doc(&mut text, &doc);
    let returns = outputs.iter().any(|o| matches!(o, Output::Return(_)));
    if returns {
        writeln!(text, "    #[must_use = {MUST_USE:?}]").unwrap();
    }
    writeln!(text, "    #[allow(unused_variables, clippy::all)]").unwrap();
    let ret = if returns { " -> S" } else { "" };
    writeln!(text, "    pub fn {name}({public_params}){ret} {{").unwrap();
    // Matrices of too many runs of structural zeros are zeroed whole first (`zero_stores`).
    for out in outputs {
        if let Output::Matrix {
            name: o,
            rows,
            cols,
            ..
        } = out
        {
            if zero_writes.filled().contains(o) {
                writeln!(text, "        *{o} = [[{zero}; {cols}]; {rows}];").unwrap();
            }
        }
    }
    if nslots > 0 {
        writeln!(
            text,
            "        let mut s: {} = ({});",
            scratch_type(name),
            format!("{}, ", constant_text(0.0, lanes))
                .repeat(nslots)
                .trim_end()
        )
        .unwrap();
    }
    for part_function in &part_functions {
        writeln!(text, "        {part_function}({part_call_args});").unwrap();
    }
    let outside = |v: &Sym| -> Option<String> {
        match v {
            Sym::Const(x) => Some(constant_text(*x, lanes)),
            Sym::Node(n) => match nodes[*n as usize] {
                Op::Input { arg, index } => Some(args[arg as usize].entry_text(index)),
                _ => None,
            },
        }
    };
    let mut result = None;
    for out in outputs {
        match out {
            Output::Vector { name: o, values } => {
                for (i, v) in values.iter().enumerate() {
                    if let Some(value) = outside(v) {
                        writeln!(text, "        {o}[{i}] = {value};").unwrap();
                    }
                }
            }
            Output::Matrix {
                name: o,
                cols,
                values,
                ..
            } => {
                let filled = crate::emit::zero_filled(values);
                for (k, v) in values.iter().enumerate() {
                    if filled && crate::emit::is_positive_zero(v) {
                        continue;
                    }
                    if let Some(value) = outside(v) {
                        writeln!(text, "        {o}[{}][{}] = {value};", k / cols, k % cols)
                            .unwrap();
                    }
                }
            }
            Output::Return(v) => {
                result = Some(outside(v).unwrap_or_else(|| match v {
                    Sym::Node(n) => slot_text(slot[n]),
                    Sym::Const(_) => unreachable!("constants are written in place"),
                }));
            }
        }
    }
    if let Some(r) = result {
        writeln!(text, "        {r}").unwrap();
    }
    writeln!(text, "    }}").unwrap();
    text
}

/// Writes `doc` as `///` comment lines. Safe as comment text: the docs are the generator's own, and
/// model names reach them only as escaped code spans, which hold no line break or control character.
fn write_doc(text: &mut String, doc: &str) {
    for line in doc_lines(doc) {
        writeln!(text, "    ///{line}").unwrap();
    }
}

/// The positions of each part, from the first positions `parts`.
fn part_ranges(parts: &[usize], len: usize) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    parts
        .iter()
        .enumerate()
        .map(move |(c, &start)| start..parts.get(c + 1).copied().unwrap_or(len))
}

/// Places the cosine right after the sine of the same angle (or the other way round): the two come
/// from one helper call, so they must be defined in the same part.
fn pair_sines_with_cosines(
    nodes: &[Op],
    order: Vec<u32>,
    sin_of: &HashMap<Sym, u32>,
    cos_of: &HashMap<Sym, u32>,
    batch: &[u32],
) -> Vec<u32> {
    let mut partner: HashMap<u32, u32> = HashMap::new();
    for (a, &s) in sin_of {
        if let Some(&c) = cos_of.get(a) {
            partner.insert(s, c);
            partner.insert(c, s);
        }
    }
    let batched: std::collections::HashSet<u32> = batch.iter().copied().collect();
    let mut placed: std::collections::HashSet<u32> = std::collections::HashSet::new();
    let mut out = Vec::with_capacity(order.len());
    for n in order {
        if !placed.insert(n) {
            continue;
        }
        out.push(n);
        if matches!(nodes[n as usize], Op::Sin(_) | Op::Cos(_)) && !batched.contains(&n) {
            if let Some(&p) = partner.get(&n) {
                if placed.insert(p) {
                    out.push(p);
                }
            }
        }
    }
    out
}

/// Start positions of the parts: each within a quarter of `CHUNK` operations of `CHUNK` long, cut
/// where the fewest computed values are live (defined before the cut and read after it), which on a
/// tree is between bodies rather than inside one.
fn cut_into_parts(order: &[u32], last_reader: &HashMap<u32, usize>) -> Vec<usize> {
    let len = order.len();
    // live[p]: computed values defined before position p and read at p or later (inputs are read in
    // place by every part, so they never cross).
    let mut ending = vec![0usize; len];
    let mut live = vec![0usize; len];
    let mut current = 0usize;
    for (i, &n) in order.iter().enumerate() {
        if i > 0 {
            current -= ending[i - 1];
        }
        live[i] = current;
        if let Some(&r) = last_reader.get(&n) {
            if r > i {
                current += 1;
                ending[r] += 1;
            }
        }
    }
    let mut starts = vec![0usize];
    let mut start = 0usize;
    while len - start > CHUNK + CHUNK / 4 {
        let (lo, hi) = (
            start + CHUNK * 3 / 4,
            (start + CHUNK * 5 / 4).min(len - CHUNK / 4),
        );
        let target = start + CHUNK;
        let cut = (lo..=hi)
            .min_by_key(|&p| (live[p], p.abs_diff(target)))
            .unwrap_or(target);
        starts.push(cut);
        start = cut;
    }
    starts
}

/// One part being written.
struct Part<'a> {
    nodes: &'a [Op],
    order: &'a [u32],
    part_of: &'a HashMap<u32, usize>,
    index: usize,
    slot: &'a HashMap<u32, usize>,
    destinations: &'a HashMap<u32, Vec<Destination>>,
    outputs: &'a [Output],
    args: &'a [Arg],
    batched: &'a std::collections::HashSet<u32>,
    angles: &'a [Sym],
    sin_of: &'a HashMap<Sym, u32>,
    cos_of: &'a HashMap<Sym, u32>,
    helpers: &'a str,
    /// A lane function: constants as `S::splat(…)`, comparisons through `select_gt`.
    lanes: bool,
    names: &'a ValueNames,
}

impl Part<'_> {
    fn is_local(&self, n: u32) -> bool {
        self.part_of.get(&n) == Some(&self.index)
    }

    /// Writes the statements of the part.
    fn write_body(&self, text: &mut String) {
        let nodes = self.nodes;
        // Readers of each value inside this part (an operation reading a value twice counts twice).
        let mut readers: HashMap<u32, u32> = HashMap::new();
        for &n in self.order {
            for o in operands(&nodes[n as usize]) {
                if let Sym::Node(m) = o {
                    *readers.entry(m).or_insert(0) += 1;
                }
            }
        }
        let leaves_part = |n: u32| self.slot.contains_key(&n) || self.destinations.contains_key(&n);
        // How each value is referred to; the size of each inline expression.
        let mut reference: HashMap<u32, Reference> = HashMap::new();
        let mut size: HashMap<u32, u32> = HashMap::new();
        for &n in self.order {
            let mut total = 1u32;
            for o in operands(&nodes[n as usize]) {
                let Sym::Node(m) = o else { continue };
                if reference.contains_key(&m) && self.is_local(m) {
                    continue;
                }
                let single = readers[&m] == 1;
                let r = if !self.is_local(m) || self.batched.contains(&m) {
                    // An input, a value of an earlier part or a batched sine: read in place when read
                    // once, else named once at the top (measured: a name read twice costs rustc less
                    // than two reads of a field).
                    if single {
                        Reference::Access
                    } else {
                        Reference::Name
                    }
                } else if single
                    && !leaves_part(m)
                    && !matches!(nodes[m as usize], Op::Sin(_) | Op::Cos(_))
                    && total + size[&m] <= MAX_EXPRESSION
                {
                    total += size[&m];
                    Reference::Inline
                } else {
                    Reference::Name
                };
                reference.insert(m, r);
            }
            size.insert(n, total);
        }
        // Inputs and values of earlier parts read more than once: named at the top.
        let mut preloads: Vec<u32> = reference
            .iter()
            .filter(|(&m, &r)| r == Reference::Name && !self.is_local(m))
            .map(|(&m, _)| m)
            .collect();
        preloads.sort_unstable();
        for m in preloads {
            writeln!(
                text,
                "        let {} = {};",
                self.names.name(m),
                self.access(m)
            )
            .unwrap();
        }
        let mut batch_written = false;
        let mut sines_written: std::collections::HashSet<u32> = std::collections::HashSet::new();
        for &n in self.order {
            let op = &nodes[n as usize];
            if reference.get(&n) == Some(&Reference::Inline) {
                continue;
            }
            if self.batched.contains(&n) {
                if !batch_written {
                    self.write_batch(text, &reference);
                    batch_written = true;
                }
                continue;
            }
            if let Op::Sin(a) | Op::Cos(a) = op {
                // The pair was placed together: the first of the two writes both.
                if !sines_written.insert(n) {
                    continue;
                }
                let (s, c) = (self.sin_of.get(a).copied(), self.cos_of.get(a).copied());
                sines_written.extend([s, c].into_iter().flatten());
                let name_of = |x: Option<u32>| match x {
                    Some(x) if readers.contains_key(&x) || leaves_part(x) => self.names.name(x),
                    _ => "_".to_string(),
                };
                let (angle, _) = self.operand(a, &reference);
                writeln!(
                    text,
                    "        let ({}, {}) = {}::sincos({angle});",
                    name_of(s),
                    name_of(c),
                    self.helpers
                )
                .unwrap();
                for x in [s, c].into_iter().flatten() {
                    self.write_destinations(text, x, &self.names.name(x));
                }
                continue;
            }
            let (value, _) = self.operation(n, &reference);
            let dests = self.destinations_of(n);
            if !readers.contains_key(&n) && dests.len() == 1 {
                writeln!(text, "        {} = {value};", dests[0]).unwrap();
            } else {
                let id = self.names.name(n);
                writeln!(text, "        let {id} = {value};").unwrap();
                self.write_destinations(text, n, &id);
            }
        }
    }

    fn write_batch(&self, text: &mut String, reference: &HashMap<u32, Reference>) {
        let args: Vec<String> = self
            .angles
            .iter()
            .map(|a| match a {
                Sym::Node(m) => self.expr(*m, reference).0,
                Sym::Const(x) => constant_text(*x, self.lanes),
            })
            .collect();
        writeln!(
            text,
            "        let (sin_batch, cos_batch) = {}::sincos_batch([{}]);",
            self.helpers,
            args.join(", ")
        )
        .unwrap();
        for (k, a) in self.angles.iter().enumerate() {
            for (x, array) in [
                (self.sin_of.get(a), "sin_batch"),
                (self.cos_of.get(a), "cos_batch"),
            ] {
                let Some(&x) = x else { continue };
                let named = reference.get(&x) == Some(&Reference::Name);
                if named || (!reference.contains_key(&x) && self.destinations_of(x).len() > 1) {
                    let id = self.names.name(x);
                    writeln!(text, "        let {id} = {array}[{k}];").unwrap();
                    self.write_destinations(text, x, &id);
                } else {
                    self.write_destinations(text, x, &format!("{array}[{k}]"));
                }
            }
        }
    }

    /// `s[k]`, `qdd[i]`, `m[r][c]`: where value `n` goes besides its name.
    fn destinations_of(&self, n: u32) -> Vec<String> {
        let mut d: Vec<String> = Vec::new();
        if let Some(k) = self.slot.get(&n) {
            d.push(slot_text(*k));
        }
        for dest in self.destinations.get(&n).into_iter().flatten() {
            d.push(match *dest {
                Destination::Vector(o, i) => format!("{}[{i}]", self.output_name(o)),
                Destination::Matrix(o, r, c) => format!("{}[{r}][{c}]", self.output_name(o)),
            });
        }
        d
    }

    fn output_name(&self, o: usize) -> &'static str {
        match &self.outputs[o] {
            Output::Vector { name, .. } | Output::Matrix { name, .. } => name,
            Output::Return(_) => unreachable!("the returned value has a slot"),
        }
    }

    fn write_destinations(&self, text: &mut String, n: u32, value: &str) {
        for d in self.destinations_of(n) {
            writeln!(text, "        {d} = {value};").unwrap();
        }
    }

    /// Reading a value that is not computed in this part: an input, a batched sine, or a slot.
    fn access(&self, m: u32) -> String {
        match self.nodes[m as usize] {
            Op::Input { arg, index } => self.args[arg as usize].entry_text(index),
            Op::Sin(a) | Op::Cos(a) if self.batched.contains(&m) && self.is_local(m) => {
                let k = self
                    .angles
                    .iter()
                    .position(|x| *x == a)
                    .expect("a batched angle");
                let array = if matches!(self.nodes[m as usize], Op::Sin(_)) {
                    "sin_batch"
                } else {
                    "cos_batch"
                };
                format!("{array}[{k}]")
            }
            _ => slot_text(self.slot[&m]),
        }
    }

    /// An operand: its name, its access, or its whole expression; with its binding strength.
    fn expr(&self, m: u32, reference: &HashMap<u32, Reference>) -> (String, u8) {
        match reference.get(&m) {
            Some(Reference::Inline) => self.operation(m, reference),
            Some(Reference::Access) => (self.access(m), ATOM),
            _ => (self.names.name(m), ATOM),
        }
    }

    fn operand(&self, s: &Sym, reference: &HashMap<u32, Reference>) -> (String, u8) {
        match s {
            Sym::Const(x) => {
                let t = constant_text(*x, self.lanes);
                let strength = if t.starts_with('-') { UNARY } else { ATOM };
                (t, strength)
            }
            Sym::Node(m) => self.expr(*m, reference),
        }
    }

    /// The expression of operation `n`, with its binding strength.
    fn operation(&self, n: u32, reference: &HashMap<u32, Reference>) -> (String, u8) {
        let wrap = |(t, strength): (String, u8), at_least: u8| {
            if strength < at_least {
                format!("({t})")
            } else {
                t
            }
        };
        let binary = |a: &Sym, b: &Sym, op: &str, strength: u8| {
            // Left-associative: the left operand may be as weak as the operator, the right must bind
            // tighter (a − (b − c) is not a − b − c, nor is a + (b + c) in floating point).
            let l = wrap(self.operand(a, reference), strength);
            let r = wrap(self.operand(b, reference), strength + 1);
            (format!("{l} {op} {r}"), strength)
        };
        match &self.nodes[n as usize] {
            Op::Add(a, b) => binary(a, b, "+", SUM),
            Op::Sub(a, b) => binary(a, b, "-", SUM),
            Op::Mul(a, b) => binary(a, b, "*", PRODUCT),
            Op::Div(a, b) => binary(a, b, "/", PRODUCT),
            Op::Neg(a) => (
                format!("-{}", wrap(self.operand(a, reference), ATOM)),
                UNARY,
            ),
            Op::Sqrt(a) => (
                format!("{}::sqrt({})", self.helpers, self.operand(a, reference).0),
                ATOM,
            ),
            Op::Abs(a) => (
                format!("{}::abs({})", self.helpers, self.operand(a, reference).0),
                ATOM,
            ),
            Op::Select {
                lhs,
                rhs,
                then,
                otherwise,
            } if self.lanes => (
                format!(
                    "{}::select_gt({}, {}, {}, {})",
                    self.helpers,
                    self.operand(lhs, reference).0,
                    self.operand(rhs, reference).0,
                    self.operand(then, reference).0,
                    self.operand(otherwise, reference).0
                ),
                ATOM,
            ),
            Op::Select {
                lhs,
                rhs,
                then,
                otherwise,
            } => (
                format!(
                    "if {} > {} {{ {} }} else {{ {} }}",
                    wrap(self.operand(lhs, reference), SUM),
                    wrap(self.operand(rhs, reference), SUM),
                    self.operand(then, reference).0,
                    self.operand(otherwise, reference).0
                ),
                CONDITIONAL,
            ),
            Op::Input { .. } | Op::Sin(_) | Op::Cos(_) => (self.access(n), ATOM),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constants_are_written_as_the_token_form_writes_them() {
        // The two forms of emission must print the same literal for every constant (same bits).
        for x in [
            0.5f64,
            3.0,
            1e-300,
            1.7976931348623157e308,
            0.1 + 0.2,
            -0.003887210469140914,
            -2.0,
            5e-324,
        ] {
            let tokens = proc_macro2::Literal::f64_unsuffixed(x.abs()).to_string();
            let text = float_text(x);
            assert_eq!(text.trim_start_matches('-'), tokens, "{x:e}");
            assert_eq!(text.starts_with('-'), x < 0.0);
            assert_eq!(text.parse::<f64>().unwrap().to_bits(), x.to_bits());
        }
        assert_eq!(float_text(-0.0), "-0.0");
    }

    #[test]
    fn scratch_types_are_named_after_their_functions() {
        assert_eq!(scratch_type("aba"), "aba_scratch");
        assert_ne!(scratch_type("frame_x1"), scratch_type("frame_x_1"));
    }
}

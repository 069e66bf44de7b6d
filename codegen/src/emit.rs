//! From a traced tape to Rust: liveness, chunking into small functions (rustc's optimizer is superlinear
//! in function size), and emission with `quote`.

use crate::trace::{Op, Sym, Tape};
use proc_macro2::{Ident, Literal, TokenStream};
use quote::{format_ident, quote};
use std::collections::{HashMap, HashSet};

/// One argument of a generated function: `name: &[S; len]`.
pub struct Arg {
    pub name: &'static str,
    pub len: usize,
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

fn node_ident(n: u32) -> Ident {
    format_ident!("t{}", n)
}

/// Errors of emission (a constant that folded to a non-finite number).
#[derive(Debug)]
pub struct EmitError(pub String);

/// Emits `pub fn name(args…, outputs…)` for one scalar module; `helpers` is the path of the helper module.
pub fn function(
    name: &str,
    doc: &str,
    args: &[Arg],
    outputs: &[Output],
    tape: &Tape,
    helpers: &TokenStream,
) -> Result<TokenStream, EmitError> {
    let nodes = &tape.nodes;
    // Liveness from the outputs.
    let mut live = vec![false; nodes.len()];
    let mut stack: Vec<u32> = Vec::new();
    let mut out_syms: Vec<Sym> = Vec::new();
    for o in outputs {
        let values = match o {
            Output::Vector { values, .. } | Output::Matrix { values, .. } => values,
        };
        out_syms.extend(values.iter().copied());
    }
    for s in &out_syms {
        match s {
            Sym::Node(n) => stack.push(*n),
            Sym::Const(c) if !c.is_finite() => {
                return Err(EmitError(format!(
                    "`{name}`: an output folded to the non-finite constant {c}"
                )))
            }
            _ => {}
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
                    return Err(EmitError(format!("`{name}`: a constant folded to {c}")))
                }
                _ => {}
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
    let chunks: Vec<&[u32]> = if order.is_empty() {
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
        for s in &out_syms {
            if let Sym::Node(x) = s {
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
    let scalar_args: Vec<TokenStream> = args
        .iter()
        .map(|a| {
            let id = format_ident!("{}", a.name);
            let len = a.len;
            quote!(#id: &[S; #len])
        })
        .collect();
    let arg_names: Vec<Ident> = args.iter().map(|a| format_ident!("{}", a.name)).collect();
    let nslots = slot.len().max(1);

    let operand = |s: &Sym| -> TokenStream {
        match s {
            Sym::Const(c) => lit(*c),
            Sym::Node(n) => {
                let id = node_ident(*n);
                quote!(#id)
            }
        }
    };
    let mut chunk_fns = Vec::new();
    let mut bodies = Vec::new();
    for (c, ns) in chunks.iter().enumerate() {
        let mut stmts = Vec::new();
        let mut defined: HashSet<u32> = HashSet::new();
        // Inputs and earlier chunks' values this chunk reads.
        let mut needed: Vec<u32> = Vec::new();
        for &n in ns.iter() {
            for o in operands(&nodes[n as usize]) {
                if let Sym::Node(m) = o {
                    if !ns.contains(&m) && !needed.contains(&m) {
                        needed.push(m);
                    }
                }
            }
        }
        needed.sort_unstable();
        for m in needed {
            let id = node_ident(m);
            match nodes[m as usize] {
                Op::Input { arg, index } => {
                    let a = &arg_names[arg as usize];
                    let i = index as usize;
                    stmts.push(quote!(let #id: S = #a[#i];));
                }
                _ => {
                    let k = slot[&m];
                    stmts.push(quote!(let #id: S = s[#k];));
                }
            }
            defined.insert(m);
        }
        for &n in ns.iter() {
            if defined.contains(&n) {
                continue;
            }
            let id = node_ident(n);
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
                Op::Sin(a) | Op::Cos(a) => {
                    let (s_id, c_id) = (sin_of.get(a).copied(), cos_of.get(a).copied());
                    let x = operand(a);
                    let s_tok = s_id.map_or_else(|| format_ident!("_"), node_ident);
                    let c_tok = c_id.map_or_else(|| format_ident!("_"), node_ident);
                    stmts.push(quote!(let (#s_tok, #c_tok): (S, S) = #helpers::sincos(#x);));
                    if let Some(si) = s_id {
                        defined.insert(si);
                    }
                    if let Some(ci) = c_id {
                        defined.insert(ci);
                    }
                    continue;
                }
            };
            stmts.push(quote!(let #id: S = #expr;));
            defined.insert(n);
        }
        if split {
            for &n in ns.iter() {
                if let Some(k) = slot.get(&n) {
                    let id = node_ident(n);
                    stmts.push(quote!(s[#k] = #id;));
                }
            }
            let fname = format_ident!("{}_part{}", name, c);
            chunk_fns.push(quote! {
                #[inline(never)]
                #[allow(unused_variables, clippy::all)]
                fn #fname(#(#scalar_args,)* s: &mut [S; #nslots]) {
                    #(#stmts)*
                }
            });
        } else {
            bodies.push(stmts);
        }
    }
    // Outputs.
    let mut out_params = Vec::new();
    let mut out_stmts = Vec::new();
    for o in outputs {
        match o {
            Output::Vector {
                name: oname,
                values,
            } => {
                let id = format_ident!("{}", oname);
                let n = values.len();
                out_params.push(quote!(#id: &mut [S; #n]));
                for (i, v) in values.iter().enumerate() {
                    let val = value_tokens(v, split, &slot, &operand, nodes, &arg_names);
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
                out_params.push(quote!(#id: &mut [[S; #cols]; #rows]));
                for r in 0..*rows {
                    for c in 0..*cols {
                        let val = value_tokens(
                            &values[r * cols + c],
                            split,
                            &slot,
                            &operand,
                            nodes,
                            &arg_names,
                        );
                        out_stmts.push(quote!(#id[#r][#c] = #val;));
                    }
                }
            }
        }
    }
    let fname = format_ident!("{}", name);
    let body = if split {
        let calls: Vec<TokenStream> = (0..chunks.len())
            .map(|c| {
                let f = format_ident!("{}_part{}", name, c);
                quote!(#f(#(#arg_names,)* &mut s);)
            })
            .collect();
        quote! {
            let mut s: [S; #nslots] = [0.0; #nslots];
            #(#calls)*
            #(#out_stmts)*
        }
    } else {
        let stmts = bodies.pop().unwrap_or_default();
        quote! {
            #(#stmts)*
            #(#out_stmts)*
        }
    };
    Ok(quote! {
        #(#chunk_fns)*
        #[doc = #doc]
        #[allow(unused_variables, clippy::all)]
        pub fn #fname(#(#scalar_args,)* #(#out_params),*) {
            #body
        }
    })
}

fn value_tokens(
    v: &Sym,
    split: bool,
    slot: &HashMap<u32, usize>,
    operand: &dyn Fn(&Sym) -> TokenStream,
    nodes: &[Op],
    args: &[Ident],
) -> TokenStream {
    match v {
        // An input passed straight through to an output.
        Sym::Node(n) if matches!(nodes[*n as usize], Op::Input { .. }) => {
            let Op::Input { arg, index } = nodes[*n as usize] else {
                unreachable!()
            };
            let a = &args[arg as usize];
            let i = index as usize;
            quote!(#a[#i])
        }
        Sym::Node(n) if split => {
            let k = slot[n];
            quote!(s[#k])
        }
        _ => operand(v),
    }
}

fn operands(op: &Op) -> Vec<Sym> {
    match *op {
        Op::Input { .. } => vec![],
        Op::Add(a, b) | Op::Sub(a, b) | Op::Mul(a, b) | Op::Div(a, b) => vec![a, b],
        Op::Neg(a) | Op::Sqrt(a) | Op::Sin(a) | Op::Cos(a) | Op::Abs(a) => vec![a],
    }
}

//! The bodies of a twinned function's leaves written once, in a module `{function}_shared`, and called
//! by the baseline code and by each of its twins.
//!
//! Why: an AVX twin used to be a second copy of the function's source, and rustc checked, borrow-checked
//! and optimized that copy's MIR a second time. Worse, its MIR inliner only inlines a callee whose target
//! features are those of the caller, so in the twin (`avx`) the pair operations (`PairF64`'s `*`, `+`,
//! no target feature) stayed calls, each passing its 128-bit values through memory, and LLVM spent more
//! than twice as long on the twin as on the baseline copy (promoting those stack slots back into
//! registers: `PromoteMemToReg` alone was a quarter of rustc's time). Measured (2026-12-05, AMD EPYC,
//! 2 cores, release): the floating TALOS's `rnea_derivatives` (21k statements) took 3.4 s to compile
//! alone and 7.4–8.1 s with its twin; with the twin's parts calling the shared bodies, 5.1–5.3 s.
//!
//! How: a leaf (a function that calls no other function of the code: the parts of a long function, or a
//! short function written whole) keeps its signature and attributes, and its body becomes one call of
//! its copy in `{function}_shared`, which carries `#[inline(always)]`. The twin is then made from this
//! code as before: its leaves are the same calls, compiled with the twin's target features, into which
//! LLVM inlines the shared body (a function without target features may be inlined into one with more).
//! So the body is type-checked and borrow-checked once and its MIR optimized once, with the pair
//! operations inlined; LLVM still optimizes it once per copy, for each instruction set. The functions
//! that call others (a long function's public function, which runs its parts in turn) are copied as
//! before: sharing them would inline every part into one function.
//!
//! The calls reach the shared module by `super::` up to the function's code, where the module is
//! declared beside the public function; the twin modules import it with their `use super::*`. Its name
//! takes the family of `{function}_avx` and `{function}_parts_{k}`: a function's name is unique in its
//! scalar module, so no other module can take it.

use crate::emit::Code;
use proc_macro2::{Ident, TokenStream, TokenTree};
use quote::{format_ident, quote};
use std::collections::HashSet;

/// The shared module's name for the code of `function`.
pub fn module_name(function: &str) -> String {
    format!("{function}_shared")
}

/// `code` with its leaves' bodies replaced by calls of their copies in `{function}_shared`, and that
/// module as items of the same kind (tokens or text indented by four spaces), or `None` where the code
/// has no leaf to share.
pub fn share(code: &Code, function: &str) -> Option<(Code, Code)> {
    match code {
        Code::Tokens(tokens) => {
            let (calls, shared) = share_tokens(tokens.clone(), function)?;
            Some((Code::Tokens(calls), Code::Tokens(shared)))
        }
        Code::Text(text) => {
            let (calls, shared) = share_text(text, function)?;
            Some((Code::Text(calls), Code::Text(shared)))
        }
    }
}

/// Whether `tokens` call one of `names`: the name, then parentheses. (Only a call: a parameter or a
/// value may have a function's name, `com` in `com`'s parts, and is never called.)
fn calls_one_of(tokens: TokenStream, names: &HashSet<String>) -> bool {
    let trees: Vec<TokenTree> = tokens.into_iter().collect();
    trees.iter().enumerate().any(|(i, tree)| match tree {
        TokenTree::Ident(ident) => {
            names.contains(&ident.to_string())
                && matches!(trees.get(i + 1), Some(TokenTree::Group(g)) if g.delimiter() == proc_macro2::Delimiter::Parenthesis)
        }
        TokenTree::Group(group) => calls_one_of(group.stream(), names),
        _ => false,
    })
}

/// The names of a signature's parameters, if every one is a plain name (`q`, `mut s`).
fn parameter_names(signature: &syn::Signature) -> Option<Vec<Ident>> {
    signature
        .inputs
        .iter()
        .map(|input| match input {
            syn::FnArg::Typed(typed) => match &*typed.pat {
                syn::Pat::Ident(p) if p.by_ref.is_none() && p.subpat.is_none() => {
                    Some(p.ident.clone())
                }
                _ => None,
            },
            syn::FnArg::Receiver(_) => None,
        })
        .collect()
}

/// The call of a leaf's shared copy from `depth` modules below the code's top: `super::`s up to it,
/// then the shared module and the leaf's `path` of modules.
fn shared_call(depth: usize, module: &str, path: &[String], name: &str, args: &[Ident]) -> String {
    let mut call = "super::".repeat(depth);
    call.push_str(module);
    for m in path {
        call.push_str("::");
        call.push_str(m);
    }
    let args: Vec<String> = args.iter().map(Ident::to_string).collect();
    format!("{call}::{name}({})", args.join(", "))
}

fn collect_token_names(items: &[syn::Item], names: &mut HashSet<String>) {
    for item in items {
        match item {
            syn::Item::Fn(f) => {
                names.insert(f.sig.ident.to_string());
            }
            syn::Item::Mod(m) => {
                if let Some((_, inner)) = &m.content {
                    collect_token_names(inner, names);
                }
            }
            _ => {}
        }
    }
}

/// A function's parameters, if it is a leaf: it calls no function of the code.
fn token_leaf(f: &syn::ItemFn, names: &HashSet<String>) -> Option<Vec<Ident>> {
    let block = &f.block;
    if calls_one_of(quote!(#block), names) {
        return None;
    }
    parameter_names(&f.sig)
}

/// The leaves' bodies among `items` (at `path` below the code's top) replaced by calls; whether any was.
fn calls_in_tokens(
    items: &mut [syn::Item],
    path: &mut Vec<String>,
    names: &HashSet<String>,
    module: &str,
) -> bool {
    let mut any = false;
    for item in items {
        match item {
            syn::Item::Fn(f) => {
                if let Some(args) = token_leaf(f, names) {
                    let call =
                        shared_call(path.len(), module, path, &f.sig.ident.to_string(), &args);
                    let call: syn::Expr = syn::parse_str(&call).expect("a shared call parses");
                    *f.block = syn::parse_quote!({ #call });
                    any = true;
                }
            }
            syn::Item::Mod(m) => {
                if let Some((_, inner)) = &mut m.content {
                    path.push(m.ident.to_string());
                    any |= calls_in_tokens(inner, path, names, module);
                    path.pop();
                }
            }
            _ => {}
        }
    }
    any
}

/// Whether an item imports from the code's own modules (`use self::aba_parts_0::aba_part;`): the shared
/// module leaves those out, for its functions call none, and an import of a function it does not hold
/// would reach the code's private import through `use super::*` (E0603).
fn imports_own_items(item: &syn::Item) -> bool {
    matches!(item, syn::Item::Use(u) if matches!(&u.tree, syn::UseTree::Path(p) if p.ident == "self"))
}

/// The shared module's items: the leaves, `#[inline(always)]` and visible to the code; the functions that
/// call others and the imports of the code's own functions left out; modules visible to the code.
fn shared_tokens(items: Vec<syn::Item>, names: &HashSet<String>) -> Vec<syn::Item> {
    let crate_visible: syn::Visibility = syn::parse_quote!(pub(crate));
    items
        .into_iter()
        .filter(|item| !imports_own_items(item))
        .filter_map(|item| match item {
            syn::Item::Fn(mut f) => {
                token_leaf(&f, names)?;
                f.vis = crate_visible.clone();
                f.attrs
                    .retain(|a| !a.path().is_ident("inline") && !a.path().is_ident("doc"));
                f.attrs.push(syn::parse_quote!(#[inline(always)]));
                Some(syn::Item::Fn(f))
            }
            syn::Item::Mod(mut m) => {
                m.vis = crate_visible.clone();
                if let Some((brace, inner)) = m.content.take() {
                    m.content = Some((brace, shared_tokens(inner, names)));
                }
                Some(syn::Item::Mod(m))
            }
            other => Some(other),
        })
        .collect()
}

fn share_tokens(tokens: TokenStream, function: &str) -> Option<(TokenStream, TokenStream)> {
    let file: syn::File = syn::parse2(tokens).expect("generated code parses as items");
    let mut names = HashSet::new();
    collect_token_names(&file.items, &mut names);
    let module = module_name(function);
    let mut calls = file.items.clone();
    if !calls_in_tokens(&mut calls, &mut Vec::new(), &names, &module) {
        return None;
    }
    let shared = shared_tokens(file.items, &names);
    let module = format_ident!("{}", module);
    Some((
        quote!(#(#calls)*),
        quote! {
            /// The bodies of the functions above that call no other, written once for them and their
            /// twins (`#[inline(always)]`: each copy compiles the body for its own instruction set).
            #[allow(dead_code, unused_imports, unused_variables, clippy::all)]
            mod #module {
                use super::*;
                #(#shared)*
            }
        },
    ))
}

/// A function item of text starting at a line: where its signature ends (the first line at its
/// indentation that ends with `{`, as `dispatch` reads them) and its closing line.
struct TextFunction {
    name: String,
    signature_end: usize,
    close: usize,
    /// Its parameters, if it is a leaf.
    leaf: Option<Vec<Ident>>,
}

/// The name a trimmed `fn` line declares.
fn declared_name(trimmed: &str) -> Option<&str> {
    let after = &trimmed[trimmed.find("fn ")? + 3..];
    let end = after.find(|c: char| !(c.is_alphanumeric() || c == '_'))?;
    Some(&after[..end])
}

/// Whether a trimmed line opens a module (`mod m {`, with a visibility or none).
fn opened_module(trimmed: &str) -> Option<&str> {
    let rest = ["mod ", "pub mod ", "pub(super) mod ", "pub(crate) mod "]
        .iter()
        .find_map(|p| trimmed.strip_prefix(p))?;
    rest.strip_suffix(" {")
}

/// Whether a line of text calls one of `names`: the name (identifiers of ASCII letters, digits and `_`,
/// as the generator writes them), then `(`, as in [`calls_one_of`].
fn text_calls_one_of(line: &str, names: &HashSet<String>) -> bool {
    let bytes = line.as_bytes();
    let word = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    let mut i = 0;
    while i < bytes.len() {
        if word(bytes[i]) {
            let start = i;
            while i < bytes.len() && word(bytes[i]) {
                i += 1;
            }
            if bytes.get(i) == Some(&b'(') && names.contains(&line[start..i]) {
                return true;
            }
        } else {
            i += 1;
        }
    }
    false
}

/// The signature of lines `start..=end` as syn reads it: without visibility and the opening brace.
fn text_signature(lines: &[&str], start: usize, end: usize) -> Option<syn::Signature> {
    let joined: String = lines[start..=end]
        .iter()
        .map(|l| l.trim())
        .collect::<Vec<_>>()
        .join(" ");
    let joined = joined.trim_end().strip_suffix('{')?.trim_end();
    syn::parse_str(without_visibility(joined)).ok()
}

/// A trimmed item line without its visibility (`pub`, `pub(super)`, `pub(crate)`, as the emitters
/// write them).
fn without_visibility(trimmed: &str) -> &str {
    ["pub(super) ", "pub(crate) ", "pub "]
        .iter()
        .find_map(|p| trimmed.strip_prefix(p))
        .unwrap_or(trimmed)
}

fn text_function(lines: &[&str], i: usize, names: &HashSet<String>) -> Option<TextFunction> {
    let line = lines[i];
    let trimmed = line.trim_start();
    let indent = &line[..line.len() - trimmed.len()];
    let name = declared_name(trimmed)?.to_string();
    let signature_end = (i..lines.len())
        .find(|&j| lines[j].starts_with(indent) && lines[j].trim_end().ends_with('{'))?;
    let closing = format!("{indent}}}");
    let close = (signature_end + 1..lines.len()).find(|&k| lines[k] == closing)?;
    let leaf = text_signature(lines, i, signature_end).and_then(|signature| {
        let body = &lines[signature_end + 1..close];
        if body.iter().any(|l| text_calls_one_of(l, names)) {
            None
        } else {
            parameter_names(&signature)
        }
    });
    Some(TextFunction {
        name,
        signature_end,
        close,
        leaf,
    })
}

/// Whether a trimmed line is an attribute or a doc comment (what precedes a function item).
fn attribute_line(trimmed: &str) -> bool {
    trimmed.starts_with("#[") || trimmed.starts_with("///")
}

fn share_text(text: &str, function: &str) -> Option<(String, String)> {
    let lines: Vec<&str> = text.lines().collect();
    let names: HashSet<String> = lines
        .iter()
        .map(|l| l.trim_start())
        .filter(|t| crate::dispatch::starts_function(t))
        .filter_map(declared_name)
        .map(str::to_string)
        .collect();
    let module = module_name(function);
    let mut calls = String::with_capacity(text.len() / 4);
    let mut shared: Vec<String> = Vec::with_capacity(lines.len());
    // The modules open at each point, with their indentation.
    let mut path: Vec<(String, String)> = Vec::new();
    let mut any = false;
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let trimmed = line.trim_start();
        let indent = &line[..line.len() - trimmed.len()];
        if let Some((open_indent, _)) = path.last() {
            if trimmed == "}" && indent == open_indent {
                path.pop();
            }
        }
        if trimmed.starts_with("use self::") {
            // An import of the code's own functions: not in the shared module (`imports_own_items`).
            loop {
                calls.push_str(lines[i]);
                calls.push('\n');
                i += 1;
                if lines[i - 1].trim_end().ends_with(';') || i == lines.len() {
                    break;
                }
            }
            continue;
        }
        if let Some(m) = opened_module(trimmed) {
            path.push((indent.to_string(), m.to_string()));
            calls.push_str(line);
            calls.push('\n');
            shared.push(format!("{indent}pub(crate) mod {m} {{"));
            i += 1;
            continue;
        }
        if crate::dispatch::starts_function(trimmed) {
            if let Some(f) = text_function(&lines, i, &names) {
                // Its attributes and docs, already copied to the shared module's lines.
                let mut attributes = Vec::new();
                while shared
                    .last()
                    .is_some_and(|l| l.starts_with(indent) && attribute_line(l.trim_start()))
                {
                    attributes.push(shared.pop().expect("a line"));
                }
                attributes.reverse();
                let signature = &lines[i..=f.signature_end];
                for l in signature {
                    calls.push_str(l);
                    calls.push('\n');
                }
                if let Some(args) = &f.leaf {
                    any = true;
                    let modules: Vec<String> = path.iter().map(|(_, m)| m.clone()).collect();
                    let call = shared_call(path.len(), &module, &modules, &f.name, args);
                    calls.push_str(&format!("{indent}    {call}\n{indent}}}\n"));
                    shared.extend(attributes.into_iter().filter(|a| {
                        let a = a.trim_start();
                        !a.starts_with("#[inline") && !a.starts_with("///")
                    }));
                    shared.push(format!("{indent}#[inline(always)]"));
                    let first = without_visibility(signature[0].trim_start());
                    shared.push(format!("{indent}pub(crate) {first}"));
                    shared.extend(signature[1..].iter().map(|l| l.to_string()));
                    shared.extend(
                        lines[f.signature_end + 1..=f.close]
                            .iter()
                            .map(|l| l.to_string()),
                    );
                } else {
                    for l in &lines[f.signature_end + 1..=f.close] {
                        calls.push_str(l);
                        calls.push('\n');
                    }
                }
                i = f.close + 1;
                continue;
            }
        }
        calls.push_str(line);
        calls.push('\n');
        shared.push(line.to_string());
        i += 1;
    }
    if !any {
        return None;
    }
    let mut out = String::with_capacity(text.len());
    out.push_str(&format!(
        "    /// The bodies of the functions above that call no other, written once for them and their twins\n    /// (`#[inline(always)]`: each copy compiles the body for its own instruction set).\n    #[allow(dead_code, unused_imports, unused_variables, clippy::all)]\n    mod {module} {{\n        use super::*;\n"
    ));
    for l in shared {
        if !l.is_empty() {
            out.push_str("    ");
        }
        out.push_str(&l);
        out.push('\n');
    }
    out.push_str("    }\n");
    Some((calls, out))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The parts of a long function (text, as `emit_large` writes it): each part's body moves to the shared
    /// module, `#[inline(always)]` and visible to the code, and the part calls it; the public function,
    /// which calls the parts, stays as it is and has no shared copy.
    #[test]
    fn text_parts_call_their_shared_bodies_and_the_caller_stays() {
        let text = "    mod g_parts_0 {\n        #[allow(unused_imports)]\n        use super::*;\n        /// Part 1.\n        #[inline(never)]\n        pub(super) fn g_part(q: &[S; 2], s: &mut [S; 1]) {\n            let a = q[0] * q[1];\n            s[0] = a;\n        }\n    }\n    use self::g_parts_0::g_part;\n    /// Doc.\n    pub fn g(\n        q: &[S; 2],\n        out: &mut [[S; 1]; 1],\n    ) {\n        let mut s: [S; 1] = [0.0; 1];\n        g_part(q, &mut s);\n        out[0][0] = s[0];\n    }\n";
        let Some((Code::Text(calls), Code::Text(shared))) = share(&Code::Text(text.into()), "g")
        else {
            panic!("text has a leaf to share")
        };
        let expected_calls = "    mod g_parts_0 {\n        #[allow(unused_imports)]\n        use super::*;\n        /// Part 1.\n        #[inline(never)]\n        pub(super) fn g_part(q: &[S; 2], s: &mut [S; 1]) {\n            super::g_shared::g_parts_0::g_part(q, s)\n        }\n    }\n    use self::g_parts_0::g_part;\n    /// Doc.\n    pub fn g(\n        q: &[S; 2],\n        out: &mut [[S; 1]; 1],\n    ) {\n        let mut s: [S; 1] = [0.0; 1];\n        g_part(q, &mut s);\n        out[0][0] = s[0];\n    }\n";
        assert_eq!(calls, expected_calls);
        assert!(shared.contains("    mod g_shared {\n"), "{shared}");
        assert!(
            shared.contains("        pub(crate) mod g_parts_0 {\n"),
            "{shared}"
        );
        assert!(
            shared.contains("            #[inline(always)]\n            pub(crate) fn g_part(q: &[S; 2], s: &mut [S; 1]) {\n                let a = q[0] * q[1];\n                s[0] = a;\n            }\n"),
            "{shared}"
        );
        assert!(!shared.contains("inline(never)"), "{shared}");
        assert!(
            !shared.contains("fn g("),
            "the caller is not shared: {shared}"
        );
        syn::parse_str::<syn::File>(&format!("{calls}{shared}")).unwrap();
    }

    /// A short function written whole is a leaf: its body moves, its signature and the call stay; code
    /// whose functions all call others has nothing to share.
    #[test]
    fn tokens_whole_functions_are_leaves() {
        let code = quote! {
            /// Doc.
            pub fn f(q: &[S; 2], out: &mut [S; 1]) -> S { out[0] = q[0] * q[1]; out[0] }
        };
        let Some((Code::Tokens(calls), Code::Tokens(shared))) = share(&Code::Tokens(code), "f")
        else {
            panic!("a whole function is a leaf")
        };
        let calls = crate::generate::format_tokens(&calls).unwrap();
        assert!(
            calls.contains(
                "pub fn f(q: &[S; 2], out: &mut [S; 1]) -> S {\n    f_shared::f(q, out)\n}"
            ),
            "{calls}"
        );
        let shared = crate::generate::format_tokens(&shared).unwrap();
        assert!(shared.contains("mod f_shared {"), "{shared}");
        assert!(
            shared.contains("#[inline(always)]\n    pub(crate) fn f(q: &[S; 2], out: &mut [S; 1]) -> S {\n        out[0] = q[0] * q[1];\n        out[0]\n    }"),
            "{shared}"
        );
        // Mutual calls only: nothing to share. A pattern that is not a plain name: not a leaf.
        let callers = quote! {
            pub fn a(q: &[S; 1]) { b(q) }
            pub fn b(q: &[S; 1]) { a(q) }
        };
        assert!(share(&Code::Tokens(callers), "a").is_none());
        let pattern = quote! {
            pub fn c((x, y): (S, S)) -> S { x * y }
        };
        assert!(share(&Code::Tokens(pattern), "c").is_none());
    }

    /// A part is a leaf though a parameter has the function's name (`com`'s output `com`) and a value
    /// another part's name (a joint `aba_l1_to_x` of link `x`, whose cosine is `aba_l1_to_x_q_cos`, the
    /// name of a part): only calls count (an attacker's trial, where such parts stayed out of the shared
    /// module and its copy of their import failed with E0603). A part that does call another stays out,
    /// and the shared module imports none of the code's functions.
    #[test]
    fn only_calls_make_a_function_a_caller_and_the_shared_module_imports_none() {
        let text = "    mod com_parts_0 {\n        #[allow(unused_imports)]\n        use super::*;\n        #[inline(never)]\n        pub(super) fn com_part0(q: &[S; 2], com: &mut [S; 3], s: &mut [S; 1]) {\n            let com_part1_q_cos = q[0];\n            com[0] = com_part1_q_cos;\n            s[0] = q[1];\n        }\n        #[inline(never)]\n        pub(super) fn com_part1(q: &[S; 2], com: &mut [S; 3], s: &mut [S; 1]) {\n            com[1] = s[0] * q[0];\n        }\n        #[inline(never)]\n        pub(super) fn com_part2(q: &[S; 2], com: &mut [S; 3], s: &mut [S; 1]) {\n            com_part1(q, com, s);\n        }\n    }\n    use self::com_parts_0::{com_part0, com_part1,\n        com_part2};\n    pub fn com(q: &[S; 2], com: &mut [S; 3]) {\n        let mut s: [S; 1] = [0.0; 1];\n        com_part0(q, com, &mut s);\n        com_part2(q, com, &mut s);\n    }\n";
        let Some((Code::Text(calls), Code::Text(shared))) = share(&Code::Text(text.into()), "com")
        else {
            panic!("text has leaves to share")
        };
        for leaf in ["com_part0", "com_part1"] {
            assert!(
                calls.contains(&format!(
                    "super::com_shared::com_parts_0::{leaf}(q, com, s)"
                )),
                "{calls}"
            );
            assert!(
                shared.contains(&format!("pub(crate) fn {leaf}(")),
                "{shared}"
            );
        }
        assert!(
            calls.contains("            com_part1(q, com, s);\n"),
            "{calls}"
        );
        assert!(!shared.contains("fn com_part2("), "{shared}");
        assert!(!shared.contains("use self::"), "{shared}");
        syn::parse_str::<syn::File>(&format!("{calls}{shared}")).unwrap();

        let tokens = quote! {
            mod f_parts_0 {
                use super::*;
                pub(super) fn f_part(q: &[S; 2], f: &mut [S; 1]) { let f_caller = q[0]; f[0] = f_caller; }
                pub(super) fn f_caller(q: &[S; 2], f: &mut [S; 1]) { f_part(q, f) }
            }
            use self::f_parts_0::{f_caller, f_part};
            pub fn f(q: &[S; 2], f: &mut [S; 1]) { f_caller(q, f) }
        };
        let Some((_, Code::Tokens(shared))) = share(&Code::Tokens(tokens), "f") else {
            panic!("f_part is a leaf")
        };
        let shared = crate::generate::format_tokens(&shared).unwrap();
        assert!(shared.contains("pub(crate) fn f_part("), "{shared}");
        assert!(!shared.contains("fn f_caller("), "{shared}");
        assert!(!shared.contains("use self::"), "{shared}");
    }

    /// With its twin, a leaf's AVX copy calls the same shared body, which is written once.
    #[test]
    fn a_twin_calls_the_bodies_the_baseline_code_calls() {
        let text = "    mod h_parts_0 {\n        #[allow(unused_imports)]\n        use super::*;\n        #[inline(never)]\n        pub(super) fn h_part(q: &[S; 2], s: &mut [S; 1]) {\n            s[0] = q[0] + q[1];\n        }\n    }\n    use self::h_parts_0::h_part;\n    pub fn h(q: &[S; 2], out: &mut [S; 1]) {\n        h_part(q, out);\n    }\n";
        let helpers = quote!(crate::helpers);
        let Code::Text(out) = crate::dispatch::with_avx_twin(
            &Code::Text(text.into()),
            "h",
            &helpers,
            crate::dispatch::TwinOf::Scalar { avx512: false },
        ) else {
            panic!("text stays text")
        };
        syn::parse_str::<syn::File>(&out).unwrap();
        assert_eq!(out.matches("q[0] + q[1]").count(), 1, "{out}");
        assert_eq!(
            out.matches("super::h_shared::h_parts_0::h_part(q, s)")
                .count(),
            2,
            "{out}"
        );
        let twin = out.find("mod h_avx {").unwrap();
        let shared = out.find("mod h_shared {").unwrap();
        assert!(twin < shared, "{out}");
        assert!(!out[shared..].contains("target_feature"), "{out}");
        assert_eq!(
            out.matches("h_part(q, out);").count(),
            2,
            "the caller is copied: {out}"
        );
    }
}

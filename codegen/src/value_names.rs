//! What generated code calls its values and its parts: the names the traced algorithm gave
//! ([`Real::named`](embedyn_runtime::Real::named), kept in [`Tape::labels`]) made into Rust identifiers.
//!
//! A value the algorithm named is `owner_quantity[_component]` (`thigh_v_ang_x`, `knee_d_inv`), the
//! owner (a body or joint name, hostile data) through the one sanitizer [`identifier`]; the sine and
//! cosine of a named angle are `knee_q_sin`, `knee_q_cos`; a negated named value is `…_neg`; any other
//! value keeps its tape number (`t123`). Names are unique within a function (a repeated name gets
//! `_2`, `_3`, …) and never one of the function's own names (arguments, outputs, scratch). Naming only
//! reads the tape: the operations and their order are the same with or without names.

use crate::names::identifier;
use crate::trace::{Label, Op, Sym, Tape};
use std::collections::{HashMap, HashSet};

/// The body each owner (a body or a joint name) belongs to: a body to itself, a joint to the body it
/// moves; as the body's position in the model and its name. Names that are neither come after every
/// body, as themselves.
#[derive(Clone, Debug, Default)]
pub struct Owners {
    body_of: HashMap<String, (usize, String)>,
}

impl Owners {
    /// From the model's joints and bodies (joint `i` moves body `i`); a body's own name wins over a
    /// joint of the same name.
    pub fn new<'a>(
        joints: impl IntoIterator<Item = &'a str>,
        bodies: impl IntoIterator<Item = &'a str> + Clone,
    ) -> Owners {
        let mut body_of: HashMap<String, (usize, String)> = HashMap::new();
        for (i, (joint, body)) in joints.into_iter().zip(bodies.clone()).enumerate() {
            body_of.insert(joint.to_string(), (i, body.to_string()));
        }
        for (i, body) in bodies.into_iter().enumerate() {
            body_of.insert(body.to_string(), (i, body.to_string()));
        }
        Owners { body_of }
    }

    /// Also `links`, each as the body (by its position in the model) it rides on, where no body or
    /// joint has its name (named inputs of a link: `lf_foot_f_ext_fx`).
    pub fn with_links<'a>(
        mut self,
        links: impl IntoIterator<Item = (&'a str, usize)>,
        bodies: &[&str],
    ) -> Owners {
        for (link, b) in links {
            if let Some(body) = bodies.get(b) {
                self.body_of
                    .entry(link.to_string())
                    .or_insert_with(|| (b, body.to_string()));
            }
        }
        self
    }

    fn body(&self, owner: &str) -> (usize, String) {
        self.body_of
            .get(owner)
            .cloned()
            .unwrap_or_else(|| (usize::MAX, owner.to_string()))
    }
}

/// The names of one function's values.
pub(crate) struct ValueNames {
    names: HashMap<u32, String>,
    /// The body of each named value: its position in the model and its name as the model spells it.
    body: HashMap<u32, (usize, String)>,
}

/// The sanitized form of an owner, for identifiers (`"b"` starts a name that does not start with a
/// letter).
fn owner_identifier(owner: &str, cache: &mut HashMap<String, String>) -> String {
    cache
        .entry(owner.to_string())
        .or_insert_with(|| identifier(owner, "b"))
        .clone()
}

impl ValueNames {
    /// Names the nodes `live` (in tape order, so that a name reads the names of its operands) of
    /// `tape`; `reserved` are the identifiers the function uses for other things.
    pub(crate) fn new(tape: &Tape, live: &[u32], reserved: &[&str], owners: &Owners) -> ValueNames {
        let mut used: HashSet<String> = reserved.iter().map(|r| r.to_string()).collect();
        let mut names: HashMap<u32, String> = HashMap::new();
        let mut body: HashMap<u32, (usize, String)> = HashMap::new();
        let mut cache: HashMap<String, String> = HashMap::new();
        let mut sorted = live.to_vec();
        sorted.sort_unstable();
        for n in sorted {
            let derived = |suffix: &str, x: &Sym| match x {
                Sym::Node(m) => names.get(m).map(|name| format!("{name}_{suffix}")),
                Sym::Const(_) => None,
            };
            let label = tape.labels.get(&n);
            let base = match (&tape.nodes[n as usize], label) {
                (Op::Sin(x), _) if derived("sin", x).is_some() => derived("sin", x),
                (Op::Cos(x), _) if derived("cos", x).is_some() => derived("cos", x),
                (_, Some(label)) => Some(labelled(label, &mut cache)),
                (Op::Neg(x), None) => derived("neg", x),
                _ => None,
            };
            let Some(base) = base else { continue };
            let mut name = base.clone();
            let mut k = 2;
            while !used.insert(name.clone()) {
                name = format!("{base}_{k}");
                k += 1;
            }
            names.insert(n, name);
            if let Some(label) = label {
                body.insert(n, owners.body(&label.owner));
            }
        }
        ValueNames { names, body }
    }

    /// The identifier of value `n`.
    pub(crate) fn name(&self, n: u32) -> String {
        self.names
            .get(&n)
            .cloned()
            .unwrap_or_else(|| format!("t{n}"))
    }

    /// The bodies whose named values are among `nodes`, in the model's order.
    pub(crate) fn bodies<'a>(&'a self, nodes: impl IntoIterator<Item = &'a u32>) -> Vec<&'a str> {
        let mut covered: Vec<&(usize, String)> =
            nodes.into_iter().filter_map(|n| self.body.get(n)).collect();
        covered.sort_unstable();
        covered.dedup();
        covered.into_iter().map(|(_, name)| name.as_str()).collect()
    }
}

/// `owner_quantity[_component]` of a label.
fn labelled(label: &Label, cache: &mut HashMap<String, String>) -> String {
    let owner = owner_identifier(&label.owner, cache);
    if label.component.is_empty() {
        format!("{owner}_{}", label.quantity)
    } else {
        format!("{owner}_{}_{}", label.quantity, label.component)
    }
}

/// The names of a function's parts, from the bodies each part covers: `aba_thigh_to_foot`, `aba_base`
/// (one body), `aba_part3` (no named value); distinct from every name in `taken` — the module's public
/// functions and the parts named before — which they join (a taken name gets `_2`, …). Without the
/// module-wide set, a body named `ext` would give `aba` a part `aba_ext`, the public function's name.
pub(crate) fn part_names(
    function: &str,
    bodies: &[Vec<&str>],
    taken: &mut HashSet<String>,
) -> Vec<String> {
    let mut cache: HashMap<String, String> = HashMap::new();
    let used = taken;
    bodies
        .iter()
        .enumerate()
        .map(|(c, covered)| {
            let base = match (covered.first(), covered.last()) {
                (Some(first), Some(last)) if first == last => {
                    format!("{function}_{}", owner_identifier(first, &mut cache))
                }
                (Some(first), Some(last)) => format!(
                    "{function}_{}_to_{}",
                    owner_identifier(first, &mut cache),
                    owner_identifier(last, &mut cache)
                ),
                _ => format!("{function}_part{c}"),
            };
            let mut name = base.clone();
            let mut k = 2;
            while !used.insert(name.clone()) {
                name = format!("{base}_{k}");
                k += 1;
            }
            name
        })
        .collect()
}

/// The doc line listing bodies: `` `base`, `thigh`, `shin` `` (names shown as escaped code spans).
pub(crate) fn body_list(bodies: &[&str]) -> String {
    bodies
        .iter()
        .map(|b| crate::names::code_span(b))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::{input, record};
    use embedyn_runtime::Real;

    /// Labels become identifiers made by the sanitizer, unique, never a reserved name; hostile owners
    /// stay valid identifiers; unnamed values keep their tape number.
    #[test]
    fn names_are_distinct_identifiers() {
        let (nodes, tape) = record(|| {
            let q = input(0, 0).named("knee", "q", "");
            let (s, c) = (q.sin(), q.cos());
            let a = (s * c).named("Thigh", "v", "ang_x");
            let b = (s + c).named("thigh", "v", "ang_x");
            let e = (s - c).named("x\"\n*/ fn", "v", "");
            let f = (a * b).named("fn", "s", "");
            let g = a / b;
            [q, s, c, a, b, e, f, g]
        });
        let live: Vec<u32> = nodes
            .iter()
            .map(|s| match s {
                Sym::Node(n) => *n,
                Sym::Const(_) => unreachable!(),
            })
            .collect();
        let owners = Owners::new(["knee"], ["thigh"]);
        let names = ValueNames::new(&tape, &live, &["q", "knee_q_sin"], &owners);
        let all: Vec<String> = live.iter().map(|&n| names.name(n)).collect();
        assert_eq!(
            all[..5],
            [
                "knee_q",
                "knee_q_sin_2",
                "knee_q_cos",
                "thigh_v_ang_x",
                "thigh_v_ang_x_2"
            ],
            "a reserved name is not reused, a repeated one is numbered"
        );
        assert_eq!(all[7], format!("t{}", live[7]));
        for name in &all {
            assert!(syn::parse_str::<syn::Ident>(name).is_ok(), "{name}");
        }
        let distinct: HashSet<&String> = all.iter().collect();
        assert_eq!(distinct.len(), all.len());
        // The model's bodies in its order, then other owners (by name).
        assert_eq!(names.bodies(&live), ["thigh", "Thigh", "fn", "x\"\n*/ fn"]);
    }

    #[test]
    fn parts_are_named_after_their_bodies() {
        // The module's public functions are taken: a body named `ext` must not give `aba` a part called
        // `aba_ext` (attacker trial, issue 11).
        let mut taken: HashSet<String> = ["aba", "aba_ext"].map(String::from).into();
        let names = part_names(
            "aba",
            &[
                vec!["base", "Thigh"],
                vec!["foot"],
                vec![],
                vec!["foot"],
                vec!["ext"],
            ],
            &mut taken,
        );
        assert_eq!(
            names,
            [
                "aba_base_to_thigh",
                "aba_foot",
                "aba_part2",
                "aba_foot_2",
                "aba_ext_2"
            ]
        );
        // And a later function's parts avoid the earlier ones'.
        let later = part_names("aba_ext", &[vec!["foot"]], &mut taken);
        assert_eq!(later, ["aba_ext_foot"]);
        assert!(taken.contains("aba_ext_2"));
    }
}

//! Pairs of isomorphic branches computed side by side: a robot's left and right legs (or front and hind,
//! or its arms) go through the same operations on different numbers, so generated code computes each
//! step of two such branches with one two-lane SIMD instruction (the helpers' `Float::Pair`: one SSE2
//! register on x86-64).
//!
//! Which values pair is decided on the tape, not assumed from the model: the model only proposes seeds
//! (the coordinates of corresponding joints of two sibling subtrees of the same shape, [`BranchPairs`]),
//! and [`find`] pairs two operations only where they are the same operation on operands that pair in
//! turn, are the same value, or are both constants. So any pairing is exact: each lane does the scalar
//! code's IEEE operation on the scalar code's operands, and the results are bit-identical. Where the
//! branches differ (a joint axis flipped, an offset folded to zero on one side) the differing values
//! simply stay scalar.

use crate::trace::{Op, Sym};
use embedyn_runtime::Model;
use embedyn_runtime::Real;
use std::collections::HashMap;

/// Corresponding coordinates of the model's isomorphic sibling branches: `q` indices and `v` indices,
/// first branch then second.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BranchPairs {
    /// Pairs of `q` indices.
    pub q: Vec<(u32, u32)>,
    /// Pairs of `v` indices.
    pub v: Vec<(u32, u32)>,
    /// Length of `q`, for recognizing a configuration argument.
    pub nq: usize,
    /// Length of `v`, for recognizing a velocity-like argument.
    pub nv: usize,
}

impl BranchPairs {
    /// From the kinematic tree: children of one parent (or roots) whose subtrees have the same shape
    /// (joint types and the same shape below, child by child) pair up in order of appearance; inside a
    /// pair the joints correspond one to one. Unpaired subtrees are searched for pairs further down.
    pub fn of<T: Real>(model: &Model<T>) -> BranchPairs {
        let n = model.joints.len();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        let mut roots = Vec::new();
        for (i, j) in model.joints.iter().enumerate() {
            match j.parent {
                Some(p) => children[p].push(i),
                None => roots.push(i),
            }
        }
        // Shape of each subtree, as an interned number (children are after their parent).
        let mut shape = vec![0usize; n];
        let mut shapes: HashMap<(String, Vec<usize>), usize> = HashMap::new();
        for i in (0..n).rev() {
            let key = (
                format!("{:?}", model.joints[i].joint_type),
                children[i].iter().map(|&c| shape[c]).collect::<Vec<_>>(),
            );
            let next = shapes.len();
            shape[i] = *shapes.entry(key).or_insert(next);
        }
        let mut pairs = BranchPairs {
            nq: model.nq(),
            nv: model.nv(),
            ..BranchPairs::default()
        };
        let mut stack = vec![roots];
        while let Some(siblings) = stack.pop() {
            let mut open: Vec<usize> = Vec::new();
            for &c in &siblings {
                match open.iter().position(|&o| shape[o] == shape[c]) {
                    Some(k) => {
                        let a = open.remove(k);
                        pairs.add_subtrees(model, &children, a, c);
                    }
                    None => open.push(c),
                }
            }
            for c in open {
                stack.push(children[c].clone());
            }
        }
        pairs
    }

    fn add_subtrees<T: Real>(
        &mut self,
        model: &Model<T>,
        children: &[Vec<usize>],
        a: usize,
        b: usize,
    ) {
        let (ja, jb) = (&model.joints[a], &model.joints[b]);
        for k in 0..ja.nq() {
            self.q
                .push(((ja.q_index + k) as u32, (jb.q_index + k) as u32));
        }
        for k in 0..ja.nv() {
            self.v
                .push(((ja.v_index + k) as u32, (jb.v_index + k) as u32));
        }
        for (&ca, &cb) in children[a].iter().zip(&children[b]) {
            self.add_subtrees(model, children, ca, cb);
        }
    }

    /// The seeds on a tape: pairs of input nodes of corresponding coordinates, for each argument as long
    /// as `q` (configuration) or `v` (velocities, torques, accelerations). `arg_lens[a]` is the number of
    /// entries of argument `a` (matrices and single numbers: `None`, never seeded).
    pub(crate) fn seeds(&self, nodes: &[Op], arg_lens: &[Option<usize>]) -> Vec<(u32, u32)> {
        let mut input: HashMap<(u8, u32), u32> = HashMap::new();
        for (n, op) in nodes.iter().enumerate() {
            if let Op::Input { arg, index } = *op {
                input.insert((arg, index), n as u32);
            }
        }
        let mut seeds = Vec::new();
        for (arg, len) in arg_lens.iter().enumerate() {
            let table = match len {
                Some(l) if *l == self.nq => &self.q,
                Some(l) if *l == self.nv => &self.v,
                _ => continue,
            };
            for &(i, j) in table {
                if let (Some(&a), Some(&b)) =
                    (input.get(&(arg as u8, i)), input.get(&(arg as u8, j)))
                {
                    seeds.push((a, b));
                }
            }
        }
        seeds
    }
}

/// Which live values of a tape are computed as pairs: `second[a] = b` puts `a` in the first lane and `b`
/// in the second (or `-b`, where `a` is in `negated`). A pair of inputs, sines or cosines is packed from
/// its two scalars; any other pair is one operation on pairs.
///
/// Why a lane may hold the negation: mirrored branches often compute the same value with the opposite
/// sign (TALOS's right gripper hangs turned by π about its wrist against the left one, so its rotations
/// have -1 where the left's have 1), and the tape folds signs into the operations: `-(x - y)` is traced as
/// `y - x` and `x + (-c) y` as `x - c y`. Negation is exact in IEEE arithmetic (rounding is symmetric), so
/// a lane holding `-b` computes with the same roundings and `-b` taken out of it is `b` bit for bit.
#[derive(Clone, Debug, Default)]
pub(crate) struct Pairing {
    /// First member → second member.
    pub second: HashMap<u32, u32>,
    /// Second member → first member.
    pub first: HashMap<u32, u32>,
    /// First members of pairs whose second member's operands are in the other order (commutative
    /// operations, and sums against differences).
    pub swapped: std::collections::HashSet<u32>,
    /// First members of pairs whose second lane holds the negated second member.
    pub negated: std::collections::HashSet<u32>,
    /// The signs the operands' second lanes carry in each computed pair's operation, by first member
    /// (a pair register read with the other sign is read through `negate_second`).
    pub signs: HashMap<u32, [bool; 2]>,
}

impl Pairing {
    fn taken(&self, n: u32) -> bool {
        self.second.contains_key(&n) || self.first.contains_key(&n)
    }

    /// Whether the pair of first member `a` is packed from two scalars rather than computed.
    pub(crate) fn is_packed(nodes: &[Op], a: u32) -> bool {
        matches!(
            nodes[a as usize],
            Op::Input { .. } | Op::Sin(_) | Op::Cos(_)
        )
    }

    /// The sign each operand's second lane must carry for the pair of first member `a` to compute its
    /// own second lane (`true`: negated), operand by operand in the first member's order, as the
    /// unification that formed the pair chose them.
    pub(crate) fn operand_signs(&self, nodes: &[Op], a: u32) -> Vec<bool> {
        let arity = crate::emit::operands(&nodes[a as usize]).len();
        self.signs[&a][..arity].to_vec()
    }

    /// The pair register that holds the operands `x` (first lane) and `y` (second lane, up to its
    /// sign), where one does: the pair `(x, y)` itself, or through a negation that one side has and the
    /// other not (`y = -y'` with the pair `(x, y')`, or `x = -x'` with `(x', y)`, read as `-(x', y)`:
    /// lane one must hold the first member as it is). `None` for constants, a shared operand, or operands
    /// that only pack from their scalars.
    pub(crate) fn operand(&self, nodes: &[Op], x: Sym, y: Sym) -> Option<PairOperand> {
        let (Sym::Node(x), Sym::Node(y)) = (x, y) else {
            return None;
        };
        if self.second.get(&x) == Some(&y) {
            return Some(PairOperand {
                first: x,
                negate: false,
                second_negated: false,
                sign: self.negated.contains(&x),
            });
        }
        match (&nodes[x as usize], &nodes[y as usize]) {
            (Op::Neg(_), Op::Neg(_)) => None,
            (_, Op::Neg(Sym::Node(y))) if self.second.get(&x) == Some(y) => Some(PairOperand {
                first: x,
                negate: false,
                second_negated: true,
                sign: !self.negated.contains(&x),
            }),
            (Op::Neg(Sym::Node(x)), _) if self.second.get(x) == Some(&y) => Some(PairOperand {
                first: *x,
                negate: true,
                second_negated: false,
                sign: !self.negated.contains(x),
            }),
            _ => None,
        }
    }

    /// Whether an operand that needs its second lane's sign to be `sign` is read from the register `o`
    /// (through `negate_second` where the signs differ) rather than packed again from the pair's scalars
    /// (a packed pair read with the other sign). The statements' dependencies and their text both ask.
    pub(crate) fn reads_register(nodes: &[Op], o: &PairOperand, sign: bool) -> bool {
        o.sign == sign || !Pairing::is_packed(nodes, o.first)
    }

    /// Number of pairs computed by one operation.
    pub(crate) fn computed(&self, nodes: &[Op]) -> usize {
        self.second
            .keys()
            .filter(|&&a| !Pairing::is_packed(nodes, a))
            .count()
    }
}

/// An operand of a pair operation read from a pair register ([`Pairing::operand`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PairOperand {
    /// The register's pair, by first member.
    pub first: u32,
    /// Whether the operand is the register negated.
    pub negate: bool,
    /// Whether the second member's operand is the negation of the register's second member.
    pub second_negated: bool,
    /// Whether the operand's second lane holds the second member's operand negated.
    pub sign: bool,
}

/// How deep [`find`] follows operands that are not yet paired.
const MAX_DEPTH: usize = 10;

/// Pairs the live operations of `nodes` (in trace order, operands before users) that the seeds lead
/// to: an operation that reads the first member of a pair pairs with an operation of the same kind that
/// reads the second member at the same place, when their other operands pair too (recursively: both
/// constants, one and the same value, an existing pair, or two operations that pair in turn).
pub(crate) fn find(nodes: &[Op], live: &[bool], seeds: &[(u32, u32)]) -> Pairing {
    let mut pairing = Pairing::default();
    for &(a, b) in seeds {
        if a != b && live[a as usize] && live[b as usize] && !pairing.taken(a) && !pairing.taken(b)
        {
            pairing.second.insert(a, b);
            pairing.first.insert(b, a);
        }
    }
    let mut users: Vec<Vec<u32>> = vec![Vec::new(); nodes.len()];
    for (n, op) in nodes.iter().enumerate() {
        if !live[n] {
            continue;
        }
        for o in crate::emit::operands(op) {
            if let Sym::Node(m) = o {
                users[m as usize].push(n as u32);
            }
        }
    }
    for n in 0..nodes.len() as u32 {
        if !live[n as usize] || pairing.taken(n) || !pairable(&nodes[n as usize]) {
            continue;
        }
        'operands: for o in crate::emit::operands(&nodes[n as usize]) {
            let Sym::Node(mut o) = o else { continue };
            // An operand negated on the first side only.
            if let (false, Op::Neg(Sym::Node(x))) =
                (pairing.second.contains_key(&o), &nodes[o as usize])
            {
                o = *x;
            }
            let Some(&o2) = pairing.second.get(&o) else {
                continue;
            };
            // The second member's readers, and the readers of its negation.
            let mut candidates: Vec<u32> = users[o2 as usize].clone();
            for &u in &users[o2 as usize] {
                if matches!(nodes[u as usize], Op::Neg(_)) {
                    candidates.extend(&users[u as usize]);
                }
            }
            for c in candidates {
                if c == n || pairing.taken(c) || !compatible(&nodes[n as usize], &nodes[c as usize])
                {
                    continue;
                }
                // Without reading a pair negated first; with, where that costs fewer negations than
                // the pairs save.
                for (flexible, negated) in
                    [(false, false), (false, true), (true, false), (true, true)]
                {
                    let mut trial = Trial {
                        flexible,
                        ..Trial::default()
                    };
                    if unify(
                        nodes,
                        &pairing,
                        Sym::Node(n),
                        Sym::Node(c),
                        negated,
                        &mut trial,
                        0,
                    ) && trial.flips < trial.pairs.len()
                    {
                        for (a, b, negated) in trial.pairs {
                            pairing.second.insert(a, b);
                            pairing.first.insert(b, a);
                            if negated {
                                pairing.negated.insert(a);
                            }
                        }
                        for (a, swapped, signs) in trial.ways {
                            if swapped {
                                pairing.swapped.insert(a);
                            }
                            pairing.signs.insert(a, signs);
                        }
                        break 'operands;
                    }
                }
            }
        }
    }
    pairing
}

/// Operations that can pair: the arithmetic (one SIMD instruction), sines and cosines (packed).
fn pairable(op: &Op) -> bool {
    matches!(
        op,
        Op::Add(..)
            | Op::Sub(..)
            | Op::Mul(..)
            | Op::Div(..)
            | Op::Neg(_)
            | Op::Sin(_)
            | Op::Cos(_)
    )
}

/// Operations one pair instruction can compute: the same kind, or a sum against a difference (the
/// lanes' signs make up for it, [`addend_signs`]).
fn compatible(a: &Op, b: &Op) -> bool {
    core::mem::discriminant(a) == core::mem::discriminant(b) || (is_sum(a) && is_sum(b))
}

fn is_sum(op: &Op) -> bool {
    matches!(op, Op::Add(..) | Op::Sub(..))
}

/// The signs of a sum's operands' second lanes. The first member is `x ± y` (`left_minus`: `x - y`), the
/// second `u ± w` (`right_minus`), and the pair holds `±` it (`negated`); `x` pairs with `u` and `y` with
/// `w`, or `x` with `w` and `y` with `u` (`swapped`). Lane two computes `σx r + s σy r'` with the first
/// member's operation `s`, which equals `σ` times the second member when each operand's sign is `σ` times
/// its coefficients in both members.
fn addend_signs(negated: bool, left_minus: bool, right_minus: bool, swapped: bool) -> [bool; 2] {
    if swapped {
        [negated ^ right_minus, negated ^ left_minus]
    } else {
        [negated, negated ^ left_minus ^ right_minus]
    }
}

/// Pairs tried for one candidate, kept only if the whole candidate pairs.
#[derive(Default)]
struct Trial {
    /// (first, second, negated).
    pairs: Vec<(u32, u32, bool)>,
    /// How the operands of computed pairs pair: (first, swapped, the operands' signs).
    ways: Vec<(u32, bool, [bool; 2])>,
    /// Unifications tried, bounded by [`MAX_STEPS`].
    steps: usize,
    /// Whether an existing pair may be read with its second lane negated (one `negate_second`).
    flexible: bool,
    /// Reads that do.
    flips: usize,
}

/// Unifications tried per candidate at most: the signs double the ways a product can pair, and this
/// keeps the search linear in the tape.
const MAX_STEPS: usize = 2_000;

impl Trial {
    fn get(&self, a: u32) -> Option<(u32, bool)> {
        self.pairs.iter().find(|p| p.0 == a).map(|p| (p.1, p.2))
    }
    fn uses(&self, n: u32) -> bool {
        self.pairs.iter().any(|p| p.0 == n || p.1 == n)
    }
    fn rollback(&mut self, pairs: usize, ways: usize, flips: usize) {
        self.pairs.truncate(pairs);
        self.ways.truncate(ways);
        self.flips = flips;
    }
}

/// Whether `a` and `b` pair with the second lane holding `b` (`negated`: `-b`), recording the new pairs
/// in `trial`.
fn unify(
    nodes: &[Op],
    pairing: &Pairing,
    a: Sym,
    b: Sym,
    negated: bool,
    trial: &mut Trial,
    depth: usize,
) -> bool {
    let (a, b) = match (a, b) {
        (Sym::Const(_), Sym::Const(_)) => return true,
        (Sym::Node(a), Sym::Node(b)) => (a, b),
        _ => return false,
    };
    if a == b {
        return !negated;
    }
    // A pair read with the other sign costs one operation: a packed pair (inputs, sines, cosines) is
    // packed again from its scalars, a computed one goes through `negate_second`.
    let existing = match pairing.second.get(&a) {
        Some(&second) if second == b => Some(pairing.negated.contains(&a)),
        _ => trial.get(a).filter(|t| t.0 == b).map(|t| t.1),
    };
    if let Some(sign) = existing {
        if sign == negated {
            return true;
        }
        trial.flips += 1;
        return trial.flexible;
    }
    if depth > MAX_DEPTH || trial.steps >= MAX_STEPS {
        return false;
    }
    trial.steps += 1;
    let (opa, opb) = (&nodes[a as usize], &nodes[b as usize]);
    // A negation on one side only: the second lane carries it, or the reader negates the register
    // (`Pairing::operand`).
    match (opa, opb) {
        (Op::Neg(_), Op::Neg(_)) => {}
        (_, &Op::Neg(y)) => {
            return unify(nodes, pairing, Sym::Node(a), y, !negated, trial, depth + 1)
        }
        (&Op::Neg(x), _) => {
            return unify(nodes, pairing, x, Sym::Node(b), !negated, trial, depth + 1)
        }
        _ => {}
    }
    if pairing.taken(a) || pairing.taken(b) || trial.uses(a) || trial.uses(b) {
        return false;
    }
    if !pairable(opa) || !compatible(opa, opb) {
        return false;
    }
    // Sines and cosines are packed from their two scalars as they are.
    if negated && matches!(opa, Op::Sin(_) | Op::Cos(_)) {
        return false;
    }
    let (xa, xb) = (crate::emit::operands(opa), crate::emit::operands(opb));
    // The ways the operands may pair: (swapped, sign of each operand's second lane).
    let ways: Vec<(bool, [bool; 2])> = match opa {
        Op::Add(..) | Op::Sub(..) => {
            let (l, r) = (matches!(opa, Op::Sub(..)), matches!(opb, Op::Sub(..)));
            vec![
                (false, addend_signs(negated, l, r, false)),
                (true, addend_signs(negated, l, r, true)),
            ]
        }
        // A product's sign is its operands' signs multiplied: either may carry it.
        Op::Mul(..) => vec![
            (false, [false, negated]),
            (false, [true, !negated]),
            (true, [false, negated]),
            (true, [true, !negated]),
        ],
        Op::Div(..) => vec![(false, [false, negated]), (false, [true, !negated])],
        Op::Neg(_) => vec![(false, [negated, false])],
        _ => vec![(false, [false, false])],
    };
    let mark = (trial.pairs.len(), trial.ways.len(), trial.flips);
    trial.pairs.push((a, b, negated));
    for (swapped, signs) in ways {
        let mut xb = xb.clone();
        if swapped {
            xb.reverse();
        }
        if xa
            .iter()
            .zip(&xb)
            .zip(signs)
            .all(|((&x, &y), sign)| unify(nodes, pairing, x, y, sign, trial, depth + 1))
        {
            trial.ways.push((a, swapped, signs));
            return true;
        }
        trial.rollback(mark.0 + 1, mark.1, mark.2);
    }
    trial.rollback(mark.0, mark.1, mark.2);
    false
}

/// Functions of up to this many operations are paired: in trace order, emitted as one function or as
/// parts of `CHUNK` statements (a pair counting once). Longer ones (the derivatives of humanoids) are written
/// unpaired by `emit_large`, whose form rustc compiles in less memory, and whose pairing search would take
/// long (TALOS's `aba_derivatives`, 249k operations: a minute, and it then failed the statement rule of
/// `LONG_PAIRED_PERCENT`). A quadruped's derivatives are under the limit: the floating ANYmal B's
/// `aba_derivatives` (52k operations, 61 % as many statements) paired takes 0.77× the time of the unpaired
/// form and compiles in 5.9 s instead of 5.0 (2026-12-03, one binary, identical results). It used to take
/// 2.1× the time, when paired functions were scheduled by height and their outputs crossed the scratch
/// arrays to the public function (docs/generated-code.md).
pub(crate) const PAIRING_LIMIT: usize = 60_000;

/// Fewer computed pairs than this are not worth the packing: the function stays scalar.
pub(crate) const MIN_PAIRS: usize = 8;

/// One statement group of a paired function body.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Item {
    /// A scalar value (or the batched sines and cosines, at the first of them).
    Scalar(u32),
    /// A pair computed by one operation, named by its first member.
    Computed(u32),
    /// A pair packed from its two scalars (inputs, sines, cosines), named by its first member.
    Packed(u32),
}

/// The statements of a paired function body, in `order` (trace order) as far as the
/// pairs allow: a pair comes when both its members would have, after everything it reads. A member of a
/// computed pair that something reads as a scalar (a scalar operation, an output, an operand shared by
/// both lanes) is taken out of its pair right after it. `None` where the pairing would need a value before
/// it exists (a pair whose member depends on the other's pair): then the function stays scalar.
pub(crate) fn statements(
    writer: &crate::emit::Writer,
    order: &[u32],
    pairing: &Pairing,
    outputs: &[Sym],
    pair_names: &HashMap<u32, proc_macro2::Ident>,
) -> Option<Vec<Statement>> {
    use proc_macro2::TokenStream;
    use quote::quote;
    use std::cmp::Reverse;
    use std::collections::{BinaryHeap, HashSet};
    let nodes = writer.nodes;
    let helpers = writer.helpers;
    let computed = |a: u32| !Pairing::is_packed(nodes, a);
    let pos: HashMap<u32, usize> = order.iter().enumerate().map(|(i, &n)| (n, i)).collect();
    let at = |n: u32| pos.get(&n).copied().unwrap_or(0);
    // The items and when the scalar order would reach them.
    let mut items: Vec<(Item, usize)> = Vec::new();
    for &n in order {
        match (pairing.first.get(&n), pairing.second.get(&n)) {
            (Some(&a), _) if computed(a) => {}
            (_, Some(&b)) if computed(n) => items.push((Item::Computed(n), at(n).max(at(b)))),
            _ => items.push((Item::Scalar(n), at(n))),
        }
    }
    // Operand positions of a computed pair: (first's operand, second's operand).
    let operand_pairs = |a: u32| -> Vec<(Sym, Sym)> {
        let b = pairing.second[&a];
        let (xa, mut xb) = (
            crate::emit::operands(&nodes[a as usize]),
            crate::emit::operands(&nodes[b as usize]),
        );
        if pairing.swapped.contains(&a) {
            xb.reverse();
        }
        xa.into_iter().zip(xb).collect()
    };
    // Packed pairs that some computed pair reads (the others would be dead code).
    let mut read_as_pair: HashSet<u32> = HashSet::new();
    for &a in pairing.second.keys() {
        if computed(a) {
            for (x, y) in operand_pairs(a) {
                read_as_pair.extend(pairing.operand(nodes, x, y).map(|o| o.first));
            }
        }
    }
    let mut packed: Vec<(u32, u32)> = pairing
        .second
        .iter()
        .filter(|(&a, _)| !computed(a) && read_as_pair.contains(&a))
        .map(|(&a, &b)| (a, b))
        .collect();
    packed.sort_unstable();
    for (a, b) in packed {
        items.push((Item::Packed(a), at(a).max(at(b))));
    }
    let index: HashMap<Item, usize> = items
        .iter()
        .enumerate()
        .map(|(i, (it, _))| (*it, i))
        .collect();
    // Who provides a value as a scalar, and who as a pair (None: an input, always there).
    let scalar_from = |m: u32| -> Option<usize> {
        if matches!(nodes[m as usize], Op::Input { .. }) {
            return None;
        }
        let item = match pairing.first.get(&m) {
            Some(&a) if computed(a) => Item::Computed(a),
            _ if pairing.second.contains_key(&m) && computed(m) => Item::Computed(m),
            _ => Item::Scalar(m),
        };
        index.get(&item).copied()
    };
    let pair_from = |a: u32| -> Option<usize> {
        let item = if computed(a) {
            Item::Computed(a)
        } else {
            Item::Packed(a)
        };
        index.get(&item).copied()
    };
    let batched: HashSet<u32> = writer.batch.iter().copied().collect();
    let mut needs_scalar: HashSet<u32> = HashSet::new();
    let mut deps: Vec<Vec<usize>> = vec![Vec::new(); items.len()];
    // What each item reads: scalars (inputs included) and pairs (by first member).
    let mut reads: Vec<(Vec<u32>, Vec<u32>)> = vec![(Vec::new(), Vec::new()); items.len()];
    for (i, (item, _)) in items.iter().enumerate() {
        let mut reads_scalar: Vec<u32> = Vec::new();
        match *item {
            Item::Scalar(n) => {
                for o in crate::emit::operands(&nodes[n as usize]) {
                    if let Sym::Node(m) = o {
                        reads_scalar.push(m);
                    }
                }
                if batched.contains(&n) {
                    reads_scalar.extend(writer.angles.iter().filter_map(|s| match s {
                        Sym::Node(m) => Some(*m),
                        Sym::Const(_) => None,
                    }));
                }
            }
            Item::Computed(a) => {
                let signs = pairing.operand_signs(nodes, a);
                for ((x, y), sign) in operand_pairs(a).into_iter().zip(signs) {
                    match pairing.operand(nodes, x, y) {
                        Some(o) if Pairing::reads_register(nodes, &o, sign) => {
                            deps[i].extend(pair_from(o.first));
                            reads[i].1.push(o.first);
                            continue;
                        }
                        // Packed again from its scalars, the second lane negated.
                        Some(o) => {
                            reads_scalar.extend([o.first, pairing.second[&o.first]]);
                            continue;
                        }
                        None => {}
                    }
                    match (x, y) {
                        (Sym::Node(x), Sym::Node(y)) => reads_scalar.extend([x, y]),
                        (Sym::Node(x), Sym::Const(_)) | (Sym::Const(_), Sym::Node(x)) => {
                            reads_scalar.push(x)
                        }
                        (Sym::Const(_), Sym::Const(_)) => {}
                    }
                }
            }
            Item::Packed(a) => reads_scalar.extend([a, pairing.second[&a]]),
        }
        for &m in &reads_scalar {
            needs_scalar.insert(m);
            deps[i].extend(scalar_from(m));
        }
        reads[i].0 = reads_scalar;
    }
    for s in outputs {
        if let Sym::Node(m) = s {
            needs_scalar.insert(*m);
        }
    }
    // Kahn's order, earliest scalar position first.
    let mut pending: Vec<usize> = vec![0; items.len()];
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); items.len()];
    for (i, d) in deps.iter_mut().enumerate() {
        d.sort_unstable();
        d.dedup();
        d.retain(|&j| j != i);
        pending[i] = d.len();
        for &j in d.iter() {
            users[j].push(i);
        }
    }
    let mut ready: BinaryHeap<Reverse<(usize, usize)>> = (0..items.len())
        .filter(|&i| pending[i] == 0)
        .map(|i| Reverse((items[i].1, i)))
        .collect();
    let mut statements: Vec<Statement> = Vec::new();
    let mut defined: HashSet<u32> = HashSet::new();
    // An operand of a pair operation: the first member's operand `x` and the second's `y`, whose second
    // lane holds `-y` where `negated`.
    let vector = |x: Sym, y: Sym, negated: bool| -> TokenStream {
        if let Some(o) = pairing.operand(nodes, x, y) {
            if Pairing::reads_register(nodes, &o, negated) {
                let id = &pair_names[&o.first];
                let register = if o.sign == negated {
                    quote!(#id)
                } else {
                    quote!(#helpers::negate_second::<S>(#id))
                };
                return if o.negate {
                    quote!((-#register))
                } else {
                    register
                };
            }
            let first = writer.operand(&Sym::Node(o.first));
            let second = writer.operand(&Sym::Node(pairing.second[&o.first]));
            let first = if o.negate {
                quote!(-#first)
            } else {
                quote!(#first)
            };
            let second = if negated ^ o.second_negated {
                quote!(-#second)
            } else {
                quote!(#second)
            };
            return quote!(#helpers::pair::<S>(#first, #second));
        }
        match (x, y) {
            (Sym::Const(c), Sym::Const(d)) => {
                let d = if negated { -d } else { d };
                let (x, y) = (
                    writer.operand(&Sym::Const(c)),
                    writer.operand(&Sym::Const(d)),
                );
                if c.to_bits() == d.to_bits() {
                    quote!(#helpers::splat::<S>(#x))
                } else {
                    quote!(#helpers::pair::<S>(#x, #y))
                }
            }
            (Sym::Node(m), Sym::Node(n)) if m == n && !negated => {
                let m = writer.operand(&x);
                quote!(#helpers::splat::<S>(#m))
            }
            _ => {
                let (x, y) = (writer.operand(&x), writer.operand(&y));
                if negated {
                    quote!(#helpers::pair::<S>(#x, -#y))
                } else {
                    quote!(#helpers::pair::<S>(#x, #y))
                }
            }
        }
    };
    while let Some(Reverse((_, i))) = ready.pop() {
        let mut stmts: Vec<TokenStream> = Vec::new();
        let mut scalars: Vec<u32> = Vec::new();
        let mut pair = None;
        match items[i].0 {
            Item::Scalar(n) => {
                // A sine or cosine call defines its partner too, the batch all its values.
                let trig = matches!(nodes[n as usize], Op::Sin(_) | Op::Cos(_));
                let before: HashSet<u32> = if trig {
                    defined.clone()
                } else {
                    HashSet::new()
                };
                writer.scalar(n, &mut stmts, &mut defined);
                if trig {
                    scalars.extend(defined.difference(&before).copied());
                    scalars.sort_unstable();
                } else if !stmts.is_empty() {
                    scalars.push(n);
                }
            }
            Item::Packed(a) => {
                pair = Some(a);
                let id = &pair_names[&a];
                let (x, y) = (
                    writer.operand(&Sym::Node(a)),
                    writer.operand(&Sym::Node(pairing.second[&a])),
                );
                stmts.push(quote!(let #id: P = #helpers::pair::<S>(#x, #y);));
            }
            Item::Computed(a) => {
                pair = Some(a);
                let b = pairing.second[&a];
                let id = &pair_names[&a];
                let xs = operand_pairs(a);
                let signs = pairing.operand_signs(nodes, a);
                let expr = match nodes[a as usize] {
                    Op::Neg(_) => {
                        let x = vector(xs[0].0, xs[0].1, signs[0]);
                        quote!(-#x)
                    }
                    ref op => {
                        let (x, y) = (
                            vector(xs[0].0, xs[0].1, signs[0]),
                            vector(xs[1].0, xs[1].1, signs[1]),
                        );
                        match op {
                            Op::Add(..) => quote!(#x + #y),
                            Op::Sub(..) => quote!(#x - #y),
                            Op::Mul(..) => quote!(#x * #y),
                            Op::Div(..) => quote!(#x / #y),
                            _ => unreachable!("only arithmetic pairs are computed"),
                        }
                    }
                };
                stmts.push(quote!(let #id: P = #expr;));
                let negated = pairing.negated.contains(&a);
                for (m, lane) in [(a, quote!(first)), (b, quote!(second))] {
                    if needs_scalar.contains(&m) {
                        let mid = writer.operand(&Sym::Node(m));
                        // A negated second lane gives its member back negated (exact).
                        let sign = (m == b && negated).then(|| quote!(-));
                        stmts.push(quote!(let #mid: S = #sign #helpers::#lane::<S>(#id);));
                        defined.insert(m);
                        scalars.push(m);
                    }
                }
            }
        }
        let (reads_scalars, reads_pairs) = std::mem::take(&mut reads[i]);
        statements.push(Statement {
            tokens: stmts,
            scalars,
            pair,
            reads_scalars,
            reads_pairs,
        });
        for &u in &users[i] {
            pending[u] -= 1;
            if pending[u] == 0 {
                ready.push(Reverse((items[u].1, u)));
            }
        }
    }
    (statements.len() == items.len()).then_some(statements)
}

/// The statements of one item of a paired body, with what they define and read (for cutting a long body
/// into parts whose crossing values go through scratch arrays).
pub(crate) struct Statement {
    pub tokens: Vec<proc_macro2::TokenStream>,
    /// Scalar values defined (a pair's members taken out of it, the batched sines and cosines).
    pub scalars: Vec<u32>,
    /// The pair defined, by its first member.
    pub pair: Option<u32>,
    /// Scalar values read (inputs included).
    pub reads_scalars: Vec<u32>,
    /// Pairs read, by first member.
    pub reads_pairs: Vec<u32>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(file: &str) -> Model<f64> {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
        let loaded = crate::load(&path).unwrap();
        crate::generation_model(&loaded, &crate::ModelOptions::default()).unwrap()
    }

    /// The biped's legs pair joint by joint (hips, then knees), in q and in v.
    #[test]
    fn mirrored_legs_pair_joint_by_joint() {
        let m = model("tests/golden/biped.urdf");
        let index = |name: &str| {
            let j = m.joints.iter().find(|j| j.name == name).unwrap();
            j.q_index as u32
        };
        let pairs = BranchPairs::of(&m);
        let want = vec![
            (index("l_hip"), index("r_hip")),
            (index("l_knee"), index("r_knee")),
        ];
        assert_eq!(pairs.q, want);
        assert_eq!(pairs.v, want);
    }

    /// A lone leg has no partner: nothing to pair.
    #[test]
    fn a_single_branch_has_no_pairs() {
        let pairs = BranchPairs::of(&model("tests/golden/leg.urdf"));
        assert!(pairs.q.is_empty() && pairs.v.is_empty());
    }

    /// Two operations pair where they are the same kind on pairing operands (constants may differ, a
    /// shared operand is broadcast, a commutative pair may read its operands in the other order), and not
    /// where the kinds differ.
    #[test]
    fn operations_pair_only_where_they_agree() {
        let c = Sym::Const;
        let n = Sym::Node;
        let nodes = vec![
            Op::Input { arg: 0, index: 0 }, // 0: left
            Op::Input { arg: 0, index: 1 }, // 1: right
            Op::Input { arg: 0, index: 2 }, // 2: shared
            Op::Mul(n(0), c(2.0)),          // 3
            Op::Mul(n(1), c(3.0)),          // 4: pairs with 3 (constants differ)
            Op::Add(n(3), n(2)),            // 5
            Op::Add(n(2), n(4)),            // 6: pairs with 5, operands swapped
            Op::Sub(n(5), n(2)),            // 7
            Op::Add(n(6), n(2)),            // 8: another kind, no pair
            Op::Neg(n(0)),                  // 9
            Op::Mul(n(1), c(-1.0)),         // 10: another kind, no pair
            Op::Sin(n(0)),                  // 11
            Op::Sin(n(1)),                  // 12: packed pair
        ];
        let live = vec![true; nodes.len()];
        let p = find(&nodes, &live, &[(0, 1)]);
        let mut got: Vec<(u32, u32)> = p.second.iter().map(|(&a, &b)| (a, b)).collect();
        got.sort_unstable();
        assert_eq!(got, vec![(0, 1), (3, 4), (5, 6), (11, 12)]);
        assert!(p.swapped.contains(&5));
        assert_eq!(p.computed(&nodes), 2);
    }

    /// Values that are each other's negation pair, the second lane holding the negation: a difference
    /// against the reversed difference (the tape writes `-(x - y)` as `y - x`), what is computed from them,
    /// and a product against one with a negated factor (read through the negation).
    #[test]
    fn negated_values_pair_with_a_signed_second_lane() {
        let c = Sym::Const;
        let n = Sym::Node;
        let nodes = vec![
            Op::Input { arg: 0, index: 0 }, // 0: x, left
            Op::Input { arg: 0, index: 1 }, // 1: x, right
            Op::Input { arg: 0, index: 2 }, // 2: y, left
            Op::Input { arg: 0, index: 3 }, // 3: y, right
            Op::Sub(n(0), n(2)),            // 4: x - y
            Op::Sub(n(3), n(1)),            // 5: y' - x' = -(x' - y')
            Op::Mul(n(4), c(2.0)),          // 6
            Op::Mul(n(5), c(2.0)),          // 7: -(2 (x' - y'))
            Op::Mul(n(0), n(2)),            // 8: x y
            Op::Neg(n(3)),                  // 9: -y'
            Op::Mul(n(1), n(9)),            // 10: x' (-y') = -(x' y')
            Op::Add(n(6), n(8)),            // 11
            Op::Sub(n(7), n(10)),           // 12: -(2 (x' - y')) + x' y': not ± the left
        ];
        let live = vec![true; nodes.len()];
        let p = find(&nodes, &live, &[(0, 1), (2, 3)]);
        for (a, b) in [(4, 5), (8, 10)] {
            assert_eq!(p.second.get(&a), Some(&b), "{a} pairs with {b}");
            assert!(p.negated.contains(&a), "{a}'s second lane is negated");
        }
        // A product by a constant needs no sign of its own: the constants' pair carries it (2, -2).
        assert_eq!(p.second.get(&6), Some(&7));
        assert!(!p.negated.contains(&6));
        assert_eq!(p.signs[&6], [true, true]);
        // x - y against -(x' - y'), read with the second lanes' signs: Add(6, 8) is 2(x - y) + xy, the
        // right's Sub(7, 10) is -2(x' - y') + x'y': equal up to the sign of one addend only, which a
        // negated read (`negate_second`) makes up for.
        assert_eq!(p.second.get(&11), Some(&12));
        assert_eq!(p.computed(&nodes), 4);
    }

    /// Without seeds nothing pairs, however alike the operations.
    #[test]
    fn nothing_pairs_without_seeds() {
        let nodes = vec![
            Op::Input { arg: 0, index: 0 },
            Op::Input { arg: 0, index: 1 },
            Op::Mul(Sym::Node(0), Sym::Const(2.0)),
            Op::Mul(Sym::Node(1), Sym::Const(2.0)),
        ];
        let p = find(&nodes, &[true; 4], &[]);
        assert!(p.second.is_empty());
    }
}

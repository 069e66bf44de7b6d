//! Symbolic tracing: the interpreted algorithms run on [`Sym`], a scalar that records every operation on
//! runtime values into a tape and folds every operation on constants. The algorithm's loops over bodies
//! and its branches on joint types run at generation time, so the tape is the algorithm unrolled for one
//! model: straight-line code with the model's constants folded and the zero structure of axes, transforms
//! and inertias removed (a product with an exact 0 never reaches the tape).
//!
//! One source of truth: the generated code is the oracle's own arithmetic, specialized.

use embedyn_runtime::Real;
use std::cell::RefCell;
use std::collections::HashMap;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A traced scalar: a constant known at generation time, or a node of the tape.
#[derive(Clone, Copy, Debug)]
pub enum Sym {
    /// A value known at generation time (folded, never recorded).
    Const(f64),
    /// The value of tape node `n`.
    Node(u32),
}

/// An operation recorded on the tape. Operands are [`Sym`]s, so constants stay inline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Op {
    /// Input `index` of argument `arg` (0: q, 1: v, 2: tau/qdd).
    Input {
        /// Which argument: 0 `q`, 1 `v`, 2 `tau`/`qdd`.
        arg: u8,
        /// The entry of that argument.
        index: u32,
    },
    /// `a + b`.
    Add(Sym, Sym),
    /// `a - b`.
    Sub(Sym, Sym),
    /// `a * b`.
    Mul(Sym, Sym),
    /// `a / b`.
    Div(Sym, Sym),
    /// `-a`.
    Neg(Sym),
    /// `a.sqrt()`.
    Sqrt(Sym),
    /// `a.sin()`.
    Sin(Sym),
    /// `a.cos()`.
    Cos(Sym),
    /// `a.abs()`.
    Abs(Sym),
    /// `if lhs > rhs { then } else { otherwise }`.
    Select {
        /// Left side of the comparison.
        lhs: Sym,
        /// Right side of the comparison.
        rhs: Sym,
        /// The value when `lhs > rhs`.
        then: Sym,
        /// The value otherwise.
        otherwise: Sym,
    },
}

/// A hashable key of an operation (constants by their bits), for common-subexpression elimination.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Input(u8, u32),
    Bin(u8, (u8, u64), (u8, u64)),
    Un(u8, (u8, u64)),
    Select([(u8, u64); 4]),
}

fn sym_key(s: Sym) -> (u8, u64) {
    match s {
        Sym::Const(c) => (0, c.to_bits()),
        Sym::Node(n) => (1, n as u64),
    }
}

/// The name an algorithm gave a value ([`Real::named`]): component `component` (empty for a scalar)
/// of `quantity` of the body or joint `owner`. Names live beside the tape, never in it: they change
/// neither the operations nor their order.
#[derive(Clone, Debug, PartialEq)]
pub struct Label {
    /// The body or joint the value belongs to.
    pub owner: String,
    /// What the value is (`v`, `d_inv`, …).
    pub quantity: String,
    /// Which component (empty for a scalar).
    pub component: String,
}

/// The recording of one traced function: its operations in order, deduplicated as they are added.
#[derive(Default)]
pub struct Tape {
    /// The operations; node `n` is `nodes[n]`.
    pub nodes: Vec<Op>,
    map: HashMap<Key, u32>,
    /// The first name given to each node (a node reached again under another name, by folding or
    /// common-subexpression elimination, keeps the name of where it was first computed).
    pub labels: HashMap<u32, Label>,
}

thread_local! {
    static TAPE: RefCell<Tape> = RefCell::new(Tape::default());
}

/// A tape reached its budget of nodes ([`record_within`]): tracing stopped there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TapeFull {
    /// The nodes recorded when it stopped (the budget).
    pub nodes: usize,
}

thread_local! {
    /// The nodes the current tape may hold ([`record_within`]).
    static BUDGET: std::cell::Cell<usize> = const { std::cell::Cell::new(usize::MAX) };
}

/// [`record`] with at most `budget` nodes on the tape (`None`: no bound). Past the budget the trace
/// stops at once, by unwinding out of the algorithm (with [`std::panic::resume_unwind`], which prints
/// nothing), and its tape is dropped: a model whose functions trace far beyond what any limit allows (a
/// loop group's cubic growth, which no prediction from the model's size foresees) costs the budget's time
/// and memory, not the full trace's. A build with `panic = "abort"` cannot unwind and traces in full.
pub fn record_within<R>(
    budget: Option<usize>,
    f: impl FnOnce() -> R,
) -> Result<(R, Tape), TapeFull> {
    #[cfg(panic = "unwind")]
    {
        BUDGET.with(|b| b.set(budget.unwrap_or(usize::MAX)));
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| record(f)));
        BUDGET.with(|b| b.set(usize::MAX));
        match result {
            Ok(recorded) => Ok(recorded),
            Err(payload) => match payload.downcast::<TapeFull>() {
                Ok(full) => {
                    TAPE.with(|t| *t.borrow_mut() = Tape::default());
                    Err(*full)
                }
                Err(other) => std::panic::resume_unwind(other),
            },
        }
    }
    #[cfg(not(panic = "unwind"))]
    {
        let _ = budget;
        Ok(record(f))
    }
}

/// Runs `f` on a fresh tape and returns its result with the tape.
pub fn record<R>(f: impl FnOnce() -> R) -> (R, Tape) {
    TAPE.with(|t| *t.borrow_mut() = Tape::default());
    let r = f();
    let tape = TAPE.with(|t| std::mem::take(&mut *t.borrow_mut()));
    (r, tape)
}

fn push(op: Op) -> Sym {
    let key = match op {
        Op::Input { arg, index } => Key::Input(arg, index),
        Op::Add(a, b) => Key::Bin(0, sym_key(a), sym_key(b)),
        Op::Sub(a, b) => Key::Bin(1, sym_key(a), sym_key(b)),
        Op::Mul(a, b) => Key::Bin(2, sym_key(a), sym_key(b)),
        Op::Div(a, b) => Key::Bin(3, sym_key(a), sym_key(b)),
        Op::Neg(a) => Key::Un(0, sym_key(a)),
        Op::Sqrt(a) => Key::Un(1, sym_key(a)),
        Op::Sin(a) => Key::Un(2, sym_key(a)),
        Op::Cos(a) => Key::Un(3, sym_key(a)),
        Op::Abs(a) => Key::Un(4, sym_key(a)),
        Op::Select {
            lhs,
            rhs,
            then,
            otherwise,
        } => Key::Select([
            sym_key(lhs),
            sym_key(rhs),
            sym_key(then),
            sym_key(otherwise),
        ]),
    };
    TAPE.with(|t| {
        let mut t = t.borrow_mut();
        if let Some(&n) = t.map.get(&key) {
            return Sym::Node(n);
        }
        let n = t.nodes.len() as u32;
        if t.nodes.len() >= BUDGET.with(std::cell::Cell::get) {
            let full = TapeFull {
                nodes: t.nodes.len(),
            };
            drop(t);
            std::panic::resume_unwind(Box::new(full));
        }
        t.nodes.push(op);
        t.map.insert(key, n);
        Sym::Node(n)
    })
}

/// An input value of the generated function.
pub fn input(arg: u8, index: usize) -> Sym {
    push(Op::Input {
        arg,
        index: index as u32,
    })
}

/// A value within 1e-14 of 0 or ±1 becomes exactly that (cos(π/2) = 6e-17 is a 0 of the model, not a
/// number to multiply by); anything else stays exactly as computed.
pub fn snap(x: f64) -> f64 {
    if x.abs() < 1e-14 {
        0.0
    } else if (x - 1.0).abs() < 1e-14 {
        1.0
    } else if (x + 1.0).abs() < 1e-14 {
        -1.0
    } else {
        x
    }
}

impl Sym {
    /// The value, when it is a generation-time constant.
    pub fn constant(&self) -> Option<f64> {
        match self {
            Sym::Const(c) => Some(*c),
            Sym::Node(_) => None,
        }
    }
    fn is(&self, v: f64) -> bool {
        matches!(self, Sym::Const(c) if *c == v)
    }
    /// Order of commutative operands, so that `a + b` and `b + a` share one node.
    fn order(a: Sym, b: Sym) -> (Sym, Sym) {
        if sym_key(a) <= sym_key(b) {
            (a, b)
        } else {
            (b, a)
        }
    }
}

impl PartialEq for Sym {
    fn eq(&self, other: &Self) -> bool {
        sym_key(*self) == sym_key(*other)
    }
}

impl Eq for Sym {}

impl std::hash::Hash for Sym {
    fn hash<H: std::hash::Hasher>(&self, h: &mut H) {
        sym_key(*self).hash(h)
    }
}

/// Only constants compare. A comparison involving a value computed from the generated function's inputs
/// has no answer at generation time, and answering it anyway would silently freeze one branch into the
/// generated code: it is a generation-time error instead (as CasADi and JAX refuse). Algorithms choose
/// between run-time values with [`Real::select_gt`] (a select in the generated code) and check them
/// through [`Real::value`] (which is `None` here, so the generated function returns the measure instead).
impl PartialOrd for Sym {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        match (self, other) {
            (Sym::Const(a), Sym::Const(b)) => a.partial_cmp(b),
            _ => branch_on_traced_value("a comparison"),
        }
    }
}

/// The generation-time error of a branch on a traced value (a bug in the algorithm being traced, not in
/// the user's model: the message says where to look).
#[cold]
#[track_caller]
fn branch_on_traced_value(what: &str) -> ! {
    panic!(
        "embedyn code generation: {what} on a value only known at run time, at {}; the traced algorithm must use Real::select_gt for a run-time choice or Real::value for a check",
        std::panic::Location::caller()
    )
}

impl Add for Sym {
    type Output = Sym;
    fn add(self, b: Sym) -> Sym {
        match (self, b) {
            (Sym::Const(x), Sym::Const(y)) => Sym::Const(x + y),
            _ if self.is(0.0) => b,
            _ if b.is(0.0) => self,
            // x + (−x) = 0 exactly for every finite x.
            _ if is_neg_of(self, b) || is_neg_of(b, self) => Sym::Const(0.0),
            // Negations fold into the operation (exact): a + (−y) = a − y.
            _ if negated(b).is_some() => self - negated(b).unwrap(),
            _ if negated(self).is_some() => b - negated(self).unwrap(),
            _ => {
                let (x, y) = Sym::order(self, b);
                push(Op::Add(x, y))
            }
        }
    }
}

/// `Some(x)` when `a` is the node `−x`.
fn negated(a: Sym) -> Option<Sym> {
    match a {
        Sym::Node(n) => TAPE.with(|t| match t.borrow().nodes[n as usize] {
            Op::Neg(x) => Some(x),
            _ => None,
        }),
        Sym::Const(_) => None,
    }
}

/// Whether `a` is the node `−b`.
fn is_neg_of(a: Sym, b: Sym) -> bool {
    match a {
        Sym::Node(n) => TAPE.with(|t| matches!(t.borrow().nodes[n as usize], Op::Neg(x) if x == b)),
        Sym::Const(_) => false,
    }
}

impl Sub for Sym {
    type Output = Sym;
    fn sub(self, b: Sym) -> Sym {
        match (self, b) {
            (Sym::Const(x), Sym::Const(y)) => Sym::Const(x - y),
            _ if b.is(0.0) => self,
            _ if self.is(0.0) => -b,
            _ if self == b => Sym::Const(0.0),
            _ if negated(b).is_some() => self + negated(b).unwrap(),
            _ => push(Op::Sub(self, b)),
        }
    }
}

impl Mul for Sym {
    type Output = Sym;
    fn mul(self, b: Sym) -> Sym {
        match (self, b) {
            (Sym::Const(x), Sym::Const(y)) => Sym::Const(x * y),
            _ if self.is(0.0) || b.is(0.0) => Sym::Const(0.0),
            _ if self.is(1.0) => b,
            _ if b.is(1.0) => self,
            _ if self.is(-1.0) => -b,
            _ if b.is(-1.0) => -self,
            // (−x)(−y) = xy; c (−y) = (−c) y: the sign moves into a constant or disappears.
            _ if negated(self).is_some() && negated(b).is_some() => {
                negated(self).unwrap() * negated(b).unwrap()
            }
            (Sym::Const(c), _) if negated(b).is_some() => Sym::Const(-c) * negated(b).unwrap(),
            (_, Sym::Const(c)) if negated(self).is_some() => {
                negated(self).unwrap() * Sym::Const(-c)
            }
            _ => {
                let (x, y) = Sym::order(self, b);
                push(Op::Mul(x, y))
            }
        }
    }
}

impl Div for Sym {
    type Output = Sym;
    fn div(self, b: Sym) -> Sym {
        match (self, b) {
            (Sym::Const(x), Sym::Const(y)) => Sym::Const(x / y),
            _ if b.is(1.0) => self,
            _ if b.is(-1.0) => -self,
            _ if self.is(0.0) => Sym::Const(0.0),
            _ => push(Op::Div(self, b)),
        }
    }
}

impl Neg for Sym {
    type Output = Sym;
    fn neg(self) -> Sym {
        match self {
            Sym::Const(x) => Sym::Const(-x),
            Sym::Node(n) => {
                let inner = TAPE.with(|t| t.borrow().nodes[n as usize]);
                match inner {
                    Op::Neg(x) => x,
                    // −(c y) = (−c) y and −(a − b) = b − a: no separate negation.
                    Op::Mul(Sym::Const(c), y) => Sym::Const(-c) * y,
                    Op::Mul(y, Sym::Const(c)) => y * Sym::Const(-c),
                    Op::Sub(a, b) => b - a,
                    _ => push(Op::Neg(self)),
                }
            }
        }
    }
}

macro_rules! assign_ops {
    ($($tr:ident $f:ident $op:tt),*) => {$(
        impl $tr for Sym {
            fn $f(&mut self, b: Sym) {
                *self = *self $op b;
            }
        }
    )*};
}
assign_ops!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

impl num_traits::Zero for Sym {
    fn zero() -> Self {
        Sym::Const(0.0)
    }
    fn is_zero(&self) -> bool {
        self.is(0.0)
    }
}

impl num_traits::One for Sym {
    fn one() -> Self {
        Sym::Const(1.0)
    }
}

impl Real for Sym {
    const NAME: &'static str = "sym";
    fn from_f64(x: f64) -> Self {
        Sym::Const(x)
    }
    /// Constants convert; runtime values have no value at generation time (NaN marks them).
    fn to_f64(self) -> f64 {
        self.constant().unwrap_or(f64::NAN)
    }
    /// Known only for constants: checks on runtime values are the generated code's caller's job.
    fn value(self) -> Option<f64> {
        self.constant()
    }
    fn sqrt(self) -> Self {
        match self {
            Sym::Const(x) => Sym::Const(x.sqrt()),
            _ => push(Op::Sqrt(self)),
        }
    }
    fn sin(self) -> Self {
        match self {
            Sym::Const(x) => Sym::Const(snap(x.sin())),
            _ => push(Op::Sin(self)),
        }
    }
    fn cos(self) -> Self {
        match self {
            Sym::Const(x) => Sym::Const(snap(x.cos())),
            _ => push(Op::Cos(self)),
        }
    }
    fn abs(self) -> Self {
        match self {
            Sym::Const(x) => Sym::Const(x.abs()),
            _ => push(Op::Abs(self)),
        }
    }
    fn epsilon() -> Self {
        Sym::Const(f64::EPSILON)
    }
    fn named(self, owner: &str, quantity: &str, component: &str) -> Self {
        if let Sym::Node(n) = self {
            TAPE.with(|t| {
                t.borrow_mut().labels.entry(n).or_insert_with(|| Label {
                    owner: owner.to_string(),
                    quantity: quantity.to_string(),
                    component: component.to_string(),
                });
            });
        }
        self
    }
    /// A check, answerable for constants only (see [`PartialOrd`] for `Sym`).
    #[track_caller]
    fn is_finite(self) -> bool {
        match self {
            Sym::Const(c) => c.is_finite(),
            Sym::Node(_) => branch_on_traced_value("a finiteness check"),
        }
    }
    fn select_gt(self, other: Self, then: Self, otherwise: Self) -> Self {
        if then == otherwise {
            return then;
        }
        if let (Sym::Const(a), Sym::Const(b)) = (self, other) {
            return if a > b { then } else { otherwise };
        }
        // 0 > |x| never holds.
        if self.is(0.0) {
            if let Sym::Node(n) = other {
                if TAPE.with(|t| matches!(t.borrow().nodes[n as usize], Op::Abs(_))) {
                    return otherwise;
                }
            }
        }
        push(Op::Select {
            lhs: self,
            rhs: other,
            then,
            otherwise,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A branch on a traced value is a loud generation-time error, not a silently frozen branch; a
    /// run-time choice is a select, and constants still compare.
    #[test]
    fn branching_on_a_traced_value_is_refused() {
        let ((), tape) = record(|| {
            let x = input(0, 0);
            let two = Sym::Const(2.0);
            assert!(two > Sym::Const(1.0));
            let refused = std::panic::catch_unwind(|| x > two).unwrap_err();
            let message = refused.downcast_ref::<String>().unwrap();
            assert!(message.contains("select_gt"), "{message}");
            assert!(std::panic::catch_unwind(|| x.is_finite()).is_err());
            assert!(std::panic::catch_unwind(|| x.is_positive_finite()).is_err());
            assert_eq!(x.value(), None);
            assert_eq!(two.value(), Some(2.0));
            // max is a select node, not a guess.
            assert!(matches!(x.max(two), Sym::Node(_)));
        });
        assert!(tape.nodes.iter().any(|op| matches!(op, Op::Select { .. })));
    }

    /// A trace past its budget stops there and reports it; within it, it records as `record` does;
    /// other panics pass through.
    #[test]
    fn a_trace_stops_at_its_budget() {
        let chain = || {
            let mut x = input(0, 0);
            for _ in 0..1000 {
                x = x * x + Sym::Const(1.0);
            }
            x
        };
        assert_eq!(
            record_within(Some(100), chain).err(),
            Some(TapeFull { nodes: 100 })
        );
        let (_, tape) = record_within(Some(5000), chain).unwrap();
        assert_eq!(tape.nodes.len(), 2001);
        let (_, tape) = record_within(None, chain).unwrap();
        assert_eq!(tape.nodes.len(), 2001);
        // The budget ends with its trace.
        let (_, tape) = record(chain);
        assert_eq!(tape.nodes.len(), 2001);
        let other = std::panic::catch_unwind(|| record_within(Some(10), || panic!("other")));
        assert!(other.is_err());
    }

    /// A name is kept beside the tape: it adds no node, returns the value unchanged, and the first
    /// name of a node stays (a value reached again under another name keeps where it was computed).
    #[test]
    fn names_are_kept_beside_the_tape() {
        let ((), tape) = record(|| {
            let x = input(0, 0);
            let y = x * x;
            assert_eq!(y.named("thigh", "v", "ang_x"), y);
            assert_eq!((x * x).named("shin", "a", ""), y);
            assert_eq!(Sym::Const(2.0).named("thigh", "m", ""), Sym::Const(2.0));
        });
        assert_eq!(tape.nodes.len(), 2);
        assert_eq!(tape.labels.len(), 1);
        let label = &tape.labels[&1];
        assert_eq!(
            (
                label.owner.as_str(),
                label.quantity.as_str(),
                label.component.as_str()
            ),
            ("thigh", "v", "ang_x")
        );
    }
}

//! The checker's term definitions over symbolica expressions: a [`Real`] instance whose values
//! are symbolic, so that each definition, written once, yields its potential, dissipation
//! function and velocity-dependent Lagrangian as expressions that can be differentiated.

use lagra_checker::real::Real;
use std::cell::RefCell;
use std::ops::{Add, Div, Mul, Neg, Sub};
use symbolica::prelude::*;

/// A symbolic real.
#[derive(Clone, Debug, PartialEq)]
pub struct Sym(pub Atom);

thread_local! {
    /// The cutoff conditions `lt` was asked (as `bound − self`, positive inside), innermost
    /// last: the `select` that asked is the next to call `hull`, which turns it into a step.
    static CONDITIONS: RefCell<Vec<Atom>> = const { RefCell::new(vec![]) };
}

macro_rules! binary {
    ($($tr:ident $f:ident $op:tt),*) => {$(
        impl $tr for Sym {
            type Output = Sym;
            fn $f(self, o: Sym) -> Sym {
                Sym(&self.0 $op &o.0)
            }
        }
    )*};
}
binary!(Add add +, Sub sub -, Mul mul *, Div div /);

impl Neg for Sym {
    type Output = Sym;
    fn neg(self) -> Sym {
        Sym(-&self.0)
    }
}

/// The exact rational value of a finite binary64 number, m·2^e.
pub fn exact(c: f64) -> Atom {
    assert!(c.is_finite(), "only finite constants");
    if c == 0.0 {
        return Atom::num(0);
    }
    let bits = c.to_bits();
    let (sign, exponent, fraction) = (bits >> 63, ((bits >> 52) & 0x7ff) as i64, bits & ((1 << 52) - 1));
    let (mut m, mut e) =
        if exponent == 0 { (fraction as i64, -1074) } else { ((fraction | (1 << 52)) as i64, exponent - 1075) };
    while m % 2 == 0 {
        m /= 2;
        e += 1;
    }
    let m = if sign == 1 { -m } else { m };
    Atom::num(m) * Atom::num(2).pow(Atom::num(e))
}

fn call(f: Symbol, args: &[&Atom]) -> Atom {
    let mut b = FunctionBuilder::new(f);
    for a in args {
        b = b.add_arg(*a);
    }
    b.finish()
}

impl Real for Sym {
    fn lift(&self, c: f64) -> Self {
        Sym(exact(c))
    }
    fn sqrt(self) -> Self {
        Sym(self.0.pow(Atom::num(1) / Atom::num(2)))
    }
    fn powi(self, n: i32) -> Self {
        Sym(self.0.pow(Atom::num(n as i64)))
    }
    fn exp(self) -> Self {
        Sym(call(Symbol::EXP, &[&self.0]))
    }
    fn ln(self) -> Self {
        Sym(call(Symbol::LOG, &[&self.0]))
    }
    /// Uninterpreted: a symmetry must leave its argument alone, which is what the analysis asks.
    fn acos(self) -> Self {
        Sym(call(symbol!("acos"), &[&self.0]))
    }
    fn cos(self) -> Self {
        Sym(call(Symbol::COS, &[&self.0]))
    }
    fn sin(self) -> Self {
        Sym(call(Symbol::SIN, &[&self.0]))
    }
    fn atan2(self, x: Self) -> Self {
        Sym(call(symbol!("atan2"), &[&self.0, &x.0]))
    }
    fn lt(&self, bound: &Self) -> Option<bool> {
        CONDITIONS.with(|c| c.borrow_mut().push(&bound.0 - &self.0));
        None
    }
    /// `step(c)·yes + (1 − step(c))·no` with `c` the condition, step an uninterpreted function:
    /// its derivative is a `der(step)` times the variation of `c`, so a cutoff is a symmetry
    /// exactly when its condition is (a distance is; a height is not).
    fn hull(self, o: Self) -> Self {
        let c = CONDITIONS.with(|c| c.borrow_mut().pop()).expect("hull follows an undecided lt");
        let step = call(symbol!("step"), &[&c]);
        Sym(&step * &self.0 + (Atom::num(1) - &step) * &o.0)
    }
}

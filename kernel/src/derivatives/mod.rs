//! The terms' definitions differentiated: dual numbers over any `Real` (nested for second
//! derivatives), and the Euler–Lagrange force they give, with its derivatives. Built on the
//! checker's definitions alone.

pub mod dual;
pub mod exact;

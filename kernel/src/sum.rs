//! Compensated summation (Neumaier's variant of Kahan's): the f64 witnesses add up thousands of
//! terms, and plain summation's round-off could look like energy drift.

/// A running sum with its rounding error carried alongside.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sum {
    sum: f64,
    carry: f64,
}

impl Sum {
    pub fn add(&mut self, x: f64) {
        let t = self.sum + x;
        // the low-order bits that fell off, whichever operand was larger
        self.carry += if self.sum.abs() >= x.abs() { (self.sum - t) + x } else { (x - t) + self.sum };
        self.sum = t;
    }

    /// Adds another running sum, its carry included.
    pub fn merge(&mut self, other: Sum) {
        self.add(other.sum);
        self.carry += other.carry;
    }

    /// The sum and its carry, to send (a run cut into domains adds the ranks' sums in rank order).
    pub fn parts(self) -> [f64; 2] {
        [self.sum, self.carry]
    }

    pub fn of_parts([sum, carry]: [f64; 2]) -> Sum {
        Sum { sum, carry }
    }

    pub fn value(self) -> f64 {
        self.sum + self.carry
    }
}

impl FromIterator<f64> for Sum {
    fn from_iter<I: IntoIterator<Item = f64>>(iter: I) -> Self {
        let mut s = Sum::default();
        iter.into_iter().for_each(|x| s.add(x));
        s
    }
}

#[cfg(test)]
mod tests {
    use super::Sum;

    #[test]
    fn it_keeps_what_plain_summation_loses() {
        let terms = [1e16, 1.0, -1e16, 1.0];
        assert_eq!(terms.iter().sum::<f64>(), 1.0, "plain summation loses the first one");
        assert_eq!(terms.into_iter().collect::<Sum>().value(), 2.0);
    }

    #[test]
    fn a_million_tenths_sum_correctly_rounded() {
        let plain: f64 = std::iter::repeat_n(0.1, 1_000_000).sum();
        let compensated = std::iter::repeat_n(0.1, 1_000_000).collect::<Sum>().value();
        // 0.1 is 0.1000000000000000055511151231257827…: a million of them is
        // 100000.0000000000055…, which rounds to 100000 (as Python's correctly rounded fsum says)
        assert_eq!(compensated, 100000.0);
        assert_eq!(plain, 100000.00000133288, "plain summation is 1.3e-6 off");
    }
}

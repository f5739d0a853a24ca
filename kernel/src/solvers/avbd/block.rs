//! A body's Newton system in a sweep: the symmetric 6×6 Hessian of its share of the energy and
//! the force on it, summed row by row, in 3×3 blocks
//!
//!   H = [ A  Bᵀ ]   (A: moves against moves, B: turns against moves, C: turns against turns)
//!       [ B  C  ]
//!
//! and solved through the Schur complement S = C − B A⁻¹ Bᵀ, each 3×3 inverse by its adjugate.
//! The solve is the sweeps' inner loop (one a body a sweep: 20,000 a step on
//! `scenes/bench/stack_1000.lagra`): a 6×6 Cholesky factorisation is a chain of six square roots
//! and divisions, each waiting on the last, and took 155 ns (3.1 ms of a step's 8.2); the blocks
//! take two divisions and independent products.

use nalgebra::{Matrix3, Vector3, Vector6};

type V = Vector3<f64>;

/// H in 3×3 blocks (A and C symmetric, their upper triangles packed xx, xy, xz, yy, yz, zz) and
/// the force f, in H Δ = f.
pub struct Block {
    a: [f64; 6],
    b: [[f64; 3]; 3],
    c: [f64; 6],
    f: [f64; 6],
}

/// Where entry (i, j) of a symmetric 3×3 lies in its packed upper triangle.
const PACKED: [[usize; 3]; 3] = [[0, 1, 2], [1, 3, 4], [2, 4, 5]];

impl Block {
    /// The inertial term alone: H = diag(m, m, m) ⊕ I (the world inertia over dt², or the
    /// identity for a point mass, which does not turn), f = H (target − moved) with a point
    /// mass's turn held at nothing.
    pub fn inertial(mass: f64, inertia: Option<&Matrix3<f64>>, towards: &Vector6<f64>) -> Block {
        let (c, turned) = match inertia {
            Some(i) => (packed(|r, c| i[(r, c)]), i * towards.fixed_rows::<3>(3)),
            None => ([1.0, 0.0, 0.0, 1.0, 0.0, 1.0], V::zeros()),
        };
        let f = [0, 1, 2, 3, 4, 5].map(|i| if i < 3 { mass * towards[i] } else { turned[i - 3] });
        Block { a: [mass, 0.0, 0.0, mass, 0.0, mass], b: [[0.0; 3]; 3], c, f }
    }

    /// A contact's (or a pin's) three rows, all with the same arm r from the body's centre:
    /// row n's Jacobian (d_n, r × d_n), stiffness k_n, force `push`_n. With K = Σ k_n d_n d_nᵀ
    /// and F = Σ push_n d_n, H gains (I; [r]×) K (I, [r]×ᵀ), f loses (F; r × F): a contact's
    /// rows added at once rather than one by one (k J Jᵀ, 6×6 each), two fifths the work.
    #[inline]
    pub fn add_rows(&mut self, dirs: &[V; 3], arm: &V, k: [f64; 3], push: [f64; 3]) {
        let stiff = packed(|i, j| (0..3).fold(0.0, |sum, n| (k[n] * dirs[n][i]).mul_add(dirs[n][j], sum)));
        let pushed = V::from([0, 1, 2].map(|i| (0..3).fold(0.0, |sum, n| push[n].mul_add(dirs[n][i], sum))));
        // B's new part [r]× K, column by column; C's, [r]× K [r]×ᵀ, row i being r × (row i of [r]× K)
        let turned = [0, 1, 2].map(|j| cross(arm, &[0, 1, 2].map(|i| stiff[PACKED[i][j]])));
        let rows = [0, 1, 2].map(|i| [turned[0][i], turned[1][i], turned[2][i]]);
        let twice = [0, 1, 2].map(|i| cross(arm, &rows[i]));
        for (n, (a, c)) in self.a.iter_mut().zip(&mut self.c).enumerate() {
            let (i, j) = UPPER[n];
            *a += stiff[n];
            *c += twice[i][j];
        }
        for (b, row) in self.b.iter_mut().zip(&rows) {
            b.iter_mut().zip(row).for_each(|(b, r)| *b += r);
        }
        let torque = cross(arm, &pushed.into());
        for i in 0..3 {
            self.f[i] -= pushed[i];
            self.f[3 + i] -= torque[i];
        }
    }

    /// Δ with H Δ = f: the turn from S Δθ = f_θ − B A⁻¹ f_x, the move from A Δx = f_x − Bᵀ Δθ;
    /// nothing where A or S is not positive definite (H is not).
    pub fn solve(&self) -> Option<Vector6<f64>> {
        let a = positive_inverse(&self.a)?;
        // W = B A⁻¹, row by row (A⁻¹ is symmetric: W's row i is A⁻¹ times B's)
        let w = self.b.map(|row| times(&a, &row));
        let s = packed(|i, j| self.c[PACKED[i][j]] - dot(&w[i], &self.b[j]));
        let s = positive_inverse(&s)?;
        let moves = [self.f[0], self.f[1], self.f[2]];
        let turn = times(&s, &[0, 1, 2].map(|i| self.f[3 + i] - dot(&w[i], &moves)));
        let back = [0, 1, 2].map(|j| (0..3).fold(0.0, |sum, i| w[i][j].mul_add(turn[i], sum)));
        let shift = times(&a, &moves);
        Some(Vector6::new(shift[0] - back[0], shift[1] - back[1], shift[2] - back[2], turn[0], turn[1], turn[2]))
    }
}

/// The inverse of a packed symmetric 3×3 by its adjugate, where its leading minors are positive
/// (Sylvester's criterion: it is positive definite); nothing otherwise, or where any is not
/// finite.
fn positive_inverse(m: &[f64; 6]) -> Option<[f64; 6]> {
    let [xx, xy, xz, yy, yz, zz] = *m;
    let cofactor = [
        yy.mul_add(zz, -yz * yz),
        xz.mul_add(yz, -xy * zz),
        xy.mul_add(yz, -xz * yy),
        xx.mul_add(zz, -xz * xz),
        xy.mul_add(xz, -xx * yz),
        xx.mul_add(yy, -xy * xy),
    ];
    let det = xx.mul_add(cofactor[0], xy.mul_add(cofactor[1], xz * cofactor[2]));
    let positive = xx > 0.0 && cofactor[5] > 0.0 && det > 0.0 && det.is_finite();
    positive.then(|| cofactor.map(|c| c / det)).filter(|i| i.iter().all(|x| x.is_finite()))
}

/// A packed symmetric 3×3 times v.
#[inline]
fn times(m: &[f64; 6], v: &[f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| dot(&[m[PACKED[i][0]], m[PACKED[i][1]], m[PACKED[i][2]]], v))
}

#[inline]
fn dot(u: &[f64; 3], v: &[f64; 3]) -> f64 {
    u[0].mul_add(v[0], u[1].mul_add(v[1], u[2] * v[2]))
}

/// The packed entries (i, j), j ≥ i, in order.
const UPPER: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];

/// A symmetric 3×3 packed from its entries.
fn packed(entry: impl Fn(usize, usize) -> f64) -> [f64; 6] {
    UPPER.map(|(i, j)| entry(i, j))
}

/// r × v, in numbers.
#[inline]
fn cross(r: &V, v: &[f64; 3]) -> [f64; 3] {
    [r.y.mul_add(v[2], -r.z * v[1]), r.z.mul_add(v[0], -r.x * v[2]), r.x.mul_add(v[1], -r.y * v[0])]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix6;
    use proptest::prelude::*;

    proptest! {
        /// The block's solve agrees with nalgebra's on the same system: an inertial term with
        /// a rigid body's inertia and a handful of contacts, each three rows k J Jᵀ into H and
        /// −push J into f, J = (d, r × d), added to a full 6×6 one by one.
        #[test]
        fn the_block_solves_what_nalgebra_solves(
            mass in 0.1f64..1e4,
            spread in prop::array::uniform9(-1.0f64..1.0),
            towards in prop::array::uniform6(-1.0f64..1.0),
            contacts in prop::collection::vec((
                prop::array::uniform9(-1.0f64..1.0),
                prop::array::uniform3(-1.0f64..1.0),
                prop::array::uniform3(0.0f64..1e3),
                prop::array::uniform3(-10.0f64..10.0),
            ), 0..8),
        ) {
            let a = Matrix3::from_row_slice(&spread);
            let inertia = a * a.transpose() + Matrix3::identity() * mass;
            let towards = Vector6::from(towards);
            let mut block = Block::inertial(mass, Some(&inertia), &towards);
            let mut h = Matrix6::from_diagonal_element(mass);
            h.fixed_view_mut::<3, 3>(3, 3).copy_from(&inertia);
            let mut f = h * towards;
            for (dirs, arm, k, push) in &contacts {
                let dirs = [0, 1, 2].map(|n| V::new(dirs[3 * n], dirs[3 * n + 1], dirs[3 * n + 2]));
                let arm = V::from(*arm);
                block.add_rows(&dirs, &arm, *k, *push);
                for n in 0..3 {
                    let t = arm.cross(&dirs[n]);
                    let j = Vector6::new(dirs[n].x, dirs[n].y, dirs[n].z, t.x, t.y, t.z);
                    h += j * j.transpose() * k[n];
                    f -= j * push[n];
                }
            }
            let expected = h.cholesky().expect("positive definite").solve(&f);
            let got = block.solve().expect("positive definite");
            prop_assert!((got - expected).norm() <= 1e-9 * expected.norm().max(1e-12), "{got} vs {expected}");
        }
    }

    #[test]
    fn a_point_mass_does_not_turn() {
        let block = Block::inertial(2.0, None, &Vector6::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0));
        assert_eq!(block.solve(), Some(Vector6::new(1.0, 2.0, 3.0, 0.0, 0.0, 0.0)));
    }

    #[test]
    fn a_turn_that_nothing_resists_has_no_solution() {
        let block = Block::inertial(1.0, Some(&Matrix3::from_diagonal(&V::new(1.0, 0.0, 1.0))), &Vector6::zeros());
        assert_eq!(block.solve(), None);
    }

    #[test]
    fn a_matrix_that_is_not_positive_definite_has_no_solution() {
        let mut block = Block::inertial(1.0, None, &Vector6::zeros());
        block.add_rows(&[V::x(), V::y(), V::z()], &V::zeros(), [-2.0, 0.0, 0.0], [0.0; 3]);
        assert_eq!(block.solve(), None);
    }
}

; Why `Outward` (checker/src/outward.rs) encloses, in z3's model of IEEE binary64.
; 1. For each operation it rounds, the exact result x lies between pred(RN(x)) and succ(RN(x)):
;    for every a, b, no binary64 value f lies strictly between the result rounded to nearest and
;    the result rounded up (or down). The result rounded up is ≥ x and the one rounded down ≤ x,
;    so with nothing in between, succ(RN(x)) ≥ RU(x) ≥ x and pred(RN(x)) ≤ RD(x) ≤ x, overflow
;    to ±∞ included. √ is left to the tests: z3 did not settle it within ten minutes here (its
;    enclosure is tested against MPFR, rounded both ways).
; 2. `up(r) = fma(|r|, 2⁻⁵², r + 2⁻⁵¹¹)` (one rounding of r + |r|·2⁻⁵² + 2⁻⁵¹¹, after the
;    rounded r + 2⁻⁵¹¹) is above every finite r, so at or above succ(r), and leaves +∞ as it
;    is; `down(r) = −fma(|r|, 2⁻⁵², 2⁻⁵¹¹ − r)` likewise below, leaving −∞. (−∞ under `up` and
;    +∞ under `down` give NaN, which the code takes for "nothing known".) With 1,
;    up(RN(x)) ≥ x ≥ down(RN(x)).
; Run: z3 checker/proofs/outward.smt2 (expect twelve `unsat`; about two minutes).
(set-logic QF_FP)
(declare-const a Float64)
(declare-const b Float64)
(declare-const f Float64)
(push) (assert (and (fp.lt (fp.add RNE a b) f) (fp.lt f (fp.add RTP a b)))) (check-sat) (pop)
(push) (assert (and (fp.lt (fp.add RTN a b) f) (fp.lt f (fp.add RNE a b)))) (check-sat) (pop)
(push) (assert (and (fp.lt (fp.sub RNE a b) f) (fp.lt f (fp.sub RTP a b)))) (check-sat) (pop)
(push) (assert (and (fp.lt (fp.sub RTN a b) f) (fp.lt f (fp.sub RNE a b)))) (check-sat) (pop)
(push) (assert (and (fp.lt (fp.mul RNE a b) f) (fp.lt f (fp.mul RTP a b)))) (check-sat) (pop)
(push) (assert (and (fp.lt (fp.mul RTN a b) f) (fp.lt f (fp.mul RNE a b)))) (check-sat) (pop)
(push) (assert (and (fp.lt (fp.div RNE a b) f) (fp.lt f (fp.div RTP a b)))) (check-sat) (pop)
(push) (assert (and (fp.lt (fp.div RTN a b) f) (fp.lt f (fp.div RNE a b)))) (check-sat) (pop)
(declare-const r Float64)
(define-fun ulp1 () Float64 (fp #b0 #b01111001011 #x0000000000000)) ; 2^-52
(define-fun floor () Float64 (fp #b0 #b01000000000 #x0000000000000)) ; 2^-511
(define-fun up () Float64 (fp.fma RNE (fp.abs r) ulp1 (fp.add RNE r floor)))
(define-fun down () Float64 (fp.neg (fp.fma RNE (fp.abs r) ulp1 (fp.sub RNE floor r))))
(push) (assert (and (not (fp.isNaN r)) (not (fp.isInfinite r)) (not (fp.gt up r)))) (check-sat) (pop)
(push) (assert (and (not (fp.isNaN r)) (not (fp.isInfinite r)) (not (fp.lt down r)))) (check-sat) (pop)
(push) (assert (and (fp.isInfinite r) (fp.isPositive r) (not (fp.eq up r)))) (check-sat) (pop)
(push) (assert (and (fp.isInfinite r) (fp.isNegative r) (not (fp.eq down r)))) (check-sat) (pop)

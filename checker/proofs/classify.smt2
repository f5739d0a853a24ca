; The decision's one comparison, `classify` in checker/src/decision.rs, as an SMT-LIB model over
; IEEE binary64 (z3's floating-point theory). Each query asserts the negation of a property;
; `unsat` means the property holds for every binary64 lo, hi, tol and x. This proves the model;
; the Rust function is held to the same property by exhaustive and random tests, and by a Kani
; harness where Kani is installed. Run: z3 checker/proofs/classify.smt2 (expect four `unsat`).
(set-logic QF_FP)
(declare-const lo Float64)
(declare-const hi Float64)
(declare-const tol Float64)
(declare-const x Float64)

; if lo.is_nan() || hi.is_nan() || tol.is_nan() || lo > hi || tol < 0.0 || tol == INFINITY
(define-fun undecidable () Bool
  (or (fp.isNaN lo) (fp.isNaN hi) (fp.isNaN tol) (fp.gt lo hi)
      (fp.lt tol (_ +zero 11 53)) (fp.eq tol (_ +oo 11 53))))
; else if hi <= tol { Within } else if lo > tol { Beyond } else { Straddles }
(define-fun within () Bool (and (not undecidable) (fp.leq hi tol)))
(define-fun beyond () Bool (and (not undecidable) (not (fp.leq hi tol)) (fp.gt lo tol)))
(define-fun inside () Bool (and (fp.leq lo x) (fp.leq x hi)))

; 1. Within: every value in the enclosure is within tolerance.
(push) (assert (and within inside (not (fp.leq x tol)))) (check-sat) (pop)
; 2. Beyond: every value in the enclosure breaks it.
(push) (assert (and beyond inside (not (fp.gt x tol)))) (check-sat) (pop)
; 3. A NaN anywhere decides nothing.
(push) (assert (and (or (fp.isNaN lo) (fp.isNaN hi) (fp.isNaN tol)) (or within beyond))) (check-sat) (pop)
; 4. Within and Beyond exclude each other.
(push) (assert (and within beyond)) (check-sat) (pop)

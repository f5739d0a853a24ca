; The state file's length arithmetic, `file_len` and `count_for` in checker/src/states.rs, over
; unbounded integers: a length that fits in 64 bits gives back exactly the count it was made
; from, for any number of bodies, thermostat links and rigid bodies (the linked format's header
; is 8 bytes longer, the spun one's 16; a spin takes four links' bytes). Run:
; z3 checker/proofs/lengths.smt2 (expect one `unsat`).
(set-logic QF_NIA)
(declare-const bodies Int)
(declare-const links Int)
(declare-const spins Int)
(declare-const count Int)
(define-fun u64 ((v Int)) Bool (and (<= 0 v) (< v 18446744073709551616)))
(define-fun slots () Int (+ links (* 4 spins)))
(define-fun record () Int (+ 16 (* 48 bodies) (* 16 slots)))
(define-fun framing () Int (ite (> spins 0) 56 (ite (= links 0) 40 48)))
(define-fun len () Int (+ framing (* count record)))
(assert (and (u64 bodies) (u64 links) (u64 spins) (u64 count) (u64 slots) (u64 (* 16 slots)) (u64 record) (u64 len)))
(assert (not (and (= (mod (- len framing) record) 0) (= (div (- len framing) record) count))))
(check-sat)

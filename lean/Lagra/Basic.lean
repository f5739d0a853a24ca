/-!
# Lagra in Lean: the shared vocabulary

Lean core only (no Mathlib), so that the files check with the WASM build of Lean as well as
with an official toolchain. Quantities are rationals: a binary64 value is a dyadic rational
and is written exactly. Functions that are not rational functions (√, exp, log, the inverse
and direct trigonometric functions) are uninterpreted constants: a theorem proved about a
definition that uses them holds for *every* interpretation, the real one included.
-/

namespace Lagra

opaque sqrt : Rat → Rat
opaque exp : Rat → Rat
opaque log : Rat → Rat
opaque acos : Rat → Rat
opaque cos : Rat → Rat
opaque sin : Rat → Rat
opaque atan2 : Rat → Rat → Rat

/-- What a term sees of a body: position, velocity, mass, charge, colour charge. -/
structure Site where
  x : Rat
  y : Rat
  z : Rat
  vx : Rat
  vy : Rat
  vz : Rat
  m : Rat
  q : Rat
  c1 : Rat
  c2 : Rat

/-- A common translation leaves a difference of positions as it was. -/
theorem shift_sub (p q a : Rat) : (p + a) - (q + a) = p - q := by grind

/-- A common translation of the positions. -/
def Site.shift (s : Site) (a b c : Rat) : Site :=
  { s with x := s.x + a, y := s.y + b, z := s.z + c }

/-- A quarter turn about the z axis, of positions and velocities alike. -/
def Site.quarterTurnZ (s : Site) : Site :=
  { s with x := -s.y, y := s.x, vx := -s.vy, vy := s.vx }

/-- A quarter turn about z leaves z alone, and what a body carries. -/
theorem Site.quarterTurnZ_z (s : Site) : s.quarterTurnZ.z = s.z := rfl
theorem Site.quarterTurnZ_m (s : Site) : s.quarterTurnZ.m = s.m := rfl
theorem Site.quarterTurnZ_q (s : Site) : s.quarterTurnZ.q = s.q := rfl
theorem Site.quarterTurnZ_c1 (s : Site) : s.quarterTurnZ.c1 = s.c1 := rfl
theorem Site.quarterTurnZ_c2 (s : Site) : s.quarterTurnZ.c2 = s.c2 := rfl

/-- ... and the x, y part of a dot product of two differences of positions: so every distance
and angle between bodies, which the definitions build from such dot products, is unchanged. -/
theorem Site.dot_quarterTurnZ (a b c d : Site) :
    ((a.quarterTurnZ.x - b.quarterTurnZ.x) * (c.quarterTurnZ.x - d.quarterTurnZ.x))
      + ((a.quarterTurnZ.y - b.quarterTurnZ.y) * (c.quarterTurnZ.y - d.quarterTurnZ.y))
    = ((a.x - b.x) * (c.x - d.x)) + ((a.y - b.y) * (c.y - d.y)) := by
  simp only [Site.quarterTurnZ]
  grind

/-- The dyadic rational m·2^e: every binary64 value is one, written exactly this way. -/
def dyadic (m : Int) (e : Int) : Rat :=
  if 0 ≤ e then (m : Rat) * ((2 ^ e.toNat : Nat) : Rat) else (m : Rat) / ((2 ^ (-e).toNat : Nat) : Rat)

/-- 2^n is positive, as a rational. -/
theorem two_pow_pos (n : Nat) : (0 : Rat) < ((2 ^ n : Nat) : Rat) := by
  have : 0 < 2 ^ n := Nat.two_pow_pos n
  exact_mod_cast this

/-- Scaling by a power of two keeps the order of integers. -/
theorem dyadic_mono {a b : Int} (e : Int) (h : a ≤ b) : dyadic a e ≤ dyadic b e := by
  have hab : (a : Rat) ≤ (b : Rat) := by exact_mod_cast h
  unfold dyadic
  split
  · exact Rat.mul_le_mul_of_nonneg_right hab (Rat.le_of_lt (two_pow_pos _))
  · rw [Rat.div_def, Rat.div_def]
    exact Rat.mul_le_mul_of_nonneg_right hab (Rat.le_of_lt (Rat.inv_pos.mpr (two_pow_pos _)))

/-- One checkpoint of a certified claim: the certified upper bound of the claim's deviation at
that step, `hm·2^e`, and the tolerance it was held to, `tm·2^e` — the binary64 values the
checker compared, exactly, written over their common power of two (`lagra lean` chooses the
smaller exponent of the two, so both are integers). -/
structure Mark where
  step : Nat
  hm : Int
  tm : Int
  e : Int

def Mark.hi (m : Mark) : Rat := dyadic m.hm m.e
def Mark.tol (m : Mark) : Rat := dyadic m.tm m.e

/-- The checker's `Within` decision for a checkpoint, on integers alone: over one power of two,
comparing the mantissas is comparing the values (`Mark.ok_le`), and the kernel decides it
without building a rational or a power per checkpoint. -/
def Mark.ok (m : Mark) : Bool := decide (m.hm ≤ m.tm)

theorem Mark.ok_le (m : Mark) (h : m.ok = true) : m.hi ≤ m.tol :=
  dyadic_mono m.e (of_decide_eq_true h)

/-- What `Within` means: every deviation the enclosure admits is within the tolerance. -/
theorem Mark.bounds (m : Mark) (h : m.ok = true) (x : Rat) (hx : x ≤ m.hi) : x ≤ m.tol :=
  Rat.le_trans hx (m.ok_le h)

/-- A trail every checkpoint of which was decided `Within` holds at every checkpoint. -/
theorem Mark.all_ok {l : List Mark} (h : l.all Mark.ok = true) : ∀ m ∈ l, m.hi ≤ m.tol :=
  fun m hm => m.ok_le (List.all_eq_true.mp h m hm)

/-- One more chunk of checkpoints, decided `Mark.ok`, in front of chunks that were: how the
generated files join their chunks, one term per chunk (no search, no rewriting). -/
theorem Mark.chunk {l : List Mark} {ls : List (List Mark)} (h : l.all Mark.ok = true)
    (hs : ls.all (fun l => l.all Mark.ok) = true) : (l :: ls).all (fun l => l.all Mark.ok) = true := by
  simp only [List.all_cons, h, hs, Bool.and_self]

/-- Chunks every checkpoint of which was decided `Mark.ok` hold at every checkpoint of the
trail they make up. -/
theorem Mark.flatten_ok {ls : List (List Mark)} (h : ls.all (fun l => l.all Mark.ok) = true) :
    ∀ m ∈ ls.flatten, m.hi ≤ m.tol := by
  intro m hm
  obtain ⟨l, hl, hml⟩ := List.mem_flatten.mp hm
  exact Mark.all_ok (List.all_eq_true.mp h l hl) m hml

end Lagra

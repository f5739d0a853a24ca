//! Fluids: the SPH term, its walls and the dam-break prediction.

use super::*;

const FLUID: &str = "scene s {
  entity { mass: 0.001, position: [0.05, 0.05, 0] }
  entity { mass: 0.001, position: [0.15, 0.05, 0] }
  sph { h: 0.13, rest_density: 1000, sound_speed: 10, alpha: 0.1 }
  wall { normal: [1, 0, 0], k: 100 }
  gravity { g: [0, -9.81, 0] }
  @predict dam_break_front { tol: 0.05 }
  solver { dt: 0.001, steps: 10 }
}";

#[test]
fn a_fluid_is_one_term_on_every_body_with_its_walls() {
    let s = compile(FLUID).unwrap();
    use lagra_checker::terms::Kind;
    let kinds: Vec<Kind> = s.model.terms.iter().map(|t| t.kind).collect();
    assert_eq!(kinds, [Kind::Sph, Kind::Wall, Kind::UniformAcceleration]);
    // γ = 7 and β = 0 by default; the wall at the origin
    assert_eq!(s.model.terms[0].params, [0.13, 1000.0, 10.0, 7.0, 0.1, 0.0]);
    assert_eq!(s.model.terms[1].params, [1.0, 0.0, 0.0, 0.0, 100.0]);
    assert!(s.model.terms[0].dissipates());
    // two bodies 0.1 apart stand for a column 0.2 wide from 0, whose front is at 1
    let column = crate::prediction::Column::of(&s.model, &s.x0).unwrap();
    assert!((column.a - 0.2).abs() < 1e-15 && column.back.abs() < 1e-15 && column.g == 9.81);
    assert!((column.front(&s.x0) - 1.0).abs() < 1e-15);
}

#[test]
fn a_kernel_chooses_the_fluids_term() {
    use lagra_checker::terms::Kind;
    let kind = |with: &str| compile(&FLUID.replace("h: 0.13", with)).unwrap().model.terms[0].kind;
    assert_eq!(kind("kernel: cubic_spline, h: 0.13"), Kind::SphCubicSpline);
    assert_eq!(kind("kernel: \"cubic_spline\", h: 0.13"), Kind::SphCubicSpline);
    assert_eq!(kind("kernel: wendland_c2, h: 0.13"), Kind::Sph);
    assert_eq!(kind("h: 0.13"), Kind::Sph);
    // the parameters are the same six
    let s = compile(&FLUID.replace("h: 0.13", "kernel: cubic_spline, h: 0.13")).unwrap();
    assert_eq!(s.model.terms[0].params, [0.13, 1000.0, 10.0, 7.0, 0.1, 0.0]);
}

#[test]
fn bad_fluids_are_refused_where_they_are_written() {
    let e = |from: &str, to: &str| error_in(FLUID, from, to);
    assert_eq!(e("h: 0.13", "h: 0"), at(4, 12, "Sph.h must be positive, got 0"));
    assert_eq!(e("h: 0.13", "h: -1"), at(4, 12, "Sph.h must be positive, got -1"));
    assert_eq!(e("rest_density: 1000", "rest_density: 0"), at(4, 32, "Sph.rest_density must be positive, got 0"));
    assert_eq!(e("sound_speed: 10", "sound_speed: -3"), at(4, 51, "Sph.sound_speed must be positive, got -3"));
    assert_eq!(
        e("alpha: 0.1", "gamma: 1, alpha: 0.1"),
        at(4, 62, "Sph.gamma must exceed 1 (the internal energy divides by γ − 1)")
    );
    assert_eq!(e("h: 0.13", "kernel: 2, h: 0.13"), at(4, 17, "sph.kernel expects a name, found `2`"));
    assert_eq!(
        e("h: 0.13", "kernel: quintic, h: 0.13"),
        at(4, 17, "unknown kernel `quintic` for sph; known: wendland_c2, cubic_spline")
    );
    assert_eq!(
        e("h: 0.13", "kernal: cubic_spline, h: 0.13"),
        at(4, 9, "unknown field `kernal` for Sph; expected h, rest_density, sound_speed, gamma, alpha, beta, kernel")
    );
    assert_eq!(
        e("sph { h", "sph { on: [0], h"),
        at(4, 9, "Sph acts on every body of the fluid; `on` belongs to external terms")
    );
    assert_eq!(
        e("normal: [1, 0, 0]", "normal: [0, 0, 0]"),
        at(5, 18, "Wall.normal must not be zero: it says which side of the wall is the room")
    );
    assert_eq!(e("k: 100", "k: 0"), at(5, 32, "Wall.k must be positive, got 0"));
    assert_eq!(
        e("  wall { normal: [1, 0, 0], k: 100 }\n", ""),
        at(6, 12, "dam_break_front: needs a back wall, a `wall` with normal +x")
    );
}

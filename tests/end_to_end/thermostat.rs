//! End-to-end: thermostats through the `lagra` binary — the extended energy certified and
//! re-checked from the state file (and a forged link caught), the observables in the JSON, a
//! Langevin run the same bits on any number of threads, bad input located, and a short run
//! against the NIST table.

use crate::common::{lagra, reseal, scene, stderr, stdout};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

/// A small liquid under `bath`, with `claims`.
fn liquid(bath: &str, claims: &str, steps: u64) -> String {
    format!(
        "scene l {{ entity atom {{ mass: 1 }}
           lattice {{ type: atom, density: 0.8442, cells: [4, 4, 4], temperature: 1.0, seed: 3 }}
           interaction lj_shifted {{ epsilon: 1, sigma: 1, cutoff: 2.5 }}
           thermostat {bath}
           {claims}
           solver {{ dt: 0.005, steps: {steps}, equilibrate: 1, steps_per_frame: 50 }} }}"
    )
}

#[test]
fn the_extended_energy_is_certified_and_reported_with_the_observables() {
    let o = lagra(&["run", "scenes/lj_nvt.lagra", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    let energy = v["claims"][0]["line"].as_str().unwrap();
    assert!(energy.starts_with("energy_conservation PASS  max|ΔH′|/|H′₀|"), "{energy}");
    assert!(energy.contains("H′ = H + the Nosé–Hoover chain's energy"), "{energy}");
    assert!(v["thermostat"].as_str().unwrap().starts_with("nose_hoover at kT 1, tau 0.5: a chain of 3 link(s)"));
    let o = &v["observables"];
    for name in ["potential_energy_per_body", "kinetic_temperature", "pressure", "diffusion"] {
        let (mean, err) = (o[name]["mean"].as_f64().unwrap(), o[name]["stderr"].as_f64().unwrap());
        assert!(mean.is_finite() && err > 0.0 && err < mean.abs(), "{name}: {mean} ± {err}");
    }
    let t = o["kinetic_temperature"]["mean"].as_f64().unwrap();
    assert!((t - 1.0).abs() < 0.05, "T = {t}");
    assert_eq!(o["from_step"], 1000, "equilibrate: 5 at dt 0.005");
    let g = o["rdf"]["g"].as_array().unwrap();
    assert_eq!(g.len(), 100);
    // no pair closer than the core, and a first peak above 2
    assert_eq!(g[0].as_f64(), Some(0.0));
    assert!(g.iter().filter_map(Value::as_f64).fold(0.0, f64::max) > 2.0);
}

/// The state file carries the chain's links; the standalone checker re-derives the extended
/// energy from them, and a link changed by a forger who re-seals every checksum is caught.
#[test]
fn a_forged_thermostat_link_is_caught_by_the_re_check() {
    let dir = tempfile::tempdir().unwrap();
    let file = scene(
        dir.path(),
        "l.lagra",
        &liquid("nose_hoover { T: 1, tau: 0.2 }", "@expect energy_conservation { tol: 1e-3, every: 20 }", 200),
    );
    let (cert, states) = (dir.path().join("c.json"), dir.path().join("s.bin"));
    let (c, s) = (cert.to_str().unwrap(), states.to_str().unwrap());
    let o = lagra(&["run", file.to_str().unwrap(), "--certificate", c, "--states", s]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let standalone = Path::new(env!("CARGO_BIN_EXE_lagra")).with_file_name("lagra-check");
    let check = || Command::new(&standalone).args([c, "--states", s]).output().unwrap();
    let honest = check();
    assert_eq!(honest.status.code(), Some(0), "{}", stdout(&honest));
    assert!(stdout(&honest).contains("AGREES"));
    // state 100's first link: its η, after 256 bodies' positions and velocities
    let mut b = std::fs::read(&states).unwrap();
    assert_eq!(&b[..16], b"lagra-states/2\0\0");
    let record = 16 + 48 * 256 + 16 * 3;
    let at = 32 + record * 100 + 16 + 48 * 256;
    let eta = f64::from_le_bytes(b[at..at + 8].try_into().unwrap());
    b[at..at + 8].copy_from_slice(&(eta + 1.0).to_le_bytes());
    reseal(&states, &cert, b);
    let forged = check();
    assert_ne!(forged.status.code(), Some(0), "{}", stdout(&forged));
    // the extended energy at state 100 moves by N_f·kT = 765: the replay halts there
    let said = stdout(&forged) + &stderr(&forged);
    assert!(said.contains("halted at step 100: energy_conservation is certainly violated"), "{said}");
}

/// Langevin noise is drawn per (seed, step, body, axis): the trace is the same bytes on one
/// thread and on three, and another seed gives another one.
#[test]
fn a_langevin_run_is_the_same_bits_on_any_number_of_threads() {
    let dir = tempfile::tempdir().unwrap();
    let text = |seed: u32| {
        format!(
            "scene g {{ entity atom {{ mass: 1 }}
               lattice {{ type: atom, density: 0.8442, cells: [11, 11, 11], temperature: 1.0, seed: 3 }}
               interaction lj_shifted {{ epsilon: 1, sigma: 1, cutoff: 2.5 }}
               thermostat langevin {{ T: 1.0, gamma: 1, seed: {seed} }}
               solver {{ dt: 0.005, steps: 6, steps_per_frame: 3 }} }}"
        )
    };
    let trace = |seed: u32, threads: &str| {
        let file = scene(dir.path(), &format!("g{seed}.lagra"), &text(seed));
        let t = dir.path().join(format!("t{seed}_{threads}.jsonl"));
        let o = lagra(&["run", file.to_str().unwrap(), "--threads", threads, "--trace", t.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
        std::fs::read(t).unwrap()
    };
    let one = trace(7, "1");
    assert_eq!(one, trace(7, "3"));
    assert_ne!(one, trace(8, "1"));
}

#[test]
fn bad_thermostats_are_errors_at_their_place() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("nose_hoover { T: 0, tau: 0.5 }", "", "l.lagra:4:40: nose_hoover.T must be positive, got 0"),
        ("nose_hoover { T: 1, tau: -0.5 }", "", "l.lagra:4:48: nose_hoover.tau must be positive, got -0.5"),
        (
            "langevin { T: 1, gamma: 1 }",
            "@expect energy_conservation { tol: 1e-3 }",
            "l.lagra:5:20: energy_conservation: a Langevin thermostat exchanges energy",
        ),
    ];
    for (bath, claims, want) in cases {
        let file = scene(dir.path(), "l.lagra", &liquid(bath, claims, 10));
        let o = lagra(&["run", file.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{bath}: {}", stdout(&o));
        assert!(stderr(&o).contains(want), "{bath}: {}", stderr(&o));
        assert!(!stderr(&o).contains("panicked"));
    }
}

/// A short run at two state points of the NIST table — a liquid under the Nosé–Hoover chain
/// (T = 0.90, ρ = 0.86) and a gas under the Langevin bath (T = 0.85, ρ = 0.001) — lands within
/// four combined standard errors of the published ⟨U⟩/N and ⟨P⟩ (`lagra bench validation
/// --quick`: 12,000 steps, the first 10 time units left out). The full runs and every state
/// point are in docs/bench/validation.md.
#[test]
fn a_short_run_lands_within_four_standard_errors_of_the_nist_table() {
    for only in ["t090_rho0860", "t085_rho0001"] {
        let o = lagra(&["bench", "validation", "--quick", "--only", only, "--json"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
        let row = &v[0];
        assert_eq!(row["steps"], 12_000);
        for z in ["z_energy", "z_pressure"] {
            let z = row[z].as_f64().unwrap();
            assert!(z.abs() <= 4.0, "{only}: {z}: {row}");
        }
    }
}

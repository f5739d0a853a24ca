//! `lagra bench`: the work-precision study, the checker's overhead and what compensated sums buy,
//! each in its smoke-test size.

use crate::common::{lagra, stderr, stdout};
use serde_json::Value;

/// The work-precision study writes its CSV, plot and table, and even its two-step smoke run
/// shows the oscillator's orders: 2 for velocity Verlet, 4 for Yoshida.
#[test]
fn bench_precision_writes_csv_plot_and_orders() {
    let dir = tempfile::tempdir().unwrap();
    let o = lagra(&["bench", "precision", "--quick", "--out", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
    let csv = std::fs::read_to_string(dir.path().join("precision.csv")).unwrap();
    // five integrators on four conservative problems, four on the cyclotron, RATTLE on the rotor
    assert_eq!(csv.lines().count(), 1 + (5 * 4 + 4 + 1) * 2, "{csv}");
    let svg = std::fs::read_to_string(dir.path().join("precision.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("yoshida4") && svg.contains("boris"));
    let table = std::fs::read_to_string(dir.path().join("precision.md")).unwrap();
    let header: Vec<String> = table.lines().next().unwrap().split('|').map(|c| c.trim().to_string()).collect();
    let order = |problem: &str, integrator: &str| -> f64 {
        let row = table.lines().find(|l| l.starts_with(&format!("| {problem} "))).expect(problem);
        let column = header.iter().position(|h| h == integrator).expect(integrator);
        row.split('|').nth(column).unwrap().trim().parse().unwrap_or(f64::NAN)
    };
    for (integrator, p) in [("velocity_verlet", 2.0), ("yoshida4", 4.0), ("action_descent", 2.0)] {
        let measured = order("oscillator", integrator);
        assert!((measured - p).abs() < 0.3, "{integrator}: {measured}\n{table}");
    }
    // first order, still short of its asymptote at the smoke run's two large steps (1.38)
    assert!((0.8..1.6).contains(&order("oscillator", "symplectic_euler")), "{table}");
    assert!((order("cyclotron", "boris") - 2.0).abs() < 0.3, "{table}");
    assert!((order("rigid_rotor", "rattle") - 2.0).abs() < 0.3, "{table}");
}

/// The gradient's cost against the forward run, and its serial part, which bites both ways: on
/// 256 atoms nothing spreads at any thread count, so most of it is serial; on 32,000 the pair
/// passes spread, so little is (a clock that missed them would give nearly all).
#[test]
fn bench_gradient_reports_a_ratio_and_a_serial_part() {
    let o = lagra(&["bench", "gradient", "--repeats", "1", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = v.as_array().unwrap();
    assert_eq!((&rows[0]["system"], &rows[1]["system"]), (&"lj_liquid".into(), &"lj_32k".into()));
    assert!(rows.iter().all(|r| r["ratio"].as_f64().unwrap() > 1.0), "a gradient costs more than the run: {v}");
    let serial = |r: &Value| r["reverse_serial"].as_f64().unwrap();
    assert!(serial(&rows[0]) > 0.5 && serial(&rows[0]) <= 1.0, "{v}");
    assert!(serial(&rows[1]) > 0.0 && serial(&rows[1]) < 0.5, "{v}");
}

#[test]
fn bench_overhead_reports_a_ratio() {
    let o = lagra(&["bench", "overhead", "--steps", "2000", "--repeats", "1", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["ratio"].as_f64().unwrap() > 0.0);
    assert!(v["final_position_difference"].as_f64().unwrap() < 1e-9, "the engine and the hand loop agree");
}

/// On the 32,000-atom benchmark the compensated sums are the exact sums of the same terms to
/// within an ulp, and the plain sums are not: at step 0 plain summation's momentum error
/// exceeds the momentum's true change over a step (round-off that would look like drift).
#[test]
fn bench_summation_shows_what_compensation_buys() {
    let o = lagra(&["bench", "summation", "--steps", "1", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let get = |at: &str, w: &str, how: &str| v[at][w][how].as_f64().unwrap();
    assert!(v["start"]["terms"].as_u64().unwrap() > 800_000);
    for at in ["start", "end"] {
        for w in ["energy", "momentum_x"] {
            let exact = get(at, w, "exact");
            let ulp = f64::EPSILON * exact.abs();
            assert!((get(at, w, "compensated") - exact).abs() <= ulp, "{at} {w}");
        }
    }
    let plain_error = (get("start", "energy", "plain") - get("start", "energy", "exact")).abs();
    assert!(plain_error > 1e-12 * get("start", "energy", "exact").abs(), "plain summation loses bits here");
    let true_change = (get("end", "momentum_x", "exact") - get("start", "momentum_x", "exact")).abs();
    assert!((get("start", "momentum_x", "plain") - get("start", "momentum_x", "exact")).abs() > true_change);
}

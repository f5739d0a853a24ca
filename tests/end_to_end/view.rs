//! `lagra view` and `lagra run --view`: the page loaded in headless Chromium (Debian's
//! `chromium`, which `setup.sh` installs): the 3D view is drawn, each plot has a point per frame
//! or per checkpoint, a failing step is marked, and nothing is fetched from the network.

use crate::common::{lagra, scene};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

/// What the page reports it drew (its `status` element), after its script ran in Chromium.
fn drawn(page: &Path, profile: &Path) -> Value {
    drawn_from(page, profile, "")
}

/// The same, seen from the view the address asks for (`#yaw=0&pitch=0`).
fn drawn_from(page: &Path, profile: &Path, view: &str) -> Value {
    let o = Command::new("chromium")
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            &format!("--user-data-dir={}", profile.display()),
            "--virtual-time-budget=3000",
            "--dump-dom",
        ])
        .arg(format!("file://{}{view}", page.display()))
        .output()
        .expect("chromium runs (setup.sh installs it)");
    let dom = String::from_utf8_lossy(&o.stdout);
    let start = dom.find("<pre id=\"status\">").unwrap_or_else(|| panic!("no status in the page:\n{dom}")) + 17;
    let end = start + dom[start..].find("</pre>").unwrap();
    serde_json::from_str(&dom[start..end]).unwrap_or_else(|e| panic!("{e}: {}", &dom[start..end]))
}

#[test]
fn a_run_with_a_failure_is_drawn_with_its_plots_and_the_failure_marked() {
    let dir = tempfile::tempdir().unwrap();
    // the oscillator at a time step its energy claim cannot keep: a certified FAIL
    let scene = std::fs::read_to_string("scenes/oscillator.lagra").unwrap().replace("dt: 0.002", "dt: 0.05");
    let scene_file = dir.path().join("o.lagra");
    std::fs::write(&scene_file, scene).unwrap();
    let (page, trace) = (dir.path().join("o.html"), dir.path().join("o.jsonl"));
    let o = lagra(&[
        "run",
        scene_file.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
        "--view",
        page.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stdout));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(!html.contains("http://") && !html.contains("https://") && !html.contains("src="), "the page reaches out");
    let frames = std::fs::read_to_string(&trace).unwrap().lines().count() as u64;
    let status = drawn(&page, &dir.path().join("chromium"));
    assert_eq!(status["frames"].as_u64(), Some(frames), "{status}");
    assert!(status["drawn"].as_u64().unwrap() > 200, "the 3D view is blank: {status}");
    // energy and momentum per frame, then each claim's checkpoints up to the failure
    let plots: Vec<u64> = status["plots"].as_array().unwrap().iter().map(|p| p.as_u64().unwrap()).collect();
    assert_eq!(&plots[..2], &[frames, frames], "{status}");
    let fail = status["fails"][0].as_u64().expect("a failing step marked");
    assert!(plots[2..].iter().any(|&n| n == fail), "{status}: a claim checked every step up to step {fail}");
}

#[test]
fn view_reads_a_trace_with_its_scene_and_certificate() {
    let dir = tempfile::tempdir().unwrap();
    let (trace, cert, page) = (dir.path().join("k.jsonl"), dir.path().join("k.cert"), dir.path().join("k.html"));
    // 200 steps: too short for the scene's statistical predictions (exit 1), enough to view
    let o = lagra(&[
        "run",
        "scenes/lj_liquid.lagra",
        "--steps",
        "200",
        "--trace",
        trace.to_str().unwrap(),
        "--certificate",
        cert.to_str().unwrap(),
    ]);
    assert!(o.status.code().is_some_and(|c| c <= 1) && cert.exists());
    let o = lagra(&[
        "view",
        trace.to_str().unwrap(),
        "--scene",
        "scenes/lj_liquid.lagra",
        "--certificate",
        cert.to_str().unwrap(),
        "-o",
        page.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let status = drawn(&page, &dir.path().join("chromium"));
    assert_eq!(status["frames"].as_u64(), Some(3), "{status}");
    assert!(status["drawn"].as_u64().unwrap() > 1000, "{status}");
    // bad input: a truncated trace line names its place
    std::fs::write(&trace, "{\"step\": 0, \"t\": 0, \"x\": [[0,0,0]], \"v\": [[0,0,0]]}\n{\"step\": 1").unwrap();
    let o = lagra(&["view", trace.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("k.jsonl:2: not a trace line"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// A rigid box is drawn as a box turned as its orientation says: a long box (4 × 1 × 1) turned
/// 30° about the line of sight (the view from +z) is drawn with its long axis 30° from the
/// horizontal, the same box unturned along it.
#[test]
fn a_tilted_box_is_drawn_tilted() {
    let dir = tempfile::tempdir().unwrap();
    for angle in [0.0, 30.0] {
        let scene = scene(
            dir.path(),
            "box.lagra",
            &format!(
                "scene tilted {{ uses newtonian.rigid_bodies
                   entity {{ shape: box, size: [4, 1, 1], mass: 1, position: [0, 0, 0], velocity: [0.1, 0, 0],
                             orientation: {{ axis: [0, 0, 1], angle: {angle} deg }} }}
                   @expect energy_conservation {{ tol: 1e-9 }}
                   solver {{ dt: 0.01, steps: 10 }} }}"
            ),
        );
        let page = dir.path().join("box.html");
        let o = lagra(&["run", scene.to_str().unwrap(), "--view", page.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
        let status = drawn_from(&page, &dir.path().join("chromium"), "#yaw=0&pitch=0");
        let tilt = status["tilt"].as_f64().unwrap();
        assert!((tilt - angle).abs() < 1.0, "turned {angle}°, drawn at {tilt}°: {status}");
        assert!(status["drawn"].as_u64().unwrap() > 2000, "a box, not a dot: {status}");
    }
    // bad input: an orientation per body, four finite numbers each, not all zero
    let trace = dir.path().join("q.jsonl");
    for q in ["[[1,0,0]]", "[[1,0,0,0],[1,0,0,0]]", "[[0,0,0,0]]"] {
        std::fs::write(&trace, format!("{{\"step\": 0, \"t\": 0, \"x\": [[0,0,0]], \"v\": [[0,0,0]], \"q\": {q}}}\n"))
            .unwrap();
        let o = lagra(&["view", trace.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{q}");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("q.jsonl:1: `q`"),
            "{q}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
}

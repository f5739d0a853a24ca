//! The tools called directly (the protocol is tested end to end in tests/end_to_end/mcp.rs and by the
//! official Python SDK in tests/mcp_client.py).

use super::tools::call;
use super::Server;
use serde_json::{json, Value};
use std::sync::atomic::AtomicBool;

fn server(budget: f64) -> Server {
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let roots = crate::reading::Roots::new(&[std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))]).unwrap();
    Server {
        out: std::io::stdout().into(),
        running: Default::default(),
        scenes,
        budget,
        roots: roots.into(),
        limits: Default::default(),
        client_roots: Default::default(),
    }
}

fn text(v: &Value) -> &str {
    v["content"][0]["text"].as_str().unwrap()
}

#[test]
fn a_broken_scene_is_a_tool_error_with_its_position() {
    let r = call(
        &server(1e9),
        "check_scene",
        &json!({ "scene": "scene s { entity { mass: 1 } }" }),
        None,
        &AtomicBool::new(false),
    );
    assert_eq!(r["isError"], true);
    assert!(text(&r).starts_with("scene.lagra:1:18: entity needs a position"), "{}", text(&r));
}

#[test]
fn run_scene_reports_verdicts_and_honours_set_and_the_budget() {
    let s = server(1e9);
    let osc = std::fs::read_to_string(s.scenes.join("oscillator.lagra")).unwrap();
    let r = call(
        &s,
        "run_scene",
        &json!({ "scene": osc, "set": { "harmonic.k": 2.5 }, "steps": 3000 }),
        None,
        &AtomicBool::new(false),
    );
    assert_eq!(r["isError"], false, "{r}");
    let doc = &r["structuredContent"];
    assert_eq!(doc["steps"], 3000);
    assert!(doc["claims"].as_array().unwrap().iter().all(|c| c["line"].as_str().unwrap().contains("PASS")), "{doc}");
    let tight =
        call(&server(10.0), "run_scene", &json!({ "path": "scenes/oscillator.lagra" }), None, &AtomicBool::new(false));
    assert_eq!(tight["isError"], true);
    assert!(text(&tight).contains("over the server's budget"), "{}", text(&tight));
    let bad =
        call(&s, "run_scene", &json!({ "scene": osc, "set": { "spring.k": 1.0 } }), None, &AtomicBool::new(false));
    assert_eq!(bad["isError"], true);
    assert!(text(&bad).contains("the scene has no term `spring`"), "{}", text(&bad));
}

#[test]
fn a_cancelled_run_stops() {
    let s = server(1e12);
    let r = call(
        &s,
        "run_scene",
        &json!({ "path": "scenes/oscillator.lagra", "steps": 2_000_000 }),
        None,
        &AtomicBool::new(true),
    );
    let halted = r["structuredContent"]["halted"].as_str().unwrap_or_default().to_string();
    assert!(halted.starts_with("cancelled at step "), "{r}");
}

//! The tools `lagra mcp` offers, and the scenes as resources. Each tool does what the CLI
//! command of the same purpose does and returns its report as text (and, where it is JSON, as
//! structured content too); a tool that cannot do its job (a scene with errors, a run over the
//! budget, a missing file) says why in a result marked `isError`. A claim that FAILs is not a
//! tool error: it is the answer, in the report (`passed`, `claims`).

use super::Server;
use crate::{grad, list, noether, reading, report, run, terms};
use lagra_run::compile;
use lagra_run::run::Options;
use serde_json::{json, Value};
use std::path::Path;
use std::sync::atomic::AtomicBool;

pub const INSTRUCTIONS: &str =
    "Lagra runs physics scenes written as Lagrangians (.lagra) and certifies their declared \
invariants with interval arithmetic: a PASS is a proved bound on the exact states the kernel produced. Read a scene \
(read_scene), change it (its text, or `set` a parameter like harmonic.k), run it (run_scene) and read the verdicts; \
check_scene reports errors with line:col; terms lists the vocabulary; gradient differentiates an objective of the run.";

/// (name, description, input schema) of every tool.
fn specs() -> Vec<(&'static str, &'static str, Value)> {
    let source = json!({
        "scene": { "type": "string", "description": "The scene's .lagra source text." },
        "path": { "type": "string", "description": "Or a .lagra file on the server's machine." }
    });
    let with_source = |extra: Value, required: &[&str]| {
        let mut props = source.clone();
        if let (Some(p), Some(e)) = (props.as_object_mut(), extra.as_object()) {
            p.extend(e.clone());
        }
        json!({ "type": "object", "properties": props, "required": required })
    };
    let set = json!({ "type": "object", "additionalProperties": { "type": "number" },
        "description": "Parameters to change first, by name: {\"harmonic.k\": 2.5, \"body[0].mass\": 2}." });
    vec![
        ("list_scenes", "The scenes this server offers: file, name, domain, bodies, terms, claims, predictions.", json!({ "type": "object", "properties": {} })),
        ("read_scene", "The source text of one of the offered scenes.", json!({ "type": "object", "properties": { "name": { "type": "string", "description": "Its name or file name (oscillator, kepler.lagra)." } }, "required": ["name"] })),
        ("terms", "The vocabulary of interaction terms: how each is written, its parameters and their dimensions.", json!({ "type": "object", "properties": {} })),
        ("check_scene", "Parse and compile a scene (units and dimensions checked): a summary, or the error with line:col.", with_source(json!({}), &[])),
        ("run_scene", "Run a scene and certify its @expect claims; returns the JSON report (verdicts, bounds, predictions, timing).",
            with_source(json!({
                "steps": { "type": "integer", "minimum": 1, "description": "Run this many steps instead of the scene's own." },
                "dt": { "type": "number", "exclusiveMinimum": 0, "description": "Use this time step instead." },
                "set": set.clone(),
                "threads": { "type": "integer", "minimum": 1, "maximum": 64 }
            }), &[])),
        ("noether", "What the scene's symmetries conserve (Noether's theorem, from the derived table), and what breaks the rest.", with_source(json!({}), &[])),
        ("recheck_certificate", "Re-check a certificate without the kernel: every enclosure and verdict recomputed from the state file.",
            json!({ "type": "object", "properties": {
                "certificate": { "type": "string", "description": "The certificate file `lagra run --certificate` wrote." },
                "states": { "type": "string", "description": "Its state file (`--states`): every enclosure is evaluated again." }
            }, "required": ["certificate"] })),
        ("gradient", "The exact gradient of an objective of the run (e.g. position[1].x@end, energy@end, mse:trace.jsonl) with respect to parameters (e.g. harmonic.k, body[0].velocity).",
            with_source(json!({
                "objective": { "type": "string" },
                "wrt": { "type": "string", "description": "Comma-separated parameter names." },
                "method": { "type": "string", "enum": ["reverse", "forward", "check"] },
                "steps": { "type": "integer", "minimum": 1 },
                "set": set
            }), &["objective", "wrt"])),
    ]
}

pub fn list() -> Vec<Value> {
    specs()
        .into_iter()
        .map(|(name, description, schema)| json!({ "name": name, "description": description, "inputSchema": schema }))
        .collect()
}

pub fn names() -> Vec<&'static str> {
    specs().into_iter().map(|s| s.0).collect()
}

pub fn exists(name: &str) -> bool {
    names().contains(&name)
}

/// A tool's answer: text, optionally the same as structured JSON, marked an error or not.
fn answer(text: String, structured: Option<Value>, is_error: bool) -> Value {
    let mut r = json!({ "content": [{ "type": "text", "text": text }], "isError": is_error });
    if let Some(s) = structured {
        r["structuredContent"] = s;
    }
    r
}

fn failed(e: impl std::fmt::Display) -> Value {
    answer(e.to_string(), None, true)
}

/// The scene a call names: its text under `scene`, or a file under `path` (under the roots).
fn source(server: &Server, args: &Value) -> Result<(String, String), String> {
    match (args.get("scene").and_then(Value::as_str), args.get("path").and_then(Value::as_str)) {
        (Some(text), None) => {
            Ok((reading::inline("scene", text, server.limits.scene)?.to_string(), "scene.lagra".into()))
        }
        (None, Some(path)) => {
            let file = server.resolve(path)?;
            reading::text(&file, server.limits.scene).map(|t| (t, path.to_string()))
        }
        (Some(_), Some(_)) => Err("give the scene's text under `scene` or a file under `path`, not both".into()),
        (None, None) => Err("give the scene's text under `scene` (or a file under `path`)".into()),
    }
}

/// The most parameters one call may set (a scene has a handful; each is looked up by name).
const MOST_SET: usize = 1000;

/// `set: {"name": value}` as `NAME=VALUE` settings.
fn settings(args: &Value) -> Result<Vec<String>, String> {
    match args.get("set") {
        None | Some(Value::Null) => Ok(vec![]),
        Some(Value::Object(m)) if m.len() > MOST_SET => {
            Err(format!("`set` names {} parameters, more than the {MOST_SET} a call may set", m.len()))
        }
        Some(Value::Object(m)) => m
            .iter()
            .map(|(k, v)| {
                v.as_f64().map(|x| format!("{k}={x:e}")).ok_or_else(|| format!("set.{k} must be a number, got {v}"))
            })
            .collect(),
        Some(other) => Err(format!("`set` must be an object of numbers, got {other}")),
    }
}

fn positive_integer(args: &Value, name: &str) -> Result<Option<u64>, String> {
    match args.get(name) {
        None | Some(Value::Null) => Ok(None),
        Some(v) => v
            .as_u64()
            .filter(|n| *n >= 1)
            .map(Some)
            .ok_or_else(|| format!("`{name}` must be a whole number ≥ 1, got {v}")),
    }
}

pub fn call(server: &Server, name: &str, args: &Value, token: Option<&Value>, cancel: &AtomicBool) -> Value {
    let result = match name {
        "list_scenes" => list::entries_within(&server.scenes, &|f: &Path| server.resolve(&f.display().to_string()))
            .map(|e| {
                let doc = json!({ "scenes": e });
                answer(serde_json::to_string_pretty(&doc).unwrap_or_default(), Some(doc), false)
            }),
        "read_scene" => read_scene(server, args.get("name").and_then(Value::as_str).unwrap_or(""))
            .map(|(_, t)| answer(t, None, false)),
        "terms" => Ok(answer(terms::table(), None, false)),
        "check_scene" => source(server, args).map(|(text, path)| match compile(&text) {
            Ok(s) => answer(
                format!(
                    "{} compiles: {} bodies, {} terms, {} claims, integrator {}",
                    s.name,
                    s.model.bodies.len(),
                    s.model.terms.len(),
                    s.claims.len(),
                    s.solver.integrator.name()
                ),
                None,
                false,
            ),
            Err(d) => answer(d.render(&path, &text).to_string(), None, true),
        }),
        "run_scene" => run_scene(server, args, token, cancel),
        "noether" => source(server, args).map(|(text, path)| match noether::report(&text, &path) {
            Ok((doc, text)) => answer(text, Some(doc), false),
            Err(e) => answer(e, None, true),
        }),
        "recheck_certificate" => recheck(server, args),
        "gradient" => gradient(server, args, token),
        _ => Err(format!("unknown tool `{name}`")),
    };
    result.unwrap_or_else(failed)
}

/// One of the offered scenes by name: its path and text.
fn read_scene(server: &Server, name: &str) -> Result<(String, String), String> {
    let files = list::files(&server.scenes)?;
    let wanted = name.trim_end_matches(".lagra");
    let f = files.iter().find(|f| f.file_stem().is_some_and(|s| s == wanted)).ok_or_else(|| {
        let known: Vec<String> =
            files.iter().filter_map(|f| f.file_stem().map(|s| s.to_string_lossy().into_owned())).collect();
        format!("no scene `{name}`; scenes: {}", known.join(", "))
    })?;
    let file = server.resolve(&f.display().to_string())?;
    reading::text(&file, server.limits.scene).map(|t| (f.display().to_string(), t))
}

fn run_scene(server: &Server, args: &Value, token: Option<&Value>, cancel: &AtomicBool) -> Result<Value, String> {
    let (text, path) = source(server, args)?;
    let dt = args.get("dt").and_then(Value::as_f64);
    let prepared = match run::prepare(&text, &path, &settings(args)?, dt) {
        Ok(p) => p,
        Err(e) => return Ok(answer(e, None, true)),
    };
    let steps = positive_integer(args, "steps")?;
    let scene = &prepared.scene;
    let threads =
        lagra_run::run::threads_for(scene.model.bodies.len(), positive_integer(args, "threads")?.map(|n| n as usize))?;
    let planned = steps.unwrap_or(scene.solver.steps);
    let atom_steps = planned as f64 * scene.model.bodies.len() as f64;
    if atom_steps > server.budget {
        return Err(format!(
            "this run is {atom_steps:.3e} atom-steps ({} bodies × {planned} steps), over the server's budget of {:.3e} (`lagra mcp --budget`): ask for fewer steps",
            scene.model.bodies.len(),
            server.budget
        ));
    }
    // at most five notifications a second: the run calls back every step when it is watched
    let mut last: Option<std::time::Instant> = None;
    let mut tick = |step: u64| {
        let due = last.is_none_or(|l| l.elapsed() >= std::time::Duration::from_millis(200));
        if let (Some(t), true) = (token, due) {
            server.progress(t, step as f64, Some(planned as f64), "steps");
            last = Some(std::time::Instant::now());
        }
    };
    let opts = Options {
        steps,
        trace: None,
        record: None,
        threads,
        progress: Some(&mut tick),
        stop: Some(cancel),
        watch: None,
        // the answer is the summary: the marks are not kept
        marks: Some(lagra_run::marks::dropped()),
        ..Options::plain(steps)
    };
    let rep = lagra_run::run::run(scene, opts)?;
    let summary: report::Summary = run::summarize(&path, &prepared, &rep, threads, false);
    let doc = serde_json::to_value(&summary).map_err(|e| e.to_string())?;
    Ok(answer(serde_json::to_string_pretty(&doc).unwrap_or_default(), Some(doc), false))
}

fn recheck(server: &Server, args: &Value) -> Result<Value, String> {
    let cert =
        args.get("certificate").and_then(Value::as_str).ok_or("give the certificate's file under `certificate`")?;
    // under the roots, regular and within the limits, before the checker opens them
    let cert = server.resolve(cert).and_then(|p| reading::regular(&p, server.limits.certificate).map(|_| p))?;
    let states = match args.get("states").and_then(Value::as_str) {
        None => None,
        Some(s) => Some(server.resolve(s).and_then(|p| reading::regular(&p, server.limits.states).map(|_| p))?),
    };
    let r = lagra_checker::cli::check(&cert, states.as_deref());
    let text = format!("{}{}", r.stdout, r.stderr);
    // 2: a file missing or malformed; 0 and 1 are the re-check's answer
    Ok(answer(text, Some(json!({ "exit_code": r.code, "agrees_and_passes": r.code == 0 })), r.code == 2))
}

fn gradient(server: &Server, args: &Value, token: Option<&Value>) -> Result<Value, String> {
    let (text, path) = source(server, args)?;
    let prepared = match run::prepare(&text, &path, &settings(args)?, None) {
        Ok(p) => p,
        Err(e) => return Ok(answer(e, None, true)),
    };
    let mut scene = prepared.scene;
    if let Some(n) = positive_integer(args, "steps")? {
        scene.solver.steps = n;
    }
    let steps = scene.solver.steps;
    let atom_steps = 3.0 * steps as f64 * scene.model.bodies.len() as f64;
    if atom_steps > server.budget {
        return Err(format!(
            "this gradient is about {atom_steps:.3e} atom-steps (three passes), over the server's budget of {:.3e}",
            server.budget
        ));
    }
    let method = match args.get("method").and_then(Value::as_str) {
        None => grad::GradMethod::Reverse,
        Some(m) => {
            grad::GradMethod::from_name(m).ok_or_else(|| format!("method `{m}` is not reverse, forward or check"))?
        }
    };
    let (objective, wrt) =
        match (args.get("objective").and_then(Value::as_str), args.get("wrt").and_then(Value::as_str)) {
            (Some(o), Some(w)) => (o, w),
            _ => return Err("give `objective` and `wrt`".into()),
        };
    let (mut done, mut last) = (0u64, None::<std::time::Instant>);
    let mut tell = |what: &str, _: u64, _: u64| {
        done += 1;
        let due = last.is_none_or(|l| l.elapsed() >= std::time::Duration::from_millis(200));
        if let (Some(t), true) = (token, due) {
            server.progress(t, done as f64, None, &format!("gradient: {what} pass"));
            last = Some(std::time::Instant::now());
        }
    };
    let read = |file: &str| server.resolve(file).and_then(|p| reading::text(&p, server.limits.certificate));
    let (_, text) = grad::compute(&scene, objective, wrt, method, 1, &read, &mut tell)?;
    let doc = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    Ok(answer(text, Some(doc), false))
}

/// Each offered scene as a resource, `lagra://scenes/FILE`.
pub fn resources(dir: &Path) -> Result<Vec<Value>, String> {
    Ok(list::files(dir)?
        .iter()
        .filter_map(|f| f.file_name().map(|n| n.to_string_lossy().into_owned()))
        .map(|n| json!({ "uri": format!("lagra://scenes/{n}"), "name": n, "mimeType": "text/plain", "description": "A .lagra scene" }))
        .collect())
}

pub fn read_resource(server: &Server, uri: &str) -> Result<Value, String> {
    let name = uri
        .strip_prefix("lagra://scenes/")
        .ok_or_else(|| format!("no resource `{uri}`: resources are lagra://scenes/FILE"))?;
    let (_, text) = read_scene(server, name)?;
    Ok(json!({ "contents": [{ "uri": uri, "mimeType": "text/plain", "text": text }] }))
}

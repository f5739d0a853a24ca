//! `lagra mcp`: a Model Context Protocol server over stdio, for an agent that proposes changes
//! to a Lagrangian and reads back certified evidence.
//!
//! JSON-RPC 2.0, one message per line, on stdin and stdout (anything else goes to stderr). The
//! protocol is the handshake era's newest revision, 2025-11-25 (earlier ones down to 2024-11-05
//! are answered in their own name): `initialize`, `ping`, `tools/list`, `tools/call`,
//! `resources/list`, `resources/read`, progress notifications for a call that asks for them,
//! and `notifications/cancelled`. A client of the 2026-07-28 revision probes `server/discover`
//! first; it is answered "method not found", on which the official SDKs fall back to the
//! handshake. Each `tools/call` runs on a thread of its own, so that a long run can be
//! cancelled, and pinged, while it runs.
//!
//! Why no MCP crate: rmcp, the official Rust SDK, is built on tokio and macro-generated
//! routers; this server is a blocking loop, a thread per call and the eight methods above,
//! about two hundred lines, tested end to end by the official Python SDK (`tests/mcp_client.py`).
//! Bad input never stops the server: malformed JSON is a parse error, an unknown method or
//! tool a protocol error, a failing tool a result with `isError`.
//!
//! The server reads only under its roots (`--root`, the folder it was started in by default,
//! and the folder of scenes it offers), narrowed to the client's where the client offers them
//! (`roots/list`, asked after the handshake and again when the client says they changed; until
//! the answer comes, the server's own apply); every path is resolved, symlinks included, before
//! it is checked. Every input is bounded: files (regular files only, within `reading::Limits`),
//! inline scenes, `set` lists, a message's line, a run's atom-steps. It writes no file.

mod tools;

use crate::reading::{Limits, Roots};
use serde_json::{json, Value};
use std::collections::HashMap;
use std::io::{BufRead, Read, Write};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The revisions of the handshake era this server answers in, newest first.
const VERSIONS: [&str; 4] = ["2025-11-25", "2025-06-18", "2025-03-26", "2024-11-05"];

const PARSE_ERROR: i64 = -32700;
const INVALID_REQUEST: i64 = -32600;
const METHOD_NOT_FOUND: i64 = -32601;
const INVALID_PARAMS: i64 = -32602;

#[derive(clap::Args)]
pub struct Args {
    /// The folder of scenes the server offers (list_scenes, read_scene, resources).
    #[arg(long, value_name = "DIR", default_value = "scenes")]
    scenes: PathBuf,
    /// The largest run a call may ask for, in atom-steps (bodies × steps): a longer one is a
    /// tool error that says so.
    #[arg(long, value_name = "ATOM_STEPS", default_value_t = 2e9)]
    budget: f64,
    /// A folder the server may read under (repeatable; default: the folder it was started in;
    /// the scenes' folder is one too). Paths outside every root are refused, symlinks resolved
    /// first. File sizes are bounded by LAGRA_MAX_SCENE_BYTES (16 MiB),
    /// LAGRA_MAX_CERTIFICATE_BYTES (1 GiB) and LAGRA_MAX_STATES_BYTES (16 GiB).
    #[arg(long = "root", value_name = "DIR")]
    roots: Vec<PathBuf>,
}

/// The longest line (one JSON-RPC message) read: an inline scene at its limit, escaped.
fn longest_message(limits: &Limits) -> u64 {
    limits.scene.saturating_mul(2).saturating_add(1 << 20)
}

/// What every call's thread shares: the output, the calls in flight, the settings.
pub struct Server {
    out: Mutex<std::io::Stdout>,
    running: Mutex<HashMap<String, Arc<AtomicBool>>>,
    pub scenes: PathBuf,
    pub budget: f64,
    pub roots: Mutex<Roots>,
    pub limits: Limits,
    /// Whether the client offers its roots (asked for after the handshake).
    client_roots: AtomicBool,
}

impl Server {
    /// Writes one message, a line of JSON.
    fn send(&self, message: &Value) {
        let mut out = self.out.lock().unwrap_or_else(|p| p.into_inner());
        // a client that has gone away cannot be told anything: nothing to do but carry on
        let _ = writeln!(out, "{message}").and_then(|_| out.flush());
    }

    fn reply(&self, id: &Value, result: Value) {
        self.send(&json!({ "jsonrpc": "2.0", "id": id, "result": result }));
    }

    fn error(&self, id: &Value, code: i64, message: impl Into<String>) {
        self.send(&json!({ "jsonrpc": "2.0", "id": id, "error": { "code": code, "message": message.into() } }));
    }

    /// A progress notification for a call that gave a progress token.
    pub fn progress(&self, token: &Value, progress: f64, total: Option<f64>, message: &str) {
        let mut params = json!({ "progressToken": token, "progress": progress, "message": message });
        if let Some(t) = total {
            params["total"] = json!(t);
        }
        self.send(&json!({ "jsonrpc": "2.0", "method": "notifications/progress", "params": params }));
    }

    /// `path` resolved under the roots.
    pub fn resolve(&self, path: &str) -> Result<PathBuf, String> {
        self.roots.lock().unwrap_or_else(|p| p.into_inner()).resolve(path)
    }

    /// Asks the client for its roots; its answer narrows the server's (`answered`).
    fn ask_roots(&self) {
        if self.client_roots.load(Ordering::Relaxed) {
            self.send(&json!({ "jsonrpc": "2.0", "id": ROOTS_REQUEST, "method": "roots/list" }));
        }
    }

    /// A response from the client: the roots it was asked for.
    fn answered(&self, id: &Value, message: &Value) {
        if id != &json!(ROOTS_REQUEST) {
            return;
        }
        let roots = message.pointer("/result/roots").and_then(Value::as_array);
        let uris: Vec<String> = roots
            .into_iter()
            .flatten()
            .filter_map(|r| r.get("uri").and_then(Value::as_str).map(String::from))
            .collect();
        // an error or a malformed answer narrows to nothing: the client meant to say something
        self.roots.lock().unwrap_or_else(|p| p.into_inner()).narrow(&uris);
    }
}

/// The id of the server's one request, `roots/list`.
const ROOTS_REQUEST: &str = "lagra-roots";

pub fn main(a: Args) -> ExitCode {
    // the folder of scenes it offers is a root too, where it exists
    let mut dirs = if a.roots.is_empty() { vec![PathBuf::from(".")] } else { a.roots.clone() };
    dirs.extend(Some(a.scenes.clone()).filter(|s| s.is_dir()));
    let roots = match Roots::new(&dirs) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("lagra mcp: {e}");
            return ExitCode::from(2);
        }
    };
    let limits = Limits::from_env();
    let server = Arc::new(Server {
        out: Mutex::new(std::io::stdout()),
        running: Mutex::new(HashMap::new()),
        scenes: a.scenes,
        budget: a.budget,
        roots: Mutex::new(roots),
        limits,
        client_roots: AtomicBool::new(false),
    });
    let mut calls = vec![];
    let mut input = std::io::stdin().lock();
    let longest = longest_message(&limits);
    loop {
        let mut bytes = vec![];
        match (&mut input).take(longest + 1).read_until(b'\n', &mut bytes) {
            Ok(0) | Err(_) => break,
            Ok(_) => {}
        }
        if bytes.len() as u64 > longest {
            let mut rest = bytes.split_off(bytes.len() - 1);
            // the rest of the line is dropped unread into memory, a chunk at a time
            while !rest.ends_with(b"\n") {
                rest.clear();
                match (&mut input).take(1 << 20).read_until(b'\n', &mut rest) {
                    Ok(0) | Err(_) => break,
                    Ok(_) => {}
                }
            }
            server.error(&Value::Null, PARSE_ERROR, format!("a message longer than {longest} bytes: not read"));
            continue;
        }
        let line = String::from_utf8_lossy(&bytes);
        if line.trim().is_empty() {
            continue;
        }
        if let Some(call) = handle(&server, &line) {
            calls.push(call);
        }
        calls.retain(|c: &std::thread::JoinHandle<()>| !c.is_finished());
    }
    // stdin closed: the calls still running finish and answer (a client that will not wait
    // ends the process, as the stdio transport's shutdown says)
    calls.into_iter().for_each(|c| {
        let _ = c.join();
    });
    ExitCode::SUCCESS
}

/// Handles one line; a tool call is started on a thread of its own, whose handle is returned.
fn handle(server: &Arc<Server>, line: &str) -> Option<std::thread::JoinHandle<()>> {
    let message: Value = match serde_json::from_str(line) {
        Ok(v) => v,
        Err(e) => {
            server.error(&Value::Null, PARSE_ERROR, format!("not JSON: {e}"));
            return None;
        }
    };
    let id = message.get("id").cloned();
    let method = message.get("method").and_then(Value::as_str);
    let (Some(method), true) = (method, message.get("jsonrpc") == Some(&json!("2.0"))) else {
        // a response from the client answers our one request (`roots/list`); anything else is
        // invalid
        let response = message.get("result").is_some() || message.get("error").is_some();
        if let (Some(id), true) = (&id, response) {
            server.answered(id, &message);
        } else if id.is_some() && !response {
            server.error(
                id.as_ref().unwrap_or(&Value::Null),
                INVALID_REQUEST,
                "not a JSON-RPC 2.0 request: it needs \"jsonrpc\": \"2.0\" and a method",
            );
        } else if id.is_none() {
            server.error(&Value::Null, INVALID_REQUEST, "not a JSON-RPC 2.0 message");
        }
        return None;
    };
    let params = message.get("params").cloned().unwrap_or(json!({}));
    let Some(id) = id else {
        // a notification: cancellation is the one that asks for something
        match method {
            "notifications/cancelled" => {
                let key = params.get("requestId").map(|r| r.to_string()).unwrap_or_default();
                if let Some(flag) = server.running.lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
                    flag.store(true, Ordering::Relaxed);
                }
            }
            "notifications/initialized" | "notifications/roots/list_changed" => server.ask_roots(),
            _ => {}
        }
        return None;
    };
    match method {
        "initialize" => {
            let asked = params.get("protocolVersion").and_then(Value::as_str).unwrap_or(VERSIONS[0]);
            let version = VERSIONS.iter().find(|v| **v == asked).copied().unwrap_or(VERSIONS[0]);
            let offers_roots = params.pointer("/capabilities/roots").is_some_and(|r| !r.is_null());
            server.client_roots.store(offers_roots, Ordering::Relaxed);
            server.reply(
                &id,
                json!({
                    "protocolVersion": version,
                    "capabilities": { "tools": { "listChanged": false }, "resources": { "listChanged": false } },
                    "serverInfo": { "name": "lagra", "title": "Lagra", "version": env!("CARGO_PKG_VERSION") },
                    "instructions": tools::INSTRUCTIONS,
                }),
            );
        }
        "ping" => server.reply(&id, json!({})),
        "tools/list" => server.reply(&id, json!({ "tools": tools::list() })),
        "resources/list" => match tools::resources(&server.scenes) {
            Ok(r) => server.reply(&id, json!({ "resources": r })),
            Err(e) => server.error(&id, INVALID_PARAMS, e),
        },
        "resources/read" => {
            match tools::read_resource(server, params.get("uri").and_then(Value::as_str).unwrap_or("")) {
                Ok(r) => server.reply(&id, r),
                Err(e) => server.error(&id, INVALID_PARAMS, e),
            }
        }
        "tools/call" => {
            let name = params.get("name").and_then(Value::as_str).unwrap_or("").to_string();
            if !tools::exists(&name) {
                let known = tools::names().join(", ");
                server.error(&id, INVALID_PARAMS, format!("unknown tool `{name}`; tools: {known}"));
                return None;
            }
            let arguments = params.get("arguments").cloned().unwrap_or(json!({}));
            let token = params.get("_meta").and_then(|m| m.get("progressToken")).cloned();
            let cancel = Arc::new(AtomicBool::new(false));
            server.running.lock().unwrap_or_else(|p| p.into_inner()).insert(id.to_string(), cancel.clone());
            let server = server.clone();
            return Some(std::thread::spawn(move || {
                let result = tools::call(&server, &name, &arguments, token.as_ref(), &cancel);
                server.running.lock().unwrap_or_else(|p| p.into_inner()).remove(&id.to_string());
                // a cancelled request gets no response (the client has stopped waiting)
                if !cancel.load(Ordering::Relaxed) {
                    server.reply(&id, result);
                }
            }));
        }
        _ => server.error(&id, METHOD_NOT_FOUND, format!("method `{method}` not found")),
    }
    None
}

#[cfg(test)]
mod tests;

//! `lagra mcp` end to end: the raw protocol (bad input never stops the server; a long run
//! reports progress and can be cancelled while the server answers pings), and the official MCP
//! Python SDK driving it (tests/mcp_client.py, with the Python that `setup.sh` prepares).

use serde_json::{json, Value};
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::Duration;

struct Server {
    child: Child,
    stdin: ChildStdin,
    lines: Receiver<Value>,
}

impl Server {
    fn start(extra: &[&str]) -> Server {
        let mut child = Command::new(env!("CARGO_BIN_EXE_lagra"))
            .args([&["mcp"], extra].concat())
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        let stdin = child.stdin.take().unwrap();
        let stdout: ChildStdout = child.stdout.take().unwrap();
        let (tx, lines) = channel();
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                let v: Value =
                    serde_json::from_str(&line).unwrap_or_else(|e| panic!("the server wrote non-JSON {line:?}: {e}"));
                if tx.send(v).is_err() {
                    break;
                }
            }
        });
        Server { child, stdin, lines }
    }

    fn send(&mut self, raw: &str) {
        writeln!(self.stdin, "{raw}").unwrap();
        self.stdin.flush().unwrap();
    }

    fn request(&mut self, id: u64, method: &str, params: Value) {
        self.send(&json!({ "jsonrpc": "2.0", "id": id, "method": method, "params": params }).to_string());
    }

    /// The next message with this id (notifications before it are returned too).
    fn answer(&mut self, id: u64) -> (Value, Vec<Value>) {
        let mut notes = vec![];
        loop {
            let m = self.lines.recv_timeout(Duration::from_secs(60)).expect("the server answers");
            if m["id"] == json!(id) {
                return (m, notes);
            }
            notes.push(m);
        }
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
    }
}

#[test]
fn bad_input_gets_an_error_and_the_server_carries_on() {
    let mut s = Server::start(&[]);
    s.request(
        1,
        "initialize",
        json!({ "protocolVersion": "2025-06-18", "capabilities": {}, "clientInfo": { "name": "t", "version": "0" } }),
    );
    let (init, _) = s.answer(1);
    assert_eq!(init["result"]["protocolVersion"], "2025-06-18", "{init}");
    s.send("{ not json");
    let parse = s.lines.recv_timeout(Duration::from_secs(10)).unwrap();
    assert_eq!((parse["error"]["code"].as_i64(), parse["id"].clone()), (Some(-32700), Value::Null), "{parse}");
    s.send(r#"{"id": 2, "method": "ping"}"#);
    assert_eq!(s.answer(2).0["error"]["code"], -32600);
    s.request(3, "no/such/method", json!({}));
    assert_eq!(s.answer(3).0["error"]["code"], -32601);
    s.request(4, "tools/call", json!({ "name": "fly", "arguments": {} }));
    let (unknown, _) = s.answer(4);
    assert!(unknown["error"]["message"].as_str().unwrap().starts_with("unknown tool `fly`"), "{unknown}");
    s.request(
        5,
        "tools/call",
        json!({ "name": "run_scene", "arguments": { "scene": "scene s { solver { dt: 1 } }" } }),
    );
    let (broken, _) = s.answer(5);
    assert_eq!(broken["result"]["isError"], true);
    assert!(
        broken["result"]["content"][0]["text"].as_str().unwrap().contains("scene.lagra:1:1: scene s has no entities"),
        "{broken}"
    );
    s.request(6, "tools/call", json!({ "name": "run_scene", "arguments": { "path": "scenes/no_such.lagra" } }));
    assert_eq!(s.answer(6).0["result"]["isError"], true);
    s.request(7, "resources/read", json!({ "uri": "lagra://scenes/nowhere.lagra" }));
    assert!(s.answer(7).0["error"]["message"].as_str().unwrap().contains("no scene `nowhere.lagra`"));
    s.request(8, "ping", json!({}));
    assert_eq!(s.answer(8).0["result"], json!({}));
}

#[test]
fn a_long_run_reports_progress_and_can_be_cancelled() {
    let mut s = Server::start(&[]);
    s.request(
        1,
        "tools/call",
        json!({ "name": "run_scene", "arguments": { "path": "scenes/oscillator.lagra", "steps": 200_000_000 }, "_meta": { "progressToken": "run" } }),
    );
    let note = s.lines.recv_timeout(Duration::from_secs(60)).expect("a progress notification");
    assert_eq!(
        (note["method"].as_str(), note["params"]["progressToken"].as_str()),
        (Some("notifications/progress"), Some("run")),
        "{note}"
    );
    assert_eq!(note["params"]["total"], json!(2e8));
    // the server answers while the run goes on, and stops it when asked
    s.request(2, "ping", json!({}));
    assert_eq!(s.answer(2).0["result"], json!({}));
    s.send(&json!({ "jsonrpc": "2.0", "method": "notifications/cancelled", "params": { "requestId": 1, "reason": "test" } }).to_string());
    s.request(3, "ping", json!({}));
    let (pong, between) = s.answer(3);
    assert_eq!(pong["result"], json!({}));
    assert!(between.iter().all(|m| m["id"] != json!(1)), "the cancelled call was answered: {between:?}");
    // and over the budget a call is refused with the reason
    s.request(
        4,
        "tools/call",
        json!({ "name": "run_scene", "arguments": { "path": "scenes/oscillator.lagra", "steps": 2_000_000_000_u64 } }),
    );
    let (over, _) = s.answer(4);
    assert_eq!(over["result"]["isError"], true);
    assert!(over["result"]["content"][0]["text"].as_str().unwrap().contains("over the server's budget"), "{over}");
}

/// The Python that `setup.sh` prepares (the official MCP SDK in it), running `script`.
fn python(script: &str, args: &[&str]) -> (bool, String) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python =
        std::env::var("LAGRA_PYTHON").map(std::path::PathBuf::from).unwrap_or_else(|_| root.join(".venv/bin/python"));
    assert!(python.exists(), "{} is missing: run `bash setup.sh` (it makes .venv with the MCP SDK)", python.display());
    let o = Command::new(&python).arg(script).args(args).current_dir(root).output().unwrap();
    let (out, err) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    (o.status.success(), format!("{out}\n{err}"))
}

/// The official MCP Python SDK, which no one here wrote, as the client.
#[test]
fn the_official_python_sdk_drives_it() {
    let (ok, out) = python("tests/mcp_client.py", &[env!("CARGO_BIN_EXE_lagra")]);
    assert!(ok && out.contains("mcp_client: ok"), "{out}");
}

/// The same SDK asks for what lies outside the server's roots, and for inputs that are no
/// regular file or too large: each is refused, nothing echoed, and the server answers after.
#[test]
fn the_server_reads_only_under_its_roots_and_within_bounds() {
    let work = tempfile::tempdir().unwrap();
    let (ok, out) = python("tests/mcp_confined.py", &[env!("CARGO_BIN_EXE_lagra"), work.path().to_str().unwrap()]);
    assert!(ok && out.contains("mcp_confined: ok"), "{out}");
}

/// A client that offers roots is asked for them after the handshake; its answer narrows what
/// the server reads, and a change is asked about again.
#[test]
fn the_client_roots_narrow_the_server_roots() {
    let mut s = Server::start(&[]);
    s.request(1, "initialize", json!({ "protocolVersion": "2025-11-25", "capabilities": { "roots": { "listChanged": true } }, "clientInfo": { "name": "t", "version": "0" } }));
    s.answer(1);
    s.send(r#"{"jsonrpc":"2.0","method":"notifications/initialized"}"#);
    let asked = s.lines.recv_timeout(Duration::from_secs(60)).unwrap();
    assert_eq!((asked["method"].as_str(), asked["id"].as_str()), (Some("roots/list"), Some("lagra-roots")), "{asked}");
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let roots = |dir: &Path| json!({ "jsonrpc": "2.0", "id": "lagra-roots", "result": { "roots": [{ "uri": format!("file://{}", dir.display()) }] } });
    s.send(&roots(&here.join("scenes")).to_string());
    let check = |s: &mut Server, id: u64, path: &str| {
        s.request(id, "tools/call", json!({ "name": "check_scene", "arguments": { "path": path } }));
        s.answer(id).0["result"].clone()
    };
    assert_eq!(check(&mut s, 2, "scenes/oscillator.lagra")["isError"], json!(false));
    let outside = check(&mut s, 3, "tests/scenes_in_tests_are_outside.lagra");
    assert!(outside["content"][0]["text"].as_str().unwrap().contains("narrowed by the client"), "{outside}");
    s.send(r#"{"jsonrpc":"2.0","method":"notifications/roots/list_changed"}"#);
    let again = s.lines.recv_timeout(Duration::from_secs(60)).unwrap();
    assert_eq!(again["method"], json!("roots/list"));
    s.send(&roots(&here.join("no-such-folder")).to_string());
    assert_eq!(check(&mut s, 4, "scenes/oscillator.lagra")["isError"], json!(true));
}

/// A message longer than any inline scene could make is refused unread, and the next one is
/// answered as usual.
#[test]
fn an_overlong_message_is_refused_unread() {
    let mut s = Server::start(&[]);
    s.send(&"x".repeat(34 << 20));
    let refused = s.lines.recv_timeout(Duration::from_secs(60)).unwrap();
    assert!(refused["error"]["message"].as_str().unwrap().contains("not read"), "{refused}");
    s.request(1, "ping", json!({}));
    assert_eq!(s.answer(1).0["result"], json!({}));
}

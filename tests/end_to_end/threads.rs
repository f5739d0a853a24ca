//! Threads change nothing but the speed: every shipped scene steps to the same bits on any
//! number of threads (oversubscribed on a small machine), the checker starts no thread per
//! checkpoint, and a thread count the run cannot use is refused.

use crate::common::{lagra, scene, stderr, stdout};
use serde_json::Value;

/// Every scene in scenes/ (and the 32,000-atom bench, whose list is cut in 15 pieces), 30 steps
/// on 1, 2, 3, 7, 16 and 64 threads: the traces are the same bytes.
#[test]
fn every_shipped_scene_is_the_same_bits_on_any_number_of_threads() {
    let dir = tempfile::tempdir().unwrap();
    let mut scenes: Vec<String> = std::fs::read_dir("scenes")
        .unwrap()
        .map(|e| e.unwrap().path().to_string_lossy().into_owned())
        .filter(|p| p.ends_with(".lagra"))
        .collect();
    scenes.sort();
    scenes.push("scenes/bench/lj_32k.lagra".into());
    assert!(scenes.len() >= 19, "{scenes:?}");
    for scene in &scenes {
        let mut first: Option<Vec<u8>> = None;
        for threads in ["1", "2", "3", "7", "16", "64"] {
            let trace = dir.path().join(format!("t{threads}.jsonl"));
            let o = lagra(&[
                "run",
                scene,
                "--steps",
                "30",
                "--threads",
                threads,
                "--quiet",
                "--trace",
                trace.to_str().unwrap(),
            ]);
            assert!(matches!(o.status.code(), Some(0 | 1)), "{scene} on {threads}: {}{}", stdout(&o), stderr(&o));
            let bytes = std::fs::read(&trace).unwrap();
            assert!(bytes.len() > 100, "{scene}: a trace");
            match &first {
                None => first = Some(bytes),
                Some(one) => assert!(*one == bytes, "{scene}: {threads} threads differ from one"),
            }
        }
    }
}

/// The 32,000-atom bench's list is cut by its size, not by the threads, and says so.
#[test]
fn the_pieces_follow_the_size_and_explain_names_them() {
    for threads in ["1", "5"] {
        let o =
            lagra(&["run", "scenes/bench/lj_32k.lagra", "--steps", "2", "--threads", threads, "--explain", "--quiet"]);
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        assert!(stdout(&o).contains("15 piece(s) by size (halos: "), "{}", stdout(&o));
        assert!(stdout(&o).contains(&format!("on {threads} thread(s)")), "{}", stdout(&o));
    }
}

/// Kepler, judged at each of its 18,850 steps, has two bodies: no checkpoint spreads its sums,
/// so the checker starts no helper at all (one per checkpoint before); a liquid of 2,048 atoms
/// judged every step starts one pool for the whole run, whatever the number of checkpoints.
#[test]
fn a_checked_run_starts_no_thread_per_checkpoint() {
    let report = |args: &[&str]| -> Value {
        let o = lagra(args);
        assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
        serde_json::from_str(&stdout(&o)).unwrap()
    };
    let kepler = report(&["run", "scenes/kepler.lagra", "--json", "--quiet"]);
    assert_eq!(kepler["checker_helpers"], 0, "{kepler}");
    let dir = tempfile::tempdir().unwrap();
    let liquid = scene(
        dir.path(),
        "liquid.lagra",
        "scene liquid { entity atom { mass: 1 }
           lattice { type: atom, density: 0.8442, cells: [8, 8, 8], temperature: 1.44, seed: 3 }
           interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }
           @expect energy_conservation { tol: 1e-2, every: 1 }
           solver { dt: 0.002, steps: 20 } }",
    );
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    // (a trace keeps the checker inline: every checkpoint spreads over every CPU)
    let trace = dir.path().join("liquid.xyz");
    let liquid = report(&["run", liquid.to_str().unwrap(), "--json", "--quiet", "--trace", trace.to_str().unwrap()]);
    assert!(liquid["checker"].as_str().unwrap().starts_with("inline"), "{liquid}");
    let helpers = liquid["checker_helpers"].as_u64().unwrap() as usize;
    assert_eq!(helpers, if cpus > 1 { cpus } else { 0 }, "{helpers} helpers on {cpus} CPUs");
}

/// No thread, or more than a run may use, is a clear error before anything runs; without
/// `--threads` a small scene runs on one and says so.
#[test]
fn thread_counts_are_checked_and_the_default_is_reported() {
    let o = lagra(&["run", "scenes/oscillator.lagra", "--threads", "0"]);
    assert_eq!((o.status.code(), stderr(&o).trim()), (Some(2), "lagra: --threads must be at least 1"));
    let o = lagra(&["run", "scenes/oscillator.lagra", "--threads", "5000"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--threads 5000 is more than the 1024 a run may use"), "{}", stderr(&o));
    let o = lagra(&["run", "scenes/oscillator.lagra", "--json", "--quiet"]);
    let v: Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(v["threads"], 1);
}

/// `--threads` changes nothing but the speed: the trace is the same bytes, and `--explain`
/// names the plan the planner chose.
#[test]
fn threads_give_the_same_trajectory_and_explain_shows_the_plan() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(
        dir.path(),
        "melt.lagra",
        "scene melt { entity atom { mass: 1 }
           lattice { type: atom, density: 0.8442, cells: [11, 11, 11], temperature: 1.44, seed: 3 }
           interaction lj_shifted { epsilon: 1, sigma: 1, cutoff: 2.5 }
           @expect momentum_conservation { every: 5 }
           solver { dt: 0.005, steps: 10, steps_per_frame: 5 } }",
    );
    let scene = scene.to_str().unwrap();
    let mut traces = vec![];
    for threads in ["1", "2"] {
        let trace = dir.path().join(format!("t{threads}.jsonl"));
        let o = lagra(&["run", scene, "--threads", threads, "--explain", "--trace", trace.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(0), "{}{}", stdout(&o), stderr(&o));
        assert!(stdout(&o).contains("plan        LennardJonesShifted: cluster-pair list"), "{}", stdout(&o));
        assert!(stdout(&o).contains("piece(s) by size"), "{}", stdout(&o));
        // where the time went: four parts of the pair term's, together within the wall time
        let out = stdout(&o);
        let seconds = |after: &str| -> f64 {
            let at = out.find(after).unwrap_or_else(|| panic!("no `{after}` in {out}")) + after.len();
            out[at..].split(' ').next().unwrap().parse().unwrap()
        };
        let parts: Vec<f64> = ["time: builds ", "updates ", "pieces ", "sums "].iter().map(|p| seconds(p)).collect();
        assert!(parts[0] > 0.0 && parts[2] > 0.0, "{parts:?}");
        assert!(parts.iter().sum::<f64>() <= seconds("wall        ") + 0.002, "{parts:?}\n{out}");
        traces.push(std::fs::read(trace).unwrap());
    }
    assert!(traces[0].len() > 100_000);
    assert!(traces[0] == traces[1], "the trajectories differ between 1 and 2 threads");
    let o = lagra(&["run", scene, "--threads", "0"]);
    assert_eq!((o.status.code(), stderr(&o).trim()), (Some(2), "lagra: --threads must be at least 1"));
}

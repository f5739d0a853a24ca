//! `lagra._lagra`: the extension module behind `import lagra`. It compiles and runs scenes with
//! the same code as the `lagra` command (`lagra::run::prepare`, `summarize`), so a run's report
//! is the document `lagra run --json` prints; the Python package (`python/lagra`) wraps it.
//! A run releases the GIL; it takes it back only to call the progress and callback functions
//! and to look for Ctrl-C, which stops the run cleanly at the next look.

use lagra::grad::{compute, GradMethod};
use lagra::reading::source_digest;
use lagra::run::{prepare, summarize, Prepared};
use lagra_checker::model::Cell;
use lagra_kernel::state::State;
use lagra_lang::params::apply_settings;
use lagra_run::marks::Spill;
use lagra_run::restart::Restart;
use lagra_run::run::{run, Options, Restarts, Watch};
use lagra_run::thinned::Kept;
use lagra_run::trace::{rigid_bodies, Format, Recorded, Writer};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

create_exception!(_lagra, SceneError, PyValueError, "A scene that does not compile, or a setting it cannot take.");

/// A compiled scene.
#[pyclass(module = "lagra._lagra", name = "Scene")]
struct PyScene {
    prepared: Prepared,
    path: String,
    /// `sha256:` and the digest of the source, which a restart file must name.
    digest: String,
}

fn scene_error(e: impl Into<String>) -> PyErr {
    SceneError::new_err(e.into())
}

fn positive(name: &str, x: f64) -> PyResult<f64> {
    if x > 0.0 && x.is_finite() {
        Ok(x)
    } else {
        Err(PyValueError::new_err(format!("{name} must be positive and finite, got {x}")))
    }
}

fn at_least_one(name: &str, n: Option<u64>) -> PyResult<Option<u64>> {
    match n {
        Some(0) => Err(PyValueError::new_err(format!("{name} must be at least 1"))),
        n => Ok(n),
    }
}

/// An (n, 3) array as the state's vectors, checked: shape and finiteness.
fn vectors(name: &str, a: &PyReadonlyArray2<f64>, n: usize) -> PyResult<Vec<[f64; 3]>> {
    let shape = a.shape();
    if shape != [n, 3] {
        return Err(PyValueError::new_err(format!("{name} must have shape ({n}, 3), one row per body; got {shape:?}")));
    }
    let a = a.as_array();
    let out: Vec<[f64; 3]> = a.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
    if let Some(i) = out.iter().position(|v| v.iter().any(|c| !c.is_finite())) {
        return Err(PyValueError::new_err(format!("{name}: body {i} is not finite: {:?}", out[i])));
    }
    Ok(out)
}

fn rows<'py>(py: Python<'py>, v: &[[f64; 3]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = v.iter().flatten().copied().collect();
    flat.into_pyarray(py).reshape([v.len(), 3]).expect("n × 3 values")
}

#[pymethods]
impl PyScene {
    /// Compiles a scene's text; `path` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, path = "<string>"))]
    fn from_str(text: &str, path: &str) -> PyResult<Self> {
        let prepared = prepare(text, path, &[], None).map_err(scene_error)?;
        Ok(PyScene { prepared, path: path.into(), digest: source_digest(text) })
    }

    #[staticmethod]
    fn from_file(path: PathBuf) -> PyResult<Self> {
        let shown = path.display().to_string();
        if !path.exists() {
            return Err(PyFileNotFoundError::new_err(format!("{shown}: no such file")));
        }
        let text = lagra::reading::text(&path, lagra::reading::Limits::from_env().scene).map_err(PyOSError::new_err)?;
        Self::from_str(&text, &shown)
    }

    #[getter]
    fn name(&self) -> String {
        self.prepared.scene.name.clone()
    }

    #[getter]
    fn description(&self) -> Option<String> {
        self.prepared.scene.description.clone()
    }

    /// What the scene's declared claims cannot be supported by (Noether), as messages.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.prepared.warnings.clone()
    }

    #[getter]
    fn dt(&self) -> f64 {
        self.prepared.scene.solver.dt
    }

    #[getter]
    fn steps(&self) -> u64 {
        self.prepared.scene.solver.steps
    }

    #[getter]
    fn steps_per_frame(&self) -> u64 {
        self.prepared.scene.solver.steps_per_frame
    }

    /// Each term instance: kind, keyword, sites (bodies; empty for every pair or body) and its
    /// parameters by name.
    #[getter]
    fn terms<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.prepared
            .scene
            .model
            .terms
            .iter()
            .map(|t| {
                let d = PyDict::new(py);
                let spec = t.kind.spec();
                d.set_item("kind", spec.name)?;
                d.set_item("keyword", spec.keyword)?;
                d.set_item("sites", t.sites.clone())?;
                let params = PyDict::new(py);
                let mut at = 0;
                for p in spec.params {
                    let v = &t.params[at..at + p.len];
                    if p.len == 1 {
                        params.set_item(p.name, v[0])?;
                    } else {
                        params.set_item(p.name, v.to_vec())?;
                    }
                    at += p.len;
                }
                d.set_item("params", params)?;
                Ok(d)
            })
            .collect()
    }

    /// Each body's mass and charge.
    #[getter]
    fn bodies<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.prepared
            .scene
            .model
            .bodies
            .iter()
            .map(|b| {
                let d = PyDict::new(py);
                d.set_item("mass", b.mass)?;
                d.set_item("charge", b.charge)?;
                Ok(d)
            })
            .collect()
    }

    /// The initial positions, (bodies, 3).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &self.prepared.scene.x0)
    }

    #[setter]
    fn set_positions(&mut self, a: PyReadonlyArray2<f64>) -> PyResult<()> {
        let n = self.prepared.scene.x0.len();
        self.prepared.scene.x0 = vectors("positions", &a, n)?;
        self.prepared.scene.repredict().map_err(scene_error)
    }

    /// The initial velocities, (bodies, 3).
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows(py, &self.prepared.scene.v0)
    }

    #[setter]
    fn set_velocities(&mut self, a: PyReadonlyArray2<f64>) -> PyResult<()> {
        let n = self.prepared.scene.v0.len();
        self.prepared.scene.v0 = vectors("velocities", &a, n)?;
        self.prepared.scene.repredict().map_err(scene_error)
    }

    /// Sets a parameter by the spellings of `lagra grad` (`trap.k`, `body[0].mass`, ...).
    fn set(&mut self, name: &str, value: f64) -> PyResult<()> {
        let mut scene = self.prepared.scene.clone();
        apply_settings(&mut scene, &[format!("{name}={value}")]).map_err(scene_error)?;
        self.prepared.scene = scene;
        Ok(())
    }

    /// Runs the scene; the report is `lagra run --json`'s document.
    #[pyo3(signature = (steps=None, dt=None, threads=None, frame_every=None, progress=None, callback=None, callback_every=None, restart=None, resume=None, until=None))]
    #[allow(clippy::too_many_arguments)]
    fn _run(
        &self,
        py: Python<'_>,
        steps: Option<u64>,
        dt: Option<f64>,
        threads: Option<usize>,
        frame_every: Option<u64>,
        progress: Option<Py<PyAny>>,
        callback: Option<Py<PyAny>>,
        callback_every: Option<u64>,
        restart: Option<PathBuf>,
        resume: Option<PathBuf>,
        until: Option<u64>,
    ) -> PyResult<PyRun> {
        let resumed = resume
            .map(|p| Restart::read(&p).and_then(|r| r.belongs_to(&self.digest).map(|_| r)))
            .transpose()
            .map_err(|e| scene_error(format!("resume: {e}")))?;
        let mut prepared = self.prepared.clone();
        if let Some(dt) = dt {
            prepared.scene.solver.dt = positive("dt", dt)?;
        }
        if let Some(n) = at_least_one("frame_every", frame_every)? {
            prepared.scene.solver.steps_per_frame = n;
        }
        let steps = at_least_one("steps", steps)?;
        let callback_every = at_least_one("every", callback_every)?.unwrap_or(prepared.scene.solver.steps_per_frame);
        let threads = lagra_run::run::threads_for(prepared.scene.model.bodies.len(), threads)
            .map_err(|e| PyValueError::new_err(e.replacen("--threads", "threads", 1)))?;
        let stop = AtomicBool::new(false);
        let failure: Mutex<Option<PyErr>> = Mutex::new(None);
        let fail = |e: PyErr| {
            failure.lock().unwrap_or_else(|p| p.into_inner()).get_or_insert(e);
            stop.store(true, Ordering::Relaxed);
        };
        let mut frames = Kept::within(FRAME_BYTES);
        let marks =
            Spill::new(prepared.scene.claims.len(), None, true).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let scene = &prepared.scene;
        let outcome = py.detach(|| {
            // the restart at the end is the report's; none is written on the way
            let mut unused = |_: Restart| Ok(());
            let restarts = restart.is_some().then(|| Restarts { every: u64::MAX, write: &mut unused });
            // Ctrl-C is seen here, and the progress function called, about every 10⁶ atom-steps
            let mut tick = |step: u64| {
                Python::attach(|py| {
                    let seen = py.check_signals().and_then(|_| match &progress {
                        Some(p) => p.call1(py, (step,)).map(drop),
                        None => Ok(()),
                    });
                    seen.unwrap_or_else(fail)
                })
            };
            let mut see = |s: &State| {
                if let Some(c) = &callback {
                    Python::attach(|py| {
                        let state = PyDict::new(py);
                        let called = state
                            .set_item("t", s.t)
                            .and_then(|_| state.set_item("positions", rows(py, &s.x)))
                            .and_then(|_| state.set_item("velocities", rows(py, &s.v)))
                            .and_then(|_| c.call1(py, (s.step, state)).map(drop));
                        called.unwrap_or_else(fail)
                    })
                }
            };
            let watch = callback.is_some().then(|| Watch { every: callback_every, see: &mut see });
            let opts = Options {
                steps,
                trace: Some(&mut frames),
                record: None,
                threads,
                pool: None,
                progress: Some(&mut tick),
                stop: Some(&stop),
                watch,
                marks: Some(marks.sink()),
                resume: resumed,
                until,
                restarts,
                shared: None,
            };
            run(scene, opts)
        });
        // written where the run stopped, a Ctrl-C included, before that is raised
        let mut outcome = outcome;
        if let (Some(p), Ok(report)) = (&restart, outcome.as_mut()) {
            match report.restart.take() {
                Some(Ok(mut r)) => {
                    r.scene.clone_from(&self.digest);
                    r.write(p).map_err(PyOSError::new_err)?
                }
                Some(Err(why)) => return Err(scene_error(format!("no restart file written: {why}"))),
                None => {}
            }
        }
        if let Some(e) = failure.into_inner().unwrap_or_else(|p| p.into_inner()) {
            return Err(e);
        }
        let report = outcome.map_err(scene_error)?;
        let summary = summarize(&self.path, &prepared, &report, threads, false);
        let json = serde_json::to_string(&summary).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let (_, plotted) = marks.finish(&scene.claims).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let trails = serde_json::to_string(&plotted).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let frames = frames.into_recorded();
        let (k, n) = (frames.steps.len(), frames.bodies);
        // the frames' storage becomes the arrays' (no copy)
        let shaped = |v: Vec<f64>| v.into_pyarray(py).reshape([k, n, 3]).map(Bound::unbind);
        let rigid = rigid_bodies(&scene.model);
        let orientations = orientations(&frames.turns, &rigid, k, n)
            .map(|q| q.into_pyarray(py).reshape([k, n, 4]).map(Bound::unbind))
            .transpose()?;
        Ok(PyRun {
            report: json,
            trails,
            orientations,
            rigid,
            positions: shaped(frames.x)?,
            velocities: shaped(frames.v)?,
            frame_steps: frames.steps.into_pyarray(py).unbind(),
            times: frames.times.into_pyarray(py).unbind(),
            energies: frames.energies.into_pyarray(py).unbind(),
            cell: scene.model.cell,
        })
    }

    /// The gradient of `objective` with respect to `wrt` (the spellings of `lagra grad`), by
    /// reverse mode: `lagra grad --json`'s document.
    #[pyo3(signature = (objective, wrt, threads=1))]
    fn _gradient(&self, py: Python<'_>, objective: &str, wrt: Vec<String>, threads: usize) -> PyResult<String> {
        let scene = &self.prepared.scene;
        let wrt = wrt.join(",");
        py.detach(|| {
            compute(scene, objective, &wrt, GradMethod::Reverse, threads, &lagra::grad::read_trace, &mut |_, _, _| {})
        })
        .map(|(_, json)| json)
        .map_err(scene_error)
    }

    fn __repr__(&self) -> String {
        let s = &self.prepared.scene;
        format!(
            "<lagra.Scene {} : {} bodies, {} terms, {} steps of {}>",
            s.name,
            s.model.bodies.len(),
            s.model.terms.len(),
            s.solver.steps,
            s.solver.dt
        )
    }
}

/// The frames a run keeps for `Run.positions` and `Run.velocities` at most (1 GiB): past it every
/// 2nd, 4th, ... frame and the last (`frame_steps` says which); `lagra run --trace` keeps all.
const FRAME_BYTES: usize = 1 << 30;

/// A finished run: the report and the frames.
#[pyclass(module = "lagra._lagra", name = "Run")]
struct PyRun {
    #[pyo3(get)]
    report: String,
    /// Each claim's certified enclosure per checkpoint (the certificate's trails), at most
    /// `lagra_run::marks::PLOTTED` a claim: past that every 2nd, 4th, ... and the last.
    #[pyo3(get)]
    trails: String,
    #[pyo3(get)]
    positions: Py<PyArray3<f64>>,
    #[pyo3(get)]
    velocities: Py<PyArray3<f64>>,
    /// Each frame's orientation of every body (w, x, y, z), the identity for a point mass; None
    /// where the scene has no rigid body.
    #[pyo3(get)]
    orientations: Option<Py<PyArray3<f64>>>,
    /// The rigid bodies' indices (whose orientations a trace carries).
    rigid: Vec<usize>,
    #[pyo3(get)]
    frame_steps: Py<PyArray1<u64>>,
    #[pyo3(get)]
    times: Py<PyArray1<f64>>,
    #[pyo3(get)]
    energies: Py<PyArray1<f64>>,
    cell: Option<Cell>,
}

#[pymethods]
impl PyRun {
    /// Writes the frames as `lagra run --trace` would: `.jsonl`, `.xyz` or `.lammpstrj`.
    fn write(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let format = Format::of(&path).map_err(PyValueError::new_err)?;
        let x = self.positions.bind(py).readonly();
        let v = self.velocities.bind(py).readonly();
        let frames = Recorded {
            bodies: x.shape()[1],
            steps: self.frame_steps.bind(py).readonly().as_slice()?.to_vec(),
            times: self.times.bind(py).readonly().as_slice()?.to_vec(),
            energies: self.energies.bind(py).readonly().as_slice()?.to_vec(),
            x: x.as_slice()?.to_vec(),
            v: v.as_slice()?.to_vec(),
            turns: match &self.orientations {
                Some(q) => {
                    let q = q.bind(py).readonly();
                    let q = q.as_slice()?;
                    let n = x.shape()[1];
                    (0..x.shape()[0])
                        .flat_map(|k| self.rigid.iter().flat_map(move |&b| &q[4 * (k * n + b)..4 * (k * n + b) + 4]))
                        .copied()
                        .collect()
                }
                None => vec![],
            },
        };
        let file = std::fs::File::create(&path)
            .map_err(|e| PyOSError::new_err(format!("cannot create {}: {e}", path.display())))?;
        let mut w = Writer { out: std::io::BufWriter::new(file), format, cell: self.cell, rigid: self.rigid.clone() };
        frames
            .replay(&mut w)
            .and_then(|_| std::io::Write::flush(&mut w.out))
            .map_err(|e| PyOSError::new_err(e.to_string()))
    }
}

/// Every body's orientation in each of `k` frames of `n` bodies, flat (the identity for a point
/// mass), from the rigid bodies' (`turns`, four numbers each, `rigid` saying whose); none
/// without a rigid body.
fn orientations(turns: &[f64], rigid: &[usize], k: usize, n: usize) -> Option<Vec<f64>> {
    if rigid.is_empty() {
        return None;
    }
    let mut q: Vec<f64> = std::iter::repeat_n([1.0, 0.0, 0.0, 0.0], k * n).flatten().collect();
    for (at, turn) in turns.chunks_exact(4).enumerate() {
        let (frame, body) = (at / rigid.len(), rigid[at % rigid.len()]);
        q[4 * (frame * n + body)..4 * (frame * n + body) + 4].copy_from_slice(turn);
    }
    Some(q)
}

/// `lagra-check CERTIFICATE [--states STATES]`: (exit code, stdout, stderr).
#[pyfunction]
#[pyo3(signature = (certificate, states=None))]
fn check(certificate: PathBuf, states: Option<PathBuf>) -> (u8, String, String) {
    let r = lagra_checker::cli::check(&certificate, states.as_deref());
    (r.code, r.stdout, r.stderr)
}

#[pymodule]
fn _lagra(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyScene>()?;
    m.add_class::<PyRun>()?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    Ok(())
}

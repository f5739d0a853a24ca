//! Trajectories in the formats other tools read: JSON lines (Lagra's own: `lagra view` reads
//! it), extended XYZ (ASE, OVITO) and the LAMMPS text dump (OVITO, VMD, MDAnalysis). Numbers are
//! written in the shortest form that reads back to the same binary64, so a reader gets the
//! exact state.

use lagra_checker::model::{Cell, Model};
use lagra_kernel::state::State;
use serde::Serialize;
use std::io::{self, Write};
use std::path::Path;
use std::sync::mpsc::{sync_channel, SyncSender};
use std::thread::JoinHandle;

/// What a run hands each frame to.
pub trait Frames {
    fn frame(&mut self, s: &State, energy: f64) -> io::Result<()>;
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Format {
    Jsonl,
    Xyz,
    LammpsDump,
}

impl Format {
    /// By the file's extension: `.jsonl`, `.xyz`, `.lammpstrj`.
    pub fn of(path: &Path) -> Result<Format, String> {
        match path.extension().and_then(|e| e.to_str()) {
            Some("jsonl") => Ok(Format::Jsonl),
            Some("xyz") => Ok(Format::Xyz),
            Some("lammpstrj") => Ok(Format::LammpsDump),
            _ => Err(format!(
                "{}: a trace is .jsonl (Lagra's own), .xyz (extended XYZ) or .lammpstrj (LAMMPS text dump)",
                path.display()
            )),
        }
    }
}

/// Frames written to `out` in `format`; `cell` is the scene's box, if it has one; `rigid` the
/// rigid bodies' indices, in body order (a state's `spin[k]` is body `rigid[k]`'s).
pub struct Writer<W: Write> {
    pub out: W,
    pub format: Format,
    pub cell: Option<Cell>,
    pub rigid: Vec<usize>,
}

impl<W: Write> Writer<W> {
    /// A writer of the frames of a run of `model`.
    pub fn new(out: W, format: Format, model: &Model) -> Writer<W> {
        Writer { out, format, cell: model.cell, rigid: rigid_bodies(model) }
    }

    /// Every body's orientation (w, x, y, z), from its body frame to the world, the identity for
    /// a point mass; none where the model has no rigid body (the frame is then as it always was).
    fn orientations(&self, s: &State) -> Option<Vec<[f64; 4]>> {
        if self.rigid.is_empty() {
            return None;
        }
        let mut q = vec![[1.0, 0.0, 0.0, 0.0]; s.x.len()];
        for (&b, spin) in self.rigid.iter().zip(&s.spin) {
            q[b] = [spin[0], spin[1], spin[2], spin[3]];
        }
        Some(q)
    }
}

/// The indices of a model's rigid bodies, in body order.
pub fn rigid_bodies(model: &Model) -> Vec<usize> {
    (0..model.bodies.len()).filter(|&i| model.bodies[i].moments.is_some()).collect()
}

#[derive(Serialize)]
struct Line<'a> {
    step: u64,
    t: f64,
    energy: f64,
    x: &'a [[f64; 3]],
    v: &'a [[f64; 3]],
    /// Each body's orientation, where the scene has rigid bodies.
    #[serde(skip_serializing_if = "Option::is_none")]
    q: Option<Vec<[f64; 4]>>,
}

impl<W: Write> Frames for Writer<W> {
    fn frame(&mut self, s: &State, energy: f64) -> io::Result<()> {
        let q = self.orientations(s);
        let w = &mut self.out;
        match self.format {
            Format::Jsonl => {
                serde_json::to_writer(&mut *w, &Line { step: s.step, t: s.t, energy, x: &s.x, v: &s.v, q })?;
                writeln!(w)
            }
            Format::Xyz => {
                writeln!(w, "{}", s.x.len())?;
                let lattice = match &self.cell {
                    Some(c) => {
                        let [a, b, cc] = c.size;
                        let pbc = c.periodic.map(|p| if p { "T" } else { "F" }).join(" ");
                        format!("Lattice=\"{a} 0 0 0 {b} 0 0 0 {cc}\" pbc=\"{pbc}\" ")
                    }
                    None => String::new(),
                };
                // orientations as ASE names them (its readers' `quaternions` array)
                let turned = if q.is_some() { ":quaternions:R:4" } else { "" };
                writeln!(
                    w,
                    "{lattice}Properties=species:S:1:pos:R:3:velo:R:3{turned} step={} time={} energy={energy}",
                    s.step, s.t
                )?;
                for (i, (x, v)) in s.x.iter().zip(&s.v).enumerate() {
                    write!(w, "X {} {} {} {} {} {}", N(x[0]), N(x[1]), N(x[2]), N(v[0]), N(v[1]), N(v[2]))?;
                    quaternion(w, q.as_deref(), i)?;
                }
                Ok(())
            }
            Format::LammpsDump => {
                writeln!(w, "ITEM: TIMESTEP\n{}\nITEM: NUMBER OF ATOMS\n{}", s.step, s.x.len())?;
                // a periodic axis is the box; another one is what the bodies span
                let bounds: [(f64, f64, &str); 3] = std::array::from_fn(|a| match &self.cell {
                    Some(c) if c.periodic[a] => (0.0, c.size[a], "pp"),
                    _ => {
                        let lo = s.x.iter().map(|x| x[a]).fold(f64::INFINITY, f64::min);
                        let hi = s.x.iter().map(|x| x[a]).fold(f64::NEG_INFINITY, f64::max);
                        // a flat axis (a planar orbit) still gets a box a reader accepts
                        (lo, if hi > lo { hi } else { lo + 1.0 }, "ff")
                    }
                });
                writeln!(w, "ITEM: BOX BOUNDS {} {} {}", bounds[0].2, bounds[1].2, bounds[2].2)?;
                for (lo, hi, _) in bounds {
                    writeln!(w, "{} {}", N(lo), N(hi))?;
                }
                // unwrapped positions: Lagra never wraps a body into the box; orientations as
                // LAMMPS's dump custom names an ellipsoid's (body frame to space frame)
                let turned = if q.is_some() { " quatw quati quatj quatk" } else { "" };
                writeln!(w, "ITEM: ATOMS id type xu yu zu vx vy vz{turned}")?;
                for (i, (x, v)) in s.x.iter().zip(&s.v).enumerate() {
                    write!(w, "{} 1 {} {} {} {} {} {}", i + 1, N(x[0]), N(x[1]), N(x[2]), N(v[0]), N(v[1]), N(v[2]))?;
                    quaternion(w, q.as_deref(), i)?;
                }
                Ok(())
            }
        }
    }
}

/// Ends a body's line: its orientation's four numbers first, where there are orientations.
fn quaternion(w: &mut impl Write, q: Option<&[[f64; 4]]>, i: usize) -> io::Result<()> {
    match q {
        Some(q) => writeln!(w, " {} {} {} {}", N(q[i][0]), N(q[i][1]), N(q[i][2]), N(q[i][3])),
        None => writeln!(w),
    }
}

/// Frames written by a thread of their own, so that formatting them (the shortest digits of
/// every number: longer than a step on a big system) does not hold up the kernel. The run hands
/// over a copy of each frame's state; at most two wait, so memory stays that of two states. A
/// write error ends the writer: the next frame, or `finish`, returns it.
pub struct Behind<F: Frames + Send + 'static> {
    to: Option<SyncSender<(State, f64)>>,
    writer: Option<JoinHandle<(F, io::Result<()>)>>,
}

impl<F: Frames + Send + 'static> Behind<F> {
    pub fn new(mut inner: F) -> Behind<F> {
        let (to, frames) = sync_channel::<(State, f64)>(2);
        let writer = std::thread::Builder::new().name("lagra-trace".into()).spawn(move || {
            let written = frames.into_iter().try_for_each(|(s, energy)| inner.frame(&s, energy));
            (inner, written)
        });
        match writer {
            Ok(w) => Behind { to: Some(to), writer: Some(w) },
            // no thread to be had: no writer either (`finish` says so)
            Err(_) => Behind { to: None, writer: None },
        }
    }

    /// Waits for every frame to be written; the writer back, and how the writing went.
    pub fn finish(mut self) -> io::Result<F> {
        drop(self.to.take());
        let (inner, written) = self.joined()?;
        written.map(|_| inner)
    }

    fn joined(&mut self) -> io::Result<(F, io::Result<()>)> {
        let thread = self.writer.take().ok_or_else(|| io::Error::other("the trace's writer thread could not start"))?;
        thread.join().map_err(|_| io::Error::other("the trace's writer thread panicked"))
    }
}

impl<F: Frames + Send + 'static> Frames for Behind<F> {
    fn frame(&mut self, s: &State, energy: f64) -> io::Result<()> {
        let sent = self.to.as_ref().map(|to| to.send((s.clone(), energy)));
        match sent {
            Some(Ok(())) => Ok(()),
            // the writer stopped on an error: that error
            _ => {
                self.to = None;
                let (_, written) = self.joined()?;
                written.and(Err(io::Error::other("the trace's writer stopped")))
            }
        }
    }
}

/// A number in text, exactly (the shortest digits that read back to the same binary64), with an
/// exponent where plain digits would run long: 0.1, 3, 1e-300.
struct N(f64);

impl std::fmt::Display for N {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-5..1e16).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// Frames kept in memory, flat: frame k's body i's coordinate c at `x[3·(k·n + i) + c]`.
#[derive(Clone, Debug, Default)]
pub struct Recorded {
    pub bodies: usize,
    pub steps: Vec<u64>,
    pub times: Vec<f64>,
    pub energies: Vec<f64>,
    pub x: Vec<f64>,
    pub v: Vec<f64>,
    /// Each frame's rigid bodies' orientations (w, x, y, z), four numbers a rigid body.
    pub turns: Vec<f64>,
}

impl Frames for Recorded {
    fn frame(&mut self, s: &State, energy: f64) -> io::Result<()> {
        self.bodies = s.x.len();
        self.steps.push(s.step);
        self.times.push(s.t);
        self.energies.push(energy);
        self.x.extend(s.x.iter().flatten());
        self.v.extend(s.v.iter().flatten());
        self.turns.extend(s.spin.iter().flat_map(|r| &r[..4]));
        Ok(())
    }
}

impl Recorded {
    /// Writes every frame again, to `to`.
    pub fn replay(&self, to: &mut dyn Frames) -> io::Result<()> {
        let n = self.bodies;
        let vecs =
            |a: &[f64], k: usize| a[3 * k * n..3 * (k + 1) * n].chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        let rigid = self.turns.len() / (4 * self.steps.len()).max(1);
        // (a writer reads a spin's orientation only: its angular momentum is left zero)
        let spins = |k: usize| {
            self.turns[4 * k * rigid..4 * (k + 1) * rigid]
                .chunks_exact(4)
                .map(|q| [q[0], q[1], q[2], q[3], 0.0, 0.0, 0.0])
                .collect()
        };
        for k in 0..self.steps.len() {
            let s = State {
                step: self.steps[k],
                t: self.times[k],
                x: vecs(&self.x, k),
                v: vecs(&self.v, k),
                chain: vec![],
                spin: spins(k),
            };
            to.frame(&s, self.energies[k])?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> State {
        State {
            step: 7,
            t: 0.035,
            x: vec![[0.1, -2.5, 1e-300], [3.0, 4.0, 5.0]],
            v: vec![[1.0, 0.0, -1.0], [0.5, 0.25, 0.125]],
            chain: vec![],
            spin: vec![],
        }
    }

    fn written(format: Format, cell: Option<Cell>) -> String {
        let mut w = Writer { out: vec![], format, cell, rigid: vec![] };
        w.frame(&state(), -1.5).unwrap();
        String::from_utf8(w.out).unwrap()
    }

    #[test]
    fn extended_xyz_has_the_cell_the_step_and_exact_numbers() {
        let cell = Cell { size: [10.0, 11.0, 12.5], periodic: [true, true, false] };
        assert_eq!(
            written(Format::Xyz, Some(cell)),
            "2\nLattice=\"10 0 0 0 11 0 0 0 12.5\" pbc=\"T T F\" Properties=species:S:1:pos:R:3:velo:R:3 step=7 time=0.035 energy=-1.5\nX 0.1 -2.5 1e-300 1 0 -1\nX 3 4 5 0.5 0.25 0.125\n"
        );
        assert!(written(Format::Xyz, None).lines().nth(1).unwrap().starts_with("Properties="));
    }

    #[test]
    fn a_lammps_dump_has_the_box_or_the_span() {
        let cell = Cell { size: [10.0, 11.0, 12.5], periodic: [true, true, false] };
        let text = written(Format::LammpsDump, Some(cell));
        assert!(
            text.starts_with(
                "ITEM: TIMESTEP\n7\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS pp pp ff\n0 10\n0 11\n1e-300 5\n"
            ),
            "{text}"
        );
        assert!(text.ends_with(
            "ITEM: ATOMS id type xu yu zu vx vy vz\n1 1 0.1 -2.5 1e-300 1 0 -1\n2 1 3 4 5 0.5 0.25 0.125\n"
        ));
    }

    /// A scene with a rigid body: every format carries each body's orientation (the identity
    /// for a point mass), as its readers name it; exact numbers.
    #[test]
    fn orientations_go_wherever_the_state_goes() {
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let turned = State { spin: vec![[c, 0.0, 0.0, s, 0.0, 0.0, 0.5]], ..state() };
        let write = |format| {
            let mut w = Writer { out: vec![], format, cell: None, rigid: vec![1] };
            w.frame(&turned, -1.5).unwrap();
            String::from_utf8(w.out).unwrap()
        };
        let line: serde_json::Value = serde_json::from_str(&write(Format::Jsonl)).unwrap();
        assert_eq!(line["q"], serde_json::json!([[1.0, 0.0, 0.0, 0.0], [c, 0.0, 0.0, s]]));
        let xyz = write(Format::Xyz);
        assert!(xyz.contains("Properties=species:S:1:pos:R:3:velo:R:3:quaternions:R:4 "), "{xyz}");
        assert!(xyz.ends_with(&format!("X 3 4 5 0.5 0.25 0.125 {c} 0 0 {s}\n")), "{xyz}");
        let dump = write(Format::LammpsDump);
        assert!(
            dump.contains(
                "ITEM: ATOMS id type xu yu zu vx vy vz quatw quati quatj quatk\n1 1 0.1 -2.5 1e-300 1 0 -1 1 0 0 0\n"
            ),
            "{dump}"
        );
        // without rigid bodies, the frames are as they always were
        assert!(!written(Format::Jsonl, None).contains("\"q\""));
    }

    /// Frames written behind, on the writer's thread, are the bytes written in place.
    #[test]
    fn frames_written_behind_are_the_same_bytes() {
        let mut here = Writer { out: vec![], format: Format::Jsonl, cell: None, rigid: vec![] };
        let mut behind = Behind::new(Writer { out: vec![], format: Format::Jsonl, cell: None, rigid: vec![] });
        for k in 0..50 {
            let s = State { step: k, ..state() };
            here.frame(&s, k as f64).unwrap();
            behind.frame(&s, k as f64).unwrap();
        }
        assert_eq!(behind.finish().unwrap().out, here.out);
    }

    /// A writer that fails: its error comes back, at a later frame or at the end.
    #[test]
    fn a_failing_writer_behind_says_why() {
        struct Full;
        impl Frames for Full {
            fn frame(&mut self, _: &State, _: f64) -> io::Result<()> {
                Err(io::Error::other("no space left"))
            }
        }
        let mut behind = Behind::new(Full);
        let sent: Vec<io::Result<()>> = (0..10).map(|_| behind.frame(&state(), 0.0)).collect();
        let error = sent.into_iter().find_map(Result::err).or_else(|| behind.finish().err());
        assert_eq!(error.map(|e| e.to_string()), Some("no space left".into()));
    }

    #[test]
    fn formats_come_from_the_extension() {
        assert_eq!(Format::of(Path::new("a/b.xyz")), Ok(Format::Xyz));
        assert_eq!(Format::of(Path::new("run.lammpstrj")), Ok(Format::LammpsDump));
        assert_eq!(Format::of(Path::new("t.jsonl")), Ok(Format::Jsonl));
        assert!(Format::of(Path::new("t.csv")).unwrap_err().contains(".jsonl (Lagra's own), .xyz"));
    }

    #[test]
    fn recorded_frames_replay_to_the_same_text() {
        // a point mass and a rigid body, turning
        let turned = |k: u64| State { step: k, spin: vec![[0.6, 0.0, 0.8, 0.0, 1.0, 2.0, 3.0]], ..state() };
        let mut r = Recorded::default();
        r.frame(&turned(7), -1.5).unwrap();
        r.frame(&State { spin: vec![[0.0, 1.0, 0.0, 0.0, 1.0, 2.0, 3.0]], ..turned(8) }, -1.25).unwrap();
        let writer = || Writer { out: vec![], format: Format::Jsonl, cell: None, rigid: vec![1] };
        let mut direct = writer();
        direct.frame(&turned(7), -1.5).unwrap();
        direct.frame(&State { spin: vec![[0.0, 1.0, 0.0, 0.0, 1.0, 2.0, 3.0]], ..turned(8) }, -1.25).unwrap();
        let mut again = writer();
        r.replay(&mut again).unwrap();
        assert_eq!(String::from_utf8(direct.out).unwrap(), String::from_utf8(again.out).unwrap());
    }
}

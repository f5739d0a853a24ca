//! `lagra bench validation`: Lagra's Lennard-Jones fluid against a table no one here made — the
//! NIST Standard Reference Simulation Website's Monte Carlo NVT results (`nist_mc_nvt.csv` in
//! the validation directory, one scene per state point beside it). Prints ⟨U⟩/N and ⟨P⟩ with
//! their standard errors beside the published values, and each difference in combined
//! standard errors (z), and writes the table as Markdown.

use lagra_run::compile;
use lagra_run::observables::Estimate;
use lagra_run::run::{run, Options};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// `--quick`: this many steps, the first `QUICK_EQUILIBRATE` time units left out.
pub const QUICK_STEPS: u64 = 12_000;
pub const QUICK_EQUILIBRATE: f64 = 10.0;

/// |z| above this is a disagreement.
pub const AGREE: f64 = 3.0;

/// A published value and its uncertainty (absent where the table gives none).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Published {
    pub value: f64,
    pub err: Option<f64>,
}

/// One state point of the table.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    pub t: String,
    pub rho: String,
    pub energy: Published,
    pub pressure: Published,
}

impl Point {
    /// The scene that runs it (`scenes/generate.py` writes them).
    pub fn scene(&self, dir: &Path) -> PathBuf {
        dir.join(format!("lj_t{}_rho{}.lagra", self.t.replace('.', ""), self.rho.replace('.', "")))
    }
}

#[derive(Serialize)]
pub struct Compared {
    pub point: Point,
    pub steps: u64,
    pub wall_s: f64,
    pub energy: Estimate,
    pub pressure: Option<Estimate>,
    pub z_energy: Option<f64>,
    pub z_pressure: Option<f64>,
}

/// The table: `T,rho,U,U_err,P,P_err`, `#` comments.
pub fn table(dir: &Path) -> Result<Vec<Point>, String> {
    let path = dir.join("nist_mc_nvt.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut rows = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#')).skip(1);
    rows.try_fold(vec![], |mut out, (n, line)| {
        let at = |what: &str| format!("{}:{}: {what}", path.display(), n + 1);
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != 6 {
            return Err(at(&format!("expected 6 fields (T,rho,U,U_err,P,P_err), got {}", f.len())));
        }
        let number = |s: &str| s.parse::<f64>().map_err(|_| at(&format!("`{s}` is not a number")));
        let optional = |s: &str| if s.is_empty() { Ok(None) } else { number(s).map(Some) };
        out.push(Point {
            t: f[0].to_string(),
            rho: f[1].to_string(),
            energy: Published { value: number(f[2])?, err: optional(f[3])? },
            pressure: Published { value: number(f[4])?, err: optional(f[5])? },
        });
        Ok(out)
    })
}

/// (ours − theirs) over the combined standard error.
pub fn z(ours: &Estimate, theirs: &Published) -> Option<f64> {
    let se = (ours.stderr?.powi(2) + theirs.err.unwrap_or(0.0).powi(2)).sqrt();
    (se > 0.0).then(|| (ours.mean - theirs.value) / se)
}

/// Runs one state point (for `steps` steps, equilibrating over the first `equilibrate` time, if
/// given: a shorter run than the scene's).
pub fn compare(point: &Point, dir: &Path, shorter: Option<(u64, f64)>) -> Result<Compared, String> {
    let path = point.scene(dir);
    let source = std::fs::read_to_string(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let mut scene = compile(&source).map_err(|d| d.render(&path.display().to_string(), &source).to_string())?;
    let mut steps = None;
    if let (Some((n, equilibrate)), Some(s)) = (shorter, scene.sampling.as_mut()) {
        steps = Some(n);
        s.equilibrate = equilibrate;
    }
    let opts = Options { marks: Some(lagra_run::marks::dropped()), ..Options::plain(steps) };
    let report = run(&scene, opts)?;
    if let Some(stop) = &report.stop {
        return Err(format!("{}: the run stopped early: {stop:?}", path.display()));
    }
    let o = report.observables.ok_or_else(|| format!("{}: the run measured nothing", path.display()))?;
    Ok(Compared {
        z_energy: z(&o.potential_energy_per_body, &point.energy),
        z_pressure: o.pressure.as_ref().and_then(|p| z(p, &point.pressure)),
        point: point.clone(),
        steps: report.steps,
        wall_s: report.wall_s,
        energy: o.potential_energy_per_body,
        pressure: o.pressure,
    })
}

/// A mean and its error, to two significant digits of the error.
fn shown(e: &Estimate) -> String {
    match e.stderr.filter(|s| *s > 0.0) {
        Some(s) => {
            let digits = (1.0 - s.log10().floor()).clamp(0.0, 12.0) as usize;
            format!("{:.digits$} ± {:.digits$}", e.mean, s)
        }
        None => format!("{:.6}", e.mean),
    }
}

fn published(p: &Published) -> String {
    match p.err {
        Some(e) => format!("{} ± {e}", p.value),
        None => format!("{}", p.value),
    }
}

fn zed(z: Option<f64>) -> String {
    z.map_or("–".into(), |z| format!("{z:+.1}{}", if z.abs() > AGREE { " ✗" } else { "" }))
}

/// The comparison as a Markdown table.
pub fn markdown(rows: &[Compared]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "| T* | ρ* | steps | Lagra ⟨U⟩/N | NIST U/N | z | Lagra ⟨P⟩ | NIST P | z | wall (s) |");
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.1} |",
            r.point.t,
            r.point.rho,
            r.steps,
            shown(&r.energy),
            published(&r.point.energy),
            zed(r.z_energy),
            r.pressure.as_ref().map_or("–".into(), shown),
            published(&r.point.pressure),
            zed(r.z_pressure),
            r.wall_s
        );
    }
    s
}

/// `lagra bench validation`.
pub fn study(dir: &Path, out: Option<&Path>, only: Option<&str>, quick: bool, json: bool) -> Result<String, String> {
    let points: Vec<Point> = table(dir)?
        .into_iter()
        .filter(|p| only.is_none_or(|o| p.scene(dir).display().to_string().contains(o)))
        .collect();
    if points.is_empty() {
        return Err(format!("no state point of {} matches", dir.join("nist_mc_nvt.csv").display()));
    }
    let shorter = quick.then_some((QUICK_STEPS, QUICK_EQUILIBRATE));
    let mut rows = vec![];
    for p in &points {
        let r = compare(p, dir, shorter)?;
        eprintln!(
            "lagra: T {} rho {}: U/N {} (NIST {}), P {} (NIST {})",
            p.t,
            p.rho,
            shown(&r.energy),
            published(&p.energy),
            r.pressure.as_ref().map_or("–".into(), shown),
            published(&p.pressure)
        );
        rows.push(r);
    }
    let table = markdown(&rows);
    if let Some(out) = out {
        std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
        let path = out.join("validation_table.md");
        std::fs::write(&path, &table).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    }
    if json {
        return serde_json::to_string_pretty(&rows).map(|t| t + "\n").map_err(|e| e.to_string());
    }
    Ok(table)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_reads_and_names_its_scenes() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/validation");
        let points = table(&dir).unwrap();
        assert_eq!(points.len(), 20);
        for p in &points {
            assert!(p.scene(&dir).exists(), "{}", p.scene(&dir).display());
        }
        let dense = points.iter().find(|p| p.t == "0.85" && p.rho == "0.860").unwrap();
        assert_eq!((dense.energy.value, dense.energy.err), (-6.0305, Some(2.3e-4)));
    }

    #[test]
    fn a_malformed_table_is_an_error_with_its_line() {
        let dir = std::env::temp_dir().join(format!("lagra-validation-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("nist_mc_nvt.csv"), "# c\nT,rho,U,U_err,P,P_err\n0.85,0.86,x,,1,\n").unwrap();
        let e = table(&dir).unwrap_err();
        assert!(e.ends_with("nist_mc_nvt.csv:3: `x` is not a number"), "{e}");
        std::fs::write(dir.join("nist_mc_nvt.csv"), "T,rho,U,U_err,P,P_err\n0.85,0.86\n").unwrap();
        assert!(table(&dir).unwrap_err().contains("expected 6 fields"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_mean_is_shown_to_its_error() {
        let e = |mean, stderr| shown(&Estimate { mean, stderr: Some(stderr), samples: 1 });
        assert_eq!(e(-6.03142, 0.0018), "-6.0314 ± 0.0018");
        assert_eq!(e(0.000843, 0.0000012), "0.0008430 ± 0.0000012");
        assert_eq!(e(1.25, 0.3), "1.25 ± 0.30");
    }

    #[test]
    fn z_combines_both_errors() {
        let ours = Estimate { mean: 1.0, stderr: Some(0.3), samples: 10 };
        assert_eq!(z(&ours, &Published { value: 0.5, err: Some(0.4) }), Some(1.0));
        assert_eq!(z(&ours, &Published { value: 0.4, err: None }), Some(2.0));
        assert_eq!(z(&Estimate { stderr: None, ..ours }, &Published { value: 0.4, err: None }), None);
    }
}

//! `lagra check CERTIFICATE... [--states FILE]... [--scene FILE [--set NAME=VALUE]...]`.

use lagra_checker::certificate::Certificate;
use lagra_run::compile;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    /// The certificate `lagra run --certificate` wrote; for a run resumed from restart files,
    /// every segment's certificate, in order (re-checked as one run).
    #[arg(required = true, num_args = 1..)]
    certificate: Vec<PathBuf>,
    /// The state file `lagra run --states` wrote: every enclosure is then evaluated again (one
    /// per certificate, in the same order).
    #[arg(long, value_name = "FILE")]
    states: Vec<PathBuf>,
    /// The scene source: the certificate must be of this exact source, its model and claims
    /// those the source compiles to (catches a certificate edited and re-sealed).
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// With --scene: the settings the run was made with (`lagra run --set`, a `lagra sweep`
    /// variant's row), applied to the scene before it is compared.
    #[arg(long = "set", value_name = "NAME=VALUE", requires = "scene")]
    set: Vec<String>,
}

pub fn main(a: Args) -> ExitCode {
    if !a.states.is_empty() && a.states.len() != a.certificate.len() {
        eprintln!(
            "lagra: {} state files for {} certificates: one per certificate, in order",
            a.states.len(),
            a.certificate.len()
        );
        return ExitCode::from(2);
    }
    let r = lagra_checker::cli::check_chain(&paths(&a.certificate), &paths(&a.states));
    print!("{}", r.stdout);
    eprint!("{}", r.stderr);
    let mut code = r.code;
    if let (Some(scene), 0 | 1) = (&a.scene, code) {
        match a.certificate.iter().try_for_each(|c| of_scene(c, scene, &a.set)) {
            Ok(()) => println!("scene       {} compiles to the certified model and claims", scene.display()),
            Err(why) => {
                println!("scene       DISAGREES: {why}");
                code = 1;
            }
        }
    }
    ExitCode::from(code)
}

/// The certificate's source digest, model and claims are those of `scene` with `set` applied.
fn of_scene(cert: &PathBuf, scene: &PathBuf, set: &[String]) -> Result<(), String> {
    let limits = crate::reading::Limits::from_env();
    let source = crate::reading::text(scene, limits.scene)?;
    let text = crate::reading::text(cert, limits.certificate)?;
    let c = Certificate::read(&text)?;
    if c.source_digest != crate::reading::source_digest(&source) {
        return Err(format!("the certificate is of another source ({})", c.source_digest));
    }
    let path = scene.display().to_string();
    let mut s = compile(&source).map_err(|d| d.render(&path, &source).head)?;
    lagra_lang::params::apply_settings(&mut s, set)?;
    // `@expect noether` stands for the claims the derived table gives
    crate::noether::apply(&mut s, &path, &source);
    if *s.model != c.model {
        return Err("the certified model is not the one the source compiles to".into());
    }
    if s.claims != c.claims {
        return Err("the certified claims are not the ones the source declares".into());
    }
    Ok(())
}

fn paths(v: &[PathBuf]) -> Vec<&std::path::Path> {
    v.iter().map(PathBuf::as_path).collect()
}

//! Any text as a scene: compiled (the language, the kernel's placing, the tail corrections) it
//! gives a scene or a located error whose rendering must not panic either; a small scene that
//! compiles is run for a few steps, claims checked, which must end in a report or an error.
#![no_main]

use lagra_run::run::{run, Options};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(source) = std::str::from_utf8(data) else { return };
    match lagra_run::compile(source) {
        Err(d) => drop(d.render("fuzz.lagra", source).to_string()),
        Ok(scene) if scene.model.bodies.len() <= 64 => drop(run(&scene, Options::plain(Some(3)))),
        Ok(_) => {}
    }
});

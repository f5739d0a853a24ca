//! The house stays drawn: docs/DESIGN.md's table of rooms says, for each crate of the
//! workspace, which project crates it may import and the order of its own modules from the
//! bottom up. This test holds the code to it: a crate whose manifest names a project crate
//! outside its row fails, and so does a module that reaches (by `use` or by a path) a module
//! listed after it — a circle needs one such edge. Test code (`#[cfg(test)]` items and the
//! `tests.rs` files they declare) may reach anything: it stands above every room.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use syn::visit::Visit;

/// One row of the table: a crate, the project crates it may depend on, its modules bottom-up.
#[derive(Debug)]
struct Room {
    package: String,
    folder: String,
    may_import: BTreeSet<String>,
    modules: Vec<String>,
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The rows of the table that follows the `<!-- rooms -->` mark in docs/DESIGN.md:
/// `| room | folder | package | may import | modules, bottom up |`.
fn rooms() -> Vec<Room> {
    let design = std::fs::read_to_string(root().join("docs/DESIGN.md")).unwrap();
    let table = design.split("<!-- rooms -->").nth(1).expect("docs/DESIGN.md has a `<!-- rooms -->` table");
    let cells = |line: &str| -> Vec<String> {
        line.trim().trim_matches('|').split('|').map(|c| c.trim().replace('`', "")).collect()
    };
    let list = |cell: &str| -> Vec<String> {
        cell.split(',').map(str::trim).filter(|s| !s.is_empty() && *s != "nothing").map(String::from).collect()
    };
    table
        .lines()
        .skip_while(|l| !l.trim_start().starts_with('|'))
        .take_while(|l| l.trim_start().starts_with('|'))
        .skip(2)
        .map(|l| {
            let c = cells(l);
            assert_eq!(c.len(), 5, "a row of the rooms table has five cells: {l}");
            Room {
                folder: c[1].trim_end_matches('/').to_string(),
                package: c[2].clone(),
                may_import: list(&c[3]).into_iter().collect(),
                modules: list(&c[4]),
            }
        })
        .collect()
}

/// Each workspace package and the workspace packages it depends on (normal and build
/// dependencies; dev-dependencies are test code), as cargo itself resolves them.
fn manifests() -> BTreeMap<String, BTreeSet<String>> {
    let out = std::process::Command::new(env!("CARGO"))
        .args(["metadata", "--format-version", "1", "--no-deps", "--offline"])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(out.status.success(), "cargo metadata: {}", String::from_utf8_lossy(&out.stderr));
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let members: BTreeSet<String> =
        meta["packages"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_string()).collect();
    meta["packages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|d| d["kind"].as_str() != Some("dev"))
                .map(|d| d["name"].as_str().unwrap().to_string())
                .filter(|n| members.contains(n))
                .collect();
            (p["name"].as_str().unwrap().to_string(), deps)
        })
        .collect()
}

#[test]
fn every_crate_imports_only_the_rooms_its_row_allows() {
    let rooms = rooms();
    let manifests = manifests();
    for (package, deps) in &manifests {
        let room = rooms.iter().find(|r| &r.package == package);
        let room = room.unwrap_or_else(|| panic!("{package} has no row in docs/DESIGN.md's rooms table"));
        let outside: Vec<_> = deps.difference(&room.may_import).collect();
        assert!(outside.is_empty(), "{package} depends on {outside:?}, which its row in docs/DESIGN.md does not allow");
    }
    assert!(rooms.iter().all(|r| manifests.contains_key(&r.package)), "a row names no workspace package");
}

/// The top-level modules a file reaches, outside test code: `crate::m…` and, from the file's
/// own place, `super::m…`.
struct Reach<'a> {
    /// The file's module path below the crate root (`["forces", "pairs"]`).
    at: &'a [String],
    found: BTreeSet<String>,
}

impl Reach<'_> {
    fn path<'s>(&mut self, segments: impl IntoIterator<Item = &'s syn::Ident>) {
        let names: Vec<String> = segments.into_iter().map(|i| i.to_string()).collect();
        let mut here: Vec<String> = self.at.to_vec();
        let mut rest = names.as_slice();
        match rest.first().map(String::as_str) {
            Some("crate") => {
                here.clear();
                rest = &rest[1..];
            }
            Some("super") => {
                while rest.first().map(String::as_str) == Some("super") {
                    here.pop();
                    rest = &rest[1..];
                }
            }
            _ => return,
        }
        let top = here.first().or(rest.first());
        if let Some(top) = top.filter(|t| *t != "self" && *t != "super") {
            self.found.insert(top.clone());
        }
    }

    fn tree(&mut self, prefix: &mut Vec<syn::Ident>, tree: &syn::UseTree) {
        match tree {
            syn::UseTree::Path(p) => {
                prefix.push(p.ident.clone());
                self.tree(prefix, &p.tree);
                prefix.pop();
            }
            syn::UseTree::Name(n) => self.path(prefix.iter().chain([&n.ident])),
            syn::UseTree::Rename(r) => self.path(prefix.iter().chain([&r.ident])),
            syn::UseTree::Glob(_) => self.path(prefix.iter()),
            syn::UseTree::Group(g) => g.items.iter().for_each(|t| self.tree(prefix, t)),
        }
    }
}

fn is_test(attrs: &[syn::Attribute]) -> bool {
    attrs
        .iter()
        .any(|a| a.path().is_ident("cfg") && a.parse_args::<syn::Meta>().is_ok_and(|m| m.path().is_ident("test")))
}

impl<'ast> Visit<'ast> for Reach<'_> {
    fn visit_item_mod(&mut self, m: &'ast syn::ItemMod) {
        if !is_test(&m.attrs) {
            syn::visit::visit_item_mod(self, m);
        }
    }
    fn visit_item_fn(&mut self, f: &'ast syn::ItemFn) {
        if !is_test(&f.attrs) {
            syn::visit::visit_item_fn(self, f);
        }
    }
    fn visit_item_use(&mut self, u: &'ast syn::ItemUse) {
        if !is_test(&u.attrs) {
            self.tree(&mut vec![], &u.tree);
        }
    }
    fn visit_path(&mut self, p: &'ast syn::Path) {
        self.path(p.segments.iter().map(|s| &s.ident));
        syn::visit::visit_path(self, p);
    }
}

/// Every `.rs` file under `src` but the test files (`tests.rs`, or a `tests/` folder), with its
/// module path.
fn sources(src: &Path) -> Vec<(PathBuf, Vec<String>)> {
    let mut out = vec![];
    let mut stack = vec![src.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n != "bin" && n != "tests") {
                    stack.push(p);
                }
                continue;
            }
            let name = p.file_stem().unwrap().to_str().unwrap().to_string();
            if p.extension().is_none_or(|x| x != "rs") || name == "tests" {
                continue;
            }
            let mut module: Vec<String> = p
                .parent()
                .unwrap()
                .strip_prefix(src)
                .unwrap()
                .iter()
                .map(|c| c.to_str().unwrap().to_string())
                .collect();
            if !["lib", "main", "mod"].contains(&name.as_str()) {
                module.push(name);
            }
            out.push((p, module));
        }
    }
    out.sort();
    out
}

#[test]
fn every_module_reaches_only_the_modules_below_it() {
    let mut wrong = vec![];
    for room in rooms().iter().filter(|r| !r.modules.is_empty()) {
        let src = root().join(&room.folder).join("src");
        let place = |m: &str| room.modules.iter().position(|n| n == m);
        for (file, module) in sources(&src) {
            let Some(top) = module.first() else { continue };
            let me = place(top).unwrap_or_else(|| {
                panic!(
                    "{}: module `{top}` is not in {}'s row of docs/DESIGN.md's rooms table",
                    file.display(),
                    room.package
                )
            });
            let text = std::fs::read_to_string(&file).unwrap();
            let parsed = syn::parse_file(&text).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            let mut reach = Reach { at: &module, found: BTreeSet::new() };
            reach.visit_file(&parsed);
            for other in reach.found.iter().filter(|m| *m != top) {
                // a name the row does not list is an item of the crate root (a re-export, `compile`)
                if place(other).is_some_and(|o| o > me) {
                    wrong.push(format!("{}: `{top}` reaches `{other}`, listed above it", file.display()));
                }
            }
        }
    }
    assert!(wrong.is_empty(), "modules reaching up (docs/DESIGN.md's rooms table):\n{}", wrong.join("\n"));
}

/// The test bites: a module reaching one above it, and a circle, are both found.
#[test]
fn a_module_reaching_up_is_found() {
    let at = vec!["state".to_string()];
    let mut reach = Reach { at: &at, found: BTreeSet::new() };
    let file: syn::File = syn::parse_str(
        "use crate::{sum::Sum, forces::{self, Force}}; use super::graph::*; fn f() { crate::solvers::go(); }
         #[cfg(test)] mod tests { use crate::run::run; }",
    )
    .unwrap();
    reach.visit_file(&file);
    assert_eq!(reach.found, ["forces", "graph", "solvers", "sum"].map(String::from).into_iter().collect());
    let nested = vec!["forces".to_string(), "pairs".to_string()];
    let mut reach = Reach { at: &nested, found: BTreeSet::new() };
    reach.visit_file(&syn::parse_str("use super::groups::Rows; use super::super::neighbours::Neighbours;").unwrap());
    assert_eq!(reach.found, ["forces", "neighbours"].map(String::from).into_iter().collect());
}

/// The figure after `before` in `text` (whitespace taken as one space), thousands' commas
/// dropped: "**4,221 lines**" after "The trusted core is" is 4221.
fn figure_after(text: &str, before: &str) -> usize {
    let flat = text.split_whitespace().collect::<Vec<_>>().join(" ");
    let at = flat.find(before).unwrap_or_else(|| panic!("no `{before}`")) + before.len();
    let digits: String =
        flat[at..].trim_start_matches([' ', '*']).chars().take_while(|c| c.is_ascii_digit() || *c == ',').collect();
    digits.replace(',', "").parse().unwrap_or_else(|e| panic!("`{before}` is followed by no figure: {e}"))
}

/// The trusted core's size, as README.md and docs/trust.md state it, is what
/// `checker/tcb-lines.sh` counts now, and within the budget they state: a change to the checker
/// that moves a line updates the figure (and, past the budget, says why in docs/trust.md).
#[test]
fn the_trusted_core_is_the_size_the_docs_say() {
    let out = std::process::Command::new("bash").arg(root().join("checker/tcb-lines.sh")).output().unwrap();
    assert!(out.status.success(), "tcb-lines.sh: {}", String::from_utf8_lossy(&out.stderr));
    let counted = String::from_utf8(out.stdout).unwrap();
    let (core, terms) = (figure_after(&counted, "core"), figure_after(&counted, "term definitions"));
    let read = |f: &str| std::fs::read_to_string(root().join(f)).unwrap();
    let (readme, trust) = (read("README.md"), read("docs/trust.md"));
    assert_eq!(figure_after(&readme, "The trusted core is"), core, "README.md: the core's lines");
    assert_eq!(figure_after(&readme, "lines** of code, plus"), terms, "README.md: the terms' lines");
    assert_eq!(figure_after(&trust, "tests and proofs: a core of"), core, "docs/trust.md: the core's lines");
    let after_core = &trust[trust.find("a core of").unwrap()..];
    assert_eq!(figure_after(after_core, "lines and"), terms, "docs/trust.md: the terms' lines");
    let (budget, each) = (figure_after(&readme, "the budget is"), figure_after(&readme, "for the core and"));
    let count = figure_after(&readme, "of term definitions (");
    assert!(core <= budget, "the core's {core} lines are over README.md's budget of {budget}");
    assert!(terms <= each * count, "the terms' {terms} lines are over {each} for each of {count}");
}

/// The test bites: the figure is read past bold marks, commas and a line break, and a
/// different figure is a different number.
#[test]
fn a_figure_is_read_from_the_docs() {
    assert_eq!(figure_after("The trusted core is **4,221\n  lines** of", "The trusted core is"), 4221);
    assert_eq!(figure_after("core 3743\nterm definitions 631", "term definitions"), 631);
    assert_ne!(figure_after("a core of 3,743 lines", "a core of"), 4221);
}

/// GitHub's anchor for a heading: lower case, punctuation dropped but for `-` and `_`, spaces as
/// hyphens ("The last checkpoint's list (2026-12-04)" is `the-last-checkpoints-list-2026-12-04`);
/// a heading seen before gets `-1`, `-2`, ….
fn anchors(markdown: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    for (_, line) in prose(markdown).filter(|l| l.1.starts_with('#')) {
        let slug: String = line
            .trim_start_matches('#')
            .trim()
            .to_lowercase()
            .chars()
            .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
            .map(|c| if c == ' ' { '-' } else { c })
            .collect();
        let free = (0..).map(|n| if n == 0 { slug.clone() } else { format!("{slug}-{n}") }).find(|s| !seen.contains(s));
        seen.insert(free.expect("a free name"));
    }
    seen
}

/// The lines of a markdown text outside its fenced code blocks, numbered from 1.
fn prose(markdown: &str) -> impl Iterator<Item = (usize, &str)> {
    let mut fenced = false;
    markdown.lines().enumerate().filter_map(move |(n, l)| {
        let fence = l.starts_with("```");
        fenced ^= fence;
        (!fenced && !fence).then_some((n + 1, l))
    })
}

/// The targets of the inline links `[text](target)` outside code blocks, with their lines.
fn links(markdown: &str) -> Vec<(usize, &str)> {
    let mut found = vec![];
    for (n, line) in prose(markdown) {
        for (at, _) in line.match_indices("](") {
            let rest = &line[at + 2..];
            found.push((n, &rest[..rest.find(')').unwrap_or(rest.len())]));
        }
    }
    found
}

/// Every link of the project's own markdown (README.md, docs/) to a file of the project names one
/// that is there, and every `#anchor` a heading of its file: a section renamed or moved (as the
/// goals' log moved to docs/bench/history.md) leaves no link to nothing behind.
#[test]
fn every_link_of_the_docs_leads_somewhere() {
    let mut docs = vec![root().join("README.md")];
    let mut folders = vec![root().join("docs")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(folder).unwrap().map(Result::unwrap) {
            match entry.path() {
                p if p.is_dir() => folders.push(p),
                p if p.extension().is_some_and(|e| e == "md") => docs.push(p),
                _ => {}
            }
        }
    }
    let mut broken = vec![];
    for doc in &docs {
        let text = std::fs::read_to_string(doc).unwrap();
        for (line, target) in links(&text).into_iter().filter(|(_, t)| !t.contains(':')) {
            let (file, anchor) = target.split_once('#').unwrap_or((target, ""));
            let path = if file.is_empty() { doc.clone() } else { doc.parent().unwrap().join(file) };
            let at = format!("{}:{line}: ({target})", doc.strip_prefix(root()).unwrap().display());
            if !path.exists() {
                broken.push(format!("{at}: no such file"));
            } else if !anchor.is_empty() && !anchors(&std::fs::read_to_string(&path).unwrap()).contains(anchor) {
                broken.push(format!("{at}: no such heading"));
            }
        }
    }
    assert!(docs.len() > 10, "{docs:?}");
    assert_eq!(broken, Vec::<String>::new());
}

/// The anchors are GitHub's, and a link inside a code block is not a link.
#[test]
fn anchors_are_githubs_and_code_blocks_hold_no_links() {
    let doc = "# Threads on 16 cores, beside LAMMPS (2026-11-27)\n## The last checkpoint's list\n## A\n## A\n\
               ```\n## not a heading [x](nowhere.md)\n```\nsee [it](docs/x.md#y) and [b](#c)\n";
    let want = ["threads-on-16-cores-beside-lammps-2026-11-27", "the-last-checkpoints-list", "a", "a-1"];
    assert_eq!(anchors(doc), want.into_iter().map(String::from).collect());
    assert_eq!(links(doc), vec![(8, "docs/x.md#y"), (8, "#c")]);
}

//! Issue #12: dependencies point one way. The numeric core never names the edges
//! (`ingest`, `report`, `cli`), the CLI and rendering crates (clap, polars,
//! plotters) or anyhow, and touches no file (`std::fs`): it can be read, tested and
//! reused without them. Every source file is classified below, so a new module must
//! be placed on one side or the other before this test passes.
//!
//! The scan reads code, not comments (doc comments may say where a file is read).

use std::path::{Path, PathBuf};

/// The core: files and folders (every `.rs` below a folder).
const CORE: &[&str] = &[
    "src/calibrate.rs",
    "src/campaign_means.rs",
    "src/ensemble.rs",
    "src/error.rs",
    "src/facade.rs",
    "src/fit.rs",
    "src/fragility.rs",
    "src/outcomes.rs",
    "src/ground_motion",
    "src/peaks",
    "src/reduction.rs",
    "src/restitution.rs",
    "src/signal",
    "src/solver",
    "src/stats.rs",
    "src/study.rs",
    "src/synth.rs",
    "src/wall.rs",
];

/// The edges, and the crate root that declares every module (it names the edges
/// to declare them).
const EDGES: &[&str] = &[
    "src/archive",
    "src/ingest",
    "src/report",
    "src/cli",
    "src/atomic.rs",
    "src/main.rs",
    "src/lib.rs",
];

/// What a core file must not name: (pattern, why).
const FORBIDDEN: &[(&str, &str)] = &[
    ("crate::ingest", "the input edge"),
    ("rocklab::ingest", "the input edge"),
    ("crate::report", "the report edge"),
    ("rocklab::report", "the report edge"),
    ("crate::cli", "the binary"),
    ("clap", "the CLI crate"),
    ("polars", "a rendering crate"),
    ("plotters", "a rendering crate"),
    ("anyhow", "the binary's error crate"),
    ("std::fs", "file access"),
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn rust_files(p: &Path, out: &mut Vec<PathBuf>) {
    if p.is_dir() {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(p).unwrap().map(|e| e.unwrap().path()).collect();
        entries.sort();
        for e in entries {
            rust_files(&e, out);
        }
    } else if p.extension().is_some_and(|e| e == "rs") {
        out.push(p.to_path_buf());
    }
}

fn files_of(list: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for p in list {
        let p = root().join(p);
        assert!(p.exists(), "{} is listed but does not exist", p.display());
        rust_files(&p, &mut out);
    }
    out
}

/// The code of a line: without its `//` comment (a `//` inside a string is rare
/// enough in this crate; a false alarm would show as a failure to look at).
fn code(line: &str) -> &str {
    line.split("//").next().unwrap_or("")
}

/// Whether `word` stands in `text` as a whole identifier or path segment.
fn names(text: &str, word: &str) -> bool {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    text.match_indices(word).any(|(i, _)| {
        let before = text[..i].chars().next_back();
        let after = text[i + word.len()..].chars().next();
        !before.is_some_and(ident) && !after.is_some_and(ident)
    })
}

#[test]
fn the_core_names_no_edge_and_touches_no_file() {
    let mut offences = Vec::new();
    let core = files_of(CORE);
    assert!(core.len() >= 20, "the scan found only {} core files", core.len());
    for f in &core {
        let text = std::fs::read_to_string(f).unwrap();
        for (n, line) in text.lines().enumerate() {
            for (pattern, why) in FORBIDDEN {
                if names(code(line), pattern) {
                    offences.push(format!(
                        "{}:{}: names {pattern} ({why}): {}",
                        f.strip_prefix(root()).unwrap().display(),
                        n + 1,
                        line.trim()
                    ));
                }
            }
        }
    }
    assert!(offences.is_empty(), "the core depends on the edges:\n{}", offences.join("\n"));
}

#[test]
fn every_source_file_is_core_or_edge() {
    let mut listed = files_of(CORE);
    listed.extend(files_of(EDGES));
    let mut all = Vec::new();
    rust_files(&root().join("src"), &mut all);
    let unlisted: Vec<_> = all.iter().filter(|f| !listed.contains(f)).collect();
    assert!(unlisted.is_empty(), "classify these in tests/architecture.rs: {unlisted:?}");
    let core = files_of(CORE);
    let both: Vec<_> = files_of(EDGES).into_iter().filter(|f| core.contains(f)).collect();
    assert!(both.is_empty(), "both core and edge: {both:?}");
}

/// The checker itself: it sees a forbidden name in code, not in a comment, and not
/// inside a longer identifier.
#[test]
fn the_scan_sees_what_it_must() {
    assert!(names(code("use crate::ingest::Campaign;"), "crate::ingest"));
    assert!(names(code("    let e = anyhow::anyhow!(\"x\");"), "anyhow"));
    assert!(!names(code("/// read by `crate::ingest::record`"), "crate::ingest"));
    assert!(!names(code("let x = 1; // std::fs is not used"), "std::fs"));
    assert!(!names("let my_anyhow_like = 1;", "anyhow"));
    assert!(names("use std::fs;", "std::fs"));
}

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
    "src/impacts.rs",
    "src/law_fit.rs",
    "src/law_replay.rs",
    "src/limits.rs",
    "src/outcomes.rs",
    "src/ground_motion",
    "src/peaks",
    "src/reduction.rs",
    "src/restitution.rs",
    "src/restitution_law.rs",
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

// ---------------------------------------------------------------------------
// Issue #21: no import cycles between the files of `src`.
//
// The module graph is read from the paths the code names: `crate::…`, `super::…`,
// `self::…`, a child module declared in the file (`mod x;` then `x::…`), and
// `rocklab::…` from the binary. A path is followed to the file that defines its
// item: through `pub use` re-exports (a re-export is an alias, not a dependency of
// the file that holds it), to the longest module prefix that is a file. Inline
// modules (`mod tests { … }`) are left out: their `super` is the file itself.
// A module's paths into its own submodules (`peaks/mod.rs` calling `segments::…`)
// are the module tree, not an import: a folder's `mod.rs` may hold the types its
// files share and orchestrate them. Every other path to another file is an edge
// (a child naming its parent's types included); any loop among the edges fails.

use std::collections::{BTreeMap, BTreeSet};

/// A module: (crate, path), crate "lib" (src/lib.rs) or "bin" (src/main.rs, src/cli).
type Module = (&'static str, Vec<String>);

/// The module a source file defines, from its path relative to the repository.
fn module_of(rel: &str) -> Module {
    let rel = rel.strip_prefix("src/").unwrap_or(rel).trim_end_matches(".rs");
    let krate = if rel == "main" || rel.starts_with("cli/") || rel == "cli" {
        "bin"
    } else {
        "lib"
    };
    let mut segs: Vec<String> = rel.split('/').map(str::to_string).collect();
    if segs.last().is_some_and(|s| s == "mod") {
        segs.pop();
    }
    if segs.len() == 1 && (segs[0] == "lib" || segs[0] == "main") {
        segs.clear();
    }
    (krate, segs)
}

/// The code of a file without comments and without inline `mod x { … }` blocks.
fn code_without_inline_modules(text: &str) -> String {
    let mut out = String::new();
    let mut skip_depth: Option<i64> = None;
    for line in text.lines() {
        let c = code(line);
        let t = c.trim_start();
        let t = t.strip_prefix("pub(crate) ").or_else(|| t.strip_prefix("pub ")).unwrap_or(t);
        if skip_depth.is_none() && t.starts_with("mod ") && c.contains('{') {
            skip_depth = Some(0);
        }
        if let Some(d) = skip_depth.as_mut() {
            *d += c.matches('{').count() as i64 - c.matches('}').count() as i64;
            if *d <= 0 && c.contains('}') {
                skip_depth = None;
            }
            continue;
        }
        out.push_str(c);
        out.push('\n');
    }
    out
}

/// Tokens of a path expression: identifiers, `::`, `{`, `}`, `,`, `*`.
fn path_tokens(s: &str) -> Vec<String> {
    let mut toks = Vec::new();
    let mut chars = s.chars().peekable();
    while let Some(&c) = chars.peek() {
        if c.is_alphanumeric() || c == '_' {
            let mut id = String::new();
            while let Some(&c) = chars.peek().filter(|c| c.is_alphanumeric() || **c == '_') {
                id.push(c);
                chars.next();
            }
            toks.push(id);
        } else if c == ':' {
            chars.next();
            if chars.peek() == Some(&':') {
                chars.next();
                toks.push("::".into());
            }
        } else {
            chars.next();
            if "{},*".contains(c) {
                toks.push(c.to_string());
            }
        }
    }
    toks
}

/// Expand a use tree (`a::{b, c::{d as e, *}}`) into (path, name it binds).
fn expand_use(toks: &[String], pos: &mut usize, prefix: &[String], out: &mut Vec<(Vec<String>, String)>) {
    let mut path = prefix.to_vec();
    while *pos < toks.len() {
        let t = toks[*pos].clone();
        *pos += 1;
        match t.as_str() {
            "::" => {}
            "{" => {
                loop {
                    expand_use(toks, pos, &path, out);
                    if *pos >= toks.len() || toks[*pos] == "}" {
                        *pos += 1;
                        return;
                    }
                    *pos += 1; // ','
                }
            }
            "," | "}" => {
                *pos -= 1;
                break;
            }
            "as" => {
                let name = toks.get(*pos).cloned().unwrap_or_default();
                *pos += 1;
                out.push((path.clone(), name));
                return;
            }
            _ => path.push(t),
        }
    }
    if path.len() > 1 && path.last().is_some_and(|s| s == "self") {
        path.pop();
    }
    if let Some(name) = path.last().cloned() {
        out.push((path, name));
    }
}

/// The files of a crate source tree, their edges and aliases.
struct ModuleGraph {
    files: BTreeMap<Module, String>,
    /// `pub use` re-exports: the path they define → the path they name.
    aliases: BTreeMap<Module, Module>,
    /// Paths each file names: (file, absolute path).
    named: Vec<(String, Module)>,
}

impl ModuleGraph {
    fn new(sources: &[(String, String)]) -> ModuleGraph {
        let mut g = ModuleGraph {
            files: BTreeMap::new(),
            aliases: BTreeMap::new(),
            named: Vec::new(),
        };
        for (rel, _) in sources {
            g.files.insert(module_of(rel), rel.clone());
        }
        for (rel, text) in sources {
            g.scan(rel, &code_without_inline_modules(text));
        }
        g
    }

    /// An absolute path for `path` as written in the module `here`, or None for an
    /// external crate.
    fn absolute(&self, here: &Module, path: &[String]) -> Option<Module> {
        let (krate, mut segs) = (here.0, here.1.clone());
        let mut rest = path;
        match rest.first().map(String::as_str) {
            Some("crate") => segs.clear(),
            Some("rocklab") => return Some(("lib", rest[1..].to_vec())),
            Some("super") => {
                while rest.first().is_some_and(|s| s == "super") {
                    segs.pop();
                    rest = &rest[1..];
                }
                segs.extend(rest.iter().cloned());
                return Some((krate, segs));
            }
            Some("self") => {}
            Some(first) => {
                let mut child = segs.clone();
                child.push(first.to_string());
                if !self.files.contains_key(&(krate, child)) {
                    return None;
                }
                segs.extend(rest.iter().cloned());
                return Some((krate, segs));
            }
            None => return None,
        }
        segs.extend(rest[1..].iter().cloned());
        Some((krate, segs))
    }

    fn scan(&mut self, rel: &str, code: &str) {
        let here = module_of(rel);
        // `use` statements, `pub use` as aliases.
        let mut rest = code;
        while let Some(i) = find_word(rest, "use") {
            let before = rest[..i].trim_end();
            let public = before.ends_with("pub") || before.ends_with("pub(crate)");
            let end = rest[i..].find(';').map_or(rest.len(), |e| i + e);
            let toks = path_tokens(&rest[i + 3..end]);
            let mut bound = Vec::new();
            expand_use(&toks, &mut 0, &[], &mut bound);
            for (path, name) in bound {
                let Some(abs) = self.absolute(&here, &path) else { continue };
                if public && name != "*" {
                    let mut at = here.1.clone();
                    at.push(name);
                    self.aliases.insert((here.0, at), abs);
                } else {
                    let mut abs = abs;
                    if abs.1.last().is_some_and(|s| s == "*") {
                        abs.1.pop();
                    }
                    self.named.push((rel.to_string(), abs));
                }
            }
            rest = &rest[end.min(rest.len())..];
        }
        // Paths in the code: `crate::a::b`, `super::c`, `rocklab::d`.
        let no_use = strip_use_statements(code);
        for root_word in ["crate", "super", "rocklab"] {
            let mut rest = no_use.as_str();
            while let Some(i) = find_word(rest, root_word) {
                let tail = &rest[i..];
                let end = tail.find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':')).unwrap_or(tail.len());
                let toks = path_tokens(&tail[..end]);
                let path: Vec<String> = toks.into_iter().filter(|t| t != "::").collect();
                if path.len() > 1 {
                    if let Some(abs) = self.absolute(&here, &path) {
                        self.named.push((rel.to_string(), abs));
                    }
                }
                rest = &tail[end.max(1)..];
            }
        }
    }

    /// The file that defines `path`: re-exports followed, then the longest module
    /// prefix that is a file.
    fn resolve(&self, path: &Module) -> Option<&String> {
        let mut path = path.clone();
        for _ in 0..16 {
            let mut n = path.1.len();
            while n > 0 && !self.files.contains_key(&(path.0, path.1[..n].to_vec())) {
                n -= 1;
            }
            if n < path.1.len() {
                let key = (path.0, path.1[..=n].to_vec());
                if let Some(target) = self.aliases.get(&key) {
                    let mut next = target.clone();
                    next.1.extend(path.1[n + 1..].iter().cloned());
                    path = next;
                    continue;
                }
            }
            return self.files.get(&(path.0, path.1[..n].to_vec()));
        }
        None
    }

    fn edges(&self) -> BTreeMap<String, BTreeSet<String>> {
        let mut e: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for f in self.files.values() {
            e.entry(f.clone()).or_default();
        }
        for (from, path) in &self.named {
            if let Some(to) = self.resolve(path) {
                let (a, b) = (module_of(from), module_of(to));
                let into_own_child = a.0 == b.0 && b.1.len() > a.1.len() && b.1.starts_with(&a.1);
                if to != from && !into_own_child {
                    e.entry(from.clone()).or_default().insert(to.clone());
                }
            }
        }
        e
    }
}

/// Where `word` next stands as a whole identifier in `text` (not after `::`).
fn find_word(text: &str, word: &str) -> Option<usize> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    text.match_indices(word).map(|(i, _)| i).find(|&i| {
        let before = text[..i].chars().next_back();
        let after = text[i + word.len()..].chars().next();
        !before.is_some_and(ident) && !after.is_some_and(ident) && !text[..i].ends_with("::")
    })
}

/// The code with its `use …;` statements blanked (they are read separately).
fn strip_use_statements(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(i) = find_word(rest, "use") {
        out.push_str(&rest[..i]);
        let end = rest[i..].find(';').map_or(rest.len(), |e| i + e + 1);
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// Every loop in the graph, each as the files of one strongly connected component.
fn import_cycles(sources: &[(String, String)]) -> Vec<Vec<String>> {
    let edges = ModuleGraph::new(sources).edges();
    let reach = |from: &String| {
        let mut seen = BTreeSet::new();
        let mut todo: Vec<&String> = edges[from].iter().collect();
        while let Some(f) = todo.pop() {
            if seen.insert(f.clone()) {
                todo.extend(edges[f].iter());
            }
        }
        seen
    };
    let reachable: BTreeMap<&String, BTreeSet<String>> = edges.keys().map(|f| (f, reach(f))).collect();
    let mut cycles: Vec<Vec<String>> = Vec::new();
    for f in edges.keys() {
        if !reachable[f].contains(f) || cycles.iter().any(|c| c.contains(f)) {
            continue;
        }
        let scc: Vec<String> = edges
            .keys()
            .filter(|g| reachable[f].contains(*g) && reachable[*g].contains(f))
            .cloned()
            .collect();
        cycles.push(scc);
    }
    cycles
}

fn src_sources() -> Vec<(String, String)> {
    let mut all = Vec::new();
    rust_files(&root().join("src"), &mut all);
    all.iter()
        .map(|f| {
            let rel = f.strip_prefix(root()).unwrap().to_string_lossy().replace('\\', "/");
            (rel, std::fs::read_to_string(f).unwrap())
        })
        .collect()
}

#[test]
fn no_import_cycles_in_src() {
    let sources = src_sources();
    let edges = ModuleGraph::new(&sources).edges();
    let n_edges: usize = edges.values().map(BTreeSet::len).sum();
    assert!(n_edges > 100, "the scan found only {n_edges} imports between files");
    let cycles = import_cycles(&sources);
    let shown: Vec<String> = cycles
        .iter()
        .map(|c| {
            c.iter()
                .map(|f| format!("  {f} → {:?}", edges[f].iter().filter(|g| c.contains(g)).collect::<Vec<_>>()))
                .collect::<Vec<_>>()
                .join("\n")
        })
        .collect();
    assert!(cycles.is_empty(), "files that import each other in a loop:\n{}", shown.join("\n\n"));
}

/// The checker finds loops through `crate::`, `super::`, braces, child modules and
/// re-exports, ignores test modules and external crates, and sees one planted in
/// the real tree.
#[test]
fn the_cycle_check_sees_a_planted_cycle() {
    let src = |v: &[(&str, &str)]| v.iter().map(|(a, b)| (a.to_string(), b.to_string())).collect::<Vec<_>>();
    let clean = src(&[
        ("src/lib.rs", "pub mod a;\npub mod b;\npub use a::x as y;\n"),
        ("src/a/mod.rs", "pub mod x;\nuse serde::Serialize;\n"),
        (
            "src/a/x.rs",
            "use super::super::b::{self, Thing};\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use crate::a::Z;\n}\n",
        ),
        ("src/b.rs", "pub struct Thing;\nfn f() { let _ = std::fs::read(\"x\"); }\n"),
    ]);
    assert!(import_cycles(&clean).is_empty(), "{:?}", import_cycles(&clean));
    let planted = |path: &str, line: &str| {
        let mut s = clean.clone();
        s.iter_mut().find(|(p, _)| p == path).unwrap().1.push_str(line);
        import_cycles(&s)
    };
    assert_eq!(planted("src/b.rs", "use crate::a::x::Q;\n").len(), 1);
    assert_eq!(
        planted("src/b.rs", "fn g() { crate::y::q(); }\n"),
        vec![vec!["src/a/x.rs".to_string(), "src/b.rs".into()]]
    );
    assert_eq!(
        planted("src/a/mod.rs", "use x::{Q, R};\nfn f() { x::g(); }\n").len(),
        0,
        "a module using its own file"
    );
    assert_eq!(planted("src/a/mod.rs", "use crate::b::Thing;\n").len(), 0, "b ← x, b ← a: no loop");
    assert_eq!(
        planted("src/b.rs", "fn g() -> crate::a::A { todo!() }\n").len(),
        0,
        "b → a, x → b: no loop"
    );
    assert_eq!(planted("src/a/x.rs", "").len(), 0);
    assert_eq!(planted("src/b.rs", "use crate::{a::{x::{self}}};\n").len(), 1);
    // In the real tree: the table model naming a page closes a loop.
    let mut real = src_sources();
    let table = real.iter_mut().find(|(p, _)| p == "src/report/table.rs").unwrap();
    table.1.push_str("\nuse crate::report::campaign::Sources;\n");
    assert!(import_cycles(&real).iter().any(|c| c.contains(&"src/report/table.rs".to_string())));
}

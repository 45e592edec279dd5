//! The top-level modules of `server/` and of `core/src/` depend on each other one way only,
//! and the core crate's dependency tree holds no runtime, server, database or recorder.
//!
//! A cycle (`http` mounts `ws` while `ws` takes `http`'s state, say) means neither module can be
//! read, tested or moved without the other, so this test reads every `crate::<module>` path in
//! the sources, test modules included, and fails with the modules and the lines that close each
//! cycle. It reads the source text, not the compiler's view: a path written inside a string or
//! after code on the same line as a `//` comment counts, and `super::` chains that climb out of
//! a module do not (none do).

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Where a module names another: the first file and line that does, for the failure message.
type Edges = BTreeMap<String, BTreeMap<String, String>>;

/// A crate's top-level modules: each `.rs` file and each folder directly in its source folder,
/// but the crate roots themselves.
fn top_level_modules(root: &Path) -> BTreeSet<String> {
    fs::read_dir(root)
        .expect("the source folder reads")
        .map(|entry| entry.expect("an entry of the source folder").path())
        .filter(|path| path.is_dir() || path.extension().is_some_and(|e| e == "rs"))
        .map(|path| path.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|name| name != "lib" && name != "main")
        .collect()
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("a source folder reads") {
        let path = entry.expect("an entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The modules a line of code names through `crate::`: `crate::a::b` gives `a`, and
/// `crate::{a, b::c}` gives `a` and `b` (a group may span lines, so `rest` is the file's text
/// from this line on).
fn named_modules(rest: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut text = rest;
    let line_end = rest.find('\n').unwrap_or(rest.len());
    while let Some(at) = text.find("crate::") {
        let start = rest.len() - text.len() + at;
        if start >= line_end {
            break;
        }
        let after = &text[at + "crate::".len()..];
        if let Some(group) = after.strip_prefix('{') {
            names.extend(group_heads(group));
        } else {
            names.push(identifier(after).to_owned());
        }
        text = after;
    }
    names
}

/// The first path segment of each item of a `{...}` group, up to its closing brace.
fn group_heads(group: &str) -> Vec<String> {
    let mut heads = Vec::new();
    let mut depth = 0;
    let mut expect_head = true;
    for (i, c) in group.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => break,
            '}' => depth -= 1,
            ',' if depth == 0 => expect_head = true,
            c if expect_head && depth == 0 && (c.is_alphabetic() || c == '_') => {
                heads.push(identifier(&group[i..]).to_owned());
                expect_head = false;
            }
            _ => {}
        }
    }
    heads
}

fn identifier(text: &str) -> &str {
    let end = text
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(text.len());
    &text[..end]
}

fn module_graph(root: &Path) -> Edges {
    let modules = top_level_modules(root);
    let mut files = Vec::new();
    rust_files(root, &mut files);
    files.sort();
    let mut edges = Edges::new();
    for file in files {
        let relative = file.strip_prefix(root).unwrap();
        let top = relative.iter().next().unwrap().to_string_lossy();
        let from = top.strip_suffix(".rs").unwrap_or(&top).to_owned();
        if !modules.contains(&from) {
            continue;
        }
        let text = fs::read_to_string(&file).expect("a source file reads");
        let mut offset = 0;
        for (number, line) in text.lines().enumerate() {
            let rest = &text[offset..];
            offset += line.len() + 1;
            if line.trim_start().starts_with("//") {
                continue;
            }
            for to in named_modules(rest) {
                if to != from && modules.contains(&to) {
                    let place = format!("{}:{}", file.display(), number + 1);
                    edges
                        .entry(from.clone())
                        .or_default()
                        .entry(to)
                        .or_insert(place);
                }
            }
        }
    }
    edges
}

/// The groups of modules that reach each other (Tarjan's strongly connected components), those
/// of more than one module only.
fn cycles(edges: &Edges) -> Vec<BTreeSet<String>> {
    struct Search<'a> {
        edges: &'a Edges,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        found: Vec<BTreeSet<String>>,
    }
    impl<'a> Search<'a> {
        fn visit(&mut self, v: &'a str) {
            let i = self.index.len();
            self.index.insert(v, i);
            self.low.insert(v, i);
            self.stack.push(v);
            for w in self.edges.get(v).into_iter().flat_map(|to| to.keys()) {
                let w = w.as_str();
                if !self.index.contains_key(w) {
                    self.visit(w);
                    self.low.insert(v, self.low[v].min(self.low[w]));
                } else if self.stack.contains(&w) {
                    self.low.insert(v, self.low[v].min(self.index[w]));
                }
            }
            if self.low[v] == self.index[v] {
                let mut group = BTreeSet::new();
                loop {
                    let w = self.stack.pop().unwrap();
                    group.insert(w.to_owned());
                    if w == v {
                        break;
                    }
                }
                if group.len() > 1 {
                    self.found.push(group);
                }
            }
        }
    }
    let mut search = Search {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        found: Vec::new(),
    };
    for v in edges.keys() {
        if !search.index.contains_key(v.as_str()) {
            search.visit(v);
        }
    }
    search.found
}

/// The pairs of a group that name each other directly, the shortest cycles to break.
fn mutual_pairs<'a>(edges: &'a Edges, group: &'a BTreeSet<String>) -> Vec<(&'a str, &'a str)> {
    let names = |from: &str, to: &str| edges.get(from).is_some_and(|e| e.contains_key(to));
    let mut pairs = Vec::new();
    for a in group {
        for b in
            group.range::<String, _>((std::ops::Bound::Excluded(a), std::ops::Bound::Unbounded))
        {
            if names(a, b) && names(b, a) {
                pairs.push((a.as_str(), b.as_str()));
            }
        }
    }
    pairs
}

#[test]
fn top_level_modules_depend_on_each_other_one_way() {
    // The service's modules, and the core crate's (sim, scene_graph, rl, guidance).
    for root in ["server", "core/src"] {
        assert_no_cycles(&Path::new(env!("CARGO_MANIFEST_DIR")).join(root));
    }
}

fn assert_no_cycles(root: &Path) {
    let edges = module_graph(root);
    assert!(
        !edges.is_empty(),
        "{} has modules that name each other",
        root.display()
    );
    let found = cycles(&edges);
    let mut report = String::new();
    for group in &found {
        let names: Vec<&str> = group.iter().map(String::as_str).collect();
        report += &format!("cycle among {{{}}}:\n", names.join(", "));
        for (a, b) in mutual_pairs(&edges, group) {
            report += &format!("  {a} <-> {b}\n");
        }
        for from in group {
            for (to, place) in &edges[from] {
                if group.contains(to) {
                    report += &format!("  {from} -> {to}  ({place})\n");
                }
            }
        }
    }
    println!("{report}");
    assert!(found.is_empty(), "module cycles:\n{report}");
}

#[test]
fn reads_paths_and_groups() {
    assert_eq!(named_modules("use crate::http::AppState;"), ["http"]);
    assert_eq!(
        named_modules("use crate::{api::error::ApiError, hub, store::{Store, Row}};"),
        ["api", "hub", "store"]
    );
    assert_eq!(
        named_modules("let x = 1;\nuse crate::ws;"),
        Vec::<String>::new()
    );
}

/// The rule "algorithms do no IO" is the compiler's: the core crate cannot name tokio, axum,
/// sqlx or rerun because none of them is in its dependency tree (normal dependencies, its own
/// features only, as `cargo test -p dualrep-core` builds it).
#[test]
fn the_core_crate_depends_on_no_runtime_server_database_or_recorder() {
    let out = std::process::Command::new(env!("CARGO"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "tree",
            "--offline",
            "-p",
            "dualrep-core",
            "-e",
            "normal",
            "--prefix",
            "none",
        ])
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "cargo tree: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let tree = String::from_utf8(out.stdout).unwrap();
    let packages: BTreeSet<&str> = tree.lines().filter_map(|l| l.split(' ').next()).collect();
    assert!(
        packages.contains("dualrep-core") && packages.contains("rapier3d"),
        "{tree}"
    );
    // Each name and its family (`sqlx-core`, `rerun-sdk`, ...); and the service crate itself.
    let families = ["tokio", "axum", "sqlx", "rerun", "hyper", "tower", "utoipa"];
    let found: Vec<&&str> = packages
        .iter()
        .filter(|p| {
            **p == "dualrep"
                || families
                    .iter()
                    .any(|f| p == &f || p.starts_with(&format!("{f}-")))
        })
        .collect();
    assert!(
        found.is_empty(),
        "the core crate's tree holds {found:?}:\n{tree}"
    );
}

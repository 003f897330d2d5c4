//! The layout's promises, checked on the source tree: no module cycle in any crate, no non-test source file
//! over 600 lines, and every file or folder ARCHITECTURE.md names exists.
//!
//! Module graph: one node per module file (`a/b.rs`, `a/b/mod.rs`); an edge from a module to the module that
//! holds each item it names by path (`use crate::…`, `super::…`, `self::…`, and such paths in code). The crate
//! root is a façade (it declares modules and re-exports), so edges into and out of it are not counted. Test
//! files (`tests.rs`, `testutil.rs`, `*_tests.rs`) and inline `#[cfg(test)]` modules are left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Library and binary source roots of the workspace's crates (a `src/bin/NAME/` folder is a crate of its own).
const CRATES: [&str; 8] = [
    "proto/src",
    "server/planner/src",
    "server/engine/src",
    "server/daemon/src",
    "tests/src",
    "clients/rust/src",
    "clients/rust/src/bin/shiftctl",
    "clients/sim/src",
];

fn rs_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = entries.filter_map(Result::ok).map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rs_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

fn is_test_file(p: &Path) -> bool {
    let name = p.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    name == "tests" || name == "testutil" || name.ends_with("_tests")
}

/// The module path of a file below `root` (`[]` for the crate root).
fn module_of(root: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(root).unwrap_or(file);
    let mut parts: Vec<String> = rel.iter().map(|c| c.to_string_lossy().into_owned()).collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.trim_end_matches(".rs");
    if !(stem == "mod" || (parts.is_empty() && (stem == "lib" || stem == "main"))) {
        parts.push(stem.to_owned());
    }
    parts
}

/// The text without comments and without an inline `#[cfg(test)] mod … { … }` (which ends the file here).
fn code_of(text: &str) -> String {
    let cut = text
        .find("#[cfg(test)]\nmod tests {")
        .or_else(|| text.find("#[cfg(test)]\nmod props {"))
        .unwrap_or(text.len());
    text[..cut]
        .lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Expands `a::{b, c::{d, e}}` into `a::b`, `a::c::d`, `a::c::e`.
fn expand(tree: &str) -> Vec<String> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        return vec![tree.split(" as ").next().unwrap_or(tree).trim().to_owned()];
    };
    let prefix = tree[..open].trim_end_matches("::").trim();
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, ch) in inner.char_indices() {
        match ch {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    parts
        .into_iter()
        .filter(|p| !p.trim().is_empty())
        .flat_map(expand)
        .map(|p| {
            if p == "self" {
                prefix.to_owned()
            } else {
                format!("{prefix}::{p}")
            }
        })
        .collect()
}

/// Every `crate::`, `super::` and `self::` path the code names.
fn paths_named(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    // `use` statements, braces expanded.
    let mut rest = code;
    while let Some(i) = rest.find("use ") {
        let before = rest[..i].chars().last();
        rest = &rest[i + 4..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let end = rest.find(';').unwrap_or(rest.len());
        out.extend(expand(&rest[..end]));
        rest = &rest[end..];
    }
    // Paths in code.
    let bytes = code.as_bytes();
    for start in ["crate::", "super::", "self::"] {
        let mut from = 0;
        while let Some(i) = code[from..].find(start) {
            let at = from + i;
            from = at + start.len();
            if at > 0 && (bytes[at - 1].is_ascii_alphanumeric() || bytes[at - 1] == b'_' || bytes[at - 1] == b':') {
                continue;
            }
            let end = code[at..]
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .map_or(code.len(), |e| at + e);
            out.push(code[at..end].trim_end_matches(':').to_owned());
        }
    }
    out.into_iter()
        .filter(|p| p.starts_with("crate") || p.starts_with("super") || p.starts_with("self"))
        .collect()
}

/// A path named in module `me`, made absolute (segments after `crate`).
fn absolute(me: &[String], path: &str) -> Option<Vec<String>> {
    let mut segs: Vec<&str> = path.split("::").filter(|s| !s.is_empty()).collect();
    let mut abs: Vec<String> = match segs.first().copied() {
        Some("crate") => Vec::new(),
        Some("self") => me.to_vec(),
        Some("super") => {
            let mut m = me.to_vec();
            while segs.first() == Some(&"super") {
                m.pop();
                segs.remove(0);
            }
            segs.insert(0, "super");
            m
        }
        _ => return None,
    };
    abs.extend(segs.iter().skip(1).map(|s| (*s).to_owned()));
    Some(abs)
}

/// Module graph of one crate: module → modules it names.
fn graph(root: &Path) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut files = Vec::new();
    rs_files(root, &mut files);
    // Binaries under `src/bin/` are crates of their own, with their own root.
    let files: Vec<PathBuf> = files
        .into_iter()
        .filter(|f| !is_test_file(f) && !f.strip_prefix(root).is_ok_and(|r| r.starts_with("bin")))
        .collect();
    let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_of(root, f)).collect();
    let codes: Vec<(Vec<String>, String)> = files
        .iter()
        .map(|f| {
            (
                module_of(root, f),
                code_of(&std::fs::read_to_string(f).unwrap_or_default()),
            )
        })
        .collect();
    // The deepest module an absolute path goes through, and the segments after it.
    let split = |abs: &[String]| -> (Vec<String>, Vec<String>) {
        let n = (0..=abs.len())
            .rev()
            .find(|&n| modules.contains(&abs[..n]))
            .unwrap_or(0);
        (abs[..n].to_vec(), abs[n..].to_vec())
    };
    // Items a module re-exports (`pub use x::Item;`): (module, item) → the module they come from.
    let mut reexports: BTreeMap<(Vec<String>, String), Vec<String>> = BTreeMap::new();
    for (me, code) in &codes {
        let mut rest = code.as_str();
        while let Some(i) = rest.find("pub use ") {
            rest = &rest[i + 8..];
            let end = rest.find(';').unwrap_or(rest.len());
            for path in expand(&rest[..end]) {
                let path = if path.starts_with("crate") || path.starts_with("super") || path.starts_with("self") {
                    path
                } else {
                    format!("self::{path}")
                };
                if let Some(abs) = absolute(me, &path)
                    && let Some(item) = abs.last()
                {
                    let (from, _) = split(&abs);
                    if &from != me {
                        reexports.insert((me.clone(), item.clone()), from);
                    }
                }
            }
            rest = &rest[end..];
        }
    }
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (me, code) in &codes {
        if me.is_empty() {
            continue;
        }
        for path in paths_named(code) {
            let Some(abs) = absolute(me, &path) else { continue };
            let (mut target, mut rest) = split(&abs);
            // Through re-exports to where the item is defined (a few hops at most).
            for _ in 0..4 {
                let Some(next) = rest
                    .first()
                    .and_then(|item| reexports.get(&(target.clone(), item.clone())))
                else {
                    break;
                };
                target = next.clone();
                rest = rest[1..].to_vec();
                if let Some(item) = abs.last() {
                    rest = vec![item.clone()];
                }
            }
            if !target.is_empty() && &target != me {
                edges.entry(me.clone()).or_default().insert(target);
            }
        }
        edges.entry(me.clone()).or_default();
    }
    edges
}

/// One cycle of the graph, if there is one.
fn find_cycle(g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Option<Vec<Vec<String>>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        Open,
        Done,
    }
    fn visit(
        n: &Vec<String>,
        g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        mark: &mut BTreeMap<Vec<String>, Mark>,
        stack: &mut Vec<Vec<String>>,
    ) -> Option<Vec<Vec<String>>> {
        mark.insert(n.clone(), Mark::Open);
        stack.push(n.clone());
        for m in g.get(n).into_iter().flatten() {
            match mark.get(m).copied().unwrap_or(Mark::New) {
                Mark::Open => {
                    let at = stack.iter().position(|s| s == m).unwrap_or(0);
                    let mut cycle = stack[at..].to_vec();
                    cycle.push(m.clone());
                    return Some(cycle);
                }
                Mark::New => {
                    if let Some(c) = visit(m, g, mark, stack) {
                        return Some(c);
                    }
                }
                Mark::Done => {}
            }
        }
        stack.pop();
        mark.insert(n.clone(), Mark::Done);
        None
    }
    let mut mark = BTreeMap::new();
    for n in g.keys() {
        if mark.get(n).copied().unwrap_or(Mark::New) == Mark::New
            && let Some(c) = visit(n, g, &mut mark, &mut Vec::new())
        {
            return Some(c);
        }
    }
    None
}

#[test]
fn no_crate_has_a_module_cycle() {
    let mut cycles = Vec::new();
    for krate in CRATES {
        let mut g = graph(&workspace().join(krate));
        assert!(g.len() > 1, "{krate}: modules found");
        // Every cycle, each reported once: cut the edge that closes it and look again.
        while let Some(cycle) = find_cycle(&g) {
            let names: Vec<String> = cycle.iter().map(|m| m.join("::")).collect();
            cycles.push(format!("{krate}: {}", names.join(" → ")));
            let n = cycle.len();
            if let Some(out) = g.get_mut(&cycle[n - 2]) {
                out.remove(&cycle[n - 1]);
            }
        }
    }
    assert!(cycles.is_empty(), "module cycles:\n{}", cycles.join("\n"));
}

#[test]
fn the_cycle_finder_finds_cycles() {
    let m = |s: &str| vec![s.to_owned()];
    let mut g: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    g.insert(m("a"), [m("b")].into());
    g.insert(m("b"), [m("c")].into());
    g.insert(m("c"), BTreeSet::new());
    assert!(find_cycle(&g).is_none());
    g.insert(m("c"), [m("a")].into());
    assert_eq!(find_cycle(&g).map(|c| c.len()), Some(4));
    assert_eq!(
        expand("crate::a::{b, c::{d, e as f}, self}"),
        ["crate::a::b", "crate::a::c::d", "crate::a::c::e", "crate::a"]
    );
}

#[test]
fn no_source_file_is_over_600_lines() {
    let mut long = Vec::new();
    for krate in [
        "proto",
        "server/planner",
        "server/engine",
        "server/daemon",
        "tests",
        "clients/rust",
        "clients/sim",
    ] {
        let mut files = Vec::new();
        rs_files(&workspace().join(krate), &mut files);
        for f in files.iter().filter(|f| !is_test_file(f)) {
            let text = std::fs::read_to_string(f).unwrap_or_default();
            // Integration tests (`tests/`) are test code too.
            let in_tests_dir =
                f.components().any(|c| c.as_os_str() == "tests") && !f.starts_with(workspace().join("tests/src"));
            let n = code_of(&text).lines().count();
            if n > 600 && !in_tests_dir {
                long.push(format!("{} ({n} lines)", f.display()));
            }
        }
    }
    assert!(long.is_empty(), "over 600 lines: {long:?}");
}

#[test]
fn every_path_architecture_md_names_exists() {
    let text = std::fs::read_to_string(workspace().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let mut missing = Vec::new();
    let mut checked = 0;
    for (i, chunk) in text.split('`').enumerate() {
        // Odd chunks are inside backticks.
        if i % 2 == 0 {
            continue;
        }
        let path = chunk.split_whitespace().next().unwrap_or("");
        let looks_like_path = path.contains('/')
            && !path.contains("://")
            && !path.contains('{')
            && !path.contains('*')
            && (path.ends_with(".rs") || path.ends_with('/') || path.ends_with(".py") || path.ends_with(".toml"));
        if !looks_like_path {
            continue;
        }
        checked += 1;
        if !workspace().join(path).exists() {
            missing.push(path.to_owned());
        }
    }
    assert!(checked > 30, "ARCHITECTURE.md names files ({checked} found)");
    assert!(missing.is_empty(), "named in ARCHITECTURE.md but missing: {missing:?}");
}

#[test]
fn architecture_md_stands_alone() {
    let text = std::fs::read_to_string(workspace().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    assert!(
        !text.contains("../shared"),
        "ARCHITECTURE.md links outside the repository"
    );
}

//! The code base's shape, checked: no import loop between sibling modules of a folder, and no
//! source file past ~700 lines without a reason written at its top (ARCHITECTURE.md's
//! invariants). A module's references to its siblings are read from the text: `super::x`,
//! `crate::x` (at a crate's top level) and `crate::folder::x`, test modules left out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// A file's text without its `#[cfg(test)] mod tests { … }` (which may use anything).
fn product_text(p: &Path) -> String {
    let t = std::fs::read_to_string(p).unwrap();
    match t.find("#[cfg(test)]\nmod tests") {
        Some(i) => t[..i].to_string(),
        None => t,
    }
}

/// The modules a folder's `mod.rs` / `lib.rs` declares under `#[cfg(test)]` (test helpers:
/// not product code, so not part of the product's import graph).
fn test_only(dir: &Path) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for root in ["mod.rs", "lib.rs"] {
        let Ok(text) = std::fs::read_to_string(dir.join(root)) else {
            continue;
        };
        let mut lines = text.lines().map(str::trim);
        while let Some(l) = lines.next() {
            if l == "#[cfg(test)]"
                && let Some(next) = lines.next()
                && let Some(name) = next
                    .strip_prefix("mod ")
                    .or_else(|| next.strip_prefix("pub mod "))
                    .and_then(|n| n.strip_suffix(';'))
            {
                out.insert(name.to_string());
            }
        }
    }
    out
}

/// The sibling modules of a folder (files and subfolders, `mod.rs` / `lib.rs` / `main.rs`
/// and test-only modules left out) with every file each holds, test files (`tests.rs`)
/// left out.
fn modules(dir: &Path) -> BTreeMap<String, Vec<PathBuf>> {
    let skip = test_only(dir);
    let mut out = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().to_string();
        if skip.contains(&name) {
            continue;
        }
        if p.is_dir() {
            let mut files = Vec::new();
            rust_files(&p, &mut files);
            files.retain(|f| f.file_name().is_none_or(|n| n != "tests.rs"));
            out.entry(name).or_insert_with(Vec::new).extend(files);
        } else if p.extension().is_some_and(|x| x == "rs")
            && !["mod", "lib", "main", "tests"].contains(&name.as_str())
        {
            out.entry(name).or_insert_with(Vec::new).push(p);
        }
    }
    out
}

/// Whether `text` names sibling `m` through one of the prefixes.
fn names(text: &str, prefixes: &[String], m: &str) -> bool {
    prefixes.iter().any(|pre| {
        text.match_indices(pre.as_str()).any(|(i, _)| {
            let rest = &text[i + pre.len()..];
            let word_end = |s: &str| !s.starts_with(|c: char| c.is_alphanumeric() || c == '_');
            if let Some(after) = rest.strip_prefix(m) {
                return word_end(after);
            }
            // `prefix{a, b::c, m}`: a brace list (one level is enough for our imports).
            rest.strip_prefix('{').is_some_and(|list| {
                let list = &list[..list.find('}').unwrap_or(list.len())];
                list.split(',').any(|item| {
                    let item = item.trim();
                    item.strip_prefix(m).is_some_and(word_end)
                })
            })
        })
    })
}

/// The import loops among a folder's modules (strongly connected groups of two or more).
fn loops(dir: &Path, crate_path: &str) -> Vec<Vec<String>> {
    let mods = modules(dir);
    let prefixes: Vec<String> = if crate_path.is_empty() {
        vec!["super::".into(), "crate::".into()]
    } else {
        vec!["super::".into(), format!("crate::{crate_path}::")]
    };
    let edges: BTreeMap<&String, BTreeSet<&String>> = mods
        .iter()
        .map(|(m, files)| {
            let text: String = files.iter().map(|f| product_text(f)).collect();
            let to = mods
                .keys()
                .filter(|o| *o != m && names(&text, &prefixes, o))
                .collect();
            (m, to)
        })
        .collect();
    // Reachability by repeated search: small graphs.
    let reach = |from: &String| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from];
        while let Some(n) = stack.pop() {
            for t in &edges[n] {
                if seen.insert(*t) {
                    stack.push(t);
                }
            }
        }
        seen
    };
    let mut out: Vec<Vec<String>> = Vec::new();
    for m in mods.keys() {
        let r = reach(m);
        if r.contains(m) {
            let group: Vec<String> = mods
                .keys()
                .filter(|o| r.contains(o) && reach(o).contains(m))
                .cloned()
                .collect();
            if !out.contains(&group) {
                out.push(group);
            }
        }
    }
    out
}

#[test]
fn no_import_loops_between_sibling_modules() {
    let r = root();
    let folders = [
        ("app/src", ""),
        ("app/src/ui", "ui"),
        ("app/src/formats", "formats"),
        ("app/src/editor", "editor"),
        ("app/src/cli", "cli"),
        ("brickmap/src", ""),
        ("brickmap/src/objects", "objects"),
        ("render/src", ""),
    ];
    let mut found = Vec::new();
    for (dir, path) in folders {
        for l in loops(&r.join(dir), path) {
            found.push(format!("{dir}: {}", l.join(" → ")));
        }
    }
    assert!(found.is_empty(), "import loops: {found:#?}");
}

#[test]
fn the_loop_finder_finds_a_loop() {
    let dir = std::env::temp_dir().join(format!("voxbrick-structure-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("c")).unwrap();
    std::fs::write(dir.join("a.rs"), "use super::b::B;\n").unwrap();
    std::fs::write(dir.join("b.rs"), "use super::{c, x};\n").unwrap();
    std::fs::write(dir.join("c/inner.rs"), "use crate::f::a::A;\n").unwrap();
    std::fs::write(
        dir.join("d.rs"),
        "use super::ab;\n#[cfg(test)]\nmod tests { use super::a; }\n",
    )
    .unwrap();
    // Test-only code does not count: a cfg(test) module using d, and a tests.rs file in d
    // using it back.
    std::fs::write(dir.join("mod.rs"), "mod a;\n#[cfg(test)]\nmod helpers;\n").unwrap();
    std::fs::write(dir.join("helpers.rs"), "use super::d::D;\n").unwrap();
    std::fs::create_dir_all(dir.join("d")).unwrap();
    std::fs::write(dir.join("d/tests.rs"), "use crate::f::helpers::H;\n").unwrap();
    let found = loops(&dir, "f");
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(found, vec![vec!["a".to_string(), "b".into(), "c".into()]]);
}

#[test]
fn long_files_say_why_at_their_top() {
    let r = root();
    let mut files = Vec::new();
    // The product's sources and the tests' and benchmarks' own.
    for dir in [
        "app/src",
        "brickmap/src",
        "render/src",
        "app/tests",
        "brickmap/tests",
        "render/tests",
        "tests/src",
        "tests/tests",
        "app/benches",
        "brickmap/benches",
    ] {
        rust_files(&r.join(dir), &mut files);
    }
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            let lines = text.lines().count();
            let head: String = text.lines().take(30).collect::<Vec<_>>().join("\n");
            (lines > 750 && !head.contains("Long because"))
                .then(|| format!("{} ({lines} lines)", f.display()))
        })
        .collect();
    assert!(
        long.is_empty(),
        "split these files or say at their top why they are long (\"Long because …\"): {long:#?}"
    );
}

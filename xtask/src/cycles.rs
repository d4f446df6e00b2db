//! `cargo xtask cycles`: import cycles between the files of a crate (issue 27, item 2).
//!
//! Why: a cycle between files (`a.rs` uses `b.rs`, which uses `a.rs`) means neither can be read,
//! tested or moved alone; the issue found four. This reads each crate's `.rs` files (the module
//! tree from file names: `a.rs` or `a/mod.rs` is `crate::a`), takes every path that starts with
//! `crate::`, `super::`, `self::` or a child module's name (in `use` trees and in code), resolves
//! it to the file of its longest module prefix and reports each strongly connected component of
//! that graph as a chain of files. A module's own paths into its subtree are not edges: a parent
//! declares and re-exports its children (the usual facade of `mod.rs`); a child's paths to its
//! parent are. Tests (`#[cfg(test)] mod ..`, inline or a file) may use anything and are not
//! read, nor are comments, strings and `#[path]` modules; `super` inside an inline `mod x { .. }`
//! is the file itself. Measured 2026-12-05: 0.1 s on the three crates.
//!
//! Cycles known when the checker came are in [`ALLOWED`], each with its reason; the check fails
//! on a cycle not in it and on an entry that is no longer a cycle, so the list only shrinks.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// The crates whose files are checked, relative to the workspace root.
pub const CRATE_SOURCES: [&str; 3] = ["shared/src", "host/src", "firmware/src"];

/// Cycles allowed for now, each as its files (relative to the workspace root, sorted) and why.
/// None today: the last, `cmd/mission/mod.rs` and `cmd/mission_link.rs` sharing `Args` both
/// ways, went with issue 27 item 1 (the link's file is `cmd/mission/link.rs`, and the final
/// report's recovery, which needs the follower, is in `follower.rs`).
pub const ALLOWED: &[(&[&str], &str)] = &[];

/// A file's module path (`["plan", "astar"]`) and whether it owns a directory of children
/// (`lib.rs`, `main.rs`, `mod.rs`).
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    if let Some(last) = parts.pop() {
        let stem = last.trim_end_matches(".rs");
        if !matches!(stem, "mod" | "lib" | "main") {
            parts.push(stem.to_string());
        }
    }
    parts
}

/// Every `.rs` file under `dir`, relative to it, sorted.
fn rust_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in
            std::fs::read_dir(&d).with_context(|| format!("cannot read {}", d.display()))?
        {
            let path = entry?.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path.strip_prefix(dir).unwrap_or(&path).to_path_buf());
            }
        }
    }
    out.sort();
    Ok(out)
}

/// The tokens of Rust source that matter here: identifiers, `::`, `{`, `}`, `;`, `,`, `*`;
/// comments, strings and character literals dropped (lifetimes are kept as identifiers).
fn tokens(src: &str) -> Vec<String> {
    let b = src.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if c == b'/' && b.get(i + 1) == Some(&b'*') {
            let mut depth = 0;
            while i < b.len() {
                if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                    depth += 1;
                    i += 2;
                } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if c == b'r'
            && matches!(b.get(i + 1), Some(b'"' | b'#'))
            && raw_string_end(b, i).is_some()
        {
            i = raw_string_end(b, i).unwrap_or(b.len());
        } else if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += if b[i] == b'\\' { 2 } else { 1 };
            }
            i += 1;
        } else if c == b'\'' {
            // A character literal ('x', 'é', '\n', '\u{..}') or a lifetime ('a: skipped as is).
            if b.get(i + 1) == Some(&b'\\') {
                i += 2;
                while i < b.len() && b[i] != b'\'' {
                    i += 1;
                }
                i += 1;
            } else {
                let len = src[i + 1..].chars().next().map_or(1, char::len_utf8);
                i += if b.get(i + 1 + len) == Some(&b'\'') {
                    len + 2
                } else {
                    1
                };
            }
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push(src[start..i].to_string());
        } else if c == b':' && b.get(i + 1) == Some(&b':') {
            out.push("::".into());
            i += 2;
        } else if matches!(c, b'{' | b'}' | b';' | b',' | b'*' | b'!' | b'#' | b'$') {
            out.push((c as char).to_string());
            i += 1;
        } else {
            if !c.is_ascii_whitespace() {
                out.push(".".into());
            }
            i += 1;
        }
    }
    out
}

/// End (exclusive) of a raw string `r#".."#` starting at `i`, if one starts there.
fn raw_string_end(b: &[u8], i: usize) -> Option<usize> {
    let mut j = i + 1;
    let mut hashes = 0;
    while b.get(j) == Some(&b'#') {
        hashes += 1;
        j += 1;
    }
    if b.get(j) != Some(&b'"') {
        return None;
    }
    j += 1;
    while j < b.len() {
        if b[j] == b'"'
            && b[j + 1..]
                .iter()
                .take(hashes)
                .filter(|&&h| h == b'#')
                .count()
                == hashes
        {
            return Some(j + 1 + hashes);
        }
        j += 1;
    }
    Some(b.len())
}

/// The paths a file names, each as its segments (`["crate", "geom", "Pose"]`), with `use`
/// trees expanded, and the depth of inline modules each sits in.
fn paths(tokens: &[String]) -> Vec<(usize, Vec<String>)> {
    let mut out = Vec::new();
    // Brace depths at which inline modules opened.
    let mut inline: Vec<usize> = Vec::new();
    let mut depth = 0usize;
    let mut i = 0;
    while i < tokens.len() {
        let t = tokens[i].as_str();
        match t {
            "{" => depth += 1,
            "}" => {
                depth = depth.saturating_sub(1);
                if inline.last() == Some(&depth) {
                    inline.pop();
                }
            }
            "mod" if tokens.get(i + 2).map(String::as_str) == Some("{") => {
                if after_cfg_test(tokens, i) {
                    // Tests may use anything: skip the module.
                    i = block_end(tokens, i + 2);
                    continue;
                }
                inline.push(depth);
                depth += 1;
                i += 3;
                continue;
            }
            "use" => {
                let end = (i..tokens.len())
                    .find(|&j| tokens[j] == ";")
                    .unwrap_or(tokens.len());
                expand_use(&tokens[i + 1..end], &[], &mut |p| {
                    out.push((inline.len(), p))
                });
                i = end + 1;
                continue;
            }
            "crate" | "super" | "self"
                if tokens.get(i + 1).map(String::as_str) == Some("::")
                    && (i == 0 || tokens[i - 1] != "::") =>
            {
                let mut p = vec![t.to_string()];
                let mut j = i + 1;
                while tokens.get(j).map(String::as_str) == Some("::") {
                    match tokens.get(j + 1) {
                        Some(s) if is_ident(s) => p.push(s.clone()),
                        _ => break,
                    }
                    j += 2;
                }
                out.push((inline.len(), p));
                i = j;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// `true` when the item at `i` follows `#[cfg(test)]`.
fn after_cfg_test(tokens: &[String], i: usize) -> bool {
    const CFG_TEST: [&str; 7] = ["#", ".", "cfg", ".", "test", ".", "."];
    i >= CFG_TEST.len() && tokens[i - CFG_TEST.len()..i].iter().eq(CFG_TEST.iter())
}

/// The index after the block whose `{` is at `open`.
fn block_end(tokens: &[String], open: usize) -> usize {
    let mut depth = 0usize;
    for (j, t) in tokens.iter().enumerate().skip(open) {
        match t.as_str() {
            "{" => depth += 1,
            "}" => {
                depth = depth.saturating_sub(1);
                if depth == 0 {
                    return j + 1;
                }
            }
            _ => {}
        }
    }
    tokens.len()
}

/// The names of the file modules `tokens` declares under `#[cfg(test)]` (`mod tests;`).
fn test_modules(tokens: &[String]) -> Vec<String> {
    (0..tokens.len())
        .filter(|&i| {
            tokens[i] == "mod"
                && tokens.get(i + 2).map(String::as_str) == Some(";")
                && after_cfg_test(tokens, i)
        })
        .filter_map(|i| tokens.get(i + 1).cloned())
        .collect()
}

fn is_ident(s: &str) -> bool {
    s.chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
}

/// Call `f` with each full path of the `use` tree `tree` under `prefix`.
fn expand_use(tree: &[String], prefix: &[String], f: &mut dyn FnMut(Vec<String>)) {
    // Split at top-level commas.
    let mut depth = 0;
    let mut start = 0;
    let mut items = Vec::new();
    for (k, t) in tree.iter().enumerate() {
        match t.as_str() {
            "{" => depth += 1,
            "}" => depth -= 1,
            "," if depth == 0 => {
                items.push(&tree[start..k]);
                start = k + 1;
            }
            _ => {}
        }
    }
    items.push(&tree[start..]);
    for item in items {
        let mut p = prefix.to_vec();
        let mut k = 0;
        while k < item.len() {
            match item[k].as_str() {
                "::" => {}
                "{" => {
                    let close =
                        item.len() - 1 - item.iter().rev().position(|t| t == "}").unwrap_or(0);
                    expand_use(&item[k + 1..close], &p, f);
                    p.clear();
                    break;
                }
                "as" => break,
                s if is_ident(s) => p.push(s.to_string()),
                _ => {}
            }
            k += 1;
        }
        if !p.is_empty() {
            f(p);
        }
    }
}

/// The import graph of one crate: file -> files it names.
fn crate_graph(root: &Path, src: &str) -> Result<BTreeMap<String, BTreeSet<String>>> {
    let dir = root.join(src);
    let files = rust_files(&dir)?;
    // Module path -> file (relative to the workspace root); `lib.rs` wins over `main.rs` for
    // the empty path, but each is the root of its own crate for its own paths.
    let mut by_module: BTreeMap<Vec<String>, String> = BTreeMap::new();
    for f in &files {
        let name = format!("{src}/{}", f.display());
        by_module.entry(module_of(f)).or_insert(name);
    }
    let mut texts = BTreeMap::new();
    // Modules only compiled for tests (`#[cfg(test)] mod tests;`): tests may use anything.
    let mut test_only: Vec<Vec<String>> = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(dir.join(f))
            .with_context(|| format!("cannot read {src}/{}", f.display()))?;
        let toks = tokens(&text);
        for name in test_modules(&toks) {
            let mut m = module_of(f);
            m.push(name);
            test_only.push(m);
        }
        texts.insert(f.clone(), toks);
    }
    let mut graph = BTreeMap::new();
    for (f, toks) in &texts {
        let name = format!("{src}/{}", f.display());
        let module = module_of(f);
        if test_only.iter().any(|t| module.starts_with(t)) {
            continue;
        }
        let mut targets = BTreeSet::new();
        for (inline, path) in paths(toks) {
            let Some(absolute) = absolute_path(&module, inline, &path, &by_module) else {
                continue;
            };
            // A module's paths into its own subtree: declarations and re-exports.
            if absolute.starts_with(&module) {
                continue;
            }
            if let Some(target) = (0..=absolute.len())
                .rev()
                .find_map(|n| by_module.get(&absolute[..n]))
            {
                if *target != name {
                    targets.insert(target.clone());
                }
            }
        }
        graph.insert(name, targets);
    }
    Ok(graph)
}

/// `path` (as written in module `module`, `inline` inline modules deep) from the crate root;
/// `None` for another crate's path.
fn absolute_path(
    module: &[String],
    inline: usize,
    path: &[String],
    by_module: &BTreeMap<Vec<String>, String>,
) -> Option<Vec<String>> {
    let first = path.first()?;
    let mut base: Vec<String> = module.to_vec();
    let mut rest = path;
    match first.as_str() {
        "crate" => {
            base.clear();
            rest = &path[1..];
        }
        "self" => rest = &path[1..],
        "super" => {
            // Inline modules absorb the first `super`s.
            let mut up = inline;
            while rest.first().map(String::as_str) == Some("super") {
                if up > 0 {
                    up -= 1;
                } else {
                    base.pop()?;
                }
                rest = &rest[1..];
            }
        }
        name => {
            // A child module of this one (2018 paths), else another crate or a local item.
            let mut child = module.to_vec();
            child.push(name.to_string());
            if inline > 0 || !by_module.contains_key(&child) {
                return None;
            }
        }
    }
    base.extend(rest.iter().cloned());
    Some(base)
}

/// The strongly connected components with a cycle, each sorted (Tarjan's algorithm).
fn cycles(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct State<'g> {
        graph: &'g BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'g str, usize>,
        low: BTreeMap<&'g str, usize>,
        stack: Vec<&'g str>,
        on_stack: BTreeSet<&'g str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'g>(s: &mut State<'g>, v: &'g str) {
        let n = s.index.len();
        s.index.insert(v, n);
        s.low.insert(v, n);
        s.stack.push(v);
        s.on_stack.insert(v);
        for w in s.graph.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !s.index.contains_key(w) {
                visit(s, w);
                let lw = s.low[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(lw);
            } else if s.on_stack.contains(w) {
                let iw = s.index[w];
                let lv = s.low.get_mut(v).expect("visited");
                *lv = (*lv).min(iw);
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = Vec::new();
            while let Some(w) = s.stack.pop() {
                s.on_stack.remove(w);
                component.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                s.out.push(component);
            }
        }
    }
    let mut s = State {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out.sort();
    s.out
}

/// A shortest cycle through the first file of `component`, as a chain `a -> b -> a`.
fn chain(graph: &BTreeMap<String, BTreeSet<String>>, component: &[String]) -> String {
    let Some(start) = component.first() else {
        return String::new();
    };
    let inside: BTreeSet<&String> = component.iter().collect();
    let mut parent: BTreeMap<&String, &String> = BTreeMap::new();
    let mut queue = std::collections::VecDeque::from([start]);
    while let Some(v) = queue.pop_front() {
        for w in graph.get(v).into_iter().flatten() {
            if w == start {
                let mut files = vec![v];
                while let Some(p) = parent.get(files[files.len() - 1]) {
                    files.push(p);
                }
                files.reverse();
                files.push(start);
                if files[0] != start {
                    files.insert(0, start);
                }
                return files
                    .iter()
                    .map(|f| f.as_str())
                    .collect::<Vec<_>>()
                    .join(" -> ");
            }
            if inside.contains(w) && !parent.contains_key(w) && w != start {
                parent.insert(w, v);
                queue.push_back(w);
            }
        }
    }
    component.join(" -> ")
}

/// The cycles of every crate in [`CRATE_SOURCES`] under `root`, each with one chain.
pub fn find(root: &Path) -> Result<Vec<(Vec<String>, String)>> {
    let mut found = Vec::new();
    for src in CRATE_SOURCES {
        let graph = crate_graph(root, src)?;
        for component in cycles(&graph) {
            let c = chain(&graph, &component);
            found.push((component, c));
        }
    }
    Ok(found)
}

/// `cargo xtask cycles`: fail on a cycle not in [`ALLOWED`] or an entry of it that is gone.
pub fn check(root: &Path) -> Result<()> {
    let found = find(root)?;
    let mut errors = Vec::new();
    for (component, chain) in &found {
        let allowed = ALLOWED.iter().any(|(files, _)| {
            files
                .iter()
                .copied()
                .eq(component.iter().map(String::as_str))
        });
        if allowed {
            eprintln!("xtask cycles: allowed for now: {chain}");
        } else {
            errors.push(format!("import cycle: {chain}"));
        }
    }
    for (files, _) in ALLOWED {
        if !found
            .iter()
            .any(|(c, _)| files.iter().copied().eq(c.iter().map(String::as_str)))
        {
            errors.push(format!(
                "xtask/src/cycles.rs: ALLOWED lists the cycle {} that no longer exists: remove it",
                files.join(" <-> ")
            ));
        }
    }
    if !errors.is_empty() {
        bail!("{}", errors.join("\n"));
    }
    eprintln!(
        "xtask cycles: no import cycle in {} beyond the {} allowed",
        CRATE_SOURCES.join(", "),
        ALLOWED.len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn graph_of(files: &[(&str, &str)]) -> BTreeMap<String, BTreeSet<String>> {
        // One directory per call: the tests run in parallel.
        static CALLS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let call = CALLS.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
        let dir = std::env::temp_dir().join(format!("twil-cycles-{}-{call}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for (name, text) in files {
            let path = dir.join("src").join(name);
            std::fs::create_dir_all(path.parent().expect("a parent")).expect("mkdir");
            std::fs::write(path, text).expect("write");
        }
        let graph = crate_graph(&dir, "src").expect("graph");
        let _ = std::fs::remove_dir_all(&dir);
        graph
    }

    #[test]
    fn a_cycle_through_three_files_is_one_chain() {
        let g = graph_of(&[
            ("lib.rs", "mod a; mod b; mod c;"),
            ("a.rs", "use crate::b::X; pub struct Y;"),
            ("b.rs", "pub fn f() { crate::c::g() }"),
            ("c/mod.rs", "use crate::{geom::P, a::{Y as Z}};"),
        ]);
        let found = cycles(&g);
        assert_eq!(found, vec![vec!["src/a.rs", "src/b.rs", "src/c/mod.rs"]]);
        assert_eq!(
            chain(&g, &found[0]),
            "src/a.rs -> src/b.rs -> src/c/mod.rs -> src/a.rs"
        );
    }

    #[test]
    fn a_parent_reexporting_its_children_is_no_cycle_but_a_private_use_is() {
        let facade = graph_of(&[
            ("lib.rs", "mod p;"),
            ("p/mod.rs", "mod k; pub use k::K; pub struct E;"),
            (
                "p/k.rs",
                "use super::E; /* crate::p::k */ const S: &str = \"crate::x\";",
            ),
        ]);
        assert!(cycles(&facade).is_empty(), "{facade:?}");
        // Siblings through `super::`: a cycle.
        let siblings = graph_of(&[
            ("lib.rs", "mod p;"),
            ("p/mod.rs", "mod k; mod l;"),
            ("p/k.rs", "use super::l::L; pub struct K;"),
            ("p/l.rs", "pub struct L(super::k::K);"),
        ]);
        assert_eq!(cycles(&siblings), vec![vec!["src/p/k.rs", "src/p/l.rs"]]);
    }

    #[test]
    fn super_in_an_inline_module_is_the_file_itself() {
        let g = graph_of(&[
            ("lib.rs", "mod p; pub struct R;"),
            ("p/mod.rs", "mod k; pub struct E;"),
            (
                "p/k.rs",
                "pub fn f() {} mod inner { use super::*; use super::super::E; }",
            ),
        ]);
        assert_eq!(
            g["src/p/k.rs"],
            BTreeSet::from(["src/p/mod.rs".to_string()])
        );
        assert!(g["src/lib.rs"].is_empty());
    }

    #[test]
    fn tests_may_use_anything() {
        let g = graph_of(&[
            ("lib.rs", "mod a; mod b;"),
            (
                "a.rs",
                "use crate::b::B; pub struct A; #[cfg(test)] mod tests;",
            ),
            ("a/tests.rs", "use crate::b::uses_a;"),
            (
                "b.rs",
                "pub struct B; #[cfg(test)] mod tests { use crate::a::A; }",
            ),
        ]);
        assert!(cycles(&g).is_empty(), "{g:?}");
        assert_eq!(g["src/a.rs"], BTreeSet::from(["src/b.rs".to_string()]));
        assert!(!g.contains_key("src/a/tests.rs"));
    }

    #[test]
    fn the_workspace_has_only_the_allowed_cycles() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        check(&root).expect("cargo xtask cycles");
    }
}

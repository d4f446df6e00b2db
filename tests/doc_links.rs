//! Every relative link of `README.md`, `CONTRIBUTING.md` and `docs/*.md` leads somewhere: the
//! file or folder exists and, for a link into a Markdown file, its `#anchor` is one of that
//! file's headings (issue 27, item 8: the README's long sections moved into `docs/`, and a
//! moved section must not leave links pointing at the old place).
//!
//! Anchors are GitHub's: the heading's text, lower case, with every character that is not a
//! letter, a digit, `_`, `-` or a space dropped, and spaces turned into `-`; a repeated heading
//! gets `-1`, `-2`, … Links inside code (fenced blocks and `inline code`) are not links; web
//! links (`https:` …) are not checked (the test runs offline).
//!
//! Measured: 19 docs, 192 relative links, 0.01 s.

use crate::common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The docs whose links are checked, relative to the repository root.
fn docs() -> Vec<PathBuf> {
    let mut docs = vec![PathBuf::from("README.md"), PathBuf::from("CONTRIBUTING.md")];
    let mut more: Vec<PathBuf> = std::fs::read_dir(common::repo().join("docs"))
        .expect("docs/")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".md"))
        .map(|name| Path::new("docs").join(name))
        .collect();
    more.sort();
    docs.extend(more);
    docs
}

/// The lines of `text` outside fenced code blocks, with their 1-based numbers.
fn prose_lines(text: &str) -> Vec<(usize, &str)> {
    let mut fence: Option<(char, usize)> = None;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim_start();
        let marker = trimmed.chars().next().filter(|c| *c == '`' || *c == '~');
        let run = marker.map_or(0, |c| trimmed.len() - trimmed.trim_start_matches(c).len());
        match (fence, marker) {
            (None, Some(c)) if run >= 3 => fence = Some((c, run)),
            (Some((c, n)), Some(m)) if m == c && run >= n && trimmed[run..].trim().is_empty() => {
                fence = None
            }
            (None, _) => out.push((i + 1, line)),
            _ => {}
        }
    }
    out
}

/// `line` without its `inline code` spans.
fn without_code(line: &str) -> String {
    let mut out = String::new();
    let mut in_code = false;
    for c in line.chars() {
        if c == '`' {
            in_code = !in_code;
        } else if !in_code {
            out.push(c);
        }
    }
    out
}

/// The text of `[text](target)` links kept, their targets dropped.
fn link_texts(heading: &str) -> String {
    let mut out = String::new();
    let mut rest = heading;
    while let Some(open) = rest.find("](") {
        let Some(close) = rest[open..].find(')') else {
            break;
        };
        out.push_str(&rest[..open]);
        rest = &rest[open + close + 1..];
    }
    out.push_str(rest);
    out.replace('[', "")
}

/// GitHub's anchor for a heading's text (see the file's opening).
fn slug(heading: &str) -> String {
    link_texts(heading)
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '_' | '-' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Every anchor a Markdown file's headings define.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let mut out = BTreeSet::new();
    for (_, line) in prose_lines(text) {
        let hashes = line.len() - line.trim_start_matches('#').len();
        if !(1..=6).contains(&hashes) || !line[hashes..].starts_with(' ') {
            continue;
        }
        let base = slug(line[hashes..].trim());
        let n = seen.entry(base.clone()).or_insert(0);
        out.insert(if *n == 0 {
            base.clone()
        } else {
            format!("{base}-{n}")
        });
        *n += 1;
    }
    out
}

/// The targets of the inline links and images of one line (`[text](target)`, `![alt](target)`).
fn targets(line: &str) -> Vec<String> {
    let line = without_code(line);
    let mut out = Vec::new();
    let mut rest = line.as_str();
    while let Some(open) = rest.find("](") {
        let after = &rest[open + 2..];
        let end = after.find([')', ' ']).unwrap_or(after.len());
        out.push(after[..end].to_string());
        rest = &after[end..];
    }
    out
}

/// What is wrong with one link of `doc`, if anything.
fn check(
    doc: &Path,
    target: &str,
    anchors_of: &mut BTreeMap<PathBuf, BTreeSet<String>>,
) -> Option<String> {
    let is_web = target
        .split_once(':')
        .is_some_and(|(scheme, _)| scheme.chars().all(|c| c.is_ascii_alphabetic()));
    if is_web || target.is_empty() {
        return None;
    }
    let (path, anchor) = match target.split_once('#') {
        Some((path, anchor)) => (path, Some(anchor)),
        None => (target, None),
    };
    let file = if path.is_empty() {
        common::repo().join(doc)
    } else {
        common::repo()
            .join(doc.parent().unwrap_or(Path::new("")))
            .join(path)
    };
    if !file.exists() {
        return Some(format!("`{path}` does not exist"));
    }
    let anchor = anchor?;
    if file.extension().is_none_or(|e| e != "md") {
        return None;
    }
    let known = anchors_of.entry(file.clone()).or_insert_with(|| {
        anchors(&std::fs::read_to_string(&file).expect("a linked Markdown file reads"))
    });
    (!known.contains(anchor)).then(|| {
        format!(
            "no heading of {} has the anchor `#{anchor}`",
            if path.is_empty() { "this file" } else { path }
        )
    })
}

#[test]
fn every_relative_link_and_anchor_resolves() {
    let mut anchors_of = BTreeMap::new();
    let mut problems = Vec::new();
    let mut links = 0;
    for doc in docs() {
        let text = std::fs::read_to_string(common::repo().join(&doc)).expect("doc reads");
        for (number, line) in prose_lines(&text) {
            for target in targets(line) {
                links += 1;
                if let Some(problem) = check(&doc, &target, &mut anchors_of) {
                    problems.push(format!("{}:{number}: ({target}): {problem}", doc.display()));
                }
            }
        }
    }
    println!("doc links: {links} checked");
    assert!(
        links > 100,
        "only {links} links found: is the parser broken?"
    );
    assert!(
        problems.is_empty(),
        "broken links:\n{}",
        problems.join("\n")
    );
}

#[test]
fn anchors_follow_github() {
    let text = "# Presets (`--preset seed|ours`)\n## A\\*: jump point search\n\
                ```sh\n# not a heading\n```\n## Tests\n## Tests\n\
                ### Measured: ray against beam, the [RCD](x.md) filter\n";
    let found: Vec<String> = anchors(text).into_iter().collect();
    assert_eq!(
        found,
        [
            "a-jump-point-search",
            "measured-ray-against-beam-the-rcd-filter",
            "presets---preset-seedours",
            "tests",
            "tests-1",
        ]
    );
    let mut cache = BTreeMap::new();
    let readme = Path::new("README.md");
    assert!(check(readme, "docs/no-such-doc.md", &mut cache).is_some());
    assert!(check(readme, "docs/plan.md#no-such-heading", &mut cache).is_some());
    assert!(check(readme, "docs/plan.md#options", &mut cache).is_none());
    assert!(check(readme, "https://example.com/x.md#y", &mut cache).is_none());
    assert_eq!(
        targets("see [a](b.md#c) and `[x](y)` and ![p](img/q.png)"),
        ["b.md#c", "img/q.png"]
    );
}

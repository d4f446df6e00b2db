//! Every command example in `README.md`, `CONTRIBUTING.md` and `docs/*.md` runs here and its
//! output is compared with the one the doc shows (issue 16, item 4: the README once showed a
//! `min_clearance_m` of 0.171 where the program printed 0.122).
//!
//! Convention (explained for authors in `CONTRIBUTING.md`, "Documented examples"): an example is
//! a ```` ```console ```` block. A line `$ COMMAND` starts a command (a line ending in `\`
//! continues it); an optional `? N` line right after it is the exit status the command must end
//! with (0 otherwise); the lines up to the next `$ ` or the end of the block are its stdout
//! followed by its stderr, compared with snapbox (`[..]` elides part of a line, `...` on its own
//! line elides lines; the doc says why next to each). Commands run through `sh -c` with the
//! built `twil` first on `PATH`, one doc at a time in a temporary directory that holds a copy of
//! the repository's `worlds/` and empty `out/` and `docs/img/` folders: the examples of one doc
//! see each other's files (a recording, then `twil view` of it) but never write into the
//! repository.
//!
//! A `twil` command anywhere else (a `sh` block, or a `$ twil` line in another block) fails this
//! test unless [`SKIPPED`] lists it with the reason it cannot run here. `SNAPSHOTS=overwrite` rewrites the
//! output of every failing example in its doc from the program (elisions included: put them
//! back by hand).
//!
//! Run time: 52 examples in 14 to 28 s (`--release`, the 2-core machine shared with other
//! builds; one thread per doc, the longest being the two missions that write GIFs, about 10 s
//! each).

use crate::common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

/// Command examples that cannot run in this test: `(doc, part of the command line, reason)`.
/// Every entry must match an example (an entry that matches nothing fails the test).
const SKIPPED: &[(&str, &str, &str)] = &[
    (
        "README.md",
        "cargo run --release -p twil-host -- simulate --real worlds/office.da --params worlds/office.par --out out/office",
        "the quick start: the same mission runs as `twil simulate … --out out/office --record …` in the README's tour",
    ),
    (
        "CONTRIBUTING.md",
        "twil plan --world",
        "the convention's own illustration (its output is abbreviated with …)",
    ),
    (
        "docs/firmware.md",
        "TWIL_QEMU_LOG=q.log twil ping",
        "a recipe with cargo xtask defmt-log (the log's timestamps vary)",
    ),
    (
        "docs/firmware.md",
        "twil ping --remote tcp:127.0.0.1:PORT",
        "needs a QEMU started by cargo xtask qemu PORT",
    ),
    (
        "docs/firmware.md",
        "twil ping --remote qemu       # or let twil",
        "needs QEMU and the firmware ELF (the console example beside it runs it)",
    ),
    (
        "docs/bring-up.md",
        "twil ping --remote /dev/ttyUSB0",
        "needs a board on a serial port (tests/serial_pty.rs runs it on QEMU's pseudo-terminal)",
    ),
    (
        "docs/bring-up.md",
        "twil check --remote /dev/ttyUSB0",
        "needs a board on a serial port (tests/serial_pty.rs runs it on QEMU's pseudo-terminal)",
    ),
    (
        "docs/bring-up.md",
        "twil mission --remote /dev/ttyUSB0",
        "needs a board on a serial port and a room (tests/serial_pty.rs runs a mission on QEMU's pseudo-terminal)",
    ),
    (
        "docs/mission.md",
        "twil mission --remote qemu",
        "QEMU runs the firmware for minutes (tests/mission_remote.rs covers it under cargo xtask test)",
    ),
    (
        "docs/recording.md",
        "--live --speed 5",
        "paces a 482 s mission to the wall clock (about 96 s) and serves WebSocket clients",
    ),
    (
        "docs/robot-model.md",
        "twil simulate --real worlds/$w.da",
        "a loop over placeholders (S, B): the recipe for a table, not one command",
    ),
    (
        "docs/simulate.md",
        "twil simulate --real worlds/$w.da",
        "a loop over placeholders (SPEEDS, P.par, R): the recipe for a table, not one command",
    ),
];

/// One command example of a doc.
#[derive(Debug, Clone)]
struct Example {
    doc: String,
    /// 1-based line of the `$ ` line, for messages.
    line: usize,
    /// The command as `sh -c` gets it (continuation lines kept).
    command: String,
    /// Exit status the doc implies.
    status: i32,
    /// Whether it is a ```` ```console ```` example (others are only counted, or skipped).
    console: bool,
    /// Expected stdout then stderr; `None` when the doc shows no output (status only).
    expected: Option<String>,
    /// 0-based line range of the expected output in the doc, for `SNAPSHOTS=overwrite`.
    output_lines: std::ops::Range<usize>,
}

/// The docs this test walks, as paths relative to the repository root.
fn docs() -> Vec<String> {
    let mut docs = vec!["README.md".to_string(), "CONTRIBUTING.md".to_string()];
    let mut more: Vec<String> = std::fs::read_dir(common::repo().join("docs"))
        .expect("docs/")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| name.ends_with(".md"))
        .map(|name| format!("docs/{name}"))
        .collect();
    more.sort();
    docs.extend(more);
    docs
}

/// Whether a line of a shell recipe runs `twil` (directly, after variable assignments, or
/// through `cargo run -p twil-host`).
fn runs_twil(line: &str) -> bool {
    let line = line.trim_start().trim_start_matches("$ ");
    if line.starts_with('#') {
        return false;
    }
    let words: Vec<&str> = line.split_whitespace().collect();
    let first = words
        .iter()
        .position(|w| !w.contains('=') || w.starts_with('-'));
    match first.map(|i| words[i]) {
        Some("twil") => true,
        Some("cargo") => line.contains("-p twil-host") && line.contains(" run "),
        _ => false,
    }
}

/// Parses `doc`'s text: the examples of its console blocks and the `twil` command lines found
/// elsewhere (shell recipes, or `$ twil` lines in other blocks), as examples without output.
fn parse(doc: &str, text: &str) -> (Vec<Example>, Vec<Example>) {
    let lines: Vec<&str> = text.lines().collect();
    let mut console = Vec::new();
    let mut elsewhere = Vec::new();
    // The open fence: its number of backticks and its language.
    let mut fence: Option<(usize, String)> = None;
    let mut i = 0;
    while i < lines.len() {
        let trimmed = lines[i].trim_start();
        let ticks = trimmed.len() - trimmed.trim_start_matches('`').len();
        if ticks >= 3 {
            let info = trimmed[ticks..].trim();
            match &fence {
                None => {
                    fence = Some((ticks, info.to_string()));
                    i += 1;
                    continue;
                }
                // Only a bare fence at least as long closes (a ```` block may show ``` ones).
                Some((open, _)) if ticks >= *open && info.is_empty() => {
                    fence = None;
                    i += 1;
                    continue;
                }
                Some(_) => {}
            }
        }
        let Some(lang) = fence.as_ref().map(|(_, lang)| lang.as_str()) else {
            i += 1;
            continue;
        };
        if lang == "console" {
            if let Some(first) = trimmed.strip_prefix("$ ") {
                let line = i + 1;
                let mut command = first.to_string();
                while command.ends_with('\\') && i + 1 < lines.len() {
                    i += 1;
                    command.push('\n');
                    command.push_str(lines[i]);
                }
                i += 1;
                let mut status = 0;
                if let Some(code) = lines.get(i).and_then(|l| l.strip_prefix("? ")) {
                    status = code
                        .trim()
                        .parse()
                        .unwrap_or_else(|_| panic!("{doc}:{}: `? {code}`: not a status", i + 1));
                    i += 1;
                }
                let start = i;
                while i < lines.len()
                    && !lines[i].starts_with("$ ")
                    && !lines[i].trim_start().starts_with("```")
                {
                    i += 1;
                }
                let expected: String = lines[start..i].iter().map(|l| format!("{l}\n")).collect();
                console.push(Example {
                    doc: doc.to_string(),
                    line,
                    command,
                    status,
                    console: true,
                    expected: (!expected.trim().is_empty()).then_some(expected),
                    output_lines: start..i,
                });
                continue;
            }
        } else {
            // Shell recipes: every twil line; other blocks: only `$ twil` lines (a usage
            // synopsis such as `twil plan --world W.da` is not an example).
            let shell = matches!(lang, "sh" | "bash" | "shell");
            let is_prompt = trimmed.starts_with("$ ");
            if (shell || is_prompt) && runs_twil(trimmed) {
                elsewhere.push(Example {
                    doc: doc.to_string(),
                    line: i + 1,
                    command: trimmed.to_string(),
                    status: 0,
                    console: false,
                    expected: None,
                    output_lines: 0..0,
                });
            }
        }
        i += 1;
    }
    (console, elsewhere)
}

/// The reason `example` is skipped, and which entry of [`SKIPPED`] said so.
fn skip_reason(example: &Example) -> Option<usize> {
    SKIPPED
        .iter()
        .position(|(doc, part, _)| *doc == example.doc && example.command.contains(part))
}

/// A temporary directory the examples of one doc run in.
fn sandbox() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temporary directory");
    // A copy (72 KB), not a link: an example that writes into `worlds/` cannot change the
    // repository's.
    let worlds = dir.path().join("worlds");
    std::fs::create_dir_all(&worlds).expect("worlds/");
    for entry in std::fs::read_dir(common::repo().join("worlds")).expect("worlds/") {
        let from = entry.expect("worlds/ entry").path();
        if from.is_file() {
            std::fs::copy(&from, worlds.join(from.file_name().expect("name"))).expect("copy");
        }
    }
    std::fs::create_dir_all(dir.path().join("out")).expect("out/");
    std::fs::create_dir_all(dir.path().join("docs/img")).expect("docs/img/");
    dir
}

/// Runs one example; `Err` describes how it differs from the doc.
fn run(example: &Example, dir: &Path) -> Result<(), (String, String)> {
    let bin = Path::new(env!("CARGO_BIN_EXE_twil"));
    let path = format!(
        "{}:{}",
        bin.parent().expect("bin dir").display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let output = Command::new("sh")
        .arg("-c")
        .arg(&example.command)
        .current_dir(dir)
        .env("PATH", path)
        // The documented outputs assume none of twil's debugging switches.
        .env_remove("TWIL_LINK_DEBUG")
        .env_remove("TWIL_SIM_DEBUG")
        .env_remove("TWIL_QEMU_LOG")
        .output()
        .expect("sh");
    let actual = format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let mut problems = Vec::new();
    let status = output.status.code().unwrap_or(-1);
    if status != example.status {
        problems.push(format!(
            "exit status {status}, the doc implies {}",
            example.status
        ));
    }
    if let Some(expected) = &example.expected {
        let label = format!("{}:{}", example.doc, example.line);
        if let Err(e) = snapbox::Assert::new()
            // `\` in the output (escaped control characters) is not a path separator.
            .normalize_paths(false)
            .try_eq(
                Some(&label),
                snapbox::Data::text(actual.clone()),
                snapbox::Data::text(expected.clone()),
            )
        {
            problems.push(e.to_string());
        }
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err((problems.join("\n"), actual))
    }
}

#[test]
fn every_documented_example_runs_and_prints_what_the_doc_shows() {
    let started = Instant::now();
    let overwrite = std::env::var("SNAPSHOTS").is_ok_and(|v| v == "overwrite");
    let mut texts = BTreeMap::new();
    let mut to_run: Vec<Vec<Example>> = Vec::new();
    let mut skipped = Vec::new();
    let mut unlisted = Vec::new();
    let mut used = vec![false; SKIPPED.len()];
    for doc in docs() {
        let text = std::fs::read_to_string(common::repo().join(&doc)).expect("doc");
        let (console, elsewhere) = parse(&doc, &text);
        texts.insert(doc.clone(), text);
        let mut runs = Vec::new();
        for example in console.into_iter().chain(elsewhere) {
            match skip_reason(&example) {
                Some(entry) => {
                    used[entry] = true;
                    skipped.push((example, SKIPPED[entry].2));
                }
                None if example.console => runs.push(example),
                None => unlisted.push(example),
            }
        }
        if !runs.is_empty() {
            to_run.push(runs);
        }
    }

    // One thread per doc: the slow examples (missions that write GIFs) overlap.
    let failures: Vec<(Example, String, String)> = std::thread::scope(|scope| {
        let handles: Vec<_> = to_run
            .iter()
            .map(|runs| {
                scope.spawn(move || {
                    let dir = sandbox();
                    let mut failures = Vec::new();
                    for example in runs {
                        if let Err((why, actual)) = run(example, dir.path()) {
                            failures.push((example.clone(), why, actual));
                        }
                    }
                    failures
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("a doc's thread"))
            .collect()
    });

    let ran: usize = to_run.iter().map(Vec::len).sum();
    skipped.sort_by_key(|(e, _)| (e.doc.clone(), e.line));
    println!(
        "documented examples: {ran} ran, {} skipped ({:.1} s)",
        skipped.len(),
        started.elapsed().as_secs_f64()
    );
    for (example, reason) in &skipped {
        println!("  skipped {}:{}: {reason}", example.doc, example.line);
    }

    if overwrite {
        rewrite(&texts, &failures);
    }
    let mut report = String::new();
    for example in &unlisted {
        report.push_str(&format!(
            "{}:{}: `{}` is neither a ```console example nor listed in SKIPPED\n",
            example.doc, example.line, example.command
        ));
    }
    for (entry, (doc, part, _)) in SKIPPED.iter().enumerate() {
        if !used[entry] {
            report.push_str(&format!(
                "SKIPPED entry ({doc}, `{part}`) matches no example\n"
            ));
        }
    }
    for (example, why, _) in &failures {
        report.push_str(&format!(
            "{}:{}: $ {}\n{why}\n",
            example.doc, example.line, example.command
        ));
    }
    assert!(
        report.is_empty(),
        "{report}(SNAPSHOTS=overwrite rewrites the docs' outputs from the program)"
    );
}

/// `SNAPSHOTS=overwrite`: the failing examples' output blocks, replaced by what the program
/// printed.
fn rewrite(texts: &BTreeMap<String, String>, failures: &[(Example, String, String)]) {
    for (doc, text) in texts {
        // Only shown outputs are rewritten (a status-only example keeps showing none).
        let mut mine: Vec<&(Example, String, String)> = failures
            .iter()
            .filter(|(e, _, _)| &e.doc == doc && e.expected.is_some())
            .collect();
        if mine.is_empty() {
            continue;
        }
        mine.sort_by_key(|(e, _, _)| std::cmp::Reverse(e.output_lines.start));
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        for (example, _, actual) in mine {
            let new: Vec<String> = actual.lines().map(str::to_string).collect();
            lines.splice(example.output_lines.clone(), new);
        }
        let mut out = lines.join("\n");
        out.push('\n');
        std::fs::write(common::repo().join(doc), out).expect("rewrite doc");
        println!("rewrote {doc}");
    }
}

/// The parser reads what the convention says: commands with continuations, statuses, outputs;
/// a `twil` line of a shell recipe or a `$ twil` line elsewhere is found, a synopsis is not.
#[test]
fn the_parser_follows_the_convention() {
    let doc = "text\n\
        ```console\n\
        $ twil plan \\\n    --json\n\
        {\"status\":\"found\"}\n\
        $ twil plan --world /dev/zero\n\
        ? 1\n\
        twil: /dev/zero: [..]\n\
        $ printf 'x' > a.ROB\n\
        ```\n\
        ````text\n\
        ```console\n\
        $ twil shown --inside\n\
        ```\n\
        ````\n\
        ```sh\n\
        cargo xtask test\n\
        TWIL_QEMU_LOG=q.log twil ping --remote qemu\n\
        cargo run --release -p twil-host -- plan --json\n\
        ```\n\
        ```text\n\
        twil plan --world W.da --params P.par [--json]\n\
        ```\n";
    let (console, elsewhere) = parse("x.md", doc);
    let got: Vec<(usize, &str, i32, Option<&str>)> = console
        .iter()
        .map(|e| (e.line, e.command.as_str(), e.status, e.expected.as_deref()))
        .collect();
    assert_eq!(
        got,
        [
            (
                3,
                "twil plan \\\n    --json",
                0,
                Some("{\"status\":\"found\"}\n")
            ),
            (
                6,
                "twil plan --world /dev/zero",
                1,
                Some("twil: /dev/zero: [..]\n")
            ),
            (9, "printf 'x' > a.ROB", 0, None),
        ]
    );
    let lines: Vec<usize> = elsewhere.iter().map(|e| e.line).collect();
    assert_eq!(lines, [13, 18, 19], "{elsewhere:?}");
}

//! docs/formats.md's example files, read by the readers `twil` uses, so the document a user
//! writes a first world from cannot drift from what the tools accept.
//!
//! Each example is a ```` ```text ```` block right after a `<!-- file: NAME -->` line; the
//! test writes them all into one folder (so a `.MAP` can name its `.ROB`) and reads each by
//! its extension. It also checks that every format the tools read has an example.

use std::collections::BTreeMap;
use std::path::Path;

use crate::common::repo;
use twil_host::cspace::load::{load_map, load_robot, load_tra};
use twil_host::world_io::{read_da, read_par};

/// The `<!-- file: NAME -->` examples of `doc`: name → text.
fn examples(doc: &str) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let mut lines = doc.lines();
    while let Some(line) = lines.next() {
        let Some(name) = line
            .trim()
            .strip_prefix("<!-- file:")
            .and_then(|rest| rest.strip_suffix("-->"))
        else {
            continue;
        };
        assert_eq!(
            lines.next().map(str::trim),
            Some("```text"),
            "the example {name} must be a ```text block right after its marker"
        );
        let mut text = String::new();
        for l in lines.by_ref() {
            if l.trim() == "```" {
                break;
            }
            text.push_str(l);
            text.push('\n');
        }
        out.insert(name.trim().to_string(), text);
    }
    out
}

#[test]
fn every_example_file_in_formats_md_reads_back() {
    let doc = std::fs::read_to_string(repo().join("docs/formats.md")).unwrap();
    let files = examples(&doc);
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in &files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let path = |name: &str| dir.path().join(name);
    let mut robot = None;
    let mut read = Vec::new();
    // .ROB first: a .MAP is read for a robot.
    let mut names: Vec<&String> = files.keys().collect();
    names.sort_by_key(|n| !n.ends_with(".ROB"));
    for name in names {
        let ext = Path::new(name).extension().unwrap().to_str().unwrap();
        let p = path(name);
        match ext {
            "da" => {
                read_da(&p).unwrap_or_else(|e| panic!("{e}"));
            }
            "par" => {
                read_par(&p).unwrap_or_else(|e| panic!("{e}"));
            }
            "ROB" => robot = Some(load_robot(&p).unwrap_or_else(|e| panic!("{e}"))),
            "MAP" => {
                let robot = robot.as_ref().expect("a .ROB example for the .MAP");
                load_map(&p, robot).unwrap_or_else(|e| panic!("{e}"));
            }
            "TRA" => {
                load_tra(&p).unwrap_or_else(|e| panic!("{e}"));
            }
            "toml" => {
                let file = twil_host::robot_file::read(&p).unwrap_or_else(|e| panic!("{e}"));
                let default = twil_core::robot::RobotConfig::DEFAULT;
                twil_host::robot_file::resolve(default, Some(&file), &[])
                    .unwrap_or_else(|e| panic!("{e}"));
            }
            other => panic!("{name}: no reader for .{other}"),
        }
        read.push(ext.to_string());
    }
    for ext in ["da", "par", "ROB", "MAP", "TRA", "toml"] {
        assert!(
            read.iter().any(|r| r == ext),
            "docs/formats.md has no .{ext} example"
        );
    }
}

#[test]
fn a_broken_example_is_caught() {
    // The check is not vacuous: the .da example with a vertex cut off fails to read.
    let doc = std::fs::read_to_string(repo().join("docs/formats.md")).unwrap();
    let da = examples(&doc)["room.da"].clone();
    let broken = da.trim_end().rsplit_once(' ').unwrap().0.to_string();
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("broken.da");
    std::fs::write(&p, broken).unwrap();
    let e = read_da(&p).unwrap_err().to_string();
    assert!(e.ends_with("; see docs/formats.md#da"), "{e}");
}

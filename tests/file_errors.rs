//! Every file the `twil` commands read, fed what a careless or hostile user might give: an
//! endless device, a 10 MB file, terminal escape sequences, bytes that are not UTF-8, joint
//! limits that ask for an absurd map. Each must end quickly with exit code 1 and one line on
//! stderr that names the file, the line (or the size and cap) and the field, quotes values
//! escaped, and prints no absurd number.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

/// Run `twil args`, expect exit code 1 within `limit` and return stderr.
fn fails(args: &[&str]) -> String {
    let t = Instant::now();
    let out: Output = common::twil().args(args).output().unwrap();
    let elapsed = t.elapsed();
    assert!(
        elapsed < Duration::from_secs(10),
        "{args:?} took {elapsed:?}"
    );
    assert_eq!(
        out.status.code(),
        Some(1),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.stdout.is_empty(), "{args:?} printed on stdout");
    // Nothing raw from the file reaches the terminal.
    assert!(
        !out.stderr.iter().any(|b| *b == 0x1b || *b == 0x07),
        "{args:?}: raw control byte in {:?}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8(out.stderr).expect("stderr is UTF-8");
    assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
    assert!(!err.contains("18446744073709551615"), "{err}");
    err
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn world(name: &str) -> PathBuf {
    common::world(name)
}

/// `cspace` with a `.ROB` and more options.
fn cspace(rob: &Path, extra: &[&str]) -> String {
    let mut args = vec!["cspace", "--rob", s(rob)];
    args.extend_from_slice(&["--start", "-60,-35", "--goal", "140,-5"]);
    if !extra.contains(&"--from-map") && !extra.contains(&"--increments") {
        args.extend_from_slice(&["--increments", "2,2"]);
    }
    args.extend_from_slice(extra);
    fails(&args)
}

/// Every file option of every command, with `file` in its place and good files elsewhere.
fn every_file_option(file: &Path) -> Vec<(&'static str, Vec<String>)> {
    let (da, par, rob) = (
        world("office.da"),
        world("office.par"),
        world("seed000-nav.ROB"),
    );
    let own = |p: &Path| p.to_str().unwrap().to_owned();
    let f = own(file);
    let cs = |opt: &str, rob: &str| {
        let mut v = vec![
            "cspace", "--rob", rob, "--start", "-60,-35", "--goal", "140,-5",
        ];
        if opt != "--from-map" {
            v.extend_from_slice(&["--increments", "2,2"]);
        }
        v.into_iter().map(str::to_owned).collect::<Vec<_>>()
    };
    let plan =
        |a: &[&str]| -> Vec<String> { ["plan"].iter().chain(a).map(|x| x.to_string()).collect() };
    let sim = |a: &[&str]| -> Vec<String> {
        ["simulate"]
            .iter()
            .chain(a)
            .map(|x| x.to_string())
            .collect()
    };
    vec![
        (
            "plan --world",
            plan(&["--world", &f, "--params", &own(&par)]),
        ),
        (
            "plan --params",
            plan(&["--world", &own(&da), "--params", &f]),
        ),
        ("plan --map", plan(&["--map", &f, "--params", &own(&par)])),
        (
            "simulate --real",
            sim(&["--real", &f, "--params", &own(&par)]),
        ),
        (
            "simulate --params",
            sim(&["--real", &own(&da), "--params", &f]),
        ),
        (
            "simulate --known",
            sim(&["--real", &own(&da), "--params", &own(&par), "--known", &f]),
        ),
        (
            "plan --robot",
            plan(&["--world", &own(&da), "--params", &own(&par), "--robot", &f]),
        ),
        (
            "simulate --robot",
            sim(&["--real", &own(&da), "--params", &own(&par), "--robot", &f]),
        ),
        ("cspace --rob", cs("--rob", &f)),
        (
            "cspace --from-map",
            [
                cs("--from-map", &own(&rob)),
                vec!["--from-map".into(), f.clone()],
            ]
            .concat(),
        ),
        (
            "cspace --compare",
            [
                cs("--compare", &own(&rob)),
                vec!["--compare".into(), f.clone()],
            ]
            .concat(),
        ),
    ]
}

#[test]
fn an_endless_device_is_refused_at_the_cap_by_every_reader() {
    let zero = Path::new("/dev/zero");
    if !zero.exists() {
        return;
    }
    for (option, args) in every_file_option(zero) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let err = fails(&args);
        assert!(err.starts_with("twil: /dev/zero: "), "{option}: {err}");
        assert!(
            err.contains("goes on beyond the cap, more than the")
                && err.contains("bytes allowed for"),
            "{option}: {err}"
        );
    }
}

#[test]
fn a_10_mb_file_is_refused_by_its_size_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let big = dir.path().join("big.txt");
    // Sparse where the file system allows: the test writes no 10 MB.
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(10_000_000).unwrap();
    for (option, args) in every_file_option(&big) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let err = fails(&args);
        assert!(
            err.contains("big.txt: is 10000000 bytes, more than the "),
            "{option}: {err}"
        );
        // Every file error ends citing its format's section (docs/formats.md).
        assert!(
            err.trim_end().contains("; see docs/formats.md#"),
            "{option}: {err}"
        );
    }
    let err = cspace(&big, &[]);
    assert!(
        err.ends_with(
            "big.txt: is 10000000 bytes, more than the 1048576 bytes allowed for a .ROB file; \
             see docs/formats.md#rob\n"
        ),
        "{err}"
    );
}

#[test]
fn escape_sequences_in_files_are_shown_escaped() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    // ESC ] 0 ; title BEL, ESC [ 2 J: set the window title, clear the screen.
    let rob = write("esc.ROB", "1\n\u{1b}]0;pwned\u{7}\u{1b}[2J 0 0\n");
    let err = cspace(&rob, &[]);
    assert!(
        err.contains("esc.ROB: line 2: field `vertex count` of obstacle polygon 1: `\\u{1b}]0;pwned\\u{7}\\u{1b}[2J` is not a number"),
        "{err}"
    );
    let map = write("esc.MAP", "nav\n-180 -75\n2 2\n\u{1b}[31m 111\n");
    let err = cspace(&world("seed000-nav.ROB"), &["--from-map", s(&map)]);
    assert!(
        err.contains("esc.MAP: line 4: field `values of joint 1`: `\\u{1b}[31m`"),
        "{err}"
    );
    let tra = write("esc.TRA", "nav\n-180 -75\n2 2\n61 21\n\u{9b}6n 1\n");
    let err = cspace(&world("seed000-nav.ROB"), &["--compare", s(&tra)]);
    assert!(
        err.contains("esc.TRA: line 5: field `index of joint 1` of path point 2: `\\u{9b}6n`"),
        "{err}"
    );
    // The .da reader too (through the same escaping).
    let da = write("esc.da", "1\n3\n0 0\n1 \u{1b}[0m\n");
    let err = fails(&[
        "plan",
        "--world",
        s(&da),
        "--params",
        s(&world("office.par")),
    ]);
    assert!(
        err.contains("esc.da: line 4") && err.contains("\\u{1b}[0m"),
        "{err}"
    );
    // And the robot file's, whether the TOML parser or the key check refuses it.
    for text in ["wheel_radius_m = \u{1b}[2J\n", "\"\u{9b}6n\" = 1\n"] {
        let robot = write("esc.toml", text);
        let err = fails(&[
            "plan",
            "--world",
            s(&world("office.da")),
            "--params",
            s(&world("office.par")),
            "--robot",
            s(&robot),
        ]);
        assert!(err.contains("esc.toml:1: "), "{err}");
    }
}

#[test]
fn bytes_that_are_not_utf8_are_named_by_line_and_offset() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = std::fs::read(world("seed000-nav.ROB")).unwrap();
    // The 3rd line's first byte becomes 0xff.
    let at = text
        .iter()
        .enumerate()
        .filter(|(_, b)| **b == b'\n')
        .nth(1)
        .unwrap()
        .0
        + 1;
    text[at] = 0xff;
    let rob = dir.path().join("latin1.ROB");
    std::fs::write(&rob, &text).unwrap();
    let err = cspace(&rob, &[]);
    assert!(
        err.ends_with(&format!(
            "latin1.ROB: line 3: not text: byte 0xff at offset {at} is not UTF-8; \
             see docs/formats.md#rob\n"
        )),
        "{err}"
    );
    for (opt, name, anchor) in [
        ("--from-map", "bin.MAP", "map"),
        ("--compare", "bin.TRA", "tra"),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, b"nav\n-180 -75\n\xc3(\n").unwrap();
        let err = cspace(&world("seed000-nav.ROB"), &[opt, s(&p)]);
        assert!(
            err.ends_with(&format!(
                "{name}: line 3: not text: byte 0xc3 at offset 13 is not UTF-8; \
                 see docs/formats.md#{anchor}\n"
            )),
            "{err}"
        );
    }
}

#[test]
fn huge_joint_limits_name_the_file_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let rob = dir.path().join("huge.ROB");
    std::fs::write(
        &rob,
        "% no obstacles\n0\n2\nP -1e30 1e30 0\n0\n% joint 2\nP 0 10\n90 0\n",
    )
    .unwrap();
    let err = cspace(&rob, &[]);
    assert_eq!(
        err,
        format!(
            "twil: {}: line 4: field `maximum length` of joint 1: the limits -1e30 to 1e30 in \
             steps of 2 need more than the 4096 values this build holds; use a larger increment \
             or narrower limits; see docs/formats.md#rob\n",
            rob.display()
        )
    );
    // Each joint within its own cap, but not the two together: both limits named.
    std::fs::write(&rob, "0\n2\nP 0 1000 0\n0\nP 0\n 1000 90\n0\n").unwrap();
    let err = cspace(&rob, &[]);
    assert!(
        err.contains("huge.ROB: lines 3 and 6: fields `maximum length` of joint 1 and `maximum length` of joint 2: the map would need 501 x 501 = 251001 cells, more than the 131072"),
        "{err}"
    );
    // A bad increment is the command line's, not the file's.
    let err = cspace(&world("seed000-nav.ROB"), &["--increments", "0,2"]);
    assert!(
        err.starts_with("twil: --increments: increment 0 of joint 1"),
        "{err}"
    );
}

/// `twil --help` lists the exit statuses and the environment variables (the README shows the
/// whole list, checked by `tests/doc_examples.rs`).
#[test]
fn help_lists_exit_status_and_environment() {
    let o = common::twil().arg("--help").output().unwrap();
    assert!(o.status.success());
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(
        help.contains("Exit status:") && help.contains("Environment:"),
        "{help}"
    );
    for var in [
        "TWIL_QEMU_ELF",
        "TWIL_QEMU_LOG",
        "TWIL_LINK_DEBUG",
        "TWIL_SIM_DEBUG",
    ] {
        assert!(help.contains(var), "{var}");
    }
}

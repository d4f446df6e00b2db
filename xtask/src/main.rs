//! `cargo xtask …`: firmware builds, QEMU runs and the CI entry point.

use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{bail, Context, Result};

mod cycles;
mod defmt_log;
mod fuzz;

/// The QEMU command line, shared with `twil --remote qemu`.
#[path = "../../host/src/qemu_cmd.rs"]
mod qemu_cmd;

/// `cargo xtask …`: the project's own commands (firmware, QEMU, CI).
#[derive(clap::Parser, Debug)]
#[command(name = "cargo xtask", bin_name = "cargo xtask", about, after_help = ENVIRONMENT)]
struct Cli {
    #[command(subcommand)]
    command: Task,
}

/// Environment variables the tasks read.
const ENVIRONMENT: &str = "Environment:
  CARGO_TARGET_DIR  where the ELFs are built and looked for (default: target/)
  CARGO             the cargo to run (set by cargo itself)";

#[derive(clap::Subcommand, Debug)]
enum Task {
    /// Install qemu-system-arm if missing, check import cycles, build the firmware, check fmt +
    /// clippy + `cargo doc` (warnings as errors), run every test (the CI entry point, `.ci/run`).
    Test,
    /// Build both firmware ELFs (hardware, and QEMU: twil-firmware-qemu) and print their sizes.
    Firmware,
    /// Print flash / static RAM / CCM of the built ELFs.
    Size,
    /// Run the QEMU firmware with USART1 on tcp:127.0.0.1:PORT.
    Qemu {
        /// TCP port (default: a free port).
        port: Option<String>,
    },
    /// Instructions per plan on 300x300 grids (open, 20% random, maze) and of the worst marking
    /// requests (tests/firmware_requests.rs) under QEMU.
    McuBench,
    /// Fail on an import cycle between the files of shared/, host/ or firmware/ (each printed
    /// as a chain of files) beyond the allow-list in xtask/src/cycles.rs.
    Cycles,
    /// Build the firmware's on-target tests (defmt-test) and run them under QEMU.
    OnTarget,
    /// Decode a saved QEMU log (TWIL_QEMU_LOG=FILE twil … --remote qemu).
    DefmtLog {
        /// The log file.
        file: PathBuf,
    },
    /// Run the cargo-fuzz targets of shared/fuzz (nightly + cargo-fuzz).
    Fuzz {
        /// One target, or `all` (default).
        target: Option<String>,
        /// Seconds per target (default 60).
        seconds: Option<String>,
    },
}

/// The packages of every host-side cargo run (the firmware builds only for the thumb target).
/// One selection for the tests, the instruction benchmark and clippy, so that cargo resolves
/// the same features for all three and each reuses the others' builds.
const HOST_PACKAGES: [&str; 3] = ["--workspace", "--exclude", "twil-firmware"];

/// Target of the firmware.
const THUMB: &str = "thumbv7em-none-eabihf";
/// Static RAM budget of the firmware, bytes: 120 KiB of the 128 KiB SRAM, so that the stack
/// (below the statics, flip-link) has at least 8 KiB; its measured high-water mark is logged
/// and must leave 4 KiB of it.
const STATIC_RAM_BUDGET: u64 = 120 * 1024;
/// SRAM of the STM32F405 (`memory.x`).
const RAM: std::ops::Range<u64> = 0x2000_0000..0x2002_0000;
/// CCM of the STM32F405 (`memory.x`), and where the QEMU build puts it (see firmware/build.rs).
const CCM: std::ops::Range<u64> = 0x1000_0000..0x1001_0000;
const QEMU_CCM: std::ops::Range<u64> = 0x2002_0000..0x2003_0000;
/// Flash of the STM32F405.
const FLASH: std::ops::Range<u64> = 0x0800_0000..0x0810_0000;

fn main() -> Result<()> {
    use clap::Parser;
    match Cli::parse().command {
        Task::Test => test(),
        Task::Firmware => firmware(),
        Task::Size => size(),
        Task::Qemu { port } => qemu(port.as_deref()),
        Task::McuBench => mcu_bench(),
        Task::OnTarget => on_target(),
        Task::Cycles => cycles::check(&workspace_root()),
        Task::Fuzz { target, seconds } => {
            fuzz::fuzz(&workspace_root(), target.as_deref(), seconds.as_deref())
        }
        Task::DefmtLog { file } => defmt_log_file(&file),
    }
}

fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(workspace_root());
    c
}

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace_root().join("target"))
}

/// The two ELFs: (hardware, QEMU).
fn elf_paths() -> (PathBuf, PathBuf) {
    let dir = target_dir().join(THUMB).join("firmware");
    (dir.join("twil-firmware"), dir.join(qemu_cmd::QEMU_ELF_NAME))
}

fn run(mut c: Command) -> Result<()> {
    eprintln!("xtask: running {c:?}");
    let status = c
        .status()
        .with_context(|| format!("could not start {c:?}"))?;
    if !status.success() {
        bail!("{c:?} failed with {status}");
    }
    Ok(())
}

/// Make sure the thumb target of `rust-toolchain.toml` is installed (rustup does not add the
/// file's targets to a toolchain that is already there).
fn ensure_thumb_target() -> Result<()> {
    let out = Command::new("rustc")
        .current_dir(workspace_root())
        .args(["--print", "target-libdir", "--target", THUMB])
        .output()
        .context("could not run rustc")?;
    let libdir = String::from_utf8_lossy(&out.stdout).trim().to_string();
    if out.status.success() && Path::new(&libdir).exists() {
        return Ok(());
    }
    // `rustup toolchain install` is not enough: under `cargo` the active toolchain comes from
    // `RUSTUP_TOOLCHAIN`, and rustup then installs that name without the file's targets (seen
    // when the pinned toolchain is already present, e.g. as a link to `stable`).
    let mut c = Command::new("rustup");
    c.current_dir(workspace_root())
        .args(["target", "add", THUMB]);
    run(c)
}

/// Install flip-link when it is missing: `.cargo/config.toml` links the firmware with it (the
/// stack goes below the statics, so an overflow faults instead of overwriting them).
fn ensure_flip_link() -> Result<()> {
    let found = Command::new("flip-link")
        .arg("--help")
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if found {
        return Ok(());
    }
    eprintln!(
        "xtask: flip-link (the firmware's linker, see .cargo/config.toml) is missing; \
         installing it with `cargo install flip-link --locked`"
    );
    let mut c = cargo();
    c.args(["install", "flip-link", "--locked"]);
    run(c).context("could not install flip-link; run `cargo install flip-link --locked`")
}

/// Install `qemu-system-arm` with apt when it is missing (CI runs on a fresh Debian machine).
fn ensure_qemu() -> Result<()> {
    let found = Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if found {
        return Ok(());
    }
    eprintln!("xtask: qemu-system-arm is missing; installing it with apt-get");
    let root = Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false);
    let apt = |args: &[&str]| -> Command {
        let mut c = if root {
            Command::new("apt-get")
        } else {
            let mut c = Command::new("sudo");
            c.arg("apt-get");
            c
        };
        c.args(args).env("DEBIAN_FRONTEND", "noninteractive");
        c
    };
    run(apt(&["update"]))?;
    run(apt(&[
        "install",
        "-y",
        "--no-install-recommends",
        "qemu-system-arm",
    ]))
    .context("could not install qemu-system-arm; install it by hand")?;
    Ok(())
}

fn build_firmware(qemu: bool) -> Result<()> {
    let mut c = cargo();
    c.args([
        "build",
        "--package",
        "twil-firmware",
        "--target",
        THUMB,
        "--profile",
        "firmware",
    ]);
    if qemu {
        c.args(["--no-default-features", "--features", "qemu"]);
    }
    run(c)
}

/// Build the QEMU ELF (copied to `twil-firmware-qemu`), then the hardware ELF, and report sizes.
fn firmware() -> Result<()> {
    ensure_thumb_target()?;
    ensure_flip_link()?;
    let (hardware, qemu) = elf_paths();
    build_firmware(true)?;
    std::fs::copy(&hardware, &qemu)
        .with_context(|| format!("copying {} to {}", hardware.display(), qemu.display()))?;
    build_firmware(false)?;
    size()
}

/// Sizes of an ELF, bytes.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
struct Sizes {
    /// Flash: code, constants, vector table and the initial values of `.data` and `.ccmram`.
    flash: u64,
    /// SRAM: `.data` + `.bss` + `.uninit` (+ RTIC's and the HAL's statics, all in these).
    static_ram: u64,
    /// CCM: `.ccmram`.
    ccm: u64,
    /// Stack: from `_stack_end` (its bottom, SRAM's start with flip-link) up to `_stack_start`
    /// (the initial stack pointer, right below the statics with flip-link).
    stack: u64,
}

fn sizes(elf: &Path) -> Result<Sizes> {
    use object::{Object, ObjectSection, ObjectSymbol, SectionFlags};
    let data = std::fs::read(elf)
        .with_context(|| format!("cannot read {} (run `cargo xtask firmware`)", elf.display()))?;
    let file =
        object::File::parse(&*data).with_context(|| format!("{} is not an ELF", elf.display()))?;
    let mut s = Sizes::default();
    for section in file.sections() {
        let SectionFlags::Elf { sh_flags } = section.flags() else {
            continue;
        };
        const SHF_ALLOC: u64 = 0x2;
        if sh_flags & SHF_ALLOC == 0 || section.size() == 0 {
            continue;
        }
        let addr = section.address();
        // SRAM holds `.data`, `.bss` and `.uninit` (the stack is no section: with flip-link
        // it is the SRAM below them, see `stack`). NOBITS sections (.bss, .uninit) have no
        // bytes in the file, hence none in flash.
        let nobits = section.file_range().is_none();
        if FLASH.contains(&addr) {
            s.flash += section.size();
        } else if RAM.contains(&addr) {
            s.static_ram += section.size();
            if !nobits {
                s.flash += section.size(); // initial values of .data
            }
        } else if CCM.contains(&addr) || QEMU_CCM.contains(&addr) {
            s.ccm += section.size();
            if !nobits {
                s.flash += section.size();
            }
        }
    }
    let symbol = |name: &str| {
        file.symbols()
            .find(|sym| sym.name() == Ok(name))
            .map(|sym| sym.address())
            .with_context(|| format!("{}: no symbol {name}", elf.display()))
    };
    s.stack = symbol("_stack_start")? - symbol("_stack_end")?;
    Ok(s)
}

fn size() -> Result<()> {
    let (hardware, qemu) = elf_paths();
    println!("| build | flash (bytes) | static SRAM (bytes) | CCM (bytes) | stack (bytes) |");
    println!("|-------|--------------:|--------------------:|------------:|--------------:|");
    let mut over = Vec::new();
    for (name, elf) in [("hardware", &hardware), ("qemu", &qemu)] {
        let s = sizes(elf)?;
        println!(
            "| {name} | {} | {} ({:.1} KiB) | {} | {} ({:.1} KiB) |",
            s.flash,
            s.static_ram,
            s.static_ram as f64 / 1024.0,
            s.ccm,
            s.stack,
            s.stack as f64 / 1024.0
        );
        if s.static_ram > STATIC_RAM_BUDGET {
            over.push(format!(
                "{name}: {} bytes of static SRAM, budget {STATIC_RAM_BUDGET}",
                s.static_ram
            ));
        }
    }
    if !over.is_empty() {
        bail!("static RAM over budget: {}", over.join("; "));
    }
    Ok(())
}

/// Run the QEMU firmware with USART1 on a TCP server port until interrupted.
fn qemu(port: Option<&str>) -> Result<()> {
    ensure_qemu()?;
    let (_, elf) = elf_paths();
    if !elf.is_file() {
        firmware()?;
    }
    let port: u16 = match port {
        Some(p) => p
            .parse()
            .with_context(|| format!("`{p}` is not a TCP port"))?,
        None => std::net::TcpListener::bind("127.0.0.1:0")?
            .local_addr()?
            .port(),
    };
    println!("xtask: QEMU netduinoplus2 running {}", elf.display());
    println!("xtask: USART1 on tcp:127.0.0.1:{port} (QEMU waits for a client)");
    println!("xtask: try `cargo run --release -p twil-host -- ping --remote tcp:127.0.0.1:{port}`");
    println!("xtask: the firmware's defmt log follows (decoded); Ctrl-C stops QEMU");
    let table = defmt_log::table(&elf)?;
    let mut child = Command::new("qemu-system-arm")
        .args(qemu_cmd::qemu_args(
            &elf,
            &qemu_cmd::tcp_server_serial(port),
        ))
        .stdout(std::process::Stdio::piped())
        .spawn()
        .context("cannot start qemu-system-arm")?;
    let stdout = child.stdout.take().context("QEMU's stdout")?;
    defmt_log::decode(&table, stdout, |line| {
        println!("{line}");
        true
    })?;
    let status = child.wait()?;
    if !status.success() {
        bail!("qemu-system-arm exited with {status}");
    }
    Ok(())
}

/// Decode a saved QEMU log (the firmware's defmt frames) with the QEMU ELF's table.
fn defmt_log_file(file: &Path) -> Result<()> {
    let (_, elf) = elf_paths();
    let table = defmt_log::table(&elf)?;
    let input =
        std::fs::File::open(file).with_context(|| format!("cannot open {}", file.display()))?;
    defmt_log::decode(&table, input, |line| {
        println!("{line}");
        true
    })
}

/// Measure instructions per plan under QEMU (the `mcu_bench` test of tests/firmware_qemu.rs,
/// which also asserts the 5 M budget) and print the table.
fn mcu_bench() -> Result<()> {
    ensure_qemu()?;
    firmware()?;
    run_mcu_bench()
}

/// The `mcu_bench` test alone (the firmware is built), on [`HOST_PACKAGES`] like the full test
/// run, which then reuses this build (measured: 6 min 23 s of a CI run went to rebuilding the
/// host crates when this selected `--package twil-host`).
fn run_mcu_bench() -> Result<()> {
    let mut c = cargo();
    c.args(["test", "--release"]).args(HOST_PACKAGES).args([
        "--test",
        "suite",
        "--",
        "--ignored",
        "--exact",
        "firmware_qemu::mcu_bench",
        "--nocapture",
    ]);
    run(c)?;
    // The worst requests other than `Plan` (marking obstacles), and a ping right after each.
    let mut c = cargo();
    c.args(["test", "--release"]).args(HOST_PACKAGES).args([
        "--test",
        "suite",
        "--",
        "--ignored",
        "firmware_requests::",
        "--nocapture",
    ]);
    run(c)
}

/// Build the on-target tests (`firmware/tests/on_target.rs`, QEMU build) and run them.
fn on_target() -> Result<()> {
    ensure_thumb_target()?;
    ensure_flip_link()?;
    ensure_qemu()?;
    let elf = build_on_target()?;
    run_on_target(&elf)
}

/// `cargo test --no-run` of the on-target tests; the path of the test ELF.
fn build_on_target() -> Result<PathBuf> {
    let mut c = cargo();
    c.args([
        "test",
        "--package",
        "twil-firmware",
        "--target",
        THUMB,
        "--profile",
        "firmware",
        "--no-default-features",
        "--features",
        "qemu",
        "--test",
        "on_target",
        "--no-run",
        "--message-format=json-render-diagnostics",
    ])
    .stdout(std::process::Stdio::piped());
    eprintln!("xtask: running {c:?}");
    let out = c.output().context("could not run cargo test")?;
    if !out.status.success() {
        bail!("building the on-target tests failed with {}", out.status);
    }
    // One JSON object per line; the test's artifact names its ELF in "executable".
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.contains("\"reason\":\"compiler-artifact\"") && l.contains("on_target"))
        .find_map(|l| {
            let rest = &l[l.find("\"executable\":\"")? + 14..];
            Some(PathBuf::from(&rest[..rest.find('"')?]))
        })
        .context("cargo did not report the on-target test's executable")
}

/// Run the on-target test ELF under QEMU, print its decoded defmt log, and fail when a test
/// failed (defmt-test ends with a semihosting exit: 0 when all passed; a failure panics and
/// the test's HardFault handler exits with 1) or when QEMU runs longer than a minute.
fn run_on_target(elf: &Path) -> Result<()> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    let table = defmt_log::table(elf)?;
    let mut args = qemu_cmd::qemu_args(elf, "null");
    args.splice(0..0, ["-no-reboot".to_string()]);
    eprintln!("xtask: running qemu-system-arm {}", args.join(" "));
    let mut child = Command::new("qemu-system-arm")
        .args(&args)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .context("cannot start qemu-system-arm")?;
    let stdout = child.stdout.take().context("QEMU's stdout")?;
    let timed_out = Arc::new(AtomicBool::new(false));
    let pid = child.id().to_string();
    let flag = timed_out.clone();
    std::thread::spawn(move || {
        std::thread::sleep(std::time::Duration::from_secs(60));
        flag.store(true, Ordering::SeqCst);
        let _ = Command::new("kill").args(["-9", &pid]).status();
    });
    defmt_log::decode(&table, stdout, |line| {
        println!("{line}");
        true
    })?;
    let status = child.wait()?;
    if timed_out.load(Ordering::SeqCst) {
        bail!("on-target tests: QEMU still running after 60 s (a test hangs?)");
    }
    if !status.success() {
        bail!("on-target tests failed (QEMU exited with {status})");
    }
    eprintln!("xtask: on-target tests passed");
    Ok(())
}

fn test() -> Result<()> {
    // Seconds, before anything is built.
    cycles::check(&workspace_root())?;
    ensure_qemu()?;
    firmware()?;
    // The firmware's own tests, on the (emulated) chip.
    run_on_target(&build_on_target()?)?;
    lint()?;
    doc()?;
    // The 5 M instruction budget per 300 x 300 plan is a test too (about a minute of QEMU).
    run_mcu_bench()?;
    // Last, so that the run ends with cargo test's own summary (and, on a failure, with the
    // failing tests' messages).
    let mut c = cargo();
    c.args(["test", "--release"]).args(HOST_PACKAGES);
    run_tests(c)
}

/// `cargo test`, its output passed through as it comes; when it fails, the failing tests'
/// messages are printed again at the very end, without their backtraces. A CI log often shows
/// only its head and tail, and cargo's own end (the list of names, then a backtrace) left the
/// message that said *why* in the cut middle (stop 32's doc-example failure).
fn run_tests(mut c: Command) -> Result<()> {
    use std::io::{BufRead, BufReader, Write};
    eprintln!("xtask: running {c:?}");
    let mut child = c
        .stdout(std::process::Stdio::piped())
        .spawn()
        .with_context(|| format!("could not start {c:?}"))?;
    let mut kept = Vec::new();
    if let Some(out) = child.stdout.take() {
        let mut stdout = std::io::stdout().lock();
        for line in BufReader::new(out).lines() {
            let line = line.unwrap_or_else(|e| format!("(unreadable line: {e})"));
            let _ = writeln!(stdout, "{line}");
            kept.push(line);
        }
    }
    let status = child.wait().with_context(|| format!("waiting for {c:?}"))?;
    if !status.success() {
        let recap = failure_recap(&kept, 60);
        if !recap.is_empty() {
            println!("\nxtask: the failing tests' messages again (backtraces left out):");
            for line in recap {
                println!("{line}");
            }
        }
        bail!("{c:?} failed with {status}");
    }
    Ok(())
}

/// The `---- NAME stdout ----` blocks of libtest's failure section, without backtrace lines,
/// each cut to `lines_per_test` lines.
fn failure_recap(output: &[String], lines_per_test: usize) -> Vec<String> {
    let mut recap = Vec::new();
    let mut in_block = false;
    let mut block_lines = 0;
    for line in output {
        if line.starts_with("---- ") && line.ends_with(" ----") {
            in_block = true;
            block_lines = 0;
            recap.push(line.clone());
            continue;
        }
        if !in_block {
            continue;
        }
        // libtest's list of failing names ends the blocks.
        if line == "failures:" || line.starts_with("test result:") {
            in_block = false;
            continue;
        }
        let trimmed = line.trim_start();
        let backtrace = trimmed == "stack backtrace:"
            || trimmed.starts_with("at ")
            || trimmed.starts_with("note: Some details are omitted")
            || trimmed
                .split_once(": ")
                .is_some_and(|(n, _)| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
        if backtrace {
            continue;
        }
        block_lines += 1;
        if block_lines <= lines_per_test {
            recap.push(line.clone());
        } else if block_lines == lines_per_test + 1 {
            recap.push("  [… cut: the whole message is above]".to_string());
        }
    }
    recap
}

/// The API documentation of the host crates with warnings as errors: a broken or private
/// intra-doc link fails the run (issue 27, item 5). In the `release` profile, after clippy's:
/// the dependencies' metadata, build scripts and proc-macros are the ones clippy built (11 s);
/// in `dev` they were all built again (3 min 45 s on the 2-core machine, 2026-12-06).
fn doc() -> Result<()> {
    let mut c = cargo();
    c.args(["doc", "--release", "--no-deps"])
        .args(HOST_PACKAGES)
        .env("RUSTDOCFLAGS", "-D warnings");
    run(c)
}

/// The style gates: formatting, and clippy with warnings as errors on the host crates and on
/// both firmware builds.
fn lint() -> Result<()> {
    let mut c = cargo();
    c.args(["fmt", "--all", "--", "--check"]);
    run(c)?;
    // In the profiles of the builds that follow (`release` for the host tests, `firmware`),
    // so that the proc-macros and build scripts clippy compiles are the ones those builds use
    // (the `dev` profile compiles them at opt-level 2, see `Cargo.toml`, and shares nothing).
    let mut c = cargo();
    c.args(["clippy", "--release"]).args(HOST_PACKAGES).args([
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ]);
    run(c)?;
    // `--all-targets` lints the on-target tests too (they need the `qemu` build).
    for features in [
        &["--features", "hardware"][..],
        &[
            "--all-targets",
            "--no-default-features",
            "--features",
            "qemu",
        ][..],
    ] {
        let mut c = cargo();
        c.args([
            "clippy",
            "--package",
            "twil-firmware",
            "--target",
            "thumbv7em-none-eabihf",
            "--profile",
            "firmware",
        ])
        .args(features)
        .args(["--", "-D", "warnings"]);
        run(c)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The recap keeps each failing test's message and drops its backtrace and the name list.
    #[test]
    fn the_failure_recap_keeps_messages_and_drops_backtraces() {
        let output: Vec<String> = [
            "test a::b ... FAILED",
            "",
            "failures:",
            "",
            "---- a::b stdout ----",
            "thread 'a::b' panicked at tests/a.rs:3:5:",
            "docs/x.md:12: $ twil ping",
            "stack backtrace:",
            "   0: rust_begin_unwind",
            "             at /rustc/abc/library/std/src/panicking.rs:665:5",
            "  12: main",
            "",
            "failures:",
            "    a::b",
            "",
            "test result: FAILED. 1 passed; 1 failed",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        assert_eq!(
            failure_recap(&output, 60),
            [
                "---- a::b stdout ----",
                "thread 'a::b' panicked at tests/a.rs:3:5:",
                "docs/x.md:12: $ twil ping",
                "",
            ]
        );
        assert_eq!(failure_recap(&output, 1).len(), 3);
    }

    /// The QEMU firmware's defmt log (semihosting) decodes into its boot lines, with their
    /// timestamps, and the instruction-count calibration it logs is within 0.1 % of the truth. Needs the QEMU ELF
    /// and `qemu-system-arm`, which `cargo xtask test` provides before running the tests.
    #[test]
    fn qemu_firmware_defmt_log_decodes() {
        let (_, elf) = elf_paths();
        assert!(
            elf.is_file(),
            "{} is missing: run `cargo xtask firmware` (or `cargo xtask test`)",
            elf.display()
        );
        let table = defmt_log::table(&elf).expect("defmt table");
        let mut child = Command::new("qemu-system-arm")
            .args(qemu_cmd::qemu_args(&elf, "null"))
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("qemu-system-arm");
        let stdout = child.stdout.take().expect("stdout");
        // A firmware that never logs would block the read: stop QEMU after 60 s whatever.
        let pid = child.id().to_string();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_secs(60));
            let _ = Command::new("kill").args(["-9", &pid]).status();
        });
        let mut lines = Vec::new();
        let result = defmt_log::decode(&table, stdout, |line| {
            lines.push(line);
            lines.len() < 2
        });
        let _ = child.kill();
        let _ = child.wait();
        result.expect("decode");
        assert_eq!(lines.len(), 2, "QEMU ended before two log lines: {lines:?}");
        // Each line: the time since start-up (seconds, µs resolution, from the monotonic),
        // the level, the message.
        let split = |line: &str| -> (f64, String) {
            let (time, rest) = line.split_once(' ').unwrap_or_else(|| panic!("{lines:?}"));
            let time = time
                .parse()
                .unwrap_or_else(|_| panic!("no timestamp: {lines:?}"));
            (time, rest.to_string())
        };
        let (t0, first) = split(&lines[0]);
        let (t1, second) = split(&lines[1]);
        assert!(
            first.starts_with("INFO twil firmware up: static RAM "),
            "{lines:?}"
        );
        // The calibration runs after the first line, and takes 1 ms of virtual time.
        assert!(t0 < t1 && t1 < 1.0, "{lines:?}");
        let measured: u64 = second
            .strip_prefix("INFO calibration: 1000002 instructions measured as ")
            .and_then(|n| n.trim().parse().ok())
            .unwrap_or_else(|| panic!("{lines:?}"));
        assert!(measured.abs_diff(1_000_002) < 1_000, "{measured}");
    }
}

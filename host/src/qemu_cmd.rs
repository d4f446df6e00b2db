//! The one QEMU command line for the firmware, shared by `twil --remote qemu` and
//! `cargo xtask qemu` (xtask compiles this file with `#[path]`, so it depends on `std` only).
//!
//! `netduinoplus2` is QEMU's STM32F405 board. `-icount shift=0,sleep=off` makes one instruction
//! take exactly 1 ns of virtual time (so SysTick counts instructions) and lets QEMU run ahead of
//! real time when the core sleeps. Semihosting carries the firmware's log lines to QEMU's stdout.

use std::path::Path;

/// File name of the QEMU build of the firmware (next to the hardware ELF).
pub const QEMU_ELF_NAME: &str = "twil-firmware-qemu";

/// The `qemu-system-arm` arguments that run `elf` with USART1 on `serial` (a QEMU chardev
/// spec, e.g. `tcp:127.0.0.1:4444,server=on,wait=on,nodelay=on`), one instruction per
/// nanosecond (`-icount shift=0`: SysTick counts instructions).
pub fn qemu_args(elf: &Path, serial: &str) -> Vec<String> {
    qemu_args_paced(elf, serial, 0)
}

/// [`qemu_args`] at `-icount shift=SHIFT`: one instruction per 2^SHIFT ns of virtual time.
/// Missions run at shift 3 (8 ns, 125 M instructions per second: no faster than the 168 MHz
/// chip), so a deadline met under QEMU is met on the board.
pub fn qemu_args_paced(elf: &Path, serial: &str, shift: u8) -> Vec<String> {
    let icount = format!("shift={shift},sleep=off");
    [
        "-machine",
        "netduinoplus2",
        "-display",
        "none",
        "-monitor",
        "none",
        "-serial",
        serial,
        "-semihosting-config",
        "enable=on,target=native",
        "-icount",
        &icount,
        "-kernel",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([elf.display().to_string()])
    .collect()
}

/// The chardev spec of a TCP server on localhost `port` that waits for its client, so that no
/// byte the firmware sends at boot is lost.
pub fn tcp_server_serial(port: u16) -> String {
    format!("tcp:127.0.0.1:{port},server=on,wait=on,nodelay=on")
}

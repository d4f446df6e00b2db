//! Put the repository's `memory.x` (STM32F405RG) on the linker's search path, and add `ccm.x`:
//! a `.ccmram` output section in the 64 KiB core-coupled memory (CCMRAM of `memory.x`), loaded
//! from flash like `.data` (the firmware copies it at start-up, see `main.rs`).
//!
//! QEMU 7.2's `netduinoplus2` does not map the CCM but maps 192 KiB of SRAM at 0x2000_0000, so the
//! `qemu` build places the same section at 0x2002_0000 (above the 128 KiB of the real chip):
//! both builds have the same layout and sizes, only the CCM's base address differs.
use std::{env, fs, path::PathBuf};

const CCM_X: &str =
    "/* Statics placed with #[link_section = \".ccmram.NAME\"] live in the CCM. Their initial
   values are stored in flash after .data and copied by the firmware's init, before use. */
SECTIONS
{
  .ccmram : ALIGN(4)
  {
    __sccmram = .;
    *(.ccmram .ccmram.*);
    . = ALIGN(4);
    __eccmram = .;
  } > @CCM@ AT > FLASH
  __siccmram = LOADADDR(.ccmram);
}
INSERT BEFORE .bss;
";

/// Where QEMU gets the CCM's contents: SRAM that the real chip lacks.
const QEMU_CCM_MEMORY: &str = "MEMORY { QEMU_CCMRAM : ORIGIN = 0x20020000, LENGTH = 64K }\n";

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").unwrap());
    let memory = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").unwrap()).join("../memory.x");
    fs::copy(&memory, out.join("memory.x")).unwrap();
    let ccm = if env::var_os("CARGO_FEATURE_QEMU").is_some() {
        format!("{QEMU_CCM_MEMORY}{}", CCM_X.replace("@CCM@", "QEMU_CCMRAM"))
    } else {
        CCM_X.replace("@CCM@", "CCMRAM")
    };
    fs::write(out.join("ccm.x"), ccm).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tccm.x");
    println!("cargo:rustc-link-arg-tests=-Tccm.x");
    println!("cargo:rerun-if-changed={}", memory.display());
    println!("cargo:rerun-if-changed=build.rs");
}

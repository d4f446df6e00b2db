//! Where the firmware's memory is, as the linker placed it, and what only the chip can tell:
//! the CCM's start-up copy, the static SRAM figure and the stack's high-water mark.
//!
//! Layout (`memory.x`, cortex-m-rt's `link.x`, `ccm.x` from `build.rs`, and flip-link):
//!
//! ```text
//! SRAM 0x2000_0000 ┌──────────────┐ _stack_end: the stack's bottom; an overflow faults here
//!                  │ stack  ↓     │ (flip-link put it below the statics)
//!                  ├──────────────┤ _stack_start: initial SP = __sdata
//!                  │ .data .bss   │
//!                  │ .uninit      │ __euninit (≤ 0x2002_0000)
//! CCM  0x1000_0000 │ .ccmram      │ (QEMU: 0x2002_0000, see build.rs)
//! ```
//!
//! cortex-m-rt's `paint-stack` feature fills [`_stack_end`, `_stack_start`) with
//! [`STACK_PAINT`] at reset, before `.data` is copied and before any Rust code runs; the
//! high-water mark is the lowest word that no longer holds the paint.

use core::ops::Range;
use core::sync::atomic::{AtomicBool, Ordering};

/// The word cortex-m-rt paints the stack with at reset (and [`paint_stack`] with later).
pub const STACK_PAINT: u32 = cortex_m_rt::STACK_PAINT_VALUE;

/// Bytes below the stack pointer that [`paint_stack`] leaves alone (its own calls, and an
/// interrupt's frame that may be stacked while it runs).
const PAINT_MARGIN: usize = 256;

extern "C" {
    static mut __sccmram: u32;
    static mut __eccmram: u32;
    static __siccmram: u32;
    static __sdata: u32;
    static __euninit: u32;
    static _stack_start: u32;
    static _stack_end: u32;
}

/// The address of a linker symbol (never its contents).
macro_rules! symbol {
    ($name:ident) => {
        // Only the address of the extern static is taken (safe since Rust 1.82), never read.
        // `black_box`: the compiler takes two distinct statics to have distinct addresses and
        // would fold `_stack_start == __sdata` to false; linker symbols may coincide.
        core::hint::black_box(core::ptr::addr_of!($name) as usize)
    };
}

/// Addresses of `.ccmram` (the CCM on the chip, 0x2002_0000… under QEMU).
pub fn ccm_range() -> Range<usize> {
    symbol!(__sccmram)..symbol!(__eccmram)
}

/// Addresses of the statically allocated SRAM: `.data`, `.bss`, `.uninit`.
pub fn static_ram_range() -> Range<usize> {
    symbol!(__sdata)..symbol!(__euninit)
}

/// Statically allocated SRAM (`.data` + `.bss` + `.uninit`, not the CCM and not the stack),
/// bytes: what the 112 KiB budget is about.
pub fn static_ram_bytes() -> u32 {
    let r = static_ram_range();
    (r.end - r.start) as u32
}

/// Addresses of the stack: from its bottom (`_stack_end`, where an overflow faults) to its top
/// (`_stack_start`, the initial stack pointer).
pub fn stack_range() -> Range<usize> {
    symbol!(_stack_end)..symbol!(_stack_start)
}

/// Bytes of stack.
pub fn stack_bytes() -> u32 {
    let r = stack_range();
    (r.end - r.start) as u32
}

/// The most stack used since the last paint (at reset, or [`paint_stack`]), bytes: from the
/// top down to the lowest word that lost the paint.
pub fn stack_high_water_bytes() -> u32 {
    let r = stack_range();
    let mut addr = r.start;
    while addr < r.end {
        // SAFETY: `addr` is a word-aligned address inside the stack (the linker script asserts
        // both ends are 4-aligned), which is RAM and always readable. The words below the
        // high-water mark belong to no Rust object; the first word that lost the paint may
        // belong to a live frame, and a volatile word read of it races with nothing (one core,
        // interrupts only push and pop below the current stack pointer).
        let word = unsafe { (addr as *const u32).read_volatile() };
        if word != STACK_PAINT {
            break;
        }
        addr += 4;
    }
    (r.end - addr) as u32
}

/// Paint the free stack again: every word from the bottom up to [`PAINT_MARGIN`] bytes below
/// the current stack pointer. After it, [`stack_high_water_bytes`] measures from here on.
pub fn paint_stack() {
    let sp = cortex_m::register::msp::read() as usize;
    let bottom = stack_range().start;
    let top = sp.saturating_sub(PAINT_MARGIN) & !3;
    let mut addr = bottom;
    while addr < top {
        // SAFETY: `addr` is word-aligned, inside the stack and more than `PAINT_MARGIN` bytes
        // below the stack pointer of this function, so no frame lives there: no Rust object
        // is overwritten. An interrupt that preempts this loop stacks its frame below the
        // stack pointer and is gone before the loop resumes (one core); its words then lose
        // the paint or get it back, both harmless.
        unsafe { (addr as *mut u32).write_volatile(STACK_PAINT) };
        addr += 4;
    }
}

/// Set when [`copy_ccm`] starts (so it copies once).
static CCM_COPY_STARTED: AtomicBool = AtomicBool::new(false);
/// Set when [`copy_ccm`] has copied: the `.ccmram` statics hold their initial values.
static CCM_COPIED: AtomicBool = AtomicBool::new(false);

/// Whether [`copy_ccm`] has run.
pub fn ccm_copied() -> bool {
    CCM_COPIED.load(Ordering::Acquire)
}

/// Copy the initial values of `.ccmram` from flash (the start-up code copies only `.data`);
/// `true` the first time, `false` (and nothing copied) afterwards.
///
/// # Safety
///
/// No `.ccmram` static may have been read or referenced before the first call (its memory is
/// overwritten). `.ccmram` statics must be `static mut` or interior-mutable (a plain `static`
/// could be read from its initializer by the compiler, never from the CCM).
pub unsafe fn copy_ccm() -> bool {
    if CCM_COPY_STARTED.swap(true, Ordering::AcqRel) {
        return false;
    }
    let r = ccm_range();
    // SAFETY: runs once (the flag above), before any use of the statics (the caller's
    // contract). `ccm.x` makes [__sccmram, __eccmram) a word-aligned part of the CCM (QEMU:
    // SRAM above the chip's) that only `.ccmram` statics occupy, and __siccmram its image in
    // flash, of the same length; the two do not overlap.
    unsafe {
        core::ptr::copy_nonoverlapping(
            core::ptr::addr_of!(__siccmram),
            core::ptr::addr_of_mut!(__sccmram),
            (r.end - r.start) / 4,
        );
    }
    CCM_COPIED.store(true, Ordering::Release);
    true
}

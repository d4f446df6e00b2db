//! On-target tests: what only the chip (here QEMU's `netduinoplus2`) shows. Memory placement,
//! the CCM's start-up copy and stack painting, checked on the firmware's own code
//! (`twil_firmware::memory`) with the firmware's linker scripts (`memory.x`, `ccm.x`, flip-link).
//!
//! `cargo xtask test` builds this with the `qemu` feature and runs it under QEMU; defmt-test
//! logs each test (defmt over semihosting, decoded by xtask) and ends with a semihosting exit:
//! 0 when every test passed; a failed test panics, `panic-probe` raises a HardFault and the
//! handler below exits with 1. Run alone: `cargo xtask on-target`.
#![no_std]
#![no_main]

use defmt_semihosting as _;
use panic_probe as _;
// The interrupt vector table (the PAC, through the HAL).
use stm32f4xx_hal as _;

/// A failed test ends in a HardFault (panic-probe's `udf`): make QEMU exit with an error
/// instead of spinning (the knurling app-template does the same).
#[cortex_m_rt::exception]
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    semihosting::process::exit(1)
}

/// Use about `bytes` of stack below the caller's frame.
#[inline(never)]
fn use_stack(bytes: usize) -> u32 {
    let mut buffer = [0u8; 2048];
    let n = bytes.min(buffer.len());
    for (i, b) in buffer[..n].iter_mut().enumerate() {
        // Volatile, so that the buffer is really written.
        // SAFETY: `b` is a valid, aligned `&mut u8`.
        unsafe { core::ptr::write_volatile(b, i as u8) };
    }
    buffer[..n].iter().map(|&b| b as u32).sum()
}

#[defmt_test::tests]
mod tests {
    use core::sync::atomic::{AtomicU32, Ordering};
    use defmt::{assert, assert_eq};
    use twil_firmware::memory;

    use super::use_stack;

    /// Where `.ccmram` is: the CCM (0x1000_0000, 64 KiB) on the chip, 0x2002_0000 under QEMU
    /// (which does not map the CCM), see `build.rs`.
    const CCM: core::ops::Range<usize> = 0x2002_0000..0x2003_0000;
    /// SRAM of the STM32F405 (`memory.x`).
    const SRAM: core::ops::Range<usize> = 0x2000_0000..0x2002_0000;

    /// A CCM static with a nonzero initial value: it only holds it after `copy_ccm`.
    #[link_section = ".ccmram.on_target"]
    static CCM_WORD: AtomicU32 = AtomicU32::new(0x7E57_C0DE);
    /// An SRAM static (`.data`, copied by cortex-m-rt), for the layout checks.
    static DATA_WORD: AtomicU32 = AtomicU32::new(0x0DA7_A000);

    #[init]
    fn init() {
        // SAFETY: no reference to a `.ccmram` static exists yet (the tests below take them
        // after this), and this is the only call.
        assert!(unsafe { memory::copy_ccm() });
    }

    #[test]
    fn ccm_statics_are_in_the_ccm() {
        let ccm = memory::ccm_range();
        assert!(CCM.start <= ccm.start && ccm.end <= CCM.end);
        let addr = core::ptr::addr_of!(CCM_WORD) as usize;
        assert!(
            ccm.contains(&addr),
            "{=usize:#x} not in the CCM section",
            addr
        );
        // The firmware's own CCM statics: the mission, the two queues, the real world.
        let statics = twil_firmware::take_ccm_statics().unwrap();
        let mission = statics.mission as *const _ as usize;
        let queue = statics.rx_queue as *const _ as usize;
        let tx_queue = statics.tx_queue as *const _ as usize;
        let world = statics.world as *const _ as usize;
        assert!(
            ccm.contains(&mission)
                && ccm.contains(&queue)
                && ccm.contains(&tx_queue)
                && ccm.contains(&world)
        );
        assert!(twil_firmware::take_ccm_statics().is_none());
    }

    #[test]
    fn the_ccm_start_up_copy_gives_initial_values() {
        assert_eq!(CCM_WORD.load(Ordering::Relaxed), 0x7E57_C0DE);
        // And a second copy is refused (it would overwrite live statics).
        // SAFETY: it copies nothing (the first call happened in `init`).
        assert!(!unsafe { memory::copy_ccm() });
        CCM_WORD.store(1, Ordering::Relaxed);
        assert_eq!(CCM_WORD.load(Ordering::Relaxed), 1);
    }

    #[test]
    fn the_stack_is_below_the_statics() {
        let stack = memory::stack_range();
        let statics = memory::static_ram_range();
        // flip-link: the stack grows down from the statics towards the start of SRAM, so an
        // overflow runs off SRAM (a HardFault) instead of into `.bss` / `.data`.
        assert_eq!(stack.start, SRAM.start);
        assert_eq!(stack.end, statics.start);
        assert!(statics.end <= SRAM.end);
        let data = core::ptr::addr_of!(DATA_WORD) as usize;
        assert!(statics.contains(&data));
        assert_eq!(DATA_WORD.load(Ordering::Relaxed), 0x0DA7_A000);
        let sp = cortex_m::register::msp::read() as usize;
        assert!(stack.contains(&sp));
        assert_eq!(
            memory::static_ram_bytes() as usize,
            statics.end - statics.start
        );
        assert!(memory::stack_bytes() >= 4096);
    }

    #[test]
    fn painting_measures_the_stack_high_water_mark() {
        let stack = memory::stack_range();
        memory::paint_stack();
        let before = memory::stack_high_water_bytes();
        let sp = cortex_m::register::msp::read() as usize;
        // Everything above the stack pointer is in use; the paint ends a little below it.
        assert!(before as usize >= stack.end - sp);
        assert!((before as usize) < stack.end - sp + 1024);
        // Painted words remain from the bottom up to the mark.
        let mark = stack.end - before as usize;
        let mut addr = stack.start;
        while addr < mark {
            // SAFETY: a word-aligned address in the stack, below the stack pointer.
            let word = unsafe { (addr as *const u32).read_volatile() };
            assert_eq!(word, memory::STACK_PAINT);
            addr += 4;
        }
        // Using 2 KiB more stack moves the mark down by about that much (less the margin that
        // `paint_stack` leaves below its own frame).
        let sum = use_stack(2048);
        assert_eq!(sum, (0..2048u32).map(|i| i % 256).sum::<u32>());
        let after = memory::stack_high_water_bytes();
        let grown = after.saturating_sub(before);
        assert!((1536..2560).contains(&grown), "{} -> {}", before, after);
        // Painting again from here forgets the deeper use.
        memory::paint_stack();
        assert!(memory::stack_high_water_bytes() < after);
    }

    /// The parameter store (`twil_core::params_store`) on the Cortex-M4, over the QEMU build's
    /// RAM flash: values round trip, and the stack a save takes (its `sequential-storage`
    /// futures are polled once, on the caller's stack) is printed and stays under 3 KiB.
    #[test]
    fn the_parameter_store_round_trips_on_the_chip() {
        use twil_core::params_store::ram_flash::RamFlash;
        use twil_core::params_store::{ParamId, ParamStore, StoreStatus};
        let mut flash = RamFlash::<2048, 1024>::ERASED;
        let (a, b) = (
            ParamId::of_name("wheel_radius_m"),
            ParamId::of_name("half_axle_m"),
        );
        memory::paint_stack();
        let before = memory::stack_high_water_bytes();
        let mut store = ParamStore::new(&mut flash, 0..2048).unwrap();
        let mut values = [None; 2];
        assert_eq!(store.load(&[a, b], &mut values).status, StoreStatus::Empty);
        store.save(a, 0.05).unwrap();
        store.save(b, 0.2).unwrap();
        store.save(a, 0.06).unwrap();
        let grown = memory::stack_high_water_bytes().saturating_sub(before);
        defmt::println!(
            "parameter store: load and 3 saves took {} B of stack",
            grown
        );
        assert!(grown < 3072, "{}", grown);
        let mut store = ParamStore::new(store.into_flash(), 0..2048).unwrap();
        let report = store.load(&[a, b], &mut values);
        assert_eq!(report.status, StoreStatus::Ok);
        assert!(values == [Some(0.06), Some(0.2)]);
    }
}

//! Where the parameter store lives (`twil_core::params_store`), and its boot: load it, apply
//! the values to the robot's config through the core's validation, say what was found.
//!
//! - Board: the STM32F405's flash sectors 10 and 11 (128 KiB each, 0x080C_0000..0x0810_0000,
//!   RM0090, "Embedded Flash memory", its sector table), taken from the program by `memory.x`
//!   (FLASH 768K). `stm32f4xx-hal`'s `LockedFlash` reads them; each write or erase unlocks the
//!   flash for its own duration (`UnlockedFlash`, locked again when dropped). Programming is
//!   byte-wide (PSIZE x8, what the HAL sets): 16 µs a byte typical (DS8626, table "Flash
//!   memory programming"), so a record of 16 bytes takes about
//!   0.3 ms. Erasing a 128 KiB sector at x8 takes 2 s typical, 4 s at most, and the core stalls
//!   the whole time (it fetches its code from the same bank): no interrupt runs and the
//!   watchdog cannot be fed. The store erases only when a page is full (after about 8 190
//!   saves), on `ParamStore::erase`, on the first save over a store that is not `Ok`, or when
//!   it repairs an erase cut by a power loss. The boot's load runs in `init`, before the
//!   independent watchdog starts, and formats a store that is not `Ok` (see [`boot`]). A
//!   `ParamSet` (refused while a mission runs) then writes one record. The erase that
//!   `sequential-storage` makes when a page fills (after about 8 190 saves) stalls the core
//!   for seconds: every erase runs with the watchdog's window widened to 32.8 s and put back
//!   after (`with_wide_watchdog`), so the 150 ms watchdog does not reset the chip in the
//!   middle of it. (An erase cut by a power loss is repaired at the next boot: the power-loss
//!   tests cover it.) Not run here: QEMU has neither the flash writes nor the IWDG.
//! - QEMU: QEMU 7.2's `netduinoplus2` does not emulate flash programming or erasing, so the
//!   QEMU build keeps the store in a 2 KiB [`RamFlash`] in SRAM (two 1 KiB pages: 63 records
//!   each), erased at every reset: it always boots `Empty`, on the defaults. Above the flash,
//!   the code is the same.

use twil_core::params_store::robot::{load_robot_config, BootParams};
use twil_core::params_store::{ParamStore, StoreStatus};
use twil_core::robot::RobotConfig;

#[cfg(feature = "qemu")]
use twil_core::params_store::ram_flash::RamFlash;

/// The QEMU build's store: two pages of 1 KiB in SRAM.
#[cfg(feature = "qemu")]
pub type StoreFlash = RamFlash<2048, 1024>;

/// The QEMU build's store range: the whole RAM flash.
#[cfg(feature = "qemu")]
pub const STORE_RANGE: core::ops::Range<u32> = 0..2048;

/// The board's store: the chip's flash.
#[cfg(feature = "hardware")]
pub use board_flash::BoardFlash as StoreFlash;

/// The board's store range, offsets from the flash's start (0x0800_0000): sectors 10 and 11.
#[cfg(feature = "hardware")]
pub const STORE_RANGE: core::ops::Range<u32> = 0x000C_0000..0x0010_0000;

#[cfg(feature = "hardware")]
mod board_flash {
    use embedded_storage::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
    use stm32f4xx_hal::flash::{Error, FlashExt, LockedFlash};
    use stm32f4xx_hal::pac::FLASH;

    /// The chip's flash, locked except during each write or erase.
    pub struct BoardFlash(LockedFlash);

    impl BoardFlash {
        /// The flash peripheral (`rcc` sets its wait states through the register block, so
        /// taking the peripheral here changes nothing there).
        pub fn new(flash: FLASH) -> Self {
            Self(LockedFlash::new(flash))
        }
    }

    impl ErrorType for BoardFlash {
        type Error = Error;
    }

    impl ReadNorFlash for BoardFlash {
        const READ_SIZE: usize = 1;

        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Error> {
            ReadNorFlash::read(&mut self.0, offset, bytes)
        }

        fn capacity(&self) -> usize {
            ReadNorFlash::capacity(&self.0)
        }
    }

    impl NorFlash for BoardFlash {
        const WRITE_SIZE: usize = 1;
        // The HAL's erase unit: 128 KiB, the size of sectors 5 to 11.
        const ERASE_SIZE: usize = 128 * 1024;

        fn erase(&mut self, from: u32, to: u32) -> Result<(), Error> {
            super::with_wide_watchdog(|| NorFlash::erase(&mut self.0.unlocked(), from, to))
        }

        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Error> {
            NorFlash::write(&mut self.0.unlocked(), offset, bytes)
        }
    }
}

/// Run `erase` with the independent watchdog's window widened to its longest, 32.8 s (LSI
/// / 256, reload 4095), then put the window back as it was, restarted. An erase stalls the
/// core for up to 4 s per 128 KiB sector (nothing runs, nothing feeds the watchdog); the LSI
/// and the watchdog count on. Before `init` starts the watchdog (the boot's format) this
/// changes nothing that matters: the values written are the ones `start` overwrites.
#[cfg(feature = "hardware")]
fn with_wide_watchdog<R>(erase: impl FnOnce() -> R) -> R {
    use stm32f4xx_hal::pac::IWDG;
    // SAFETY: the IWDG's registers, owned by the control task's `IndependentWatchdog`, which
    // only writes the key register (a feed). The changes below are made with interrupts off,
    // so no feed falls between the unlock key and the writes it unlocks (any other key would
    // lock them again); a feed after them only restarts the count.
    let iwdg = unsafe { &*IWDG::ptr() };
    // A prescaler or reload update takes up to 5 LSI periods (RM0090, IWDG_SR): wait for it,
    // bounded (about 2 ms at 168 MHz, ten times the need).
    let settled = || {
        for _ in 0..100_000 {
            let sr = iwdg.sr().read();
            if !sr.pvu().bit() && !sr.rvu().bit() {
                return;
            }
        }
    };
    settled();
    let prescaler = iwdg.pr().read().pr().variant();
    let reload = iwdg.rlr().read().rl().bits();
    cortex_m::interrupt::free(|_| {
        iwdg.kr().write(|w| w.key().unlock());
        iwdg.pr().write(|w| w.pr().divide_by256());
        iwdg.rlr().write(|w| w.rl().set(0xFFF));
    });
    settled();
    // The count restarts from the new reload only once it is in effect.
    iwdg.kr().write(|w| w.key().feed());
    let result = erase();
    settled();
    cortex_m::interrupt::free(|_| {
        iwdg.kr().write(|w| w.key().unlock());
        iwdg.pr().write(|w| w.pr().variant(prescaler));
        iwdg.rlr().write(|w| w.rl().set(reload));
    });
    settled();
    iwdg.kr().write(|w| w.key().feed());
    result
}

/// The store the device writes `ParamSet`'s values to.
#[cfg(feature = "qemu")]
pub type Store = ParamStore<&'static mut StoreFlash>;
/// The store the device writes `ParamSet`'s values to.
#[cfg(feature = "hardware")]
pub type Store = ParamStore<StoreFlash>;

/// Load the store in `flash` and apply it to the defaults: the config to run, what was found,
/// and the store for `ParamSet` (`None` when it cannot even be opened: a wrong range, a
/// defect; then the defaults and `Corrupt`).
///
/// On the board, a store that is not `Ok` is formatted here (erased, the format word
/// written), before the watchdog starts: the first `ParamSet` then writes one record (0.3 ms)
/// instead of erasing two sectors (up to 8 s, which the 150 ms watchdog would cut). What was
/// found is still reported (`Empty`, `Corrupt`, `OldVersion`) for this boot; the values were
/// the defaults' anyway. It costs up to 8 s at the first boot of a blank chip, once.
pub fn boot<F: embedded_storage::nor_flash::NorFlash>(
    flash: F,
) -> (RobotConfig, BootParams, Option<ParamStore<F>>) {
    match ParamStore::new(flash, STORE_RANGE) {
        Ok(mut store) => {
            let (config, boot) = load_robot_config(&mut store, &RobotConfig::DEFAULT);
            if cfg!(feature = "hardware") && boot.load.status != StoreStatus::Ok {
                // A failure leaves the status unknown: the first save tries again.
                let _ = store.format();
            }
            (config, boot, Some(store))
        }
        Err(_) => (
            RobotConfig::DEFAULT,
            BootParams {
                load: twil_core::params_store::LoadReport {
                    status: StoreStatus::Corrupt,
                    found: 0,
                    unknown: 0,
                    records: 0,
                    format_word: None,
                },
                applied: 0,
                refused: 0,
                first_refused: None,
            },
            None,
        ),
    }
}

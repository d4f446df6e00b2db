//! The chip-level parts of the Twil firmware that the program (`src/main.rs`) and the on-target
//! tests (`tests/on_target.rs`) share: where the linker put memory ([`memory`]: the CCM's
//! start-up copy, static SRAM, the painted stack) and the statics that live in the CCM.
#![no_std]
#![deny(missing_docs)]

pub mod memory;

use core::sync::atomic::{AtomicBool, Ordering};

use heapless::spsc::Queue;
use twil_core::link::{Build, DeviceInfo};

/// Bytes of the receive queue (holds one less).
pub const RX_QUEUE_BYTES: usize = 1024;

/// The device: grid (400 x 400 cells), obstacles, last path, framing.
pub type TwilDevice = twil_core::link::mcu::McuDevice;

/// The receive queue, in the CCM (SRAM is the planner's). Only reached through
/// [`take_ccm_statics`], after the CCM's start-up copy.
#[link_section = ".ccmram.rx_queue"]
static mut RX_QUEUE: Queue<u8, RX_QUEUE_BYTES> = Queue::new();

/// The device in the CCM. Only reached through [`take_ccm_statics`], after the copy.
#[link_section = ".ccmram.device"]
static mut DEVICE: TwilDevice = TwilDevice::new(DeviceInfo::for_build(Build::Hardware));

/// The device and the receive queue, once [`memory::copy_ccm`] has given them their initial
/// values: `None` before that, and after the first call.
pub fn take_ccm_statics() -> Option<(
    &'static mut TwilDevice,
    &'static mut Queue<u8, RX_QUEUE_BYTES>,
)> {
    static TAKEN: AtomicBool = AtomicBool::new(false);
    if !memory::ccm_copied() || TAKEN.swap(true, Ordering::AcqRel) {
        return None;
    }
    // SAFETY: the flag hands the two statics out once, so these are the only references to
    // them; the CCM copy has run (checked above), so they hold their initial values.
    unsafe {
        Some((
            &mut *core::ptr::addr_of_mut!(DEVICE),
            &mut *core::ptr::addr_of_mut!(RX_QUEUE),
        ))
    }
}

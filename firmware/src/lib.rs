//! The chip-level parts of the Twil firmware that the program (`src/main.rs`) and the on-target
//! tests (`tests/on_target.rs`) share: where the linker put memory ([`memory`]: the CCM's
//! start-up copy, static SRAM, the painted stack) and the statics that live in the CCM (the
//! mission, the receive and transmit queues and, under QEMU, the real world).
#![no_std]
#![deny(missing_docs)]

pub mod memory;

use core::sync::atomic::{AtomicBool, Ordering};

use heapless::spsc::Queue;
#[cfg(feature = "qemu")]
use twil_core::link::WorldUpload;

/// Bytes of the receive queue (holds one less).
pub const RX_QUEUE_BYTES: usize = 1024;

/// Bytes of the transmit queue (holds one less): four of the link's largest frames
/// (`MAX_FRAME_BYTES` = 512), 178 ms of 115 200 baud. The mission task queues a frame only
/// when the whole frame fits and pulls telemetry only while a largest frame fits
/// (backpressure: telemetry waits, it is never cut); the USART1 interrupt sends it.
pub const TX_QUEUE_BYTES: usize = 2048;

/// The device: the planning service and the mission requests (in SRAM).
pub type TwilDevice = twil_core::link::mcu::McuRobotDevice;
/// The mission: its 300 x 300 map (also the planning service's), the seen space, the paths.
pub type TwilMission = twil_core::link::mcu::McuMission;

/// The receive queue, in the CCM. Only reached through [`take_ccm_statics`], after the CCM's
/// start-up copy.
#[link_section = ".ccmram.rx_queue"]
static mut RX_QUEUE: Queue<u8, RX_QUEUE_BYTES> = Queue::new();

/// The transmit queue, in the CCM (the USART1 interrupt empties it byte by byte; a DMA
/// transmit would need it in SRAM: the DMA controllers do not reach the CCM). Only reached
/// through [`take_ccm_statics`], after the CCM's start-up copy.
#[link_section = ".ccmram.tx_queue"]
static mut TX_QUEUE: Queue<u8, TX_QUEUE_BYTES> = Queue::new();

/// The mission in the CCM (50 KB: the SRAM holds the planner). Only reached through
/// [`take_ccm_statics`], after the copy.
#[link_section = ".ccmram.mission"]
static mut MISSION: TwilMission = TwilMission::IDLE;

/// The real world the QEMU build's simulated sonar sees (uploaded with `WorldChunk`).
#[cfg(feature = "qemu")]
#[link_section = ".ccmram.world"]
static mut WORLD: WorldUpload = WorldUpload::new();

/// The statics that live in the CCM.
pub struct CcmStatics {
    /// The mission.
    pub mission: &'static mut TwilMission,
    /// The receive queue.
    pub rx_queue: &'static mut Queue<u8, RX_QUEUE_BYTES>,
    /// The transmit queue.
    pub tx_queue: &'static mut Queue<u8, TX_QUEUE_BYTES>,
    /// The real world (QEMU build).
    #[cfg(feature = "qemu")]
    pub world: &'static mut WorldUpload,
}

/// The CCM statics, once [`memory::copy_ccm`] has given them their initial values: `None`
/// before that, and after the first call.
pub fn take_ccm_statics() -> Option<CcmStatics> {
    static TAKEN: AtomicBool = AtomicBool::new(false);
    if !memory::ccm_copied() || TAKEN.swap(true, Ordering::AcqRel) {
        return None;
    }
    // SAFETY: the flag hands the statics out once, so these are the only references to them;
    // the CCM copy has run (checked above), so they hold their initial values.
    unsafe {
        Some(CcmStatics {
            mission: &mut *core::ptr::addr_of_mut!(MISSION),
            rx_queue: &mut *core::ptr::addr_of_mut!(RX_QUEUE),
            tx_queue: &mut *core::ptr::addr_of_mut!(TX_QUEUE),
            #[cfg(feature = "qemu")]
            world: &mut *core::ptr::addr_of_mut!(WORLD),
        })
    }
}

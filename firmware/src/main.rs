//! Twil firmware for the STM32F405: the link to the host on USART1 and the planner, on RTIC 2.
//!
//! All logic is in `twil-core`: this program owns a [`twil_core::link::Device`] (grid,
//! obstacles, last path, framing) and a [`twil_core::plan::Planner`] in static memory and moves
//! bytes between them and USART1.
//!
//! ## Memory
//!
//! - SRAM, top (`.data`, `.bss`, `.uninit`): the planner (4-bit scratch for 400 x 400 cells, a
//!   [`QUEUE`]-entry open list, its path buffer), RTIC's state. Its size is what
//!   `static_ram_bytes` reports and what the 112 KiB budget is about.
//! - SRAM, bottom: the stack, below the statics (flip-link), so an overflow faults. Painted at
//!   reset; its high-water mark is logged (see [`memory`]).
//! - CCM (64 KiB at 0x1000_0000, `.ccmram`, see `build.rs`): the [`TwilDevice`] (the 400 x 400
//!   grid, the obstacles, the last path, the frame decoder) and the receive queue. Their initial
//!   values are stored in flash and copied by `init` before anything reads them.
//!
//! ## Tasks (highest priority first)
//!
//! | task       | binds    | prio | does                                                        |
//! |------------|----------|------|-------------------------------------------------------------|
//! | `SysTick`  | SysTick  | -    | [`Mono`]'s tick (1 kHz, from `rtic-monotonics`): time, delays |
//! | `usart1_rx`| USART1   | 2    | moves every received byte into the RX queue (never blocks)   |
//! | `idle`     | -        | 0    | drains the queue into the `Device`, plans, writes replies    |
//!
//! The receive interrupt preempts everything that is slow (planning, writing replies), so no
//! byte is lost at full rate: at 115200 baud a byte arrives every 87 µs and the interrupt needs
//! well under 1 µs. The queue holds [`RX_QUEUE_BYTES`] - 1 bytes, several frames; bytes that do
//! not fit are counted (`rx_dropped_bytes` in the `Status` reply), never silently lost.
//!
//! ## Builds
//!
//! - default (`hardware`): PLL at 168 MHz from the HSI, defmt over RTT, `panic-probe`.
//! - `--no-default-features --features qemu`: for QEMU's `netduinoplus2`; QEMU does not emulate
//!   the RCC, so the clock stays on the HSI and nothing waits on a ready flag; defmt logs go
//!   out over semihosting (decoded by `cargo xtask qemu`), panics as text over semihosting.
#![no_std]
#![no_main]

#[cfg(all(feature = "qemu", feature = "hardware"))]
compile_error!("features `hardware` and `qemu` exclude each other: build QEMU with --no-default-features --features qemu");
#[cfg(not(any(feature = "qemu", feature = "hardware")))]
compile_error!("choose a build: feature `hardware` (default) or `qemu`");

#[cfg(feature = "hardware")]
use defmt_rtt as _;
#[cfg(feature = "qemu")]
use defmt_semihosting as _;
#[cfg(feature = "hardware")]
use panic_probe as _;
#[cfg(feature = "qemu")]
use panic_semihosting as _;

// Wired into the app by the mission firmware; until then only its build is checked.
#[cfg(feature = "hardware")]
#[allow(dead_code)]
mod board;

use core::sync::atomic::{AtomicU32, Ordering};

use twil_core::link::{Build, PROTOCOL_VERSION};
pub use twil_firmware::{memory, TwilDevice, RX_QUEUE_BYTES};

/// Log a line with defmt: over RTT on a board (probe-rs prints it), over semihosting under QEMU
/// (`cargo xtask qemu` decodes it with the ELF's defmt table).
macro_rules! log {
    ($($arg:tt)*) => {{
        defmt::info!($($arg)*);
    }};
}

/// Planner open-list capacity, entries (`twil_core::link::mcu`, shared with the host).
pub const QUEUE: usize = twil_core::link::mcu::PLANNER_QUEUE;
/// The planner (scratch for 400 x 400 cells, [`QUEUE`] open-list entries).
pub type TwilPlanner = twil_core::link::mcu::McuPlanner;

/// Rate of the monotonic [`Mono`], Hz: one SysTick interrupt per millisecond. At 168 MHz that
/// is one interrupt (about a hundred instructions) per 168 000 cycles, 0.06 % of the core; a
/// 5 M-instruction plan sees 5 of them. It is also the resolution of `Mono::delay`.
pub const MONO_HZ: u32 = 1_000;

// (A literal: the macro uses it both as SysTick's rate and as the tick type's rate.)
rtic_monotonics::systick_monotonic!(Mono, 1_000);

/// SysTick's input clock, Hz: the core clock on the board (PLL at 168 MHz); under QEMU 7.2 the
/// `netduinoplus2`'s SysTick counts at a fixed 168 MHz of virtual time whatever the RCC says
/// (the QEMU build runs on the 16 MHz HSI), so both builds start the monotonic with this value.
pub const SYSTICK_HZ: u32 = 168_000_000;
/// SysTick counts per monotonic tick: SysTick's reload is this minus one.
const SYSTICK_PER_MONO: u32 = SYSTICK_HZ / MONO_HZ;

/// Bytes dropped by the receive interrupt (queue full or a line error).
static RX_DROPPED: AtomicU32 = AtomicU32::new(0);

/// SysTick counts since [`Mono`] started: monotonic ticks × [`SYSTICK_PER_MONO`] + the count
/// down of the current period. Differences of two readings are elapsed SysTick counts (the
/// 32-bit tick count wraps after 2^32 ms, 49.7 days: a reading across that goes back to 0).
fn systick_counts() -> u64 {
    use rtic_monotonics::rtic_time::monotonic::TimerQueueBasedInstant;
    use rtic_monotonics::Timebase;
    loop {
        // `Mono::now()` counts a wrap (SysTick's COUNTFLAG, set on the 1 -> 0 step) whether or
        // not its interrupt has run yet, exactly once. A wrap between the two readings changes
        // the tick count: read again.
        let before = Mono::now().ticks();
        let value = cortex_m::peripheral::SYST::get_current();
        let after = Mono::now().ticks();
        if before != after {
            continue;
        }
        // Counts into the period: 0 at the 1 -> 0 step (the wrap already counted), then
        // RELOAD, RELOAD - 1, ... are 1, 2, ... (a value above RELOAD, before start: 0).
        let into_period = if value == 0 || value >= SYSTICK_PER_MONO {
            0
        } else {
            SYSTICK_PER_MONO - value
        };
        return before as u64 * SYSTICK_PER_MONO as u64 + into_period as u64;
    }
}

// defmt log lines carry the time since start-up in microseconds (SysTick counts at 168 MHz on
// both builds; QEMU: virtual time, 1 ns per instruction while the core runs).
defmt::timestamp!(
    "{=u64:us}",
    systick_counts() / (SYSTICK_HZ / 1_000_000) as u64
);

/// Instructions (QEMU) or cycles (board) counted so far (see [`systick_counts`]).
///
/// QEMU's SysTick runs at 168 MHz of virtual time; with `-icount shift=0` one instruction takes
/// 1 ns, so instructions = counts × 1000 / 168. On a board at 168 MHz, counts are core cycles.
fn instructions() -> u64 {
    let t = systick_counts();
    if cfg!(feature = "qemu") {
        t * 1000 / 168
    } else {
        t
    }
}

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use super::*;
    use heapless::spsc::{Consumer, Producer};
    use stm32f4xx_hal::{
        pac::USART1,
        prelude::*,
        rcc,
        serial::{Config, Rx, Serial, Tx},
    };
    use twil_core::link::{DeviceFrame, Telemetry};

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        rx: Rx<USART1>,
        tx: Tx<USART1>,
        producer: Producer<'static, u8>,
        consumer: Consumer<'static, u8>,
        device: &'static mut TwilDevice,
        planner: &'static mut TwilPlanner,
    }

    #[init(local = [
        planner_memory: TwilPlanner = TwilPlanner::new(),
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        // QEMU: stay on the HSI (16 MHz), no PLL (its ready flag is never set under QEMU).
        #[cfg(feature = "qemu")]
        let mut rcc = cx.device.RCC.freeze(rcc::Config::hsi());
        #[cfg(feature = "hardware")]
        let mut rcc = cx.device.RCC.freeze(rcc::Config::hsi().sysclk(168.MHz()));

        let gpioa = cx.device.GPIOA.split(&mut rcc);
        let serial: Serial<USART1> = Serial::new(
            cx.device.USART1,
            (gpioa.pa9, gpioa.pa10),
            Config::default().baudrate(115_200.bps()),
            &mut rcc,
        )
        .unwrap_or_else(|_| panic!("115200 baud is reachable from any clock"));
        let (mut tx, mut rx) = serial.split();
        rx.listen();

        // The monotonic: SysTick at MONO_HZ, never paused (see SYSTICK_HZ for the clock).
        #[cfg(feature = "hardware")]
        assert_eq!(
            rcc.clocks.sysclk().raw(),
            SYSTICK_HZ,
            "SysTick runs from the core clock"
        );
        Mono::start(cx.core.SYST, SYSTICK_HZ);

        // SAFETY: the first thing that touches `.ccmram`: nothing has read or referenced a CCM
        // static yet (the device and the queue are handed out just below).
        unsafe { memory::copy_ccm() };
        let (device, rx_queue) =
            twil_firmware::take_ccm_statics().expect("init takes the CCM statics once");
        device.handler.set_build(if cfg!(feature = "qemu") {
            Build::Qemu
        } else {
            Build::Hardware
        });
        device
            .handler
            .set_static_ram_bytes(memory::static_ram_bytes());
        device.send_frame(
            &DeviceFrame::Telemetry(Telemetry::Boot {
                protocol_version: PROTOCOL_VERSION,
            }),
            &mut |bytes: &[u8]| write_all(&mut tx, bytes),
        );
        log!(
            "twil firmware up: static RAM {} bytes, stack {} bytes",
            memory::static_ram_bytes(),
            memory::stack_bytes()
        );
        let (producer, consumer) = rx_queue.split();
        (
            Shared {},
            Local {
                rx,
                tx,
                producer,
                consumer,
                device,
                planner: cx.local.planner_memory,
            },
        )
    }

    /// Every received byte goes into the queue; nothing here waits.
    #[task(binds = USART1, priority = 2, local = [rx, producer])]
    fn usart1_rx(cx: usart1_rx::Context) {
        loop {
            match cx.local.rx.read() {
                Ok(byte) => {
                    if cx.local.producer.enqueue(byte).is_err() {
                        RX_DROPPED.fetch_add(1, Ordering::Relaxed);
                    }
                }
                Err(nb::Error::WouldBlock) => break,
                // Overrun, framing, noise, parity: the HAL has cleared the flag; a byte is lost.
                Err(nb::Error::Other(_)) => {
                    RX_DROPPED.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
    }

    #[idle(local = [consumer, tx, device, planner])]
    fn idle(cx: idle::Context) -> ! {
        // Calibration of the instruction count: `asm::delay(n)` runs n + 1 times a two-instruction
        // loop, so 500 000 gives 1 000 002 instructions (+ a few for the reads).
        let before = instructions();
        cortex_m::asm::delay(500_000);
        let after = instructions();
        log!(
            "calibration: 1000002 instructions measured as {}",
            (after - before) as u32
        );
        // The stack was painted at reset (cortex-m-rt's `paint-stack`); report its high-water
        // mark now and whenever a request took it deeper.
        let mut high_water = memory::stack_high_water_bytes();
        log_stack(high_water);

        let mut chunk = [0u8; 64];
        loop {
            let mut n = 0;
            while n < chunk.len() {
                match cx.local.consumer.dequeue() {
                    Some(b) => {
                        chunk[n] = b;
                        n += 1;
                    }
                    None => break,
                }
            }
            if n == 0 {
                // Sleep until the next interrupt. Interrupts are masked while checking so a
                // byte that arrives between the check and WFI still wakes the core.
                cortex_m::interrupt::free(|_| {
                    if !cx.local.consumer.ready() {
                        cortex_m::asm::wfi();
                    }
                });
                continue;
            }
            let dropped = RX_DROPPED.swap(0, Ordering::Relaxed);
            if dropped > 0 {
                cx.local.device.handler.note_rx_dropped(dropped);
            }
            let tx = &mut *cx.local.tx;
            cx.local.device.receive(
                &chunk[..n],
                &mut **cx.local.planner,
                &mut instructions,
                &mut |bytes: &[u8]| write_all(tx, bytes),
            );
            let now = memory::stack_high_water_bytes();
            if now > high_water {
                high_water = now;
                log_stack(high_water);
            }
        }
    }

    /// Log the stack's high-water mark and what is left below it.
    fn log_stack(high_water: u32) {
        let stack = memory::stack_bytes();
        log!(
            "stack high-water: {} of {} bytes ({} free)",
            high_water,
            stack,
            stack.saturating_sub(high_water)
        );
    }

    /// Write bytes, waiting for the transmitter.
    fn write_all(tx: &mut Tx<USART1>, bytes: &[u8]) {
        for &b in bytes {
            // Writing a byte cannot fail on this USART; WouldBlock is waited out.
            let _ = nb::block!(tx.write(b));
        }
    }
}

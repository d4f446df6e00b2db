//! Twil firmware for the STM32F405, on RTIC 2: the robot's brain. It sweeps the sonar, keeps the
//! map, plans, drives the wheels with the 50 ms controller and repeats until the goal, by
//! itself; the host sends the mission over USART1 and watches the telemetry. It also answers
//! the planning service of protocol 1 (upload a map, plan, read back).
//!
//! All logic is in `twil-core`: the pilot (`mission::Pilot`: odometry, supplier, controller),
//! the mission and the link (`link::RobotDevice`), the planner. This program places them in
//! memory and moves values between tasks, pins and the USART.
//!
//! ## Tasks (highest priority first)
//!
//! | task | prio | period | does |
//! |---|---|---|---|
//! | `usart1` | 5 | per byte (USART1 interrupt: RXNE, TXE) | received bytes into a 256-byte queue, then pends `link_rx`; the next bytes of the transmit queue into the data register. Nothing else: no decoding, no waiting |
//! | `control` | 4 | 50 ms (`Mono::delay_until`) | encoders → `Pilot::tick` → motors; the stop flag (abort, e-stop) zeroes the motors; the report to `mission` |
//! | `link_rx` | 3 | per batch of bytes (pended by `usart1`) | bytes on to the mission's queue; frames decoded to look for `AbortMission` / `EmergencyStop`, which set the stop flag at once |
//! | `sonar` | 2 | per request | board: neck steps paced by `Mono`, a trigger, the echo's two edges latched by a timer and read after `Mono::delay`; QEMU: a ray cast on the real world; the reading to `mission` |
//! | `mission` | 1 | when woken (a frame's end, a report, a reading, room to send), at least every 50 ms | the link's requests and replies, the mission's steps, the planner, the pilot's commands, telemetry into the transmit queue (`mission_task.rs`) |
//!
//! Nothing at or above the receive path waits in a loop: the USART interrupt is the highest
//! priority and moves one byte per register access, the decoding runs in `link_rx`, and the
//! sonar waits with `Mono` (its only spins, the 10 µs trigger pulse and the neck's 2 µs step
//! pulse, are at priority 2, below both). The control period never waits for the planner: the
//! planner runs in `mission`, the lowest priority, and everything above preempts it. Values
//! cross between tasks through `rtic-sync` channels (reports, sonar requests, readings),
//! single-producer queues (bytes) and two locked resources (the pilot, taken by `mission` only
//! to hand it a command; the body). The tasks that leave `mission` work also write its wake
//! signal (`rtic-sync`'s `Signal`): it waits on that, with a timeout, instead of polling
//! (`mission_task.rs` says when each task writes it, and why the timeout).
//!
//! ## Memory
//!
//! - SRAM (`.data`, `.bss`): the planner (framed scratch, open list, path cells), the device
//!   (the planning service without a map of its own), the pilot, RTIC's state, the interrupt's
//!   256-byte receive queue. Below it the stack (flip-link), painted at reset; its high-water
//!   mark is reported.
//! - CCM (64 KiB, `.ccmram`, see `build.rs`): the mission (its 300 x 300 map, which is also the
//!   planning service's, the seen space, the paths), the mission's receive queue, the transmit
//!   queue and, under QEMU, the real world. Copied from flash by `init` before anything reads
//!   it.
//!
//! ## Builds
//!
//! - default (`hardware`): PLL at 168 MHz from the board's 8 MHz crystal (HSE; the HSI if the
//!   crystal does not start, logged), defmt over RTT, `panic-probe`, the drivers of `board.rs`
//!   (Olimex STM32-H405).
//! - `--no-default-features --features qemu`: QEMU's `netduinoplus2`; the clock stays on the
//!   HSI (QEMU does not emulate the RCC); the simulated robot (`twil_core::plant`) stands in for
//!   the drivers; defmt and panics over semihosting.
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

#[cfg(feature = "hardware")]
mod board;
mod body;
mod params;

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use twil_core::failsafe::{ResetCause, WatchdogDecision, WatchdogGate};
use twil_core::link::{Build, PROTOCOL_VERSION};
pub use twil_firmware::{memory, TwilDevice, TwilMission, RX_QUEUE_BYTES};

/// Log a line with defmt: over RTT on a board (probe-rs prints it), over semihosting under QEMU
/// (`cargo xtask qemu` decodes it with the ELF's defmt table).
macro_rules! log {
    ($($arg:tt)*) => {{
        defmt::info!($($arg)*);
    }};
}

mod mission_task;

/// Planner open-list capacity, entries (`twil_core::link::mcu`, shared with the host).
pub const QUEUE: usize = twil_core::link::mcu::PLANNER_QUEUE;
/// The planner (framed scratch for up to 362 x 362 cells, [`QUEUE`] open-list entries).
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

/// Virtual nanoseconds (QEMU) or cycles (board) counted so far (see [`systick_counts`]).
fn raw_clock() -> u64 {
    let t = systick_counts();
    if cfg!(feature = "qemu") {
        t * 1000 / 168
    } else {
        t
    }
}

/// Nanoseconds one instruction takes under QEMU (`-icount shift=N`: 2^N), measured at boot; 1
/// on a board (the clock counts cycles there).
static NS_PER_INSTRUCTION: AtomicU32 = AtomicU32::new(1);

/// Instructions (QEMU) or cycles (board) counted so far (see [`systick_counts`]).
///
/// QEMU's SysTick runs at 168 MHz of virtual time; with `-icount shift=N` one instruction takes
/// 2^N ns, so instructions = counts × 1000 / 168 / 2^N, N found at boot by timing a known
/// number of instructions. On a board at 168 MHz, counts are core cycles.
fn instructions() -> u64 {
    raw_clock() / NS_PER_INSTRUCTION.load(Ordering::Relaxed).max(1) as u64
}

// The atomics that stay are counters written from the USART1 interrupt (priority 5) or from
// every task: an atomic add or `fetch_max` is lock-free, where an RTIC resource would raise
// every task that notes a number to the interrupt's priority. (`NS_PER_INSTRUCTION` above is
// measured once at boot and read by `instructions()` everywhere.) The state the tasks share
// is in RTIC resources (`Shared`: `stop`, `control_state`) and channels.

/// Bytes dropped on the way in (a queue full, or a line error: overrun, framing, noise).
static RX_DROPPED: AtomicU32 = AtomicU32::new(0);
/// QEMU only: `usart1` stopped reading (receive interrupt off) because its queue was full;
/// `link_rx` pends it again once it has taken bytes out. See `usart1`.
static RX_PAUSED: AtomicBool = AtomicBool::new(false);
/// Frames not sent because the transmit queue could not take the whole frame (the mission
/// task checks for room first, so this stays 0 unless that rule is broken).
static TX_DROPPED_FRAMES: AtomicU32 = AtomicU32::new(0);
/// Most instructions (QEMU) or cycles (board) one run of each task took, for the latency
/// table of docs/firmware.md: a sonar reading's own work (QEMU: the ray cast; board: the
/// neck's pulses and the trigger, not the `Mono` waits), one USART1 interrupt, one `link_rx`
/// run (decoding), one step of the body (QEMU: the simulated robot, not charged to the control
/// step; board: the drivers). Logged when a mission ends.
static WORST_SONAR_INSTRUCTIONS: AtomicU32 = AtomicU32::new(0);
static WORST_USART_INSTRUCTIONS: AtomicU32 = AtomicU32::new(0);
static WORST_DECODE_INSTRUCTIONS: AtomicU32 = AtomicU32::new(0);
static WORST_BODY_INSTRUCTIONS: AtomicU32 = AtomicU32::new(0);

/// Note `spent` instructions in `worst` if it is the most so far.
fn note_worst(worst: &AtomicU32, spent: u64) {
    worst.fetch_max(spent.min(u32::MAX as u64) as u32, Ordering::Relaxed);
}

/// Independent watchdog timeout, milliseconds (hardware build), at the LSI's typical 32 kHz:
/// three control periods. The LSI runs at 17 … 47 kHz (DS8626, table "LSI oscillator
/// characteristics"), so the real timeout is 102 … 282 ms: never shorter than two periods
/// (the control task feeds every period), and a locked-up core, whose last PWM duty keeps
/// running, is reset within 282 ms. The gate ([`WatchdogGate`]) stops feeding it when a task
/// makes no progress for [`WatchdogGate::MISSION_LIMIT_MS`], so a stall resets the chip
/// within that plus this.
pub const WATCHDOG_TIMEOUT_MS: u32 = 150;

/// Reports queued from `control` to `mission` (8 periods, 400 ms).
const REPORTS: usize = 8;
/// Readings queued from `sonar` to `mission`.
const READINGS: usize = 8;
/// Commands queued from `mission` to `sonar`: a mission's restart, its one reading at a time,
/// and room for a reading of an ended mission still queued (the mission's requests are sent
/// with `try_send`: one dropped would leave the mission waiting).
const SONAR_REQUESTS: usize = 3;
/// Stop causes queued from `control` and `sonar` to `mission` (the body's faults: each ends
/// the mission, so one per mission is all that matters; a full queue drops the later ones).
const FAULTS: usize = 4;
/// The self-test's reports waiting for the mission task (sonar task → mission task).
const SELF_TEST_REPORTS: usize = 1;
/// Bytes of the queue from the USART1 interrupt to `link_rx` (holds one less): 22 ms of
/// 115 200 baud, while `link_rx` runs within a control step's time of the interrupt.
const IRQ_QUEUE_BYTES: usize = 256;

/// The control period, milliseconds (`RobotConfig::controller_period_s`).
const PERIOD_MS: u32 = 50;
/// One simulated sonar reading takes the neck's step plus the echo window, milliseconds
/// (`neck_step_time_s` and `echo_wait_s`, the seed's figures). Kept so that the missions under
/// QEMU do not change; the board's HC-SR04 takes at least its 60 ms cycle (docs/firmware.md).
#[cfg(feature = "qemu")]
const READING_MS: u32 = 36;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true, dispatchers = [SPI1, SPI2, SPI3])]
mod app {
    use super::*;
    use heapless::spsc::{Consumer, Producer};
    use mission_task::{Wake, WakeReader};
    use rtic_monotonics::rtic_time::monotonic::TimerQueueBasedInstant;
    use rtic_monotonics::systick::prelude::*;
    use rtic_sync::channel::{Receiver, Sender};
    use rtic_sync::make_channel;
    use stm32f4xx_hal::{
        pac::{Interrupt, USART1},
        prelude::*,
        serial::{Config, Rx, Serial, Tx},
    };
    use twil_core::failsafe::{StopCause, StopTiming};
    use twil_core::link::{
        DeviceInfo, FrameDecoder, Request, RequestFrame, Telemetry, MAX_FRAME_BYTES,
    };
    use twil_core::mission::{Pilot, PilotReport, SonarRequest};
    use twil_core::selftest::SelfTestReport;

    /// The independent watchdog (hardware); QEMU 7.2 does not emulate the IWDG (writes to it
    /// are ignored), so the QEMU build has none and only logs the gate's decision.
    #[cfg(feature = "hardware")]
    pub type Watchdog = stm32f4xx_hal::watchdog::IndependentWatchdog;
    /// No watchdog under QEMU (see above).
    #[cfg(feature = "qemu")]
    pub type Watchdog = ();

    /// A sonar reading: the neck angle and the range (`None`: no echo).
    pub type Reading = (f32, Option<f32>);

    /// What the mission task asks of the sonar task.
    pub enum HeadCommand {
        /// A mission starts: its robot (sonar window, neck geometry); the board homes the neck.
        Restart(twil_core::robot::RobotConfig),
        /// One reading.
        Read(SonarRequest),
        /// The bring-up self-test with this robot (the device's parameters) and clock: the
        /// board runs its probes stepwise in the sonar task (the wheel pulses in the control
        /// task's periods) and sends each report as rows come in.
        #[cfg(feature = "hardware")]
        SelfTest(
            twil_core::robot::RobotConfig,
            twil_core::selftest::ClockFacts,
        ),
    }

    /// The vector `link_rx` is bound to: CAN1's first receive FIFO, whose peripheral is never
    /// clocked, so only `rtic::pend` (from `usart1`) raises it.
    pub const LINK_RX_VECTOR: Interrupt = Interrupt::CAN1_RX0;

    /// What the control task and the mission task tell each other besides the pilot's
    /// reports (a channel) and the stop's timing (`StopTiming`).
    pub struct ControlState {
        /// A mission runs (or is paused): the control task ticks the pilot; otherwise the
        /// motors stay at 0.
        pub active: bool,
        /// The control task missed a period (motors already zeroed): the mission task ends
        /// the mission with `StopCause::ControllerOverrun`.
        pub overrun: bool,
        /// Most instructions one control step took in this mission (the pilot's tick; not the
        /// simulated body's step).
        pub max_control_instructions: u32,
        /// `Mono` milliseconds when the mission task last turned its loop: the watchdog
        /// gate's progress mark of that task.
        pub mission_turn_ms: u32,
    }

    #[shared]
    struct Shared {
        pilot: &'static mut Pilot,
        body: body::Body,
        world: body::World,
        /// The stop's timing: asked by `link_rx` (a stop frame) or the control task (the
        /// e-stop input), measured by the control task, reported by the mission task.
        stop: StopTiming,
        control_state: ControlState,
    }

    #[local]
    struct Local {
        rx: Rx<USART1>,
        tx: Tx<USART1>,
        /// `usart1` → `link_rx`: the bytes as they arrive.
        irq_producer: Producer<'static, u8>,
        irq_consumer: Consumer<'static, u8>,
        /// `link_rx` → `mission`: the bytes, checked for stop frames.
        producer: Producer<'static, u8>,
        consumer: Consumer<'static, u8>,
        /// `mission` → `usart1`: whole frames to send.
        tx_producer: Producer<'static, u8>,
        tx_consumer: Consumer<'static, u8>,
        /// The mission task's wake signal (`mission_task.rs`): its reader, a writer for
        /// `control` and `sonar` (cloned when they are spawned), `usart1`'s and `link_rx`'s.
        wake: WakeReader,
        wake_writer: Wake,
        usart_wake: Wake,
        link_wake: Wake,
        device: &'static mut TwilDevice,
        planner: &'static mut TwilPlanner,
        mission: &'static mut TwilMission,
        head: body::Head,
        watchdog: Watchdog,
        /// Where `ParamSet` keeps its values (`None`: the store could not be opened).
        store: Option<params::Store>,
        /// The core clock and its source (the crystal or not, found in `init`): the
        /// self-test's clock row.
        clock: twil_core::selftest::ClockFacts,
    }

    #[init(local = [
        planner_memory: TwilPlanner = TwilPlanner::new(),
        device_memory: TwilDevice = TwilDevice::new(DeviceInfo::for_build(Build::Hardware)),
        pilot_memory: Pilot = Pilot::IDLE,
        irq_queue: heapless::spsc::Queue<u8, IRQ_QUEUE_BYTES> = heapless::spsc::Queue::new(),
        #[cfg(feature = "qemu")]
        param_ram: params::StoreFlash = params::StoreFlash::ERASED,
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        #[cfg_attr(feature = "qemu", allow(unused_mut))]
        let mut rcc = cx.device.RCC.constrain();
        // First of all, the motor bridges' inputs: from reset until here they float (inputs);
        // now they are driven low, bridges disabled, before anything that could take time.
        #[cfg(feature = "hardware")]
        let (gpiob, motor_pins) = {
            let gpiob = cx.device.GPIOB.split(&mut rcc);
            let pins = board::MotorPins::low(gpiob.pb12, gpiob.pb13, gpiob.pb14, gpiob.pb15);
            (
                board::PortBRest {
                    pb0: gpiob.pb0,
                    pb1: gpiob.pb1,
                    pb5: gpiob.pb5,
                    pb6: gpiob.pb6,
                    pb7: gpiob.pb7,
                },
                pins,
            )
        };
        #[cfg(feature = "hardware")]
        log!("bring-up 1: motor outputs PB12..PB15 driven low (bridges off)");

        // Why the chip reset: RCC_CSR's flags, then cleared (RMVF) so the next reset reports
        // its own. QEMU does not emulate the RCC: unknown.
        #[cfg(feature = "hardware")]
        let reset_cause = {
            let csr = rcc.csr().read().bits();
            rcc.csr().modify(|_, w| w.rmvf().set_bit());
            ResetCause::from_rcc_csr(csr)
        };
        #[cfg(feature = "qemu")]
        let reset_cause = ResetCause::Unknown;
        // QEMU: stay on the HSI (16 MHz), no PLL and no HSE: QEMU 7.2 does not emulate the RCC,
        // its ready flags never set, so nothing may wait on them.
        #[cfg(feature = "qemu")]
        let mut rcc = rcc.freeze(stm32f4xx_hal::rcc::Config::hsi());
        #[cfg(feature = "qemu")]
        let clock_source = twil_core::selftest::ClockSource::Emulated;
        // The board: the 8 MHz crystal through the PLL to 168 MHz (the HSI if the crystal does
        // not start; logged).
        #[cfg(feature = "hardware")]
        let (mut rcc, clock_source) = {
            let (rcc, source) = board::start_clocks(rcc);
            board::log_clocks(&rcc, source);
            let clock_source = if matches!(source, board::ClockSource::Crystal { .. }) {
                twil_core::selftest::ClockSource::Crystal
            } else {
                twil_core::selftest::ClockSource::Internal
            };
            (rcc, clock_source)
        };

        let gpioa = cx.device.GPIOA.split(&mut rcc);
        let serial: Serial<USART1> = Serial::new(
            cx.device.USART1,
            (gpioa.pa9, gpioa.pa10),
            Config::default().baudrate(115_200.bps()),
            &mut rcc,
        )
        .unwrap_or_else(|_| panic!("115200 baud is reachable from any clock"));
        let (tx, mut rx) = serial.split();
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
        // static yet (they are handed out just below).
        unsafe { memory::copy_ccm() };
        let ccm = twil_firmware::take_ccm_statics().expect("init takes the CCM statics once");
        let (mut tx_producer, tx_consumer) = ccm.tx_queue.split();
        let device = cx.local.device_memory;
        device.handler.set_build(if cfg!(feature = "qemu") {
            Build::Qemu
        } else {
            Build::Hardware
        });
        device
            .handler
            .set_static_ram_bytes(memory::static_ram_bytes());
        device.handler.set_reset_cause(reset_cause);
        // Queued now, sent by `usart1` as soon as interrupts are on (after `init`).
        TwilDevice::send_telemetry(
            &Telemetry::Boot {
                protocol_version: PROTOCOL_VERSION,
                reset_cause,
            },
            &mut |bytes: &[u8]| mission_task::queue_frame(&mut tx_producer, bytes),
        );
        // The stored parameters, before the watchdog starts: a repair of a cut erase may erase
        // a sector, which stalls the core for up to 4 s (params.rs).
        #[cfg(feature = "hardware")]
        let (robot_config, stored, store) = params::boot(params::StoreFlash::new(cx.device.FLASH));
        #[cfg(feature = "qemu")]
        let (robot_config, stored, store) = params::boot(cx.local.param_ram);
        // The next mission starts from the stored values; `ParamSet` changes them.
        device.set_params(twil_core::link::params::DeviceParams {
            robot: robot_config,
            store: store.as_ref().map(|_| stored.load.status),
        });
        log!(
            "twil firmware up: static RAM {} bytes, stack {} bytes, reset cause {}, parameters {} ({} applied, {} refused)",
            memory::static_ram_bytes(),
            memory::stack_bytes(),
            reset_cause,
            stored.load.status,
            stored.applied,
            stored.refused
        );
        if let Some(e) = stored.first_refused {
            defmt::warn!(
                "parameters: {} stored values refused, kept at their defaults; first: {}",
                stored.refused,
                e
            );
        }
        // (Board only: under QEMU the line after the first is the calibration's, which
        // xtask's log test reads.)
        #[cfg(feature = "hardware")]
        log!("bring-up 3: USART1 115200 8N1, TX PA9, RX PA10; boot frame queued");
        let (producer, consumer) = ccm.rx_queue.split();
        let (irq_producer, irq_consumer) = cx.local.irq_queue.split();
        let (wake_writer, wake) = rtic_sync::make_signal!(());

        // The simulated body runs on the defaults (the QEMU store boots empty: params.rs).
        #[cfg(feature = "qemu")]
        let (body, head, world, _) = (body::Body::new(), body::Head, ccm.world, robot_config);
        #[cfg(feature = "hardware")]
        let (body, head, world) = {
            let gpioc = cx.device.GPIOC.split(&mut rcc);
            let parts = board::BoardParts {
                tim2: cx.device.TIM2,
                tim3: cx.device.TIM3,
                tim4: cx.device.TIM4,
                tim5: cx.device.TIM5,
                tim12: cx.device.TIM12,
                adc1: cx.device.ADC1,
                motor_pins,
                pa1: gpioa.pa1,
                pa5: gpioa.pa5,
                pa6: gpioa.pa6,
                pa7: gpioa.pa7,
                pb0: gpiob.pb0,
                pb1: gpiob.pb1,
                pb5: gpiob.pb5,
                pb6: gpiob.pb6,
                pb7: gpiob.pb7,
                pc0: gpioc.pc0,
                pc8: gpioc.pc8,
                pc9: gpioc.pc9,
                pc10: gpioc.pc10,
            };
            let board = board::take(parts, &mut rcc, &robot_config);
            let (body, head) = body::split(board);
            (body, head, ())
        };

        // The independent watchdog, last: from here the control task must feed it every
        // WATCHDOG_TIMEOUT_MS (its first tick comes 50 ms after the mission task's start-up).
        #[cfg(feature = "hardware")]
        let watchdog = {
            let mut w = stm32f4xx_hal::watchdog::IndependentWatchdog::new(cx.device.IWDG);
            // A core halted by the debugger must not be reset under it.
            w.stop_on_debug(&cx.device.DBGMCU, true);
            w.start(stm32f4xx_hal::prelude::_fugit_ExtU32::millis(
                WATCHDOG_TIMEOUT_MS,
            ));
            log!(
                "bring-up 5: watchdog (IWDG) started: {} ms at the LSI's typical 32 kHz",
                WATCHDOG_TIMEOUT_MS
            );
            w
        };
        #[cfg(feature = "qemu")]
        let watchdog = ();

        mission::spawn().unwrap_or_else(|_| panic!("mission spawns once"));
        // The boot frame goes out once interrupts are enabled.
        rtic::pend(Interrupt::USART1);
        (
            Shared {
                pilot: cx.local.pilot_memory,
                body,
                world,
                stop: StopTiming::NEW,
                control_state: ControlState {
                    active: false,
                    overrun: false,
                    max_control_instructions: 0,
                    mission_turn_ms: 0,
                },
            },
            Local {
                rx,
                tx,
                irq_producer,
                irq_consumer,
                producer,
                consumer,
                tx_producer,
                tx_consumer,
                wake,
                usart_wake: wake_writer.clone(),
                link_wake: wake_writer.clone(),
                wake_writer,
                device,
                planner: cx.local.planner_memory,
                mission: ccm.mission,
                head,
                watchdog,
                store,
                clock: twil_core::selftest::ClockFacts {
                    core_hz: SYSTICK_HZ,
                    source: clock_source,
                },
            },
        )
    }

    /// Nothing to do: sleep until the next interrupt (RTIC's default idle spins, which keeps
    /// the core busy and QEMU's virtual clock at the pace of the emulation).
    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// The USART, both ways, and nothing else: received bytes into the interrupt's queue (then
    /// `link_rx` is pended to look at them), and queued bytes into the data register while it
    /// takes them. The highest priority, so that no task can hold a received byte past the
    /// next one (87 µs at 115 200 baud: the data register holds one byte, the shift register
    /// the next). TXE raises this interrupt only while bytes wait (`listen` / `unlisten`);
    /// `mission` pends it after queueing a frame. QEMU 7.2's USART raises no TXE interrupt
    /// and takes every byte at once, so there the pended run sends the whole queue.
    #[task(binds = USART1, priority = 5, local = [rx, tx, irq_producer, tx_consumer, usart_wake, held: heapless::Vec<u8, 2> = heapless::Vec::new()])]
    fn usart1(cx: usart1::Context) {
        let before = instructions();
        let mut received = false;
        // QEMU hands over the next byte as soon as the data register is read, not one per
        // 87 µs, so a burst sent while `link_rx` and `mission` are busy would overflow the
        // queues that a baud rate keeps from filling on the board. Under QEMU a byte that
        // does not fit is held here and the receive interrupt turned off: QEMU delivers no
        // further byte while one waits in the data register, the host's socket buffers the
        // rest, and `link_rx` pends this interrupt once it has taken bytes out, which queues
        // the held bytes and turns reception back on. (QEMU 7.2 lowers the interrupt line
        // only when the data register is read, never when the interrupt is turned off, so no
        // byte that raised it may be left there: that would raise this interrupt for ever.)
        // The board keeps reading, and counts what it drops.
        let pause_when_full = cfg!(feature = "qemu");
        let mut paused = RX_PAUSED.load(Ordering::Relaxed);
        let held = cx.local.held;
        let producer = cx.local.irq_producer;
        if paused && producer.capacity() - producer.len() >= held.len() {
            for &byte in held.iter() {
                // Room was checked: the enqueue cannot fail.
                let _ = producer.enqueue(byte);
            }
            received |= !held.is_empty();
            held.clear();
            paused = false;
            RX_PAUSED.store(false, Ordering::Relaxed);
            cx.local.rx.listen();
        }
        while !paused {
            match cx.local.rx.read() {
                Ok(byte) => {
                    received = true;
                    if let Err(byte) = producer.enqueue(byte) {
                        if pause_when_full {
                            cx.local.rx.unlisten();
                            let _ = held.push(byte);
                            // A byte that came in between the read and turning the interrupt
                            // off raised the line; reading it lowers the line (QEMU 7.2).
                            if let Ok(late) = cx.local.rx.read() {
                                let _ = held.push(late);
                            }
                            paused = true;
                            RX_PAUSED.store(true, Ordering::Relaxed);
                        } else {
                            RX_DROPPED.fetch_add(1, Ordering::Relaxed);
                        }
                    }
                }
                Err(nb::Error::WouldBlock) => break,
                // Overrun, framing, noise, parity: the HAL has cleared the flag; a byte is lost.
                Err(nb::Error::Other(_)) => {
                    RX_DROPPED.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
        if received {
            rtic::pend(LINK_RX_VECTOR);
        }
        let tx = cx.local.tx;
        // The mission task holds received frames and telemetry back while a largest frame
        // does not fit: it is woken when one fits again.
        let short = mission_task::room_behind(cx.local.tx_consumer) < MAX_FRAME_BYTES;
        while tx.is_tx_empty() {
            let Some(byte) = cx.local.tx_consumer.dequeue() else {
                break;
            };
            // The data register is empty: the write cannot block.
            let _ = tx.write(byte);
        }
        if cx.local.tx_consumer.ready() {
            tx.listen();
        } else {
            tx.unlisten();
        }
        if short && mission_task::room_behind(cx.local.tx_consumer) >= MAX_FRAME_BYTES {
            cx.local.usart_wake.write(());
        }
        note_worst(
            &WORST_USART_INSTRUCTIONS,
            instructions().saturating_sub(before),
        );
    }

    /// The received bytes on to the mission's queue; a frame that asks to stop asks the
    /// stop (`StopTiming::ask`) at once (the mission task, which may be planning, answers it later). Decoding a whole
    /// frame (its CRC and postcard) takes up to ~20 k instructions, longer than a byte time,
    /// which is why it is here and not in `usart1`.
    #[task(binds = CAN1_RX0, priority = 3, shared = [stop], local = [irq_consumer, producer, link_wake, peek: FrameDecoder = FrameDecoder::new()])]
    fn link_rx(mut cx: link_rx::Context) {
        let before = instructions();
        // The mission task is woken by a frame's end, or by a chunk's worth of bytes without
        // one (`mission_task.rs`), not by every byte.
        let mut wake = false;
        // Under QEMU bytes wait here while the mission's queue is full (see `usart1`); the
        // mission task pends this task when it has taken some. The board moves them on, and
        // counts the ones the full queue drops, but looks at them all for a stop.
        let hold_when_full = cfg!(feature = "qemu");
        let mut moved = false;
        loop {
            if hold_when_full && !cx.local.producer.ready() {
                wake = true;
                break;
            }
            let Some(byte) = cx.local.irq_consumer.dequeue() else {
                break;
            };
            moved = true;
            if cx.local.producer.enqueue(byte).is_err() {
                RX_DROPPED.fetch_add(1, Ordering::Relaxed);
            }
            wake |= byte == 0 || cx.local.producer.len() == mission_task::CHUNK_BYTES;
            let (got, _) = cx.local.peek.feed::<RequestFrame>(&[byte]);
            if let Some(Ok(frame)) = got {
                if matches!(
                    frame.request,
                    Request::AbortMission | Request::EmergencyStop
                ) {
                    let counts = systick_counts() as u32;
                    cx.shared.stop.lock(|stop| stop.ask(counts));
                }
            }
        }
        if wake {
            cx.local.link_wake.write(());
        }
        if moved && RX_PAUSED.load(Ordering::Relaxed) {
            rtic::pend(Interrupt::USART1);
        }
        note_worst(
            &WORST_DECODE_INSTRUCTIONS,
            instructions().saturating_sub(before),
        );
    }

    /// Every 50 ms: encoders → pilot → motors. Idle (motors at 0) while no mission runs. It
    /// feeds the watchdog while the gate allows it, and zeroes the motors when a step misses
    /// its period.
    #[task(priority = 4, shared = [pilot, body, stop, control_state], local = [watchdog])]
    async fn control(
        mut cx: control::Context,
        mut reports: Sender<'static, PilotReport, REPORTS>,
        mut faults: Sender<'static, StopCause, FAULTS>,
        mut wake: Wake,
    ) {
        let period_s = PERIOD_MS as f32 / 1000.0;
        let mut next = Mono::now();
        let mut last = Mono::now();
        let mut gate = WatchdogGate::new(WatchdogGate::MISSION_LIMIT_MS, next.ticks());
        // The gate refused to feed (logged once; on QEMU, which has no IWDG, nothing resets).
        let mut starved = false;
        loop {
            next += ms(PERIOD_MS);
            Mono::delay_until(next).await;
            let now = Mono::now();
            let elapsed_s = now.ticks().wrapping_sub(last.ticks()) as f32 / MONO_HZ as f32;
            last = now;
            gate.control_ticked(now.ticks());
            gate.mission_turned(cx.shared.control_state.lock(|c| c.mission_turn_ms));
            match gate.check(now.ticks()) {
                WatchdogDecision::Feed => feed(cx.local.watchdog),
                WatchdogDecision::Starve {
                    control_silent_ms,
                    mission_silent_ms,
                } => {
                    if !core::mem::replace(&mut starved, true) {
                        log!(
                            "watchdog: not fed (control silent {} ms, mission silent {} ms): the IWDG resets the board{}",
                            control_silent_ms,
                            mission_silent_ms,
                            if cfg!(feature = "qemu") { " (QEMU has no IWDG: nothing resets)" } else { "" }
                        );
                    }
                }
            }
            let tick = cx.shared.stop.lock(|stop| stop.tick());
            if !cx.shared.control_state.lock(|c| c.active) {
                // No mission: the motors stay at 0 (a board's chassis, disarmed, is told so each
                // period; the simulated robot stands still without being stepped).
                // A self-test's wheel pulse runs here, in the control periods.
                #[cfg(feature = "hardware")]
                let stop = cx.shared.body.lock(|b| b.idle_period());
                #[cfg(feature = "qemu")]
                let stop = None;
                body_stopped(stop, &mut faults, &mut wake, &mut cx.shared.stop);
                note_stop(tick, true, &mut cx.shared.stop);
                continue;
            }
            let (left, right) = cx.shared.body.lock(|b| b.encoder_deltas());
            let before = instructions();
            let stopping = cx.shared.stop.lock(|stop| stop.asked());
            let report = cx.shared.pilot.lock(|pilot| {
                if stopping {
                    pilot.stop();
                }
                pilot.tick(left, right, elapsed_s)
            });
            let motors_off =
                stopping && report.left_voltage_v == 0.0 && report.right_voltage_v == 0.0;
            let spent = instructions().saturating_sub(before);
            let spent = spent.min(u32::MAX as u64) as u32;
            let worst = cx.shared.control_state.lock(|c| {
                let worst = c.max_control_instructions;
                c.max_control_instructions = worst.max(spent);
                worst
            });
            if spent > worst {
                log!("worst control step so far: {} instructions", spent);
            }
            // The simulated body's own step is not the control step's cost.
            let before = instructions();
            let stop = cx
                .shared
                .body
                .lock(|b| b.drive(report.left_voltage_v, report.right_voltage_v, period_s));
            note_worst(
                &WORST_BODY_INSTRUCTIONS,
                instructions().saturating_sub(before),
            );
            let body_stop = stop.is_some();
            if body_stop {
                // The body zeroed its motors; the pilot stops too.
                cx.shared.pilot.lock(|p| p.stop());
            }
            body_stopped(stop, &mut faults, &mut wake, &mut cx.shared.stop);
            if body_stop {
                note_stop(tick, true, &mut cx.shared.stop);
            }
            // The motors have their voltages now: a stop is measured to here.
            note_stop(tick, motors_off, &mut cx.shared.stop);
            // A step that ends after the next one was due: the controller cannot be trusted to
            // hold the robot on its path. Motors to zero now, the mission ends (mission task).
            if twil_core::failsafe::control_period_missed(
                next.ticks(),
                Mono::now().ticks(),
                PERIOD_MS,
            ) && !cx
                .shared
                .control_state
                .lock(|c| core::mem::replace(&mut c.overrun, true))
            {
                cx.shared.pilot.lock(|p| p.stop());
                let stop = cx.shared.body.lock(|b| b.drive(0.0, 0.0, period_s));
                body_stopped(stop, &mut faults, &mut wake, &mut cx.shared.stop);
                log!("controller overrun at tick {}: motors zeroed", tick);
            }
            // A full queue means the mission task is more than 400 ms behind: the report is
            // dropped (the mission's clock then runs slow), the wheels are not affected.
            let _ = reports.try_send(report);
            wake.write(());
        }
    }

    /// One reading per request: it takes the neck's steps and the echo window, all waited with
    /// `Mono` (the board), so every task above runs meanwhile. At a mission's start the board
    /// homes the neck with the mission's geometry. A fault (the home switch not found, a pin, a
    /// sonar that stays silent) goes to the mission task, which ends the mission with it.
    #[task(priority = 2, shared = [body, world], local = [head])]
    async fn sonar(
        mut cx: sonar::Context,
        mut requests: Receiver<'static, HeadCommand, SONAR_REQUESTS>,
        mut readings: Sender<'static, Reading, READINGS>,
        mut faults: Sender<'static, StopCause, FAULTS>,
        mut checks: Sender<'static, SelfTestReport, SELF_TEST_REPORTS>,
        mut wake: Wake,
    ) {
        #[cfg(feature = "hardware")]
        let _ = &mut cx.shared.world;
        #[cfg(feature = "qemu")]
        let _ = &mut checks;
        let mut first = true;
        // The mission's sonar range, for the simulated sonar (each start sends its robot).
        #[cfg(feature = "qemu")]
        let mut range_m = twil_core::robot::RobotConfig::DEFAULT.sonar_range_m;
        while let Ok(command) = requests.recv().await {
            let request = match command {
                HeadCommand::Restart(robot) => {
                    #[cfg(feature = "hardware")]
                    {
                        log!("bring-up 6: neck homing (towards the home switch, paced by Mono)");
                        match cx
                            .local
                            .head
                            .restart(&robot, &WORST_SONAR_INSTRUCTIONS)
                            .await
                        {
                            Ok(steps) => log!(
                                "bring-up 6: neck homed: switch closed after {} steps",
                                steps
                            ),
                            Err(cause) => {
                                defmt::error!("bring-up 6: neck homing failed: {}", cause);
                                let _ = faults.send(cause).await;
                                wake.write(());
                            }
                        }
                    }
                    #[cfg(feature = "qemu")]
                    {
                        range_m = robot.sonar_range_m;
                        let _ = &mut faults;
                    }
                    continue;
                }
                HeadCommand::Read(request) => request,
                #[cfg(feature = "hardware")]
                HeadCommand::SelfTest(robot, clock) => {
                    cx.local
                        .head
                        .self_test(&mut cx.shared.body, &robot, clock, &mut checks, &mut wake)
                        .await;
                    continue;
                }
            };
            let angle = request.neck_angle_rad;
            #[cfg(feature = "qemu")]
            let range_m = {
                Mono::delay(ms(READING_MS)).await;
                let before = instructions();
                let mut plant = cx.shared.body.lock(|b| b.snapshot());
                let range = range_m;
                let range_m = cx
                    .shared
                    .world
                    .lock(|w| body::sonar_range_m(&mut plant, w, angle, range));
                note_worst(
                    &WORST_SONAR_INSTRUCTIONS,
                    instructions().saturating_sub(before),
                );
                range_m
            };
            #[cfg(feature = "hardware")]
            let range_m = match cx.local.head.read(angle, &WORST_SONAR_INSTRUCTIONS).await {
                Ok(range_m) => range_m,
                Err(cause) => {
                    // No reading to map: the mission ends with the fault instead.
                    defmt::error!("sonar head fault: {}", cause);
                    let _ = faults.send(cause).await;
                    wake.write(());
                    None
                }
            };
            if first {
                first = false;
                log!(
                    "bring-up 7: first sonar reading: {} rad, range {} m",
                    angle,
                    range_m
                );
            }
            if readings.send((angle, range_m)).await.is_err() {
                return;
            }
            wake.write(());
        }
    }

    /// The mission task: the link, the mission's steps and the planner, at the lowest priority
    /// (its loop, and how it waits for work: `mission_task.rs`).
    #[task(priority = 1, shared = [pilot, body, world, stop, control_state], local = [consumer, tx_producer, device, planner, mission, store, clock, wake, wake_writer])]
    async fn mission(mut cx: mission::Context) {
        // Calibration of the instruction count: `asm::delay(n)` runs n + 1 times a
        // two-instruction loop, so 500 000 gives 1 000 002 instructions (+ a few for the
        // reads). Under QEMU the time it takes tells the icount shift: 1 ns per instruction at
        // shift 0 (instruction counts), 8 ns at shift 3 (missions: the chip's pace or slower).
        let before = raw_clock();
        cortex_m::asm::delay(500_000);
        let measured = raw_clock() - before;
        log!(
            "calibration: 1000002 instructions measured as {}",
            measured as u32
        );
        if cfg!(feature = "qemu") {
            let ns = (measured + 500_000) / 1_000_002;
            NS_PER_INSTRUCTION.store(ns.clamp(1, 1024) as u32, Ordering::Relaxed);
            log!("QEMU pace: {} ns per instruction", ns as u32);
        }
        let (reports_tx, reports) = make_channel!(PilotReport, REPORTS);
        let (readings_tx, readings) = make_channel!(Reading, READINGS);
        let (sonar_tx, sonar_rx) = make_channel!(HeadCommand, SONAR_REQUESTS);
        let (faults_tx, faults) = make_channel!(StopCause, FAULTS);
        let (checks_tx, checks) = make_channel!(SelfTestReport, SELF_TEST_REPORTS);
        control::spawn(reports_tx, faults_tx.clone(), cx.local.wake_writer.clone())
            .unwrap_or_else(|_| panic!("control spawns once"));
        sonar::spawn(
            sonar_rx,
            readings_tx,
            faults_tx,
            checks_tx,
            cx.local.wake_writer.clone(),
        )
        .unwrap_or_else(|_| panic!("sonar spawns once"));
        let mail = mission_task::Mail {
            reports,
            readings,
            sonar: sonar_tx,
            faults,
            checks,
        };
        mission_task::run(&mut cx.shared, &mut cx.local, mail).await
    }

    /// The body stopped the motors (`stop`: why, once): an e-stop press is timed like a stop
    /// frame (from this tick); the cause goes to the mission task, which ends the mission.
    fn body_stopped(
        stop: Option<StopCause>,
        faults: &mut Sender<'static, StopCause, FAULTS>,
        wake: &mut Wake,
        timing: &mut impl rtic::Mutex<T = StopTiming>,
    ) {
        let Some(cause) = stop else {
            return;
        };
        let counts = systick_counts() as u32;
        if cause == StopCause::EmergencyStop && timing.lock(|t| t.ask(counts)) {
            log!("emergency-stop input tripped: motors zeroed at this tick");
        }
        // A full queue: earlier causes are waiting, and the first one ends the mission.
        let _ = faults.try_send(cause);
        wake.write(());
    }

    /// At control tick `tick`, with zero volts on the motors (`motors_off`): if a stop frame
    /// came and this is the first such tick since, note how many periods it took.
    fn note_stop(tick: u32, motors_off: bool, timing: &mut impl rtic::Mutex<T = StopTiming>) {
        // SysTick counts at 168 MHz on both builds (QEMU: virtual time).
        let counts = systick_counts() as u32;
        timing.lock(|t| t.motors_at(tick, motors_off, counts, SYSTICK_HZ / 1_000_000));
    }

    /// Feed the independent watchdog (hardware; QEMU has none).
    #[cfg(feature = "hardware")]
    fn feed(watchdog: &mut Watchdog) {
        watchdog.feed();
    }

    /// QEMU: no watchdog to feed.
    #[cfg(feature = "qemu")]
    fn feed(_: &mut Watchdog) {}

    /// `n` milliseconds of [`Mono`] (one tick per millisecond).
    fn ms(n: u32) -> fugit::Duration<u32, 1, { MONO_HZ as u64 }> {
        fugit::Duration::<u32, 1, { MONO_HZ as u64 }>::from_ticks(n)
    }
}

/// Zero both motors with raw register writes, trusting no driver state: TIM12's CCR1 / CCR2
/// (both motors' PWM, board.rs) to 0 and its outputs off (CCER = 0). For the fault handlers.
#[cfg(feature = "hardware")]
fn motors_off_raw() {
    // SAFETY: called only from fault handlers, which preempt everything and end in a reset:
    // no task will touch TIM12 again.
    let tim12 = unsafe { &*stm32f4xx_hal::pac::TIM12::ptr() };
    tim12.ccr1().write(|w| unsafe { w.bits(0) });
    tim12.ccr2().write(|w| unsafe { w.bits(0) });
    tim12.ccer().write(|w| unsafe { w.bits(0) });
}

/// The NMI: on this chip, the clock security system (the crystal stopped; the core runs on the
/// HSI now, at 16 MHz instead of 168, so every period would be 10.5 times too long). Motors
/// off, then a reset: the next boot finds no crystal and runs on the HSI's PLL, logged.
#[cfg(feature = "hardware")]
#[cortex_m_rt::exception]
unsafe fn NonMaskableInt() {
    motors_off_raw();
    defmt::error!("the crystal stopped (clock security system): motors zeroed, resetting");
    cortex_m::peripheral::SCB::sys_reset()
}

/// A HardFault (a bus or usage fault escalated, or a stack overflow: flip-link puts the stack
/// below the statics, so an overflow faults instead of corrupting them): zero the motors with
/// raw register writes (no driver state is trusted any more), then reset the chip (the next
/// boot reports `ResetCause::Software`). If the fault left no stack to run this handler, the
/// core locks up and the independent watchdog resets it within [`WATCHDOG_TIMEOUT_MS`].
#[cortex_m_rt::exception]
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    #[cfg(feature = "hardware")]
    motors_off_raw();
    defmt::error!("hard fault: motors zeroed, resetting");
    cortex_m::peripheral::SCB::sys_reset()
}

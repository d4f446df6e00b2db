//! The mission task's loop: the link's requests and replies, the mission's steps, the
//! planner, the pilot's commands and the telemetry, at the lowest priority (1). `main.rs` sets
//! the task up (calibration, channels, the other tasks spawned) and calls [`run`], which never
//! returns.
//!
//! ## One turn
//!
//! Each turn marks the task's progress for the watchdog gate (`mission_turn_ms`), gives the
//! link the time (`set_now_ms`, for its silence), then does what is there: at most one frame of
//! received bytes (only while its reply fits in the transmit queue), the self-test, the
//! failsafes (a missed control period, a silent host), a mission's start, the body's faults,
//! the control task's reports and the sonar's readings, the pilot's command and the sonar's
//! request, the mission's plan, the end of a mission, and up to four telemetry messages.
//!
//! ## Waiting for work
//!
//! A turn that found nothing to do waits on one [`Wake`] signal (`rtic_sync::signal`), raced
//! with a timeout (`Mono::timeout_after`, at most [`IDLE_TURN_MS`]: below). Every task that leaves work for this one writes the
//! signal after leaving it, so the work is never missed (a signal written while a turn runs
//! stays set, and the next wait returns at once):
//!
//! - `link_rx`, when a frame's end (0x00) reaches the receive queue, or the queue fills to
//!   [`CHUNK_BYTES`] (a long run without a 0x00: the turn takes a chunk at a time);
//! - `usart1`, when the transmit queue drains back to room for a largest frame (a turn that
//!   found no room left received bytes or telemetry waiting);
//! - `control`, after each period's report (and a missed period, which comes with one), and
//!   after a body fault;
//! - `sonar`, after a reading, a fault or a self-test report.
//!
//! A busy turn (a frame, a report, a plan, telemetry sent, ...) is followed by another
//! at once, without waiting, until a turn finds nothing.
//!
//! The timeout is for the work that time alone brings. The watchdog gate wants a turn within
//! `WatchdogGate::MISSION_LIMIT_MS` (1 s): during a mission the control task's reports wake
//! the task every 50 ms anyway, between missions nothing else does, so a wait lasts at most
//! [`IDLE_TURN_MS`] (one control period: the mark stays 20 times fresher than its limit, at
//! 20 turns a second instead of the 1 000 of the old 1 ms poll). The link's silence is checked
//! on a turn: a wait also ends when the host's silence reaches the mission's link-loss timeout
//! (`RobotDevice::link_loss_in_ms`), so the mission stops at the timeout, to the millisecond,
//! as with the poll, not up to a period after it.
use core::sync::atomic::Ordering;

use heapless::spsc::{Consumer, Producer};
use rtic::Mutex;
use rtic_monotonics::rtic_time::monotonic::TimerQueueBasedInstant;
use rtic_monotonics::systick::prelude::*;
use rtic_sync::channel::{Receiver, Sender};
use twil_core::failsafe::StopCause;
use twil_core::link::{WorldAccess, WorldUpload, MAX_FRAME_BYTES};
use twil_core::mission::PilotReport;
use twil_core::selftest::SelfTestReport;

use crate::app::{mission as task, HeadCommand, Reading};
use crate::{
    instructions, memory, Mono, TwilDevice, FAULTS, PERIOD_MS, READINGS, REPORTS, RX_DROPPED,
    SELF_TEST_REPORTS, SONAR_REQUESTS, TX_DROPPED_FRAMES, WORST_BODY_INSTRUCTIONS,
    WORST_DECODE_INSTRUCTIONS, WORST_SONAR_INSTRUCTIONS, WORST_USART_INSTRUCTIONS,
};

/// The signal that wakes the mission task: written by the tasks that leave it work (see the
/// module's doc), waited on by the task when a turn found nothing to do.
pub type Wake = rtic_sync::signal::SignalWriter<'static, ()>;
/// The mission task's end of [`Wake`].
pub type WakeReader = rtic_sync::signal::SignalReader<'static, ()>;

/// Longest wait of a turn that found nothing to do, milliseconds: one control period (see the
/// module's doc).
pub const IDLE_TURN_MS: u32 = PERIOD_MS;

/// Received bytes taken per turn at most (a frame ends a turn's take earlier); also the fill
/// of the receive queue at which `link_rx` wakes the task without a frame's end.
pub const CHUNK_BYTES: usize = 64;

/// The mission task's ends of the channels to and from the other tasks.
pub struct Mail {
    /// The control task's reports, one per period of a mission.
    pub reports: Receiver<'static, PilotReport, REPORTS>,
    /// The sonar's readings.
    pub readings: Receiver<'static, Reading, READINGS>,
    /// Requests to the sonar task.
    pub sonar: Sender<'static, HeadCommand, SONAR_REQUESTS>,
    /// The body's faults (from `control` and `sonar`).
    pub faults: Receiver<'static, StopCause, FAULTS>,
    /// The board's self-test reports (the sonar task runs it).
    #[cfg_attr(feature = "qemu", allow(dead_code))]
    pub checks: Receiver<'static, SelfTestReport, SELF_TEST_REPORTS>,
}

/// The mission task's loop, with the task's resources.
pub async fn run(
    shared: &mut task::SharedResources<'_>,
    local: &mut task::LocalResources<'_>,
    mut mail: Mail,
) -> ! {
    let mut high_water = memory::stack_high_water_bytes();
    log_stack(high_water);
    let device = &mut **local.device;
    let mission = &mut **local.mission;
    let planner = &mut **local.planner;
    let tx = &mut *local.tx_producer;
    let mut chunk = [0u8; CHUNK_BYTES];
    let mut reported_end = false;
    loop {
        let turn_start = instructions();
        let mut busy = false;
        // Progress mark for the watchdog gate; the link's clock for its silence.
        let now_ms = Mono::now().ticks();
        shared.control_state.lock(|c| c.mission_turn_ms = now_ms);
        device.set_now_ms(now_ms);
        // The link: requests in, replies out. At most one frame per round (the bytes up to
        // its 0x00), and only while its reply fits in the transmit queue: a slow host
        // holds its own requests back (their bytes wait in the receive queue).
        let mut n = 0;
        if room(tx) >= MAX_FRAME_BYTES {
            while n < chunk.len() {
                match local.consumer.dequeue() {
                    Some(b) => {
                        chunk[n] = b;
                        n += 1;
                        if b == 0 {
                            break;
                        }
                    }
                    None => break,
                }
            }
        }
        if n > 0 {
            busy = true;
            // Under QEMU, `link_rx` holds bytes back while this queue is full (`usart1`).
            if cfg!(feature = "qemu") {
                rtic::pend(crate::app::LINK_RX_VECTOR);
            }
            let dropped = RX_DROPPED.swap(0, Ordering::Relaxed);
            if dropped > 0 {
                device.handler.note_rx_dropped(dropped);
            }
            let mut world = LockedWorld(&mut shared.world);
            let mut link = match local.store.as_mut() {
                Some(store) => device.link_with_store(mission, store),
                None => device.link(mission),
            };
            link.receive(
                &chunk[..n],
                planner,
                &mut instructions,
                &mut world,
                &mut |bytes: &[u8]| queue_frame(tx, bytes),
            );
        }
        // The bring-up self-test, between missions (the device refuses it during one).
        #[cfg(feature = "qemu")]
        if device.take_self_test() {
            busy = true;
            let robot = device.params().robot;
            let clock = *local.clock;
            let report = self_test(&robot, clock, &mut shared.body, &mut shared.world);
            log!(
                "self-test: {} rows, {} failed",
                report.rows.len(),
                report.failures()
            );
            device.note_self_test(&report);
        }
        // The board's runs in the sonar task, which sends the report as rows come in.
        #[cfg(feature = "hardware")]
        {
            if device.take_self_test() {
                busy = true;
                log!("self-test: started");
                let _ = mail
                    .sonar
                    .send(HeadCommand::SelfTest(device.params().robot, *local.clock))
                    .await;
            }
            while let Ok(report) = mail.checks.try_recv() {
                busy = true;
                if report.done {
                    log!(
                        "self-test: {} rows, {} failed",
                        report.rows.len(),
                        report.failures()
                    );
                }
                device.note_self_test(&report);
            }
        }
        // Failsafes: a control step that missed its period (motors already zeroed), a host
        // silent for longer than the mission's link-loss timeout.
        if shared
            .control_state
            .lock(|c| core::mem::replace(&mut c.overrun, false))
        {
            device.link(mission).fail(StopCause::ControllerOverrun);
        }
        if let Some(reaction) = device.link(mission).watch_link() {
            log!(
                "link lost: the host silent for {} ms: {}",
                device.link(mission).link_silent_ms(),
                reaction
            );
        }
        // A mission that starts: the pilot and the body at its start.
        if let Some(config) = device.link(mission).take_started() {
            shared
                .control_state
                .lock(|c| c.max_control_instructions = 0);
            let body = shared.body.lock(|b| b.restart(&config));
            shared.pilot.lock(|p| p.restart(&config));
            shared.stop.lock(|stop| stop.restart());
            shared.control_state.lock(|c| c.active = true);
            // The head homes with the mission's geometry before its first reading (the
            // queue is in order).
            let _ = mail.sonar.send(HeadCommand::Restart(config.robot)).await;
            log!("mission start: e-stop cleared: {}", body.is_ok());
            if let Err(cause) = body {
                // The e-stop still pressed (or unreadable): the mission ends at once.
                device.link(mission).fail(cause);
            }
        }
        // The body's faults (an e-stop press, a sensor) end the mission with their cause.
        while let Ok(cause) = mail.faults.try_recv() {
            busy = true;
            log!("the body stopped the mission: {}", cause);
            device.link(mission).fail(cause);
        }
        let worst_control = shared.control_state.lock(|c| c.max_control_instructions);
        let (stop_ticks, stop_latency_us) = shared
            .stop
            .lock(|stop| (stop.stop_ticks(), stop.latency_us()));
        device.note_timing(worst_control as u64, high_water, stop_ticks);
        device.note_stop_latency_us(stop_latency_us);
        // What the other tasks sent.
        while let Ok(report) = mail.reports.try_recv() {
            busy = true;
            device.link(mission).tick(&report);
        }
        while let Ok((angle, range_m)) = mail.readings.try_recv() {
            busy = true;
            device.link(mission).reading(angle, range_m);
        }
        // What the mission asks.
        if let Some(command) = device.take_pilot_command() {
            let prefix = mission.prefix();
            shared.pilot.lock(|p| {
                let _ = p.command(command, prefix);
            });
        }
        if let Some(request) = device.take_sonar_request() {
            // At most one is out at a time (the mission waits for its answer).
            let _ = mail.sonar.try_send(HeadCommand::Read(request));
        }
        if device.plan_pending() {
            device.link(mission).run_planner(planner, &mut instructions);
            busy = true;
        }
        let ended = device.state() == twil_core::link::RunState::Ended;
        if ended && !reported_end {
            let r = device.link(mission).report();
            log!(
                "mission done: worst instructions: control step {}, plan {}, mission turn {}, sonar reading {}, usart1 interrupt {}, link_rx {}, body step {}; frames not sent {}; stack {} bytes; stop cause {}, stop latency {} us",
                r.max_control_instructions as u32,
                r.max_plan_instructions as u32,
                r.max_turn_instructions.min(u32::MAX as u64) as u32,
                WORST_SONAR_INSTRUCTIONS.load(Ordering::Relaxed),
                WORST_USART_INSTRUCTIONS.load(Ordering::Relaxed),
                WORST_DECODE_INSTRUCTIONS.load(Ordering::Relaxed),
                WORST_BODY_INSTRUCTIONS.load(Ordering::Relaxed),
                TX_DROPPED_FRAMES.load(Ordering::Relaxed),
                r.stack_high_water_bytes,
                r.stop_cause,
                r.stop_latency_us
            );
        }
        if ended && !reported_end {
            // Motors at 0 and, on the board, disarmed until the next start.
            shared.body.lock(|b| b.stop());
        }
        reported_end = ended;
        if device.state() != twil_core::link::RunState::Running {
            let paused = device.state() == twil_core::link::RunState::Paused;
            shared.control_state.lock(|c| c.active = paused);
        }
        // Telemetry, a few messages per round so that readings and reports are not held
        // up, each only while a largest frame fits: otherwise it waits in the device
        // (backpressure), and the loop sleeps while the USART sends.
        for _ in 0..4 {
            if room(tx) < MAX_FRAME_BYTES {
                break;
            }
            let Some(t) = device.link(mission).next_telemetry() else {
                break;
            };
            busy = true;
            TwilDevice::send_telemetry(&t, &mut |bytes: &[u8]| queue_frame(tx, bytes));
        }
        // The turn's length for the report (the watchdog gate's 1 s is per turn): instructions
        // (QEMU) or cycles (board), the preemptions by the other tasks included.
        device.note_turn_instructions(instructions().saturating_sub(turn_start));
        let now = memory::stack_high_water_bytes();
        if now > high_water {
            high_water = now;
            log_stack(high_water);
        }
        if !busy {
            // Nothing left to do now: sleep until a task brings work (`Wake`), a period
            // passes or the host's silence reaches the link-loss timeout, whichever is first
            // (see the module's doc for why the bounds).
            let wait_ms = device
                .link_loss_in_ms()
                .map_or(IDLE_TURN_MS, |left| left.clamp(1, IDLE_TURN_MS));
            let _ = Mono::timeout_after(ms(wait_ms), local.wake.wait()).await;
        }
    }
}

/// `n` milliseconds of [`Mono`] (one tick per millisecond).
fn ms(n: u32) -> fugit::Duration<u32, 1, { crate::MONO_HZ as u64 }> {
    fugit::Duration::<u32, 1, { crate::MONO_HZ as u64 }>::from_ticks(n)
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

/// Free bytes in the transmit queue.
fn room(tx: &Producer<'static, u8>) -> usize {
    tx.capacity() - tx.len()
}

/// Free bytes in the transmit queue, seen from `usart1`'s end.
pub fn room_behind(tx: &Consumer<'static, u8>) -> usize {
    tx.capacity() - tx.len()
}

/// Queue one whole frame for `usart1` and pend it; a frame that does not fit is dropped
/// whole (counted), never cut: the receiver would lose the next frame too.
pub fn queue_frame(tx: &mut Producer<'static, u8>, bytes: &[u8]) {
    if room(tx) < bytes.len() {
        TX_DROPPED_FRAMES.fetch_add(1, Ordering::Relaxed);
        return;
    }
    for &b in bytes {
        // Checked above: there is room.
        let _ = tx.enqueue(b);
    }
    rtic::pend(stm32f4xx_hal::pac::Interrupt::USART1);
}

/// The world of a simulated build, reached through its lock.
struct LockedWorld<'a, M>(&'a mut M);

#[cfg(feature = "qemu")]
impl<M: Mutex<T = &'static mut WorldUpload>> WorldAccess for LockedWorld<'_, M> {
    fn with_world(&mut self, f: &mut dyn FnMut(&mut WorldUpload)) {
        self.0.lock(|w| f(w));
    }
}

#[cfg(feature = "hardware")]
impl<M> WorldAccess for LockedWorld<'_, M> {
    fn with_world(&mut self, _f: &mut dyn FnMut(&mut WorldUpload)) {
        // A board has no real world to upload: the request is answered NotOnThisBuild.
        let _ = &self.0;
    }
}

/// The self-test on the simulated robot where it stands (QEMU): the sonar's pings on the
/// real world, the pulses on a copy of the plant; at once (a few thousand plant sub-steps).
#[cfg(feature = "qemu")]
fn self_test(
    robot: &twil_core::robot::RobotConfig,
    clock: twil_core::selftest::ClockFacts,
    body: &mut impl Mutex<T = crate::body::Body>,
    world: &mut impl Mutex<T = crate::body::World>,
) -> SelfTestReport {
    use twil_core::selftest::{run, simulated::SimulatedCheck};
    let config = *robot;
    let plant = body.lock(|b| b.snapshot());
    let mut test = twil_core::selftest::SelfTest::new(&config, clock);
    world.lock(|w| {
        let mut check = SimulatedCheck::new(&plant, &w.obstacles, config.sonar_range_m);
        run(&mut test, &mut check).clone()
    })
}

//! `--remote sim`: the mission device in this process. The core's device shell
//! ([`DeviceShell300`]: a [`RobotDevice`] with the pilot, the mission planner, the real world
//! the host uploads and the simulated body, wired once for this shell and the link tests) runs
//! on its own thread with a parameter store in RAM and the wall clock; [`SimLink`] is the byte
//! stream between it and [`crate::remote::Remote`].
//!
//! The device runs as fast as it can in simulated time (50 ms per tick; `sim:N` paces it at N
//! times real time, to watch the live display or try Ctrl-C): it answers requests
//! between ticks and sends the telemetry it pulls with [`RobotLink::next_telemetry`]. The
//! pipe towards the host is bounded ([`PIPE_CHUNKS`] writes), so a fast device waits for a slow
//! reader rather than filling memory. It reports [`Build::Host`]. The thread ends when the host
//! drops its end of the link.
//!
//! [`RobotDevice`]: twil_core::link::RobotDevice
//! [`RobotLink::next_telemetry`]: twil_core::link::RobotLink::next_telemetry

use std::collections::VecDeque;
use std::io::{Read, Write};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender, SyncSender, TryRecvError};
use std::thread::JoinHandle;
use std::time::Duration;

use anyhow::{anyhow, Result};
use twil_core::control::Pose;
use twil_core::link::params::{DeviceParams, ParamSave};
use twil_core::link::{Build, DeviceInfo, RunState};
use twil_core::mission::DeviceShell300;
use twil_core::params_store::ram_flash::RamFlash;
use twil_core::params_store::robot::load_robot_config;
use twil_core::params_store::ParamStore;
use twil_core::plant::Plant;
use twil_core::robot::RobotConfig;

/// The device's parameter store: in RAM, as the QEMU build's (two pages of 1 KiB), empty at
/// every start, so a value set lasts as long as this device (one `twil` command).
pub type SimStore = ParamStore<RamFlash<2048, 1024>>;

/// Writes (a request's reply, or one tick's telemetry) the pipe towards the host holds before
/// the device waits.
pub const PIPE_CHUNKS: usize = 64;

/// Control period of the simulated robot, seconds.
const PERIOD_S: f32 = 0.05;

/// Stack of the device thread: the shell (device, mission, planner) is built before it is boxed.
const STACK_BYTES: usize = 64 << 20;

/// The host's end of the link to the in-process device. Reads time out after 200 ms
/// (`TimedOut`), as a serial port's do.
pub struct SimLink {
    to_device: Option<Sender<Vec<u8>>>,
    from_device: Receiver<Vec<u8>>,
    pending: VecDeque<u8>,
    thread: Option<JoinHandle<()>>,
}

impl SimLink {
    /// Start the device on its own thread: as fast as it can (`pace` 0) or `pace` times real
    /// time.
    pub fn spawn(pace: u32) -> Result<Self> {
        let (to_device, requests) = mpsc::channel::<Vec<u8>>();
        let (telemetry, from_device) = mpsc::sync_channel::<Vec<u8>>(PIPE_CHUNKS);
        let thread = std::thread::Builder::new()
            .name("twil-device-sim".into())
            .stack_size(STACK_BYTES)
            .spawn(move || DeviceThread::new(pace).run(&requests, &telemetry))
            .map_err(|e| anyhow!("cannot start the simulated device: {e}"))?;
        Ok(Self {
            to_device: Some(to_device),
            from_device,
            pending: VecDeque::new(),
            thread: Some(thread),
        })
    }
}

impl Read for SimLink {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.pending.is_empty() {
            match self.from_device.recv_timeout(Duration::from_millis(200)) {
                Ok(bytes) => self.pending.extend(bytes),
                Err(RecvTimeoutError::Timeout) => return Err(std::io::ErrorKind::TimedOut.into()),
                Err(RecvTimeoutError::Disconnected) => return Ok(0),
            }
        }
        let n = buf.len().min(self.pending.len());
        for (b, o) in buf.iter_mut().zip(self.pending.drain(..n)) {
            *b = o;
        }
        Ok(n)
    }
}

impl Write for SimLink {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        let sent = self
            .to_device
            .as_ref()
            .map(|tx| tx.send(bytes.to_vec()).is_ok())
            .unwrap_or(false);
        if sent {
            Ok(bytes.len())
        } else {
            Err(std::io::ErrorKind::BrokenPipe.into())
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Drop for SimLink {
    fn drop(&mut self) {
        // Closing both ends ends the device's loop (a blocked send fails once the receiver is
        // gone, which needs `from_device` dropped: it is, after this body, so do not join a
        // thread that may be blocked on it; detaching is enough).
        self.to_device = None;
        drop(self.thread.take());
    }
}

/// The in-process device: the core's [`DeviceShell300`] with this shell's own parts, the
/// parameter store, the wall clock and the pace.
struct DeviceThread {
    shell: Box<DeviceShell300>,
    /// Where `ParamSet` keeps its values (`None` only if the store could not be opened: a
    /// defect, then values last in RAM).
    store: Option<SimStore>,
    /// Real time per tick (zero: as fast as it can).
    tick_time: Duration,
    /// The device's clock for the host's silence (link-loss policy): wall time, as on the
    /// firmware, since the host's heartbeats are paced in wall time too.
    started: std::time::Instant,
}

impl DeviceThread {
    fn new(pace: u32) -> Self {
        let mut shell = Box::new(DeviceShell300::new(DeviceInfo::for_build(Build::Host)));
        // The firmware's boot: load the store, apply it through the one validation.
        let mut store = SimStore::new(RamFlash::ERASED, 0..2048).ok();
        if let Some(store) = store.as_mut() {
            let (robot, boot) = load_robot_config(store, &RobotConfig::DEFAULT);
            shell.device.set_params(DeviceParams {
                robot,
                store: Some(boot.load.status),
            });
        }
        Self {
            shell,
            store,
            tick_time: if pace == 0 {
                Duration::ZERO
            } else {
                Duration::from_secs_f32(PERIOD_S / pace as f32)
            },
            started: std::time::Instant::now(),
        }
    }

    /// Serve requests and run the mission until the host goes away.
    fn run(mut self, requests: &Receiver<Vec<u8>>, out: &SyncSender<Vec<u8>>) {
        loop {
            let running = matches!(
                self.shell.device.state(),
                RunState::Running | RunState::Paused
            );
            // Between ticks: every request that has arrived; idle, wait for one.
            let mut received = Vec::new();
            if running {
                loop {
                    match requests.try_recv() {
                        Ok(bytes) => received.push(bytes),
                        Err(TryRecvError::Empty) => break,
                        Err(TryRecvError::Disconnected) => return,
                    }
                }
            } else {
                match requests.recv_timeout(Duration::from_millis(100)) {
                    Ok(bytes) => received.push(bytes),
                    Err(RecvTimeoutError::Timeout) => {}
                    Err(RecvTimeoutError::Disconnected) => return,
                }
            }
            let now_ms = self.started.elapsed().as_millis() as u32;
            self.shell.device.set_now_ms(now_ms);
            let mut wire = Vec::new();
            for bytes in received {
                let store = self.store.as_mut().map(|s| s as &mut dyn ParamSave);
                self.shell
                    .receive(&bytes, store, &mut |b: &[u8]| wire.extend_from_slice(b));
                // A stop, hold or follow asked for by a request reaches the pilot before the
                // next tick.
                self.shell.command_pilot();
            }
            if self.shell.device.take_self_test() {
                self.self_test();
            }
            // The host silent for longer than the mission's link timeout: its reaction.
            if self.shell.link().watch_link().is_some() {
                self.shell.command_pilot();
            }
            if matches!(
                self.shell.device.state(),
                RunState::Running | RunState::Paused
            ) {
                self.shell.tick(PERIOD_S);
                if !self.tick_time.is_zero() {
                    std::thread::sleep(self.tick_time);
                }
            }
            self.shell
                .send_telemetry(&mut |b: &[u8]| wire.extend_from_slice(b));
            if !wire.is_empty() && out.send(wire).is_err() {
                return;
            }
        }
    }

    /// The self-test on the simulated robot where it stands (at the origin before the first
    /// mission), at once: the report goes to the device, which answers the host's polls.
    fn self_test(&mut self) {
        use twil_core::selftest::{run, simulated::SimulatedCheck, ClockFacts, ClockSource};
        let config = twil_core::robot::RobotConfig::DEFAULT;
        let plant = match &self.shell.body {
            Some(body) => body.plant().clone(),
            None => Plant::new(&config, Pose::default()),
        };
        let clock = ClockFacts {
            core_hz: twil_core::selftest::CORE_CLOCK_HZ,
            source: ClockSource::Emulated,
        };
        let mut test = twil_core::selftest::SelfTest::new(&config, clock);
        let mut body =
            SimulatedCheck::new(&plant, &self.shell.world.obstacles, config.sonar_range_m);
        let report = run(&mut test, &mut body).clone();
        self.shell.device.note_self_test(&report);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::remote::Remote;
    use std::time::Instant;
    use twil_core::geom::PointM;
    use twil_core::link::{MapParams, MissionSetup, Reply, Request, Telemetry, PROTOCOL_VERSION};
    use twil_core::mission::{MissionMode, MissionStatus};

    /// The mission across the tiny world's wall, from (3, 1.5) to (3, 5) m.
    fn tiny_mission(link_loss: twil_core::failsafe::LinkLossPolicy) -> MissionSetup {
        let params = twil_core::world::Params {
            robot_radius_m: 0.35,
            speed_m_s: 0.3,
            initial_heading_deg: 90.0,
            start: PointM::new(3.0, 1.5),
            goal: PointM::new(3.0, 5.0),
        };
        MissionSetup {
            initial_heading_rad: std::f32::consts::FRAC_PI_2,
            time_limit_s: 300.0,
            link_loss,
            ..MissionSetup::from_params(&params, MissionMode::Continuous)
        }
    }

    /// A mission on the tiny world at real-time pace (`sim:1`, 12 s to the goal) that reacts
    /// to `timeout_ms` of silence by stopping; started.
    fn paced_mission_with_link_timeout(timeout_ms: u32) -> Remote {
        let mut remote = Remote::over(SimLink::spawn(1).unwrap());
        remote.hello().unwrap();
        let map = MapParams {
            robot_radius_m: 0.35,
            ..MapParams::default()
        };
        remote.call(Request::SetParams(map)).unwrap();
        let setup = tiny_mission(twil_core::failsafe::LinkLossPolicy {
            timeout_ms,
            reaction: twil_core::failsafe::LinkLossReaction::StopAndHold,
        });
        assert_eq!(remote.call(Request::SetMission(setup)).unwrap(), Reply::Ack);
        assert_eq!(remote.call(Request::StartMission).unwrap(), Reply::Ack);
        remote
    }

    #[test]
    fn heartbeats_keep_a_mission_alive_and_silence_stops_it_as_link_lost() {
        use twil_core::failsafe::StopCause;
        use twil_core::link::{DeviceFrame, RunState};
        let mut remote = paced_mission_with_link_timeout(300);
        // 1.5 s of heartbeats every 100 ms: still running.
        let mut last_sent = Instant::now();
        for _ in 0..15 {
            std::thread::sleep(Duration::from_millis(100));
            last_sent = Instant::now();
            match remote.call(Request::MissionStatus).unwrap() {
                Reply::Mission(r) => assert_eq!(r.state, RunState::Running, "{r:?}"),
                other => panic!("{other:?}"),
            }
        }
        // Silence: the device ends the mission 300 ms (plus a tick) after the last request
        // reached it (its reply leaves at the end of the device's tick, up to 50 ms later).
        let deadline = Instant::now() + Duration::from_secs(10);
        remote.telemetry.clear();
        let report = loop {
            match remote.next_frame(deadline).unwrap() {
                Ok(DeviceFrame::Telemetry(Telemetry::Finished(r))) => break r,
                Ok(_) => {}
                Err(fault) => panic!("{fault:?}"),
            }
        };
        let waited = last_sent.elapsed();
        assert!(
            waited >= Duration::from_millis(299) && waited < Duration::from_millis(1_500),
            "stopped {waited:?} after the last request"
        );
        assert_eq!(report.status, MissionStatus::Aborted, "{report:?}");
        assert_eq!(report.stop_cause, StopCause::LinkLost);
    }

    #[test]
    fn hello_ping_and_a_short_mission_that_reaches_its_goal() {
        let mut remote = Remote::over(SimLink::spawn(0).unwrap());
        let info = remote.hello().unwrap();
        assert_eq!(info.build, Build::Host);
        assert_eq!(info.protocol_version, PROTOCOL_VERSION);
        assert!(info.grid_capacity_cells >= 300 * 300);
        assert!(remote.ping(7).is_ok());

        // A tiny world: one wall between start and goal, the same wall known and real.
        let wall = [
            PointM::new(2.0, 3.0),
            PointM::new(4.0, 3.0),
            PointM::new(4.0, 3.2),
            PointM::new(2.0, 3.2),
        ];
        let map = MapParams {
            robot_radius_m: 0.35,
            ..MapParams::default()
        };
        remote.call(Request::SetParams(map)).unwrap();
        let reply = remote
            .call(Request::WorldChunk {
                first_vertex: 0,
                vertices: heapless::Vec::from_slice(&wall).unwrap(),
                last: true,
            })
            .unwrap();
        assert!(
            matches!(reply, Reply::Obstacles { polygons: 1, .. }),
            "{reply:?}"
        );
        let setup = tiny_mission(twil_core::failsafe::LinkLossPolicy::NEVER);
        assert_eq!(remote.call(Request::SetMission(setup)).unwrap(), Reply::Ack);
        assert_eq!(remote.call(Request::StartMission).unwrap(), Reply::Ack);
        let deadline = Instant::now() + Duration::from_secs(60);
        let mut poses = 0;
        let report = loop {
            let t = if !remote.telemetry.is_empty() {
                remote.telemetry.remove(0)
            } else {
                match remote.next_frame(deadline).unwrap().unwrap() {
                    twil_core::link::DeviceFrame::Telemetry(t) => t,
                    other => panic!("unasked reply {other:?}"),
                }
            };
            match t {
                Telemetry::Pose(_) => poses += 1,
                Telemetry::Finished(report) => break report,
                _ => {}
            }
        };
        assert_eq!(report.status, MissionStatus::Reached, "{report:?}");
        assert!(poses > 10, "{poses} poses");
        // The device answers after the mission too.
        assert!(remote.ping(8).is_ok());
    }
}

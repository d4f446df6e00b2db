//! Tests of `remote`.

use super::*;

#[test]
fn remote_specs_parse() {
    assert_eq!("qemu".parse::<RemoteSpec>().unwrap(), RemoteSpec::Qemu);
    assert_eq!("sim".parse::<RemoteSpec>().unwrap(), RemoteSpec::Sim(0));
    assert_eq!("sim:10".parse::<RemoteSpec>().unwrap(), RemoteSpec::Sim(10));
    assert!("sim:0".parse::<RemoteSpec>().is_err());
    assert!("sim:fast".parse::<RemoteSpec>().is_err());
    assert_eq!(
        "tcp:127.0.0.1:4000".parse::<RemoteSpec>().unwrap(),
        RemoteSpec::Tcp("127.0.0.1:4000".into())
    );
    assert_eq!(
        "/dev/ttyUSB0".parse::<RemoteSpec>().unwrap(),
        RemoteSpec::Serial("/dev/ttyUSB0".into())
    );
    assert!("tcp:nohost".parse::<RemoteSpec>().is_err());
    assert!("".parse::<RemoteSpec>().is_err());
    assert_eq!(
        "COM3".parse::<RemoteSpec>().unwrap(),
        RemoteSpec::Serial("COM3".into())
    );
    // A misspelt keyword is not taken for a serial port: the error suggests the keyword.
    for (typo, keyword) in [
        ("qmeu", "qemu"),
        ("QEMU", "qemu"),
        ("sm", "sim"),
        ("tpc:", "tcp:"),
    ] {
        let e = typo.parse::<RemoteSpec>().unwrap_err().to_string();
        assert!(
            e.contains(&format!("did you mean `{keyword}`?")),
            "{typo}: {e}"
        );
    }
    let e = "bluetooth".parse::<RemoteSpec>().unwrap_err().to_string();
    assert!(
        e.contains("expected `qemu`") && !e.contains("did you mean"),
        "{e}"
    );
}

/// The firmware's device and planner in this process, behind a byte-stream interface.
struct Loopback {
    device: Box<twil_core::link::mcu::McuDevice>,
    planner: Box<twil_core::link::mcu::McuPlanner>,
    out: std::collections::VecDeque<u8>,
    /// Flip a bit in the next write (a line error).
    corrupt_next: std::sync::Arc<std::sync::atomic::AtomicBool>,
    /// Lose the device's next replies (this many).
    lose_replies: std::sync::Arc<std::sync::atomic::AtomicU32>,
}

impl Loopback {
    fn new() -> Self {
        Self {
            device: Box::new(twil_core::link::mcu::McuDevice::new(DeviceInfo::default())),
            planner: Box::new(twil_core::link::mcu::McuPlanner::new()),
            out: Default::default(),
            corrupt_next: Default::default(),
            lose_replies: Default::default(),
        }
    }
}

impl Write for Loopback {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        let mut bytes = bytes.to_vec();
        if self
            .corrupt_next
            .swap(false, std::sync::atomic::Ordering::Relaxed)
        {
            let last = bytes.len() - 2;
            bytes[last] ^= 0x08;
        }
        let out = &mut self.out;
        let lose = &self.lose_replies;
        self.device
            .receive(&bytes, &mut *self.planner, &mut || 0, &mut |b: &[u8]| {
                let lost = lose
                    .fetch_update(
                        std::sync::atomic::Ordering::Relaxed,
                        std::sync::atomic::Ordering::Relaxed,
                        |n| n.checked_sub(1),
                    )
                    .is_ok();
                if !lost {
                    out.extend(b)
                }
            });
        Ok(bytes.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Read for Loopback {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.out.is_empty() {
            return Err(std::io::ErrorKind::WouldBlock.into());
        }
        let n = buf.len().min(self.out.len());
        for (b, o) in buf.iter_mut().zip(self.out.drain(..n)) {
            *b = o;
        }
        Ok(n)
    }
}

#[test]
fn remote_over_an_in_process_device_uploads_plans_and_reads_back() {
    let mut remote = Remote::over(Loopback::new());
    let info = remote.hello().unwrap();
    assert_eq!(
        info.grid_capacity_cells as usize,
        twil_core::link::mcu::GRID_WORDS * 32
    );
    assert!(remote.ping(9).is_ok());

    let mut obstacles = Obstacles::new();
    // A wall with a 40-vertex outline (two chunks).
    let wall: Vec<PointM> = (0..40)
        .map(|i| PointM::new(3.0 + i as f32 * 0.2, if i % 2 == 0 { 7.0 } else { 7.2 }))
        .collect();
    obstacles.push(&wall).unwrap();
    let params = MapParams {
        robot_radius_m: 0.3,
        ..MapParams::default()
    };
    remote.upload_world(params, &obstacles).unwrap();

    let mut grid =
        twil_core::grid::Grid300::new(twil_core::grid::GridGeometry::seed_default()).unwrap();
    let half = grid.geometry().expansion_cells(0.3);
    twil_core::raster::mark_polygon(&mut grid, &wall, half);
    let (w, h, words) = remote.read_map().unwrap();
    assert_eq!((w, h), (300, 300));
    assert_eq!(&words[..], grid.words());

    let (start, goal) = (PointM::new(7.0, 2.0), PointM::new(7.5, 13.0));
    let planned = remote.plan(PlannerKind::AStar, start, goal).unwrap();
    let mut planner = Box::new(twil_core::link::mcu::McuPlanner::new());
    let mut path = twil_core::plan::PathM::new();
    let report = planner
        .plan(PlannerKind::AStar, &grid, start, goal, &mut path)
        .unwrap();
    assert_eq!(planned.summary.expanded, report.expanded);
    assert_eq!(planned.path, path.to_vec());

    // Writing the map back replaces it.
    remote.write_map(&vec![0u32; words.len()]).unwrap();
    assert!(remote.read_map().unwrap().2.iter().all(|&w| w == 0));

    // Device errors become readable `Err`s; the link keeps working.
    let e = remote.call(Request::ReadPath { offset: 5000 }).unwrap_err();
    assert!(e.to_string().starts_with("read from 5000"), "{e}");
    assert!(remote.ping(10).is_ok());
}

#[test]
fn a_request_damaged_on_the_line_is_sent_again_and_answered() {
    let loopback = Loopback::new();
    let corrupt = loopback.corrupt_next.clone();
    let mut remote = Remote::over(loopback);
    // Damaged: the device's unnumbered error makes the host send it again at once.
    corrupt.store(true, std::sync::atomic::Ordering::Relaxed);
    assert_eq!(
        remote.request(Request::Ping { nonce: 1 }).unwrap(),
        Reply::Pong { nonce: 1 }
    );
    assert_eq!(remote.retries(), 1);
    match remote.unmatched_errors.last() {
        Some(Reply::Error(e)) => assert_eq!(e.code, twil_core::link::ErrorCode::BadCrc),
        other => panic!("{other:?}"),
    }
    // After a stale partial frame as well.
    remote.send_raw(&[0x05, 0x01, 0x02]).unwrap();
    corrupt.store(true, std::sync::atomic::Ordering::Relaxed);
    assert_eq!(
        remote.request(Request::Ping { nonce: 2 }).unwrap(),
        Reply::Pong { nonce: 2 }
    );
    assert!(remote.ping(3).is_ok());
}

#[test]
fn a_lost_reply_is_asked_again_and_the_request_runs_once() {
    let loopback = Loopback::new();
    let lose = loopback.lose_replies.clone();
    let mut remote = Remote::over(loopback);
    remote.hello().unwrap();
    let square = [
        PointM::new(1.0, 1.0),
        PointM::new(2.0, 1.0),
        PointM::new(2.0, 2.0),
        PointM::new(1.0, 2.0),
    ];
    // The reply to the closing chunk is lost: the host sends it again after the silence
    // and gets the same reply, where a second execution would be out of order.
    lose.store(1, std::sync::atomic::Ordering::Relaxed);
    let t0 = Instant::now();
    remote.upload_polygon(&square).unwrap();
    assert!(t0.elapsed() >= RETRY_AFTER, "{:?}", t0.elapsed());
    assert_eq!(remote.retries(), 1);
    match remote.call(Request::Status).unwrap() {
        Reply::Status(s) => {
            assert_eq!((s.polygons, s.vertices, s.pending_vertices), (1, 4, 0));
        }
        other => panic!("{other:?}"),
    }
}

/// A device that never answers: the host gives up after the timeout, having sent again.
struct Silent(std::sync::Arc<std::sync::atomic::AtomicU32>);
impl Write for Silent {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}
impl Read for Silent {
    fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
        std::thread::sleep(Duration::from_millis(5));
        Err(std::io::ErrorKind::WouldBlock.into())
    }
}

#[test]
fn a_silent_device_gets_the_request_again_then_a_clear_error() {
    let writes = std::sync::Arc::new(std::sync::atomic::AtomicU32::new(0));
    let mut remote = Remote::over(Silent(writes.clone()));
    remote.set_timeout(Duration::from_millis(1600));
    let e = remote.request(Request::Status).unwrap_err();
    // Sends at 0, 0.5 s and 1.5 s (the wait doubles).
    assert_eq!(writes.load(std::sync::atomic::Ordering::Relaxed), 3);
    assert_eq!(remote.retries(), 2);
    assert!(
        e.to_string()
            .starts_with("no reply from the device within 1.6 s (request 1 sent 3 times)"),
        "{e:#}"
    );
}

#[test]
fn a_missing_serial_port_is_a_clear_error() {
    let e = Remote::open(&RemoteSpec::Serial("/dev/twil-no-such-port".into()))
        .err()
        .expect("no such port");
    assert!(
        format!("{e:#}").contains("cannot open serial port /dev/twil-no-such-port"),
        "{e:#}"
    );
}

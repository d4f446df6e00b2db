//! Foxglove recordings and the live view: `twil simulate --record` read back with the `mcap`
//! crate and checked against the run's own files, `twil plan --record`, and a WebSocket
//! client subscribed to `twil simulate --live` (see docs/recording.md).

use crate::common;

use std::collections::{BTreeMap, BTreeSet};
use std::io::{BufRead, BufReader};
use std::net::TcpListener;
use std::path::Path;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

/// Per topic: schema name, schema encoding, message encoding, message count and log times.
#[derive(Debug, Default)]
struct TopicInfo {
    schema: String,
    schema_encoding: String,
    message_encoding: String,
    log_times_ns: Vec<u64>,
    last_data: Vec<u8>,
}

fn read_mcap(path: &Path) -> BTreeMap<String, TopicInfo> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut topics: BTreeMap<String, TopicInfo> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).expect("an MCAP file") {
        let message = message.expect("a readable message");
        let info = topics.entry(message.channel.topic.clone()).or_default();
        if let Some(schema) = &message.channel.schema {
            info.schema.clone_from(&schema.name);
            info.schema_encoding.clone_from(&schema.encoding);
        }
        info.message_encoding
            .clone_from(&message.channel.message_encoding);
        info.log_times_ns.push(message.log_time);
        info.last_data = message.data.to_vec();
    }
    topics
}

fn count(topics: &BTreeMap<String, TopicInfo>, topic: &str) -> usize {
    topics.get(topic).map_or(0, |t| t.log_times_ns.len())
}

const ALL_TOPICS: [&str; 10] = [
    "/band", "/control", "/map", "/plan", "/pose", "/prefix", "/sonar", "/status", "/tf", "/world",
];

#[test]
fn simulate_record_matches_the_run_summary_and_csv() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("office");
    let mcap_path = tmp.path().join("office.mcap");
    let o = common::twil()
        .args(["simulate", "--real"])
        .arg(common::world("office.da"))
        .arg("--params")
        .arg(common::world("office.par"))
        .arg("--out")
        .arg(&out)
        .arg("--record")
        .arg(&mcap_path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.starts_with("reached: "), "{stdout}");
    let recorded_line = stdout
        .lines()
        .find(|l| l.starts_with("recorded "))
        .unwrap_or_else(|| panic!("no `recorded` line: {stdout}"));
    assert!(recorded_line.contains(" MB; messages: "), "{recorded_line}");

    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    let topics = read_mcap(&mcap_path);

    let names: BTreeSet<&str> = topics.keys().map(String::as_str).collect();
    assert_eq!(names, ALL_TOPICS.into_iter().collect());
    // A finished file: the summary section (statistics, chunk index) that lets the Foxglove
    // app seek, counting every message read, in zstd chunks.
    let bytes = std::fs::read(&mcap_path).unwrap();
    let mcap_summary = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("a summary section");
    let stats = mcap_summary.stats.expect("statistics");
    let messages: usize = topics.values().map(|t| t.log_times_ns.len()).sum();
    assert_eq!(stats.message_count as usize, messages);
    assert_eq!(stats.channel_count, 10);
    assert!(!mcap_summary.chunk_indexes.is_empty());
    assert!(mcap_summary
        .chunk_indexes
        .iter()
        .all(|c| c.compression == "zstd"));
    let expected_schemas = [
        ("/map", "foxglove.Grid"),
        ("/world", "foxglove.SceneUpdate"),
        ("/plan", "foxglove.SceneUpdate"),
        ("/prefix", "foxglove.SceneUpdate"),
        ("/band", "foxglove.SceneUpdate"),
        ("/tf", "foxglove.FrameTransform"),
        ("/pose", "foxglove.PoseInFrame"),
        ("/sonar", "foxglove.PointCloud"),
    ];
    for (topic, schema) in expected_schemas {
        let t = &topics[topic];
        assert_eq!(t.schema, schema, "{topic}");
        assert_eq!(t.message_encoding, "protobuf", "{topic}");
    }
    for (topic, ends) in [("/status", "StatusMessage"), ("/control", "ControlMessage")] {
        let t = &topics[topic];
        assert!(t.schema.ends_with(ends), "{topic}: {}", t.schema);
        assert_eq!(t.schema_encoding, "jsonschema", "{topic}");
        assert_eq!(t.message_encoding, "json", "{topic}");
    }

    // One pose, one transform and one controller sample per trajectory row.
    assert_eq!(count(&topics, "/pose"), rows.len());
    assert_eq!(count(&topics, "/tf"), rows.len());
    assert_eq!(count(&topics, "/control"), rows.len());
    // One point cloud per sweep, one band per sweep started, one plan and prefix per plan.
    let sweeps = summary["sweeps"].as_u64().unwrap() as usize;
    let plans = summary["plans"].as_u64().unwrap() as usize;
    assert!(sweeps >= summary["stops"].as_u64().unwrap() as usize);
    assert_eq!(count(&topics, "/sonar"), sweeps);
    let bands = count(&topics, "/band");
    assert!(
        bands == sweeps || bands == sweeps + 1,
        "{bands} bands, {sweeps} sweeps"
    );
    assert_eq!(count(&topics, "/plan"), plans);
    assert_eq!(count(&topics, "/prefix"), plans);
    assert_eq!(count(&topics, "/world"), 1);
    // The map only when it changed: the start, then at most once per sweep.
    let maps = count(&topics, "/map");
    assert!(
        maps >= 2 && maps <= sweeps + 1,
        "{maps} maps, {sweeps} sweeps"
    );

    // Mission time: the poses run from 0 to the end of the run, 50 ms apart (to the
    // 30 µs an f32 time keeps at 500 s), and the last
    // /status says how the run ended.
    let pose_times = &topics["/pose"].log_times_ns;
    assert_eq!(pose_times[0], 0);
    let sim_time_s = summary["sim_time_s"].as_f64().unwrap();
    let last_s = *pose_times.last().unwrap() as f64 / 1e9;
    assert!(
        (last_s - sim_time_s).abs() < 0.01,
        "{last_s} vs {sim_time_s}"
    );
    assert!(pose_times
        .windows(2)
        .all(|w| (w[1] - w[0]).abs_diff(50_000_000) < 100_000));
    let last_status: Value = serde_json::from_slice(&topics["/status"].last_data).unwrap();
    assert_eq!(last_status["status"], "reached");
    // The controller's signals are plottable numbers, as in the CSV.
    let control: Value = serde_json::from_slice(&topics["/control"].last_data).unwrap();
    for key in [
        "left_voltage_v",
        "right_voltage_v",
        "reference_x_m",
        "left_speed_ref_rad_s",
    ] {
        assert!(control[key].is_number(), "{key}: {control}");
    }

    // Read back with the Foxglove SDK's decoders (`twil view`'s reader), the contents match
    // the run: every pose of the CSV, the last one where the CSV ends, start and goal of the
    // .par, a 300 x 300 map, and a last plan that ends at the goal.
    let state = twil_host::record::read::read(&mcap_path, None).unwrap();
    assert_eq!(state.trail.len(), rows.len());
    let last_row: Vec<f32> = rows
        .last()
        .unwrap()
        .split(',')
        .take(3)
        .map(|v| v.parse().unwrap())
        .collect();
    let last_pose = state.trail.last().unwrap();
    assert!(
        (last_pose.x_m - last_row[1]).abs() < 1e-3,
        "{last_pose:?} vs {last_row:?}"
    );
    assert!(
        (last_pose.y_m - last_row[2]).abs() < 1e-3,
        "{last_pose:?} vs {last_row:?}"
    );
    let goal = state.goal.unwrap();
    assert_eq!((goal.x_m, goal.y_m), (13.5, 13.0));
    let start = state.start.unwrap();
    assert_eq!((start.x_m, start.y_m), (1.5, 1.5));
    let map = state.map.as_ref().unwrap();
    assert_eq!(
        (map.geometry().width(), map.geometry().height()),
        (300, 300)
    );
    assert!(map.count_occupied() > 0);
    let plan_end = *state.plan.last().unwrap();
    assert!(plan_end.distance_m(goal) < 0.1, "{plan_end:?}");
    assert_eq!(state.status.as_ref().unwrap().status, "reached");
    assert_eq!(state.real.len(), 9);
    assert!((state.body_radius_m.unwrap() - 0.3).abs() < 1e-5);

    // `twil view` at 60 s: the poses up to then, and a picture with the trail and the robot.
    let png = tmp.path().join("view.png");
    let o = common::twil()
        .arg("view")
        .arg(&mcap_path)
        .arg("--png")
        .arg(&png)
        .args(["--at", "60", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let view: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(view["poses"], 1201, "{view}");
    assert_eq!(view["status"], "running", "{view}");
    let image = image::open(&png).unwrap().to_rgb8();
    let has = |c: image::Rgb<u8>| image.pixels().any(|p| *p == c);
    use twil_host::picture::palette;
    for (what, colour) in [
        ("trail", palette::TRAIL),
        ("robot", palette::ROBOT),
        ("start", palette::START),
        ("goal", palette::GOAL),
        ("scale bar", palette::SCALE_BAR),
    ] {
        assert!(has(colour), "no {what} pixel in the view");
    }
}

#[test]
fn mission_record_follows_the_telemetry() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("mission.mcap");
    let o = common::twil()
        .args(["mission", "--remote", "sim", "--json", "--real"])
        .arg(common::world("office.da"))
        .arg("--params")
        .arg(common::world("office.par"))
        .arg("--record")
        .arg(&path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // `--json` keeps stdout to its one object; the recording's line goes to stderr.
    let result: Value = serde_json::from_slice(&o.stdout).expect("one JSON object");
    assert!(String::from_utf8_lossy(&o.stderr).contains("recorded "));
    let topics = read_mcap(&path);
    let names: BTreeSet<&str> = topics.keys().map(String::as_str).collect();
    assert_eq!(names, ALL_TOPICS.into_iter().collect());
    // Poses at 5 Hz over the mission, one plan and prefix per plan, a point cloud per sweep
    // (at least one per stop).
    let sim_time_s = result["sim_time_s"].as_f64().unwrap();
    let poses = count(&topics, "/pose") as f64;
    assert!(
        (poses - sim_time_s * 5.0).abs() <= 3.0,
        "{poses} poses in {sim_time_s} s"
    );
    assert_eq!(count(&topics, "/tf") as f64, poses);
    // One plan and prefix per plan the device reported: every plan but those replaced within
    // one step of the mission (the evidence map replans round a suspect at once), whose
    // `Planned` note the next one overwrote.
    let plans = result["replans"].as_u64().unwrap() as usize + 1;
    let recorded = count(&topics, "/plan");
    assert!(
        recorded <= plans && recorded * 10 >= plans * 9,
        "{recorded} of {plans}"
    );
    assert_eq!(count(&topics, "/prefix"), recorded);
    assert!(count(&topics, "/sonar") >= result["stops"].as_u64().unwrap() as usize);
    let last_status: Value = serde_json::from_slice(&topics["/status"].last_data).unwrap();
    assert_eq!(last_status["status"], "reached");
    // The telemetry carries the voltages, not the references.
    let control: Value = serde_json::from_slice(&topics["/control"].last_data).unwrap();
    assert!(control["left_voltage_v"].is_number(), "{control}");
    assert!(control["reference_x_m"].is_null(), "{control}");
}

/// Stops the mission once mission time passes `stop_at_s`; keeps what it was shown.
struct StopAt {
    stop_at_s: f32,
    rows: Vec<twil_host::sim::TrajectoryRow>,
    sweeps_done: usize,
    started: bool,
}

impl twil_host::sim::Observer for StopAt {
    fn start(&mut self, _: &twil_core::mission::Mission400) {
        self.started = true;
    }
    fn tick(&mut self, view: &twil_host::sim::TickView) -> std::ops::ControlFlow<()> {
        self.sweeps_done += view
            .events
            .iter()
            .filter(|e| matches!(e, twil_core::mission::MissionEvent::SweepDone { .. }))
            .count();
        if view.t_s >= self.stop_at_s {
            std::ops::ControlFlow::Break(())
        } else {
            std::ops::ControlFlow::Continue(())
        }
    }
    fn row(&mut self, row: &twil_host::sim::TrajectoryRow) {
        self.rows.push(*row);
    }
}

#[test]
fn an_observer_sees_every_row_and_can_stop_the_mission() {
    use clap::Parser;
    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: twil_host::cmd::simulate::Args,
    }
    let real = common::world("office.da").display().to_string();
    let params = common::world("office.par").display().to_string();
    let cli = Cli::parse_from(["twil", "--real", &real, "--params", &params]);
    let setup = twil_host::cmd::simulate::setup_from_args(&cli.args).unwrap();
    let mut observer = StopAt {
        stop_at_s: 30.0,
        rows: Vec::new(),
        sweeps_done: 0,
        started: false,
    };
    let result =
        twil_host::sim::run_observed(&setup, &mut twil_host::sim::NoProgress, &mut observer)
            .unwrap();
    assert!(observer.started);
    assert_eq!(result.status, twil_host::sim::SimStatus::Aborted);
    assert!(
        (result.sim_time_s - 30.0).abs() < 0.06,
        "{}",
        result.sim_time_s
    );
    assert_eq!(observer.rows, result.trajectory);
    assert_eq!(observer.sweeps_done, result.sweeps as usize);
    assert!(result.sweeps >= 1);
}

#[test]
fn trajectory_csv_carries_references_voltages_and_phase() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("corridor");
    let o = common::twil()
        .args(["simulate", "--real"])
        .arg(common::world("corridor.da"))
        .arg("--params")
        .arg(common::world("corridor.par"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("t,x,y,theta,ref_x,ref_y,left_speed_ref_rad_s,right_speed_ref_rad_s,left_v,right_v,phase")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(rows.iter().all(|r| r.len() == 11));
    // The first row is the start: no controller step yet.
    assert_eq!(rows[0][4], "");
    let phases: BTreeSet<&str> = rows.iter().map(|r| r[10]).collect();
    // The last row is the period before the mission ended: no row is in phase `done`.
    for phase in ["sweep", "plan", "follow", "settle"] {
        assert!(phases.contains(phase), "{phase} missing from {phases:?}");
    }
    let following: Vec<&Vec<&str>> = rows.iter().filter(|r| r[10] == "follow").collect();
    let volts = |r: &Vec<&str>, i: usize| r[i].parse::<f64>().unwrap();
    assert!(following
        .iter()
        .any(|r| volts(r, 8) > 0.5 && volts(r, 9) > 0.5));
    assert!(following.iter().all(|r| r[4].parse::<f64>().is_ok()));
}

#[test]
fn plan_record_has_one_message_per_topic() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("plan.mcap");
    let o = common::twil()
        .args(["plan", "--world"])
        .arg(common::world("office.da"))
        .arg("--params")
        .arg(common::world("office.par"))
        .arg("--record")
        .arg(&path)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let topics = read_mcap(&path);
    let names: BTreeSet<&str> = topics.keys().map(String::as_str).collect();
    assert_eq!(names, ["/map", "/plan", "/world"].into_iter().collect());
    for t in topics.values() {
        assert_eq!(t.log_times_ns, vec![0]);
    }
    assert_eq!(topics["/map"].schema, "foxglove.Grid");
    assert_eq!(topics["/plan"].schema, "foxglove.SceneUpdate");
}

#[test]
fn the_layout_shows_only_topics_twil_writes() {
    let path = common::repo().join("docs/foxglove-layout.json");
    let layout: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let configs = layout["configById"].as_object().unwrap();
    let three_d = configs
        .iter()
        .find(|(k, _)| k.starts_with("3D!"))
        .expect("a 3D panel")
        .1;
    let shown: BTreeSet<&str> = three_d["topics"]
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    for topic in ["/map", "/world", "/plan", "/prefix", "/sonar", "/band"] {
        assert!(shown.contains(topic), "3D panel lacks {topic}");
    }
    assert!(shown.iter().all(|t| ALL_TOPICS.contains(t)), "{shown:?}");
    let plot = configs
        .iter()
        .find(|(k, _)| k.starts_with("Plot!"))
        .expect("a plot panel")
        .1;
    for path in plot["paths"].as_array().unwrap() {
        assert!(path["value"].as_str().unwrap().starts_with("/control."));
    }
    let raw = configs
        .iter()
        .find(|(k, _)| k.starts_with("RawMessages!"))
        .expect("a raw-messages panel")
        .1;
    assert_eq!(raw["topicPath"], "/status");
}

#[test]
fn a_record_path_that_cannot_be_created_is_named() {
    let tmp = tempfile::tempdir().unwrap();
    let blocker = tmp.path().join("not-a-dir");
    std::fs::write(&blocker, "a file").unwrap();
    let path = blocker.join("office.mcap");
    let o = common::twil()
        .args(["simulate", "--real"])
        .arg(common::world("office.da"))
        .arg("--params")
        .arg(common::world("office.par"))
        .arg("--record")
        .arg(&path)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(o.stdout.is_empty());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains(&format!("--record {}", path.display())),
        "{stderr}"
    );
}

#[test]
fn live_paces_mission_time_to_the_wall_clock() {
    let started = Instant::now();
    let o = common::twil()
        .args(["simulate", "--real"])
        .arg(common::world("corridor.da"))
        .arg("--params")
        .arg(common::world("corridor.par"))
        .args(["--live", "127.0.0.1:0", "--speed", "200"])
        .output()
        .unwrap();
    let wall_s = started.elapsed().as_secs_f64();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    // "reached: 28.90 m travelled in 402.5 s simulated; …"
    let sim_s: f64 = stdout
        .split(" s simulated")
        .next()
        .and_then(|head| head.rsplit(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no simulated time in {stdout}"));
    assert!(
        wall_s >= sim_s / 200.0,
        "{wall_s} s of wall time for {sim_s} s at 200x"
    );
    assert!(stdout.contains("served live; messages: /map "), "{stdout}");
}

/// A TCP port free right now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Kills the child if the test fails before it ends.
struct Reap(Child);

impl Drop for Reap {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn live_server_streams_poses_and_ctrl_c_ends_cleanly() {
    use tungstenite::client::IntoClientRequest;
    use tungstenite::Message;

    let tmp = tempfile::tempdir().unwrap();
    let mcap_path = tmp.path().join("live.mcap");
    let port = free_port();
    let child = common::twil()
        .args(["simulate", "--real"])
        .arg(common::world("office.da"))
        .arg("--params")
        .arg(common::world("office.par"))
        .args(["--live", &format!("127.0.0.1:{port}"), "--speed", "50"])
        .arg("--record")
        .arg(&mcap_path)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut child = Reap(child);
    // The server is up once twil says so on stderr.
    let mut stderr = BufReader::new(child.0.stderr.take().unwrap());
    let mut line = String::new();
    stderr.read_line(&mut line).unwrap();
    assert!(line.contains(&format!("ws://127.0.0.1:{port}")), "{line}");

    // Connect late: the world has gone out (at mission time 0) before this client was there.
    std::thread::sleep(Duration::from_millis(300));
    let mut request = format!("ws://127.0.0.1:{port}")
        .into_client_request()
        .unwrap();
    // The SDK's server speaks the Foxglove WebSocket protocol v1 under the subprotocol
    // `foxglove.sdk.v1` (the protocol's former name, `foxglove.websocket.v1`, is refused).
    request
        .headers_mut()
        .insert("Sec-WebSocket-Protocol", "foxglove.sdk.v1".parse().unwrap());
    let (mut socket, _) = tungstenite::connect(request).expect("connect to --live");
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut pose_channel = None;
    let mut pose_times_ns: Vec<u64> = Vec::new();
    let mut world_times_ns: Vec<u64> = Vec::new();
    while pose_times_ns.len() < 5 || world_times_ns.is_empty() {
        assert!(Instant::now() < deadline, "no poses within 20 s");
        match socket.read().expect("read") {
            Message::Text(text) => {
                let v: Value = serde_json::from_str(text.as_str()).unwrap();
                if v["op"] != "advertise" {
                    continue;
                }
                for ch in v["channels"].as_array().unwrap() {
                    // Subscription 7: the poses; 8: the world, sent once at mission time 0,
                    // before this client connected (the server resends it to late subscribers).
                    let subscription = match ch["topic"].as_str() {
                        Some("/pose") => {
                            assert_eq!(ch["schemaName"], "foxglove.PoseInFrame");
                            pose_channel = ch["id"].as_u64();
                            7
                        }
                        Some("/world") => 8,
                        _ => continue,
                    };
                    let subscribe = serde_json::json!({
                        "op": "subscribe",
                        "subscriptions": [{"id": subscription, "channelId": ch["id"]}],
                    });
                    socket
                        .send(Message::Text(subscribe.to_string().into()))
                        .unwrap();
                }
            }
            // Message data: opcode 1, subscription id (u32 LE), log time (u64 LE), payload.
            Message::Binary(data) if data.first() == Some(&1) && data.len() > 13 => {
                let subscription = u32::from_le_bytes(data[1..5].try_into().unwrap());
                let log_time_ns = u64::from_le_bytes(data[5..13].try_into().unwrap());
                match subscription {
                    7 => pose_times_ns.push(log_time_ns),
                    8 => world_times_ns.push(log_time_ns),
                    other => panic!("data for subscription {other}"),
                }
            }
            _ => {}
        }
    }
    assert!(pose_channel.is_some());
    assert_eq!(
        world_times_ns,
        vec![0],
        "the world, once, stamped mission time 0"
    );
    // Mission time, one controller period (50 ms) apart.
    assert!(pose_times_ns
        .windows(2)
        .all(|w| (w[1] - w[0]).abs_diff(50_000_000) < 100_000));
    drop(socket);

    // Ctrl-C: the mission stops, the recording is closed and readable, exit status 130.
    let pid = child.0.id().to_string();
    let killed = std::process::Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap();
    assert!(killed.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let status = child.0.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{rest}");
    assert!(rest.contains("interrupted"), "{rest}");
    let topics = read_mcap(&mcap_path);
    assert!(count(&topics, "/pose") >= pose_times_ns.len());
    let last_status: Value = serde_json::from_slice(&topics["/status"].last_data).unwrap();
    assert_eq!(last_status["status"], "aborted");
}

/// `twil view` on something that is not a recording, or before its first message, says so
/// and names the file; a negative `--at` is refused.
#[test]
fn view_refuses_what_is_not_a_recording() {
    let tmp = tempfile::tempdir().unwrap();
    let text = tmp.path().join("notes.mcap");
    std::fs::write(&text, "not an mcap file\n").unwrap();
    let png = tmp.path().join("v.png");
    let o = common::twil()
        .arg("view")
        .arg(&text)
        .arg("--png")
        .arg(&png)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("notes.mcap") && err.contains("not an MCAP file"),
        "{err}"
    );
    assert!(!png.exists());
    let o = common::twil()
        .arg("view")
        .arg(&text)
        .arg("--png")
        .arg(&png)
        .arg("--at=-1")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--at -1"));
}

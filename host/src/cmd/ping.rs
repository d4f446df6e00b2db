//! `twil ping --remote …`: check the link to the firmware, print its version and the round trip.

use anyhow::Result;

use crate::remote::{Remote, RemoteSpec};

/// Arguments of `twil ping`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The device: `qemu` (starts QEMU with the firmware), `tcp:HOST:PORT`, or a serial port
    /// (`/dev/ttyUSB0`, 115200 8N1).
    #[arg(long)]
    pub remote: RemoteSpec,
    /// Pings to send.
    #[arg(long, default_value_t = 1)]
    pub count: u32,
    /// Print one JSON object (the device's description and each round trip) instead.
    #[arg(long)]
    pub json: bool,
}

/// Run `twil ping`.
pub fn run(args: Args) -> Result<crate::exit::Ending> {
    let (mut remote, info) = Remote::connect(&args.remote)?;
    let firmware = info.build != twil_core::link::Build::Host;
    // What the parameter store held at boot (protocol 6; see docs/params.md).
    let store = remote.param_store();
    if args.json {
        let mut round_trips_ms = Vec::new();
        for i in 0..args.count {
            let rtt = remote.ping(0x7711_0000 + i)?;
            round_trips_ms.push((rtt.as_secs_f64() * 1e6).round() / 1e3);
        }
        let json = serde_json::json!({
            "protocol_version": info.protocol_version,
            "build": format!("{:?}", info.build).to_lowercase(),
            "grid_capacity_cells": info.grid_capacity_cells,
            "planner_capacity_cells": info.planner_capacity_cells,
            "max_polygons": info.max_polygons,
            "max_vertices": info.max_vertices,
            "max_frame_bytes": info.max_frame_bytes,
            "static_ram_bytes": firmware.then_some(info.static_ram_bytes),
            "param_store": store,
            "round_trips_ms": round_trips_ms,
        });
        println!("{json}");
        return Ok(crate::exit::Ending::Done);
    }
    // The in-process device (`--remote sim`) is no firmware and has no static RAM to report.
    let (who, ram) = if firmware {
        (
            "twil firmware",
            format!(", static RAM {} bytes", info.static_ram_bytes),
        )
    } else {
        ("twil device (in process, no firmware)", String::new())
    };
    let store = store
        .map(|s| format!(", parameter store {s}"))
        .unwrap_or_default();
    println!(
        "{who}: protocol v{}, build {:?}, grid {} cells, planner {} cells, {} polygons / {} vertices, frames up to {} bytes{ram}{store}",
        info.protocol_version,
        info.build,
        info.grid_capacity_cells,
        info.planner_capacity_cells,
        info.max_polygons,
        info.max_vertices,
        info.max_frame_bytes,
    );
    for i in 0..args.count {
        let rtt = remote.ping(0x7711_0000 + i)?;
        println!(
            "ping {}: round trip {:.3} ms",
            i + 1,
            rtt.as_secs_f64() * 1e3
        );
    }
    Ok(crate::exit::Ending::Done)
}

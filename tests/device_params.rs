//! The device's parameters (issue 25, part 2) over `--remote sim` and the firmware under QEMU:
//! a value set lasts across missions and the next mission uses it; a refused value changes
//! nothing and the refusal names the rule; an unknown name gets the nearest one; `twil param`
//! prints the JSON shapes the issue gives.

use std::time::{Duration, Instant};

use serde_json::Value;
use twil_core::failsafe::LinkLossPolicy;
use twil_core::link::{DeviceFrame, MissionReport, Telemetry};
use twil_core::mission::MissionMode;
use twil_core::params_store::StoreStatus;
use twil_host::remote::{Remote, RemoteSpec, SetOutcome};

use crate::common;
use crate::firmware_qemu::start_mission_on;

/// A whole mission on `world` over `remote`: its final report.
fn mission(remote: &mut Remote, world: &str) -> MissionReport {
    start_mission_on(remote, world, MissionMode::Stop, LinkLossPolicy::NEVER);
    let deadline = Instant::now() + Duration::from_secs(600);
    loop {
        match remote.next_frame(deadline).expect("telemetry") {
            Ok(DeviceFrame::Telemetry(Telemetry::Finished(report))) => return report,
            Ok(_) => {}
            Err(fault) => panic!("damaged frame from the device: {fault:?}"),
        }
    }
}

fn set(remote: &mut Remote, name: &str, value: f32) -> SetOutcome {
    remote.param_set(name, value).expect("ParamSet answered")
}

/// What every device must do with its parameters; `store` is what its store held at boot.
fn set_get_refuse_and_suggest(remote: &mut Remote, store: StoreStatus) {
    let rows = remote.param_list().unwrap();
    assert_eq!(rows.len(), twil_core::params::PARAM_COUNT);
    assert!(rows.iter().all(|r| r.store == Some(store)), "{:?}", rows[0]);
    assert!(rows.iter().all(|r| r.value == r.default));
    match set(remote, "wheel_radius_m", 0.07) {
        SetOutcome::Set(e) => assert_eq!((e.value, e.store), (0.07, Some(StoreStatus::Ok))),
        other => panic!("{other:?}"),
    }
    // Refused: nothing changes, and the reply names the rule.
    match set(remote, "wheel_radius_m", 2.0) {
        SetOutcome::Refused(r) => {
            assert_eq!(r.name.as_str(), "wheel_radius_m");
            assert_eq!(r.rule.as_str(), "above 0 and at most 1 m");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(remote.param_get("wheel_radius_m").unwrap().value, 0.07);
    let e = remote.param_get("wheel_radius").unwrap_err().to_string();
    assert_eq!(
        e,
        "the device has no parameter `wheel_radius`; did you mean `wheel_radius_m`?"
    );
}

#[test]
fn sim_set_lasts_across_missions_and_the_next_mission_uses_it() {
    let (mut remote, _) = Remote::connect(&RemoteSpec::Sim(0)).unwrap();
    set_get_refuse_and_suggest(&mut remote, StoreStatus::Empty);
    let before = mission(&mut remote, "office");
    // A coarser neck step: every sweep of the next mission reads half as many positions
    // (symmetric layout: 2n + 1 readings, n whole steps in the half-sweep; a normal sweep
    // is ±95 degrees, a full one ±180).
    let readings = |r: &MissionReport, normal: u32, full: u32| {
        r.stats.stops * normal + r.stats.full_sweeps * full
    };
    assert_eq!(
        before.stats.readings,
        readings(&before, 105, 201),
        "{:?}",
        before.stats
    );
    assert!(matches!(
        set(&mut remote, "neck_step_deg", 3.6),
        SetOutcome::Set(_)
    ));
    let after = mission(&mut remote, "office");
    assert_eq!(
        after.stats.readings,
        readings(&after, 53, 101),
        "{:?}",
        after.stats
    );
    let again = mission(&mut remote, "office");
    assert_eq!(again.stats.readings, after.stats.readings);
    assert_eq!(remote.param_get("wheel_radius_m").unwrap().value, 0.07);
    assert_eq!(remote.param_get("neck_step_deg").unwrap().value, 3.6);
}

#[test]
fn qemu_firmware_sets_stores_and_refuses_like_the_sim() {
    let (mut remote, _) = match Remote::connect(&RemoteSpec::Qemu) {
        Ok(r) => r,
        Err(e) => panic!("cannot run the firmware under QEMU: {e:#} (run `cargo xtask firmware`)"),
    };
    // The QEMU build's store is in RAM: empty at every boot.
    set_get_refuse_and_suggest(&mut remote, StoreStatus::Empty);
    // While a mission runs a set is refused; after it, the value is still there.
    start_mission_on(
        &mut remote,
        "office",
        MissionMode::Stop,
        LinkLossPolicy::NEVER,
    );
    let e = remote
        .param_set("wheel_radius_m", 0.08)
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "parameter `wheel_radius_m`: not now: a mission is running"
    );
    remote.call(twil_core::link::Request::AbortMission).unwrap();
    assert_eq!(remote.param_get("wheel_radius_m").unwrap().value, 0.07);
}

fn json(args: &[&str]) -> Value {
    let out = common::twil().args(args).output().expect("run twil");
    assert!(out.status.success(), "{out:?}");
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

#[test]
fn twil_param_prints_the_issues_json_shapes() {
    let v = json(&["param", "list", "--remote", "sim", "--json"]);
    let rows = v["params"].as_array().unwrap();
    assert_eq!(rows.len(), twil_core::params::PARAM_COUNT);
    let mut keys: Vec<&str> = rows[1]
        .as_object()
        .unwrap()
        .keys()
        .map(|k| k.as_str())
        .collect();
    keys.sort();
    assert_eq!(keys, ["default", "max", "min", "name", "unit", "value"]);
    assert_eq!(rows[1]["name"], "wheel_radius_m");
    assert_eq!(v["store"], "empty");
    let v = json(&["param", "get", "sonar_beam", "--remote", "sim", "--json"]);
    assert_eq!(v, serde_json::json!({"name": "sonar_beam", "value": false}));
    let v = json(&[
        "param",
        "set",
        "sweep_layout",
        "seed",
        "--remote",
        "sim",
        "--json",
    ]);
    assert_eq!(
        v,
        serde_json::json!({"name": "sweep_layout", "value": "seed"})
    );
    let out = common::twil()
        .args(["param", "set", "sonar_min_range_m", "2", "--remote", "sim"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        String::from_utf8_lossy(&out.stderr).trim(),
        "twil: the device refuses `sonar_min_range_m` = 2: with it `sonar_range_m` = 1.5 \
         breaks its rule (above sonar_min_range_m and at most 6 m); nothing changed"
    );
}

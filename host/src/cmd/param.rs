//! `twil param list|get NAME|set NAME VALUE --remote R [--json]`: the device's parameters.
//!
//! Why: a user tunes the robot on the bench without reflashing (issue 25, part 2): the names
//! are the robot file's keys, the device validates with the same rules (a refused value
//! changes nothing and the reply names the rule) and keeps what it accepts in its flash (a RAM
//! store under QEMU and `--remote sim`, which lasts until the device resets). The requests
//! are `ParamList` / `ParamGet` / `ParamSet` (docs/protocol.md); the device side is
//! `twil_core::link::params`.
//!
//! Measured: `tests/suite.rs` module `params` (over `--remote sim` and QEMU) and the console
//! examples of docs/params.md.

use anyhow::{anyhow, bail, Result};
use twil_core::link::ParamEntry;
use twil_core::params::{self, Kind, Param};
use twil_core::params_store::StoreStatus;

use crate::remote::{Remote, RemoteSpec, SetOutcome};

/// Arguments of `twil param`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub action: Action,
    /// The device: `qemu`, `sim`, `tcp:HOST:PORT` or a serial port (required).
    #[arg(long, global = true)]
    pub remote: Option<RemoteSpec>,
    /// Print JSON: `list` gives `{"params":[{"name","value","unit","default","min","max"}],
    /// "store"}`, `get` and `set` give `{"name","value"}`.
    #[arg(long, global = true)]
    pub json: bool,
}

/// What `twil param` does.
#[derive(clap::Subcommand, Debug)]
pub enum Action {
    /// Every parameter of the device: value, unit, default, limits, and its store's status.
    List,
    /// One parameter's value.
    Get {
        /// Its name (the robot file's key).
        name: String,
    },
    /// Set a parameter (validated and stored by the device; the next mission uses it).
    Set {
        /// Its name (the robot file's key).
        name: String,
        /// The value: a number, `true` / `false`, or a choice's name.
        value: String,
    },
}

/// Run `twil param`.
pub fn run(args: Args) -> Result<crate::exit::Ending> {
    let Some(spec) = &args.remote else {
        bail!("twil param: --remote is required (qemu, sim, tcp:HOST:PORT or a serial port)");
    };
    let (mut remote, _) = Remote::connect(spec)?;
    match &args.action {
        Action::List => list(&mut remote, args.json)?,
        Action::Get { name } => {
            let entry = remote.param_get(name)?;
            if args.json {
                println!("{}", value_json(&entry));
            } else {
                println!("{}", line(&entry));
            }
        }
        Action::Set { name, value } => {
            let number = table_value(name, value)?;
            let before = remote.param_get(name)?;
            match remote.param_set(name, number)? {
                SetOutcome::Set(entry) => {
                    if args.json {
                        println!("{}", value_json(&entry));
                    } else {
                        println!(
                            "{} = {}{} (was {}; {})",
                            entry.name,
                            shown(&entry, entry.value),
                            unit(&entry),
                            shown(&before, before.value),
                            match entry.store {
                                Some(_) => "stored on the device",
                                None => "not stored: this device has no store",
                            }
                        );
                    }
                }
                SetOutcome::Refused(r) => bail!("{}", refusal_words(name, value, &r)),
            }
        }
    }
    Ok(crate::exit::Ending::Done)
}

fn list(remote: &mut Remote, json: bool) -> Result<()> {
    let rows = remote.param_list()?;
    let store = rows.first().and_then(|r| r.store);
    if json {
        let params: Vec<serde_json::Value> = rows
            .iter()
            .map(|e| {
                serde_json::json!({
                    "name": e.name.as_str(),
                    "value": json_of(e, e.value),
                    "unit": e.unit.as_str(),
                    "default": json_of(e, e.default),
                    "min": finite(e.min),
                    "max": finite(e.max),
                })
            })
            .collect();
        println!(
            "{}",
            serde_json::json!({"params": params, "store": store_word(store)})
        );
        return Ok(());
    }
    println!("{} parameters; store: {}", rows.len(), store_words(store));
    for e in &rows {
        println!("{}", line(e));
    }
    Ok(())
}

/// The store's status as a JSON word (`null`: no store).
fn store_word(store: Option<StoreStatus>) -> Option<&'static str> {
    store.map(|s| match s {
        StoreStatus::Ok => "ok",
        StoreStatus::Empty => "empty",
        StoreStatus::Corrupt => "corrupt",
        StoreStatus::OldVersion => "old_version",
    })
}

/// The store's status in words, with what it means for the values.
fn store_words(store: Option<StoreStatus>) -> &'static str {
    match store {
        Some(StoreStatus::Ok) => "ok",
        Some(StoreStatus::Empty) => "empty (nothing stored: defaults)",
        Some(StoreStatus::Corrupt) => "corrupt at boot (defaults; the next set erases it)",
        Some(StoreStatus::OldVersion) => "old version at boot (defaults; the next set erases it)",
        None => "none (values last until the device resets)",
    }
}

/// Why the device refused `name` = `text`, in words.
pub fn refusal_words(name: &str, text: &str, r: &twil_core::link::ParamRefusal) -> String {
    if r.name.as_str() == name {
        format!(
            "the device refuses `{name}` = {text}: expected {}; nothing changed",
            r.rule
        )
    } else {
        format!(
            "the device refuses `{name}` = {text}: with it `{}` = {} breaks its rule ({}); nothing changed",
            r.name, r.value, r.rule
        )
    }
}

/// ` unit`, or nothing for a number without one.
fn unit(e: &ParamEntry) -> String {
    if e.unit.is_empty() {
        String::new()
    } else {
        format!(" {}", e.unit)
    }
}

/// One row in words: `name = value unit (default D; rule)`.
fn line(e: &ParamEntry) -> String {
    let unit = unit(e);
    let limits = match params::find(&e.name) {
        Some(p) => p.rule.to_string(),
        None if e.max.is_finite() => format!("{} to {}", e.min, e.max),
        None => format!("{} or more", e.min),
    };
    format!(
        "{} = {}{unit} (default {}; {limits})",
        e.name,
        shown(e, e.value),
        shown(e, e.default)
    )
}

/// The host's row of `e` (the same table as the firmware's, unless the versions differ).
fn row(e: &ParamEntry) -> Option<&'static Param> {
    params::find(&e.name)
}

/// A value as the robot file writes it (`true`, `"seed"`, `0.075`).
fn shown(e: &ParamEntry, value: f32) -> String {
    match row(e) {
        Some(p) => crate::robot_file::toml_text(p, value).replace('"', ""),
        None => format!("{value}"),
    }
}

/// A value as JSON (a boolean, a choice's name, a number).
fn json_of(e: &ParamEntry, value: f32) -> serde_json::Value {
    match row(e) {
        Some(p) => crate::robot_file::json_value(p, value),
        None => finite(value),
    }
}

fn finite(value: f32) -> serde_json::Value {
    if value.is_finite() {
        serde_json::Value::from(format!("{value}").parse::<f64>().unwrap_or(value as f64))
    } else {
        serde_json::Value::Null
    }
}

fn value_json(e: &ParamEntry) -> serde_json::Value {
    serde_json::json!({"name": e.name.as_str(), "value": json_of(e, e.value)})
}

/// `text` as the table's `f32` for parameter `name`: a number; for a flag `true` / `false`;
/// for a choice its name (or index).
fn table_value(name: &str, text: &str) -> Result<f32> {
    let number = text.trim().parse::<f32>().ok().filter(|v| v.is_finite());
    let Some(p) = params::find(name) else {
        // Not in this host's table: the device may know it (it answers for itself).
        return number.ok_or_else(|| anyhow!("`{name}` = {text}: expected a number"));
    };
    let value = match p.kind {
        Kind::Bool => match text.trim() {
            "true" => Some(1.0),
            "false" => Some(0.0),
            _ => number,
        },
        Kind::Choice(_) => p.choice_index(text.trim()).or(number),
        Kind::Real | Kind::Integer => number,
    };
    value.ok_or_else(|| {
        let expected = match p.kind {
            Kind::Bool => "true or false".to_string(),
            Kind::Choice(names) => format!("one of {}", names.join(", ")),
            Kind::Integer => "a whole number".to_string(),
            Kind::Real if p.unit.is_empty() => "a number".to_string(),
            Kind::Real => format!("a number ({})", p.unit),
        };
        anyhow!("`{name}` = {text}: expected {expected}")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_read_as_the_robot_file_writes_them() {
        assert_eq!(table_value("wheel_radius_m", "0.07").unwrap(), 0.07);
        assert_eq!(table_value("sonar_beam", "true").unwrap(), 1.0);
        assert_eq!(table_value("sweep_layout", "seed").unwrap(), 1.0);
        assert_eq!(table_value("sweep_layout", "0").unwrap(), 0.0);
        let e = table_value("sweep_layout", "spiral")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "`sweep_layout` = spiral: expected one of symmetric, seed"
        );
        let e = table_value("wheel_radius_m", "big")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "`wheel_radius_m` = big: expected a number (m)");
        assert!(table_value("wheel_radius_m", "inf").is_err());
    }
}

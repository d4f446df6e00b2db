//! The robot file: every constant of the robot model as one TOML key, so a user describes
//! their own robot without editing Rust (issue 25).
//!
//! `twil robot init FILE.toml` writes [`init_text`]: one key per row of
//! [`twil_core::params::PARAMS`], with its meaning, unit, accepted values and the default's
//! source as comments. `--robot FILE.toml` ([`read`]) gives the keys the file sets; keys left
//! out keep their defaults, and [`resolve`] puts the file's values and the explicit command-line
//! options on a command's robot in one step, validated once by the core
//! ([`twil_core::params::set_many`], that is [`RobotConfig::validate`], the validation the
//! firmware runs too). Unknown keys, wrong types and refused values are one line naming the
//! file, the line, the key and the value; a misspelt key gets the nearest name.
//!
//! Values: real numbers (an integer is accepted), whole numbers, `true`/`false`, and a choice
//! by its name (`sweep_layout = "seed"`), as [`twil_core::params::Kind`] describes. The same
//! representation is `summary.json`'s `robot` object ([`robot_json`]).
//!
//! Measured: `tests/robot_file.rs` (a larger `planning_radius_m` turns a narrow doorway
//! `unreachable`; every error kind names file:line; `summary.json`'s `robot` equals the file).

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use twil_core::params::{self, Kind, Param, PARAMS};
use twil_core::robot::{ConfigError, RobotConfig};

use crate::files::printable;

/// One key the file sets.
#[derive(Clone, Copy, Debug)]
pub struct Entry {
    /// The constant.
    pub param: &'static Param,
    /// Its value, as the parameter table carries it (`Kind`).
    pub value: f32,
    /// 1-based line of the key.
    pub line: usize,
}

/// A robot file read and checked for names and types (not yet for the model's rules: see
/// [`resolve`]).
#[derive(Clone, Debug)]
pub struct RobotFile {
    /// Where it was read from.
    pub path: PathBuf,
    /// The keys it sets, in file order.
    pub entries: Vec<Entry>,
    /// The source text of each entry's value (for messages), same order.
    value_texts: Vec<String>,
}

impl RobotFile {
    /// The entry for constant `name`, if the file sets it.
    pub fn get(&self, name: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.param.name == name)
    }

    fn value_text(&self, name: &str) -> Option<&str> {
        let i = self.entries.iter().position(|e| e.param.name == name)?;
        self.value_texts.get(i).map(String::as_str)
    }
}

/// Read and parse the robot file at `path`.
pub fn read(path: &Path) -> Result<RobotFile> {
    let text = crate::files::read_text(path, crate::files::ROBOT)?;
    parse(path, &text).map_err(|line| anyhow::anyhow!("{line}"))
}

/// 1-based line of byte `offset` of `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|b| **b == b'\n')
        .count()
        + 1
}

/// The nearest constant's name to a misspelt `key`, if one is close.
pub fn suggest(key: &str) -> Option<&'static str> {
    PARAMS
        .iter()
        .map(|p| (strsim::jaro_winkler(key, p.name), p.name))
        .filter(|(score, _)| *score >= 0.8)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, name)| name)
}

/// What a key of `param`'s kind must hold, in words.
fn expected_type(param: &Param) -> String {
    match param.kind {
        Kind::Real if param.unit.is_empty() => "a number".into(),
        Kind::Real => format!("a number ({})", param.unit),
        Kind::Integer => "a whole number".into(),
        Kind::Bool => "true or false".into(),
        Kind::Choice(names) => format!(
            "one of {}",
            names
                .iter()
                .map(|n| format!("\"{n}\""))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// The table value of a TOML value for `param`, or `None` when the type is wrong.
fn table_value(param: &Param, value: &toml::Value) -> Option<f32> {
    match (param.kind, value) {
        (Kind::Real, toml::Value::Float(f)) => Some(*f as f32),
        (Kind::Real, toml::Value::Integer(i)) => Some(*i as f32),
        (Kind::Integer, toml::Value::Integer(i)) => Some(*i as f32),
        (Kind::Bool, toml::Value::Boolean(b)) => Some(if *b { 1.0 } else { 0.0 }),
        (Kind::Choice(_), toml::Value::String(s)) => param.choice_index(s),
        _ => None,
    }
}

/// Parse the text of a robot file; the error is one line naming the file and the line.
pub fn parse(path: &Path, text: &str) -> Result<RobotFile, String> {
    let file = printable(&path.display().to_string());
    let spanned = toml::de::DeTable::parse(text).map_err(|e| {
        let line = e.span().map_or(1, |s| line_of(text, s.start));
        let message = printable(e.message().trim()).replace("\\n", "; ");
        format!("{file}:{line}: {message}")
    })?;
    let values: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| format!("{file}: {}", e.message().trim()))?;
    let mut keys: Vec<(usize, String, String)> = spanned
        .get_ref()
        .iter()
        .map(|(k, v)| {
            let span = v.span();
            let shown = printable(text.get(span).unwrap_or("?").trim());
            (k.span().start, k.get_ref().to_string(), shown)
        })
        .collect();
    keys.sort();
    let mut entries = Vec::new();
    let mut value_texts = Vec::new();
    for (offset, key, shown) in keys {
        let line = line_of(text, offset);
        let Some(param) = params::find(&key) else {
            let hint = match suggest(&key) {
                Some(name) => format!("; did you mean `{name}`?"),
                None => "; `twil robot init` lists every key".to_string(),
            };
            let key = printable(&key);
            return Err(format!(
                "{file}:{line}: unknown key `{key}` = {shown}{hint}"
            ));
        };
        let value = values
            .get(&key)
            .and_then(|v| table_value(param, v))
            .ok_or_else(|| {
                format!(
                    "{file}:{line}: `{key}` = {shown}: expected {}",
                    expected_type(param)
                )
            })?;
        entries.push(Entry { param, value, line });
        value_texts.push(shown);
    }
    Ok(RobotFile {
        path: path.to_path_buf(),
        entries,
        value_texts,
    })
}

/// A command-line option that sets a constant, given explicitly: it overrides the file.
#[derive(Clone, Copy, Debug)]
pub struct Explicit {
    /// The constant it sets.
    pub name: &'static str,
    /// The option's value, as the table carries it.
    pub value: f32,
}

/// The robot of a run: `base` (the defaults with the command's own defaults and the `.par`
/// radius), then the file's keys, then the explicit options, validated once. A refused value
/// is named where it came from: the option (`args::option_error` wording), or the file's line.
pub fn resolve(
    base: RobotConfig,
    file: Option<&RobotFile>,
    explicit: &[Explicit],
) -> Result<RobotConfig> {
    let mut values: Vec<(&Param, f32)> = Vec::new();
    if let Some(file) = file {
        for e in &file.entries {
            if !explicit.iter().any(|x| x.name == e.param.name) {
                values.push((e.param, e.value));
            }
        }
    }
    for x in explicit {
        if let Some(p) = params::find(x.name) {
            values.push((p, x.value));
        }
    }
    let mut robot = base;
    if let Err(e) = params::set_many(&mut robot, &values) {
        let mut shown = robot;
        // The config as it would have been, for the option wording's bounds.
        for (p, v) in &values {
            let _ = p.set(&mut shown, *v);
        }
        bail!("{}", refused(&e, file, explicit, &shown));
    }
    Ok(robot)
}

/// The one line for a refused value.
fn refused(
    e: &ConfigError,
    file: Option<&RobotFile>,
    explicit: &[Explicit],
    robot: &RobotConfig,
) -> String {
    let from_file = file.and_then(|f| f.get(e.field).map(|entry| (f, entry)));
    match from_file {
        Some((f, entry)) if !explicit.iter().any(|x| x.name == e.field) => format!(
            "{}:{}: `{}` = {}: {}",
            printable(&f.path.display().to_string()),
            entry.line,
            e.field,
            f.value_text(e.field).unwrap_or("?"),
            e.expected
        ),
        _ if explicit.iter().any(|x| x.name == e.field) || file.is_none() => {
            crate::cmd::args::option_error(e, robot)
        }
        _ => format!(
            "{}: `{}` = {} (not set in the file, so the command's value): {}; set it in the file",
            file.map_or(String::new(), |f| printable(&f.path.display().to_string())),
            e.field,
            e.value,
            e.expected
        ),
    }
}

/// `value` of `param` as the robot file and `summary.json` write it.
pub fn json_value(param: &Param, value: f32) -> serde_json::Value {
    match param.kind {
        Kind::Real => serde_json::Value::from(short_f64(value)),
        Kind::Integer => serde_json::Value::from(value as i64),
        Kind::Bool => serde_json::Value::from(value == 1.0),
        Kind::Choice(_) => serde_json::Value::from(param.choice_name(value).unwrap_or("?")),
    }
}

/// The `f64` that prints as the `f32`'s shortest form (0.075, not 0.07500000298023224).
fn short_f64(value: f32) -> f64 {
    format!("{value}").parse().unwrap_or(value as f64)
}

/// `value` of `param` as TOML text.
pub fn toml_text(param: &Param, value: f32) -> String {
    match param.kind {
        Kind::Real if value.fract() == 0.0 && value.abs() < 1.0e7 => format!("{value:.1}"),
        Kind::Real => format!("{value}"),
        Kind::Integer => format!("{}", value as i64),
        Kind::Bool => format!("{}", value == 1.0),
        Kind::Choice(_) => format!("\"{}\"", param.choice_name(value).unwrap_or("?")),
    }
}

/// `summary.json`'s `robot` object: every constant of `robot`, under the robot file's keys.
pub fn robot_json(robot: &RobotConfig) -> serde_json::Value {
    let map: serde_json::Map<String, serde_json::Value> = PARAMS
        .iter()
        .map(|p| (p.name.to_string(), json_value(p, p.get(robot))))
        .collect();
    serde_json::Value::Object(map)
}

/// The accepted values of a row, in words (its rule; bounds and the kind's values).
fn accepted(p: &Param) -> String {
    match p.kind {
        Kind::Real | Kind::Integer => p.rule.to_string(),
        _ => expected_type(p),
    }
}

/// The text of `twil robot init`: every constant at the host tools' default
/// ([`RobotConfig::SIMULATED`]: the core's, with the simulated ranger), with comments.
pub fn init_text() -> String {
    let mut s = String::from(
        "# Twil robot file: every constant of the robot model, at its default (`twil robot init`).\n\
         # Edit the values of your robot; a key left out keeps its default. `--robot FILE.toml` on\n\
         # twil plan, simulate, mission and compare reads it; an explicit command-line option\n\
         # overrides the file's value. docs/formats.md describes the format, docs/robot-model.md\n\
         # the model.\n",
    );
    for p in PARAMS.iter() {
        let unit = if p.unit.is_empty() {
            String::new()
        } else {
            format!("Unit: {}. ", p.unit)
        };
        s.push_str(&format!(
            "\n# {}.\n# {unit}Accepted: {}.\n# Default: {}.\n{} = {}\n",
            capitalised(p.doc),
            accepted(p),
            p.source,
            p.name,
            toml_text(p, p.get(&RobotConfig::SIMULATED))
        ));
    }
    s
}

fn capitalised(text: &str) -> String {
    let mut c = text.chars();
    match c.next() {
        Some(first) => first.to_uppercase().chain(c).collect(),
        None => String::new(),
    }
}

/// The constants table of `docs/robot-model.md`, generated from the parameter table.
pub fn docs_table() -> String {
    let mut s = String::from(
        "| Key | Default | Unit | Accepted | Meaning | Source of the default |\n|---|---|---|---|---|---|\n",
    );
    for p in PARAMS.iter() {
        s.push_str(&format!(
            "| `{}` | {} | {} | {} | {} | {} |\n",
            p.name,
            toml_text(p, p.get(&RobotConfig::SIMULATED)).replace('"', "`"),
            p.unit,
            accepted(p).replace('|', "\\|"),
            p.doc,
            p.source
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parsed(text: &str) -> Result<RobotFile, String> {
        parse(Path::new("robot.toml"), text)
    }

    #[test]
    fn the_generated_file_reads_back_as_the_defaults() {
        let file = parsed(&init_text()).unwrap();
        assert_eq!(file.entries.len(), PARAMS.len());
        let robot = resolve(RobotConfig::SIMULATED, Some(&file), &[]).unwrap();
        assert_eq!(robot, RobotConfig::SIMULATED);
    }

    #[test]
    fn every_robot_config_field_but_the_noise_seed_is_a_key() {
        let fields = serde_json::to_value(RobotConfig::DEFAULT).unwrap();
        let mut fields: Vec<&String> = fields.as_object().unwrap().keys().collect();
        fields.retain(|k| *k != "noise_seed");
        fields.sort();
        let mut keys: Vec<&str> = PARAMS.iter().map(|p| p.name).collect();
        keys.sort();
        assert_eq!(fields, keys);
    }

    #[test]
    fn errors_are_one_line_with_file_line_key_and_value() {
        let e = parsed("# mine\nwheel_radius = 0.08\n").unwrap_err();
        assert_eq!(
            e,
            "robot.toml:2: unknown key `wheel_radius` = 0.08; did you mean `wheel_radius_m`?"
        );
        let e = parsed("\n\nhalf_axle_m = \"wide\"\n").unwrap_err();
        assert_eq!(
            e,
            "robot.toml:3: `half_axle_m` = \"wide\": expected a number (m)"
        );
        let e = parsed("encoder_pulses_per_rev = 2000.5\n").unwrap_err();
        assert_eq!(
            e,
            "robot.toml:1: `encoder_pulses_per_rev` = 2000.5: expected a whole number"
        );
        let e = parsed("sweep_layout = \"spiral\"\n").unwrap_err();
        assert!(
            e.ends_with("expected one of \"symmetric\", \"seed\""),
            "{e}"
        );
        let e = parsed("a = 1\nb = = 2\n").unwrap_err();
        assert!(e.starts_with("robot.toml:2: "), "{e}");
        assert!(!e.contains('\n'), "{e}");
        let file = parsed("wheel_radius_m = 0.08\nsonar_range_m = 7\n").unwrap();
        let e = resolve(RobotConfig::DEFAULT, Some(&file), &[]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "robot.toml:2: `sonar_range_m` = 7: above sonar_min_range_m and at most 6 m"
        );
    }

    #[test]
    fn an_explicit_option_overrides_the_file_and_keeps_its_wording() {
        let file = parsed("sonar_range_m = 2.5\nwheel_radius_m = 0.1\n").unwrap();
        let option = Explicit {
            name: "sonar_range_m",
            value: 1.0,
        };
        let robot = resolve(RobotConfig::DEFAULT, Some(&file), &[option]).unwrap();
        assert_eq!((robot.sonar_range_m, robot.wheel_radius_m), (1.0, 0.1));
        let bad = Explicit {
            name: "sonar_range_m",
            value: 100.0,
        };
        let e = resolve(RobotConfig::DEFAULT, Some(&file), &[bad]).unwrap_err();
        assert_eq!(e.to_string(), "--sonar-range 100: at most 6 m");
        // A value the file depends on but leaves at the command's value.
        let file = parsed("sonar_min_range_m = 2.0\n").unwrap();
        let e = resolve(RobotConfig::DEFAULT, Some(&file), &[]).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("robot.toml: `sonar_range_m` = 1.5 (not set"),
            "{e}"
        );
    }

    #[test]
    fn json_and_toml_show_each_kind_once() {
        let robot = robot_json(&RobotConfig::DEFAULT);
        assert_eq!(robot["wheel_radius_m"], serde_json::json!(0.075));
        assert_eq!(robot["encoder_pulses_per_rev"], serde_json::json!(2000));
        assert_eq!(robot["sonar_beam"], serde_json::json!(false));
        assert_eq!(robot["sweep_layout"], serde_json::json!("symmetric"));
        let p = params::find("max_voltage_v").unwrap();
        assert_eq!(toml_text(p, 12.0), "12.0");
        assert!(docs_table().contains("| `wheel_radius_m` | 0.075 | m |"));
    }
}

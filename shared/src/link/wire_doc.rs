//! `docs/protocol.md`'s wire tables checked against the Rust types, so the document a client
//! in another language is written from cannot drift from what the device sends.
//!
//! serde-reflection traces [`RequestFrame`] and [`DeviceFrame`] through serde (the same derive
//! postcard encodes with) and gives every type reached: a struct's fields in wire order with
//! their types, an enum's variants with their indices. Each must have a `### \`Name\`` section
//! under `## Wire types` whose table lists exactly those rows (index, name, wire type); the
//! last column (units, meaning) is the document's own. A mismatch prints the rows expected, so
//! the fix is a copy. `#[serde(skip)]` fields are not on the wire and so not in the tables.

extern crate std;

use std::collections::BTreeMap;
use std::format;
use std::string::{String, ToString};
use std::vec::Vec;

use serde_reflection::{
    ContainerFormat, Format, Named, Registry, Tracer, TracerConfig, VariantFormat,
};

use super::message::{
    Build, DeviceFrame, ErrorCode, Reply, Request, RequestFrame, RunState, Telemetry,
};
use crate::failsafe::{LinkLossReaction, ResetCause, Sensor, StopCause};
use crate::mission::{MissionMode, MissionPhase, MissionStatus, SettleRule, UnreachableReason};
use crate::params_store::StoreStatus;
use crate::plan::{PlanStatus, PlannerKind};
use crate::sonar::SweepLayout;

const PROTOCOL_MD: &str = include_str!("../../../docs/protocol.md");

/// Every type on the wire, by name.
fn registry() -> Registry {
    let mut tracer = Tracer::new(TracerConfig::default());
    tracer
        .trace_simple_type::<RequestFrame>()
        .expect("trace RequestFrame");
    tracer
        .trace_simple_type::<DeviceFrame>()
        .expect("trace DeviceFrame");
    // Tracing a type explores all of its own enum's variants but stops the nested enums at
    // their first variant that ends the recursion: trace each enum on its own too. The
    // registry refuses to close over an enum left incomplete, so a new enum nested in these
    // is caught.
    macro_rules! trace {
        ($($t:ty),*) => {
            $(tracer.trace_simple_type::<$t>().expect(stringify!($t));)*
        };
    }
    trace!(
        Request,
        Reply,
        Telemetry,
        Build,
        ResetCause,
        ErrorCode,
        LinkLossReaction,
        MissionMode,
        MissionPhase,
        MissionStatus,
        PlanStatus,
        PlannerKind,
        RunState,
        Sensor,
        SettleRule,
        StopCause,
        StoreStatus,
        SweepLayout,
        UnreachableReason,
        crate::selftest::Check,
        crate::selftest::CheckStatus,
        crate::selftest::Hint
    );
    tracer
        .registry()
        .expect("every enum variant traced (a new enum on the wire: add it to the list above)")
}

/// A wire type as the document writes it.
fn wire(format: &Format) -> String {
    match format {
        Format::TypeName(name) => name.clone(),
        Format::Unit => "()".into(),
        Format::Bool => "bool".into(),
        Format::I8 => "i8".into(),
        Format::I16 => "i16".into(),
        Format::I32 => "i32".into(),
        Format::I64 => "i64".into(),
        Format::I128 => "i128".into(),
        Format::U8 => "u8".into(),
        Format::U16 => "u16".into(),
        Format::U32 => "u32".into(),
        Format::U64 => "u64".into(),
        Format::U128 => "u128".into(),
        Format::F32 => "f32".into(),
        Format::F64 => "f64".into(),
        Format::Char => "char".into(),
        Format::Str => "str".into(),
        Format::Bytes => "bytes".into(),
        Format::Option(inner) => format!("Option<{}>", wire(inner)),
        Format::Seq(inner) => format!("Vec<{}>", wire(inner)),
        Format::Map { key, value } => format!("Map<{}, {}>", wire(key), wire(value)),
        Format::Tuple(items) => format!("({})", list(items)),
        Format::TupleArray { content, size } => format!("[{}; {size}]", wire(content)),
        Format::Variable(_) => "?".into(),
    }
}

fn list(items: &[Format]) -> String {
    items.iter().map(wire).collect::<Vec<_>>().join(", ")
}

fn fields(named: &[Named<Format>]) -> String {
    let inner = named
        .iter()
        .map(|f| format!("{}: {}", f.name, wire(&f.value)))
        .collect::<Vec<_>>()
        .join(", ");
    format!("{{ {inner} }}")
}

/// The rows (index, name, wire type) a type's table must have.
fn expected_rows(container: &ContainerFormat) -> Vec<[String; 3]> {
    match container {
        ContainerFormat::Struct(named) => named
            .iter()
            .enumerate()
            .map(|(i, f)| [i.to_string(), f.name.clone(), wire(&f.value)])
            .collect(),
        ContainerFormat::Enum(variants) => variants
            .iter()
            .map(|(i, v)| {
                let payload = match &v.value {
                    VariantFormat::Unit => "—".to_string(),
                    VariantFormat::NewType(inner) => format!("({})", wire(inner)),
                    VariantFormat::Tuple(items) => format!("({})", list(items)),
                    VariantFormat::Struct(named) => fields(named),
                    VariantFormat::Variable(_) => "?".into(),
                };
                [i.to_string(), v.name.clone(), payload]
            })
            .collect(),
        ContainerFormat::NewTypeStruct(inner) => {
            std::vec![["0".into(), "0".into(), wire(inner)]]
        }
        ContainerFormat::TupleStruct(items) => items
            .iter()
            .enumerate()
            .map(|(i, f)| [i.to_string(), i.to_string(), wire(f)])
            .collect(),
        ContainerFormat::UnitStruct => Vec::new(),
    }
}

/// A table cell without its code marks.
fn cell(text: &str) -> String {
    text.trim().trim_matches('`').trim().to_string()
}

/// The documented tables of `## Wire types`: type name → its rows' first three cells.
fn documented(doc: &str) -> BTreeMap<String, Vec<[String; 3]>> {
    let mut tables = BTreeMap::new();
    let mut in_section = false;
    let mut current: Option<String> = None;
    let mut rows_seen = 0;
    for line in doc.lines() {
        if line.starts_with("## ") {
            in_section = line.trim() == "## Wire types";
            current = None;
            continue;
        }
        if !in_section {
            continue;
        }
        if let Some(title) = line.strip_prefix("### ") {
            let name = cell(title.split_whitespace().next().unwrap_or(""));
            tables.insert(name.clone(), Vec::new());
            current = Some(name);
            rows_seen = 0;
            continue;
        }
        let Some(name) = &current else { continue };
        let Some(body) = line.trim().strip_prefix('|') else {
            continue;
        };
        rows_seen += 1;
        if rows_seen <= 2 {
            continue; // the header and its `|---|` line
        }
        let cells: Vec<String> = body.split('|').map(cell).collect();
        if cells.len() >= 3 {
            let row = [cells[0].clone(), cells[1].clone(), cells[2].clone()];
            tables.get_mut(name).expect("inserted above").push(row);
        }
    }
    tables
}

fn render(rows: &[[String; 3]]) -> String {
    rows.iter()
        .map(|[a, b, c]| format!("| {a} | `{b}` | `{c}` | |\n"))
        .collect()
}

#[test]
fn protocol_md_lists_every_wire_type_as_the_code_has_it() {
    let registry = registry();
    let doc = documented(PROTOCOL_MD);
    let mut problems = Vec::new();
    for (name, container) in &registry {
        let want = expected_rows(container);
        match doc.get(name) {
            None => problems.push(format!(
                "docs/protocol.md has no `### `{name}`` under `## Wire types`; its rows:\n{}",
                render(&want)
            )),
            Some(got) if *got != want => problems.push(format!(
                "docs/protocol.md's table of `{name}` differs from the type; it should read:\n{}",
                render(&want)
            )),
            Some(_) => {}
        }
    }
    for name in doc.keys() {
        if !registry.contains_key(name) {
            problems.push(format!(
                "docs/protocol.md documents `{name}`, which is not on the wire"
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_doc_parser_reads_a_table_and_the_checker_sees_a_change() {
    let doc = "## Wire types\n\n### `PointM` (struct)\n\n| # | field | wire type | meaning |\n\
               |---|---|---|---|\n| 0 | `x_m` | `f32` | metres |\n| 1 | `y_m` | `f32` | metres |\n\
               \n## Next\n| 9 | `z` | `u8` | |\n";
    let tables = documented(doc);
    let registry = registry();
    let want = expected_rows(&registry["PointM"]);
    assert_eq!(tables["PointM"], want);
    assert_eq!(tables.len(), 1, "tables after the section are not read");
    let swapped = doc.replace("| 1 | `y_m` | `f32`", "| 1 | `y_m` | `u32`");
    assert_ne!(documented(&swapped)["PointM"], want);
}

//! The device's parameters through [`Remote`]: list, get, set (protocol 6, issue 25 part 2),
//! and the robot file's values sent before a mission.
//!
//! Why here: `twil param` and `twil mission --robot` ask the same three requests and explain
//! the same refusals (an unknown name gets the nearest name of the host's table, which is the
//! firmware's: both are `twil_core::params::PARAMS`).

use anyhow::{anyhow, bail, Result};
use twil_core::link::params::wire_name;
use twil_core::link::{ErrorCode, ParamEntry, ParamRefusal, Reply, Request};

use super::Remote;

/// What the device made of a `ParamSet`.
#[derive(Clone, Debug, PartialEq)]
pub enum SetOutcome {
    /// Set (and stored, when the device has a store): the row as it is now.
    Set(ParamEntry),
    /// Refused by the robot model: nothing changed.
    Refused(ParamRefusal),
}

/// `name` for a request, or the error a user sees (naming the name and the bound).
fn name_on_wire(name: &str) -> Result<heapless::String<{ twil_core::link::PARAM_NAME_BYTES }>> {
    wire_name(name).ok_or_else(|| {
        anyhow!(
            "parameter name `{name}` has {} bytes, more than the {} a name may have; {}",
            name.len(),
            twil_core::link::PARAM_NAME_BYTES,
            hint(name)
        )
    })
}

/// What to try instead of an unknown `name`.
fn hint(name: &str) -> String {
    match crate::robot_file::suggest(name) {
        Some(near) => format!("did you mean `{near}`?"),
        None => "`twil param list` shows every name".into(),
    }
}

/// The error of a reply that is not a parameter, naming `name`.
fn refused(name: &str, reply: Reply) -> anyhow::Error {
    match reply {
        Reply::Error(e) if e.code == ErrorCode::UnknownParam => {
            anyhow!("the device has no parameter `{name}`; {}", hint(name))
        }
        Reply::Error(e) if e.code == ErrorCode::NotOnThisBuild => {
            anyhow!("this device answers no parameter requests (a planning-only firmware?)")
        }
        Reply::Error(e) => anyhow!("parameter `{name}`: {e}"),
        other => anyhow!("parameter `{name}`: unexpected reply {other:?}"),
    }
}

impl Remote {
    /// Every row of the device's table, in its order.
    pub fn param_list(&mut self) -> Result<Vec<ParamEntry>> {
        let mut rows = Vec::new();
        let mut index = 0u16;
        loop {
            match self.request(Request::ParamList { index })? {
                Reply::Param(entry) => {
                    let count = entry.count;
                    rows.push(entry);
                    index += 1;
                    if index >= count {
                        return Ok(rows);
                    }
                }
                other => return Err(refused(&format!("#{index}"), other)),
            }
        }
    }

    /// What the device's parameter store held at boot, in words (`ok`, `empty`, `corrupt`,
    /// `old version`, `none` for a device without one); `None` when the device answers no
    /// parameter requests (a planning-only firmware).
    pub fn param_store(&mut self) -> Option<String> {
        match self.request(Request::ParamList { index: 0 }) {
            Ok(Reply::Param(entry)) => Some(match entry.store {
                Some(status) => status.to_string(),
                None => "none".into(),
            }),
            _ => None,
        }
    }

    /// The row `name`.
    pub fn param_get(&mut self, name: &str) -> Result<ParamEntry> {
        match self.request(Request::ParamGet {
            name: name_on_wire(name)?,
        })? {
            Reply::Param(entry) => Ok(entry),
            other => Err(refused(name, other)),
        }
    }

    /// Set `name` to `value` (the table's `f32`: a whole number, 0 / 1, a choice's index).
    pub fn param_set(&mut self, name: &str, value: f32) -> Result<SetOutcome> {
        match self.request(Request::ParamSet {
            name: name_on_wire(name)?,
            value,
        })? {
            Reply::Param(entry) => Ok(SetOutcome::Set(entry)),
            Reply::ParamRefused(r) => Ok(SetOutcome::Refused(r)),
            other => Err(refused(name, other)),
        }
    }

    /// Send the values `values` (name, value, where it came from for the messages) to the
    /// device, skipping those it already has. Values that depend on each other are sent in
    /// an order that works: a refused one is tried again after the others, as long as one
    /// more goes through each round. The error names where the refused value came from and
    /// the device's rule. Returns how many were set.
    pub fn send_params(&mut self, values: &[(&str, f32, String)]) -> Result<usize> {
        let mut todo: Vec<&(&str, f32, String)> = Vec::new();
        for v in values {
            if self.param_get(v.0)?.value != v.1 {
                todo.push(v);
            }
        }
        let mut set = 0;
        while !todo.is_empty() {
            let mut left = Vec::new();
            let mut last_refusal = None;
            for v in &todo {
                match self.param_set(v.0, v.1)? {
                    SetOutcome::Set(_) => set += 1,
                    SetOutcome::Refused(r) => {
                        last_refusal.get_or_insert((*v, r));
                        left.push(*v);
                    }
                }
            }
            if left.len() == todo.len() {
                let Some(((name, value, origin), r)) = last_refusal else {
                    break;
                };
                bail!(
                    "{origin}: {}",
                    crate::cmd::param::refusal_words(name, &format!("{value}"), &r)
                );
            }
            todo = left;
        }
        Ok(set)
    }
}

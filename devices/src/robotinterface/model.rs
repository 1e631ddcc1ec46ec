//! The robot description as C++ `yarp::robotinterface` models it: a robot with devices,
//! each with parameters (name -> value text) and actions in phases and levels.
//!
//! Parameter values stay text until a device is opened; [`Device::to_property`] then
//! turns them into the `Property` C++ builds (`paramsAsProperty`): `device` = type,
//! `id` = name, and each parameter read as the Bottle text `(name value)`. So
//! `<param name="joints">8</param>` is the integer 8, `<param name="names">a b</param>`
//! the group `(names a b)`, `(1 2 3)` a list, and a `<group>` a nested `(name (k v)...)`.

use super::error::{Location, XmlError};
use std::fmt;
use yarp_proto::{Property, Value};

/// One parameter; a group's value is the text of its members, `(k v) (k2 v2)`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Param {
    pub name: String,
    pub value: String,
    pub is_group: bool,
}

impl Param {
    pub fn new(name: impl Into<String>, value: impl Into<String>) -> Self {
        Param {
            name: name.into(),
            value: value.into(),
            is_group: false,
        }
    }

    pub fn group(name: impl Into<String>, value: impl Into<String>) -> Self {
        Param {
            is_group: true,
            ..Param::new(name, value)
        }
    }
}

/// Whether `params` has one named `name` (C++ `hasParam`).
pub fn has_param(params: &[Param], name: &str) -> bool {
    params.iter().any(|p| p.name == name)
}

/// The value of the first parameter named `name` (C++ `findParam`).
pub fn find_param<'a>(params: &'a [Param], name: &str) -> Option<&'a str> {
    params
        .iter()
        .find(|p| p.name == name)
        .map(|p| p.value.as_str())
}

/// Joins groups of the same name into one (C++ `mergeDuplicateGroups`); a repeated name
/// that is not a group on both sides is returned as the error.
pub fn merge_duplicate_groups(params: &[Param]) -> Result<Vec<Param>, String> {
    let mut merged: Vec<Param> = Vec::with_capacity(params.len());
    for p in params {
        match merged.iter_mut().find(|m| m.name == p.name) {
            None => merged.push(p.clone()),
            Some(m) if m.is_group && p.is_group => {
                m.value.push(' ');
                m.value.push_str(&p.value);
            }
            Some(_) => return Err(p.name.clone()),
        }
    }
    Ok(merged)
}

/// When actions run (C++ `ActionPhase`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ActionPhase {
    Startup,
    Run,
    Interrupt1,
    Interrupt2,
    Interrupt3,
    Shutdown,
}

impl ActionPhase {
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "startup" => ActionPhase::Startup,
            "run" => ActionPhase::Run,
            "interrupt1" => ActionPhase::Interrupt1,
            "interrupt2" => ActionPhase::Interrupt2,
            "interrupt3" => ActionPhase::Interrupt3,
            "shutdown" => ActionPhase::Shutdown,
            _ => return None,
        })
    }

    pub fn as_str(self) -> &'static str {
        match self {
            ActionPhase::Startup => "startup",
            ActionPhase::Run => "run",
            ActionPhase::Interrupt1 => "interrupt1",
            ActionPhase::Interrupt2 => "interrupt2",
            ActionPhase::Interrupt3 => "interrupt3",
            ActionPhase::Shutdown => "shutdown",
        }
    }

    /// Phases whose levels run in reverse when the robot asks for
    /// `reverse-shutdown-action-order`.
    pub fn is_stopping(self) -> bool {
        matches!(
            self,
            ActionPhase::Interrupt1
                | ActionPhase::Interrupt2
                | ActionPhase::Interrupt3
                | ActionPhase::Shutdown
        )
    }
}

impl fmt::Display for ActionPhase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// What an action does (C++ `ActionType`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ActionType {
    Configure,
    Calibrate,
    Attach,
    Abort,
    Detach,
    Park,
    Custom,
}

impl ActionType {
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "configure" => ActionType::Configure,
            "calibrate" => ActionType::Calibrate,
            "attach" => ActionType::Attach,
            "abort" => ActionType::Abort,
            "detach" => ActionType::Detach,
            "park" => ActionType::Park,
            "custom" => ActionType::Custom,
            _ => return None,
        })
    }

    pub fn as_str(self) -> &'static str {
        match self {
            ActionType::Configure => "configure",
            ActionType::Calibrate => "calibrate",
            ActionType::Attach => "attach",
            ActionType::Abort => "abort",
            ActionType::Detach => "detach",
            ActionType::Park => "park",
            ActionType::Custom => "custom",
        }
    }
}

impl fmt::Display for ActionType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// An `<action phase level type>` of a device.
#[derive(Debug, Clone, PartialEq)]
pub struct Action {
    pub phase: ActionPhase,
    pub kind: ActionType,
    pub level: u32,
    pub params: Vec<Param>,
    pub at: Location,
}

/// A `<device name type>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Device {
    pub name: String,
    /// The driver name (`type` attribute), e.g. `fakeMotionControl`.
    pub kind: String,
    pub params: Vec<Param>,
    pub actions: Vec<Action>,
    pub at: Location,
}

impl Device {
    /// The configuration the device is opened with (C++ `paramsAsProperty`).
    pub fn to_property(&self) -> Result<Property, XmlError> {
        let params =
            merge_duplicate_groups(&self.params).map_err(|param| XmlError::DuplicateParam {
                at: self.at.clone(),
                device: self.name.clone(),
                param,
            })?;
        let mut prop = Property::new();
        prop.put("device", Value::from(self.kind.as_str()));
        prop.put("id", Value::from(self.name.as_str()));
        for p in &params {
            if !parens_balanced(&p.value) {
                tracing::warn!(
                    "{}: parentheses not balanced for param {} of device {}",
                    self.at,
                    p.name,
                    self.name
                );
            }
            prop.merge_text(format!("({} {})", p.name, p.value));
        }
        Ok(prop)
    }
}

/// C++'s check: counting stops at the first unmatched `)`.
fn parens_balanced(s: &str) -> bool {
    let mut depth: i64 = 0;
    for c in s.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            _ => {}
        }
        if depth < 0 {
            return false;
        }
    }
    depth == 0
}

/// The whole `<robot>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    pub name: String,
    pub build: u32,
    pub portprefix: String,
    pub reverse_shutdown_action_order: bool,
    pub params: Vec<Param>,
    pub devices: Vec<Device>,
}

impl Robot {
    /// The device named `name`.
    pub fn device(&self, name: &str) -> Option<&Device> {
        self.devices.iter().find(|d| d.name == name)
    }

    /// The distinct levels that have actions in `phase`, ascending (descending for
    /// stopping phases of a robot with `reverse-shutdown-action-order`).
    pub fn levels(&self, phase: ActionPhase) -> Vec<u32> {
        let mut levels: Vec<u32> = self
            .devices
            .iter()
            .flat_map(|d| &d.actions)
            .filter(|a| a.phase == phase)
            .map(|a| a.level)
            .collect();
        levels.sort_unstable();
        levels.dedup();
        if self.reverse_shutdown_action_order && phase.is_stopping() {
            levels.reverse();
        }
        levels
    }

    /// The actions of `phase` at `level`, in device order, with their device's index.
    pub fn actions(&self, phase: ActionPhase, level: u32) -> Vec<(usize, &Action)> {
        self.devices
            .iter()
            .enumerate()
            .flat_map(|(i, d)| d.actions.iter().map(move |a| (i, a)))
            .filter(|(_, a)| a.phase == phase && a.level == level)
            .collect()
    }

    /// Adds `verbose 1` to every device that does not set `verbose` itself
    /// (C++ `Robot::setVerbose`, from `yarprobotinterface --verbose`).
    pub fn set_verbose(&mut self) {
        self.add_default_param("verbose", "1");
    }

    /// Adds `name value` to every device that does not set `name` itself.
    pub fn add_default_param(&mut self, name: &str, value: &str) {
        for d in &mut self.devices {
            if !has_param(&d.params, name) {
                d.params.push(Param::new(name, value));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn device(params: Vec<Param>) -> Device {
        Device {
            name: "dev".into(),
            kind: "fakeMotionControl".into(),
            params,
            actions: vec![],
            at: Location::new(&Arc::from("t.xml"), 1),
        }
    }

    #[test]
    fn params_become_bottle_values() {
        let d = device(vec![
            Param::new("joints", "8"),
            Param::new("period", "0.01"),
            Param::new("name", "/icub/left_arm"),
            Param::new("AxisName", "\"a\" \"b\""),
            Param::new("list", "(1 2 3)"),
            Param::group("GENERAL", "(Joints 4) (Verbose 0 0 0 0)"),
        ]);
        let p = d.to_property().unwrap();
        assert_eq!(
            p.find("device").and_then(|v| v.as_str()),
            Some("fakeMotionControl")
        );
        assert_eq!(p.find("id").and_then(|v| v.as_str()), Some("dev"));
        assert_eq!(p.find("joints").and_then(|v| v.as_i64()), Some(8));
        assert_eq!(p.find("period").and_then(|v| v.as_f64()), Some(0.01));
        assert_eq!(
            p.find("name").and_then(|v| v.as_str()),
            Some("/icub/left_arm")
        );
        assert_eq!(
            p.find_group("AxisName").unwrap().to_string(),
            "AxisName a b"
        );
        assert_eq!(p.find("list").unwrap().to_string(), "(1 2 3)");
        let general = p.find_group("GENERAL").unwrap();
        assert_eq!(general.find("Joints").and_then(|v| v.as_i64()), Some(4));
    }

    #[test]
    fn duplicate_groups_merge_and_plain_duplicates_fail() {
        let d = device(vec![
            Param::group("GENERAL", "(a 1)"),
            Param::group("GENERAL", "(b 2)"),
        ]);
        let p = d.to_property().unwrap();
        let g = p.find_group("GENERAL").unwrap();
        assert_eq!(g.find("a").and_then(|v| v.as_i64()), Some(1));
        assert_eq!(g.find("b").and_then(|v| v.as_i64()), Some(2));

        let d = device(vec![Param::new("x", "1"), Param::new("x", "2")]);
        let e = d.to_property().unwrap_err().to_string();
        assert!(e.contains("`dev`") && e.contains("`x`"), "{e}");
    }

    #[test]
    fn balance_check() {
        assert!(parens_balanced("(a (b)) c"));
        assert!(!parens_balanced(")("));
        assert!(!parens_balanced("(("));
    }
}

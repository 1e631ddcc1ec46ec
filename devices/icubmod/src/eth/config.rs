//! Reading the groups of a device's configuration the way icub-main's parsers do
//! (`findGroup(..).find(..)`, multi-value lines `(key v1 v2 ...)`), with errors that name
//! the parameter by its path from the group it was read in (`GENERAL/Encoder`,
//! `ETH_BOARD/ETH_BOARD_PROPERTIES`). What each device looks up is listed in its table
//! ([`crate::eth::tables`]), which a test keeps equal to these lookups ([`lookups`]).

use yarp_proto::{Bottle, Property, Value};

/// A parameter that is missing or does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("parameter `{param}` should be {expected}, got `{got}`")]
pub struct ParamError {
    /// The parameter's path, groups separated by `/`.
    pub param: String,
    pub expected: &'static str,
    /// What was found (`<missing>` when absent).
    pub got: String,
}

impl ParamError {
    pub fn missing(param: impl Into<String>, expected: &'static str) -> Self {
        Self {
            param: param.into(),
            expected,
            got: "<missing>".into(),
        }
    }
    pub fn bad(param: impl Into<String>, expected: &'static str, got: impl Into<String>) -> Self {
        Self {
            param: param.into(),
            expected,
            got: got.into(),
        }
    }
    /// As the device layer's error, naming the device.
    pub fn for_device(self, device: &str) -> yarp_devices::DeviceError {
        yarp_devices::DeviceError::BadParam {
            device: device.to_string(),
            param: self.param,
            expected: self.expected,
            got: self.got,
        }
    }
}

/// A group (or the whole configuration) of a device.
#[derive(Clone, Copy)]
pub enum Node<'a> {
    Root(&'a Property),
    Group(&'a Bottle, &'a str),
}

impl<'a> Node<'a> {
    pub fn root(p: &'a Property) -> Self {
        Node::Root(p)
    }

    fn path_of(&self, key: &str) -> String {
        match self {
            Node::Root(_) => key.to_string(),
            Node::Group(_, path) => format!("{path}/{key}"),
        }
    }

    /// The line `(key ...)` of this node.
    fn line(&self, key: &str) -> Option<&'a Bottle> {
        lookups::note(self, key);
        match *self {
            Node::Root(p) => p.find_group(key),
            Node::Group(b, _) => b.find_group(key),
        }
    }

    /// The sub-group `name` (a line whose values are lines).
    pub fn group(&self, name: &str) -> Option<Node<'a>> {
        let b = self.line(name)?;
        // messages name it by the line's own first word, which lives as long as the file
        Some(Node::Group(
            b,
            b.get(0).and_then(|v| v.as_str()).unwrap_or_default(),
        ))
    }

    /// The sub-group `name`, or an error naming it.
    pub fn need_group(&self, name: &str) -> Result<Node<'a>, ParamError> {
        self.group(name)
            .ok_or_else(|| ParamError::missing(self.path_of(name), "a group"))
    }

    pub fn has(&self, key: &str) -> bool {
        self.line(key).is_some()
    }

    /// The values after `key` (a single list value is flattened), as text.
    pub fn strings(&self, key: &str) -> Option<Vec<String>> {
        let line = self.line(key)?;
        let rest: Vec<&Value> = line.iter().skip(1).collect();
        if let [only] = rest.as_slice() {
            if let Some(list) = only.as_list() {
                return Some(list.iter().map(Value::to_string_bare).collect());
            }
        }
        Some(rest.into_iter().map(Value::to_string_bare).collect())
    }

    /// The first value of `key`, as text.
    pub fn string(&self, key: &str) -> Option<String> {
        self.strings(key).and_then(|v| v.into_iter().next())
    }

    pub fn need_string(&self, key: &str, expected: &'static str) -> Result<String, ParamError> {
        self.string(key)
            .ok_or_else(|| ParamError::missing(self.path_of(key), expected))
    }

    /// The first value of `key` as a number.
    pub fn number(&self, key: &str) -> Result<Option<f64>, ParamError> {
        match self.string(key) {
            None => Ok(None),
            Some(s) => parse_number(&s)
                .map(Some)
                .ok_or_else(|| ParamError::bad(self.path_of(key), "a number", s)),
        }
    }

    /// `key` as a boolean (`true`/`false`/`1`/`0`).
    pub fn boolean(&self, key: &str) -> Option<bool> {
        self.string(key)
            .map(|s| matches!(s.trim_matches('"'), "true" | "1" | "TRUE" | "True"))
    }

    /// `key`'s values as numbers, exactly `n` of them.
    pub fn numbers(&self, key: &str, n: usize) -> Result<Option<Vec<f64>>, ParamError> {
        let Some(v) = self.strings(key) else {
            return Ok(None);
        };
        let nums: Vec<f64> = v.iter().filter_map(|s| parse_number(s)).collect();
        if nums.len() != v.len() || v.len() != n {
            return Err(ParamError::bad(
                self.path_of(key),
                "one number per joint",
                v.join(" "),
            ));
        }
        Ok(Some(nums))
    }

    /// Like [`Self::numbers`], but an error when absent.
    pub fn need_numbers(&self, key: &str, n: usize) -> Result<Vec<f64>, ParamError> {
        self.numbers(key, n)?
            .ok_or_else(|| ParamError::missing(self.path_of(key), "one number per joint"))
    }

    /// `key`'s values as text, exactly `n` of them.
    pub fn need_strings(&self, key: &str, n: usize) -> Result<Vec<String>, ParamError> {
        let v = self
            .strings(key)
            .ok_or_else(|| ParamError::missing(self.path_of(key), "one value per joint"))?;
        if v.len() != n {
            return Err(ParamError::bad(
                self.path_of(key),
                "one value per joint",
                v.join(" "),
            ));
        }
        Ok(v)
    }
}

/// Which parameters a device looks up, for the test that keeps each `embObj*` device's
/// declared table ([`crate::eth::tables`]) equal to what its readers read.
#[doc(hidden)]
pub mod lookups {
    use super::Node;
    use std::cell::RefCell;
    use yarp_proto::{Bottle, Property};

    thread_local! {
        /// The lookups of the running [`record`], as (group, key); the group by address.
        static SEEN: RefCell<Option<Vec<(usize, String)>>> = const { RefCell::new(None) };
    }

    pub(super) fn note(node: &Node, key: &str) {
        SEEN.with_borrow_mut(|seen| {
            if let Some(seen) = seen {
                let group = match node {
                    Node::Root(_) => 0,
                    Node::Group(b, _) => std::ptr::from_ref::<Bottle>(b) as usize,
                };
                seen.push((group, key.to_string()));
            }
        });
    }

    /// Runs `f` and returns what it looked up in `config`, each as its path from the top
    /// (`SERVICE::PROPERTIES::SENSORS::id`).
    pub fn record<R>(config: &Property, f: impl FnOnce() -> R) -> (R, Vec<String>) {
        SEEN.with_borrow_mut(|seen| *seen = Some(Vec::new()));
        let r = f();
        let seen = SEEN.with_borrow_mut(Option::take).unwrap_or_default();
        let mut paths = std::collections::HashMap::new();
        for (name, group) in config.iter() {
            walk(
                group,
                String::from_utf8_lossy(name).into_owned(),
                &mut paths,
            );
        }
        let keys = seen
            .into_iter()
            .filter_map(|(group, key)| match group {
                0 => Some(key),
                g => paths.get(&g).map(|p| format!("{p}::{key}")),
            })
            .collect();
        (r, keys)
    }

    /// The path of every group under `group` (itself named `path`), by address.
    fn walk(group: &Bottle, path: String, paths: &mut std::collections::HashMap<usize, String>) {
        for line in group.iter().skip(1).filter_map(|v| v.as_list()) {
            let Some(name) = line.get(0).and_then(|v| v.as_str()) else {
                continue;
            };
            if line.iter().skip(1).any(|v| v.as_list().is_some()) {
                walk(line, format!("{path}::{name}"), paths);
            }
        }
        paths.insert(std::ptr::from_ref(group) as usize, path);
    }
}

/// A number as YARP reads it (decimal, `0x` hex).
pub fn parse_number(s: &str) -> Option<f64> {
    let s = s.trim().trim_matches('"');
    if let Some(h) = s.strip_prefix("0x").or_else(|| s.strip_prefix("0X")) {
        return i64::from_str_radix(h, 16).ok().map(|v| v as f64);
    }
    s.parse::<f64>().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nested_groups_and_lists() {
        let p = Property::from_text(
            "(ETH_BOARD (ETH_BOARD_PROPERTIES (IpAddress \"10.0.1.1\") (IpPort 12345))) (GENERAL (Encoder 1.5 2.5) (AxisName \"a\" \"b\"))",
        );
        let root = Node::root(&p);
        let props = root
            .need_group("ETH_BOARD")
            .unwrap()
            .need_group("ETH_BOARD_PROPERTIES")
            .unwrap();
        assert_eq!(props.string("IpAddress").unwrap(), "10.0.1.1");
        assert_eq!(props.number("IpPort").unwrap(), Some(12345.0));
        let g = root.need_group("GENERAL").unwrap();
        assert_eq!(g.need_numbers("Encoder", 2).unwrap(), [1.5, 2.5]);
        let e = g.need_numbers("Encoder", 3).unwrap_err();
        assert_eq!(e.param, "GENERAL/Encoder");
        assert_eq!(g.need_strings("AxisName", 2).unwrap(), ["a", "b"]);
        assert!(root.need_group("NOPE").is_err());
    }
}

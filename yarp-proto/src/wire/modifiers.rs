//! Carrier names with qualifiers, as C++ YARP writes them for a connection:
//! `fast_tcp+send.portmonitor+file.depthimage_compression_zlib+type.dll` is the carrier
//! `fast_tcp` with the qualifiers `send=portmonitor`, `file=...`, `type=dll`.
//!
//! The accepting side learns the qualifiers from the sender name of the connection
//! header, where C++ (`Protocol::getSenderSpecifier`) appends them to the port name as
//! lists: every `+` opens a list and every `.` separates words,
//!
//! ```text
//! /depthCamera/depthImage:o (send portmonitor) (file depthimage_compression_zlib) (type dll)
//! ```
//!
//! and the receiver (`Protocol::setRoute`) takes the first word as the sender's port and
//! rebuilds the carrier name from the lists.

use crate::Bottle;

/// A carrier and its qualifiers, in the order written.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct CarrierName {
    /// The carrier proper (`fast_tcp`).
    pub base: String,
    /// `(key, value)` of every `+key.value` (`+key` alone has an empty value).
    pub qualifiers: Vec<(String, String)>,
}

impl CarrierName {
    /// Splits `base+key.value+...`.
    pub fn parse(carrier: &str) -> CarrierName {
        let mut parts = carrier.split('+');
        let base = parts.next().unwrap_or_default().to_string();
        let qualifiers = parts
            .filter(|p| !p.is_empty())
            .map(|p| match p.split_once('.') {
                Some((k, v)) => (k.to_string(), v.to_string()),
                None => (p.to_string(), String::new()),
            })
            .collect();
        CarrierName { base, qualifiers }
    }

    /// The first value given to `key` (C++ `Bottle::find` on the sender specifier).
    pub fn find(&self, key: &str) -> Option<&str> {
        self.qualifiers
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    pub fn has_qualifiers(&self) -> bool {
        !self.qualifiers.is_empty()
    }

    /// The sender name a connecting port puts in its header: `port (k v) (k v)`, each
    /// `.` of a value a word break, as C++ writes it.
    pub fn sender_specifier(&self, port: &str) -> String {
        let mut out = port.to_string();
        for (k, v) in &self.qualifiers {
            out.push_str(" (");
            out.push_str(k);
            if !v.is_empty() {
                out.push(' ');
                out.push_str(&v.replace('.', " "));
            }
            out.push(')');
        }
        out
    }

    /// Reads a received sender name: the sender's port, and the qualifiers it carries
    /// (on the carrier `base`).
    pub fn from_sender_specifier(base: &str, sender: &str) -> (String, CarrierName) {
        let mut name = CarrierName {
            base: base.to_string(),
            qualifiers: Vec::new(),
        };
        if !sender.contains(' ') {
            return (sender.to_string(), name);
        }
        let b = Bottle::from_text(sender);
        let port = match b.get(0) {
            Some(v) => v.as_str().map_or_else(|| v.to_string(), str::to_string),
            None => return (sender.to_string(), name),
        };
        for v in b.iter().skip(1) {
            match v.as_list() {
                Some(l) => {
                    let word = |i: usize| {
                        l.get(i)
                            .map(|w| w.as_str().map_or_else(|| w.to_string(), str::to_string))
                            .unwrap_or_default()
                    };
                    name.qualifiers.push((word(0), word(1)));
                }
                None => name.qualifiers.push((v.to_string(), String::new())),
            }
        }
        (port, name)
    }
}

impl std::fmt::Display for CarrierName {
    /// `base+key.value+...`, as C++ rebuilds it on the receiving side.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.base)?;
        for (k, v) in &self.qualifiers {
            if v.is_empty() {
                write!(f, "+{k}")?;
            } else {
                write!(f, "+{k}.{v}")?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ERGOCUB_DEPTH: &str = "fast_tcp+send.portmonitor+file.depthimage_compression_zlib+recv.portmonitor+file.depthimage_compression_zlib+type.dll";

    #[test]
    fn the_ergocub_depth_carrier_splits_and_becomes_a_sender_specifier() {
        let c = CarrierName::parse(ERGOCUB_DEPTH);
        assert_eq!(c.base, "fast_tcp");
        assert_eq!(c.find("send"), Some("portmonitor"));
        assert_eq!(c.find("recv"), Some("portmonitor"));
        assert_eq!(c.find("file"), Some("depthimage_compression_zlib"));
        assert_eq!(c.find("type"), Some("dll"));
        assert_eq!(c.to_string(), ERGOCUB_DEPTH);
        assert_eq!(
            c.sender_specifier("/depthCamera/depthImage:o"),
            "/depthCamera/depthImage:o (send portmonitor) (file depthimage_compression_zlib) \
             (recv portmonitor) (file depthimage_compression_zlib) (type dll)"
        );
    }

    #[test]
    fn the_receiving_side_gets_the_port_and_the_carrier_back() {
        let sent = CarrierName::parse(ERGOCUB_DEPTH).sender_specifier("/out");
        let (port, c) = CarrierName::from_sender_specifier("fast_tcp", &sent);
        assert_eq!(port, "/out");
        assert_eq!(c.to_string(), ERGOCUB_DEPTH);
        // a plain sender name
        let (port, c) = CarrierName::from_sender_specifier("tcp", "/w");
        assert_eq!((port.as_str(), c.has_qualifiers()), ("/w", false));
    }

    #[test]
    fn dots_in_a_value_are_word_breaks_as_in_cpp() {
        let c = CarrierName::parse("tcp+recv.portmonitor+file.my.script+debug_compression_info");
        assert_eq!(c.find("file"), Some("my.script"));
        assert_eq!(c.find("debug_compression_info"), Some(""));
        assert_eq!(
            c.sender_specifier("/p"),
            "/p (recv portmonitor) (file my script) (debug_compression_info)"
        );
        assert_eq!(CarrierName::parse("tcp").qualifiers, vec![]);
    }
}

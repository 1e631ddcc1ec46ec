//! Contacts: where a port lives (name, carrier, host, port number), and the
//! `carrier://host:port/` and `carrier:/port/name` forms C++ YARP writes them in.

use std::fmt;

/// A port's contact information, as the name server and port descriptions carry it.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Contact {
    /// Registered port name (`/rd`); may be empty for an address-only contact.
    pub name: String,
    /// Carrier name (`tcp`, `fast_tcp`, `udp`, `text`, ...); empty when not specified.
    pub carrier: String,
    pub host: String,
    /// TCP/UDP port number; 0 when unknown.
    pub port: u16,
}

impl Contact {
    pub fn new(name: &str, carrier: &str, host: &str, port: u16) -> Contact {
        Contact {
            name: name.to_string(),
            carrier: carrier.to_string(),
            host: host.to_string(),
            port,
        }
    }

    /// The address form `tcp://127.0.0.1:10002/` used in port descriptions.
    pub fn to_uri(&self) -> String {
        let carrier = if self.carrier.is_empty() {
            "tcp"
        } else {
            &self.carrier
        };
        format!("{carrier}://{}:{}/", self.host, self.port)
    }

    /// Whether this contact has a usable network address.
    pub fn is_addressable(&self) -> bool {
        !self.host.is_empty() && self.port != 0
    }
}

impl fmt::Display for Contact {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} at {}", self.name, self.to_uri())
    }
}

/// A port name with an optional carrier prefix, as users write them:
/// `/port`, `udp://port` (= carrier udp, name `/port`), `tcp:/port`, `udp://cbcap/stateExt:i`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PortRef {
    pub carrier: Option<String>,
    pub name: String,
}

impl PortRef {
    /// Splits `carrier:/name` / `carrier://name` forms. A plain `/name` has no carrier.
    /// Anything before `:/` that is a bare word is taken as the carrier, as C++ does.
    pub fn parse(s: &str) -> PortRef {
        if !s.starts_with('/') {
            if let Some(idx) = s.find(":/") {
                let carrier = &s[..idx];
                if !carrier.is_empty()
                    && carrier
                        .bytes()
                        .all(|c| c.is_ascii_alphanumeric() || c == b'_' || c == b'+' || c == b'.')
                {
                    let rest = &s[idx + 1..];
                    // `udp://name` carries the name's own leading slash after `//`
                    let name = rest
                        .strip_prefix('/')
                        .filter(|r| r.starts_with('/'))
                        .unwrap_or(rest);
                    let name = if name.starts_with('/') {
                        name.to_string()
                    } else {
                        format!("/{name}")
                    };
                    return PortRef {
                        carrier: Some(carrier.to_string()),
                        name,
                    };
                }
            }
        }
        PortRef {
            carrier: None,
            name: s.to_string(),
        }
    }
}

impl fmt::Display for PortRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.carrier {
            // C++ writes `udp://cbcap/stateExt:i` for carrier udp and name /cbcap/stateExt:i
            Some(c) => write!(f, "{c}:/{}", self.name),
            None => f.write_str(&self.name),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn carrier_prefixed_names() {
        let r = PortRef::parse("udp://cbcap/stateExt:i");
        assert_eq!(r.carrier.as_deref(), Some("udp"));
        assert_eq!(r.name, "/cbcap/stateExt:i");
        assert_eq!(r.to_string(), "udp://cbcap/stateExt:i");
        let r = PortRef::parse("tcp:/rd");
        assert_eq!(
            (r.carrier.as_deref(), r.name.as_str()),
            (Some("tcp"), "/rd")
        );
        let r = PortRef::parse("/a:b");
        assert_eq!((r.carrier, r.name.as_str()), (None, "/a:b"));
        let r = PortRef::parse("fast_tcp://grabcap");
        assert_eq!(r.name, "/grabcap");
    }

    #[test]
    fn uri_form() {
        let c = Contact::new("/rd", "tcp", "127.0.0.1", 10002);
        assert_eq!(c.to_string(), "/rd at tcp://127.0.0.1:10002/");
    }
}

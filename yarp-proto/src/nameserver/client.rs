//! The client side: the exact request bytes C++ `NameClient` sends (one TCP connection per
//! request, no `CONNECT` header) and the parsing of the replies.
//!
//! Two kinds of request exist in C++, and they end differently:
//! * plain text commands (`query`, `unregister`, `announce`) are written as
//!   `NAME_SERVER <cmd>\n`;
//! * Bottle commands (`register`, `set ...`) go through the `name_ser` carrier, whose
//!   8-byte header `NAME_SER` followed by `VER ` reads `NAME_SERVER `, then the Bottle
//!   in text mode with every `"` removed, ended by `\r\n`.

use crate::contact::Contact;
use crate::nameserver::registry::atoi;
use crate::nameserver::reply::strip_quotes;
use crate::value::{Bottle, Value};

/// The end marker of old-style replies (followed by `\r\n`).
pub const END_OF_MESSAGE: &str = "*** end of message";

/// The carriers a C++ 3.12 port lists in its `offers` / `accepts` properties, in the
/// order `Carriers::listCarriers()` gives them.
pub const CPP_CARRIERS: &[&str] = &[
    "http",
    "name_ser",
    "local",
    "tcp",
    "fast_tcp",
    "mcast",
    "udp",
    "text",
    "text_ack",
    "bayer",
    "human",
    "mjpeg",
    "portmonitor",
    "priority",
    "shmem",
    "unix_stream",
    "websocket",
];

fn text_request(cmd: &str, name: &str) -> Vec<u8> {
    format!("NAME_SERVER {cmd} {name}\n").into_bytes()
}

/// `NAME_SERVER query <name>\n`.
pub fn request_query(name: &str) -> Vec<u8> {
    text_request("query", name)
}

/// `NAME_SERVER unregister <name>\n`.
pub fn request_unregister(name: &str) -> Vec<u8> {
    text_request("unregister", name)
}

/// `NAME_SERVER announce <name>\n` (sent after a port is ready; reply `[ok]\r\n`).
pub fn request_announce(name: &str) -> Vec<u8> {
    text_request("announce", name)
}

/// `NAME_SERVER get <name> <key>\n` (as `yarp name get` sends it).
pub fn request_get(name: &str, key: &str) -> Vec<u8> {
    format!("NAME_SERVER get {name} {key}\n").into_bytes()
}

/// `NAME_SERVER check <name> <key> <value>\n`.
pub fn request_check(name: &str, key: &str, value: &str) -> Vec<u8> {
    format!("NAME_SERVER check {name} {key} {value}\n").into_bytes()
}

/// `NAME_SERVER list [<prefix>]\n`.
pub fn request_list(prefix: Option<&str>) -> Vec<u8> {
    match prefix {
        Some(p) => format!("NAME_SERVER list {p}\n").into_bytes(),
        None => b"NAME_SERVER list\n".to_vec(),
    }
}

/// A Bottle command as the `name_ser` carrier sends it: `NAME_SERVER ` + text without
/// quotes + `\r\n`.
pub fn request_bottle(cmd: &Bottle) -> Vec<u8> {
    let mut out = b"NAME_SERVER ".to_vec();
    out.extend_from_slice(&strip_quotes(&cmd.to_text()));
    out.extend_from_slice(b"\r\n");
    out
}

/// What `NameClient::registerName(name, suggest)` puts in its `register` command.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RegisterRequest {
    /// `None` (or empty) lets the server choose a name (`...`).
    pub name: Option<String>,
    pub carrier: Option<String>,
    pub host: Option<String>,
    pub port: Option<u16>,
    /// Nested type name (`register ... <type>`).
    pub type_name: Option<String>,
}

impl RegisterRequest {
    /// `register <name>`: everything else chosen by the server.
    pub fn name(name: &str) -> RegisterRequest {
        RegisterRequest {
            name: Some(name.to_string()),
            ..Default::default()
        }
    }

    /// `register <name> <carrier> <host> <port>`.
    pub fn explicit(name: &str, carrier: &str, host: &str, port: u16) -> RegisterRequest {
        RegisterRequest {
            name: Some(name.to_string()),
            carrier: Some(carrier.to_string()),
            host: Some(host.to_string()),
            port: Some(port),
            type_name: None,
        }
    }

    /// The command Bottle, with C++'s rules: the long form (with `...` for what is
    /// missing) when an address or port or type is given, else only the carrier if any.
    pub fn to_bottle(&self) -> Bottle {
        let mut cmd = Bottle::new();
        cmd.push("register");
        match self.name.as_deref() {
            Some(n) if !n.is_empty() => cmd.push(n),
            _ => cmd.push("..."),
        };
        let nonempty =
            |o: &Option<String>| o.as_deref().filter(|s| !s.is_empty()).map(String::from);
        let carrier = nonempty(&self.carrier);
        let host = nonempty(&self.host);
        let typ = nonempty(&self.type_name);
        let port = self.port.filter(|p| *p != 0);
        if host.is_some() || port.is_some() || typ.is_some() {
            cmd.push(carrier.unwrap_or_else(|| "...".into()));
            cmd.push(host.unwrap_or_else(|| "...".into()));
            match port {
                Some(p) => cmd.push(p as i32),
                None => cmd.push("..."),
            };
            if let Some(t) = typ {
                cmd.push(t);
            }
        } else if let Some(c) = carrier {
            cmd.push(c);
        }
        cmd
    }
}

/// The `register` request bytes (`NAME_SERVER register ...\r\n`).
pub fn request_register(req: &RegisterRequest) -> Vec<u8> {
    request_bottle(&req.to_bottle())
}

/// `NAME_SERVER set <name> <key> <values...>\r\n`.
pub fn request_set(name: &str, key: &str, values: &[Value]) -> Vec<u8> {
    let mut cmd = Bottle::new();
    cmd.push("set").push(name).push(key);
    for v in values {
        cmd.push(v.clone());
    }
    request_bottle(&cmd)
}

fn carriers() -> Vec<Value> {
    CPP_CARRIERS.iter().map(|c| Value::from(*c)).collect()
}

/// `set <name> offers <the C++ carrier list>`.
pub fn request_set_offers(name: &str) -> Vec<u8> {
    request_set(name, "offers", &carriers())
}

/// `set <name> accepts <the C++ carrier list>`.
pub fn request_set_accepts(name: &str) -> Vec<u8> {
    request_set(name, "accepts", &carriers())
}

/// `set <name> ips <addresses...>` (C++ lists every interface address, e.g. `127.0.0.1 ::1`).
pub fn request_set_ips(name: &str, ips: &[&str]) -> Vec<u8> {
    let v: Vec<Value> = ips.iter().map(|s| Value::from(*s)).collect();
    request_set(name, "ips", &v)
}

/// `set <name> process <pid>`.
pub fn request_set_process(name: &str, pid: i32) -> Vec<u8> {
    request_set(name, "process", &[Value::Int32(pid)])
}

/// Splits like C++ `NameClient`'s `Params`: on spaces and newlines, dropping other control
/// characters (so `\r` disappears), at most 20 words.
fn params(text: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    for ch in text.chars().chain(std::iter::once('\0')) {
        if out.len() >= 20 {
            break;
        }
        if ch == ' ' || ch == '\n' || ch == '\0' {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
        } else if (ch as u32) >= 32 {
            cur.push(ch);
        }
    }
    out
}

fn contact(name: &str, carrier: &str, host: &str, port: i64) -> Option<Contact> {
    let port = u16::try_from(port).ok()?;
    Some(Contact::new(name, carrier, host, port))
}

/// Parses `registration name /x ip 127.0.0.1 port 10002 type tcp` (the reply to `query`,
/// `register`, or a line of `list`), as C++ `NameClient::extractAddress(string)`.
/// `None` for an unknown name (the reply is only the end marker) or a port number that
/// does not fit a TCP port.
pub fn parse_registration(reply: &str) -> Option<Contact> {
    let p = params(reply);
    if p.len() >= 9 && p[0] == "registration" {
        return contact(&p[2], &p[8], &p[4], atoi(&p[6]) as i64);
    }
    None
}

/// Parses a registration reply read as a Bottle (what C++ does for `register` sent as a
/// Bottle: it reads the first reply line in text mode).
pub fn parse_registration_bottle(reply: &Bottle) -> Option<Contact> {
    if reply.len() >= 9 && reply.get(0).and_then(|v| v.as_str()) == Some("registration") {
        let s = |i: usize| {
            reply
                .get(i)
                .and_then(|v| v.as_str())
                .unwrap_or("")
                .to_string()
        };
        let port = reply.get(6).and_then(|v| v.as_i64()).unwrap_or(0);
        return contact(&s(2), &s(8), &s(4), port);
    }
    None
}

/// A parsed `port <name> property <key> = <values...>` line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PropertyReply {
    pub port: String,
    pub key: String,
    pub values: Vec<String>,
}

/// Parses the reply of `set` / `get` (text form). `None` when the port is unknown (only
/// the end marker comes back).
pub fn parse_property_reply(reply: &str) -> Option<PropertyReply> {
    let line = reply.lines().next()?;
    let w: Vec<&str> = line.split_whitespace().collect();
    if w.len() >= 5 && w[0] == "port" && w[2] == "property" && w[4] == "=" {
        return Some(PropertyReply {
            port: w[1].to_string(),
            key: w[3].to_string(),
            values: w[5..].iter().map(|s| s.to_string()).collect(),
        });
    }
    None
}

/// A parsed `port <name> property <key> value <v> present true|false` line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckReply {
    pub port: String,
    pub key: String,
    pub value: String,
    pub present: bool,
}

/// Parses the reply of `check`.
pub fn parse_check_reply(reply: &str) -> Option<CheckReply> {
    let line = reply.lines().next()?;
    let w: Vec<&str> = line.split_whitespace().collect();
    if w.len() == 8 && w[0] == "port" && w[2] == "property" && w[4] == "value" && w[6] == "present"
    {
        return Some(CheckReply {
            port: w[1].to_string(),
            key: w[3].to_string(),
            value: w[5].to_string(),
            present: w[7] == "true",
        });
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests() {
        assert_eq!(request_query("/r"), b"NAME_SERVER query /r\n");
        assert_eq!(
            request_register(&RegisterRequest::name("/x")),
            b"NAME_SERVER register /x\r\n"
        );
        assert_eq!(
            request_register(&RegisterRequest::explicit("/c", "tcp", "127.0.0.1", 30010)),
            b"NAME_SERVER register /c tcp 127.0.0.1 30010\r\n"
        );
        let r = RegisterRequest {
            name: None,
            port: Some(5),
            ..Default::default()
        };
        assert_eq!(
            request_register(&r),
            b"NAME_SERVER register ... ... ... 5\r\n"
        );
        assert_eq!(
            request_set_ips("/x", &["127.0.0.1", "::1"]),
            b"NAME_SERVER set /x ips 127.0.0.1 ::1\r\n"
        );
        assert_eq!(
            request_set_process("/x", 42),
            b"NAME_SERVER set /x process 42\r\n"
        );
    }

    #[test]
    fn parsing() {
        let c = parse_registration(
            "registration name /r ip 127.0.0.1 port 10002 type tcp\r\n*** end of message\r\n",
        )
        .unwrap();
        assert_eq!(c, Contact::new("/r", "tcp", "127.0.0.1", 10002));
        assert_eq!(parse_registration("*** end of message\r\n"), None);
        let b = Bottle::from_text("registration name /r ip 127.0.0.1 port 10002 type tcp");
        assert_eq!(parse_registration_bottle(&b), Some(c));
        let p = parse_property_reply("port /r property ips = 127.0.0.1 ::1\r\n").unwrap();
        assert_eq!(p.values, vec!["127.0.0.1", "::1"]);
        let p = parse_property_reply("port /r property x =\r\n").unwrap();
        assert!(p.values.is_empty());
        let c = parse_check_reply("port /b property tags value beta present true\r\n").unwrap();
        assert!(c.present);
    }
}

//! Carriers and the connection header: the first 8 bytes of every connection say which
//! carrier (protocol) the connecting side speaks.
//!
//! The tcp family uses a YARP number `7777 + specifier`; C++ matches a carrier when
//! `specifier % 16` equals its code (and, for tcp / fast_tcp, when bit 128 "acks
//! required" agrees). Other carriers use 8 ASCII bytes. Carriers are described by
//! [`CarrierSpec`] rows in a [`CarrierRegistry`], tried in order exactly as C++
//! `Carriers::chooseCarrier(header)` tries its delegates; new carriers are added with
//! [`CarrierRegistry::register`].

use super::error::WireError;
use super::number::YarpNumber;

/// A tcp-family header carries the YARP number `SPECIFIER_BASE + specifier`.
pub const SPECIFIER_BASE: i32 = 7777;
/// Specifier bit saying the receiver must acknowledge every message.
pub const ACK_FLAG: i32 = 128;

/// Specifier codes as C++ YARP 3.12 defines them (`getSpecifierCode()`).
pub mod specifier {
    /// `UdpCarrier`: header 7777.
    pub const UDP: i32 = 0;
    /// `McastCarrier`: header 7778.
    pub const MCAST: i32 = 1;
    /// `TcpCarrier` (tcp = 3 + 128 = header 7908, fast_tcp = 3 = header 7780).
    pub const TCP: i32 = 3;
    /// `ShmemCarrier` (plugin): header 7791.
    pub const SHMEM: i32 = 14;
}

/// What C++ sends to a peer whose first 8 bytes match no carrier, before closing.
pub const PROTOCOL_NOT_FOUND: &str = "* Error. Protocol not found.\r\n\
* Hello. You appear to be trying to communicate with a YARP Port.\r\n\
* The first 8 bytes sent to a YARP Port are critical for identifying the\r\n\
* protocol you wish to speak.\r\n\
* The first 8 bytes you sent were not associated with any particular protocol.\r\n\
* If you are a human, try typing \"CONNECT foo\" followed by a <RETURN>.\r\n\
* The 8 bytes \"CONNECT \" correspond to a simple text-mode protocol.\r\n\
* Goodbye.\r\n";

/// A carrier, by name. The built-in ones are those C++ YARP 3.12 registers in
/// `Carriers::Carriers()` plus the `shmem` plugin; [`Carrier::Custom`] names carriers
/// registered by users of this crate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Carrier {
    /// `tcp`: binary framing with acknowledgements.
    Tcp,
    /// `fast_tcp`: binary framing, no acknowledgements.
    FastTcp,
    /// `udp`: tcp-family handshake on TCP, data in UDP datagrams.
    Udp,
    /// `mcast`: tcp-family handshake (plus a multicast address), data in UDP multicast.
    Mcast,
    /// `shmem` (plugin): tcp-family handshake, then shared memory.
    Shmem,
    /// `local`: in-process (`LOCALITY` header, then object references).
    Local,
    /// `unix_stream` (plugin): `UNIX_STR` and the sender name on TCP, then index-less
    /// messages over a Unix socket.
    UnixStream,
    /// `unix_stream_ack` (plugin): as `unix_stream` (`UNIX_ACK`), with `ACK\0` answers.
    UnixStreamAck,
    /// `text`: line-based, `CONNECT ` header.
    Text,
    /// `text_ack`: line-based with `<ACK>` lines, `CONNACK ` header.
    TextAck,
    /// `name_ser`: `NAME_SERVER <command>` lines to the name server.
    NameSer,
    /// `http`: `GET /...` or `POST /form`.
    Http,
    /// `mjpeg` (plugin): a pull connection; the reader sends `GET /?action=stream` and
    /// the writer answers with a multipart stream of JPEG images ([`super::mjpeg`]).
    Mjpeg,
    /// A carrier added to a [`CarrierRegistry`] by name.
    Custom(&'static str),
}

impl Carrier {
    /// The carrier name as C++ prints it (`tcp`, `fast_tcp`, `text_ack`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            Carrier::Tcp => "tcp",
            Carrier::FastTcp => "fast_tcp",
            Carrier::Udp => "udp",
            Carrier::Mcast => "mcast",
            Carrier::Shmem => "shmem",
            Carrier::Local => "local",
            Carrier::UnixStream => "unix_stream",
            Carrier::UnixStreamAck => "unix_stream_ack",
            Carrier::Text => "text",
            Carrier::TextAck => "text_ack",
            Carrier::NameSer => "name_ser",
            Carrier::Http => "http",
            Carrier::Mjpeg => "mjpeg",
            Carrier::Custom(name) => name,
        }
    }

    /// A built-in carrier by its name (`"tcp"`, `"fast_tcp"`, ...).
    pub fn from_name(name: &str) -> Option<Carrier> {
        BUILTIN.iter().map(|s| s.carrier).find(|c| c.name() == name)
    }

    /// The built-in description of this carrier. A [`Carrier::Custom`] gets a
    /// pass-through description (its real one lives in the registry that knows it).
    pub fn spec(&self) -> CarrierSpec {
        BUILTIN
            .iter()
            .find(|s| s.carrier == *self)
            .copied()
            .unwrap_or(CarrierSpec {
                carrier: *self,
                header: [0; 8],
                pattern: HeaderPattern::Custom(|_| false),
                framing: Framing::Raw,
                requires_ack: false,
                supports_reply: false,
            })
    }

    /// The 8 header bytes this carrier sends when it opens a connection.
    pub fn header(&self) -> [u8; 8] {
        self.spec().header
    }

    /// Whether the writer opens the connection (C++ `Carrier::isPush`). `mjpeg` is pulled:
    /// the reading port connects to the writing one, as a web browser to a camera.
    pub fn is_push(&self) -> bool {
        !matches!(self, Carrier::Mjpeg)
    }
}

impl std::fmt::Display for Carrier {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How a carrier's connection continues after its 8 header bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Framing {
    /// tcp / fast_tcp: sender name, header reply, then indexed messages; acks and
    /// index-less replies flow back.
    Stream,
    /// udp / mcast / shmem: the tcp-family handshake (sender name, header reply with the
    /// data port); afterwards the data leaves this TCP stream (bytes pass through raw).
    Handshake,
    /// local / unix_stream: sender name only, no reply; afterwards bytes pass through raw.
    Local,
    /// text / text_ack: `CONNECT <name>` line, `Welcome <name>` line, command lines.
    Text,
    /// name_ser: `NAME_SERVER <command>` lines, plain text replies.
    NameServer,
    /// Not decoded here (http, unknown custom carriers): bytes pass through raw.
    Raw,
}

/// How a carrier recognises its 8 header bytes.
#[derive(Debug, Clone, Copy)]
pub enum HeaderPattern {
    /// A YARP number `7777 + s` with `s % 16 == code` (C++ signed remainder) and, when
    /// `ack` is given, bit 128 of `s` equal to it.
    Specifier { code: i32, ack: Option<bool> },
    /// These 8 bytes exactly.
    Exact([u8; 8]),
    /// Any test.
    Custom(fn(&[u8; 8]) -> bool),
}

impl HeaderPattern {
    pub fn matches(&self, header: &[u8; 8]) -> bool {
        match *self {
            HeaderPattern::Specifier { code, ack } => match specifier_of(header) {
                Some(s) => {
                    s % 16 == code
                        && match ack {
                            Some(a) => ((s & ACK_FLAG) != 0) == a,
                            None => true,
                        }
                }
                None => false,
            },
            HeaderPattern::Exact(bytes) => *header == bytes,
            HeaderPattern::Custom(f) => f(header),
        }
    }
}

/// The specifier of a tcp-family header as C++ `AbstractCarrier::getSpecifier` computes
/// it (`value - 7777` for non-negative values, the value itself otherwise); `None` when
/// the bytes are not a YARP number.
pub fn specifier_of(header: &[u8]) -> Option<i32> {
    let v = YarpNumber::decode(header)?.0;
    Some(if v >= 0 { v - SPECIFIER_BASE } else { v })
}

/// One row of the carrier table.
#[derive(Debug, Clone, Copy)]
pub struct CarrierSpec {
    pub carrier: Carrier,
    /// The 8 bytes this carrier sends as its header (C++ `getHeader`).
    pub header: [u8; 8],
    /// How an incoming header is recognised (C++ `checkHeader`).
    pub pattern: HeaderPattern,
    pub framing: Framing,
    /// The receiver acknowledges every message (tcp, shmem, text_ack).
    pub requires_ack: bool,
    /// Replies can travel back on the connection (C++ `supportReply`).
    pub supports_reply: bool,
}

fn http_header(h: &[u8; 8]) -> bool {
    (h.starts_with(b"GET /") && !h.starts_with(b"GET /?ac") && !h.starts_with(b"GET /?ws"))
        || h.starts_with(b"POST /fo")
}

/// The built-in carriers in C++ `Carriers` order (http, name_ser, local, tcp, fast_tcp,
/// mcast, udp, text, text_ack), then the `shmem`, `unix_stream` and `mjpeg` plugins.
pub static BUILTIN: [CarrierSpec; 13] = [
    CarrierSpec {
        carrier: Carrier::Http,
        header: *b"GET / HT",
        pattern: HeaderPattern::Custom(http_header),
        framing: Framing::Raw,
        requires_ack: false,
        supports_reply: true,
    },
    CarrierSpec {
        carrier: Carrier::NameSer,
        header: *b"NAME_SER",
        pattern: HeaderPattern::Exact(*b"NAME_SER"),
        framing: Framing::NameServer,
        requires_ack: false,
        supports_reply: true,
    },
    CarrierSpec {
        carrier: Carrier::Local,
        header: *b"LOCALITY",
        pattern: HeaderPattern::Exact(*b"LOCALITY"),
        framing: Framing::Local,
        requires_ack: false,
        supports_reply: true,
    },
    CarrierSpec {
        carrier: Carrier::Tcp,
        header: YarpNumber(SPECIFIER_BASE + specifier::TCP + ACK_FLAG).to_bytes(),
        pattern: HeaderPattern::Specifier {
            code: specifier::TCP,
            ack: Some(true),
        },
        framing: Framing::Stream,
        requires_ack: true,
        supports_reply: true,
    },
    CarrierSpec {
        carrier: Carrier::FastTcp,
        header: YarpNumber(SPECIFIER_BASE + specifier::TCP).to_bytes(),
        pattern: HeaderPattern::Specifier {
            code: specifier::TCP,
            ack: Some(false),
        },
        framing: Framing::Stream,
        requires_ack: false,
        supports_reply: true,
    },
    CarrierSpec {
        carrier: Carrier::Mcast,
        header: YarpNumber(SPECIFIER_BASE + specifier::MCAST).to_bytes(),
        pattern: HeaderPattern::Specifier {
            code: specifier::MCAST,
            ack: None,
        },
        framing: Framing::Handshake,
        requires_ack: false,
        supports_reply: false,
    },
    CarrierSpec {
        carrier: Carrier::Udp,
        header: YarpNumber(SPECIFIER_BASE + specifier::UDP).to_bytes(),
        pattern: HeaderPattern::Specifier {
            code: specifier::UDP,
            ack: None,
        },
        framing: Framing::Handshake,
        requires_ack: false,
        supports_reply: false,
    },
    CarrierSpec {
        carrier: Carrier::Text,
        header: *b"CONNECT ",
        pattern: HeaderPattern::Exact(*b"CONNECT "),
        framing: Framing::Text,
        requires_ack: false,
        supports_reply: false,
    },
    CarrierSpec {
        carrier: Carrier::TextAck,
        header: *b"CONNACK ",
        pattern: HeaderPattern::Exact(*b"CONNACK "),
        framing: Framing::Text,
        requires_ack: true,
        supports_reply: true,
    },
    CarrierSpec {
        carrier: Carrier::Shmem,
        header: YarpNumber(SPECIFIER_BASE + specifier::SHMEM).to_bytes(),
        pattern: HeaderPattern::Specifier {
            code: specifier::SHMEM,
            ack: None,
        },
        framing: Framing::Handshake,
        requires_ack: true,
        supports_reply: true,
    },
    CarrierSpec {
        carrier: Carrier::UnixStream,
        header: *b"UNIX_STR",
        pattern: HeaderPattern::Exact(*b"UNIX_STR"),
        framing: Framing::Local,
        requires_ack: false,
        supports_reply: false,
    },
    CarrierSpec {
        carrier: Carrier::UnixStreamAck,
        header: *b"UNIX_ACK",
        pattern: HeaderPattern::Exact(*b"UNIX_ACK"),
        framing: Framing::Local,
        requires_ack: true,
        supports_reply: false,
    },
    CarrierSpec {
        carrier: Carrier::Mjpeg,
        header: super::mjpeg::HEADER,
        pattern: HeaderPattern::Exact(super::mjpeg::HEADER),
        framing: Framing::Raw,
        requires_ack: false,
        supports_reply: false,
    },
];

/// The carrier table used to classify incoming headers.
#[derive(Debug, Clone)]
pub struct CarrierRegistry {
    specs: Vec<CarrierSpec>,
}

impl Default for CarrierRegistry {
    fn default() -> Self {
        CarrierRegistry::builtin()
    }
}

impl CarrierRegistry {
    /// The built-in carriers ([`BUILTIN`]).
    pub fn builtin() -> CarrierRegistry {
        CarrierRegistry {
            specs: BUILTIN.to_vec(),
        }
    }

    /// A registry that knows no carrier.
    pub fn empty() -> CarrierRegistry {
        CarrierRegistry { specs: Vec::new() }
    }

    /// Adds a carrier, tried after those already present.
    pub fn register(&mut self, spec: CarrierSpec) -> &mut Self {
        self.specs.push(spec);
        self
    }

    pub fn specs(&self) -> &[CarrierSpec] {
        &self.specs
    }

    /// The first carrier whose pattern matches, as C++ `chooseCarrier(header)`.
    pub fn classify(&self, header: &[u8; 8]) -> Result<ConnectionHeader, WireError> {
        self.specs
            .iter()
            .find(|s| s.pattern.matches(header))
            .map(|s| ConnectionHeader {
                spec: *s,
                raw: *header,
            })
            .ok_or(WireError::UnknownProtocol { header: *header })
    }
}

/// Classifies a header against the built-in carriers.
pub fn classify_header(header: &[u8; 8]) -> Result<ConnectionHeader, WireError> {
    BUILTIN
        .iter()
        .find(|s| s.pattern.matches(header))
        .map(|s| ConnectionHeader {
            spec: *s,
            raw: *header,
        })
        .ok_or(WireError::UnknownProtocol { header: *header })
}

/// A classified connection header.
#[derive(Debug, Clone, Copy)]
pub struct ConnectionHeader {
    pub spec: CarrierSpec,
    /// The 8 bytes as received.
    pub raw: [u8; 8],
}

impl PartialEq for ConnectionHeader {
    fn eq(&self, other: &Self) -> bool {
        self.spec.carrier == other.spec.carrier && self.raw == other.raw
    }
}

impl ConnectionHeader {
    /// The header a carrier sends when connecting.
    pub fn outgoing(carrier: Carrier) -> ConnectionHeader {
        let spec = carrier.spec();
        ConnectionHeader {
            spec,
            raw: spec.header,
        }
    }

    pub fn carrier(&self) -> Carrier {
        self.spec.carrier
    }

    /// The YARP number value of a tcp-family header (`7908` for tcp).
    pub fn value(&self) -> Option<i32> {
        YarpNumber::decode(&self.raw).map(|n| n.0)
    }

    /// The specifier of a tcp-family header (`131` for tcp).
    pub fn specifier(&self) -> Option<i32> {
        specifier_of(&self.raw)
    }

    pub fn framing(&self) -> Framing {
        self.spec.framing
    }

    pub fn requires_ack(&self) -> bool {
        self.spec.requires_ack
    }
}

/// C++ reads at most this many bytes of a sender name (longer lengths are clamped).
pub const MAX_SENDER_NAME: usize = 1000;

/// Appends a tcp-family sender name: int32 LE length including the NUL, name, NUL.
pub fn encode_sender_name(name: &[u8], out: &mut Vec<u8>) {
    out.extend_from_slice(&((name.len() as i32).wrapping_add(1)).to_le_bytes());
    out.extend_from_slice(name);
    out.push(0);
}

/// The header reply of the accepting side: its own port number as a YARP number.
pub fn encode_header_reply(port: i32) -> [u8; 8] {
    YarpNumber(port).to_bytes()
}

/// Everything the connecting side sends before its first message, as C++ does:
/// tcp family and local: header + sender name; text carriers: `CONNECT <name>\r\n` /
/// `CONNACK <name>\r\n`; name_ser: just `NAME_SER` (the first request then starts with
/// `VER `, see [`name_server_request`]); http: `GET / HTTP/1.0\r\n\r\n`; custom: the
/// header bytes.
pub fn encode_connection_start(spec: &CarrierSpec, sender: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + sender.len());
    match spec.framing {
        Framing::Stream | Framing::Handshake | Framing::Local => {
            out.extend_from_slice(&spec.header);
            encode_sender_name(sender, &mut out);
        }
        Framing::Text => {
            out.extend_from_slice(&spec.header);
            out.extend_from_slice(sender);
            out.extend_from_slice(b"\r\n");
        }
        Framing::NameServer => out.extend_from_slice(&spec.header),
        Framing::Raw if spec.carrier == Carrier::Http => {
            out.extend_from_slice(b"GET / HTTP/1.0\r\n\r\n")
        }
        Framing::Raw => out.extend_from_slice(&spec.header),
    }
    out
}

/// A complete name-server request line as the C++ client sends it, with no
/// `CONNECT` header: `NAME_SERVER <command><eol>` (C++ uses `\r\n` for register/set and
/// `\n` for the others).
pub fn name_server_request(command: &str, eol: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(12 + command.len() + eol.len());
    out.extend_from_slice(b"NAME_SERVER ");
    out.extend_from_slice(command.as_bytes());
    out.extend_from_slice(eol.as_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::number::encode;

    fn c(h: [u8; 8]) -> Result<Carrier, WireError> {
        classify_header(&h).map(|h| h.carrier())
    }

    #[test]
    fn classifies_like_cpp() {
        assert_eq!(c(encode(7908)), Ok(Carrier::Tcp));
        assert_eq!(c(encode(7780)), Ok(Carrier::FastTcp));
        assert_eq!(c(encode(7777)), Ok(Carrier::Udp));
        assert_eq!(c(encode(7778)), Ok(Carrier::Mcast));
        assert_eq!(c(encode(7791)), Ok(Carrier::Shmem));
        // C++ compares `specifier % 16`: 7777+16+3 is still fast_tcp, 7777+16 udp.
        assert_eq!(c(encode(7777 + 19)), Ok(Carrier::FastTcp));
        assert_eq!(c(encode(7777 + 16)), Ok(Carrier::Udp));
        assert_eq!(c(*b"CONNECT "), Ok(Carrier::Text));
        assert_eq!(c(*b"CONNACK "), Ok(Carrier::TextAck));
        assert_eq!(c(*b"NAME_SER"), Ok(Carrier::NameSer));
        assert_eq!(c(*b"LOCALITY"), Ok(Carrier::Local));
        assert_eq!(c(*b"UNIX_STR"), Ok(Carrier::UnixStream));
        assert_eq!(c(*b"UNIX_ACK"), Ok(Carrier::UnixStreamAck));
        assert_eq!(c(*b"GET /foo"), Ok(Carrier::Http));
        assert_eq!(c(*b"POST /fo"), Ok(Carrier::Http));
        // the mjpeg plug-in's request (http leaves it alone)
        assert_eq!(c(*b"GET /?ac"), Ok(Carrier::Mjpeg));
        assert!(c(*b"GET /?ws").is_err());
        assert_eq!(
            c(*b"ping\n\0\0\0"),
            Err(WireError::UnknownProtocol {
                header: *b"ping\n\0\0\0"
            })
        );
        // small or negative YARP numbers are no carrier
        assert!(c(encode(5)).is_err());
        assert!(c(encode(-1)).is_err());
        // ...but C++ also applies `% 16` to negative values, so -16 or i32::MIN is udp
        assert_eq!(c(encode(-16)), Ok(Carrier::Udp));
        assert_eq!(c(encode(i32::MIN)), Ok(Carrier::Udp));
    }

    #[test]
    fn headers_and_names() {
        assert_eq!(Carrier::Tcp.header(), encode(7908));
        assert_eq!(Carrier::FastTcp.header(), encode(7780));
        assert_eq!(Carrier::Udp.header(), encode(7777));
        assert_eq!(Carrier::from_name("text_ack"), Some(Carrier::TextAck));
        assert_eq!(
            classify_header(&encode(7908)).map(|h| h.specifier()),
            Ok(Some(131))
        );
        let mut out = Vec::new();
        encode_sender_name(b"/w", &mut out);
        assert_eq!(out, [3, 0, 0, 0, b'/', b'w', 0]);
        assert_eq!(
            encode_connection_start(&Carrier::Text.spec(), b"/w"),
            b"CONNECT /w\r\n"
        );
        assert_eq!(encode_header_reply(10002), encode(10002));
    }

    #[test]
    fn registry_is_extensible() {
        let mut reg = CarrierRegistry::empty();
        assert!(reg.classify(b"HUMANITY").is_err());
        reg.register(CarrierSpec {
            carrier: Carrier::Custom("human"),
            header: *b"HUMANITY",
            pattern: HeaderPattern::Exact(*b"HUMANITY"),
            framing: Framing::Raw,
            requires_ack: false,
            supports_reply: false,
        });
        assert_eq!(
            reg.classify(b"HUMANITY").map(|h| h.carrier()),
            Ok(Carrier::Custom("human"))
        );
    }
}

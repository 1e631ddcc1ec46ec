//! The YARP name server protocol, free of sockets: the registry state machine that
//! C++ `yarpserver` 3.12 runs (`NameServiceOnTriples` + `AllocatorOnTriples` +
//! the `announce` part of the subscriber), the exact reply bytes it produces, the
//! requests the C++ client (`NameClient`) sends and the parsing of their replies, and
//! the `yarp.conf` lookup of `NameConfig`.
//!
//! ```
//! use yarp_proto::nameserver::{Registry, RegistryConfig, reply_text};
//! use yarp_proto::Bottle;
//! let mut reg = Registry::new(RegistryConfig::new("127.0.0.1", 10000));
//! let reply = reg.apply(&Bottle::from_text("register /a"), Some("127.0.0.1"));
//! assert_eq!(
//!     reply_text(&reply),
//!     b"registration name /a ip 127.0.0.1 port 10002 type tcp\r\n*** end of message\r\n"
//! );
//! ```
//!
//! Facts carried over from the C++ sources (and checked against recordings):
//!
//! * Port numbers are handed out from `socket + 2` upwards by a cursor that only grows;
//!   a name that registers again gets back the number it had if that number is free
//!   (the "prefer" table); freed numbers are reused (lowest first, compared as text)
//!   only once the cursor reached `socket + 9999`. Explicitly requested numbers are not
//!   checked against the pool (C++ does not either).
//! * `mcast` registrations without an address get `224.1.x.y` groups; the first one is
//!   `224.1.1.3` (C++ starts its cursor at 1 and increments before use); freed groups are
//!   reused first.
//! * Properties (including `carrier`, `host` and `socket`, which live in the same table)
//!   are kept sorted by value, as the SQLite index C++ scans returns them; `list` is sorted
//!   by port name.

mod client;
mod config;
mod registry;
mod reply;

pub use client::{
    parse_check_reply, parse_property_reply, parse_registration, parse_registration_bottle,
    request_announce, request_bottle, request_check, request_get, request_list, request_query,
    request_register, request_set, request_set_accepts, request_set_ips, request_set_offers,
    request_set_process, request_unregister, CheckReply, PropertyReply, RegisterRequest,
    CPP_CARRIERS, END_OF_MESSAGE,
};
pub use config::{
    config_file_name, config_home, format_conf, namespace, parse_conf, ConfAddress,
    CONFIG_FILENAME, NAMESPACE_FILENAME,
};
pub use registry::{parse_name, ParsedName, Registry, RegistryConfig, FALLBACK_HOST};
pub use reply::{is_old_reply, reply_binary, reply_text, strip_quotes};

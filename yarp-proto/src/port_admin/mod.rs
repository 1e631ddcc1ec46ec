//! The port administration protocol, free of sockets: what a YARP port answers when a
//! peer connects to it and sends commands instead of data (C++ `PortCore::adminBlock`,
//! `PortCore::describe`/`addOutput`/`removeOutput`/`removeInput` and the text commands of
//! `PortCoreInputUnit`).
//!
//! The I/O layer keeps the live state of a port and hands a [`PortSnapshot`] to these
//! functions; they return the reply (a Bottle or the text C++ writes back) and, for
//! commands that change the port, a list of [`AdminAction`]s for the I/O layer to carry
//! out. Where C++'s reply depends on how an action went (`[add]`, `[del]`, `/port`,
//! `!/port`, `~/port`, some `[prop] [set]` forms), the reply is finished with one of the
//! `format_*` functions once the outcome is known.
//!
//! ```
//! use yarp_proto::port_admin::{handle_admin, PortSnapshot, Route};
//! use yarp_proto::Bottle;
//! let mut port = PortSnapshot::new("/rd", "tcp", "127.0.0.1", 10002);
//! port.inputs.push(Route::new("/w", "/rd", "tcp").into());
//! let r = handle_admin(&Bottle::from_text("[list] [in]"), &port);
//! assert_eq!(r.reply.to_string(), "\"/w\"");
//! ```
//!
//! Text-mode sessions (`CONNECT name` / `CONNACK name`, then lines): every line is a port
//! command whose *first character* decides what happens, see [`TextCommand`].

mod admin;
mod command;
mod describe;

pub use admin::{
    admin_help, format_add_result, format_atch_result, format_del_result, format_prop_set_result,
    format_unknown_result, handle_admin, reply_text_line, responder_text_lines, AddOutcome,
    AdminAction, AdminResponse, Direction, Pending, ADMIN_VERSION,
};
pub use command::TextCommand;
pub use describe::{
    add_output_text, contact_uri, describe, describe_for_stdout, help_text, remove_input_text,
    remove_output_text, text_reply, NOT_UNDERSTOOD_TEXT,
};

use crate::{Bottle, Value};
use std::collections::BTreeMap;

/// A connection route: who sends, who receives, over which carrier (C++ `Route`).
///
/// For an input of port `/rd` the route is `from = sender, to = /rd`; for an output it is
/// `from = /rd, to = target`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Route {
    pub from: String,
    pub to: String,
    pub carrier: String,
}

impl Route {
    pub fn new(from: &str, to: &str, carrier: &str) -> Route {
        Route {
            from: from.to_string(),
            to: to.to_string(),
            carrier: carrier.to_string(),
        }
    }
}

/// One live connection of the port, as the admin protocol sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct Connection {
    pub route: Route,
    /// The carrier is connectionless (`udp`, `mcast`): `[list] ... $portname` adds
    /// `(connectionless 1)`.
    pub connectionless: bool,
    /// The carrier pushes data from the sender (true for every YARP-native carrier):
    /// when false, `[list] ... $portname` adds `(push 0)`.
    pub push: bool,
    /// Carrier parameters (`[get] [in] $portname` replies them as a dict), in key order.
    pub params: BTreeMap<String, Value>,
    /// Thread id, scheduling priority and policy of the connection's thread (`[prop] [get]
    /// $portname`).
    pub tid: i32,
    pub priority: i32,
    pub policy: i32,
    /// IP type-of-service of the connection's socket (-1 when unknown).
    pub tos: i32,
}

impl Connection {
    /// A connection with the carrier's usual properties (udp and mcast are connectionless,
    /// everything pushes).
    pub fn new(route: Route) -> Connection {
        let connectionless = carrier_is_connectionless(&route.carrier);
        Connection {
            route,
            connectionless,
            push: true,
            params: BTreeMap::new(),
            tid: 0,
            priority: -1,
            policy: -1,
            tos: -1,
        }
    }
}

impl From<Route> for Connection {
    fn from(route: Route) -> Connection {
        Connection::new(route)
    }
}

/// Whether C++ YARP treats the carrier as connectionless (`Carrier::isConnectionless`).
pub fn carrier_is_connectionless(carrier: &str) -> bool {
    let base = carrier.split('+').next().unwrap_or("");
    matches!(base, "udp" | "mcast")
}

/// Information about the process owning the port (`[prop] [get] $cur_port`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ProcessInfo {
    pub pid: i32,
    /// Executable name (C++ prints `unknown` when the pid is -1).
    pub name: String,
    pub arguments: String,
    pub priority: i32,
    pub policy: i32,
    /// Operating system name (`SystemInfo::getPlatformInfo().name`, e.g. `Linux`).
    pub os: String,
    /// The port server thread's id, priority and policy.
    pub tid: i32,
    pub thread_priority: i32,
    pub thread_policy: i32,
}

/// Everything the admin protocol needs to know about a port, as a plain snapshot.
#[derive(Debug, Clone, PartialEq)]
pub struct PortSnapshot {
    /// Registered name (`/rd`).
    pub name: String,
    /// Carrier, host and port number the port listens on (`tcp`, `127.0.0.1`, 10002).
    pub carrier: String,
    pub host: String,
    pub port: i32,
    /// Live input connections (including the one the command arrives on).
    pub inputs: Vec<Connection>,
    /// Live output connections.
    pub outputs: Vec<Connection>,
    /// User-defined port properties (`[prop] [set] key value`), in key order as C++ keeps
    /// them.
    pub properties: BTreeMap<String, Value>,
    pub process: ProcessInfo,
    /// Port flags (`PORTCORE_IS_INPUT` / `_OUTPUT` / `_RPC`) and type name.
    pub is_input: bool,
    pub is_output: bool,
    pub is_rpc: bool,
    pub type_name: String,
    /// A portmonitor plug-in is attached to the port's input / output.
    pub input_monitor: bool,
    pub output_monitor: bool,
    /// The owner installed an admin reader (`setAdminReader`): unknown admin commands
    /// are passed to it instead of failing.
    pub has_admin_reader: bool,
    /// `$YARP_ROBOT_NAME`, used by `[pray]`.
    pub robot_name: Option<String>,
    /// Seed for `[pray]`'s dice (C++ uses `std::random_device`).
    pub seed: u64,
}

impl PortSnapshot {
    /// A port with no connections and no properties.
    pub fn new(name: &str, carrier: &str, host: &str, port: i32) -> PortSnapshot {
        PortSnapshot {
            name: name.to_string(),
            carrier: carrier.to_string(),
            host: host.to_string(),
            port,
            inputs: Vec::new(),
            outputs: Vec::new(),
            properties: BTreeMap::new(),
            process: ProcessInfo::default(),
            is_input: true,
            is_output: true,
            is_rpc: false,
            type_name: String::new(),
            input_monitor: false,
            output_monitor: false,
            has_admin_reader: false,
            robot_name: None,
            seed: 0,
        }
    }

    /// User properties as C++ `Property::toString` renders them, re-read as a Bottle
    /// (`[prop] [get]` does `result.fromString(p->toString())`).
    pub fn properties_bottle(&self) -> Bottle {
        let mut b = Bottle::new();
        for (k, v) in &self.properties {
            let g = b.add_list();
            g.push(k.as_str());
            g.push(v.clone());
        }
        Bottle::from_text(b.to_text())
    }
}

#[cfg(test)]
mod tests;

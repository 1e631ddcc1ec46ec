//! Administrative Bottles (`a` port command): C++ `PortCore::adminBlock`.

use super::{Connection, PortSnapshot};
use crate::contact::PortRef;
use crate::{Bottle, Value, Vocab32};
use std::collections::BTreeMap;

/// `[ver]` reply: the admin protocol version (distinct from the library version).
pub const ADMIN_VERSION: [i32; 3] = [1, 2, 3];

/// `[in]` / `[out]` argument of `[list]`, `[set]`, `[get]`, `[atch]`, `[dtch]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    In,
    Out,
}

/// Something the I/O layer must do to the live port. For the ones whose result shapes the
/// reply, [`AdminResponse::pending`] says which `format_*` function finishes it.
#[derive(Debug, Clone, PartialEq)]
pub enum AdminAction {
    /// Connect a new output to `target` (the carrier, if any, prefixes the name:
    /// `udp://cbcap/stateExt:i`). C++ first removes every existing connection from this
    /// port to the same name. `dest` is the text the reply lines quote.
    AddOutput { dest: String, target: PortRef },
    /// Remove every connection whose route goes *to* `to` (C++ `removeOutput`).
    RemoveOutput { to: String },
    /// Remove every connection whose route comes *from* `from` (C++ `removeInput`).
    RemoveInput { from: String },
    /// Pass carrier parameters to the connection from (`In`) / to (`Out`) `target`.
    /// `params` is the whole command, which C++ reads as a Property (`Property::fromString`).
    SetCarrierParams {
        direction: Direction,
        target: String,
        params: Bottle,
    },
    /// Pass parameters to the portmonitor attached to the port's input / output.
    SetMonitorParams {
        direction: Direction,
        params: Bottle,
    },
    /// Attach a portmonitor plug-in configured by `config` (Property text).
    AttachMonitor {
        direction: Direction,
        config: String,
    },
    /// Detach the portmonitor plug-in (always succeeds).
    DetachMonitor { direction: Direction },
    /// Store a user property (done by every `[prop] [set]`, whatever else it does).
    SetProperty { key: String, value: Value },
    /// Set the scheduling priority/policy of every thread of the process.
    SetProcessScheduling { priority: i32, policy: i32 },
    /// Set the scheduling priority/policy of the thread of the connection to/from `name`.
    SetConnectionScheduling {
        name: String,
        priority: i32,
        policy: i32,
    },
    /// Set the IP type-of-service of the connection to/from `name`.
    SetTypeOfService { name: String, tos: i32 },
    /// Unknown command: give it to the owner's admin reader; its reply replaces ours.
    ForwardToAdminReader { cmd: Bottle },
    /// ROS `publisherUpdate`: keep subscriptions only to `publishers` of `topic`.
    RosPublisherUpdate {
        topic: String,
        publishers: Vec<String>,
    },
    /// Close the connection after replying (C++ `requestDrop`, ROS commands).
    DropConnection,
}

/// How the reply of [`AdminResponse`] is finished.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Pending {
    /// `reply` is final.
    None,
    /// Call [`format_add_result`] with the outcome of the `AddOutput` action.
    Add { dest: String },
    /// Call [`format_del_result`] with whether `RemoveOutput` / `RemoveInput` matched.
    Del { dest: String },
    /// The reply is `[ok]` iff action number `action` succeeded: [`format_prop_set_result`].
    PropSet { action: usize },
    /// Call [`format_atch_result`] with the outcome of `AttachMonitor`.
    Attach,
    /// Call [`format_unknown_result`] with the admin reader's reply.
    Unknown,
}

/// The result of [`handle_admin`].
#[derive(Debug, Clone, PartialEq)]
pub struct AdminResponse {
    /// The reply Bottle; when `pending` is not `None`, the reply C++ would give if every
    /// action succeeded (for `[atch]`: the failure a port without portmonitor support
    /// gives, as recorded).
    pub reply: Bottle,
    /// What to do, in order.
    pub actions: Vec<AdminAction>,
    pub pending: Pending,
}

impl AdminResponse {
    fn done(reply: Bottle) -> AdminResponse {
        AdminResponse {
            reply,
            actions: Vec::new(),
            pending: Pending::None,
        }
    }
}

/// How an attempt to add an output ended (C++ `PortCore::addOutput`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AddOutcome {
    /// Connected. `note` is appended to the line (C++ adds `; /a will forward messages
    /// and replies (if any) to /b` for `log.in` carriers).
    Added { note: Option<String> },
    /// A connection with the same carrier was already there (only when C++ is asked to
    /// connect "only if needed", never from `[add]`).
    AlreadyPresent,
    /// The name server does not know the target: `Do not know how to connect to X`.
    UnknownTarget,
    /// The port refuses: `Outputs not allowed`, `RPC output already connected`, or
    /// `Logger configured as log.X, but only log.in is supported`.
    NotAllowed(String),
    /// The carrier could not connect: `Cannot connect to X`.
    CannotConnect,
}

/// The `[help]` reply: `[many]` then one string per command.
pub fn admin_help() -> Bottle {
    const LINES: [&str; 20] = [
        "[help]                  # give this help",
        "[ver]                   # report protocol version information",
        "[add] $portname         # add an output connection",
        "[add] $portname $car    # add an output with a given protocol",
        "[del] $portname         # remove an input or output connection",
        "[list] [in]             # list input connections",
        "[list] [out]            # list output connections",
        "[list] [in]  $portname  # give details for input",
        "[list] [out] $portname  # give details for output",
        "[prop] [get]            # get all user-defined port properties",
        "[prop] [get] $prop      # get a user-defined port property (prop, val)",
        "[prop] [set] $prop $val # set a user-defined port property (prop, val)",
        "[prop] [get] $portname  # get Qos properties of a connection to/from a port",
        "[prop] [set] $portname  # set Qos properties of a connection to/from a port",
        "[prop] [get] $cur_port  # get information about current process (e.g., scheduling priority, pid)",
        "[prop] [set] $cur_port  # set properties of the current process (e.g., scheduling priority, pid)",
        "[atch] [out] $prop      # attach a portmonitor plug-in to the port's output",
        "[atch] [in]  $prop      # attach a portmonitor plug-in to the port's input",
        "[dtch] [out]            # detach portmonitor plug-in from the port's output",
        "[dtch] [in]             # detach portmonitor plug-in from the port's input",
    ];
    let mut b = Bottle::new();
    b.add_vocab("many");
    for l in LINES {
        b.push(l);
    }
    b
}

/// The reply to `[add]`: `0 "Added connection from /p to dest\r\n"` on success, else
/// `-1 "<reason>\r\n"` (C++: 0 iff the text starts with `A`).
pub fn format_add_result(port_name: &str, dest: &str, outcome: &AddOutcome) -> Bottle {
    let text = super::add_output_text(port_name, dest, outcome);
    let code = if text.starts_with('A') { 0 } else { -1 };
    Bottle::new().with(code).with(text)
}

/// The reply to `[del] dest`: code 0 if an output or an input matched, else -1; the
/// text is the line of the half that matched, or both lines concatenated when both or
/// neither did (e.g. `-1 "Could not find an outgoing connection to /x\r\nCould not find
/// an incoming connection from /x\r\n"`).
pub fn format_del_result(
    port_name: &str,
    dest: &str,
    removed_output: bool,
    removed_input: bool,
) -> Bottle {
    let r1 = super::remove_output_text(port_name, dest, removed_output);
    let r2 = super::remove_input_text(port_name, dest, removed_input);
    let code = if removed_output || removed_input {
        0
    } else {
        -1
    };
    let text = match (removed_output, removed_input) {
        (true, false) => r1,
        (false, true) => r2,
        _ => r1 + &r2,
    };
    Bottle::new().with(code).with(text)
}

/// `[ok]` / `[fail]` for `[prop] [set]`.
pub fn format_prop_set_result(ok: bool) -> Bottle {
    let mut b = Bottle::new();
    b.add_vocab(if ok { "ok" } else { "fail" });
    b
}

/// The reply to `[atch]` once the plug-in was (not) attached: `[ok]` or `[fail] "msg"`.
pub fn format_atch_result(outcome: Result<(), String>) -> Bottle {
    let mut b = Bottle::new();
    match outcome {
        Ok(()) => {
            b.add_vocab("ok");
        }
        Err(msg) => {
            b.add_vocab("fail");
            b.push(msg);
        }
    }
    b
}

/// The reply to an unknown command: the admin reader's reply, or `[fail] "send [help]
/// for list of valid commands"` when there is none or it failed.
pub fn format_unknown_result(reader_reply: Option<Bottle>) -> Bottle {
    match reader_reply {
        Some(b) => b,
        None => fail_msg("send [help] for list of valid commands"),
    }
}

/// How a reply Bottle travels back on a text connection: its text then CRLF (an empty
/// reply is just `\r\n`). `text_ack` sessions then add `<ACK>\r\n`.
pub fn reply_text_line(reply: &Bottle) -> Vec<u8> {
    let mut v = reply.to_text();
    v.extend_from_slice(b"\r\n");
    v
}

/// How a C++ `DeviceResponder` writes its reply on a text connection: a reply whose first
/// element is `many` (the `help` listing) goes out one line per following element, a
/// list as its contents and anything else as a one-element Bottle (so a string keeps its
/// quotes); any other reply is one line, as [`reply_text_line`].
pub fn responder_text_lines(reply: &Bottle) -> Vec<u8> {
    let is_many = match reply.get(0) {
        Some(Value::Vocab32(v)) => *v == crate::Vocab32::encode("many"),
        Some(Value::String(s)) => s == b"many",
        _ => false,
    };
    if !is_many {
        return reply_text_line(reply);
    }
    let mut out = Vec::new();
    for v in reply.iter().skip(1) {
        let line = match v.as_list() {
            Some(list) => list.clone(),
            None => Bottle::new().with(v.clone()),
        };
        out.extend_from_slice(&reply_text_line(&line));
    }
    out
}

fn fail_msg(msg: &str) -> Bottle {
    let mut b = Bottle::new();
    b.add_vocab("fail");
    b.push(msg);
    b
}

fn code_msg(code: i32, msg: String) -> Bottle {
    Bottle::new().with(code).with(msg)
}

/// C++ `Value::asVocab32`: vocabs and integers give their value, strings the vocab of
/// their first four characters, everything else (and a missing element) 0.
fn as_vocab(v: Option<&Value>) -> Vocab32 {
    match v {
        Some(Value::Vocab32(x)) => *x,
        Some(Value::String(s)) => Vocab32::encode(s),
        Some(Value::Int8(x)) => Vocab32(*x as i32),
        Some(Value::Int16(x)) => Vocab32(*x as i32),
        Some(Value::Int32(x)) => Vocab32(*x),
        Some(Value::Int64(x)) => Vocab32(*x as i32),
        _ => Vocab32(0),
    }
}

/// C++ `Value::asString`: a string's text, a vocab's text, else empty.
fn as_string(v: Option<&Value>) -> String {
    match v {
        Some(Value::String(s)) => String::from_utf8_lossy(s).into_owned(),
        Some(Value::Vocab32(x)) => String::from_utf8_lossy(&x.to_text_bare()).into_owned(),
        _ => String::new(),
    }
}

/// C++ `Value::asInt32` (floats truncate, strings give 0).
fn as_int32(v: Option<&Value>) -> i32 {
    match v {
        Some(Value::String(_)) | Some(Value::Blob(_)) | None => 0,
        Some(Value::List(_)) | Some(Value::Dict(_)) => 0,
        Some(Value::Float32(f)) => *f as i32,
        Some(Value::Float64(f)) => *f as i32,
        Some(other) => other.as_i32().unwrap_or(0),
    }
}

trait VocabBare {
    fn to_text_bare(&self) -> Vec<u8>;
}
impl VocabBare for Vocab32 {
    /// `StoreVocab32::toString`: `false`/`true` for 0 and `'1'`, else the characters.
    fn to_text_bare(&self) -> Vec<u8> {
        match *self {
            Vocab32::FALSE | Vocab32::TRUE => self.to_text(),
            v => v.decode(),
        }
    }
}

fn direction(v: Option<&Value>, error_is_out: bool) -> Option<Direction> {
    let v = as_vocab(v);
    if v == Vocab32::new("in") {
        Some(Direction::In)
    } else if v == Vocab32::new("out") || error_is_out {
        Some(Direction::Out)
    } else {
        None
    }
}

fn dict(entries: BTreeMap<&str, Value>) -> Value {
    let mut b = Bottle::new();
    for (k, v) in entries {
        let g = b.add_list();
        g.push(k);
        g.push(v);
    }
    Value::Dict(b)
}

fn named(name: &str, v: Value) -> Value {
    Value::List(Bottle::new().with(name).with(v))
}

/// Answers an administrative Bottle (what follows an `a` port command) as C++
/// `PortCore::adminBlock` does. Never panics; malformed commands get C++'s replies.
pub fn handle_admin(cmd: &Bottle, state: &PortSnapshot) -> AdminResponse {
    let head = cmd.get(0);
    if let Some(Value::String(s)) = head {
        match s.as_slice() {
            b"publisherUpdate" => {
                let topic = as_string(cmd.get(2));
                let topic = from_ros_name(&topic);
                let publishers = cmd
                    .get(3)
                    .and_then(Value::as_list)
                    .map(|l| l.iter().map(|v| as_string(Some(v))).collect())
                    .unwrap_or_default();
                let mut r = AdminResponse::done(Bottle::new().with(1).with("ok"));
                r.actions = vec![
                    AdminAction::RosPublisherUpdate { topic, publishers },
                    AdminAction::DropConnection,
                ];
                return r;
            }
            b"requestTopic" => {
                let mut lst = Bottle::new();
                lst.push("TCPROS")
                    .push(state.host.as_str())
                    .push(state.port);
                let reply = Bottle::new().with(1).with(node_name(&state.name)).with(lst);
                return dropping(reply);
            }
            b"getPid" => {
                return dropping(Bottle::new().with(1).with("").with(state.process.pid));
            }
            b"getBusInfo" => {
                let mut reply = Bottle::new().with(1).with("");
                reply.add_list().add_list();
                return dropping(reply);
            }
            _ => {}
        }
    }
    let verb = as_vocab(head);
    let v = |s: &str| Vocab32::new(s);
    if verb == v("help") {
        AdminResponse::done(admin_help())
    } else if verb == v("ver") {
        let mut b = Bottle::new();
        b.add_vocab("ver");
        for n in ADMIN_VERSION {
            b.push(n);
        }
        AdminResponse::done(b)
    } else if verb == v("pray") {
        AdminResponse::done(pray(state))
    } else if verb == v("add") {
        let mut dest = as_string(cmd.get(1));
        let carrier = as_string(cmd.get(2));
        if !carrier.is_empty() {
            dest = format!("{carrier}:/{dest}");
        }
        AdminResponse {
            reply: format_add_result(&state.name, &dest, &AddOutcome::Added { note: None }),
            actions: vec![AdminAction::AddOutput {
                dest: dest.clone(),
                target: PortRef::parse(&dest),
            }],
            pending: Pending::Add { dest },
        }
    } else if verb == v("del") {
        let dest = as_string(cmd.get(1));
        let out = connection_to(state, &dest);
        let inp = connection_from(state, &dest);
        AdminResponse {
            reply: format_del_result(&state.name, &dest, out, inp),
            actions: vec![
                AdminAction::RemoveOutput { to: dest.clone() },
                AdminAction::RemoveInput { from: dest.clone() },
            ],
            pending: Pending::Del { dest },
        }
    } else if verb == v("atch") {
        match direction(cmd.get(1), false) {
            None => {
                AdminResponse::done(fail_msg("attach command must be followed by [out] or [in]"))
            }
            Some(d) => AdminResponse {
                reply: fail_msg("Failed to configure the portmonitor plug-in"),
                actions: vec![AdminAction::AttachMonitor {
                    direction: d,
                    config: as_string(cmd.get(2)),
                }],
                pending: Pending::Attach,
            },
        }
    } else if verb == v("dtch") {
        match direction(cmd.get(1), false) {
            None => {
                AdminResponse::done(fail_msg("detach command must be followed by [out] or [in]"))
            }
            Some(d) => AdminResponse {
                reply: format_prop_set_result(true),
                actions: vec![AdminAction::DetachMonitor { direction: d }],
                pending: Pending::None,
            },
        }
    } else if verb == v("list") {
        let d = direction(cmd.get(1), true).unwrap_or(Direction::Out);
        AdminResponse::done(list(state, d, &as_string(cmd.get(2))))
    } else if verb == v("set") {
        let d = direction(cmd.get(1), true).unwrap_or(Direction::Out);
        set_params(state, d, &as_string(cmd.get(2)), cmd)
    } else if verb == v("get") {
        let d = direction(cmd.get(1), true).unwrap_or(Direction::Out);
        AdminResponse::done(get_params(state, d, &as_string(cmd.get(2))))
    } else if verb == v("prop") {
        let action = as_vocab(cmd.get(1));
        let key = as_string(cmd.get(2));
        if action == v("get") {
            AdminResponse::done(prop_get(state, &key))
        } else if action == v("set") {
            prop_set(state, &key, cmd)
        } else {
            AdminResponse::done(fail_msg("property action not known"))
        }
    } else if state.has_admin_reader {
        AdminResponse {
            reply: format_unknown_result(None),
            actions: vec![AdminAction::ForwardToAdminReader { cmd: cmd.clone() }],
            pending: Pending::Unknown,
        }
    } else {
        AdminResponse::done(format_unknown_result(None))
    }
}

fn dropping(reply: Bottle) -> AdminResponse {
    AdminResponse {
        reply,
        actions: vec![AdminAction::DropConnection],
        pending: Pending::None,
    }
}

/// `NestedContact(name).getNodeName()` for the common forms: `/topic@/node` -> `/node`;
/// a plain name is its own node.
fn node_name(name: &str) -> String {
    match name.find('@') {
        Some(i) => name[i + 1..].to_string(),
        None => name.to_string(),
    }
}

/// `RosNameSpace::fromRosName`: ROS topic names are used as they are, except that a
/// name without a leading slash gets one.
fn from_ros_name(name: &str) -> String {
    if name.starts_with('/') || name.is_empty() {
        name.to_string()
    } else {
        format!("/{name}")
    }
}

/// Every live connection (outputs first, as they rarely collide) with the name C++
/// compares for `[prop] ... /name`: the target of an output, the source of an input.
fn named_connections(state: &PortSnapshot) -> impl Iterator<Item = (&str, &Connection)> {
    state
        .outputs
        .iter()
        .map(|c| (c.route.to.as_str(), c))
        .chain(state.inputs.iter().map(|c| (c.route.from.as_str(), c)))
}

fn connection_to(state: &PortSnapshot, to: &str) -> bool {
    state
        .outputs
        .iter()
        .chain(state.inputs.iter())
        .any(|c| c.route.to == to)
}

fn connection_from(state: &PortSnapshot, from: &str) -> bool {
    state
        .outputs
        .iter()
        .chain(state.inputs.iter())
        .any(|c| c.route.from == from)
}

fn describe_route(c: &Connection, out: &mut Bottle) {
    out.push(Bottle::new().with("from").with(c.route.from.as_str()));
    out.push(Bottle::new().with("to").with(c.route.to.as_str()));
    out.push(Bottle::new().with("carrier").with(c.route.carrier.as_str()));
    if c.connectionless {
        out.push(Bottle::new().with("connectionless").with(1));
    }
    if !c.push {
        out.push(Bottle::new().with("push").with(0));
    }
}

fn list(state: &PortSnapshot, d: Direction, target: &str) -> Bottle {
    let mut out = Bottle::new();
    match d {
        Direction::In => {
            for c in &state.inputs {
                if target.is_empty() {
                    if !c.route.from.is_empty() {
                        out.push(c.route.from.as_str());
                    }
                } else if c.route.from == target {
                    describe_route(c, &mut out);
                }
            }
        }
        Direction::Out => {
            for c in &state.outputs {
                if target.is_empty() {
                    out.push(c.route.to.as_str());
                } else if c.route.to == target {
                    describe_route(c, &mut out);
                }
            }
        }
    }
    out
}

fn not_found(d: Direction, target: &str) -> Bottle {
    // C++ says "incoming" in both messages.
    let msg = match d {
        Direction::In => format!("Could not find an incoming connection from {target}\r\n"),
        Direction::Out => format!("Could not find an incoming connection to {target}\r\n"),
    };
    code_msg(-1, msg)
}

fn no_monitor(d: Direction) -> Bottle {
    fail_msg(match d {
        Direction::In => "No port modifier is attached to the input",
        Direction::Out => "No port modifier is attached to the output",
    })
}

fn has_monitor(state: &PortSnapshot, d: Direction) -> bool {
    match d {
        Direction::In => state.input_monitor,
        Direction::Out => state.output_monitor,
    }
}

fn find_conn<'a>(state: &'a PortSnapshot, d: Direction, target: &str) -> Option<&'a Connection> {
    match d {
        Direction::In => state.inputs.iter().find(|c| c.route.from == target),
        Direction::Out => state.outputs.iter().find(|c| c.route.to == target),
    }
}

fn set_params(state: &PortSnapshot, d: Direction, target: &str, cmd: &Bottle) -> AdminResponse {
    if target.is_empty() {
        return AdminResponse::done(code_msg(-1, "target port is not specified.\r\n".into()));
    }
    if target == state.name {
        if !has_monitor(state, d) {
            return AdminResponse::done(no_monitor(d));
        }
        return AdminResponse {
            reply: format_prop_set_result(true),
            actions: vec![AdminAction::SetMonitorParams {
                direction: d,
                params: cmd.clone(),
            }],
            pending: Pending::None,
        };
    }
    match find_conn(state, d, target) {
        Some(c) => {
            let msg = match d {
                Direction::In => format!("Configured connection from {}\r\n", c.route.from),
                Direction::Out => format!("Configured connection to {}\r\n", c.route.to),
            };
            AdminResponse {
                reply: code_msg(0, msg),
                actions: vec![AdminAction::SetCarrierParams {
                    direction: d,
                    target: target.to_string(),
                    params: cmd.clone(),
                }],
                pending: Pending::None,
            }
        }
        None => AdminResponse::done(not_found(d, target)),
    }
}

fn get_params(state: &PortSnapshot, d: Direction, target: &str) -> Bottle {
    if target.is_empty() {
        return code_msg(-1, "target port is not specified.\r\n".into());
    }
    if target == state.name {
        if !has_monitor(state, d) {
            return no_monitor(d);
        }
        return Bottle::new().with(Value::Dict(Bottle::new()));
    }
    match find_conn(state, d, target) {
        Some(c) => {
            let entries = c
                .params
                .iter()
                .map(|(k, v)| (k.as_str(), v.clone()))
                .collect();
            Bottle::new().with(dict(entries))
        }
        None => not_found(d, target),
    }
}

fn prop_get(state: &PortSnapshot, key: &str) -> Bottle {
    if key.is_empty() {
        return state.properties_bottle();
    }
    if !key.starts_with('/') {
        // A missing key gives C++'s null value, which adds nothing.
        return state
            .properties
            .get(key)
            .map(|v| Bottle::new().with(v.clone()))
            .unwrap_or_default();
    }
    let mut out = Bottle::new();
    if key == state.name {
        let p = &state.process;
        let known = p.pid != -1;
        let unknown = |s: &str| {
            if known {
                s.to_string()
            } else {
                "unknown".into()
            }
        };
        out.push(named(
            "sched",
            dict(BTreeMap::from([
                ("tid", Value::Int32(p.tid)),
                ("priority", Value::Int32(p.thread_priority)),
                ("policy", Value::Int32(p.thread_policy)),
            ])),
        ));
        out.push(named(
            "process",
            dict(BTreeMap::from([
                ("pid", Value::Int32(p.pid)),
                ("name", Value::from(unknown(&p.name))),
                ("arguments", Value::from(unknown(&p.arguments))),
                ("priority", Value::Int32(p.priority)),
                ("policy", Value::Int32(p.policy)),
            ])),
        ));
        out.push(named(
            "platform",
            dict(BTreeMap::from([
                ("os", Value::from(p.os.as_str())),
                ("hostname", Value::from(state.host.as_str())),
            ])),
        ));
        out.push(named(
            "port",
            dict(BTreeMap::from([
                ("is_input", Value::Int32(state.is_input as i32)),
                ("is_output", Value::Int32(state.is_output as i32)),
                ("is_rpc", Value::Int32(state.is_rpc as i32)),
                ("type", Value::from(state.type_name.as_str())),
            ])),
        ));
        return out;
    }
    for (name, c) in named_connections(state) {
        if name == key {
            out.push(named(
                "sched",
                dict(BTreeMap::from([
                    ("tid", Value::Int32(c.tid)),
                    ("priority", Value::Int32(c.priority)),
                    ("policy", Value::Int32(c.policy)),
                ])),
            ));
            out.push(named(
                "qos",
                dict(BTreeMap::from([("tos", Value::Int32(c.tos))])),
            ));
        }
    }
    if out.is_empty() {
        out.add_vocab("fail");
        out.push(format!("cannot find any connection to/from {key}"));
    }
    out
}

/// Reads `(priority N) (policy M)` style settings, -1 when absent.
fn prio_policy(settings: &Bottle) -> (i32, i32) {
    let get = |k: &str| {
        if settings.check(k) {
            as_int32(settings.find(k))
        } else {
            -1
        }
    };
    (get("priority"), get("policy"))
}

/// DSCP class names (`QosStyle::getDSCPByVocab`).
fn dscp_by_vocab(v: Vocab32) -> Option<i32> {
    const CLASSES: [(&str, i32); 22] = [
        ("CS0", 0),
        ("CS1", 8),
        ("CS2", 16),
        ("CS3", 24),
        ("CS4", 32),
        ("CS5", 40),
        ("CS6", 48),
        ("CS7", 56),
        ("AF11", 10),
        ("AF12", 12),
        ("AF13", 14),
        ("AF21", 18),
        ("AF22", 20),
        ("AF23", 22),
        ("AF31", 26),
        ("AF32", 28),
        ("AF33", 30),
        ("AF41", 34),
        ("AF42", 36),
        ("AF43", 38),
        ("VA", 44),
        ("EF", 46),
    ];
    CLASSES
        .iter()
        .find(|(n, _)| Vocab32::new(n) == v)
        .map(|&(_, d)| d)
}

fn tos_of(qos: &Bottle) -> i32 {
    if qos.check("priority") {
        let p = as_vocab(qos.find("priority"));
        let dscp = [("LOW", 10), ("NORM", 0), ("HIGH", 36), ("CRIT", 44)]
            .iter()
            .find(|(n, _)| Vocab32::new(n) == p)
            .map(|&(_, d)| d);
        dscp.map(|d| d << 2).unwrap_or(-1)
    } else if qos.check("dscp") {
        let val = qos.find("dscp");
        let dscp = match dscp_by_vocab(as_vocab(val)) {
            Some(d) => d,
            None => match val {
                Some(Value::Int32(d)) => *d,
                _ => -1,
            },
        };
        if (0..64).contains(&dscp) {
            dscp << 2
        } else {
            -1
        }
    } else if qos.check("tos") {
        match qos.find("tos") {
            Some(Value::Int32(t)) => *t,
            _ => -1,
        }
    } else {
        -1
    }
}

fn prop_set(state: &PortSnapshot, key: &str, cmd: &Bottle) -> AdminResponse {
    let mut actions = Vec::new();
    if let Some(value) = cmd.get(3) {
        actions.push(AdminAction::SetProperty {
            key: key.to_string(),
            value: value.clone(),
        });
    }
    // The verdict: Some(fixed) or the index of the action that decides it.
    let mut ok: Result<bool, usize> = Ok(true);
    let group_list = |name: &str| {
        cmd.find_group(name)
            .and_then(|g| g.find(name))
            .and_then(Value::as_list)
    };
    if cmd.find_group("process").is_some() && key.starts_with('/') && key == state.name {
        ok = Ok(false);
        if let Some(p) = group_list("process") {
            let (priority, policy) = prio_policy(p);
            actions.push(AdminAction::SetProcessScheduling { priority, policy });
            ok = Err(actions.len() - 1);
        }
    }
    if cmd.find_group("sched").is_some() && key.starts_with('/') {
        ok = Ok(false);
        if named_connections(state).any(|(n, _)| n == key) {
            if let Some(s) = group_list("sched") {
                let (priority, policy) = prio_policy(s);
                actions.push(AdminAction::SetConnectionScheduling {
                    name: key.to_string(),
                    priority,
                    policy,
                });
                ok = Err(actions.len() - 1);
            }
        }
    }
    if cmd.find_group("qos").is_some() && key.starts_with('/') {
        ok = Ok(false);
        if named_connections(state).any(|(n, _)| n == key) {
            if let Some(q) = group_list("qos") {
                let tos = tos_of(q);
                if tos >= 0 {
                    actions.push(AdminAction::SetTypeOfService {
                        name: key.to_string(),
                        tos,
                    });
                    ok = Err(actions.len() - 1);
                }
            }
        }
    }
    match ok {
        Ok(fixed) => AdminResponse {
            reply: format_prop_set_result(fixed),
            actions,
            pending: Pending::None,
        },
        Err(action) => AdminResponse {
            reply: format_prop_set_result(true),
            actions,
            pending: Pending::PropSet { action },
        },
    }
}

/// `[pray]`: a nethack-style prayer to the robot (`$YARP_ROBOT_NAME`, else the first
/// part of the port name). The dice come from `state.seed`.
fn pray(state: &PortSnapshot) -> Bottle {
    let name = match &state.robot_name {
        Some(n) => n.clone(),
        None => {
            let n = state.name.trim_start_matches('/');
            n.split('/').next().unwrap_or("").to_string()
        }
    };
    let mut seed = state.seed ^ 0x9e37_79b9_7f4a_7c15;
    let mut roll = |n: usize| {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % n as u64) as usize
    };
    const VOICES: [&str; 4] = ["booms out", "thunders", "rings out", "booms"];
    const CREATURES: [&str; 3] = ["mortal", "creature", "robot"];
    const AURAS: [&str; 6] = ["amber", "light blue", "golden", "white", "orange", "black"];
    const ITEMS: [&str; 8] = [
        "keyboard",
        "mouse",
        "monitor",
        "headphones",
        "smartphone",
        "wallet",
        "eyeglasses",
        "shirt",
    ];
    const BLESSINGS: [&str; 17] = [
        "You feel more limber.",
        "The slime disappears.",
        "Your amulet vanishes! You can breathe again.",
        "You can breathe again.",
        "You are back on solid ground.",
        "Your stomach feels content.",
        "You feel better.",
        "You feel much better.",
        "Your surroundings change.",
        "Your shape becomes uncertain.",
        "Your chain disappears.",
        "There's a tiger in your tank.",
        "You feel in good health again.",
        "Your eye feels better.",
        "Your eyes feel better.",
        "Looks like you are back in Kansas.",
        "Your <ITEM> softly glows <AURA>.",
    ];
    let mut out = Bottle::new();
    out.push(format!("You begin praying to {name}."));
    out.push("You finish your prayer.");
    let case = roll(13);
    let voice = VOICES[roll(VOICES.len())];
    let voice_of = format!("The voice of {name} {voice}: ");
    let blessing = |roll: &mut dyn FnMut(usize) -> usize| {
        BLESSINGS[roll(BLESSINGS.len())]
            .replace("<ITEM>", ITEMS[roll(ITEMS.len())])
            .replace("<AURA>", AURAS[roll(AURAS.len())])
    };
    let pick = |roll: &mut dyn FnMut(usize) -> usize, a: &'static str, b: &'static str| {
        if roll(2) == 1 {
            a
        } else {
            b
        }
    };
    match case {
        0 | 1 => {
            let mood = pick(&mut roll, "bummed", "displeased");
            out.push(format!("You feel that {name} is {mood}."));
        }
        2 | 3 => {
            let sin = pick(&mut roll, "hast strayed from the path", "art arrogant");
            let c = CREATURES[roll(CREATURES.len())];
            out.push(format!(
                "{voice_of}\"Thou {sin}, {c}. Thou must relearn thy lessons!\""
            ));
        }
        4 | 5 => {
            out.push(format!("{voice_of}\"Thou hast angered me.\""));
            out.push("A black glow surrounds you.");
        }
        6 => {
            out.push(format!("{voice_of}\"Thou hast angered me.\""));
        }
        7 | 8 => {
            let how = pick(&mut roll, "scorn", "call upon");
            let c = CREATURES[roll(CREATURES.len())];
            out.push(format!("{voice_of}\"Thou durst {how} me? Then die, {c}!\""));
        }
        9..=11 => {
            let (a, b) = match case {
                9 => ("pleased as punch", "well-pleased"),
                10 => ("ticklish", "pleased"),
                _ => ("full", "satisfied"),
            };
            let mood = pick(&mut roll, a, b);
            out.push(format!("You feel that {name} is {mood}."));
            out.push(blessing(&mut roll));
        }
        _ => {
            out.push(format!("{voice_of}\"Thou hast angered me.\""));
            out.push("Suddenly, a bolt of lightning strikes you!");
            out.push("You fry to a crisp!");
        }
    }
    out
}

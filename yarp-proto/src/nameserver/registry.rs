//! The registry: what C++ `yarpserver` 3.12 keeps in its SQLite triple store, and the
//! commands that read and change it, ported function by function from
//! `NameServiceOnTriples` / `AllocatorOnTriples` so that odd inputs give the same replies.

use crate::value::{Bottle, Value};
use std::collections::BTreeMap;

/// Address of the multicast "fallback" name server C++ registers next to `/root`.
pub const FALLBACK_HOST: &str = "224.2.1.1";

/// Deepest chain of `owns` properties followed by `unregister` (C++ has no limit and
/// recurses forever on a cycle).
const MAX_OWNS_DEPTH: usize = 32;

/// Settings of a [`Registry`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RegistryConfig {
    /// The server's own address, registered as `/root` (and used for `topic` carriers).
    pub host: String,
    /// The server's own port number, registered as `/root`.
    pub port: i32,
    /// First number the allocator hands out (C++: server port + 2).
    pub min_port: i32,
    /// Last number the cursor reaches before freed numbers are reused (C++: port + 9999).
    pub max_port: i32,
    /// Port number of the `fallback` registration (C++: the default port range, 10000,
    /// whatever `--socket` says).
    pub fallback_port: i32,
    /// Name of the server's own registration (the namespace, `/root` by default).
    pub root_name: String,
    /// Register the root name and `fallback` at start, as `yarpserver` does.
    pub register_self: bool,
}

impl RegistryConfig {
    /// The settings `yarpserver --ip host --socket port` uses.
    pub fn new(host: &str, port: i32) -> RegistryConfig {
        RegistryConfig {
            host: host.to_string(),
            port,
            min_port: port.saturating_add(2),
            max_port: port.saturating_add(9999),
            fallback_port: 10000,
            root_name: "/root".to_string(),
            register_self: true,
        }
    }
}

/// A port name as the query code splits it: `carrier:/name` and `/net=PREFIX/name`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ParsedName {
    pub carrier: String,
    pub network: String,
    pub port_name: String,
}

/// C++ `ParseName::apply`.
pub fn parse_name(s: &str) -> ParsedName {
    let mut name = s.to_string();
    let mut carrier = String::new();
    let mut network = String::new();
    if let Some(mid) = name.find(":/") {
        if mid > 0 {
            carrier = name[..mid].to_string();
            if let Some(c) = carrier.strip_prefix('/') {
                carrier = c.to_string();
            }
            name = name[mid + 2..].to_string();
        }
    }
    if name.starts_with("/net=") || name.starts_with("/NET=") {
        if let Some(end) = name[5..].find('/') {
            let end = end + 5;
            network = name[5..end].to_string();
            name = name[end..].to_string();
        }
    }
    ParsedName {
        carrier,
        network,
        port_name: name,
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Use {
    InUse,
    Free,
}

/// One allocation pool (`alloc` triples under one cursor row in C++).
#[derive(Debug, Clone, Default)]
struct Pool {
    cursor: Option<i32>,
    /// Keyed by the text C++ stores, so that "lowest first" is SQLite's text order.
    state: BTreeMap<String, Use>,
}

impl Pool {
    fn first_free(&self) -> Option<String> {
        self.state
            .iter()
            .find(|(_, u)| **u == Use::Free)
            .map(|(k, _)| k.clone())
    }
    fn free(&mut self, key: &str) {
        if let Some(u) = self.state.get_mut(key) {
            *u = Use::Free;
        }
    }
}

/// Per-command state (C++ `NameTripleState`).
struct Act<'a> {
    cmd: Bottle,
    reply: Bottle,
    bottle_mode: bool,
    nested_mode: bool,
    remote: Option<&'a str>,
    depth: usize,
}

/// The name server's state machine.
#[derive(Debug, Clone)]
pub struct Registry {
    config: RegistryConfig,
    /// Port name -> property -> values (sorted, duplicates kept). `carrier`, `host`,
    /// `socket` and `type` are properties like any other, as in C++.
    ports: BTreeMap<String, BTreeMap<String, Vec<String>>>,
    ports_pool: Pool,
    /// Port number text -> the name that last got it (C++ `prefer` triples).
    prefer: BTreeMap<String, String>,
    mcast_pool: Pool,
    names_pool: Pool,
    last_register: String,
}

fn as_string(v: Option<&Value>) -> String {
    match v {
        Some(Value::String(s)) => String::from_utf8_lossy(s).into_owned(),
        _ => String::new(),
    }
}

fn bare(v: Option<&Value>) -> String {
    match v {
        Some(v) => v.to_string_bare(),
        None => String::new(),
    }
}

fn as_i32(v: Option<&Value>) -> i32 {
    v.and_then(|v| v.as_i32()).unwrap_or(0)
}

/// C `atoi`: optional sign and leading digits, 0 otherwise (saturating instead of UB).
pub(crate) fn atoi(s: &str) -> i32 {
    let t = s.trim_start();
    let (neg, digits) = match t.as_bytes().first() {
        Some(b'-') => (true, &t[1..]),
        Some(b'+') => (false, &t[1..]),
        _ => (false, t),
    };
    let mut v: i64 = 0;
    for ch in digits.bytes() {
        if !ch.is_ascii_digit() {
            break;
        }
        v = (v * 10 + (ch - b'0') as i64).min(i32::MAX as i64 + 1);
    }
    let v = if neg { -v } else { v };
    v.clamp(i32::MIN as i64, i32::MAX as i64) as i32
}

/// C++ `Value::fromString`: one parsed element, or a list when the text holds several.
fn value_from_string(s: &str) -> Value {
    let b = Bottle::from_text(s);
    if b.len() == 1 {
        if let Some(v) = b.get(0) {
            return v.clone();
        }
    }
    Value::List(b)
}

fn tail(b: &Bottle) -> Bottle {
    b.iter().skip(1).cloned().collect::<Vec<Value>>().into()
}

fn cmd2(a: &str, b: &str) -> Bottle {
    let mut c = Bottle::new();
    c.push(a).push(b);
    c
}

fn insert_sorted(values: &mut Vec<String>, v: String) {
    let at = values.partition_point(|x| x.as_bytes() <= v.as_bytes());
    values.insert(at, v);
}

/// What a query found: C++ builds a `Contact` even for odd stored values.
struct Found {
    host: String,
    sock: i32,
    carrier: String,
}

impl Registry {
    /// A registry as a freshly started `yarpserver`: holding the root name and `fallback`
    /// (when `config.register_self`), with the root's `nameserver` property set.
    pub fn new(config: RegistryConfig) -> Registry {
        let mut r = Registry {
            config,
            ports: BTreeMap::new(),
            ports_pool: Pool::default(),
            prefer: BTreeMap::new(),
            mcast_pool: Pool::default(),
            names_pool: Pool::default(),
            last_register: String::new(),
        };
        if r.config.register_self {
            let c = r.config.clone();
            let mut reg = Bottle::new();
            reg.push("register")
                .push(c.root_name.as_str())
                .push("tcp")
                .push(c.host.as_str())
                .push(c.port);
            r.apply(&reg, None);
            let mut fb = Bottle::new();
            fb.push("register")
                .push("fallback")
                .push("mcast")
                .push(FALLBACK_HOST)
                .push(c.fallback_port);
            r.apply(&fb, None);
            let mut set = Bottle::new();
            set.push("set")
                .push(c.root_name.as_str())
                .push("nameserver")
                .push("true");
            r.apply(&set, None);
        }
        r
    }

    pub fn config(&self) -> &RegistryConfig {
        &self.config
    }

    /// Registered names, sorted.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.ports.keys().map(|s| s.as_str())
    }

    /// The values of one property of a registered name (sorted as `get` lists them).
    pub fn property(&self, port: &str, key: &str) -> Option<&[String]> {
        self.ports
            .get(port)
            .and_then(|p| p.get(key))
            .map(|v| v.as_slice())
    }

    /// The line C++ prints on the server console for a command (` * cmd`, or `   + cmd`
    /// for a `set` right after the `register` of the same name). Call once per command,
    /// before [`Registry::apply`], to keep the same bookkeeping.
    pub fn log_line(&mut self, cmd: &Bottle) -> String {
        let key = bare(cmd.get(0));
        let mut prefix = " * ";
        if key == "register" {
            self.last_register = as_string(cmd.get(1));
        } else if key == "set" {
            if as_string(cmd.get(1)) == self.last_register {
                prefix = "   + ";
            }
        } else {
            self.last_register.clear();
        }
        format!("{prefix}{}", String::from_utf8_lossy(&cmd.to_text()))
    }

    /// Runs one command as C++ `yarpserver` does and returns its reply Bottle. A reply whose
    /// first element is the string `old` is sent in the old multi-line text form (see
    /// [`super::reply_text`]); any other reply is sent as a Bottle.
    ///
    /// `remote` is the address of the peer that sent the command: registrations with
    /// `...` as address take it (C++ does the same), `localhost` when unknown.
    pub fn apply(&mut self, cmd: &Bottle, remote: Option<&str>) -> Bottle {
        // The subscriber sees the command first, with any NAME_SERVER prefix still on.
        if as_string(cmd.get(0)) == "announce" {
            let mut r = Bottle::new();
            r.add_vocab("ok");
            return r;
        }
        let mut act = Act {
            cmd: cmd.clone(),
            reply: Bottle::new(),
            bottle_mode: false,
            nested_mode: false,
            remote,
            depth: 0,
        };
        let mut key = bare(cmd.get(0));
        if cmd.check("format") && as_string(cmd.find("format")) == "json" {
            act.bottle_mode = true;
        }
        if key == "NAME_SERVER" {
            act.cmd = tail(&act.cmd);
            key = as_string(act.cmd.get(0));
        }
        if key == "bot" {
            act.bottle_mode = true;
            act.cmd = tail(&act.cmd);
            key = as_string(act.cmd.get(0));
        }
        match key.as_str() {
            "register" => self.cmd_register(&mut act),
            "unregister" => self.cmd_unregister(&mut act),
            "query" => self.cmd_query(&mut act),
            "list" => self.cmd_list(&mut act, false),
            "runners" => self.cmd_list(&mut act, true),
            "set" => self.cmd_set(&mut act),
            "get" => self.cmd_get(&mut act),
            "check" => self.cmd_check(&mut act),
            "route" => self.cmd_route(&mut act),
            "gc" => {
                act.reply.push("old");
                act.reply.add_list().push("garbage collection done.");
            }
            "help" => cmd_help(&mut act),
            _ => {
                act.reply.push("old");
            }
        }
        act.reply
    }

    fn lookup(&self, name: &str, network: &str) -> Option<Found> {
        let props = self.ports.get(name)?;
        let first = |k: &str| props.get(k).and_then(|v| v.first()).cloned();
        let mut host = String::new();
        if !network.is_empty() {
            if let Some(ips) = props.get("ips") {
                if let Some(ip) = ips.iter().find(|ip| ip.starts_with(network)) {
                    host = ip.clone();
                }
            }
        }
        if host.is_empty() {
            host = first("host").unwrap_or_default();
        }
        if host.is_empty() {
            host = "localhost".to_string();
        }
        let sock = first("socket").map(|s| atoi(&s)).unwrap_or(10000);
        let carrier = first("carrier").unwrap_or_else(|| "tcp".to_string());
        Some(Found {
            host,
            sock,
            carrier,
        })
    }

    fn cmd_query(&mut self, act: &mut Act) {
        let parsed = parse_name(&as_string(act.cmd.get(1)));
        let port = parsed.port_name;
        if act.reply.is_empty() && !act.bottle_mode {
            act.reply.push("old");
        }
        let found = self.lookup(&port, &parsed.network);
        let q: &mut Bottle = if act.bottle_mode && !act.nested_mode {
            &mut act.reply
        } else {
            act.reply.add_list()
        };
        match found {
            Some(c) if c.sock >= 0 => {
                if !act.bottle_mode {
                    q.push("registration")
                        .push("name")
                        .push(port.as_str())
                        .push("ip")
                        .push(c.host.as_str())
                        .push("port")
                        .push(c.sock)
                        .push("type")
                        .push(c.carrier.as_str());
                } else {
                    q.push("port");
                    q.add_list().push("name").push(port.as_str());
                    q.add_list().push("ip").push(c.host.as_str());
                    q.add_list().push("port_number").push(c.sock);
                    q.add_list().push("carrier").push(c.carrier.as_str());
                }
            }
            _ => {
                if act.bottle_mode {
                    q.push("port");
                    q.add_list().push("error").push(-2).push("port not known");
                }
            }
        }
    }

    fn cmd_register(&mut self, act: &mut Act) {
        let mut port = as_string(act.cmd.get(1));
        if self.ports.contains_key(&port) {
            self.cmd_unregister(act);
            act.reply.clear();
        }
        act.reply.push("old");
        let len = act.cmd.len();
        let mut at = 2;
        let mut sock = -1;
        let mut carrier = "...".to_string();
        let mut machine = "...".to_string();
        let mut typ = "*".to_string();
        if len > at {
            carrier = as_string(act.cmd.get(at));
            at += 1;
        }
        if carrier == "..." {
            carrier = "tcp".to_string();
        }
        if len > at {
            machine = as_string(act.cmd.get(at));
            at += 1;
        }
        if machine == "..." {
            if carrier == "topic" {
                machine = self.config.host.clone();
            } else if carrier != "mcast" {
                machine = match act.remote {
                    Some(r) if !r.is_empty() && r != "..." => r.to_string(),
                    _ => "localhost".to_string(),
                };
            }
        }
        if len > at {
            sock = as_i32(act.cmd.get(at));
            at += 1;
        } else if carrier == "topic" {
            sock = self.config.port;
        }
        if len > at {
            typ = as_string(act.cmd.get(at));
        }
        if port == "..." || port.starts_with('=') {
            let name = self.complete_port_name();
            port = if port == "..." { name } else { name + &port };
        }
        let mut props: BTreeMap<String, Vec<String>> = BTreeMap::new();
        props.insert("carrier".into(), vec![carrier.clone()]);
        let host = self.complete_host(&carrier, machine);
        let sock = self.complete_port_number(&port, sock);
        props.insert("host".into(), vec![host]);
        props.insert("socket".into(), vec![sock.to_string()]);
        if typ != "*" {
            props.insert("type".into(), vec![typ]);
        }
        self.ports.insert(port.clone(), props);
        act.cmd = cmd2("query", &port);
        self.cmd_query(act);
    }

    fn cmd_unregister(&mut self, act: &mut Act) {
        let port = as_string(act.cmd.get(1));
        if let Some(c) = self.lookup(&port, "") {
            self.free_port_resources(&port, c.sock, &c.host);
        }
        act.reply.push("old");
        if let Some(props) = self.ports.get(&port) {
            let owned = props.get("owns").cloned().unwrap_or_default();
            if act.depth < MAX_OWNS_DEPTH {
                act.depth += 1;
                for o in owned {
                    act.cmd = cmd2("unregister", &o);
                    self.cmd_unregister(act);
                }
                act.depth -= 1;
            }
            self.ports.remove(&port);
        }
        self.cmd_query(act);
    }

    fn cmd_list(&mut self, act: &mut Act, runners: bool) {
        act.reply
            .push(if act.bottle_mode { "ports" } else { "old" });
        let prefix = if act.cmd.len() > 1 && !runners {
            as_string(act.cmd.get(1))
        } else {
            String::new()
        };
        act.nested_mode = true;
        let names: Vec<String> = self.ports.keys().cloned().collect();
        for name in names {
            let wanted = if runners {
                self.ports
                    .get(&name)
                    .and_then(|p| p.get("yarprun"))
                    .is_some_and(|v| v.iter().any(|x| x == "true"))
            } else {
                prefix.is_empty()
                    || (name.starts_with(&prefix)
                        && (name == prefix
                            || name.as_bytes().get(prefix.len()) == Some(&b'/')
                            || prefix.ends_with('/')))
            };
            if wanted {
                act.cmd = cmd2("query", &name);
                self.cmd_query(act);
            }
        }
    }

    fn cmd_set(&mut self, act: &mut Act) {
        if !act.bottle_mode {
            act.reply.push("old");
        }
        let port = as_string(act.cmd.get(1));
        let key = bare(act.cmd.get(2));
        let Some(props) = self.ports.get_mut(&port) else {
            return;
        };
        let mut values = Vec::new();
        for v in act.cmd.iter().skip(3) {
            insert_sorted(&mut values, bare(Some(v)));
        }
        if values.is_empty() {
            props.remove(&key);
        } else {
            props.insert(key.clone(), values);
        }
        let mut get = cmd2("get", &port);
        get.push(key.as_str());
        act.cmd = get;
        self.cmd_get(act);
    }

    fn cmd_get(&mut self, act: &mut Act) {
        if !act.bottle_mode && act.reply.is_empty() {
            act.reply.push("old");
        }
        let port = as_string(act.cmd.get(1));
        let key = bare(act.cmd.get(2));
        let Some(props) = self.ports.get(&port) else {
            return;
        };
        let values = props.get(&key).cloned().unwrap_or_default();
        if !act.bottle_mode {
            let q = act.reply.add_list();
            q.push("port")
                .push(port.as_str())
                .push("property")
                .push(key.as_str())
                .push("=");
            for v in values {
                q.push(v);
            }
        } else {
            for v in values {
                act.reply.push(value_from_string(&v));
            }
        }
    }

    fn cmd_check(&mut self, act: &mut Act) {
        if act.reply.is_empty() {
            act.reply.push("old");
        }
        let port = as_string(act.cmd.get(1));
        let key = bare(act.cmd.get(2));
        let val = bare(act.cmd.get(3));
        let Some(props) = self.ports.get(&port) else {
            return;
        };
        let present = props.get(&key).is_some_and(|v| v.contains(&val));
        act.reply
            .add_list()
            .push("port")
            .push(port.as_str())
            .push("property")
            .push(key.as_str())
            .push("value")
            .push(val.as_str())
            .push("present")
            .push(if present { "true" } else { "false" });
    }

    fn cmd_route(&mut self, act: &mut Act) {
        if act.reply.is_empty() {
            act.reply.push("old");
        }
        let p1 = as_string(act.cmd.get(1));
        let p2 = as_string(act.cmd.get(2));
        act.reply
            .add_list()
            .push("port")
            .push(p1.as_str())
            .push("route")
            .push(p2.as_str())
            .push("=")
            .push(format!("tcp:/{p2}"));
    }

    fn complete_port_name(&mut self) -> String {
        let name = match self.names_pool.first_free() {
            Some(n) => n,
            None => {
                let id = self.names_pool.cursor.unwrap_or(0).saturating_add(1);
                self.names_pool.cursor = Some(id);
                format!("/tmp/port/{id}")
            }
        };
        self.names_pool.state.insert(name.clone(), Use::InUse);
        name
    }

    fn complete_host(&mut self, carrier: &str, host: String) -> String {
        if carrier != "mcast" || host != "..." {
            return host;
        }
        let name = match self.mcast_pool.first_free() {
            Some(n) => n,
            None => {
                let cursor = self.mcast_pool.cursor.unwrap_or(1).saturating_add(1);
                let (v1, v2) = (cursor % 255, cursor / 255);
                if v2 >= 255 {
                    // C++ exits the whole server here ("Ran out of mcast addresses").
                    return host;
                }
                self.mcast_pool.cursor = Some(cursor);
                format!("224.1.{}.{}", v2 + 1, v1 + 1)
            }
        };
        self.mcast_pool.state.insert(name.clone(), Use::InUse);
        name
    }

    fn complete_port_number(&mut self, name: &str, sock: i32) -> i32 {
        if sock != -1 && sock != 0 {
            return sock;
        }
        let mut chosen: Option<String> = None;
        if let Some((npref, _)) = self.prefer.iter().find(|(_, n)| n.as_str() == name) {
            if self.ports_pool.state.get(npref) != Some(&Use::InUse) {
                chosen = Some(npref.clone());
            }
        }
        if chosen.is_none() {
            let cursor = self
                .ports_pool
                .cursor
                .unwrap_or(self.config.min_port.saturating_sub(1));
            if cursor >= self.config.max_port && self.config.max_port != 0 {
                self.ports_pool.cursor = Some(cursor);
                // C++ exits the whole server when nothing is free ("Ran out of port
                // numbers"); this registry answers with an invalid registration instead.
                chosen = Some(self.ports_pool.first_free().unwrap_or_else(|| "-1".into()));
            } else {
                let next = cursor.saturating_add(1);
                self.ports_pool.cursor = Some(next);
                chosen = Some(next.to_string());
            }
        }
        let nstring = chosen.unwrap_or_else(|| "-1".into());
        if nstring != "-1" {
            self.ports_pool.state.insert(nstring.clone(), Use::InUse);
            self.prefer.insert(nstring.clone(), name.to_string());
        }
        atoi(&nstring)
    }

    fn free_port_resources(&mut self, name: &str, sock: i32, host: &str) {
        self.names_pool.free(name);
        self.ports_pool.free(&sock.to_string());
        self.mcast_pool.free(host);
    }
}

fn cmd_help(act: &mut Act) {
    if !act.bottle_mode {
        act.reply.push("old");
        act.reply.push("Here are some ways to use the name server:");
    }
    for line in [
        "+ help",
        "+ list [$prefix]",
        "+ register $portname",
        "+ register $portname $carrier $ipAddress $portNumber",
        "  (if you want a field set automatically, write '...')",
        "+ unregister $portname",
        "+ query $portname",
        "+ set $portname $property $value",
        "+ get $portname $property",
        "+ check $portname $property",
        "+ route $port1 $port2",
        "+ runners",
        "  (to get a list of the yarprun ports)",
    ] {
        act.reply.push(line);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::nameserver::reply_text;

    fn run(r: &mut Registry, cmd: &str) -> String {
        let reply = r.apply(&Bottle::from_text(cmd), Some("127.0.0.1"));
        String::from_utf8(reply_text(&reply)).unwrap()
    }

    fn reg() -> Registry {
        Registry::new(RegistryConfig::new("127.0.0.1", 10000))
    }

    #[test]
    fn allocation_follows_cpp() {
        let mut r = reg();
        assert!(run(&mut r, "register /a").contains("port 10002 type tcp"));
        assert!(run(&mut r, "register /b mcast").contains("ip 224.1.1.3 port 10003 type mcast"));
        assert!(run(&mut r, "register /c mcast").contains("ip 224.1.1.4 port 10004"));
        // freed group is reused first
        run(&mut r, "unregister /b");
        assert!(run(&mut r, "register /d mcast").contains("ip 224.1.1.3 port 10005"));
        // a name coming back gets its number back; others do not take it
        run(&mut r, "unregister /a");
        assert!(run(&mut r, "register /e").contains("port 10006"));
        assert!(run(&mut r, "register /a").contains("port 10002"));
        // re-registering frees then reuses
        assert!(run(&mut r, "register /a").contains("port 10002"));
        // explicit
        assert!(run(&mut r, "register /x tcp 1.2.3.4 30000").contains("ip 1.2.3.4 port 30000"));
        // automatic names
        assert!(run(&mut r, "register ...").contains("name /tmp/port/1 "));
        assert!(run(&mut r, "register =/sub").contains("name /tmp/port/2=/sub "));
    }

    #[test]
    fn pool_wraps_to_free_numbers() {
        let mut c = RegistryConfig::new("127.0.0.1", 10000);
        c.max_port = 10003;
        let mut r = Registry::new(c);
        run(&mut r, "register /a");
        run(&mut r, "register /b");
        assert_eq!(run(&mut r, "register /c"), "*** end of message\r\n");
        run(&mut r, "unregister /b");
        assert!(run(&mut r, "register /d").contains("port 10003"));
        assert_eq!(run(&mut r, "register /e"), "*** end of message\r\n");
    }

    #[test]
    fn replies() {
        let mut r = reg();
        run(&mut r, "register /b tcp 127.0.0.1 30000");
        assert_eq!(
            run(&mut r, "set /b tags beta alpha \"two words\""),
            "port /b property tags = alpha beta two words\r\n*** end of message\r\n"
        );
        assert_eq!(
            run(&mut r, "get /b nothing"),
            "port /b property nothing =\r\n*** end of message\r\n"
        );
        assert_eq!(
            run(&mut r, "check /b tags gamma"),
            "port /b property tags value gamma present false\r\n*** end of message\r\n"
        );
        assert_eq!(run(&mut r, "get /zz x"), "*** end of message\r\n");
        run(&mut r, "set /b colour red \"/x\" 3");
        assert_eq!(run(&mut r, "bot get /b colour"), "\"/x\" 3 red\r\n");
        assert_eq!(run(&mut r, "bot get /zz tags"), "\r\n");
        assert_eq!(
            run(&mut r, "bot query /b"),
            "port (name \"/b\") (ip \"127.0.0.1\") (port_number 30000) (carrier tcp)\r\n"
        );
        assert_eq!(
            run(&mut r, "bot query /zz"),
            "port (error -2 \"port not known\")\r\n"
        );
        assert_eq!(
            run(&mut r, "route /a /b"),
            "port /a route /b = tcp://b\r\n*** end of message\r\n"
        );
        assert_eq!(
            run(&mut r, "gc"),
            "garbage collection done.\r\n*** end of message\r\n"
        );
        assert_eq!(run(&mut r, "announce /b"), "[ok]\r\n");
        assert_eq!(
            run(&mut r, "NAME_SERVER announce /b"),
            "*** end of message\r\n"
        );
        assert_eq!(
            run(&mut r, "list /b"),
            "registration name /b ip 127.0.0.1 port 30000 type tcp\r\n*** end of message\r\n"
        );
        assert_eq!(run(&mut r, "list /ro"), "*** end of message\r\n");
        assert_eq!(
            run(&mut r, "get /root nameserver"),
            "port /root property nameserver = true\r\n*** end of message\r\n"
        );
        // carrier/host/socket are ordinary properties
        assert_eq!(
            run(&mut r, "get /b socket"),
            "port /b property socket = 30000\r\n*** end of message\r\n"
        );
    }

    #[test]
    fn owns_and_cycles() {
        let mut r = reg();
        run(&mut r, "register /a");
        run(&mut r, "register /b");
        run(&mut r, "set /a owns /b");
        run(&mut r, "set /b owns /a");
        run(&mut r, "unregister /a");
        assert_eq!(r.names().collect::<Vec<_>>(), vec!["/root", "fallback"]);
    }

    #[test]
    fn parse_names() {
        assert_eq!(parse_name("/net=10.0/foo").network, "10.0");
        assert_eq!(parse_name("/net=10.0/foo").port_name, "/foo");
        assert_eq!(parse_name("tcp://foo").port_name, "/foo");
        assert_eq!(parse_name("tcp://foo").carrier, "tcp");
        assert_eq!(parse_name("/foo").port_name, "/foo");
    }

    #[test]
    fn log_lines() {
        let mut r = reg();
        assert_eq!(
            r.log_line(&Bottle::from_text("register /x")),
            " * register \"/x\""
        );
        assert_eq!(
            r.log_line(&Bottle::from_text("set /x a b")),
            "   + set \"/x\" a b"
        );
        assert_eq!(r.log_line(&Bottle::from_text("list")), " * list");
    }

    #[test]
    fn atoi_like_c() {
        assert_eq!(atoi("10002"), 10002);
        assert_eq!(atoi("-3x"), -3);
        assert_eq!(atoi("x"), 0);
        assert_eq!(atoi("99999999999"), i32::MAX);
    }
}

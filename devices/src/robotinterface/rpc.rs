//! The `/<portprefix>/yarprobotinterface` RPC service (C++ `yarprobotinterfaceRpc`,
//! a YARP thrift service), as a pure request -> reply function.
//!
//! Commands: `get_phase` (string), `get_level` (int32), `get_robot` (string),
//! `is_ready` (bool: `[ok]` / `[fail]`), `quit` / `bye` / `exit` (`"bye"`, and the
//! program stops), `help` (the command list).

use super::model::ActionPhase;
use yarp_proto::{Bottle, Value, Vocab32};

/// What the service reports; the program updates it as phases run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RpcStatus {
    pub robot: String,
    pub phase: Option<ActionPhase>,
    pub level: u32,
}

/// The answer to one request.
#[derive(Debug, Clone, PartialEq)]
pub struct RpcReply {
    pub reply: Bottle,
    /// The request asked the program to stop.
    pub quit: bool,
}

const COMMANDS: [&str; 8] = [
    "get_phase",
    "get_level",
    "get_robot",
    "is_ready",
    "quit",
    "bye",
    "exit",
    "help",
];

fn one(v: impl Into<Value>) -> Bottle {
    let mut b = Bottle::new();
    b.push(v.into());
    b
}

/// Answers `cmd` from `status`. Unknown commands get `[fail]`, as thrift servers reply.
pub fn handle(cmd: &Bottle, status: &RpcStatus) -> RpcReply {
    let tag = cmd.get(0).map(Value::to_string_bare).unwrap_or_default();
    let reply = |b| RpcReply {
        reply: b,
        quit: false,
    };
    match tag.as_str() {
        "get_phase" => reply(one(status.phase.map(|p| p.as_str()).unwrap_or(""))),
        "get_level" => reply(one(status.level as i32)),
        "get_robot" => reply(one(status.robot.as_str())),
        "is_ready" => {
            let ready = status.phase == Some(ActionPhase::Run);
            reply(one(Vocab32::new(if ready { "ok" } else { "fail" })))
        }
        "quit" | "bye" | "exit" => RpcReply {
            reply: one("bye"),
            quit: true,
        },
        "help" => {
            let mut list = Bottle::new();
            list.push("*** Available commands:");
            for c in COMMANDS {
                list.push(c);
            }
            reply(one(Value::List(list)))
        }
        _ => reply(one(Vocab32::new("fail"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ask(cmd: &str, status: &RpcStatus) -> String {
        handle(&Bottle::from_text(cmd), status).reply.to_string()
    }

    #[test]
    fn answers_like_the_thrift_service() {
        let mut s = RpcStatus {
            robot: "iCub".into(),
            phase: Some(ActionPhase::Startup),
            level: 15,
        };
        assert_eq!(ask("get_phase", &s), "startup");
        assert_eq!(ask("get_level", &s), "15");
        assert_eq!(ask("get_robot", &s), "iCub");
        assert_eq!(ask("is_ready", &s), "[fail]");
        s.phase = Some(ActionPhase::Run);
        assert_eq!(ask("is_ready", &s), "[ok]");
        assert_eq!(ask("nonsense 1 2", &s), "[fail]");
        assert_eq!(ask("", &s), "[fail]");
        let q = handle(&Bottle::from_text("quit"), &s);
        assert!(q.quit);
        assert_eq!(q.reply.to_string(), "bye");
        assert!(ask("help", &s).starts_with("(\"*** Available commands:\" get_phase"));
    }
}

//! std_srvs <-> YARP RPC mapping (pure): request and reply shapes on both sides.
//!
//! *ROS service -> YARP RPC port* (`ros_to_yarp`): the request selects the configured
//! command Bottle (`command`, or `command_true`/`command_false` for SetBool); the YARP
//! reply becomes `success` (see [`reply_success`]) and `message` (the reply's text).
//!
//! *YARP RPC port -> ROS service* (`yarp_to_ros`): any Bottle calls the service (SetBool
//! takes its `data` from the first value); the reply Bottle is `[ok] "message"` or
//! `[fail] "message"` (Empty: `[ok]`).

use serde::{Deserialize, Serialize};
use yarp_proto::{Bottle, Value, Vocab32};

/// The request of services without fields (rosidl adds one dummy byte to empty structs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct EmptyMsg {
    pub structure_needs_at_least_one_member: u8,
}
impl ros2_client::Message for EmptyMsg {}

/// `std_srvs/SetBool` request.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SetBoolRequest {
    pub data: bool,
}
impl ros2_client::Message for SetBoolRequest {}

/// `std_srvs/Trigger` and `std_srvs/SetBool` response.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct OutcomeResponse {
    pub success: bool,
    pub message: String,
}
impl ros2_client::Message for OutcomeResponse {}

/// The std_srvs type of a service entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StdSrv {
    Trigger,
    SetBool,
    Empty,
}

impl StdSrv {
    pub fn from_type(ros_type: &str) -> Option<StdSrv> {
        match ros_type {
            "std_srvs/srv/Trigger" => Some(StdSrv::Trigger),
            "std_srvs/srv/SetBool" => Some(StdSrv::SetBool),
            "std_srvs/srv/Empty" => Some(StdSrv::Empty),
            _ => None,
        }
    }
}

/// Whether a YARP RPC reply means success: it is not empty and does not start with the
/// vocab `[fail]`, `[nack]`, `[err]` or `[no]`, the integer 0, or the string "fail".
pub fn reply_success(reply: &Bottle) -> bool {
    const FAILS: [&str; 4] = ["fail", "nack", "err", "no"];
    match reply.get(0) {
        None => false,
        Some(Value::Vocab32(v)) => !FAILS.contains(&v.as_string().as_str()),
        Some(v) if v.is_int() => v.as_i64() != Some(0),
        Some(v) => v.as_str() != Some("fail"),
    }
}

/// A YARP reply as a std_srvs response.
pub fn outcome_from_reply(reply: &Bottle) -> OutcomeResponse {
    OutcomeResponse {
        success: reply_success(reply),
        message: reply.to_string(),
    }
}

/// A Trigger/SetBool response for the YARP reply, or for the reason there was none.
pub fn outcome_from_call<E: std::fmt::Display>(reply: Result<Bottle, E>) -> OutcomeResponse {
    match reply {
        Ok(b) => outcome_from_reply(&b),
        Err(e) => OutcomeResponse {
            success: false,
            message: e.to_string(),
        },
    }
}

/// A std_srvs response as the reply Bottle for a YARP caller.
pub fn reply_from_outcome(r: &OutcomeResponse) -> Bottle {
    let mut b = Bottle::new();
    b.push(Value::Vocab32(Vocab32::encode(if r.success {
        "ok"
    } else {
        "fail"
    })));
    if !r.message.is_empty() {
        b.push(r.message.as_str());
    }
    b
}

/// The reply for a completed Empty call.
pub fn ok_reply() -> Bottle {
    let mut b = Bottle::new();
    b.push(Value::Vocab32(Vocab32::encode("ok")));
    b
}

/// The reply when the ROS side fails (no server, timeout).
pub fn fail_reply(why: &str) -> Bottle {
    let mut b = Bottle::new();
    b.push(Value::Vocab32(Vocab32::encode("fail")));
    b.push(why);
    b
}

/// SetBool's `data` from a YARP command: the first value as a bool (numbers, the vocabs
/// `[ok]`/`[on]`/`[true]`…, or the strings "true"/"on"). `None` when there is no usable
/// first value.
pub fn setbool_from_command(cmd: &Bottle) -> Option<bool> {
    let v = cmd.get(0)?;
    let word = match v {
        Value::Vocab32(voc) => voc.as_string(),
        Value::String(_) => v.as_str()?.to_ascii_lowercase(),
        _ => return v.as_bool(),
    };
    match word.as_str() {
        "true" | "on" | "ok" | "yes" | "1" => Some(true),
        "false" | "off" | "no" | "0" | "" => Some(false),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(s: &str) -> Bottle {
        Bottle::from_text(s)
    }

    #[test]
    fn success_rules() {
        for ok in ["[ok]", "[is] [axes] 4", "1", "\"done\"", "[ack]"] {
            assert!(reply_success(&t(ok)), "{ok}");
        }
        for bad in ["", "[fail]", "[nack]", "[err] 3", "0", "\"fail\""] {
            assert!(!reply_success(&t(bad)), "{bad}");
        }
    }

    #[test]
    fn outcome_both_ways() {
        let r = outcome_from_reply(&t("[ok] \"homed\""));
        assert_eq!(
            r,
            OutcomeResponse {
                success: true,
                message: "[ok] homed".into()
            }
        );
        let b = reply_from_outcome(&OutcomeResponse {
            success: false,
            message: "not ready".into(),
        });
        assert_eq!(b.to_string(), "[fail] \"not ready\"");
        assert_eq!(
            reply_from_outcome(&OutcomeResponse::default()).to_string(),
            "[fail]"
        );
        assert_eq!(ok_reply().to_string(), "[ok]");
    }

    #[test]
    fn setbool_commands() {
        assert_eq!(setbool_from_command(&t("1")), Some(true));
        assert_eq!(setbool_from_command(&t("0")), Some(false));
        assert_eq!(setbool_from_command(&t("[on]")), Some(true));
        assert_eq!(setbool_from_command(&t("\"off\"")), Some(false));
        assert_eq!(setbool_from_command(&t("\"maybe\"")), None);
        assert_eq!(setbool_from_command(&t("")), None);
    }

    #[test]
    fn types() {
        assert_eq!(
            StdSrv::from_type("std_srvs/srv/SetBool"),
            Some(StdSrv::SetBool)
        );
        assert_eq!(StdSrv::from_type("std_srvs/srv/Nope"), None);
    }
}

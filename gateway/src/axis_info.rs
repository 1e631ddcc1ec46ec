//! Joint names from a control board's RPC port (C++ `IAxisInfo` over `/<part>/rpc:i`):
//! `[get] [axes]` answers `[is] [axes] N [ok]`, `[get] [name] j` answers
//! `[is] [name] "name" [ok]`, `[get] [type] j` answers `[is] [type] <joint type> [ok]`
//! (`VOCAB_JOINTTYPE_PRISMATIC` for prismatic joints). The requests and replies are the
//! control-board protocol's own (`yarp_devices::controlboard::methods`).

use yarp_devices::controlboard::methods::{self as m, Method};
use yarp_devices::controlboard::v3::{self, Answer};
use yarp_proto::Bottle;

/// `[get] [axes]`.
pub fn axes_request() -> Bottle {
    v3::request(&m::Axes {})
}

/// `[get] [name] j`.
pub fn name_request(j: usize) -> Bottle {
    v3::request(&m::GetAxisName { j })
}

/// `[get] [type] j` (C++ `IAxisInfo::getJointType`).
pub fn type_request(j: usize) -> Bottle {
    v3::request(&m::GetJointType { j })
}

/// The value of `M`'s reply, if it is one.
fn value<M: Method>(reply: &Bottle) -> Option<M::Reply> {
    match v3::answer::<M>(reply) {
        Answer::Value(v) => Some(v),
        Answer::Refused | Answer::Malformed => None,
    }
}

/// Whether a `[get] [type] j` reply names a prismatic joint (`None`: not a type reply).
/// C++ sends the vocab (`VOCAB_JOINTTYPE_PRISMATIC`) as an int32; a vocab value is
/// accepted too.
pub fn parse_prismatic(reply: &Bottle) -> Option<bool> {
    value::<m::GetJointType>(reply).map(|t| t == yarp_devices::vocabs::JOINTTYPE_PRISMATIC.0)
}

/// The axis count from a `[get] [axes]` reply.
pub fn parse_axes(reply: &Bottle) -> Option<usize> {
    value::<m::Axes>(reply)
}

/// The joint name from a `[get] [name] j` reply.
pub fn parse_name(reply: &Bottle) -> Option<String> {
    value::<m::GetAxisName>(reply)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests() {
        assert_eq!(axes_request().to_string(), "[get] [axes]");
        assert_eq!(name_request(3).to_string(), "[get] [name] 3");
    }

    #[test]
    fn replies() {
        assert_eq!(
            parse_axes(&Bottle::from_text("[is] [axes] 6 [ok]")),
            Some(6)
        );
        assert_eq!(parse_axes(&Bottle::from_text("[fail]")), None);
        assert_eq!(parse_axes(&Bottle::from_text("[is] [axes] -1 [ok]")), None);
        assert_eq!(
            parse_name(&Bottle::from_text("[is] [name] \"l_shoulder_pitch\" [ok]")).as_deref(),
            Some("l_shoulder_pitch")
        );
        assert_eq!(parse_name(&Bottle::from_text("[is] [axes] 6 [ok]")), None);
        use yarp_devices::vocabs::{JOINTTYPE_PRISMATIC, JOINTTYPE_REVOLUTE};
        let (pri, rev) = (JOINTTYPE_PRISMATIC.0, JOINTTYPE_REVOLUTE.0);
        assert_eq!(
            parse_prismatic(&Bottle::from_text(format!("[is] [type] {pri} [ok]"))),
            Some(true)
        );
        assert_eq!(
            parse_prismatic(&Bottle::from_text(format!("[is] [type] {rev} [ok]"))),
            Some(false)
        );
        let mut as_vocab = Bottle::from_text("[is] [type]");
        as_vocab.push(yarp_proto::Value::Vocab32(JOINTTYPE_PRISMATIC));
        assert_eq!(parse_prismatic(&as_vocab), Some(true));
        assert_eq!(parse_prismatic(&Bottle::from_text("[fail]")), None);
        assert_eq!(type_request(2).to_string(), "[get] [type] 2");
    }
}

//! Joint names from a control board's RPC port (C++ `IAxisInfo` over `/<part>/rpc:i`):
//! `[get] [axes]` answers `[is] [axes] N [ok]`, `[get] [name] j` answers
//! `[is] [name] "name" [ok]`, `[get] [type] j` answers `[is] [type] <joint type vocab>
//! [ok]` (`VOCAB_JOINTTYPE_PRISMATIC` for prismatic joints). Request building and reply parsing are pure.

use yarp_proto::{Bottle, Value, Vocab32};

/// `[get] [axes]`.
pub fn axes_request() -> Bottle {
    let mut b = Bottle::new();
    b.add_vocab("get").add_vocab("axes");
    b
}

/// `[get] [name] j`.
pub fn name_request(j: usize) -> Bottle {
    let mut b = Bottle::new();
    b.add_vocab("get").add_vocab("name");
    b.push(j as i32);
    b
}

/// `[get] [type] j` (C++ `IAxisInfo::getJointType`).
pub fn type_request(j: usize) -> Bottle {
    let mut b = Bottle::new();
    b.add_vocab("get").add_vocab("type");
    b.push(j as i32);
    b
}

/// Whether a `[get] [type] j` reply names a prismatic joint (`None`: not a type reply).
/// C++ sends the vocab (`VOCAB_JOINTTYPE_PRISMATIC`) as an int32; a vocab value is
/// accepted too.
pub fn parse_prismatic(reply: &Bottle) -> Option<bool> {
    let t = is_reply(reply, "type")?.first()?;
    let code = t.as_vocab().map(|v| v.0).or_else(|| t.as_i32())?;
    Some(code == yarp_devices::vocabs::JOINTTYPE_PRISMATIC.0)
}

fn is_reply<'a>(reply: &'a Bottle, what: &str) -> Option<&'a [Value]> {
    let items = reply.items();
    let ok = items.first()? == &Value::Vocab32(Vocab32::encode("is"))
        && items.get(1)? == &Value::Vocab32(Vocab32::encode(what));
    ok.then(|| &items[2..])
}

/// The axis count from a `[get] [axes]` reply.
pub fn parse_axes(reply: &Bottle) -> Option<usize> {
    let n = is_reply(reply, "axes")?.first()?;
    n.is_int()
        .then(|| n.as_i64())
        .flatten()
        .and_then(|n| usize::try_from(n).ok())
}

/// The joint name from a `[get] [name] j` reply.
pub fn parse_name(reply: &Bottle) -> Option<String> {
    is_reply(reply, "name")?
        .first()?
        .as_str()
        .map(str::to_string)
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

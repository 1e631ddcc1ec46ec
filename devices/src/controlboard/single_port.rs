//! The single-port dialect of the control-board wrapper (`--single_port`), as C++ YARP 2's
//! `ServerControlBoard` spoke it in YARP's design paper: commands, RPC and the state
//! stream all on one port, and a device responder that answers `help`.
//!
//! Differences from the four-port protocol of C++ 3.12 (`rpc`), both from that server:
//! * `help` lists one usage line per command (`[many]` then one string each, then
//!   `[ok]`); `help more` adds an explanation after each. The listing is YARP 2's.
//! * `get` replies carry no `[tsta] <count> <time>` timestamp: `[is] [axes] 2 [ok]`.

use super::rpc::{handle_rpc, RpcStamp};
use super::v3::vocab;
use crate::driver::DeviceDriver;
use crate::vocabs::{OK, TIMESTAMP};
use yarp_proto::{Bottle, Value, Vocab32};

/// One usage line and its explanation, in the order C++ YARP 2 listed them; the `$f`
/// placeholders of the all-axes commands are filled in per axis.
pub fn usage(axes: usize) -> Vec<(String, &'static str)> {
    let all: Vec<String> = (0..axes).map(|i| format!("$f{i}")).collect();
    let all = all.join(" ");
    let mut u: Vec<(String, &'static str)> = [
        ("[help]", "list usage"),
        ("[help] [more]", "list usage with some comments"),
        ("[get] [axes]", "get the number of axes"),
        (
            "[get] [name] $iAxisNumber",
            "get a human-readable name for an axis, if available",
        ),
        (
            "[set] [pos] $iAxisNumber $fPosition",
            "command the position of an axis",
        ),
        (
            "[set] [rel] $iAxisNumber $fPosition",
            "command the relative position of an axis",
        ),
        (
            "[set] [vmo] $iAxisNumber $fVelocity",
            "command the velocity of an axis",
        ),
        (
            "[get] [enc] $iAxisNumber",
            "get the encoder value for an axis",
        ),
    ]
    .into_iter()
    .map(|(a, b)| (a.to_string(), b))
    .collect();
    u.push((
        format!("[set] [poss] ({all})"),
        "command the position of all axes",
    ));
    u.push((
        format!("[set] [rels] ({all})"),
        "command the relative position of all axes",
    ));
    u.push((
        format!("[set] [vmos] ({all})"),
        "command the velocity of all axes",
    ));
    for (a, b) in [
        (
            "[set] [aen] $iAxisNumber",
            "enable (amplifier for) the given axis",
        ),
        (
            "[set] [adi] $iAxisNumber",
            "disable (amplifier for) the given axis",
        ),
        ("[get] [acu] $iAxisNumber", "get current for the given axis"),
        ("[get] [acus]", "get current for all axes"),
    ] {
        u.push((a.to_string(), b));
    }
    u
}

/// The reply to `help` (usage strings) or `help more` (each usage as a list, then its
/// explanation indented by three spaces), as C++ `DeviceResponder`, ending in `[ok]`.
pub fn help_reply(more: bool, axes: usize) -> Bottle {
    let mut b = Bottle::new();
    b.push(Vocab32::encode("many"));
    for (line, explain) in usage(axes) {
        if more {
            b.push(Value::List(Bottle::from_text(&line)));
            b.push(format!("   {explain}"));
        } else {
            b.push(line);
        }
    }
    b.push(Vocab32(OK));
    b
}

/// Serves one command on the single port: `help [more]`, else the control-board RPC
/// (`handle_rpc`) answered without the timestamp of `get` replies.
pub fn handle_single_port(
    cmd: &Bottle,
    dev: &mut dyn DeviceDriver,
    stamp: &mut RpcStamp,
    axes: usize,
) -> Bottle {
    if vocab(cmd.get(0)) == Vocab32::encode("help").0 {
        let more = vocab(cmd.get(1)) == Vocab32::encode("more").0;
        return help_reply(more, axes);
    }
    without_timestamp(handle_rpc(cmd, dev, stamp))
}

/// `[is] x v [tsta] c t [ok]` -> `[is] x v [ok]`.
fn without_timestamp(reply: Bottle) -> Bottle {
    let n = reply.len();
    let stamped = n >= 5
        && reply.get(n - 4) == Some(&Value::Vocab32(Vocab32(TIMESTAMP)))
        && reply.get(n - 1) == Some(&Value::Vocab32(Vocab32(OK)));
    if !stamped {
        return reply;
    }
    reply
        .iter()
        .enumerate()
        .filter(|(i, _)| !(n - 4..n - 1).contains(i))
        .map(|(_, v)| v.clone())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_motor::TestMotor;
    use yarp_proto::port_admin::responder_text_lines;

    fn ask(m: &mut TestMotor, text: &str) -> Bottle {
        handle_single_port(&Bottle::from_text(text), m, &mut RpcStamp::new(), 2)
    }

    #[test]
    fn paper_replies() {
        let mut m = TestMotor::with_axes(2);
        assert_eq!(
            ask(&mut m, "[get] [axes]").to_string(),
            "[is] [axes] 2 [ok]"
        );
        assert_eq!(ask(&mut m, "get axes").to_string(), "[is] axes 2 [ok]");
        assert_eq!(ask(&mut m, "[set] [pos] 0 100.0").to_string(), "[ok]");
        assert_eq!(ask(&mut m, "[get] [enc] 7").to_string(), "[fail]");
    }

    #[test]
    fn help_lists_one_usage_per_line() {
        let mut m = TestMotor::with_axes(2);
        let text = String::from_utf8(responder_text_lines(&ask(&mut m, "help"))).unwrap();
        let lines: Vec<&str> = text.split("\r\n").collect();
        assert_eq!(lines[0], "\"[help]\"");
        assert_eq!(lines[2], "\"[get] [axes]\"");
        assert_eq!(lines[8], "\"[set] [poss] ($f0 $f1)\"");
        assert_eq!(lines[15], "[ok]");
        assert_eq!(lines.len(), 17, "{text}");
        let more = String::from_utf8(responder_text_lines(&ask(&mut m, "help more"))).unwrap();
        assert!(
            more.starts_with("[help]\r\n\"   list usage\"\r\n[help] [more]\r\n"),
            "{more}"
        );
    }
}

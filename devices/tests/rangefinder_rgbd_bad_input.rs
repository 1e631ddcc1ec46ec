//! The rangefinder and RGB-D wrappers' network parsers on every Bottle of the C++
//! recordings (bottles.jsonl), alone and behind each command head: no panic, every reply
//! decodes (a setter's bare `ReturnValue` as one), and whatever is not a request of
//! theirs gets `[fail]`.

use yarp_devices::rangefinder::fake::FakeLaser;
use yarp_devices::rangefinder::protocol::{self as laser, LaserScan2D};
use yarp_devices::rgbd::fake::FakeDepthCamera;
use yarp_devices::rgbd::protocol as rgbd;
use yarp_devices::thrift::ReturnValue;
use yarp_devices::DeviceDriver;
use yarp_interop_tests::{hex_field, load_records};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Property, Value};

/// The recorded Bottles.
fn recorded() -> Vec<Bottle> {
    load_records("bottles.jsonl")
        .iter()
        .filter(|r| r["binary"].is_string())
        .filter_map(|r| Bottle::decode(&hex_field(r, "binary")).ok())
        .collect()
}

/// `head` followed by the elements of `b`.
fn behind(head: &str, b: &Bottle) -> Bottle {
    let mut cmd = Bottle::from_text(head);
    for v in b.iter() {
        cmd.push(v.clone());
    }
    cmd
}

#[test]
fn recorded_bottles_never_break_the_parsers() {
    let bottles = recorded();
    assert!(
        bottles.len() > 50,
        "only {} recorded bottles",
        bottles.len()
    );
    let mut l = FakeLaser::new();
    l.open(&Property::from_config_text("test use_constant").unwrap())
        .unwrap();
    let mut c = FakeDepthCamera::new();
    c.open(&Property::from_config_text("width 8\nheight 6").unwrap())
        .unwrap();
    let mut answered = 0;
    for b in &bottles {
        assert!(LaserScan2D::from_bottle(b).is_err() || b.len() == 6);
        for head in [
            "",
            "getDistanceRange RPC",
            "setScanRate RPC",
            "setScanLimits",
        ] {
            let cmd = behind(head, b);
            let bytes = laser::handle_rpc(&cmd, Some(&mut l), Generation::V3);
            if let Some(ret) = ReturnValue::from_bare(&bytes) {
                answered += 1;
                assert!(cmd.to_string().contains("set"), "{cmd} -> {ret:?}");
                continue;
            }
            let reply = Bottle::decode(&bytes).unwrap();
            if reply.to_string() != "[fail]" {
                answered += 1;
                assert!(
                    reply.get(0).and_then(Value::as_i32).is_some(),
                    "{cmd} -> {reply}"
                );
            }
        }
        for head in [
            "",
            "[visr] [get]",
            "[visd] [set]",
            "[rgdb] [get]",
            "[visd] [get] [fov]",
        ] {
            let cmd = behind(head, b);
            let reply = rgbd::handle_rpc(&cmd, Some(&mut c));
            assert!(!reply.is_empty(), "{cmd}");
            // every reply goes back over the wire
            Bottle::decode(&reply.encode()).unwrap();
        }
    }
    // requests that happen to be well formed (`setScanRate RPC <number>`) are answered
    assert!(answered > 0);
}

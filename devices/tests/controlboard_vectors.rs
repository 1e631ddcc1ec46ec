//! Replays every `yarp_rpc` record of controlboard.jsonl (C++ controlBoard_nws_yarp +
//! fakeMotionControl, 4 joints) against `handle_rpc` + our fakeMotionControl and compares
//! the reply structure: length, type of every element (recursively), vocabs and strings
//! exactly; numbers by type only (timestamps, counters and the C++ fake's moving state).

use yarp_devices::controlboard::{handle_rpc, RpcStamp};
use yarp_devices::{DeviceDriver, FakeMotionControl};
use yarp_proto::{Bottle, Property, Value};

fn same_shape(a: &Value, b: &Value) -> bool {
    if a.tag() != b.tag() {
        return false;
    }
    match (a, b) {
        (Value::Vocab32(x), Value::Vocab32(y)) => x == y,
        (Value::String(x), Value::String(y)) => x == y,
        (Value::List(x), Value::List(y)) => same_bottle(x, y),
        _ => true,
    }
}

fn same_bottle(a: &Bottle, b: &Bottle) -> bool {
    a.len() == b.len() && a.iter().zip(b.iter()).all(|(x, y)| same_shape(x, y))
}

#[test]
fn replay_yarp_rpc_records() {
    // the vectors must be there: never skip silently
    let path = yarp_interop_tests::vectors_dir().join("controlboard.jsonl");
    let text = std::fs::read_to_string(&path).expect("controlboard.jsonl");
    let mut dev = FakeMotionControl::new();
    dev.open(&Property::from_config_text("[GENERAL]\njoints 4\n").unwrap())
        .unwrap();
    let mut stamp = RpcStamp::new();
    let (mut total, mut pass) = (0, 0);
    let mut failures = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let r: serde_json::Value = serde_json::from_str(line).unwrap();
        if r["kind"] != "yarp_rpc" {
            continue;
        }
        total += 1;
        let req_hex = r["request"][0]["payload_hex"].as_str().unwrap();
        let cmd = Bottle::decode(&hex::decode(req_hex).unwrap()).unwrap();
        let rep = r["reply"]
            .as_array()
            .unwrap()
            .iter()
            .find(|u| u["unit"] == "reply")
            .unwrap();
        let want =
            Bottle::decode(&hex::decode(rep["payload_hex"].as_str().unwrap()).unwrap()).unwrap();
        let got = handle_rpc(&cmd, &mut dev, &mut stamp);
        if same_bottle(&got, &want) {
            pass += 1;
        } else {
            failures.push(format!("{} {cmd}: want {want}, got {got}", r["id"]));
        }
    }
    println!("controlboard yarp_rpc vectors: {pass} of {total} pass");
    for f in &failures {
        println!("  FAIL {f}");
    }
    assert!(total > 0);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The RPCs the recorded C++ remote_controlboard sent (cpp_client records) replayed
/// against `handle_rpc`: same reply structure, except for the commands whose device
/// interface this crate does not have yet (listed, and answered `[fail]`).
#[test]
fn replay_cpp_client_rpc_requests() {
    // the vectors must be there: never skip silently
    let path = yarp_interop_tests::vectors_dir().join("controlboard.jsonl");
    let text = std::fs::read_to_string(&path).expect("controlboard.jsonl");
    // getPidError, getPidOutput, resetPid, getTorqueRange, getNumberOfMotors, getGearboxRatio
    let unsupported = [
        "[get] [pid] [err] [pos] 0",
        "[get] [pid] [out] [pos] 0",
        "[set] [pid] [res] [pos] 0",
        "[get] [torq] [rng] 0",
        "[get] [mtnm]",
        "[get] [gbxr] 0",
    ];
    let mut dev = FakeMotionControl::new();
    dev.open(&Property::from_config_text("[GENERAL]\njoints 4\n").unwrap())
        .unwrap();
    let mut stamp = RpcStamp::new();
    let (mut total, mut pass, mut known) = (0, 0, 0);
    let mut failures = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let r: serde_json::Value = serde_json::from_str(line).unwrap();
        if r["kind"] != "cpp_client" {
            continue;
        }
        let units = r["units"].as_array().unwrap();
        let rpc = |kind: &str| {
            units
                .iter()
                .find(|u| u["unit"] == kind && u["port"] == "/proxyfake/rpc:i")
                .map(|u| Bottle::decode(&hex::decode(u["payload_hex"].as_str().unwrap()).unwrap()))
        };
        let (Some(Ok(cmd)), Some(Ok(want))) = (rpc("message"), rpc("reply")) else {
            continue;
        };
        total += 1;
        let got = handle_rpc(&cmd, &mut dev, &mut stamp);
        if unsupported.contains(&cmd.to_string().as_str()) {
            assert_eq!(got.to_string(), "[fail]");
            known += 1;
        } else if same_bottle(&got, &want) {
            pass += 1;
        } else {
            failures.push(format!("{} {cmd}: want {want}, got {got}", r["call"]));
        }
    }
    println!(
        "controlboard cpp_client RPC vectors: {pass} of {total} pass, {known} need interfaces this crate lacks"
    );
    assert!(total > 0);
    assert!(failures.is_empty(), "{failures:#?}");
}

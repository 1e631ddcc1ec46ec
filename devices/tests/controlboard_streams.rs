//! The streaming ports of `controlBoard_nws_yarp` against the C++ 3.12.3 recordings in
//! controlboard.jsonl: `state:o` / `stateExt:o` (envelope and payload bytes, over a
//! real tcp connection to a raw receiver) and `command:i` (the recorded C++
//! remote_controlboard streaming messages, replayed byte for byte). Run under netns-run.

mod controlboard_common;

use controlboard_common::{hex, name_client, read_message, records, run, wait_for};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use yarp_devices::controlboard::{
    positions_bottle, positions_from_bottle, ControlBoardNws, JointData,
};
use yarp_devices::{shared, PolyDriver, SharedDevice};
use yarp_proto::nameserver::RegisterRequest;
use yarp_proto::wire::command::PortCommand;
use yarp_proto::{Bottle, Property, Stamp, Value};

fn streams<'a>(recs: &'a [serde_json::Value], port: &str) -> Vec<&'a serde_json::Value> {
    recs.iter()
        .filter(|r| r["kind"] == "stream" && r["port"] == port)
        .collect()
}

#[test]
fn state_payloads_reencode_to_the_recorded_bytes() {
    let Some(recs) = records() else { return };
    let (mut n_state, mut n_ext) = (0, 0);
    for r in streams(&recs, "/fake/stateExt:o") {
        let payload = hex(&r["payload_hex"]);
        let b = Bottle::decode(&payload).unwrap();
        let data = JointData::from_bottle(&b).unwrap_or_else(|e| panic!("{}: {e}", r["id"]));
        assert_eq!(data.axes(), 4);
        assert!(data.joint_position.valid && data.interaction_mode.valid);
        assert_eq!(data.to_bottle().encode(), payload, "{}", r["id"]);
        n_ext += 1;
    }
    for r in streams(&recs, "/fake/state:o") {
        let payload = hex(&r["payload_hex"]);
        let q = positions_from_bottle(&Bottle::decode(&payload).unwrap()).unwrap();
        assert_eq!(positions_bottle(&q).encode(), payload, "{}", r["id"]);
        n_state += 1;
    }
    println!("stream payload vectors: state:o {n_state}, stateExt:o {n_ext} pass");
    assert!(n_state > 0 && n_ext > 0);
}

#[test]
fn envelopes_are_written_as_cpp_does() {
    let Some(recs) = records() else { return };
    let mut n = 0;
    for r in recs.iter().filter(|r| r["kind"] == "stream") {
        let text = r["port_command_text"].as_str().unwrap();
        let stamp = Stamp::from_text(text.strip_prefix("D ").unwrap()).unwrap();
        let mut block = Vec::new();
        PortCommand::with_stamp(&stamp, false).encode_binary(&mut block);
        assert_eq!(block, hex(&r["blocks_hex"][0]), "{}", r["id"]);
        n += 1;
    }
    println!("envelope vectors: {n} pass");
    assert!(n > 0);
}

/// Our fakeMotionControl, driven into the state the C++ one had when the streams were
/// recorded (after the yarp rpc and C++ client sessions), reads back exactly the
/// recorded `stateExt:o` and `state:o` payloads: all 11 channels, valid, same bytes.
#[test]
fn fake_state_reads_back_the_recorded_payload_bytes() {
    use yarp_devices::interfaces::*;
    use yarp_devices::vocabs::IM_COMPLIANT;
    use yarp_devices::{DeviceDriver, FakeMotionControl};
    let Some(recs) = records() else { return };
    let mut dev = FakeMotionControl::with_joints(4);
    dev.set_encoders(&[3.399033308029175, 2.0, 8.0, 33.0])
        .unwrap();
    dev.set_interaction_mode(0, IM_COMPLIANT).unwrap();
    dev.set_ref_duty_cycle(0, 10.0).unwrap(); // setRefDutyCycle(0,10.0)
    dev.set_ref_current(0, 0.5).unwrap(); // setRefCurrent(0,0.5): current 0.25
    dev.set_ref_torque(0, 1.5).unwrap(); // setRefTorque(0,1.5): hardware fault
    let (data, times) = JointData::read(&mut dev as &mut dyn DeviceDriver, 4);
    assert_eq!(times.len(), 4);
    let ext = streams(&recs, "/fake/stateExt:o");
    assert_eq!(
        hex::encode(data.to_bottle().encode()),
        ext[0]["payload_hex"].as_str().unwrap(),
        "{}",
        data.to_bottle()
    );
    let state = streams(&recs, "/fake/state:o");
    assert_eq!(
        hex::encode(positions_bottle(&data.joint_position.values).encode()),
        state[0]["payload_hex"].as_str().unwrap()
    );
    println!("stateExt:o / state:o payload bytes reproduced by our fake");
}

/// What `yarp read <port> envelope` printed (stream_text): the envelope `count time`,
/// then the data, which is our Bottle text of the recorded state exactly (our fake in
/// the recorded state prints the same `stateExt` line).
#[test]
fn yarp_read_prints_our_state_text() {
    use yarp_devices::interfaces::*;
    use yarp_devices::{DeviceDriver, FakeMotionControl};
    let Some(recs) = records() else { return };
    let mut dev = FakeMotionControl::with_joints(4);
    dev.set_encoders(&[3.399033308029175, 2.0, 8.0, 33.0])
        .unwrap();
    dev.set_interaction_mode(0, yarp_devices::vocabs::IM_COMPLIANT)
        .unwrap();
    dev.set_ref_duty_cycle(0, 10.0).unwrap();
    dev.set_ref_current(0, 0.5).unwrap();
    dev.set_ref_torque(0, 1.5).unwrap();
    let (data, _) = JointData::read(&mut dev as &mut dyn DeviceDriver, 4);
    let mut n = 0;
    for r in recs.iter().filter(|r| r["kind"] == "stream_text") {
        let ours = if r["port"] == "/fake/stateExt:o" {
            data.to_bottle().to_string()
        } else {
            positions_bottle(&data.joint_position.values).to_string()
        };
        let mut counts = Vec::new();
        for line in r["text_out"].as_array().unwrap() {
            let (envelope, text) = line.as_str().unwrap().split_once("     ").unwrap();
            let env = Bottle::from_text(envelope);
            assert!(
                env.len() == 2 && env[0].is_int() && env[1].is_float(),
                "{envelope}"
            );
            counts.push(env[0].as_i64().unwrap());
            assert_eq!(Bottle::from_text(text).to_string(), text);
            assert_eq!(ours, text, "{}", r["id"]);
            n += 1;
        }
        assert!(counts.windows(2).all(|w| w[1] == w[0] + 1), "{counts:?}");
    }
    println!("stream_text vectors: {n} printed lines reproduced");
    assert!(n > 0);
}

/// The streaming command messages the C++ client sent over tcp (cpp_client_tcp) decode
/// and re-encode unchanged, and equal, byte for byte, the `CommandMessage`s with the
/// heads our remote_controlboard sends for the same calls.
#[test]
fn command_messages_encode_as_the_cpp_client_does() {
    use yarp_devices::controlboard::CommandMessage;
    use yarp_proto::Vocab32;
    let Some(recs) = records() else { return };
    let v = |s: &str| Value::Vocab32(Vocab32::new(s));
    let ours = |call: &str| -> Option<CommandMessage> {
        let m = |head: Vec<Value>, body: &[f64]| {
            Some(CommandMessage::new(
                head.into_iter().collect(),
                body.to_vec(),
            ))
        };
        match call {
            "velocityMove(0,5.0)" => m(vec![v("vmo"), Value::Int32(0)], &[5.0]),
            "velocityMove(all)" => m(vec![v("vmos")], &[1.0, 2.0, 3.0, 4.0]),
            "setPosition(0,1.5)" => m(vec![v("dpo"), Value::Int32(0)], &[1.5]),
            "setPositions(all)" => m(vec![v("dpos")], &[1.0, 2.0, 3.0, 4.0]),
            "setRefCurrent(0,0.5)" => m(vec![v("icur"), v("ref"), Value::Int32(0)], &[0.5]),
            _ => None,
        }
    };
    let mut n = 0;
    for r in recs.iter().filter(|r| r["kind"] == "cpp_client_tcp") {
        for u in r["units"].as_array().unwrap() {
            if u["port"] != "/proxyfake/command:i" || u["unit"] != "message" {
                continue;
            }
            let payload = hex(&u["payload_hex"]);
            let got = CommandMessage::from_bottle(&Bottle::decode(&payload).unwrap()).unwrap();
            assert_eq!(got.to_bottle().encode(), payload);
            let call = r["call"].as_str().unwrap();
            let want = ours(call).unwrap_or_else(|| panic!("no message for {call}"));
            assert_eq!(
                hex::encode(want.to_bottle().encode()),
                hex::encode(&payload),
                "{call}"
            );
            n += 1;
        }
    }
    println!("cpp_client_tcp command messages: {n} byte-exact");
    assert!(n >= 5);
}

/// A served 4-joint fake board under `prefix`, publishing every `period`.
fn serve_fake(prefix: &str, period: Duration) -> (ControlBoardNws, SharedDevice) {
    let ns = name_client();
    let cfg = Property::from_config_text("device fakeMotionControl\n[GENERAL]\njoints 4\n");
    let dev = shared(PolyDriver::open(&cfg.unwrap()).unwrap());
    let prefix = prefix.to_string();
    let d = dev.clone();
    let nws = run(async move {
        let mut nws = ControlBoardNws::open_ports(&prefix, ns, period)
            .await
            .unwrap();
        nws.attach(d).unwrap();
        nws
    });
    (nws, dev)
}

/// Splits a message body into (envelope text, payload).
fn split_envelope(body: &[u8]) -> (String, Vec<u8>) {
    let (pc, used) = PortCommand::decode_binary(body).unwrap();
    assert_eq!(pc.key(), b'D', "data without reply");
    let text = String::from_utf8(pc.envelope_text().expect("envelope").to_vec()).unwrap();
    (text, body[used..].to_vec())
}

/// Same types (recursively) and same vocabs; numbers are compared by type only.
fn same_shape(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::List(x), Value::List(y)) => {
            x.len() == y.len() && x.iter().zip(y.iter()).all(|(p, q)| same_shape(p, q))
        }
        (Value::Vocab32(x), Value::Vocab32(y)) => x == y,
        _ => a.tag() == b.tag(),
    }
}

/// Connects `from` to a raw tcp receiver registered as `cap`, checks the connection
/// header against the recorded one, and returns three received message bodies.
fn capture(from: &str, cap: &str, recorded_header: Vec<u8>) -> Vec<Vec<u8>> {
    let ns = name_client();
    let (from, cap) = (from.to_string(), cap.to_string());
    run(async move {
        let l = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let port = l.local_addr().unwrap().port();
        ns.register_port(
            &RegisterRequest::explicit(&cap, "tcp", "127.0.0.1", port),
            &["127.0.0.1"],
            1,
        )
        .await
        .unwrap();
        let ns2 = ns.clone();
        let (f2, c2) = (from.clone(), cap.clone());
        let connect = tokio::spawn(async move {
            yarp_net::network::connect(&ns2, &f2, &c2, None)
                .await
                .unwrap()
        });
        let (mut s, _) = l.accept().await.unwrap();
        let mut header = vec![0u8; recorded_header.len()];
        s.read_exact(&mut header).await.unwrap();
        assert_eq!(hex::encode(&header), hex::encode(&recorded_header));
        let mut reply = b"YA".to_vec();
        reply.extend_from_slice(&i32::from(port).to_le_bytes());
        reply.extend_from_slice(b"RP");
        s.write_all(&reply).await.unwrap();
        let (ok, msg) = connect.await.unwrap();
        assert!(ok, "{msg}");
        let mut out = Vec::new();
        for _ in 0..3 {
            out.push(read_message(&mut s).await);
            s.write_all(&hex::decode("5941000000005250").unwrap())
                .await
                .unwrap();
        }
        out
    })
}

#[test]
fn state_ports_stream_the_recorded_layout_over_tcp() {
    let Some(recs) = records() else { return };
    let (nws, _dev) = serve_fake("/fake", Duration::from_millis(20));
    for (port, conn_id) in [("/fake/state:o", "cb-169"), ("/fake/stateExt:o", "cb-174")] {
        let conn = recs.iter().find(|r| r["id"] == conn_id).unwrap();
        let header = hex(&conn["events"][0]["hex"]);
        let want: Vec<Bottle> = streams(&recs, port)
            .iter()
            .map(|r| Bottle::decode(&hex(&r["payload_hex"])).unwrap())
            .collect();
        let cap = format!("/cap{}", port.replace(':', "_"));
        let mut counts = Vec::new();
        for body in capture(port, &cap, header) {
            let (env, payload) = split_envelope(&body);
            let env = env.as_str();
            let stamp = Stamp::from_text(env).expect("stamp");
            // the envelope is `count time` printed as C++ does
            assert_eq!(stamp.to_text(), env);
            counts.push(stamp.count);
            let got = Bottle::decode(&payload).unwrap();
            // every channel and validity flag as C++ (values move with the fake)
            assert!(
                same_shape(&Value::List(got.clone()), &Value::List(want[0].clone())),
                "{got}"
            );
            assert_eq!(
                payload.len(),
                hex(&streams(&recs, port)[0]["payload_hex"]).len()
            );
        }
        assert!(counts.windows(2).all(|w| w[1] == w[0] + 1), "{counts:?}");
    }
    run(nws.close());
}

#[test]
fn recorded_streaming_commands_drive_the_device() {
    let Some(recs) = records() else { return };
    let (nws, dev) = serve_fake("/cmdtest", Duration::from_millis(50));
    let ns = name_client();
    let open = recs
        .iter()
        .find(|r| r["kind"] == "cpp_client_tcp" && r["call"] == "open");
    let open = open.expect("cpp_client_tcp open record");
    // the handshake the C++ client sent to command:i
    let mut hello = Vec::new();
    for u in open["units"].as_array().unwrap() {
        if u["port"] == "/proxyfake/command:i" && u["dir"] == "c2s" {
            hello.extend(hex(&u["hex"]));
        }
    }
    let mut sent = Vec::new();
    let mut acks = Vec::new();
    let mut calls = Vec::new();
    for r in recs
        .iter()
        .filter(|r| r["kind"] == "cpp_client_tcp" && r["call"] != "open")
    {
        for u in r["units"].as_array().unwrap() {
            if u["port"] != "/proxyfake/command:i" {
                continue;
            }
            match u["unit"].as_str().unwrap() {
                "message" => {
                    let mut m = hex(&u["index_hex"]);
                    for b in u["blocks_hex"].as_array().unwrap() {
                        m.extend(hex(b));
                    }
                    sent.push(m);
                    calls.push(r["call"].as_str().unwrap().to_string());
                }
                "ack" => acks.push(hex(&u["hex"])),
                _ => {}
            }
        }
    }
    assert!(!sent.is_empty());
    let n = sent.len();
    let got_acks = run(async move {
        let c = ns.query("/cmdtest/command:i").await.unwrap().unwrap();
        let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
        s.write_all(&hello).await.unwrap();
        let mut reply = [0u8; 8];
        s.read_exact(&mut reply).await.unwrap();
        assert_eq!(&reply[..2], b"YA");
        let mut got = Vec::new();
        for m in sent {
            s.write_all(&m).await.unwrap();
            let mut ack = [0u8; 8];
            s.read_exact(&mut ack).await.unwrap();
            got.push(ack.to_vec());
        }
        got
    });
    assert_eq!(got_acks, acks);
    println!("command:i vectors: {n} messages acked as recorded: {calls:?}");
    // velocityMove(all) (1 2 3 4) came after velocityMove(0, 5.0)
    let speeds = wait_for("velocity commands applied", || {
        let mut pd = dev.lock();
        let v = pd.device().as_velocity_control().unwrap();
        let s = v.get_ref_velocities().unwrap();
        (s == [1.0, 2.0, 3.0, 4.0]).then_some(s)
    });
    assert_eq!(speeds, [1.0, 2.0, 3.0, 4.0]);
    // setPosition(0,1.5) then setPositions(1 2 3 4), then setRefCurrent(0,0.5) (acks
    // come on receipt: wait until the commands are applied)
    wait_for("position-direct and current references applied", || {
        let mut pd = dev.lock();
        let d = pd.device();
        let refs = d.as_position_direct()?.get_ref_positions().ok()?;
        let current = d.as_current_control()?.get_ref_current(0).ok()?;
        (refs == [1.0, 2.0, 3.0, 4.0] && current == 0.5).then_some(())
    });
    run(nws.close());
}

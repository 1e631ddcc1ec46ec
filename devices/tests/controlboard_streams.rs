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
            let w = &want[0];
            if port.ends_with("stateExt:o") {
                // the C++ fake fills motor speeds/accelerations and measured PWM, which
                // our interfaces cannot read yet: those flags are [fail] here
                let mut w = w.clone();
                for i in [9, 11, 15] {
                    *w.get_mut(i).unwrap() = got[i].clone();
                    assert_eq!(got[i].to_string(), "[fail]");
                }
                assert!(
                    same_shape(&Value::List(got.clone()), &Value::List(w)),
                    "{got}"
                );
            } else {
                assert!(
                    same_shape(&Value::List(got.clone()), &Value::List(w.clone())),
                    "{got}"
                );
            }
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
        let mut pd = dev.lock().unwrap();
        let v = pd.device().as_velocity_control().unwrap();
        let s = v.get_ref_velocities().unwrap();
        (s == [1.0, 2.0, 3.0, 4.0]).then_some(s)
    });
    assert_eq!(speeds, [1.0, 2.0, 3.0, 4.0]);
    run(nws.close());
}

//! `controlBoard_nws_yarp` as a registered device: opened through `PolyDriver` (with a
//! `subdevice`, or attached later), its parameters and their errors, and RPC robustness
//! over real sockets (run under netns-run).

mod controlboard_common;

use controlboard_common::{hex, name_client, records, run, same_bottle, with_recorded_stamps, T};
use std::io::Write;
use std::sync::{Arc, Mutex};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use yarp_devices::{shared, DeviceError, PolyDriver, Registry};
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Property};

fn config(text: &str) -> Property {
    Property::from_config_text(text).expect("config text")
}

/// Sends `cmds` (Bottle text) over one RPC connection to `port`; returns the replies.
fn rpc(port: &str, cmds: &[&str]) -> Vec<String> {
    let ns = name_client();
    let port = port.to_string();
    let cmds: Vec<String> = cmds.iter().map(|s| s.to_string()).collect();
    run(async move {
        let c = ns.query(&port).await.unwrap().expect("rpc port registered");
        let mut client = RpcClient::connect(&c, "/anon_rpc", Carrier::Tcp)
            .await
            .expect("connect");
        let mut out = Vec::new();
        for cmd in cmds {
            let reply = client.call(&Bottle::from_text(&cmd)).await.expect("reply");
            out.push(reply.to_string());
        }
        client.close().await;
        out
    })
}

fn registered(port: &str) -> bool {
    let ns = name_client();
    let port = port.to_string();
    run(async move { ns.query(&port).await.unwrap().is_some() })
}

#[test]
fn registry_lists_the_wrapper() {
    assert!(Registry::names().contains(&"controlBoard_nws_yarp"));
}

#[test]
fn polydriver_opens_wrapper_with_subdevice() {
    name_client();
    let mut pd = PolyDriver::open(&config(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /foo\nperiod 0.01\n\
         [GENERAL]\njoints 4\n",
    ))
    .expect("open wrapper");
    for p in [
        "/foo/rpc:i",
        "/foo/command:i",
        "/foo/state:o",
        "/foo/stateExt:o",
    ] {
        assert!(registered(p), "{p} not registered");
    }
    let replies = rpc(
        "/foo/rpc:i",
        &[
            "[get] [axes]",
            "[set] [pos] 0 10.0",
            "[get] [pos] 0",
            "[get] [prot]",
        ],
    );
    assert!(
        replies[0].starts_with("[is] [axes] 4 [tsta] 0 "),
        "{replies:?}"
    );
    assert_eq!(replies[1], "[ok]");
    assert!(
        replies[2].starts_with("[is] [pos] 10.0 [tsta] 1 "),
        "{replies:?}"
    );
    assert_eq!(replies[3], "[prot] 1 9 0 [ok]");
    pd.close().unwrap();
    for p in ["/foo/rpc:i", "/foo/state:o"] {
        assert!(!registered(p), "{p} still registered after close");
    }
}

#[test]
fn name_without_slash_gets_one() {
    name_client();
    let _pd = PolyDriver::open(&config(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname icub/left_arm\n",
    ))
    .expect("open");
    assert!(registered("/icub/left_arm/rpc:i"));
}

#[test]
fn attach_later_and_multiple_wrapper_rules() {
    name_client();
    let mut pd = PolyDriver::open(&config("device controlBoard_nws_yarp\nname /late\n"))
        .expect("open without device");
    // nothing attached yet: RPCs fail cleanly
    assert_eq!(rpc("/late/rpc:i", &["[get] [axes]"]), ["[fail]"]);
    let a = shared(PolyDriver::open(&config("device fakeMotionControl\naxes 2\n")).unwrap());
    let b = shared(PolyDriver::open(&config("device fakeMotionControl\naxes 3\n")).unwrap());
    let w = pd.device().as_multiple_wrapper().expect("IMultipleWrapper");
    let err = w
        .attach_all(&[("a".into(), a.clone()), ("b".into(), b)])
        .unwrap_err();
    assert!(err.to_string().contains("exactly one"), "{err}");
    w.attach_all(&[("a".into(), a.clone())])
        .expect("attach one");
    assert!(rpc("/late/rpc:i", &["[get] [axes]"])[0].starts_with("[is] [axes] 2 "));
    // a second attach is refused until detach
    let wr = pd.device().as_wrapper().expect("IWrapper");
    assert!(wr.attach(a.clone()).is_err());
    wr.detach().unwrap();
    assert_eq!(rpc("/late/rpc:i", &["[get] [axes]"]), ["[fail]"]);
    wr.attach(a).expect("attach after detach");
    assert!(rpc("/late/rpc:i", &["[get] [axes]"])[0].starts_with("[is] [axes] 2 "));
}

#[test]
fn parameter_errors_name_param_and_device() {
    name_client();
    let err = PolyDriver::open(&config("device controlBoard_nws_yarp\n"))
        .err()
        .unwrap();
    assert_eq!(
        err,
        DeviceError::MissingParam {
            device: "controlBoard_nws_yarp".into(),
            param: "name".into()
        }
    );
    for bad in ["period 20", "period -0.5", "period fast", "period 0.0"] {
        let err = PolyDriver::open(&config(&format!(
            "device controlBoard_nws_yarp\nname /p\n{bad}\n"
        )))
        .err()
        .unwrap();
        let text = err.to_string();
        assert!(
            text.contains("`period`") && text.contains("controlBoard_nws_yarp"),
            "{bad}: {text}"
        );
    }
}

/// Collects log output for the assertion that bad RPCs are logged.
#[derive(Clone, Default)]
struct LogBuf(Arc<Mutex<Vec<u8>>>);

impl Write for LogBuf {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().unwrap().extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn malformed_rpcs_get_fail_and_a_log_line_never_a_crash() {
    let log = LogBuf::default();
    let sink = log.clone();
    let _ = tracing_subscriber::fmt()
        .with_writer(move || sink.clone())
        .with_ansi(false)
        .try_init();
    name_client();
    let _pd = PolyDriver::open(&config(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /bad\naxes 2\n",
    ))
    .expect("open");
    let bad = [
        "[set] [poss] 5",                  // list expected
        "[set] [poss] (1.0 2.0 3.0)",      // wrong count
        "[set] [posg] 2 (1) (1.0)",        // group sizes disagree
        "[get] [enc] 99",                  // joint out of range
        "[set] [icmd] [cmds] ([pos])",     // wrong count
        "[set] [pid] [pid] [pos] (1 2) 3", // joint is a list
        "[get] [intm] [mobg] 1 7",         // joints not a list
        "[get] [zzzz]",                    // unknown
        "\"set\" 3.5 (nested (list))",     // nonsense types
    ];
    let replies = rpc("/bad/rpc:i", &bad);
    for (cmd, r) in bad.iter().zip(&replies) {
        assert_eq!(r, "[fail]", "{cmd}");
    }
    assert_eq!(rpc("/bad/rpc:i", &["[help]", "42"]), ["[nak]", "[nak]"]);
    // still serving
    assert!(rpc("/bad/rpc:i", &["[get] [axes]"])[0].starts_with("[is] [axes] 2 "));
    let text = String::from_utf8_lossy(&log.0.lock().unwrap()).into_owned();
    let logged = text.matches("replying [fail]").count();
    assert!(logged >= bad.len(), "only {logged} log lines:\n{text}");
    assert!(text.contains("replying [nak]"), "{text}");
    let _ = T;
}

/// The whole recorded `yarp rpc` connection (cb-077: every command typed, including the
/// ones kept back from the per-command records) replayed byte for byte into our wrapper
/// serving a fresh fake: each reply has the recorded structure and is followed by the
/// ack, and all but the known value differences are byte-exact apart from the stamp.
#[test]
fn recorded_yarp_rpc_connection_gets_the_recorded_replies() {
    let Some(recs) = records() else { return };
    let rec = recs
        .iter()
        .find(|r| r["kind"] == "yarp_rpc_connection")
        .expect("yarp_rpc_connection record");
    let c2s = rec["c2s_units"].as_array().unwrap().clone();
    let s2c = rec["s2c_units"].as_array().unwrap().clone();
    name_client();
    let _pd = PolyDriver::open(&config(
        "device controlBoard_nws_yarp\nsubdevice fakeMotionControl\nname /rpcconn\n\
         [GENERAL]\njoints 4\n",
    ))
    .expect("open wrapper");
    let ns = name_client();
    let messages: Vec<Vec<u8>> = c2s
        .iter()
        .filter(|u| u["unit"] == "message")
        .map(|u| {
            let mut m = hex(&u["index_hex"]);
            for b in u["blocks_hex"].as_array().unwrap() {
                m.extend(hex(b));
            }
            m
        })
        .collect();
    let replies: Vec<Vec<u8>> = s2c
        .iter()
        .filter(|u| u["unit"] == "reply")
        .map(|u| hex(&u["payload_hex"]))
        .collect();
    assert_eq!(messages.len(), replies.len());
    let hello = [hex(&c2s[0]["hex"]), hex(&c2s[1]["hex"])].concat();
    let got = run(async move {
        let c = ns
            .query("/rpcconn/rpc:i")
            .await
            .unwrap()
            .expect("registered");
        let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
        s.write_all(&hello).await.unwrap();
        let mut header = [0u8; 8];
        s.read_exact(&mut header).await.unwrap();
        assert_eq!((&header[..2], &header[6..]), (&b"YA"[..], &b"RP"[..]));
        assert_eq!(
            i32::from_le_bytes([header[2], header[3], header[4], header[5]]),
            i32::from(c.port),
            "the header reply carries our own port"
        );
        let ack = hex::decode("5941000000005250").unwrap();
        let mut got = Vec::new();
        for m in messages {
            s.write_all(&m).await.unwrap();
            // the reply Bottle, then the ack
            let mut r = Vec::new();
            let mut buf = [0u8; 4096];
            while !r.ends_with(&ack) {
                let n = s.read(&mut buf).await.unwrap();
                assert!(n > 0, "connection closed after {} replies", got.len());
                r.extend_from_slice(&buf[..n]);
            }
            r.truncate(r.len() - ack.len());
            got.push(r);
        }
        got
    });
    let (mut exact, mut failures) = (0, Vec::new());
    for (k, (body, want)) in got.iter().zip(&replies).enumerate() {
        let (gb, wb) = (Bottle::decode(body).unwrap(), Bottle::decode(want).unwrap());
        if !same_bottle(&gb, &wb) {
            failures.push(format!("reply {k}: {gb} vs {wb}"));
        } else if with_recorded_stamps(&gb, &wb).encode() == *want {
            exact += 1;
        } else {
            println!("  values differ: reply {k}: {gb} vs {wb}");
        }
    }
    println!(
        "yarp rpc connection: {} replies with the recorded structure, {exact} byte-exact apart from the stamp",
        replies.len()
    );
    assert!(failures.is_empty(), "{failures:#?}");
    // only the two checkMotionDone replies differ (see controlboard_vectors.rs)
    assert_eq!(exact + 2, replies.len(), "{exact} of {}", replies.len());
}

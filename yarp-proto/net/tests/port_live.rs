//! Ports over real loopback sockets with a real (in-process) name server: data, RPC,
//! envelopes, text-mode telnet sessions, admin commands, reverse connections, dead peers.
//! Run under ../shared/netns-run.

mod common;
use common::{name_server, T};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::time::timeout;
use yarp_net::nameserver::{NameClient, NameServer};
use yarp_net::port::Port;
use yarp_proto::{bottle, Bottle, Stamp, Vocab32};

async fn read_bottle(p: &Port) -> Bottle {
    let m = timeout(T, p.read())
        .await
        .expect("message in time")
        .expect("port open");
    m.bottle().expect("valid bottle")
}

/// Reads from a raw socket until `want` has been seen (bounded).
async fn read_until(s: &mut TcpStream, want: &[u8]) -> Vec<u8> {
    let mut got = Vec::new();
    let mut buf = [0u8; 4096];
    timeout(T, async {
        while !got.windows(want.len()).any(|w| w == want) {
            let n = s.read(&mut buf).await.expect("read");
            assert!(
                n > 0,
                "peer closed; got {:?}",
                String::from_utf8_lossy(&got)
            );
            got.extend_from_slice(&buf[..n]);
        }
    })
    .await
    .unwrap_or_else(|_| panic!("timed out; got {:?}", String::from_utf8_lossy(&got)));
    got
}

#[tokio::test]
async fn write_and_read_over_tcp_fast_tcp_and_text() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/w", ns.clone()).await.expect("open /w");
    let r = Port::open("/r", ns.clone()).await.expect("open /r");
    for carrier in ["tcp", "fast_tcp", "text", "text_ack"] {
        w.connect("/r", Some(carrier)).await.expect("connect");
        let b = bottle!["hello", 42, 2.5, Vocab32::new("ok")];
        assert_eq!(w.write(&b).await, 1);
        assert_eq!(read_bottle(&r).await, b, "{carrier}");
        assert!(w.disconnect("/r"));
        // the reader notices the disconnection
        timeout(T, async {
            while !r.inputs().is_empty() {
                tokio::time::sleep(Duration::from_millis(10)).await;
            }
        })
        .await
        .expect("input removed");
    }
    // envelopes travel with the message
    w.connect("/r", None).await.expect("connect");
    w.write_stamped(&bottle![1], Stamp::new(7, 1795298248.55057))
        .await;
    let m = timeout(T, r.read()).await.unwrap().unwrap();
    assert_eq!(m.stamp, Some(Stamp::new(7, 1795298248.55057)));
    assert_eq!(r.inputs(), vec!["/w".to_string()]);
    w.close().await;
    r.close().await;
    assert_eq!(ns.query("/w").await.unwrap(), None, "unregistered on close");
    stop.shutdown();
}

#[tokio::test]
async fn rpc_round_trip() {
    let (ns, stop) = name_server().await;
    let server = Port::open("/srv", ns.clone()).await.unwrap();
    let client = Port::open("/cli", ns.clone()).await.unwrap();
    tokio::spawn(async move {
        while let Some(mut m) = server.read().await {
            let b = m.bottle().unwrap();
            let mut reply = bottle![Vocab32::new("is")];
            reply.extend(b.into_items());
            m.reply(reply);
        }
    });
    for carrier in ["tcp", "text_ack"] {
        client.connect("/srv", Some(carrier)).await.unwrap();
        let reply = timeout(T, client.rpc(&bottle![Vocab32::new("get"), 3]))
            .await
            .unwrap()
            .unwrap();
        assert_eq!(reply.to_string(), "[is] [get] 3", "{carrier}");
        client.disconnect("/srv");
    }
    stop.shutdown();
}

#[tokio::test]
async fn telnet_style_text_session_and_admin() {
    let (ns, stop) = name_server().await;
    let r = Port::open("/rd", ns.clone()).await.unwrap();
    let c = r.contact().clone();
    let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
    s.write_all(b"CONNECT /rawtext\n").await.unwrap();
    assert_eq!(read_until(&mut s, b"\r\n").await, b"Welcome /rawtext\r\n");
    s.write_all(b"d\nhello from raw text\n").await.unwrap();
    assert_eq!(read_bottle(&r).await.to_string(), "hello from raw text");
    s.write_all(b"*\n").await.unwrap();
    let desc = read_until(&mut s, b"using text\r\n").await;
    let desc = String::from_utf8_lossy(&desc);
    assert!(
        desc.starts_with(&format!("This is /rd at tcp://127.0.0.1:{}/\r\n", c.port)),
        "{desc}"
    );
    assert!(desc.contains("There is an input connection from /rawtext to /rd using text"));

    // the paper's session: a sender name without a slash
    let mut p = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
    p.write_all(b"CONNECT foo\n").await.unwrap();
    assert_eq!(read_until(&mut p, b"\r\n").await, b"Welcome foo\r\n");
    drop(p);

    let mut a = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
    a.write_all(b"CONNACK /rawadm\n").await.unwrap();
    read_until(&mut a, b"Welcome /rawadm\r\n").await;
    a.write_all(b"a\n[ver]\n").await.unwrap();
    assert_eq!(
        read_until(&mut a, b"<ACK>\r\n").await,
        b"[ver] 1 2 3\r\n<ACK>\r\n"
    );
    a.write_all(b"a\n[list] [in]\n").await.unwrap();
    let listed = read_until(&mut a, b"<ACK>\r\n").await;
    assert_eq!(listed, b"\"/rawtext\" \"/rawadm\"\r\n<ACK>\r\n");
    // garbage does not hurt the port
    a.write_all(b"zzz\n").await.unwrap();
    read_until(&mut a, b"<ACK>\r\n").await;
    a.write_all(b"q\n").await.unwrap();
    read_until(&mut a, b"<ACK>\r\n").await;
    r.close().await;
    stop.shutdown();
}

#[tokio::test]
async fn third_party_connect_through_admin_add() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/w3", ns.clone()).await.unwrap();
    let r = Port::open("/r3", ns.clone()).await.unwrap();
    // what `yarp connect /w3 /r3` does: an admin [add] sent to /w3
    let c = w.contact().clone();
    let mut a = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
    a.write_all(b"CONNACK /admin\n").await.unwrap();
    read_until(&mut a, b"\r\n").await;
    a.write_all(b"a\n[add] /r3\n").await.unwrap();
    let reply = read_until(&mut a, b"<ACK>\r\n").await;
    assert_eq!(
        String::from_utf8_lossy(&reply),
        "0 \"Added connection from /w3 to /r3\\r\\n\"\r\n<ACK>\r\n"
    );
    assert_eq!(w.outputs(), vec!["/r3".to_string()]);
    w.write(&bottle![5]).await;
    assert_eq!(read_bottle(&r).await, bottle![5]);
    a.write_all(b"a\n[del] /r3\n").await.unwrap();
    let reply = read_until(&mut a, b"<ACK>\r\n").await;
    assert!(String::from_utf8_lossy(&reply).starts_with("0 \"Removed connection from /w3 to /r3"));
    a.write_all(b"a\n[add] /nobody\n").await.unwrap();
    let reply = read_until(&mut a, b"<ACK>\r\n").await;
    assert_eq!(
        String::from_utf8_lossy(&reply),
        "-1 \"Do not know how to connect to /nobody\\r\\n\"\r\n<ACK>\r\n"
    );
    stop.shutdown();
}

#[tokio::test]
async fn reverse_connection_carries_output() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/wrev", ns.clone()).await.unwrap();
    let c = w.contact().clone();
    let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
    s.write_all(b"CONNECT /rawrev\n").await.unwrap();
    read_until(&mut s, b"\r\n").await;
    s.write_all(b"r\n").await.unwrap();
    timeout(T, async {
        while w.outputs().is_empty() {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .expect("reversed into an output");
    w.write(&Bottle::from_text("reversed 1 2.5")).await;
    assert_eq!(
        read_until(&mut s, b"2.5\r\n").await,
        b"D\r\nreversed 1 2.5\r\n"
    );
    stop.shutdown();
}

#[tokio::test]
async fn dead_peers_and_garbage_are_survived() {
    let (ns, stop) = name_server().await;
    let r = Port::open("/rg", ns.clone()).await.unwrap();
    let c = r.contact().clone();
    // garbage header, truncated header, a peer dying mid-message
    for junk in [
        &b"GARBAGE!xxxx"[..],
        b"YA",
        b"\x59\x41\xe4\x1e\x00\x00\x52\x50\x03\x00\x00\x00/x\x00\x59\x41\x0a",
    ] {
        let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
        s.write_all(junk).await.unwrap();
        drop(s);
    }
    let w = Port::open("/wg", ns.clone()).await.unwrap();
    w.connect("/rg", None).await.unwrap();
    w.write(&bottle![1, 2]).await;
    assert_eq!(read_bottle(&r).await, bottle![1, 2]);
    // the reader vanishes: the writer drops the output instead of hanging
    r.close().await;
    timeout(T, async {
        loop {
            w.write(&bottle![3]).await;
            if w.outputs().is_empty() {
                break;
            }
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    })
    .await
    .expect("dead output removed");
    stop.shutdown();
}

#[tokio::test]
async fn ports_register_again_after_a_name_server_restart() {
    let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1").await.unwrap();
    let addr = ns.local_addr();
    let stop = ns.shutdown_handle();
    let server = tokio::spawn(ns.serve());
    let client = NameClient::new(addr).with_timeout(T);
    let p = Port::open("/survivor", client.clone()).await.unwrap();
    let contact = p.contact().clone();
    stop.shutdown();
    let _ = timeout(T, server).await;
    // a fresh, empty server on the same address
    let ns2 = NameServer::bind(addr, "127.0.0.1")
        .await
        .expect("rebind same port");
    let stop2 = ns2.shutdown_handle();
    tokio::spawn(ns2.serve());
    timeout(T, async {
        loop {
            if let Ok(Some(c)) = client.query("/survivor").await {
                assert_eq!(
                    (c.host.as_str(), c.port),
                    (contact.host.as_str(), contact.port)
                );
                break;
            }
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    })
    .await
    .expect("re-registered");
    p.close().await;
    stop2.shutdown();
}

#[tokio::test]
async fn many_ports_and_many_connections() {
    let (ns, stop) = name_server().await;
    let r = Port::open("/hub", ns.clone()).await.unwrap();
    // 100 concurrent connections into one port
    let c = r.contact().clone();
    let mut tasks = Vec::new();
    for i in 0..100 {
        let c = c.clone();
        tasks.push(tokio::spawn(async move {
            let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
            s.write_all(format!("CONNECT /c{i}\nd\n{i}\n").as_bytes())
                .await
                .unwrap();
            read_until(&mut s, b"\r\n").await;
            s
        }));
    }
    let mut streams = Vec::new();
    for t in tasks {
        streams.push(timeout(T, t).await.unwrap().unwrap());
    }
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..100 {
        let b = read_bottle(&r).await;
        seen.insert(b.get(0).and_then(|v| v.as_i64()).unwrap());
    }
    assert_eq!(seen.len(), 100);
    drop(streams);
    // 1000 registered ports
    let mut names = Vec::new();
    for i in 0..1000 {
        let name = format!("/many/{i}");
        ns.register(&yarp_proto::nameserver::RegisterRequest::explicit(
            &name,
            "tcp",
            "127.0.0.1",
            20000 + i,
        ))
        .await
        .unwrap();
        names.push(name);
    }
    let listed = ns.list(Some("/many")).await.unwrap();
    assert_eq!(listed.len(), 1000);
    stop.shutdown();
}

#[tokio::test]
async fn datagram_carriers_udp_and_mcast() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/wd", ns.clone()).await.unwrap();
    let r1 = Port::open("/rd1", ns.clone()).await.unwrap();
    let r2 = Port::open("/rd2", ns.clone()).await.unwrap();
    w.connect("/rd1", Some("udp")).await.expect("udp connect");
    timeout(T, async {
        while r1.inputs().is_empty() {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .expect("udp input registered");
    let big = Bottle::from_text(format!("{{{}}}", "7 ".repeat(200_000)));
    w.write(&bottle!["over", "udp", 1]).await;
    assert_eq!(read_bottle(&r1).await.to_string(), "over udp 1");
    w.write(&big).await;
    assert_eq!(read_bottle(&r1).await, big);
    // disconnecting a udp output asks the reader to drop the input (`~/wd`)
    assert!(w.disconnect("/rd1"));
    timeout(T, async {
        while !r1.inputs().is_empty() {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .expect("udp input removed");

    // one multicast group reaches both readers
    w.connect("/rd1", Some("mcast"))
        .await
        .expect("mcast connect 1");
    w.connect("/rd2", Some("mcast"))
        .await
        .expect("mcast connect 2");
    timeout(T, async {
        while r1.inputs().is_empty() || r2.inputs().is_empty() {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .expect("mcast inputs registered");
    w.write(&bottle!["to", "everyone"]).await;
    assert_eq!(read_bottle(&r1).await.to_string(), "to everyone");
    assert_eq!(read_bottle(&r2).await.to_string(), "to everyone");
    stop.shutdown();
}

#[tokio::test]
async fn a_port_seen_from_a_browser() {
    let (ns, stop) = name_server().await;
    let r = Port::open("/web", ns.clone()).await.unwrap();
    let c = r.contact().clone();
    let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
    s.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
        .await
        .unwrap();
    let page = read_until(&mut s, b"</html>").await;
    let page = String::from_utf8_lossy(&page);
    assert!(page.starts_with("HTTP/1.1 200 OK\r\n"), "{page}");
    assert!(page.contains("This is /web at tcp://"), "{page}");
    let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
    s.write_all(b"GET /?data=hello+%5Bok%5D+3 HTTP/1.1\r\n\r\n")
        .await
        .unwrap();
    read_until(&mut s, b"</html>").await;
    assert_eq!(read_bottle(&r).await.to_string(), "hello [ok] 3");
    stop.shutdown();
}

#[tokio::test]
async fn local_carrier_between_ports_of_one_process() {
    let (ns, stop) = name_server().await;
    let w = Port::open("/wl", ns.clone()).await.unwrap();
    let r = Port::open("/rl", ns.clone()).await.unwrap();
    w.connect("/rl", Some("local"))
        .await
        .expect("local connect");
    assert_eq!(r.inputs(), vec!["/wl".to_string()]);
    let big = Bottle::from_text(format!("{{{}}}", "9 ".repeat(100_000)));
    w.write_stamped(&big, Stamp::new(3, 1.5)).await;
    let m = timeout(T, r.read()).await.unwrap().unwrap();
    assert_eq!(m.stamp, Some(Stamp::new(3, 1.5)));
    assert_eq!(m.bottle().unwrap(), big);
    // a shared Bottle reaches the reader itself, not a copy
    let shared = std::sync::Arc::new(big.clone());
    w.write_shared(shared.clone(), None).await;
    let m = timeout(T, r.read()).await.unwrap().unwrap();
    assert!(std::sync::Arc::ptr_eq(&m.shared_bottle().unwrap(), &shared));
    // RPC over local
    let r2 = std::sync::Arc::new(r);
    let server = r2.clone();
    tokio::spawn(async move {
        while let Some(mut m) = server.read().await {
            let b = m.bottle().unwrap();
            m.reply(bottle![Vocab32::new("ok"), b.len() as i32]);
        }
    });
    let reply = timeout(T, w.rpc(&bottle![1, 2, 3])).await.unwrap().unwrap();
    assert_eq!(reply.to_string(), "[ok] 3");
    assert!(w.disconnect("/rl"));
    timeout(T, async {
        while !r2.inputs().is_empty() {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .expect("local input removed");
    // a port of another process cannot be reached locally
    assert!(w.connect("/nowhere", Some("local")).await.is_err());
    stop.shutdown();
}

#[tokio::test]
async fn name_server_found_by_multicast() {
    use yarp_net::nameserver::{fallback, ServerConfig};
    // a port number of our own so that other servers in the namespace do not answer
    let probe = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let mport = probe.local_addr().unwrap().port();
    drop(probe);
    let mut cfg = ServerConfig::new("127.0.0.1");
    cfg.fallback_port = mport as i32;
    let ns = NameServer::bind_with("127.0.0.1:0", cfg).await.unwrap();
    let addr = ns.local_addr();
    let stop = ns.shutdown_handle();
    tokio::spawn(ns.serve());
    let mut found = None;
    for _ in 0..20 {
        found = fallback::detect(
            mport,
            "/root",
            std::net::Ipv4Addr::LOCALHOST,
            Duration::from_millis(300),
        )
        .await
        .expect("multicast available in the test namespace");
        if found.is_some() {
            break;
        }
    }
    let c = found.expect("the server answered the multicast query");
    assert_eq!(
        (c.name.as_str(), c.host.as_str(), c.port),
        ("/root", "127.0.0.1", addr.port())
    );
    stop.shutdown();
}

#[tokio::test]
async fn unix_stream_between_ports_with_envelopes_and_acks() {
    let dir = std::env::temp_dir().join(format!("yarp-rs-unix-{}", std::process::id()));
    std::env::set_var("YARP_RUNTIME_DIR", &dir);
    let (ns, stop) = name_server().await;
    let w = Port::open("/wu", ns.clone()).await.unwrap();
    let r = Port::open("/ru", ns.clone()).await.unwrap();
    for carrier in ["unix_stream", "unix_stream_ack"] {
        w.connect("/ru", Some(carrier)).await.expect(carrier);
        timeout(T, async {
            while r.inputs().is_empty() {
                tokio::time::sleep(Duration::from_millis(5)).await;
            }
        })
        .await
        .expect("input appears");
        let big = Bottle::from_text(format!("{carrier} {{{}}}", "7 ".repeat(50_000)));
        for i in 0..3 {
            assert_eq!(w.write_stamped(&big, Stamp::new(i, 0.25)).await, 1);
            let m = timeout(T, r.read()).await.unwrap().unwrap();
            assert_eq!(m.stamp, Some(Stamp::new(i, 0.25)));
            assert_eq!(m.bottle().unwrap(), big);
        }
        // no replies on this carrier: the RPC is refused, not hung
        assert!(timeout(T, w.rpc(&bottle![1])).await.unwrap().is_err());
        assert!(w.disconnect("/ru"));
        timeout(T, async {
            while !r.inputs().is_empty() {
                tokio::time::sleep(Duration::from_millis(5)).await;
            }
        })
        .await
        .expect("input removed after q");
    }
    // the sockets are gone once connected
    let left: Vec<_> = std::fs::read_dir(&dir).map_or(Vec::new(), |d| d.collect());
    assert!(left.is_empty(), "left-over sockets: {left:?}");
    stop.shutdown();
    let _ = std::fs::remove_dir_all(&dir);
}

//! udp and mcast carriers over real loopback sockets: handshakes on TCP, messages in
//! datagrams, loss and garbage, multicast to several receivers.
//! Run under ../shared/netns-run (the multicast route must be on lo).

use std::net::{Ipv4Addr, SocketAddr, SocketAddrV4};
use std::time::Duration;
use tokio::net::{TcpListener, TcpStream, UdpSocket};
use tokio::time::timeout;
use yarp_net::dgram::{
    mcast_handshake_connect, read_dgram_start, udp_connect, udp_handshake_accept, McastReceiver,
    McastSender, UdpReceiver, UdpSender, DEFAULT_MCAST_INTERFACE,
};
use yarp_proto::wire::datagram::{encode_datagram, DatagramEvent, DatagramWriter};
use yarp_proto::wire::{data_message, Carrier};
use yarp_proto::{bottle, Bottle, Value};

const T: Duration = Duration::from_secs(10);

async fn recv_bottle(r: &mut UdpReceiver) -> Bottle {
    let m = timeout(T, r.recv())
        .await
        .expect("message in time")
        .expect("socket ok");
    m.bottle().expect("valid bottle")
}

fn big_bottle(n: usize, tag: &str) -> Bottle {
    let mut b = bottle![tag];
    b.push(Value::Blob((0..n).map(|i| (i * 7 % 251) as u8).collect()));
    b
}

/// A udp connection set up through the real TCP handshake.
async fn udp_pair(name: &str) -> (UdpSender, UdpReceiver) {
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let accept = tokio::spawn(async move {
        let (mut s, _) = listener.accept().await.unwrap();
        let start = read_dgram_start(&mut s).await.unwrap();
        let rx = udp_handshake_accept(&mut s, Ipv4Addr::UNSPECIFIED.into())
            .await
            .unwrap();
        (start, rx)
    });
    let tcp = TcpStream::connect(addr).await.unwrap();
    let tx = timeout(T, udp_connect(tcp, name)).await.unwrap().unwrap();
    let (start, rx) = accept.await.unwrap();
    assert_eq!(start.carrier, Carrier::Udp);
    assert_eq!(start.sender_name, name);
    assert_eq!(start.group, None);
    assert_eq!(
        tx.peer_addr().unwrap(),
        SocketAddr::from((Ipv4Addr::LOCALHOST, rx.local_port().unwrap()))
    );
    (tx, rx)
}

#[tokio::test]
async fn udp_round_trip_small_and_large() {
    let (mut tx, mut rx) = udp_pair("/w").await;
    let small = bottle!["hello", 42, 2.5];
    assert_eq!(tx.send_bottle(&small).await.unwrap(), 1);
    assert_eq!(recv_bottle(&mut rx).await, small);

    // 1 MB: 17 datagrams, read concurrently as a real port would
    let big = big_bottle(1 << 20, "big");
    let reader = tokio::spawn(async move {
        let b = recv_bottle(&mut rx).await;
        let after = recv_bottle(&mut rx).await;
        (b, after, rx)
    });
    assert_eq!(tx.send_bottle(&big).await.unwrap(), 17);
    tx.send_bottle(&bottle!["after"]).await.unwrap();
    let (got, after, rx) = reader.await.unwrap();
    assert!(got == big, "1 MB bottle differs");
    assert_eq!(after, bottle!["after"]);
    let s = rx.stats();
    assert_eq!((s.messages, s.dropped, s.lost), (3, 0, 0));
    assert_eq!(tx.datagrams(), 19);
}

#[tokio::test]
async fn udp_survives_garbage_and_loss() {
    let (mut tx, mut rx) = udp_pair("/w").await;
    let target = SocketAddr::from((Ipv4Addr::LOCALHOST, rx.local_port().unwrap()));
    let raw = UdpSocket::bind("127.0.0.1:0").await.unwrap();
    raw.connect(target).await.unwrap();

    tx.send_bottle(&bottle!["first"]).await.unwrap();
    // garbage: empty, short, bad crc, valid crc but not a message, interrupt, huge
    for g in [
        &b""[..],
        b"abc",
        &[0x5a; 100],
        &encode_datagram(0, b"not a message"),
        &encode_datagram(-1, &[0; 10]),
        &vec![0x11; 60000],
    ] {
        raw.send(g).await.unwrap();
    }
    tx.send_bottle(&bottle!["second"]).await.unwrap();

    // a message with a lost datagram (split small so it takes several datagrams)
    let mut w = DatagramWriter::with_datagram_size(1000);
    let lossy = data_message(&big_bottle(5000, "lossy"), false);
    for (i, d) in w.split(&lossy).enumerate() {
        if i != 2 {
            raw.send(&d).await.unwrap();
        }
    }
    // a message whose tail is lost, directly followed by a good one
    let partial: Vec<_> = w
        .split(&data_message(&big_bottle(5000, "tail"), false))
        .collect();
    for d in &partial[..partial.len() - 1] {
        raw.send(d).await.unwrap();
    }
    tx.send_bottle(&bottle!["third"]).await.unwrap();
    // and garbage with a valid CRC in the middle of a message does not break it
    let ok: Vec<_> = w
        .split(&data_message(&big_bottle(3000, "whole"), false))
        .collect();
    raw.send(&ok[0]).await.unwrap();
    raw.send(&[0x5a; 30]).await.unwrap();
    for d in &ok[1..] {
        raw.send(d).await.unwrap();
    }

    let mut got = Vec::new();
    let mut events = Vec::new();
    while got.len() < 4 {
        let e = timeout(T, rx.recv_event()).await.unwrap().unwrap();
        if let DatagramEvent::Message(m) = &e {
            let b = m.bottle().unwrap();
            got.push(b.get(0).unwrap().as_str().unwrap().to_string());
        }
        events.push(e);
    }
    assert_eq!(got, ["first", "second", "third", "whole"]);
    let s = rx.stats();
    assert!(s.dropped >= 6, "{s:?}");
    assert_eq!(s.lost, 3, "{events:#?}");
    assert_eq!(s.interrupts, 1);
}

#[tokio::test]
async fn udp_sender_handles_unreachable_peer() {
    // nobody listens: sends succeed or fail with an io error, never panic
    let sock = UdpSocket::bind("127.0.0.1:0").await.unwrap();
    let addr = sock.local_addr().unwrap();
    drop(sock);
    let mut tx = UdpSender::connect(addr).await.unwrap();
    for _ in 0..3 {
        let _ = tx.send_bottle(&bottle!["nobody"]).await;
    }
}

#[tokio::test]
async fn mcast_to_two_receivers() {
    let group = SocketAddrV4::new(Ipv4Addr::new(224, 1, 1, 7), 19071);
    let mut r1 = McastReceiver::join(group, DEFAULT_MCAST_INTERFACE)
        .await
        .expect("join 1");
    let mut r2 = McastReceiver::join(group, DEFAULT_MCAST_INTERFACE)
        .await
        .expect("join 2");
    // a receiver of another group on the same port sees nothing of this one
    let other = SocketAddrV4::new(Ipv4Addr::new(224, 1, 1, 8), 19071);
    let mut r3 = McastReceiver::join(other, DEFAULT_MCAST_INTERFACE)
        .await
        .expect("join 3");

    // the handshake a receiving port reads on TCP
    let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let accept = tokio::spawn(async move {
        let (mut s, _) = listener.accept().await.unwrap();
        read_dgram_start(&mut s).await.unwrap()
    });
    let mut tcp = TcpStream::connect(addr).await.unwrap();
    mcast_handshake_connect(&mut tcp, "/w", group)
        .await
        .unwrap();
    drop(tcp);
    let start = accept.await.unwrap();
    assert_eq!(start.carrier, Carrier::Mcast);
    assert_eq!(start.sender_name, "/w");
    assert_eq!(start.group, Some(group));

    let mut tx = McastSender::open(group, DEFAULT_MCAST_INTERFACE)
        .await
        .expect("mcast sender");
    assert_eq!(tx.group(), group);
    let small = bottle!["to", "all", 1];
    let big = big_bottle(300_000, "big");
    let readers: Vec<_> = [r1, r2]
        .into_iter()
        .map(|mut r| {
            tokio::spawn(async move {
                let a = recv_bottle(&mut r).await;
                let b = recv_bottle(&mut r).await;
                (a, b, r)
            })
        })
        .collect();
    tx.send_bottle(&small).await.unwrap();
    tx.send_bottle(&big).await.unwrap();
    let mut back = Vec::new();
    for h in readers {
        let (a, b, r) = h.await.unwrap();
        assert_eq!(a, small);
        assert!(b == big, "300 kB bottle differs");
        assert_eq!(r.stats().lost, 0);
        back.push(r);
    }
    r1 = back.remove(0);
    r2 = back.remove(0);
    let _ = (&mut r1, &mut r2);
    assert!(timeout(Duration::from_millis(200), r3.recv())
        .await
        .is_err());

    assert!(McastSender::open(
        SocketAddrV4::new(Ipv4Addr::LOCALHOST, 1),
        DEFAULT_MCAST_INTERFACE
    )
    .await
    .is_err());
}

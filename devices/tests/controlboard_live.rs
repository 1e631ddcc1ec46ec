//! controlBoard_nws_yarp over real sockets with an in-process name server (netns-run).

use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::time::timeout;
use yarp_devices::controlboard::ControlBoardNws;
use yarp_devices::PolyDriver;
use yarp_net::nameserver::{NameClient, NameServer};
use yarp_proto::Property;

const T: Duration = Duration::from_secs(10);

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
async fn text_session_get_axes() {
    let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1")
        .await
        .expect("bind ns");
    let addr = ns.local_addr();
    tokio::spawn(ns.serve());
    let client = NameClient::new(addr).with_timeout(T);

    let cfg =
        Property::from_config_text("device fakeMotionControl\n[GENERAL]\njoints 4\n").unwrap();
    let pd = yarp_devices::driver::shared(PolyDriver::open(&cfg).expect("open fake"));
    let nws = ControlBoardNws::open("/fake", client.clone(), pd)
        .await
        .expect("nws");
    assert_eq!(nws.rpc_name(), "/fake/rpc:i");

    let c = client
        .query("/fake/rpc:i")
        .await
        .expect("query")
        .expect("registered");
    let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
    s.write_all(b"CONNECT foo\n").await.unwrap();
    let w = read_until(&mut s, b"\r\n").await;
    assert!(w.starts_with(b"Welcome "), "{w:?}");
    s.write_all(b"d\n[get] [axes]\n").await.unwrap();
    let got = read_until(&mut s, b"[ok]\r\n").await;
    let line = String::from_utf8_lossy(&got);
    assert!(line.starts_with("[is] [axes] 4 [tsta] 0 "), "{line}");
    nws.close().await;
}

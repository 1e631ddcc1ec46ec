//! In-process checks that the name server bounds what clients can make it do: idle
//! clients, overlong lines, oversized or malformed binary messages, shutdown.

use std::time::Duration;

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio::time::timeout;
use yarp_net::nameserver::{NameClient, NameServer, ServerConfig};

const WAIT: Duration = Duration::from_secs(5);

async fn closed(s: &mut TcpStream) -> bool {
    let mut b = [0u8; 1024];
    loop {
        match timeout(WAIT, s.read(&mut b)).await {
            Ok(Ok(0)) | Ok(Err(_)) => return true,
            Ok(Ok(_)) => continue,
            Err(_) => return false,
        }
    }
}

fn yarp_number(v: i32) -> Vec<u8> {
    let mut out = b"YA".to_vec();
    out.extend_from_slice(&v.to_le_bytes());
    out.extend_from_slice(b"RP");
    out
}

#[tokio::test]
async fn limits_and_shutdown() {
    let mut cfg = ServerConfig::new("127.0.0.1");
    cfg.idle_timeout = Duration::from_millis(300);
    cfg.max_line = 100;
    cfg.max_message = 1000;
    let server = NameServer::bind_with("127.0.0.1:0", cfg)
        .await
        .expect("bind");
    let addr = server.local_addr();
    let handle = server.shutdown_handle();
    let task = tokio::spawn(server.serve());

    // idle before the header
    let mut s = TcpStream::connect(addr).await.expect("connect");
    assert!(closed(&mut s).await);

    // idle inside a text session
    let mut s = TcpStream::connect(addr).await.expect("connect");
    s.write_all(b"CONNECT /x\n").await.expect("write");
    assert!(closed(&mut s).await);

    // overlong line
    let mut s = TcpStream::connect(addr).await.expect("connect");
    s.write_all(b"NAME_SERVER ").await.expect("write");
    let _ = s.write_all(&[b'a'; 5000]).await;
    assert!(closed(&mut s).await);

    // binary: oversized message, negative name length, bad index
    let mut s = TcpStream::connect(addr).await.expect("connect");
    let mut m = yarp_number(7777 + 131);
    m.extend_from_slice(&2i32.to_le_bytes());
    m.extend_from_slice(b"/\0");
    m.extend_from_slice(&yarp_number(10));
    m.extend_from_slice(&[1, 1]);
    m.extend_from_slice(&[0xff; 8]);
    m.extend_from_slice(&100_000i32.to_le_bytes());
    m.extend_from_slice(&0i32.to_le_bytes());
    s.write_all(&m).await.expect("write");
    assert!(closed(&mut s).await);
    let mut s = TcpStream::connect(addr).await.expect("connect");
    let mut m = yarp_number(7777 + 131);
    m.extend_from_slice(&(-5i32).to_le_bytes());
    s.write_all(&m).await.expect("write");
    assert!(closed(&mut s).await);
    let mut s = TcpStream::connect(addr).await.expect("connect");
    let mut m = yarp_number(7777 + 131);
    m.extend_from_slice(&2i32.to_le_bytes());
    m.extend_from_slice(b"/\0");
    m.extend_from_slice(b"garbage!");
    s.write_all(&m).await.expect("write");
    assert!(closed(&mut s).await);

    // still serving
    let client = NameClient::new(addr).with_timeout(WAIT);
    let root = client.query("/root").await.expect("query").expect("root");
    assert_eq!(root.port, addr.port());

    handle.shutdown();
    timeout(WAIT, task)
        .await
        .expect("serve returns after shutdown")
        .expect("join")
        .expect("serve ok");
    assert!(TcpStream::connect(addr).await.is_err());
}

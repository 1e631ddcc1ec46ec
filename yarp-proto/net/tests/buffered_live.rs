//! BufferedPort, RpcServer and the blocking facade over real loopback sockets with an
//! in-process name server. Run under ../shared/netns-run.

mod common;
use common::{name_server, T};
use std::time::Duration;
use tokio::time::timeout;
use yarp_net::buffered::{BufferedPort, RpcServer};
use yarp_net::nameserver::NameServer;
use yarp_net::port::Port;
use yarp_proto::{bottle, Bottle, Stamp, Vocab32};

async fn read(p: &BufferedPort) -> yarp_net::buffered::Message {
    timeout(T, p.read())
        .await
        .expect("message in time")
        .expect("port open")
}

/// Polls `cond` every 5 ms until it holds (bounded by `T`).
async fn until(what: &str, mut cond: impl FnMut() -> bool) {
    timeout(T, async {
        while !cond() {
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
    })
    .await
    .unwrap_or_else(|_| panic!("timed out waiting for {what}"));
}

use yarp_proto::stamp::now;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn latest_only_drops_old_messages_for_a_slow_reader() {
    let (ns, stop) = name_server().await;
    let w = BufferedPort::open("/lo/w", ns.clone())
        .await
        .expect("open w");
    let r = BufferedPort::open("/lo/r", ns.clone())
        .await
        .expect("open r");
    assert!(!r.is_strict(), "latest-only is the default");
    w.connect("/lo/r", None).await.expect("connect");
    for i in 0..100 {
        assert_eq!(w.write_strict(&bottle!["msg", i]).await, 1);
    }
    // the slow reader looks only after everything has arrived
    until("100 received", || r.received_count() == 100).await;
    assert_eq!(r.pending_count(), 1);
    let m = read(&r).await;
    assert_eq!(m.bottle, bottle!["msg", 99]);
    assert_eq!(m.from, "/lo/w");
    assert!(r.dropped_count() > 0);
    assert_eq!(r.dropped_count(), 99);
    assert!(r.try_read().is_none(), "nothing new after the latest");
    w.close().await;
    r.close().await;
    assert_eq!(
        ns.query("/lo/r").await.expect("query"),
        None,
        "unregistered"
    );
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn strict_fifo_receives_everything_in_order() {
    let (ns, stop) = name_server().await;
    let w = BufferedPort::open("/st/w", ns.clone())
        .await
        .expect("open w");
    let r = BufferedPort::open("/st/r", ns.clone())
        .await
        .expect("open r");
    r.set_strict(true);
    // a small buffer: the rest waits upstream (back-pressure), nothing is lost
    r.set_capacity(4);
    w.connect("/st/r", None).await.expect("connect");
    let writer = tokio::spawn(async move {
        for i in 0..100 {
            assert_eq!(w.write_strict(&bottle![i]).await, 1, "message {i} taken");
        }
        w
    });
    tokio::time::sleep(Duration::from_millis(300)).await;
    assert!(r.pending_count() <= 4, "bounded: {}", r.pending_count());
    for i in 0..100 {
        assert_eq!(read(&r).await.bottle, bottle![i]);
    }
    let w = timeout(T, writer)
        .await
        .expect("writer done")
        .expect("writer ok");
    assert_eq!(r.dropped_count(), 0);
    assert!(r.try_read().is_none());
    w.close().await;
    r.close().await;
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn envelopes_auto_increment() {
    let (ns, stop) = name_server().await;
    let w = BufferedPort::open("/env/w", ns.clone())
        .await
        .expect("open w");
    let r = BufferedPort::open("/env/r", ns.clone())
        .await
        .expect("open r");
    r.set_strict(true);
    w.connect("/env/r", None).await.expect("connect");
    w.set_auto_envelope(true);
    let before = now();
    for i in 0..5 {
        w.write_strict(&bottle![i]).await;
    }
    let after = now();
    let mut last_time = 0.0;
    for i in 0..5 {
        let m = read(&r).await;
        let s = m.stamp.expect("envelope attached");
        assert_eq!(s.count, i, "C++ Stamp::update counts from 0");
        assert!(s.time >= last_time && s.time >= before - 1e-3 && s.time <= after + 1e-3);
        last_time = s.time;
        assert_eq!(r.last_stamp(), Some(s), "envelope of the last read");
    }
    // an explicit envelope travels as given; the automatic count is not disturbed
    w.write_strict_stamped(&bottle!["x"], Stamp::new(77, 12.5))
        .await;
    w.write_strict(&bottle!["y"]).await;
    assert_eq!(read(&r).await.stamp, Some(Stamp::new(77, 12.5)));
    assert_eq!(read(&r).await.stamp.map(|s| s.count), Some(5));
    // without envelopes the last stamp is cleared
    w.set_auto_envelope(false);
    w.write_strict(&bottle!["z"]).await;
    assert_eq!(read(&r).await.stamp, None);
    assert_eq!(r.last_stamp(), None);
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn try_read_returns_only_new_messages() {
    let (ns, stop) = name_server().await;
    let w = BufferedPort::open("/tr/w", ns.clone())
        .await
        .expect("open w");
    let r = BufferedPort::open("/tr/r", ns.clone())
        .await
        .expect("open r");
    w.connect("/tr/r", Some("fast_tcp")).await.expect("connect");
    assert!(r.try_read().is_none());
    assert_eq!(r.pending_count(), 0);
    w.write(&bottle!["one"]);
    until("one pending", || r.pending_count() == 1).await;
    assert_eq!(r.try_read().map(|m| m.bottle), Some(bottle!["one"]));
    assert!(r.try_read().is_none(), "read already");
    assert_eq!(r.pending_count(), 0);
    // read() waits for the next one
    let waiting = async { read(&r).await.bottle };
    let (got, _) = tokio::join!(waiting, async {
        tokio::time::sleep(Duration::from_millis(50)).await;
        w.write(&bottle!["two"]);
    });
    assert_eq!(got, bottle!["two"]);
    stop.shutdown();
}

/// Single-threaded, so the sending task cannot run between the writes: each non-strict
/// write replaces the queued one.
#[tokio::test]
async fn non_strict_write_replaces_the_queued_message() {
    let (ns, stop) = name_server().await;
    let w = BufferedPort::open("/nw/w", ns.clone())
        .await
        .expect("open w");
    let r = BufferedPort::open("/nw/r", ns.clone())
        .await
        .expect("open r");
    r.set_strict(true);
    w.connect("/nw/r", None).await.expect("connect");
    assert!(w.write(&bottle![0]));
    for i in 1..10 {
        assert!(!w.write(&bottle![i]), "replaced a queued write");
    }
    assert!(w.is_writing());
    assert_eq!(w.dropped_writes(), 9);
    w.flush().await;
    assert!(!w.is_writing());
    assert_eq!(read(&r).await.bottle, bottle![9]);
    tokio::time::sleep(Duration::from_millis(50)).await;
    assert_eq!(r.received_count(), 1);
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn callback_gets_every_message() {
    let (ns, stop) = name_server().await;
    let w = BufferedPort::open("/cb/w", ns.clone())
        .await
        .expect("open w");
    let r = BufferedPort::open("/cb/r", ns.clone())
        .await
        .expect("open r");
    r.set_strict(true);
    let (tx, mut rx) = tokio::sync::mpsc::unbounded_channel();
    r.on_read(move |m| {
        let _ = tx.send(m.bottle);
    });
    w.connect("/cb/r", None).await.expect("connect");
    for i in 0..3 {
        w.write_strict(&bottle![i]).await;
    }
    for i in 0..3 {
        let b = timeout(T, rx.recv()).await.expect("in time").expect("open");
        assert_eq!(b, bottle![i]);
    }
    // once disabled, the callback gets nothing more: messages go to read()
    r.disable_callback();
    assert_eq!(w.write_strict(&bottle!["after"]).await, 1);
    assert_eq!(read(&r).await.bottle, bottle!["after"]);
    assert!(rx.try_recv().is_err(), "callback called after disable");
    // a new callback takes over again
    let (tx2, mut rx2) = tokio::sync::mpsc::unbounded_channel();
    r.on_read(move |m| {
        let _ = tx2.send(m.bottle);
    });
    w.write_strict(&bottle!["again"]).await;
    let b = timeout(T, rx2.recv())
        .await
        .expect("in time")
        .expect("open");
    assert_eq!(b, bottle!["again"]);
    stop.shutdown();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn rpc_server_round_trip() {
    let (ns, stop) = name_server().await;
    let srv = RpcServer::open("/rpc/srv", ns.clone())
        .await
        .expect("open srv");
    let served = tokio::spawn(async move {
        srv.serve(|req| {
            let mut reply = bottle![Vocab32::new("ok")];
            reply.extend(req.clone().into_items());
            reply
        })
        .await
    });
    let cli = Port::open("/rpc/cli", ns.clone()).await.expect("open cli");
    cli.connect("/rpc/srv", None).await.expect("connect");
    let reply = timeout(T, cli.rpc(&bottle!["get", 3]))
        .await
        .expect("in time")
        .expect("reply");
    assert_eq!(reply.to_string(), "[ok] get 3");
    // a BufferedPort client, over text_ack
    let bcli = BufferedPort::open("/rpc/bcli", ns.clone())
        .await
        .expect("open bcli");
    bcli.connect("/rpc/srv", Some("text_ack"))
        .await
        .expect("connect");
    let reply = timeout(T, bcli.rpc(&bottle!["x"]))
        .await
        .expect("in time")
        .expect("reply");
    assert_eq!(reply.to_string(), "[ok] x");
    served.abort();

    // answering by hand through the reply handle
    let srv2 = RpcServer::open("/rpc/srv2", ns.clone())
        .await
        .expect("open srv2");
    cli.connect("/rpc/srv2", None).await.expect("connect");
    cli.disconnect("/rpc/srv");
    let call = tokio::spawn(async move {
        let r = timeout(T, cli.rpc(&bottle![1, 2])).await;
        (cli, r)
    });
    let mut req = timeout(T, srv2.read())
        .await
        .expect("request in time")
        .expect("open");
    assert!(req.wants_reply());
    assert_eq!(req.from, "/rpc/cli");
    let replier = req.take_replier().expect("replier");
    replier.send(bottle!["sum", 3]);
    let (cli, r) = timeout(T, call).await.expect("done").expect("task");
    assert_eq!(r.expect("in time").expect("reply"), bottle!["sum", 3]);
    cli.close().await;
    srv2.close().await;
    stop.shutdown();
}

/// The blocking facade from a plain thread: no async in the test body.
#[test]
fn blocking_facade_open_connect_write_read_rpc() {
    use yarp_net::blocking;

    // the name server runs on its own runtime in its own thread
    let (addr_tx, addr_rx) = std::sync::mpsc::channel();
    let server = std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .expect("runtime");
        rt.block_on(async {
            let ns = NameServer::bind("127.0.0.1:0", "127.0.0.1")
                .await
                .expect("bind ns");
            addr_tx
                .send((ns.local_addr(), ns.shutdown_handle()))
                .expect("send addr");
            let _ = ns.serve().await;
        });
    });
    let (addr, stop) = addr_rx.recv_timeout(T).expect("name server up");

    let net = blocking::Network::with_name_server(addr).expect("network");
    let w = blocking::Port::open(&net, "/bl/w").expect("open w");
    let r = blocking::BufferedPort::open(&net, "/bl/r").expect("open r");
    assert!(net.exists("/bl/r").expect("exists"));
    assert!(!net.exists("/bl/nobody").expect("exists"));
    let (ok, msg) = net.connect("/bl/w", "/bl/r", None).expect("connect");
    assert!(ok, "{msg}");
    assert!(net.is_connected("/bl/w", "/bl/r").expect("is_connected"));
    assert_eq!(w.write(&bottle!["hello", 1]), 1);
    let m = r.read_timeout(T).expect("message");
    assert_eq!(m.bottle, bottle!["hello", 1]);
    assert!(r.read_timeout(Duration::from_millis(50)).is_none());
    let (ok, msg) = net.disconnect("/bl/w", "/bl/r").expect("disconnect");
    assert!(ok, "{msg}");

    // rpc: a blocking server thread answers a blocking client
    let srv = blocking::RpcServer::open(&net, "/bl/srv").expect("open srv");
    let cli = blocking::Port::open(&net, "/bl/cli").expect("open cli");
    cli.connect("/bl/srv", None).expect("connect");
    std::thread::scope(|s| {
        s.spawn(|| {
            let mut req = srv.read_timeout(T).expect("request");
            let mut reply = Bottle::new();
            reply.add_vocab("ok");
            reply.extend(req.bottle.clone().into_items());
            req.reply(reply);
        });
        let reply = cli.rpc_timeout(&bottle!["ping"], T).expect("reply in time");
        assert_eq!(reply.to_string(), "[ok] ping");
    });

    // a buffered writer with the blocking calls
    let bw = blocking::BufferedPort::open(&net, "/bl/bw").expect("open bw");
    bw.set_auto_envelope(true);
    bw.connect("/bl/r", Some("fast_tcp")).expect("connect");
    assert_eq!(bw.write_strict(&bottle![42]), 1);
    let m = r.read_timeout(T).expect("message");
    assert_eq!((m.bottle, m.stamp.map(|s| s.count)), (bottle![42], Some(0)));
    assert_eq!(r.last_stamp().map(|s| s.count), Some(0));

    // explicit close unregisters; drop closes the rest without panicking
    w.close();
    assert!(!net.exists("/bl/w").expect("exists"));
    drop(r);
    drop(bw);
    drop(cli);
    srv.close();
    let ns = net.name_client().clone();
    let left = net
        .block_on(async move { ns.list(None).await })
        .expect("list");
    assert!(
        left.iter().all(|c| !c.name.starts_with("/bl/")),
        "dropped ports unregistered: {left:?}"
    );
    stop.shutdown();
    server.join().expect("name server thread");
}

/// Dropping blocking ports from inside an async context must not panic.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn blocking_ports_drop_inside_a_runtime() {
    let (ns, stop) = name_server().await;
    let net = yarp_net::blocking::Network::with_client(ns.clone()).expect("network");
    // blocking calls made from async code run on a helper thread instead of panicking
    let p = yarp_net::blocking::Port::open(&net, "/drop/p").expect("open");
    let b = yarp_net::blocking::BufferedPort::open(&net, "/drop/b").expect("open");
    drop(p);
    drop(b);
    // the closes run in the background; the names go away
    timeout(T, async {
        while ns.query("/drop/p").await.expect("query").is_some()
            || ns.query("/drop/b").await.expect("query").is_some()
        {
            tokio::time::sleep(Duration::from_millis(10)).await;
        }
    })
    .await
    .expect("unregistered after drop");
    stop.shutdown();
}

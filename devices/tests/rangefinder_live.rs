//! rangefinder2D_nws_yarp over fakeLaser on real sockets, with an in-process name server
//! (run under netns-run): our reader gets `LaserScan2D` scans with envelopes on `<name>`,
//! our RPC client and C++ `yarp rpc` / `yarp read` (3.12.3 from
//! tests/peers/install-cpp-peers.sh icub, when installed; in CI required)
//! get the `IRangefinder2DMsgs` answers and the stream. Every wait is bounded.

use yarp_devices::rangefinder::protocol::LaserScan2D;
use yarp_devices::thrift::parse_reply;
use yarp_devices::{runtime, PolyDriver};
use yarp_interop_tests::{name_client, T};
use yarp_net::buffered::BufferedPort;
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Property, Value};

fn run<F>(fut: F) -> F::Output
where
    F: std::future::Future + Send + 'static,
    F::Output: Send + 'static,
{
    runtime::block_on(async move { tokio::time::timeout(T, fut).await.expect("timed out") })
        .expect("the device runtime")
}

/// The wrapper over a fakeLaser seeing 2.5 m everywhere, 0.5 degree steps.
fn laser(name: &str) -> PolyDriver {
    name_client();
    let cfg = format!(
        "device rangefinder2D_nws_yarp\nsubdevice fakeLaser\nname {name}\nperiod 0.01\n\
         test use_constant\n[SENSOR]\nmin_distance 0.1\nmax_distance 30\nresolution 0.5\n\
         [CONSTANT_MODE]\nconst_distance 2.5\n"
    );
    PolyDriver::open(&Property::from_config_text(&cfg).unwrap())
        .unwrap_or_else(|e| panic!("open {cfg:?}: {e}"))
}

#[test]
fn our_reader_gets_scans_and_rpc_answers_ranges() {
    let mut server = laser("/robot/laser:o");
    let ns = name_client();
    let (scans, replies) = run(async move {
        let reader = BufferedPort::open("/laser_reader", ns.clone())
            .await
            .unwrap();
        let (ok, msg) = yarp_net::network::connect(&ns, "/robot/laser:o", "/laser_reader", None)
            .await
            .unwrap();
        assert!(ok, "{msg}");
        let mut scans = Vec::new();
        while scans.len() < 3 {
            let m = reader.read().await.expect("a scan");
            scans.push((
                LaserScan2D::from_bottle(&m.bottle).unwrap(),
                m.stamp.unwrap(),
            ));
        }
        reader.close().await;
        let c = ns
            .query("/robot/laser:o/rpc:i")
            .await
            .unwrap()
            .expect("rpc port");
        let mut rpc = RpcClient::connect(&c, "/anon_rpc", Carrier::Tcp)
            .await
            .unwrap();
        let mut replies = Vec::new();
        for text in [
            "getDistanceRange RPC",
            "getScanLimits RPC",
            "getHorizontalResolution RPC",
            "getScanRate RPC",
            "getDeviceStatus RPC",
            "getDeviceInfo RPC",
            "setScanRate RPC 50.0",
            "getScanRate RPC",
            "getDistanceRange",
            "nonsense 1 2",
        ] {
            replies.push(rpc.call(&Bottle::from_text(text)).await.unwrap());
        }
        rpc.close().await;
        (scans, replies)
    });
    for (scan, _) in &scans {
        assert_eq!(scan.scans.len(), 720);
        assert!(scan.scans.iter().all(|&d| d == 2.5));
        assert_eq!((scan.angle_min, scan.angle_max), (0.0, 360.0));
        assert_eq!((scan.range_min, scan.range_max), (0.1, 30.0));
        assert_eq!(scan.status, 1, "DEVICE_OK_IN_USE");
    }
    assert!(scans[1].1.count > scans[0].1.count && scans[2].1.time >= scans[0].1.time);
    let nums = |b: &Bottle| b.iter().filter_map(Value::as_f64).collect::<Vec<_>>();
    assert_eq!(nums(&replies[0]), [0.0, 0.1, 30.0]);
    assert_eq!(nums(&replies[1]), [0.0, 0.0, 360.0]);
    assert_eq!(nums(&replies[2]), [0.0, 0.5]);
    assert_eq!(nums(&replies[3]), [0.0, 100.0]);
    let (code, status) = parse_reply(&replies[4]).unwrap();
    assert_eq!(
        (code, status[0].as_vocab().map(|v| v.0)),
        (yarp_devices::thrift::ReturnValue::Ok, Some(1))
    );
    assert_eq!(
        replies[5].get(1).and_then(Value::as_str),
        Some("Fake Laser device for test/debugging")
    );
    // 3.12's bare `ok` ([INT32] 0) reads as an empty compact list, as in C++
    assert!(replies[6].is_empty(), "{}", replies[6]);
    assert_eq!(nums(&replies[7]), [0.0, 50.0]);
    assert_eq!(replies[8].to_string(), "[fail]");
    assert_eq!(replies[9].to_string(), "[fail]");
    server.close().unwrap();
    let ns = name_client();
    assert!(run(async move { ns.query("/robot/laser:o").await.unwrap() }).is_none());
}

#[test]
fn cpp_yarp_read_and_rpc_talk_to_our_wrapper() {
    let Some(yarp) =
        yarp_interop_tests::cpp_program("cpp_yarp_read_and_rpc_talk_to_our_wrapper", "yarp")
    else {
        return;
    };
    let mut server = laser("/cpplaser:o");
    let out = yarp_interop_tests::cpp_rpc_output(
        &yarp,
        "/cpplaser:o/rpc:i",
        "getDistanceRange RPC\ngetScanRate RPC\n",
    );
    // C++ 3.12.3 prints doubles with all their digits (0.100000000000000005551)
    let responses: Vec<Vec<f64>> = out
        .lines()
        .filter_map(|l| l.strip_prefix("Response: "))
        .map(|l| {
            Bottle::from_text(l)
                .iter()
                .filter_map(Value::as_f64)
                .collect()
        })
        .collect();
    assert_eq!(responses, [vec![0.0, 0.1, 30.0], vec![0.0, 100.0]], "{out}");

    let line = yarp_interop_tests::cpp_read_until(&yarp, "/cpp_laser_rd", "/cpplaser:o", |l| {
        l.contains("2.5").then(|| l.to_string())
    });
    let scan = LaserScan2D::from_bottle(&Bottle::from_text(&line)).unwrap();
    assert_eq!(scan.scans.len(), 720);
    assert!(scan.scans.iter().all(|&d| d == 2.5));
    assert_eq!((scan.range_max, scan.status), (30.0, 1));
    eprintln!("interop: C++ yarp rpc and yarp read -> rangefinder2D_nws_yarp OK");
    server.close().unwrap();
}

#[test]
fn nwc_reads_scans_and_forwards_settings() {
    let mut server = laser("/nwc_laser:o");
    let mut client = PolyDriver::open(
        &Property::from_config_text(
            "device rangefinder2D_nwc_yarp\nlocal /nwc_laser_client\nremote /nwc_laser:o\n",
        )
        .unwrap(),
    )
    .expect("open the client");
    let rf = client.device().as_rangefinder_2d().unwrap();
    let (scans, t) = yarp_interop_tests::wait_for("a scan", || {
        let (s, t) = rf.get_raw_data().ok()?;
        (!s.is_empty()).then_some((s, t))
    });
    assert_eq!(scans.len(), 720);
    assert!(scans.iter().all(|&d| d == 2.5) && t > 1.6e9);
    assert_eq!(rf.get_device_status().unwrap() as i32, 1);
    assert_eq!(rf.get_distance_range().unwrap(), (0.1, 30.0));
    assert_eq!(rf.get_scan_limits().unwrap(), (0.0, 360.0));
    assert_eq!(rf.get_horizontal_resolution().unwrap(), 0.5);
    rf.set_scan_rate(40.0).unwrap();
    assert_eq!(rf.get_scan_rate().unwrap(), 40.0);
    assert_eq!(
        rf.get_device_info().unwrap(),
        "Fake Laser device for test/debugging"
    );
    client.close().unwrap();
    server.close().unwrap();
    // a client of nothing fails to open, clearly
    let err = PolyDriver::open(
        &Property::from_config_text(
            "device rangefinder2D_nwc_yarp\nlocal /lonely\nremote /none:o\n",
        )
        .unwrap(),
    )
    .err()
    .expect("no server");
    assert!(err.to_string().contains("/none:o"), "{err}");
}

//! battery_nws_yarp over fakeBattery on real sockets, with an in-process name server (run
//! under netns-run): our reader gets `BatteryData` with envelopes on `<name>/data:o`, our
//! RPC client and C++ `yarp rpc` / `yarp read` (3.12.3 from tests/peers/install-cpp-peers.sh
//! icub, when installed; in CI required) get
//! the `IBatteryMsgs` answer and the stream; our `battery_nwc_yarp` reads it all back.
//! Every wait is bounded.

use yarp_devices::battery::protocol::BatteryData;
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

/// The wrapper over a fakeBattery (30 V, 3 A out, 20 C, 50 % draining), 50 ms period.
fn battery(name: &str) -> PolyDriver {
    name_client();
    let cfg = format!("device battery_nws_yarp\nsubdevice fakeBattery\nname {name}\nperiod 0.05\n");
    PolyDriver::open(&Property::from_config_text(&cfg).unwrap())
        .unwrap_or_else(|e| panic!("open {cfg:?}: {e}"))
}

#[test]
fn our_reader_gets_battery_data_and_rpc_answers_the_info() {
    let mut server = battery("/robot/battery");
    let ns = name_client();
    let (data, replies) = run(async move {
        let reader = BufferedPort::open("/battery_reader", ns.clone())
            .await
            .unwrap();
        let (ok, msg) =
            yarp_net::network::connect(&ns, "/robot/battery/data:o", "/battery_reader", None)
                .await
                .unwrap();
        assert!(ok, "{msg}");
        let mut data = Vec::new();
        while data.len() < 3 {
            let m = reader.read().await.expect("battery data");
            data.push((
                BatteryData::from_bottle(&m.bottle).unwrap(),
                m.stamp.unwrap(),
            ));
        }
        reader.close().await;
        let c = ns
            .query("/robot/battery/rpc:i")
            .await
            .unwrap()
            .expect("rpc port");
        let mut rpc = RpcClient::connect(&c, "/anon_rpc", Carrier::Tcp)
            .await
            .unwrap();
        let mut replies = Vec::new();
        for text in ["getBatteryInfoRPC", "getBatteryInfo RPC", "nonsense"] {
            replies.push(rpc.call(&Bottle::from_text(text)).await.unwrap());
        }
        rpc.close().await;
        (data, replies)
    });
    for (d, _) in &data {
        assert_eq!((d.voltage, d.current, d.temperature), (30.0, 3.0, 20.0));
        assert!(d.charge > 49.0 && d.charge <= 50.0, "{d:?}");
        assert_eq!(d.status, 2, "BATTERY_OK_IN_USE while current flows out");
    }
    assert!(data[2].1.count > data[0].1.count && data[2].1.time >= data[0].1.time);
    assert_eq!(replies[0].get(0).and_then(Value::as_i32), Some(0));
    assert_eq!(
        replies[0].get(1).and_then(Value::as_str),
        Some("Fake battery system v2.0")
    );
    assert_eq!(replies[1].to_string(), "[fail]");
    assert_eq!(replies[2].to_string(), "[fail]");
    server.close().unwrap();
    let ns = name_client();
    assert!(run(async move { ns.query("/robot/battery/data:o").await.unwrap() }).is_none());
}

#[test]
fn a_shutdown_we_would_not_perform_is_refused_at_open() {
    name_client();
    let cfg = "device battery_nws_yarp\nsubdevice fakeBattery\nname /refused/battery\nenable_shutdown true\n";
    let e = PolyDriver::open(&Property::from_config_text(cfg).unwrap())
        .err()
        .expect("enable_shutdown refused");
    assert!(e.to_string().contains("enable_shutdown"), "{e}");
}

#[test]
fn cpp_yarp_read_and_rpc_talk_to_our_battery_wrapper() {
    let Some(yarp) = yarp_interop_tests::cpp_program(
        "cpp_yarp_read_and_rpc_talk_to_our_battery_wrapper",
        "yarp",
    ) else {
        return;
    };
    let mut server = battery("/cppbattery");
    let out = yarp_interop_tests::cpp_rpc_output(&yarp, "/cppbattery/rpc:i", "getBatteryInfoRPC\n");
    let response = out
        .lines()
        .find_map(|l| l.strip_prefix("Response: "))
        .map(Bottle::from_text)
        .unwrap_or_else(|| panic!("no response: {out}"));
    assert_eq!(response.get(0).and_then(Value::as_i32), Some(0), "{out}");
    assert_eq!(
        response.get(1).and_then(Value::as_str),
        Some("Fake battery system v2.0"),
        "{out}"
    );

    let d =
        yarp_interop_tests::cpp_read_until(&yarp, "/cpp_battery_rd", "/cppbattery/data:o", |l| {
            BatteryData::from_bottle(&Bottle::from_text(l)).ok()
        });
    assert_eq!(
        (d.voltage, d.current, d.temperature, d.status),
        (30.0, 3.0, 20.0, 2)
    );
    eprintln!("interop: C++ yarp rpc and yarp read -> battery_nws_yarp OK");
    server.close().unwrap();
}

#[test]
fn nwc_reads_the_stream_and_asks_the_info() {
    let mut server = battery("/nwc/battery");
    let mut client = PolyDriver::open(
        &Property::from_config_text(
            "device battery_nwc_yarp\nlocal /nwc/battery_client\nremote /nwc/battery\n",
        )
        .unwrap(),
    )
    .expect("open the client");
    let b = client.device().as_battery().unwrap();
    // before the first message: C++'s thrift defaults (zeros, BATTERY_GENERAL_ERROR)
    let v = yarp_interop_tests::wait_for("battery data", || {
        let v = b.get_battery_voltage().ok()?;
        (v != 0.0).then_some(v)
    });
    assert_eq!(v, 30.0);
    assert_eq!(b.get_battery_current().unwrap(), 3.0);
    assert_eq!(b.get_battery_temperature().unwrap(), 20.0);
    let charge = b.get_battery_charge().unwrap();
    assert!(charge > 49.0 && charge <= 50.0, "{charge}");
    assert_eq!(
        b.get_battery_status().unwrap(),
        yarp_devices::battery::BatteryStatus::OkInUse
    );
    assert_eq!(b.get_battery_info().unwrap(), "Fake battery system v2.0");
    client.close().unwrap();
    server.close().unwrap();
    // a client of nothing fails to open, naming what it could not reach
    let err = PolyDriver::open(
        &Property::from_config_text(
            "device battery_nwc_yarp\nlocal /lonely_battery\nremote /no/battery\n",
        )
        .unwrap(),
    )
    .err()
    .expect("no server");
    assert!(err.to_string().contains("/no/battery/data:o"), "{err}");
}

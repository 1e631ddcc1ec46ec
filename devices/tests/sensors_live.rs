//! multipleanalogsensorsserver <-> multipleanalogsensorsclient over real sockets, with
//! an in-process name server (run under netns-run): fakeIMU and fakeFTs served and read
//! back; the stream checked on the wire against the C++ recording's layout; bad RPC
//! requests answered `[fail]` without harm. Every wait is bounded.

use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use yarp_devices::sensors::{MasStatus, SensorStreamingData};
use yarp_devices::{DeviceError, PolyDriver};
use yarp_interop_tests::{name_client, wait_for, T};
use yarp_net::rpc::RpcClient;
use yarp_proto::nameserver::RegisterRequest;
use yarp_proto::wire::{Carrier, PortCommand};
use yarp_proto::{Bottle, Property, Stamp, Vocab32};

fn run<F>(fut: F) -> F::Output
where
    F: std::future::Future + Send + 'static,
    F::Output: Send + 'static,
{
    yarp_devices::runtime::block_on(async move {
        tokio::time::timeout(T, fut).await.expect("timed out")
    })
    .expect("the device runtime")
}

fn open(text: &str) -> PolyDriver {
    name_client();
    PolyDriver::open(&Property::from_config_text(text).unwrap())
        .unwrap_or_else(|e| panic!("open {text:?}: {e}"))
}

#[test]
fn imu_client_reads_what_the_server_streams() {
    let mut server = open(
        "device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /imu1\nperiod 10\nsensorName head_imu\nframeName head_frame\n",
    );
    let mut client =
        open("device multipleanalogsensorsclient\nremote /imu1\nlocal /imu1cl\ntimeout 1.0\n");
    let dev = client.device();
    let gyro = dev.as_three_axis_gyroscopes().unwrap();
    assert_eq!(gyro.get_nr_of_three_axis_gyroscopes(), 1);
    assert_eq!(gyro.get_three_axis_gyroscope_name(0).unwrap(), "head_imu");
    assert_eq!(
        gyro.get_three_axis_gyroscope_frame_name(0).unwrap(),
        "head_frame"
    );
    assert!(gyro.get_three_axis_gyroscope_name(1).is_err());
    let m = wait_for("a first measurement", || {
        (gyro.get_three_axis_gyroscope_status(0) == MasStatus::Ok)
            .then(|| gyro.get_three_axis_gyroscope_measure(0).unwrap())
    });
    assert_eq!(m.values.len(), 3);
    assert!(m
        .values
        .iter()
        .all(|v| *v == m.values[0] && (0.0..360.0).contains(v)));
    // the counter moves (one step every 10 ms)
    let later = wait_for("a newer measurement", || {
        let n = gyro.get_three_axis_gyroscope_measure(0).ok()?;
        (n.timestamp > m.timestamp).then_some(n)
    });
    assert_ne!(later.values[0], m.values[0]);

    let acc = client
        .device()
        .as_three_axis_linear_accelerometers()
        .unwrap()
        .get_three_axis_linear_accelerometer_measure(0)
        .unwrap();
    let g = acc.values.iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!((g - 9.81).abs() < 1e-9, "{acc:?}");
    assert!(
        client
            .device()
            .as_six_axis_force_torque_sensors()
            .unwrap()
            .get_nr_of_six_axis_force_torque_sensors()
            == 0
    );

    client.close().unwrap();
    server.close().unwrap();
    // closing unregisters the ports
    let ns = name_client();
    assert!(run(async move { ns.query("/imu1/measures:o").await.unwrap() }).is_none());
}

#[test]
fn force_torque_client_reads_fake_fts() {
    let mut server = open(
        "device multipleanalogsensorsserver\nsubdevice fakeFTs\nname /ft\nperiod 10\nsensorNames (l_arm_ft r_arm_ft)\n",
    );
    let mut client =
        open("device multipleanalogsensorsclient\nremote /ft\nlocal /ftcl\ntimeout 1.0\n");
    let ft = client.device().as_six_axis_force_torque_sensors().unwrap();
    assert_eq!(ft.get_nr_of_six_axis_force_torque_sensors(), 2);
    assert_eq!(
        ft.get_six_axis_force_torque_sensor_name(1).unwrap(),
        "r_arm_ft"
    );
    assert_eq!(
        ft.get_six_axis_force_torque_sensor_frame_name(0).unwrap(),
        "l_arm_ft"
    );
    let w = wait_for("an F/T measurement", || {
        ft.get_six_axis_force_torque_sensor_measure(1).ok()
    });
    assert_eq!(w.values.len(), 6);
    let temp = client.device().as_temperature_sensors().unwrap();
    assert_eq!(temp.get_nr_of_temperature_sensors(), 2);
    assert_eq!(
        temp.get_temperature_sensor_measure(0).unwrap().values.len(),
        1
    );
    client.close().unwrap();
    server.close().unwrap();
}

#[test]
fn client_without_server_fails_naming_the_device() {
    name_client();
    let err = PolyDriver::open(
        &Property::from_config_text(
            "device multipleanalogsensorsclient\nremote /nobody\nlocal /lonely\n",
        )
        .unwrap(),
    )
    .err()
    .expect("no server, no client");
    let msg = err.to_string();
    assert!(msg.contains("multipleanalogsensorsclient"), "{msg}");
    // the local ports were given back
    let ns = name_client();
    assert!(run(async move { ns.query("/lonely/rpc:i").await.unwrap() }).is_none());
}

#[test]
fn missing_parameters_are_named() {
    name_client();
    let err = PolyDriver::open(
        &Property::from_config_text("device multipleanalogsensorsserver\nname /x\n").unwrap(),
    )
    .err()
    .unwrap();
    assert!(
        matches!(&err, DeviceError::MissingParam { param, .. } if param == "period"),
        "{err}"
    );
    let err = PolyDriver::open(&Property::from_config_text("device fakeFTs\nperiod 10\n").unwrap())
        .err()
        .unwrap();
    assert!(err.to_string().contains("sensorNames"), "{err}");
}

#[test]
fn bad_rpc_gets_fail_and_the_server_keeps_serving() {
    let mut server =
        open("device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /imu2\nperiod 20\n");
    let ns = name_client();
    let replies = run(async move {
        let c = ns.query("/imu2/rpc:o").await.unwrap().expect("registered");
        let mut rpc = RpcClient::connect(&c, "/anon_rpc", Carrier::Tcp)
            .await
            .unwrap();
        let mut out = Vec::new();
        for text in [
            "[zzz]",
            "getMetadata 1 2",
            "42",
            "",
            "(getMetadata)",
            "help getMetadata",
            "getMetadata",
        ] {
            out.push(rpc.call(&Bottle::from_text(text)).await.unwrap());
        }
        rpc.close().await;
        out
    });
    let fail = Bottle::new().with(Vocab32::new("fail"));
    for r in &replies[..5] {
        assert_eq!(r, &fail);
    }
    assert_eq!(
        replies[5].to_string(),
        "[many] (\"SensorRPCData MultipleAnalogSensorsMetadata::getMetadata()\" \"Read the sensor metadata necessary to configure the MultipleAnalogSensorsClient device.\")"
    );
    assert_eq!(replies[6].len(), 12);
    server.close().unwrap();
}

/// Reads one message (index + blocks) from a raw tcp connection; returns its body.
async fn read_message(s: &mut TcpStream) -> Vec<u8> {
    let mut head = [0u8; 18];
    s.read_exact(&mut head).await.unwrap();
    assert_eq!(&head[..8], b"YA\x0a\0\0\0RP");
    let n_blocks = head[8] as usize;
    let mut lens = vec![0u8; 4 * (n_blocks + 1)];
    s.read_exact(&mut lens).await.unwrap();
    let total: usize = lens[..4 * n_blocks]
        .chunks(4)
        .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]) as usize)
        .sum();
    let mut body = vec![0u8; total];
    s.read_exact(&mut body).await.unwrap();
    body
}

#[test]
fn stream_on_the_wire_has_the_recorded_layout() {
    let mut server =
        open("device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /imu\nperiod 20\n");
    let ns = name_client();
    let bodies = run(async move {
        let l = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let port = l.local_addr().unwrap().port();
        let req = RegisterRequest::explicit("/cap/imu", "tcp", "127.0.0.1", port);
        ns.register_port(&req, &["127.0.0.1"], 1).await.unwrap();
        let ns2 = ns.clone();
        let connect = tokio::spawn(async move {
            yarp_net::network::connect(&ns2, "/imu/measures:o", "/cap/imu", None)
                .await
                .unwrap()
        });
        let (mut s, _) = l.accept().await.unwrap();
        // the recorded connection start: tcp header, then the sender's name
        let mut start = vec![0u8; 28];
        s.read_exact(&mut start).await.unwrap();
        assert_eq!(
            hex::encode(&start),
            "5941e41e00005250100000002f696d752f6d656173757265733a6f00"
        );
        let mut reply = b"YA".to_vec();
        reply.extend_from_slice(&i32::from(port).to_le_bytes());
        reply.extend_from_slice(b"RP");
        s.write_all(&reply).await.unwrap();
        assert!(connect.await.unwrap().0);
        let mut bodies = Vec::new();
        for _ in 0..3 {
            bodies.push(read_message(&mut s).await);
            s.write_all(b"YA\0\0\0\0RP").await.unwrap();
        }
        bodies
    });
    let mut counts = Vec::new();
    for body in bodies {
        let (pc, used) = PortCommand::decode_binary(&body).unwrap();
        assert_eq!(pc.key(), b'D');
        let env = std::str::from_utf8(pc.envelope_text().expect("an envelope")).unwrap();
        let stamp = Stamp::from_text(env).unwrap();
        counts.push(stamp.count);
        let payload = &body[used..];
        let data = SensorStreamingData::from_bottle(&Bottle::decode(payload).unwrap()).unwrap();
        // same layout as the recording: 4 families with one sensor, 8 empty ones
        let sizes: Vec<usize> = data.families.iter().map(Vec::len).collect();
        assert_eq!(sizes, [1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(data.to_bottle().encode(), payload);
        assert!((stamp.time - data.families[0][0].timestamp).abs() < 1.0);
    }
    assert!(counts.windows(2).all(|w| w[1] > w[0]), "{counts:?}");
    server.close().unwrap();
}

/// Opens a reader port connected from `from` and returns its first `n` messages.
fn read_from(from: &str, reader: &str, n: usize) -> Vec<(Option<Stamp>, Bottle)> {
    let ns = name_client();
    let (from, reader) = (from.to_string(), reader.to_string());
    run(async move {
        let port = yarp_net::port::Port::open(&reader, ns.clone())
            .await
            .unwrap();
        let (ok, msg) = yarp_net::network::connect(&ns, &from, &reader, None)
            .await
            .unwrap();
        assert!(ok, "{msg}");
        let mut out = Vec::new();
        for _ in 0..n {
            let m = port.read().await.expect("a message");
            out.push((m.stamp, m.bottle().unwrap()));
        }
        port.close().await;
        out
    })
}

fn rpc_calls(port: &str, texts: &[&str]) -> Vec<String> {
    let ns = name_client();
    let port = port.to_string();
    let texts: Vec<String> = texts.iter().map(|t| t.to_string()).collect();
    run(async move {
        let c = ns.query(&port).await.unwrap().expect("registered");
        let mut rpc = RpcClient::connect(&c, "/anon_rpc", Carrier::Tcp)
            .await
            .unwrap();
        let mut out = Vec::new();
        for t in texts {
            out.push(rpc.call(&Bottle::from_text(&t)).await.unwrap().to_string());
        }
        rpc.close().await;
        out
    })
}

#[test]
fn analog_server_streams_and_calibrates() {
    let mut server = open(
        "device analogServer\nsubdevice fakeAnalogSensor\nname /icub/left_hand/analog:o\nperiod 10\nchannelsNum 4\n",
    );
    let msgs = read_from("/icub/left_hand/analog:o", "/an/reader", 3);
    let mut counts = Vec::new();
    for (stamp, b) in &msgs {
        let stamp = stamp.expect("an envelope");
        counts.push(stamp.count);
        assert_eq!(b.len(), 4);
        // a yarp::sig::Vector: a compact float64 list
        assert_eq!(b.encode()[..4], (0x10a_i32).to_le_bytes());
        let t = b.get(0).unwrap().as_f64().unwrap();
        assert!((t - stamp.time).abs() < 1.0, "channel 0 reads the time");
    }
    assert!(counts.windows(2).all(|w| w[1] > w[0]), "{counts:?}");
    let replies = rpc_calls(
        "/icub/left_hand/analog:o/rpc:i",
        &[
            "[iana] [cal]",
            "[iana] [calc] 1 2.5",
            "[iana] [cal] 1 2 3",
            "[zzz]",
            "",
            "[iana] [calc] x",
        ],
    );
    assert_eq!(replies, ["0", "0", "0", "[fail]", "[fail]", "1"]);
    server.close().unwrap();
}

#[test]
fn analog_server_splits_the_vector_over_ports() {
    let mut server = open(
        "device analogServer\nsubdevice fakeAnalogSensor\nname /skin\nperiod 10\nchannelsNum 4\nports (hand arm)\nchannels 4\nhand 0 0 0 0\narm 1 3 0 2\n",
    );
    let hand = read_from("/skin/hand", "/skin/r1", 1);
    let arm = read_from("/skin/arm", "/skin/r2", 1);
    assert_eq!(hand[0].1.len(), 1);
    assert_eq!(arm[0].1.to_string(), "0.0 0.0 0.0");
    server.close().unwrap();

    name_client();
    let err = PolyDriver::open(
        &Property::from_config_text(
            "device analogServer\nname /skin2\nperiod 10\nports (hand)\nchannels 3\nhand 0 1 0 1\n",
        )
        .unwrap(),
    )
    .err()
    .unwrap();
    assert!(err.to_string().contains("channels"), "{err}");
    let err = PolyDriver::open(
        &Property::from_config_text("device analogServer\ndeviceId left_hand\nperiod 10\n")
            .unwrap(),
    )
    .err()
    .unwrap();
    assert!(err.to_string().contains("deviceId"), "{err}");
}

/// The iCub legs layout: two strain devices joined by the remapper, served by one
/// multipleanalogsensorsserver (`left_leg-FT_remapper.xml` + `left_leg_FT_wrapper.xml`).
#[test]
fn remapper_joins_devices_in_the_configured_order() {
    use yarp_devices::shared;
    let leg = shared(open("device fakeFTs\nperiod 10\nsensorNames (l_leg_ft)\n"));
    let foot = shared(open(
        "device fakeFTs\nperiod 10\nsensorNames (l_foot_ft l_spare_ft)\n",
    ));
    let remapper = shared(open(
        "device multipleanalogsensorsremapper\nSixAxisForceTorqueSensorsNames (l_foot_ft l_leg_ft)\n",
    ));
    remapper
        .lock()
        .device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[
            ("left_leg_strain".into(), leg.clone()),
            ("left_foot_strain".into(), foot.clone()),
        ])
        .unwrap();
    let mut server =
        open("device multipleanalogsensorsserver\nname /icub/left_leg/FT\nperiod 10\n");
    server
        .device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("FirstStrain".into(), remapper.clone())])
        .unwrap();
    let mut client = open(
        "device multipleanalogsensorsclient\nremote /icub/left_leg/FT\nlocal /legcl\ntimeout 1.0\n",
    );
    let ft = client.device().as_six_axis_force_torque_sensors().unwrap();
    assert_eq!(ft.get_nr_of_six_axis_force_torque_sensors(), 2);
    assert_eq!(
        ft.get_six_axis_force_torque_sensor_name(0).unwrap(),
        "l_foot_ft"
    );
    assert_eq!(
        ft.get_six_axis_force_torque_sensor_name(1).unwrap(),
        "l_leg_ft"
    );
    let w = wait_for("a remapped measurement", || {
        ft.get_six_axis_force_torque_sensor_measure(1).ok()
    });
    assert_eq!(w.values.len(), 6);
    // temperature is not remapped: not exposed
    assert_eq!(
        client
            .device()
            .as_temperature_sensors()
            .unwrap()
            .get_nr_of_temperature_sensors(),
        0
    );
    client.close().unwrap();
    server.close().unwrap();

    // a name no attached device has is refused, naming the parameter
    let mut bad =
        open("device multipleanalogsensorsremapper\nSixAxisForceTorqueSensorsNames (r_leg_ft)\n");
    let err = bad
        .device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("x".into(), leg)])
        .unwrap_err();
    assert!(
        err.to_string().contains("SixAxisForceTorqueSensorsNames"),
        "{err}"
    );
}

#[test]
fn analog_client_reads_and_calibrates_through_the_server() {
    use yarp_devices::sensors::AnalogStatus;
    let mut server = open(
        "device analogServer\nsubdevice fakeAnalogSensor\nname /icub/right_hand/analog:o\nperiod 10\nchannelsNum 3\n",
    );
    // the default carrier of the data connection is udp, as in C++
    for (local, carrier) in [("/rh/analog:i", ""), ("/rh2/analog:i", "carrier tcp\n")] {
        let mut client = open(&format!(
            "device analogsensorclient\nremote /icub/right_hand/analog:o\nlocal {local}\n{carrier}"
        ));
        let sensor = client.device().as_analog_sensor().unwrap();
        let mut v = Vec::new();
        wait_for("a first vector", || {
            (sensor.read(&mut v) == AnalogStatus::Ok).then_some(())
        });
        assert_eq!(v.len(), 3);
        assert_eq!(sensor.get_channels(), 3);
        sensor.calibrate_sensor().unwrap();
        sensor.calibrate_sensor_with(&[1.0, 2.0, 3.0]).unwrap();
        sensor.calibrate_channel(2).unwrap();
        sensor.calibrate_channel_with(1, 0.5).unwrap();
        client.close().unwrap();
    }
    server.close().unwrap();
}

/// This process's CPU time (user + system) in seconds, from /proc/self/stat.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit_once(") ")
        .map(|(_, rest)| rest.split(' ').collect())
        .unwrap_or_default();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0 // utime, stime (fields 14, 15) at 100 Hz
}

/// Figures for the report: the IMU served at 1 kHz to a reader port in this process
/// (`--run-ignored only`).
#[test]
#[ignore]
fn measure_imu_stream_at_1khz() {
    let mut server =
        open("device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /imufast\nperiod 1\n");
    let ns = name_client();
    let (n, first, last, wall, cpu) = run(async move {
        let port = yarp_net::port::Port::open("/imufast/reader", ns.clone())
            .await
            .unwrap();
        let (ok, _) =
            yarp_net::network::connect(&ns, "/imufast/measures:o", "/imufast/reader", None)
                .await
                .unwrap();
        assert!(ok);
        port.read().await.unwrap();
        let (t0, c0) = (Instant::now(), cpu_seconds());
        let (mut n, mut first, mut last) = (0u64, None, 0);
        while t0.elapsed() < Duration::from_secs(3) {
            let m = port.read().await.unwrap();
            let count = m.stamp.map(|s| s.count).unwrap_or(0);
            first.get_or_insert(count);
            last = count;
            n += 1;
        }
        let wall = t0.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - c0;
        port.close().await;
        (n, first.unwrap_or(0), last, wall, cpu)
    });
    println!(
        "imu at 1 kHz: {:.0} messages/s received ({} sent in the window); process CPU {:.1}% of one core (server + reader, debug build)",
        n as f64 / wall,
        last - first + 1,
        100.0 * cpu / wall
    );
    server.close().unwrap();
}

/// The recorded C++ client's `getMetadata` call (imu-005), sent byte for byte to our
/// server over a raw tcp connection; the reply must be the recorded bytes.
#[test]
fn live_metadata_reply_is_byte_exact() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/yarp-vectors/imu.jsonl"
    );
    let Ok(text) = std::fs::read_to_string(path) else {
        eprintln!("SKIPPED: {path}");
        return;
    };
    let open_rec: serde_json::Value = text
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find(|r| r["kind"] == "cpp_client" && r["call"] == "open")
        .unwrap();
    let units = open_rec["units"].as_array().unwrap().clone();
    let hex_of = |kind: &str, field: &str| -> Vec<u8> {
        let u = units.iter().find(|u| u["unit"] == kind).unwrap();
        hex::decode(u[field].as_str().unwrap()).unwrap()
    };
    let mut request = hex_of("message", "index_hex");
    for b in units.iter().find(|u| u["unit"] == "message").unwrap()["blocks_hex"]
        .as_array()
        .unwrap()
    {
        request.extend(hex::decode(b.as_str().unwrap()).unwrap());
    }
    let mut want = hex_of("reply", "payload_hex");
    want.extend(hex_of("ack", "hex"));
    let start = [hex_of("header", "hex"), hex_of("sender", "hex")].concat();

    let mut server =
        open("device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /imu3\nperiod 20\n");
    let ns = name_client();
    let n = want.len();
    let got = run(async move {
        let c = ns.query("/imu3/rpc:o").await.unwrap().expect("registered");
        let mut s = TcpStream::connect((c.host.as_str(), c.port)).await.unwrap();
        s.write_all(&start).await.unwrap();
        let mut header_reply = [0u8; 8];
        s.read_exact(&mut header_reply).await.unwrap();
        s.write_all(&request).await.unwrap();
        // what arrives until the expected length, or 1 s of silence
        let mut got = Vec::new();
        let mut buf = [0u8; 4096];
        while got.len() < n {
            match tokio::time::timeout(Duration::from_secs(1), s.read(&mut buf)).await {
                Ok(Ok(k)) if k > 0 => got.extend_from_slice(&buf[..k]),
                _ => break,
            }
        }
        got
    });
    server.close().unwrap();
    assert_eq!(hex::encode(got), hex::encode(want));
}

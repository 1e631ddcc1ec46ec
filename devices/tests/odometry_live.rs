//! odometry2D_nws_yarp and odometry2D_nwc_yarp (R1's base odometry wrapper) on real
//! sockets, with a name server of the test's own (run under netns-run): our wrapper over
//! fakeOdometry2D streams `OdometryData`, the odometer and the velocity with one envelope;
//! our client reads it and resets it. Against C++ YARP 3.12.3 (tests/peers/
//! install-cpp-peers.sh icub; in CI required): C++ `yarp read` reads our stream, and C++'s
//! own client and wrapper relay our odometry (C++ odometry2D_nwc_yarp reading ours, C++
//! odometry2D_nws_yarp serving it again) to our client, whose reset travels back through
//! both C++ devices to ours. Every wait is bounded.

use yarp_devices::navigation::OdometryData;
use yarp_devices::{runtime, PolyDriver};
use yarp_interop_tests::{name_client, wait_for, T};
use yarp_net::buffered::BufferedPort;
use yarp_proto::{Bottle, Property, Value};

fn run<F>(fut: F) -> F::Output
where
    F: std::future::Future + Send + 'static,
    F::Output: Send + 'static,
{
    runtime::block_on(async move { tokio::time::timeout(T, fut).await.expect("timed out") })
        .expect("the device runtime")
}

fn open(cfg: &str) -> PolyDriver {
    name_client();
    PolyDriver::open(&Property::from_config_text(cfg).unwrap())
        .unwrap_or_else(|e| panic!("open {cfg:?}: {e}"))
}

/// Our wrapper over a fakeOdometry2D at `name`, 20 ms period.
fn wrapper(name: &str) -> PolyDriver {
    open(&format!(
        "device odometry2D_nws_yarp\nsubdevice fakeOdometry2D\nname {name}\nperiod 0.02\n"
    ))
}

fn client(local: &str, remote: &str) -> PolyDriver {
    open(&format!(
        "device odometry2D_nwc_yarp\nlocal {local}\nremote {remote}\n"
    ))
}

/// The client's odometry once it has one whose pose has moved past `x`.
fn odometry_past(pd: &mut PolyDriver, x: f64) -> (OdometryData, f64) {
    let o = pd.device().as_odometry_2d().expect("IOdometry2D");
    wait_for("odometry", || {
        let (d, t) = o.get_odometry().ok()?;
        (d.odom_x > x).then_some((d, t))
    })
}

fn nums(b: &Bottle) -> Vec<f64> {
    b.iter().filter_map(Value::as_f64).collect()
}

#[test]
fn our_wrapper_streams_and_our_client_reads_and_resets() {
    let mut server = wrapper("/base/odom");
    let ns = name_client();
    // one message of each port, read together
    let (odometry, odometer, velocity) = run(async move {
        let mut readers = Vec::new();
        for port in ["odometry", "odometer", "velocity"] {
            let local = format!("/reader/{port}:i");
            let r = BufferedPort::open(&local, ns.clone()).await.unwrap();
            let from = format!("/base/odom/{port}:o");
            let (ok, msg) = yarp_net::network::connect(&ns, &from, &local, None)
                .await
                .unwrap();
            assert!(ok, "{msg}");
            readers.push(r);
        }
        let mut got = Vec::new();
        for r in &readers {
            let m = r.read().await.expect("a message");
            got.push((m.bottle.clone(), m.stamp.expect("an envelope")));
        }
        for r in readers {
            r.close().await;
        }
        (got[0].clone(), got[1].clone(), got[2].clone())
    });
    let d = OdometryData::from_bottle(&odometry.0).unwrap();
    assert!(d.odom_x > 0.0 && d.odom_y > 0.0, "{d:?}");
    // fakeOdometry2D moves at the same random velocity in both frames
    assert_eq!(
        (d.base_vel_x, d.base_vel_theta),
        (d.odom_vel_x, d.odom_vel_theta)
    );
    assert!(
        odometry.1.time > 1.6e9,
        "the odometry's own time: {:?}",
        odometry.1
    );
    let (odo, vel) = (nums(&odometer.0), nums(&velocity.0));
    assert_eq!((odo.len(), vel.len()), (2, 2), "{odometer:?} {velocity:?}");
    assert!(vel[0] >= 0.0 && odo[0] >= 0.0);

    let mut c = client("/base/odom_client", "/base/odom");
    let (before, t) = odometry_past(&mut c, 4.0);
    assert!(t > 1.6e9, "{t}");
    c.device()
        .as_odometry_2d()
        .unwrap()
        .reset_odometry()
        .expect("reset");
    // after the reset the pose starts again from zero: well below where it was
    let (after, _) = wait_for("the reset pose", || {
        let got = c.device().as_odometry_2d()?.get_odometry().ok()?;
        (got.0.odom_x < before.odom_x / 2.0).then_some(got)
    });
    assert!(after.odom_x >= 0.0);
    c.close().unwrap();
    server.close().unwrap();

    // a client of nothing fails to open, naming the port it could not reach
    let err = PolyDriver::open(
        &Property::from_config_text("device odometry2D_nwc_yarp\nlocal /lonely\nremote /no/odom\n")
            .unwrap(),
    )
    .err()
    .expect("no server");
    assert!(err.to_string().contains("/no/odom/odometry:o"), "{err}");
}

#[test]
fn cpp_reads_and_relays_our_odometry_and_our_reset_reaches_through_it() {
    let test = "cpp_reads_and_relays_our_odometry_and_our_reset_reaches_through_it";
    let Some(bin) =
        yarp_interop_tests::cpp_devices(test, &["odometry2D_nws_yarp", "odometry2D_nwc_yarp"])
    else {
        return;
    };
    let mut server = wrapper("/ours/odom");
    // C++ yarp read: nine numbers of OdometryData
    let read = yarp_interop_tests::cpp_read_until(
        &bin.join("yarp"),
        "/cpp_odom_rd",
        "/ours/odom/odometry:o",
        |l| OdometryData::from_bottle(&Bottle::from_text(l)).ok(),
    );
    assert!(read.odom_x > 0.0, "{read:?}");

    // C++'s client reads ours, C++'s wrapper serves it again at /cpprelay
    let _cpp = yarp_interop_tests::cpp_yarpdev(
        &bin,
        &[
            "--device",
            "odometry2D_nws_yarp",
            "--subdevice",
            "odometry2D_nwc_yarp",
            "--local",
            "/cpp/odom_client",
            "--remote",
            "/ours/odom",
            "--name",
            "/cpprelay",
            "--period",
            "0.02",
        ],
        "/cpprelay/rpc",
    );
    let mut c = client("/ours/relay_client", "/cpprelay");
    let (before, t) = odometry_past(&mut c, 4.0);
    assert!(t > 1.6e9, "the envelope C++ passes on: {t}");
    // the reset goes: our client -> C++ wrapper -> C++ client -> our wrapper -> the fake
    c.device()
        .as_odometry_2d()
        .unwrap()
        .reset_odometry()
        .expect("reset through C++");
    wait_for("the reset pose through C++", || {
        let (d, _) = c.device().as_odometry_2d()?.get_odometry().ok()?;
        (d.odom_x < before.odom_x / 2.0).then_some(())
    });
    eprintln!("interop: C++ odometry2D_nwc_yarp/nws_yarp relay our odometry and reset OK");
    c.close().unwrap();
    server.close().unwrap();
}

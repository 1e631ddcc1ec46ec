//! The sensor NWS/NWC pairs YARP 4.0 kept but re-laid (4.0 renumbered the float tags and
//! `yarp::dev::ReturnValue`): rangefinder, battery and multiple analog sensors, live
//! against C++ 3.12.3 and C++ 4.0.0 at once. For each C++ generation a chain runs: C++'s
//! server over C++'s client of OUR server; our client then reads C++'s server. What it
//! gets is what our server's fake device holds only if C++'s client read ours (RPC and
//! stream) and ours read C++'s server, both ways in that generation's bytes, while the
//! other generation's chain reads the same server of ours.
//! Run under ../shared/netns-run (C++ peers: tests/peers/install-cpp-peers.sh icub yarp4).

use std::path::PathBuf;
use yarp_devices::PolyDriver;
use yarp_interop_tests::{cpp4_devices, cpp_devices, cpp_yarpdev, name_client, wait_for, Reaped};
use yarp_proto::Property;

/// Both C++ peers' bin directories when both have `devices`.
fn both_peers(test: &str, devices: &[&str]) -> Option<[(&'static str, PathBuf); 2]> {
    let v3 = cpp_devices(test, devices);
    let v4 = cpp4_devices(test, devices);
    Some([("3", v3?), ("4", v4?)])
}

fn open(cfg: &str) -> PolyDriver {
    name_client();
    PolyDriver::open(&Property::from_config_text(cfg).unwrap())
        .unwrap_or_else(|e| panic!("open {cfg:?}: {e}"))
}

/// C++ `server` over C++ `client` (of the peer in `bin`), all `args` given to both, ready
/// once `port` is registered.
fn chain(bin: &std::path::Path, server: &str, client: &str, args: &[&str], port: &str) -> Reaped {
    let mut all = vec!["--device", server, "--subdevice", client];
    all.extend_from_slice(args);
    cpp_yarpdev(bin, &all, port)
}

#[test]
fn rangefinder_through_cpp_3_12_and_4_0() {
    let test = "rangefinder_through_cpp_3_12_and_4_0";
    let Some(peers) = both_peers(test, &["rangefinder2D_nws_yarp", "rangefinder2D_nwc_yarp"])
    else {
        return;
    };
    let mut server = open(
        "device rangefinder2D_nws_yarp\nsubdevice fakeLaser\nname /rfp/ours\nperiod 0.01\n\
         test use_constant\n[SENSOR]\nmin_distance 0.1\nmax_distance 30\nresolution 0.5\n\
         [CONSTANT_MODE]\nconst_distance 2.5\n",
    );
    for (generation, bin) in &peers {
        let name = format!("/rfp/chain{generation}");
        let local = format!("/rfp/cpp{generation}");
        let args = [
            "--local",
            &local,
            "--remote",
            "/rfp/ours",
            "--name",
            &name,
            "--period",
            "0.01",
        ];
        let _chain = chain(
            bin,
            "rangefinder2D_nws_yarp",
            "rangefinder2D_nwc_yarp",
            &args,
            &name,
        );
        let mut client = open(&format!(
            "device rangefinder2D_nwc_yarp\nlocal /rfp/client{generation}\nremote {name}\n"
        ));
        let rf = client.device().as_rangefinder_2d().unwrap();
        let at = format!("through C++ {generation}");
        let (scans, t) = wait_for("a scan", || {
            let (s, t) = rf.get_raw_data().ok()?;
            (!s.is_empty()).then_some((s, t))
        });
        assert_eq!(scans.len(), 720, "{at}");
        assert!(scans.iter().all(|&d| d == 2.5) && t > 1.6e9, "{at}: {t}");
        assert_eq!(rf.get_distance_range().unwrap(), (0.1, 30.0), "{at}");
        assert_eq!(rf.get_scan_limits().unwrap(), (0.0, 360.0), "{at}");
        assert_eq!(rf.get_horizontal_resolution().unwrap(), 0.5, "{at}");
        // a setter's bare ReturnValue, both ways
        let rate = if generation == &"3" { 40.0 } else { 45.0 };
        rf.set_scan_rate(rate).unwrap();
        assert_eq!(rf.get_scan_rate().unwrap(), rate, "{at}");
        assert_eq!(
            rf.get_device_info().unwrap(),
            "Fake Laser device for test/debugging",
            "{at}"
        );
        client.close().unwrap();
        eprintln!("interop: ours <-> C++ {generation} rangefinder2D_nwc/nws_yarp OK");
    }
    server.close().unwrap();
}

#[test]
fn battery_through_cpp_3_12_and_4_0() {
    let test = "battery_through_cpp_3_12_and_4_0";
    let Some(peers) = both_peers(test, &["battery_nws_yarp", "battery_nwc_yarp"]) else {
        return;
    };
    let mut server =
        open("device battery_nws_yarp\nsubdevice fakeBattery\nname /bp/ours\nperiod 0.05\n");
    for (generation, bin) in &peers {
        let name = format!("/bp/chain{generation}");
        let local = format!("/bp/cpp{generation}");
        let args = [
            "--local", &local, "--remote", "/bp/ours", "--name", &name, "--period", "0.05",
        ];
        let _chain = chain(
            bin,
            "battery_nws_yarp",
            "battery_nwc_yarp",
            &args,
            &format!("{name}/data:o"),
        );
        let mut client = open(&format!(
            "device battery_nwc_yarp\nlocal /bp/client{generation}\nremote {name}\n"
        ));
        let b = client.device().as_battery().unwrap();
        let at = format!("through C++ {generation}");
        let v = wait_for("battery data", || {
            let v = b.get_battery_voltage().ok()?;
            (v.is_finite() && v != 0.0).then_some(v)
        });
        assert_eq!(v, 30.0, "{at}");
        assert_eq!(b.get_battery_current().unwrap(), 3.0, "{at}");
        assert_eq!(b.get_battery_temperature().unwrap(), 20.0, "{at}");
        let charge = b.get_battery_charge().unwrap();
        assert!(charge > 40.0 && charge <= 50.0, "{at}: {charge}");
        assert_eq!(
            b.get_battery_info().unwrap(),
            "Fake battery system v2.0",
            "{at}"
        );
        client.close().unwrap();
        eprintln!("interop: ours <-> C++ {generation} battery_nwc/nws_yarp OK");
    }
    server.close().unwrap();
}

#[test]
fn multiple_analog_sensors_through_cpp_3_12_and_4_0() {
    let test = "multiple_analog_sensors_through_cpp_3_12_and_4_0";
    let Some(peers) = both_peers(
        test,
        &["multipleanalogsensorsserver", "multipleanalogsensorsclient"],
    ) else {
        return;
    };
    let mut server =
        open("device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /mp/ours\nperiod 20\n");
    for (generation, bin) in &peers {
        let name = format!("/mp/chain{generation}");
        let local = format!("/mp/cpp{generation}");
        let args = [
            "--remote", "/mp/ours", "--local", &local, "--name", &name, "--period", "20",
        ];
        let _chain = chain(
            bin,
            "multipleanalogsensorsserver",
            "multipleanalogsensorsclient",
            &args,
            &format!("{name}/measures:o"),
        );
        let mut client = open(&format!(
            "device multipleanalogsensorsclient\nremote {name}\nlocal /mp/client{generation}\n\
             timeout 1.0\n"
        ));
        let at = format!("through C++ {generation}");
        let gyro = client.device().as_three_axis_gyroscopes().unwrap();
        assert_eq!(gyro.get_nr_of_three_axis_gyroscopes(), 1, "{at}");
        let m = wait_for("a gyroscope measurement", || {
            (gyro.get_three_axis_gyroscope_status(0)
                == yarp_devices::sensors::interfaces::MasStatus::Ok)
                .then(|| gyro.get_three_axis_gyroscope_measure(0).ok())
                .flatten()
        });
        assert_eq!(m.values.len(), 3, "{at}");
        assert!(
            m.values.iter().all(|v| v.is_finite()),
            "{at}: {:?}",
            m.values
        );
        client.close().unwrap();
        eprintln!("interop: ours <-> C++ {generation} multipleanalogsensors server/client OK");
    }
    server.close().unwrap();
}

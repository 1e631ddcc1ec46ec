//! ergoCubSN001's left-hand position sensors (`hardware/POS/left_hand-pos2.xml` and
//! `left_hand-pos4.xml`, with the hand's `multipleanalogsensorsremapper` and
//! `multipleanalogsensorsserver` files of `wrappers/POS`, all unmodified; the robot's top
//! file has the wrappers commented out, so a top file of this test includes them) through
//! `embObjPOS` against the emulated board (address map 10.0.1.0/24 -> 127.0.9.0/24, under
//! netns-run). Each device gives its sensors as `IEncoderArrays`, read at the hand ports
//! C++ maps them to: open/close sensors at ports 0-3, the abductions at 4 and 6. The
//! emulated board sends 100 k + c deci-degrees at port k (c common to all ports of one
//! message), so the differences between sensors show which ports were read.

mod eth_common;

use std::time::{Duration, Instant};

use eth_common::{bring_up, robot_dir};
use yarp_devices::robotinterface::ActionPhase;
use yarp_devices::SharedDevice;

/// The names and one reading (degrees) of every encoder array of `dev`.
fn read(dev: &SharedDevice) -> (Vec<String>, Vec<f64>) {
    let mut pd = dev.lock();
    let e = pd.device().as_encoder_arrays().expect("IEncoderArrays");
    let n = e.get_nr_of_encoder_arrays();
    let names = (0..n)
        .map(|i| e.get_encoder_array_name(i).unwrap())
        .collect();
    let values = (0..n)
        .map(|i| {
            assert_eq!(e.get_encoder_array_size(i), 1);
            let m = e.get_encoder_array_measure(i).unwrap();
            assert_eq!(m.values.len(), 1);
            m.values[0]
        })
        .collect();
    (names, values)
}

/// Reads until the board's first status has come (its zeros before).
fn settled(dev: &SharedDevice) -> (Vec<String>, Vec<f64>) {
    let start = Instant::now();
    loop {
        let (names, values) = read(dev);
        // two sensors of one message differ by at least 10 degrees once data came
        if values.windows(2).all(|w| (w[1] - w[0]).abs() > 5.0)
            || start.elapsed() > Duration::from_secs(10)
        {
            return (names, values);
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn ergocub_hand_position_sensors_as_encoder_arrays() {
    let dir = robot_dir("ergoCubSN001");
    let work = tempfile::tempdir().unwrap();
    let top = work.path().join("pos.xml");
    let include = |f: &str| {
        let href = yarp_interop_tests::include_href(work.path(), &dir.join(f));
        format!("    <xi:include href=\"{href}\" />\n")
    };
    let files = [
        "hardware/POS/left_hand-pos2.xml",
        "hardware/POS/left_hand-pos4.xml",
        "wrappers/POS/left_hand-pos_remapper2.xml",
        "wrappers/POS/left_hand-pos_remapper4.xml",
        "wrappers/POS/left_hand-pos_wrapper2.xml",
        "wrappers/POS/left_hand-pos_wrapper4.xml",
    ];
    std::fs::write(
        &top,
        format!(
            r#"<?xml version="1.0" encoding="UTF-8" ?>
<!DOCTYPE robot PUBLIC "-//YARP//DTD yarprobotinterface 3.0//EN" "http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd">
<robot name="ergoCubSN001" build="1" portprefix="/ergocub" xmlns:xi="http://www.w3.org/2001/XInclude">
  <devices>
{}  </devices>
</robot>
"#,
            files.iter().map(|f| include(f)).collect::<String>()
        ),
    )
    .unwrap();
    let (mut runner, _conf) = bring_up(&dir, &top, "10.0.1.0/24=127.0.9.0/24");
    assert!(runner.failures().is_empty(), "{:?}", runner.failures());

    let pos4 = runner
        .device("left_hand-pos4")
        .expect("left_hand-pos4 opened");
    let (names, v) = settled(&pos4);
    assert_eq!(
        names,
        ["l_id_fapAA", "l_id_fapBB", "l_id_fapCC", "l_id_fapDD"]
    );
    for k in 1..4 {
        // ports 0, 1, 2, 3: 10 degrees apart
        assert!((v[k] - v[k - 1] - 10.0).abs() < 0.15, "{v:?}");
    }

    let pos2 = runner
        .device("left_hand-pos2")
        .expect("left_hand-pos2 opened");
    let (names, v) = settled(&pos2);
    assert_eq!(names, ["l_id_fapEE", "l_id_fapFF"]);
    // ports 4 (thumb abduction) and 6 (index abduction): 20 degrees apart
    assert!((v[1] - v[0] - 20.0).abs() < 0.15, "{v:?}");

    // The remappers serve them on by name, as the wrappers attached them.
    let remapper = runner
        .device("left_hand-pos2_remapper")
        .expect("the remapper opened");
    let (names, v) = settled(&remapper);
    assert_eq!(names, ["l_id_fapEE", "l_id_fapFF"]);
    assert!((v[1] - v[0] - 20.0).abs() < 0.15, "{v:?}");

    runner.enter_phase(ActionPhase::Interrupt1).unwrap();
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}

//! ergoCubSN001's battery (`hardware/battery/battery_bms.xml`, unmodified: the BMS behind
//! the left arm's board 10.0.1.2, service `eomn_serv_AS_battery`; the robot's top file has
//! it commented out, so a top file of this test includes it) through `embObjBattery`
//! against the emulated board (address map 10.0.1.0/24 -> 127.0.9.0/24, under netns-run):
//! the service is verified, configured and started, and `IBattery` gives the emulated
//! pack's values with C++'s roundings.

mod eth_common;

use std::time::{Duration, Instant};

use eth_common::{bring_up, robot_dir};
use yarp_devices::battery::BatteryStatus;
use yarp_devices::robotinterface::ActionPhase;

#[test]
fn ergocub_battery_reports_through_embobjbattery() {
    let dir = robot_dir("ergoCubSN001");
    let work = tempfile::tempdir().unwrap();
    let top = work.path().join("battery.xml");
    std::fs::write(
        &top,
        format!(
            r#"<?xml version="1.0" encoding="UTF-8" ?>
<!DOCTYPE robot PUBLIC "-//YARP//DTD yarprobotinterface 3.0//EN" "http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd">
<robot name="ergoCubSN001" build="1" portprefix="/ergocub" xmlns:xi="http://www.w3.org/2001/XInclude">
  <devices>
    <xi:include href="{}" />
  </devices>
</robot>
"#,
            yarp_interop_tests::include_href(work.path(), &dir.join("hardware/battery/battery_bms.xml"))
        ),
    )
    .unwrap();
    let (mut runner, _conf) = bring_up(&dir, &top, "10.0.1.0/24=127.0.9.0/24");
    assert!(runner.failures().is_empty(), "{:?}", runner.failures());
    let dev = runner.device("battery_bms").expect("battery_bms opened");

    // The first regulars may still carry the board's zeros.
    let start = Instant::now();
    let voltage = loop {
        let v = dev
            .lock()
            .device()
            .as_battery()
            .expect("IBattery")
            .get_battery_voltage()
            .unwrap();
        if v > 0.0 || start.elapsed() > Duration::from_secs(10) {
            break v;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let mut pd = dev.lock();
    let b = pd.device().as_battery().unwrap();
    // The emulated pack: 48.3 V, ~2 A, 85 %, 25.0 °C (250 in 0.1 °C), in use.
    assert!((voltage - 48.3).abs() < 1e-4, "{voltage}");
    let current = b.get_battery_current().unwrap();
    assert!((1.7..=2.2).contains(&current), "{current}");
    assert_eq!(b.get_battery_charge().unwrap(), 85.0);
    assert_eq!(b.get_battery_temperature().unwrap(), 25.0);
    assert_eq!(b.get_battery_status().unwrap(), BatteryStatus::OkInUse);
    let info = b.get_battery_info().unwrap();
    assert!(
        info.starts_with("{\"temperature\":25,\"voltage\":48.3,"),
        "{info}"
    );
    drop(pd);
    runner.enter_phase(ActionPhase::Interrupt1).unwrap();
    runner.enter_phase(ActionPhase::Shutdown).unwrap();
}

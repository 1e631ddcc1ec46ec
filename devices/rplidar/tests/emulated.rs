//! `rpLidar3` on an emulated A3 (Boost: ultra capsules) and `rpLidar2` on an emulated A2
//! (firmware 1.20: express capsules), each on a pseudo-terminal: the scans are the
//! emulated room, mirrored as C++ mirrors them.

use std::time::{Duration, Instant};

use icub_emulators::rplidar::{pty_link, room, Model};
use rplidar::device::RpLidar;
use yarp_devices::driver::DeviceDriver;
use yarp_proto::Property;

fn scan_of(model: Model, mut device: RpLidar, baud: u32) {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("ttyUSB0");
    let (_lidar, _pts) = pty_link(&link, model).unwrap();
    let config = Property::from_text(format!(
        "(GENERAL (serial_port {}) (serial_baudrate {baud}) (sample_buffer_life 1)) \
         (SENSOR (max_distance 20.0) (min_distance 0.1) (max_angle 360) (min_angle 0) (resolution 0.5) (allow_infinity 1))",
        link.display()
    ));
    device
        .open(&config)
        .unwrap_or_else(|e| panic!("{model:?}: {e}"));
    let laser = device.as_rangefinder_2d().unwrap();
    let start = Instant::now();
    let data = loop {
        std::thread::sleep(Duration::from_millis(100));
        let (data, _) = laser.get_raw_data().unwrap();
        // A2 express: 400 samples a revolution, A3 Boost: 1587
        if data.iter().filter(|d| d.is_finite()).count() > 300 {
            break data;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "{model:?}: no scan within 10 s"
        );
    };
    assert_eq!(data.len(), 720);
    let mut close = 0;
    let mut measured = 0;
    for (i, d) in data.iter().enumerate().filter(|(_, d)| d.is_finite()) {
        measured += 1;
        // element i is at 0.5·i degrees, mirrored from the lidar's own angle
        let lidar_angle = (360.0 - 0.5 * i as f64).rem_euclid(360.0);
        let expected = room(lidar_angle)
            .min(room(lidar_angle - 0.5))
            .min(room(lidar_angle + 0.5));
        let farthest = room(lidar_angle)
            .max(room(lidar_angle - 0.5))
            .max(room(lidar_angle + 0.5));
        if *d >= expected - 0.03 && *d <= farthest + 0.03 {
            close += 1;
        }
    }
    assert!(
        close * 100 >= measured * 98,
        "{model:?}: {close} of {measured} measurements on the room"
    );
    assert!(device
        .as_rangefinder_2d()
        .unwrap()
        .get_device_info()
        .unwrap()
        .starts_with("Firmware Version: "));
    device.close().unwrap();
}

#[test]
fn rplidar3_scans_an_emulated_a3_in_boost() {
    scan_of(Model::A3, RpLidar::three(), 256_000);
}

#[test]
fn rplidar2_scans_an_emulated_a2_in_express() {
    scan_of(Model::A2, RpLidar::two(), 115_200);
}

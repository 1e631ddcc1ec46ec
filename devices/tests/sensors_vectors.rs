//! Every record of imu.jsonl (C++ multipleanalogsensorsserver + fakeIMU, and the C++
//! multipleanalogsensorsclient) reproduced byte for byte: RPC replies (with their ack),
//! the client's request, the measurement messages (port command, envelope, payload), the
//! fakeIMU values and what `yarp read` prints for them.

use serde_json::Value as Json;
use yarp_devices::sensors::rpc::handle_rpc;
use yarp_devices::sensors::server::collect_metadata;
use yarp_devices::sensors::wire::encode_get_metadata_request;
use yarp_devices::sensors::{FakeImu, SensorMeasurement, SensorStreamingData};
use yarp_devices::DeviceDriver;
use yarp_proto::wire::{ack, PortCommand};
use yarp_proto::{Bottle, Property, Stamp};

/// The recorded IMU vectors (panics clearly when `../shared` is missing).
fn records() -> Option<Vec<Json>> {
    Some(yarp_interop_tests::load_records("imu.jsonl"))
}

fn hex_of(v: &Json) -> Vec<u8> {
    hex::decode(v.as_str().expect("hex string")).expect("valid hex")
}

/// The metadata the recording's device (fakeIMU with default names) serves.
fn imu_metadata() -> yarp_devices::sensors::SensorRpcData {
    let mut imu = FakeImu::new();
    imu.open(&Property::from_config_text("period 20\n").unwrap())
        .unwrap();
    collect_metadata(&mut imu).unwrap()
}

fn unit<'a>(units: &'a [Json], kind: &str) -> &'a Json {
    units
        .iter()
        .find(|u| u["unit"] == kind)
        .unwrap_or_else(|| panic!("no {kind} unit"))
}

#[test]
fn yarp_rpc_replies_are_byte_exact() {
    let Some(recs) = records() else { return };
    let md = imu_metadata();
    let mut n = 0;
    for r in recs.iter().filter(|r| r["kind"] == "yarp_rpc") {
        let req = unit(r["request"].as_array().unwrap(), "message");
        let cmd = Bottle::decode(&hex_of(&req["payload_hex"])).unwrap();
        let mut got = handle_rpc(&cmd, &md, yarp_proto::tags::Generation::V3);
        got.extend_from_slice(&ack());
        assert_eq!(
            hex::encode(&got),
            r["reply_hex"].as_str().unwrap(),
            "{} ({})",
            r["id"],
            r["text_in"]
        );
        n += 1;
    }
    println!("imu yarp_rpc vectors: {n} of {n} byte-exact");
    assert_eq!(n, 3);
}

#[test]
fn cpp_client_open_request_and_reply_are_byte_exact() {
    let Some(recs) = records() else { return };
    let md = imu_metadata();
    let open = recs
        .iter()
        .find(|r| r["kind"] == "cpp_client" && r["call"] == "open")
        .expect("open record");
    let units = open["units"].as_array().unwrap();
    let req = unit(units, "message");
    let request = hex_of(&req["payload_hex"]);
    assert_eq!(request, encode_get_metadata_request());
    assert_eq!(
        hex_of(&req["port_command_hex"]),
        PortCommand::data(true).header()
    );
    let reply = handle_rpc(
        &Bottle::decode(&request).unwrap(),
        &md,
        yarp_proto::tags::Generation::V3,
    );
    assert_eq!(hex::encode(reply), unit(units, "reply")["payload_hex"]);

    // calls answered from the metadata (no traffic) have what the C++ client returned
    for r in recs.iter().filter(|r| r["kind"] == "cpp_client") {
        match r["call"].as_str().unwrap() {
            "getNrOfThreeAxisGyroscopes" => {
                assert_eq!(r["result_values"], md.families[0].len().to_string())
            }
            "getThreeAxisGyroscopeName(0)" => {
                assert_eq!(r["result_values"], md.families[0][0].name.as_str())
            }
            _ => {}
        }
    }
}

/// The measurement message the server sends for these fakeIMU values.
fn imu_message(count: f64, t: f64) -> SensorStreamingData {
    let mut d = SensorStreamingData::default();
    let c = SensorMeasurement::new(vec![count; 3], t);
    d.families[0].push(c.clone());
    d.families[1].push(SensorMeasurement::new(
        FakeImu::acceleration(count).to_vec(),
        t,
    ));
    d.families[2].push(c.clone());
    d.families[3].push(c);
    d
}

#[test]
fn stream_messages_are_byte_exact() {
    let Some(recs) = records() else { return };
    let mut n = 0;
    for r in recs.iter().filter(|r| r["kind"] == "stream") {
        let payload = hex_of(&r["payload_hex"]);
        let received = SensorStreamingData::from_bottle(&Bottle::decode(&payload).unwrap())
            .expect("a measurement message");
        // rebuild it from the fakeIMU model: the counter and the timestamp vary
        let gyro = &received.families[0][0];
        let ours = imu_message(gyro.values[0], gyro.timestamp);
        assert_eq!(ours, received, "{}", r["id"]);
        assert_eq!(ours.to_bottle().encode(), payload, "{}", r["id"]);

        // the envelope: port command with "D <count> <time>"
        let stamp = Stamp::from_text(
            r["port_command_text"]
                .as_str()
                .unwrap()
                .trim_start_matches("D "),
        )
        .unwrap();
        let mut cmd = Vec::new();
        PortCommand::with_stamp(&stamp, false).encode_binary(&mut cmd);
        assert_eq!(
            hex::encode(&cmd),
            format!(
                "{}{}",
                r["port_command_hex"].as_str().unwrap(),
                r["port_command_text_hex"].as_str().unwrap()
            )
        );
        // and the whole message: index + blocks, concatenated as a receiver sees it
        let whole = yarp_proto::wire::envelope_message(&ours.to_bottle(), &stamp, false);
        let blocks: Vec<u8> = r["blocks_hex"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(hex_of)
            .collect();
        assert!(whole.ends_with(&blocks), "{}", r["id"]);
        n += 1;
    }
    println!("imu stream vectors: {n} of {n} byte-exact");
    assert_eq!(n, 2);
}

#[test]
fn stream_text_matches_yarp_read() {
    let Some(recs) = records() else { return };
    let text = recs.iter().find(|r| r["kind"] == "stream_text").unwrap();
    for line in text["text_out"].as_array().unwrap() {
        let line = line.as_str().unwrap();
        // "<count> <time>     <data>"
        let (_, data) = line.split_once("     ").unwrap();
        let parsed = SensorStreamingData::from_bottle(&Bottle::from_text(data)).unwrap();
        let gyro = &parsed.families[0][0];
        let ours = imu_message(gyro.values[0], gyro.timestamp);
        assert_eq!(String::from_utf8(ours.to_bottle().to_text()).unwrap(), data);
    }
}

//! icub-main's raw values publisher on real sockets (run under netns-run), as ergoCubSN003
//! publishes its torso's raw encoders: our rawValuesPublisherServer/Remapper/Client and
//! fakeRawValuesPublisher, ergoCubSN003's own torso files against the emulated boards, and
//! C++ icub-main 2.11.1's devices (tests/peers/install-cpp-peers.sh icub; in CI required):
//! C++'s client reads our server, and C++'s server wrapping that client serves what it got
//! to our client again (the metadata asked of ours at C++'s attach). (icub-main's own
//! fakeRawValuesPublisher does not compile against YARP 3.12: an abstract class.)

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use icub_emulators::eth::{robot_boards, serve, AddressMap, ADDRESS_MAP_ENV};
use yarp_devices::driver::{shared, SharedDevice};
use yarp_devices::raw_values::RawValuesKeyMetadata;
use yarp_devices::robotinterface::read_robot_file;
use yarp_devices::{PolyDriver, Registry};
use yarp_interop_tests::{name_client, wait_for};
use yarp_proto::Property;

fn open(cfg: &str) -> PolyDriver {
    Registry::install(icubmod::register);
    name_client();
    PolyDriver::open(&Property::from_config_text(cfg).unwrap())
        .unwrap_or_else(|e| panic!("open {cfg:?}: {e}"))
}

fn attach(wrapper: &mut PolyDriver, devices: &[(&str, &SharedDevice)]) {
    let list: Vec<(String, SharedDevice)> = devices
        .iter()
        .map(|(k, d)| (k.to_string(), (*d).clone()))
        .collect();
    wrapper
        .device()
        .as_multiple_wrapper()
        .expect("a wrapper")
        .attach_all(&list)
        .expect("attach");
}

fn fake(njomos: usize, threshold: i64) -> SharedDevice {
    shared(open(&format!(
        "device fakeRawValuesPublisher\nname fake\nnjomos {njomos}\nthreshold {threshold}\n"
    )))
}

/// The client's map once it holds `key`.
fn map_with(client: &mut PolyDriver, key: &str) -> BTreeMap<String, Vec<i32>> {
    let p = client
        .device()
        .as_raw_values_publisher()
        .expect("a publisher");
    wait_for("raw values", || {
        let m = p.get_raw_data_map().ok()?;
        m.contains_key(key).then_some(m)
    })
}

#[test]
fn our_server_remapper_and_client_over_fakes() {
    let (a, b) = (fake(2, 100), fake(3, 100));
    let mut remapper = open("device rawValuesPublisherRemapper\naxesNames (a0 a1 b0 b1 b2)\n");
    attach(&mut remapper, &[("a", &a), ("b", &b)]);
    let remapper = shared(remapper);
    let mut server = open("device rawValuesPublisherServer\nname /ours/raw\nperiod 10\n");
    attach(&mut server, &[("remapper", &remapper)]);
    let mut client =
        open("device rawValuesPublisherClient\nremote /ours/raw\nlocal /ours/raw_client\n");
    let key = icubmod::raw_values::fake::KEY;
    let m = map_with(&mut client, key);
    // the two fakes' values, concatenated: two counters' values, 2 then 3 of each
    let v = &m[key];
    assert_eq!(v.len(), 5, "{m:?}");
    assert!(
        v[..2].iter().all(|x| *x == v[0]) && v[2..].iter().all(|x| *x == v[2]),
        "{v:?}"
    );
    let p = client.device().as_raw_values_publisher().unwrap();
    let meta = p.get_metadata_map().expect("getMetadata");
    let want = RawValuesKeyMetadata {
        raw_value_names: ["0", "1", "0", "1", "2"]
            .map(|i| format!("fake_jomo_rawvalue_{i}"))
            .to_vec(),
        axes_names: ["0", "1", "0", "1", "2"]
            .map(|i| format!("fake_jomo_{i}"))
            .to_vec(),
        size: 5,
    };
    assert_eq!(meta, BTreeMap::from([(key.to_string(), want)]));
    assert_eq!(p.get_keys().unwrap(), vec![key.to_string()]);
    // the counter goes on
    let later = wait_for("a later counter", || {
        let m = p.get_raw_data_map().ok()?;
        (m[key][0] != v[0]).then_some(m)
    });
    assert_eq!(later[key].len(), 5);
    client.close().unwrap();
    server.close().unwrap();
    // the remapper refuses what is no publisher
    let mut r = open("device rawValuesPublisherRemapper\naxesNames (x)\n");
    let not = shared(open("device fakeMotionControl\n"));
    let e = r
        .device()
        .as_multiple_wrapper()
        .unwrap()
        .attach_all(&[("m".to_string(), not)])
        .unwrap_err();
    assert!(e.to_string().contains("no IRawValuesPublisher"), "{e}");
}

#[test]
fn cpp_client_and_server_relay_ours_to_our_client() {
    let test = "cpp_client_and_server_relay_ours_to_our_client";
    let Some(bin) = yarp_interop_tests::cpp_devices(
        test,
        &["rawValuesPublisherServer", "rawValuesPublisherClient"],
    ) else {
        return;
    };
    let key = icubmod::raw_values::fake::KEY;
    // ours -> C++ client -> C++ server -> our client
    let source = fake(4, 1000);
    let mut server = open("device rawValuesPublisherServer\nname /ours/raw4\nperiod 10\n");
    attach(&mut server, &[("fake", &source)]);
    let _relay = yarp_interop_tests::cpp_yarpdev(
        &bin,
        &[
            "--device",
            "rawValuesPublisherServer",
            "--subdevice",
            "rawValuesPublisherClient",
            "--remote",
            "/ours/raw4",
            "--local",
            "/cpp/raw_client",
            "--name",
            "/cpprelay/raw",
            "--period",
            "10",
        ],
        "/cpprelay/raw/rawdata:o",
    );
    let mut client =
        open("device rawValuesPublisherClient\nremote /cpprelay/raw\nlocal /ours/relay_client\n");
    let m = map_with(&mut client, key);
    assert_eq!(m[key].len(), 4, "{m:?}");
    // C++'s server asked C++'s client for the metadata at attach, which asked ours
    let meta = client
        .device()
        .as_raw_values_publisher()
        .unwrap()
        .get_metadata_map()
        .expect("metadata through C++");
    assert_eq!(
        meta[key].axes_names,
        ["0", "1", "2", "3"].map(|i| format!("fake_jomo_{i}"))
    );
    assert_eq!(meta[key].size, 4);
    eprintln!("interop: C++ rawValuesPublisher client/server and ours exchange data and metadata");
    client.close().unwrap();
    server.close().unwrap();
}

const MAP: &str = "10.0.1.0/24=127.0.1.0/24";

/// ergoCubSN003's torso board and its raw values remapper and server, from the robot's own
/// files, against the emulated board: the key icub-main names, three values per joint
/// (the primary encoder's raw value first), the joints' names.
#[test]
fn ergocub_sn003_torso_publishes_its_raw_encoders() {
    std::env::set_var(ADDRESS_MAP_ENV, MAP);
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/robots-configuration/ergoCubSN003");
    let top = dir.join("ergocub.xml");
    let robot = read_robot_file(&top, &Property::default())
        .expect("ergocub.xml")
        .robot;
    let specs = robot_boards(&dir, Some(&top)).expect("robot boards");
    let stop = Arc::new(AtomicBool::new(false));
    let (_served, _threads) =
        serve(specs, &AddressMap::parse(MAP).unwrap(), stop.clone()).expect("emulated boards");
    let cfg = |name: &str| robot.device(name).expect(name).to_property().unwrap();
    Registry::install(icubmod::register);
    name_client();
    let board = shared(PolyDriver::open(&cfg("torso-eb5-j0_2-mc")).expect("the torso board"));
    let mut remapper = PolyDriver::open(&cfg("torso-rawval_remapper")).expect("the remapper");
    attach(&mut remapper, &[("torso_joints1", &board)]);
    let remapper = shared(remapper);
    let mut server = PolyDriver::open(&cfg("torso-rawval_nws_yarp")).expect("the server");
    attach(&mut server, &[("torso-rawval_remapper", &remapper)]);
    let mut client =
        open("device rawValuesPublisherClient\nremote /torso/raw_data\nlocal /ours/torso_raw\n");
    let key = icubmod::eth::motion_control::RAW_VALUES_KEY;
    let m = map_with(&mut client, key);
    assert_eq!(m[key].len(), 9, "{m:?}");
    let meta = client
        .device()
        .as_raw_values_publisher()
        .unwrap()
        .get_metadata_map()
        .unwrap();
    let axes = ["torso_roll", "torso_pitch", "torso_yaw"];
    assert_eq!(meta[key].axes_names, axes);
    assert_eq!(meta[key].size, 9);
    assert_eq!(
        meta[key].raw_value_names[0],
        "torso_roll_primary_encoder_raw_value"
    );
    assert_eq!(
        meta[key].raw_value_names[5],
        "torso_pitch_primary_encoder_diagnostic"
    );
    // the primary raw value is the board's joint position, raw: the same as its encoder
    let enc = board
        .lock()
        .device()
        .as_encoders()
        .unwrap()
        .get_encoders()
        .unwrap();
    assert_eq!(enc.len(), 3);
    client.close().unwrap();
    server.close().unwrap();
    stop.store(true, std::sync::atomic::Ordering::SeqCst);
}

//! The C++ `yarp rpc` tool (YARP 3.5 from `tests/peers/install-cpp-yarp.sh`, or the
//! directory in `YARP_CPP_BIN`) against our multipleanalogsensorsserver: it must print
//! exactly what it printed against C++ 3.12 in imu.jsonl. Without a C++ YARP the test
//! says SKIPPED loudly (in CI: fails). Run under netns-run.

use std::io::{Read, Write};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use yarp_devices::PolyDriver;
use yarp_interop_tests::{cpp_program, name_server, Reaped};
use yarp_proto::Property;

const WAIT: Duration = Duration::from_secs(10);

fn recorded_rpc() -> Vec<(String, Vec<String>)> {
    yarp_interop_tests::load_records("imu.jsonl")
        .into_iter()
        .filter(|r| r["kind"] == "yarp_rpc")
        .map(|r| {
            let lines = r["stdout_lines"]
                .as_array()
                .unwrap()
                .iter()
                .map(|l| l.as_str().unwrap().to_string())
                .collect();
            (r["text_in"].as_str().unwrap().to_string(), lines)
        })
        .collect()
}

#[test]
fn cpp_yarp_rpc_prints_what_it_printed_against_cpp() {
    let Some(yarp) = cpp_program("sensors_cpp", "yarp") else {
        return;
    };
    let cases = recorded_rpc();
    name_server();
    let mut server = PolyDriver::open(
        &Property::from_config_text(
            "device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /imu\nperiod 20\n",
        )
        .unwrap(),
    )
    .expect("server");
    let mut child = Reaped(
        Command::new(&yarp)
            .args(["rpc", "/imu/rpc:o"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("run C++ yarp rpc"),
    );
    let mut stdin = child.0.stdin.take().unwrap();
    for (text_in, _) in &cases {
        writeln!(stdin, "{text_in}").unwrap();
    }
    drop(stdin); // yarp rpc stops at end of input
    let mut stdout = child.0.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stdout.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    while child.0.try_wait().unwrap().is_none() {
        assert!(start.elapsed() < WAIT, "C++ yarp rpc did not finish");
        std::thread::sleep(Duration::from_millis(20));
    }
    let out = reader.join().unwrap();
    let printed: Vec<&str> = out
        .lines()
        .filter(|l| !l.starts_with('[') || l.starts_with("[fail]"))
        .filter(|l| !l.trim().is_empty())
        .collect();
    let want: Vec<&str> = cases
        .iter()
        .flat_map(|(_, lines)| lines.iter().map(String::as_str))
        .collect();
    assert_eq!(printed, want, "full output:\n{out}");
    eprintln!("interop: C++ yarp rpc -> multipleanalogsensorsserver OK");
    server.close().unwrap();
}

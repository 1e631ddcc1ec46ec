//! The C++ `yarp rpc` tool (YARP 3.12.3 from `tests/peers/install-cpp-peers.sh icub`, or
//! the directory in `YARP_CPP_BIN`) against our multipleanalogsensorsserver: it must print
//! exactly what it printed against C++ 3.12 in imu.jsonl. C++'s MAS client reads our server
//! and ours reads C++'s. Without a C++ YARP the tests say SKIPPED loudly (in CI: fail).
//! Run under netns-run.

use std::io::{Read, Write};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use yarp_devices::sensors::MasStatus;
use yarp_devices::PolyDriver;
use yarp_interop_tests::{cpp_program, name_server, Reaped};
use yarp_proto::{Bottle, Property, Value};

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

/// What `yarp rpc` printed for a MAS server, without log lines.
fn printed(out: &str) -> Vec<String> {
    out.lines()
        .filter(|l| !l.starts_with('[') || l.starts_with("[fail]"))
        .filter(|l| !l.trim().is_empty())
        .map(str::to_string)
        .collect()
}

/// C++ `multipleanalogsensorsserver` over C++ `multipleanalogsensorsclient` reading the
/// server `remote`, named `name`: each `yarp rpc` line at it is answered by the C++
/// client's view of `remote`.
fn cpp_client_chain(bin: &std::path::Path, name: &str, remote: &str) -> Reaped {
    yarp_interop_tests::cpp_yarpdev(
        bin,
        &[
            "--device",
            "multipleanalogsensorsserver",
            "--subdevice",
            "multipleanalogsensorsclient",
            "--remote",
            remote,
            "--local",
            &format!("{name}/client"),
            "--name",
            name,
            "--period",
            "20",
        ],
        &format!("{name}/measures:o"),
    )
}

/// C++ `multipleanalogsensorsclient` reads our server (over our `fakeIMU`): through C++'s
/// server wrapping the C++ client, the recorded `yarp rpc` session prints what it prints
/// over C++'s server + `fakeIMU` (the metadata the C++ client got from ours).
#[test]
fn cpp_mas_client_reads_our_server() {
    let test = "cpp_mas_client_reads_our_server";
    let Some(bin) = yarp_interop_tests::cpp_devices(
        test,
        &[
            "multipleanalogsensorsserver",
            "multipleanalogsensorsclient",
            "fakeIMU",
        ],
    ) else {
        return;
    };
    let cases = recorded_rpc();
    let input: String = cases.iter().map(|(t, _)| format!("{t}\n")).collect();
    name_server();
    let mut server = PolyDriver::open(
        &Property::from_config_text(
            "device multipleanalogsensorsserver\nsubdevice fakeIMU\nname /mas_ours\nperiod 20\n",
        )
        .unwrap(),
    )
    .expect("our server");
    let yarp = bin.join("yarp");
    let _chain_ours = cpp_client_chain(&bin, "/mas_chain_ours", "/mas_ours");
    let over_ours = printed(&yarp_interop_tests::cpp_rpc_output(
        &yarp,
        "/mas_chain_ours/rpc:o",
        &input,
    ));
    let _cpp = yarp_interop_tests::cpp_yarpdev(
        &bin,
        &[
            "--device",
            "multipleanalogsensorsserver",
            "--subdevice",
            "fakeIMU",
            "--name",
            "/mas_cpp",
            "--period",
            "20",
        ],
        "/mas_cpp/measures:o",
    );
    let _chain_cpp = cpp_client_chain(&bin, "/mas_chain_cpp", "/mas_cpp");
    let over_cpp = printed(&yarp_interop_tests::cpp_rpc_output(
        &yarp,
        "/mas_chain_cpp/rpc:o",
        &input,
    ));
    assert!(!over_cpp.is_empty(), "the C++ reference printed nothing");
    assert_eq!(over_ours, over_cpp, "inputs:\n{input}");

    // The measurements pass too: C++'s server over C++'s client republishes what the
    // client read from ours, in the layout it gives C++'s own (the values move with time)
    let shape = |port: &str, reader: &str| {
        yarp_interop_tests::cpp_read_until(&yarp, reader, port, |l| {
            let b = Bottle::from_text(l);
            // a measurement: 12 families, the gyroscope's one sensor measured
            (b.len() == 12 && b.get(0)?.as_list()?.len() == 1).then(|| layout(&b))
        })
    };
    let over_ours = shape("/mas_chain_ours/measures:o", "/mas_rd_ours");
    let over_cpp = shape("/mas_chain_cpp/measures:o", "/mas_rd_cpp");
    assert_eq!(over_ours, over_cpp);
    server.close().unwrap();
}

/// The layout of a Bottle: for a list its elements' layouts, else the value's kind.
fn layout(b: &Bottle) -> String {
    let kinds: Vec<String> = b
        .iter()
        .map(|v| match v {
            Value::List(l) => format!("({})", layout(l)),
            Value::Float64(_) | Value::Float32(_) => "f".to_string(),
            v if v.as_i64().is_some() => "i".to_string(),
            _ => "s".to_string(),
        })
        .collect();
    kinds.join(" ")
}

/// Our `multipleanalogsensorsclient` reads C++'s server over C++'s `fakeIMU`: the
/// metadata (one sensor of each IMU family) and the measurements.
#[test]
fn our_mas_client_reads_cpp_server() {
    let test = "our_mas_client_reads_cpp_server";
    let Some(bin) =
        yarp_interop_tests::cpp_devices(test, &["multipleanalogsensorsserver", "fakeIMU"])
    else {
        return;
    };
    name_server();
    let _cpp = yarp_interop_tests::cpp_yarpdev(
        &bin,
        &[
            "--device",
            "multipleanalogsensorsserver",
            "--subdevice",
            "fakeIMU",
            "--name",
            "/masr_cpp",
            "--period",
            "20",
        ],
        "/masr_cpp/measures:o",
    );
    let mut client = PolyDriver::open(
        &Property::from_config_text(
            "device multipleanalogsensorsclient\nremote /masr_cpp\nlocal /masr_ours\ntimeout 1.0\n",
        )
        .unwrap(),
    )
    .expect("our client reads C++ 3.12.3's metadata");
    let gyro = client.device().as_three_axis_gyroscopes().unwrap();
    assert_eq!(gyro.get_nr_of_three_axis_gyroscopes(), 1);
    let start = Instant::now();
    let m = loop {
        if gyro.get_three_axis_gyroscope_status(0) == MasStatus::Ok {
            break gyro.get_three_axis_gyroscope_measure(0).unwrap();
        }
        assert!(start.elapsed() < WAIT, "no measurement from C++'s server");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(m.values.len(), 3);
    let acc = client
        .device()
        .as_three_axis_linear_accelerometers()
        .unwrap()
        .get_three_axis_linear_accelerometer_measure(0)
        .unwrap();
    assert_eq!(acc.values.len(), 3);
    client.close().unwrap();
}

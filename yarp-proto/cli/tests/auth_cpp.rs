//! Port authentication (`auth.conf`, C++ `AuthHMAC`) live against C++ YARP 3.12.3: with one
//! key, our programs and C++'s register with each other's name server and exchange data
//! both ways; with another key or none, each side refuses the other; telnet gets no
//! welcome; hostile bytes where the exchange belongs are refused and the server goes on.
//! Run under ../shared/netns-run.

use std::io::{Read, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::Command;
use std::time::Duration;
use yarp_interop_tests::{cpp_command, cpp_program, run_fed, Proc, YarpNet, STEP};

const KEY: &str = "[AUTH]\nkey \"lab secret\"\n";

/// A network whose config dir holds `yarp.conf` (for C++ too) and, with `auth`, an
/// `auth.conf`.
fn net(auth: Option<&str>) -> YarpNet {
    let n = YarpNet::new();
    if let Some(text) = auth {
        std::fs::write(n.dir.path().join("auth.conf"), text).expect("auth.conf");
    }
    std::fs::write(
        n.dir.path().join("yarp.conf"),
        format!("127.0.0.1 {} yarp\n", n.port),
    )
    .expect("yarp.conf");
    n
}

/// The same name server seen with another config dir (another key, or none).
fn beside(n: &YarpNet, auth: Option<&str>) -> YarpNet {
    let other = net(auth);
    std::fs::write(
        other.dir.path().join("yarp.conf"),
        format!("127.0.0.1 {} yarp\n", n.port),
    )
    .expect("yarp.conf");
    other
}

fn cpp(bin: &Path, n: &YarpNet, program: &str) -> Command {
    let mut c = cpp_command(&bin.join(program));
    c.env("YARP_CONFIG_HOME", n.dir.path())
        .env_remove("YARP_NAMESPACE");
    c
}

fn cpp_server(bin: &Path, n: &YarpNet) -> Proc {
    let mut c = cpp(bin, n, "yarpserver");
    c.args([
        "--ip",
        "127.0.0.1",
        "--socket",
        &n.port.to_string(),
        "--read",
    ]);
    let mut p = Proc::spawn("C++ yarpserver", c);
    // With authentication on, C++ yarpserver never gets to print "Ok. Ready!"; it serves.
    p.wait_line("Port /root active", STEP);
    assert!(
        yarp_interop_tests::eventually(STEP, || name_list_ok(cpp(bin, n, "yarp"))),
        "C++ yarpserver never answered C++ yarp with the key"
    );
    p
}

/// Our `yarp read PORT` on network `n`.
fn our_reader(n: &YarpNet, port: &str) -> Proc {
    let mut c = n.yarp();
    c.args(["read", port]);
    Proc::spawn("our yarp read", c)
}

fn succeeds(mut c: Command) -> bool {
    c.output().is_ok_and(|o| o.status.success())
}

fn name_list_ok(c: Command) -> bool {
    let mut c = c;
    c.args(["name", "list"]);
    succeeds(c)
}

#[test]
fn one_key_connects_cpp_and_ours_another_or_none_is_refused() {
    let Some(yarp) = cpp_program("auth_cpp", "yarp") else {
        return;
    };
    let bin = yarp.parent().expect("bin").to_path_buf();
    let n = net(Some(KEY));
    let _server = cpp_server(&bin, &n);

    // Ours registers with the authenticated C++ name server, and C++ writes to it.
    let mut reader = our_reader(&n, "/auth/r");
    assert!(n.wait_registered("/auth/r") > 0);
    let mut c = cpp(&bin, &n, "yarp");
    c.args(["write", "/auth/w", "/auth/r"]);
    run_fed("C++ yarp write", c, "hello 42\n", STEP);
    reader.wait_line("hello 42", STEP);

    // C++ reads what ours writes.
    let mut cpp_reader = Proc::spawn("C++ yarp read", {
        let mut c = cpp(&bin, &n, "yarp");
        c.args(["read", "/auth/cr"]);
        c
    });
    n.wait_registered("/auth/cr");
    let mut c = n.yarp();
    c.args(["write", "/auth/w2", "/auth/cr"]);
    run_fed("our yarp write", c, "from rust\n", STEP);
    cpp_reader.wait_line("from rust", STEP);

    // Another key, or none: the C++ name server refuses ours, and our port refuses C++.
    let wrong = beside(&n, Some("[AUTH]\nkey guess\n"));
    let none = beside(&n, None);
    assert!(
        !name_list_ok(wrong.yarp()),
        "a wrong key reached the C++ name server"
    );
    assert!(
        !name_list_ok(none.yarp()),
        "no key reached the C++ name server"
    );
    assert!(name_list_ok(n.yarp()), "the right key must still work");
    let mut c = cpp(&bin, &wrong, "yarp");
    c.args(["write", "/auth/w3", "/auth/r"]);
    run_fed(
        "C++ yarp write, wrong key",
        c,
        "intruder\n",
        Duration::from_secs(15),
    );
    std::thread::sleep(Duration::from_secs(1));
    assert!(
        !reader.drain().iter().any(|l| l.contains("intruder")),
        "a writer with the wrong key delivered"
    );
}

#[test]
fn our_authenticated_server_and_port_refuse_cpp_without_the_key_and_telnet() {
    let Some(yarp) = cpp_program("auth_cpp", "yarp") else {
        return;
    };
    let bin = yarp.parent().expect("bin").to_path_buf();
    let n = net(Some(KEY));
    let _server = n.server();
    let mut reader = our_reader(&n, "/auth2/r");
    let port = n.wait_registered("/auth2/r");

    // C++ with the key uses our name server and port; without it, neither.
    assert!(name_list_ok(cpp(&bin, &n, "yarp")), "C++ with the key");
    let wrong = beside(&n, Some("[AUTH]\nkey guess\n"));
    assert!(
        !name_list_ok(cpp(&bin, &wrong, "yarp")),
        "C++ with a wrong key"
    );
    let mut c = cpp(&bin, &n, "yarp");
    c.args(["write", "/auth2/w", "/auth2/r"]);
    run_fed("C++ yarp write", c, "with the key\n", STEP);
    reader.wait_line("with the key", STEP);

    // telnet: the port speaks first (the exchange's 40 bytes), never a welcome.
    let mut s = TcpStream::connect(("127.0.0.1", port)).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    s.write_all(b"CONNECT foo\r\n").unwrap();
    let mut got = Vec::new();
    let _ = s.read_to_end(&mut got);
    assert!(got.len() >= 40, "the exchange's first message: {got:?}");
    assert!(
        !String::from_utf8_lossy(&got).contains("Welcome"),
        "telnet was welcomed"
    );

    // Hostile: a forged answer to the server, then silence, then a peer that leaves.
    for bytes in [&[0u8; 40][..], b"NAME_SER", b""] {
        let mut s = TcpStream::connect(("127.0.0.1", n.port)).expect("connect");
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        let mut first = [0u8; 40];
        s.read_exact(&mut first)
            .expect("the server's first message");
        let _ = s.write_all(bytes);
        let mut rest = Vec::new();
        let _ = s.read_to_end(&mut rest);
        assert!(
            rest.is_empty(),
            "the server answered {bytes:?} with {rest:?}"
        );
    }
    assert!(
        name_list_ok(n.yarp()),
        "our name server still serves after the probes"
    );
}

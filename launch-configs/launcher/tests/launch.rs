//! End-to-end tests of `yarp-launch` with real child processes (`yarpserver`, `yarp read`,
//! `yarp write`, shell scripts). Run under `../shared/netns-run`; every child is reaped.

mod common;

use common::*;
use std::time::Duration;

const UP: Duration = Duration::from_secs(40);
const STOP: Duration = Duration::from_secs(30);

fn module_pids(status: &serde_json::Value) -> Vec<i32> {
    status["modules"]
        .as_array()
        .expect("modules")
        .iter()
        .filter_map(|m| m["pid"].as_i64())
        .map(|p| p as i32)
        .collect()
}

#[test]
fn demo_starts_connects_serves_and_stops_in_reverse_order() {
    let demo = configs_dir().join("demo.toml");
    let mut l = Launch::start(&demo, &["--dashboard", "127.0.0.1:0"]);
    let url = l.dashboard_url();
    l.wait_line("demo is up in", UP);
    l.wait_line("Ctrl-C here stops everything", UP);
    let hints = l.drain().join("\n");
    assert!(hints.contains("yarp read /me /demo/writer"), "{hints}");
    assert!(hints.contains(&format!("open {url}")), "{hints}");

    // The launcher's view: three modules ready, the connection made.
    let status = get_json(&format!("{url}api/status"));
    let states: Vec<(&str, &str)> = status["modules"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| (m["name"].as_str().unwrap(), m["state"].as_str().unwrap()))
        .collect();
    assert_eq!(
        states,
        [
            ("yarpserver", "ready"),
            ("reader", "ready"),
            ("writer", "ready")
        ]
    );
    assert_eq!(status["connections"][0]["connected"], true);
    let pids = module_pids(&status);
    assert_eq!(pids.len(), 3);

    // The port graph, as the name server and the ports' admin replies tell it.
    let graph = get_json(&format!("{url}api/graph"));
    let ports: Vec<&str> = graph["ports"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    for p in ["/demo/reader", "/demo/writer", "/root"] {
        assert!(ports.contains(&p), "{p} missing from {ports:?}");
    }
    let edge = graph["connections"]
        .as_array()
        .unwrap()
        .iter()
        .find(|e| e["from"] == "/demo/writer" && e["to"] == "/demo/reader")
        .unwrap_or_else(|| panic!("no writer->reader edge in {graph}"));
    assert_eq!(edge["carrier"], "tcp");
    let (code, svg) = http_get(&format!("{url}api/graph.svg"));
    assert_eq!(code, 200);
    let svg = String::from_utf8(svg).unwrap();
    assert!(svg.contains(r#"data-port="/demo/writer""#), "{svg}");

    // Live plot samples of the writer's numbers (two series: sine and cosine).
    let plot = eventually(Duration::from_secs(15), || {
        let p = get_json(&format!("{url}api/plot"));
        (p["t"].as_array().map_or(0, Vec::len) >= 5).then_some(p)
    })
    .expect("plot samples");
    assert_eq!(plot["series"].as_array().unwrap().len(), 2, "{plot}");
    let (code, _) = http_get(&format!("{url}api/camera.png"));
    assert_eq!(code, 404, "no camera configured");
    let bridge = get_json(&format!("{url}api/bridge"));
    assert_eq!(bridge["rows"].as_array().unwrap().len(), 0);

    // The reader prints what the writer sends, prefixed with its module name.
    l.wait_line("[reader] ", Duration::from_secs(10));

    // SIGTERM: everything stops, in reverse order, nothing left behind.
    assert_eq!(l.stop(Signal::SIGTERM, STOP), Some(0));
    let out = l.seen.join("\n");
    let pos = |s: &str| {
        out.find(s)
            .unwrap_or_else(|| panic!("{s:?} not in output:\n{out}"))
    };
    assert!(pos("writer: stopped") < pos("reader: stopped"), "{out}");
    assert!(pos("reader: stopped") < pos("yarpserver: stopped"), "{out}");
    assert!(out.contains("all modules stopped"));
    assert_eq!(wait_gone(&pids, Duration::from_secs(5)), Vec::<i32>::new());
}

#[test]
fn a_module_after_a_disabled_one_still_starts() {
    // as a robot config run against real boards: `--set module.emulator.enabled=false`
    let (_dir, cfg) = write_config(
        "after-disabled.toml",
        r#"
name = "after-disabled"
[[module]]
name = "emulator"
program = "/bin/sh"
args = ["-c", "echo emulating; exec sleep 30"]
[[module]]
name = "robot"
program = "/bin/sh"
args = ["-c", "echo robot up; exec sleep 30"]
after = ["emulator"]
"#,
    );
    let mut l = Launch::start(&cfg, &["--set", "module.emulator.enabled=false"]);
    l.wait_line("[robot] robot up", Duration::from_secs(20));
    assert!(!l.drain().iter().any(|x| x.contains("emulating")));
    assert_eq!(l.stop(Signal::SIGINT, STOP), Some(0));
}

#[test]
fn restart_policy_and_readiness_timeout() {
    let (_dir, cfg) = write_config(
        "restart.toml",
        r#"
name = "restart"
[[module]]
name = "flaky"
program = "/bin/sh"
args = ["-c", "echo flaky run; exit 3"]
restart = "on-failure"
max_restarts = 2
[[module]]
name = "slow"
program = "/bin/sh"
args = ["-c", "echo never ready; exec sleep 30"]
ready = { port = "/never/there", timeout = 1 }
[[module]]
name = "once"
program = "/bin/sh"
args = ["-c", "echo done"]
restart = "on-failure"
"#,
    );
    let mut l = Launch::start(
        &cfg,
        &["--ready-timeout", "20", "--dashboard", "127.0.0.1:0"],
    );
    let url = l.dashboard_url();
    l.wait_line("flaky: gave up after 2 restarts", Duration::from_secs(30));
    l.wait_line("slow: not ready within", Duration::from_secs(30));
    // States settle once the slow module has been stopped.
    let status = eventually(Duration::from_secs(10), || {
        let s = get_json(&format!("{url}api/status"));
        let settled = s["modules"]
            .as_array()
            .unwrap()
            .iter()
            .all(|m| m["state"] != "starting" && m["state"] != "waiting");
        settled.then_some(s)
    })
    .expect("states settle");
    let m = |n: &str| {
        status["modules"]
            .as_array()
            .unwrap()
            .iter()
            .find(|m| m["name"] == n)
            .cloned()
            .unwrap()
    };
    assert_eq!(m("flaky")["state"], "failed");
    assert_eq!(m("flaky")["restarts"], 2);
    assert_eq!(m("slow")["state"], "failed");
    // A clean exit is not a failure: no restart.
    assert_eq!(m("once")["state"], "exited");
    assert_eq!(m("once")["code"], 0);
    assert_eq!(m("once")["restarts"], 0);
    let runs = l
        .drain()
        .iter()
        .filter(|x| x.contains("[flaky] flaky run"))
        .count();
    assert_eq!(runs, 3, "first run + 2 restarts");
    assert_eq!(l.stop(Signal::SIGINT, STOP), Some(0));
}

#[test]
fn stubborn_modules_get_sigterm_then_sigkill() {
    let (_dir, cfg) = write_config(
        "stubborn.toml",
        r#"
[[module]]
name = "deaf-to-int"
program = "/bin/sh"
args = ["-c", "trap 'exit 0' TERM; trap '' INT; echo up; while true; do sleep 0.1; done"]
ready = { log = "up", timeout = 10 }
stop_timeout = 0.5
[[module]]
name = "deaf"
program = "/bin/sh"
# The child shell ignores everything but SIGKILL, and so does its own child.
args = ["-c", "trap '' INT TERM; sh -c \"trap '' INT TERM; sleep 60\" & echo up; wait"]
ready = { log = "up", timeout = 10 }
stop_timeout = 0.5
"#,
    );
    let mut l = Launch::start(&cfg, &["--dashboard", "127.0.0.1:0"]);
    let url = l.dashboard_url();
    l.wait_line("is up in", UP);
    let pids = module_pids(&get_json(&format!("{url}api/status")));
    assert_eq!(pids.len(), 3);
    assert_eq!(l.stop(Signal::SIGINT, STOP), Some(0));
    let out = l.seen.join("\n");
    assert!(out.contains("deaf: stopped (SIGKILL"), "{out}");
    assert!(out.contains("deaf-to-int: stopped (SIGTERM"), "{out}");
    assert!(out.contains("yarpserver: stopped (SIGINT"), "{out}");
    assert_eq!(wait_gone(&pids, Duration::from_secs(5)), Vec::<i32>::new());
}

#[test]
fn yarpmanager_xml_application() {
    let (_dir, cfg) = write_config(
        "app.xml",
        r#"<application>
  <name>xml-demo</name>
  <module><name>yarp</name><parameters>read /app/in</parameters><node>localhost</node></module>
  <module>
    <name>/bin/sh</name>
    <parameters>-c "while true; do echo 1 2 3; sleep 0.1; done | exec ${bin:yarp} write /app/out"</parameters>
    <dependencies><port timeout="10">/app/in</port></dependencies>
  </module>
  <connection><from>/app/out</from><to>/app/in</to><protocol>udp</protocol></connection>
</application>"#,
    );
    let mut l = Launch::start(&cfg, &["--dashboard", "127.0.0.1:0"]);
    let url = l.dashboard_url();
    l.wait_line("connected /app/out -> /app/in (udp)", UP);
    let graph = eventually(Duration::from_secs(10), || {
        let g = get_json(&format!("{url}api/graph"));
        let found = g["connections"]
            .as_array()
            .unwrap()
            .iter()
            .any(|e| e["from"] == "/app/out" && e["to"] == "/app/in" && e["carrier"] == "udp");
        found.then_some(g)
    });
    assert!(graph.is_some(), "no udp edge in the graph");
    l.wait_line("[1-yarp] 1 2 3", Duration::from_secs(10));
    assert_eq!(l.stop(Signal::SIGTERM, STOP), Some(0));
}

#[test]
fn uses_a_running_name_server_and_remakes_lost_connections() {
    // A name server started outside the launcher is used as it is, not replaced.
    let port = free_port();
    let ns = std::process::Command::new(program("yarpserver", "yarp-net"))
        .args([
            "--ip",
            "127.0.0.1",
            "--socket",
            &port.to_string(),
            "--local",
            "--silent",
        ])
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Reaped even if an assertion fails.
    struct Reap(std::process::Child);
    impl Drop for Reap {
        fn drop(&mut self) {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }
    let ns = Reap(ns);
    let listening = eventually(Duration::from_secs(20), || {
        std::net::TcpStream::connect(("127.0.0.1", port)).ok()
    });
    assert!(listening.is_some(), "yarpserver did not start");
    let demo = configs_dir().join("demo.toml");
    let mut l = Launch::start(
        &demo,
        &[
            "--set",
            &format!("name_server.address=127.0.0.1:{port}"),
            "--set",
            "module.writer.restart=always",
        ],
    );
    l.wait_line("using the name server already running", UP);
    l.wait_line("demo is up in", UP);
    // Kill the writer: it is restarted and the connection is made again.
    let line = l.wait_line("writer: started (pid", UP);
    let pid: i32 = line
        .rsplit("pid ")
        .next()
        .and_then(|p| p.trim_end_matches(')').parse().ok())
        .expect("pid");
    nix::sys::signal::killpg(nix::unistd::Pid::from_raw(pid), Signal::SIGKILL).unwrap();
    l.wait_line("writer: restarting", Duration::from_secs(10));
    // The connection is made a second time once the new writer is up.
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    loop {
        let n = l
            .drain()
            .iter()
            .filter(|x| x.contains("connected /demo/writer -> /demo/reader"))
            .count();
        if n >= 2 {
            break;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "{}",
            l.seen.join("\n")
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    assert_eq!(l.stop(Signal::SIGTERM, STOP), Some(0));
    assert!(!l.seen.iter().any(|x| x.contains("yarpserver: stopped")));
    // Still ours to stop.
    assert!(process_alive(ns.0.id() as i32));
}

#[test]
fn bad_configs_fail_fast_with_clear_errors() {
    let (_dir, cfg) = write_config(
        "bad.toml",
        "[[module]]\nname = 'x'\nprogram = 'no-such-program-here'\n",
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_yarp-launch"))
        .arg(&cfg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("program \"no-such-program-here\" not found"),
        "{err}"
    );

    let (_dir2, cfg) = write_config(
        "cycle.toml",
        "[[module]]\nname='a'\nprogram='sh'\nafter=['a']\n",
    );
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_yarp-launch"))
        .arg(&cfg)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cycle"));

    // --check prints the plan without starting anything.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_yarp-launch"))
        .arg(configs_dir().join("demo.toml"))
        .args(["--check", "--set", "prefix=/p"])
        .env("YARP_BIN_DIR", bin_dir())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let plan = String::from_utf8_lossy(&out.stdout);
    assert!(
        plan.contains("connect /p/writer -> /p/reader (tcp)"),
        "{plan}"
    );
    assert!(plan.contains("module writer:"), "{plan}");
}

#[test]
fn a_dashboard_port_in_use_stops_what_was_started() {
    let busy = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = busy.local_addr().unwrap().to_string();
    let mut l = Launch::start(&configs_dir().join("demo.toml"), &["--dashboard", &addr]);
    let code = l.stop_when_exited(Duration::from_secs(30));
    assert_eq!(code, Some(1));
    let out = l.seen.join("\n");
    assert!(out.contains("cannot serve the dashboard"), "{out}");
    assert!(out.contains("yarpserver: stopped"), "{out}");
}

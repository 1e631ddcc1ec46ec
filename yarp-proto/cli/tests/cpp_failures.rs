//! The `yarp` command line's failure paths, live against the C++ `yarp` (3.12.3, from
//! `tests/peers/install-cpp-peers.sh icub`): one row per case (unknown ports, refused or
//! duplicate connections, an absent name server, bad arguments), each run by C++ `yarp`
//! and by ours in the same situation; the exit code and the error lines must be the same,
//! and both must be what the row says C++ does. Run under ../shared/netns-run.
//!
//! Compared: the exit status, and the `[ERROR]`/`[WARNING]` lines of stdout and stderr
//! with the `|component|` tag C++ puts after the level removed (ours names no
//! components). Without the C++ peer the test says SKIPPED loudly; in CI it fails.

use std::io::{Read, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};
use yarp_net::port::Port;

/// Longest a case may run: C++ gives up on an absent name server after a few seconds.
const LIMIT: Duration = Duration::from_secs(30);

/// Where a case runs.
#[derive(Clone, Copy, Debug, PartialEq)]
enum World {
    /// Our name server, with `/fp/w` (an output) connected to `/fp/r`, and `/fp/r2`
    /// connected to nothing.
    Ports,
    /// `yarp.conf` names 127.0.0.1 and a port nobody listens on.
    NoServer,
}

struct Case {
    args: &'static [&'static str],
    world: World,
    /// The exit status C++ gives.
    code: i32,
    /// A fragment of the error lines C++ prints (empty: it prints none).
    says: &'static str,
}

const fn case(args: &'static [&'static str], world: World, code: i32, says: &'static str) -> Case {
    Case {
        args,
        world,
        code,
        says,
    }
}

use World::{NoServer, Ports};

const CASES: &[Case] = &[
    // name
    case(
        &["name", "query", "/fp/none"],
        Ports,
        1,
        "/fp/none not known.",
    ),
    case(
        &["name", "query", "/fp/none"],
        NoServer,
        1,
        "/fp/none not known.",
    ),
    // exists
    case(&["exists", "/fp/none"], Ports, 1, ""),
    case(
        &["exists", "/fp/w", "/fp/none"],
        Ports,
        1,
        "Failure: could not find destination port /fp/none",
    ),
    case(&["exists", "/fp/w", "/fp/r2"], Ports, 1, ""),
    case(&["exists"], Ports, 1, "Please specify a port name"),
    case(
        &["exists", "/a", "/b", "/c", "/d"],
        Ports,
        1,
        "Please specify a port name",
    ),
    case(&["exists", "/fp/none"], NoServer, 1, ""),
    // ping
    case(&["ping"], Ports, 1, "Usage:"),
    case(&["ping", "/fp/none"], Ports, 1, "could not find port"),
    // wait
    case(&["wait"], Ports, 1, "Please specify a single port name"),
    case(
        &["wait", "/a", "/b", "/c"],
        Ports,
        1,
        "Please specify a single port name",
    ),
    // connect
    // C++ lists the name server's persistent connections here (none): exit 0
    case(
        &["connect"],
        Ports,
        0,
        "[get help with 'yarp connect --help']",
    ),
    case(&["connect", "/fp/w"], Ports, 0, ""),
    case(
        &["connect", "/a", "/b", "tcp", "/d"],
        Ports,
        1,
        "two/three arguments",
    ),
    case(
        &["connect", "/fp/none", "/fp/r"],
        Ports,
        1,
        "could not find source port",
    ),
    case(&["connect", "/fp/w", "/fp/none"], Ports, 1, "Failure"),
    case(
        &["connect", "/fp/w", "/fp/r", "nosuchcarrier"],
        Ports,
        1,
        "Failure",
    ),
    case(&["connect", "/fp/w", "/fp/r"], Ports, 0, ""),
    case(&["connect", "/fp/w", "/fp/r"], NoServer, 1, "Failure"),
    // disconnect
    case(
        &["disconnect", "/fp/w"],
        Ports,
        1,
        "Must have two arguments",
    ),
    case(
        &["disconnect", "/a", "/b", "/c"],
        Ports,
        1,
        "Must have two arguments",
    ),
    case(&["disconnect", "/fp/none", "/fp/r"], Ports, 1, "Failure"),
    case(&["disconnect", "/fp/w", "/fp/none"], Ports, 1, "Failure"),
    case(&["disconnect", "/fp/w", "/fp/r2"], Ports, 1, "Failure"),
    // rpc
    case(&["rpc"], Ports, 1, ""),
    case(&["rpc", "/fp/none"], Ports, 1, "Cannot make connection"),
    // read / write
    case(&["read"], Ports, 1, "Usage:"),
    case(&["write"], Ports, 1, "Please supply the port name"),
    // where, with no name server
    case(&["where"], NoServer, 1, ""),
];

/// The C++ and our outcome of one case.
#[derive(Debug, PartialEq)]
struct Outcome {
    code: i32,
    errors: Vec<String>,
}

/// `[ERROR] |yarp.os.Network| text` -> `[ERROR] text`; other lines are dropped.
fn error_lines(text: &str) -> Vec<String> {
    text.lines()
        .map(str::trim_end)
        .filter(|l| l.starts_with("[ERROR]") || l.starts_with("[WARNING]"))
        .map(|l| {
            let (level, rest) = l.split_once(' ').unwrap_or((l, ""));
            let rest = rest.trim_start();
            let rest = match rest.strip_prefix('|') {
                Some(r) => r.split_once("| ").map(|(_, t)| t).unwrap_or(r),
                None => rest,
            };
            format!("{level} {rest}")
        })
        .collect()
}

/// Runs `program args` in `conf_home`; `cpp` adds the C++ peer's environment.
fn run(program: &Path, args: &[&str], conf_home: &Path, cpp: bool) -> Outcome {
    let mut cmd = if cpp {
        yarp_interop_tests::cpp_command(program)
    } else {
        Command::new(program)
    };
    let mut child = cmd
        .args(args)
        .env("YARP_CONFIG_HOME", conf_home)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| panic!("run {}: {e}", program.display()));
    drop(child.stdin.take());
    let collect = |mut r: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            let _ = r.read_to_string(&mut s);
            s
        })
    };
    let out = collect(Box::new(child.stdout.take().unwrap()));
    let err = collect(Box::new(child.stderr.take().unwrap()));
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if start.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "`{} {}` did not finish within {LIMIT:?}",
                program.display(),
                args.join(" ")
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let text = out.join().unwrap() + &err.join().unwrap();
    Outcome {
        code: status.code().unwrap_or(-1),
        errors: error_lines(&text),
    }
}

/// The ports of [`World::Ports`], open for the whole test process.
fn ports() {
    static PORTS: OnceLock<(tokio::runtime::Runtime, Vec<Port>)> = OnceLock::new();
    PORTS.get_or_init(|| {
        yarp_interop_tests::name_server();
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .unwrap();
        let ports = rt.block_on(async {
            let ns = yarp_interop_tests::name_client();
            let w = Port::open("/fp/w", ns.clone()).await.expect("open /fp/w");
            let r = Port::open("/fp/r", ns.clone()).await.expect("open /fp/r");
            let r2 = Port::open("/fp/r2", ns).await.expect("open /fp/r2");
            w.connect("/fp/r", None).await.expect("connect /fp/w /fp/r");
            vec![w, r, r2]
        });
        (rt, ports)
    });
}

/// A `YARP_CONFIG_HOME` whose yarp.conf names a port where no name server listens.
fn no_server_home() -> &'static Path {
    static HOME: OnceLock<std::path::PathBuf> = OnceLock::new();
    HOME.get_or_init(|| {
        let dir = yarp_interop_tests::process_dir("yarp-rs-test-no-server");
        let port = TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let conf = dir.join("yarp.conf");
        std::fs::File::create(conf)
            .and_then(|mut f| writeln!(f, "127.0.0.1 {port} yarp"))
            .unwrap();
        dir
    })
}

#[test]
fn yarp_failure_paths_match_cpp() {
    let Some(cpp) = yarp_interop_tests::cpp_program("yarp_failure_paths_match_cpp", "yarp") else {
        return;
    };
    let ours = PathBuf::from(env!("CARGO_BIN_EXE_yarp"));
    ports();
    let server_home = PathBuf::from(std::env::var_os("YARP_CONFIG_HOME").unwrap());
    let mut table = String::new();
    let mut bad = Vec::new();
    for c in CASES {
        let home = match c.world {
            Ports => server_home.as_path(),
            NoServer => no_server_home(),
        };
        let theirs = run(&cpp, c.args, home, true);
        let mine = run(&ours, c.args, home, false);
        let expected = theirs.code == c.code
            && (c.says.is_empty() && theirs.errors.is_empty()
                || !c.says.is_empty() && theirs.errors.iter().any(|l| l.contains(c.says)));
        let verdict = match (expected, mine == theirs) {
            (true, true) => "ok",
            (false, _) => "C++ DIFFERS FROM ROW",
            (true, false) => "OURS DIFFERS",
        };
        let line = format!(
            "{verdict:20} yarp {:40} {:?} exit {} {:?}\n",
            c.args.join(" "),
            c.world,
            theirs.code,
            theirs.errors
        );
        table.push_str(&line);
        if verdict != "ok" {
            bad.push(format!(
                "{line}      ours: exit {} {:?}",
                mine.code, mine.errors
            ));
        }
    }
    eprintln!("yarp failure paths (C++ `yarp` vs ours):\n{table}");
    assert!(
        bad.is_empty(),
        "{} rows fail:\n{}",
        bad.len(),
        bad.join("\n")
    );
}

//! Driving the C++ peer's programs from a test: `yarp rpc` sessions and `yarpdev`
//! devices registered with this process's name server ([`crate::name_server`]).

use crate::{cpp_command, name_client, Reaped, T};
use std::io::{Read, Write};
use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

/// C++ `yarp rpc <port>` with `input` typed (then end of input): everything it printed
/// on stdout. Panics if it does not finish within 3 [`T`].
pub fn cpp_rpc_output(yarp: &Path, port: &str, input: &str) -> String {
    let mut child = cpp_command(yarp)
        .args(["rpc", port])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn C++ yarp rpc");
    let _ = child.stdin.take().unwrap().write_all(input.as_bytes());
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stdout.read_to_string(&mut s);
        s
    });
    let mut child = Reaped(child);
    let start = Instant::now();
    while child.0.try_wait().expect("try_wait").is_none() {
        assert!(
            start.elapsed() < 3 * T,
            "C++ yarp rpc {port} did not finish"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    reader.join().unwrap_or_default()
}

/// C++ `yarp read <reader> <port>`: the first printed line that `parse` accepts, within
/// 3 [`T`] (panics otherwise); the reader is killed and reaped before this returns.
pub fn cpp_read_until<R>(
    yarp: &Path,
    reader: &str,
    port: &str,
    parse: impl FnMut(&str) -> Option<R>,
) -> R {
    cpp_read(yarp, reader, port, None, parse)
}

/// As [`cpp_read_until`], the connection `port` -> `reader` made with `carrier` (as `yarp
/// connect port reader carrier` does) once the C++ reader is registered.
pub fn cpp_read_over<R>(
    yarp: &Path,
    reader: &str,
    port: &str,
    carrier: &str,
    parse: impl FnMut(&str) -> Option<R>,
) -> R {
    cpp_read(yarp, reader, port, Some(carrier), parse)
}

fn cpp_read<R>(
    yarp: &Path,
    reader: &str,
    port: &str,
    carrier: Option<&str>,
    mut parse: impl FnMut(&str) -> Option<R>,
) -> R {
    use std::io::BufRead;
    let mut cmd = cpp_command(yarp);
    cmd.args(["read", reader]);
    if carrier.is_none() {
        cmd.arg(port);
    }
    let mut child = Reaped(
        cmd.stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("spawn C++ yarp read"),
    );
    let stdout = child.0.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::BufReader::new(stdout)
            .lines()
            .map_while(Result::ok)
        {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let start = Instant::now();
    if let Some(carrier) = carrier {
        while !registered(reader) {
            assert!(
                start.elapsed() < T,
                "C++ yarp read did not register {reader}"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
        let ns = name_client();
        let (from, to, carrier) = (port.to_string(), reader.to_string(), carrier.to_string());
        let (ok, msg) = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .expect("runtime")
            .block_on(async move {
                yarp_net::network::connect(&ns, &from, &to, Some(&carrier))
                    .await
                    .expect("connect")
            });
        assert!(ok, "{port} -> {reader}: {msg}");
    }
    loop {
        let left = (3 * T).saturating_sub(start.elapsed());
        assert!(
            !left.is_zero(),
            "C++ yarp read {port} printed nothing accepted"
        );
        if let Ok(l) = rx.recv_timeout(left.min(Duration::from_millis(200))) {
            if let Some(r) = parse(&l) {
                return r;
            }
        }
    }
}

/// Whether `port` is registered with this process's name server.
pub fn registered(port: &str) -> bool {
    let ns = name_client();
    let port = port.to_string();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    rt.block_on(async move { ns.query(&port).await.ok().flatten().is_some() })
}

/// C++ `yarpdev` of the bin directory `bin` with `args`, returned once `port` is
/// registered (killed and reaped on drop).
pub fn cpp_yarpdev(bin: &Path, args: &[&str], port: &str) -> Reaped {
    name_client();
    // its log goes to a file, shown if the port never comes
    let log = std::env::temp_dir().join(format!(
        "cpp-yarpdev-{}-{}.log",
        std::process::id(),
        port.replace('/', "_")
    ));
    let file = std::fs::File::create(&log).expect("yarpdev log file");
    let child = cpp_command(&bin.join("yarpdev"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(file.try_clone().expect("log file"))
        .stderr(file)
        .spawn()
        .expect("spawn C++ yarpdev");
    let child = Reaped(child);
    let start = Instant::now();
    while !registered(port) {
        if start.elapsed() > T {
            let text = std::fs::read_to_string(&log).unwrap_or_default();
            panic!(
                "C++ yarpdev {} did not register {port}; its log:\n{text}",
                args.join(" ")
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = std::fs::remove_file(&log);
    child
}

//! Driving the C++ peer's programs from a test: `yarp rpc` sessions and `yarpdev`
//! devices registered with this process's name server ([`crate::name_server`]).

use crate::{cpp_command, name_client, Reaped, T};
use std::io::{Read, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::ChildStdin;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;
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

/// The `Response: ...` lines of a C++ `yarp rpc` session, one per call answered.
pub fn rpc_responses(out: &str) -> Vec<String> {
    out.lines()
        .filter_map(|l| l.strip_prefix("Response: "))
        .map(str::to_string)
        .collect()
}

/// The same `yarp rpc` session (`calls`, one per line) at `ours` and at C++'s `theirs`
/// answers alike, row by row (the table goes to stderr; panics naming the rows that
/// differ).
pub fn assert_same_rpc_session(yarp: &Path, calls: &[&str], ours: &str, theirs: &str) {
    let input: String = calls.iter().map(|t| format!("{t}\n")).collect();
    let over_ours = rpc_responses(&cpp_rpc_output(yarp, ours, &input));
    let over_cpp = rpc_responses(&cpp_rpc_output(yarp, theirs, &input));
    let mut bad = Vec::new();
    for ((call, o), c) in calls.iter().zip(&over_ours).zip(&over_cpp) {
        let verdict = if o == c { "ok" } else { "DIFFERS" };
        eprintln!("{verdict:7} {call:32} {o}   | C++: {c}");
        if o != c {
            bad.push(format!("`{call}`: over ours {o:?}, over C++ {c:?}"));
        }
    }
    assert_eq!(over_cpp.len(), calls.len(), "C++ reference: {over_cpp:#?}");
    assert_eq!(over_ours.len(), calls.len(), "over ours: {over_ours:#?}");
    assert!(
        bad.is_empty(),
        "{} rows differ:\n{}",
        bad.len(),
        bad.join("\n")
    );
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
        // C++ registers a port's name before its socket listens: a refused connection
        // right after registration is retried
        let (ok, msg) = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .expect("runtime")
            .block_on(async move {
                loop {
                    match yarp_net::network::connect(&ns, &from, &to, Some(&carrier)).await {
                        // our port saying it could not reach the reader: the same race
                        Ok((false, msg)) if start.elapsed() < T => {
                            eprintln!("connect {from} -> {to}: {msg}; retrying");
                            tokio::time::sleep(Duration::from_millis(50)).await;
                        }
                        Ok(done) => break done,
                        Err(e) if start.elapsed() < T => {
                            eprintln!("connect {from} -> {to}: {e}; retrying");
                            tokio::time::sleep(Duration::from_millis(50)).await;
                        }
                        Err(e) => panic!("connect {from} -> {to}: {e}"),
                    }
                }
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

/// The command that serves the device C++ `yarpdev` `args` name, with the C++ peer of
/// `bin`. `yarpdev --device W --subdevice D` (a wrapper over a device it opens) is gone
/// from C++ YARP 3.12 (it points to `deviceBundler`, which the peer of
/// `tests/peers/install-cpp-peers.sh icub` does not build): such `args` become a C++
/// `yarprobotinterface` configuration that opens D, then W attached to it, both with every
/// parameter of `args` (as the old `--subdevice` passed its whole configuration to both).
/// The configuration file (returned, to remove once the device is up) is read at start.
pub fn cpp_device_command(bin: &Path, args: &[&str]) -> (Command, Option<PathBuf>) {
    let Some(xml) = bundle_xml(args) else {
        let mut cmd = cpp_command(&bin.join("yarpdev"));
        cmd.args(args);
        return (cmd, None);
    };
    static N: AtomicUsize = AtomicUsize::new(0);
    let file = std::env::temp_dir().join(format!(
        "cpp-bundle-{}-{}.xml",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::write(&file, xml).expect("write the yarprobotinterface configuration");
    let mut cmd = cpp_command(&bin.join("yarprobotinterface"));
    cmd.arg("--config").arg(&file);
    (cmd, Some(file))
}

/// The `yarprobotinterface` configuration for `yarpdev` `args` holding `--device W
/// --subdevice D`, or `None` for a plain device. `--G::k v` is `k` in group `G`.
fn bundle_xml(args: &[&str]) -> Option<String> {
    let mut params: Vec<(String, String)> = Vec::new();
    let (mut wrapper, mut attached) = (None, None);
    let mut it = args.iter().peekable();
    while let Some(a) = it.next() {
        let Some(key) = a.strip_prefix("--") else {
            continue;
        };
        let value = match it.peek() {
            Some(v) if !v.starts_with("--") => it.next().unwrap().to_string(),
            _ => "true".to_string(),
        };
        match key {
            "device" => wrapper = Some(value),
            "subdevice" => attached = Some(value),
            _ => params.push((key.to_string(), value)),
        }
    }
    let (wrapper, attached) = (wrapper?, attached?);
    let esc = |t: &str| {
        t.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    let mut body = String::new();
    let mut groups: Vec<(String, Vec<(String, String)>)> = Vec::new();
    for (k, v) in &params {
        match k.split_once("::") {
            Some((g, k)) => match groups.iter_mut().find(|(name, _)| name == g) {
                Some((_, ps)) => ps.push((k.to_string(), v.clone())),
                None => groups.push((g.to_string(), vec![(k.to_string(), v.clone())])),
            },
            None => body.push_str(&format!(
                "      <param name=\"{}\">{}</param>\n",
                esc(k),
                esc(v)
            )),
        }
    }
    for (g, ps) in &groups {
        body.push_str(&format!("      <group name=\"{}\">\n", esc(g)));
        for (k, v) in ps {
            body.push_str(&format!(
                "        <param name=\"{}\">{}</param>\n",
                esc(k),
                esc(v)
            ));
        }
        body.push_str("      </group>\n");
    }
    // a port prefix of its own: two of these in one test must not clash
    static N: AtomicUsize = AtomicUsize::new(0);
    let prefix = format!(
        "/cppbundle{}_{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    );
    Some(format!(
        r#"<?xml version="1.0" encoding="UTF-8" ?>
<!DOCTYPE robot PUBLIC "-//YARP//DTD yarprobotinterface 3.0//EN" "http://www.yarp.it/DTD/yarprobotinterfaceV3.0.dtd">
<robot name="bundle" build="1" portprefix="{prefix}">
  <devices>
    <device name="attached" type="{attached}">
{body}    </device>
    <device name="wrapper" type="{wrapper}">
{body}      <action phase="startup" level="5" type="attach">
        <param name="device">attached</param>
      </action>
      <action phase="interrupt1" level="1" type="detach"/>
    </device>
  </devices>
</robot>
"#,
        attached = esc(&attached),
        wrapper = esc(&wrapper),
    ))
}

/// C++ `yarpdev` of the bin directory `bin` with `args` (through
/// [`cpp_device_command`]: a wrapper over a `--subdevice` runs in C++
/// `yarprobotinterface`), returned once `port` is registered (killed and reaped on drop).
pub fn cpp_yarpdev(bin: &Path, args: &[&str], port: &str) -> Reaped {
    name_client();
    // its log goes to a file, shown if the port never comes
    let log = std::env::temp_dir().join(format!(
        "cpp-yarpdev-{}-{}.log",
        std::process::id(),
        port.replace('/', "_")
    ));
    let file = std::fs::File::create(&log).expect("yarpdev log file");
    let (mut cmd, xml) = cpp_device_command(bin, args);
    let child = cmd
        .stdin(Stdio::null())
        .stdout(file.try_clone().expect("log file"))
        .stderr(file)
        .spawn()
        .expect("spawn C++ yarpdev");
    let child = Reaped(child);
    let start = Instant::now();
    // a wrapper in yarprobotinterface registers its ports when it opens, before it is
    // attached: wait for the end of the startup phase too
    let ready = || {
        registered(port)
            && (xml.is_none()
                || std::fs::read_to_string(&log)
                    .is_ok_and(|t| t.contains("startup phase finished")))
    };
    while !ready() {
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
    if let Some(xml) = xml {
        let _ = std::fs::remove_file(xml);
    }
    child
}

/// Starts, once per test process, the C++ `yarpserver` of `bin` on 127.0.0.1, announced by
/// a private `yarp.conf` (`YARP_CONFIG_HOME`, so our devices and the C++ programs both use
/// it). A test process uses one name server: the first call's.
pub fn cpp_yarpserver(bin: &Path) {
    static SERVER: OnceLock<(Reaped, ChildStdin)> = OnceLock::new();
    SERVER.get_or_init(|| {
        let dir = crate::process_dir("yarp-rs-test-cpp-conf");
        std::env::set_var("YARP_CONFIG_HOME", &dir);
        // Below the ephemeral range: yarpserver hands out numbers from its own port up,
        // and an ephemeral one collides with outgoing connections (C++ yarpdev then fails
        // to open its ports and never registers).
        let port = crate::low_ports()
            .find(|p| TcpListener::bind(("127.0.0.1", *p)).is_ok())
            .expect("a free port below the ephemeral range");
        std::fs::File::create(dir.join("yarp.conf"))
            .and_then(|mut f| writeln!(f, "127.0.0.1 {port} yarp"))
            .unwrap();
        let mut cmd = cpp_command(&bin.join("yarpserver"));
        cmd.args(["--ip", "127.0.0.1", "--socket", &port.to_string(), "--read"])
            .env("YARP_CONFIG_HOME", &dir);
        // Kept in a static for every test of this process: tied to the process, so it
        // does not outlive it.
        let (server, tie) = crate::spawn_tied_to_process(&cmd).expect("spawn C++ yarpserver");
        let start = Instant::now();
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(start.elapsed() < T, "C++ yarpserver did not listen");
            std::thread::sleep(Duration::from_millis(20));
        }
        (server, tie)
    });
}

/// A C++ test program built once (cached by its sources and the peer) against the C++ YARP
/// of `$YARP_CPP_BIN`: `sources` compiled with `include_dirs` and linked to YARP's
/// `libs`. `None` after [`crate::peer_missing`] when the peer is absent. With it, the
/// program's run environment: `LD_LIBRARY_PATH` and the plugin directories
/// ([`cpp_program_command`]).
pub fn build_cpp_program(
    test: &str,
    name: &str,
    sources: &[PathBuf],
    include_dirs: &[PathBuf],
    libs: &[&str],
) -> Option<PathBuf> {
    let Some(bin) = crate::cpp_bin_dir() else {
        crate::peer_missing(
            test,
            "C++ YARP with icub-main",
            "no YARP_CPP_BIN",
            crate::CPP_YARP_INSTALL,
        );
        return None;
    };
    let prefix = std::fs::canonicalize(bin).ok()?.parent()?.to_path_buf();
    let mut text = prefix.to_string_lossy().as_bytes().to_vec();
    for s in sources {
        text.extend(std::fs::read(s).unwrap_or_else(|e| panic!("{}: {e}", s.display())));
    }
    let stamp = text.iter().fold(0xcbf29ce484222325u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x100000001b3)
    });
    let dir = std::env::temp_dir().join("yarp-rs-cpp-programs");
    std::fs::create_dir_all(&dir).ok()?;
    let out = dir.join(format!("{name}-{stamp:x}"));
    if !out.is_file() {
        let tmp = dir.join(format!("{name}-{stamp:x}.{}", std::process::id()));
        let mut cmd = Command::new("g++");
        cmd.args(["-std=c++17", "-O1", "-o"])
            .arg(&tmp)
            .args(sources);
        for d in include_dirs
            .iter()
            .chain(std::iter::once(&prefix.join("include")))
        {
            cmd.arg(format!("-I{}", d.display()));
        }
        cmd.arg(format!("-L{}", prefix.join("lib").display()));
        for l in libs {
            cmd.arg(format!("-l{l}"));
        }
        let st = cmd.status().expect("g++");
        assert!(st.success(), "{test}: building {name} failed");
        std::fs::rename(&tmp, &out).ok()?;
    }
    Some(out)
}

/// A command running a program of [`build_cpp_program`] with the C++ peer's libraries and
/// plugins (`LD_LIBRARY_PATH`, `YARP_DATA_DIRS`).
pub fn cpp_program_command(program: &Path) -> Command {
    let mut cmd = Command::new(program);
    if let Some(prefix) = crate::cpp_bin_dir()
        .and_then(|b| std::fs::canonicalize(b).ok())
        .and_then(|b| b.parent().map(Path::to_path_buf))
    {
        cmd.env("LD_LIBRARY_PATH", prefix.join("lib")).env(
            "YARP_DATA_DIRS",
            format!(
                "{}:{}",
                prefix.join("share/yarp").display(),
                prefix.join("share/iCub").display()
            ),
        );
    }
    cmd
}

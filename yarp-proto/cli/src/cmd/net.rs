//! The networking subcommands of `yarp`, with C++ YARP's arguments and output formats.

use anyhow::{anyhow, bail, Context, Result};
use std::io::{BufRead, Write};
use std::time::Duration;
use yarp_net::network;
use yarp_net::port::Port;
use yarp_net::rpc::RpcClient;
use yarp_proto::wire::Carrier;
use yarp_proto::{Bottle, Value};

fn runtime() -> Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting the async runtime")
}

/// Resolves when the user asks us to stop (Ctrl-C or SIGTERM).
async fn stop_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{signal, SignalKind};
        if let Ok(mut term) = signal(SignalKind::terminate()) {
            tokio::select! {
                _ = tokio::signal::ctrl_c() => {}
                _ = term.recv() => {}
            }
            return;
        }
    }
    let _ = tokio::signal::ctrl_c().await;
}

fn info(msg: &str) {
    println!("[INFO] |yarp.os.Network| {msg}");
}

/// A failure already reported to the user (in C++'s words): `yarp` exits 1 and says no
/// more.
#[derive(Debug)]
pub struct Reported;

impl std::fmt::Display for Reported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("reported")
    }
}

impl std::error::Error for Reported {}

/// Prints `lines` as C++ `yarp` prints its errors (`[ERROR] ...` on stderr) and gives the
/// error that makes `yarp` exit 1.
fn cpp_error<S: AsRef<str>>(lines: &[S]) -> anyhow::Error {
    let mut e = std::io::stderr().lock();
    for l in lines {
        let _ = writeln!(e, "[ERROR] {}", l.as_ref());
    }
    anyhow::Error::new(Reported)
}

/// Stdin lines, read on a thread of their own so that the async side can also watch
/// ports and signals; the channel closes at end of input.
fn stdin_lines() -> tokio::sync::mpsc::Receiver<String> {
    let (tx, rx) = tokio::sync::mpsc::channel::<String>(16);
    std::thread::spawn(move || {
        for line in std::io::stdin().lock().lines() {
            let Ok(line) = line else { break };
            if tx.blocking_send(line).is_err() {
                break;
            }
        }
    });
    rx
}

/// How `yarp read` shows a message's envelope.
#[derive(Clone, Copy, PartialEq)]
enum ShowEnvelope {
    No,
    /// `envelope`: `<envelope>     <data>` on one line.
    Inline,
    /// `envelope2`: the envelope on a line of its own, then the data.
    TwoLines,
}

/// `yarp read <port> [remote port] [envelope|envelope2] [trim [length]] [once]`, as
/// C++ 3.12.3 parses it: `trim` cuts every printed line to `length` (80 when no number
/// follows), `once` exits after the first message, any other word is a port to read from.
pub fn read(args: &[String]) -> Result<()> {
    let Some((port, rest)) = args.split_first() else {
        return Err(cpp_error(&[
            "Usage:",
            "  yarp read <port> [remote port] [envelope] [trim [length]] [once]",
        ]));
    };
    let mut envelope = ShowEnvelope::No;
    let mut trim = usize::MAX;
    let mut once = false;
    let mut sources: Vec<&String> = Vec::new();
    let mut words = rest.iter();
    while let Some(w) = words.next() {
        match w.as_str() {
            "envelope" => envelope = ShowEnvelope::Inline,
            "envelope2" => envelope = ShowEnvelope::TwoLines,
            // C++ takes the next word as the length whatever it is (atoi: 0 if no number)
            "trim" => trim = words.next().map_or(80, |n| atoi(n).max(0) as usize),
            "once" => once = true,
            _ => sources.push(w),
        }
    }
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        let p = Port::open(port, ns.clone()).await?;
        for s in sources {
            let (ok, msg) = network::connect(&ns, s, port, None).await?;
            if !ok {
                bail!("cannot connect {s} to {port}: {}", msg.trim_end());
            }
        }
        let stdout = std::io::stdout();
        loop {
            tokio::select! {
                _ = stop_signal() => break,
                m = p.read() => {
                    let Some(m) = m else { break };
                    let text = match m.bottle() {
                        Ok(b) => String::from_utf8_lossy(&b.to_text()).into_owned(),
                        Err(e) => { eprintln!("yarp: undecodable message from {}: {e}", m.from); continue }
                    };
                    let text = cut(&text, trim);
                    let env = m.stamp.map(|s| format!("{} {:.4}", s.count, s.time)).unwrap_or_default();
                    let mut out = stdout.lock();
                    // C++ 3.12.3 prints `<envelope>     <data>`, the five spaces even
                    // when the message has no envelope
                    let _ = match envelope {
                        ShowEnvelope::No => writeln!(out, "{text}"),
                        ShowEnvelope::Inline => writeln!(out, "{env}     {text}"),
                        ShowEnvelope::TwoLines => writeln!(out, "{env}\n{text}"),
                    };
                    let _ = out.flush();
                    if once {
                        break;
                    }
                }
            }
        }
        p.close().await;
        Ok(())
    })
}

/// C's `atoi`: the leading integer of `s` (after spaces), 0 when there is none.
fn atoi(s: &str) -> i64 {
    let t = s.trim_start();
    let (sign, digits) = match t.strip_prefix('-') {
        Some(r) => (-1, r),
        None => (1, t.strip_prefix('+').unwrap_or(t)),
    };
    let n: String = digits.chars().take_while(char::is_ascii_digit).collect();
    sign * n.parse::<i64>().unwrap_or(0)
}

/// The first `n` bytes of `s` (C++'s `substr(0, n)`), kept on a character boundary.
fn cut(s: &str, n: usize) -> &str {
    if n >= s.len() {
        return s;
    }
    let mut end = n;
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    &s[..end]
}

/// `yarp write <port> [target...] [--period <s>]`: one Bottle per stdin line; with a
/// period, the last line read is written every `<s>` seconds until end of input instead
/// (C++ 3.12.3's writer thread).
pub fn write(args: &[String]) -> Result<()> {
    let Some((port, targets)) = args.split_first() else {
        return Err(cpp_error(&[
            "Usage:",
            "Please supply the port name, and optionally some targets, e.g.",
            "  yarp write <port> [remote port1] [remote port2] [...] [--period <s>]",
            "If the period optional parameter is given, then the message is written periodically",
        ]));
    };
    let mut targets = targets;
    let mut period = 0.0;
    if targets.last().is_some_and(|a| a == "--period") {
        return Err(cpp_error(&["Invalid period value"]));
    }
    if targets.len() >= 2 && targets[targets.len() - 2] == "--period" {
        let pp: f64 = targets[targets.len() - 1].trim().parse().unwrap_or(0.0);
        if pp.is_nan() || pp < 0.0 {
            return Err(cpp_error(&["Invalid period value"]));
        }
        period = pp;
        println!("Message will be published with a period of {period:.6} s");
        targets = &targets[..targets.len() - 2];
    }
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        let p = Port::open(port, ns.clone()).await?;
        for t in targets {
            p.connect(t, None)
                .await
                .with_context(|| format!("connecting {port} to {t}"))?;
        }
        let mut rx = stdin_lines();
        let mut last: Option<Bottle> = None;
        let mut tick = (period > 0.0).then(|| {
            let mut t = tokio::time::interval(Duration::from_secs_f64(period));
            t.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            t
        });
        loop {
            tokio::select! {
                _ = stop_signal() => break,
                line = rx.recv() => {
                    let Some(line) = line else { break };
                    let b = Bottle::from_text(line.trim_end_matches('\r'));
                    // with a period only the periodic writer sends (as C++)
                    if tick.is_some() {
                        last = Some(b);
                    } else {
                        p.write(&b).await;
                    }
                }
                _ = async { tick.as_mut().expect("period").tick().await }, if tick.is_some() => {
                    if let Some(b) = last.as_ref().filter(|b| !b.is_empty()) {
                        p.write(b).await;
                    }
                }
            }
        }
        // let queued messages drain before closing
        tokio::time::sleep(Duration::from_millis(50)).await;
        p.close().await;
        Ok(())
    })
}

/// `yarp readwrite <read-port> <write-port>`: prints what arrives on the first port and
/// writes stdin lines (one Bottle each) from the second.
pub fn readwrite(read_port: &str, write_port: &str) -> Result<()> {
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        let r = Port::open(read_port, ns.clone()).await?;
        let w = Port::open(write_port, ns).await?;
        let mut rx = stdin_lines();
        loop {
            tokio::select! {
                _ = stop_signal() => break,
                line = rx.recv() => {
                    let Some(line) = line else { break };
                    w.write(&Bottle::from_text(line.trim_end_matches('\r'))).await;
                }
                m = r.read() => {
                    let Some(m) = m else { break };
                    match m.bottle() {
                        Ok(b) => println!("{b}"),
                        Err(e) => eprintln!("yarp: undecodable message from {}: {e}", m.from),
                    }
                }
            }
        }
        w.close().await;
        r.close().await;
        Ok(())
    })
}

/// `yarp ping <port>` describes a port (what it is connected to) as the port itself tells
/// it; `yarp ping --time <port>` times connections to it, in C++'s format.
pub fn ping(args: &[String]) -> Result<()> {
    let time = args.iter().any(|a| a == "--time");
    let Some(port) = args.iter().find(|a| !a.starts_with("--")) else {
        return Err(cpp_error(&[
            "Usage:",
            "  yarp ping /port",
            "  yarp ping --time /port",
            "  yarp ping --rate /port",
        ]));
    };
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        let Some(contact) = ns.query(port).await.ok().flatten() else {
            return Err(cpp_error(&["could not find port"]));
        };
        if !time {
            let text = network::admin_text_ack(&contact, "<ping>", &["*"]).await?;
            print!("{}", text.replace("\r\n", "\n"));
            return Ok(());
        }
        println!("Timing communication with {port}...");
        let (mut conn, mut total) = (Vec::new(), Vec::new());
        for i in 1..=10 {
            let t0 = std::time::Instant::now();
            let c = ns
                .query(port)
                .await?
                .ok_or_else(|| anyhow!("{port} disappeared"))?;
            let t1 = std::time::Instant::now();
            network::admin_text_ack(&c, "<ping>", &[]).await?;
            let t2 = std::time::Instant::now();
            conn.push((t2 - t1).as_secs_f64());
            total.push((t2 - t0).as_secs_f64());
            println!("[INFO] |yarp.os.Ping| Ping #{i}:");
            println!(
                "[INFO] |yarp.os.Ping|   {} connection time ({} with name lookup)",
                fmt_secs(conn[conn.len() - 1]),
                fmt_secs(total[total.len() - 1])
            );
            if i > 1 {
                let (m1, s1) = mean_sd(&conn);
                let (m2, s2) = mean_sd(&total);
                println!(
                    "[INFO] |yarp.os.Ping|   {} +/- {} on average ({} +/- {} with name lookup)",
                    fmt_secs(m1),
                    fmt_secs(s1),
                    fmt_secs(m2),
                    fmt_secs(s2)
                );
            }
        }
        Ok(())
    })
}

fn mean_sd(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / n;
    (m, v.sqrt())
}

/// `494.71855 us` / `1.59192 ms`, as C++ Ping prints durations.
fn fmt_secs(s: f64) -> String {
    if s < 1e-3 {
        format!("{:.5} us", s * 1e6)
    } else if s < 1.0 {
        format!("{:.5} ms", s * 1e3)
    } else {
        format!("{s:.5} s")
    }
}

/// Prints an RPC reply as `yarp rpc` does (`Response:` or `Responses:` for `[many]`).
fn print_response(reply: &Bottle) {
    if reply.get(0) == Some(&Value::vocab("many")) {
        println!("Responses:");
        for v in reply.iter().skip(1) {
            println!("  {}", String::from_utf8_lossy(&v.to_text_bare()));
        }
    } else {
        println!("Response: {reply}");
    }
}

/// `yarp rpc <target> [carrier]`: stdin lines are commands, replies printed.
pub fn rpc(args: &[String]) -> Result<()> {
    let (target, carrier) = match args {
        [t] => (t.as_str(), None),
        [t, c] => (t.as_str(), Some(c.as_str())),
        _ => {
            for l in [
                "Usage:",
                "  yarp [admin] rpc </destport>",
                "    Open an RPC client and connect to 'destport'",
            ] {
                println!("[INFO] {l}");
            }
            return Err(anyhow::Error::new(Reported));
        }
    };
    let carrier = match carrier {
        Some(c) => Carrier::from_name(c).ok_or_else(|| anyhow!("unknown carrier {c}"))?,
        None => Carrier::Tcp,
    };
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        let Some(contact) = ns.query(target).await? else {
            return Err(cpp_error(&[
                "Cannot make connection",
                "Alternative method: precede port name with --client",
            ]));
        };
        let mut client = RpcClient::connect(&contact, "anon_rpc", carrier).await?;
        let stdin = std::io::stdin();
        for line in stdin.lock().lines() {
            let line = line?;
            let cmd = Bottle::from_text(line.trim_end_matches('\r'));
            let reply = client.call(&cmd).await?;
            print_response(&reply);
        }
        client.close().await;
        Ok(())
    })
}

/// `yarp rpcserver <port>`: prints each request and answers with the next stdin line.
pub fn rpcserver(port: &str) -> Result<()> {
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        let p = Port::open(port, ns).await?;
        let mut lines = std::io::stdin().lock().lines();
        loop {
            tokio::select! {
                _ = stop_signal() => break,
                m = p.read() => {
                    let Some(mut m) = m else { break };
                    println!("Message: {}", m.bottle().map(|b| b.to_string()).unwrap_or_default());
                    print!("Reply: ");
                    let _ = std::io::stdout().flush();
                    let reply = lines.next().and_then(|l| l.ok()).unwrap_or_default();
                    m.reply(Bottle::from_text(reply));
                }
            }
        }
        p.close().await;
        Ok(())
    })
}

/// `yarp connect <from> <to> [carrier]`
pub fn connect(args: &[String]) -> Result<()> {
    let (from, to, carrier) = match args {
        [f, t] => (f, t, None),
        [f, t, c] => (f, t, Some(c.as_str())),
        // C++ lists the name server's persistent connections (of the port) here: we keep
        // none, so there is nothing to list
        [] => {
            let _ = cpp_error(&["[get help with 'yarp connect --help']"]);
            return Ok(());
        }
        [_] => return Ok(()),
        _ => {
            return Err(cpp_error(&[
                "Currently must have two/three arguments, a sender port and receiver port (and an optional protocol)",
            ]))
        }
    };
    if let Some(c) = carrier {
        // C++ looks up the carrier proper: `fast_tcp+send.portmonitor+...` is fast_tcp with
        // modifiers, which the ports resolve when they connect
        let base = yarp_proto::wire::modifiers::CarrierName::parse(c).base;
        if Carrier::from_name(&base).is_none() {
            unknown_carrier(from, to, c);
            return Err(anyhow::Error::new(Reported));
        }
    }
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        ends_exist(&ns, from, to).await?;
        let (ok, msg) = network::connect(&ns, from, to, carrier).await?;
        if ok {
            info(&format!("Success: {msg}"));
            Ok(())
        } else {
            println!("[ERROR] |yarp.os.Network| Failure: {msg}");
            bail!("connection failed")
        }
    })
}

/// What C++ `yarp connect` prints for a carrier it has no plugin for (its search for a
/// plugin library, then the refusal), line for line.
fn unknown_carrier(from: &str, to: &str, c: &str) {
    let mut e = std::io::stderr().lock();
    let _ = writeln!(
        e,
        "[ERROR] |yarp.os.YarpPluginSettings| Cannot find \"{c}\" plugin (not built in, and no \
         .ini file found for it)Check that YARP_DATA_DIRS leads to at least one directory with \
         plugins/{c}.ini or share/yarp/plugins/{c}.ini in it"
    );
    let _ = writeln!(
        e,
        "[WARNING] |yarp.os.YarpPluginSettings| Cannot load plugin from shared library ()"
    );
    let _ = writeln!(
        e,
        "[WARNING] |yarp.os.YarpPluginSettings| (yarp_{c}: cannot open shared object file: No \
         such file or directory\nyarp_{c}.so: cannot open shared object file: No such file or \
         directory\nlibyarp_{c}.so: cannot open shared object file: No such file or directory)"
    );
    let _ = writeln!(
        e,
        "[ERROR] |yarp.os.Network| Failed to find library support for carrier {c}"
    );
    let _ = writeln!(
        e,
        "[ERROR] |yarp.os.Carriers| Could not find carrier \"{c}\""
    );
    let _ = writeln!(
        e,
        "[ERROR] |yarp.os.Network| Failure: no way to make connection {from}->{c}:/{to}"
    );
}

/// C++'s check before a connection is made, changed or looked for: both ports known.
async fn ends_exist(ns: &yarp_net::nameserver::NameClient, from: &str, to: &str) -> Result<()> {
    if ns.query(from).await.ok().flatten().is_none() {
        return Err(cpp_error(&[format!(
            "Failure: could not find source port {from}"
        )]));
    }
    if ns.query(to).await.ok().flatten().is_none() {
        return Err(cpp_error(&[format!(
            "Failure: could not find destination port {to}"
        )]));
    }
    Ok(())
}

/// `yarp disconnect <from> <to>`
pub fn disconnect(args: &[String]) -> Result<()> {
    let [from, to] = args else {
        return Err(cpp_error(&[
            "Must have two arguments, a sender port and receiver port",
        ]));
    };
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        ends_exist(&ns, from, to).await?;
        if let Some(carrier) = network::connection_carrier(&ns, from, to).await? {
            info(&format!(
                "Connection found between {from} and {to} using carrier {carrier}"
            ));
        }
        let (ok, msg) = network::disconnect(&ns, from, to).await?;
        if ok {
            info(&format!("Success: {msg}"));
            Ok(())
        } else {
            // C++'s words whatever the port said
            Err(cpp_error(&["Failure: no such connection"]))
        }
    })
}

/// `yarp exists <port>` (exit status only) or `yarp exists <from> <to>` (connection).
pub fn exists(args: &[String]) -> Result<bool> {
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        Ok(match args {
            [p] => network::exists(&ns, p).await?,
            // C++ checks for a connection with the given carrier, tcp by default
            [from, to] | [from, to, _] => {
                if ends_exist(&ns, from, to).await.is_err() {
                    return Ok(false);
                }
                let want = args.get(2).map(String::as_str).unwrap_or("tcp");
                match network::connection_carrier(&ns, from, to)
                    .await
                    .unwrap_or(None)
                {
                    Some(c) => {
                        info(&format!(
                            "Connection found between {from} and {to} using carrier {c}"
                        ));
                        if c == want {
                            true
                        } else {
                            info(&format!("No connection from {from} to {to} found"));
                            false
                        }
                    }
                    None => false,
                }
            }
            _ => return Err(cpp_error(&["Please specify a port name"])),
        })
    })
}

/// `yarp wait <port>`: waits until the port exists; `yarp wait <from> <to>`: until
/// the connection exists.
pub fn wait(args: &[String]) -> Result<()> {
    if !(1..=2).contains(&args.len()) {
        return Err(cpp_error(&[
            "Please specify a single port name, or a source and destination port name",
        ]));
    }
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        loop {
            let there = match args {
                [port] => network::exists(&ns, port).await.unwrap_or(false),
                [from, to] => network::connection_carrier(&ns, from, to)
                    .await
                    .ok()
                    .flatten()
                    .is_some(),
                _ => false,
            };
            if there {
                return Ok(());
            }
            tokio::select! {
                _ = stop_signal() => bail!("interrupted"),
                _ = tokio::time::sleep(Duration::from_millis(200)) => {}
            }
        }
    })
}

/// `yarp name <command...>`: a raw name-server command, printed as C++ does.
pub fn name(args: &[String]) -> Result<()> {
    if args.is_empty() {
        bail!("usage: yarp name <command> [args...] (try `yarp name help`)");
    }
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        if let [query, port] = args {
            if query == "query" && ns.query(port).await.ok().flatten().is_none() {
                return Err(cpp_error(&[format!("{port} not known.")]));
            }
        }
        let cmd = args.join(" ");
        let eol = if matches!(args[0].as_str(), "register" | "set") {
            "\r\n"
        } else {
            "\n"
        };
        let reply = ns
            .request(&yarp_proto::wire::name_server_request(&cmd, eol))
            .await?;
        let text = reply.replace("\r\n", "\n");
        match args[0].as_str() {
            "query" | "register" => {
                print!("{}", text.replace("*** end of message\n", ""));
                println!();
            }
            "unregister" => println!("Unregistered name."),
            _ => print!("{text}"),
        }
        Ok(())
    })
}

/// `yarp clean`: unregister ports that no longer answer.
pub fn clean() -> Result<()> {
    runtime()?.block_on(async {
        let ns = network::name_client()?;
        let ports = ns.list(None).await?;
        for c in ports {
            if c.name == "/root" || !c.name.starts_with('/') || c.carrier == "mcast" {
                continue;
            }
            if !network::exists(&ns, &c.name).await.unwrap_or(false) {
                println!("Removing {} (was at {})", c.name, c.to_uri());
                ns.unregister(&c.name).await?;
            }
        }
        Ok(())
    })
}

/// `yarp conf [--clean | <ip> <port>]`
pub fn conf(args: &[String]) -> Result<()> {
    match args {
        [] => println!("{}", network::conf_path().display()),
        [c] if c == "--clean" => {
            let p = network::conf_path();
            let _ = std::fs::remove_file(&p);
            println!("Cleaned {}", p.display());
        }
        [ip, port] => {
            let port: u16 = port.parse().with_context(|| format!("bad port {port}"))?;
            let p = network::write_conf(ip, port)?;
            println!("Configuration stored in file {}", p.display());
        }
        _ => bail!("usage: yarp conf [--clean | <ip> <port>]"),
    }
    Ok(())
}

/// `yarp where`: where yarp.conf says the name server is, and whether it answers.
pub fn where_() -> Result<()> {
    let conf = network::read_conf()?;
    println!(
        "Looking for name server on {}, port number {}",
        conf.host, conf.port
    );
    println!("If there is a long delay, try:\n  yarp conf --clean");
    if !reachable(&conf.host, conf.port) {
        println!("No valid name server found");
        bail!("name server not available");
    }
    println!(
        "Name server /root is available at ip {} port {}",
        conf.host, conf.port
    );
    Ok(())
}

fn reachable(host: &str, port: i32) -> bool {
    format!("{host}:{port}")
        .parse()
        .ok()
        .is_some_and(|a| std::net::TcpStream::connect_timeout(&a, Duration::from_secs(3)).is_ok())
}

/// `yarp detect [--write]`: the name server of yarp.conf if it answers, else one found by
/// multicast on 224.2.1.1 (as C++); `--write` stores what was found in yarp.conf.
pub fn detect(args: &[String]) -> Result<()> {
    let write = args.iter().any(|a| a == "--write");
    let mut found = None;
    if let Ok(conf) = network::read_conf() {
        println!(
            "Checking for name server at ip {} port {}",
            conf.host, conf.port
        );
        println!("If there is a long delay, try:\n  yarp conf --clean");
        if reachable(&conf.host, conf.port) {
            found = Some((conf.host.clone(), conf.port));
        }
    }
    if found.is_none() {
        let port = std::env::var("YARP_PORT_RANGE")
            .ok()
            .and_then(|p| p.trim().parse().ok())
            .unwrap_or(10000u16);
        let env = |k: &str| std::env::var(k).ok();
        let read = |p: &std::path::Path| std::fs::read_to_string(p).ok();
        let space = yarp_proto::nameserver::namespace(&env, &read);
        let c = runtime()?.block_on(async {
            for _ in 0..3 {
                let r = yarp_net::nameserver::fallback::detect(
                    port,
                    &space,
                    std::net::Ipv4Addr::UNSPECIFIED,
                    Duration::from_millis(500),
                )
                .await?;
                if r.is_some() {
                    return Ok::<_, anyhow::Error>(r);
                }
            }
            Ok(None)
        })?;
        found = c.map(|c| (c.host, c.port as i32));
    }
    let Some((host, port)) = found else {
        println!("No valid name server found");
        bail!("name server not found");
    };
    println!("\n=========================================================\n==\n== FOUND");
    println!("== /root is available at ip {host} port {port}");
    println!("== /root can be browsed at http://{host}:{port}/");
    println!("== ");
    if write {
        network::write_conf(&host, port as u16)?;
        println!("== Address saved.");
        println!("== YARP programs will now be able to use the name server.");
        println!("== ");
    }
    println!("=========================================================");
    Ok(())
}

/// `yarp namespace [name]`
pub fn namespace(args: &[String]) -> Result<()> {
    match args {
        [] => {
            let env = |k: &str| std::env::var(k).ok();
            let read = |p: &std::path::Path| std::fs::read_to_string(p).ok();
            println!("{}", yarp_proto::nameserver::namespace(&env, &read));
        }
        [ns] => {
            let env = |k: &str| std::env::var(k).ok();
            let dir = yarp_proto::nameserver::config_home(&env);
            std::fs::create_dir_all(&dir)?;
            let f = dir.join(yarp_proto::nameserver::NAMESPACE_FILENAME);
            std::fs::write(&f, format!("{ns}\n"))?;
            println!("Namespace set to {ns}");
        }
        _ => bail!("usage: yarp namespace [/name]"),
    }
    Ok(())
}

/// `yarp server [yarpserver options]`: the name server, in this process.
pub fn server(args: &[String]) -> Result<()> {
    yarp_net::nameserver::program::main_with_args(args.iter().cloned())
}

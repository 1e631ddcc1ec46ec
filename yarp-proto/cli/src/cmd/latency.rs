//! `yarp latency-test`: the round-trip benchmark of C++ `yarp latency-test`
//! (`Companion.cmdLatencyTest.cpp`), wire-compatible in both roles.
//!
//! * Server (`--server [--server_wait <s>] [--details]`): opens `/latencyTest/server` and
//!   waits for `("start" <payload_size:int32> <use_reply:int32>)`. It then answers every
//!   frame `(<counter:int32> <time:float64>)` with the frame plus a string of
//!   `payload_size - 1` bytes `p`, the time spent appending it (float64) and its own frame
//!   counter (int32): as the RPC reply when `use_reply` is 1, otherwise by writing it on
//!   its output (which the client connected back to itself). `stop` ends a test (the port
//!   is closed and opened again for the next one); `quit` ends the server.
//! * Client (`--client --nframes <n> (--payload_size <b> | --multitest ["(min max)"] |
//!   --customtest "(b1 b2 ...)") [--client_wait <s>] [--protocol <carrier>] [--no-reply]
//!   [--logfile <prefix>] [--details]`): opens `/latencyTest/client`, connects it to the
//!   server (and, without replies, the server back to it), sends `start`, times `n` frames
//!   and sends `stop`. Latency of a frame = (arrival - send time - server copy time), in
//!   ms. Statistics are printed as C++ 3.12.3 prints them, each frame's
//!   `latency copytime bandwidth` is written to `<prefix><size>.txt` and the test's
//!   `size mean stdev bandwidth` to `<prefix>report.txt` (created by the first test of a
//!   run, appended to by the next ones of a `--multitest`/`--customtest`).

use anyhow::{anyhow, bail, Context, Result};
use std::collections::BTreeMap;
use std::time::Duration;
use yarp_net::nameserver::NameClient;
use yarp_net::network;
use yarp_net::port::Port;
use yarp_proto::wire::{Carrier, Framing};
use yarp_proto::{Bottle, Value};

/// The server's port name.
pub const SERVER_PORT: &str = "/latencyTest/server";
/// The client's port name.
pub const CLIENT_PORT: &str = "/latencyTest/client";

const HELP: &[&str] = &[
    "This is yarp latency-test",
    "Syntax for the server:",
    "yarp latency-test --server [--details]",
    "--server_wait <time>",
    " ",
    "Syntax for the client:",
    "yarp latency-test --client [--details]",
    "--nframes <X> --payload_size <Y> --client_wait <Z> [--protocol <protocol>] [--no-reply] [--logfile <filename_prefix>]",
    "--nframes <X> --multitest --client_wait <Z> [--protocol <protocol>] [--no-reply] [--logfile <filename_prefix>]",
    "--nframes <X> --multitest \"(1 400000)\" --client_wait <Z> [--protocol <protocol>] [--no-reply] [--logfile <filename_prefix>]",
    "--nframes <X> --customtest \"(1 40 100 10000)\" --client_wait <Z> [--protocol <protocol>] [--no-reply] [--logfile <filename_prefix>]",
    "Default value for filename_prefix: log_",
];

/// The options as C++ `Property::fromCommand` reads them: `--key [value]`, a value being
/// the next argument unless that starts with `--`; values are parsed as Bottle text.
struct Options(BTreeMap<String, Option<Value>>);

impl Options {
    fn parse(args: &[String]) -> Options {
        let mut map = BTreeMap::new();
        let mut i = 0;
        while i < args.len() {
            let Some(key) = args[i].strip_prefix("--") else {
                i += 1;
                continue;
            };
            let value = match args.get(i + 1) {
                Some(v) if !v.starts_with("--") => {
                    i += 1;
                    Bottle::from_text(v).get(0).cloned()
                }
                _ => None,
            };
            map.insert(key.to_string(), value);
            i += 1;
        }
        Options(map)
    }

    fn check(&self, key: &str) -> bool {
        self.0.contains_key(key)
    }

    fn find(&self, key: &str) -> Option<&Value> {
        self.0.get(key).and_then(Option::as_ref)
    }

    fn f64(&self, key: &str) -> f64 {
        self.find(key).and_then(Value::as_f64).unwrap_or(0.0)
    }

    fn i32(&self, key: &str) -> i32 {
        self.find(key).and_then(Value::as_i32).unwrap_or(0)
    }

    fn string(&self, key: &str) -> Option<String> {
        self.find(key).map(|v| match v.as_bytes() {
            Some(b) => String::from_utf8_lossy(b).into_owned(),
            None => v.to_string(),
        })
    }
}

/// `yarp latency-test ...`
pub fn run(args: &[String]) -> Result<()> {
    let p = Options::parse(args);
    if p.check("help") || args.is_empty() {
        for l in HELP {
            println!("{l}");
        }
        bail!("no test requested");
    }
    let verbose = p.check("details");
    if p.check("server") {
        let wait = p.f64("server_wait");
        return on_worker(server_loop(wait, verbose));
    }
    if !p.check("client") {
        bail!("Missing option. Use --help");
    }
    if !p.check("nframes") {
        bail!("Missing mandatory parameter nframes. See available options with yarp latency-test");
    }
    let cfg = ClientConfig {
        nframes: p.i32("nframes").max(0) as usize,
        wait: if p.check("client_wait") {
            p.f64("client_wait")
        } else {
            0.0
        },
        proto: p.string("protocol").unwrap_or_else(|| "tcp".to_string()),
        no_reply: p.check("no-reply"),
        logfile: p.string("logfile").unwrap_or_else(|| "log_".to_string()),
        verbose,
    };
    let sizes: Vec<i32> = match (
        p.check("payload_size"),
        p.check("multitest"),
        p.check("customtest"),
    ) {
        (true, false, false) => vec![p.i32("payload_size")],
        (false, true, false) => {
            let (min, max) = match p.find("multitest").and_then(Value::as_list) {
                Some(b) if b.len() == 2 => {
                    (b[0].as_f64().unwrap_or(0.0), b[1].as_f64().unwrap_or(0.0))
                }
                _ => (1.0, 800_000_000.0),
            };
            multitest_sizes(min, max)
        }
        (false, false, true) => {
            let mut sizes = Vec::new();
            if let Some(b) = p.find("customtest").and_then(Value::as_list) {
                for v in b.iter() {
                    match v {
                        Value::Int32(n) => sizes.push(*n),
                        _ => eprintln!(
                            "Syntax error. Invalid value for customtest. See available options with yarp latency-test"
                        ),
                    }
                }
            }
            sizes
        }
        _ => bail!("Syntax error. See available options with yarp latency-test"),
    };
    let carrier =
        Carrier::from_name(&cfg.proto).ok_or_else(|| anyhow!("unknown carrier {}", cfg.proto))?;
    if !matches!(
        carrier.spec().framing,
        Framing::Stream | Framing::Text | Framing::Handshake | Framing::Local
    ) || carrier == Carrier::Local
    {
        bail!(
            "carrier {} is not supported by ports in this implementation yet",
            cfg.proto
        );
    }
    on_worker(async move {
        let ns = network::name_client()?;
        for (test_number, size) in sizes.into_iter().enumerate() {
            client(&ns, &cfg, carrier, size, test_number).await?;
        }
        Ok(())
    })
}

/// Runs the test loop as a task of the runtime, not on the main thread: a frame's hops
/// between the loop and the port's tasks then stay on the worker threads.
fn on_worker<F>(fut: F) -> Result<()>
where
    F: std::future::Future<Output = Result<()>> + Send + 'static,
{
    let rt = runtime()?;
    rt.block_on(async { tokio::spawn(fut).await })
        .map_err(|e| anyhow!("test task failed: {e}"))?
}

/// One worker thread (measured best for both small and large frames); the main thread
/// only waits.
fn runtime() -> Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .enable_all()
        .build()
        .context("starting the async runtime")
}

use yarp_proto::stamp::now;

/// The payload sizes of `--multitest`: 1 2 4 8 10 20 40 80 100 ... 800000000, kept
/// within `[min, max]`.
pub fn multitest_sizes(min: f64, max: f64) -> Vec<i32> {
    let mut sizes = Vec::new();
    let mut val: i64 = 1;
    for pot in 1..10u32 {
        for _ in 0..4 {
            if val as f64 >= min && val as f64 <= max {
                sizes.push(val as i32);
            }
            val *= 2;
        }
        val -= val % 10i64.pow(pot);
    }
    sizes
}

async fn open_port(name: &str, ns: &NameClient) -> Result<Port> {
    let p = Port::open(name, ns.clone())
        .await
        .with_context(|| format!("opening {name}"))?;
    println!(
        "[INFO] |yarp.os.Port| Port {name} active at {}",
        p.contact().to_uri()
    );
    Ok(p)
}

/// Resolves on Ctrl-C or SIGTERM.
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

enum ServerEnd {
    Test,
    Quit,
    Error,
    Interrupted,
}

async fn server_loop(wait: f64, verbose: bool) -> Result<()> {
    let ns = network::name_client()?;
    let mut counter = 0usize;
    loop {
        let p = open_port(SERVER_PORT, &ns).await?;
        let end = tokio::select! {
            _ = stop_signal() => ServerEnd::Interrupted,
            end = serve_test(&p, wait, verbose) => end,
        };
        p.close().await;
        match end {
            ServerEnd::Test => println!("Test {counter} complete"),
            ServerEnd::Quit => {
                println!("Test {counter} complete, quitting");
                return Ok(());
            }
            ServerEnd::Error => eprintln!("[ERROR] Test {counter} error"),
            ServerEnd::Interrupted => return Ok(()),
        }
        counter += 1;
    }
}

/// One test, as C++ `server()`.
async fn serve_test(p: &Port, wait: f64, verbose: bool) -> ServerEnd {
    println!("I am the server, now listening to the client for a `start` command");
    let Some(m) = p.read().await else {
        return ServerEnd::Interrupted;
    };
    let start = m.bottle().unwrap_or_default();
    if start.get(0).and_then(Value::as_str) != Some("start") {
        eprintln!("[ERROR] Invalid command received from the client");
        return ServerEnd::Error;
    }
    drop(m);
    let size = start.get(1).and_then(Value::as_i32).unwrap_or(0);
    let use_reply = start.get(2).and_then(Value::as_i32) == Some(1);
    // C++ fills `size - 1` bytes with 'p' and a terminating NUL
    let text = vec![b'p'; (size.max(1) - 1) as usize];
    let payload = Value::String(text);
    println!(
        "Generated a string of {} bytes, as requested by the client ({size})",
        payload.as_bytes().map_or(0, <[u8]>::len) + 1
    );
    if use_reply {
        println!("Replying on the same connection, as requested by the client");
    } else {
        println!("Using a separate connection for replies, as requested by the client");
    }
    let mut frame: i32 = 0;
    loop {
        let Some(mut m) = p.read().await else {
            return ServerEnd::Interrupted;
        };
        let mut b = m.take_bottle().unwrap_or_default();
        if verbose {
            println!("Received: \"{b}\"");
        }
        match b.get(0).and_then(Value::as_str) {
            Some("stop") => return ServerEnd::Test,
            Some("quit") => return ServerEnd::Quit,
            _ => {}
        }
        let t1 = now();
        b.push(payload.clone());
        let t2 = now();
        b.push(t2 - t1);
        b.push(frame);
        if verbose {
            println!("Replying: \"{b}\"");
            println!(
                "This time was required to append the payload: {:.6}",
                t2 - t1
            );
            println!("Sending the frame number: {frame}");
        }
        if use_reply {
            m.reply(b);
        } else {
            drop(m);
            p.write_shared(std::sync::Arc::new(b), None).await;
        }
        if wait > 0.0 {
            tokio::time::sleep(Duration::from_secs_f64(wait)).await;
        }
        frame = frame.wrapping_add(1);
    }
}

struct ClientConfig {
    nframes: usize,
    wait: f64,
    proto: String,
    no_reply: bool,
    logfile: String,
    verbose: bool,
}

/// Summary statistics over the frames' latencies (ms), as C++ computes them
/// (population standard deviation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stats {
    pub mean: f64,
    pub max: f64,
    pub min: f64,
    pub stdev: f64,
}

impl Stats {
    pub fn of(latencies: &[f64]) -> Stats {
        let n = latencies.len() as f64;
        let mean = latencies.iter().sum::<f64>() / n;
        let var = latencies.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / n;
        Stats {
            mean,
            max: latencies.iter().copied().fold(0.0, f64::max),
            min: latencies.iter().copied().fold(f64::INFINITY, f64::min),
            stdev: var.sqrt(),
        }
    }
}

/// The bandwidth (Mb/s) C++ 3.12.3 estimates for `size` bytes in `latency_ms`.
pub fn bandwidth(size: i32, latency_ms: f64) -> f64 {
    f64::from(size) * 8.0 / 1_000_000.0 * 1000.0 / latency_ms
}

/// The summary line C++ 3.12.3 prints after a test.
pub fn summary_line(frames: usize, size: i32, s: &Stats) -> String {
    format!(
        "Processed {frames} frames of {size} bytes, estimated bandwidth {}[Mb/s], average latency {}[ms], max {}[ms], min {}[ms], stdev {}[ms]",
        printf_3f(bandwidth(size, s.mean)),
        printf_3f(s.mean),
        printf_3f(s.max),
        printf_3f(s.min),
        printf_3f(s.stdev)
    )
}

/// `printf("%.3lf")`, including glibc's spelling of infinities and NaN (0/0 is -nan).
fn printf_3f(x: f64) -> String {
    if x.is_nan() {
        "-nan".to_string()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        format!("{x:.3}")
    }
}

/// A double as C++ `std::ostream << double` writes it (`%g`, 6 significant digits).
pub fn ostream_double(x: f64) -> String {
    if x.is_nan() {
        return if x.is_sign_negative() { "-nan" } else { "nan" }.to_string();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.to_string();
    }
    if x == 0.0 {
        return if x.is_sign_negative() { "-0" } else { "0" }.to_string();
    }
    let sci = format!("{x:.5e}");
    let (mantissa, exp) = sci.split_once('e').unwrap_or((&sci, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    if !(-4..6).contains(&exp) {
        let mantissa = strip_zeros(mantissa);
        let sign = if exp < 0 { '-' } else { '+' };
        format!("{mantissa}e{sign}{:02}", exp.abs())
    } else {
        let decimals = (5 - exp) as usize;
        strip_zeros(&format!("{x:.decimals$}")).to_string()
    }
}

fn strip_zeros(s: &str) -> &str {
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.')
    } else {
        s
    }
}

/// One test of `size` bytes, as C++ `client()`.
async fn client(
    ns: &NameClient,
    cfg: &ClientConfig,
    carrier: Carrier,
    size: i32,
    test_number: usize,
) -> Result<()> {
    let p = open_port(CLIENT_PORT, ns).await?;
    let use_reply = carrier.spec().supports_reply && !cfg.no_reply;
    while let Err(e) = p.connect(SERVER_PORT, Some(&cfg.proto)).await {
        if cfg.verbose {
            println!("{e}");
        }
        println!("Waiting for connection..");
        tokio::time::sleep(Duration::from_millis(500)).await;
    }
    if !use_reply {
        while !matches!(
            network::connect(ns, SERVER_PORT, CLIENT_PORT, Some(&cfg.proto)).await,
            Ok((true, _))
        ) {
            println!("Waiting for connection..");
            tokio::time::sleep(Duration::from_millis(500)).await;
        }
    }
    let mut start = Bottle::new();
    start.push("start");
    start.push(size);
    start.push(i32::from(use_reply));
    p.write(&start).await;

    let mut latencies = Vec::with_capacity(cfg.nframes);
    let mut copytimes = Vec::with_capacity(cfg.nframes);
    for frame in 0..cfg.nframes {
        let mut datum = Bottle::new();
        datum.push(frame as i32);
        datum.push(now());
        let reply = if use_reply {
            p.rpc(&datum).await?
        } else {
            p.write(&datum).await;
            let mut m = p.read().await.ok_or_else(|| anyhow!("port closed"))?;
            m.take_bottle()?
        };
        let final_time = now();
        if reply.is_empty() && use_reply {
            bail!(
                "the server answered frame {frame} with an empty reply: servers older than \
                 C++ YARP 3.12 (e.g. 3.5) answer on their output only (use --no-reply), and \
                 a C++ 3.12 server sometimes answers the first frame so (run it again)"
            );
        }
        let sent = reply.get(1).and_then(Value::as_f64).unwrap_or(0.0);
        let received = reply
            .get(2)
            .and_then(Value::as_bytes)
            .map_or(0, <[u8]>::len);
        let copytime = reply.get(3).and_then(Value::as_f64).unwrap_or(0.0);
        let latency = (final_time - sent - copytime) * 1000.0;
        latencies.push(latency);
        copytimes.push(copytime);
        if cfg.verbose {
            println!("Received a payload of {received} bytes");
            println!(
                "latency for frame {frame} is: {:.6} ms",
                (final_time - sent) * 1000.0
            );
        }
        if cfg.wait > 0.0 {
            tokio::time::sleep(Duration::from_secs_f64(cfg.wait)).await;
        }
    }

    let mut stop = Bottle::new();
    stop.push("stop");
    p.write(&stop).await;
    if !use_reply {
        let _ = network::disconnect(ns, SERVER_PORT, CLIENT_PORT).await;
    }
    tokio::time::sleep(Duration::from_millis(500)).await;
    p.close().await;

    let stats = Stats::of(&latencies);
    println!("{}", summary_line(cfg.nframes, size, &stats));
    let filename = format!("{}{size}.txt", cfg.logfile);
    let mut text = String::new();
    for (l, c) in latencies.iter().zip(&copytimes) {
        text.push_str(&format!(
            "{} {} {}\n",
            ostream_double(*l),
            ostream_double(*c),
            ostream_double(bandwidth(size, *l))
        ));
    }
    std::fs::write(&filename, text).with_context(|| format!("writing {filename}"))?;
    println!("Test complete. Data saved to file: {filename}");
    // the report of all tests of the run: C++ creates it for the first, appends after
    let report = format!("{}report.txt", cfg.logfile);
    let line = format!(
        "{size} {} {} {}\n",
        ostream_double(stats.mean),
        ostream_double(stats.stdev),
        ostream_double(bandwidth(size, stats.mean))
    );
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .write(true)
        .append(test_number > 0)
        .truncate(test_number == 0)
        .open(&report)
        .with_context(|| format!("writing {report}"))?;
    std::io::Write::write_all(&mut f, line.as_bytes())
        .with_context(|| format!("writing {report}"))?;
    println!("Report written to file: {report}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn multitest_sequence_matches_cpp() {
        let all = multitest_sizes(1.0, 800_000_000.0);
        assert_eq!(&all[..9], &[1, 2, 4, 8, 10, 20, 40, 80, 100]);
        assert_eq!(*all.last().unwrap(), 800_000_000);
        assert_eq!(all.len(), 36);
        assert_eq!(
            multitest_sizes(1.0, 400_000.0).last().copied(),
            Some(400_000)
        );
    }

    #[test]
    fn ostream_formatting_matches_cpp() {
        assert_eq!(ostream_double(0.141859), "0.141859");
        assert_eq!(ostream_double(9.53674e-07), "9.53674e-07");
        assert_eq!(ostream_double(0.0), "0");
        assert_eq!(ostream_double(0.13113), "0.13113");
        assert_eq!(ostream_double(1234567.0), "1.23457e+06");
        assert_eq!(ostream_double(12.5), "12.5");
        assert_eq!(ostream_double(100000.0), "100000");
    }

    #[test]
    fn options_like_property_from_command() {
        let args: Vec<String> = [
            "--client",
            "--nframes",
            "10",
            "--multitest",
            "(1 400000)",
            "--no-reply",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let p = Options::parse(&args);
        assert!(p.check("client") && p.check("no-reply"));
        assert_eq!(p.i32("nframes"), 10);
        assert_eq!(
            p.find("multitest").and_then(Value::as_list).unwrap().len(),
            2
        );
    }

    #[test]
    fn summary_like_cpp() {
        let s = Stats::of(&[0.1, 0.2, 0.3]);
        assert_eq!(
            summary_line(3, 100, &s),
            "Processed 3 frames of 100 bytes, estimated bandwidth 4.000[Mb/s], average latency 0.200[ms], max 0.300[ms], min 0.100[ms], stdev 0.082[ms]"
        );
    }
}

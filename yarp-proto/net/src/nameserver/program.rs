//! The `yarpserver` program: the YARP name server, with the options and console lines of the C++
//! `yarpserver` 3.12 (`yarp::serversql::Server::run`).
//!
//! * `--ip IP` / `--socket N`: address to serve and advertise (default: the address in
//!   `yarp.conf`, else this machine's address; port `$YARP_PORT_RANGE` or 10000).
//! * `--read`: use the existing `yarp.conf` (fails if it is missing or disagrees);
//!   `--write`: allow overwriting it. Without either, a missing file is written and a
//!   differing one is an error, as in C++.
//! * `--config FILE`: read options (`key value` lines, `--` optional) from a file.
//! * `--portdb`, `--subdb`: accepted and ignored (state is kept in memory only, as with
//!   the C++ default `:memory:`). `--web`, `--no-web-cache`, `--ros`, `--memory`,
//!   `--cautious` are accepted and ignored too (no web pages, no ROS delegation).
//! * `--local`: do not read or write `yarp.conf`. `--silent`: no per-command lines;
//!   `--verbose`: more logging.
//!
//! SIGINT / SIGTERM stop the server cleanly ("closing yarp server").

use std::net::{IpAddr, SocketAddr, TcpListener as StdListener, UdpSocket};
use std::path::Path;

use crate::nameserver::{NameServer, ServerConfig};
use anyhow::{bail, Context, Result};
use clap::Parser;
use yarp_proto::nameserver::{config_file_name, format_conf, parse_conf};

const SERVER: &str = "yarp.serversql.Server";
const CONTAINER: &str = "yarp.serversql.impl.NameServerContainer";

#[derive(Parser, Debug, Default, Clone)]
#[command(
    name = "yarpserver",
    disable_help_flag = true,
    disable_version_flag = true
)]
struct Args {
    #[arg(long)]
    ip: Option<String>,
    #[arg(long)]
    socket: Option<i32>,
    #[arg(long)]
    read: bool,
    #[arg(long)]
    write: bool,
    #[arg(long)]
    config: Option<String>,
    #[arg(long)]
    portdb: Option<String>,
    #[arg(long)]
    subdb: Option<String>,
    #[arg(long)]
    web: Option<String>,
    #[arg(long = "no-web-cache")]
    no_web_cache: bool,
    #[arg(long)]
    ros: bool,
    #[arg(long)]
    memory: bool,
    #[arg(long)]
    cautious: bool,
    #[arg(long)]
    local: bool,
    #[arg(long)]
    silent: bool,
    #[arg(long)]
    verbose: bool,
    #[arg(long)]
    help: bool,
}

fn info(component: &str, msg: &str) {
    println!("[INFO] |{component}| {msg}");
}

fn error(component: &str, msg: &str) {
    eprintln!("[ERROR] |{component}| {msg}");
}

/// Options from a `--config` file: `key value` or `--key value` lines; bare keys are flags.
fn apply_config_file(args: &mut Args, path: &str) -> Result<()> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {path}"))?;
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        let mut it = line.split_whitespace();
        let Some(key) = it.next() else { continue };
        let key = key.trim_start_matches('-');
        let val = it.next().map(str::to_string);
        match key {
            "ip" if args.ip.is_none() => args.ip = val,
            "socket" if args.socket.is_none() => {
                args.socket = val.and_then(|v| v.parse().ok());
            }
            "read" => args.read = true,
            "write" => args.write = true,
            "local" => args.local = true,
            "silent" => args.silent = true,
            "verbose" => args.verbose = true,
            _ => {}
        }
    }
    Ok(())
}

fn env(k: &str) -> Option<String> {
    std::env::var(k).ok()
}

fn read_file(p: &Path) -> Option<String> {
    std::fs::read_to_string(p).ok()
}

/// `NetworkBase::getDefaultPortRange`.
fn default_port() -> i32 {
    env("YARP_PORT_RANGE")
        .map(|s| s.trim().parse::<i32>().unwrap_or(0))
        .filter(|p| *p != 0)
        .unwrap_or(10000)
}

/// This machine's preferred non-loopback IPv4 address, 127.0.0.1 when there is none
/// (`NameConfig::getHostName`, approximated with the address of the default route).
fn host_name() -> String {
    let probe = || -> Option<IpAddr> {
        let s = UdpSocket::bind("0.0.0.0:0").ok()?;
        s.connect("192.0.2.1:9").ok()?;
        Some(s.local_addr().ok()?.ip())
    };
    match probe() {
        Some(ip) if !ip.is_loopback() && !ip.is_unspecified() => ip.to_string(),
        _ => "127.0.0.1".to_string(),
    }
}

/// `NameConfig::isLocalName`: localhost, the host name, or an address of this machine.
fn is_local_name(name: &str) -> bool {
    if name == "localhost" || name == "127.0.0.1" {
        return true;
    }
    if read_file(Path::new("/proc/sys/kernel/hostname")).is_some_and(|h| h.trim() == name) {
        return true;
    }
    match name.parse::<IpAddr>() {
        Ok(ip) => StdListener::bind(SocketAddr::new(ip, 0)).is_ok(),
        Err(_) => false,
    }
}

/// `BootstrapServer::configFileBootstrap`: merge with `yarp.conf`, maybe write it.
fn config_file_bootstrap(
    host: &mut String,
    port: &mut i32,
    required: bool,
    may_edit: bool,
) -> Result<()> {
    let fname = config_file_name(&env, &read_file);
    let prev = read_file(&fname).and_then(|t| parse_conf(&t));
    if prev.is_none() && required {
        eprintln!("Could not read configuration file {}", fname.display());
        bail!("Aborting.");
    }
    if let Some(p) = &prev {
        if host == "..." {
            *host = p.host.clone();
        }
        if *port == 0 {
            *port = p.port;
        }
    }
    if *port == 0 {
        *port = 10000;
    }
    if host == "..." {
        *host = host_name();
    }
    if !required {
        if !is_local_name(host) {
            eprintln!("Overriding non-local address for name server");
            *host = host_name();
        } else {
            let better = host_name();
            let loopback =
                host.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback()) || host == "localhost";
            if loopback && better != *host && better != "127.0.0.1" {
                eprintln!("Overriding loopback address for name server");
                *host = better;
            }
        }
    }
    let changed = prev.as_ref().is_some_and(|p| {
        p.host != *host || p.port != *port || (p.mode != "yarp" && !p.mode.is_empty())
    });
    if changed && !may_edit {
        let p = prev
            .as_ref()
            .map(|p| (p.host.clone(), p.port, p.mode.clone()))
            .unwrap_or_default();
        let f = fname.display();
        eprintln!("PROBLEM: need to change settings in {f}");
        eprintln!(
            "  Current settings: host {} port {} family {}",
            p.0,
            p.1,
            if p.2.is_empty() { "yarp" } else { &p.2 }
        );
        eprintln!("  Desired settings:  host {host} port {port} family yarp");
        eprintln!("Please specify '--write' if it is ok to overwrite current settings, or");
        eprintln!("Please specify '--read' to use the current settings, or");
        eprintln!("delete {f}");
        bail!("Aborting.");
    }
    if changed || prev.is_none() {
        let write = || -> std::io::Result<()> {
            if let Some(dir) = fname.parent() {
                if !dir.as_os_str().is_empty() {
                    std::fs::create_dir_all(dir)?;
                }
            }
            std::fs::write(&fname, format_conf(host, *port, "yarp"))
        };
        if write().is_err() {
            eprintln!("Could not save configuration file {}", fname.display());
        }
    }
    Ok(())
}

async fn shutdown_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{signal, SignalKind};
        match (
            signal(SignalKind::interrupt()),
            signal(SignalKind::terminate()),
        ) {
            (Ok(mut i), Ok(mut t)) => {
                tokio::select! {
                    _ = i.recv() => {}
                    _ = t.recv() => {}
                }
            }
            _ => {
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = tokio::signal::ctrl_c().await;
    }
}

async fn run(mut args: Args) -> Result<()> {
    info(
        SERVER,
        "\n     ==========================\n    | __  __ ___  ____   ____  |\n    | \\ \\/ //   ||  _ \\ |  _ \\ |\n    |  \\  // /| || |/ / | |/ / |\n    |  / // ___ ||  _ \\ |  _/  |\n    | /_//_/  |_||_| \\_\\|_|    |\n    |                          |\n     ==========================",
    );
    info(SERVER, "");
    if args.help {
        info(SERVER, "Welcome to the YARP name server.\n");
        for l in [
            "  --write                  Write IP address and socket on the configuration file.\n",
            "  --config filename.conf   Load options from a file.\n",
            "  --portdb ports.db        Store port information in named database.\n",
            "                           Must not be on an NFS file system.\n",
            "                           Set to :memory: to store in memory (faster).\n",
            "  --subdb subs.db          Store subscription information in named database.\n",
            "                           Must not be on an NFS file system.\n",
            "                           Set to :memory: to store in memory (faster).\n",
            "  --ip IP.AD.DR.ESS        Set IP address of server.\n",
            "  --socket NNNNN           Set port number of server.\n",
            "  --web dir                Serve web resources from given directory.\n",
            "  --no-web-cache           Reload pages from file for each request.\n",
            "  --ros                    Delegate pub/sub to ROS name server.\n",
            "  --silent                 Start in silent mode.\n",
        ] {
            info(SERVER, l);
        }
        return Ok(());
    }
    info(
        SERVER,
        "Call with --help for information on available options\n",
    );
    if let Some(c) = args.config.clone() {
        apply_config_file(&mut args, &c)?;
    }
    if args.memory {
        eprintln!("[WARNING] |{CONTAINER}| The --memory option was given, but that is now a default. Continuing.");
    }
    let portdb = args.portdb.clone().unwrap_or_else(|| ":memory:".into());
    let subdb = args.subdb.clone().unwrap_or_else(|| ":memory:".into());
    info(CONTAINER, &format!("Using port database: {portdb}"));
    info(CONTAINER, &format!("Using subscription database: {subdb}"));
    if portdb != ":memory:" || subdb != ":memory:" {
        eprintln!("[WARNING] |{CONTAINER}| --portdb/--subdb are ignored by this implementation: state is kept in memory only.");
    }
    if args.web.is_some() || args.ros {
        eprintln!("[WARNING] |{CONTAINER}| --web/--ros are ignored by this implementation.");
    }
    let mut host = args.ip.clone().unwrap_or_else(|| "...".into());
    let mut port = args.socket.unwrap_or_else(default_port);
    info(
        CONTAINER,
        &format!(
            "IP address: {}",
            if host == "..." { "default" } else { &host }
        ),
    );
    info(CONTAINER, &format!("Port number: {port}"));
    if args.ip.is_some() || args.socket.is_some() {
        info(
            CONTAINER,
            "Database needs to be reset, IP or port number set.",
        );
    }
    if !args.local {
        if let Err(e) = config_file_bootstrap(&mut host, &mut port, args.read, args.write) {
            error(CONTAINER, &format!("{e}\n"));
            std::process::exit(1);
        }
    } else if host == "..." {
        host = host_name();
    }
    let port16 = u16::try_from(port).context("port number out of range")?;
    let mut config = ServerConfig::new(&host);
    config.advertised_port = Some(port16);
    config.echo_commands = !args.silent;
    let bind_ip: IpAddr = host.parse().unwrap_or(IpAddr::from([0, 0, 0, 0]));
    let server = match NameServer::bind_with(SocketAddr::new(bind_ip, port16), config.clone()).await
    {
        Ok(s) => s,
        Err(_) if !bind_ip.is_unspecified() => {
            NameServer::bind_with(SocketAddr::new(IpAddr::from([0, 0, 0, 0]), port16), config)
                .await?
        }
        Err(e) => {
            error(SERVER, "Name server failed to open\n");
            return Err(e.into());
        }
    };
    info(SERVER, "Registering name server with itself");
    info(
        SERVER,
        &format!("Name server can be browsed at http://{host}:{port}/"),
    );
    info(SERVER, "Ok. Ready!");
    let handle = server.shutdown_handle();
    let task = tokio::spawn(server.serve());
    shutdown_signal().await;
    info(SERVER, "closing yarp server");
    handle.shutdown();
    match task.await {
        Ok(r) => r?,
        Err(e) => bail!("server task failed: {e}"),
    }
    Ok(())
}

/// Runs the name server program with command-line `args` (without the program name);
/// `yarpserver` and `yarp server` both end up here.
pub fn main_with_args<I: IntoIterator<Item = String>>(args: I) -> Result<()> {
    let args = match Args::try_parse_from(std::iter::once("yarpserver".to_string()).chain(args)) {
        Ok(a) => a,
        Err(e) => {
            let _ = e.print();
            bail!("bad arguments");
        }
    };
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("cannot start the runtime")?;
    rt.block_on(run(args))
}

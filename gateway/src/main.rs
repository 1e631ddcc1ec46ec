//! `yarp-ros2-gateway`: bridges YARP ports and RPC to ROS 2 topics and services as the
//! mapping files say (format: `mappings/README.md`).
#![forbid(unsafe_code)]

use anyhow::{bail, Context as _};
use clap::{Parser, Subcommand};
use std::net::{IpAddr, SocketAddr, ToSocketAddrs};
use std::path::PathBuf;
use std::time::Duration;
use yarp_net::nameserver::{NameClient, NameServer};
use yarp_net::network;
use yarp_ros2_gateway::gateway::{Gateway, Options};
use yarp_ros2_gateway::mapping::Mappings;

#[derive(Parser, Debug)]
#[command(
    name = "yarp-ros2-gateway",
    version,
    about,
    subcommand_negates_reqs = true
)]
struct Args {
    #[command(subcommand)]
    command: Option<Command>,
    /// Mapping files (TOML) to load; entry names must be unique across them.
    #[arg(long, num_args = 1.., required = true)]
    mappings: Vec<PathBuf>,
    /// Directories of ROS interface definitions (`.msg`, `.srv`) besides
    /// $AMENT_PREFIX_PATH's: an install prefix, a directory of packages or one package
    /// (repeatable; they take precedence).
    #[arg(long = "interfaces", global = true)]
    interfaces: Vec<PathBuf>,
    /// ROS domain id (default: $ROS_DOMAIN_ID, else 0).
    #[arg(long)]
    domain_id: Option<u16>,
    /// Interface addresses DDS may use (repeatable; default: all, or loopback only when
    /// ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST or ROS_LOCALHOST_ONLY=1). Use 127.0.0.1 to
    /// stay on this machine. ROS arguments (`--ros-args -r __node:=NAME -r __ns:=/NS -r
    /// from:=to -p name:=value --params-file FILE --log-level LEVEL`) may follow.
    #[arg(long = "network")]
    networks: Vec<IpAddr>,
    /// The YARP name server (default: the one in yarp.conf).
    #[arg(long)]
    name_server: Option<String>,
    /// When no name server answers, start one here (host:port) instead of failing.
    #[arg(long, default_value = "127.0.0.1:10000")]
    embedded_name_server: String,
    /// Never start an embedded name server.
    #[arg(long)]
    no_embedded_name_server: bool,
    /// ROS node name and namespace.
    #[arg(long, default_value = "yarp_ros2_gateway")]
    node_name: String,
    #[arg(long, default_value = "/")]
    namespace: String,
    /// Seconds between /diagnostics messages (0 disables them).
    #[arg(long, default_value_t = 1.0)]
    diagnostics_period: f64,
    /// YARP port that carries the same counters as Bottles.
    #[arg(long, default_value = "/yarp_ros2_gateway/diagnostics:o")]
    diagnostics_port: String,
    /// Only load and check the mapping files, print what would be bridged, and exit.
    #[arg(long)]
    check: bool,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Print the Bottle layout of a ROS message type (as the generic conversion reads
    /// and writes it) and an example Bottle, e.g. `show-type nav_msgs/msg/Odometry`.
    ShowType {
        /// `pkg/msg/Type` (or `pkg/Type`).
        ros_type: String,
    },
}

/// `show-type`: the layout of a type, its constants and an example for `yarp write`.
fn show_type(name: &str) -> anyhow::Result<()> {
    use yarp_ros2_gateway::{generic, interfaces, types};
    let full = match name.split('/').collect::<Vec<_>>().as_slice() {
        [p, t] => format!("{p}/msg/{t}"),
        _ => name.to_string(),
    };
    let Some(t) = types::lookup(&full) else {
        match interfaces::problem(&full) {
            Some(p) => bail!("{full}: its definition does not parse: {p}"),
            None => bail!(
                "{full}: unknown type (not built in, and no definition under \
                 $AMENT_PREFIX_PATH or --interfaces)"
            ),
        }
    };
    let source = if interfaces::lookup(&full).is_some() {
        "its definition"
    } else {
        "the built-in catalog"
    };
    println!(
        "{full} (from {source}; hash {})",
        yarp_ros2_gateway::hash::rihs01(&full)?
    );
    println!("Bottle layout (fields in order; nested messages are lists; trailing fields");
    println!("may be left out when writing):");
    print!("{}", generic::layout(t));
    if !t.constants.is_empty() {
        println!("constants:");
        for c in t.constants {
            println!("  {} = {}", c.name, c.value);
        }
    }
    let ex = generic::example(t).map_err(|e| anyhow::anyhow!("{full}: {e}"))?;
    println!("example (for `yarp write`):");
    println!("{ex}");
    Ok(())
}

fn main() -> std::process::ExitCode {
    // `ros2 run`/`ros2 launch` append `--ros-args ...`: ours before, rcl's after.
    let (ours, ros) = yarp_ros2_gateway::ros_args::split(std::env::args_os());
    let mut args = Args::parse_from(ours);
    let ros_args = match yarp_ros2_gateway::ros_args::parse(&ros) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("yarp-ros2-gateway: {e}");
            return std::process::ExitCode::from(2);
        }
    };
    if let Some(n) = &ros_args.node_name {
        args.node_name = n.clone();
    }
    if let Some(ns) = &ros_args.namespace {
        args.namespace = ns.clone();
    }
    let mut params = Vec::new();
    let fqn = format!(
        "{}/{}",
        args.namespace.trim_end_matches('/'),
        args.node_name
    );
    for f in &ros_args.params_files {
        let text = match std::fs::read_to_string(f) {
            Ok(t) => t,
            Err(e) => {
                eprintln!("yarp-ros2-gateway: --params-file {}: {e}", f.display());
                return std::process::ExitCode::from(2);
            }
        };
        match yarp_ros2_gateway::ros_args::params_from_file(&text, &fqn, &f.display().to_string()) {
            Ok(p) => params.extend(p),
            Err(e) => {
                eprintln!("yarp-ros2-gateway: {e}");
                return std::process::ExitCode::from(2);
            }
        }
    }
    // `-p` comes after the files: it wins, as in rcl.
    params.extend(ros_args.params.iter().cloned());
    let log_level = ros_args
        .log_levels
        .iter()
        .rev()
        .find(|(l, _)| l.is_none())
        .map(|(_, level)| level.to_lowercase());
    if let Some(e) = &ros_args.enclave {
        yarp_ros2_gateway::security::set_enclave(e);
    }
    yarp_ros2_gateway::ros::set_ros_args(ros_args, &args.namespace, &args.node_name, params);
    for d in &args.interfaces {
        if yarp_ros2_gateway::interfaces::add_dir(d) == 0 {
            eprintln!(
                "yarp-ros2-gateway: --interfaces {}: no .msg or .srv definitions there",
                d.display()
            );
        }
    }
    if let Some(Command::ShowType { ros_type }) = &args.command {
        return match show_type(ros_type) {
            Ok(()) => std::process::ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("yarp-ros2-gateway: {e:#}");
                std::process::ExitCode::FAILURE
            }
        };
    }
    // RustDDS and ros2-client log many harmless warnings (and errors while a node shuts
    // down); show them only when RUST_LOG asks, e.g. RUST_LOG=info,rustdds=warn. The
    // errors of RustDDS's two threads stay visible: they are the ones that end DDS.
    // `--log-level LEVEL` sets our default level (rcl's names; fatal is error here).
    let level = match log_level.as_deref() {
        Some("debug") => "debug",
        Some("warn") => "warn",
        Some("error") | Some("fatal") => "error",
        _ => "info",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| {
        tracing_subscriber::EnvFilter::new(format!(
            "{level},rustdds=off,rustdds::rtps::dp_event_loop=error,\
             rustdds::discovery::discovery=error,ros2_client=off"
        ))
    });
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .init();
    // Runs for hours: keep glibc's freed pages from piling up in the RSS (set before
    // DDS's threads start allocating).
    yarp_net::heap::for_long_runs();
    let rt = match tokio::runtime::Runtime::new() {
        Ok(rt) => rt,
        Err(e) => {
            eprintln!("yarp-ros2-gateway: cannot start tokio: {e}");
            return std::process::ExitCode::FAILURE;
        }
    };
    match rt.block_on(run(args)) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("yarp-ros2-gateway: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

async fn run(args: Args) -> anyhow::Result<()> {
    let mappings = Mappings::load(&args.mappings)?;
    if args.check {
        for t in &mappings.topics {
            println!(
                "topic   {:<20} {:<10} {}",
                t.name,
                t.direction.to_string(),
                yarp_ros2_gateway::ros::remapped(&t.ros_topic)
            );
        }
        for s in &mappings.services {
            println!(
                "service {:<20} {:<10} {}",
                s.name,
                s.direction.to_string(),
                yarp_ros2_gateway::ros::remapped(&s.ros_service)
            );
        }
        for a in &mappings.actions {
            println!(
                "action  {:<20} {:<10} {}",
                a.name,
                a.direction.to_string(),
                yarp_ros2_gateway::ros::remapped(&a.ros_action)
            );
        }
        for r in &mappings.robots {
            let mut topics = Vec::new();
            if let Some(js) = &r.joint_states {
                topics.push(format!("{} ({})", js.ros_topic, js.parts.join(" ")));
            }
            if let Some(d) = &r.robot_description {
                topics.push(format!("{} ({})", d.ros_topic, d.urdf.display()));
            }
            println!(
                "robot   {:<20} {:<10} {}",
                r.name,
                "yarp->ros",
                topics.join(", ")
            );
        }
        return Ok(());
    }
    let domain_id = match args.domain_id {
        Some(d) => d,
        None => match std::env::var("ROS_DOMAIN_ID") {
            Ok(s) if !s.trim().is_empty() => s
                .trim()
                .parse()
                .with_context(|| format!("ROS_DOMAIN_ID `{s}` is not a number"))?,
            _ => 0,
        },
    };
    let (ns, _embedded) = name_server(&args).await?;
    yarp_ros2_gateway::ros::set_read_only_parameters(settings(&args, domain_id, &ns));
    let opt = Options {
        domain_id,
        // --network, else the ROS environment (ROS_AUTOMATIC_DISCOVERY_RANGE, ROS_LOCALHOST_ONLY)
        networks: if args.networks.is_empty() {
            yarp_ros2_gateway::ros::networks_from_env()
        } else {
            args.networks.clone()
        },
        namespace: args.namespace.clone(),
        node_name: args.node_name.clone(),
        diagnostics_period: (args.diagnostics_period > 0.0)
            .then(|| Duration::from_secs_f64(args.diagnostics_period)),
        diagnostics_port: Some(args.diagnostics_port.clone()),
    };
    let gw = Gateway::start(&mappings, ns.clone(), opt).await?;
    println!(
        "yarp-ros2-gateway: ROS domain {domain_id}, YARP name server {}, {} mapping(s):",
        ns.server(),
        gw.bridges().len()
    );
    print!("{}", gw.table());
    tokio::signal::ctrl_c().await.ok();
    println!("yarp-ros2-gateway: shutting down");
    gw.shutdown().await;
    Ok(())
}

/// The gateway's settings as read-only ROS parameters of its node.
fn settings(
    args: &Args,
    domain_id: u16,
    ns: &yarp_net::nameserver::NameClient,
) -> Vec<(String, ros2_client::ParameterValue)> {
    use ros2_client::ParameterValue as P;
    let paths = |v: &[PathBuf]| P::StringArray(v.iter().map(|p| p.display().to_string()).collect());
    vec![
        ("mappings".into(), paths(&args.mappings)),
        ("interfaces".into(), paths(&args.interfaces)),
        ("domain_id".into(), P::Integer(domain_id.into())),
        (
            "network".into(),
            P::StringArray(args.networks.iter().map(|n| n.to_string()).collect()),
        ),
        (
            "yarp_name_server".into(),
            P::String(ns.server().to_string()),
        ),
        (
            "diagnostics_period".into(),
            P::Double(args.diagnostics_period),
        ),
        (
            "diagnostics_port".into(),
            P::String(args.diagnostics_port.clone()),
        ),
    ]
}

fn resolve(s: &str) -> anyhow::Result<SocketAddr> {
    s.to_socket_addrs()
        .ok()
        .and_then(|mut a| a.next())
        .with_context(|| format!("`{s}` is not host:port"))
}

/// The name server to use: the configured one if it answers, else an embedded one.
async fn name_server(
    args: &Args,
) -> anyhow::Result<(NameClient, Option<tokio::task::JoinHandle<()>>)> {
    let configured = match &args.name_server {
        Some(s) => Some(NameClient::new(resolve(s)?)),
        None => network::name_client().ok(),
    };
    if let Some(ns) = configured {
        let probe = ns.clone().with_timeout(Duration::from_secs(2));
        if probe.list(None).await.is_ok() {
            return Ok((ns, None));
        }
        eprintln!(
            "yarp-ros2-gateway: no YARP name server answers at {}",
            ns.server()
        );
    }
    if args.no_embedded_name_server {
        bail!("no YARP name server reachable (and --no-embedded-name-server)");
    }
    let addr = resolve(&args.embedded_name_server)?;
    let server = NameServer::bind(addr, &addr.ip().to_string())
        .await
        .with_context(|| format!("embedded name server on {addr}"))?;
    let addr = server.local_addr();
    // Other YARP programs find it through yarp.conf; write one only on a first run.
    if network::read_conf().is_err() {
        if let Ok(path) = network::write_conf(&addr.ip().to_string(), addr.port()) {
            eprintln!("yarp-ros2-gateway: wrote {}", path.display());
        }
    }
    eprintln!("yarp-ros2-gateway: embedded YARP name server on {addr}");
    let task = tokio::spawn(async move {
        if let Err(e) = server.serve().await {
            eprintln!("yarp-ros2-gateway: embedded name server stopped: {e}");
        }
    });
    Ok((NameClient::new(addr), Some(task)))
}

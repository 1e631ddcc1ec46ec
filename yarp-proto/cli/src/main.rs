//! `yarp`: the YARP command-line tool, with C++ YARP's subcommand names, arguments and
//! output formats, so scripts written for C++ `yarp` keep working.

mod cmd;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "yarp",
    version,
    about = "YARP command-line tool (Rust implementation)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a name server (same options as `yarpserver`).
    Server {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Read from a port and print what arrives: `yarp read /port [envelope] [/source...]`.
    Read {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Write stdin lines (one Bottle each) to a port: `yarp write /port [/target...]`.
    Write {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Read from one port and write stdin lines to another: `yarp readwrite /in /out`.
    Readwrite {
        read_port: String,
        write_port: String,
    },
    /// Send stdin lines as RPC commands to a port and print the replies:
    /// `yarp rpc /port [carrier]`.
    Rpc {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Serve RPC on a port: print each request and reply with the next stdin line.
    Rpcserver { port: String },
    /// Connect two ports: `yarp connect /from /to [carrier]`.
    Connect {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Remove a connection: `yarp disconnect /from /to`.
    Disconnect {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Send a command to the name server: `yarp name query /port`, `yarp name list` ...
    Name {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Exit status 0 if a port (or a connection `/from /to`) exists, 1 otherwise.
    Exists { args: Vec<String> },
    /// Describe a port, or time connections to it (`--time`).
    Ping {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Wait until a port (or a connection `/from /to`) exists.
    Wait {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Unregister ports that no longer answer.
    Clean,
    /// Show or set where the name server is: `yarp conf [<ip> <port> | --clean]`.
    Conf {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Report where the name server is and whether it answers.
    Where,
    /// Look for the name server (yarp.conf, then multicast) and report it; `--write`
    /// saves it to yarp.conf.
    Detect {
        #[arg(allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Show or set the YARP namespace.
    Namespace { args: Vec<String> },
    /// Bottle debugging aid: convert between YARP text and the binary wire encoding.
    #[command(subcommand)]
    Bottle(cmd::bottle::BottleCommand),
    /// Round-trip latency benchmark, compatible with C++ `yarp latency-test`.
    #[command(disable_help_flag = true)]
    LatencyTest {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Print the version of this YARP implementation.
    Version,
}

fn main() -> ExitCode {
    // Behave like C tools when the reader of our output goes away (`yarp read | head`):
    // end quietly on SIGPIPE instead of panicking on a failed print.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Server { args } => cmd::net::server(&args),
        Command::Read { args } => cmd::net::read(&args),
        Command::Write { args } => cmd::net::write(&args),
        Command::Readwrite {
            read_port,
            write_port,
        } => cmd::net::readwrite(&read_port, &write_port),
        Command::Rpc { args } => cmd::net::rpc(&args),
        Command::Rpcserver { port } => cmd::net::rpcserver(&port),
        Command::Connect { args } => cmd::net::connect(&args),
        Command::Disconnect { args } => cmd::net::disconnect(&args),
        Command::Name { args } => cmd::net::name(&args),
        Command::Exists { args } => match cmd::net::exists(&args) {
            Ok(true) => Ok(()),
            Ok(false) => return ExitCode::FAILURE,
            Err(e) => Err(e),
        },
        Command::Ping { args } => cmd::net::ping(&args),
        Command::Wait { args } => cmd::net::wait(&args),
        Command::Clean => cmd::net::clean(),
        Command::Conf { args } => cmd::net::conf(&args),
        Command::Where => cmd::net::where_(),
        Command::Detect { args } => cmd::net::detect(&args),
        Command::Namespace { args } => cmd::net::namespace(&args),
        Command::Bottle(c) => cmd::bottle::run(c),
        Command::LatencyTest { args } => cmd::latency::run(&args),
        Command::Version => {
            println!("YARP version {} (Rust)", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // already said, in C++'s words
        Err(e) if e.is::<cmd::net::Reported>() => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("yarp: {e:#}");
            ExitCode::FAILURE
        }
    }
}

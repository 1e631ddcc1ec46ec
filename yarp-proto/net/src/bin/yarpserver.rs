//! `yarpserver`: the YARP name server program (see `yarp_net::nameserver::program`).

fn main() -> std::process::ExitCode {
    // Runs for hours: keep glibc's freed pages from piling up in the RSS.
    yarp_net::heap::for_long_runs();
    match yarp_net::nameserver::program::main_with_args(std::env::args().skip(1)) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("yarpserver: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

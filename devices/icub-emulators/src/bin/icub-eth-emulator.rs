//! `icub-eth-emulator ROBOT_DIR [--config FILE.xml] [--address-map FROM/LEN=TO/LEN]
//! [--xsens PATH] [--bno055 PATH] [--record DIR]`: emulates every Ethernet board of a robots-configuration
//! robot directory, each on its own `IpAddress:12345` UDP socket. The address map (also
//! `YARP_ICUB_ETH_ADDRESS_MAP`) serves the robot's addresses elsewhere, e.g.
//! `10.0.1.0/24=127.0.1.0/24` on a laptop without the robot's addresses; the devices must
//! use the same map. `--xsens PATH` also emulates an Xsens MTi (the ergoCub waist IMU,
//! `xsensmt`) on a pseudo-terminal linked at PATH (name it in `YARP_ICUB_XSENS_SERIAL`);
//! `--bno055 PATH` a Bosch BNO055 (the head IMU of `imuBosch_BNO055`, name it in
//! `YARP_BNO055_COMPORT`).
//! `--record DIR` appends every ROP a host sends to a board, from its first datagram on,
//! to `DIR/<board's robot IP>.jsonl`, one JSON object a line (`t` in seconds since the
//! boards began serving, `ropcode`, `id32`, `data` in hex, the frame's `seq`/`age`, the
//! ROP's `ctrl`, `signature`, `time`: see `icub_emulators::eth::record`), flushed after
//! each datagram. SIGINT or SIGTERM stops it (exit 0; the `--xsens`/`--bno055` links are
//! removed).

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use icub_emulators::eth::{robot_boards, serve_with, AddressMap, ServeOptions, ADDRESS_MAP_ENV};

const HELP: &str = "usage: icub-eth-emulator ROBOT_DIR [--config FILE.xml] [--address-map FROM/LEN=TO/LEN] [--xsens PATH] [--bno055 PATH] [--record DIR]

Emulates every Ethernet board of a robots-configuration robot directory, each on its own
IpAddress:IpPort UDP socket (hardware/electronics/*-eln.xml); a board learns its sensors
and running cycle from the host's service configurations, as a real one.

  --config FILE.xml     the robot's top-level file (default: yarprobotinterface.ini's config)
  --address-map MAP     serve the robot's addresses elsewhere, e.g. 10.0.1.0/24=127.0.1.0/24
                        (default: $YARP_ICUB_ETH_ADDRESS_MAP); the devices must use the same
  --xsens PATH          also emulate an Xsens MTi on a pseudo-terminal linked at PATH
  --bno055 PATH         also emulate a Bosch BNO055 on a pseudo-terminal linked at PATH
  --record DIR          append every ROP a host sends to a board (from its first datagram)
                        to DIR/<board's robot IP>.jsonl, one JSON object a line:
                        {\"t\": seconds since the boards began serving, \"from\", \"seq\", \"age\",
                         \"ropcode\", \"rop\", \"id32\": \"0x........\", \"ep\", \"entity\", \"index\",
                         \"tag\", \"ctrl\", \"rqstconf\", \"rqsttime\", [\"signature\"], [\"time\"],
                         \"data\": \"hex\"}; flushed after each datagram

SIGINT or SIGTERM stops it (exit 0).";

fn usage() -> ! {
    eprintln!("{HELP}");
    std::process::exit(2)
}

fn main() {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .with_writer(std::io::stderr)
        .init();
    let mut args = std::env::args().skip(1);
    let mut dir: Option<PathBuf> = None;
    let mut top: Option<PathBuf> = None;
    let mut map_text = std::env::var(ADDRESS_MAP_ENV).unwrap_or_default();
    let mut xsens: Option<PathBuf> = None;
    let mut bno055: Option<PathBuf> = None;
    let mut options = ServeOptions::default();
    while let Some(a) = args.next() {
        match a.as_str() {
            "--xsens" => xsens = Some(args.next().unwrap_or_else(|| usage()).into()),
            "--bno055" => bno055 = Some(args.next().unwrap_or_else(|| usage()).into()),
            "--config" => top = Some(args.next().unwrap_or_else(|| usage()).into()),
            "--address-map" => map_text = args.next().unwrap_or_else(|| usage()),
            "--record" => options.record = Some(args.next().unwrap_or_else(|| usage()).into()),
            "-h" | "--help" => {
                println!("{HELP}");
                std::process::exit(0)
            }
            _ if dir.is_none() => dir = Some(a.into()),
            _ => usage(),
        }
    }
    let dir = dir.unwrap_or_else(|| usage());
    let map = AddressMap::parse(&map_text).unwrap_or_else(|e| {
        eprintln!("icub-eth-emulator: {e}");
        std::process::exit(2)
    });
    let top = top.map(|t| if t.is_absolute() { t } else { dir.join(t) });
    let specs = robot_boards(&dir, top.as_deref()).unwrap_or_else(|e| {
        eprintln!("icub-eth-emulator: {e}");
        std::process::exit(1)
    });
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        if let Err(e) = signal_hook::flag::register(sig, stop.clone()) {
            eprintln!("icub-eth-emulator: {e}");
            std::process::exit(1)
        }
    }
    let _mti = xsens.map(|link| {
        let mti = icub_can::xsens::mti::EmulatedMti::default();
        match icub_can::emulator::mtx::pty_link_with(&link, mti) {
            Ok((handle, pts)) => {
                println!("xsens {} {}", link.display(), pts.display());
                handle
            }
            Err(e) => {
                eprintln!("icub-eth-emulator: --xsens {}: {e}", link.display());
                std::process::exit(1)
            }
        }
    });
    let _bno055 = bno055.map(|link| match icub_emulators::bno055::pty_link(&link) {
        Ok((handle, pts)) => {
            println!("bno055 {} {}", link.display(), pts.display());
            handle
        }
        Err(e) => {
            eprintln!("icub-eth-emulator: --bno055 {}: {e}", link.display());
            std::process::exit(1)
        }
    });
    let (served, threads) = serve_with(specs, &map, stop, &options).unwrap_or_else(|e| {
        eprintln!("icub-eth-emulator: {e}");
        std::process::exit(1)
    });
    for b in &served {
        let s = &b.spec;
        let users = if s.users.is_empty() {
            String::new()
        } else {
            format!(", for {}", s.users.join(", "))
        };
        println!(
            "board {} {} at {} ({} joints{users})",
            s.params.name, s.params.type_name, b.local, s.joints,
        );
    }
    if let Some(d) = &options.record {
        println!(
            "icub-eth-emulator: recording the hosts' ROPs in {}",
            d.display()
        );
    }
    println!("icub-eth-emulator: serving {} boards", served.len());
    for t in threads {
        let _ = t.join();
    }
}

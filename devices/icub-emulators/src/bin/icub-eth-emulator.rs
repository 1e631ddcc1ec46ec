//! `icub-eth-emulator ROBOT_DIR [--config FILE.xml] [--address-map FROM/LEN=TO/LEN]
//! [--xsens PATH] [--bno055 PATH] [--record DIR] [--urdf PATH [--stance STANCE]
//! [--xsens-sensor NAME]]`: emulates every Ethernet board of a robots-configuration
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
//! each datagram. `--urdf PATH` gives the emulated robot a body (`icub_emulators::body`):
//! its F/T sensors then read what the URDF's masses, posed by the boards' joints, weigh on
//! them, held at the root link (`--stance fixed-root`, the default) or standing on frames
//! (`--stance standing:l_sole,r_sole`), and the MTi reads the body's accelerometer
//! `--xsens-sensor NAME`; a line `push LINK FX FY FZ` on standard input pushes the link
//! with that force (N, world axes, z up; zeros remove it), `report` prints what the body's
//! joint torques and F/T sensors are (`body torques NAME=N·m …`, `body ft NAME=fx,…,tz …`). SIGINT or SIGTERM stops it (exit 0; the `--xsens`/`--bno055` links are
//! removed).

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use icub_emulators::body::{Body, Stance};
use icub_emulators::eth::{
    robot_boards, serve_with, AddressMap, ServeOptions, SharedBody, ADDRESS_MAP_ENV,
};

const HELP: &str = "usage: icub-eth-emulator ROBOT_DIR [--config FILE.xml] [--address-map FROM/LEN=TO/LEN] [--xsens PATH] [--bno055 PATH] [--record DIR]

Emulates every Ethernet board of a robots-configuration robot directory, each on its own
IpAddress:IpPort UDP socket (hardware/electronics/*-eln.xml); a board learns its sensors
and running cycle from the host's service configurations, as a real one.

  --config FILE.xml     the robot's top-level file (default: yarprobotinterface.ini's config)
  --address-map MAP     serve the robot's addresses elsewhere, e.g. 10.0.1.0/24=127.0.1.0/24
                        (default: $YARP_ICUB_ETH_ADDRESS_MAP); the devices must use the same
  --xsens PATH          also emulate an Xsens MTi on a pseudo-terminal linked at PATH
  --bno055 PATH         also emulate a Bosch BNO055 on a pseudo-terminal linked at PATH
  --urdf PATH           the robot's body: F/T sensors and the MTi read its statics
  --stance STANCE       fixed-root (default) or standing:FRAME,FRAME,... (the first flat)
  --xsens-sensor NAME   the body's accelerometer the MTi is (with --urdf)
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

/// `push LINK FX FY FZ` lines on standard input push the body's links.
fn listen_for_pushes(body: SharedBody) {
    std::thread::spawn(move || {
        use std::io::BufRead;
        for line in std::io::stdin().lock().lines().map_while(Result::ok) {
            let words: Vec<&str> = line.split_whitespace().collect();
            let result = match words.as_slice() {
                ["push", link, f @ ..] if f.len() == 3 => match f
                    .iter()
                    .map(|x| x.parse::<f64>())
                    .collect::<Result<Vec<_>, _>>()
                {
                    Ok(f) => body
                        .body
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .push(link, [f[0], f[1], f[2]]),
                    Err(e) => Err(e.to_string()),
                },
                ["report"] => {
                    // what the body's sensors read now, one line per kind
                    let r = body
                        .readings
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .clone();
                    let mut torques: Vec<_> = r
                        .torques
                        .iter()
                        .map(|(k, v)| format!("{k}={v:.6}"))
                        .collect();
                    torques.sort();
                    println!("body torques {}", torques.join(" "));
                    let mut ft: Vec<_> =
                        r.ft.iter()
                            .map(|(k, v)| format!("{k}={}", v.map(|x| format!("{x:.6}")).join(",")))
                            .collect();
                    ft.sort();
                    println!("body ft {}", ft.join(" "));
                    continue;
                }
                [] => continue,
                _ => Err("expected `push LINK FX FY FZ` or `report`".to_string()),
            };
            match result {
                Ok(()) => println!("pushed: {line}"),
                Err(e) => eprintln!("icub-eth-emulator: {line}: {e}"),
            }
        }
    });
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
    let mut urdf: Option<PathBuf> = None;
    let mut stance = Stance::FixedRoot;
    let mut xsens_sensor: Option<String> = None;
    while let Some(a) = args.next() {
        match a.as_str() {
            "--urdf" => urdf = Some(args.next().unwrap_or_else(|| usage()).into()),
            "--stance" => {
                let text = args.next().unwrap_or_else(|| usage());
                stance = match text.split_once(':') {
                    None if text == "fixed-root" => Stance::FixedRoot,
                    Some(("standing", frames)) => {
                        Stance::Standing(frames.split(',').map(str::to_string).collect())
                    }
                    _ => usage(),
                };
            }
            "--xsens-sensor" => xsens_sensor = Some(args.next().unwrap_or_else(|| usage())),
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
    options.body = urdf.map(|path| {
        let body = Body::from_urdf(&path, stance).unwrap_or_else(|e| {
            eprintln!("icub-eth-emulator: --urdf {e}");
            std::process::exit(2)
        });
        let shared = SharedBody::new(body);
        listen_for_pushes(shared.clone());
        shared
    });
    let body = options.body.clone();
    let _mti = xsens.map(|link| {
        let mti = icub_can::xsens::mti::EmulatedMti::default();
        let started = match (&body, &xsens_sensor) {
            (Some(b), Some(name)) => {
                let (readings, name) = (b.readings.clone(), name.clone());
                icub_can::emulator::mtx::pty_link_moving(&link, mti, move |_| {
                    let acc = readings
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .acc
                        .get(&name)
                        .copied()
                        .unwrap_or_default();
                    icub_can::xsens::Sample {
                        acc: acc.map(|x| x as f32),
                        gyr: [0.0; 3],
                        mag: [1.0, 0.0, 0.4],
                        euler: [0.0; 3],
                    }
                })
            }
            _ => icub_can::emulator::mtx::pty_link_with(&link, mti),
        };
        match started {
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

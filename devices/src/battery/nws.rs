//! `battery_nws_yarp` (C++ YARP 3.12 `Battery_nws_yarp`): serves an attached `IBattery`
//! on YARP ports.
//!
//! Parameters as C++: `name` (required, starts with `/`: the ports are `<name>/data:o`
//! and `<name>/rpc:i`), `period` (s, default 1.0), `enable_log` (a `batteryLog.txt` in the
//! working directory, one line per period as C++ writes it, stamped in seconds since the
//! epoch where C++ writes `asctime`), `enable_shutdown` and
//! `quitPortName`. The stream starts on attach: a `BatteryData` with an envelope every
//! period while the device reports its status; the low-charge warnings of C++ (15, 12,
//! 10, 5 %) are logged. C++'s `enable_shutdown` powers the computer off below 5 %: this
//! device refuses to open with it rather than pretend to.

use super::protocol::{handle_rpc, read_battery, BatteryData, ChargeWarnings};
use super::BatteryStatus;
use crate::driver::{DeviceDriver, IWrapper, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::sensors::params::now;
use crate::sensors::periodic::Ticker;
use crate::wrapper_ports::{FailureStreak, Reply, Serving};
use std::io::Write;
use std::sync::Arc;
use std::time::Duration;
use yarp_net::peer_generation::PeerGenerations;
use yarp_net::port::Port;
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Property, Stamp};

const NAME: &str = "battery_nws_yarp";

/// `enable_shutdown` must stay off: this wrapper never shuts the computer down.
fn never(enable: &bool) -> Result<(), &'static str> {
    match enable {
        false => Ok(()),
        true => Err("false (this battery_nws_yarp never shuts the computer down)"),
    }
}

crate::device_params! {
    /// What `battery_nws_yarp` reads (C++ `Battery_nws_yarp_params.md`).
    pub struct BatteryNwsYarpParams for "battery_nws_yarp" {
        /// prefix of the ports opened by the device
        name: String = required; check crate::params::port_name,
        /// refresh period of the broadcasted values in seconds
        period: f64 = 1.0; "s"; check crate::params::positive,
        /// if enabled, batteryWrapper will start a system shutdown when charge is below 5%
        enable_shutdown: bool = false; check never,
        /// if enabled, stores a log of battery usage on disk
        enable_log: bool = false,
        /// if present, this yarp port will be opened and used to send a shutdown command to other applications
        "quitPortName" quit_port_name: String = optional,
    }
}

/// The `battery_nws_yarp` device.
#[derive(Default)]
pub struct BatteryNwsYarp {
    name: String,
    period: Duration,
    log: bool,
    serving: Serving,
}

impl BatteryNwsYarp {
    pub fn new() -> Self {
        Self::default()
    }

    /// `<name>/data:o`.
    pub fn data_port_name(&self) -> String {
        format!("{}/data:o", self.name)
    }

    /// `<name>/rpc:i`.
    pub fn rpc_port_name(&self) -> String {
        format!("{}/rpc:i", self.name)
    }
}

/// The line C++ appends to `batteryLog.txt` (the stamp in seconds, not `asctime`).
fn log_line(d: &BatteryData) -> String {
    format!(
        "battery status: {:+6.1}A   {: >6.1}V   charge:{: >6.1}%    time: {}\n",
        d.current,
        d.voltage,
        d.charge,
        now()
    )
}

async fn stream_battery(
    port: Arc<Port>,
    peers: PeerGenerations,
    period: Duration,
    device: SharedDevice,
    log: bool,
) {
    let mut ticker = Ticker::new(period);
    let mut last = BatteryData::default();
    let mut warnings = ChargeWarnings::default();
    let mut count: i32 = 0;
    let mut failing = FailureStreak::default();
    let mut log_file = log
        .then(|| {
            std::fs::File::create("batteryLog.txt")
                .map_err(|e| tracing::error!("{NAME}: batteryLog.txt: {e}"))
                .ok()
        })
        .flatten();
    loop {
        ticker.tick().await;
        let read = {
            let mut pd = device.lock();
            match pd.device().as_battery() {
                Some(b) => read_battery(b, &last),
                None => Err(DeviceError::Unsupported(
                    "the attached device is no IBattery",
                )),
            }
        };
        match read {
            Ok(d) => {
                failing.passed();
                port.write_by_generation(&d.to_bottle(), &peers, Some(Stamp::new(count, now())))
                    .await;
                count = count.wrapping_add(1);
                if d.status != BatteryStatus::OkStandby as i32 {
                    if let Some(msg) = warnings.check(d.charge) {
                        tracing::warn!("{NAME}: {msg}");
                    }
                }
                if let Some(f) = &mut log_file {
                    let _ = f.write_all(log_line(&d).as_bytes());
                }
                last = d;
            }
            Err(e) => failing.failed(|| format!("{NAME}: sensor returned error: {e}")),
        }
    }
}

fn answer(cmd: &Bottle, dev: Option<&mut dyn DeviceDriver>, generation: Generation) -> Reply {
    Reply::Encoded(handle_rpc(
        cmd,
        dev.and_then(|d| d.as_battery()),
        generation,
    ))
}

impl DeviceDriver for BatteryNwsYarp {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        BatteryNwsYarpParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = BatteryNwsYarpParams::read(config)?;
        self.log = p.enable_log;
        self.name = p.name;
        self.period = Duration::from_secs_f64(p.period);
        self.serving.open(
            NAME,
            vec![self.data_port_name()],
            self.rpc_port_name(),
            answer,
            // C++'s client reads `<local>/data:i`, calls from `<local>/rpc:o`
            |rpc| Some(format!("{}/data:i", rpc.strip_suffix("/rpc:o")?)),
        )
    }

    fn close(&mut self) -> DevResult<()> {
        self.serving.close();
        Ok(())
    }

    crate::views!(as_wrapper, as_multiple_wrapper);
}

impl IWrapper for BatteryNwsYarp {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()> {
        let (period, log) = (self.period, self.log);
        self.serving.attach(
            device,
            |d| {
                d.as_battery().map(drop).ok_or(DeviceError::Unsupported(
                    "battery_nws_yarp attaches an IBattery",
                ))
            },
            |ports, device| {
                let (port, peers) = (ports.streams[0].clone(), ports.peers.clone());
                stream_battery(port, peers, period, device, log)
            },
        )
    }

    fn detach(&mut self) -> DevResult<()> {
        self.serving.detach();
        Ok(())
    }
}

crate::one_device_multiple_wrapper!(
    BatteryNwsYarp,
    "battery_nws_yarp attaches exactly one device"
);

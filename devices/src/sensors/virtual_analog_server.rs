//! `virtualAnalogServer` (C++ YARP `VirtualAnalogWrapper`, formerly icub-main's
//! `virtualAnalogServer`): reads the joint torques wholeBodyDynamics estimates from a
//! port and hands them to the attached `IVirtualAnalogSensor`s (the
//! `canBusVirtualAnalogSensor` of each part).
//!
//! Parameters (as `wrappers/VFT/*_VFT_wrapper.xml`): `name` (the full input port name,
//! e.g. `/icub/joint_vsens/left_arm:i`; C++ default `controlboard`), `networks` (the
//! names of the attached devices) and one line per network mapping its channels,
//! `net (c0 c1 b0 b1)`: channels `c0..=c1` of the part go to channels `b0..=b1` of that
//! device (the text form `"c0 c1 b0 b1"` and the deprecated `net c0 c1 b0 b1` are read
//! too; every entry below 255). `robotName` is required, `deviceId` is refused, as in
//! C++. `period` and `channels` are accepted and unused (C++ ignores them too).
//!
//! The Bottles on the port (`VirtualAnalogWrapper::run`) are `type v1 v2 ...`:
//!
//! | type | part | channels set |
//! |------|------|--------------|
//! | 1 | arm | 0..5 = v1..v5, 5 = 0 |
//! | 2 | leg | 0..6 = v1..v6 |
//! | 3 | wrist | 0 = v6, 1 = v7, 2..6 = 0 |
//! | 4 | torso | 0..3 = v1..v3 |
//!
//! After each message every attached device gets its whole torque vector
//! (`updateVirtualAnalogSensorMeasure`). When no message came for 80 ms after a valid
//! one, the torques are set to zero and sent once (C++ does the same).
//! Deviations: a Bottle whose type is unknown, which is too short for its type, whose
//! values are not numbers, or whose channels are not all mapped, is logged (rate-limited)
//! and ignored — C++ reads missing values as 0 and re-sends the previous torques.

use parking_lot::Mutex;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::driver::{DeviceDriver, IMultipleWrapper, Params, SharedDevice};
use crate::error::{DevResult, DeviceError};
use crate::runtime;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Value};

const NAME: &str = "virtualAnalogServer";

/// `deviceId` is deprecated in C++.
fn deprecated(_: &Value) -> Result<(), &'static str> {
    Err("absent (deprecated in C++; give the full port as `name`, e.g. /icub/joint_vsens/left_arm:i)")
}

crate::device_params! {
    /// What `virtualAnalogServer` reads (C++ `VirtualAnalogWrapper::open`), besides the
    /// line `NETWORK base top wBase wTop` of each of the `networks`.
    pub struct VirtualAnalogServerParams for "virtualAnalogServer" {
        /// The boards attached, by their key in attachAll
        networks: Vec<String> = required,
        /// The robot's name (required by C++, unused)
        "robotName" robot_name: Value = required,
        /// The port receiving the torques (a leading '/' is added when missing)
        name: String = "controlboard",
        /// Deprecated in C++
        "deviceId" device_id: Value = optional; check deprecated,
    }
}
/// C++ `MAX_ENTRIES`: channel and board indices are below this.
const MAX_ENTRIES: i64 = 255;
/// C++ resets the torques when nothing arrived for 80 ms.
pub const RECEIVE_TIMEOUT: Duration = Duration::from_millis(80);
/// At most one log line per this interval for bad Bottles.
const BAD_LOG_EVERY: Duration = Duration::from_secs(1);

/// One attached device: the slice `base..=top` of its channels this wrapper fills.
#[derive(Debug, Clone, PartialEq)]
pub struct Network {
    pub key: String,
    pub base: usize,
    pub top: usize,
    /// The torques to send, one per channel `base..=top`.
    pub torques: Vec<f64>,
}

impl Network {
    /// C++ `AnalogSubDevice::setTorque`: channels outside `base..=top` are ignored.
    fn set(&mut self, channel: usize, torque: f64) {
        if (self.base..=self.top).contains(&channel) {
            self.torques[channel - self.base] = torque;
        }
    }
}

/// The channel mapping and the torques of every network (the protocol, without I/O).
#[derive(Debug, Clone, PartialEq)]
pub struct TorqueMap {
    pub networks: Vec<Network>,
    /// For each part channel, the network and the device channel it goes to.
    chan: Vec<Option<(usize, usize)>>,
}

/// Why a Bottle was ignored.
#[derive(Debug, Clone, PartialEq)]
pub enum BadTorques {
    UnknownType(String),
    TooShort {
        kind: i64,
        needed: usize,
        got: usize,
    },
    NotANumber {
        index: usize,
        value: String,
    },
    Unmapped {
        channel: usize,
    },
}

impl std::fmt::Display for BadTorques {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::UnknownType(t) => write!(
                f,
                "unexpected message type {t} (1 arm, 2 leg, 3 wrist, 4 torso)"
            ),
            Self::TooShort { kind, needed, got } => {
                write!(f, "type {kind} needs {needed} values, got {got}")
            }
            Self::NotANumber { index, value } => {
                write!(f, "value {index} ({value}) is not a number")
            }
            Self::Unmapped { channel } => {
                write!(f, "channel {channel} is not mapped by `networks`")
            }
        }
    }
}

impl TorqueMap {
    /// Reads `networks` and the line of each network (C++ `VirtualAnalogWrapper::open`).
    pub fn from_config(p: &Params<'_>) -> DevResult<Self> {
        let bad = |param: &str, expected: &'static str, got: String| DeviceError::BadParam {
            device: NAME.into(),
            param: param.into(),
            expected,
            got,
        };
        let list = p.find("networks").ok_or_else(|| p.missing("networks"))?;
        let names: Vec<String> = match list.as_list() {
            Some(l) => l.iter().map(Value::to_string_bare).collect(),
            None => vec![list.to_string_bare()],
        };
        let mut networks = Vec::new();
        let mut chan = vec![None; MAX_ENTRIES as usize];
        for (k, name) in names.iter().enumerate() {
            let line = p.config.find_group(name).ok_or_else(|| p.missing(name))?;
            let rest: Vec<Value> = line.iter().skip(1).cloned().collect();
            let values: Vec<Value> = match rest.as_slice() {
                [Value::List(l)] => l.iter().cloned().collect(),
                [v] => Bottle::from_text(v.to_string_bare()).into_items(),
                more => more.to_vec(),
            };
            let nums: Option<Vec<i64>> = values
                .iter()
                .map(|v| v.is_int().then(|| v.as_i64()).flatten())
                .collect();
            let Some(&[c0, c1, b0, b1]) = nums.as_deref() else {
                return Err(bad(
                    name,
                    "four integers between parentheses: (part_from part_to device_from device_to)",
                    line.to_string(),
                ));
            };
            if [c0, c1, b0, b1]
                .iter()
                .any(|v| !(0..MAX_ENTRIES).contains(v))
            {
                return Err(bad(name, "entries 0..254", line.to_string()));
            }
            // C++ checks only the device range (`AnalogSubDevice::configure`); part
            // channels past the device range are dropped by `setTorque`, as there
            if c1 < c0 || b1 < b0 {
                return Err(bad(name, "ranges with from <= to", line.to_string()));
            }
            for j in c0..=c1 {
                chan[j as usize] = Some((k, (j - c0 + b0) as usize));
            }
            networks.push(Network {
                key: name.clone(),
                base: b0 as usize,
                top: b1 as usize,
                torques: vec![0.0; (b1 - b0 + 1) as usize],
            });
        }
        Ok(Self { networks, chan })
    }

    /// Applies one message of wholeBodyDynamics; an error leaves the torques unchanged.
    pub fn apply(&mut self, b: &Bottle) -> Result<(), BadTorques> {
        let kind = b
            .get(0)
            .filter(|v| v.is_int())
            .and_then(Value::as_i64)
            .ok_or_else(|| {
                BadTorques::UnknownType(
                    b.get(0).map_or_else(|| "(empty)".into(), |v| v.to_string()),
                )
            })?;
        // (part channel, index of the value in the Bottle; 0 for "set to zero")
        let plan: &[(usize, usize)] = match kind {
            1 => &[(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 0)],
            2 => &[(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 6)],
            3 => &[(0, 6), (1, 7), (2, 0), (3, 0), (4, 0), (5, 0)],
            4 => &[(0, 1), (1, 2), (2, 3)],
            other => return Err(BadTorques::UnknownType(other.to_string())),
        };
        let needed = plan.iter().map(|&(_, i)| i + 1).max().unwrap_or(1);
        if b.len() < needed {
            return Err(BadTorques::TooShort {
                kind,
                needed,
                got: b.len(),
            });
        }
        let mut updates = Vec::with_capacity(plan.len());
        for &(channel, index) in plan {
            let (net, dev_ch) = self.chan[channel].ok_or(BadTorques::Unmapped { channel })?;
            let value = if index == 0 {
                0.0
            } else {
                let v = &b[index];
                v.as_f64()
                    .filter(|_| v.is_int() || v.is_float())
                    .ok_or_else(|| BadTorques::NotANumber {
                        index,
                        value: v.to_string(),
                    })?
            };
            updates.push((net, dev_ch, value));
        }
        for (net, dev_ch, value) in updates {
            self.networks[net].set(dev_ch, value);
        }
        Ok(())
    }

    /// C++ `resetTorque` on every network.
    pub fn reset(&mut self) {
        for n in &mut self.networks {
            n.torques.iter_mut().for_each(|t| *t = 0.0);
        }
    }
}

/// A log line at most every [`BAD_LOG_EVERY`], counting what it held back.
#[derive(Default)]
struct RateLimited {
    last: Option<Instant>,
    held: u64,
}

impl RateLimited {
    fn warn(&mut self, port: &str, what: &str) {
        if self.last.is_some_and(|t| t.elapsed() < BAD_LOG_EVERY) {
            self.held += 1;
            return;
        }
        if self.held > 0 {
            tracing::warn!(
                "{NAME} {port}: ignoring a Bottle: {what} ({} more ignored since the last report)",
                self.held
            );
        } else {
            tracing::warn!("{NAME} {port}: ignoring a Bottle: {what}");
        }
        self.last = Some(Instant::now());
        self.held = 0;
    }
}

/// What the reading task and the device share.
struct Core {
    port_name: String,
    map: TorqueMap,
    /// The attached devices, by network; empty until `attach_all`.
    devices: Vec<SharedDevice>,
    last_recv: Option<Instant>,
    /// A valid message has been applied (C++ `first_check`): enables the timeout.
    started: bool,
    reset_sent: bool,
    bad: RateLimited,
    /// Counters, for tests and diagnostics: (applied, ignored).
    applied: u64,
    ignored: u64,
}

impl Core {
    /// Sends every network's torques to its device (C++ `flushTorques`).
    fn flush(&mut self) {
        for (net, dev) in self.map.networks.iter().zip(&self.devices) {
            let mut pd = dev.lock();
            if let Some(s) = pd.device().as_virtual_analog_sensor() {
                if let Err(e) = s.update_virtual_analog_sensor_measure(&net.torques) {
                    tracing::debug!("{NAME} {}: {}: {e}", self.port_name, net.key);
                }
            }
        }
    }

    fn on_bottle(&mut self, b: &Bottle) {
        self.last_recv = Some(Instant::now());
        match self.map.apply(b) {
            Ok(()) => {
                self.started = true;
                self.reset_sent = false;
                self.applied += 1;
                self.flush();
            }
            Err(e) => {
                self.ignored += 1;
                let port = self.port_name.clone();
                self.bad.warn(&port, &e.to_string());
            }
        }
    }

    fn on_idle(&mut self) {
        let late = self
            .last_recv
            .is_some_and(|t| t.elapsed() > RECEIVE_TIMEOUT);
        if self.started && late && !self.reset_sent {
            tracing::error!(
                "{NAME} {}: no torques for more than {:?}: sending zeros",
                self.port_name,
                RECEIVE_TIMEOUT
            );
            self.map.reset();
            self.flush();
            self.reset_sent = true;
        }
    }
}

type SharedCore = Arc<Mutex<Core>>;

fn lock(core: &SharedCore) -> parking_lot::MutexGuard<'_, Core> {
    core.lock()
}

async fn serve(port: Arc<Port>, core: SharedCore) {
    loop {
        match tokio::time::timeout(Duration::from_millis(10), port.read()).await {
            Ok(Some(msg)) => {
                let mut c = lock(&core);
                if c.devices.is_empty() {
                    continue; // not attached: C++ reads nothing before attachAll
                }
                match msg.bottle() {
                    // the boards' devices may wait on the network: not on a held worker
                    Ok(b) => crate::runtime::device_call(|| c.on_bottle(&b)),
                    Err(e) => {
                        c.ignored += 1;
                        let port = c.port_name.clone();
                        c.bad
                            .warn(&port, &format!("undecodable from {}: {e}", msg.from));
                    }
                }
            }
            Ok(None) => break,
            Err(_) => crate::runtime::device_call(|| lock(&core).on_idle()),
        }
    }
}

/// The `virtualAnalogServer` device.
#[derive(Default)]
pub struct VirtualAnalogServer {
    core: Option<SharedCore>,
    port: Option<(Arc<Port>, tokio::task::JoinHandle<()>)>,
}

impl VirtualAnalogServer {
    pub fn new() -> Self {
        Self::default()
    }

    /// The input port's name, once open.
    pub fn port_name(&self) -> Option<String> {
        self.core.as_ref().map(|c| lock(c).port_name.clone())
    }

    /// (Bottles applied, Bottles ignored) since open.
    pub fn counts(&self) -> (u64, u64) {
        self.core.as_ref().map_or((0, 0), |c| {
            let c = lock(c);
            (c.applied, c.ignored)
        })
    }
}

impl DeviceDriver for VirtualAnalogServer {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        VirtualAnalogServerParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let map = TorqueMap::from_config(&Params::new(NAME, config))?;
        let mut name = VirtualAnalogServerParams::read(config)?.name;
        if !name.starts_with('/') {
            name.insert(0, '/');
        }
        let ns = yarp_net::network::name_client().map_err(|e| port_error(&name, e))?;
        let n = name.clone();
        let port =
            runtime::block_on_result(
                async move { Port::open(&n, ns).await.map_err(|e| e.to_string()) },
            )
            .map_err(|e| port_error(&name, e))?;
        let port = Arc::new(port);
        let core = Arc::new(Mutex::new(Core {
            port_name: name,
            map,
            devices: Vec::new(),
            last_recv: None,
            started: false,
            reset_sent: false,
            bad: RateLimited::default(),
            applied: 0,
            ignored: 0,
        }));
        let task = runtime::handle().spawn(serve(port.clone(), core.clone()));
        self.core = Some(core);
        self.port = Some((port, task));
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        let _ = self.detach_all();
        if let Some((port, task)) = self.port.take() {
            runtime::block_on_logged("virtual_analog_server: closing", async move {
                task.abort();
                let _ = task.await;
                if let Ok(p) = Arc::try_unwrap(port) {
                    p.close().await;
                }
            });
        }
        self.core = None;
        Ok(())
    }

    crate::views!(as_multiple_wrapper);
}

fn port_error(name: &str, e: impl std::fmt::Display) -> DeviceError {
    DeviceError::BadParam {
        device: NAME.into(),
        param: "name".into(),
        expected: "a port name that can be registered (is the name server running?)",
        got: format!("{name}: {e}"),
    }
}

impl IMultipleWrapper for VirtualAnalogServer {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let core = self.core.as_ref().ok_or(DeviceError::NotOpen)?;
        let mut c = lock(core);
        let mut found: Vec<Option<SharedDevice>> = vec![None; c.map.networks.len()];
        for (key, dev) in devices {
            // C++ AnalogSubDevice::attach: keys naming no network are ignored
            let Some(k) = c.map.networks.iter().position(|n| &n.key == key) else {
                continue;
            };
            let mut pd = dev.lock();
            let name = pd.name().to_string();
            let Some(s) = pd.device().as_virtual_analog_sensor() else {
                tracing::error!("{NAME}: {key}: device {name} is not an IVirtualAnalogSensor");
                return Err(DeviceError::Unsupported(
                    "virtualAnalogServer: the device is not an IVirtualAnalogSensor",
                ));
            };
            let channels = s.get_virtual_analog_sensor_channels();
            let net = &c.map.networks[k];
            if channels != net.top + 1 {
                tracing::warn!(
                    "{NAME}: {key}: device {name} has {channels} channels, the mapping fills {}..={}",
                    net.base,
                    net.top
                );
            }
            found[k] = Some(dev.clone());
        }
        let missing: Vec<&str> = c
            .map
            .networks
            .iter()
            .zip(&found)
            .filter(|(_, d)| d.is_none())
            .map(|(n, _)| n.key.as_str())
            .collect();
        if !missing.is_empty() {
            tracing::error!("{NAME}: no device attached for networks {missing:?}");
            return Err(DeviceError::MissingParam {
                device: NAME.into(),
                param: missing.join(" "),
            });
        }
        c.devices = found.into_iter().flatten().collect();
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        if let Some(core) = &self.core {
            let mut c = lock(core);
            c.devices.clear();
            c.started = false;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(text: &str) -> DevResult<TorqueMap> {
        let cfg = Property::from_text(text);
        TorqueMap::from_config(&Params::new(NAME, &cfg))
    }

    #[test]
    fn networks_in_every_syntax() {
        // as yarprobotinterface gives `<elem name="net_VFT_LA">( 0 5 0 5 )</elem>`
        let m = map("(networks (net_VFT_LA)) (net_VFT_LA (0 5 0 5))").unwrap();
        assert_eq!(m.networks.len(), 1);
        assert_eq!(m.networks[0].torques.len(), 6);
        let m = map("(networks (a b)) (a \"0 2 0 2\") (b 3 5 1 3)").unwrap();
        assert_eq!((m.networks[1].base, m.networks[1].top), (1, 3));
        assert_eq!(m.chan[4], Some((1, 2)));
        for bad in [
            "(networks (a)) (a (0 5 0))",
            "(networks (a)) (a (0 5 3 2))",
            "(networks (a)) (a (5 0 5 0))",
            "(networks (a)) (a (0 300 0 300))",
            "(networks (a)) (a (x 1 0 1))",
        ] {
            let e = map(bad).unwrap_err().to_string();
            assert!(e.contains("`a`"), "{bad}: {e}");
        }
        assert!(map("(networks (a))")
            .unwrap_err()
            .to_string()
            .contains("`a`"));
        assert!(map("(x 1)").unwrap_err().to_string().contains("networks"));
    }

    #[test]
    fn messages_fill_the_channels_as_cpp() {
        let mut m = map("(networks (n)) (n (0 5 0 5))").unwrap();
        m.apply(&Bottle::from_text("1 1.0 2.0 3.0 4.0 5.0 6.0 7.0"))
            .unwrap();
        assert_eq!(m.networks[0].torques, [1.0, 2.0, 3.0, 4.0, 5.0, 0.0]);
        m.apply(&Bottle::from_text("2 1 2 3 4 5 6")).unwrap();
        assert_eq!(m.networks[0].torques, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        m.apply(&Bottle::from_text("3 0 0 0 0 0 -6.5 7.5")).unwrap();
        assert_eq!(m.networks[0].torques, [-6.5, 7.5, 0.0, 0.0, 0.0, 0.0]);
        m.apply(&Bottle::from_text("4 0.1 0.2 0.3")).unwrap();
        assert_eq!(m.networks[0].torques, [0.1, 0.2, 0.3, 0.0, 0.0, 0.0]);
        m.reset();
        assert_eq!(m.networks[0].torques, [0.0; 6]);

        // two networks, the second offset on its device
        let mut m = map("(networks (a b)) (a (0 2 0 2)) (b (3 5 1 3))").unwrap();
        m.apply(&Bottle::from_text("2 1 2 3 4 5 6")).unwrap();
        assert_eq!(m.networks[0].torques, [1.0, 2.0, 3.0]);
        assert_eq!(m.networks[1].torques, [4.0, 5.0, 6.0]);

        // part channels past the device's range are dropped, as C++ setTorque does
        let mut m = map("(networks (a)) (a (0 5 0 2))").unwrap();
        m.apply(&Bottle::from_text("2 1 2 3 4 5 6")).unwrap();
        assert_eq!(m.networks[0].torques, [1.0, 2.0, 3.0]);
    }

    #[test]
    fn bad_bottles_change_nothing() {
        let mut m = map("(networks (n)) (n (0 2 0 2))").unwrap();
        m.apply(&Bottle::from_text("4 1 2 3")).unwrap();
        let before = m.clone();
        let cases = [
            ("", "empty"),
            ("hello 1 2 3", "type"),
            ("7 1 2 3", "type"),
            ("1.5 1 2 3", "type"),
            ("4 1 2", "needs 4"),
            ("4 1 x 3", "not a number"),
            ("4 1 (2) 3", "not a number"),
            ("2 1 2 3 4 5 6", "not mapped"),
        ];
        for (text, what) in cases {
            let e = m.apply(&Bottle::from_text(text)).unwrap_err();
            assert!(e.to_string().contains(what), "{text:?}: {e}");
            assert_eq!(m, before, "{text:?}");
        }
        let mut r = RateLimited::default();
        r.warn("/p", "one");
        r.warn("/p", "two");
        assert_eq!(r.held, 1);
    }
}

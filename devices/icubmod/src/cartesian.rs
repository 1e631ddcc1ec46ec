//! `cartesiancontrollerserver` (icub-main `ServerCartesianController`), as far as its
//! state stream goes: the end-effector pose of a limb computed with iKin-equivalent
//! kinematics ([`icub_ikin`]) from the encoders of the control boards it is attached to.
//!
//! * `/<ControllerName>/state:o` — every `ControllerPeriod` ms, the 7-vector
//!   `x y z ax ay az theta` (metres, axis-angle in radians) with an envelope
//!   (sequence number, time of the reading), as C++ streams it.
//!
//! Parameters, as in robots-configuration's `cartesian/*.xml`: `GENERAL::ControllerName`
//! (required), `ControllerPeriod` (ms, default 10), `KinematicPart` (`arm` or `leg`),
//! `KinematicType` (iKin type, e.g. `left_v2`), `NumberOfDrivers`, `RobotTimeout` (s,
//! default 1: a board whose encoders fail for longer is logged, and the pose stops),
//! and per driver `DRIVER_<i>::Key` (the attach key, e.g. `torso`) and `JointsOrder`
//! (`direct` or `reversed`). The joints of the drivers, each in its order, fill the
//! chain's links from the root, as C++ `ServerCartesianController::attachAll` does
//! (for an arm: torso reversed — pitch, roll, yaw — then the first 7 arm joints).
//! Accepted and unused: `TaskRefVelPeriodFactor`, `SolverNameToConnect`,
//! `PositionControl`, `MultipleJointsControl`, `MinAbsVels`, `PLANT_MODEL`: this
//! build has no solver, so `rpc:i`, `command:i` and `events:o` are not offered.
//!
//! The pose computation ([`CartesianState`]) is pure; the device is the tokio layer.

use icub_ikin::{Limb, LimbKind, DEG2RAD};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::task::JoinHandle;
use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, Params, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::runtime;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Stamp};

/// The C++ device name.
pub const NAME: &str = "cartesiancontrollerserver";

yarp_devices::device_params! {
    /// What `cartesiancontrollerserver` reads (icub-main's `ServerCartesianController`),
    /// besides the groups `DRIVER_<i>` (`Key`, `JointsOrder direct|reversed`) of each driver.
    pub struct CartesianControllerServerParams for "cartesiancontrollerserver" {
        /// Name of the controller's ports (`/<name>/...`)
        "GENERAL::ControllerName" controller_name: String = required,
        /// Period of the controller
        "GENERAL::ControllerPeriod" controller_period: i64 = 10; "ms"; in 1..=10000,
        /// Time after which the robot's encoders count as lost
        "GENERAL::RobotTimeout" robot_timeout: f64 = 1.0; "s"; check yarp_devices::params::positive,
        /// The limb: arm or leg (custom chains are not supported)
        "GENERAL::KinematicPart" kinematic_part: String = required,
        /// The iKin limb type (e.g. right_v2)
        "GENERAL::KinematicType" kinematic_type: String = required,
        /// Number of the DRIVER_<i> groups
        "GENERAL::NumberOfDrivers" number_of_drivers: i64 = required; in 1..=8,
    }
}

/// One `DRIVER_<i>` group: which attached device feeds which links.
#[derive(Debug, Clone, PartialEq)]
pub struct DriverDesc {
    /// The attach key (`networks` name) of the device.
    pub key: String,
    /// `JointsOrder reversed`: the device's joints fill the links last to first.
    pub reversed: bool,
}

/// The configuration of a cartesian controller server.
#[derive(Debug, Clone, PartialEq)]
pub struct CartesianConfig {
    /// `ControllerName`, without the leading `/`.
    pub name: String,
    pub period: Duration,
    pub robot_timeout: Duration,
    pub kind: LimbKind,
    pub kinematic_type: String,
    pub drivers: Vec<DriverDesc>,
}

impl CartesianConfig {
    /// Reads the `GENERAL` and `DRIVER_<i>` groups of a device configuration.
    pub fn from_property(config: &Property) -> DevResult<Self> {
        let declared = CartesianControllerServerParams::read(config)?;
        let p = Params::new(NAME, config);
        let req = |key: &str| -> DevResult<String> { p.string(key)?.ok_or_else(|| p.missing(key)) };
        let name = declared.controller_name.trim_start_matches('/').to_string();
        let bad = |param: &str, expected: &'static str, got: String| DeviceError::BadParam {
            device: NAME.into(),
            param: param.into(),
            expected,
            got,
        };
        let period_ms = declared.controller_period;
        let timeout = declared.robot_timeout;
        let part = declared.kinematic_part;
        let kind = match part.as_str() {
            "arm" => LimbKind::Arm,
            "leg" => LimbKind::Leg,
            _ => {
                return Err(bad(
                    "GENERAL::KinematicPart",
                    "`arm` or `leg` (custom chains are not supported)",
                    part,
                ))
            }
        };
        let kinematic_type = declared.kinematic_type;
        // an unknown type is refused now, naming the known ones
        Limb::new(kind, &kinematic_type).map_err(|e| {
            bad(
                "GENERAL::KinematicType",
                "an iKin limb type",
                format!("{kinematic_type} ({e})"),
            )
        })?;
        let n = declared.number_of_drivers;
        let mut drivers = Vec::new();
        for i in 0..n {
            let key = req(&format!("DRIVER_{i}::Key"))?;
            let order_key = format!("DRIVER_{i}::JointsOrder");
            let reversed = match p.string(&order_key)?.as_deref() {
                None | Some("direct") => false,
                Some("reversed") => true,
                Some(other) => return Err(bad(&order_key, "`direct` or `reversed`", other.into())),
            };
            drivers.push(DriverDesc { key, reversed });
        }
        Ok(CartesianConfig {
            name,
            period: Duration::from_millis(period_ms as u64),
            robot_timeout: Duration::from_secs_f64(timeout),
            kind,
            kinematic_type,
            drivers,
        })
    }
}

/// The kinematic chain fed from encoders (sans-I/O).
pub struct CartesianState {
    limb: Limb,
    drivers: Vec<DriverDesc>,
}

impl CartesianState {
    pub fn new(config: &CartesianConfig) -> DevResult<Self> {
        let limb = Limb::new(config.kind, &config.kinematic_type)
            .map_err(|_| DeviceError::Unsupported("unknown KinematicType"))?;
        Ok(CartesianState {
            limb,
            drivers: config.drivers.clone(),
        })
    }

    /// The chain's link count.
    pub fn links(&self) -> usize {
        self.limb.chain().n()
    }

    /// Checks that drivers with `axes` joints each fill the chain.
    pub fn check_axes(&self, axes: &[usize]) -> DevResult<()> {
        let got: usize = axes.iter().sum();
        if axes.len() != self.drivers.len() || got < self.links() {
            return Err(DeviceError::WrongSize {
                expected: self.links(),
                got,
            });
        }
        Ok(())
    }

    /// The pose `x y z ax ay az theta` for the encoders (degrees) of each driver, in
    /// the drivers' order. The joints fill the links from the root, each driver's in
    /// its `JointsOrder`, extra joints (a hand) ignored; too few joints is an error.
    pub fn pose(&mut self, encoders: &[Vec<f64>]) -> DevResult<[f64; 7]> {
        if encoders.len() != self.drivers.len() {
            return Err(DeviceError::WrongSize {
                expected: self.drivers.len(),
                got: encoders.len(),
            });
        }
        let n = self.links();
        let mut angles: Vec<f64> = Vec::with_capacity(n);
        for (desc, enc) in self.drivers.iter().zip(encoders) {
            let take = enc.len().min(n - angles.len());
            let used = &enc[..take];
            if desc.reversed {
                angles.extend(used.iter().rev());
            } else {
                angles.extend_from_slice(used);
            }
        }
        if angles.len() < n {
            return Err(DeviceError::WrongSize {
                expected: n,
                got: angles.len(),
            });
        }
        let chain = self.limb.chain_mut();
        for (i, q) in angles.iter().enumerate() {
            chain
                .set_link_ang(i, q * DEG2RAD)
                .map_err(|_| DeviceError::Unsupported("non-finite encoder value"))?;
        }
        let x = chain.end_eff_pose();
        Ok([x[0], x[1], x[2], x[3], x[4], x[5], x[6]])
    }
}

/// The attached boards, in the drivers' order.
type Boards = Vec<SharedDevice>;

/// `cartesiancontrollerserver`: opens `state:o` at open, publishes once attached.
#[derive(Default)]
pub struct CartesianControllerServer {
    config: Option<CartesianConfig>,
    state_port: Option<Arc<Port>>,
    publisher: Option<JoinHandle<()>>,
}

impl CartesianControllerServer {
    pub fn new() -> Self {
        Self::default()
    }

    /// The name of the state port (`/<ControllerName>/state:o`), once opened.
    pub fn state_port_name(&self) -> Option<String> {
        self.state_port.as_ref().map(|p| p.name().to_string())
    }

    fn stop_publishing(&mut self) {
        if let Some(p) = self.publisher.take() {
            p.abort();
        }
    }
}

impl Drop for CartesianControllerServer {
    fn drop(&mut self) {
        self.stop_publishing();
    }
}

impl DeviceDriver for CartesianControllerServer {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        CartesianControllerServerParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let cfg = CartesianConfig::from_property(config)?;
        let port_name = format!("/{}/state:o", cfg.name);
        let network = |e: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "GENERAL::ControllerName".into(),
            expected: "a port prefix that can be registered (is the name server running?)",
            got: format!("{port_name}: {e}"),
        };
        let ns = yarp_net::network::name_client().map_err(|e| network(e.to_string()))?;
        let name = port_name.clone();
        let port = runtime::block_on_result(async move {
            Port::open(&name, ns).await.map_err(|e| e.to_string())
        })
        .map_err(|e| network(e.to_string()))?;
        self.close()?;
        self.state_port = Some(Arc::new(port));
        self.config = Some(cfg);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(task) = self.publisher.take() {
            task.abort();
            // the task holds the port: wait until it is gone so that the port can close
            runtime::block_on_logged("cartesiancontrollerserver: closing", async move {
                let _ = task.await;
            });
        }
        if let Some(port) = self.state_port.take() {
            if let Ok(port) = Arc::try_unwrap(port) {
                runtime::block_on_logged("cartesiancontrollerserver: closing", port.close());
            }
        }
        Ok(())
    }

    yarp_devices::views!(as_multiple_wrapper);
}

impl IMultipleWrapper for CartesianControllerServer {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let (Some(cfg), Some(port)) = (&self.config, &self.state_port) else {
            return Err(DeviceError::NotOpen);
        };
        let mut boards: Boards = Vec::new();
        for d in &cfg.drivers {
            let Some((_, dev)) = devices.iter().find(|(k, _)| *k == d.key) else {
                return Err(DeviceError::MissingParam {
                    device: NAME.into(),
                    param: format!("attach network `{}` (DRIVER Key)", d.key),
                });
            };
            let mut pd = dev.lock();
            if pd.device().as_encoders().is_none() {
                return Err(DeviceError::Unsupported(
                    "cartesiancontrollerserver: an attached device has no encoders",
                ));
            }
            boards.push(dev.clone());
        }
        let state = CartesianState::new(cfg)?;
        // check the joint counts now, as C++ does at attach (without waiting on the
        // boards: a late encoder stream is the publisher's business)
        let axes = boards
            .iter()
            .map(|b| {
                let mut pd = b.lock();
                pd.device()
                    .as_encoders()
                    .ok_or(DeviceError::NotOpen)?
                    .get_axes()
            })
            .collect::<DevResult<Vec<usize>>>()?;
        state.check_axes(&axes)?;
        align_joints_bounds(cfg, &boards, &axes, state.links())?;
        let task = publish(state, boards, port.clone(), cfg.period, cfg.robot_timeout);
        self.stop_publishing();
        self.publisher = Some(runtime::handle().spawn(task));
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.stop_publishing();
        Ok(())
    }
}

/// C++ `alignJointsBounds`: the limits of every chain joint, asked of its part in the
/// chain's order (each part's first joints, reversed where its `JointsOrder` says so; a
/// failure fails the attach). They bound the solver's chain in C++; this build has none,
/// but the parts are asked as C++ asks them (the boards answer what they were given).
fn align_joints_bounds(
    cfg: &CartesianConfig,
    boards: &Boards,
    axes: &[usize],
    links: usize,
) -> DevResult<()> {
    let mut remaining = links;
    let mut cnt = 0;
    for ((desc, board), &n) in cfg.drivers.iter().zip(boards).zip(axes) {
        let joints = n.min(remaining);
        remaining -= joints;
        let mut pd = board.lock();
        let limits = pd
            .device()
            .as_control_limits()
            .ok_or(DeviceError::Unsupported(
                "cartesiancontrollerserver: an attached device has no IControlLimits",
            ))?;
        for k in 0..joints {
            let j = if desc.reversed { joints - k - 1 } else { k };
            let (min, max) = limits.get_limits(j).map_err(|e| {
                DeviceError::failed(NAME, format!("joint #{cnt}: failed getting limits! ({e})"))
            })?;
            tracing::debug!(
                "{NAME}: part {}: joint #{cnt}: [{min}, {max}] deg",
                desc.key
            );
            cnt += 1;
        }
    }
    Ok(())
}

fn read_encoders(boards: &Boards) -> DevResult<Vec<Vec<f64>>> {
    boards
        .iter()
        .map(|b| {
            let mut pd = b.lock();
            pd.device()
                .as_encoders()
                .ok_or(DeviceError::NotOpen)?
                .get_encoders()
        })
        .collect()
}

fn now_seconds() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs_f64())
        .unwrap_or(0.0)
}

/// Publishes the pose every `period` while someone listens.
async fn publish(
    mut state: CartesianState,
    boards: Boards,
    port: Arc<Port>,
    period: Duration,
    timeout: Duration,
) {
    let mut tick = tokio::time::interval(period);
    tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
    let mut count: i32 = 0;
    let mut last_ok = Instant::now();
    let mut reported = false;
    loop {
        tick.tick().await;
        if port.outputs().is_empty() {
            continue;
        }
        // board calls block on CAN round trips; let other tasks run meanwhile
        let pose =
            tokio::task::block_in_place(|| read_encoders(&boards).and_then(|enc| state.pose(&enc)));
        match pose {
            Ok(x) => {
                last_ok = Instant::now();
                reported = false;
                let b: Bottle = x.iter().copied().collect();
                port.write_nowait(&b, Some(Stamp::new(count, now_seconds())));
                count = if count == i32::MAX { 0 } else { count + 1 };
            }
            Err(e) if !reported && last_ok.elapsed() >= timeout => {
                tracing::error!(
                    "{}: no valid encoders for {:?} ({e}); pose not published",
                    port.name(),
                    timeout
                );
                reported = true;
            }
            Err(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn left_arm_config() -> Property {
        Property::from_config_text(
            "[GENERAL]\nControllerName icub/cartesianController/left_arm\nControllerPeriod 10\n\
             KinematicPart arm\nKinematicType left_v2\nNumberOfDrivers 2\n\
             [DRIVER_0]\nKey torso\nJointsOrder reversed\n\
             [DRIVER_1]\nKey left_arm\nJointsOrder direct\n",
        )
        .unwrap()
    }

    #[test]
    fn reads_the_robots_configuration_params() {
        let c = CartesianConfig::from_property(&left_arm_config()).unwrap();
        assert_eq!(c.name, "icub/cartesianController/left_arm");
        assert_eq!(c.period, Duration::from_millis(10));
        assert_eq!(c.drivers.len(), 2);
        assert!(c.drivers[0].reversed && !c.drivers[1].reversed);
        assert_eq!(c.drivers[1].key, "left_arm");
    }

    #[test]
    fn bad_params_name_themselves() {
        let p = Property::from_config_text(
            "[GENERAL]\nControllerName c\nKinematicPart arm\nKinematicType left_v9\nNumberOfDrivers 1\n",
        )
        .unwrap();
        let e = CartesianConfig::from_property(&p).unwrap_err().to_string();
        assert!(e.contains("KinematicType"), "{e}");
    }

    #[test]
    fn pose_matches_ikin_from_encoders() {
        let c = CartesianConfig::from_property(&left_arm_config()).unwrap();
        let mut s = CartesianState::new(&c).unwrap();
        let torso = vec![10.0, 5.0, 20.0];
        let mut arm = vec![0.0; 16];
        arm[..7].copy_from_slice(&[-30.0, 30.0, 10.0, 45.0, 0.0, 0.0, 0.0]);
        let got = s.pose(&[torso.clone(), arm.clone()]).unwrap();
        let want = Limb::arm("left_v2")
            .unwrap()
            .pose_from_encoders(&torso, &arm)
            .unwrap();
        for i in 0..7 {
            assert!((got[i] - want[i]).abs() < 1e-12, "{got:?} {want:?}");
        }
        assert!(s.check_axes(&[3, 16]).is_ok());
        assert!(s.check_axes(&[3, 4]).is_err());
        assert!(matches!(
            s.pose(&[torso, vec![0.0; 3]]),
            Err(DeviceError::WrongSize { .. })
        ));
    }
}

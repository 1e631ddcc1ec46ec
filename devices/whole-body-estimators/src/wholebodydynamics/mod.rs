//! `wholebodydynamics` (whole-body-estimators' `WholeBodyDynamicsDevice`): every
//! period, the joint torques and the external wrenches of the robot estimated from its
//! encoders, F/T sensors and IMU on its URDF ([`robot_dynamics`]), as C++ does:
//!
//! - open: the model from `modelFile` (found as the ResourceFinder finds it, in
//!   `robots/$YARP_ROBOT_NAME/` of the data directories), its degrees of freedom
//!   `axesNames`, split at the F/T sensors `SixAxisForceTorqueSensorsNames`, one contact
//!   per submodel from `defaultContactFrames` (or `overrideContactFrames`); a
//!   `controlboardremapper` over the axes and a `multipleanalogsensorsremapper` over
//!   the F/T sensors; the ports.
//! - attach (a robotinterface `attach` action): the boards with `IEncoders` to the
//!   remapper, the boards with `IVirtualAnalogSensor` by their axis names, the F/T
//!   sensors and the IMU (`HW_USE_MAS_IMU`) by name; then the F/T offsets are calibrated
//!   assuming the robot held at `base_link` (100 samples) unless
//!   `startWithZeroFTSensorOffsets`.
//! - each period ([`core`]): read, filter, estimate; once the offsets are known, the
//!   torques to the boards (`updateVirtualAnalogSensorMeasure`), gravity compensation
//!   (`setImpedanceOffset`) to the joints in compliant interaction of the
//!   `GRAVITY_COMPENSATION` axes, the wrenches on `WBD_OUTPUT_EXTERNAL_WRENCH_PORTS`
//!   (names used as given), `<prefix>/netExternalWrenches:o` and
//!   `<prefix>/filteredFT/<sensor>`.
//! - `<prefix>/rpc` ([`rpc`]): calibrations, offsets, filters, kinematic source.
//!
//! Not served: the skin contacts (`useSkinForContacts`: the configured frames are the
//! contacts, as C++ when no skin message came), the `<prefix>/settings` editor and the
//! Kalman filter of `estimateJointVelocityAcceleration`.

pub mod config;
pub mod core;
pub mod filter;
pub mod rpc;

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

use parking_lot::Mutex;
use robot_dynamics::estimation::Estimator;
use robot_dynamics::urdf;
use yarp_devices::device_thread::{stopped, DeviceThread};
use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, PolyDriver, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::robotinterface::resource::find_file;
use yarp_devices::runtime;
use yarp_devices::vocabs::{CM_MIXED, CM_POSITION, CM_POSITION_DIRECT, CM_VELOCITY, IM_COMPLIANT};
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property};

use self::config::{Config, WbdParams};
use self::core::{Core, KinematicSource, Outputs, Readings};

pub const NAME: &str = "wholebodydynamics";

/// How long attach waits for the F/T sensors and the IMU to read (C++: 2 s).
const SENSOR_READ_TIMEOUT: Duration = Duration::from_secs(2);

fn failed(reason: impl ToString) -> DeviceError {
    DeviceError::failed(NAME, reason)
}

/// A board that takes estimated torques: its channels, each the estimated axis it
/// gets (C++'s `virtualAnalogRemapper`).
struct TorqueTarget {
    device: SharedDevice,
    channels: Vec<Option<usize>>,
}

/// An IMU's accelerometer or gyroscope: the device and the sensor's index there.
type ImuPart = (SharedDevice, usize);

/// The devices the estimation reads and writes.
struct Hardware {
    boards: PolyDriver,
    sensors: PolyDriver,
    torques: Vec<TorqueTarget>,
    imu: Option<(ImuPart, ImuPart)>,
}

impl Hardware {
    fn read(
        &mut self,
        n_ft: usize,
        want_speeds: bool,
        want_accelerations: bool,
    ) -> DevResult<Readings> {
        let mut r = Readings::default();
        let enc = self
            .boards
            .device()
            .as_encoders()
            .ok_or(DeviceError::NoInterface("IEncoders"))?;
        r.q = enc.get_encoders()?;
        if want_speeds {
            r.dq = enc.get_encoder_speeds()?;
        }
        if want_accelerations {
            r.ddq = enc.get_encoder_accelerations()?;
        }
        let ft = self
            .sensors
            .device()
            .as_six_axis_force_torque_sensors()
            .ok_or(DeviceError::NoInterface("ISixAxisForceTorqueSensors"))?;
        for i in 0..n_ft {
            let m = ft.get_six_axis_force_torque_sensor_measure(i)?;
            let v: [f64; 6] = m.values.get(..6).and_then(|v| v.try_into().ok()).ok_or(
                DeviceError::WrongSize {
                    expected: 6,
                    got: m.values.len(),
                },
            )?;
            if v.iter().any(|x| x.is_nan()) {
                return Err(failed(format!("F/T sensor {i} reads NaN")));
            }
            r.ft.push(v);
        }
        if let Some(((acc_dev, acc_i), (gyro_dev, gyro_i))) = &self.imu {
            let a = acc_dev
                .lock()
                .device()
                .as_three_axis_linear_accelerometers()
                .ok_or(DeviceError::NoInterface("IThreeAxisLinearAccelerometers"))?
                .get_three_axis_linear_accelerometer_measure(*acc_i)?;
            let g = gyro_dev
                .lock()
                .device()
                .as_three_axis_gyroscopes()
                .ok_or(DeviceError::NoInterface("IThreeAxisGyroscopes"))?
                .get_three_axis_gyroscope_measure(*gyro_i)?;
            r.acc = a.values.get(..3).and_then(|v| v.try_into().ok()).ok_or(
                DeviceError::WrongSize {
                    expected: 3,
                    got: a.values.len(),
                },
            )?;
            r.gyro = g.values.get(..3).and_then(|v| v.try_into().ok()).ok_or(
                DeviceError::WrongSize {
                    expected: 3,
                    got: g.values.len(),
                },
            )?;
        }
        Ok(r)
    }

    /// The estimated torques to the boards: a whole vector where every channel of a
    /// board is estimated, else channel by channel.
    fn publish_torques(&mut self, torques: &[f64]) {
        for t in &self.torques {
            let mut pd = t.device.lock();
            let Some(vas) = pd.device().as_virtual_analog_sensor() else {
                continue;
            };
            let result = if t.channels.iter().all(Option::is_some) {
                let v: Vec<f64> = t
                    .channels
                    .iter()
                    .map(|a| torques[a.expect("all mapped")])
                    .collect();
                vas.update_virtual_analog_sensor_measure(&v)
            } else {
                t.channels
                    .iter()
                    .enumerate()
                    .filter_map(|(ch, a)| a.map(|a| (ch, a)))
                    .try_for_each(|(ch, a)| {
                        vas.update_virtual_analog_sensor_channel(ch, torques[a])
                    })
            };
            if let Err(e) = result {
                tracing::warn!(
                    "{NAME}: sending the estimated torques to {}: {e}",
                    pd.name()
                );
            }
        }
    }

    /// Gravity compensation to the axes in position, position direct, mixed or
    /// velocity control and compliant interaction.
    fn gravity_compensation(&mut self, torques: &[(usize, f64)]) {
        let dev = self.boards.device();
        for &(axis, tau) in torques {
            let mode = dev
                .as_control_mode()
                .and_then(|c| c.get_control_mode(axis).ok());
            let interaction = dev
                .as_interaction_mode()
                .and_then(|c| c.get_interaction_mode(axis).ok());
            let controlled = mode.is_some_and(|m| {
                [CM_POSITION, CM_POSITION_DIRECT, CM_MIXED, CM_VELOCITY].contains(&m)
            });
            if controlled && interaction == Some(IM_COMPLIANT) {
                if let Some(Err(e)) = dev
                    .as_impedance_control()
                    .map(|i| i.set_impedance_offset(axis, tau))
                {
                    tracing::warn!("{NAME}: setImpedanceOffset({axis}): {e}");
                }
            }
        }
    }

    /// Every gravity-compensated axis back to no offset (at detach).
    fn reset_gravity_compensation(&mut self, axes: &[usize]) {
        if let Some(i) = self.boards.device().as_impedance_control() {
            for &a in axes {
                let _ = i.set_impedance_offset(a, 0.0);
            }
        }
    }
}

/// The output ports.
#[derive(Default)]
struct Ports {
    rpc: Option<Arc<Port>>,
    wrenches: Vec<Arc<Port>>,
    net: Option<Arc<Port>>,
    filtered_ft: Vec<Arc<Port>>,
    rpc_task: Option<tokio::task::JoinHandle<()>>,
}

fn vector(v: &[f64]) -> Bottle {
    let mut b = Bottle::new();
    for x in v {
        b.push(*x);
    }
    b
}

impl Ports {
    fn publish(&self, out: &Outputs) {
        for (port, w) in self.wrenches.iter().zip(&out.wrench_ports) {
            port.write_nowait(&vector(w), None);
        }
        if let Some(port) = &self.net {
            // whole-body-estimators' VectorsCollection: a struct of one map<string,
            // list<double>>, the links in alphabetical order
            let mut map = Bottle::new();
            for (link, w) in &out.net_external_wrenches {
                map.push(Bottle::new().with(link.as_str()).with(vector(w)));
            }
            port.write_nowait(&Bottle::new().with(map), None);
        }
        for (port, w) in self.filtered_ft.iter().zip(&out.filtered_ft) {
            port.write_nowait(&vector(w), None);
        }
    }

    fn close(&mut self) {
        let ports: Vec<Arc<Port>> = self
            .rpc
            .take()
            .into_iter()
            .chain(self.wrenches.drain(..))
            .chain(self.net.take())
            .chain(self.filtered_ft.drain(..))
            .collect();
        let task = self.rpc_task.take();
        runtime::block_on_logged("wholebodydynamics: closing its ports", async move {
            if let Some(t) = task {
                t.abort();
                let _ = t.await;
            }
            for p in ports {
                if let Ok(p) = Arc::try_unwrap(p) {
                    p.close().await;
                }
            }
        });
    }
}

/// What the thread and the RPC share.
struct Shared {
    core: Core,
    imu_attached: bool,
}

/// The `wholebodydynamics` device.
pub struct WholeBodyDynamics {
    config: Option<Config>,
    shared: Option<Arc<Mutex<Shared>>>,
    hardware: Option<Arc<Mutex<Hardware>>>,
    ports: Ports,
    thread: DeviceThread,
}

impl Default for WholeBodyDynamics {
    fn default() -> Self {
        Self::new()
    }
}

impl WholeBodyDynamics {
    pub fn new() -> Self {
        WholeBodyDynamics {
            config: None,
            shared: None,
            hardware: None,
            ports: Ports::default(),
            thread: DeviceThread::default(),
        }
    }

    fn open_ports(&mut self, config: &Config, shared: Arc<Mutex<Shared>>) -> DevResult<()> {
        let p = &config.params;
        let prefix = p.port_prefix.clone();
        let mut names = vec![format!("{prefix}/rpc")];
        names.extend(config.wrench_ports.iter().map(|w| w.port.clone()));
        if p.publish_net_external_wrenches {
            names.push(format!("{prefix}/netExternalWrenches:o"));
        }
        if p.stream_filtered_ft {
            names.extend(
                p.ft_names
                    .iter()
                    .map(|n| format!("{prefix}/filteredFT/{n}")),
            );
        }
        let ns =
            yarp_net::network::name_client().map_err(|e| failed(format!("YARP network: {e}")))?;
        let opened = runtime::block_on_result(async move {
            let mut opened = Vec::new();
            for name in &names {
                match Port::open(name, ns.clone()).await {
                    Ok(port) => opened.push(Arc::new(port)),
                    Err(e) => {
                        for p in opened {
                            if let Ok(p) = Arc::try_unwrap(p) {
                                p.close().await;
                            }
                        }
                        return Err(failed(format!("could not open port {name}: {e}")));
                    }
                }
            }
            Ok(opened)
        })?;
        let mut it = opened.into_iter();
        let rpc = it.next().expect("the rpc port first");
        self.ports.wrenches = it.by_ref().take(config.wrench_ports.len()).collect();
        if p.publish_net_external_wrenches {
            self.ports.net = it.next();
        }
        self.ports.filtered_ft = it.collect();
        self.ports.rpc_task = Some(runtime::handle().spawn(serve_rpc(rpc.clone(), shared)));
        self.ports.rpc = Some(rpc);
        Ok(())
    }
}

async fn serve_rpc(port: Arc<Port>, shared: Arc<Mutex<Shared>>) {
    while let Some(mut msg) = port.read().await {
        let cmd = msg.bottle().unwrap_or_default();
        let reply = {
            let mut s = shared.lock();
            let imu_attached = s.imu_attached;
            rpc::answer(
                &cmd,
                &mut rpc::Target {
                    core: &mut s.core,
                    imu_attached,
                },
            )
        };
        if msg.wants_reply() {
            msg.reply(reply.unwrap_or_default());
        }
    }
}

/// The model as the device reads it: the URDF's joints `axesNames` as degrees of
/// freedom, its F/T sensors narrowed to those named.
fn load_model(p: &WbdParams) -> DevResult<Estimator> {
    let path = find_file(&p.model_file, None).ok_or_else(|| {
        failed(format!(
            "impossible to find modelFile {} (searched as the ResourceFinder does: robots/{}/ in the data directories)",
            p.model_file,
            std::env::var("YARP_ROBOT_NAME").unwrap_or_else(|_| "$YARP_ROBOT_NAME".into())
        ))
    })?;
    let model = urdf::read_file(&path).map_err(failed)?;
    let mut model = model
        .with_dofs(&p.axes_names, &[])
        .map_err(|e| failed(format!("{}: {e}", path.display())))?;
    model.select_ft(&p.ft_names).map_err(|e| {
        failed(format!(
            "{}: {e} (SixAxisForceTorqueSensorsNames)",
            path.display()
        ))
    })?;
    let root = model.links[model.root()].name.clone();
    Estimator::new(model, &root).map_err(failed)
}

fn open_remapper(text: &str) -> DevResult<PolyDriver> {
    PolyDriver::open(&Property::from_text(text))
}

impl DeviceDriver for WholeBodyDynamics {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        WbdParams::PARAMS.to_vec()
    }

    fn open(&mut self, property: &Property) -> DevResult<()> {
        let config = Config::read(property)?;
        let est = load_model(&config.params)?;
        let core = Core::new(&config, est).map_err(failed)?;
        let shared = Arc::new(Mutex::new(Shared {
            core,
            imu_attached: false,
        }));
        self.open_ports(&config, shared.clone())?;
        self.shared = Some(shared);
        self.config = Some(config);
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        let _ = IMultipleWrapper::detach_all(self);
        self.ports.close();
        self.shared = None;
        Ok(())
    }

    yarp_devices::views!(as_multiple_wrapper);
}

/// The boards' axis names and virtual channels: which estimated axis each channel of
/// each board with `IVirtualAnalogSensor` gets.
fn torque_targets(
    axes: &[String],
    devices: &[(String, SharedDevice)],
) -> DevResult<Vec<TorqueTarget>> {
    let mut targets = Vec::new();
    for (key, device) in devices {
        let mut pd = device.lock();
        let d = pd.device();
        let Some(channels) = d
            .as_virtual_analog_sensor()
            .map(|v| v.get_virtual_analog_sensor_channels())
        else {
            continue;
        };
        let info = d.as_axis_info().ok_or_else(|| {
            failed(format!(
                "{key} offers IVirtualAnalogSensor without IAxisInfo"
            ))
        })?;
        let mut map = Vec::with_capacity(channels);
        for ch in 0..channels {
            let name = info.get_axis_name(ch)?;
            map.push(axes.iter().position(|a| *a == name));
        }
        drop(pd);
        if map.iter().any(Option::is_some) {
            targets.push(TorqueTarget {
                device: device.clone(),
                channels: map,
            });
        }
    }
    Ok(targets)
}

/// The one accelerometer or gyroscope named `name` among the devices.
fn find_imu_part(devices: &[(String, SharedDevice)], name: &str, gyro: bool) -> Option<ImuPart> {
    for (_, device) in devices {
        let mut pd = device.lock();
        let d = pd.device();
        let (count, names): (usize, Vec<String>) = if gyro {
            let Some(g) = d.as_three_axis_gyroscopes() else {
                continue;
            };
            let n = g.get_nr_of_three_axis_gyroscopes();
            (
                n,
                (0..n)
                    .filter_map(|i| g.get_three_axis_gyroscope_name(i).ok())
                    .collect(),
            )
        } else {
            let Some(a) = d.as_three_axis_linear_accelerometers() else {
                continue;
            };
            let n = a.get_nr_of_three_axis_linear_accelerometers();
            (
                n,
                (0..n)
                    .filter_map(|i| a.get_three_axis_linear_accelerometer_name(i).ok())
                    .collect(),
            )
        };
        if let Some(i) = names.iter().position(|n| n == name).filter(|&i| i < count) {
            return Some((device.clone(), i));
        }
    }
    None
}

impl IMultipleWrapper for WholeBodyDynamics {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let config = self.config.clone().ok_or(DeviceError::NotOpen)?;
        let shared = self.shared.clone().ok_or(DeviceError::NotOpen)?;
        let p = &config.params;
        self.thread.stop();
        // The boards' axes, by name.
        let mut boards = open_remapper(&format!(
            "(device controlboardremapper) (axesNames ({}))",
            p.axes_names.join(" ")
        ))?;
        let with_encoders: Vec<(String, SharedDevice)> = devices
            .iter()
            .filter(|(_, d)| d.lock().device().as_encoders().is_some())
            .cloned()
            .collect();
        boards
            .device()
            .as_multiple_wrapper()
            .ok_or(DeviceError::NoInterface("IMultipleWrapper"))?
            .attach_all(&with_encoders)
            .map_err(|e| failed(format!("attachAll of the remapped control board: {e}")))?;
        let torques = torque_targets(&p.axes_names, devices)?;
        // The F/T sensors, by name.
        let mut sensors = open_remapper(&format!(
            "(device multipleanalogsensorsremapper) (SixAxisForceTorqueSensorsNames ({}))",
            p.ft_names.join(" ")
        ))?;
        sensors
            .device()
            .as_multiple_wrapper()
            .ok_or(DeviceError::NoInterface("IMultipleWrapper"))?
            .attach_all(devices)
            .map_err(|e| failed(format!("attachAll of the F/T sensors: {e}")))?;
        // The IMU, by its sensors' names, when it is the kinematic source.
        let uses_imu = shared.lock().core.settings.kinematic_source == KinematicSource::Imu;
        let imu = if uses_imu {
            match (find_imu_part(devices, &p.accelerometer, false), find_imu_part(devices, &p.gyroscope, true)) {
                (Some(a), Some(g)) => Some((a, g)),
                _ => {
                    return Err(failed(format!(
                        "Did not find one IMU with accelerometer {} and gyroscope {} among the attached devices (HW_USE_MAS_IMU)",
                        p.accelerometer, p.gyroscope
                    )))
                }
            }
        } else {
            None
        };
        let mut hw = Hardware {
            boards,
            sensors,
            torques,
            imu,
        };
        let n_ft = p.ft_names.len();
        if !p.disable_read_check {
            let start = Instant::now();
            loop {
                match hw.read(n_ft, false, false) {
                    Ok(_) => break,
                    Err(e) if start.elapsed() > SENSOR_READ_TIMEOUT => {
                        return Err(failed(format!(
                            "unable to correctly read from the sensors after {} seconds: {e}",
                            SENSOR_READ_TIMEOUT.as_secs()
                        )))
                    }
                    Err(_) => std::thread::sleep(Duration::from_millis(1)),
                }
            }
        }
        {
            let mut s = shared.lock();
            s.imu_attached = hw.imu.is_some();
            if p.start_with_zero_offsets {
                s.core.zero_offsets();
            } else {
                s.core
                    .start_calibration(&["base_link"], 100)
                    .map_err(failed)?;
            }
        }
        let hardware = Arc::new(Mutex::new(hw));
        self.hardware = Some(hardware.clone());
        let ports = PortsRef {
            wrenches: self.ports.wrenches.clone(),
            net: self.ports.net.clone(),
            filtered_ft: self.ports.filtered_ft.clone(),
        };
        self.thread
            .spawn("wholebodydynamics".into(), move |stop| {
                run(shared, hardware, ports, stop)
            })
            .map_err(|e| failed(format!("could not start its thread: {e}")))?;
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.thread.stop();
        if let (Some(hw), Some(config)) = (self.hardware.take(), &self.config) {
            let mut hw = hw.lock();
            if let (Some(shared), Some((_, axes))) = (&self.shared, &config.gravity_compensation) {
                let m = &shared.lock().core.est.model;
                let dofs: Vec<usize> = axes
                    .iter()
                    .filter_map(|a| m.joint(a).and_then(|j| m.joints[j].dof))
                    .collect();
                hw.reset_gravity_compensation(&dofs);
            }
            if let Some(w) = hw.boards.device().as_multiple_wrapper() {
                let _ = w.detach_all();
            }
            if let Some(w) = hw.sensors.device().as_multiple_wrapper() {
                let _ = w.detach_all();
            }
        }
        Ok(())
    }
}

/// The thread's handles on the output ports.
struct PortsRef {
    wrenches: Vec<Arc<Port>>,
    net: Option<Arc<Port>>,
    filtered_ft: Vec<Arc<Port>>,
}

/// The periodic estimation, until `stop`.
fn run(
    shared: Arc<Mutex<Shared>>,
    hardware: Arc<Mutex<Hardware>>,
    ports: PortsRef,
    stop: &AtomicBool,
) {
    let (period, n_ft) = {
        let s = shared.lock();
        (
            Duration::from_secs_f64(s.core.period()),
            s.core.est.model.sensors.ft.len(),
        )
    };
    let ports = Ports {
        rpc: None,
        wrenches: ports.wrenches,
        net: ports.net,
        filtered_ft: ports.filtered_ft,
        rpc_task: None,
    };
    let mut next = Instant::now();
    let mut last_error = String::new();
    let mut publishing = false;
    tracing::info!("{NAME}: estimating every {period:?}");
    while !stopped(stop) {
        let (vel, acc) = {
            let s = shared.lock();
            (
                s.core.settings.use_joint_velocity,
                s.core.settings.use_joint_acceleration,
            )
        };
        let readings = hardware.lock().read(n_ft, vel, acc);
        let outputs = readings
            .map_err(|e| e.to_string())
            .and_then(|r| shared.lock().core.step(&r));
        match outputs {
            Ok(Some(out)) => {
                if !publishing {
                    tracing::info!("{NAME}: the F/T offsets are known: publishing the estimates");
                    publishing = true;
                }
                let mut hw = hardware.lock();
                hw.publish_torques(&out.torques);
                hw.gravity_compensation(&out.gravity_torques);
                drop(hw);
                ports.publish(&out);
            }
            Ok(None) => {}
            Err(e) => {
                if e != last_error {
                    tracing::error!("{NAME}: {e}");
                    last_error = e;
                }
            }
        }
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            // Late: start again from now rather than run a burst of cycles.
            next = now;
        }
    }
}

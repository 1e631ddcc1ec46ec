//! The device framework: `DeviceDriver`, the `Registry` of known drivers (C++ names) and
//! `PolyDriver`, which opens a driver from a `Property` by its `device` key.
//!
//! Interface access is through `as_*` methods on `DeviceDriver` that return `None` unless
//! the driver implements that interface (the Rust form of C++ `PolyDriver::view`).

use crate::battery::IBattery;
use crate::cartesian_control::ICartesianControl;
use crate::error::{DevResult, DeviceError};
use crate::framegrabber::interfaces::{
    IFrameGrabberControls, IFrameGrabberControlsDC1394, IFrameGrabberImage,
};
use crate::frames::{IFrameTransformStorageGet, IFrameTransformStorageSet};
use crate::gaze_control::IGazeControl;
use crate::interfaces::*;
use crate::kind::{kind_of, suggest, Kind};
use crate::navigation::{INavigation2DVelocityActions, IOdometry2D};
pub use crate::params::Params;
use crate::rangefinder::IRangefinder2D;
use crate::raw_values::IRawValuesPublisher;
use crate::rgbd::IRGBDSensor;
use crate::sensors::interfaces::*;
use crate::sensors::virtual_analog::IVirtualAnalogSensor;
use parking_lot::{Mutex, RwLock};
use std::sync::{Arc, LazyLock};
use yarp_proto::{Property, Value};

/// A device shared between its owner and the wrappers attached to it.
pub type SharedDevice = Arc<Mutex<PolyDriver>>;

/// Wraps `pd` for sharing with wrappers.
pub fn shared(pd: PolyDriver) -> SharedDevice {
    Arc::new(Mutex::new(pd))
}

/// A wrapper that serves one device (C++ `IWrapper`).
pub trait IWrapper {
    fn attach(&mut self, device: SharedDevice) -> DevResult<()>;
    fn detach(&mut self) -> DevResult<()>;
}

/// A wrapper that serves several devices, each under a key (C++ `IMultipleWrapper`,
/// whose `attachAll` takes a `PolyDriverList`; the keys are the `networks` names of a
/// robotinterface `attach` action, or the device names).
pub trait IMultipleWrapper {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()>;
    fn detach_all(&mut self) -> DevResult<()>;
}

/// Implements [`IMultipleWrapper`] for a wrapper that serves exactly one device, as the
/// C++ network wrappers do: `attach_all` attaches the only device of the list and refuses
/// any other count with `$why` (which names what joins several devices, where YARP has
/// one); `detach_all` detaches it.
#[macro_export]
macro_rules! one_device_multiple_wrapper {
    ($wrapper:ty, $why:expr) => {
        impl $crate::driver::IMultipleWrapper for $wrapper {
            fn attach_all(
                &mut self,
                devices: &[(String, $crate::driver::SharedDevice)],
            ) -> $crate::error::DevResult<()> {
                match devices {
                    [(_, d)] => $crate::driver::IWrapper::attach(self, d.clone()),
                    _ => Err($crate::error::DeviceError::Unsupported($why)),
                }
            }

            fn detach_all(&mut self) -> $crate::error::DevResult<()> {
                $crate::driver::IWrapper::detach(self)
            }
        }
    };
}

/// A calibrator device (C++ `ICalibrator` as used by robotinterface's `calibrate` and
/// `park` actions on their `target`).
pub trait ICalibrator {
    fn calibrate(&mut self, target: SharedDevice) -> DevResult<()>;
    fn park(&mut self, target: SharedDevice, wait: bool) -> DevResult<()>;
    fn quit_calibrate(&mut self) -> DevResult<()> {
        Ok(())
    }
    fn quit_park(&mut self) -> DevResult<()> {
        Ok(())
    }
}

/// Declares the interfaces a device may offer, once: each view's method, trait, C++ name
/// and the [`Kind`] it makes a device. Generates [`DeviceDriver`] (a view returns `None`
/// unless the driver overrides it: the Rust form of C++ `PolyDriver::view`),
/// [`INTERFACES`] and [`interfaces_of`].
#[macro_export]
#[doc(hidden)]
macro_rules! device_interfaces {
    ($($(#[$doc:meta])* $view:ident: $trait:ident => $cpp:literal ($kind:ident),)*) => {
        /// A device driver, as C++ `yarp::dev::DeviceDriver`.
        pub trait DeviceDriver: Send {
            /// Configures and starts the device.
            fn open(&mut self, config: &Property) -> DevResult<()>;
            /// The parameters the device reads, as declared with [`$crate::device_params!`]
            /// (what `--help` prints); empty for a device that declares none.
            fn parameters(&self) -> Vec<$crate::params::ParamSpec> {
                Vec::new()
            }
            /// Stops the device; it may be reopened.
            fn close(&mut self) -> DevResult<()> {
                Ok(())
            }
            $(
                #[doc = concat!("The device as `", $cpp, "`, if it offers it.")]
                fn $view(&mut self) -> Option<&mut dyn $trait> {
                    None
                }
            )*
        }

        /// The type of each view of [`DeviceDriver`], named as the view: what [`views!`]
        /// implements a view with.
        ///
        /// [`views!`]: crate::views
        #[allow(non_camel_case_types)]
        pub mod views {
            use super::*;
            $(
                #[doc = concat!("What [`DeviceDriver::", stringify!($view), "`] returns.")]
                pub type $view<'a> = Option<&'a mut dyn $trait>;
            )*
        }

        /// Every interface a device may offer: its C++ name and the kind it makes a device,
        /// in the order of [`DeviceDriver`]'s views.
        pub const INTERFACES: &[(&str, Kind)] = &[$(($cpp, Kind::$kind)),*];

        /// The C++ names of the interfaces `d` offers, in the order of [`INTERFACES`].
        pub fn interfaces_of(d: &mut dyn DeviceDriver) -> Vec<&'static str> {
            let mut names = Vec::new();
            $(
                if d.$view().is_some() {
                    names.push($cpp);
                }
            )*
            names
        }
    };
}

crate::device_interfaces! {
    // Motor control.
    as_encoders: IEncoders => "IEncodersTimed" (Motor),
    as_position_control: IPositionControl => "IPositionControl" (Motor),
    as_velocity_control: IVelocityControl => "IVelocityControl" (Motor),
    as_velocity_direct: IVelocityDirect => "IVelocityDirect" (Motor),
    as_joint_brake: IJointBrake => "IJointBrake" (Other),
    as_joint_fault: IJointFault => "IJointFault" (Other),
    as_remote_variables: IRemoteVariables => "IRemoteVariables" (Other),
    as_control_mode: IControlMode => "IControlMode" (Motor),
    as_axis_info: IAxisInfo => "IAxisInfo" (Other),
    as_control_limits: IControlLimits => "IControlLimits" (Other),
    as_interaction_mode: IInteractionMode => "IInteractionMode" (Other),
    as_torque_control: ITorqueControl => "ITorqueControl" (Motor),
    as_motor_encoders: IMotorEncoders => "IMotorEncoders" (Other),
    as_amplifier_control: IAmplifierControl => "IAmplifierControl" (Other),
    as_motor: IMotor => "IMotor" (Other),
    as_pid_control: IPidControl => "IPidControl" (Other),
    as_current_control: ICurrentControl => "ICurrentControl" (Motor),
    as_pwm_control: IPwmControl => "IPWMControl" (Motor),
    as_position_direct: IPositionDirect => "IPositionDirect" (Other),
    as_impedance_control: IImpedanceControl => "IImpedanceControl" (Other),
    as_control_calibration: IControlCalibration => "IControlCalibration" (Other),
    as_remote_calibrator: IRemoteCalibrator => "IRemoteCalibrator" (Other),
    as_raw_values_publisher: IRawValuesPublisher => "IRawValuesPublisher" (Other),
    // Frame grabbers.
    as_frame_grabber_image: IFrameGrabberImage => "IFrameGrabberImage" (Camera),
    as_frame_grabber_controls: IFrameGrabberControls => "IFrameGrabberControls" (Other),
    as_frame_grabber_controls_dc1394: IFrameGrabberControlsDC1394 => "IFrameGrabberControlsDC1394" (Other),
    // Sensors.
    as_three_axis_gyroscopes: IThreeAxisGyroscopes => "IThreeAxisGyroscopes" (Sensor),
    as_three_axis_linear_accelerometers: IThreeAxisLinearAccelerometers => "IThreeAxisLinearAccelerometers" (Sensor),
    as_three_axis_magnetometers: IThreeAxisMagnetometers => "IThreeAxisMagnetometers" (Sensor),
    as_orientation_sensors: IOrientationSensors => "IOrientationSensors" (Sensor),
    as_six_axis_force_torque_sensors: ISixAxisForceTorqueSensors => "ISixAxisForceTorqueSensors" (Sensor),
    as_skin_patches: ISkinPatches => "ISkinPatches" (Sensor),
    as_encoder_arrays: IEncoderArrays => "IEncoderArrays" (Sensor),
    as_temperature_sensors: ITemperatureSensors => "ITemperatureSensors" (Sensor),
    as_analog_sensor: IAnalogSensor => "IAnalogSensor" (Sensor),
    as_virtual_analog_sensor: IVirtualAnalogSensor => "IVirtualAnalogSensor" (Sensor),
    // Lasers, RGB-D cameras, batteries, mobile bases, frames.
    as_rangefinder_2d: IRangefinder2D => "IRangefinder2D" (Sensor),
    as_rgbd_sensor: IRGBDSensor => "IRGBDSensor" (Camera),
    as_battery: IBattery => "IBattery" (Sensor),
    as_odometry_2d: IOdometry2D => "IOdometry2D" (Sensor),
    as_navigation_2d_velocity: INavigation2DVelocityActions => "INavigation2DVelocityActions" (Motor),
    as_frame_transform_storage_get: IFrameTransformStorageGet => "IFrameTransformStorageGet" (Other),
    as_frame_transform_storage_set: IFrameTransformStorageSet => "IFrameTransformStorageSet" (Other),
    // Operational-space control.
    as_cartesian_control: ICartesianControl => "ICartesianControl" (Other),
    as_gaze_control: IGazeControl => "IGazeControl" (Other),
    // Wrappers and calibrators.
    as_wrapper: IWrapper => "IWrapper" (Wrapper),
    as_multiple_wrapper: IMultipleWrapper => "IMultipleWrapper" (Wrapper),
    as_calibrator: ICalibrator => "ICalibrator" (Calibrator),
}

/// The `DeviceDriver` views a driver offers as itself, by name: inside
/// `impl DeviceDriver for T { ... }`, `yarp_devices::views!(as_encoders, as_axis_info);`
/// for a `T` that implements `IEncoders` and `IAxisInfo` (the types come from the one
/// declaration of the interfaces, [`views`]).
#[macro_export]
macro_rules! views {
    ($($view:ident),+ $(,)?) => {$(
        fn $view(&mut self) -> $crate::driver::views::$view<'_> {
            Some(self)
        }
    )+};
}

/// The `DeviceDriver` views of an IMU (gyroscope, linear accelerometer, magnetometer and
/// orientation sensor: fakeIMU, imuFilter, xsensmtx): use inside
/// `impl DeviceDriver for T { ... }` as `crate::imu_views!();`.
#[macro_export]
macro_rules! imu_views {
    () => {
        $crate::views!(
            as_three_axis_gyroscopes,
            as_three_axis_linear_accelerometers,
            as_three_axis_magnetometers,
            as_orientation_sensors,
        );
    };
}

/// The four multiple-analog-sensors interfaces of a device that is a single IMU, from its
/// inherent methods `status(i) -> MasStatus`, `name(i)` and `frame(i) -> DevResult<String>`
/// and one `fn(&self, i) -> DevResult<SensorMeasurement>` per family (fakeIMU, xsensmtx).
#[macro_export]
macro_rules! single_imu_interfaces {
    ($ty:ty { gyro: $gyro:ident, acc: $acc:ident, mag: $mag:ident, rpy: $rpy:ident }) => {
        $crate::single_imu_interfaces!(@one $ty, IThreeAxisGyroscopes, $gyro,
            get_nr_of_three_axis_gyroscopes, get_three_axis_gyroscope_status,
            get_three_axis_gyroscope_name, get_three_axis_gyroscope_frame_name,
            get_three_axis_gyroscope_measure);
        $crate::single_imu_interfaces!(@one $ty, IThreeAxisLinearAccelerometers, $acc,
            get_nr_of_three_axis_linear_accelerometers,
            get_three_axis_linear_accelerometer_status,
            get_three_axis_linear_accelerometer_name,
            get_three_axis_linear_accelerometer_frame_name,
            get_three_axis_linear_accelerometer_measure);
        $crate::single_imu_interfaces!(@one $ty, IThreeAxisMagnetometers, $mag,
            get_nr_of_three_axis_magnetometers, get_three_axis_magnetometer_status,
            get_three_axis_magnetometer_name, get_three_axis_magnetometer_frame_name,
            get_three_axis_magnetometer_measure);
        $crate::single_imu_interfaces!(@one $ty, IOrientationSensors, $rpy,
            get_nr_of_orientation_sensors, get_orientation_sensor_status,
            get_orientation_sensor_name, get_orientation_sensor_frame_name,
            get_orientation_sensor_measure_as_roll_pitch_yaw);
    };
    (@one $ty:ty, $iface:ident, $measure:ident, $nr:ident, $status:ident, $name:ident,
        $frame:ident, $get:ident) => {
        impl $crate::sensors::$iface for $ty {
            fn $nr(&self) -> usize {
                1
            }
            fn $status(&self, i: usize) -> $crate::sensors::MasStatus {
                self.status(i)
            }
            fn $name(&self, i: usize) -> $crate::error::DevResult<String> {
                self.name(i)
            }
            fn $frame(&self, i: usize) -> $crate::error::DevResult<String> {
                self.frame(i)
            }
            fn $get(
                &self,
                i: usize,
            ) -> $crate::error::DevResult<$crate::sensors::SensorMeasurement> {
                self.$measure(i)
            }
        }
    };
}

/// The `DeviceDriver` views of a driver that implements every motor-control interface
/// (fakeMotionControl, remote_controlboard, controlboardremapper): use inside
/// `impl DeviceDriver for T { ... }` as `crate::motor_control_views!();`.
#[macro_export]
macro_rules! motor_control_views {
    () => {
        $crate::views!(
            as_encoders,
            as_position_control,
            as_velocity_control,
            as_control_mode,
            as_axis_info,
            as_control_limits,
            as_interaction_mode,
            as_torque_control,
            as_motor_encoders,
            as_amplifier_control,
            as_motor,
            as_pid_control,
            as_current_control,
            as_pwm_control,
            as_position_direct,
            as_impedance_control,
            as_control_calibration,
        );
    };
}

/// Makes a fresh, unopened driver.
pub type Factory = fn() -> Box<dyn DeviceDriver>;

/// One known driver: its C++ name, the crate that provides it and its factory.
#[derive(Clone, Copy)]
pub struct DriverEntry {
    pub name: &'static str,
    /// The cargo crate the driver comes from (`yarp-devices`, `icubmod`, ...), shown by
    /// `yarpdev --list` as C++ shows a plugin's library.
    pub provider: &'static str,
    pub factory: Factory,
}

/// The drivers known to this process, by C++ name.
///
/// Each device crate adds its own drivers with a `register(&mut Registry)` function; this
/// crate's are added when the table is first used (`crate::register`), those of the
/// others by the program that links them, before it opens devices:
///
/// ```
/// # mod icubmod { pub fn register(_: &mut yarp_devices::Registry) {} }
/// yarp_devices::Registry::install(icubmod::register);
/// ```
///
/// Registration is explicit rather than distributed (`inventory`, `linkme`): those collect
/// entries through linker sections, so a device crate that nothing references is silently
/// dropped from the link and its devices vanish, and a test binary gets whatever happens
/// to be linked; here a program or test registers exactly the crates it names, and the
/// framework never names a driver module (no import circle between registry and drivers).
#[derive(Default)]
pub struct Registry {
    drivers: Vec<DriverEntry>,
}

/// The process-wide table.
static TABLE: LazyLock<RwLock<Registry>> = LazyLock::new(|| {
    let mut table = Registry::default();
    crate::register(&mut table);
    RwLock::new(table)
});

fn table() -> parking_lot::RwLockReadGuard<'static, Registry> {
    TABLE.read()
}

impl Registry {
    /// Adds `provider`'s drivers. Adding the same driver again is a no-op, so that each
    /// test may register what it needs; one name from two crates is a programming error.
    pub fn add(&mut self, provider: &'static str, drivers: &[(&'static str, Factory)]) {
        for &(name, factory) in drivers {
            match self.drivers.iter().find(|e| e.name == name) {
                Some(e) if e.provider == provider => {}
                Some(e) => panic!(
                    "device {name:?} registered by both {} and {provider}",
                    e.provider
                ),
                None => self.drivers.push(DriverEntry {
                    name,
                    provider,
                    factory,
                }),
            }
        }
    }

    /// Runs a device crate's `register` on the process-wide table.
    pub fn install(register: impl FnOnce(&mut Registry)) {
        register(&mut TABLE.write());
    }

    /// Every known driver, sorted by name (case-insensitive).
    pub fn entries() -> Vec<DriverEntry> {
        let mut entries = table().drivers.clone();
        entries.sort_unstable_by_key(|e| e.name.to_lowercase());
        entries
    }

    /// Every known device name.
    pub fn names() -> Vec<&'static str> {
        Self::entries().iter().map(|e| e.name).collect()
    }

    /// Whether a driver called `name` is known.
    pub fn knows(name: &str) -> bool {
        table().drivers.iter().any(|e| e.name == name)
    }

    /// The crate that provides driver `name`.
    pub fn provider(name: &str) -> Option<&'static str> {
        table()
            .drivers
            .iter()
            .find(|e| e.name == name)
            .map(|e| e.provider)
    }

    /// The C++ names of the interfaces driver `name` offers (read from a fresh,
    /// unopened instance), and the kind they make it.
    pub fn interfaces(name: &str) -> Option<(Vec<&'static str>, Kind)> {
        let factory = table()
            .drivers
            .iter()
            .find(|e| e.name == name)
            .map(|e| e.factory)?;
        let interfaces = interfaces_of(factory().as_mut());
        let kind = kind_of(&interfaces);
        Some((interfaces, kind))
    }

    /// A fresh (unopened) driver; an unknown name lists the closest known names, and
    /// devices of the kind the name asks for (motor devices for a motor-like name).
    pub fn get(name: &str) -> DevResult<Box<dyn DeviceDriver>> {
        let factory = table()
            .drivers
            .iter()
            .find(|e| e.name == name)
            .map(|e| e.factory);
        if let Some(f) = factory {
            return Ok(f());
        }
        let known: Vec<(&str, Kind)> = Self::entries()
            .into_iter()
            .map(|e| (e.name, kind_of(&interfaces_of((e.factory)().as_mut()))))
            .collect();
        let s = suggest(name, &known);
        Err(DeviceError::UnknownDevice {
            name: name.to_string(),
            closest: s.names,
            kind: s.kind,
        })
    }
}

/// An opened device chosen by the `device` key of its configuration (C++ `PolyDriver`).
pub struct PolyDriver {
    name: String,
    driver: Box<dyn DeviceDriver>,
    open: bool,
    /// The device a wrapper opened through its `subdevice` key; closed after the wrapper.
    subdevice: Option<SharedDevice>,
}

impl PolyDriver {
    /// Opens the driver named by `config`'s `device` key with the whole `config`.
    ///
    /// A wrapper given a `subdevice` key first opens that device with the same
    /// configuration and attaches to it, as C++ `yarpdev --device W --subdevice D` does.
    pub fn open(config: &Property) -> DevResult<PolyDriver> {
        let name = match config.find("device") {
            None => return Err(DeviceError::NoDeviceName),
            Some(v) => v.to_string_bare(),
        };
        let mut driver = Registry::get(&name)?;
        driver.open(config)?;
        let mut pd = PolyDriver {
            name,
            driver,
            open: true,
            subdevice: None,
        };
        if let Some(sub) = config.find("subdevice").map(Value::to_string_bare) {
            if pd.driver.as_wrapper().is_none() && pd.driver.as_multiple_wrapper().is_none() {
                return Err(DeviceError::BadParam {
                    device: pd.name.clone(),
                    param: "subdevice".into(),
                    expected: "absent (this device is not a wrapper)",
                    got: sub,
                });
            }
            let mut sub_config = config.clone();
            sub_config.put("device", Value::from(sub.as_str()));
            sub_config.unput("subdevice");
            let sub = shared(PolyDriver::open(&sub_config)?);
            match pd.driver.as_wrapper() {
                Some(w) => w.attach(sub.clone())?,
                None => {
                    let key = sub.lock().name.clone();
                    if let Some(w) = pd.driver.as_multiple_wrapper() {
                        w.attach_all(&[(key, sub.clone())])?;
                    }
                }
            }
            pd.subdevice = Some(sub);
        }
        Ok(pd)
    }

    /// Wraps an already-made driver (opened by the caller) in a `PolyDriver`.
    pub fn from_driver(name: &str, driver: Box<dyn DeviceDriver>) -> PolyDriver {
        PolyDriver {
            name: name.to_string(),
            driver,
            open: true,
            subdevice: None,
        }
    }

    /// The driver's C++ name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The driver, to reach its interfaces (`pd.device().as_encoders()`).
    pub fn device(&mut self) -> &mut dyn DeviceDriver {
        self.driver.as_mut()
    }

    pub fn is_open(&self) -> bool {
        self.open
    }

    pub fn close(&mut self) -> DevResult<()> {
        if !self.open {
            return Ok(());
        }
        self.open = false;
        if self.subdevice.is_some() {
            if let Some(w) = self.driver.as_wrapper() {
                let _ = w.detach();
            } else if let Some(w) = self.driver.as_multiple_wrapper() {
                let _ = w.detach_all();
            }
        }
        let result = self.driver.close();
        if let Some(sub) = self.subdevice.take() {
            let _ = sub.lock().close();
        }
        result
    }
}

impl Drop for PolyDriver {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

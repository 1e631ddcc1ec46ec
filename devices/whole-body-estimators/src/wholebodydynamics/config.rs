//! What `wholebodydynamics` reads from its configuration: the declared parameters
//! (`yarpdev --device wholebodydynamics --help` prints them) and the groups whose keys
//! the robot's file chooses (output ports, per-sensor calibration matrices and offsets).

use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::params::FloatOnly;
use yarp_proto::{Bottle, Property, Value};

use super::NAME;

yarp_devices::device_params! {
    /// What `wholebodydynamics` reads (whole-body-estimators' `WholeBodyDynamicsDevice`).
    pub struct WbdParams for "wholebodydynamics" {
        // In the order C++'s open reads them (its first missing one is ours): the F/T
        // sensors' remapper, the estimator, the settings, then the rest.
        /// The F/T sensors used, by name (each a force_torque sensor of the URDF), in this order
        "multipleAnalogSensorsNames::SixAxisForceTorqueSensorsNames" ft_names: Vec<String> = required,
        /// The joints estimated, by name: the model's degrees of freedom in this order,
        /// found on the attached boards by their axis names
        "axesNames" axes_names: Vec<String> = required,
        /// Fixed joints kept in the model besides the F/T sensors'
        "additionalConsideredFixedJoints" additional_fixed_joints: Vec<String> = optional,
        /// The URDF, found as the ResourceFinder finds files (robots/$YARP_ROBOT_NAME/ in
        /// the data directories)
        "modelFile" model_file: String = "model.urdf",
        /// Gravity in the fixed frame
        "fixedFrameGravity" fixed_frame_gravity: Vec<f64> = required; "m/s^2",
        /// Take this frame as fixed in the world instead of reading the IMU
        "assume_fixed" assume_fixed: String = optional,
        /// The model frame the IMU's measurements are expressed in
        "imuFrameName" imu_frame_name: String = optional,
        /// Prefix of the device's ports
        "portPrefix" port_prefix: String = "/wholeBodyDynamics",
        /// Period of the estimation
        "devicePeriodInSeconds" period: FloatOnly = 0.01; "s"; check yarp_devices::params::positive_float,
        /// Stream each F/T sensor's filtered, offset-free measurement on <prefix>/filteredFT/<sensor>
        "streamFilteredFT" stream_filtered_ft: bool = false,
        /// Take the contacts from the skin (<prefix>/skin_contacts:i)
        "useSkinForContacts" use_skin_for_contacts: bool = true,
        /// Use the joints' velocities in the dynamics
        "useJointVelocity" use_joint_velocity: bool = true,
        /// Use the joints' accelerations in the dynamics
        "useJointAcceleration" use_joint_acceleration: bool = true,
        /// Estimate the joints' velocities and accelerations with a Kalman filter
        "estimateJointVelocityAcceleration" estimate_joint_velocity_acceleration: bool = false,
        /// Cut-off of the IMU's low-pass filter
        "imuFilterCutoffInHz" imu_cutoff: FloatOnly = required; "Hz",
        /// Cut-off of the F/T sensors' low-pass filter
        "forceTorqueFilterCutoffInHz" ft_cutoff: FloatOnly = required; "Hz",
        /// Cut-off of the joint velocities' low-pass filter (required with useJointVelocity)
        "jointVelFilterCutoffInHz" joint_vel_cutoff: FloatOnly = optional; "Hz",
        /// Cut-off of the joint accelerations' low-pass filter (required with useJointAcceleration)
        "jointAccFilterCutoffInHz" joint_acc_cutoff: FloatOnly = optional; "Hz",
        /// Start with zero F/T offsets instead of calibrating them (base_link held, 100 samples)
        "startWithZeroFTSensorOffsets" start_with_zero_offsets: bool = false,
        /// Do not wait for the F/T sensors and the IMU to read at attach
        "disableSensorReadCheckAtStartup" disable_read_check: bool = false,
        /// The IMU's accelerometer, by its multiple-analog-sensors name
        "HW_USE_MAS_IMU::accelerometer" accelerometer: String = required,
        /// The IMU's gyroscope, by its multiple-analog-sensors name
        "HW_USE_MAS_IMU::gyroscope" gyroscope: String = required,
        /// Frames of a full-wrench contact, the first of each submodel taken
        "defaultContactFrames" default_contact_frames: Vec<String> = optional,
        /// Contact frames replacing defaultContactFrames, with their types
        "overrideContactFrames" override_contact_frames: Vec<String> = optional,
        /// One per override frame: full, pure or pureKnown
        "contactWrenchType" contact_wrench_type: Vec<String> = optional,
        /// Three per override frame: a pureKnown force's direction in the frame
        "contactWrenchDirection" contact_wrench_direction: Vec<f64> = optional,
        /// Three per override frame: the contact point in the frame
        "contactWrenchPosition" contact_wrench_position: Vec<f64> = optional; "m",
        /// Send gravity compensation torques to the compliant joints
        "GRAVITY_COMPENSATION::enableGravityCompensation" gravity_compensation: bool = optional,
        /// The link gravity compensation holds the robot from
        "GRAVITY_COMPENSATION::gravityCompensationBaseLink" gravity_compensation_base_link: String = optional,
        /// The axes gravity compensation serves
        "GRAVITY_COMPENSATION::gravityCompensationAxesNames" gravity_compensation_axes: Vec<String> = optional,
        /// netWrench (each port's link's net external wrench) or contactWrenches
        "outputWrenchPortInfoType" output_wrench_port_info_type: String = "netWrench",
        /// Publish every link's net external wrench on <prefix>/netExternalWrenches:o
        "publishNetExternalWrenches" publish_net_external_wrenches: bool = false,
    }
}

/// A port of `WBD_OUTPUT_EXTERNAL_WRENCH_PORTS`: the net external wrench on `link`,
/// about `origin`'s origin, in `orientation`'s axes.
#[derive(Debug, Clone, PartialEq)]
pub struct WrenchPort {
    pub port: String,
    pub link: String,
    pub origin: String,
    pub orientation: String,
}

/// The contact type of an override frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WrenchType {
    Full,
    Pure,
    PureKnown([f64; 3]),
}

/// Everything read, checked as C++ checks it at open.
#[derive(Debug, Clone)]
pub struct Config {
    pub params: WbdParams,
    /// `(frame, type, contact point in the frame)`.
    pub contacts: Vec<(String, WrenchType, [f64; 3])>,
    pub wrench_ports: Vec<WrenchPort>,
    /// `FT_SECONDARY_CALIBRATION`: a row-major 6×6 matrix per sensor.
    pub secondary_calibration: Vec<(String, [f64; 36])>,
    /// `FT_OFFSET`: the pre-estimated offsets `usePreEstimatedOffset` applies.
    pub pre_estimated_offsets: Vec<(String, [f64; 6])>,
    /// `GRAVITY_COMPENSATION` enabled: the base link and the axes.
    pub gravity_compensation: Option<(String, Vec<String>)>,
    /// Whether `FT_TEMPERATURE_COEFFICIENTS` is there (C++ then reads the sensors'
    /// temperatures; its coefficients are never loaded).
    pub temperature_compensation: bool,
}

fn bad(param: &str, expected: &'static str, got: impl ToString) -> DeviceError {
    DeviceError::BadParam {
        device: NAME.into(),
        param: param.into(),
        expected,
        got: got.to_string(),
    }
}

fn missing(param: &str) -> DeviceError {
    DeviceError::MissingParam {
        device: NAME.into(),
        param: param.into(),
    }
}

/// The `(key value…)` lines of a group, without its name.
fn group_lines<'a>(
    config: &'a Property,
    group: &str,
) -> Option<impl Iterator<Item = (String, &'a [Value])>> {
    let g: &Bottle = config.find_group(group)?;
    Some(g.items().iter().skip(1).filter_map(|v| {
        let line = v.as_list()?;
        let (key, rest) = line.items().split_first()?;
        Some((key.to_string_bare(), rest))
    }))
}

/// The numbers of a group line: `(name (n1 n2 …))` or `(name n1 n2 …)`.
fn numbers(rest: &[Value]) -> Option<Vec<f64>> {
    let items = match rest {
        [v] if v.is_list() => v.as_list()?.items(),
        _ => rest,
    };
    items.iter().map(Value::as_f64).collect()
}

fn strings(rest: &[Value]) -> Vec<String> {
    let items = match rest {
        [v] if v.is_list() => v.as_list().map(Bottle::items).unwrap_or_default(),
        _ => rest,
    };
    items.iter().map(Value::to_string_bare).collect()
}

impl Config {
    pub fn read(config: &Property) -> DevResult<Config> {
        let mut params = WbdParams::read(config)?;
        // C++ trims nothing, but its list parser splits at commas and spaces alike
        params.axes_names.retain(|s| !s.is_empty());
        if params.fixed_frame_gravity.len() != 3 {
            return Err(bad(
                "fixedFrameGravity",
                "three numbers",
                format!("{:?}", params.fixed_frame_gravity),
            ));
        }
        if params.assume_fixed.is_none() && params.imu_frame_name.is_none() {
            return Err(missing("imuFrameName"));
        }
        if params.use_joint_velocity && params.joint_vel_cutoff.is_none() {
            return Err(missing("jointVelFilterCutoffInHz"));
        }
        if params.use_joint_acceleration && params.joint_acc_cutoff.is_none() {
            return Err(missing("jointAccFilterCutoffInHz"));
        }
        let contacts = Self::contacts(&params)?;
        let mut wrench_ports = Vec::new();
        if let Some(lines) = group_lines(config, "WBD_OUTPUT_EXTERNAL_WRENCH_PORTS") {
            for (port, rest) in lines {
                if ["outputWrenchPortInfoType", "publishNetExternalWrenches"]
                    .contains(&port.as_str())
                {
                    continue;
                }
                let names = strings(rest);
                let (link, origin, orientation) = match names.as_slice() {
                    [link, frame] => (link.clone(), frame.clone(), frame.clone()),
                    [link, origin, orientation] => {
                        (link.clone(), origin.clone(), orientation.clone())
                    }
                    _ => {
                        return Err(bad(
                            &format!("WBD_OUTPUT_EXTERNAL_WRENCH_PORTS::{port}"),
                            "(link, frame) or (link, originFrame, orientationFrame)",
                            names.join(" "),
                        ))
                    }
                };
                wrench_ports.push(WrenchPort {
                    port,
                    link,
                    origin,
                    orientation,
                });
            }
        } else {
            // C++ reads these two only inside the group's presence
            params.publish_net_external_wrenches = false;
        }
        let mut secondary_calibration = Vec::new();
        for (name, rest) in group_lines(config, "FT_SECONDARY_CALIBRATION")
            .into_iter()
            .flatten()
        {
            let m: [f64; 36] = numbers(rest)
                .and_then(|v| v.try_into().ok())
                .ok_or_else(|| {
                    bad(
                        &format!("FT_SECONDARY_CALIBRATION::{name}"),
                        "36 numbers (a 6x6 matrix by rows): the group is malformed",
                        name.clone(),
                    )
                })?;
            secondary_calibration.push((name, m));
        }
        let mut pre_estimated_offsets = Vec::new();
        for (name, rest) in group_lines(config, "FT_OFFSET").into_iter().flatten() {
            let o: [f64; 6] = numbers(rest)
                .and_then(|v| v.try_into().ok())
                .ok_or_else(|| bad(&format!("FT_OFFSET::{name}"), "6 numbers", name.clone()))?;
            pre_estimated_offsets.push((name, o));
        }
        let gravity_compensation = if config.find_group("GRAVITY_COMPENSATION").is_some() {
            let enabled = params
                .gravity_compensation
                .ok_or_else(|| missing("GRAVITY_COMPENSATION::enableGravityCompensation"))?;
            let base = params
                .gravity_compensation_base_link
                .clone()
                .ok_or_else(|| missing("GRAVITY_COMPENSATION::gravityCompensationBaseLink"))?;
            let axes = params
                .gravity_compensation_axes
                .clone()
                .ok_or_else(|| missing("GRAVITY_COMPENSATION::gravityCompensationAxesNames"))?;
            enabled.then_some((base, axes))
        } else {
            tracing::warn!(
                "{NAME}: no GRAVITY_COMPENSATION group: gravity compensation is disabled"
            );
            None
        };
        Ok(Config {
            params,
            contacts,
            wrench_ports,
            secondary_calibration,
            pre_estimated_offsets,
            gravity_compensation,
            temperature_compensation: config.find_group("FT_TEMPERATURE_COEFFICIENTS").is_some(),
        })
    }

    fn contacts(p: &WbdParams) -> DevResult<Vec<(String, WrenchType, [f64; 3])>> {
        let Some(frames) = &p.override_contact_frames else {
            let frames = p
                .default_contact_frames
                .as_ref()
                .ok_or_else(|| missing("defaultContactFrames"))?;
            return Ok(frames
                .iter()
                .map(|f| (f.clone(), WrenchType::Full, [0.0; 3]))
                .collect());
        };
        let n = frames.len();
        let types = p
            .contact_wrench_type
            .as_ref()
            .ok_or_else(|| missing("contactWrenchType"))?;
        let dirs = p
            .contact_wrench_direction
            .as_ref()
            .ok_or_else(|| missing("contactWrenchDirection"))?;
        let pos = p
            .contact_wrench_position
            .as_ref()
            .ok_or_else(|| missing("contactWrenchPosition"))?;
        if types.len() != n || dirs.len() != 3 * n || pos.len() != 3 * n {
            return Err(bad("overrideContactFrames", "one contactWrenchType and three contactWrenchDirection and contactWrenchPosition values per frame", n));
        }
        frames
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let three = |v: &[f64]| [v[3 * i], v[3 * i + 1], v[3 * i + 2]];
                let kind = match types[i].as_str() {
                    "full" => WrenchType::Full,
                    "pure" => WrenchType::Pure,
                    "pureKnown" => WrenchType::PureKnown(three(dirs)),
                    other => {
                        return Err(bad("contactWrenchType", "full, pure or pureKnown", other))
                    }
                };
                Ok((f.clone(), kind, three(pos)))
            })
            .collect()
    }
}

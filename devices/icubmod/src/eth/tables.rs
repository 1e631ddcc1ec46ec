//! The parameter table of each `embObj*` device, as `yarpdev --device X --help` prints it
//! and [`yarp_devices::DeviceDriver::parameters`] gives it: the Ethernet groups every
//! device reads ([`super::params`]) and the device's own rows.
//!
//! The own rows are declared here because their readers follow icub-main's parsers line by
//! line (a group named by another parameter, a line of the wrong length counting as absent):
//! the test `eth_param_tables` opens every device of every robot of robots-configuration
//! and checks that each parameter looked up is a row here and each row is looked up.
//! A group whose name the file chooses is written `<...>` (`<PID group>::kp`,
//! `JOINTSET_<n>`).

use yarp_devices::params::ParamSpec;

use super::params::{EthBoardDeclared, Pc104Params, ServiceParams};

yarp_devices::param_table! {
    /// `SERVICE::PROPERTIES::CANBOARDS`: the CAN boards behind the Ethernet board, checked
    /// by the board before it runs the service (every service but the skin's may have them).
    pub const CAN_BOARDS = [
        /// The CAN board type (foc, strain2, mtb4, rfe, pmc, ...)
        "SERVICE::PROPERTIES::CANBOARDS::type": String = optional,
        /// The CAN protocol's major version the boards must speak
        "SERVICE::PROPERTIES::CANBOARDS::PROTOCOL::major": f64 = optional,
        /// The CAN protocol's minor version
        "SERVICE::PROPERTIES::CANBOARDS::PROTOCOL::minor": f64 = optional,
        /// The firmware's major version the boards must run
        "SERVICE::PROPERTIES::CANBOARDS::FIRMWARE::major": f64 = optional,
        /// The firmware's minor version
        "SERVICE::PROPERTIES::CANBOARDS::FIRMWARE::minor": f64 = optional,
        /// The firmware's build
        "SERVICE::PROPERTIES::CANBOARDS::FIRMWARE::build": f64 = optional,
    ];
}

yarp_devices::param_table! {
    /// What the analog sensor services share: the sensors and their rate.
    pub const SENSORS = [
        /// The sensors' names, one per sensor
        "SERVICE::PROPERTIES::SENSORS::id": Vec<String> = required,
        /// Where each sensor is (CAN1:13, CAN2:1:0, loc:..., ...)
        "SERVICE::PROPERTIES::SENSORS::location": Vec<String> = optional,
        /// The sensors the service acquires (all of them when absent)
        "SERVICE::SETTINGS::enabledSensors": Vec<String> = optional,
    ];
}

yarp_devices::param_table! {
    /// The sensor services with one acquisition period for all their sensors.
    pub const ACQUISITION = [
        /// The acquisition period (10 ms by default, embObjPOS 50 ms)
        "SERVICE::SETTINGS::acquisitionRate": f64 = optional; "ms",
    ];
}

yarp_devices::param_table! {
    /// `embObjMotionControl`'s rows (icub-main `eomcParser`, `ServiceParser`).
    pub const MOTION_CONTROL = [
        /// The board's joints
        "GENERAL::Joints": f64 = required,
        /// Logical joint -> board joint (in order by default)
        "GENERAL::AxisMap": Vec<f64> = optional,
        /// Each joint's name
        "GENERAL::AxisName": Vec<String> = required,
        /// Each joint's type (revolute by default)
        "GENERAL::AxisType": Vec<String> = optional,
        /// Encoder units per degree, per joint
        "GENERAL::Encoder": Vec<f64> = required; "units/deg",
        /// PWM counts at full scale, per joint
        "GENERAL::fullscalePWM": Vec<f64> = (32000); "counts",
        /// Current sensor units per ampere, per joint
        "GENERAL::ampsToSensor": Vec<f64> = (1000); "units/A",
        /// Motor-to-joint gearbox ratio, per joint
        "GENERAL::Gearbox_M2J": Vec<f64> = (1),
        /// Encoder-to-joint gearbox ratio, per joint
        "GENERAL::Gearbox_E2J": Vec<f64> = (1),
        /// 1 where a joint set uses the motor's speed feedback, per joint
        "GENERAL::useMotorSpeedFbk": Vec<f64> = (0),
        /// Software position limits, per joint
        "LIMITS::jntPosMax": Vec<f64> = required; "deg",
        /// Software position limits, per joint
        "LIMITS::jntPosMin": Vec<f64> = required; "deg",
        /// Hardware position limits, per joint
        "LIMITS::hardwareJntPosMax": Vec<f64> = (0); "deg",
        /// Hardware position limits, per joint
        "LIMITS::hardwareJntPosMin": Vec<f64> = (0); "deg",
        /// Velocity limit, per joint
        "LIMITS::jntVelMax": Vec<f64> = (0); "deg/s",
        /// Motor nominal current, per joint
        "LIMITS::motorNominalCurrents": Vec<f64> = (0); "mA",
        /// Motor peak current, per joint
        "LIMITS::motorPeakCurrents": Vec<f64> = (0); "mA",
        /// Motor overload current, per joint
        "LIMITS::motorOverloadCurrents": Vec<f64> = (0); "mA",
        /// Motor PWM limit, per joint
        "LIMITS::motorPwmLimit": Vec<f64> = (0); "counts",
        /// Rotor position limits, per joint
        "LIMITS::rotorPosMin": Vec<f64> = (0); "deg",
        /// Rotor position limits, per joint
        "LIMITS::rotorPosMax": Vec<f64> = (0); "deg",
        /// Motor temperature the board stops at, per joint (0: none)
        "LIMITS::hardwareTemperatureLimits": Vec<f64> = (0); "degC",
        /// Motor temperature warned about (below 85 % of the hardware limit), per joint
        "LIMITS::warningTemperatureLimits": Vec<f64> = (0); "degC",
        /// Each joint's position PID group (none for none)
        "CONTROLS::positionControl": Vec<String> = optional,
        /// Each joint's torque PID group
        "CONTROLS::torqueControl": Vec<String> = optional,
        /// Each joint's current PID group
        "CONTROLS::currentPid": Vec<String> = optional,
        /// Each joint's speed PID group
        "CONTROLS::speedPid": Vec<String> = optional,
        /// The PID's output: pwm, velocity or current
        "<PID group>::outputType": String = optional,
        /// metric_units or machine_units (joint 0's hold for the board)
        "<PID group>::fbkControlUnits": String = required,
        /// dutycycle_percent or machine_units
        "<PID group>::outputControlUnits": String = required,
        /// Proportional gain, per joint
        "<PID group>::kp": Vec<f64> = (0),
        /// Derivative gain, per joint
        "<PID group>::kd": Vec<f64> = (0),
        /// Integral gain, per joint
        "<PID group>::ki": Vec<f64> = (0),
        /// Output limit, per joint
        "<PID group>::maxOutput": Vec<f64> = (0),
        /// Integral limit, per joint
        "<PID group>::maxInt": Vec<f64> = (0),
        /// Stiction compensation up (position and torque PIDs), per joint
        "<PID group>::stictionUp": Vec<f64> = (0),
        /// Stiction compensation down (position and torque PIDs), per joint
        "<PID group>::stictionDown": Vec<f64> = (0),
        /// Feed-forward gain, per joint
        "<PID group>::kff": Vec<f64> = (0),
        /// Output shift (current and speed PIDs), per joint
        "<PID group>::shift": Vec<f64> = (0),
        /// Torque constant (torque PIDs), per joint
        "<PID group>::ktau": Vec<f64> = (0),
        /// Back-EMF constant (torque PIDs), per joint
        "<PID group>::kbemf": Vec<f64> = (0),
        /// Viscous friction, positive direction (torque PIDs), per joint
        "<PID group>::viscousPos": Vec<f64> = (0),
        /// Viscous friction, negative direction (torque PIDs), per joint
        "<PID group>::viscousNeg": Vec<f64> = (0),
        /// Coulomb friction, positive direction (torque PIDs), per joint
        "<PID group>::coulombPos": Vec<f64> = (0),
        /// Coulomb friction, negative direction (torque PIDs), per joint
        "<PID group>::coulombNeg": Vec<f64> = (0),
        /// Velocity threshold of the friction model (torque PIDs), per joint
        "<PID group>::velocityThres": Vec<f64> = (0),
        /// The torque filter (torque PIDs), per joint
        "<PID group>::filterType": Vec<f64> = (0),
        /// Joint stiffness, per joint
        "IMPEDANCE::stiffness": Vec<f64> = (0); "Nm/deg",
        /// Joint damping, per joint
        "IMPEDANCE::damping": Vec<f64> = (0); "Nm/(deg/s)",
        /// Velocity command timeout, per joint (300 for eomn_serv_MC_advfoc)
        "TIMEOUTS::velocity": Vec<f64> = (100); "ms",
        /// Current command timeout, per joint
        "TIMEOUTS::current": Vec<f64> = (100); "ms",
        /// PWM command timeout, per joint
        "TIMEOUTS::pwm": Vec<f64> = (100); "ms",
        /// Torque command timeout, per joint
        "TIMEOUTS::torque": Vec<f64> = (100); "ms",
        /// Torque measure timeout, per joint
        "TIMEOUTS::torque_measure": Vec<f64> = (100); "ms",
        /// Dead zone, per joint (else the joint encoder's default)
        "OTHER_CONTROL_PARAMETERS::deadZone": Vec<f64> = optional; "deg",
        /// Per joint: the Kalman filter runs (the group's nine lines are all needed)
        "KALMAN_FILTER::kalmanFilterEnabled": Vec<String> = optional,
        /// Initial state, per joint
        "KALMAN_FILTER::x0": Vec<f64> = optional,
        /// Initial state, per joint
        "KALMAN_FILTER::x1": Vec<f64> = optional,
        /// Initial state, per joint
        "KALMAN_FILTER::x2": Vec<f64> = optional,
        /// Process noise, per joint
        "KALMAN_FILTER::Q0": Vec<f64> = optional,
        /// Process noise, per joint
        "KALMAN_FILTER::Q1": Vec<f64> = optional,
        /// Process noise, per joint
        "KALMAN_FILTER::Q2": Vec<f64> = optional,
        /// Measurement noise, per joint
        "KALMAN_FILTER::R": Vec<f64> = optional,
        /// Initial covariance, per joint
        "KALMAN_FILTER::P0": Vec<f64> = optional,
        /// LuGre friction model, per motor (the group's nine lines are all needed)
        "LUGRE::Km": Vec<f64> = optional,
        /// LuGre model, per motor
        "LUGRE::Kw": Vec<f64> = optional,
        /// LuGre model, per motor
        "LUGRE::S0": Vec<f64> = optional,
        /// LuGre model, per motor
        "LUGRE::S1": Vec<f64> = optional,
        /// LuGre model, per motor
        "LUGRE::Vth": Vec<f64> = optional,
        /// LuGre model, per motor
        "LUGRE::Fc_pos": Vec<f64> = optional,
        /// LuGre model, per motor
        "LUGRE::Fc_neg": Vec<f64> = optional,
        /// LuGre model, per motor
        "LUGRE::Fs_pos": Vec<f64> = optional,
        /// LuGre model, per motor
        "LUGRE::Fs_neg": Vec<f64> = optional,
        /// Per joint: the motor has Hall sensors (group 2FOC, AMCBLDC or ADVFOC by service)
        "<motor group>::HasHallSensor": Vec<f64> = required,
        /// Per joint: the motor has a temperature sensor
        "<motor group>::HasTempSensor": Vec<f64> = required,
        /// Per joint: PT100, PT1000 or NONE
        "<motor group>::TemperatureSensorType": Vec<String> = optional,
        /// Per joint: the motor has a rotor encoder
        "<motor group>::HasRotorEncoder": Vec<f64> = required,
        /// Per joint: the rotor encoder has an index
        "<motor group>::HasRotorEncoderIndex": Vec<f64> = required,
        /// Per joint: the motor has a speed encoder
        "<motor group>::HasSpeedEncoder": Vec<f64> = (0),
        /// Per joint: the board reports on the motor
        "<motor group>::Verbose": Vec<f64> = required,
        /// Per joint: the rotor's index offset is found by the board
        "<motor group>::AutoCalibration": Vec<f64> = required,
        /// Rotor index offset, per joint (0..359)
        "<motor group>::RotorIndexOffset": Vec<f64> = required; "deg",
        /// Motor poles, per joint
        "<motor group>::MotorPoles": Vec<f64> = required,
        /// Back-EMF constant, per joint
        "<motor group>::Kbemf": Vec<f64> = (0),
        /// Skip the calibration of a joint already calibrated
        "MAINTENANCE::skipRecalibration": bool = false,
        /// Joint-to-motor coupling, 4x4 row by row
        "COUPLINGS::matrixJ2M": Vec<f64> = optional,
        /// Motor-to-joint coupling, 4x4
        "COUPLINGS::matrixM2J": Vec<f64> = optional,
        /// Encoder-to-joint coupling, 4x6
        "COUPLINGS::matrixE2J": Vec<f64> = optional,
        /// Joint sets of the board (1..4)
        "JOINTSET_CFG::numberofsets": f64 = optional,
        /// The set's joints
        "JOINTSET_CFG::JOINTSET_<n>::listofjoints": Vec<f64> = optional,
        /// The set's constraint (none, cerhand, trifidhand, ...)
        "JOINTSET_CFG::JOINTSET_<n>::constraint": String = (none),
        /// The constraint's first parameter
        "JOINTSET_CFG::JOINTSET_<n>::param1": f64 = (0),
        /// The constraint's second parameter
        "JOINTSET_CFG::JOINTSET_<n>::param2": f64 = (0),
        /// The Ethernet board's type as the service names it
        "SERVICE::PROPERTIES::ETHBOARD::type": String = optional,
        /// Per joint: the actuator (foc, mc4, pwm, advfoc, ...)
        "SERVICE::PROPERTIES::JOINTMAPPING::ACTUATOR::type": Vec<String> = optional,
        /// Per joint: where the actuator is (CAN1:1:0, ...)
        "SERVICE::PROPERTIES::JOINTMAPPING::ACTUATOR::port": Vec<String> = optional,
        /// Per joint: the actuator's board (advfoc)
        "SERVICE::PROPERTIES::JOINTMAPPING::ACTUATOR::onboard": Vec<String> = optional,
        /// Per joint: the first encoder (aea, amo, roie, ...)
        "SERVICE::PROPERTIES::JOINTMAPPING::ENCODER<n>::type": Vec<String> = optional,
        /// Per joint: where the encoder is read
        "SERVICE::PROPERTIES::JOINTMAPPING::ENCODER<n>::port": Vec<String> = optional,
        /// Per joint: atjoint, atmotor or none
        "SERVICE::PROPERTIES::JOINTMAPPING::ENCODER<n>::position": Vec<String> = optional,
        /// Per joint: the encoder's resolution
        "SERVICE::PROPERTIES::JOINTMAPPING::ENCODER<n>::resolution": Vec<f64> = optional,
        /// Per joint: the encoder's tolerance
        "SERVICE::PROPERTIES::JOINTMAPPING::ENCODER<n>::tolerance": Vec<f64> = optional,
        /// Where the MAIS of a mc4plusmais service is
        "SERVICE::PROPERTIES::MAIS::location": String = optional,
        /// Where the PSC boards of a mc2pluspsc service are
        "SERVICE::PROPERTIES::PSC::location": Vec<String> = optional,
        /// Where the POS boards of a mc4plusfaps service are
        "SERVICE::PROPERTIES::POS::location": Vec<String> = optional,
        /// What the mc4 boards broadcast
        "SERVICE::PROPERTIES::MC4::BROADCASTPOLICY::enable": Vec<String> = optional,
        /// The mc4 boards' velocity shift
        "SERVICE::PROPERTIES::MC4::SHIFTS::velocity": f64 = optional,
        /// The mc4 boards' joint velocity estimation shift
        "SERVICE::PROPERTIES::MC4::SHIFTS::estimJointVelocity": f64 = optional,
        /// The mc4 boards' joint acceleration estimation shift
        "SERVICE::PROPERTIES::MC4::SHIFTS::estimJointAcceleration": f64 = optional,
        /// The mc4 boards' motor velocity estimation shift
        "SERVICE::PROPERTIES::MC4::SHIFTS::estimMotorVelocity": f64 = optional,
        /// The mc4 boards' motor acceleration estimation shift
        "SERVICE::PROPERTIES::MC4::SHIFTS::estimMotorAcceleration": f64 = optional,
    ];
}

yarp_devices::param_table! {
    /// `embObjFTsensor`'s rows besides [`SENSORS`].
    pub const FT_SENSOR = [
        /// The strain2's temperature period (0: no temperature service)
        "SERVICE::SETTINGS::temperature-acquisitionRate": f64 = (0); "ms",
        /// Calibrated values (false: raw values)
        "SERVICE::STRAIN_SETTINGS::useCalibration": bool = true,
    ];
}

yarp_devices::param_table! {
    /// `embObjMultipleFTsensors`'s rows besides [`SENSORS`].
    pub const MULTIPLE_FT = [
        /// Each sensor's board (strain2, strain2c, ...)
        "SERVICE::PROPERTIES::SENSORS::board": Vec<String> = optional,
        /// Each sensor's frame
        "SERVICE::PROPERTIES::SENSORS::framename": Vec<String> = optional,
        /// Each enabled sensor's force-torque period
        "SERVICE::SETTINGS::ftPeriod": Vec<f64> = required; "ms",
        /// Each enabled sensor's temperature period
        "SERVICE::SETTINGS::temperaturePeriod": Vec<f64> = required; "ms",
        /// Per enabled sensor: calibrated values
        "SERVICE::SETTINGS::useCalibration": Vec<String> = required,
        /// How often the CAN monitor checks the boards
        "SERVICE::CANMONITOR::checkPeriod": f64 = optional; "ms",
        /// How often the CAN monitor reports
        "SERVICE::CANMONITOR::ratePeriod": f64 = optional; "ms",
        /// What the CAN monitor reports (NONE, ALL, JUSTLOSTJUSTFOUND, ...)
        "SERVICE::CANMONITOR::reportMode": String = optional,
    ];
}

yarp_devices::param_table! {
    /// `embObjIMU`'s and `embObjInertials`'s rows besides [`SENSORS`].
    pub const INERTIAL = [
        /// Each sensor's kind (eoas_imu_acc, eoas_accel_mtb_ext, ...)
        "SERVICE::PROPERTIES::SENSORS::type": Vec<String> = required,
        /// Each sensor's name as the robot calls it
        "SERVICE::PROPERTIES::SENSORS::sensorName": Vec<String> = optional,
        /// Each sensor's board
        "SERVICE::PROPERTIES::SENSORS::boardType": Vec<String> = optional,
    ];
}

yarp_devices::param_table! {
    /// `embObjPOS`'s rows besides [`SENSORS`].
    pub const POS = [
        /// Each sensor's board (pmc, ...)
        "SERVICE::PROPERTIES::SENSORS::boardType": Vec<String> = optional,
        /// Each sensor's port (POS:hand_thumb, ...)
        "SERVICE::PROPERTIES::SENSORS::port": Vec<String> = optional,
        /// Each sensor's connector on its board
        "SERVICE::PROPERTIES::SENSORS::connector": Vec<String> = optional,
        /// Each sensor's rotation (ROT:zero, plus180, plus090, minus090)
        "SERVICE::PROPERTIES::SENSORS::CALIBRATION::rotation": Vec<String> = optional,
        /// Each sensor's offset
        "SERVICE::PROPERTIES::SENSORS::CALIBRATION::offset": Vec<f64> = (0); "deg",
        /// Per sensor: the direction is inverted
        "SERVICE::PROPERTIES::SENSORS::CALIBRATION::invertDirection": Vec<String> = optional,
    ];
}

yarp_devices::param_table! {
    /// `embObjBattery`'s rows besides [`SENSORS`].
    pub const BATTERY = [
        /// The battery's board (bms, ...)
        "SERVICE::PROPERTIES::SENSORS::board": Vec<String> = optional,
    ];
}

yarp_devices::param_table! {
    /// `embObjSkin`'s rows (`skinSpec`, icub-main `SkinConfigReader`).
    pub const SKIN = [
        /// The MTBs' CAN addresses of patch n on CAN n
        "patches::skinCanAddrsPatch<n>": Vec<f64> = required,
        /// Every board's period
        "defaultCfgBoard::period": f64 = optional; "ms",
        /// Every board's skin type
        "defaultCfgBoard::skinType": f64 = optional,
        /// Every board's no-load value
        "defaultCfgBoard::noLoad": f64 = optional,
        /// Every board's diagnostic
        "defaultCfgBoard::diagnostic": bool = optional,
        /// Every triangle is enabled
        "defaultCfgTriangle::enabled": bool = optional,
        /// Every triangle's shift
        "defaultCfgTriangle::shift": f64 = optional,
        /// Every triangle's CDC offset
        "defaultCfgTriangle::cdcOffset": f64 = optional,
        /// How many special board settings follow
        "specialCfgBoards::numOfSets": f64 = optional,
        /// A special board setting (patch, first and last address, period, ...)
        "specialCfgBoards::boardSetCfg<n>": Vec<f64> = optional,
        /// How many special triangle settings follow
        "specialCfgTriangles::numOfSets": f64 = optional,
        /// A special triangle setting (patch, address, first and last triangle, ...)
        "specialCfgTriangles::triangleSetCfg<n>": Vec<f64> = optional,
    ];
}

/// The whole table of the `embObj*` device `device`: the Ethernet groups, the CAN boards,
/// then its own rows.
pub fn of(device: &str) -> Vec<ParamSpec> {
    use super::{motion_control, sensors};
    let own: &[&[ParamSpec]] = match device {
        motion_control::NAME => &[CAN_BOARDS, MOTION_CONTROL],
        sensors::FT_SENSOR => &[CAN_BOARDS, SENSORS, ACQUISITION, FT_SENSOR],
        sensors::MULTIPLE_FT => &[CAN_BOARDS, SENSORS, MULTIPLE_FT],
        sensors::IMU | sensors::INERTIALS => &[CAN_BOARDS, SENSORS, ACQUISITION, INERTIAL],
        sensors::MAIS => &[CAN_BOARDS, SENSORS, ACQUISITION],
        sensors::POS => &[CAN_BOARDS, SENSORS, ACQUISITION, POS],
        sensors::BATTERY => &[CAN_BOARDS, SENSORS, ACQUISITION, BATTERY],
        sensors::SKIN => &[CAN_BOARDS, SKIN],
        _ => &[],
    };
    let eth: [&[ParamSpec]; 3] = [
        Pc104Params::PARAMS,
        EthBoardDeclared::PARAMS,
        ServiceParams::PARAMS,
    ];
    eth.iter()
        .chain(own)
        .flat_map(|t| t.iter().copied())
        .collect()
}

/// Prints `device`'s table when `config` asks for `help`, as C++'s generated parsers do.
pub fn help_if_asked(device: &str, config: &yarp_proto::Property) {
    if config.check("help") {
        yarp_devices::params::help_if_asked(device, config, &of(device));
    }
}

//! The streamed state of a control board: `/<name>/state:o` (joint positions) and
//! `/<name>/stateExt:o` (C++ `yarp::dev::impl::jointData`), as pure values and codecs.
//!
//! `jointData` travels as a Bottle of 22 elements: for each of its 11 channels, in order,
//! a homogeneous list (float64, or int32 for the two mode channels) followed by its
//! validity flag, the vocab `[ok]` or `[fail]` (thrift `bool`). YARP 4.0's has 24: the
//! duty cycles as float32, and the motor temperatures (float32) appended.

use crate::driver::DeviceDriver;
use crate::vocabs::{FAILED, OK};
use yarp_proto::tags::Generation;
use yarp_proto::{Bottle, Value, Vocab32};

/// One channel of the extended state: a value per joint and whether the device gave it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Channel<T> {
    pub values: Vec<T>,
    pub valid: bool,
}

impl<T> Channel<T> {
    /// A channel filled from a device reading; a failed reading is `n` zeros, invalid.
    fn read<E>(n: usize, r: Option<Result<Vec<T>, E>>) -> Channel<T>
    where
        T: Default + Clone,
    {
        match r {
            Some(Ok(values)) if values.len() == n => Channel {
                values,
                valid: true,
            },
            _ => Channel {
                values: vec![T::default(); n],
                valid: false,
            },
        }
    }
}

/// The extended joint state (`jointData`) published on `stateExt:o`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct JointData {
    pub joint_position: Channel<f64>,
    pub joint_velocity: Channel<f64>,
    pub joint_acceleration: Channel<f64>,
    pub motor_position: Channel<f64>,
    pub motor_velocity: Channel<f64>,
    pub motor_acceleration: Channel<f64>,
    pub torque: Channel<f64>,
    pub pwm_duty_cycle: Channel<f64>,
    pub current: Channel<f64>,
    /// Control modes as vocab codes (`CM_*`), sent as int32.
    pub control_mode: Channel<i32>,
    /// Interaction modes as vocab codes (`IM_*`), sent as int32.
    pub interaction_mode: Channel<i32>,
    /// Motor temperatures: YARP 4.0's `jointData` only.
    pub temperature: Channel<f64>,
}

/// Why a received `stateExt` Bottle is not a `jointData`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StateError {
    #[error("jointData has 22 elements (YARP 4.0: 24), got {0}")]
    WrongLength(usize),
    #[error("jointData element {index} should be {expected}, got `{got}`")]
    WrongType {
        index: usize,
        expected: &'static str,
        got: String,
    },
}

const CHANNELS: usize = 11;

impl JointData {
    /// The number of joints (length of the position channel).
    pub fn axes(&self) -> usize {
        self.joint_position.values.len()
    }

    fn float_channels(&self) -> [&Channel<f64>; 9] {
        [
            &self.joint_position,
            &self.joint_velocity,
            &self.joint_acceleration,
            &self.motor_position,
            &self.motor_velocity,
            &self.motor_acceleration,
            &self.torque,
            &self.pwm_duty_cycle,
            &self.current,
        ]
    }

    fn float_channels_mut(&mut self) -> [&mut Channel<f64>; 9] {
        [
            &mut self.joint_position,
            &mut self.joint_velocity,
            &mut self.joint_acceleration,
            &mut self.motor_position,
            &mut self.motor_velocity,
            &mut self.motor_acceleration,
            &mut self.torque,
            &mut self.pwm_duty_cycle,
            &mut self.current,
        ]
    }

    /// The Bottle C++ 3.12 writes for this `jointData`.
    pub fn to_bottle(&self) -> Bottle {
        self.to_bottle_as(Generation::V3)
    }

    /// The Bottle C++ of `generation` writes for this `jointData` (to encode in its
    /// numbering of tags).
    pub fn to_bottle_as(&self, generation: Generation) -> Bottle {
        let v4 = generation == Generation::V4;
        let mut b = Bottle::with_capacity(2 * CHANNELS + 2);
        let flag = |valid: bool| Vocab32(if valid { OK } else { FAILED });
        let float32s = |c: &Channel<f64>| {
            Value::List(c.values.iter().map(|x| Value::Float32(*x as f32)).collect())
        };
        for c in self.float_channels() {
            if v4 && std::ptr::eq(c, &self.pwm_duty_cycle) {
                b.push(float32s(c));
            } else {
                b.push(Value::List(c.values.iter().copied().collect()));
            }
            b.push(flag(c.valid));
        }
        for c in [&self.control_mode, &self.interaction_mode] {
            b.push(Value::List(c.values.iter().copied().collect()));
            b.push(flag(c.valid));
        }
        if v4 {
            b.push(float32s(&self.temperature));
            b.push(flag(self.temperature.valid));
        }
        b
    }

    /// Reads a received `jointData` Bottle (numbers of any numeric type are accepted).
    pub fn from_bottle(b: &Bottle) -> Result<JointData, StateError> {
        if b.len() != 2 * CHANNELS && b.len() != 2 * CHANNELS + 2 {
            return Err(StateError::WrongLength(b.len()));
        }
        let wrong = |index: usize, expected: &'static str| StateError::WrongType {
            index,
            expected,
            got: b[index].to_string(),
        };
        let flag = |index: usize| -> Result<bool, StateError> {
            match &b[index] {
                Value::Vocab32(v) if v.0 == OK => Ok(true),
                Value::Vocab32(v) if v.0 == FAILED => Ok(false),
                _ => Err(wrong(index, "the vocab [ok] or [fail]")),
            }
        };
        let mut d = JointData::default();
        for (k, c) in d.float_channels_mut().into_iter().enumerate() {
            let list = b[2 * k]
                .as_list()
                .ok_or_else(|| wrong(2 * k, "a list of numbers"))?;
            c.values = list
                .iter()
                .map(|v| v.as_f64().ok_or_else(|| wrong(2 * k, "a list of numbers")))
                .collect::<Result<_, _>>()?;
            c.valid = flag(2 * k + 1)?;
        }
        for (k, c) in [&mut d.control_mode, &mut d.interaction_mode]
            .into_iter()
            .enumerate()
        {
            let i = 2 * (9 + k);
            let list = b[i].as_list().ok_or_else(|| wrong(i, "a list of int32"))?;
            c.values = list
                .iter()
                .map(|v| match v {
                    Value::Vocab32(x) => Ok(x.0),
                    v => v.as_i32().ok_or_else(|| wrong(i, "a list of int32")),
                })
                .collect::<Result<_, _>>()?;
            c.valid = flag(i + 1)?;
        }
        if b.len() == 2 * CHANNELS + 2 {
            let i = 2 * CHANNELS;
            let list = b[i]
                .as_list()
                .ok_or_else(|| wrong(i, "a list of numbers"))?;
            d.temperature.values = list
                .iter()
                .map(|v| v.as_f64().ok_or_else(|| wrong(i, "a list of numbers")))
                .collect::<Result<_, _>>()?;
            d.temperature.valid = flag(i + 1)?;
        }
        Ok(d)
    }

    /// Reads the whole state from `dev` (`n` joints), as C++ `ControlBoard_nws_yarp::run`.
    /// Returns the data and the encoder timestamps (empty when the device has no encoders).
    ///
    /// Channels whose interface the device lacks, or whose reading fails, are zeros marked
    /// invalid.
    pub fn read(dev: &mut dyn DeviceDriver, n: usize) -> (JointData, Vec<f64>) {
        let mut times = Vec::new();
        let positions = dev.as_encoders().map(|e| {
            e.get_encoders_timed().map(|(p, t)| {
                times = t;
                p
            })
        });
        let data = JointData {
            joint_position: Channel::read(n, positions),
            joint_velocity: Channel::read(n, dev.as_encoders().map(|e| e.get_encoder_speeds())),
            joint_acceleration: Channel::read(
                n,
                dev.as_encoders().map(|e| e.get_encoder_accelerations()),
            ),
            motor_position: Channel::read(
                n,
                dev.as_motor_encoders().map(|m| m.get_motor_encoders()),
            ),
            motor_velocity: Channel::read(
                n,
                dev.as_motor_encoders()
                    .map(|m| m.get_motor_encoder_speeds()),
            ),
            motor_acceleration: Channel::read(
                n,
                dev.as_motor_encoders()
                    .map(|m| m.get_motor_encoder_accelerations()),
            ),
            torque: Channel::read(n, dev.as_torque_control().map(|t| t.get_torques())),
            pwm_duty_cycle: Channel::read(
                n,
                dev.as_pwm_control()
                    .map(|p| (0..n).map(|m| p.get_duty_cycle(m)).collect()),
            ),
            current: Channel::read(
                n,
                dev.as_amplifier_control()
                    .map(|a| (0..n).map(|j| a.get_current(j)).collect()),
            ),
            control_mode: Channel::read(
                n,
                dev.as_control_mode()
                    .map(|c| c.get_control_modes().map(vocab_codes)),
            ),
            interaction_mode: Channel::read(
                n,
                dev.as_interaction_mode()
                    .map(|i| i.get_interaction_modes().map(vocab_codes)),
            ),
            temperature: Channel::read(
                n,
                dev.as_motor()
                    .map(|m| (0..n).map(|j| m.get_temperature(j)).collect()),
            ),
        };
        (data, times)
    }
}

fn vocab_codes(v: Vec<Vocab32>) -> Vec<i32> {
    v.into_iter().map(|x| x.0).collect()
}

/// The `state:o` payload: the joint positions as a float64 list (C++ `yarp::sig::Vector`).
pub fn positions_bottle(positions: &[f64]) -> Bottle {
    positions.iter().copied().collect()
}

/// Reads a `state:o` payload back into positions.
pub fn positions_from_bottle(b: &Bottle) -> Option<Vec<f64>> {
    b.iter().map(Value::as_f64).collect()
}

/// The envelope time C++ stamps the state with: the mean of the encoder timestamps, or
/// `None` when they disagree by more than a second (C++ then skips publishing).
pub fn envelope_time(times: &[f64]) -> Option<f64> {
    let first = *times.first()?;
    if times.iter().any(|t| (t - first).abs() > 1.0) {
        return None;
    }
    Some(times.iter().sum::<f64>() / times.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_flags() {
        let mut d = JointData {
            joint_position: Channel {
                values: vec![1.0, 2.0],
                valid: true,
            },
            ..JointData::default()
        };
        for c in d.float_channels_mut().into_iter().skip(1) {
            c.values = vec![0.0, 0.0];
        }
        d.control_mode.values = vec![Vocab32::new("pos").0, 0];
        d.interaction_mode.values = vec![0, 0];
        let b = d.to_bottle();
        assert_eq!(b.len(), 22);
        assert_eq!(b[3], Value::Vocab32(Vocab32::new("fail")));
        assert_eq!(JointData::from_bottle(&b).unwrap(), d);
        // 4.0's: duty cycles and temperatures as float32, read back the same
        d.temperature = Channel {
            values: vec![30.5, 31.0],
            valid: true,
        };
        let b4 = d.to_bottle_as(Generation::V4);
        assert_eq!(b4.len(), 24);
        assert_eq!(
            b4[14].as_list().unwrap().homogeneous_tag_in(Generation::V4),
            10
        );
        let back = Bottle::decode(&b4.encode_as(Generation::V4)).unwrap();
        assert_eq!(JointData::from_bottle(&back).unwrap(), d);
    }

    #[test]
    fn bad_input_is_an_error() {
        assert_eq!(
            JointData::from_bottle(&Bottle::from_text("1 2 3")),
            Err(StateError::WrongLength(3))
        );
        let mut b = JointData::default().to_bottle();
        if let Some(v) = b.get_mut(1) {
            *v = Value::Int32(1);
        }
        assert!(matches!(
            JointData::from_bottle(&b),
            Err(StateError::WrongType { index: 1, .. })
        ));
    }

    #[test]
    fn envelope_time_is_the_mean() {
        assert_eq!(envelope_time(&[1.0, 2.0]), Some(1.5));
        assert_eq!(envelope_time(&[1.0, 3.0]), None);
        assert_eq!(envelope_time(&[]), None);
    }
}

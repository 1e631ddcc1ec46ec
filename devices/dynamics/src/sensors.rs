//! The sensors of a model: six-axis F/T sensors on joints, accelerometers
//! and gyroscopes on links.

use crate::error::{DynError, Result};
use crate::model::{JointIndex, LinkIndex, Model};
use crate::spatial::{wrench_to, Iso, Wrench};

/// A six-axis force/torque sensor on a (fixed) joint, as iDynTree's
/// `SixAxisForceTorqueSensor`: it measures the wrench one of the joint's two
/// links exerts on the other, in the sensor's frame.
#[derive(Debug, Clone)]
pub struct FtSensor {
    pub name: String,
    pub joint: JointIndex,
    /// The link the measured wrench acts on (`child_to_parent`: the parent).
    pub applied_on: LinkIndex,
    /// The link the sensor frame is given on, and its pose there.
    pub link: LinkIndex,
    pub link_h_sensor: Iso,
}

impl FtSensor {
    /// `link_H_sensor` for either of the joint's two links.
    pub fn pose_on(&self, model: &Model, link: LinkIndex) -> Iso {
        let joint = &model.joints[self.joint];
        let parent_h_child = joint.transform(0.0);
        if link == self.link {
            self.link_h_sensor
        } else if link == joint.parent {
            parent_h_child * self.link_h_sensor
        } else {
            parent_h_child.inverse() * self.link_h_sensor
        }
    }

    /// The measured wrench as it acts on `link` (one of the joint's two
    /// links), in `link`'s frame about its origin.
    pub fn wrench_on(&self, model: &Model, link: LinkIndex, measured: &Wrench) -> Wrench {
        let w = wrench_to(&self.pose_on(model, link), measured);
        if link == self.applied_on {
            w
        } else {
            -w
        }
    }

    /// The wrench `link` receives from across the joint, as this sensor
    /// would measure it.
    pub fn measurement_from(&self, model: &Model, link: LinkIndex, on_link: &Wrench) -> Wrench {
        let w = wrench_to(&self.pose_on(model, link).inverse(), on_link);
        if link == self.applied_on {
            w
        } else {
            -w
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImuKind {
    Accelerometer,
    Gyroscope,
}

/// An accelerometer or gyroscope fixed to a link.
#[derive(Debug, Clone)]
pub struct ImuSensor {
    pub name: String,
    pub kind: ImuKind,
    pub link: LinkIndex,
    pub link_h_sensor: Iso,
}

#[derive(Debug, Clone, Default)]
pub struct Sensors {
    pub ft: Vec<FtSensor>,
    pub imu: Vec<ImuSensor>,
}

impl Sensors {
    pub fn ft_index(&self, name: &str) -> Result<usize> {
        self.ft
            .iter()
            .position(|s| s.name == name)
            .ok_or_else(|| DynError::UnknownSensor(name.to_owned()))
    }
}

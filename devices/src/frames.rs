//! Frame transforms: C++ `yarp::math::FrameTransform` and the storage interfaces
//! `IFrameTransformStorageGet` / `IFrameTransformStorageSet` that transform clients
//! (`frameTransformGet_nwc_*`, `frameTransformSet_nwc_*`) offer.

use crate::error::DevResult;

/// One transform from `src_frame_id` (the parent) to `dst_frame_id` (the child): the
/// child's origin and orientation in the parent frame (m; quaternion x, y, z, w).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameTransform {
    pub src_frame_id: String,
    pub dst_frame_id: String,
    /// Seconds since the epoch.
    pub timestamp: f64,
    /// Static transforms never expire.
    pub is_static: bool,
    pub translation: [f64; 3],
    pub rotation: [f64; 4],
}

/// C++ `IFrameTransformStorageGet`.
pub trait IFrameTransformStorageGet {
    fn get_transforms(&mut self) -> DevResult<Vec<FrameTransform>>;
}

/// C++ `IFrameTransformStorageSet`.
pub trait IFrameTransformStorageSet {
    fn set_transforms(&mut self, transforms: &[FrameTransform]) -> DevResult<()>;
    fn set_transform(&mut self, t: &FrameTransform) -> DevResult<()> {
        self.set_transforms(std::slice::from_ref(t))
    }
    fn delete_transform(&mut self, src: &str, dst: &str) -> DevResult<()>;
    fn clear_all(&mut self) -> DevResult<()>;
}

/// Transforms by (parent, child), the timed ones dropped once older than
/// `refresh_interval` (C++ `FrameTransformContainer`).
#[derive(Debug, Clone, Default)]
pub struct FrameTransformContainer {
    transforms: Vec<FrameTransform>,
    pub refresh_interval: f64,
}

impl FrameTransformContainer {
    pub fn new(refresh_interval: f64) -> Self {
        FrameTransformContainer {
            transforms: Vec::new(),
            refresh_interval,
        }
    }

    /// Adds or replaces the transform between the same two frames.
    pub fn set(&mut self, t: FrameTransform) {
        match self
            .transforms
            .iter_mut()
            .find(|o| o.src_frame_id == t.src_frame_id && o.dst_frame_id == t.dst_frame_id)
        {
            Some(o) => *o = t,
            None => self.transforms.push(t),
        }
    }

    pub fn delete(&mut self, src: &str, dst: &str) {
        self.transforms
            .retain(|o| !(o.src_frame_id == src && o.dst_frame_id == dst));
    }

    pub fn clear(&mut self) {
        self.transforms.clear();
    }

    /// Every static transform and the timed ones not older than the refresh interval at
    /// `now` (seconds since the epoch); the expired ones are dropped.
    pub fn current(&mut self, now: f64) -> Vec<FrameTransform> {
        let keep = self.refresh_interval;
        self.transforms
            .retain(|t| t.is_static || now - t.timestamp <= keep);
        self.transforms.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn t(src: &str, dst: &str, at: f64, is_static: bool) -> FrameTransform {
        FrameTransform {
            src_frame_id: src.into(),
            dst_frame_id: dst.into(),
            timestamp: at,
            is_static,
            translation: [1.0, 0.0, 0.0],
            rotation: [0.0, 0.0, 0.0, 1.0],
        }
    }

    #[test]
    fn timed_transforms_expire_static_ones_stay() {
        let mut c = FrameTransformContainer::new(0.1);
        c.set(t("map", "odom", 10.0, true));
        c.set(t("odom", "base", 10.0, false));
        c.set(t("odom", "base", 10.05, false));
        assert_eq!(c.current(10.1).len(), 2);
        assert_eq!(c.current(10.2), vec![t("map", "odom", 10.0, true)]);
        c.delete("map", "odom");
        assert!(c.current(10.2).is_empty());
    }
}

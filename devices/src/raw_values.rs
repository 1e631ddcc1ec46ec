//! icub-main's `IRawValuesPublisher` (iCubDev, `iCub::debugLibrary`): a device's raw values
//! (firmware units, no conversion) under named keys, with per-key metadata, for
//! diagnostics and telemetry (`rawValuesPublisherServer`/`Remapper`/`Client` in icubmod).
//! Declared here, beside YARP's interfaces, because a device's views are declared once
//! for the whole framework.

use crate::error::{DevResult, DeviceError};
use std::collections::BTreeMap;

/// C++ `iCub::rawValuesKeyMetadata`: what each raw value of a key is, the axes they
/// belong to, and how many there are.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct RawValuesKeyMetadata {
    pub raw_value_names: Vec<String>,
    pub axes_names: Vec<String>,
    pub size: i32,
}

/// C++ `IRawValuesPublisher`. Maps are ordered by key, as C++'s `std::map`.
pub trait IRawValuesPublisher {
    /// Every key's raw values.
    fn get_raw_data_map(&mut self) -> DevResult<BTreeMap<String, Vec<i32>>>;
    /// Every key's metadata (C++ fails it when there are no keys).
    fn get_metadata_map(&mut self) -> DevResult<BTreeMap<String, RawValuesKeyMetadata>>;

    /// One key's raw values.
    fn get_raw_data(&mut self, key: &str) -> DevResult<Vec<i32>> {
        self.get_raw_data_map()?
            .remove(key)
            .ok_or_else(|| unknown_key(key))
    }
    fn get_keys(&mut self) -> DevResult<Vec<String>> {
        Ok(self.get_metadata_map()?.into_keys().collect())
    }
    fn get_number_of_keys(&mut self) -> DevResult<usize> {
        Ok(self.get_keys()?.len())
    }
    fn get_key_metadata(&mut self, key: &str) -> DevResult<RawValuesKeyMetadata> {
        self.get_metadata_map()?
            .remove(key)
            .ok_or_else(|| unknown_key(key))
    }
    fn get_axes_names(&mut self, key: &str) -> DevResult<Vec<String>> {
        Ok(self.get_key_metadata(key)?.axes_names)
    }
}

/// The error of a key the publisher does not have.
pub fn unknown_key(key: &str) -> DeviceError {
    DeviceError::BadParam {
        device: "IRawValuesPublisher".into(),
        param: "key".into(),
        expected: "a key of the publisher",
        got: key.into(),
    }
}

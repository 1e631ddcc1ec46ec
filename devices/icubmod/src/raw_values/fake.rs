//! `fakeRawValuesPublisher` (icub-main 2.11): one key, `rawJomoEncoderValues`, of `njomos`
//! values that all read a counter going 1, 2, ... `threshold`, 0, 1, ... one step per read
//! of the map, as C++'s.

use std::collections::BTreeMap;
use yarp_devices::driver::DeviceDriver;
use yarp_devices::error::DevResult;
use yarp_devices::raw_values::{IRawValuesPublisher, RawValuesKeyMetadata};
use yarp_proto::Property;

pub const NAME: &str = "fakeRawValuesPublisher";
/// The fake's one key.
pub const KEY: &str = "rawJomoEncoderValues";

yarp_devices::device_params! {
    /// What `fakeRawValuesPublisher` reads (icub-main's `fakeRawValuesPublisher_params.md`).
    pub struct FakeRawValuesPublisherParams for "fakeRawValuesPublisher" {
        /// Name of the device (unused, as in C++)
        name: String = required,
        /// Number of joint-motor groups whose values are published
        njomos: i64 = required; min 0,
        /// The value the counter goes up to before it restarts from 0
        threshold: i64 = required,
    }
}

/// The `fakeRawValuesPublisher` device.
#[derive(Debug, Default)]
pub struct FakeRawValuesPublisher {
    metadata: BTreeMap<String, RawValuesKeyMetadata>,
    threshold: i64,
    counter: i64,
}

impl FakeRawValuesPublisher {
    pub fn new() -> Self {
        Self::default()
    }
}

impl DeviceDriver for FakeRawValuesPublisher {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        FakeRawValuesPublisherParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        let p = FakeRawValuesPublisherParams::read(config)?;
        let n = usize::try_from(p.njomos).unwrap_or(0);
        let m = RawValuesKeyMetadata {
            raw_value_names: (0..n).map(|i| format!("fake_jomo_rawvalue_{i}")).collect(),
            axes_names: (0..n).map(|i| format!("fake_jomo_{i}")).collect(),
            size: i32::try_from(n).unwrap_or(i32::MAX),
        };
        self.metadata = BTreeMap::from([(KEY.to_string(), m)]);
        self.threshold = p.threshold;
        self.counter = 0;
        Ok(())
    }

    yarp_devices::views!(as_raw_values_publisher);
}

impl IRawValuesPublisher for FakeRawValuesPublisher {
    fn get_raw_data_map(&mut self) -> DevResult<BTreeMap<String, Vec<i32>>> {
        self.counter = if self.counter < self.threshold {
            self.counter + 1
        } else {
            0
        };
        let v = i32::try_from(self.counter).unwrap_or(i32::MAX);
        Ok(self
            .metadata
            .iter()
            .map(|(k, m)| (k.clone(), vec![v; usize::try_from(m.size).unwrap_or(0)]))
            .collect())
    }

    fn get_metadata_map(&mut self) -> DevResult<BTreeMap<String, RawValuesKeyMetadata>> {
        if self.metadata.is_empty() {
            return Err(yarp_devices::error::DeviceError::NotOpen);
        }
        Ok(self.metadata.clone())
    }
}

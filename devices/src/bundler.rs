//! `deviceBundler` (C++ YARP 3.12): opens a wrapper and a device from one configuration
//! and attaches them, the replacement for `yarpdev --device W --subdevice D`:
//!
//! ```text
//! yarpdev --device deviceBundler --wrapper_device controlBoard_nws_yarp \
//!         --attached_device fakeMotionControl --name /robot/part
//! ```
//!
//! Parameters: `wrapper_device` and `attached_device` (required driver names),
//! `doNotAttach` (optional bool, open both but leave them apart). Every other parameter is
//! passed to both devices.

use crate::driver::{shared, DeviceDriver, PolyDriver, SharedDevice};
use crate::error::{DevResult, DeviceError};
use yarp_proto::{Property, Value};

const NAME: &str = "deviceBundler";

crate::device_params! {
    /// What `deviceBundler` reads (C++ `DeviceBundler_params.md`).
    pub struct DeviceBundlerParams for "deviceBundler" {
        /// Name of the wrapper device
        wrapper_device: String = required,
        /// Name of the subdevice that will be attached to the wrapper device
        attached_device: String = required,
        /// If set to true, the two devices are opened, but not attached
        "doNotAttach" do_not_attach: bool = false,
    }
}

pub(crate) const DRIVERS: &[(&str, crate::driver::Factory)] =
    &[(NAME, || Box::new(DeviceBundler::default()))];

/// A wrapper and the device it serves, opened and attached together.
#[derive(Default)]
pub struct DeviceBundler {
    wrapper: Option<SharedDevice>,
    attached: Option<SharedDevice>,
    is_attached: bool,
}

/// `config` with the bundler's own keys removed and `device` set to `driver`.
fn config_for(config: &Property, driver: &str) -> Property {
    let mut c = config.clone();
    for key in [
        "device",
        "wrapper_device",
        "attached_device",
        "wrapping_enabled",
    ] {
        c.unput(key);
    }
    c.put("device", Value::from(driver));
    c
}

impl DeviceBundler {
    /// The opened wrapper, e.g. to inspect its ports.
    pub fn wrapper(&self) -> Option<SharedDevice> {
        self.wrapper.clone()
    }

    /// The opened device the wrapper serves.
    pub fn attached(&self) -> Option<SharedDevice> {
        self.attached.clone()
    }
}

impl DeviceDriver for DeviceBundler {
    fn parameters(&self) -> Vec<crate::params::ParamSpec> {
        DeviceBundlerParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let DeviceBundlerParams {
            wrapper_device: wrapper_name,
            attached_device: attached_name,
            do_not_attach,
        } = DeviceBundlerParams::read(config)?;

        tracing::info!("{NAME}: opening device {wrapper_name}");
        let wrapper = shared(PolyDriver::open(&config_for(config, &wrapper_name))?);
        tracing::info!("{NAME}: opening device {attached_name}");
        let attached = match PolyDriver::open(&config_for(config, &attached_name)) {
            Ok(pd) => shared(pd),
            Err(e) => {
                let _ = wrapper.lock().close();
                return Err(e);
            }
        };
        self.wrapper = Some(wrapper.clone());
        self.attached = Some(attached.clone());
        if do_not_attach {
            tracing::info!("{NAME}: doNotAttach given; the devices are not attached");
            return Ok(());
        }

        let result = {
            let mut w = wrapper.lock();
            match w.device().as_wrapper() {
                Some(iw) => iw.attach(attached),
                None => Err(DeviceError::BadParam {
                    device: NAME.into(),
                    param: "wrapper_device".into(),
                    expected: "a wrapper device (IWrapper)",
                    got: wrapper_name.clone(),
                }),
            }
        };
        match result {
            Ok(()) => {
                self.is_attached = true;
                tracing::info!("{NAME}: attached {wrapper_name} and {attached_name}");
                Ok(())
            }
            Err(e) => {
                let _ = self.close();
                Err(e)
            }
        }
    }

    fn close(&mut self) -> DevResult<()> {
        if let Some(w) = self.wrapper.take() {
            let mut w = w.lock();
            if std::mem::take(&mut self.is_attached) {
                if let Some(iw) = w.device().as_wrapper() {
                    let _ = iw.detach();
                }
            }
            let _ = w.close();
        }
        if let Some(a) = self.attached.take() {
            let _ = a.lock().close();
        }
        Ok(())
    }
}

impl Drop for DeviceBundler {
    fn drop(&mut self) {
        let _ = self.close();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_params_are_named() {
        let mut b = DeviceBundler::default();
        let cfg = Property::from_text("(device deviceBundler) (attached_device fakeMotionControl)");
        let e = b.open(&cfg).unwrap_err().to_string();
        assert!(
            e.contains("deviceBundler") && e.contains("wrapper_device"),
            "{e}"
        );
    }

    #[test]
    fn a_non_wrapper_is_refused_and_both_close() {
        let mut b = DeviceBundler::default();
        let cfg = Property::from_text(
            "(device deviceBundler) (wrapper_device fakeMotionControl) (attached_device fakeMotionControl)",
        );
        let e = b.open(&cfg).unwrap_err().to_string();
        assert!(e.contains("IWrapper"), "{e}");
        assert!(b.wrapper().is_none() && b.attached().is_none());
    }

    #[test]
    fn do_not_attach_opens_both() {
        let mut b = DeviceBundler::default();
        let cfg = Property::from_text(
            "(device deviceBundler) (wrapper_device fakeMotionControl) (attached_device fakeMotionControl) (doNotAttach true) (joints 3)",
        );
        b.open(&cfg).unwrap();
        let a = b.attached().unwrap();
        let mut a = a.lock();
        assert_eq!(a.name(), "fakeMotionControl");
        assert_eq!(a.device().as_encoders().unwrap().get_axes().unwrap(), 3);
        drop(a);
        b.close().unwrap();
    }
}

//! `imuFilter` (icub-main `src/libraries/icubmod/imuFilter`): estimates the bias of an
//! attached IMU's gyroscope while the IMU is still, removes it, and re-exposes the IMU.
//!
//! Attach one device offering gyroscopes, accelerometers, magnetometers and orientation
//! sensors (a robotinterface `attach` with one network, or `--subdevice`); the filter
//! serves the same four families: accelerometer, magnetometer and orientation pass
//! through, the gyroscope measure is the raw one minus the current bias estimate.
//!
//! Each period (`ImuFilter::run`): when the gyroscope has a new timestamp, the gyro goes
//! through a median filter (`gyro-order`), the magnetometer through another
//! (`mag-order`); the magnetometer's rate of change is estimated by an adaptive-window
//! linear fit (`AWLinEstimator(40, 0.05)`); while its norm is below
//! `mag-vel-thres-down` (and until it exceeds `mag-vel-thres-up`) the IMU is taken as
//! still and the bias integrates the filtered, bias-corrected gyro with the Tustin rule
//! and gain `bias-gain` (`iCub::ctrl::Integrator`). The bias is streamed on
//! `<name>/bias:o` (three float64 with an envelope) when someone reads it.
//!
//! Parameters (C++ names and defaults): `name` (`imuFilter`; a `/` is prefixed),
//! `period` (ms; C++ defaults to 0.01 ms, a typo — here 10 ms), `gyro-order` (5),
//! `mag-order` (51), `mag-vel-thres-up` (0.04), `mag-vel-thres-down` (0.02),
//! `bias-gain` (0.001), `verbose`; `robot` is accepted and unused. Not supported: C++'s
//! own proxy (`subdevice` + `proxy_remote`/`proxy_local`): use the generic subdevice
//! mechanism with `remote`/`local` (`--subdevice multipleanalogsensorsclient --remote R
//! --local L`). Deviation: before its first filtered sample the gyroscope reports
//! `WaitingForFirstRead` (C++ answers an empty vector).

use parking_lot::Mutex;
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Duration;

use yarp_devices::driver::{DeviceDriver, IMultipleWrapper, SharedDevice};
use yarp_devices::error::{DevResult, DeviceError};
use yarp_devices::runtime;
use yarp_devices::sensors::interfaces::*;
use yarp_net::port::Port;
use yarp_proto::{Bottle, Property, Stamp, Value};

const NAME: &str = "imuFilter";

/// `iCub::ctrl::MedianFilter`: the median of the last `order + 1` inputs; the output
/// stays at its initial value (zero) until that many inputs arrived.
#[derive(Debug, Clone)]
pub struct MedianFilter {
    order: usize,
    window: Vec<VecDeque<f64>>,
    y: Vec<f64>,
}

impl MedianFilter {
    pub fn new(order: usize, dim: usize) -> Self {
        Self {
            order,
            window: vec![VecDeque::new(); dim],
            y: vec![0.0; dim],
        }
    }

    fn median(v: &mut [f64]) -> f64 {
        v.sort_by(f64::total_cmp);
        let l = v.len() / 2;
        if v.len() % 2 == 1 {
            v[l]
        } else {
            0.5 * (v[l] + v[l - 1])
        }
    }

    pub fn filt(&mut self, u: &[f64]) -> &[f64] {
        for (w, x) in self.window.iter_mut().zip(u) {
            w.push_front(*x);
        }
        if self.window.first().is_some_and(|w| w.len() > self.order) {
            for (w, y) in self.window.iter_mut().zip(&mut self.y) {
                let mut tmp: Vec<f64> = w.iter().copied().collect();
                *y = Self::median(&mut tmp);
                w.pop_back();
            }
        }
        &self.y
    }
}

/// `iCub::ctrl::AWLinEstimator`: the first derivative of each component by a linear
/// least-squares fit over the longest recent window (at most `n` samples) whose
/// residuals stay within `d` (Janabi-Sharifi's adaptive window).
#[derive(Debug, Clone)]
pub struct AwLinEstimator {
    n: usize,
    d: f64,
    elems: VecDeque<(f64, Vec<f64>)>,
    win_len: Vec<usize>,
}

impl AwLinEstimator {
    /// Order 1: the window is at least 2 samples (C++ makes `N` at least order + 1).
    pub fn new(n: usize, d: f64) -> Self {
        Self {
            n: n.max(2),
            d,
            elems: VecDeque::new(),
            win_len: Vec::new(),
        }
    }

    /// Bias and slope of the fit of the last `n` points (C++ `AWLinEstimator::fit`).
    fn fit(t: &[f64], x: &[f64], n: usize) -> [f64; 2] {
        let i1 = t.len() - n;
        let m = n as f64;
        let (mut sx, mut sxx, mut sy, mut sxy) = (0.0, 0.0, 0.0, 0.0);
        for i in i1..t.len() {
            sx += t[i];
            sxx += t[i] * t[i];
            sy += x[i];
            sxy += t[i] * x[i];
        }
        let den = m * sxx - sx * sx;
        [(sy * sxx - sx * sxy) / den, (m * sxy - sx * sy) / den]
    }

    /// Feeds a sample and returns the slope estimate (zeros until `n` samples arrived).
    pub fn estimate(&mut self, time: f64, data: &[f64]) -> Vec<f64> {
        self.elems.push_back((time, data.to_vec()));
        let dim = self.elems[0].1.len();
        // C++ sizes the windows on the first call; a sample of another size is padded
        self.win_len.resize(dim, self.n);
        let n = self.n;
        let Some(delta) = self.elems.len().checked_sub(n) else {
            return vec![0.0; dim];
        };
        let t0 = self.elems[delta].0;
        let t: Vec<f64> = (0..n).map(|j| self.elems[delta + j].0 - t0).collect();
        let mut out = vec![0.0; dim];
        for (i, o) in out.iter_mut().enumerate() {
            let x: Vec<f64> = (0..n)
                .map(|j| self.elems[delta + j].1.get(i).copied().unwrap_or(0.0))
                .collect();
            // try the window one shorter, as long, and one longer than last time
            let w = self.win_len[i];
            let n1 = if w > 2 { w - 1 } else { 2 };
            let n2 = if w < n { w + 1 } else { n };
            let mut coeff = [0.0, 0.0];
            for len in n1..=n2 {
                coeff = Self::fit(&t, &x, len);
                let off =
                    (n - len..n).any(|k| (x[k] - (coeff[0] + coeff[1] * t[k])).abs() > self.d);
                if off {
                    self.win_len[i] = len;
                    break;
                }
            }
            *o = coeff[1];
        }
        if delta > 10 {
            self.elems.pop_front();
        }
        out
    }
}

/// `iCub::ctrl::Integrator` without saturation: `y += (x + x_old) * ts / 2`.
#[derive(Debug, Clone)]
pub struct Integrator {
    ts: f64,
    y: Vec<f64>,
    x_old: Vec<f64>,
}

impl Integrator {
    pub fn new(ts: f64, dim: usize) -> Self {
        Self {
            ts,
            y: vec![0.0; dim],
            x_old: vec![0.0; dim],
        }
    }

    pub fn integrate(&mut self, x: &[f64]) -> &[f64] {
        for ((y, xo), xi) in self.y.iter_mut().zip(&mut self.x_old).zip(x) {
            *y += (xi + *xo) * (self.ts / 2.0);
            *xo = *xi;
        }
        &self.y
    }
}

/// The tuning of the bias estimator (the C++ parameters).
#[derive(Debug, Clone, PartialEq)]
pub struct FilterParams {
    pub gyro_order: usize,
    pub mag_order: usize,
    pub mag_vel_thres_up: f64,
    pub mag_vel_thres_down: f64,
    pub bias_gain: f64,
}

impl Default for FilterParams {
    fn default() -> Self {
        // ImuFilter::open defaults
        Self {
            gyro_order: 5,
            mag_order: 51,
            mag_vel_thres_up: 0.04,
            mag_vel_thres_down: 0.02,
            bias_gain: 0.001,
        }
    }
}

/// The estimator of `ImuFilter::run`, without I/O.
#[derive(Debug, Clone)]
pub struct BiasEstimator {
    params: FilterParams,
    gyro_filt: MedianFilter,
    mag_filt: MedianFilter,
    vel_est: AwLinEstimator,
    bias_int: Integrator,
    adapting: bool,
    bias: Vec<f64>,
}

/// One step's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// The gyro minus the bias estimated before this step.
    pub gyro: Vec<f64>,
    /// The bias after this step.
    pub bias: Vec<f64>,
    /// The norm of the magnetic field's rate of change.
    pub mag_vel: f64,
    pub adapting: bool,
}

impl BiasEstimator {
    pub fn new(params: FilterParams) -> Self {
        Self {
            gyro_filt: MedianFilter::new(params.gyro_order, 3),
            mag_filt: MedianFilter::new(params.mag_order, 3),
            // ImuFilter's constructor: velEst(40, 0.05)
            vel_est: AwLinEstimator::new(40, 0.05),
            bias_int: Integrator::new(params.bias_gain, 3),
            adapting: false,
            bias: vec![0.0; 3],
            params,
        }
    }

    /// One new gyro sample (deg/s) with the magnetometer reading taken at `mag_time`.
    pub fn step(&mut self, gyro: &[f64], mag: &[f64], mag_time: f64) -> Step {
        let mut filtered = self.gyro_filt.filt(gyro).to_vec();
        let corrected: Vec<f64> = gyro.iter().zip(&self.bias).map(|(g, b)| g - b).collect();
        for (f, b) in filtered.iter_mut().zip(&self.bias) {
            *f -= b;
        }
        let mag_filtered = self.mag_filt.filt(mag).to_vec();
        let vel = self.vel_est.estimate(mag_time, &mag_filtered);
        let mag_vel = vel.iter().map(|v| v * v).sum::<f64>().sqrt();
        self.adapting = if self.adapting {
            mag_vel < self.params.mag_vel_thres_up
        } else {
            mag_vel < self.params.mag_vel_thres_down
        };
        let input = if self.adapting {
            filtered
        } else {
            vec![0.0; 3]
        };
        self.bias = self.bias_int.integrate(&input).to_vec();
        Step {
            gyro: corrected,
            bias: self.bias.clone(),
            mag_vel,
            adapting: self.adapting,
        }
    }
}

/// What the periodic task and the interfaces share.
struct Shared {
    estimator: BiasEstimator,
    /// The last corrected gyro and its timestamp.
    gyro: Option<(Vec<f64>, f64)>,
    prev_ts: f64,
    stamp_count: i32,
}

type Attached = Arc<Mutex<Option<SharedDevice>>>;

fn lock<T>(m: &Mutex<T>) -> parking_lot::MutexGuard<'_, T> {
    m.lock()
}

/// Runs `f` on the attached device, `None` when nothing is attached.
fn with_device<R>(
    attached: &Attached,
    f: impl FnOnce(&mut dyn DeviceDriver) -> Option<R>,
) -> Option<R> {
    let dev = lock(attached).clone()?;
    let mut pd = lock(&dev);
    f(pd.device())
}

/// One period of `ImuFilter::run`.
fn run_once(attached: &Attached, shared: &Mutex<Shared>, bias_port: &Port, verbose: bool) {
    let read = with_device(attached, |d| {
        let g = d.as_three_axis_gyroscopes()?;
        let gyro = (g.get_three_axis_gyroscope_status(0) == MasStatus::Ok)
            .then(|| g.get_three_axis_gyroscope_measure(0).ok())
            .flatten();
        let m = d.as_three_axis_magnetometers()?;
        let mag = (m.get_three_axis_magnetometer_status(0) == MasStatus::Ok)
            .then(|| m.get_three_axis_magnetometer_measure(0).ok())
            .flatten();
        Some((gyro, mag))
    });
    let Some((gyro, mag)) = read else {
        tracing::debug!("{NAME}: the imu is not attached");
        return;
    };
    let Some(gyro) = gyro.filter(|g| g.values.len() == 3) else {
        tracing::debug!("{NAME}: unable to get gyro");
        return;
    };
    let mut s = lock(shared);
    if (gyro.timestamp - s.prev_ts).abs() < 1e-6 {
        return;
    }
    let Some(mag) = mag.filter(|m| m.values.len() == 3) else {
        tracing::debug!("{NAME}: unable to get magnetometer measures");
        return;
    };
    let step = s.estimator.step(&gyro.values, &mag.values, mag.timestamp);
    s.gyro = Some((step.gyro.clone(), gyro.timestamp));
    s.prev_ts = gyro.timestamp;
    // stampBias.update(ts): the magnetometer's time
    let stamp = Stamp::new(s.stamp_count, mag.timestamp);
    s.stamp_count = s.stamp_count.wrapping_add(1);
    drop(s);
    if !bias_port.outputs().is_empty() {
        let b: Bottle = step.bias.iter().copied().collect();
        bias_port.write_nowait(&b, Some(stamp));
    }
    if verbose {
        let what = if step.adapting {
            "adapt-gyroBias"
        } else {
            "no-adaption"
        };
        tracing::info!("{NAME}: magVel   = {} => [{what}]", step.mag_vel);
        tracing::info!("{NAME}: gyro     = {:?}", step.gyro);
        tracing::info!("{NAME}: gyroBias = {:?}", step.bias);
    }
}

/// The `imuFilter` device.
pub struct ImuFilter {
    params: FilterParams,
    period: Duration,
    verbose: bool,
    attached: Attached,
    shared: Arc<Mutex<Shared>>,
    bias_port: Option<Arc<Port>>,
    task: Option<(
        tokio::sync::oneshot::Sender<()>,
        tokio::task::JoinHandle<()>,
    )>,
}

impl Default for ImuFilter {
    fn default() -> Self {
        Self::new()
    }
}

impl ImuFilter {
    pub fn new() -> Self {
        let params = FilterParams::default();
        Self {
            shared: Arc::new(Mutex::new(Shared {
                estimator: BiasEstimator::new(params.clone()),
                gyro: None,
                prev_ts: 0.0,
                stamp_count: 0,
            })),
            params,
            period: Duration::from_millis(10),
            verbose: false,
            attached: Arc::default(),
            bias_port: None,
            task: None,
        }
    }

    /// The current bias estimate (deg/s).
    pub fn bias(&self) -> Vec<f64> {
        lock(&self.shared).estimator.bias.clone()
    }

    fn stop_task(&mut self) {
        if let Some((stop, task)) = self.task.take() {
            let _ = stop.send(());
            let _ = runtime::block_on(async move {
                tokio::time::timeout(Duration::from_secs(5), task).await
            });
        }
    }

    fn status_or_wait(&self, s: MasStatus) -> MasStatus {
        if s == MasStatus::Ok && lock(&self.shared).gyro.is_none() {
            MasStatus::WaitingForFirstRead
        } else {
            s
        }
    }
}

/// A filter order: a whole number, not negative (C++ reads it with `asInt32`).
fn order(v: &f64) -> Result<(), &'static str> {
    match *v >= 0.0 && v.fract() == 0.0 {
        true => Ok(()),
        false => Err("a non-negative integer"),
    }
}

/// A threshold or gain: not negative.
fn non_negative(v: &f64) -> Result<(), &'static str> {
    match *v >= 0.0 && v.is_finite() {
        true => Ok(()),
        false => Err("a non-negative number"),
    }
}

yarp_devices::device_params! {
    /// What `imuFilter` reads (icub-main's `ImuFilter::open`).
    pub struct ImuFilterParams for "imuFilter" {
        /// Not supported: give the subdevice's own `remote` and `local`
        proxy_remote: Value = optional,
        /// The subdevice's remote port (with proxy_remote)
        remote: Value = optional,
        /// Order of the median filter of the gyroscope
        "gyro-order" gyro_order: f64 = 5.0; check order,
        /// Order of the median filter of the magnetometer
        "mag-order" mag_order: f64 = 51.0; check order,
        /// Magnetometer speed above which the robot is moving
        "mag-vel-thres-up" mag_vel_thres_up: f64 = 0.04; check non_negative,
        /// Magnetometer speed below which the robot stands still
        "mag-vel-thres-down" mag_vel_thres_down: f64 = 0.02; check non_negative,
        /// Gain of the gyroscope bias estimate
        "bias-gain" bias_gain: f64 = 0.001; check non_negative,
        /// Period of the filter
        period: f64 = 10.0; "ms"; check yarp_devices::sensors::params::positive_ms,
        /// Print the bias as it is estimated
        verbose: bool = false,
        /// Prefix of the port streaming the bias (`<name>/bias:o`)
        name: String = "imuFilter",
    }
}

impl DeviceDriver for ImuFilter {
    fn parameters(&self) -> Vec<yarp_devices::params::ParamSpec> {
        ImuFilterParams::PARAMS.to_vec()
    }

    fn open(&mut self, config: &Property) -> DevResult<()> {
        self.close()?;
        let p = ImuFilterParams::read(config)?;
        if let (Some(proxy), None) = (&p.proxy_remote, &p.remote) {
            return Err(DeviceError::BadParam {
                device: NAME.into(),
                param: "proxy_remote".into(),
                expected: "absent: give the subdevice's own `remote` and `local`",
                got: proxy.to_string(),
            });
        }
        let params = FilterParams {
            gyro_order: p.gyro_order as usize,
            mag_order: p.mag_order as usize,
            mag_vel_thres_up: p.mag_vel_thres_up,
            mag_vel_thres_down: p.mag_vel_thres_down,
            bias_gain: p.bias_gain,
        };
        let period = p.period / 1000.0;
        let verbose = p.verbose;
        let mut name = p.name;
        if !name.starts_with('/') {
            name.insert(0, '/');
        }
        let port_name = format!("{name}/bias:o");
        let port_err = |e: String| DeviceError::BadParam {
            device: NAME.into(),
            param: "name".into(),
            expected: "a port prefix that can be registered (is the name server running?)",
            got: format!("{port_name}: {e}"),
        };
        let ns = yarp_net::network::name_client().map_err(|e| port_err(e.to_string()))?;
        let pn = port_name.clone();
        let port = runtime::block_on_result(async move {
            Port::open(&pn, ns).await.map_err(|e| e.to_string())
        })
        .map_err(|e| port_err(e.to_string()))?;
        *lock(&self.shared) = Shared {
            estimator: BiasEstimator::new(params.clone()),
            gyro: None,
            prev_ts: 0.0,
            stamp_count: 0,
        };
        self.params = params;
        self.period = Duration::from_secs_f64(period);
        self.verbose = verbose;
        self.bias_port = Some(Arc::new(port));
        Ok(())
    }

    fn close(&mut self) -> DevResult<()> {
        let _ = self.detach_all();
        if let Some(port) = self.bias_port.take() {
            runtime::block_on_logged("imuFilter: closing", async move {
                if let Ok(p) = Arc::try_unwrap(port) {
                    p.close().await;
                }
            });
        }
        Ok(())
    }

    yarp_devices::views!(as_multiple_wrapper);
    yarp_devices::imu_views!();
}

impl IMultipleWrapper for ImuFilter {
    fn attach_all(&mut self, devices: &[(String, SharedDevice)]) -> DevResult<()> {
        let port = self.bias_port.clone().ok_or(DeviceError::NotOpen)?;
        // PassThroughInertial::attachAll: exactly one device with all four interfaces
        let [(_, dev)] = devices else {
            return Err(DeviceError::Unsupported(
                "imuFilter attaches exactly one IMU (join several with multipleanalogsensorsremapper)",
            ));
        };
        {
            let mut pd = lock(dev);
            let d = pd.device();
            let ok = d.as_three_axis_gyroscopes().is_some()
                && d.as_three_axis_linear_accelerometers().is_some()
                && d.as_three_axis_magnetometers().is_some()
                && d.as_orientation_sensors().is_some();
            if !ok {
                return Err(DeviceError::Unsupported(
                    "imuFilter: the device lacks gyroscopes, accelerometers, magnetometers or orientation sensors",
                ));
            }
        }
        self.stop_task();
        *lock(&self.attached) = Some(dev.clone());
        let (tx, mut rx) = tokio::sync::oneshot::channel();
        let (attached, shared, period, verbose) = (
            self.attached.clone(),
            self.shared.clone(),
            self.period,
            self.verbose,
        );
        let task = runtime::handle().spawn(async move {
            let mut ticker = yarp_devices::sensors::periodic::Ticker::new(period);
            loop {
                tokio::select! {
                    _ = &mut rx => break,
                    _ = ticker.tick() => {}
                }
                run_once(&attached, &shared, &port, verbose);
            }
        });
        self.task = Some((tx, task));
        Ok(())
    }

    fn detach_all(&mut self) -> DevResult<()> {
        self.stop_task();
        *lock(&self.attached) = None;
        Ok(())
    }
}

impl IThreeAxisGyroscopes for ImuFilter {
    fn get_nr_of_three_axis_gyroscopes(&self) -> usize {
        with_device(&self.attached, |d| {
            Some(
                d.as_three_axis_gyroscopes()?
                    .get_nr_of_three_axis_gyroscopes(),
            )
        })
        .unwrap_or(0)
    }
    fn get_three_axis_gyroscope_status(&self, i: usize) -> MasStatus {
        let s = with_device(&self.attached, |d| {
            Some(
                d.as_three_axis_gyroscopes()?
                    .get_three_axis_gyroscope_status(i),
            )
        })
        .unwrap_or(MasStatus::Error);
        self.status_or_wait(s)
    }
    fn get_three_axis_gyroscope_name(&self, i: usize) -> DevResult<String> {
        with_device(&self.attached, |d| {
            Some(
                d.as_three_axis_gyroscopes()?
                    .get_three_axis_gyroscope_name(i),
            )
        })
        .unwrap_or(Err(DeviceError::NotOpen))
    }
    fn get_three_axis_gyroscope_frame_name(&self, i: usize) -> DevResult<String> {
        with_device(&self.attached, |d| {
            Some(
                d.as_three_axis_gyroscopes()?
                    .get_three_axis_gyroscope_frame_name(i),
            )
        })
        .unwrap_or(Err(DeviceError::NotOpen))
    }
    /// The gyro minus the estimated bias (C++ `ImuFilter::getThreeAxisGyroscopeMeasure`).
    fn get_three_axis_gyroscope_measure(&self, i: usize) -> DevResult<SensorMeasurement> {
        if i != 0 {
            return Err(no_sensor(NAME, i, 1));
        }
        match &lock(&self.shared).gyro {
            Some((values, t)) => Ok(SensorMeasurement::new(values.clone(), *t)),
            None => Err(DeviceError::Unsupported(
                "imuFilter: no gyroscope sample filtered yet",
            )),
        }
    }
}

/// The families that pass through to the attached IMU unchanged.
macro_rules! pass_through {
    ($trait:ident, $view:ident, $nr:ident, $status:ident, $name:ident, $frame:ident, $measure:ident) => {
        impl $trait for ImuFilter {
            fn $nr(&self) -> usize {
                with_device(&self.attached, |d| Some(d.$view()?.$nr())).unwrap_or(0)
            }
            fn $status(&self, i: usize) -> MasStatus {
                with_device(&self.attached, |d| Some(d.$view()?.$status(i)))
                    .unwrap_or(MasStatus::Error)
            }
            fn $name(&self, i: usize) -> DevResult<String> {
                with_device(&self.attached, |d| Some(d.$view()?.$name(i)))
                    .unwrap_or(Err(DeviceError::NotOpen))
            }
            fn $frame(&self, i: usize) -> DevResult<String> {
                with_device(&self.attached, |d| Some(d.$view()?.$frame(i)))
                    .unwrap_or(Err(DeviceError::NotOpen))
            }
            fn $measure(&self, i: usize) -> DevResult<SensorMeasurement> {
                with_device(&self.attached, |d| Some(d.$view()?.$measure(i)))
                    .unwrap_or(Err(DeviceError::NotOpen))
            }
        }
    };
}

pass_through!(
    IThreeAxisLinearAccelerometers,
    as_three_axis_linear_accelerometers,
    get_nr_of_three_axis_linear_accelerometers,
    get_three_axis_linear_accelerometer_status,
    get_three_axis_linear_accelerometer_name,
    get_three_axis_linear_accelerometer_frame_name,
    get_three_axis_linear_accelerometer_measure
);

pass_through!(
    IThreeAxisMagnetometers,
    as_three_axis_magnetometers,
    get_nr_of_three_axis_magnetometers,
    get_three_axis_magnetometer_status,
    get_three_axis_magnetometer_name,
    get_three_axis_magnetometer_frame_name,
    get_three_axis_magnetometer_measure
);

pass_through!(
    IOrientationSensors,
    as_orientation_sensors,
    get_nr_of_orientation_sensors,
    get_orientation_sensor_status,
    get_orientation_sensor_name,
    get_orientation_sensor_frame_name,
    get_orientation_sensor_measure_as_roll_pitch_yaw
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_filter_as_ctrl_lib() {
        let mut f = MedianFilter::new(2, 1);
        assert_eq!(f.filt(&[5.0]), [0.0]);
        assert_eq!(f.filt(&[1.0]), [0.0]);
        // three samples (order + 1): median of 5 1 3
        assert_eq!(f.filt(&[3.0]), [3.0]);
        // window 1 3 100 -> 3
        assert_eq!(f.filt(&[100.0]), [3.0]);
        let mut even = MedianFilter::new(1, 1);
        even.filt(&[1.0]);
        assert_eq!(even.filt(&[2.0]), [1.5]);
    }

    #[test]
    fn linear_estimator_finds_slopes() {
        let mut e = AwLinEstimator::new(40, 0.05);
        for k in 0..39 {
            assert_eq!(e.estimate(k as f64 * 0.01, &[0.0, 5.0]), [0.0, 0.0]);
        }
        let mut last = vec![];
        for k in 39..200 {
            let t = k as f64 * 0.01;
            last = e.estimate(t, &[2.0 * t, 5.0]);
        }
        assert!((last[0] - 2.0).abs() < 1e-9, "{last:?}");
        assert!(last[1].abs() < 1e-9, "{last:?}");
    }

    #[test]
    fn integrator_uses_tustin() {
        let mut i = Integrator::new(0.5, 1);
        assert_eq!(i.integrate(&[2.0]), [0.5]);
        assert_eq!(i.integrate(&[2.0]), [1.5]);
    }

    #[test]
    fn bias_converges_while_still_and_freezes_when_moving() {
        let params = FilterParams {
            bias_gain: 0.05,
            ..FilterParams::default()
        };
        let mut est = BiasEstimator::new(params);
        let bias = [1.5, -0.7, 0.3];
        let mut step = None;
        for k in 0..1500 {
            let t = k as f64 * 0.01;
            step = Some(est.step(&bias, &[0.2, 0.1, -0.4], t));
        }
        let s = step.unwrap();
        assert!(s.adapting);
        for (g, b) in s.gyro.iter().zip(bias) {
            assert!(g.abs() < 1e-3 * b.abs().max(1.0), "{s:?}");
        }
        for (e, b) in s.bias.iter().zip(bias) {
            assert!((e - b).abs() < 1e-3, "{s:?}");
        }
        // a magnetic field changing fast: the IMU is moving, the bias holds
        let held = s.bias.clone();
        let mut s = s;
        let mag = |t: f64| [0.2 + (t - 15.0), 0.1, -0.4];
        for k in 1500..1600 {
            let t = k as f64 * 0.01;
            s = est.step(&bias, &mag(t), t);
        }
        assert!(!s.adapting, "{s:?}");
        for k in 1600..1800 {
            let t = k as f64 * 0.01;
            s = est.step(&[10.0, 10.0, 10.0], &mag(t), t);
        }
        assert!(!s.adapting, "{s:?}");
        for (e, h) in s.bias.iter().zip(&held) {
            assert!((e - h).abs() < 0.05, "{s:?}");
        }
    }
}

//! The low-pass filter wholebodydynamics smooths its inputs with: icub-main's
//! `iCub::ctrl::realTime::FirstOrderLowPassFilter`, `1 / (τ s + 1)` with
//! `τ = 1 / (2π fc)`, discretised with Tustin's method at the device's period, and
//! started from zero as the device starts it.

/// One filter over a vector of `n` signals.
#[derive(Debug, Clone)]
pub struct LowPass {
    cutoff_hz: f64,
    period: f64,
    b: f64,
    a1: f64,
    a0: f64,
    u_old: Vec<f64>,
    y: Vec<f64>,
}

impl LowPass {
    pub fn new(n: usize, cutoff_hz: f64, period: f64) -> LowPass {
        let mut f = LowPass {
            cutoff_hz,
            period,
            b: 0.0,
            a1: 0.0,
            a0: 1.0,
            u_old: vec![0.0; n],
            y: vec![0.0; n],
        };
        f.coefficients();
        f
    }

    fn coefficients(&mut self) {
        let tau = 1.0 / (2.0 * std::f64::consts::PI * self.cutoff_hz);
        // num = [Ts, Ts], den = [2τ + Ts, Ts − 2τ]
        self.a0 = 2.0 * tau + self.period;
        self.a1 = self.period - 2.0 * tau;
        self.b = self.period;
    }

    /// A new cut-off frequency (C++ `setCutFrequency`, which ignores values ≤ 0);
    /// the state is kept.
    pub fn set_cutoff(&mut self, hz: f64) {
        if hz > 0.0 && hz != self.cutoff_hz {
            self.cutoff_hz = hz;
            self.coefficients();
        }
    }

    pub fn cutoff(&self) -> f64 {
        self.cutoff_hz
    }

    /// Filters one sample.
    pub fn filt(&mut self, u: &[f64]) -> &[f64] {
        for ((y, u_old), &u) in self.y.iter_mut().zip(&mut self.u_old).zip(u) {
            *y = (self.b * (u + *u_old) - self.a1 * *y) / self.a0;
            *u_old = u;
        }
        &self.y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_settles_to_its_value_with_the_time_constant() {
        let mut f = LowPass::new(1, 3.0, 0.001);
        let tau = 1.0 / (2.0 * std::f64::consts::PI * 3.0);
        let steps = (tau / 0.001).round() as usize;
        let mut y = 0.0;
        for _ in 0..steps {
            y = f.filt(&[1.0])[0];
        }
        // one time constant: 1 − 1/e
        assert!((y - (1.0 - (-1.0f64).exp())).abs() < 0.01, "{y}");
        for _ in 0..20 * steps {
            y = f.filt(&[1.0])[0];
        }
        assert!((y - 1.0).abs() < 1e-6);
    }
}

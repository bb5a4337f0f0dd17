//! The error-state Kalman filter on the crank's angle and speed (Sanjurjo et al.,
//! "State and force observers based on multibody models and the indirect Kalman
//! filter", their errorEKF): the twin's step is the prediction of the state, the filter
//! carries only the covariance of its error `x = (δθ1, δω1)`.
//!
//! Over a step of `h` the error propagates by `F = [[1, h], [0, 1]]` (the sensitivity
//! of the acceleration to the state neglected, as in errorEKF), driven by the model's
//! acceleration error taken as white noise of spectral density `q` (rad²/s³):
//! `Q = q [[h³/3, h²/2], [h²/2, h]]`. The measurement is the crank encoder's angle,
//! `H = [1, 0]`, with the quantization noise of an encoder of resolution `Δ`,
//! `R = Δ²/12`. The update's gain `K = P Hᵀ / (H P Hᵀ + R)` times the innovation is
//! the correction of the twin's state, after which the error's mean is 0 again (the
//! "reset" of the indirect filter) and `P` is updated in Joseph's form, symmetric and
//! positive in f32 as in f64.

use crate::scalar::Real;

/// The error's covariance, `[[P_θθ, P_θω], [P_θω, P_ωω]]` (rad², rad²/s, rad²/s²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Covariance<T> {
    /// Variance of the crank angle's error, rad².
    pub angle: T,
    /// Covariance of the angle's and speed's errors, rad²/s.
    pub cross: T,
    /// Variance of the crank speed's error, rad²/s².
    pub speed: T,
}

impl<T: Real> Covariance<T> {
    /// Uncorrelated errors of standard deviations `sigma_angle` (rad) and
    /// `sigma_speed` (rad/s).
    pub fn diagonal(sigma_angle: T, sigma_speed: T) -> Self {
        Covariance {
            angle: sigma_angle * sigma_angle,
            cross: T::zero(),
            speed: sigma_speed * sigma_speed,
        }
    }

    /// `F P Fᵀ + Q` over a step of `h` (s) with acceleration noise density `q`.
    pub fn predict(&self, h: T, q: T) -> Self {
        let (p, c, s) = (self.angle, self.cross, self.speed);
        let h2 = h * h;
        Covariance {
            angle: p + T::c(2.0) * h * c + h2 * s + q * h2 * h / T::c(3.0),
            cross: c + h * s + q * h2 / T::c(2.0),
            speed: s + q * h,
        }
    }

    /// The innovation's variance `H P Hᵀ + R` for a measurement noise variance `r`.
    pub fn innovation_variance(&self, r: T) -> T {
        self.angle + r
    }

    /// The gain `(K_θ, K_ω)` for measurement noise variance `r`.
    pub fn gain(&self, r: T) -> (T, T) {
        let s = self.innovation_variance(r);
        (self.angle / s, self.cross / s)
    }

    /// `(I - K H) P (I - K H)ᵀ + K R Kᵀ` for the gain `k` and noise variance `r`.
    pub fn update(&self, k: (T, T), r: T) -> Self {
        let (p, c, s) = (self.angle, self.cross, self.speed);
        let (a, b) = k;
        let one_a = T::one() - a;
        Covariance {
            angle: one_a * one_a * p + a * a * r,
            cross: one_a * (c - b * p) + a * b * r,
            speed: s - T::c(2.0) * b * c + b * b * p + b * b * r,
        }
    }

    /// Whether every term is finite.
    pub fn finite(&self) -> bool {
        self.angle.finite() && self.cross.finite() && self.speed.finite()
    }
}

#[cfg(test)]
mod tests {
    use super::Covariance;

    /// The Joseph update equals the textbook `(I - K H) P` at the optimal gain and the
    /// information form `P⁺⁻¹ = P⁻⁻¹ + Hᵀ R⁻¹ H` (two independent forms of the same
    /// update), step after step to the steady state.
    #[test]
    fn joseph_form_matches_the_simple_form_and_the_information_form() {
        let (h, q, r): (f64, f64, f64) = (1e-3, 50.0, 2e-7);
        let mut p = Covariance::<f64>::diagonal(0.1, 5.0);
        for _ in 0..2000 {
            let prior = p.predict(h, q);
            let k = prior.gain(r);
            let joseph = prior.update(k, r);
            // (I - K H) P
            let simple = Covariance {
                angle: (1.0 - k.0) * prior.angle,
                cross: (1.0 - k.0) * prior.cross,
                speed: prior.speed - k.1 * prior.cross,
            };
            // Information form: invert the prior, add Hᵀ R⁻¹ H, invert back.
            let det = prior.angle * prior.speed - prior.cross * prior.cross;
            let (ia, ic, is) = (
                prior.speed / det + 1.0 / r,
                -prior.cross / det,
                prior.angle / det,
            );
            let d2 = ia * is - ic * ic;
            let info = Covariance {
                angle: is / d2,
                cross: -ic / d2,
                speed: ia / d2,
            };
            for (x, y) in [
                (joseph.angle, simple.angle),
                (joseph.angle, info.angle),
                (joseph.cross, simple.cross),
                (joseph.cross, info.cross),
                (joseph.speed, simple.speed),
                (joseph.speed, info.speed),
            ] {
                assert!((x - y).abs() <= 1e-6 * y.abs().max(1e-30), "{x} vs {y}");
            }
            p = joseph;
        }
        // A steady state: the gain has settled.
        let k0 = p.predict(h, q).gain(r);
        let k1 = p.predict(h, q).update(k0, r).predict(h, q).gain(r);
        assert!((k0.0 - k1.0).abs() < 1e-9 && (k0.1 - k1.1).abs() < 1e-6);
    }
}

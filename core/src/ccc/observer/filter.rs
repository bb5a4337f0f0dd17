//! The error-state Kalman filter on the crank's angle and speed and an unknown torque
//! on the crank (Sanjurjo et al., "State and force observers based on multibody models
//! and the indirect Kalman filter", their errorEKF with force estimation): the twin's
//! step is the prediction of the state, the filter carries only the covariance of its
//! error `x = (δθ1, δω1, δd)`, `d` the torque on the crank (N·m, CCW) that the machine
//! has and the model lacks (its joints' friction, its masses' errors seen at the
//! crank), a random walk applied in the prediction as an addition to the motor's
//! torque.
//!
//! Over a step of `h` the error propagates by
//! `F = [[1, h, h² b/2], [0, 1, h b], [0, 0, 1]]`, `b = r M⁻¹ rᵀ` the crank's mobility
//! in the present mode (its angular acceleration per N·m on it, `r = ∂θ1/∂q`, `M` the
//! mode's mass matrix; the sensitivity of the acceleration to the state neglected, as
//! in errorEKF), driven by the model's acceleration error taken as white noise of
//! spectral density `q` (rad²/s³) and the torque's random walk of density `q_d`
//! (N²·m²/s): `Q = q [[h³/3, h²/2, 0], [h²/2, h, 0], [0, 0, 0]] + q_d h e₃e₃ᵀ`. The
//! measurement is the crank encoder's angle, `H = [1, 0, 0]`, with the quantization
//! noise of an encoder of resolution `Δ`, `R = n Δ²/12` for a crank that takes `n`
//! steps to cross a count (1 ≤ n ≤ 100: [`quantization_variance`](super::quantization_variance)). The update's gain
//! `K = P Hᵀ / (H P Hᵀ + R)` times the innovation is the correction of the twin's state
//! (its first two terms) and of the torque's estimate (its third), after which the
//! error's mean is 0 again (the "reset" of the indirect filter) and `P` is updated in
//! Joseph's form, symmetric and positive in f32 as in f64.

use crate::scalar::Real;
use nalgebra::{Matrix3, Vector3};

/// The error's covariance over `(δθ1, δω1, δd)` (rad, rad/s, N·m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Covariance<T: Real> {
    /// The matrix, symmetric.
    pub m: Matrix3<T>,
}

impl<T: Real> Covariance<T> {
    /// Uncorrelated errors of standard deviations `sigma` (angle rad, speed rad/s,
    /// torque N·m).
    pub fn diagonal(sigma: (T, T, T)) -> Self {
        let (a, w, d) = sigma;
        Covariance {
            m: Matrix3::from_diagonal(&Vector3::new(a * a, w * w, d * d)),
        }
    }

    /// Variance of the crank angle's error, rad².
    pub fn angle(&self) -> T {
        self.m[(0, 0)]
    }

    /// Variance of the crank speed's error, (rad/s)².
    pub fn speed(&self) -> T {
        self.m[(1, 1)]
    }

    /// Variance of the torque estimate's error, (N·m)².
    pub fn torque(&self) -> T {
        self.m[(2, 2)]
    }

    /// `F P Fᵀ + Q` over a step of `h` (s) with the crank's mobility `b` (1/(kg·m²)),
    /// acceleration noise density `q` (rad²/s³) and torque random-walk density `q_d`
    /// (N²·m²/s).
    pub fn predict(&self, h: T, b: T, q: T, q_d: T) -> Self {
        let (z, one, half) = (T::zero(), T::one(), T::c(0.5));
        let h2 = h * h;
        let f = Matrix3::new(one, h, half * h2 * b, z, one, h * b, z, z, one);
        let qm = Matrix3::new(
            q * h2 * h / T::c(3.0),
            q * h2 * half,
            z,
            q * h2 * half,
            q * h,
            z,
            z,
            z,
            q_d * h,
        );
        Covariance {
            m: f * self.m * f.transpose() + qm,
        }
    }

    /// The variances `speed` ((rad/s)²) and `torque` ((N·m)²) added: a mode change's,
    /// the impact's outcome and the new mode's inertia errors seen at the crank.
    pub fn inflate(&mut self, speed: T, torque: T) {
        self.m[(1, 1)] += speed;
        self.m[(2, 2)] += torque;
    }

    /// The innovation's variance `H P Hᵀ + R` for a measurement noise variance `r`.
    pub fn innovation_variance(&self, r: T) -> T {
        self.angle() + r
    }

    /// The gain `K = P Hᵀ / S` (angle, speed, torque) for measurement noise variance
    /// `r`.
    pub fn gain(&self, r: T) -> Vector3<T> {
        let s = self.innovation_variance(r);
        self.m.column(0) / s
    }

    /// `(I - K H) P (I - K H)ᵀ + K R Kᵀ` for the gain `k` and noise variance `r`.
    pub fn update(&self, k: &Vector3<T>, r: T) -> Self {
        let mut a = Matrix3::identity();
        a.set_column(0, &(Vector3::x() - k));
        let m = a * self.m * a.transpose() + k * k.transpose() * r;
        // Symmetric to the bit (rounding would part the halves over many steps).
        Covariance {
            m: (m + m.transpose()) * T::c(0.5),
        }
    }

    /// Whether every term is finite.
    pub fn finite(&self) -> bool {
        self.m.iter().all(|v| v.finite())
    }
}

#[cfg(test)]
mod tests {
    use super::Covariance;
    use nalgebra::{Matrix3, Vector3};

    /// The prediction equals `F P Fᵀ + Q` of the augmented state written out term by
    /// term; the Joseph update equals the textbook `(I - K H) P` at the optimal gain
    /// and the information form `P⁺⁻¹ = P⁻⁻¹ + Hᵀ R⁻¹ H` (independent forms of the same
    /// update), step after step to the steady state; there the torque's estimate has a
    /// gain (the innovation observes it through the mobility).
    #[test]
    fn joseph_form_matches_the_simple_form_and_the_information_form() {
        let (h, b, q, qd, r): (f64, f64, f64, f64, f64) = (1e-3, 8.0, 50.0, 100.0, 2e-7);
        let mut p = Covariance::<f64>::diagonal((0.1, 5.0, 2.0));
        for _ in 0..2000 {
            let prior = p.predict(h, b, q, qd);
            // x' = (θ + h ω + h² b d / 2, ω + h b d, d), term by term.
            let f = [
                [1.0, h, h * h * b / 2.0],
                [0.0, 1.0, h * b],
                [0.0, 0.0, 1.0],
            ];
            let noise = [
                [q * h * h * h / 3.0, q * h * h / 2.0, 0.0],
                [q * h * h / 2.0, q * h, 0.0],
                [0.0, 0.0, qd * h],
            ];
            let hand = Matrix3::from_fn(|i, j| {
                let mut s = noise[i][j];
                for k in 0..3 {
                    for l in 0..3 {
                        s += f[i][k] * p.m[(k, l)] * f[j][l];
                    }
                }
                s
            });
            let scale = prior.m.diagonal().amax();
            assert!((prior.m - hand).amax() <= 1e-12 * scale);
            let k = prior.gain(r);
            let joseph = prior.update(&k, r);
            // (I - K H) P
            let mut a = Matrix3::identity();
            a.set_column(0, &(Vector3::x() - k));
            let simple = a * prior.m;
            // Information form: invert the prior, add Hᵀ R⁻¹ H, invert back.
            let mut info = prior.m.try_inverse().unwrap();
            info[(0, 0)] += 1.0 / r;
            let info = info.try_inverse().unwrap();
            for (i, x) in joseph.m.iter().enumerate() {
                let tol = 1e-6 * (joseph.m[(i % 3, i % 3)] * joseph.m[(i / 3, i / 3)]).sqrt();
                assert!((x - simple[i]).abs() <= tol, "{x} vs {}", simple[i]);
                assert!((x - info[i]).abs() <= tol, "{x} vs {}", info[i]);
            }
            assert!(joseph.m == joseph.m.transpose());
            p = joseph;
        }
        // A steady state: the gain has settled, the torque's among it.
        let k0 = p.predict(h, b, q, qd).gain(r);
        let k1 = p
            .predict(h, b, q, qd)
            .update(&k0, r)
            .predict(h, b, q, qd)
            .gain(r);
        assert!((k0 - k1).amax() < 1e-6 * k0.amax());
        assert!(k0[2] > 0.0);
    }
}

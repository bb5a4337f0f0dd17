//! The error-state Kalman filter on the crank's angle and speed, an unknown torque on
//! the crank and an unknown viscous friction of the crank's bearing (Sanjurjo et al.,
//! "State and force observers based on multibody models and the indirect Kalman
//! filter", their errorEKF with force estimation, the force given a speed-proportional
//! part): the twin's step is the prediction of the state, the filter carries only the
//! covariance of its error `x = (δθ1, δω1, δd, δc)`. The crank's torque that the
//! machine has and the model lacks is `d - c ω1` (N·m, CCW; `ω1` the crank's speed,
//! rad/s): `d` (N·m) its joints' friction and its masses' errors seen at the crank, a
//! random walk; `c` (N·m·s/rad) the viscous friction of the bearing A (crank on
//! ground), a random walk too. Both are applied in the prediction with the motor's
//! torque.
//!
//! Over a step of `h` the error propagates by
//! `F = [[1, h, h² b/2, -h² b ω1/2], [0, 1, h b, -h b ω1], [0, 0, 1, 0], [0, 0, 0, 1]]`,
//! `b = r M⁻¹ rᵀ` the crank's mobility in the present mode (its angular acceleration
//! per N·m on it, `r = ∂θ1/∂q`, `M` the mode's mass matrix; the sensitivity of the
//! acceleration to the state neglected, as in errorEKF), driven by the model's
//! acceleration error taken as white noise of spectral density `q` (rad²/s³), the
//! torque's random walk of density `q_d` (N²·m²/s) and the friction's of density `q_c`
//! ((N·m·s/rad)²/s): `Q = q [[h³/3, h²/2], [h²/2, h]] ⊕ diag(q_d h, q_c h)`. With `c`'s
//! variance and `q_c` 0 the filter is the three-state one of `(δθ1, δω1, δd)`, bit for
//! bit (its terms with `c` add zeros). The
//! measurement is the crank encoder's angle, `H = [1, 0, 0, 0]`, with the quantization
//! noise of an encoder of resolution `Δ`, `R = n Δ²/12` for a crank that takes `n`
//! steps to cross a count (1 ≤ n ≤ 100: [`quantization_variance`](super::quantization_variance)). The update's gain
//! `K = P Hᵀ / (H P Hᵀ + R)` times the innovation is the correction of the twin's state
//! (its first two terms) and of the torque's and friction's estimates (its last two), after which the
//! error's mean is 0 again (the "reset" of the indirect filter) and `P` is updated in
//! Joseph's form, symmetric and positive in f32 as in f64.

use crate::scalar::Real;
use nalgebra::{Matrix4, Vector4};

/// The error's covariance over `(δθ1, δω1, δd, δc)` (rad, rad/s, N·m, N·m·s/rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Covariance<T: Real> {
    /// The matrix, symmetric.
    pub m: Matrix4<T>,
}

impl<T: Real> Covariance<T> {
    /// Uncorrelated errors of standard deviations `sigma` (angle rad, speed rad/s,
    /// torque N·m) and `friction` (N·m·s/rad).
    pub fn diagonal(sigma: (T, T, T), friction: T) -> Self {
        let (a, w, d) = sigma;
        Covariance {
            m: Matrix4::from_diagonal(&Vector4::new(a * a, w * w, d * d, friction * friction)),
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

    /// Variance of the friction estimate's error, (N·m·s/rad)².
    pub fn friction(&self) -> T {
        self.m[(3, 3)]
    }

    /// `F P Fᵀ + Q` over a step of `h` (s) with the crank's mobility `b` (1/(kg·m²))
    /// and speed `omega` (rad/s), acceleration noise density `q` (rad²/s³), torque
    /// random-walk density `q_d` (N²·m²/s) and friction random-walk density `q_c`
    /// ((N·m·s/rad)²/s).
    pub fn predict(&self, h: T, (b, omega): (T, T), q: T, q_d: T, q_c: T) -> Self {
        let (z, one, half) = (T::zero(), T::one(), T::c(0.5));
        let h2 = h * h;
        let (hb, h2b) = (h * b, half * h2 * b);
        #[rustfmt::skip]
        let f = Matrix4::new(
            one, h, h2b, -(h2b * omega),
            z, one, hb, -(hb * omega),
            z, z, one, z,
            z, z, z, one,
        );
        #[rustfmt::skip]
        let qm = Matrix4::new(
            q * h2 * h / T::c(3.0), q * h2 * half, z, z,
            q * h2 * half, q * h, z, z,
            z, z, q_d * h, z,
            z, z, z, q_c * h,
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

    /// The gain `K = P Hᵀ / S` (angle, speed, torque, friction) for measurement noise
    /// variance `r`.
    pub fn gain(&self, r: T) -> Vector4<T> {
        let s = self.innovation_variance(r);
        self.m.column(0) / s
    }

    /// `(I - K H) P (I - K H)ᵀ + K R Kᵀ` for the gain `k` and noise variance `r`.
    pub fn update(&self, k: &Vector4<T>, r: T) -> Self {
        let mut a = Matrix4::identity();
        a.set_column(0, &(Vector4::x() - k));
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
    use nalgebra::{Matrix3, Matrix4, Vector3, Vector4};

    /// The prediction equals `F P Fᵀ + Q` of the augmented state written out term by
    /// term; the Joseph update equals the textbook `(I - K H) P` at the optimal gain
    /// and the information form `P⁺⁻¹ = P⁻⁻¹ + Hᵀ R⁻¹ H` (independent forms of the same
    /// update), step after step to the steady state, with the crank's speed swinging
    /// as a converter's does; there the torque's and the friction's estimates have
    /// gains (the innovation observes them through the mobility, the friction through
    /// the speed's swing too).
    #[test]
    fn joseph_form_matches_the_simple_form_and_the_information_form() {
        let (h, b, q, qd, qc, r): (f64, f64, f64, f64, f64, f64) =
            (1e-3, 8.0, 50.0, 100.0, 0.01, 2e-7);
        let mut p = Covariance::<f64>::diagonal((0.1, 5.0, 2.0), 0.05);
        // A swing of 100 steps.
        let omega = |n: usize| -20.0 + 8.0 * (n as f64 * core::f64::consts::TAU / 100.0).sin();
        let mut gains = [Vector4::zeros(); 4000];
        for (n, gain) in gains.iter_mut().enumerate() {
            let w = omega(n);
            let prior = p.predict(h, (b, w), q, qd, qc);
            // x' = (θ + h ω + h² b (d - c ω1) / 2, ω + h b (d - c ω1), d, c), term by term.
            let f = [
                [1.0, h, h * h * b / 2.0, -h * h * b * w / 2.0],
                [0.0, 1.0, h * b, -h * b * w],
                [0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ];
            let noise = [
                [q * h * h * h / 3.0, q * h * h / 2.0, 0.0, 0.0],
                [q * h * h / 2.0, q * h, 0.0, 0.0],
                [0.0, 0.0, qd * h, 0.0],
                [0.0, 0.0, 0.0, qc * h],
            ];
            let hand = Matrix4::from_fn(|i, j| {
                let mut s = noise[i][j];
                for k in 0..4 {
                    for l in 0..4 {
                        s += f[i][k] * p.m[(k, l)] * f[j][l];
                    }
                }
                s
            });
            for (i, x) in prior.m.iter().enumerate() {
                let tol = 1e-12 * (prior.m[(i % 4, i % 4)] * prior.m[(i / 4, i / 4)]).sqrt();
                assert!((x - hand[i]).abs() <= tol, "{x} vs {}", hand[i]);
            }
            let k = prior.gain(r);
            *gain = k;
            let joseph = prior.update(&k, r);
            // (I - K H) P
            let mut a = Matrix4::identity();
            a.set_column(0, &(Vector4::x() - k));
            let simple = a * prior.m;
            // Information form: invert the prior, add Hᵀ R⁻¹ H, invert back.
            let mut info = prior.m.try_inverse().unwrap();
            info[(0, 0)] += 1.0 / r;
            let info = info.try_inverse().unwrap();
            for (i, x) in joseph.m.iter().enumerate() {
                let tol = 1e-6 * (joseph.m[(i % 4, i % 4)] * joseph.m[(i / 4, i / 4)]).sqrt();
                assert!((x - simple[i]).abs() <= tol, "{x} vs {}", simple[i]);
                assert!((x - info[i]).abs() <= tol, "{x} vs {}", info[i]);
            }
            assert!(joseph.m == joseph.m.transpose());
            p = joseph;
        }
        // A periodic steady state: the gain has settled to the swing's period (each
        // term within 1e-3 of itself a period before; the friction's settles slowest),
        // the torque's and the friction's among it.
        let (k0, k1) = (gains[3899], gains[3999]);
        for (a, b) in k0.iter().zip(k1.iter()) {
            assert!((a - b).abs() < 1e-3 * b.abs(), "{k0} {k1}");
        }
        assert!(k1[2] > 0.0);
        assert!(k1[3] != 0.0);
    }

    /// With the friction's variance and random walk 0 the filter is the three-state one
    /// of `(δθ1, δω1, δd)` to the bit: its prediction, gain and update written with 3×3
    /// matrices here, step after step.
    #[test]
    fn without_friction_the_filter_is_the_three_state_one_bit_for_bit() {
        let (h, b, q, qd, r): (f64, f64, f64, f64, f64) = (1e-3, 8.0, 50.0, 100.0, 2e-7);
        let mut p4 = Covariance::<f64>::diagonal((0.1, 5.0, 2.0), 0.0);
        let mut p3 = Matrix3::from_diagonal(&Vector3::new(0.1 * 0.1, 5.0 * 5.0, 2.0 * 2.0));
        for n in 0..500 {
            let w = -20.0 + 8.0 * (n as f64 * 0.05).sin();
            // The three-state filter's expressions, as they were written.
            let h2 = h * h;
            let f = Matrix3::new(1.0, h, 0.5 * h2 * b, 0.0, 1.0, h * b, 0.0, 0.0, 1.0);
            let qm = Matrix3::new(
                q * h2 * h / 3.0,
                q * h2 * 0.5,
                0.0,
                q * h2 * 0.5,
                q * h,
                0.0,
                0.0,
                0.0,
                qd * h,
            );
            let prior3 = f * p3 * f.transpose() + qm;
            let k3: Vector3<f64> = prior3.column(0) / (prior3[(0, 0)] + r);
            let mut a = Matrix3::identity();
            a.set_column(0, &(Vector3::x() - k3));
            let m = a * prior3 * a.transpose() + k3 * k3.transpose() * r;
            p3 = (m + m.transpose()) * 0.5;

            let prior4 = p4.predict(h, (b, w), q, qd, 0.0);
            let k4 = prior4.gain(r);
            p4 = prior4.update(&k4, r);
            for i in 0..3 {
                assert_eq!(k4[i].to_bits(), k3[i].to_bits(), "gain {i} at step {n}");
                for j in 0..3 {
                    assert_eq!(
                        p4.m[(i, j)].to_bits(),
                        p3[(i, j)].to_bits(),
                        "P at step {n}"
                    );
                }
                assert_eq!(p4.m[(i, 3)], 0.0);
            }
            assert_eq!(k4[3], 0.0);
        }
    }
}

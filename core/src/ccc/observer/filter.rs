//! The error-state Kalman filter on the crank's angle and speed, an unknown torque on
//! the crank, an unknown viscous friction of the crank's bearing and the oscillating
//! mass's error (Sanjurjo et al., "State and force observers based on multibody models
//! and the indirect Kalman filter", their errorEKF with force estimation, the force
//! given a speed-proportional part, the state augmented by a parameter): the twin's
//! step is the prediction of the state, the filter carries only the covariance of its
//! error `x = (δθ1, δω1, δd, δc, δm)`. The crank's torque that the machine has and the
//! model lacks is `d - c ω1` (N·m, CCW; `ω1` the crank's speed, rad/s): `d` (N·m) its
//! joints' friction and its masses' errors seen at the crank, a random walk; `c`
//! (N·m·s/rad) the viscous friction of the bearing A (crank on ground), a random walk
//! too. Both are applied in the prediction with the motor's torque. `m` (kg) is the
//! oscillating mass, a random walk as well, which the twin's models carry
//! ([`Twin::set_oscillating_mass`](super::Twin::set_oscillating_mass)).
//!
//! Over a step of `h` the error propagates by
//! `F = [[1, h, h² b/2, -h² b ω1/2, h² a_m/2], [0, 1, h b, -h b ω1, h a_m], [0, 0, 1, 0, 0],
//! [0, 0, 0, 1, 0], [0, 0, 0, 0, 1]]`, `b = r M⁻¹ rᵀ` the crank's mobility in the present
//! mode (its angular acceleration per N·m on it, `r = ∂θ1/∂q`, `M` the mode's mass
//! matrix) and `a_m = ∂α1/∂m` the crank's acceleration's sensitivity to the mass
//! ([`Twin::crank_mass_sensitivity`](super::Twin::crank_mass_sensitivity)); the
//! sensitivity of the acceleration to the state neglected, as in errorEKF. It is
//! driven by the model's acceleration error taken as white noise of spectral density
//! `q` (rad²/s³) and the random walks of densities `q_d` (N²·m²/s), `q_c`
//! ((N·m·s/rad)²/s) and `q_m` (kg²/s): `Q = q [[h³/3, h²/2], [h²/2, h]] ⊕ diag(q_d h,
//! q_c h, q_m h)`. With the variances and random walks of `c` and `m` 0 the filter is
//! the three-state one of `(δθ1, δω1, δd)`, bit for bit (their terms add zeros). The
//! measurement is the crank encoder's angle, `H = [1, 0, 0, 0, 0]`, with the
//! quantization noise of an encoder of resolution `Δ`, `R = n Δ²/12` for a crank that
//! takes `n` steps to cross a count (1 ≤ n ≤ 100:
//! [`quantization_variance`](super::quantization_variance)). The update's gain
//! `K = P Hᵀ / (H P Hᵀ + R)` times the innovation is the correction of the twin's state
//! (its first two terms) and of the estimates (its last three), after which the
//! error's mean is 0 again (the "reset" of the indirect filter) and `P` is updated in
//! Joseph's form, symmetric and positive in f32 as in f64.

use crate::scalar::Real;
use nalgebra::{Matrix5, SVector};

/// The error state's size: `(δθ1, δω1, δd, δc, δm)`.
pub const N: usize = 5;
type Matrix<T> = Matrix5<T>;
/// A gain, or a column of `P`.
pub type Gain<T> = SVector<T, N>;

/// The error's covariance over `(δθ1, δω1, δd, δc, δm)` (rad, rad/s, N·m, N·m·s/rad,
/// kg).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Covariance<T: Real> {
    /// The matrix, symmetric.
    pub m: Matrix<T>,
}

impl<T: Real> Covariance<T> {
    /// Uncorrelated errors of standard deviations `sigma` (angle rad, speed rad/s,
    /// torque N·m), `friction` (N·m·s/rad) and `mass` (kg).
    pub fn diagonal(sigma: (T, T, T), friction: T, mass: T) -> Self {
        let (a, w, d) = sigma;
        Covariance {
            m: Matrix::from_diagonal(&Gain::from([
                a * a,
                w * w,
                d * d,
                friction * friction,
                mass * mass,
            ])),
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

    /// Variance of the oscillating mass estimate's error, kg².
    pub fn mass(&self) -> T {
        self.m[(4, 4)]
    }

    /// `F P Fᵀ + Q` over a step of `h` (s) with the crank's mobility `b` (1/(kg·m²)),
    /// speed `omega` (rad/s) and acceleration's sensitivity to the mass `a_m`
    /// (rad/s² per kg); the acceleration noise density `q` (rad²/s³) and the random
    /// walks' densities of the torque `q_d` (N²·m²/s), the friction `q_c`
    /// ((N·m·s/rad)²/s) and the mass `q_m` (kg²/s).
    pub fn predict(
        &self,
        h: T,
        (b, omega, a_m): (T, T, T),
        (q, q_d, q_c, q_m): (T, T, T, T),
    ) -> Self {
        let (z, one, half) = (T::zero(), T::one(), T::c(0.5));
        let h2 = h * h;
        let (hb, h2b) = (h * b, half * h2 * b);
        #[rustfmt::skip]
        let f = Matrix::new(
            one, h, h2b, -(h2b * omega), half * h2 * a_m,
            z, one, hb, -(hb * omega), h * a_m,
            z, z, one, z, z,
            z, z, z, one, z,
            z, z, z, z, one,
        );
        #[rustfmt::skip]
        let qm = Matrix::new(
            q * h2 * h / T::c(3.0), q * h2 * half, z, z, z,
            q * h2 * half, q * h, z, z, z,
            z, z, q_d * h, z, z,
            z, z, z, q_c * h, z,
            z, z, z, z, q_m * h,
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

    /// The gain `K = P Hᵀ / S` (angle, speed, torque, friction, mass) for measurement noise
    /// variance `r`.
    pub fn gain(&self, r: T) -> Gain<T> {
        let s = self.innovation_variance(r);
        self.m.column(0) / s
    }

    /// `(I - K H) P (I - K H)ᵀ + K R Kᵀ` for the gain `k` and noise variance `r`.
    pub fn update(&self, k: &Gain<T>, r: T) -> Self {
        let mut a = Matrix::identity();
        let mut e0 = Gain::zeros();
        e0[0] = T::one();
        a.set_column(0, &(e0 - k));
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
    use super::{Covariance, Gain, Matrix, N};
    use nalgebra::{Matrix3, Vector3};

    /// The prediction equals `F P Fᵀ + Q` of the augmented state written out term by
    /// term; the Joseph update equals the textbook `(I - K H) P` at the optimal gain
    /// and the information form `P⁺⁻¹ = P⁻⁻¹ + Hᵀ R⁻¹ H` (independent forms of the same
    /// update), step after step to the steady state, with the crank's speed and the
    /// mass's sensitivity swinging as a converter's do; there the torque's, the
    /// friction's and the mass's estimates have gains (the innovation observes them
    /// through the mobility, the speed's swing and the sensitivity's).
    #[test]
    fn joseph_form_matches_the_simple_form_and_the_information_form() {
        let (h, b, q, qd, qc, qm, r): (f64, f64, f64, f64, f64, f64, f64) =
            (1e-3, 8.0, 50.0, 100.0, 0.01, 0.05, 2e-7);
        let mut p = Covariance::<f64>::diagonal((0.1, 5.0, 2.0), 0.05, 0.5);
        // A swing of 100 steps.
        let phase = |n: usize| n as f64 * core::f64::consts::TAU / 100.0;
        let omega = |n: usize| -20.0 + 8.0 * phase(n).sin();
        let sens = |n: usize| 30.0 * phase(n).cos() - 5.0;
        let mut gains = [Gain::zeros(); 4000];
        for (n, gain) in gains.iter_mut().enumerate() {
            let (w, am) = (omega(n), sens(n));
            let prior = p.predict(h, (b, w, am), (q, qd, qc, qm));
            // x' = (θ + h ω + h² (b (d - c ω1) + a_m m) / 2, ω + h (b (d - c ω1) + a_m m),
            // d, c, m), term by term.
            let f = [
                [
                    1.0,
                    h,
                    h * h * b / 2.0,
                    -h * h * b * w / 2.0,
                    h * h * am / 2.0,
                ],
                [0.0, 1.0, h * b, -h * b * w, h * am],
                [0.0, 0.0, 1.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 1.0, 0.0],
                [0.0, 0.0, 0.0, 0.0, 1.0],
            ];
            let noise = [
                [q * h * h * h / 3.0, q * h * h / 2.0, 0.0, 0.0, 0.0],
                [q * h * h / 2.0, q * h, 0.0, 0.0, 0.0],
                [0.0, 0.0, qd * h, 0.0, 0.0],
                [0.0, 0.0, 0.0, qc * h, 0.0],
                [0.0, 0.0, 0.0, 0.0, qm * h],
            ];
            let hand = Matrix::from_fn(|i, j| {
                let mut s = noise[i][j];
                for k in 0..N {
                    for l in 0..N {
                        s += f[i][k] * p.m[(k, l)] * f[j][l];
                    }
                }
                s
            });
            for (i, x) in prior.m.iter().enumerate() {
                let tol = 1e-12 * (prior.m[(i % N, i % N)] * prior.m[(i / N, i / N)]).sqrt();
                assert!((x - hand[i]).abs() <= tol, "{x} vs {}", hand[i]);
            }
            let k = prior.gain(r);
            *gain = k;
            let joseph = prior.update(&k, r);
            // (I - K H) P
            let mut a = Matrix::identity();
            let mut e0 = Gain::zeros();
            e0[0] = 1.0;
            a.set_column(0, &(e0 - k));
            let simple = a * prior.m;
            // Information form: invert the prior, add Hᵀ R⁻¹ H, invert back.
            let mut info = prior.m.try_inverse().unwrap();
            info[(0, 0)] += 1.0 / r;
            let info = info.try_inverse().unwrap();
            for (i, x) in joseph.m.iter().enumerate() {
                let tol = 1e-6 * (joseph.m[(i % N, i % N)] * joseph.m[(i / N, i / N)]).sqrt();
                assert!((x - simple[i]).abs() <= tol, "{x} vs {}", simple[i]);
                assert!((x - info[i]).abs() <= tol, "{x} vs {}", info[i]);
            }
            assert!(joseph.m == joseph.m.transpose());
            p = joseph;
        }
        // A periodic steady state: the gain has settled to the swing's period (each
        // term within 1e-3 of itself a period before), the estimates' among it.
        let (k0, k1) = (gains[3899], gains[3999]);
        for (a, b) in k0.iter().zip(k1.iter()) {
            assert!((a - b).abs() < 1e-3 * b.abs(), "{k0} {k1}");
        }
        assert!(k1[2] > 0.0);
        assert!(k1[3] != 0.0);
        assert!(k1[4] != 0.0);
    }

    /// With the friction's and the mass's variances and random walks 0 the filter is
    /// the three-state one of `(δθ1, δω1, δd)` to the bit: its prediction, gain and
    /// update written with 3×3 matrices here, step after step (the mass's sensitivity
    /// not 0: with no variance it moves nothing).
    #[test]
    fn without_friction_and_mass_the_filter_is_the_three_state_one_bit_for_bit() {
        let (h, b, q, qd, r): (f64, f64, f64, f64, f64) = (1e-3, 8.0, 50.0, 100.0, 2e-7);
        let mut p5 = Covariance::<f64>::diagonal((0.1, 5.0, 2.0), 0.0, 0.0);
        let mut p3 = Matrix3::from_diagonal(&Vector3::new(0.1 * 0.1, 5.0 * 5.0, 2.0 * 2.0));
        for n in 0..500 {
            let w = -20.0 + 8.0 * (n as f64 * 0.05).sin();
            let am = 30.0 * (n as f64 * 0.05).cos();
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

            let prior5 = p5.predict(h, (b, w, am), (q, qd, 0.0, 0.0));
            let k5 = prior5.gain(r);
            p5 = prior5.update(&k5, r);
            for i in 0..3 {
                assert_eq!(k5[i].to_bits(), k3[i].to_bits(), "gain {i} at step {n}");
                for j in 0..3 {
                    assert_eq!(
                        p5.m[(i, j)].to_bits(),
                        p3[(i, j)].to_bits(),
                        "P at step {n}"
                    );
                }
                assert_eq!(p5.m[(i, 3)], 0.0);
                assert_eq!(p5.m[(i, 4)], 0.0);
            }
            assert_eq!(k5[3], 0.0);
            assert_eq!(k5[4], 0.0);
        }
    }

    /// The update of a gain without the mass's row (the twin kept its mass: the
    /// observer's update when the mass's correction is refused) leaves the mass's
    /// variance as predicted, while the optimal gain shrinks it; both are symmetric
    /// and positive on the diagonal (the Joseph form holds for any gain).
    #[test]
    fn a_gain_without_the_mass_s_row_leaves_its_variance() {
        let mut p = Covariance::<f64>::diagonal((0.1, 5.0, 2.0), 0.05, 0.5);
        for _ in 0..50 {
            p = p.predict(1e-3, (8.0, -20.0, 12.0), (50.0, 100.0, 0.01, 0.05));
        }
        let r = 2e-7;
        let k = p.gain(r);
        assert!(k[4].abs() > 0.0, "the mass is observed: {k:?}");
        let mut kept = k;
        kept[4] = 0.0;
        let (full, made) = (p.update(&k, r), p.update(&kept, r));
        assert!(full.m[(4, 4)] < p.m[(4, 4)]);
        assert_eq!(made.m[(4, 4)].to_bits(), p.m[(4, 4)].to_bits());
        for c in [full, made] {
            assert_eq!(c.m, c.m.transpose());
            assert!((0..N).all(|i| c.m[(i, i)] > 0.0));
        }
    }
}

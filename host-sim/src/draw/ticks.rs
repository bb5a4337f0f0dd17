//! Axis ticks at "nice numbers" (Heckbert, *Nice numbers for graph labels*, Graphics
//! Gems, 1990): steps of 1, 2 or 5 times a power of ten.

/// A nice number near `x > 0`: 1, 2, 5 or 10 times a power of ten; `round`: the nearest
/// (thresholds 1.5, 3, 7), else the smallest not below `x`.
pub fn nice(x: f64, round: bool) -> f64 {
    if !(x.is_finite() && x > 0.0) {
        return 1.0;
    }
    let e = x.log10().floor();
    let p = 10f64.powf(e);
    let f = x / p;
    let nf = if round {
        if f < 1.5 {
            1.0
        } else if f < 3.0 {
            2.0
        } else if f < 7.0 {
            5.0
        } else {
            10.0
        }
    } else if f <= 1.0 {
        1.0
    } else if f <= 2.0 {
        2.0
    } else if f <= 5.0 {
        5.0
    } else {
        10.0
    };
    nf * p
}

/// The most tick intervals an axis takes (Heckbert's labelling gives about `n`; more
/// means the arithmetic overflowed).
const MAX_TICKS: f64 = 1000.0;

/// Ticks of an axis.
#[derive(Clone, Debug, PartialEq)]
pub struct Ticks {
    /// The axis's ends: the data range widened to whole steps.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// The step.
    pub step: f64,
    /// The tick values from `lo` to `hi`.
    pub values: Vec<f64>,
    /// Decimals that print every tick exactly (in fixed notation).
    pub decimals: usize,
}

/// About `n` (≥ 2) ticks covering `[lo, hi]` (Heckbert's loose labelling). An empty
/// range is widened (by 10 % of the value, or to ±1 around 0); non-finite ends give
/// the axis 0..1.
pub fn ticks(lo: f64, hi: f64, n: usize) -> Ticks {
    let (mut lo, mut hi) = if lo.is_finite() && hi.is_finite() {
        (lo.min(hi), lo.max(hi))
    } else {
        (0.0, 1.0)
    };
    if hi - lo <= f64::EPSILON * lo.abs().max(hi.abs()) {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        lo -= d;
        hi += d;
    }
    let n = n.max(2);
    let range = nice(hi - lo, false);
    let step = nice(range / (n - 1) as f64, true);
    let k0 = (lo / step).floor();
    let k1 = (hi / step).ceil();
    // Ends near ±f64::MAX: the span or the nice step overflows (a step of 1 over a
    // range of 1e308 would be 1e308 ticks). The axis is its two ends.
    if !(step.is_finite() && (0.0..=MAX_TICKS).contains(&(k1 - k0))) {
        return Ticks {
            lo,
            hi,
            step: hi - lo,
            values: vec![lo, hi],
            decimals: 0,
        };
    }
    // Tick k is k·step (not a running sum: no drift).
    let values: Vec<f64> = (0..=(k1 - k0) as i64)
        .map(|k| (k0 + k as f64) * step)
        .collect();
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    Ticks {
        lo: k0 * step,
        hi: k1 * step,
        step,
        values,
        decimals,
    }
}

impl Ticks {
    /// The label of tick value `v`: fixed notation with [`Ticks::decimals`], or
    /// scientific for very large or small steps.
    pub fn label(&self, v: f64) -> String {
        let big = self.lo.abs().max(self.hi.abs());
        let s = if self.step < 1e-4 || big >= 1e6 {
            format!("{v:.1e}")
        } else {
            format!("{v:.*}", self.decimals)
        };
        // -0 prints as 0.
        if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
            s[1..].to_string()
        } else {
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // Hand-computed with Heckbert's rules.
    #[test]
    fn nice_numbers() {
        assert_eq!(nice(1.0, false), 1.0);
        assert_eq!(nice(1.2, false), 2.0);
        assert_eq!(nice(9.4, false), 10.0);
        assert_eq!(nice(0.034, false), 0.05);
        assert_eq!(nice(2.5, true), 2.0);
        assert_eq!(nice(3.5, true), 5.0);
        assert_eq!(nice(7.2, true), 10.0);
        assert_eq!(nice(140.0, true), 100.0);
    }

    #[test]
    fn ticks_hand_computed() {
        // range nice(9.4) = 10, step nice(10/4 = 2.5, round) = 2: 0, 2, ..., 10.
        let t = ticks(0.3, 9.7, 5);
        assert_eq!(t.values, vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        assert_eq!((t.lo, t.hi, t.decimals), (0.0, 10.0, 0));
        // range nice(15.8) = 20, step nice(4) = 5: -5 .. 15.
        let t = ticks(-3.7, 12.1, 5);
        assert_eq!(t.values, vec![-5.0, 0.0, 5.0, 10.0, 15.0]);
        // range nice(1) = 1, step nice(0.25) = 0.2: labels with one decimal.
        let t = ticks(0.0, 1.0, 5);
        assert_eq!(t.step, 0.2);
        assert_eq!(t.values.len(), 6);
        let labels: Vec<String> = t.values.iter().map(|v| t.label(*v)).collect();
        assert_eq!(labels, ["0.0", "0.2", "0.4", "0.6", "0.8", "1.0"]);
        // range nice(8) = 10, step 2: 1000 .. 1010.
        let t = ticks(1001.0, 1009.0, 5);
        assert_eq!(
            t.values,
            vec![1000.0, 1002.0, 1004.0, 1006.0, 1008.0, 1010.0]
        );
        // A negative range of small numbers: range nice(0.0032) = 0.005, step
        // nice(0.00125) = 0.001: -0.004 .. 0.
        let t = ticks(-0.0035, -0.0003, 5);
        assert_eq!(t.decimals, 3);
        let labels: Vec<String> = t.values.iter().map(|v| t.label(*v)).collect();
        assert_eq!(labels, ["-0.004", "-0.003", "-0.002", "-0.001", "0.000"]);
    }

    #[test]
    fn degenerate_ranges() {
        let t = ticks(5.0, 5.0, 5);
        assert!(t.lo < 5.0 && t.hi > 5.0, "{t:?}");
        let t = ticks(0.0, 0.0, 5);
        assert_eq!((t.lo, t.hi), (-1.0, 1.0));
        let t = ticks(f64::NAN, 3.0, 5);
        assert_eq!((t.lo, t.hi), (0.0, 1.0));
        let t = ticks(2.0, 1.0, 5);
        assert!(t.lo <= 1.0 && t.hi >= 2.0);
    }

    /// Ends near ±f64::MAX (a CSV's 1.7e308): the nice step overflows, or the span;
    /// the axis is its two ends (it panicked allocating 2^63 ticks).
    #[test]
    fn ranges_near_the_largest_float() {
        for (lo, hi) in [(0.0, 1.7e308), (-1e308, 1e308), (-f64::MAX, f64::MAX)] {
            let t = ticks(lo, hi, 5);
            assert_eq!(t.values, [lo, hi], "{lo}..{hi}");
            assert!(t.values.iter().all(|v| !t.label(*v).is_empty()));
        }
        // 1e307 still has nice ticks: 0, 2e306, ... 1e307 (Heckbert's).
        let t = ticks(0.0, 1e307, 5);
        assert!(t.values.len() > 2 && t.values.len() < 20, "{t:?}");
    }
}

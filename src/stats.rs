//! Small statistics for the façade ensembles: the Wilson score interval of a
//! binomial proportion, the standard normal CDF, sample quantiles, and a seeded
//! counter-based random stream.
//!
//! References: E. B. Wilson (1927), "Probable inference, the law of succession,
//! and statistical inference", JASA 22, 209–212; Brown, Cai & DasGupta (2001),
//! "Interval estimation for a binomial proportion", Statistical Science 16, 101–133
//! (why Wilson and not the Wald interval at small n or extreme p); G. L. Steele,
//! D. Lea & C. H. Flood (2014), "Fast splittable pseudorandom number generators",
//! OOPSLA (SplitMix64); W. H. Press et al., Numerical Recipes, §6.2 (erfc by a
//! Chebyshev fit, fractional error below 1.2e-7 everywhere).
//!
//! Why our own random stream: every sample of an ensemble must be a pure function
//! of (seed, record, coefficient set, polarity, sample index) so that the numbers do not
//! depend on the number of threads or the order in which rayon runs the samples.
//! SplitMix64 is the standard generator for exactly that (a 64-bit mixer over a
//! counter, passing BigCrush); it is a dozen lines and its values can never
//! change under a crate upgrade.

/// z of a two-sided 95 % interval: Φ⁻¹(0.975).
pub const Z95: f64 = 1.959_963_984_540_054;

/// Wilson score interval of a proportion k/n at normal quantile z:
///
///   centre = (p̂ + z²/2n) / (1 + z²/n),
///   half   = z/(1 + z²/n) · √(p̂(1 − p̂)/n + z²/4n²),
///
/// with p̂ = k/n. Returns (lo, hi), clamped to [0, 1]; (0, 1) when n = 0.
pub fn wilson(k: usize, n: usize, z: f64) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let z2 = z * z;
    let den = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / den;
    let half = z / den * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// Complementary error function, erfc(x) = 2/√π ∫ₓ^∞ e^(−t²) dt, by the Chebyshev
/// fit of Numerical Recipes §6.2 (fractional error < 1.2e-7 for every x).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06 + t * (0.278_868_07 + t * (-1.135_203_98 + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let ans = t * (-z * z + poly).exp();
    if x >= 0.0 {
        ans
    } else {
        2.0 - ans
    }
}

/// P(χ²(k) > x) for k ≥ 1 degrees of freedom, in closed form (Abramowitz &
/// Stegun 26.4.4–5), y = x/2:
/// - k even: e^(−y) Σ_{j<k/2} yʲ/j!;
/// - k odd: erfc(√y) + e^(−y) Σ_{j=1}^{(k−1)/2} y^(j−½)/Γ(j+½).
///
/// The terms are summed from their recurrence (each is the last × y/j, or
/// × y/(j + ½)); accuracy that of [`erfc`] (1.2e-7 relative) for odd k.
pub fn chi2_sf(x: f64, k: usize) -> f64 {
    if x <= 0.0 || k == 0 {
        return 1.0;
    }
    let y = 0.5 * x;
    let odd = k % 2 == 1;
    let mut term = if odd { 2.0 * (y / std::f64::consts::PI).sqrt() } else { 1.0 };
    let mut sum = 0.0;
    for j in 0..k / 2 {
        if j > 0 {
            term *= y / (j as f64 + if odd { 0.5 } else { 0.0 });
        }
        sum += term;
    }
    let tail = if odd { erfc(y.sqrt()) } else { 0.0 };
    (tail + (-y).exp() * sum).min(1.0)
}

/// Standard normal CDF Φ(x) = ½ erfc(−x/√2).
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x / std::f64::consts::SQRT_2)
}

/// Standard normal density φ(x) = e^(−x²/2)/√(2π).
pub fn normal_pdf(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// Quantile q ∈ [0, 1] of a sorted sample, linear between order statistics
/// (Hyndman & Fan type 7: h = (n − 1) q). NaN for an empty sample.
pub fn quantile_sorted(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        1 => sorted[0],
        n => {
            let h = (n - 1) as f64 * q.clamp(0.0, 1.0);
            let i = h.floor() as usize;
            let j = (i + 1).min(n - 1);
            sorted[i] + (h - i as f64) * (sorted[j] - sorted[i])
        }
    }
}

/// Sort a copy (NaN last) and return it.
pub fn sorted(v: &[f64]) -> Vec<f64> {
    let mut s = v.to_vec();
    s.sort_by(|a, b| a.total_cmp(b));
    s
}

/// The SplitMix64 output function: a bijective 64-bit mixer.
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

const GOLDEN: u64 = 0x9e37_79b9_7f4a_7c15;

/// A SplitMix64 stream: state += γ, output mix64(state).
#[derive(Debug, Clone)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    pub fn new(state: u64) -> SplitMix64 {
        SplitMix64 { state }
    }

    /// The stream of one ensemble sample: its state is the key words folded in
    /// through the mixer one after the other, so each key gets an unrelated stream.
    pub fn for_key(words: &[u64]) -> SplitMix64 {
        let mut s = 0x5eed_u64;
        for &w in words {
            s = mix64(s.wrapping_add(GOLDEN) ^ w);
        }
        SplitMix64 { state: s }
    }

    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(GOLDEN);
        mix64(self.state)
    }

    /// Uniform on [0, 1) with 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Standard normal by Box–Muller (the cosine branch; one normal per pair of
    /// uniforms, so a draw always consumes the same two numbers).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform(); // (0, 1]
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against scipy.stats.chi2.sf (1.17.1) at odd and even k, in the tails and
    /// the middle: relative 1e-6 (the erfc's 1.2e-7 for odd k, with margin).
    #[test]
    fn chi2_sf_matches_scipy() {
        for (x, k, want) in [
            (4.3, 3, 0.23083874820887584),
            (10.0, 4, 0.04042768199451279),
            (0.5, 1, 0.47950012218695337),
            (30.0, 7, 9.495972508134177e-05),
            (1e-3, 2, 0.9995001249791693),
            (50.0, 20, 0.0002214766382487835),
        ] {
            let got = chi2_sf(x, k);
            assert!((got / want - 1.0).abs() < 1e-6, "chi2_sf({x}, {k}) = {got}, scipy {want}");
        }
        assert!(chi2_sf(2250.0, 3) < 1e-300);
        assert_eq!(chi2_sf(0.0, 3), 1.0);
    }

    /// Hand-computed: k = 7, n = 20, z = 1.96: p̂ = 0.35, z²/n = 0.19208,
    /// den = 1.19208, centre = (0.35 + 0.09604)/1.19208 = 0.374169,
    /// half = 1.96/1.19208 · √(0.011375 + 0.002401) = 0.192980: (0.181190, 0.567150).
    /// With z = Φ⁻¹(0.975) the same as R's prop.test(7, 20, correct = FALSE):
    /// 0.1811918, 0.5671457.
    #[test]
    fn wilson_hand_computed() {
        let (lo, hi) = wilson(7, 20, 1.96);
        assert!((lo - 0.181_190).abs() < 1e-6, "{lo}");
        assert!((hi - 0.567_150).abs() < 1e-6, "{hi}");
        let (lo, hi) = wilson(7, 20, Z95);
        assert!((lo - 0.181_191_8).abs() < 1e-7, "{lo}");
        assert!((hi - 0.567_145_7).abs() < 1e-7, "{hi}");
        // k = 0: lo = 0, hi = z²/(n + z²) = 3.8416/23.8416 = 0.161130.
        let (lo, hi) = wilson(0, 20, 1.96);
        assert_eq!(lo, 0.0);
        assert!((hi - 3.8416 / 23.8416).abs() < 1e-12, "{hi}");
        // k = n mirrors k = 0.
        let (lo, hi) = wilson(20, 20, 1.96);
        assert!((lo - 20.0 / 23.8416).abs() < 1e-12 && hi == 1.0, "{lo} {hi}");
        // n = 1000, k = 500, z = Z95: centre 0.5, half = z/(1+z²/n) √(1/4000 + z²/4e6)
        let (lo, hi) = wilson(500, 1000, Z95);
        let z2 = Z95 * Z95;
        let half = Z95 / (1.0 + z2 / 1000.0) * (0.25 / 1000.0 + z2 / 4e6).sqrt();
        assert!((lo - (0.5 - half)).abs() < 1e-15 && (hi - (0.5 + half)).abs() < 1e-15);
        assert!((half - 0.030_938).abs() < 1e-5, "{half}");
        assert_eq!(wilson(0, 0, Z95), (0.0, 1.0));
    }

    /// Φ against tabulated values (Abramowitz & Stegun Table 26.1), within the
    /// erfc fit's 1.2e-7 fractional error.
    #[test]
    fn normal_cdf_table() {
        for (x, p) in [
            (0.0, 0.5),
            (1.0, 0.841_344_746_068_542_9),
            (Z95, 0.975),
            (-1.644_853_626_951_472_2, 0.05),
            (-3.0, 0.001_349_898_031_630_094_6),
            (-6.0, 9.865_876_450_376_946e-10),
        ] {
            assert!((normal_cdf(x) / p - 1.0).abs() < 1.5e-7, "Φ({x}) = {} vs {p}", normal_cdf(x));
        }
    }

    #[test]
    fn quantiles() {
        let s = sorted(&[3.0, 1.0, 2.0, 4.0]);
        assert_eq!(quantile_sorted(&s, 0.5), 2.5);
        assert_eq!(quantile_sorted(&s, 0.0), 1.0);
        assert_eq!(quantile_sorted(&s, 1.0), 4.0);
        assert!((quantile_sorted(&s, 0.05) - 1.15).abs() < 1e-12);
        assert!(quantile_sorted(&[], 0.5).is_nan());
    }

    /// The reference outputs of SplitMix64 seeded with 0 (Vigna's splitmix64.c).
    #[test]
    fn splitmix_reference() {
        let mut r = SplitMix64::new(0);
        assert_eq!(r.next_u64(), 0xe220_a839_7b1d_cdaf);
        assert_eq!(r.next_u64(), 0x6e78_9e6a_a1b9_65f4);
        assert_eq!(r.next_u64(), 0x06c4_5d18_8009_454f);
    }

    /// Box–Muller draws: mean 0 and variance 1 within 4 standard errors
    /// (n = 20000: se(mean) = 0.0071, se(var) ≈ √(2/n) = 0.01).
    #[test]
    fn normal_moments() {
        let mut r = SplitMix64::for_key(&[1, 2, 3]);
        let n = 20_000;
        let v: Vec<f64> = (0..n).map(|_| r.normal()).collect();
        let m = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1) as f64;
        assert!(m.abs() < 4.0 * 0.0071, "{m}");
        assert!((var - 1.0).abs() < 4.0 * 0.01, "{var}");
        let below = v.iter().filter(|x| **x < -1.644_853_6).count() as f64 / n as f64;
        assert!((below - 0.05).abs() < 4.0 * (0.05f64 * 0.95 / n as f64).sqrt(), "{below}");
    }
}

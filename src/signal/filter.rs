//! The low-pass filters of a data logger's acquisition chain, as continuous
//! systems, and their exact response to a piecewise-cubic input.
//!
//! # Causal analogue low-pass (Bessel, Butterworth, order 2–8)
//! An all-pole filter with unit gain at DC,
//!
//!   H(s) = Π(−p_j) / Π(s − p_j) = Σ_j r_j / (s − p_j),
//!   r_j = Π_i(−p_i) / Π_{i≠j}(p_j − p_i)                    (partial fractions),
//!
//! whose poles p_j are those of the prototype with |H(iω)| = 1/√2 at ω = 1
//! (−3 dB at the cut-off: scipy's `norm="mag"`) scaled by ω_c = 2π f_c:
//! - Butterworth: p_k = exp(iπ (2k + n − 1) / (2n)), k = 1..n;
//! - Bessel: the roots of the reverse Bessel polynomial
//!   θ_n(s) = Σ_k (2n − k)! / (2^(n−k) k! (n − k)!) s^k (unit group delay at
//!   DC), scaled so that |H(i)| = 1/√2 (bisection on the frequency).
//!
//! In modal form each pole is one first-order state, x_j' = p_j x_j + r_j u,
//! y = Σ_j x_j (conjugate pairs: 2 Re of one of them). Over a step of length h
//! with an input u(s) = Σ_n c_n s^n (n ≤ 3) the update is exact:
//!
//!   x_j(h) = e^(p_j h) x_j(0) + r_j Σ_n c_n I_n,
//!   I_n = ∫₀ʰ e^(p(h−s)) s^n ds = h^(n+1) Σ_m (ph)^m n! / (n + m + 1)!,
//!
//! (the series for |ph| ≤ 4; for larger steps the recurrence
//! I_0 = (e^(ph) − 1)/p, I_n = (n I_(n−1) − h^n)/p). Fed with the cubic Hermite
//! interpolant of a model's value and slope between nodes that include its
//! kinks, this is the model seen through the filter with an error of
//! h⁴ max|y⁗|/384 (see `peaks/acquisition.rs`).
//!
//! No crate gives the analogue prototypes in modal form with an exact
//! piecewise-polynomial response; the pole formulas and the partial fractions
//! are a few lines, checked against scipy's (`tests` below).

use nalgebra::{Complex, DMatrix};

type C = Complex<f64>;

/// Family of a causal analogue low-pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Family {
    Bessel,
    Butterworth,
}

impl Family {
    pub fn as_str(self) -> &'static str {
        match self {
            Family::Bessel => "bessel",
            Family::Butterworth => "butterworth",
        }
    }
}

/// A causal analogue low-pass: family, order, −3 dB frequency.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LowPass {
    pub family: Family,
    pub order: usize,
    pub cutoff_hz: f64,
}

/// The orders a stated filter may have.
pub const ORDERS: std::ops::RangeInclusive<usize> = 2..=8;

impl LowPass {
    /// The filter in modal form.
    pub fn modal(&self) -> Modal {
        Modal::new(&prototype_poles(self.family, self.order), 2.0 * std::f64::consts::PI * self.cutoff_hz)
    }
    /// "bessel, order 4, −3 dB at 37.5 Hz".
    pub fn describe(&self) -> String {
        format!("{}, order {}, −3 dB at {:.3} Hz", self.family.as_str(), self.order, self.cutoff_hz)
    }
}

/// Poles of the prototype of `family` and `order` with −3 dB at 1 rad/s.
pub fn prototype_poles(family: Family, order: usize) -> Vec<C> {
    let n = order as f64;
    match family {
        Family::Butterworth => (1..=order)
            .map(|k| C::from_polar(1.0, std::f64::consts::PI * (2.0 * k as f64 + n - 1.0) / (2.0 * n)))
            .collect(),
        Family::Bessel => {
            let poles = bessel_delay_poles(order);
            let w = cutoff_of(&poles);
            poles.into_iter().map(|p| p / w).collect()
        }
    }
}

/// Roots of the reverse Bessel polynomial (unit group delay at DC): the
/// eigenvalues of its companion matrix.
fn bessel_delay_poles(n: usize) -> Vec<C> {
    let fact = |k: usize| (1..=k).map(|i| i as f64).product::<f64>();
    let a: Vec<f64> = (0..=n)
        .map(|k| fact(2 * n - k) / (2f64.powi((n - k) as i32) * fact(k) * fact(n - k)))
        .collect();
    let mut m = DMatrix::<f64>::zeros(n, n);
    for i in 1..n {
        m[(i, i - 1)] = 1.0;
    }
    for i in 0..n {
        m[(i, n - 1)] = -a[i] / a[n];
    }
    m.complex_eigenvalues().iter().copied().collect()
}

/// |H(iω)|² of the unit-DC all-pole filter with these poles.
fn gain2(poles: &[C], w: f64) -> f64 {
    let s = C::new(0.0, w);
    poles.iter().map(|p| (p.norm_sqr()) / (s - p).norm_sqr()).product()
}

/// The frequency where |H(iω)|² = 1/2 (bisection; the gain falls monotonically).
fn cutoff_of(poles: &[C]) -> f64 {
    let (mut lo, mut hi) = (1e-3f64, 1e3f64);
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if gain2(poles, mid) > 0.5 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo * hi).sqrt()
}

/// An all-pole unit-DC filter in modal form: one pole of each conjugate pair
/// (weight 2) and the real poles (weight 1), their residues.
#[derive(Debug, Clone, PartialEq)]
pub struct Modal {
    pub poles: Vec<C>,
    pub residues: Vec<C>,
    pub weights: Vec<f64>,
}

impl Modal {
    /// From the prototype's poles (−3 dB at 1 rad/s) and the cut-off ω_c (rad/s).
    pub fn new(prototype: &[C], omega_c: f64) -> Modal {
        let p: Vec<C> = prototype.iter().map(|&q| q * omega_c).collect();
        let k: C = p.iter().map(|&q| -q).product();
        let (mut poles, mut residues, mut weights) = (Vec::new(), Vec::new(), Vec::new());
        for (j, &pj) in p.iter().enumerate() {
            if pj.im < -1e-9 * pj.norm() {
                continue;
            }
            let den: C = p.iter().enumerate().filter(|&(i, _)| i != j).map(|(_, &pi)| pj - pi).product();
            poles.push(pj);
            residues.push(k / den);
            weights.push(if pj.im.abs() > 1e-9 * pj.norm() { 2.0 } else { 1.0 });
        }
        Modal { poles, residues, weights }
    }

    /// Gain at DC (1 by construction: Σ −w r / p).
    pub fn dc_gain(&self) -> f64 {
        self.output(&self.steady_state(1.0))
    }

    /// Group delay at DC (s): τ = −H'(0)/H(0) = Σ_j w_j Re(r_j / p_j²).
    pub fn group_delay(&self) -> f64 {
        self.poles
            .iter()
            .zip(&self.residues)
            .zip(&self.weights)
            .map(|((&p, &r), w)| w * (r / (p * p)).re)
            .sum()
    }

    /// The state that holds a constant input u forever.
    pub fn steady_state(&self, u: f64) -> Vec<C> {
        self.poles.iter().zip(&self.residues).map(|(&p, &r)| -r * u / p).collect()
    }

    pub fn output(&self, x: &[C]) -> f64 {
        x.iter().zip(&self.weights).map(|(xi, w)| w * xi.re).sum()
    }

    /// The exact step of length h with the input Σ c_n s^n (s from the start of
    /// the step), given the step's coefficients ([`Modal::step_coefficients`]).
    pub fn advance(&self, x: &mut [C], steps: &StepCoefficients, c: [f64; 4]) {
        for (j, xj) in x.iter_mut().enumerate() {
            let i = &steps.integrals[j];
            let drive = i[0] * c[0] + i[1] * c[1] + i[2] * c[2] + i[3] * c[3];
            *xj = steps.decay[j] * *xj + self.residues[j] * drive;
        }
    }

    /// e^(p h) and I_0..I_3 of every pole for a step h.
    pub fn step_coefficients(&self, h: f64) -> StepCoefficients {
        StepCoefficients {
            decay: self.poles.iter().map(|&p| (p * h).exp()).collect(),
            integrals: self.poles.iter().map(|&p| moment_integrals(p, h)).collect(),
        }
    }
}

/// What [`Modal::advance`] needs of a step length.
#[derive(Debug, Clone)]
pub struct StepCoefficients {
    decay: Vec<C>,
    integrals: Vec<[C; 4]>,
}

/// I_n = ∫₀ʰ e^(p(h−s)) s^n ds for n = 0..3 (module docs).
fn moment_integrals(p: C, h: f64) -> [C; 4] {
    let z = p * h;
    let mut out = [C::new(0.0, 0.0); 4];
    if z.norm() <= 4.0 {
        for (n, o) in out.iter_mut().enumerate() {
            // Σ_m z^m n!/(n+m+1)!: term_m = term_{m−1} z / (n + m + 1).
            let mut term = C::new(1.0 / (n + 1) as f64, 0.0);
            let mut sum = term;
            for m in 1..40 {
                term = term * z / (n + m + 1) as f64;
                sum += term;
                if term.norm() < 1e-17 * sum.norm() {
                    break;
                }
            }
            *o = sum * h.powi(n as i32 + 1);
        }
    } else {
        let e = z.exp();
        out[0] = (e - 1.0) / p;
        for n in 1..4 {
            out[n] = (out[n - 1] * n as f64 - h.powi(n as i32)) / p;
        }
    }
    out
}

/// Coefficients of the cubic on [0, h] with values y0, y1 and slopes v0, v1.
pub fn hermite_cubic(y0: f64, v0: f64, y1: f64, v1: f64, h: f64) -> [f64; 4] {
    let d = (y1 - y0) / h;
    [y0, v0, (3.0 * d - 2.0 * v0 - v1) / h, (v0 + v1 - 2.0 * d) / (h * h)]
}

/// A linear-phase windowed-sinc FIR (Hamming window, `taps` logger samples
/// long, cut-off f_c), taken about its centre (zero phase: its delay of half its
/// length shifts every time alike and is absorbed by the model's times), by its
/// kink responses. Its passband is flat to 10⁻³, so a smooth input y passes as
/// y + (m₂/2) y″ (m₂ = ∫ τ² h, from the window's ripple); a kink of slope jump
/// Δv and curvature jump Δa at t_k adds Δv C₁(t − t_k) + Δa G₂(t − t_k), with
///
///   C₁(s) = ∫ h(τ) (s − τ)₊ dτ − s₊,
///   G₂(s) = ∫ h(τ) (s − τ)₊²/2 dτ − s₊²/2 − (m₂/2) [s > 0],
///
/// both zero beyond half the length; tabulated at 64 points per sample.
#[derive(Debug, Clone)]
pub struct Fir {
    pub cutoff_hz: f64,
    /// Half the length (s).
    pub half: f64,
    /// m₂/2 (s²).
    pub m2_half: f64,
    step: f64,
    c1: Vec<f64>,
    g2: Vec<f64>,
}

impl Fir {
    pub fn new(cutoff_hz: f64, taps: usize, dt: f64) -> Fir {
        let half = 0.5 * taps as f64 * dt;
        let n = taps * 64;
        let step = 2.0 * half / n as f64;
        let tau: Vec<f64> = (0..n).map(|i| -half + (i as f64 + 0.5) * step).collect();
        let mut h: Vec<f64> = tau.iter().map(|&t| windowed_sinc(cutoff_hz, half, t)).collect();
        let area: f64 = h.iter().sum::<f64>() * step;
        h.iter_mut().for_each(|v| *v /= area);
        let m2_half = 0.5 * h.iter().zip(&tau).map(|(hv, t)| hv * t * t).sum::<f64>() * step;
        // Running sums over the cells left of each edge: Σ h, Σ h τ, Σ h τ².
        let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
        let (mut c1, mut g2) = (Vec::with_capacity(n + 1), Vec::with_capacity(n + 1));
        for i in 0..=n {
            let s = -half + i as f64 * step;
            let pos = if s > 0.0 { s } else { 0.0 };
            // ∫_{τ<s} h (s − τ) = s Σh − Σhτ; ∫ h (s − τ)²/2 = (s² Σh − 2 s Σhτ + Σhτ²)/2.
            c1.push((s * s0 - s1) * step - pos);
            let jump = if s > 0.0 { m2_half } else { 0.0 };
            g2.push(0.5 * (s * s * s0 - 2.0 * s * s1 + s2) * step - 0.5 * pos * pos - jump);
            if i < n {
                s0 += h[i];
                s1 += h[i] * tau[i];
                s2 += h[i] * tau[i] * tau[i];
            }
        }
        Fir {
            cutoff_hz,
            half,
            m2_half,
            step,
            c1,
            g2,
        }
    }

    /// (C₁, G₂) at s = t − t_k (linear in the table); zero beyond half the length.
    pub fn kink(&self, s: f64) -> (f64, f64) {
        if s <= -self.half || s >= self.half {
            return (0.0, 0.0);
        }
        let x = (s + self.half) / self.step;
        let i = (x.floor() as usize).min(self.c1.len() - 2);
        let f = x - i as f64;
        (
            self.c1[i] + f * (self.c1[i + 1] - self.c1[i]),
            self.g2[i] + f * (self.g2[i + 1] - self.g2[i]),
        )
    }
}

/// 2 f_c sinc(2 f_c τ) (0.54 + 0.46 cos(π τ / half)): the FIR before normalisation.
fn windowed_sinc(fc: f64, half: f64, tau: f64) -> f64 {
    let x = 2.0 * fc * tau;
    let sinc = if x.abs() < 1e-12 {
        1.0
    } else {
        (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
    };
    2.0 * fc * sinc * (0.54 + 0.46 * (std::f64::consts::PI * tau / half).cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// scipy.signal.bessel(4, 1, analog=True, norm="mag", output="zpk") poles
    /// (scipy 1.17.1), −3 dB at 1 rad/s.
    #[test]
    fn bessel_poles_match_scipy() {
        let scipy = [(-0.99520876, 1.25710574), (-1.37006783, 0.41024972)];
        let mut p: Vec<C> = prototype_poles(Family::Bessel, 4).into_iter().filter(|p| p.im > 0.0).collect();
        p.sort_by(|a, b| b.im.total_cmp(&a.im));
        for (q, (re, im)) in p.iter().zip(scipy) {
            assert!((q.re - re).abs() < 1e-7 && (q.im - im).abs() < 1e-7, "{q} against {re} {im}");
        }
    }

    /// Every prototype of order 2–8 has −3 dB at 1 rad/s, unit DC gain, stable poles.
    #[test]
    fn prototypes_are_normalised() {
        for family in [Family::Bessel, Family::Butterworth] {
            for n in ORDERS {
                let p = prototype_poles(family, n);
                assert_eq!(p.len(), n);
                assert!(p.iter().all(|q| q.re < 0.0));
                assert!((gain2(&p, 1.0) - 0.5).abs() < 1e-9, "{family:?} {n}");
                assert!((Modal::new(&p, 3.0).dc_gain() - 1.0).abs() < 1e-12);
            }
        }
    }

    /// A ramp through the modal filter comes out delayed by the group delay at
    /// DC: for Bessel 4 in norm="mag" 2.113918/ω_c (the delay-normalised
    /// prototype has unit delay and −3 dB at 2.11391767 rad/s, scipy's
    /// magnitude factor for n = 4; 0.99 samples at 0.34 f_s, the shift seen on
    /// daq-public-bessel-1). Checks the partial fractions and the exact steps together.
    #[test]
    fn ramp_is_delayed_by_the_group_delay() {
        let f = LowPass {
            family: Family::Bessel,
            order: 4,
            cutoff_hz: 10.0,
        };
        let m = f.modal();
        let h = 1e-3;
        let steps = m.step_coefficients(h);
        let mut y = m.steady_state(0.0);
        let mut t = 0.0;
        for _ in 0..1000 {
            m.advance(&mut y, &steps, [t, 1.0, 0.0, 0.0]);
            t += h;
        }
        let delay = t - m.output(&y);
        let want = 2.11391767 / (2.0 * std::f64::consts::PI * f.cutoff_hz);
        assert!((delay / want - 1.0).abs() < 1e-6, "delay {delay} against {want}");
        assert!((m.group_delay() / want - 1.0).abs() < 1e-6, "Σ w r/p² = {}", m.group_delay());
    }

    /// The series and the recurrence of I_n agree where both are accurate.
    #[test]
    fn moment_integrals_agree() {
        let p = C::new(-30.0, 40.0);
        for h in [0.09, 0.1, 0.11] {
            let a = moment_integrals(p, h);
            // Simpson with 20 000 cells.
            let n = 20_000;
            for (k, ak) in a.iter().enumerate() {
                let f = |s: f64| (p * (h - s)).exp() * s.powi(k as i32);
                let mut sum = f(0.0) + f(h);
                for i in 1..n {
                    sum += f(h * i as f64 / n as f64) * if i % 2 == 1 { 4.0 } else { 2.0 };
                }
                let s = sum * h / (3.0 * n as f64);
                assert!((ak - s).norm() < 1e-10 * s.norm().max(1e-12), "h {h} n {k}: {ak} {s}");
            }
        }
    }

    /// The FIR's kink responses vanish beyond half its length and C₁ is
    /// continuous through the kink; m₂ matches scipy's
    /// `firwin(1280, 2·0.42/20)` taps (Σ b τ² = 0.5725 samples², scipy 1.17.1).
    #[test]
    fn fir_kink_responses_are_local() {
        let f = Fir::new(0.42, 64, 1.0);
        assert!((2.0 * f.m2_half - 0.5725).abs() < 2e-3, "m2 {}", 2.0 * f.m2_half);
        for s in [-31.99, 31.99] {
            let (a, b) = f.kink(s);
            assert!(a.abs() < 1e-4 && b.abs() < 1e-3, "s {s}: {a} {b}");
        }
        let (l, r) = (f.kink(-1e-3), f.kink(1e-3));
        assert!((l.0 - r.0).abs() < 1e-2, "{l:?} {r:?}");
        assert!(f.kink(0.0).0 > 0.1, "a kink is rounded");
    }
}

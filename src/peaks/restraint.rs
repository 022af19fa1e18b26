//! The inward arc of one-sided rocking: the wall against the transverse walls,
//! a compression-only spring–dashpot restraint.
//!
//! On the inward side, y = L θ < 0 (outward positive) obeys
//!
//!   y'' = F + p² y + R,  R = max(0, −κ y − 2γ y'),  F = A p²,
//!
//! gravity (F + p² y, Eq. 1 linearised about θ = 0) and the restraint's push R.
//! While the restraint bears (R > 0) this is the linear arc of [`InwardArc::linear`],
//! y'' = F − λ y − 2γ y' with λ = κ − p². On the way in (y' < 0) and at the apex
//! R > 0. On the way out the dashpot pulls against the spring, and where
//! κ |y| = 2γ y' the restraint would have to pull: a contact cannot, so the wall
//! separates from it at t_s and rocks freely, y'' = F + p² y, accelerating
//! outward until y = 0 ([`InwardArc`]). The wall is then fastest at the end of
//! the half-cycle; a dashpot that could pull would brake it there and put the
//! velocity peak inside the arc, several ms early and a few per cent low (the
//! MuJoCo one-sided campaign, whose transverse walls are such contacts, showed
//! exactly that bias). With γ ≤ 0 the restraint never lets go before y = 0 and
//! the arc is the linear one (the idealised model: γ = 0).
//!
//! Written here rather than taken from an ODE crate: both pieces are closed
//! forms, and the separation time solves one scalar equation, so the arc costs
//! a dozen exponentials per model evaluation, where a general integrator would
//! cost thousands and be neither smooth in the parameters (which the
//! Levenberg–Marquardt Jacobian needs) nor exact.

use super::gravity::Illinois;

/// φ₂, φ₂' and ψ of the linear arc at τ (see [`InwardArc::linear`]), with ψ by its
/// series where |λ| T² is small (T = `t_len`).
fn parts(lambda: f64, gamma: f64, t_len: f64, x: f64) -> (f64, f64, f64) {
    let mu2 = gamma * gamma - lambda;
    let (c, s) = if (mu2 * x * x).abs() < 1e-8 {
        (1.0 + 0.5 * mu2 * x * x, x * (1.0 + mu2 * x * x / 6.0))
    } else if mu2 > 0.0 {
        let m = mu2.sqrt();
        ((m * x).cosh(), (m * x).sinh() / m)
    } else {
        let w = (-mu2).sqrt();
        ((w * x).cos(), (w * x).sin() / w)
    };
    let e = (-gamma * x).exp();
    let phi2 = e * s;
    let dphi2 = e * (c - gamma * s);
    let psi = if (lambda * t_len * t_len).abs() < 1e-2 {
        step_response_series(lambda, gamma, x)
    } else {
        (1.0 - e * (c + gamma * s)) / lambda
    };
    (psi, phi2, dphi2)
}

/// ψ(τ) of [`InwardArc::linear`] by its power series (|λ| τ² small).
fn step_response_series(lambda: f64, gamma: f64, x: f64) -> f64 {
    let (mut a1, mut a2) = (0.0, 0.5);
    let mut sum = 0.5 * x * x;
    let mut pw = x * x;
    for n in 1..40 {
        // a_{n+2} from a_{n+1} (= a2) and a_n (= a1).
        let next = (-2.0 * gamma * (n + 1) as f64 * a2 - lambda * a1) / ((n + 2) * (n + 1)) as f64;
        pw *= x;
        sum += next * pw;
        a1 = a2;
        a2 = next;
        if (next * pw).abs() < 1e-17 * sum.abs() {
            break;
        }
    }
    sum
}

/// The inward arc against a compression-only restraint (module docs), solved
/// for its length T: the linear arc from y(0) = 0, y'(0) = v₀ up to the
/// separation t_s, then the free arc
///
///   y = −c + (y_s + c) cosh(p σ) + (v_s / p) sinh(p σ),  c = F/p², σ = τ − t_s,
///
/// up to y(T) = 0. For a given t_s the restraint's push vanishes there,
/// −κ y(t_s) − 2γ y'(t_s) = 0, which fixes v₀ in closed form,
///
///   v₀ = −F (κ ψ + 2γ φ₂) / (κ φ₂ + 2γ φ₂')  at t_s,
///
/// and the free piece's zero is closed form too (a quadratic in e^{pσ}), so the
/// arc's length is t_s + σ_end(t_s); t_s solves t_s + σ_end(t_s) = T
/// (bracketed secant, to 10⁻¹³ T).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InwardArc {
    lambda: f64,
    gamma: f64,
    f: f64,
    p: f64,
    t_len: f64,
    v0: f64,
    /// Separation (t_s, y_s, v_s); None: the linear arc (γ ≤ 0, or no
    /// separation fits in T).
    sep: Option<(f64, f64, f64)>,
}

/// One try of a separation time t_s.
enum Try {
    /// t_s comes before the apex: the arc it gives is too short.
    Short,
    /// No entry speed separates this late (past the t_s where an infinitely
    /// fast entry would), or the free piece never returns: too long.
    Long,
    /// (v₀, y_s, v_s, arc length).
    Arc(f64, f64, f64, f64),
}

/// The arc whose restraint lets go at t_s: v₀ from −κ y − 2γ y' = 0 at t_s,
/// then the free piece's zero.
fn try_separation(lambda: f64, gamma: f64, f: f64, p: f64, t_len: f64, ts: f64) -> Try {
    let kappa = lambda + p * p;
    let (psi, phi2, dphi2) = parts(lambda, gamma, t_len, ts);
    let den = kappa * phi2 + 2.0 * gamma * dphi2;
    if den <= 0.0 {
        return Try::Long;
    }
    let v0 = -f * (kappa * psi + 2.0 * gamma * phi2) / den;
    let (ys, vs) = (f * psi + v0 * phi2, f * phi2 + v0 * dphi2);
    if !(v0 < 0.0 && vs > 0.0 && ys < 0.0) {
        return Try::Short;
    }
    match free_zero(f, p, ys, vs) {
        Some(sigma) => Try::Arc(v0, ys, vs, ts + sigma),
        None => Try::Long,
    }
}

/// Time σ from (y_s < 0, v_s > 0) to y = 0 on the free arc y'' = F + p² y:
/// e^{pσ} = u solves (B + D) u² − 2c u + (B − D) = 0, B = y_s + c, D = v_s/p,
/// written without cancellation for small y_s. None if the wall falls inward
/// (|y_s| ≥ F/p²).
fn free_zero(f: f64, p: f64, ys: f64, vs: f64) -> Option<f64> {
    let c = f / (p * p);
    let (b, d) = (ys + c, vs / p);
    if b <= 0.0 {
        return None;
    }
    let q = -ys * (ys + 2.0 * c);
    let root = (q + d * d).sqrt();
    let u_minus_1 = (-ys + q / (root + d)) / (b + d);
    Some(u_minus_1.ln_1p() / p)
}

impl InwardArc {
    /// The linear arc (a restraint that may pull, γ ≤ 0 or no separation): the
    /// solution of y'' = F − λ y − 2γ y' with y(0) = y(T) = 0 on τ ∈ [0, T]
    /// (y = L θ, F = A p², λ = κ − p²; [`InwardArc::at`] gives y and y'):
    ///
    ///   y = F ψ(τ) + v₀ φ₂(τ),  v₀ = −F ψ(T) / φ₂(T),
    ///
    /// with φ₂ = e^{−γτ} S(τ) (φ₂(0) = 0, φ₂'(0) = 1), φ₁ = e^{−γτ} (C + γ S),
    /// ψ = (1 − φ₁)/λ the unit step response (ψ' = φ₂), C = cosh μτ and S = sinh(μτ)/μ
    /// for μ² = γ² − λ (cos and sin/ω when μ² < 0). Near λ = 0, ψ comes from its power
    /// series, (n+2)(n+1) a_{n+2} = [n = 0] − 2γ (n+1) a_{n+1} − λ a_n.
    pub fn linear(lambda: f64, gamma: f64, f: f64, p: f64, t_len: f64) -> InwardArc {
        let (psi_t, phi2_t, _) = parts(lambda, gamma, t_len, t_len);
        InwardArc {
            lambda,
            gamma,
            f,
            p,
            t_len,
            v0: -f * psi_t / phi2_t,
            sep: None,
        }
    }

    /// The arc of length `t_len` for λ, γ, F = A p² and p: [`InwardArc::linear`]
    /// up to the separation, if the restraint lets go before y = 0.
    pub fn solve(lambda: f64, gamma: f64, f: f64, p: f64, t_len: f64) -> InwardArc {
        let linear = Self::linear(lambda, gamma, f, p, t_len);
        if gamma <= 0.0 || f.is_nan() || f <= 0.0 {
            return linear;
        }
        match Self::separation(lambda, gamma, f, p, t_len) {
            Some((ts, v0, ys, vs)) => InwardArc {
                v0,
                sep: Some((ts, ys, vs)),
                ..linear
            },
            None => linear,
        }
    }

    /// t_s with t_s + σ_end(t_s) = T by the Illinois variant of regula falsi on
    /// [0, T], a [`Try::Short`] or [`Try::Long`] counting as −T or +T. None
    /// when no arc of length T separates (to 10⁻¹³ T in 200 steps).
    fn separation(lambda: f64, gamma: f64, f: f64, p: f64, t_len: f64) -> Option<(f64, f64, f64, f64)> {
        let g = |ts: f64| match try_separation(lambda, gamma, f, p, t_len, ts) {
            Try::Short => (-t_len, None),
            Try::Long => (t_len, None),
            Try::Arc(v0, ys, vs, len) => (len - t_len, Some((ts, v0, ys, vs))),
        };
        let gb = g(t_len).0;
        if gb < 0.0 {
            return None;
        }
        let mut br = Illinois::new((0.0, -t_len), (t_len, gb));
        for _ in 0..200 {
            let x = br.secant();
            let (gx, arc) = g(x);
            if gx.abs() <= 1e-13 * t_len {
                return arc;
            }
            br.narrow(x, gx);
        }
        None
    }

    /// y and y' at τ ∈ [0, T].
    pub fn at(&self, tau: f64) -> (f64, f64) {
        match self.sep {
            Some((ts, ys, vs)) if tau > ts => {
                let (c, s) = ((self.p * (tau - ts)).cosh(), (self.p * (tau - ts)).sinh());
                let b = ys + self.f / (self.p * self.p);
                (b * c + vs / self.p * s - self.f / (self.p * self.p), b * self.p * s + vs * c)
            }
            _ => {
                let (psi, phi2, dphi2) = parts(self.lambda, self.gamma, self.t_len, tau);
                (self.f * psi + self.v0 * phi2, self.f * phi2 + self.v0 * dphi2)
            }
        }
    }

    /// y'' at τ from y and y' there: the restraint's linear arc before the
    /// separation, free gravity after it.
    pub fn accel(&self, tau: f64, y: f64, v: f64) -> f64 {
        match self.sep {
            Some((ts, _, _)) if tau > ts => self.f + self.p * self.p * y,
            _ => self.f - self.lambda * y - 2.0 * self.gamma * v,
        }
    }

    /// The arc's depth max |y| (mm): the zero of y' between the entry (y' < 0)
    /// and the exit (y' > 0), by bisection to 2⁻⁴⁰ T. Near the apex y'' > 0
    /// (the restraint and gravity both push outward), so y' has one zero.
    pub fn depth(&self) -> f64 {
        let (mut a, mut b) = (0.0, self.t_len);
        if !(self.at(a).1 < 0.0 && self.at(b).1 > 0.0) {
            return (0..=64).map(|i| -self.at(self.t_len * i as f64 / 64.0).0).fold(0.0, f64::max);
        }
        for _ in 0..40 {
            let m = 0.5 * (a + b);
            if self.at(m).1 < 0.0 {
                a = m;
            } else {
                b = m;
            }
        }
        -self.at(0.5 * (a + b)).0
    }

    /// The separation time t_s from the start of the arc, if the wall separates.
    pub fn separation_time(&self) -> Option<f64> {
        self.sep.map(|s| s.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y and y' of the linear arc (p plays no part in it).
    fn damped_arc(lambda: f64, gamma: f64, f: f64, tau: f64, t_len: f64) -> (f64, f64) {
        InwardArc::linear(lambda, gamma, f, 2.2, t_len).at(tau)
    }

    /// The lossless inward arc (the estimator's before issue #9, the reference for
    /// γ = 0): the inward arc of one-sided rocking between two impacts, per unit A p²:
    /// g = (cos(√λ τ) − cos(√λ h)) / (λ cos(√λ h)) with h = T/2 (so L θ = −A p² g),
    /// and dg/dτ; cosh for λ < 0 (gravity stronger than the spring) and the series
    /// (h² − τ²)/2 + λ [(h² − τ²) h²/4 − (h⁴ − τ⁴)/24] near λ = 0, so the arc is smooth
    /// in λ across 0.
    fn spring_arc(l: f64, tau: f64, h: f64) -> (f64, f64) {
        if (l * h * h).abs() < 1e-4 {
            let (h2, t2) = (h * h, tau * tau);
            let g = 0.5 * (h2 - t2) + l * ((h2 - t2) * h2 / 4.0 - (h2 * h2 - t2 * t2) / 24.0);
            let dg = -tau + l * (-tau * h2 / 2.0 + tau * t2 / 6.0);
            (g, dg)
        } else if l > 0.0 {
            let w = l.sqrt();
            let den = (w * h).cos();
            (((w * tau).cos() - den) / (l * den), -(w * tau).sin() / (w * den))
        } else {
            let v = (-l).sqrt();
            let den = (v * h).cosh();
            (((v * tau).cosh() - den) / (l * den), -(v * tau).sinh() / (v * den))
        }
    }

    #[test]
    fn damped_arc_solves_its_equation() {
        for (l, g) in [(900.0, 0.0), (900.0, 6.0), (-3.0, 0.5), (1e-6, 2.0), (0.0, 0.0)] {
            let (f, t_len) = (1800.0, 0.08);
            let (y0, v0) = damped_arc(l, g, f, 0.0, t_len);
            let (y1, v1) = damped_arc(l, g, f, t_len, t_len);
            assert!(y0.abs() < 1e-9 && y1.abs() < 1e-9, "λ {l} γ {g}: {y0} {y1}");
            // Residual of y'' = F − λ y − 2γ y' by central differences.
            let h = 1e-5;
            for tau in [0.01, 0.04, 0.07] {
                let (ym, _) = damped_arc(l, g, f, tau - h, t_len);
                let (y, v) = damped_arc(l, g, f, tau, t_len);
                let (yp, _) = damped_arc(l, g, f, tau + h, t_len);
                let ypp = (yp - 2.0 * y + ym) / (h * h);
                let r = ypp - (f - l * y - 2.0 * g * v);
                assert!(r.abs() < 1e-3 * f, "λ {l} γ {g} τ {tau}: residual {r}");
            }
            if g == 0.0 && l > 1.0 {
                let (gg, dg) = spring_arc(l, 0.02 - 0.04, 0.04);
                let (y, v) = damped_arc(l, g, f, 0.02, t_len);
                assert!((y + f * gg).abs() < 1e-9 * f && (v + f * dg).abs() < 1e-7 * f);
            }
            if g > 0.0 {
                assert!(v1.abs() < v0.abs(), "λ {l} γ {g}: exit {v1} entry {v0}");
            }
        }
    }

    /// Reference: the compression-only restraint integrated by RK4 (step 2 µs)
    /// from y = 0, y' = v₀ until y returns to 0: (length, exit speed).
    fn integrate(lambda: f64, gamma: f64, f: f64, p: f64, v0: f64) -> (f64, f64) {
        let kappa = lambda + p * p;
        let acc = |y: f64, v: f64| f + p * p * y + (-kappa * y - 2.0 * gamma * v).max(0.0);
        let (mut y, mut v, mut t) = (0.0, v0, 0.0);
        let h = 2e-6;
        while t < 10.0 {
            let (k1y, k1v) = (v, acc(y, v));
            let (k2y, k2v) = (v + 0.5 * h * k1v, acc(y + 0.5 * h * k1y, v + 0.5 * h * k1v));
            let (k3y, k3v) = (v + 0.5 * h * k2v, acc(y + 0.5 * h * k2y, v + 0.5 * h * k2v));
            let (k4y, k4v) = (v + h * k3v, acc(y + h * k3y, v + h * k3v));
            let (yn, vn) = (
                y + h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y),
                v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v),
            );
            if t > 0.0 && yn >= 0.0 {
                // Linear interpolation to the zero.
                let frac = -y / (yn - y);
                return (t + frac * h, v + frac * (vn - v));
            }
            (y, v, t) = (yn, vn, t + h);
        }
        panic!("λ {lambda} γ {gamma} v₀ {v0}: the wall never returns");
    }

    /// The solved arc matches a direct integration of the compression-only
    /// restraint: same length for the same entry speed, same exit speed; it is
    /// continuous at the separation; and the exit is its fastest outward point.
    #[test]
    fn inward_arc_matches_the_integrated_restraint() {
        // Stiff and soft restraints, light and heavy damping (p ≈ 2.2 s⁻¹,
        // F = A p² of a 3 m wall with α = 0.13: 1 900 mm/s²).
        for (lambda, gamma, t_len) in [
            (2250.0, 8.0, 0.04),
            (900.0, 3.0, 0.07),
            (300.0, 20.0, 0.12),
            (2250.0, 0.5, 0.05),
            (-2.0, 4.0, 0.3),
        ] {
            let (f, p) = (1900.0, 2.2);
            let arc = InwardArc::solve(lambda, gamma, f, p, t_len);
            let ts = arc.separation_time().unwrap_or_else(|| panic!("λ {lambda} γ {gamma}: no separation"));
            assert!(ts > 0.3 * t_len && ts < t_len, "λ {lambda} γ {gamma}: t_s {ts}");
            let (y_end, v_end) = arc.at(t_len);
            assert!(y_end.abs() < 1e-9 * f * t_len * t_len, "λ {lambda} γ {gamma}: y(T) {y_end}");
            let (len, v_exit) = integrate(lambda, gamma, f, p, arc.at(0.0).1);
            assert!((len - t_len).abs() < 1e-5, "λ {lambda} γ {gamma}: length {len} vs {t_len}");
            assert!((v_exit / v_end - 1.0).abs() < 1e-4, "λ {lambda} γ {gamma}: exit {v_exit} vs {v_end}");
            let (a, b) = (arc.at(ts - 1e-9), arc.at(ts + 1e-9));
            assert!((a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-4, "λ {lambda} γ {gamma}: {a:?} {b:?}");
            let fastest = (0..=200).map(|i| arc.at(t_len * i as f64 / 200.0).1).fold(f64::MIN, f64::max);
            assert!(fastest <= v_end * (1.0 + 1e-12), "λ {lambda} γ {gamma}: {fastest} > exit {v_end}");
            // The linear arc of the same length brakes before its end.
            let lin = damped_arc(lambda, gamma, f, t_len, t_len).1;
            assert!(lin < v_end, "λ {lambda} γ {gamma}: linear exit {lin} vs {v_end}");
        }
    }

    /// Without damping the restraint never lets go: the linear arc.
    #[test]
    fn lossless_restraint_is_the_linear_arc() {
        let arc = InwardArc::solve(2250.0, 0.0, 1900.0, 2.2, 0.065);
        assert!(arc.separation_time().is_none());
        for tau in [0.0, 0.02, 0.05, 0.065] {
            assert_eq!(arc.at(tau), damped_arc(2250.0, 0.0, 1900.0, tau, 0.065));
        }
    }
}

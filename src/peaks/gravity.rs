//! The exact free arc of paper Eq. 1 on a gravity side (no ground motion).
//!
//! On the outward side Eq. 1 reads θ'' = −p² sin(α − θ). With φ = α − θ it is
//! φ'' = p² sin φ, and ψ = π − φ swings as a pendulum, ψ'' = −p² sin ψ, whose
//! turning point ψ_m = π − φ_m is the arc's apex θ_m = α − φ_m. The pendulum's
//! closed form (DLMF 22.19.2), with τ the time from the apex, gives
//!
//!   sin(φ/2) = k′ / dn(p τ, k),  k′ = sin(φ_m / 2),  k² = 1 − k′²,
//!
//!   θ = α − 2 asin(k′ / dn(p τ, k)),  θ′ = −2 p k k′ sn(p τ, k) / dn(p τ, k),
//!
//! (1 − k² cd² = k′²/dn² turns the pendulum's sin(ψ/2) = k cd(p τ) into the
//! first line). An arc of length T between two zeros has the apex θ_m that
//! puts θ(T/2) = 0; θ(T/2) grows with θ_m, so it is a one-dimensional root.
//!
//! Why written here: the estimator's linearised arcs (`model.rs`,
//! `gravity_arc_params`) miss a 0.5 α arc of a squat wall by 10⁻⁴ of its
//! height, 0.01–0.06 mm on a 3 m wall: above the noise of a good sensor, so
//! that contact phases were chosen to absorb it (random draws 1166, 101045).
//! The elliptic functions are needed at k′ = 0.02–0.15, where forms in the
//! parameter m = k² lose the digits that matter; the arithmetic–geometric
//! mean started from k′ (the descending Landen transformation, DLMF 22.20)
//! keeps them and converges in 6–7 steps. That is 20 lines, not a crate.

/// sn, cn and dn of (u, k) from the complementary modulus k′ = √(1 − k²),
/// by the arithmetic–geometric mean (DLMF 22.20.1–22.20.2): a₀ = 1, b₀ = k′,
/// c₀ = k, a_{n+1} = (a_n + b_n)/2, b_{n+1} = √(a_n b_n), c_{n+1} = (a_n − b_n)/2
/// until c_N is below the rounding; φ_N = 2^N a_N u, φ_{n−1} = (φ_n +
/// asin(c_n sin φ_n / a_n))/2; sn = sin φ₀, cn = cos φ₀, dn² = k′² + k² cn².
pub fn jacobi(u: f64, kc: f64) -> (f64, f64, f64) {
    let k2 = (1.0 - kc) * (1.0 + kc);
    let (mut a, mut c) = ([0.0f64; 16], [0.0f64; 16]);
    a[0] = 1.0;
    c[0] = k2.sqrt();
    let mut b = kc;
    let mut n = 0;
    while n < 15 && c[n].abs() > 1e-16 * a[n] {
        let an = a[n];
        a[n + 1] = 0.5 * (an + b);
        c[n + 1] = 0.5 * (an - b);
        b = (an * b).sqrt();
        n += 1;
    }
    let mut phi = (1u64 << n) as f64 * a[n] * u;
    for j in (1..=n).rev() {
        phi = 0.5 * (phi + (c[j] / a[j] * phi.sin()).asin());
    }
    let (sn, cn) = phi.sin_cos();
    (sn, cn, (kc * kc + k2 * cn * cn).sqrt())
}

/// A bracket [a, b] of the root of an increasing function, f(a) ≤ 0 ≤ f(b),
/// narrowed by the Illinois variant of regula falsi: the end a new point
/// replaces moves, and where the same end moves twice in a row the other
/// end's value is halved, so that the secant does not stall on one side.
pub(crate) struct Illinois {
    pub a: f64,
    pub fa: f64,
    pub b: f64,
    pub fb: f64,
    side: i8,
}

impl Illinois {
    pub fn new((a, fa): (f64, f64), (b, fb): (f64, f64)) -> Illinois {
        Illinois { a, fa, b, fb, side: 0 }
    }

    /// The zero of the secant through both ends.
    pub fn secant(&self) -> f64 {
        (self.a * self.fb - self.b * self.fa) / (self.fb - self.fa)
    }

    /// Replace the end on the side of f(x) by (x, f(x)).
    pub fn narrow(&mut self, x: f64, fx: f64) {
        if fx > 0.0 {
            (self.b, self.fb) = (x, fx);
            if self.side == 1 {
                self.fa *= 0.5;
            }
            self.side = 1;
        } else {
            (self.a, self.fa) = (x, fx);
            if self.side == -1 {
                self.fb *= 0.5;
            }
            self.side = -1;
        }
    }
}

/// Chebyshev nodes of the correction ([`GravityArc`]).
const NODES: usize = 8;

/// Arcs solved last on this thread ([`GravityArc::solve`]): enough for the
/// arcs of a few model evaluations.
const CACHE_SIZE: usize = 48;

type Key = [u64; 5];

thread_local! {
    static CACHE: std::cell::RefCell<std::collections::VecDeque<(Key, Option<GravityArc>)>> =
        std::cell::RefCell::new(std::collections::VecDeque::with_capacity(CACHE_SIZE));
}

/// The exact arc of Eq. 1 between two zeros on a gravity side (module docs),
/// in θ (rad) about its apex: α, p (p² = 3g/4R, the rate of Eq. 1, not the
/// small-angle p √cos α), its apex θ_m and half-length.
///
/// Evaluating sn and dn at every sample of every model evaluation doubled
/// the time of a 2,000,000-row reduction (400 → 904 ms, `ingest_peaks`). The
/// arc is therefore the linearised closed form the caller gives (θ_l, in
/// `model.rs`: A_k (1 − cosh(p_k τ)/cosh(p_k T/2)) / L) plus the smooth
/// difference δ = θ − θ_l, even in τ and zero at both ends, interpolated in
/// z = (τ/half)² on [`NODES`] Chebyshev nodes: the exact arc is evaluated at
/// those only. Against the exact arc (α 0.08–0.25, apex 0.2–0.98 α, a
/// Python check) δ is 3·10⁻⁵–4·10⁻⁴ θ_m and its interpolant is within
/// 10⁻¹⁵–10⁻⁷ θ_m (the worst at 0.98 α); the test below holds it to 10⁻¹⁰ rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GravityArc {
    alpha: f64,
    p: f64,
    /// k′ = sin((α − θ_m)/2) and k.
    kc: f64,
    k: f64,
    pub apex: f64,
    pub half: f64,
    /// The linearised arc: its height A_k / L (rad) and rate p_k (s⁻¹).
    base: (f64, f64),
    /// Chebyshev coefficients of δ in w = 2 z − 1.
    corr: [f64; NODES],
}

impl GravityArc {
    fn with_apex(alpha: f64, p: f64, apex: f64, half: f64, base: (f64, f64)) -> GravityArc {
        let kc = (0.5 * (alpha - apex)).sin();
        GravityArc {
            alpha,
            p,
            kc,
            k: ((1.0 - kc) * (1.0 + kc)).sqrt(),
            apex,
            half,
            base,
            corr: [0.0; NODES],
        }
    }

    /// The arc of half-length `half` (s) whose linearised arc has height
    /// `base.0` (rad) and rate `base.1`: its apex solves θ(half) = 0, by the
    /// Illinois variant of regula falsi on (0, α) started about the
    /// linearised arc's apex, to 10⁻¹⁴ α; then the correction δ. None where
    /// α, p or the length are not positive and finite, or no apex is found.
    ///
    /// Memoised per thread ([`CACHE`]): a fit's Jacobian moves one parameter
    /// at a time, and an impact time changes two arcs, so most arcs of a
    /// model evaluation were solved for the one before it.
    pub fn solve(alpha: f64, p: f64, half: f64, base: (f64, f64)) -> Option<GravityArc> {
        let key = [alpha, p, half, base.0, base.1].map(f64::to_bits);
        if let Some(hit) = CACHE.with(|c| c.borrow().iter().find(|e| e.0 == key).map(|e| e.1)) {
            return hit;
        }
        let arc = Self::solve_uncached(alpha, p, half, base);
        CACHE.with(|c| {
            let mut c = c.borrow_mut();
            if c.len() == CACHE_SIZE {
                c.pop_front();
            }
            c.push_back((key, arc));
        });
        arc
    }

    fn solve_uncached(alpha: f64, p: f64, half: f64, base: (f64, f64)) -> Option<GravityArc> {
        let finite = [alpha, p, half, base.0, base.1].iter().all(|v| v.is_finite());
        if !(finite && alpha > 0.0 && p > 0.0 && half > 0.0) {
            return None;
        }
        let guess = base.0 * (1.0 - 1.0 / (base.1 * half).cosh());
        let apex = Self::apex_of(alpha, p, half, guess)?;
        let mut arc = GravityArc::with_apex(alpha, p, apex, half, base);
        arc.corr = arc.correction();
        Some(arc)
    }

    /// The apex whose exact arc reaches θ = 0 at `half` (module docs).
    fn apex_of(alpha: f64, p: f64, half: f64, guess: f64) -> Option<f64> {
        let end = |apex: f64| GravityArc::with_apex(alpha, p, apex, half, (0.0, 1.0)).exact(half).0;
        let top = alpha * (1.0 - 1e-12);
        let g = if guess > 0.0 && guess < alpha { guess } else { 0.5 * alpha };
        let (mut a, mut b) = (g * (1.0 - 1e-3), (g * (1.0 + 1e-3)).min(top));
        let (mut fa, mut fb) = (end(a), end(b));
        // Widen the bracket until it holds the root (θ(half) grows with the apex).
        for _ in 0..60 {
            if fa <= 0.0 {
                break;
            }
            (b, fb, a) = (a, fa, 0.5 * a);
            fa = end(a);
        }
        for _ in 0..60 {
            if fb >= 0.0 {
                break;
            }
            (a, fa, b) = (b, fb, b + 0.5 * (top - b));
            fb = end(b);
        }
        if !(fa <= 0.0 && fb >= 0.0) {
            return None;
        }
        let mut br = Illinois::new((a, fa), (b, fb));
        for _ in 0..100 {
            if br.b - br.a < 1e-14 * alpha {
                break;
            }
            let x = if br.fb > br.fa { br.secant() } else { 0.5 * (br.a + br.b) };
            let fx = end(x);
            if fx == 0.0 {
                return Some(x);
            }
            br.narrow(x, fx);
        }
        Some(0.5 * (br.a + br.b))
    }

    /// The linearised arc θ_l and θ_l′ at τ.
    fn linearised(&self, tau: f64) -> (f64, f64) {
        let (h, q) = self.base;
        let den = (q * self.half).cosh();
        (h * (1.0 - (q * tau).cosh() / den), -h * q * (q * tau).sinh() / den)
    }

    /// Chebyshev coefficients of δ = θ − θ_l on the nodes w_j = cos(π (j + ½)/N):
    /// c_m = (2 − [m = 0])/N Σ_j δ(w_j) T_m(w_j), with T_m(w_j) by the
    /// recurrence T_{m+1} = 2 w T_m − T_{m−1}.
    fn correction(&self) -> [f64; NODES] {
        let n = NODES as f64;
        let mut c = [0.0; NODES];
        for j in 0..NODES {
            let w = (std::f64::consts::PI * (j as f64 + 0.5) / n).cos();
            let tau = self.half * (0.5 * (1.0 + w)).sqrt();
            let delta = self.exact(tau).0 - self.linearised(tau).0;
            let (mut t0, mut t1) = (1.0, w);
            for (m, cm) in c.iter_mut().enumerate() {
                *cm += delta * if m == 0 { 1.0 / n } else { 2.0 / n } * t0;
                (t0, t1) = (t1, 2.0 * w * t1 - t0);
            }
        }
        c
    }

    /// θ and θ′ at τ from the apex (τ > 0 after it: θ′ < 0): the linearised
    /// arc and the interpolated correction.
    pub fn at(&self, tau: f64) -> (f64, f64) {
        let (th, w) = self.linearised(tau);
        let x = tau / self.half;
        let z = 2.0 * x * x - 1.0;
        // T_m(z) and T_m′(z) by their recurrences.
        let (mut t0, mut t1, mut d0, mut d1) = (1.0, z, 0.0, 1.0);
        let (mut v, mut dv) = (self.corr[0] + self.corr[1] * z, self.corr[1]);
        for &c in &self.corr[2..] {
            let (t2, d2) = (2.0 * z * t1 - t0, 2.0 * t1 + 2.0 * z * d1 - d0);
            v += c * t2;
            dv += c * d2;
            (t0, t1, d0, d1) = (t1, t2, d1, d2);
        }
        // dz/dτ = 4 τ / half².
        (th + v, w + dv * 4.0 * tau / (self.half * self.half))
    }

    /// θ and θ′ at τ by the elliptic functions (module docs).
    pub fn exact(&self, tau: f64) -> (f64, f64) {
        let (sn, _, dn) = jacobi(self.p * tau, self.kc);
        (self.alpha - 2.0 * (self.kc / dn).asin(), -2.0 * self.p * self.k * self.kc * sn / dn)
    }

    /// θ″ at θ: Eq. 1, −p² sin(α − θ).
    pub fn accel(&self, theta: f64) -> f64 {
        -self.p * self.p * (self.alpha - theta).sin()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Known values: dn(u, k → 1) = sech u, sn = tanh u; and k = 1/√2, u = K
    /// (K(1/√2) = 1.854074677301372): sn = 1, cn = 0, dn = k′ (DLMF 22.5.1).
    #[test]
    fn jacobi_functions_at_known_points() {
        let (sn, cn, dn) = jacobi(0.7, 1e-9);
        assert!((sn - 0.7f64.tanh()).abs() < 1e-12 && (dn - 1.0 / 0.7f64.cosh()).abs() < 1e-12);
        assert!((cn - 1.0 / 0.7f64.cosh()).abs() < 1e-12);
        let kc = 0.5f64.sqrt();
        let (sn, cn, dn) = jacobi(1.854_074_677_301_372, kc);
        assert!((sn - 1.0).abs() < 1e-14 && cn.abs() < 1e-7 && (dn - kc).abs() < 1e-12, "{sn} {cn} {dn}");
        // sn² + cn² = 1 and dn² + k² sn² = 1 at a k′ of a squat wall's arc.
        let kc = 0.03;
        for u in [0.1, 1.0, 2.5, 4.0] {
            let (sn, cn, dn) = jacobi(u, kc);
            assert!((sn * sn + cn * cn - 1.0).abs() < 1e-14);
            assert!((dn * dn + (1.0 - kc * kc) * sn * sn - 1.0).abs() < 1e-14);
        }
    }

    /// The exact arc against Runge–Kutta integration of θ'' = −p² sin(α − θ)
    /// from its apex (step 10 µs): θ and θ′ to 10⁻¹¹ rad along a 0.6 α arc of
    /// a squat wall, and the solved arc ends at θ = 0.
    #[test]
    fn exact_arc_follows_the_integrated_equation() {
        let (alpha, p, apex) = (0.25f64, 2.4f64, 0.15f64);
        let arc = GravityArc::with_apex(alpha, p, apex, 1.0, (0.0, 1.0));
        let f = |th: f64| -p * p * (alpha - th).sin();
        let (mut th, mut w, h) = (apex, 0.0f64, 1e-5);
        for step in 1..=50_000 {
            let (k1, l1) = (w, f(th));
            let (k2, l2) = (w + 0.5 * h * l1, f(th + 0.5 * h * k1));
            let (k3, l3) = (w + 0.5 * h * l2, f(th + 0.5 * h * k2));
            let (k4, l4) = (w + h * l3, f(th + h * k3));
            th += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            w += h / 6.0 * (l1 + 2.0 * l2 + 2.0 * l3 + l4);
            if th < 0.0 {
                break;
            }
            if step % 5_000 == 0 {
                let (e, ew) = arc.exact(step as f64 * h);
                assert!(
                    (e - th).abs() < 1e-11 && (ew - w).abs() < 1e-10,
                    "τ {}: {e} {th}, {ew} {w}",
                    step as f64 * h
                );
            }
        }
        // The arc of the half-length this apex gives: solved back.
        let half = {
            let (mut a, mut b) = (0.0, 5.0);
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if arc.exact(m).0 > 0.0 {
                    a = m;
                } else {
                    b = m;
                }
            }
            0.5 * (a + b)
        };
        // Solved back from linearised arcs whose apexes are off by −93 … +60 %,
        // and the interpolated correction against the elliptic functions.
        for (h, q) in [(0.2, 3.0), (0.26, 2.3), (1.0, 2.0)] {
            let solved = GravityArc::solve(alpha, p, half, (h, q)).expect("an arc");
            assert!((solved.apex - apex).abs() < 1e-12, "base {h} {q}: apex {}", solved.apex);
            assert!(solved.at(half).0.abs() < 1e-10 && solved.exact(half).0.abs() < 1e-13);
            for i in 0..=40 {
                let tau = half * (i as f64 / 20.0 - 1.0);
                let ((a, av), (e, ev)) = (solved.at(tau), solved.exact(tau));
                assert!(
                    (a - e).abs() < 1e-10 && (av - ev).abs() < 1e-8,
                    "base {h} {q}, τ {tau}: {a} {e}, {av} {ev}"
                );
            }
        }
    }
}

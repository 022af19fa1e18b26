//! Synthetic free-rocking tests with known truth: the seeded generator the
//! estimator is tested against (issue #9), and the compliant-contact model that
//! makes logs unlike the estimator's own idealisation.
//!
//! # Two contact models
//! Both integrate paper Eq. 1 without ground motion, per unit I_0, with s = sign θ:
//!
//!   θ'' = −p² s sin(α − sθ) − \[θ < 0\] κ θ                                    (Eq. 1)
//!
//! - [`Contact::Rigid`]: the paper's idealisation. Impacts are instantaneous,
//!   θ' ← e_k θ' at every crossing of θ = 0, and e_k may change impact by impact.
//!   The truth v_k is L θ' just before impact k (SPEC).
//! - [`Contact::Compliant`]: a bedding of finite stiffness and a lossy restraint.
//!   The pivot moves from one edge to the other while both edges bear, over
//!   |θ| < θ_c (a Winkler bed: the gravity moment is linear in θ there), a dashpot
//!   c_f acts while both edges bear, and the transverse walls are a
//!   compression-only spring–dashpot:
//!
//!   θ'' = −p² (sin α cos θ · sat(θ/θ_c) − sin θ) − c_f θ' \[|θ| < θ_c\]
//!   + max(0, −κ θ − c_w θ') \[θ < 0\]
//!
//!   with sat(u) = clamp(u, −1, 1) (the rigid model's s sin(α − sθ) for |θ| ≥ θ_c).
//!   An impact then lasts 2θ_c/|θ'|, loses about 1 − √(1 − 4 c_f θ_c / |θ'|) of the
//!   speed (more at low speed, as measured on walls), and the velocity peaks before
//!   θ = 0, where p² sin α θ/θ_c = c_f |θ'|; the inward half-cycle of one-sided
//!   rocking loses energy in the walls' dashpot, so the wall leaves it slower than
//!   it entered. The truth v_k is then the extreme of the sensor velocity
//!   L cos θ θ' within half-cycle k (between zero crossings k−1 and k), which is
//!   what the SPEC defines and what the MuJoCo campaigns measure.
//!
//! Both are integrated by the project's Dormand–Prince stepper: the rigid model
//! with adaptive steps and impacts located on the dense output (to 1e-13 s), the
//! compliant one with fixed 20 µs steps (its right-hand side has kinks at ±θ_c).
//!
//! # The sensor
//! x = L sin θ + drift·t/T + N(0, σ²), quantised to 0.01 mm, optional isolated
//! spikes; the logger's samples are not aligned with the release.

use crate::solver::integrator::{find_root, next_h, step, State, Tolerances};
use crate::wall::{housner_e, p_squared_rectangular, slenderness};

/// Deterministic random numbers (xorshift64* and Box–Muller): seeded draws are
/// reproducible on every machine without an extra crate.
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        // SplitMix64 of the seed, so that nearby seeds give unrelated streams.
        let mut z = seed.wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        Rng((z ^ (z >> 31)) | 1)
    }
    /// Uniform in (0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let v = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
        ((v >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.uniform()
    }
    /// Log-uniform in [a, b].
    pub fn log_range(&mut self, a: f64, b: f64) -> f64 {
        (a.ln() + (b.ln() - a.ln()) * self.uniform()).exp()
    }
    pub fn normal(&mut self) -> f64 {
        (-2.0 * self.uniform().ln()).sqrt() * (2.0 * std::f64::consts::PI * self.uniform()).cos()
    }
    pub fn pick<T: Copy>(&mut self, v: &[T]) -> T {
        v[((self.uniform() * v.len() as f64) as usize).min(v.len() - 1)]
    }
}

/// How impacts happen.
#[derive(Debug, Clone, PartialEq)]
pub enum Contact {
    /// Instantaneous impacts; `e[k]` is the coefficient of impact k (the last value
    /// repeats).
    Rigid { e: Vec<f64> },
    /// Finite-duration lossy contacts (module docs): θ_c (rad), c_f and c_w (s⁻¹).
    Compliant { theta_c: f64, c_floor: f64, c_wall: f64 },
}

/// One synthetic test.
#[derive(Debug, Clone, PartialEq)]
pub struct TestSpec {
    pub height_m: f64,
    pub thickness_m: f64,
    /// Sensor lever arm about the hinge, mm.
    pub lever_mm: f64,
    /// Inward restraint κ = k/I_0 (s⁻²); 0 for two-sided rocking.
    pub kappa: f64,
    /// Release rotation θ_0 (rad, outward).
    pub theta0: f64,
    pub contact: Contact,
    pub fs_hz: f64,
    pub sigma_mm: f64,
    pub drift_mm: f64,
    /// Number of isolated one-sample spikes.
    pub spikes: usize,
    pub seed: u64,
}

/// A generated log and its truth.
#[derive(Debug, Clone)]
pub struct Synthetic {
    pub spec: TestSpec,
    pub t: Vec<f64>,
    /// Sensor reading, mm, outward positive.
    pub x_mm: Vec<f64>,
    /// True velocity peaks v_k (mm/s, outward positive) and their times.
    pub peaks: Vec<(f64, f64)>,
    /// Zero crossings of θ after the release (s).
    pub crossings: Vec<f64>,
    /// Largest |x| (mm) of each half-cycle after the release.
    pub half_cycle_heights_mm: Vec<f64>,
}

impl TestSpec {
    pub fn alpha(&self) -> f64 {
        slenderness(self.thickness_m, self.height_m)
    }
    pub fn p2(&self) -> f64 {
        p_squared_rectangular(self.height_m, self.thickness_m)
    }
    pub fn e_housner(&self) -> f64 {
        housner_e(self.alpha())
    }
    pub fn one_sided(&self) -> bool {
        self.kappa > 0.0
    }
}

/// Hold before the release (s) and record length after it.
const HOLD_S: f64 = 1.0;

/// Generate the log of a test.
pub fn generate(spec: &TestSpec) -> Synthetic {
    let mut rng = Rng::new(spec.seed ^ 0x5EED);
    // Release at a time not aligned with the samples.
    let t_r = HOLD_S + rng.uniform() / spec.fs_hz;
    let motion = match &spec.contact {
        Contact::Rigid { e } => rigid_motion(spec, e),
        Contact::Compliant { theta_c, c_floor, c_wall } => compliant_motion(spec, *theta_c, *c_floor, *c_wall),
    };
    let duration = t_r + motion.t_end + 1.5;
    let n = (duration * spec.fs_hz) as usize;
    let t: Vec<f64> = (0..n).map(|i| i as f64 / spec.fs_hz).collect();
    let l = spec.lever_mm;
    let mut x: Vec<f64> = t
        .iter()
        .map(|&ti| {
            let th = motion.theta_at(ti - t_r, spec.theta0);
            l * th.sin() + spec.drift_mm * ti / duration + spec.sigma_mm * rng.normal()
        })
        .collect();
    for _ in 0..spec.spikes {
        let i = (rng.uniform() * n as f64) as usize % n;
        x[i] += rng.pick(&[-1.0, 1.0]) * rng.range(20.0, 80.0) * spec.sigma_mm.max(0.01);
    }
    for v in x.iter_mut() {
        *v = (*v * 100.0).round() / 100.0;
    }
    let shift = |v: &[(f64, f64)]| v.iter().map(|&(a, b)| (a + t_r, b)).collect::<Vec<_>>();
    Synthetic {
        spec: spec.clone(),
        t,
        x_mm: x,
        peaks: shift(&motion.peaks),
        crossings: motion.crossings.iter().map(|c| c + t_r).collect(),
        half_cycle_heights_mm: motion.heights.iter().map(|h| h * l).collect(),
    }
}

/// The motion after the release (time from the release), sampled finely.
struct Motion {
    /// (τ, θ) at steps small enough for linear interpolation to be exact to
    /// well below the noise (≤ 50 µs).
    path: Vec<(f64, f64)>,
    t_end: f64,
    peaks: Vec<(f64, f64)>,
    crossings: Vec<f64>,
    heights: Vec<f64>,
}

impl Motion {
    fn theta_at(&self, tau: f64, theta0: f64) -> f64 {
        if tau <= 0.0 {
            return theta0;
        }
        let i = self.path.partition_point(|p| p.0 <= tau);
        if i >= self.path.len() {
            return self.path.last().map_or(0.0, |p| p.1);
        }
        let (a, b) = (self.path[i - 1], self.path[i]);
        a.1 + (b.1 - a.1) * (tau - a.0) / (b.0 - a.0)
    }
}

/// The half-cycles of a motion as it is integrated: each ends at a crossing of
/// θ = 0 with its peak (time, sensor velocity mm/s) and its height |θ|max.
struct HalfCycles {
    peaks: Vec<(f64, f64)>,
    crossings: Vec<f64>,
    heights: Vec<f64>,
    /// |θ|max of the half-cycle under way.
    height: f64,
}

impl HalfCycles {
    fn new(theta0: f64) -> HalfCycles {
        HalfCycles {
            peaks: Vec::new(),
            crossings: Vec::new(),
            heights: Vec::new(),
            height: theta0.abs(),
        }
    }
    fn grow(&mut self, theta: f64) {
        self.height = self.height.max(theta.abs());
    }
    /// The half-cycle under way ends at `tc` with its `peak`.
    fn cross(&mut self, tc: f64, peak: (f64, f64)) {
        self.crossings.push(tc);
        self.peaks.push(peak);
        self.heights.push(self.height);
        self.height = 0.0;
    }
    fn into_motion(self, path: Vec<(f64, f64)>, t_end: f64) -> Motion {
        Motion {
            path,
            t_end,
            peaks: self.peaks,
            crossings: self.crossings,
            heights: self.heights,
        }
    }
}

/// Eq. 1 for the rigid model on side s (the sign of θ, or of the side entered).
fn rigid_accel(spec: &TestSpec, s: f64, th: f64) -> f64 {
    let (alpha, p2) = (spec.alpha(), spec.p2());
    let mut a = -p2 * s * (alpha - s * th).sin();
    if th < 0.0 && spec.kappa > 0.0 {
        a -= spec.kappa * th;
    }
    a
}

const MAX_IMPACTS: usize = 12;

/// Rigid rocking with per-impact coefficients (event-located impacts).
fn rigid_motion(spec: &TestSpec, e: &[f64]) -> Motion {
    let l = spec.lever_mm;
    let tol = Tolerances { rtol: 1e-11, atol: 1e-14 };
    let (mut t, mut y): (f64, State) = (0.0, [spec.theta0, 0.0]);
    let mut side = 1.0;
    let mut path = vec![(0.0, spec.theta0)];
    let mut cycles = HalfCycles::new(spec.theta0);
    let mut h: f64 = 1e-4;
    let max_h = 5e-5;
    loop {
        let mut f = |_t: f64, y: &State| [y[1], rigid_accel(spec, side, y[0])];
        let k1 = f(t, &y);
        let hh = h.min(max_h);
        let st = step(&mut f, t, &y, &k1, hh, tol);
        if st.err > 1.0 {
            h = next_h(hh, st.err);
            continue;
        }
        if side * st.y1[0] < 0.0 {
            // Impact: locate θ = 0 on the dense output.
            let tc = find_root(|s| st.dense.at(s)[0], t, t + hh, 1e-13);
            let yc = st.dense.at(tc);
            path.push((tc, 0.0));
            cycles.cross(tc, (tc, l * yc[1]));
            let k = cycles.crossings.len() - 1;
            let ek = e.get(k).or(e.last()).copied().unwrap_or(1.0);
            side = -side;
            t = tc;
            y = [0.0, ek * yc[1]];
            if cycles.crossings.len() >= MAX_IMPACTS || (ek * yc[1]).abs() < 1e-5 {
                break;
            }
        } else {
            t += hh;
            y = st.y1;
            cycles.grow(y[0]);
            path.push((t, y[0]));
        }
        h = next_h(hh, st.err);
        if t > 30.0 {
            break;
        }
    }
    path.push((t + 1e-9, 0.0));
    cycles.into_motion(path, t)
}

/// Compliant contacts (module docs), fixed 20 µs steps.
fn compliant_motion(spec: &TestSpec, theta_c: f64, c_floor: f64, c_wall: f64) -> Motion {
    let (alpha, p2, kappa) = (spec.alpha(), spec.p2(), spec.kappa);
    let (sa, l) = (alpha.sin(), spec.lever_mm);
    let mut f = |_t: f64, y: &State| {
        let th = y[0];
        let sat = (th / theta_c).clamp(-1.0, 1.0);
        let mut a = -p2 * (sa * th.cos() * sat - th.sin());
        if th.abs() < theta_c {
            a -= c_floor * y[1];
        }
        if th < 0.0 && kappa > 0.0 {
            a += (-kappa * th - c_wall * y[1]).max(0.0);
        }
        [y[1], a]
    };
    let tol = Tolerances { rtol: 1.0, atol: 1.0 };
    let hh = 2e-5;
    let (mut t, mut y): (f64, State) = (0.0, [spec.theta0, 0.0]);
    let mut path = vec![(0.0, spec.theta0)];
    let mut cycles = HalfCycles::new(spec.theta0);
    // Half-cycle k: expected sign of its peak (k even: inward, negative).
    let mut best: (f64, f64) = (0.0, 0.0);
    let mut quiet = 0.0;
    while t < 30.0 {
        let k1 = f(t, &y);
        let st = step(&mut f, t, &y, &k1, hh, tol);
        let sign = if cycles.crossings.len().is_multiple_of(2) { -1.0 } else { 1.0 };
        let v = l * st.y1[0].cos() * st.y1[1];
        if sign * v > sign * best.1 {
            best = (t + hh, v);
        }
        if y[0] != 0.0 && y[0].signum() != st.y1[0].signum() && st.y1[0] != 0.0 {
            let tc = find_root(|s| st.dense.at(s)[0], t, t + hh, 1e-12);
            cycles.cross(tc, best);
            best = (tc, 0.0);
        }
        t += hh;
        y = st.y1;
        cycles.grow(y[0]);
        if path.last().is_some_and(|p| t - p.0 >= 5e-5 - 1e-12) {
            path.push((t, y[0]));
        }
        // Stop once the motion stays below 1 µrad for 0.5 s.
        quiet = if y[0].abs() < 1e-6 && y[1].abs() < 1e-4 { quiet + hh } else { 0.0 };
        if quiet > 0.5 || cycles.crossings.len() > 40 {
            break;
        }
    }
    cycles.into_motion(path, t)
}

/// Which family a random draw comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Family {
    /// The paper's idealised model, per-impact coefficients varying.
    Rigid,
    /// Finite-duration lossy contacts.
    Compliant,
}

/// Why a draw was rejected: it is not resolvable (issue #9's definition).
fn resolvable(s: &Synthetic) -> bool {
    if s.peaks.len() < 7 || s.crossings.len() < 6 {
        return false;
    }
    let gap_ok = s.crossings[..6].windows(2).all(|w| w[1] - w[0] >= 6.0 / s.spec.fs_hz);
    // Half-cycles 0..=6: the last one used (peak 5 ends half-cycle 5) stands ≥ 20 σ.
    let tall = s.half_cycle_heights_mm.get(5).is_some_and(|&h| h >= 20.0 * s.spec.sigma_mm.max(0.005));
    gap_ok && tall
}

/// A random resolvable test, seeded: α 0.08–0.25, wall height 1.5–4 m, 100, 200,
/// 500 or 1000 Hz, release at 0.15–0.7 α, one-sided (κ log-uniform from 0.3 p² to
/// 60 p²) or two-sided, noise σ 0.005–0.08 mm, drift up to ±1 mm, isolated spikes
/// in a third of the tests. Rigid: per-impact coefficients drawn around a
/// per-test inward/outward pair (0.35–0.95) with ±0.05 impact to impact.
/// Compliant: θ_c such that the contact zone is 0.5–5 mm at the sensor, c_f from
/// a speed loss of 2–12 % per impact at the first impact's speed, and c_w a
/// damping ratio of 0.05–0.25 of the walls' spring. Draws that are not resolvable
/// (six impacts at least 6 samples apart, the last half-cycle at least 20 σ tall)
/// are replaced by the next seed; returns the seed used.
pub fn draw(seed: u64, family: Family) -> Synthetic {
    let mut s = seed.wrapping_mul(1_000_003);
    loop {
        let spec = draw_spec(s, family);
        let syn = generate(&spec);
        if resolvable(&syn) {
            return syn;
        }
        s = s.wrapping_add(1);
    }
}

/// The test a seed gives before the resolvability check (the `seed` a [`Scored`]
/// reports), to replay one test of a draw.
pub fn spec_for_seed(seed: u64, family: Family) -> TestSpec {
    draw_spec(seed, family)
}

fn draw_spec(seed: u64, family: Family) -> TestSpec {
    let mut r = Rng::new(seed);
    let alpha: f64 = r.range(0.08, 0.25);
    let height_m = r.range(1.5, 4.0);
    let thickness_m = height_m * alpha.tan();
    let lever_mm = 1000.0 * height_m * r.range(0.85, 0.98);
    let p2 = p_squared_rectangular(height_m, thickness_m);
    let one_sided = r.uniform() < 0.5;
    let kappa = if one_sided { p2 * r.log_range(0.3, 60.0) } else { 0.0 };
    let theta0 = alpha * r.range(0.15, 0.7);
    let fs_hz = r.pick(&[100.0, 200.0, 500.0, 1000.0]);
    let sigma_mm = r.log_range(0.005, 0.08);
    let drift_mm = r.range(-1.0, 1.0);
    let spikes = if r.uniform() < 1.0 / 3.0 { 1 + (r.uniform() * 6.0) as usize } else { 0 };
    let contact = match family {
        Family::Rigid => {
            let (e_in, e_out) = if one_sided {
                (r.range(0.35, 0.9), r.range(0.5, 0.95))
            } else {
                let e = r.range(0.6, 0.95);
                (e, e)
            };
            let e = (0..MAX_IMPACTS)
                .map(|k| {
                    let base = if k % 2 == 0 { e_in } else { e_out };
                    (base + r.range(-0.05, 0.05)).clamp(0.2, 0.99)
                })
                .collect();
            Contact::Rigid { e }
        }
        Family::Compliant => {
            let theta_c = r.range(0.5, 5.0) / lever_mm;
            // Speed at the first impact (energy, small angles): ω² ≈ p² θ0 (2α − θ0).
            let w0 = (p2 * theta0 * (2.0 * alpha - theta0)).sqrt();
            let loss: f64 = r.range(0.02, 0.12);
            // e² ≈ 1 − 4 c_f θ_c / ω  ⇒  c_f = (1 − e²) ω / (4 θ_c).
            let c_floor = (1.0 - (1.0 - loss).powi(2)) * w0 / (4.0 * theta_c);
            let c_wall = if one_sided { 2.0 * r.range(0.05, 0.25) * kappa.sqrt() } else { 0.0 };
            Contact::Compliant { theta_c, c_floor, c_wall }
        }
    };
    TestSpec {
        height_m,
        thickness_m,
        lever_mm,
        kappa,
        theta0,
        contact,
        fs_hz,
        sigma_mm,
        drift_mm,
        spikes,
        seed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rigid, e = 1, two-sided: energy is conserved, so every peak speed equals the
    /// first (the speed reached from θ_0: ½ω² = p² (cos(α − θ_0) − cos α)).
    #[test]
    fn rigid_lossless_conserves_energy() {
        let spec = TestSpec {
            height_m: 2.5,
            thickness_m: 0.3,
            lever_mm: 2400.0,
            kappa: 0.0,
            theta0: 0.05,
            contact: Contact::Rigid { e: vec![1.0] },
            fs_hz: 200.0,
            sigma_mm: 0.0,
            drift_mm: 0.0,
            spikes: 0,
            seed: 1,
        };
        let s = generate(&spec);
        let a = spec.alpha();
        let w = (2.0 * spec.p2() * ((a - 0.05).cos() - a.cos())).sqrt();
        for (k, p) in s.peaks.iter().take(6).enumerate() {
            let want = if k % 2 == 0 { -w } else { w } * 2400.0;
            assert!((p.1 - want).abs() < 1e-6 * want.abs(), "peak {k}: {} vs {want}", p.1);
        }
    }

    /// Compliant: the peak speed comes before the crossing, and impacts lose speed.
    #[test]
    fn compliant_peaks_before_crossing_and_lose_speed() {
        let spec = TestSpec {
            height_m: 3.0,
            thickness_m: 0.4,
            lever_mm: 2900.0,
            kappa: 0.0,
            theta0: 0.05,
            contact: Contact::Compliant {
                theta_c: 3.0 / 2900.0,
                c_floor: 20.0,
                c_wall: 0.0,
            },
            fs_hz: 1000.0,
            sigma_mm: 0.0,
            drift_mm: 0.0,
            spikes: 0,
            seed: 2,
        };
        let s = generate(&spec);
        assert!(s.peaks.len() >= 6);
        for k in 0..5 {
            assert!(
                s.peaks[k].0 < s.crossings[k],
                "peak {k} at {} after crossing {}",
                s.peaks[k].0,
                s.crossings[k]
            );
            assert!(s.peaks[k + 1].1.abs() < s.peaks[k].1.abs());
        }
    }

    #[test]
    fn draws_are_resolvable_and_reproducible() {
        for seed in 0..5 {
            let a = draw(seed, Family::Rigid);
            let b = draw(seed, Family::Rigid);
            assert!(resolvable(&a));
            assert_eq!(a.x_mm, b.x_mm);
        }
    }
}

/// Why a synthetic test could not be scored.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScoreError {
    /// The estimator gave up (its reason).
    #[error(transparent)]
    Peaks(#[from] crate::peaks::PeakError),
    /// Fewer than the six peaks the table values need.
    #[error("fewer than six peaks ({0})")]
    FewerThanSix(usize),
}

/// The outcome of reducing one synthetic test against its truth.
#[derive(Debug, Clone)]
pub struct Scored {
    pub seed: u64,
    pub spec: TestSpec,
    /// Worst |error| over the seven table values (percentage points), or the
    /// estimator's error message.
    pub worst_pp: Result<f64, ScoreError>,
    /// The quality `reduce` would claim ("ok", "suspect: …"): the estimator's,
    /// and a ratio read to more than ± 5 pp is not vouched for.
    pub status: String,
    /// Why an estimated logger filter was dropped for the contacts' rounding,
    /// if it was (`Analysis::acquisition_note`).
    pub acquisition_note: Option<String>,
}

/// Reduce a synthetic log with the default estimator (the geometry as a lab would
/// enter it: nominal p from height and thickness) and score it against its truth.
pub fn score(s: &Synthetic) -> Scored {
    score_with(s, &crate::peaks::PeakOptions::default())
}

/// [`score`] with the estimator's options given (a stated logger filter).
pub fn score_with(s: &Synthetic, opts: &crate::peaks::PeakOptions) -> Scored {
    use crate::peaks::{analyse, Physics};
    use crate::restitution::coefficients;
    let spec = &s.spec;
    let phys = Physics {
        rocking: if spec.one_sided() {
            crate::wall::Rocking::OneSided
        } else {
            crate::wall::Rocking::TwoSided
        },
        lever_arm_mm: spec.lever_mm,
        p_guess: spec.p2().sqrt(),
    };
    let e_h = spec.e_housner();
    let truth: Vec<f64> = s.peaks.iter().take(6).map(|p| p.1).collect();
    let tc = coefficients(&truth, e_h).expect("six true peaks");
    let res = analyse(&s.t, &s.x_mm, &phys, opts);
    let acquisition_note = res.as_ref().ok().and_then(|a| a.acquisition_note.clone());
    let (worst_pp, status) = match res {
        Err(e) => (Err(ScoreError::Peaks(e)), "error".to_string()),
        Ok(mut a) => {
            // The status `reduce` gives.
            crate::reduction::vouch(&mut a, e_h);
            let v: Vec<f64> = a.peaks.iter().map(|p| p.velocity_mm_s).collect();
            match coefficients(&v, e_h) {
                None => (Err(ScoreError::FewerThanSix(v.len())), "error".into()),
                Some(c) => {
                    let pairs = [
                        (c.r, tc.r),
                        (c.r_plus, tc.r_plus),
                        (c.r_minus, tc.r_minus),
                        (c.r1, tc.r1),
                        (c.r1_plus, tc.r1_plus),
                        (c.r1_minus, tc.r1_minus),
                        (c.r2, tc.r2),
                    ];
                    let w = pairs.iter().map(|(a, b)| 100.0 * (a - b).abs()).fold(0.0, f64::max);
                    (Ok(if w.is_finite() { w } else { f64::INFINITY }), a.quality.describe())
                }
            }
        }
    };
    Scored {
        seed: spec.seed,
        spec: spec.clone(),
        worst_pp,
        status,
        acquisition_note,
    }
}

/// The data logger's filter of a synthetic test (issue #18): the motion is
/// simulated on a grid 20× finer than the logger's, passed through the filter
/// there, then sampled; the noise, spikes and quantisation come after it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Logger {
    /// A causal analogue low-pass (Bessel or Butterworth), cut-off over f_s.
    LowPass {
        family: crate::signal::filter::Family,
        order: usize,
        fc_over_fs: f64,
    },
    /// A delta-sigma converter's linear-phase FIR: windowed sinc (Hamming), 64
    /// logger samples long, cut-off over f_s.
    Fir { fc_over_fs: f64 },
}

/// Oversampling of the fine grid the filter runs on.
const FINE: usize = 20;

impl Logger {
    /// The low-pass as the manifest would state it, for a logger rate f_s.
    pub fn stated(&self, fs_hz: f64) -> Option<crate::signal::filter::LowPass> {
        match *self {
            Logger::LowPass { family, order, fc_over_fs } => Some(crate::signal::filter::LowPass {
                family,
                order,
                cutoff_hz: fc_over_fs * fs_hz,
            }),
            Logger::Fir { .. } => None,
        }
    }

    /// The filter run over `x` sampled at `h` (s): the causal IIR in modal form
    /// with the input linear between samples (first-order hold: a discretisation
    /// independent of the estimator's, which places nodes at the kinks), or the
    /// FIR's taps, each output only where `keep(i)` (the logger's samples).
    fn apply(&self, x: &[f64], h: f64, fs_hz: f64, keep: impl Fn(usize) -> bool) -> Vec<f64> {
        match self.stated(fs_hz) {
            Some(lp) => {
                let m = lp.modal();
                let steps = m.step_coefficients(h);
                let mut state = m.steady_state(x[0]);
                let mut out = vec![x[0]];
                for w in x.windows(2) {
                    m.advance(&mut state, &steps, [w[0], (w[1] - w[0]) / h, 0.0, 0.0]);
                    out.push(m.output(&state));
                }
                out
            }
            None => {
                let Logger::Fir { fc_over_fs } = *self else { unreachable!() };
                let taps = fir_taps(fc_over_fs / FINE as f64, 64 * FINE);
                (0..x.len())
                    .map(|i| {
                        if !keep(i) {
                            return 0.0;
                        }
                        // Causal: y_i = Σ_j b_j x_(i−j), the log held before its start.
                        taps.iter().enumerate().map(|(j, b)| b * x[i.saturating_sub(j)]).sum()
                    })
                    .collect()
            }
        }
    }
}

/// Windowed-sinc low-pass taps (Hamming), cut-off `fc` in cycles per sample,
/// normalised to unit sum (scipy `firwin(n, 2 fc)`).
fn fir_taps(fc: f64, n: usize) -> Vec<f64> {
    let mid = 0.5 * (n as f64 - 1.0);
    let mut b: Vec<f64> = (0..n)
        .map(|i| {
            let m = i as f64 - mid;
            let x = 2.0 * fc * m;
            let sinc = if x.abs() < 1e-12 {
                1.0
            } else {
                (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
            };
            let w = 0.54 - 0.46 * (2.0 * std::f64::consts::PI * i as f64 / (n as f64 - 1.0)).cos();
            2.0 * fc * sinc * w
        })
        .collect();
    let sum: f64 = b.iter().sum();
    b.iter_mut().for_each(|v| *v /= sum);
    b
}

/// [`generate`] through a data logger's filter: the motion on a grid 20× finer
/// than the logger's, filtered there, sampled, then noise, spikes and
/// quantisation as in [`generate`]. The truth is the wall's motion, before the
/// filter.
pub fn generate_logged(spec: &TestSpec, logger: Logger) -> Synthetic {
    let plain = generate(&TestSpec {
        sigma_mm: 0.0,
        spikes: 0,
        ..spec.clone()
    });
    let mut rng = Rng::new(spec.seed ^ 0x10_66E5);
    let t_r = HOLD_S + Rng::new(spec.seed ^ 0x5EED).uniform() / spec.fs_hz;
    let motion = match &spec.contact {
        Contact::Rigid { e } => rigid_motion(spec, e),
        Contact::Compliant { theta_c, c_floor, c_wall } => compliant_motion(spec, *theta_c, *c_floor, *c_wall),
    };
    let n = plain.t.len();
    let duration = n as f64 / spec.fs_hz;
    let h = 1.0 / (spec.fs_hz * FINE as f64);
    let clean: Vec<f64> = (0..n * FINE)
        .map(|i| {
            let ti = i as f64 * h;
            spec.lever_mm * motion.theta_at(ti - t_r, spec.theta0).sin() + spec.drift_mm * ti / duration
        })
        .collect();
    let seen = logger.apply(&clean, h, spec.fs_hz, |i| i % FINE == 0);
    let mut x: Vec<f64> = (0..n).map(|i| seen[i * FINE] + spec.sigma_mm * rng.normal()).collect();
    for _ in 0..spec.spikes {
        let i = (rng.uniform() * n as f64) as usize % n;
        x[i] += rng.pick(&[-1.0, 1.0]) * rng.range(20.0, 80.0) * spec.sigma_mm.max(0.01);
    }
    for v in x.iter_mut() {
        *v = (*v * 100.0).round() / 100.0;
    }
    Synthetic { x_mm: x, ..plain }
}

/// Which filters a logged draw takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoggerDraw {
    /// `family`, or Bessel or Butterworth at even odds where None; order 2–8,
    /// cut-off uniform in [lo, hi] f_s.
    Causal {
        family: Option<crate::signal::filter::Family>,
        lo: f64,
        hi: f64,
    },
    /// The FIR with its cut-off uniform in 0.40–0.45 f_s.
    Fir,
}

/// A random resolvable test ([`draw`]) and a random filter of `kind`, logged
/// through it ([`generate_logged`]).
pub fn draw_logged(seed: u64, family: Family, kind: LoggerDraw) -> (Synthetic, Logger) {
    let spec = draw(seed, family).spec;
    let mut r = Rng::new(spec.seed ^ 0xF117E5);
    let logger = match kind {
        LoggerDraw::Causal { family, lo, hi } => Logger::LowPass {
            family: if let Some(f) = family {
                f
            } else if r.uniform() < 0.5 {
                crate::signal::filter::Family::Bessel
            } else {
                crate::signal::filter::Family::Butterworth
            },
            order: 2 + (r.uniform() * 7.0) as usize % 7,
            fc_over_fs: r.range(lo, hi),
        },
        LoggerDraw::Fir => Logger::Fir {
            fc_over_fs: r.range(0.40, 0.45),
        },
    };
    (generate_logged(&spec, logger), logger)
}

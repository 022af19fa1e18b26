//! Velocity peaks read where the log resolves them (issue 18): a local fit of
//! the smooth velocity extreme of a contact phase that spans several samples.
//!
//! # Why
//! The global fit ([`super::segments`]) describes every contact with one shape
//! per direction (a quintic join of a lead and a lag, [`super::model`]). A real
//! bedding's contacts lengthen as the motion dies down (MuJoCo: 7 → 55 ms in one
//! test), so one shape cannot follow them all, and the peaks it reads inside its
//! contact phases come out a few per cent low. Where a contact phase spans
//! several samples, the velocity peak is a smooth extreme that the samples
//! around it show directly, and no contact model is needed to read it.
//!
//! # The reading
//! Around the global fit's peak time t₀ the displacement (L θ space) is fitted
//! by linear least squares over the samples with |τ| ≤ h, τ = t − t₀, s = τ/h,
//! with the better (smaller χ²) of two shapes:
//! - smooth: a quartic, y = Σ_{j≤4} c_j sʲ;
//! - corner: a cubic whose curvature jumps at s_on (every quarter sample),
//!   y = Σ_{j≤3} c_j sʲ + j (s − s_on)₊²: the free arc up to the onset of
//!   contact, where the bedding's force sets in and the velocity turns over.
//!
//! The half-width h grows by about a quarter at a time from 3 samples while the
//! shape fits to the noise, χ² = Σ r²/σ² ≤ ν + 3 √(2ν) (ν = N − 5: the 3-σ
//! upper end of χ²_ν); the largest such window is kept and the fit re-centred
//! once on its extreme. The reading is the extreme of y' inside the inner 60 %
//! of the window.
//!
//! Its standard uncertainty combines (GUM 5.1.2, independent terms):
//! - the fit's: u² = σ² dᵀ(XᵀX)⁻¹d, d the gradient of y'(s*) in c (y' is
//!   linear in c; at an extreme the error of s* costs nothing to first order);
//! - the window's (model form): the readings with the chosen window and with a
//!   window two thirds as wide differ by d_w; the truth is taken as anywhere
//!   within ±|d_w| (rectangular): u² = d_w²/3 (GUM 4.3.7);
//! - the shape's (model form): the reading of the other shape on the same
//!   window differs by d_s: u² = d_s²/3.
//!
//! The shape's term is one choice for the whole test (one bedding: its
//! contacts turn the velocity over at a corner or smoothly at every impact), so
//! it is shared by the test's peaks: the covariance of the peaks read locally
//! takes it as one rank-one term D Dᵀ/3, D_k the smooth reading of peak k minus
//! its corner reading (the truth anywhere between the two readings, alike for
//! every peak), as the global fit's model spreads are
//! ([`super::uncertainty::add_model_spread`]); the fit's and the window's
//! terms stay per peak. Each peak's u is unchanged; a ratio of two peaks keeps
//! only the part of the shape's term that differs between them. On the
//! public-like stand-in Q2-s5, Q2_90_1 (500 Hz) read its peaks by corners with
//! d_s = 30–34 mm/s (the quartic does not fit the corner's 103-sample window),
//! u 3.6–7.3 % of each peak against errors of 0.0–1.9 %, and with the shape's
//! term independent per peak r₁ came out ± 5.0 pp and the test was suspect.
//!
//! # The choice, per impact and per test
//! A peak is resolved where:
//! - the smooth window holds at least 9 samples (h ≥ 4 samples);
//! - the extreme is inside the window and comes at least 1.5 samples before
//!   the log crosses its rest line (θ = 0): a compliant contact decelerates the
//!   wall before θ = 0, while a sharp impact, even one rounded by a logger's
//!   low-pass (a 4th-order Bessel at 0.25 fs rounds a kink over about two
//!   samples and delays it), peaks at its crossing;
//! - the data rule out an instantaneous impact at the crossing: a cubic with a
//!   jump of slope and of curvature (+ j (s − s_k)₊ + g (s − s_k)₊², the speed
//!   dropping by e and the gravity term changing sign) with s_k within one
//!   sample of the crossing fits the window worse than the chosen shape by at
//!   least max(9, ln N) in χ² (3 σ of evidence, and at least the Bayesian
//!   penalty of the kink's place). Where noise lets both fit, the kink stays.
//!   A window that does not reach the crossing rules nothing out, and the peak
//!   is not resolved (forty-second session): on MuJoCo q2-s4107 Q2_130_1
//!   (1000 Hz) no window wider than 9 samples fitted peak 2 to the noise, 9
//!   samples before its crossing, where the other peaks' windows grew to
//!   83–103 samples and took their crossings in; the corner read on those 9
//!   samples was 15 % off (u 7.5 %), and r₁⁻ came out 6.85 pp off with status
//!   ok (± 3.0).
//!
//! The local readings are used only where every peak of the test is resolved;
//! otherwise the test keeps the global fit's readings. The tables are ratios of
//! peaks, and a bias that the peaks of one test share (one bedding, one
//! reading) cancels in them; mixing the two readings in one test does not: on
//! the MuJoCo campaigns it moved P2_80_1 from 0.44 to 1.60 pp (its first peak
//! unresolved, the others read locally 1–2 % above the global fit's).
//!
//! No crate does this: it is ordinary least squares (nalgebra) on a window
//! chosen by the data.

use nalgebra::{DMatrix, DVector};

/// How a peak was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReadingMethod {
    /// The global fit of the free-rocking arcs: the slope at the kink of an
    /// instantaneous impact, or the extreme inside a fitted contact phase.
    KinkModel,
    /// The local fit of the smooth extreme of a resolved contact ([`read`]).
    LocalExtreme,
    /// A late peak (beyond the global fit's) read from the samples around
    /// an impact sharper than them: the left-hand slope of a local kink fit
    /// ([`super::late::read_kink`]).
    LocalKink,
    /// A one-sided wall's inward peak read by the contact model of its push
    /// into the transverse walls ([`super::inward`]).
    ContactModel,
}

/// A local reading of one velocity peak.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalReading {
    pub time_s: f64,
    pub velocity_mm_s: f64,
    /// Standard uncertainty (fit, window and shape terms), mm/s.
    pub u_mm_s: f64,
    /// The smooth shape's reading minus the corner's on the same window
    /// (signed, mm/s): the shape's term of u is |this|/√3, shared by the
    /// test's peaks (module docs).
    pub smooth_minus_corner_mm_s: f64,
    /// Half-width of the smooth window, in samples.
    pub half_width: usize,
}

/// The smallest half-width (samples) of a resolved contact's smooth window.
const MIN_HALF_WIDTH: usize = 4;
/// The largest half-width tried (samples).
const MAX_HALF_WIDTH: usize = 60;
/// How much worse (in χ²) an instantaneous impact at the crossing must fit the
/// smooth window than the chosen shape: 3 σ of evidence against it.
const KINK_EVIDENCE: f64 = 9.0;
/// How far before the rest-line crossing a resolved extreme must come (samples).
const MIN_LEAD_SAMPLES: f64 = 1.5;

/// The local shapes of the displacement (s = τ/h, h the half-width).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shape {
    /// A quartic: a smooth extreme.
    Smooth,
    /// A cubic whose curvature jumps at s_on, + j (s − s_on)₊²: the free arc
    /// up to the onset of contact, where the bedding's force sets in and the
    /// velocity turns over at a corner.
    Corner(f64),
    /// A cubic whose slope and curvature jump at s_k, + j (s − s_k)₊ +
    /// g (s − s_k)₊²: an impact sharper than a sample (the speed drops by e,
    /// the gravity term changes sign at θ = 0).
    Kink(f64),
}

impl Shape {
    fn columns(&self) -> usize {
        if matches!(self, Shape::Kink(_)) {
            6
        } else {
            5
        }
    }
    fn column(&self, j: usize, s: f64) -> f64 {
        match (self, j) {
            (_, 0..=3) | (Shape::Smooth, 4) => s.powi(j as i32),
            (Shape::Corner(on), _) | (Shape::Kink(on), 5) => (s - on).max(0.0).powi(2),
            (Shape::Kink(k), _) => (s - k).max(0.0),
            _ => 0.0,
        }
    }
    /// d/ds of column j.
    fn slope(&self, j: usize, s: f64) -> f64 {
        match (self, j) {
            (_, 0) => 0.0,
            (_, 1..=3) | (Shape::Smooth, 4) => j as f64 * s.powi(j as i32 - 1),
            (Shape::Corner(on), _) | (Shape::Kink(on), 5) => 2.0 * (s - on).max(0.0),
            (Shape::Kink(k), _) => f64::from(u8::from(s > *k)),
            _ => 0.0,
        }
    }
}

/// One local least-squares fit: its coefficients, (XᵀX)⁻¹ and χ² (cost / σ²).
struct LocalFit {
    shape: Shape,
    c: DVector<f64>,
    inv: DMatrix<f64>,
    chi2: f64,
    n: usize,
    h: f64,
}

impl LocalFit {
    /// Least squares on the samples with |t − t0| ≤ h; None with fewer than 9.
    fn fit(t: &[f64], y: &[f64], t0: f64, h: f64, sigma: f64, shape: Shape) -> Option<LocalFit> {
        let (i0, i1) = (t.partition_point(|&v| v < t0 - h), t.partition_point(|&v| v <= t0 + h));
        let n = i1.saturating_sub(i0);
        if n < 9 {
            return None;
        }
        // Scaled abscissa s = τ/h keeps XᵀX well conditioned.
        let x = DMatrix::from_fn(n, shape.columns(), |i, j| shape.column(j, (t[i0 + i] - t0) / h));
        let yv = DVector::from_column_slice(&y[i0..i1]);
        let inv = x.tr_mul(&x).try_inverse()?;
        let c = &inv * x.tr_mul(&yv);
        let r = &yv - &x * &c;
        let chi2 = r.norm_squared() / (sigma * sigma);
        Some(LocalFit { shape, c, inv, chi2, n, h })
    }
    /// The best of the smooth and corner shapes on one window, the corner
    /// placed every quarter sample within |s| ≤ 0.6.
    fn best(t: &[f64], y: &[f64], t0: f64, h: f64, dt: f64, sigma: f64) -> Option<LocalFit> {
        std::iter::once(Shape::Smooth)
            .chain(places(h, dt).map(Shape::Corner))
            .filter_map(|shape| LocalFit::fit(t, y, t0, h, sigma, shape))
            .min_by(|a, b| a.chi2.total_cmp(&b.chi2))
    }
    /// χ² within the 3-σ upper end of χ²_ν.
    fn fits_noise(&self) -> bool {
        super::checks::at_noise(self.chi2, (self.n - self.shape.columns()) as f64)
    }
    /// The gradient of y'(s) in c, per unit time.
    fn d(&self, s: f64) -> DVector<f64> {
        DVector::from_fn(self.shape.columns(), |j, _| self.shape.slope(j, s) / self.h)
    }
    /// (s*, y'(s*)) of the extreme with sign `want` within |s| ≤ 0.6, and whether
    /// it is interior (|s*| < 0.58).
    fn extreme(&self, want: f64) -> (f64, f64, bool) {
        const N: usize = 480;
        let mut best = (0.0, f64::NEG_INFINITY);
        let grid = (0..=N).map(|i| -0.6 + 1.2 * i as f64 / N as f64);
        let corner = match self.shape {
            Shape::Corner(on) | Shape::Kink(on) => Some(on),
            Shape::Smooth => None,
        };
        for s in grid.chain(corner) {
            let v = self.d(s).dot(&self.c);
            if want * v > best.1 {
                best = (s, want * v);
            }
        }
        (best.0, want * best.1, best.0.abs() < 0.58)
    }
    fn u_slope(&self, s: f64, sigma: f64) -> f64 {
        let d = self.d(s);
        (sigma * sigma * (d.transpose() * &self.inv * &d)[(0, 0)]).max(0.0).sqrt()
    }
}

/// Where a corner or a kink is placed on a window of half-width h: every
/// quarter sample within |s| ≤ 0.6.
fn places(h: f64, dt: f64) -> impl Iterator<Item = f64> + Clone {
    let steps = (2.4 * h / (0.25 * dt)).ceil().max(1.0) as usize;
    (0..=steps).map(move |i| -0.6 + 1.2 * i as f64 / steps as f64)
}

/// The best fit of one family on one window: the smooth shape, or the best
/// corner.
fn family_fit(t: &[f64], y: &[f64], t0: f64, h: f64, dt: f64, sigma: f64, smooth: bool) -> Option<LocalFit> {
    if smooth {
        return LocalFit::fit(t, y, t0, h, sigma, Shape::Smooth);
    }
    places(h, dt)
        .map(Shape::Corner)
        .filter_map(|shape| LocalFit::fit(t, y, t0, h, sigma, shape))
        .min_by(|a, b| a.chi2.total_cmp(&b.chi2))
}

/// χ² of the instantaneous impact on the window of `q`: the kink shape with its
/// jump within one sample of the log's crossing of θ = 0 (every quarter
/// sample); None where the window does not reach the crossing (then nothing
/// is ruled out, and [`read`] reads nothing).
fn kink_at_crossing_chi2(t: &[f64], y: &[f64], t0: f64, q: &LocalFit, zero: f64, dt: f64, sigma: f64) -> Option<f64> {
    (0..=8)
        .map(|i| (zero - t0 + (i as f64 / 4.0 - 1.0) * dt) / q.h)
        .filter(|s| s.abs() < 1.0)
        .filter_map(|s| LocalFit::fit(t, y, t0, q.h, sigma, Shape::Kink(s)))
        .map(|f| f.chi2)
        .filter(|c| c.is_finite())
        .min_by(f64::total_cmp)
}

/// Half-widths tried (samples), growing by about a quarter.
fn half_widths(max_half: usize) -> impl Iterator<Item = usize> {
    std::iter::successors(Some(3usize), |&n| Some((n + 1).max(n * 5 / 4))).take_while(move |&n| n <= max_half.min(MAX_HALF_WIDTH))
}

/// The largest window around `t0` (half-width in samples) that a smooth or a
/// corner shape fits to the noise, growing from 3 samples; None if none of at
/// least 4 does.
fn smooth_window(t: &[f64], y: &[f64], t0: f64, dt: f64, max_half: usize, sigma: f64) -> Option<(usize, LocalFit)> {
    let mut best = None;
    for n in half_widths(max_half) {
        match LocalFit::best(t, y, t0, (n as f64 + 0.5) * dt, dt, sigma) {
            Some(q) if q.fits_noise() => best = Some((n, q)),
            Some(_) => break,
            None => continue,
        }
    }
    best.filter(|(n, _)| *n >= MIN_HALF_WIDTH)
}

/// The time the samples cross θ = 0 (their zero line) after `from`, moving to the
/// side opposite `side` (linear interpolation), if they do within the window.
fn crossing_after(t: &[f64], y: &[f64], from: f64, side: f64) -> Option<f64> {
    let i = t.partition_point(|&v| v < from).max(1);
    (i..t.len()).find(|&j| side * y[j] < 0.0).map(|j| {
        let (a, b) = (y[j - 1], y[j]);
        if (a - b).abs() < 1e-300 {
            t[j]
        } else {
            t[j - 1] + (t[j] - t[j - 1]) * a / (a - b)
        }
    })
}

/// Read peak k locally (module docs) from the samples `t`, `y` (L θ space, the
/// rest line at 0), around the global fit's peak time `t_peak`; `want` is the
/// peak's sign (−1 for k even), `max_half` the largest half-width (samples) the
/// half-cycle allows. None where the log does not resolve a contact there.
pub fn read(t: &[f64], y: &[f64], t_peak: f64, want: f64, dt: f64, max_half: usize, sigma: f64) -> Option<LocalReading> {
    let (_, first) = smooth_window(t, y, t_peak, dt, max_half, sigma)?;
    let (s1, _, _) = first.extreme(want);
    let centre = t_peak + s1 * first.h;
    let (n, q) = smooth_window(t, y, centre, dt, max_half, sigma)?;
    let (s, v, interior) = q.extreme(want);
    if !interior {
        return None;
    }
    let time = centre + s * q.h;
    // Sharp impacts peak at their crossing; a resolved contact before it.
    let side = -want;
    let zero = crossing_after(t, y, time, side)?;
    if zero - time < MIN_LEAD_SAMPLES * dt {
        return None;
    }
    // The data must rule out an instantaneous impact at the crossing, not
    // merely allow a smooth shape; a window that does not reach the crossing
    // cannot.
    let kink = kink_at_crossing_chi2(t, y, centre, &q, zero, dt, sigma)?;
    if kink < q.chi2 + KINK_EVIDENCE.max((q.n as f64).ln()) {
        return None;
    }
    let u_fit = q.u_slope(s, sigma);
    let smaller_n = (2 * n / 3).max(MIN_HALF_WIDTH);
    let smaller = LocalFit::best(t, y, centre, (smaller_n as f64 + 0.5) * dt, dt, sigma).map(|p| p.extreme(want).1);
    let d_w = smaller.map_or(0.0, |vs| vs - v);
    // The other family on the same window: the best corner where the smooth
    // shape was chosen, and the reverse.
    let other = family_fit(t, y, centre, q.h, dt, sigma, q.shape != Shape::Smooth);
    let d_s = other.map_or(0.0, |o| o.extreme(want).1 - v);
    Some(LocalReading {
        time_s: time,
        velocity_mm_s: v,
        u_mm_s: (u_fit * u_fit + (d_w * d_w + d_s * d_s) / 3.0).sqrt(),
        smooth_minus_corner_mm_s: if q.shape == Shape::Smooth { -d_s } else { d_s },
        half_width: n,
    })
}

/// The per-impact choice (module docs) on a global fit: every peak the log
/// resolves as a smooth extreme is replaced by its local reading, its row and
/// column of the covariance by its own variance (the local reading shares no
/// parameter with the global fit). Returns the method of each peak.
pub(super) fn choose(
    fit: &super::segments::SegmentFit,
    peaks: &mut [super::Peak],
    cov: Option<&mut Vec<Vec<f64>>>,
    dt: f64,
    sigma: f64,
) -> Vec<ReadingMethod> {
    let m = fit.model();
    let readings: Vec<Option<LocalReading>> = (0..peaks.len())
        .map(|k| {
            let start = if k == 0 { m.release_time() } else { m.release_from_contact(k - 1) };
            let end = if k + 1 < m.m() {
                m.onset(k + 1)
            } else {
                fit.tw.last().copied().unwrap_or(start)
            };
            let t0 = peaks[k].time_s;
            let room = (t0 - start).min(end - t0).max(0.0);
            let max_half = (0.8 * room / dt).floor() as usize;
            let want = if k % 2 == 0 { -1.0 } else { 1.0 };
            read(&fit.tw, &fit.yw, t0, want, dt, max_half, sigma)
        })
        .collect();
    // One method for the whole test: the ratios of the tables cancel a bias
    // that its peaks share only if they share the reading (module docs).
    if readings.iter().any(Option::is_none) {
        return vec![ReadingMethod::KinkModel; peaks.len()];
    }
    let mut cov = cov;
    let methods = readings
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let Some(r) = r else { return ReadingMethod::KinkModel };
            peaks[k].time_s = r.time_s;
            peaks[k].velocity_mm_s = r.velocity_mm_s;
            peaks[k].velocity_u_mm_s = Some(r.u_mm_s);
            if let Some(c) = cov.as_deref_mut() {
                for (j, row) in c.iter_mut().enumerate() {
                    row[k] = if j == k { r.u_mm_s * r.u_mm_s } else { 0.0 };
                }
                for (j, v) in c[k].iter_mut().enumerate() {
                    if j != k {
                        *v = 0.0;
                    }
                }
            }
            ReadingMethod::LocalExtreme
        })
        .collect();
    // The shape's term, shared by the test's peaks (module docs): the rest
    // of D Dᵀ/3 (its diagonal is in each u already).
    if let Some(c) = cov {
        let d: Vec<f64> = readings.iter().map(|r| r.map_or(0.0, |r| r.smooth_minus_corner_mm_s)).collect();
        for (j, dj) in d.iter().enumerate() {
            for (k, dk) in d.iter().enumerate() {
                if j != k {
                    c[j][k] += dj * dk / 3.0;
                }
            }
        }
    }
    methods
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A smooth peak (a gravity arc that a compliant contact decelerates over
    /// 40 ms) sampled at 500 Hz: read within its u; a sharp kink: not read.
    #[test]
    fn a_resolved_contact_is_read_and_a_kink_is_not() {
        let dt = 0.002;
        // The rest line: the crossing 30 ms after the onset of contact.
        let (t, y, truth) = contact_log(dt, 0.03);
        let r = read(&t, &y, 0.0, -1.0, dt, 30, 0.001).expect("resolved");
        assert!((r.velocity_mm_s - truth).abs() < 0.01 * truth.abs(), "{r:?} against {truth}");
        assert!((r.velocity_mm_s - truth).abs() < 3.0 * r.u_mm_s + 0.05, "{r:?} against {truth}");
        // A kink at τ = 0 (the same arcs, e = 0.6): −(100 + 200 τ), then −60 + 200 τ.
        let yk = kink_arcs(&t);
        assert!(read(&t, &yk, 0.0, -1.0, dt, 30, 0.001).is_none());
    }

    /// The contact of [`a_resolved_contact_is_read_and_a_kink_is_not`]: a
    /// window that reaches the crossing 30 ms after its onset reads the peak;
    /// one held to ±17 ms (by the room the half-cycle allows) cannot rule
    /// out an instantaneous impact there, and reads nothing.
    #[test]
    fn a_window_short_of_the_crossing_reads_nothing() {
        let dt = 0.002;
        let (t, y, _) = contact_log(dt, 0.03);
        assert!(read(&t, &y, 0.0, -1.0, dt, 30, 0.001).is_some());
        assert!(read(&t, &y, 0.0, -1.0, dt, 8, 0.001).is_none());
    }

    /// A gravity arc that a compliant contact decelerates over 40 ms from τ = 0,
    /// sampled every `dt` from τ = −0.2 s, the rest line crossed at τ = `zero`:
    /// (t, displacement, the true velocity extreme).
    fn contact_log(dt: f64, zero: f64) -> (Vec<f64>, Vec<f64>, f64) {
        // Velocity: −(100 + 200 τ) before the contact (gravity speeds the wall
        // up), then a smooth blend over 40 ms into −60 + 200 (τ − 0.04) (the
        // next half-cycle, where gravity slows it); displacement by integration.
        let after = |tau: f64| -60.0 + 200.0 * (tau - 0.04);
        let vel = |tau: f64| {
            let free = -(100.0 + 200.0 * tau);
            if tau <= 0.0 {
                free
            } else if tau >= 0.04 {
                after(tau)
            } else {
                let w = 0.5 - 0.5 * (std::f64::consts::PI * tau / 0.04).cos();
                (1.0 - w) * free + w * after(tau)
            }
        };
        let fine = 1e-5;
        let t: Vec<f64> = (0..250).map(|i| -0.2 + i as f64 * dt).collect();
        let mut y = Vec::new();
        let mut acc = 0.0;
        let mut tf = -0.2;
        for &ti in &t {
            while tf < ti {
                acc += vel(tf + 0.5 * fine) * fine;
                tf += fine;
            }
            y.push(acc);
        }
        let z = y[t.partition_point(|&v| v < zero)];
        let y = y.iter().map(|v| v - z).collect();
        let truth = (0..4000).map(|i| vel(-0.02 + i as f64 * 1e-5)).fold(f64::INFINITY, f64::min);
        (t, y, truth)
    }

    /// The free arcs of an instantaneous impact at τ = 0 with e = 0.6 (gravity
    /// changing sign at θ = 0): −(100 τ + 100 τ²), then −60 τ + 100 τ² (mm).
    pub(crate) fn kink_arcs(t: &[f64]) -> Vec<f64> {
        t.iter()
            .map(|&s| {
                if s < 0.0 {
                    -(100.0 * s + 100.0 * s * s)
                } else {
                    -60.0 * s + 100.0 * s * s
                }
            })
            .collect()
    }
}

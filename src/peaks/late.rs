//! Every peak of a log read where it lies (issue 20): the velocity peaks after
//! the table's first six, each from the samples around it, with its own
//! uncertainty, without refitting the whole record.
//!
//! # Why
//! The global fit ([`super::segments`]) describes every contact with one shape
//! per direction. A real bedding's contacts lengthen as the motion dies down,
//! and fits of the whole record with 8, 10, 12 peaks turn suspect on compliant
//! walls (every test of the one-sided MuJoCo campaign) and cost a full
//! Levenberg–Marquardt run each. The peak of a late half-cycle depends only on
//! the samples around it, so it is read there.
//!
//! # The reading of peak k
//! Half-cycle k runs from the log's rest-line crossing c_{k−1} (the release
//! for k = 0) to c_k (crossings with hysteresis, as the global fit's starting
//! values). Its peak lies near c_k. The displacement (L θ space, θ =
//! asin(x/L)) is read with the better-supported of two readings:
//! - **a resolved contact** ([`super::local::read`]): where the samples show a
//!   smooth extreme before the crossing and rule out an instantaneous impact,
//!   the extreme of a local quartic or corner fit;
//! - **an impact sharper than the samples** ([`read_kink`]): otherwise, the
//!   samples on both sides of c_k fitted by least squares with a cubic whose
//!   slope and curvature jump at t_k (y = Σ_{j≤3} c_j sʲ + j (s − s_k)₊ +
//!   g (s − s_k)₊², s = (t − c_k)/h; t_k every quarter sample within one
//!   sample of c_k, the best χ²); the peak is the left-hand slope
//!   y'(t_k⁻) = (c₁ + 2 c₂ s_k + 3 c₃ s_k²)/h, the free arc's speed at the
//!   impact (paper Eq. 1's arcs are smooth up to it). The half-width h grows
//!   from 3 samples by about a quarter while the fit stays at the noise
//!   (χ² ≤ ν + 3√(2ν)), up to 0.8 of the distance to the neighbouring
//!   crossings.
//!
//! Uncertainty of a kink reading (GUM 5.1.2, independent terms):
//! - the fit's, σ² dᵀ(XᵀX)⁻¹d at the chosen t_k;
//! - the window's, d_w²/3, d_w the change of the reading with a window two
//!   thirds as wide (rectangular, GUM 4.3.7);
//! - a contact shorter than a sample, |ÿ| Δt/√12 (the wall is fastest at the
//!   onset of a contact that the samples cannot place: the global fit's term,
//!   [`super::uncertainty`]);
//! - the place of the kink: the spread of the readings over the places whose
//!   χ² is within 1 of the best, d_p²/3.
//!
//! # Where the readings stop
//! At the first peak that cannot be read, whose half-cycle is less than 20 σ
//! tall (noise-level motion: no impact to read), or whose speed exceeds the
//! previous peak's (free rocking only loses speed).
//!
//! No crate does this: ordinary least squares (nalgebra) on windows chosen by
//! the data, as in [`super::local`].

use nalgebra::{DMatrix, DVector};

use super::local::{self, ReadingMethod};

/// One reading of a velocity peak: time (s), sensor velocity (mm/s, outward
/// positive) and its standard uncertainty (mm/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reading {
    pub time_s: f64,
    pub velocity_mm_s: f64,
    pub u_mm_s: f64,
}

/// Velocity peak k read locally: as a resolved contact and as an impact
/// sharper than the samples, each where the log allows it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatePeak {
    pub k: usize,
    /// The rest-line crossing that ends half-cycle k (impact k), s.
    pub crossing_s: f64,
    /// Apex |x| (mm, sensor reading from the rest line) of half-cycle k.
    pub apex_mm: f64,
    /// [`super::local::read`]: the smooth extreme of a resolved contact.
    pub smooth: Option<Reading>,
    /// [`read_kink`]: the left-hand slope of a kink at the crossing.
    pub kink: Option<Reading>,
}

impl LatePeak {
    /// The reading by `method` (LocalExtreme or LocalKink).
    pub fn by(&self, method: ReadingMethod) -> Option<Reading> {
        match method {
            ReadingMethod::LocalExtreme => self.smooth,
            ReadingMethod::LocalKink => self.kink,
            ReadingMethod::KinkModel => None,
        }
    }
}

/// The smallest half-cycle (in σ of the noise) whose peak is read.
const MIN_HEIGHT_SIGMA: f64 = 20.0;

/// The kink's fit on one window.
struct KinkFit {
    c: DVector<f64>,
    inv: DMatrix<f64>,
    chi2: f64,
    n: usize,
    h: f64,
    s_k: f64,
}

const KINK_COLUMNS: usize = 6;

fn kink_column(j: usize, s: f64, k: f64) -> f64 {
    match j {
        0..=3 => s.powi(j as i32),
        4 => (s - k).max(0.0),
        _ => (s - k).max(0.0).powi(2),
    }
}

impl KinkFit {
    fn fit(t: &[f64], y: &[f64], t0: f64, h: f64, sigma: f64, s_k: f64) -> Option<KinkFit> {
        let (i0, i1) = (t.partition_point(|&v| v < t0 - h), t.partition_point(|&v| v <= t0 + h));
        let n = i1.saturating_sub(i0);
        // At least three samples on each side of the kink.
        let tk = t0 + s_k * h;
        if n < 9 || t[i0..i1].iter().filter(|&&v| v < tk).count() < 3 || t[i0..i1].iter().filter(|&&v| v > tk).count() < 3 {
            return None;
        }
        let x = DMatrix::from_fn(n, KINK_COLUMNS, |i, j| kink_column(j, (t[i0 + i] - t0) / h, s_k));
        let yv = DVector::from_column_slice(&y[i0..i1]);
        let inv = x.tr_mul(&x).try_inverse()?;
        let c = &inv * x.tr_mul(&yv);
        let chi2 = (&yv - &x * &c).norm_squared() / (sigma * sigma);
        Some(KinkFit { c, inv, chi2, n, h, s_k })
    }
    fn fits_noise(&self) -> bool {
        let nu = (self.n - KINK_COLUMNS) as f64;
        self.chi2 <= nu + 3.0 * (2.0 * nu).sqrt()
    }
    /// Gradient of y'(s_k⁻) in c, per unit time.
    fn d(&self) -> DVector<f64> {
        let s = self.s_k;
        DVector::from_row_slice(&[0.0, 1.0, 2.0 * s, 3.0 * s * s, 0.0, 0.0]) / self.h
    }
    fn slope(&self) -> f64 {
        self.d().dot(&self.c)
    }
    /// y''(s_k⁻), per unit time².
    fn acceleration(&self) -> f64 {
        (2.0 * self.c[2] + 6.0 * self.c[3] * self.s_k) / (self.h * self.h)
    }
    fn u_fit(&self, sigma: f64) -> f64 {
        let d = self.d();
        (sigma * sigma * (d.transpose() * &self.inv * &d)[(0, 0)]).max(0.0).sqrt()
    }
}

/// Every kink place within one sample of the crossing `zero` (quarter samples)
/// on a window of half-width h centred on it, best χ² first.
fn kink_fits(t: &[f64], y: &[f64], zero: f64, h: f64, dt: f64, sigma: f64) -> Vec<KinkFit> {
    let mut fits: Vec<KinkFit> = (0..=8)
        .filter_map(|i| KinkFit::fit(t, y, zero, h, sigma, (i as f64 / 4.0 - 1.0) * dt / h))
        .collect();
    fits.sort_by(|a, b| a.chi2.total_cmp(&b.chi2));
    fits
}

/// The reading of an impact sharper than the samples at the crossing `zero`
/// (module docs): (velocity, u, time) or None where no window of at least 4
/// samples a side fits to the noise.
pub fn read_kink(t: &[f64], y: &[f64], zero: f64, dt: f64, max_half: usize, sigma: f64) -> Option<(f64, f64, f64)> {
    let mut best: Option<(usize, Vec<KinkFit>)> = None;
    let widths = std::iter::successors(Some(3usize), |&n| Some((n + 1).max(n * 5 / 4))).take_while(|&n| n <= max_half.min(60));
    for n in widths {
        let fits = kink_fits(t, y, zero, (n as f64 + 0.5) * dt, dt, sigma);
        match fits.first() {
            Some(f) if f.fits_noise() => best = Some((n, fits)),
            Some(_) => break,
            None => continue,
        }
    }
    let (n, fits) = best.filter(|(n, _)| *n >= 4)?;
    let q = &fits[0];
    let v = q.slope();
    let spread = fits
        .iter()
        .filter(|f| f.chi2 <= q.chi2 + 1.0)
        .map(|f| (f.slope() - v).abs())
        .fold(0.0, f64::max);
    let smaller = (2 * n / 3).max(3);
    let d_w = kink_fits(t, y, zero, (smaller as f64 + 0.5) * dt, dt, sigma)
        .first()
        .map_or(0.0, |f| f.slope() - v);
    let sub_sample = q.acceleration().abs() * dt;
    let u2 = q.u_fit(sigma).powi(2) + (d_w * d_w + spread * spread) / 3.0 + sub_sample * sub_sample / 12.0;
    Some((v, u2.sqrt(), zero + q.s_k * q.h))
}

/// What the late readings need of a log: time (s), displacement from the rest
/// line (mm, outward positive), the sensor's lever arm (mm), the noise σ (mm),
/// the sampling step (s) and the rest-line crossings with hysteresis (c_0 the
/// end of the release arc).
pub struct LateInput<'a> {
    pub t: &'a [f64],
    pub x: &'a [f64],
    pub lever_mm: f64,
    pub sigma: f64,
    pub dt: f64,
    pub release_s: f64,
    pub crossings: &'a [f64],
}

/// Peaks `from` … up to the last one readable (module docs), each read
/// locally.
pub fn read_late(inp: &LateInput, from: usize) -> Vec<LatePeak> {
    let y: Vec<f64> = inp.x.iter().map(|&v| inp.lever_mm * (v / inp.lever_mm).clamp(-1.0, 1.0).asin()).collect();
    let c = inp.crossings;
    let mut out: Vec<LatePeak> = Vec::new();
    for k in from..c.len() {
        let start = if k == 0 { inp.release_s } else { c[k - 1] };
        let end_next = c.get(k + 1).copied().unwrap_or(c[k] + (c[k] - start));
        let want = if k % 2 == 0 { -1.0 } else { 1.0 };
        let Some(p) = read_one(inp, &y, k, start, end_next, want) else { break };
        if p.apex_mm < MIN_HEIGHT_SIGMA * inp.sigma || (p.smooth.is_none() && p.kink.is_none()) {
            break;
        }
        out.push(p);
    }
    out
}

/// Peak k of half-cycle [start, c_k], the next crossing at `end_next`.
fn read_one(inp: &LateInput, y: &[f64], k: usize, start: f64, end_next: f64, want: f64) -> Option<LatePeak> {
    let (t, dt, zero) = (inp.t, inp.dt, inp.crossings[k]);
    let (i0, i1) = (t.partition_point(|&v| v < start), t.partition_point(|&v| v <= zero));
    let (apex_i, apex_mm) = (i0..i1).map(|i| (i, inp.x[i].abs())).max_by(|a, b| a.1.total_cmp(&b.1))?;
    let room = (zero - t[apex_i]).min(end_next - zero).max(0.0);
    let max_half = (0.8 * room / dt).floor() as usize;
    // A resolved contact's extreme comes before the crossing: look for it from
    // the crossing's side of the apex.
    let smooth = local::read(t, y, zero - dt, want, dt, max_half, inp.sigma)
        .filter(|r| r.time_s > t[apex_i] && r.time_s < end_next && want * r.velocity_mm_s > 0.0)
        .map(|r| Reading {
            time_s: r.time_s,
            velocity_mm_s: r.velocity_mm_s,
            u_mm_s: r.u_mm_s,
        });
    let kink = read_kink(t, y, zero, dt, max_half, inp.sigma)
        .filter(|r| want * r.0 > 0.0)
        .map(|(v, u, time)| Reading {
            time_s: time,
            velocity_mm_s: v,
            u_mm_s: u,
        });
    Some(LatePeak {
        k,
        crossing_s: zero,
        apex_mm,
        smooth,
        kink,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An instantaneous impact at the crossing (the free arcs of e = 0.6,
    /// gravity changing sign at θ = 0), sampled at 500 Hz: the kink reading is
    /// the arc's slope just before it, within its u.
    #[test]
    fn a_kink_is_read_as_the_slope_before_it() {
        let dt = 0.002;
        let t: Vec<f64> = (0..200).map(|i| -0.2 + 0.0007 + i as f64 * dt).collect();
        let y = crate::peaks::local::tests::kink_arcs(&t);
        let (v, u, time) = read_kink(&t, &y, 0.0, dt, 30, 0.001).expect("a kink");
        assert!((v + 100.0).abs() < 0.05 && (v + 100.0).abs() < 3.0 * u + 1e-3, "{v} ± {u}");
        assert!(time.abs() <= dt, "{time}");
        // A half-cycle too short for four samples a side is not read.
        assert!(read_kink(&t, &y, 0.0, dt, 3, 0.001).is_none());
    }
}

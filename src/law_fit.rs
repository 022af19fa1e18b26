//! The campaign's restitution law fitted to every impact of every test
//! ([`crate::impacts`]), and whether the data reject a constant.
//!
//! # The fit
//! The form ([`crate::restitution_law`]) is linear in its parameters:
//! r_i = r∞ − c g(a_i) + ε_i, so it is fitted by weighted least squares, weights
//! W = diag(1/u_i²), and its covariance comes from the full covariance C of the
//! impacts' r (block-diagonal over tests; within a test J Σ_v Jᵀ, so that two ratios
//! sharing a peak and the fully correlated model-form terms count as they are):
//!
//!   β = A⁻¹ Xᵀ W y,   Cov β = A⁻¹ (Xᵀ W C W X) A⁻¹,   A = Xᵀ W X,   X_i = (1, −g(a_i)),
//!   χ² = (y − Xβ)ᵀ W (y − Xβ).
//!
//! Why not generalised least squares with C⁻¹: the model-form terms of the peaks are
//! large and fully correlated within a test, and GLS then exploits them and lands
//! outside the data (Peelle's puzzle): on the two-sided MuJoCo campaign its constant
//! was 0.974, above every one of the 30 impacts. The sandwich keeps the estimate
//! where the data are and the correlation in its uncertainty.
//!
//! One-sided rocking fits each side on its own impacts; two-sided rocking fits one
//! law to all impacts (the sides are the same contact).
//! The outward side of a one-sided wall is fitted with g(a) = 1/a
//! ([`crate::restitution_law::Shape::Push`]: its impacts end a push against the
//! transverse walls, speed ∝ amplitude); every other side with 1/√(a(2 − a)).
//!
//! # The form's own misfit (Paule–Mandel)
//! No two-parameter law follows a real wall exactly (each MuJoCo test follows
//! r∞ − c g^q with q 1.3–2.9, docs/restitution-law.md), so where χ²/ν > 1 the
//! misfit of the form is part of every impact's error: each impact's variance is
//! raised by τ², the same for all, with τ² chosen so that χ²/ν = 1 (the
//! Paule–Mandel estimator of an extra variance; bisection on ln τ²), and the
//! sandwich's C gets τ² on its diagonal. Why: with the bare u the first impacts of a
//! test (u 0.002, read by the global fit) outweigh the late ones (u 0.02–0.04) a
//! hundredfold, and the form's misfit at large amplitudes then sets c. On the
//! two-sided MuJoCo campaign the law fitted with the bare u (and the Birge scale
//! s² = χ²/ν on its covariance) was within RMS 0.0235 of the truth over the 40
//! listed impacts, and 0.0206 when fitted to the truth's own r with the readings'
//! u: the weighting, not the readings, was most of the gap. With τ: 0.0149.
//! Where the u already cover the scatter, τ = 0 and nothing changes.
//!
//! # The constant
//! The constant is the same fit with X_i = (1). The law rejects it on a side when
//!
//!   F = (χ²_const − χ²_law) / s²,   s² = max(1, χ²_law/ν),
//!
//! (both χ² with the same τ) is improbable under the constant: p = P(F(1, ν) > F)
//! where τ > 0 (the residual variance estimated, the F test), p = P(χ²(1) > F)
//! where the stated u already cover the scatter (the likelihood-ratio test). The data reject the constant when a side's
//! p is below 0.01 / (number of sides tested) (Bonferroni): `rejects_constant`, and
//! the report's verdict.
//!
//! # Which form the campaign's law applies
//! The test above answers whether the data *show* a trend; the law answers what r
//! to *predict* at an amplitude (the façade's impacts), and the two are different
//! questions. A side applies the speed-loss form with c > 0 (a loss, the direction
//! compliant contacts give) where Akaike's criterion prefers it to the constant
//! (the nested model): where the form's second parameter lowers the scaled χ² by
//! more than its penalty, F > 2 ([`AIC_PENALTY`]; p below about 0.16). Otherwise,
//! and where the fitted c is negative, it applies the constant: a fixed speed *gain*
//! per impact is not physics, and r would rise past 1 as the amplitude falls. The
//! speed-loss fit of every side is reported beside it, and the notes say where a
//! kept form's trend is one the data do not show at the test's level.
//!
//! Why not the test's level for a loss (the rule until the thirty-third session): a
//! loss the data favour but cannot prove was dropped for a constant that is biased
//! by all of it, and a loss that is there keeps r higher at the large amplitudes a
//! façade near overturning reaches (the safe side). Measured on 44 one-sided engine
//! campaigns (20 MuJoCo stand-ins, 5 hold-out walls, 4 check walls, 3 fixtures, 12
//! penalty walls; `fresh_engine_campaigns`), with the rule for a rise below: the
//! law read at each reported impact's amplitude, RMS against the engine's truth,
//! never rises, and falls on 7 (the public one-sided campaign 0.0300 → 0.0267,
//! the penalty walls by 0.0004–0.0089). The two-sided campaigns reject the constant
//! outright and do not change (docs/restitution-law.md).
//!
//! # A loss of energy too (thirty-seventh session)
//! Each side but the inward one of a one-sided wall is also fitted with
//! r = r∞ − c g − c₂ g² ([`fit_energy`]; [`crate::restitution_law`], "A loss of
//! energy too"), with its own τ, and the speed-loss form and the constant are
//! fitted again with the same weights. The side applies it where Akaike's
//! criterion prefers it to both (χ²/s² + 2k lowest, s² = max(1, χ²/ν) of the
//! three-parameter fit), c₂ > 0 (a loss of energy, not a gain) and r falls with g
//! from g = 1 on (c + 2 c₂ g_lo ≥ 0: the law stays monotone in a, and above the
//! data it rises along the tangent, a short step on the free arc). Otherwise the
//! rules above stand, bit for bit. Why not the inward side of a one-sided wall:
//! there the speed-loss form's sign is already a rule of its own (a rise must
//! outlive the release), and a curvature on three impacts per test (the first of
//! which is the release's) would be carried by the first impacts, which the rule
//! sets apart.
//!
//! Measured (release, `fresh_engine_campaigns`, the law read at each reported
//! impact's amplitude, RMS against the engine's truth; 90 engine campaigns at
//! hand, before → after): no campaign moves by more than 0.0001 the wrong way.
//! Two-sided: the 7 public-like walls (q2) 0.0132–0.0183 → 0.0047–0.0075, the
//! public campaign 0.0124 → 0.0116, the hold-out-preset walls (h2, the fixture,
//! s3504) 0.0238–0.0403 → 0.0129–0.0366, within issue 20's 0.02 on 4 of 7 (none
//! before); the penalty engine's walls as before. One-sided (the outward side):
//! within issue 20's 0.025 on 16 of the 35 public-like stand-ins (13 before),
//! the public campaign 0.0267 as before (its outward impacts do not favour the
//! term).
//!
//! # The inward side of a one-sided wall
//! There c < 0 is kept where the data reject the constant at the test's level, or
//! where Akaike's criterion prefers the rise both with and without each test's first
//! impact (F > 2 on both fits, c < 0 on both; where fewer than four inward impacts
//! remain without them, only where the data reject the constant, and the note says
//! why). The inward r of a one-sided wall is
//! no bare impact on the base: r_k = |v_{k+1}/v_k| spans the push into the
//! transverse walls that follows the landing, and what the push loses depends on
//! how hard the wall drives into their compliant, lossy contact (MuJoCo's one-sided
//! walls: the truth's inward r rises as the amplitude falls, c ≈ −0.025 … −0.04
//! fitted to it on the hold-out and the Q1 stand-ins, docs/restitution-law.md). The
//! speed-gain objection is to a form that would carry r past 1; the law's range
//! already holds r at its value at the smallest amplitude observed where c < 0
//! ([`crate::restitution_law`], "Range") and caps e = r e_H at 1, so the rise stays
//! within the data. Two-sided walls and the outward side (whose impacts end the
//! push, fitted in its shape g = 1/a) keep the rule above.
//!
//! Why a weak rise must outlive the release: every test's first impact is both its
//! largest-amplitude one and the release's, whose r₁ the paper sets apart (Table 3;
//! the one-sided demo's generator makes it 0.32–0.37 against 0.45–0.95 later), so a
//! rise those impacts alone carry cannot be told from the release's own loss; and a
//! rise lowers r at the large amplitudes a façade near overturning reaches, the
//! unsafe side where it is wrong. Taken on Akaike's criterion alone (measured, not
//! kept), the one-sided demo's law became a rise of +0.28 ± 0.12 from its first
//! impacts, and the laws of 20 of the 32 one-sided MuJoCo campaigns fell
//! (RMS against the truth 0.0231–0.0420 → 0.0191–0.0406; within issue 20's 0.025:
//! 9 → 15): on those walls the readings' rise rests on the first impacts, so the
//! rule that outlives the release keeps their constants (the public campaign's
//! outlives it). The engine asked directly (fifty-fifth session,
//! `tools/mujoco_release_probe.py`, docs/restitution-law.md): released from smaller
//! displacements, a release's impact reads 0.020–0.022 below a later impact at the
//! same amplitude on both walls, and the second inward impact 0.013–0.017 below the
//! third; the engine's truth without each test's first impact is flat on the eight
//! campaigns whose readings favoured the rise. The rise those campaigns' readings
//! carry is in part a transient of the first impacts, not a law of amplitude.
//!
//! The incomplete beta function (for the F distribution) is Numerical Recipes §6.4
//! (continued fraction by the modified Lentz method; ln Γ by Lanczos, §6.1): a dozen
//! lines no crate of ours carries.

use nalgebra::{DMatrix, DVector};

use crate::impacts::ImpactTable;
use crate::restitution_law::{EnergyLoss, LawForm, LawParameters, ObservedAmplitudes, PushSpeed, RestitutionLaw, Shape, SideLaw, AMPLITUDE_FLOOR};
use crate::wall::{Rocking, Side};

/// Level of the test against a constant (before the Bonferroni split over sides).
pub const ALPHA_TEST: f64 = 0.01;

/// Akaike's penalty for the law's second parameter: a side applies the speed-loss
/// form where F = Δχ²/s² exceeds it (module docs, "Which form the campaign's law
/// applies").
pub const AIC_PENALTY: f64 = 2.0;

/// One test's impacts as the fit takes them.
#[derive(Debug, Clone, Copy)]
pub struct TestImpacts<'a> {
    pub id: &'a str,
    pub table: &'a ImpactTable,
}

/// The fit of one side (or of both, two-sided).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct SideFit {
    pub impacts: usize,
    /// ν = impacts − 2.
    pub dof: usize,
    pub chi2_law: f64,
    pub chi2_constant: f64,
    /// s² = max(1, χ²_law/ν).
    pub scale: f64,
    /// The weighted constant r and its u (scaled as the law's).
    pub constant_r: f64,
    pub constant_u: f64,
    pub statistic: f64,
    pub p_value: f64,
    /// The amplitudes a = |θ|/α of this side's impacts: where its law is vouched for.
    pub amplitude_min: f64,
    pub amplitude_max: f64,
    /// The change of r the speed-loss fit gives across them,
    /// c (g(a_min) − g(a_max)), and its u: the trend the data could show there.
    pub trend: f64,
    pub trend_u: f64,
    /// τ, the form's own misfit added in quadrature to every impact's u before
    /// the fit (Paule–Mandel; 0 where the u cover the scatter).
    pub form_u: f64,
    /// The speed-and-energy-loss form fitted on this side ([`fit_energy`]; not on
    /// the inward side of a one-sided wall), and whether the side applies it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub energy: Option<EnergyFit>,
}

/// The fit of r = r∞ − c g − c₂ g² on one side (module docs, "A loss of energy
/// too"), with the nested forms' χ² at its own τ.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct EnergyFit {
    pub impacts: usize,
    /// ν = impacts − 3.
    pub dof: usize,
    pub chi2: f64,
    pub chi2_speed_loss: f64,
    pub chi2_constant: f64,
    /// F = (χ²_speed-loss − χ²)/s², s² = max(1, χ²/ν).
    pub statistic: f64,
    pub c2: f64,
    pub c2_u: f64,
    /// τ of this form (Paule–Mandel).
    pub form_u: f64,
    /// Akaike's criterion prefers it to both nested forms, c₂ > 0 and r falls
    /// with g over [1, ∞): the side applies it.
    pub applied: bool,
}

/// The campaign's law and its test against a constant.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LawFit {
    /// The law the campaign gives: the speed-loss form on the sides whose data reject
    /// a constant, the constant on the others (form "constant" where no side does).
    pub law: RestitutionLaw,
    /// The speed-loss form fitted on every side, whatever the test says.
    pub speed_loss: RestitutionLaw,
    /// The fits: ("in", "out") one-sided, ("both") two-sided.
    pub sides: Vec<(String, SideFit)>,
    /// Whether some side's p is below [`ALPHA_TEST`] / (sides tested).
    pub rejects_constant: bool,
    /// The best constant pair (the weighted constant of each side).
    pub constant: RestitutionLaw,
    pub tests_used: Vec<String>,
    /// What the law cannot vouch for, per side ([`notes`]): the amplitudes it was
    /// fitted on, why a side keeps the constant, where it extrapolates.
    pub notes: Vec<String>,
}

impl LawFit {
    /// The campaign's [`PushSpeed`] on the law, its speed-loss form and its
    /// constant pair (one-sided campaigns: the caller knows each test's p, α and
    /// lever arm, which turn a sensor speed into ŵ = ω⁻/(p α)).
    pub fn with_push_speed(mut self, push_speed: Option<PushSpeed>) -> LawFit {
        for law in [&mut self.law, &mut self.speed_loss, &mut self.constant] {
            law.parameters.push_speed = push_speed;
        }
        self
    }
}

/// Why no law could be fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LawFitError {
    #[error("no test is in the means (each is suspect, excluded or not reduced): the law is fitted to the tests the campaign vouches for")]
    NoTests,
    #[error("no test has per-impact uncertainties (the default estimator gives them)")]
    NoUncertainties,
    #[error("side {side}: {n} impacts with uncertainties; the law needs at least 4 (two parameters and two degrees of freedom)")]
    TooFewImpacts { side: &'static str, n: usize },
    #[error("side {0}: the impacts' amplitudes do not spread enough to tell r∞ from c")]
    NotIdentifiable(&'static str),
}

/// Accumulated normal equations of the GLS: XᵀWX, XᵀWy, yᵀWy for p parameters.
struct Normal {
    xtwx: DMatrix<f64>,
    xtwy: DVector<f64>,
    xtwcwx: DMatrix<f64>,
    ytwy: f64,
    n: usize,
    a_min: f64,
    a_max: f64,
}

impl Normal {
    fn new(p: usize) -> Normal {
        Normal {
            xtwx: DMatrix::zeros(p, p),
            xtwy: DVector::zeros(p),
            xtwcwx: DMatrix::zeros(p, p),
            ytwy: 0.0,
            n: 0,
            a_min: f64::INFINITY,
            a_max: 0.0,
        }
    }

    /// Adds one test's impacts `idx` with design rows from `row`: weights 1/u², and
    /// the test's full covariance block into XᵀW C W X for the sandwich.
    fn add(&mut self, table: &ImpactTable, cov: &[Vec<f64>], idx: &[usize], row: &dyn Fn(f64) -> Vec<f64>, tau2: f64) {
        let m = idx.len();
        let p = self.xtwy.len();
        let c = DMatrix::from_fn(m, m, |i, j| cov[idx[i]][idx[j]] + if i == j { tau2 } else { 0.0 });
        let w = DMatrix::from_fn(m, m, |i, j| if i == j { 1.0 / c[(i, i)] } else { 0.0 });
        let x = DMatrix::from_fn(m, p, |i, j| row(table.impacts[idx[i]].amplitude_over_alpha)[j]);
        let y = DVector::from_fn(m, |i, _| table.impacts[idx[i]].r);
        let xtw = x.transpose() * &w;
        self.xtwx += &xtw * &x;
        self.xtwy += &xtw * &y;
        self.xtwcwx += &xtw * &c * xtw.transpose();
        self.ytwy += (y.transpose() * &w * &y)[(0, 0)];
        self.n += m;
        for &i in idx {
            let a = table.impacts[i].amplitude_over_alpha;
            self.a_min = self.a_min.min(a);
            self.a_max = self.a_max.max(a);
        }
    }

    /// β, its covariance A⁻¹ (XᵀW C W X) A⁻¹ (A = XᵀWX; the sandwich, before the
    /// Birge scale) and the weighted χ².
    fn solve(&self) -> Option<(DVector<f64>, DMatrix<f64>, f64)> {
        let inv = self.xtwx.clone().try_inverse()?;
        let beta = &inv * &self.xtwy;
        let chi2 = (self.ytwy - (beta.transpose() * &self.xtwy)[(0, 0)]).max(0.0);
        let cov = &inv * &self.xtwcwx * &inv;
        Some((beta, cov, chi2))
    }
}

fn law_row(shape: Shape, a: f64) -> Vec<f64> {
    vec![1.0, -shape.eval(a.max(AMPLITUDE_FLOOR))]
}

/// The design row of the speed-and-energy-loss form: (1, −g, −g²).
fn energy_row(shape: Shape, a: f64) -> Vec<f64> {
    let g = shape.eval(a.max(AMPLITUDE_FLOOR));
    vec![1.0, -g, -g * g]
}

fn const_row(_: f64) -> Vec<f64> {
    vec![1.0]
}

/// The fit of the impacts of `sides` (one side, or both for two-sided rocking).
/// The normal equations of the law and of the constant over the impacts of
/// `sides`, each impact's variance raised by τ² (the form's own misfit).
fn normals(tests: &[TestImpacts], sides: &[Side], shape: Shape, tau2: f64) -> (Normal, Normal) {
    (
        normals_of(tests, sides, 2, &|a| law_row(shape, a), tau2),
        normals_of(tests, sides, 1, &const_row, tau2),
    )
}

/// The normal equations of a form of `p` parameters with design rows `row` over
/// the impacts of `sides`, each impact's variance raised by τ².
fn normals_of(tests: &[TestImpacts], sides: &[Side], p: usize, row: &dyn Fn(f64) -> Vec<f64>, tau2: f64) -> Normal {
    let mut normal = Normal::new(p);
    for t in tests {
        let Some(cov) = &t.table.r_cov else { continue };
        let idx: Vec<usize> = (0..t.table.impacts.len())
            .filter(|&i| sides.contains(&t.table.impacts[i].side) && t.table.impacts[i].r.is_finite() && cov[i][i] > 0.0)
            .collect();
        if !idx.is_empty() {
            normal.add(t.table, cov, &idx, row, tau2);
        }
    }
    normal
}

/// The form's own misfit τ (Paule–Mandel): the τ² ≥ 0 at which the law's χ²
/// over ν = n − 2 is 1 (0 where the u already cover the scatter), by bisection on
/// ln τ² (χ² falls as τ² grows).
fn form_variance(tests: &[TestImpacts], sides: &[Side], shape: Shape) -> f64 {
    form_variance_of(tests, sides, 2, &|a| law_row(shape, a))
}

/// [`form_variance`] of a form of `p` parameters with design rows `row`.
fn form_variance_of(tests: &[TestImpacts], sides: &[Side], p: usize, row: &dyn Fn(f64) -> Vec<f64>) -> f64 {
    let chi2_per_dof = |tau2: f64| {
        let law = normals_of(tests, sides, p, row, tau2);
        let dof = law.n.saturating_sub(p).max(1) as f64;
        law.solve().map_or(0.0, |(_, _, chi2)| chi2 / dof)
    };
    if chi2_per_dof(0.0) <= 1.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (1e-12f64.ln(), 1.0f64.ln());
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if chi2_per_dof(mid.exp()) > 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi.exp()
}

fn fit_group(tests: &[TestImpacts], sides: &[Side], shape: Shape, label: &'static str) -> Result<(SideLaw, SideFit, (f64, f64)), LawFitError> {
    let (law0, _) = normals(tests, sides, shape, 0.0);
    if law0.n < 4 {
        return Err(LawFitError::TooFewImpacts { side: label, n: law0.n });
    }
    let tau2 = form_variance(tests, sides, shape);
    let (law, cst) = normals(tests, sides, shape, tau2);
    let (beta, inv, chi2_l) = law.solve().ok_or(LawFitError::NotIdentifiable(label))?;
    let (beta_c, inv_c, chi2_c) = cst.solve().ok_or(LawFitError::NotIdentifiable(label))?;
    // Amplitudes that hardly spread leave c undetermined: its u then exceeds the whole
    // change of r over the observed range many times over.
    let g_span = shape.eval(law.a_min.max(AMPLITUDE_FLOOR)) - shape.eval(law.a_max.max(AMPLITUDE_FLOOR));
    if g_span.is_nan() || g_span <= 1e-6 || !inv[(1, 1)].is_finite() {
        return Err(LawFitError::NotIdentifiable(label));
    }
    let dof = law.n - 2;
    let scale = (chi2_l / dof as f64).max(1.0);
    let statistic = (chi2_c - chi2_l).max(0.0) / scale;
    let p_value = if scale > 1.0 || tau2 > 0.0 {
        f_sf(statistic, 1.0, dof as f64)
    } else {
        chi2_1_sf(statistic)
    };
    let cov = [[inv[(0, 0)] * scale, inv[(0, 1)] * scale], [inv[(1, 0)] * scale, inv[(1, 1)] * scale]];
    let c_scale = (chi2_c / (law.n - 1) as f64).max(1.0);
    let trend_u = g_span * cov[1][1].sqrt();
    let side = SideLaw {
        r_inf: beta[0],
        c: beta[1],
        cov,
        g: shape,
        energy: None,
    };
    let fit = SideFit {
        impacts: law.n,
        dof,
        chi2_law: chi2_l,
        chi2_constant: chi2_c,
        scale,
        constant_r: beta_c[0],
        constant_u: (inv_c[(0, 0)] * c_scale).sqrt(),
        statistic,
        p_value,
        amplitude_min: law.a_min,
        amplitude_max: law.a_max,
        trend: beta[1] * g_span,
        trend_u,
        form_u: tau2.sqrt(),
        energy: None,
    };
    Ok((side, fit, (law.a_min, law.a_max)))
}

/// The speed-and-energy-loss form r = r∞ − c g − c₂ g² on the impacts of
/// `sides` (module docs, "A loss of energy too"): its own τ (Paule–Mandel), the
/// nested forms' χ² at that τ, the sandwich covariance of (r∞, c, c₂) scaled by
/// s² = max(1, χ²/ν), and whether the side applies it. None where fewer than
/// five impacts or the normal equations are singular.
fn fit_energy(tests: &[TestImpacts], sides: &[Side], shape: Shape) -> Option<(SideLaw, EnergyFit)> {
    let row = |a: f64| energy_row(shape, a);
    if normals_of(tests, sides, 3, &row, 0.0).n < 5 {
        return None;
    }
    let tau2 = form_variance_of(tests, sides, 3, &row);
    let three = normals_of(tests, sides, 3, &row, tau2);
    let (speed_loss, constant) = normals(tests, sides, shape, tau2);
    let (beta, inv, chi2) = three.solve()?;
    let (_, _, chi2_l) = speed_loss.solve()?;
    let (_, _, chi2_c) = constant.solve()?;
    let dof = three.n - 3;
    let scale = (chi2 / dof as f64).max(1.0);
    let cov: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| inv[(i, j)] * scale));
    let (g_lo, g_hi) = (shape.eval(three.a_max.max(AMPLITUDE_FLOOR)), shape.eval(three.a_min.max(AMPLITUDE_FLOOR)));
    if !(cov.iter().flatten().all(|x| x.is_finite()) && g_hi > g_lo) {
        return None;
    }
    let (r_inf, c, c2) = (beta[0], beta[1], beta[2]);
    // Akaike's criterion on the χ² scaled as the test's: k parameters cost 2k.
    let aic = |chi2: f64, k: f64| chi2 / scale + AIC_PENALTY * k;
    let preferred = aic(chi2, 3.0) < aic(chi2_l, 2.0) && aic(chi2, 3.0) < aic(chi2_c, 1.0);
    // A loss of energy (c₂ > 0), and r falling with g from g = 1 on: the slope
    // −c − 2 c₂ g is largest at g_lo (the tangent's below it).
    let loss = c2 > 0.0 && c + 2.0 * c2 * g_lo >= 0.0;
    let side = SideLaw {
        r_inf,
        c,
        cov: [[cov[0][0], cov[0][1]], [cov[1][0], cov[1][1]]],
        g: shape,
        energy: Some(EnergyLoss { c2, cov, g_lo, g_hi }),
    };
    let fit = EnergyFit {
        impacts: three.n,
        dof,
        chi2,
        chi2_speed_loss: chi2_l,
        chi2_constant: chi2_c,
        statistic: (chi2_l - chi2).max(0.0) / scale,
        c2,
        c2_u: cov[2][2].max(0.0).sqrt(),
        form_u: tau2.sqrt(),
        applied: preferred && loss,
    };
    Some((side, fit))
}

/// The campaign's law from its tests' impacts (module docs). The caller passes only
/// the tests the campaign vouches for (status ok, not excluded from the means).
pub fn fit_law(rocking: Rocking, tests: &[TestImpacts]) -> Result<LawFit, LawFitError> {
    if tests.is_empty() {
        return Err(LawFitError::NoTests);
    }
    if tests.iter().all(|t| t.table.r_cov.is_none()) {
        return Err(LawFitError::NoUncertainties);
    }
    // The sums run over the tests in the order of their ids, so that the law does
    // not depend on the manifest's order to the last bit (the energy term's F is a
    // difference of two χ² sums).
    let mut ordered = tests.to_vec();
    ordered.sort_by_key(|t| t.id);
    let (listed, tests) = (tests, &ordered[..]);
    let groups: Vec<(&'static str, Vec<Side>)> = match rocking {
        Rocking::TwoSided => vec![("both", vec![Side::Inward, Side::Outward])],
        Rocking::OneSided => vec![("in", vec![Side::Inward]), ("out", vec![Side::Outward])],
    };
    let mut fitted = Vec::new();
    let mut energy_laws = Vec::new();
    for (label, sides) in &groups {
        let shape = Shape::of(rocking, sides[sides.len() - 1]);
        let mut group = fit_group(tests, sides, shape, label)?;
        // Not on the inward side of a one-sided wall (module docs, "A loss of
        // energy too").
        let energy = (*label != "in").then(|| fit_energy(tests, sides, shape)).flatten();
        group.1.energy = energy.map(|e| e.1);
        energy_laws.push(energy.filter(|e| e.1.applied).map(|e| e.0));
        fitted.push((*label, group));
    }
    let (a_min, a_max) = fitted.iter().fold((1.0f64, 0.0f64), |(lo, hi), f| (lo.min(f.1 .2 .0), hi.max(f.1 .2 .1)));
    let level = ALPHA_TEST / fitted.len() as f64;
    // One-sided: the inward fit without each test's first impact (module docs,
    // "The inward side of a one-sided wall"): (c, F), or None where too few remain.
    let rise_after_release = (rocking == Rocking::OneSided)
        .then(|| {
            let tables: Vec<ImpactTable> = tests.iter().map(|t| t.table.after_release()).collect();
            let trimmed: Vec<TestImpacts> = tests.iter().zip(&tables).map(|(t, table)| TestImpacts { id: t.id, table }).collect();
            fit_group(&trimmed, &[Side::Inward], Shape::of(rocking, Side::Inward), "in").ok()
        })
        .flatten()
        .map(|(law, fit, _)| (law.c, fit.statistic));
    let last = fitted.len() - 1;
    let (fin, fout) = (fitted[0].1 .1, fitted[last].1 .1);
    // Where the inward r rises (c < 0) it is held below the inward side's own
    // smallest amplitude, not the campaign's (one-sided: the outward pushes').
    let inward_a_min = fitted[0].1 .2 .0.clamp(AMPLITUDE_FLOOR, 1.0);
    // Each side's own amplitudes (one-sided: the inward free arcs' and the
    // outward pushes'; two-sided: the shared group's on both), beyond which the
    // façade study counts a run's impacts as beyond the law's data.
    let range = |i: usize| {
        let (lo, hi) = fitted[i].1 .2;
        let lo = lo.clamp(AMPLITUDE_FLOOR, 1.0);
        [lo, hi.clamp(lo, 1.0)]
    };
    let observed = ObservedAmplitudes {
        inward: range(0),
        outward: range(last),
    };
    let parameters = |inward: SideLaw, outward: SideLaw| LawParameters {
        inward,
        outward,
        shared: rocking == Rocking::TwoSided,
        amplitude_min: a_min.clamp(AMPLITUDE_FLOOR, 1.0),
        amplitude_max: a_max.clamp(a_min.clamp(AMPLITUDE_FLOOR, 1.0), 1.0),
        inward_amplitude_min: (rocking == Rocking::OneSided && inward.c < 0.0).then_some(inward_a_min),
        observed: Some(observed),
        push_speed: None,
    };
    let speed_loss = RestitutionLaw {
        form: LawForm::SpeedLoss,
        parameters: parameters(fitted[0].1 .0, fitted[last].1 .0),
    };
    // A side keeps the speed-loss form where Akaike's criterion prefers it to the
    // constant and c > 0 (a loss), or, on the inward side of a one-sided wall, c < 0
    // (module docs); otherwise the constant (the nested model). The law is a
    // constant where no side keeps the form.
    let keeps = |i: usize| {
        let (law, fit, _) = &fitted[i].1;
        let rising_allowed = fitted[i].0 == "in" && rocking == Rocking::OneSided;
        let rise_favoured = fit.statistic > AIC_PENALTY && rise_after_release.is_some_and(|(c, f)| c < 0.0 && f > AIC_PENALTY);
        (fit.statistic > AIC_PENALTY && law.c > 0.0) || (rising_allowed && law.c < 0.0 && (fit.p_value < level || rise_favoured))
    };
    let chosen = |i: usize| {
        let (law, fit, _) = &fitted[i].1;
        match energy_laws[i] {
            Some(energy) => energy,
            None if keeps(i) => *law,
            None => SideLaw::constant(fit.constant_r, fit.constant_u),
        }
    };
    let rejects = fitted.iter().any(|f| f.1 .1.p_value < level);
    let form = if energy_laws.iter().any(Option::is_some) {
        LawForm::SpeedAndEnergyLoss
    } else if (0..fitted.len()).any(keeps) {
        LawForm::SpeedLoss
    } else {
        LawForm::Constant
    };
    let law = RestitutionLaw {
        form,
        parameters: parameters(chosen(0), chosen(last)),
    };
    let constant = RestitutionLaw {
        form: LawForm::Constant,
        parameters: parameters(
            SideLaw::constant(fin.constant_r, fin.constant_u),
            SideLaw::constant(fout.constant_r, fout.constant_u),
        ),
    };
    let sides: Vec<(String, SideFit)> = fitted.iter().map(|f| (f.0.to_string(), f.1 .1)).collect();
    let kept: Vec<bool> = (0..fitted.len()).map(|i| keeps(i) || energy_laws[i].is_some()).collect();
    Ok(LawFit {
        rejects_constant: rejects,
        notes: notes(&sides, &kept, level, rise_after_release),
        sides,
        law,
        speed_loss,
        constant,
        tests_used: listed.iter().filter(|t| t.table.r_cov.is_some()).map(|t| t.id.to_string()).collect(),
    })
}

/// What the law of each side cannot vouch for, in words for the report and
/// summary.json (`restitution_law.notes`): a side that keeps the speed-loss form
/// extrapolates below and above the amplitudes it was fitted on (bounded: r ≥ 0,
/// e ≤ 1, g(1) = 1); a side that keeps the constant says why (the data do not reject
/// it, and how large a trend they could have shown over how narrow a range; or the
/// fitted speed loss is negative) and that below its smallest amplitude the constant
/// is not vouched for: with compliant contacts r falls as the amplitude falls
/// (docs/restitution-law.md), and data that stop early cannot show it.
///
/// `rise_after_release`: one-sided walls, the inward fit without each test's first
/// impact, (c, F) ([`fit_law`]), so that a rise the release's impacts alone carry
/// says so.
pub fn notes(sides: &[(String, SideFit)], kept: &[bool], level: f64, rise_after_release: Option<(f64, f64)>) -> Vec<String> {
    sides
        .iter()
        .zip(kept)
        .map(|((name, f), &keeps)| {
            let range = format!("{} impacts over a = {:.4}–{:.3}", f.impacts, f.amplitude_min, f.amplitude_max);
            if let Some(e) = f.energy.filter(|e| e.applied) {
                return format!(
                    "side {name}: speed-and-energy-loss law fitted on {range}: the loss grows faster as the amplitude falls than a fixed loss of speed gives (a fixed loss of energy too, c₂ = {:.2e} ± {:.1e}; Akaike prefers it to the speed-loss form, F = {:.2}, and to the constant); below a = {:.4} and above a = {:.3} it is extrapolated along the curve's tangent there",
                    e.c2, e.c2_u, e.statistic, f.amplitude_min, f.amplitude_max
                );
            }
            // A kept form whose trend the test against a constant does not show.
            let unproven = if keeps && f.p_value >= level {
                format!(
                    "; the data do not reject a constant at the test's level (p = {:.3}), but the trend predicts them better (Akaike: F = {:.2} > {AIC_PENALTY})",
                    f.p_value, f.statistic
                )
            } else {
                String::new()
            };
            if keeps && f.trend < 0.0 {
                let p = if unproven.is_empty() {
                    format!(", p = {:.1e}", f.p_value)
                } else {
                    String::new()
                };
                return format!(
                    "side {name}: speed-loss law fitted on {range}, r rising as the amplitude falls (the push into the transverse walls: r at a = {:.4} {:+.3} ± {:.3} from r at a = {:.3}{p}){unproven}; below a = {:.4} it is held at its value there, above a = {:.3} it is extrapolated, and e = r e_H is capped at 1",
                    f.amplitude_min, -f.trend, f.trend_u, f.amplitude_max, f.amplitude_min, f.amplitude_max
                );
            }
            if keeps {
                return format!(
                    "side {name}: speed-loss law fitted on {range}{unproven}; below a = {:.4} and above a = {:.3} it is extrapolated",
                    f.amplitude_min, f.amplitude_max
                );
            }
            // An inward rise the data favour but do not show (one-sided: the only
            // side named "in"), refused by the release check of `fit_law`.
            let unshown_rise = name == "in" && f.trend < 0.0 && f.p_value >= level && f.statistic > AIC_PENALTY;
            let why = if unshown_rise {
                let favoured = format!(
                    "the data favour a rise of r as the amplitude falls (F = {:.2}, p = {:.3}; r at a = {:.4} {:+.3} ± {:.3} from r at a = {:.3})",
                    f.statistic, f.p_value, f.amplitude_min, -f.trend, f.trend_u, f.amplitude_max
                );
                match rise_after_release {
                    None => format!("{favoured}, but without each test's first impact (the release's, whose r₁ the paper sets apart) too few inward impacts remain to show that the rise outlives it, and a rise the release's impacts alone may carry is not taken for a law of amplitude"),
                    Some((c, stat)) => format!("{favoured}, but not without each test's first impact (the release's, whose r₁ the paper sets apart: c = {c:+.4}, F = {stat:.2}), and a rise the release's impacts alone carry is not taken for a law of amplitude"),
                }
            } else if f.statistic <= AIC_PENALTY {
                format!(
                    "the data do not reject a constant (p = {:.3}): the speed-loss fit puts r at a = {:.4} {:+.3} ± {:.3} from r at a = {:.3}, a trend the impacts' scatter cannot tell from none",
                    f.p_value, f.amplitude_min, -f.trend, f.trend_u, f.amplitude_max
                )
            } else {
                let shown = if f.p_value < level {
                    format!("the data reject a constant (p = {:.1e})", f.p_value)
                } else {
                    format!("the data favour a trend (F = {:.2}, p = {:.3})", f.statistic, f.p_value)
                };
                format!(
                    "{shown} but the fitted speed loss is negative (r at a = {:.4} {:+.3} ± {:.3} from r at a = {:.3}: rising as the amplitude falls), which the form does not describe",
                    f.amplitude_min, -f.trend, f.trend_u, f.amplitude_max
                )
            };
            format!(
                "side {name}: constant r = {:.4} ± {:.4} from {range}; {why}; below a = {:.4} the constant is not vouched for",
                f.constant_r, f.constant_u, f.amplitude_min
            )
        })
        .collect()
}

/// P(χ²(1) > x) = erfc(√(x/2)).
fn chi2_1_sf(x: f64) -> f64 {
    crate::stats::erfc((x / 2.0).sqrt())
}

/// P(F(d1, d2) > f) = I_{d2/(d2 + d1 f)}(d2/2, d1/2).
pub fn f_sf(f: f64, d1: f64, d2: f64) -> f64 {
    if f <= 0.0 {
        return 1.0;
    }
    beta_reg(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f))
}

/// ln Γ(x), Lanczos (Numerical Recipes §6.1), |error| < 2e-10 for x > 0.
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 6] = [
        76.18009172947146,
        -86.50532032941677,
        24.01409824083091,
        -1.231739572450155,
        0.1208650973866179e-2,
        -0.5395239384953e-5,
    ];
    let tmp = x + 5.5 - (x + 0.5) * (x + 5.5).ln();
    let ser = C.iter().enumerate().fold(1.000000000190015, |s, (j, c)| s + c / (x + 1.0 + j as f64));
    -tmp + (2.5066282746310005 * ser / x).ln()
}

/// The regularised incomplete beta function I_x(a, b) (Numerical Recipes §6.4).
pub fn beta_reg(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front = (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * x.ln() + b * (1.0 - x).ln()).exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

/// The continued fraction of I_x(a, b) by the modified Lentz method.
fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    d = 1.0 / if d.abs() < tiny { tiny } else { d };
    let mut h = d;
    for m in 1..300 {
        let m = m as f64;
        let m2 = 2.0 * m;
        for aa in [
            m * (b - m) * x / ((qam + m2) * (a + m2)),
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
        ] {
            d = 1.0 + aa * d;
            d = 1.0 / if d.abs() < tiny { tiny } else { d };
            c = 1.0 + aa / c;
            c = if c.abs() < tiny { tiny } else { c };
            h *= d * c;
            if aa == 0.0 {
                break;
            }
        }
        if (d * c - 1.0).abs() < 3e-15 {
            break;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::impacts::ImpactCoefficient;
    use crate::restitution_law::speed_shape;

    /// F(1, ν) = t²(ν): P(F(1, 10) > 4.9646) = 0.05 (tables: t₀.₉₇₅(10) = 2.2281);
    /// P(F(2, 20) > 3.4928) = 0.05; I_x(1, 1) = x.
    #[test]
    fn f_distribution_by_tables() {
        assert!((f_sf(2.228139f64.powi(2), 1.0, 10.0) - 0.05).abs() < 1e-5);
        assert!((f_sf(3.492828, 2.0, 20.0) - 0.05).abs() < 1e-5);
        assert!((beta_reg(1.0, 1.0, 0.3) - 0.3).abs() < 1e-12);
        assert!((chi2_1_sf(3.841459) - 0.05).abs() < 1e-6);
    }

    fn table(points: &[(f64, f64, Side)], u: f64) -> ImpactTable {
        let impacts = points
            .iter()
            .enumerate()
            .map(|(k, &(a, r, side))| ImpactCoefficient {
                k,
                side,
                amplitude_over_alpha: a,
                speed_before_mm_s: 1.0,
                speed_after_mm_s: r,
                e: r,
                e_u: Some(u),
                r,
                r_u: Some(u),
            })
            .collect::<Vec<_>>();
        let n = impacts.len();
        let cov = (0..n).map(|i| (0..n).map(|j| if i == j { u * u } else { 0.0 }).collect()).collect();
        ImpactTable {
            impacts,
            r_cov: Some(cov),
            raw: Vec::new(),
            end: None,
        }
    }

    /// No test vouched for is said as such, not as missing uncertainties.
    #[test]
    fn no_test_is_not_a_missing_uncertainty() {
        assert_eq!(fit_law(Rocking::OneSided, &[]).unwrap_err(), LawFitError::NoTests);
        let mut t = table(&[(0.3, 0.9, Side::Inward)], 0.01);
        t.r_cov = None;
        let e = fit_law(Rocking::OneSided, &[TestImpacts { id: "a", table: &t }]).unwrap_err();
        assert_eq!(e, LawFitError::NoUncertainties);
    }

    /// Exact data on the form are recovered exactly, and the constant is rejected;
    /// constant data (with scatter) are not.
    #[test]
    fn recovers_a_law_and_keeps_a_constant() {
        let amps = [0.3, 0.2, 0.12, 0.08, 0.05, 0.03, 0.02];
        let pts: Vec<(f64, f64, Side)> = amps.iter().map(|&a| (a, 1.02 - 0.03 * speed_shape(a), Side::Inward)).collect();
        let t = table(&pts, 0.003);
        let fit = fit_law(Rocking::TwoSided, &[TestImpacts { id: "a", table: &t }]).unwrap();
        let p = fit.law.parameters.inward;
        assert!((p.r_inf - 1.02).abs() < 1e-9 && (p.c - 0.03).abs() < 1e-9, "{p:?}");
        assert!(fit.rejects_constant, "{:?}", fit.sides);
        // The note flags where the law extrapolates; the trend is c (g(a_min) − g(a_max)).
        assert!(
            fit.notes[0].contains("below a = 0.0200 and above a = 0.300 it is extrapolated"),
            "{:?}",
            fit.notes
        );
        let f = fit.sides[0].1;
        assert!((f.trend - 0.03 * (speed_shape(0.02) - speed_shape(0.3))).abs() < 1e-9, "{f:?}");
        // A constant 0.9 with ±0.01 alternating scatter: no trend, the constant stands.
        let pts: Vec<(f64, f64, Side)> = amps
            .iter()
            .enumerate()
            .map(|(i, &a)| (a, 0.9 + 0.01 * if i % 2 == 0 { 1.0 } else { -1.0 }, Side::Inward))
            .collect();
        let t = table(&pts, 0.003);
        let fit = fit_law(Rocking::TwoSided, &[TestImpacts { id: "a", table: &t }]).unwrap();
        assert!(!fit.rejects_constant, "{:?}", fit.sides);
        assert!((fit.constant.parameters.inward.r_inf - 0.9).abs() < 0.005);
        // The band covers the scatter: the form's misfit τ is added to every u
        // (the ±0.01 scatter against u = 0.003), and χ²/ν is then 1.
        let f = fit.sides[0].1;
        assert!(f.form_u > 0.005 && f.form_u < 0.015, "{f:?}");
        assert!((f.chi2_law / f.dof as f64 - 1.0).abs() < 1e-6, "{f:?}");
        // The report says why the constant stands and that it is not vouched for
        // below the data.
        let note = &fit.notes[0];
        assert!(
            note.contains("do not reject") && note.contains("below a = 0.0200 the constant is not vouched for"),
            "{note}"
        );
        // A rising r (c < 0) keeps the constant, and says so.
        let pts: Vec<(f64, f64, Side)> = amps.iter().map(|&a| (a, 0.60 + 0.03 * speed_shape(a), Side::Inward)).collect();
        let t = table(&pts, 0.003);
        let fit = fit_law(Rocking::TwoSided, &[TestImpacts { id: "a", table: &t }]).unwrap();
        assert!(fit.rejects_constant && fit.law.form == LawForm::Constant);
        assert!(fit.notes[0].contains("negative"), "{:?}", fit.notes);
    }

    /// One-sided walls: an inward r that rises as the amplitude falls (the
    /// push into the transverse walls) is taken where the data reject the
    /// constant, held below the smallest amplitude observed, and e capped at 1;
    /// the outward side (impacts that end the push) still keeps the constant
    /// where its fitted speed loss is negative.
    #[test]
    fn a_one_sided_inward_r_rising_as_the_amplitude_falls_is_taken() {
        let amps = [0.4, 0.3, 0.2, 0.12, 0.08, 0.05, 0.03, 0.02];
        let mut pts: Vec<(f64, f64, Side)> = amps.iter().map(|&a| (a, 0.62 + 0.03 * speed_shape(a), Side::Inward)).collect();
        pts.extend(amps.iter().map(|&a| (a / 10.0, 0.60 + 0.01 * speed_shape(a / 10.0), Side::Outward)));
        let t = table(&pts, 0.003);
        let fit = fit_law(Rocking::OneSided, &[TestImpacts { id: "a", table: &t }]).unwrap();
        let inward = fit.law.parameters.inward;
        assert_eq!(fit.law.form, LawForm::SpeedLoss);
        assert!((inward.r_inf - 0.62).abs() < 1e-9 && (inward.c + 0.03).abs() < 1e-9, "{inward:?}");
        assert!(
            fit.notes[0].contains("rising as the amplitude falls") && fit.notes[0].contains("capped at 1"),
            "{:?}",
            fit.notes
        );
        // Held below the inward side's own data (a = 0.02), not the campaign's
        // smallest amplitude (the outward side's 0.002).
        assert_eq!(fit.law.parameters.inward_amplitude_min, Some(0.02));
        assert!((fit.law.parameters.amplitude_min - 0.002).abs() < 1e-12);
        // Each side's own amplitudes, as the façade study reads them.
        let (i, o) = (fit.law.observed(Side::Inward), fit.law.observed(Side::Outward));
        assert!((i.0 - 0.02).abs() < 1e-12 && (i.1 - 0.4).abs() < 1e-12, "{i:?}");
        assert!((o.0 - 0.002).abs() < 1e-12 && (o.1 - 0.04).abs() < 1e-12, "{o:?}");
        assert!((fit.law.r(Side::Inward, 0.005) - fit.law.r(Side::Inward, 0.02)).abs() < 1e-12);
        assert!((fit.law.r(Side::Inward, 0.02) - (0.62 + 0.03 * speed_shape(0.02))).abs() < 1e-9);
        assert!(fit.law.r(Side::Inward, 0.02) > fit.law.r(Side::Inward, 0.3));
        // e = r e_H never passes 1, even with an e_H that would carry it past.
        assert!(fit.law.e(Side::Inward, 0.002, 1.3) <= 1.0);
        // Outward, the same rising r keeps the constant (a speed gain at an impact on the base).
        assert_eq!(fit.law.parameters.outward.c, 0.0);
        assert!(fit.notes[1].contains("negative"), "{:?}", fit.notes);
        // Inward data that do not reject the constant keep it.
        let flat: Vec<(f64, f64, Side)> = pts
            .iter()
            .enumerate()
            .map(|(i, &(a, r, side))| {
                if side == Side::Inward {
                    (a, 0.66 + if i % 2 == 0 { 0.01 } else { -0.01 }, side)
                } else {
                    (a, r, side)
                }
            })
            .collect();
        let t = table(&flat, 0.003);
        let fit = fit_law(Rocking::OneSided, &[TestImpacts { id: "a", table: &t }]).unwrap();
        assert_eq!(fit.law.parameters.inward.c, 0.0, "{:?}", fit.sides);
    }

    /// One-sided outward impacts on r = r∞ − c/a (the push shape) give back r∞ and
    /// c exactly, and the law says so (`"g": "push"`); the inward side and every
    /// two-sided law keep 1/√(a(2 − a)). The same data fitted two-sided (the
    /// free-arc shape) miss them: the test can fail.
    #[test]
    fn a_one_sided_outward_push_law_recovers_c() {
        use crate::restitution_law::push_shape;
        let amps = [0.05, 0.04, 0.03, 0.02, 0.015, 0.01, 0.007];
        let mut pts: Vec<(f64, f64, Side)> = amps.iter().map(|&a| (a * 8.0, 0.66, Side::Inward)).collect();
        pts.iter_mut().enumerate().for_each(|(i, p)| p.1 += if i % 2 == 0 { 0.01 } else { -0.01 });
        pts.extend(amps.iter().map(|&a| (a, 1.05 - 0.004 * push_shape(a), Side::Outward)));
        let t = table(&pts, 0.003);
        let fit = fit_law(Rocking::OneSided, &[TestImpacts { id: "a", table: &t }]).unwrap();
        let out = fit.law.parameters.outward;
        assert_eq!(out.g, Shape::Push);
        assert!((out.r_inf - 1.05).abs() < 1e-9 && (out.c - 0.004).abs() < 1e-9, "{out:?}");
        assert!((fit.law.r(Side::Outward, 0.012) - (1.05 - 0.004 / 0.012)).abs() < 1e-9);
        assert_eq!(fit.law.parameters.inward.g, Shape::Free);
        let f = fit.sides[1].1;
        assert!((f.trend - 0.004 * (push_shape(0.007) - push_shape(0.05))).abs() < 1e-9, "{f:?}");
        let two = fit_law(
            Rocking::TwoSided,
            &[TestImpacts {
                id: "a",
                table: &table(&pts[7..], 0.003),
            }],
        )
        .unwrap();
        assert_eq!(two.speed_loss.parameters.inward.g, Shape::Free);
        assert!(
            (two.speed_loss.parameters.inward.c - 0.004).abs() > 1e-3,
            "{:?}",
            two.speed_loss.parameters.inward
        );
    }

    /// A speed loss the data favour (Akaike: F > 2) but do not show at the test's
    /// level is the law the campaign applies, and its note says so; below F = 2 the
    /// constant. The trend is scanned upwards from zero until F passes each bound.
    #[test]
    fn a_trend_the_data_favour_is_applied_without_rejecting_the_constant() {
        let amps = [0.3, 0.2, 0.12, 0.08, 0.05, 0.03, 0.02];
        let fit_of = |c: f64| {
            let pts: Vec<(f64, f64, Side)> = amps
                .iter()
                .enumerate()
                .map(|(i, &a)| (a, 0.9 - c * speed_shape(a) + if i % 2 == 0 { 0.01 } else { -0.01 }, Side::Inward))
                .collect();
            fit_law(
                Rocking::TwoSided,
                &[TestImpacts {
                    id: "a",
                    table: &table(&pts, 0.003),
                }],
            )
            .unwrap()
        };
        let fits: Vec<LawFit> = (0..200).map(|i| fit_of(1e-4 * i as f64)).collect();
        let below = fits
            .iter()
            .find(|f| f.sides[0].1.statistic > 0.5 && f.sides[0].1.statistic < AIC_PENALTY)
            .unwrap();
        assert_eq!(below.law.form, LawForm::Constant, "{:?}", below.sides);
        assert!(below.notes[0].contains("the data do not reject a constant"), "{:?}", below.notes);
        let favoured = fits.iter().find(|f| f.sides[0].1.statistic > AIC_PENALTY).unwrap();
        let side = favoured.sides[0].1;
        assert!(side.p_value > ALPHA_TEST && !favoured.rejects_constant, "{side:?}");
        assert_eq!(favoured.law.form, LawForm::SpeedLoss);
        assert!(favoured.law.parameters.inward.c > 0.0);
        assert!(
            favoured.notes[0].contains("the data do not reject a constant at the test's level") && favoured.notes[0].contains("Akaike"),
            "{:?}",
            favoured.notes
        );
    }

    /// The law of a one-sided campaign of the two tests `a` and `b`.
    fn fit_two_one_sided(a: &ImpactTable, b: &ImpactTable) -> LawFit {
        fit_law(Rocking::OneSided, &[TestImpacts { id: "a", table: a }, TestImpacts { id: "b", table: b }]).unwrap()
    }

    /// The inward side favours the form (Akaike) but does not reject the constant
    /// at the level of a test of two sides.
    fn weak(f: &LawFit) -> bool {
        f.sides[0].1.statistic > AIC_PENALTY && f.sides[0].1.p_value > ALPHA_TEST / 2.0
    }

    /// One-sided, inward: a rise that only the release's impacts carry (each test's
    /// first impact low, the paper's r₁) is not taken for a law of amplitude unless
    /// the test rejects the constant; a rise the data favour without them is.
    #[test]
    fn a_weak_inward_rise_is_taken_only_where_it_outlives_the_release() {
        let amps = [0.4, 0.3, 0.2, 0.12, 0.08, 0.05, 0.03, 0.02];
        let outward: Vec<(f64, f64, Side)> = amps.iter().map(|&a| (a / 10.0, 0.9, Side::Outward)).collect();
        let test = |rise: f64, first_low: f64, flip: bool| {
            let mut pts: Vec<(f64, f64, Side)> = amps
                .iter()
                .enumerate()
                .map(|(i, &a)| {
                    let noise = if (i % 2 == 0) ^ flip { 0.02 } else { -0.02 };
                    (
                        a,
                        0.62 + rise * speed_shape(a) + noise - if i == 0 { first_low } else { 0.0 },
                        Side::Inward,
                    )
                })
                .collect();
            pts.extend(outward.iter().copied());
            table(&pts, 0.003)
        };
        let fit_of = |rise: f64, first_low: f64| fit_two_one_sided(&test(rise, first_low, false), &test(rise, first_low, true));
        // The first impacts alone low: the speed-loss fit rises, favoured but not shown.
        let release = (1..100).map(|i| fit_of(0.0, 0.005 * i as f64)).find(weak).unwrap();
        assert!(release.speed_loss.parameters.inward.c < 0.0, "{:?}", release.sides);
        assert_eq!(release.law.parameters.inward.c, 0.0, "{:?}", release.sides);
        assert!(
            release.notes[0].contains("but not without each test's first impact"),
            "{:?}",
            release.notes
        );
        // A rise over every impact is taken before the test shows it.
        let rise = (1..200)
            .map(|i| fit_of(1e-3 * i as f64, 0.0))
            .find(|f| f.law.parameters.inward.c < 0.0)
            .unwrap();
        assert!(weak(&rise), "{:?}", rise.sides);
        assert!(rise.notes[0].contains("Akaike"), "{:?}", rise.notes);
    }

    /// Where too few inward impacts remain without each test's first impact for the
    /// release check, a rise the data favour but do not show is refused, and the
    /// note says why (it read "the fitted speed loss is negative …, which the form
    /// does not describe" before the thirty-fourth session, though the inward form
    /// takes rises).
    #[test]
    fn a_rise_the_release_check_cannot_test_is_refused_in_words() {
        let outward: Vec<(f64, f64, Side)> = [0.04, 0.03, 0.02, 0.01].iter().map(|&a| (a, 0.9, Side::Outward)).collect();
        let test = |rise: f64, flip: bool| {
            let noise = if flip { 0.02 } else { -0.02 };
            let mut pts = vec![
                (0.4, 0.62 + rise * speed_shape(0.4) + noise, Side::Inward),
                (0.05, 0.62 + rise * speed_shape(0.05) - noise, Side::Inward),
            ];
            pts.extend(outward.iter().copied());
            table(&pts, 0.003)
        };
        let fit_of = |rise: f64| fit_two_one_sided(&test(rise, false), &test(rise, true));
        let fit = (1..400)
            .map(|i| fit_of(1e-3 * i as f64))
            .find(|f| weak(f) && f.speed_loss.parameters.inward.c < 0.0);
        let fit = fit.expect("a rise favoured but not shown");
        assert_eq!(fit.law.parameters.inward.c, 0.0, "{:?}", fit.sides);
        assert!(fit.notes[0].contains("too few inward impacts remain"), "{:?}", fit.notes);
        assert!(!fit.notes[0].contains("which the form does not describe"), "{:?}", fit.notes);
    }

    /// A random two-sided campaign: 4 tests of 8 impacts at amplitudes spread
    /// evenly in ln a over 0.01–0.4, each test offset by N(0, 0.01) (its bedding),
    /// each impact's r = `truth`(a) + offset + N(0, u²), u uniform in 0.01–0.03.
    fn random_campaign(rng: &mut crate::stats::SplitMix64, truth: &dyn Fn(f64) -> f64) -> Vec<ImpactTable> {
        (0..4)
            .map(|_| {
                let offset = 0.01 * rng.normal();
                let pts: Vec<(f64, f64, f64)> = (0..8)
                    .map(|_| {
                        let a = (0.01f64.ln() + rng.uniform() * (0.4f64 / 0.01).ln()).exp();
                        let u = 0.01 + 0.02 * rng.uniform();
                        (a, truth(a) + offset + u * rng.normal(), u)
                    })
                    .collect();
                let mut t = table(&pts.iter().map(|p| (p.0, p.1, Side::Inward)).collect::<Vec<_>>(), 0.01);
                let cov = t.r_cov.as_mut().unwrap();
                pts.iter().enumerate().for_each(|(i, p)| cov[i][i] = p.2 * p.2);
                t
            })
            .collect()
    }

    /// Random campaigns as above whose truth also loses energy, r = 0.85 −
    /// 0.005 g − c₂ g² (400 each): under the speed-loss truth alone (c₂ = 0) the
    /// term is applied on 0.0 % (asserted: below 5 %); at c₂ = 0.002 on 37 %, and
    /// the law is closer to the truth than the speed-loss form fitted beside it
    /// (RMS 0.0074 against 0.0079); at c₂ = 0.005 on 90 % (asserted: more than
    /// half), 0.0076 against 0.0135.
    #[test]
    fn the_energy_term_follows_a_real_energy_loss_and_rarely_appears_without_one() {
        let mut rng = crate::stats::SplitMix64::new(37);
        let n = 400;
        let mut run = |c2: f64| {
            let truth = |a: f64| 0.85 - 0.005 * speed_shape(a) - c2 * speed_shape(a).powi(2);
            let (mut applied, mut law, mut speed_loss) = (0usize, 0.0, 0.0);
            for _ in 0..n {
                let tables = random_campaign(&mut rng, &truth);
                let input: Vec<TestImpacts> = tables.iter().map(|t| TestImpacts { id: "t", table: t }).collect();
                let fit = fit_law(Rocking::TwoSided, &input).unwrap();
                applied += usize::from(fit.law.form == LawForm::SpeedAndEnergyLoss);
                let rms = |l: &RestitutionLaw| {
                    let e: Vec<f64> = tables
                        .iter()
                        .flat_map(|t| t.impacts.iter().map(|i| i.amplitude_over_alpha))
                        .map(|a| l.r(Side::Inward, a) - truth(a))
                        .collect();
                    (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt()
                };
                law += rms(&fit.law) / n as f64;
                speed_loss += rms(&fit.speed_loss) / n as f64;
            }
            (applied as f64 / n as f64, law, speed_loss)
        };
        let none = run(0.0);
        let weak = run(0.002);
        let strong = run(0.005);
        for (c2, r) in [(0.0, none), (0.002, weak), (0.005, strong)] {
            println!(
                "c₂ = {c2}: the term applied on {:.1} %, law RMS {:.4} (speed-loss form {:.4})",
                100.0 * r.0,
                r.1,
                r.2
            );
        }
        assert!(none.0 < 0.05, "{none:?}");
        assert!(weak.1 < weak.2, "{weak:?}");
        assert!(strong.0 > 0.5 && strong.1 < strong.2, "{strong:?}");
    }

    /// Random campaigns (4 tests of 8 impacts, a = 0.01–0.4 log-uniform, u 0.01–0.03,
    /// a test-to-test spread of 0.01): where r does not depend on the amplitude the
    /// law applies a spurious loss on few of them (Akaike's F > 2 with c > 0: about
    /// 8 % expected; asserted 3–13 %), and where it falls as r = 0.85 − 0.005 g(a)
    /// (0.029 across the range) the applied law is closer to the truth than under the
    /// test's level (mean RMS over the impacts' amplitudes). Measured: no trend, the
    /// form applied on 9.8 %, RMS 0.0052 against 0.0049 under the test's level; the
    /// loss, applied on 79.8 %, RMS 0.0066 against 0.0085 (0.003 g(a): 51.5 %,
    /// 0.0067 against 0.0073).
    #[test]
    fn akaike_keeps_few_spurious_losses_and_follows_real_ones() {
        // (a form applied, its RMS, the test's level's RMS, the energy term applied)
        type Draw = (bool, f64, f64, bool);
        let mut rng = crate::stats::SplitMix64::new(33);
        let mut draw = |c_true: f64| {
            let tables = random_campaign(&mut rng, &|a| 0.85 - c_true * speed_shape(a));
            let input: Vec<TestImpacts> = tables.iter().map(|t| TestImpacts { id: "t", table: t }).collect();
            let fit = fit_law(Rocking::TwoSided, &input).unwrap();
            let side = fit.sides[0].1;
            let old = if side.p_value < ALPHA_TEST && fit.speed_loss.parameters.inward.c > 0.0 {
                fit.speed_loss
            } else {
                fit.constant
            };
            let rms = |law: &RestitutionLaw| {
                let e: Vec<f64> = tables
                    .iter()
                    .flat_map(|t| t.impacts.iter().map(|i| i.amplitude_over_alpha))
                    .map(|a| law.r(Side::Inward, a) - (0.85 - c_true * speed_shape(a)))
                    .collect();
                (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt()
            };
            (
                fit.law.form != LawForm::Constant,
                rms(&fit.law),
                rms(&old),
                fit.law.form == LawForm::SpeedAndEnergyLoss,
            )
        };
        let n = 400;
        let null: Vec<Draw> = (0..n).map(|_| draw(0.0)).collect();
        let trend: Vec<Draw> = (0..n).map(|_| draw(0.005)).collect();
        let share = |d: &[Draw]| d.iter().filter(|x| x.0).count() as f64 / n as f64;
        let energy = |d: &[Draw]| d.iter().filter(|x| x.3).count() as f64 / n as f64;
        let mean = |d: &[Draw], k: usize| d.iter().map(|x| if k == 1 { x.1 } else { x.2 }).sum::<f64>() / n as f64;
        println!(
            "no trend: form applied on {:.1} % (the energy term on {:.1} %), RMS {:.4} (test's level {:.4}); loss 0.005 g(a): applied on {:.1} % (energy {:.1} %), RMS {:.4} (test's level {:.4})",
            100.0 * share(&null),
            100.0 * energy(&null),
            mean(&null, 1),
            mean(&null, 2),
            100.0 * share(&trend),
            100.0 * energy(&trend),
            mean(&trend, 1),
            mean(&trend, 2)
        );
        assert!((0.03..0.13).contains(&share(&null)), "{}", share(&null));
        assert!(mean(&trend, 1) < mean(&trend, 2));
    }

    #[test]
    fn too_few_impacts_is_an_error() {
        let t = table(&[(0.3, 0.9, Side::Inward), (0.2, 0.9, Side::Inward)], 0.01);
        let e = fit_law(Rocking::TwoSided, &[TestImpacts { id: "a", table: &t }]).unwrap_err();
        assert!(matches!(e, LawFitError::TooFewImpacts { n: 2, .. }), "{e}");
    }

    /// A loss that grows as g² besides g (r = 1 − 0.01 g − 0.02 g², exact) is
    /// applied and recovered; the inward side of a one-sided wall is never given
    /// the term; a curvature that makes r rise at large amplitudes, or an energy
    /// gain (c₂ < 0), is fitted but not applied.
    #[test]
    fn a_loss_of_energy_is_applied_where_akaike_prefers_it_and_it_is_a_loss() {
        let amps = [0.3, 0.2, 0.12, 0.08, 0.05, 0.03, 0.02];
        let on = |f: &dyn Fn(f64) -> f64, side: Side| amps.iter().map(|&a| (a, f(speed_shape(a)), side)).collect::<Vec<_>>();
        let two_sided = |f: &dyn Fn(f64) -> f64| {
            let t = table(&on(f, Side::Inward), 0.003);
            fit_law(Rocking::TwoSided, &[TestImpacts { id: "a", table: &t }]).unwrap()
        };
        let fit = two_sided(&|g| 1.0 - 0.01 * g - 0.02 * g * g);
        assert_eq!(fit.law.form, LawForm::SpeedAndEnergyLoss);
        let p = fit.law.parameters.inward;
        let e = p.energy.unwrap();
        assert!(
            (p.r_inf - 1.0).abs() < 1e-9 && (p.c - 0.01).abs() < 1e-9 && (e.c2 - 0.02).abs() < 1e-9,
            "{p:?}"
        );
        assert!((e.g_lo - speed_shape(0.3)).abs() < 1e-12 && (e.g_hi - speed_shape(0.02)).abs() < 1e-12);
        assert!(fit.sides[0].1.energy.unwrap().applied);
        assert!(fit.notes[0].contains("speed-and-energy-loss law fitted on 7 impacts"), "{:?}", fit.notes);
        assert_eq!(fit.law.parameters.outward, p);
        // Rising with g at the largest amplitudes (slope 0.1 − 0.04 g > 0 at g(0.3) = 1.40).
        let fit = two_sided(&|g| 0.9 + 0.1 * g - 0.02 * g * g);
        assert!(fit.law.form != LawForm::SpeedAndEnergyLoss && !fit.sides[0].1.energy.unwrap().applied);
        // An energy gain.
        let fit = two_sided(&|g| 1.0 - 0.08 * g + 0.005 * g * g);
        assert_eq!(fit.law.form, LawForm::SpeedLoss);
        assert!(fit.sides[0].1.energy.unwrap().c2 < 0.0);
        // One-sided: the inward side's curvature is not fitted; the outward's is.
        let mut pts = on(&|g| 0.6 + 0.05 * g - 0.01 * g * g, Side::Inward);
        // Outward: amplitudes a/10, the push's g = 1/a: r = 1 − 2·10⁻⁴ g − 10⁻⁶ g².
        pts.extend(
            amps.iter()
                .map(|&a| (a / 10.0, 1.0 - 2e-4 * 10.0 / a - 1e-6 * (10.0 / a).powi(2), Side::Outward)),
        );
        let t = table(&pts, 0.003);
        let fit = fit_law(Rocking::OneSided, &[TestImpacts { id: "a", table: &t }]).unwrap();
        assert!(fit.sides[0].1.energy.is_none() && fit.law.parameters.inward.energy.is_none());
        let out = fit.law.parameters.outward;
        assert_eq!(out.g, Shape::Push);
        assert!((out.energy.unwrap().c2 - 1e-6).abs() < 1e-12 && (out.c - 2e-4).abs() < 1e-9, "{out:?}");
    }
}

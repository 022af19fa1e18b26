//! The restitution law of a campaign: r = e/e_H of an impact as a function of the
//! dimensionless amplitude a = |θ|/α at the apex of the half-cycle that the impact ends
//! (SPEC, "Per-impact coefficients and the restitution law"), one law per side.
//!
//! # The form: a fixed loss of angular speed per impact ("speed-loss")
//!
//!   r(a) = r∞ − c · g(a),   g(a) = 1 / √(a (2 − a)),
//!
//! with the two parameters (r∞, c) per side and their covariance. The outward side of
//! a one-sided wall uses g(a) = 1/a instead ([`Shape::Push`], `"g": "push"` in its
//! parameters): its impacts end the inward half-cycle, a push against the transverse
//! walls' spring, where the speed is proportional to the amplitude (ω⁻ ∝ a), so the
//! same fixed Δω gives r = r∞ − c/a. A side without `"g"` is the free arc below.
//!
//! Why this form. Housner's impact (paper Eq. 2) takes a fixed *fraction* of the
//! angular speed: ω⁺ = e ω⁻, so e does not depend on the amplitude. A real contact
//! is compliant: the impact lasts a finite time τ (tens of ms on the engine-made
//! campaigns, growing as the amplitude falls) during which the contact dissipates and
//! gravity's moment about the new pivot still acts. To first order that removes, on
//! top of the proportional loss, a roughly fixed amount of angular speed Δω per impact
//! (of the order of p² α τ):
//!
//!   ω⁺ = e∞ ω⁻ − Δω   ⇒   e = e∞ − Δω / ω⁻.
//!
//! In free rocking (paper Eq. 1 without ground motion) the energy of a half-cycle with
//! apex θ_m = a α gives the speed at θ = 0: ω⁻² = 2 p² (cos(α − θ_m) − cos α), which
//! for small α is p² α² a (2 − a). So 1/ω⁻ = g(a) / (p α), and dividing by e_H:
//! r(a) = r∞ − c g(a) with c = Δω / (p α e_H), a dimensionless speed loss in units of
//! the wall's own p α. Written in a and r it carries from the tested wall to another
//! wall as the paper carries r to the façade.
//!
//! The data agree, within what a law of amplitude alone can do. On the engine's own
//! per-impact truth (`cargo test --test law law_form -- --nocapture`; four MuJoCo
//! campaigns, two walls per rocking type, every listed impact down to a = 0.006):
//! - Two-sided, public wall: this form fitted to the truth is within RMS 0.013 of it
//!   over a = 0.024 … 0.36 (the best constant: 0.080). r − r∞ against g, g² (a fixed
//!   *energy* loss), ln a: g fits best of the two-parameter forms (g² 0.014, ln a 0.027).
//! - One-sided outward: 0.015 over a = 0.006 … 0.034 (constant 0.076).
//! - Each test alone follows r∞ − c g^q to ±0.002 with q from 1.3 to 2.9: the contact
//!   lasts longer as the impact speed falls (30 → 69 ms two-sided), so the speed lost
//!   grows faster than a fixed Δω (q = 1 is a fixed speed loss, q = 2 a fixed energy
//!   loss). The exponent depends on the bedding (1.3–1.5 on the public wall, 2.7–2.9
//!   on the hold-out's softer one) and varies from test to test with it, as c does; what a campaign law misses (hold-out two-sided: 0.044) is mostly that
//!   spread of the tests, which no law of amplitude alone can follow.
//! - Why q = 1 and not a fitted q: fitted to the largest 60 % of the amplitudes and
//!   read below them, a free q runs to its bound and misses by up to RMS 0.28 (q = 1:
//!   at most 0.11, and then on the high side: r read too high keeps more energy, the
//!   safe side for a façade near overturning). The law must extrapolate.
//! - Inward in one-sided rocking the transverse walls take a third of the speed at
//!   every amplitude and differ from test to test (r 0.60–0.75): the fit keeps a
//!   constant there, and even the three-parameter g^q leaves RMS 0.030 on the truth.
//!
//! A constant is the nested case c = 0 (form `"constant"`, [`RestitutionLaw::constant`]);
//! the fit ([`crate::law_fit`]) says whether the data reject it. A two-sided campaign
//! fits one law for both sides (`shared`: in and out are equal and drawn together).
//!
//! # A loss of energy too (form `"speed-and-energy-loss"`, thirty-seventh session)
//!
//!   r(a) = r∞ − c g(a) − c₂ q(g(a)),   q(g) = g² over the side's observed g,
//!
//! and the tangent of g² beyond them ([`EnergyLoss`]). A compliant contact that
//! lasts longer as the impact speed falls loses more than a fixed Δω: each test
//! follows r∞ − c g^q with q 1.3–2.9 (above). The next term of the loss in powers of
//! 1/ω⁻ is a fixed loss of *energy* ΔE per impact: ω⁺² = e∞² ω⁻² − 2ΔE/I₀ gives
//! e ≈ e∞ − ΔE/(I₀ e∞ ω⁻²), a term in g². The three losses (proportional, speed,
//! energy) nest: c₂ = 0 is the speed-loss law, c = c₂ = 0 the constant. The fit
//! ([`crate::law_fit`], "A loss of energy too") applies the term only where
//! Akaike's criterion prefers it to both nested forms, c₂ > 0 (a loss), and r falls
//! with g from g = 1 on (c + 2 c₂ g_lo ≥ 0), so the law stays monotone in a and its
//! extrapolation above the data is the tangent's, a short step (g(a_max) ≈ 1.1–1.4
//! on the free arc). The 3×3 covariance of (r∞, c, c₂) gives u(r) and the draws;
//! the side's `cov` is its upper-left block.
//!
//! # Range
//! Above the largest amplitude the campaign observed the form extrapolates to a = 1,
//! where g is bounded (g(1) = 1), which is what a façade near overturning needs.
//! Below the smallest (`amplitude_min`) it extrapolates where r falls with the
//! amplitude (c ≥ 0: the fixed speed loss brings the wall to rest, as it does; r is
//! never below 0) and holds its value at `amplitude_min` where r would rise without
//! bound (c < 0; on the inward side of a one-sided wall, at the smallest amplitude
//! of its own impacts, `inward_amplitude_min`, where it is given). [`RestitutionLaw::e`]
//! caps e = r e_H at 1.
//!
//! # Reading a law by the impact's speed
//! The law is written in the amplitude, and the solver reads it at the apex of the
//! half-cycle an impact ends (SPEC). Its form is a loss of speed, e = e∞ − Δω/ω⁻,
//! and in free rocking of the test wall ω⁻ follows from the amplitude: on a free
//! arc ŵ = ω⁻/(p α) = √(a (2 − a)) (small α), after a push ŵ = (Ω/p) a with Ω the
//! push's angular frequency, which carries the test wall's restraint. On another
//! wall, or under ground motion, ω⁻ no longer follows from the apex. A façade study
//! may then read the law at the amplitude whose campaign impact had the same ŵ
//! ([`LawReading::Speed`], [`RestitutionLaw::amplitude_at_speed`]):
//! - free arc: a = 1 − arccos(cos α + ŵ² α²/2)/α, the exact inverse of the block's
//!   free-rocking energy (1 where ŵ exceeds the fall from a = 1), so that in free
//!   rocking both readings agree;
//! - push: a = ŵ/(Ω/p)_campaign, with the campaign's median ŵ/a over the outward
//!   impacts its law was fitted on ([`PushSpeed`], `parameters.push_speed`,
//!   measured by `reduce` from each impact's speed before and amplitude; the law
//!   by replay of `calibrate` carries the same). Where a law has sides fitted
//!   apart, an outward side that changes with the amplitude and no Ω/p, whether
//!   its outward impacts end pushes cannot be told, and it is not read by speed
//!   ([`RestitutionLaw::readable_by_speed`]).
//!
//! What it assumes: the lost Δω scales with the wall's own p α (c is dimensionless
//! in those units), and a push's ŵ/a is one number (on the public one-sided
//! campaign its 13 pushes give 13.5–18.0 around a median 16.9: the gravity term
//! and the compliant restraint make it vary). Neither reading can be checked
//! against measured impacts of a façade; docs/facade.md, "Reading the law by the
//! impact's speed", gives what the choice does to the demo's verdicts.
//!
//! # Uncertainty and draws
//! u(r(a))² = ∇ᵀ Σ ∇ with ∇ = (1, −g(a)) and Σ the side's 2×2 covariance of (r∞, c)
//! (with the energy term ∇ = (1, −g, −q(g)) and its 3×3 covariance).
//! [`RestitutionLaw::sample`] draws the parameters as mean + L z with L Σ's Cholesky
//! factor and z standard normals given by the caller (the core stays deterministic).

use crate::wall::Side;

/// How r depends on the amplitude.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LawForm {
    /// r = r∞ (c = 0): Housner's proportional loss, the paper's constant pair.
    Constant,
    /// r = r∞ − c / √(a (2 − a)): a proportional loss plus a fixed speed loss.
    SpeedLoss,
    /// r = r∞ − c g − c₂ g² on some side ([`EnergyLoss`]): a fixed loss of energy
    /// per impact besides the speed loss (module docs, "A loss of energy too").
    SpeedAndEnergyLoss,
}

impl LawForm {
    pub fn as_str(self) -> &'static str {
        match self {
            LawForm::Constant => "constant",
            LawForm::SpeedLoss => "speed-loss",
            LawForm::SpeedAndEnergyLoss => "speed-and-energy-loss",
        }
    }
}

/// The shape g(a) of one side's speed loss (`"g"` in a side's parameters;
/// absent = [`Shape::Free`], so laws written before it read as they did).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shape {
    /// g(a) = 1/√(a (2 − a)): the impact ends a free (gravity) arc, ω⁻ ∝ √(a(2 − a)).
    #[default]
    Free,
    /// g(a) = 1/a: the impact ends a push against a spring (the outward impacts of a
    /// one-sided wall end the inward half-cycle, pushed back by the transverse walls):
    /// ω⁻ ∝ a, so a fixed Δω gives r = r∞ − c/a (g(1) = 1 as for the free arc).
    Push,
}

impl Shape {
    /// g(a) for a in (0, 1].
    pub fn eval(self, a: f64) -> f64 {
        match self {
            Shape::Free => speed_shape(a),
            Shape::Push => push_shape(a),
        }
    }

    /// The shape a fit uses on `side` of a wall rocking `rocking`: the push on the
    /// outward side of a one-sided wall, the free arc everywhere else.
    pub fn of(rocking: crate::wall::Rocking, side: Side) -> Shape {
        match (rocking, side) {
            (crate::wall::Rocking::OneSided, Side::Outward) => Shape::Push,
            _ => Shape::Free,
        }
    }

    pub fn is_free(&self) -> bool {
        *self == Shape::Free
    }

    /// The amplitude a ∈ (0, 1] at which g(a) = `g` (g ≥ 1): a(2 − a) = 1/g² on
    /// the free arc, a = 1/g for the push.
    pub fn eval_inverse(self, g: f64) -> f64 {
        match self {
            Shape::Free => 1.0 - (1.0 - 1.0 / (g * g)).max(0.0).sqrt(),
            Shape::Push => 1.0 / g,
        }
    }
}

/// The parameters of one side: r∞, c and their covariance [[var r∞, cov], [cov, var c]],
/// and the shape g of the speed loss.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SideLaw {
    pub r_inf: f64,
    pub c: f64,
    pub cov: [[f64; 2]; 2],
    #[serde(default, skip_serializing_if = "Shape::is_free")]
    pub g: Shape,
    /// The energy-loss term c₂ q(g) and the covariance of (r∞, c, c₂), where the
    /// side applies it (form `"speed-and-energy-loss"`); absent otherwise, so laws
    /// written before it read and give the same r bit for bit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy: Option<EnergyLoss>,
}

/// A fixed loss of energy per impact on one side (module docs, "A loss of energy
/// too"): r = r∞ − c g − c₂ q(g), q(g) = g² over the side's observed shapes
/// [g_lo, g_hi] and its tangent outside them (2 g_e g − g_e² beyond the edge g_e),
/// so that the law extrapolates as the speed-loss form does, from the edge's slope.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnergyLoss {
    pub c2: f64,
    /// Covariance of (r∞, c, c₂); its upper-left block is the side's `cov`.
    pub cov: [[f64; 3]; 3],
    /// g at the side's largest and smallest observed amplitudes.
    pub g_lo: f64,
    pub g_hi: f64,
}

impl EnergyLoss {
    /// q(g): g² on [g_lo, g_hi], the tangent of g² at the nearer edge outside.
    pub fn q(&self, g: f64) -> f64 {
        let e = g.clamp(self.g_lo, self.g_hi);
        2.0 * e * g - e * e
    }
}

impl SideLaw {
    /// A constant r with standard uncertainty u (c = 0 exactly, no uncertainty on c).
    pub fn constant(r: f64, u: f64) -> SideLaw {
        SideLaw {
            r_inf: r,
            c: 0.0,
            cov: [[u * u, 0.0], [0.0, 0.0]],
            g: Shape::Free,
            energy: None,
        }
    }

    /// r∞ − c g − c₂ q(g), not clamped.
    fn value(&self, g: f64) -> f64 {
        let energy = self.energy.as_ref().map_or(0.0, |e| e.c2 * e.q(g));
        self.r_inf - self.c * g - energy
    }

    /// dr/dg at g (the side's r falls as the amplitude falls where it is negative).
    fn slope(&self, g: f64) -> f64 {
        let energy = self.energy.as_ref().map_or(0.0, |e| 2.0 * e.c2 * g.clamp(e.g_lo, e.g_hi));
        -self.c - energy
    }

    /// u(r) = √(∇ᵀ Σ ∇), ∇ = (1, −g) or (1, −g, −q(g)).
    fn u(&self, g: f64) -> f64 {
        match &self.energy {
            None => {
                let s = &self.cov;
                (s[0][0] - 2.0 * g * s[0][1] + g * g * s[1][1]).max(0.0).sqrt()
            }
            Some(e) => {
                let d = [1.0, -g, -e.q(g)];
                let v: f64 = (0..3)
                    .flat_map(|i| (0..3).map(move |j| (i, j)))
                    .map(|(i, j)| d[i] * e.cov[i][j] * d[j])
                    .sum();
                v.max(0.0).sqrt()
            }
        }
    }

    /// mean + L z, L the lower Cholesky factor of the covariance (a singular or
    /// zero covariance gives zero rows, so a constant law draws only r∞).
    fn sample(&self, z: [f64; 3]) -> SideLaw {
        match &self.energy {
            None => {
                let (l00, l10, l11) = cholesky2(&self.cov);
                SideLaw {
                    r_inf: self.r_inf + l00 * z[0],
                    c: self.c + l10 * z[0] + l11 * z[1],
                    cov: [[0.0; 2]; 2],
                    g: self.g,
                    energy: None,
                }
            }
            Some(e) => {
                let l = cholesky3(&e.cov);
                let dx: Vec<f64> = (0..3).map(|i| (0..=i).map(|j| l[i][j] * z[j]).sum()).collect();
                SideLaw {
                    r_inf: self.r_inf + dx[0],
                    c: self.c + dx[1],
                    cov: [[0.0; 2]; 2],
                    g: self.g,
                    energy: Some(EnergyLoss {
                        c2: e.c2 + dx[2],
                        cov: [[0.0; 3]; 3],
                        ..*e
                    }),
                }
            }
        }
    }

    fn validate(&self, what: &str) -> Result<(), String> {
        let s = &self.cov;
        let finite = [self.r_inf, self.c, s[0][0], s[0][1], s[1][0], s[1][1]].iter().all(|x| x.is_finite());
        if !finite {
            return Err(format!("{what}: parameters and covariance must be finite numbers"));
        }
        if !(self.r_inf > 0.0 && self.r_inf < 2.0) {
            return Err(format!("{what}: r_inf = {} is outside (0, 2)", self.r_inf));
        }
        let sym_tol = 1e-9 * (s[0][0].abs() + s[1][1].abs()).max(1e-300);
        if (s[0][1] - s[1][0]).abs() > sym_tol {
            return Err(format!("{what}: covariance is not symmetric"));
        }
        if s[0][0] < 0.0 || s[1][1] < 0.0 || s[0][1] * s[0][1] > s[0][0] * s[1][1] * (1.0 + 1e-9) + 1e-300 {
            return Err(format!("{what}: covariance is not positive semi-definite"));
        }
        match &self.energy {
            Some(e) => e.validate(what, s),
            None => Ok(()),
        }
    }
}

impl EnergyLoss {
    fn validate(&self, what: &str, block: &[[f64; 2]; 2]) -> Result<(), String> {
        let s = &self.cov;
        let finite = self.c2.is_finite() && self.g_lo.is_finite() && self.g_hi.is_finite() && s.iter().flatten().all(|x| x.is_finite());
        if !finite {
            return Err(format!("{what}: the energy term and its covariance must be finite numbers"));
        }
        if !(self.g_lo >= 1.0 && self.g_lo <= self.g_hi) {
            return Err(format!(
                "{what}: the energy term's shapes [{}, {}] must satisfy 1 ≤ g_lo ≤ g_hi",
                self.g_lo, self.g_hi
            ));
        }
        let scale = (0..3).map(|i| s[i][i].abs()).sum::<f64>().max(1e-300);
        let symmetric = (0..3).all(|i| (0..3).all(|j| (s[i][j] - s[j][i]).abs() <= 1e-9 * scale));
        if !symmetric {
            return Err(format!("{what}: the energy term's covariance is not symmetric"));
        }
        let agrees = (0..2).all(|i| (0..2).all(|j| (s[i][j] - block[i][j]).abs() <= 1e-9 * scale));
        if !agrees {
            return Err(format!("{what}: \"cov\" must be the upper-left block of the energy term's covariance"));
        }
        if !positive_semi_definite3(s) {
            return Err(format!("{what}: the energy term's covariance is not positive semi-definite"));
        }
        Ok(())
    }
}

/// Lower Cholesky factor of a 3×3 positive semi-definite matrix (rows of a
/// singular direction are zero).
fn cholesky3(s: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..=i {
            let sum: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
            if i == j {
                l[i][i] = (s[i][i] - sum).max(0.0).sqrt();
            } else {
                l[i][j] = if l[j][j] > 0.0 { (s[i][j] - sum) / l[j][j] } else { 0.0 };
            }
        }
    }
    l
}

/// Whether L Lᵀ (the Cholesky factor of `s`) gives back `s` to 1e-6 of its trace:
/// a negative pivot, clamped to 0, does not.
fn positive_semi_definite3(s: &[[f64; 3]; 3]) -> bool {
    let l = cholesky3(s);
    let scale = (0..3).map(|i| s[i][i].abs()).sum::<f64>().max(1e-300);
    (0..3).all(|i| s[i][i] >= 0.0) && (0..3).all(|i| (0..3).all(|j| ((0..3).map(|k| l[i][k] * l[j][k]).sum::<f64>() - s[i][j]).abs() <= 1e-6 * scale))
}

/// Lower Cholesky factor (l00, l10, l11) of a 2×2 positive semi-definite matrix.
fn cholesky2(s: &[[f64; 2]; 2]) -> (f64, f64, f64) {
    let l00 = s[0][0].max(0.0).sqrt();
    let l10 = if l00 > 0.0 { s[1][0] / l00 } else { 0.0 };
    let l11 = (s[1][1] - l10 * l10).max(0.0).sqrt();
    (l00, l10, l11)
}

/// The law's parameters as serialised (`restitution_law.parameters` in summary.json).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LawParameters {
    /// Impacts entering the inward side (θ < 0, towards the transverse walls).
    #[serde(rename = "in")]
    pub inward: SideLaw,
    /// Impacts entering the outward side.
    #[serde(rename = "out")]
    pub outward: SideLaw,
    /// One law for both sides (two-sided rocking): in == out, drawn together.
    pub shared: bool,
    /// The amplitudes a = |θ|/α the campaign observed; below the smallest the law
    /// holds its value there.
    pub amplitude_min: f64,
    pub amplitude_max: f64,
    /// One-sided walls whose inward r rises as the amplitude falls (c < 0): the
    /// smallest amplitude of the inward side's own impacts, below which the
    /// inward r is held (its impacts end free arcs, far larger than the
    /// outward side's pushes, which set `amplitude_min`). Absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inward_amplitude_min: Option<f64>,
    /// The amplitudes of each side's own impacts, [smallest, largest] (one-sided
    /// walls: the inward side's free arcs span far more than the outward side's
    /// pushes; two-sided: the shared law's range on both). Beyond them the law
    /// is extrapolated or held (# Range). Absent in laws written before it
    /// (then [`RestitutionLaw::observed`] falls back on the campaign's range).
    /// Read by the façade study to say how many of a run's impacts read the law
    /// beyond its data.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observed: Option<ObservedAmplitudes>,
    /// One-sided walls: how fast the campaign's pushes ended for their amplitude,
    /// ŵ/a with ŵ = ω⁻/(p α) (# Reading a law by the impact's speed). Absent on
    /// two-sided laws and in laws written before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub push_speed: Option<PushSpeed>,
}

/// The dimensionless speed per unit amplitude of a one-sided campaign's pushes,
/// ŵ/a = ω⁻/(p α a) over its outward impacts (ω⁻ the angular speed before the
/// impact, p and α the test wall's, a the push's apex |θ|/α): the push's angular
/// frequency over p, Ω/p, where the transverse walls' spring dominates gravity
/// (`restitution_law.parameters.push_speed` in summary.json: `{"median": …,
/// "range": [lo, hi], "impacts": n}`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PushSpeed {
    pub median: f64,
    pub range: [f64; 2],
    pub impacts: usize,
}

impl PushSpeed {
    /// From the outward impacts' (amplitude a, ŵ): the median and range of ŵ/a
    /// over those with a > 0 and ŵ > 0 (None without any).
    pub fn of(impacts: impl IntoIterator<Item = (f64, f64)>) -> Option<PushSpeed> {
        let q: Vec<f64> = impacts
            .into_iter()
            .filter(|(a, w)| *a > 0.0 && *w > 0.0 && a.is_finite() && w.is_finite())
            .map(|(a, w)| w / a)
            .collect();
        let q = crate::stats::sorted(&q);
        let (first, last) = (*q.first()?, *q.last()?);
        Some(PushSpeed {
            median: crate::stats::quantile_sorted(&q, 0.5),
            range: [first, last],
            impacts: q.len(),
        })
    }
}

/// How the solver picks the amplitude at which it reads a law at an impact
/// (`reading` of a façade study's law set; # Reading a law by the impact's
/// speed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LawReading {
    /// At the apex |θ|/α of the half-cycle the impact ends (SPEC; the default).
    #[default]
    Amplitude,
    /// At the amplitude whose campaign impact had the same dimensionless speed
    /// ŵ = ω⁻/(p α) ([`RestitutionLaw::amplitude_at_speed`]).
    Speed,
}

impl LawReading {
    /// "amplitude" or "speed", as a study file or Python names it.
    pub fn parse(text: &str) -> Option<LawReading> {
        match text {
            "amplitude" => Some(LawReading::Amplitude),
            "speed" => Some(LawReading::Speed),
            _ => None,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            LawReading::Amplitude => "amplitude",
            LawReading::Speed => "speed",
        }
    }
}

/// The amplitudes a = |θ|/α of each side's impacts that a law was fitted on
/// (`restitution_law.parameters.observed` in summary.json: `{"in": [lo, hi],
/// "out": [lo, hi]}`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ObservedAmplitudes {
    #[serde(rename = "in")]
    pub inward: [f64; 2],
    #[serde(rename = "out")]
    pub outward: [f64; 2],
}

/// As read from JSON, before [`RestitutionLaw::validate`].
#[derive(serde::Deserialize)]
struct RawLaw {
    form: LawForm,
    parameters: LawParameters,
}

/// A restitution law r_in(a), r_out(a). JSON: `{"form": "speed-loss", "parameters":
/// {"in": {"r_inf", "c", "cov"}, "out": {…}, "shared", "amplitude_min",
/// "amplitude_max"}}` (other keys beside them, such as the report's `curve`, are ignored
/// when reading).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "RawLaw")]
pub struct RestitutionLaw {
    pub form: LawForm,
    pub parameters: LawParameters,
}

impl TryFrom<RawLaw> for RestitutionLaw {
    type Error = String;
    fn try_from(raw: RawLaw) -> Result<Self, String> {
        let law = RestitutionLaw {
            form: raw.form,
            parameters: raw.parameters,
        };
        law.validate()?;
        Ok(law)
    }
}

/// One point of a law's curve (`restitution_law.curve[]` in summary.json).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CurvePoint {
    pub amplitude_over_alpha: f64,
    pub r_in: f64,
    pub r_in_u: f64,
    pub r_out: f64,
    pub r_out_u: f64,
}

/// g(a) = 1/√(a (2 − a)) = p α / ω⁻ in the small-α limit (module docs).
pub fn speed_shape(a: f64) -> f64 {
    1.0 / (a * (2.0 - a)).sqrt()
}

/// g(a) = 1/a = ω(1)/ω⁻ for an impact that ends a push against a spring ([`Shape::Push`]).
pub fn push_shape(a: f64) -> f64 {
    1.0 / a
}

/// The apex a = |θ|/α of a free-rocking half-cycle that reaches θ = 0 at the
/// angular speed ŵ p α on a block of slenderness α (paper Eq. 1 without ground
/// motion: ω² = 2 p² (cos(α − aα) − cos α)): a = 1 − arccos(cos α + ŵ² α²/2)/α,
/// 1 where ŵ exceeds the fall from a = 1. For small α, a(2 − a) = ŵ², so
/// g(a) = 1/ŵ ([`speed_shape`]).
pub fn free_arc_amplitude(speed_over_p_alpha: f64, alpha: f64) -> f64 {
    let w = speed_over_p_alpha.abs();
    let x = alpha.cos() + 0.5 * w * w * alpha * alpha;
    if x >= 1.0 || x.is_nan() {
        return 1.0;
    }
    (1.0 - x.acos() / alpha).max(0.0)
}

/// The smallest amplitude a law may start at (g(1e-6) ≈ 707).
pub const AMPLITUDE_FLOOR: f64 = 1e-6;

impl RestitutionLaw {
    /// The constant pair (r_in ± u_in, r_out ± u_out) as a law (c = 0), valid on a ∈ (0, 1].
    pub fn constant(r_in: f64, u_in: f64, r_out: f64, u_out: f64) -> RestitutionLaw {
        RestitutionLaw {
            form: LawForm::Constant,
            parameters: LawParameters {
                inward: SideLaw::constant(r_in, u_in),
                outward: SideLaw::constant(r_out, u_out),
                shared: false,
                amplitude_min: AMPLITUDE_FLOOR,
                amplitude_max: 1.0,
                inward_amplitude_min: None,
                observed: None,
                push_speed: None,
            },
        }
    }

    /// The parameters of one side.
    pub fn side(&self, side: Side) -> &SideLaw {
        match side {
            Side::Inward => &self.parameters.inward,
            Side::Outward => &self.parameters.outward,
        }
    }

    /// g at the amplitude for one side (module docs, "Range"): a clamped to
    /// [AMPLITUDE_FLOOR, 1] where r falls as the amplitude falls below the
    /// observed ones (c ≥ 0; with an energy term, a slope dr/dg ≤ 0 at the
    /// smallest observed amplitude) and to [amplitude_min, 1] where it would rise
    /// (the inward side: [inward_amplitude_min, 1] where it is given); 0 for a
    /// constant, so that r = r∞ exactly.
    fn g(&self, which: Side, amplitude_over_alpha: f64) -> f64 {
        let side = self.side(which);
        match self.form {
            LawForm::Constant => 0.0,
            LawForm::SpeedLoss | LawForm::SpeedAndEnergyLoss => {
                let a = amplitude_over_alpha.abs();
                let a = if a.is_finite() { a } else { 1.0 };
                let falls = match &side.energy {
                    None => side.c >= 0.0,
                    Some(e) => side.slope(e.g_hi) <= 0.0,
                };
                let lo = match (falls, which, self.parameters.inward_amplitude_min) {
                    (true, _, _) => AMPLITUDE_FLOOR,
                    (false, Side::Inward, Some(a_in)) => a_in.max(self.parameters.amplitude_min),
                    (false, _, _) => self.parameters.amplitude_min,
                };
                side.g.eval(a.clamp(lo.min(1.0), 1.0))
            }
        }
    }

    /// r of an impact entering `side` that ends a half-cycle of apex |θ|/α =
    /// `amplitude_over_alpha`: max(0, r∞ − c g(a) − c₂ q(g(a))).
    pub fn r(&self, side: Side, amplitude_over_alpha: f64) -> f64 {
        let l = self.side(side);
        l.value(self.g(side, amplitude_over_alpha)).max(0.0)
    }

    /// The standard uncertainty of [`Self::r`] from the parameters' covariance.
    pub fn r_u(&self, side: Side, amplitude_over_alpha: f64) -> f64 {
        let l = self.side(side);
        l.u(self.g(side, amplitude_over_alpha))
    }

    /// The amplitudes a = |θ|/α of `side`'s own impacts the law was fitted on,
    /// (smallest, largest): `observed` where it is given, else the campaign's
    /// `amplitude_min`–`amplitude_max` (the inward side from
    /// `inward_amplitude_min` where that is given). Beyond them the law's r
    /// comes from its form (extrapolated, or held: # Range), not from an impact
    /// the campaign measured.
    pub fn observed(&self, side: Side) -> (f64, f64) {
        let p = &self.parameters;
        match (p.observed, side) {
            (Some(o), Side::Inward) => (o.inward[0], o.inward[1]),
            (Some(o), Side::Outward) => (o.outward[0], o.outward[1]),
            (None, Side::Inward) => (p.inward_amplitude_min.unwrap_or(p.amplitude_min), p.amplitude_max),
            (None, Side::Outward) => (p.amplitude_min, p.amplitude_max),
        }
    }

    /// [`Self::observed`] of both sides, as serialised.
    pub fn observed_amplitudes(&self) -> ObservedAmplitudes {
        let ((a, b), (c, d)) = (self.observed(Side::Inward), self.observed(Side::Outward));
        ObservedAmplitudes {
            inward: [a, b],
            outward: [c, d],
        }
    }

    /// Whether `side`'s impacts end a push against the transverse walls (the
    /// outward side of a one-sided law: its shape is the push's, or the law
    /// carries the campaign's [`PushSpeed`]).
    pub fn ends_a_push(&self, side: Side) -> bool {
        side == Side::Outward && (self.parameters.push_speed.is_some() || self.parameters.outward.g == Shape::Push)
    }

    /// The amplitude at which a law read by speed is read for an impact entering
    /// `side` at the dimensionless speed ŵ = ω⁻/(p α) on a block of slenderness
    /// `alpha` (# Reading a law by the impact's speed): on a free arc, the apex
    /// whose free rocking reaches θ = 0 at that speed,
    /// a = 1 − arccos(cos α + ŵ² α²/2)/α (1 where ŵ exceeds the fall from a = 1);
    /// after a push, a = ŵ/(Ω/p) with the campaign's [`PushSpeed`] median (at
    /// most 1). None for a push side without it (a law written before it).
    pub fn amplitude_at_speed(&self, side: Side, speed_over_p_alpha: f64, alpha: f64) -> Option<f64> {
        let w = speed_over_p_alpha.abs();
        if self.ends_a_push(side) {
            return self.parameters.push_speed.map(|q| (w / q.median).min(1.0));
        }
        Some(free_arc_amplitude(w, alpha))
    }

    /// Whether the law can be read by speed: a push side needs the campaign's
    /// [`PushSpeed`]. A law whose sides are fitted apart (`shared` false: a
    /// one-sided wall's) without it, whose outward side changes with the amplitude,
    /// is refused too: its outward impacts may end pushes (a one-sided law by
    /// replay, or one written by hand), and read on the free arc they would be
    /// read at the wrong amplitude without a word. A constant side reads the same
    /// e either way.
    pub fn readable_by_speed(&self) -> Result<(), String> {
        let p = &self.parameters;
        if self.ends_a_push(Side::Outward) && p.push_speed.is_none() {
            return Err("its outward side ends pushes, and it carries no parameters.push_speed (the campaign's Ω/p, which rocklab reduce writes with a one-sided law): reduce the campaign again with this rocklab, or read the law by amplitude".into());
        }
        let outward_varies = p.outward.c != 0.0 || p.outward.energy.is_some();
        if !p.shared && p.push_speed.is_none() && outward_varies {
            return Err("its sides are fitted apart (shared = false, a one-sided wall's law) and it carries no parameters.push_speed: rocklab cannot tell whether its outward impacts end pushes, which are read at the campaign's Ω/p, or free arcs; give the law its campaign's push_speed (rocklab reduce and rocklab calibrate write it with a one-sided law), or read the law by amplitude".into());
        }
        Ok(())
    }

    /// The coefficient the solver applies: e = min(1, r(a) e_H).
    pub fn e(&self, side: Side, amplitude_over_alpha: f64, e_h: f64) -> f64 {
        (self.r(side, amplitude_over_alpha) * e_h).min(1.0)
    }

    /// The smallest amplitude a ∈ [amplitude_min, 1] at which the solver's
    /// e = min(1, r(a) e_H) reaches its cap 1 (a perfectly elastic impact), to 0.1 %
    /// of a; `None` where it never does. r(a) = r∞ − c g(a) is monotone in a for
    /// either sign of c (and a fitted energy term keeps it so: `law_fit` takes one
    /// only where r falls with g over [1, ∞)), so the first of 400 points spaced
    /// evenly in ln a that reaches the cap, refined by bisection, is the one.
    pub fn elastic_from(&self, side: Side, e_h: f64) -> Option<f64> {
        let capped = |a: f64| self.r(side, a) * e_h >= 1.0;
        let lo = self.parameters.amplitude_min.clamp(AMPLITUDE_FLOOR, 1.0);
        let at = |i: usize| lo * (1.0 / lo).powf(i as f64 / 399.0);
        let first = (0..400).find(|&i| capped(at(i)))?;
        if first == 0 {
            return Some(lo);
        }
        let (mut below, mut above) = (at(first - 1), at(first));
        while above - below > 1e-3 * above {
            let mid = 0.5 * (below + above);
            if capped(mid) {
                above = mid;
            } else {
                below = mid;
            }
        }
        Some(above)
    }

    /// `n` (at least 20) points spaced evenly in ln a over the observed amplitudes
    /// [amplitude_min, amplitude_max], with r and u(r) on each side.
    pub fn curve(&self, n: usize) -> Vec<CurvePoint> {
        self.curve_between(self.parameters.amplitude_min, self.parameters.amplitude_max, n)
    }

    /// As [`Self::curve`] over [a_lo, a_hi] (0 < a_lo ≤ a_hi).
    pub fn curve_between(&self, a_lo: f64, a_hi: f64, n: usize) -> Vec<CurvePoint> {
        let n = n.max(20);
        let (lo, hi) = (a_lo.max(AMPLITUDE_FLOOR).ln(), a_hi.max(a_lo).max(AMPLITUDE_FLOOR).ln());
        (0..n)
            .map(|i| {
                let a = (lo + (hi - lo) * i as f64 / (n - 1) as f64).exp();
                CurvePoint {
                    amplitude_over_alpha: a,
                    r_in: self.r(Side::Inward, a),
                    r_in_u: self.r_u(Side::Inward, a),
                    r_out: self.r(Side::Outward, a),
                    r_out_u: self.r_u(Side::Outward, a),
                }
            })
            .collect()
    }

    /// A draw of the parameters: mean + L z per side with z = (z[0], z[1], z[4])
    /// inward and (z[2], z[3], z[5]) outward (a shared law uses the inward ones for
    /// both; z[4], z[5] drive the energy terms, and count as 0 where `z` is
    /// shorter). The draw has zero covariance; its r may leave [0, 1/e_H] only
    /// where [`Self::r`] and [`Self::e`] clamp it.
    pub fn sample(&self, z: &[f64]) -> RestitutionLaw {
        let at = |i: usize| z.get(i).copied().unwrap_or(0.0);
        let p = &self.parameters;
        let inward = p.inward.sample([at(0), at(1), at(4)]);
        let outward = if p.shared { inward } else { p.outward.sample([at(2), at(3), at(5)]) };
        RestitutionLaw {
            form: self.form,
            parameters: LawParameters { inward, outward, ..*p },
        }
    }

    /// [`Self::sample`] with standard normals from the caller's generator: four,
    /// and two more where a side has an energy term (so a law without one draws
    /// the same parameters from the same stream as before the term existed).
    pub fn sample_with(&self, mut normal: impl FnMut() -> f64) -> RestitutionLaw {
        let mut z = vec![normal(), normal(), normal(), normal()];
        if self.parameters.inward.energy.is_some() || self.parameters.outward.energy.is_some() {
            z.extend([normal(), normal()]);
        }
        self.sample(&z)
    }

    /// Checks what deserialisation cannot: finite parameters in range, a symmetric
    /// positive semi-definite covariance, 0 < amplitude_min ≤ amplitude_max ≤ 1, c = 0
    /// for a constant, in == out for a shared law, an energy term exactly where the
    /// form is "speed-and-energy-loss" (with its own checks: finite, 1 ≤ g_lo ≤ g_hi,
    /// a symmetric positive semi-definite 3×3 covariance whose block is `cov`).
    pub fn validate(&self) -> Result<(), String> {
        let p = &self.parameters;
        p.inward.validate("restitution law, side \"in\"")?;
        p.outward.validate("restitution law, side \"out\"")?;
        let range_ok = p.amplitude_min.is_finite() && p.amplitude_max.is_finite();
        if !(range_ok && p.amplitude_min >= AMPLITUDE_FLOOR && p.amplitude_min <= p.amplitude_max && p.amplitude_max <= 1.0) {
            return Err(format!(
                "restitution law: amplitude range [{}, {}] must satisfy {AMPLITUDE_FLOOR} ≤ amplitude_min ≤ amplitude_max ≤ 1",
                p.amplitude_min, p.amplitude_max
            ));
        }
        if let Some(a) = p.inward_amplitude_min {
            if !(a.is_finite() && (AMPLITUDE_FLOOR..=1.0).contains(&a)) {
                return Err(format!("restitution law: inward_amplitude_min = {a} must lie in [{AMPLITUDE_FLOOR}, 1]"));
            }
        }
        if let Some(o) = p.observed {
            for (name, [lo, hi]) in [("in", o.inward), ("out", o.outward)] {
                if !(lo.is_finite() && hi.is_finite() && AMPLITUDE_FLOOR <= lo && lo <= hi && hi <= 1.0) {
                    return Err(format!(
                        "restitution law: observed amplitudes of side \"{name}\" [{lo}, {hi}] must satisfy {AMPLITUDE_FLOOR} ≤ lo ≤ hi ≤ 1"
                    ));
                }
            }
        }
        if let Some(q) = p.push_speed {
            let [lo, hi] = q.range;
            if !(q.median.is_finite() && hi.is_finite() && 0.0 < lo && lo <= q.median && q.median <= hi && q.impacts >= 1) {
                return Err(format!(
                    "restitution law: push_speed (median {}, range [{lo}, {hi}], {} impacts) must satisfy 0 < lo ≤ median ≤ hi and at least one impact",
                    q.median, q.impacts
                ));
            }
        }
        if self.form == LawForm::Constant && (p.inward.c != 0.0 || p.outward.c != 0.0) {
            return Err("restitution law: form \"constant\" needs c = 0 on both sides".into());
        }
        let energy = p.inward.energy.is_some() || p.outward.energy.is_some();
        if energy != (self.form == LawForm::SpeedAndEnergyLoss) {
            return Err("restitution law: an energy term (\"energy\") goes with form \"speed-and-energy-loss\", and that form needs one".into());
        }
        if p.shared && p.inward != p.outward {
            return Err("restitution law: a shared law needs equal \"in\" and \"out\" parameters".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The public one-sided campaign's outward law (r∞ 1.1614, c 0.0415, e_H 0.9738):
    /// r e_H = 1 where g = (1.1614 − 1/0.9738)/0.0415, a(2 − a) = 1/g²; a constant
    /// below 1/e_H never reaches the cap, one above it does from the start.
    #[test]
    fn the_law_reaches_an_elastic_impact_where_r_e_h_is_one() {
        let side = |r_inf: f64, c: f64| SideLaw {
            r_inf,
            c,
            cov: [[0.0; 2]; 2],
            g: Shape::Free,
            energy: None,
        };
        let law = |form, inward, outward| RestitutionLaw {
            form,
            parameters: LawParameters {
                inward,
                outward,
                shared: false,
                amplitude_min: 0.0024,
                amplitude_max: 0.391,
                inward_amplitude_min: None,
                observed: None,
                push_speed: None,
            },
        };
        let l = law(LawForm::SpeedLoss, side(0.6714, 0.0), side(1.1614, 0.0415));
        let g: f64 = (1.1614 - 1.0 / 0.9738) / 0.0415;
        let want = 1.0 - (1.0 - 1.0 / (g * g)).sqrt();
        let got = l.elastic_from(Side::Outward, 0.9738).unwrap();
        assert!((got / want - 1.0).abs() < 2e-3, "{got} vs {want}");
        assert!(l.e(Side::Outward, got, 0.9738) == 1.0 && l.e(Side::Outward, 0.998 * want, 0.9738) < 1.0);
        assert_eq!(l.elastic_from(Side::Inward, 0.9738), None);
        let c = law(LawForm::Constant, side(1.05, 0.0), side(0.9, 0.0));
        assert_eq!(c.elastic_from(Side::Inward, 0.9738), Some(0.0024));
        assert_eq!(c.elastic_from(Side::Outward, 0.9738), None);
    }

    fn law() -> RestitutionLaw {
        RestitutionLaw {
            form: LawForm::SpeedLoss,
            parameters: LawParameters {
                inward: SideLaw {
                    r_inf: 0.70,
                    c: 0.0,
                    cov: [[1e-4, 0.0], [0.0, 1e-6]],
                    g: Shape::Free,
                    energy: None,
                },
                outward: SideLaw {
                    r_inf: 1.02,
                    c: 0.02,
                    cov: [[4e-4, -2e-5], [-2e-5, 4e-6]],
                    g: Shape::Free,
                    energy: None,
                },
                shared: false,
                amplitude_min: 0.01,
                amplitude_max: 0.4,
                inward_amplitude_min: None,
                observed: None,
                push_speed: None,
            },
        }
    }

    /// r = r∞ − c/√(a(2−a)) by hand: a = 0.5 → g = 1/√0.75.
    #[test]
    fn value_by_hand() {
        let l = law();
        let g = 1.0 / 0.75f64.sqrt();
        assert!((l.r(Side::Outward, 0.5) - (1.02 - 0.02 * g)).abs() < 1e-15);
        assert_eq!(l.r(Side::Inward, 0.5), 0.70);
        // Below amplitude_min a falling side (c > 0) extrapolates, down to r = 0 …
        assert!((l.r(Side::Outward, 0.001) - (1.02 - 0.02 / (0.001f64 * 1.999).sqrt())).abs() < 1e-12);
        assert_eq!(l.r(Side::Outward, 1e-6), 0.0);
        // … and a rising side (c < 0) holds its value at amplitude_min.
        let mut up = l;
        up.parameters.inward.c = -0.01;
        assert_eq!(up.r(Side::Inward, 1e-5), up.r(Side::Inward, 0.01));
        // u² = Σ00 − 2 g Σ01 + g² Σ11.
        let u = (4e-4 + 2.0 * g * 2e-5 + g * g * 4e-6f64).sqrt();
        assert!((l.r_u(Side::Outward, 0.5) - u).abs() < 1e-15);
        // e capped at 1.
        assert_eq!(l.e(Side::Outward, 1.0, 1.0), 1.0);
    }

    /// The shape is 1/ω⁻ in units of 1/(p α): ω⁻² = 2p²(cos(α − aα) − cos α).
    #[test]
    fn shape_is_the_inverse_impact_speed() {
        let (p, alpha): (f64, f64) = (2.2, 0.03);
        for a in [0.01, 0.1, 0.5, 0.9] {
            let w = (2.0 * p * p * ((alpha - a * alpha).cos() - alpha.cos())).sqrt();
            let rel = speed_shape(a) / (p * alpha / w) - 1.0;
            assert!(rel.abs() < 1e-3, "a = {a}: {rel}");
        }
    }

    /// A constant law returns its r bit for bit at every amplitude, and a constant
    /// pair draws only r∞.
    #[test]
    fn constant_is_exact() {
        let c = RestitutionLaw::constant(0.59, 0.01, 0.68, 0.02);
        for a in [1e-7, 0.01, 0.3, 1.0, 3.0, f64::NAN] {
            assert_eq!(c.r(Side::Inward, a), 0.59);
            assert_eq!(c.r(Side::Outward, a), 0.68);
        }
        let d = c.sample(&[1.0, 5.0, -1.0, 5.0]);
        assert!((d.parameters.inward.r_inf - 0.60).abs() < 1e-12);
        assert!((d.parameters.outward.r_inf - 0.66).abs() < 1e-12);
        assert_eq!((d.parameters.inward.c, d.parameters.outward.c), (0.0, 0.0));
    }

    /// Draws reproduce the covariance (L Lᵀ = Σ) and a shared law stays shared.
    #[test]
    fn samples_have_the_covariance() {
        let l = law();
        let mut rng = crate::stats::SplitMix64::new(7);
        let n = 40_000;
        let draws: Vec<SideLaw> = (0..n).map(|_| l.sample_with(|| rng.normal()).parameters.outward).collect();
        let m0 = draws.iter().map(|d| d.r_inf).sum::<f64>() / n as f64;
        let m1 = draws.iter().map(|d| d.c).sum::<f64>() / n as f64;
        let c01 = draws.iter().map(|d| (d.r_inf - m0) * (d.c - m1)).sum::<f64>() / n as f64;
        let v1 = draws.iter().map(|d| (d.c - m1).powi(2)).sum::<f64>() / n as f64;
        // Sampling error of a covariance estimate ~ √(2/n) relative: 0.7 % at n = 40 000; 5 % allowed.
        assert!((c01 / -2e-5 - 1.0).abs() < 0.05, "{c01}");
        assert!((v1 / 4e-6 - 1.0).abs() < 0.05, "{v1}");
        let mut s = l;
        s.parameters.shared = true;
        s.parameters.outward = s.parameters.inward;
        let d = s.sample(&[0.3, -0.2, 9.0, 9.0]);
        assert_eq!(d.parameters.inward, d.parameters.outward);
    }

    #[test]
    fn curve_spans_the_observed_amplitudes() {
        let l = law();
        let c = l.curve(5);
        assert_eq!(c.len(), 20);
        assert!((c[0].amplitude_over_alpha - 0.01).abs() < 1e-12);
        assert!((c[19].amplitude_over_alpha - 0.4).abs() < 1e-12);
        assert!(c
            .windows(2)
            .all(|w| w[1].r_out > w[0].r_out && w[1].amplitude_over_alpha > w[0].amplitude_over_alpha));
    }

    /// A side without `"g"` (every law written before the push shape) reads as the
    /// free arc, bit for bit, and writes back without it; `"g": "push"` gives
    /// r∞ − c/a, its u with g = 1/a, and round-trips.
    #[test]
    fn the_shape_field_is_optional_and_push_is_one_over_a() {
        let l = law();
        let old = r#"{"form":"speed-loss","parameters":{"in":{"r_inf":0.7,"c":0.0,"cov":[[1e-4,0.0],[0.0,1e-6]]},"out":{"r_inf":1.02,"c":0.02,"cov":[[4e-4,-2e-5],[-2e-5,4e-6]]},"shared":false,"amplitude_min":0.01,"amplitude_max":0.4}}"#;
        let read: RestitutionLaw = serde_json::from_str(old).unwrap();
        assert_eq!(read, l);
        for a in [1e-7, 0.003, 0.01, 0.2, 0.5, 1.0] {
            assert_eq!(
                read.r(Side::Outward, a).to_bits(),
                (1.02 - 0.02 * speed_shape(a.max(1e-6))).max(0.0).to_bits()
            );
        }
        assert!(!serde_json::to_string(&l).unwrap().contains("\"g\""));
        let pushed: RestitutionLaw = serde_json::from_str(&old.replace("\"out\":{", "\"out\":{\"g\":\"push\",")).unwrap();
        assert_eq!(pushed.parameters.outward.g, Shape::Push);
        assert_eq!(pushed.parameters.inward.g, Shape::Free);
        for a in [0.03, 0.1, 0.5] {
            assert!((pushed.r(Side::Outward, a) - (1.02 - 0.02 / a)).abs() < 1e-15);
            let u = (4e-4 + 2.0 * 2e-5 / a + 4e-6 / (a * a)).sqrt();
            assert!((pushed.r_u(Side::Outward, a) - u).abs() < 1e-15);
        }
        // g(1) = 1 for both shapes; below r = 0 the push clamps as the free arc does.
        assert_eq!(pushed.r(Side::Outward, 1.0), read.r(Side::Outward, 1.0));
        assert_eq!(pushed.r(Side::Outward, 0.019), 0.0);
        assert_eq!(pushed.r(Side::Inward, 0.3), 0.70);
        let s = serde_json::to_string(&pushed).unwrap();
        assert!(s.contains("\"g\":\"push\""), "{s}");
        assert_eq!(serde_json::from_str::<RestitutionLaw>(&s).unwrap(), pushed);
        // A draw keeps the shape.
        assert_eq!(pushed.sample(&[0.1, 0.2, 0.3, 0.4]).parameters.outward.g, Shape::Push);
        assert!(serde_json::from_str::<RestitutionLaw>(&old.replace("\"out\":{", "\"out\":{\"g\":\"spring\",")).is_err());
    }

    #[test]
    fn json_round_trip_and_bad_input() {
        let l = law();
        let s = serde_json::to_string(&l).unwrap();
        assert!(
            s.contains("\"form\":\"speed-loss\"") && s.contains("\"in\":") && s.contains("\"out\":"),
            "{s}"
        );
        let back: RestitutionLaw = serde_json::from_str(&s).unwrap();
        assert_eq!(back, l);
        // A curve beside the parameters is ignored when reading.
        let mut v: serde_json::Value = serde_json::from_str(&s).unwrap();
        v["curve"] = serde_json::json!([{"amplitude_over_alpha": 0.1}]);
        assert_eq!(serde_json::from_value::<RestitutionLaw>(v.clone()).unwrap(), l);
        v["parameters"]["out"]["cov"] = serde_json::json!([[1e-4, 1.0], [1.0, 1e-6]]);
        let err = serde_json::from_value::<RestitutionLaw>(v).unwrap_err().to_string();
        assert!(err.contains("positive semi-definite"), "{err}");
        let bad = s.replace("\"amplitude_min\":0.01", "\"amplitude_min\":0.0");
        assert!(serde_json::from_str::<RestitutionLaw>(&bad)
            .unwrap_err()
            .to_string()
            .contains("amplitude"));
        let bad = s.replace("speed-loss", "constant");
        assert!(serde_json::from_str::<RestitutionLaw>(&bad).unwrap_err().to_string().contains("c = 0"));
        // Each side's observed amplitudes: absent (a law written before them),
        // the campaign's range on both sides; given, read back; out of order or
        // outside (0, 1], refused with the side named.
        assert!(!s.contains("observed"), "{s}");
        let range = (l.parameters.amplitude_min, l.parameters.amplitude_max);
        assert_eq!((l.observed(Side::Inward), l.observed(Side::Outward)), (range, range));
        let mut v: serde_json::Value = serde_json::from_str(&s).unwrap();
        v["parameters"]["observed"] = serde_json::json!({"in": [0.02, 0.3], "out": [0.01, 0.05]});
        let with: RestitutionLaw = serde_json::from_value(v.clone()).unwrap();
        assert_eq!((with.observed(Side::Inward), with.observed(Side::Outward)), ((0.02, 0.3), (0.01, 0.05)));
        assert_eq!(
            serde_json::from_str::<RestitutionLaw>(&serde_json::to_string(&with).unwrap()).unwrap(),
            with
        );
        for bad in [[0.05, 0.01], [0.0, 0.05], [0.01, 1.5]] {
            v["parameters"]["observed"]["out"] = serde_json::json!(bad);
            let err = serde_json::from_value::<RestitutionLaw>(v.clone()).map(|_| ()).unwrap_err().to_string();
            assert!(err.contains("observed amplitudes of side \"out\""), "{bad:?}: {err}");
        }
    }

    /// A two-sided law with the energy term: r∞ 1, c 0.02, c₂ 0.01 over
    /// g ∈ [g(0.4), g(0.04)], and a 3×3 covariance whose upper-left block is `cov`.
    fn energy_law() -> RestitutionLaw {
        let cov3 = [[1e-4, 1e-5, -1e-6], [1e-5, 4e-6, -2e-7], [-1e-6, -2e-7, 1e-7]];
        let side = SideLaw {
            r_inf: 1.0,
            c: 0.02,
            cov: [[1e-4, 1e-5], [1e-5, 4e-6]],
            g: Shape::Free,
            energy: Some(EnergyLoss {
                c2: 0.01,
                cov: cov3,
                g_lo: speed_shape(0.4),
                g_hi: speed_shape(0.04),
            }),
        };
        RestitutionLaw {
            form: LawForm::SpeedAndEnergyLoss,
            parameters: LawParameters {
                inward: side,
                outward: side,
                shared: true,
                amplitude_min: 0.04,
                amplitude_max: 0.4,
                inward_amplitude_min: None,
                observed: None,
                push_speed: None,
            },
        }
    }

    /// The energy term by hand: r = r∞ − c g − c₂ q(g) with q = g² inside the
    /// observed shapes and the tangent of g² outside (both sides of the range);
    /// u from the 3×3 covariance; below the smallest amplitude r keeps falling
    /// (the slope at g_hi is negative), so a is not held there.
    #[test]
    fn the_energy_term_by_hand() {
        let l = energy_law();
        let (lo, hi) = (speed_shape(0.4), speed_shape(0.04));
        let r = |g: f64, q: f64| 1.0 - 0.02 * g - 0.01 * q;
        let g = speed_shape(0.1);
        assert!((l.r(Side::Inward, 0.1) - r(g, g * g)).abs() < 1e-15);
        // a = 1: g = 1 < g_lo, the tangent at g_lo.
        assert!((l.r(Side::Outward, 1.0) - r(1.0, 2.0 * lo - lo * lo)).abs() < 1e-15);
        // a = 0.01: g beyond g_hi, the tangent at g_hi, not held at a = 0.04.
        let g = speed_shape(0.01);
        assert!((l.r(Side::Inward, 0.01) - r(g, 2.0 * hi * g - hi * hi)).abs() < 1e-15);
        assert!(l.r(Side::Inward, 0.01) < l.r(Side::Inward, 0.04));
        // u = √(dᵀ Σ d), d = (1, −g, −q).
        let g = speed_shape(0.1);
        let d = [1.0, -g, -g * g];
        let cov = l.parameters.inward.energy.unwrap().cov;
        let v: f64 = (0..3).map(|i| (0..3).map(|j| d[i] * cov[i][j] * d[j]).sum::<f64>()).sum();
        assert!((l.r_u(Side::Inward, 0.1) - v.sqrt()).abs() < 1e-15);
        // The curve is continuous at the edges (the tangent meets the parabola).
        let eps = 1e-9;
        for a in [0.4, 0.04] {
            assert!((l.r(Side::Inward, a * (1.0 + eps)) - l.r(Side::Inward, a * (1.0 - eps))).abs() < 1e-8);
        }
    }

    /// Draws of a law with the energy term have its 3×3 covariance; a law
    /// without one takes four normals from the caller's stream, one with it six.
    #[test]
    fn energy_draws_have_the_covariance_and_leave_other_laws_streams_alone() {
        let l = energy_law();
        let mut rng = crate::stats::SplitMix64::new(11);
        let n = 40_000;
        let draws: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                let d = l.sample_with(|| rng.normal()).parameters.inward;
                [d.r_inf, d.c, d.energy.unwrap().c2]
            })
            .collect();
        let mean: Vec<f64> = (0..3).map(|i| draws.iter().map(|d| d[i]).sum::<f64>() / n as f64).collect();
        let want = l.parameters.inward.energy.unwrap().cov;
        for i in 0..3 {
            for j in 0..=i {
                let c = draws.iter().map(|d| (d[i] - mean[i]) * (d[j] - mean[j])).sum::<f64>() / n as f64;
                // √(2/n) ≈ 0.7 % relative on a variance; a covariance's error
                // scales with √(Σᵢᵢ Σⱼⱼ / n): 5 % of that scale allowed.
                let scale = (want[i][i] * want[j][j]).sqrt();
                assert!((c - want[i][j]).abs() < 0.05 * scale, "({i}, {j}): {c} against {}", want[i][j]);
            }
        }
        let count = |law: &RestitutionLaw| {
            let mut k = 0;
            law.sample_with(|| {
                k += 1;
                0.0
            });
            k
        };
        assert_eq!((count(&law()), count(&l)), (4, 6));
    }

    /// The energy term reads back from JSON, and a law that mixes it with the
    /// wrong form, or whose `cov` is not its block, or whose 3×3 covariance is
    /// not positive semi-definite, is refused.
    #[test]
    fn energy_json_round_trip_and_bad_input() {
        let l = energy_law();
        let s = serde_json::to_string(&l).unwrap();
        assert!(s.contains("\"form\":\"speed-and-energy-loss\"") && s.contains("\"energy\":"), "{s}");
        assert_eq!(serde_json::from_str::<RestitutionLaw>(&s).unwrap(), l);
        let wrong_form = s.replace("speed-and-energy-loss", "speed-loss");
        assert!(serde_json::from_str::<RestitutionLaw>(&wrong_form)
            .unwrap_err()
            .to_string()
            .contains("energy"));
        let mut v: serde_json::Value = serde_json::from_str(&s).unwrap();
        v["parameters"]["in"]["cov"] = serde_json::json!([[2e-4, 1e-5], [1e-5, 4e-6]]);
        v["parameters"]["out"] = v["parameters"]["in"].clone();
        let err = serde_json::from_value::<RestitutionLaw>(v).unwrap_err().to_string();
        assert!(err.contains("block"), "{err}");
        let mut v: serde_json::Value = serde_json::from_str(&s).unwrap();
        v["parameters"]["in"]["energy"]["cov"] = serde_json::json!([[1e-4, 1e-5, 1e-3], [1e-5, 4e-6, 0.0], [1e-3, 0.0, 1e-7]]);
        v["parameters"]["out"] = v["parameters"]["in"].clone();
        let err = serde_json::from_value::<RestitutionLaw>(v).unwrap_err().to_string();
        assert!(err.contains("positive semi-definite"), "{err}");
    }

    /// The free arc's inverse: a block released from a·α reaches θ = 0 at
    /// ω² = 2 p² (cos(α − aα) − cos α) (Eq. 1 without ground motion, energy);
    /// read by that speed, the amplitude is a again, to 1e-9 of it, for slender
    /// and stocky blocks and from tiny swings to a = 1; faster than the fall from
    /// a = 1, it is 1.
    #[test]
    fn the_free_arc_read_by_its_speed_gives_its_apex() {
        for alpha in [0.03f64, 0.1, 0.1325, 0.25, 0.5] {
            for a in [1e-5f64, 1e-3, 0.02, 0.3, 0.77, 0.999, 1.0] {
                let w = (2.0 * ((alpha - a * alpha).cos() - alpha.cos())).sqrt() / alpha;
                let back = free_arc_amplitude(w, alpha);
                assert!((back - a).abs() <= 1e-9 * a.max(1e-3), "α {alpha}, a {a}: {back}");
                // The small-α form the law is written in: g(a) = 1/ŵ.
                if alpha <= 0.1 {
                    assert!((speed_shape(a) * w - 1.0).abs() < 0.01, "α {alpha}, a {a}");
                }
            }
            assert_eq!(free_arc_amplitude(1e3, alpha), 1.0);
            assert!(free_arc_amplitude(-0.0, alpha) < 1e-12);
        }
    }

    /// A one-sided law reads its push side at ŵ/(Ω/p) and its inward side on the
    /// free arc; two-sided laws read both on the free arc; a push side without
    /// the campaign's Ω/p cannot be read by speed, and says why.
    #[test]
    fn a_push_is_read_at_the_campaign_push_of_the_same_speed() {
        let q = PushSpeed::of([(0.25, 4.25), (0.5, 7.5), (0.25, 4.5), (0.0, 1.0), (0.02, f64::NAN)]).unwrap();
        assert_eq!((q.median, q.range, q.impacts), (17.0, [15.0, 18.0], 3));
        assert_eq!(PushSpeed::of([(0.01, 0.1), (0.02, 0.3)]).unwrap().median, 12.5);
        assert!(PushSpeed::of([(0.0, 0.1)]).is_none());
        let mut l = RestitutionLaw::constant(0.6, 0.01, 0.9, 0.01);
        l.form = LawForm::SpeedLoss;
        l.parameters.outward = SideLaw {
            r_inf: 1.03,
            c: 0.0016,
            cov: [[0.0; 2]; 2],
            g: Shape::Push,
            energy: None,
        };
        assert!(l.ends_a_push(Side::Outward) && !l.ends_a_push(Side::Inward));
        let err = l.readable_by_speed().unwrap_err();
        assert!(err.contains("push_speed"), "{err}");
        assert_eq!(l.amplitude_at_speed(Side::Outward, 0.2, 0.1), None);
        l.parameters.push_speed = Some(q);
        l.validate().unwrap();
        l.readable_by_speed().unwrap();
        assert_eq!(l.amplitude_at_speed(Side::Outward, 4.25, 0.1), Some(0.25));
        assert_eq!(l.amplitude_at_speed(Side::Outward, 100.0, 0.1), Some(1.0));
        assert_eq!(l.amplitude_at_speed(Side::Inward, 0.5, 0.1), Some(free_arc_amplitude(0.5, 0.1)));
        // A constant outward side of a one-sided law is still a push (its Ω/p says so).
        let mut c = RestitutionLaw::constant(0.6, 0.01, 0.9, 0.01);
        assert!(!c.ends_a_push(Side::Outward));
        c.readable_by_speed().unwrap();
        // Sides fitted apart with a free-arc outward curve and no Ω/p (a one-sided
        // law by replay written before, or by hand): which impacts end pushes
        // cannot be told, so it is refused; shared, or with its Ω/p, it is read.
        let mut apart = l;
        apart.parameters.push_speed = None;
        apart.parameters.outward.g = Shape::Free;
        let err = apart.readable_by_speed().unwrap_err();
        assert!(err.contains("shared = false") && err.contains("push_speed"), "{err}");
        apart.parameters.push_speed = Some(q);
        apart.readable_by_speed().unwrap();
        assert_eq!(apart.amplitude_at_speed(Side::Outward, 4.25, 0.1), Some(0.25));
        apart.parameters.push_speed = None;
        apart.parameters.shared = true;
        apart.parameters.inward = apart.parameters.outward;
        apart.readable_by_speed().unwrap();
        c.parameters.push_speed = Some(q);
        assert!(c.ends_a_push(Side::Outward));
        // JSON: written and read back; refused out of order, with the key named.
        let s = serde_json::to_string(&l).unwrap();
        assert!(s.contains("\"push_speed\":{\"median\":17.0,\"range\":[15.0,18.0],\"impacts\":3}"), "{s}");
        assert_eq!(serde_json::from_str::<RestitutionLaw>(&s).unwrap(), l);
        for bad in ["[18.5,19.0]", "[0.0,18.0]", "[-15.0,18.0]"] {
            let b = s.replace("[15.0,18.0]", bad);
            let err = serde_json::from_str::<RestitutionLaw>(&b).map(|_| ()).unwrap_err().to_string();
            assert!(err.contains("push_speed"), "{bad}: {err}");
        }
    }
}

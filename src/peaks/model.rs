//! The global free-rocking model of a log and its fit (see the docs of
//! [`crate::peaks`] for the derivation).
//!
//! A record is a chain of arcs, one per half-cycle, each a solution of paper
//! Eq. 1 (no ground motion) that starts and ends at θ = 0: the exact one on a
//! gravity side ([`super::gravity`]) and for a two-sided wall's release, the
//! closed form of Eq. 1 linearised about a point of the arc on the inward side
//! of one-sided rocking and for a one-sided wall's release. Two extensions
//! make it hold on real walls (issue #9):
//! - **lossy inward arcs** (one-sided): the transverse walls are a
//!   compression-only spring–dashpot (y = L θ, [`super::restraint`]): while they
//!   bear, y'' = A p² − λ y − 2γ y', and where the dashpot would have to pull
//!   they let go and the wall rocks freely to θ = 0. The wall leaves the
//!   half-cycle slower than it entered; γ = 0 is the lossless spring of the
//!   idealised model;
//! - **contact phases**: impacts may take time. Arc k ends at the onset of
//!   contact t_k − u, arc k+1 starts at t_k + δ + w, and in between the
//!   displacement is the quintic Hermite interpolant of the two arcs (value,
//!   slope and curvature at both ends: a compliant contact's force starts and
//!   ends at zero, so the wall keeps accelerating a few ms into the contact).
//!   u, w and δ are one set per direction. Without them (u = w = δ = 0) the
//!   impacts are instantaneous.
//!   The peak v_k is the extreme of the model's velocity from the end of arc k
//!   through its contact phase up to θ = 0 (SPEC: the extreme of the velocity
//!   in the half-cycle); θ = 0 is located twice, by the fitted zero and by the
//!   rest line, and v_k is the mean of the two readings ([`Model::peak`]).
//!
//! Parameters live in one vector; [`Layout`] names every position.

use super::gravity::GravityArc;
use super::restraint::InwardArc;
use crate::fit::{levenberg_marquardt, FitResult};
use nalgebra::DVector;

/// Names of the positions in the parameter vector. Rates and lengths are stored
/// as logarithms so that they stay positive; λ and γ are signed.
pub(crate) mod ix {
    /// Sensor zero z (mm, in L θ space).
    pub const ZERO: usize = 0;
    /// Sensor drift (mm/s): fixed by the final rest line.
    pub const DRIFT: usize = 1;
    /// ln A of the small arcs, A = L tan α_e (mm).
    pub const LN_A: usize = 2;
    /// ln p of the small arcs: kept equal to ln p0 (short arcs only see A p²).
    pub const LN_P: usize = 3;
    /// λ = κ − p² of the inward arcs of one-sided rocking (s⁻²).
    pub const LAMBDA: usize = 4;
    /// ln A0 and ln p0 of the release arc.
    pub const LN_A0: usize = 5;
    pub const LN_P0: usize = 6;
    /// Release time t_r (s).
    pub const T_R: usize = 7;
    /// Decay rate γ of the inward arcs of one-sided rocking (s⁻¹).
    pub const GAMMA: usize = 8;
    /// Impact k's zero time t_k sits at IMPACT0 + k.
    pub const IMPACT0: usize = 9;
}

/// How many impacts the vector holds, whether it carries contact phases and
/// whether they differ by direction (one-sided rocking: entering the inward side
/// meets the transverse walls)
/// (then δ, ln u and ln w follow the impact times, one set for the impacts that
/// enter the inward side and one for those that enter the outward side: one
/// contact shape per direction, not per impact, so that the contact cannot absorb
/// what the arcs must explain, and the peaks of one side share their bias,
/// which cancels in the ratios).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layout {
    pub impacts: usize,
    pub contacts: bool,
    pub by_direction: bool,
}

impl Layout {
    /// Length of the parameter vector.
    pub fn size(&self) -> usize {
        ix::IMPACT0
            + self.impacts
            + if !self.contacts {
                0
            } else if self.by_direction {
                6
            } else {
                3
            }
    }
    /// Position of δ, ln u (lead) and ln w (lag) of impact k (k even enters the
    /// inward side).
    pub fn delta(&self, k: usize) -> usize {
        ix::IMPACT0 + self.impacts + if self.by_direction { 3 * (k % 2) } else { 0 }
    }
    pub fn lead(&self, k: usize) -> usize {
        self.delta(k) + 1
    }
    pub fn lag(&self, k: usize) -> usize {
        self.delta(k) + 2
    }
    /// Parameter j in words (for the reasons of the checks).
    pub fn name(&self, j: usize) -> String {
        let contact = ix::IMPACT0 + self.impacts;
        if j >= contact {
            let what = ["the offset δ", "the lead u", "the lag w"][(j - contact) % 3];
            let whose = match (self.by_direction, (j - contact) / 3) {
                (false, _) => "the contacts",
                (true, 0) => "the contacts entering the inward side",
                (true, _) => "the contacts entering the outward side",
            };
            return format!("{what} of {whose}");
        }
        if j >= ix::IMPACT0 {
            return format!("the time of impact {}", j - ix::IMPACT0);
        }
        [
            "the sensor zero",
            "the sensor drift",
            "A of the small arcs",
            "p of the small arcs",
            "λ of the inward arcs",
            "A₀ of the release arc",
            "p₀ of the release arc",
            "the release time",
            "γ of the inward arcs",
        ][j]
            .to_string()
    }
}

/// What an arc's closed form needs beyond the impact times (see [`Model::shape`]).
#[derive(Debug, Clone, Copy)]
enum Shape {
    Release,
    Gravity {
        a: f64,
        p: f64,
    },
    /// The exact arc of Eq. 1 ([`GravityArc`]), where the lever is known.
    Exact(GravityArc),
    /// The release arc, exact ([`Model::exact_release`]).
    ExactRelease(GravityArc),
    Inward(InwardArc),
}

/// Which piece of the model owns a time.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Piece {
    /// Free arc s: the release arc for s = 0, then the arc between impacts s−1, s.
    Arc(usize),
    /// Contact phase of impact k.
    Contact(usize),
}

/// The global model: layout, parameters and the shortest arc allowed (s).
#[derive(Debug, Clone)]
pub struct Model {
    pub one_sided: bool,
    pub layout: Layout,
    /// Reference time of the drift line.
    pub t_ref: f64,
    /// Shortest arc or contact window the fit may produce (half a sample): two
    /// impacts never collapse onto one instant.
    pub min_len: f64,
    /// Sensor lever arm L (mm): the scale of the large-angle correction of the
    /// gravity arcs ([`Model::gravity_arc_params`]); infinite turns it off.
    pub lever: f64,
    pub q: Vec<f64>,
    /// The data logger's filter the samples went through, where stated or
    /// estimated: the residuals then compare the samples with the model seen
    /// through it ([`super::acquisition`]).
    pub filter: Option<std::sync::Arc<dyn Instrument>>,
    /// Contact phases whose lead and lag grow as the impacts slow down
    /// ([`Model::speed_scale`]) instead of one lead and one lag in time for
    /// every impact (two-sided fits only, `segments::contacts_by_speed`).
    pub contacts_by_speed: bool,
}

/// What the samples went through before they were logged (the data logger's
/// filter, implemented in `acquisition.rs`): the model as the logger would have
/// recorded it at the samples `t` (None where the model is undefined), and how
/// late a smooth arc comes out of it (s).
pub trait Instrument: std::fmt::Debug + Send + Sync {
    fn seen(&self, model: &Model, t: &[f64]) -> Vec<Option<f64>>;
    fn delay(&self) -> f64;
}

/// Where the gravity term is linearised on an arc of apex θ_m (θ* = β θ_m) when
/// A and p follow from α and p ([`Model::gravity_arc_params`]): the β that makes
/// the closed-form arc closest to the exact arc of Eq. 1 of the same length
/// (least squares over the arc, α 0.08–0.25, θ_m 0.1–0.9 α: β = 0.807–0.822;
/// shape error 2·10⁻⁴ θ_m at θ_m = 0.7 α, α = 0.25, against 7·10⁻³ with the
/// small-angle A and p).
const BETA_ARC: f64 = 0.81;
/// The same for the release arc, whose A₀ and p₀ are free: a free least-squares
/// fit of the closed form to the exact arc lands on the tangent at θ* = 0.69 θ_m
/// (both A₀ and p₀ agree with it to 0.02 % for α 0.1–0.25, θ_m up to 0.7 α).
const BETA_RELEASE: f64 = 0.69;
/// β of [`Model::speed_scale`]: contact phases that last (v̂₀/v̂_k)^½ times
/// the first one's. Measured on the 15 two-sided engine campaigns at hand
/// (docs/accuracy.md): β = 1 reverses the peaks' drift (v₅ −2 … −3 % below
/// v₀), β = ½ leaves a median drift of +0.5 % (+1.4 % with β = 0).
pub const CONTACT_SPEED_EXPONENT: f64 = 0.5;

/// A_k and p_k of the linearised gravity arc of half-length `half` (s) for α,
/// the small-angle rate p_s and the lever L ([`Model::gravity_arc_params`]):
/// three fixed-point steps of θ_m = A_k (1 − 1/cosh(p_k T/2)) / L,
/// θ* = β θ_m, A_k = L [tan(α − θ*) + θ*], p_k = p_s √(cos(α − θ*) / cos α).
fn linearised_arc(alpha: f64, p_s: f64, half: f64, lever: f64) -> (f64, f64) {
    let (mut ak, mut pk) = (lever * alpha.tan(), p_s);
    for _ in 0..3 {
        let apex = ak * (1.0 - 1.0 / (pk * half).cosh()) / lever;
        let ts = BETA_ARC * apex;
        ak = lever * ((alpha - ts).tan() + ts);
        pk = p_s * ((alpha - ts).cos() / alpha.cos()).sqrt();
    }
    (ak, pk)
}

impl Model {
    pub fn m(&self) -> usize {
        self.layout.impacts
    }
    pub fn impact(&self, k: usize) -> f64 {
        self.q[ix::IMPACT0 + k]
    }
    fn delta(&self, k: usize) -> f64 {
        if self.layout.contacts {
            self.q[self.layout.delta(k)]
        } else {
            0.0
        }
    }
    fn lead(&self, k: usize) -> f64 {
        if self.layout.contacts {
            self.q[self.layout.lead(k)].exp() * self.speed_scale(k)
        } else {
            0.0
        }
    }
    /// The factor on the lead and the lag of impact k's contact phase, where
    /// they follow the impacts' speeds ([`Model::contacts_by_speed`]):
    ///
    ///   s_k = (v̂₀ / v̂_k)^β,  v̂₀ = A₀ tanh(p₀ (t₀ − t_r)),  v̂_k = A tanh(p₀ T_k / 2),
    ///
    /// v̂_k the free arc's speed where it ends at impact k (Eq. 1 linearised:
    /// the arc of length T_k between two zeros ends at A tanh(p T_k/2)),
    /// s₀ = 1, bounded to [1/50, 50]^β; 1 for every k otherwise.
    ///
    /// Why: a compliant bedding bears once the wall has come within a small
    /// tilt of θ = 0 and lets go a small tilt past it. A slower wall covers
    /// that tilt in a longer time (β = 1), while the contact's own dynamics
    /// last a time of their own (β = 0). One lead in time for every impact,
    /// set by the large early ones, starts the late contacts too late: on the
    /// two-sided MuJoCo walls the peaks read from −1.4 % (v₀) up to +1 … +3 %
    /// (v₅) on 200 Hz tests and +10 % on the 70 mm ones. β = ½
    /// ([`CONTACT_SPEED_EXPONENT`]) was kept of 0, ½, ¾ and 1, measured
    /// (docs/accuracy.md, "Thirty-second session: two-sided contacts that
    /// follow the impacts' speeds").
    pub fn speed_scale(&self, k: usize) -> f64 {
        if !self.contacts_by_speed || k == 0 {
            return 1.0;
        }
        let p0 = self.p();
        let first = self.q[ix::LN_A0].exp() * (p0 * (self.impact(0) - self.release_time())).tanh();
        let (a, b) = self.zeros(k);
        let r = first / (self.q[ix::LN_A].exp() * (0.5 * p0 * (b - a)).tanh());
        let r = if r.is_finite() { r.clamp(1.0 / 50.0, 50.0) } else { 50.0 };
        r.powf(CONTACT_SPEED_EXPONENT)
    }
    fn lag(&self, k: usize) -> f64 {
        if self.layout.contacts {
            self.q[self.layout.lag(k)].exp() * self.speed_scale(k)
        } else {
            0.0
        }
    }
    /// Lead and lag (s) of the contact phase of every impact, when the model has
    /// them.
    pub fn contact_windows(&self) -> Option<Vec<(f64, f64)>> {
        self.layout.contacts.then(|| (0..self.m()).map(|k| (self.lead(k), self.lag(k))).collect())
    }
    pub fn release_time(&self) -> f64 {
        self.q[ix::T_R]
    }
    pub fn p(&self) -> f64 {
        self.q[ix::LN_P0].exp()
    }
    pub fn lambda(&self) -> Option<f64> {
        self.one_sided.then(|| self.q[ix::LAMBDA])
    }
    pub fn gamma(&self) -> Option<f64> {
        self.one_sided.then(|| self.q[ix::GAMMA])
    }
    /// Onset of contact of impact k (the end of free arc k).
    pub fn onset(&self, k: usize) -> f64 {
        self.impact(k) - self.lead(k)
    }
    /// End of the contact of impact k (the start of free arc k+1).
    pub fn release_from_contact(&self, k: usize) -> f64 {
        self.impact(k) + self.delta(k) + self.lag(k)
    }

    /// Length of free arc s (s ≥ 1: between its zeros; the release arc from t_r).
    pub fn arc_length(&self, s: usize) -> f64 {
        if s == 0 {
            self.impact(0) - self.release_time()
        } else {
            let (a, b) = self.zeros(s);
            b - a
        }
    }
    /// Zeros (start, end) of free arc s ≥ 1.
    fn zeros(&self, s: usize) -> (f64, f64) {
        (self.impact(s - 1) + self.delta(s - 1), self.impact(s))
    }
    fn zero_line(&self, t: f64) -> f64 {
        self.q[ix::ZERO] + self.q[ix::DRIFT] * (t - self.t_ref)
    }

    /// Strictly ordered pieces, each at least `min_len` long (or empty), finite values.
    pub fn valid(&self) -> bool {
        if !self.q.iter().all(|v| v.is_finite()) {
            return false;
        }
        let mut prev = self.release_time();
        for k in 0..self.m() {
            let on = self.onset(k);
            if on - prev < self.min_len {
                return false;
            }
            if k >= 1 {
                let (a, b) = self.zeros(k);
                if b - a < self.min_len {
                    return false;
                }
            }
            prev = if k + 1 < self.m() { self.release_from_contact(k) } else { on };
            if prev < on {
                return false;
            }
        }
        let under_damped = self.q[ix::LAMBDA] - self.q[ix::GAMMA].powi(2);
        if self.one_sided && under_damped > 0.0 {
            // The inward arc must stay below half a period (ω T < π, ω² = λ − γ²),
            // so that it has no zero inside.
            let w = under_damped.sqrt();
            for s in (1..self.m()).step_by(2) {
                let (a, b) = self.zeros(s);
                if w * (b - a) >= std::f64::consts::PI {
                    return false;
                }
            }
        }
        true
    }

    /// Every impact's contact phase, (onset, end), computed once for a batch
    /// of evaluations (the last impact's end is its onset: no arc follows it).
    fn bounds(&self) -> Vec<(f64, f64)> {
        let m = self.m();
        (0..m)
            .map(|k| {
                let on = self.onset(k);
                (on, if k + 1 < m { self.release_from_contact(k) } else { on })
            })
            .collect()
    }

    /// The piece owning t ([`Model::bounds`] given); None past the last
    /// impact's onset.
    fn owner(bounds: &[(f64, f64)], t: f64) -> Option<Piece> {
        let m = bounds.len();
        for (k, &(on, end)) in bounds.iter().enumerate() {
            if t < on {
                return Some(Piece::Arc(k));
            }
            if k + 1 < m && t < end {
                return Some(Piece::Contact(k));
            }
        }
        None
    }

    /// L θ of free arc s at t and its time derivative (the zero line excluded).
    ///
    /// - release arc (s = 0): L θ = A0 (1 − cosh(p0 (t − t_r)) / cosh(p0 (t_0 − t_r)))
    ///   after the release, constant before it (the wall is held);
    /// - gravity side (outward; inward in two-sided rocking, with −A):
    ///   L θ = ±A (1 − cosh(p (t − t_m)) / cosh(p T/2)), T the arc's length;
    /// - inward side of one-sided rocking: the arc against a compression-only
    ///   spring–dashpot restraint between its two zeros ([`InwardArc`]).
    pub fn arc(&self, s: usize, t: f64) -> (f64, f64) {
        self.arc_shaped(s, self.shape(s), t)
    }

    /// The shape of arc s: the exact gravity arc ([`GravityArc`], about the
    /// large-angle corrected A and p of [`Model::gravity_arc_params`], which
    /// are the arc where the lever is not known), the solved inward arc of one-sided
    /// rocking ([`InwardArc`]); the release arc has its own A₀ and p₀. They depend
    /// on the parameters only, so a sweep over the samples computes them once
    /// ([`Model::shapes`]).
    fn shape(&self, s: usize) -> Shape {
        let release = self.exact_release();
        self.shape_with(s, release, self.p_small_given(release.is_some()))
    }

    /// [`Model::shape`] with the exact release and p_s already known (one
    /// model's arcs share them: [`Model::shapes`] computes them once).
    fn shape_with(&self, s: usize, release: Option<GravityArc>, ps: f64) -> Shape {
        if s == 0 {
            return release.map_or(Shape::Release, Shape::ExactRelease);
        }
        let (ta, tb) = self.zeros(s);
        if s % 2 == 1 && self.one_sided {
            Shape::Inward(self.inward_arc_with(tb - ta, ps))
        } else {
            let half = 0.5 * (tb - ta);
            let (a, p) = self.gravity_arc_params_with(half, ps);
            match self.exact_arc(half, a, p, ps) {
                Some(arc) => Shape::Exact(arc),
                None => Shape::Gravity { a, p },
            }
        }
    }

    /// The exact gravity arc of half-length `half` (s) for this model's α and
    /// p (p² = p_s² / cos α, p_s = `ps` as [`Model::p_small`] gives it),
    /// about its linearised arc (A_k, p_k of [`Model::gravity_arc_params`]);
    /// None where the lever is not known (infinite) or the arc has no length.
    fn exact_arc(&self, half: f64, a: f64, p: f64, ps: f64) -> Option<GravityArc> {
        if !self.lever.is_finite() {
            return None;
        }
        let alpha = self.alpha();
        GravityArc::solve(alpha, ps / alpha.cos().sqrt(), half, (a / self.lever, p))
    }

    /// The release arc of a two-sided wall as the second half of an exact arc
    /// of Eq. 1 ([`GravityArc`]) of half-length t₀ − t_r, where the lever is known:
    /// from rest at its apex θ₀ at t_r to θ = 0 at t₀. Its rate is p₀ (Eq. 1's
    /// p, which the later arcs share) and its α₀ = atan(A₀/L) its own, so that
    /// the release keeps two free parameters of shape, as its linearised
    /// closed form had (A₀, p₀). That closed form missed the exact releases of
    /// three draws (0.62–0.68 α, walls 2.9–3.8 m high) by 0.002–0.006 mm RMS,
    /// and through p₀ the fit bent the later arcs to it (random draw 1185:
    /// χ²/n 1.48 with exact later arcs, contact phases chosen). One-sided
    /// walls keep the linearised release: with the exact one, three one-sided
    /// MuJoCo fixtures (`tests/truth.rs`) failed what they assert (one test's
    /// pushes at ± 6–13 % instead of under 2 %, one reduced alone flagged for
    /// its exits' residuals, one at 100 Hz flagged for another reason), and
    /// their outward arcs are small, so the release alone sets p there.
    fn exact_release(&self) -> Option<GravityArc> {
        if !self.lever.is_finite() || self.one_sided {
            return None;
        }
        let (a0, p0) = (self.q[ix::LN_A0].exp(), self.p());
        let alpha0 = (a0 / self.lever).atan();
        let half = self.impact(0) - self.release_time();
        let (ak, pk) = linearised_arc(alpha0, p0 * alpha0.cos().sqrt(), half, self.lever);
        GravityArc::solve(alpha0, p0, half, (ak / self.lever, pk))
    }

    /// [`Model::shape`] of every arc, the exact release and p_s computed once.
    fn shapes(&self) -> Vec<Shape> {
        let release = self.exact_release();
        let ps = self.p_small_given(release.is_some());
        (0..self.m()).map(|s| self.shape_with(s, release, ps)).collect()
    }

    /// [`Model::arc`] with the arc's shape given.
    fn arc_shaped(&self, s: usize, shape: Shape, t: f64) -> (f64, f64) {
        match shape {
            Shape::Release => {
                let (a0, p0, tr, t0) = (self.q[ix::LN_A0].exp(), self.p(), self.release_time(), self.impact(0));
                let c = (p0 * (t0 - tr)).cosh();
                let tau = (t - tr).max(0.0);
                (a0 * (1.0 - (p0 * tau).cosh() / c), -a0 * p0 * (p0 * tau).sinh() / c)
            }
            Shape::ExactRelease(arc) => {
                let (th, w) = arc.at((t - self.release_time()).max(0.0));
                (self.lever * th, self.lever * w)
            }
            Shape::Inward(arc) => arc.at(t - self.zeros(s).0),
            Shape::Exact(arc) => {
                let (ta, tb) = self.zeros(s);
                let sign = if s % 2 == 1 { -1.0 } else { 1.0 };
                let (th, w) = arc.at(t - 0.5 * (ta + tb));
                (sign * self.lever * th, sign * self.lever * w)
            }
            Shape::Gravity { a, p } => {
                let (ta, tb) = self.zeros(s);
                let (tm, half) = (0.5 * (ta + tb), 0.5 * (tb - ta));
                let sign = if s % 2 == 1 { -1.0 } else { 1.0 };
                let den = (p * half).cosh();
                let tau = t - tm;
                (sign * a * (1.0 - (p * tau).cosh() / den), -sign * a * p * (p * tau).sinh() / den)
            }
        }
    }

    /// α from A = L tan α (the small-angle limit of the gravity arcs).
    fn alpha(&self) -> f64 {
        (self.q[ix::LN_A].exp() / self.lever).atan()
    }

    /// The free arc of the small amplitudes as this fit found it: its rate p_s
    /// ([`Model::p_small`]) and its centre A (≈ L tan α), mm. The wall's own,
    /// where the manifest's nominal geometry is not (SPEC: real walls never
    /// match it).
    pub fn small_arc(&self) -> (f64, f64) {
        (self.p_small(), self.q[ix::LN_A].exp())
    }

    /// p of the small arcs in the small-angle limit (p_s = p √cos α, the
    /// linearisation of Eq. 1 about θ = 0), from the release arc's p₀. Short
    /// arcs only see the gravity term A p² (their curvature at θ = 0), so p and
    /// A are not separable there and p is tied to the release arc's. Where the
    /// release is exact ([`Model::exact_release`]) p₀ is Eq. 1's p. Where it
    /// is the linearised closed form, whose free fit linearises sin(α − θ)
    /// about θ* = β θ₀ ([`BETA_RELEASE`], θ₀ its height), p₀² = p² cos(α − θ*)
    /// and p_s² = p₀² cos α / cos(α − θ*).
    pub fn p_small(&self) -> f64 {
        self.p_small_given(self.exact_release().is_some())
    }

    /// [`Model::p_small`] where whether the release is exact is known.
    fn p_small_given(&self, exact_release: bool) -> f64 {
        let p0 = self.p();
        if !self.lever.is_finite() {
            return p0;
        }
        let alpha = self.alpha();
        if exact_release {
            return p0 * alpha.cos().sqrt();
        }
        let (a0, tr, t0) = (self.q[ix::LN_A0].exp(), self.release_time(), self.impact(0));
        let theta0 = a0 * (1.0 - 1.0 / (p0 * (t0 - tr)).cosh()) / self.lever;
        p0 * (alpha.cos() / (alpha - BETA_RELEASE * theta0).cos()).sqrt()
    }

    /// A and p of a gravity arc of half-length `half` (s), corrected for its
    /// amplitude. Eq. 1 on a gravity side reads θ'' = −p² sin(α − θ); linearised
    /// about θ* = β θ_m (θ_m the arc's apex, β = [`BETA_ARC`]) it is
    /// θ'' = p_k² (θ − α_k) with
    ///
    ///   p_k² = p² cos(α − θ*),  L α_k = A_k = L [tan(α − θ*) + θ*],
    ///
    /// whose arc is the closed form of [`Model::arc`] with A_k, p_k. For θ_m → 0
    /// they are A = L tan α and p_s (the small-angle arcs). θ_m depends on A_k
    /// and p_k (θ_m = A_k (1 − 1/cosh(p_k T/2)) / L): three fixed-point steps.
    pub fn gravity_arc_params(&self, half: f64) -> (f64, f64) {
        self.gravity_arc_params_with(half, self.p_small())
    }

    /// [`Model::gravity_arc_params`] with p_s given.
    fn gravity_arc_params_with(&self, half: f64, p: f64) -> (f64, f64) {
        if !self.lever.is_finite() {
            return (self.q[ix::LN_A].exp(), p);
        }
        linearised_arc(self.alpha(), p, half, self.lever)
    }

    /// The inward arc of one-sided rocking of length `t_len` (s), its gravity
    /// term corrected for its depth as [`Model::gravity_arc_params`] corrects a
    /// gravity arc. Eq. 1 on the inward side reads θ'' = p² sin(α + θ) − κ θ
    /// (θ < 0, plus the restraint's dashpot); linearised about θ* = −β θ_m
    /// (θ_m the arc's depth, β = [`BETA_ARC`]) it is the arc of
    /// [`InwardArc`] with
    ///
    ///   F_k = L p² [sin(α + θ*) − θ* cos(α + θ*)],  p_k² = p² cos(α + θ*),
    ///   λ_k = κ − p_k² = λ + p_s² − p_k²,
    ///
    /// (p² = p_s² / cos α), which for θ_m → 0 are F = A p_s² and p_s. θ_m
    /// depends on the arc: two fixed-point steps. The same β fits this arc:
    /// least squares of the closed form against the exact arc of the same
    /// length, α 0.08–0.25, κ/p² 0.2–50, depth 0.1–0.75 α, put it at
    /// 0.787–0.814 (shape error 2·10⁻⁴ θ_m at most, against 6·10⁻³ with the
    /// small-angle F and p; a Python check, `docs/estimator.md`).
    pub fn inward_arc(&self, t_len: f64) -> InwardArc {
        self.inward_arc_with(t_len, self.p_small())
    }

    /// [`Model::inward_arc`] with p_s given.
    fn inward_arc_with(&self, t_len: f64, p: f64) -> InwardArc {
        let (a, lambda, gamma) = (self.q[ix::LN_A].exp(), self.q[ix::LAMBDA], self.q[ix::GAMMA]);
        let mut arc = InwardArc::solve(lambda, gamma, a * p * p, p, t_len);
        if !self.lever.is_finite() {
            return arc;
        }
        let alpha = self.alpha();
        let p2 = p * p / alpha.cos();
        for _ in 0..2 {
            let depth = arc.depth() / self.lever;
            if !depth.is_finite() {
                break;
            }
            // Past 0.9 α the wall would fall inward: no arc to correct.
            let ts = -(BETA_ARC * depth).min(0.9 * alpha);
            let (s, c) = (alpha + ts).sin_cos();
            let pk2 = p2 * c;
            let fk = self.lever * p2 * (s - ts * c);
            arc = InwardArc::solve(lambda + p * p - pk2, gamma, fk, pk2.sqrt(), t_len);
        }
        arc
    }

    /// The contact phase of impact k: quintic Hermite ([`quintic_hermite`])
    /// between arc k at its onset and arc k+1 at the end of the contact (the
    /// arcs' shapes given, [`Model::shapes`]).
    fn contact_shaped(&self, k: usize, shapes: &[Shape], bounds: &[(f64, f64)], t: f64) -> (f64, f64) {
        let ((t0, t1), before, after) = (bounds[k], shapes[k], shapes[k + 1]);
        let (y0, v0) = self.arc_shaped(k, before, t0);
        let (y1, v1) = self.arc_shaped(k + 1, after, t1);
        let (a0, a1) = (self.arc_accel(k, before, t0, (y0, v0)), self.arc_accel(k + 1, after, t1, (y1, v1)));
        quintic_hermite([y0, v0, a0], [y1, v1, a1], t1 - t0, t - t0)
    }

    /// Acceleration of arc s at t, from its (y, y') there (the arcs' equations).
    fn arc_accel(&self, s: usize, shape: Shape, t: f64, (y, v): (f64, f64)) -> f64 {
        match shape {
            Shape::Release => {
                let (a0, p0) = (self.q[ix::LN_A0].exp(), self.p());
                if t <= self.release_time() {
                    0.0
                } else {
                    (y - a0) * p0 * p0
                }
            }
            Shape::Inward(arc) => arc.accel(t - self.zeros(s).0, y, v),
            Shape::ExactRelease(arc) => {
                if t <= self.release_time() {
                    0.0
                } else {
                    self.lever * arc.accel(y / self.lever)
                }
            }
            Shape::Exact(arc) => {
                let sign = if s % 2 == 1 { -1.0 } else { 1.0 };
                sign * self.lever * arc.accel(sign * y / self.lever)
            }
            Shape::Gravity { a, p } => {
                let sign = if s % 2 == 1 { -1.0 } else { 1.0 };
                (y - sign * a) * p * p
            }
        }
    }

    /// Modelled reading at t (L θ space) and its slope.
    pub fn eval(&self, t: f64) -> Option<(f64, f64)> {
        self.eval_many(&[t]).next().flatten()
    }

    /// [`Model::eval`] at many times, the arcs' A and p computed once.
    pub fn eval_many<'a>(&'a self, t: &'a [f64]) -> impl Iterator<Item = Option<(f64, f64)>> + 'a {
        let (shapes, bounds) = (self.shapes(), self.bounds());
        t.iter().map(move |&ti| {
            let (f, df) = match Self::owner(&bounds, ti)? {
                Piece::Arc(s) => self.arc_shaped(s, shapes[s], ti),
                Piece::Contact(k) => self.contact_shaped(k, &shapes, &bounds, ti),
            };
            Some((self.zero_line(ti) + f, df + self.q[ix::DRIFT]))
        })
    }

    /// Residuals y − model; false when the parameters are not a valid model.
    pub fn residuals(&self, t: &[f64], y: &[f64], out: &mut Vec<f64>) -> bool {
        out.clear();
        if !self.valid() {
            return false;
        }
        if let Some(f) = &self.filter {
            let seen = f.seen(self, t);
            out.extend(seen.into_iter().zip(y).map(|(m, yi)| m.map_or(0.0, |m| yi - m)));
            return true;
        }
        out.extend(self.eval_many(t).zip(y).map(|(m, yi)| m.map_or(0.0, |(m, _)| yi - m)));
        true
    }

    /// Velocity (mm/s) of the free arcs at the onset of impact k's contact (the
    /// end of arc k; v_k itself is [`Model::peak`]) and just after it.
    pub fn speeds(&self, k: usize) -> (f64, Option<f64>) {
        let drift = self.q[ix::DRIFT];
        let before = self.arc(k, self.onset(k)).1 + drift;
        let after = (k + 1 < self.m()).then(|| self.arc(k + 1, self.release_from_contact(k)).1 + drift);
        (before, after)
    }

    /// The velocity peak v_k of half-cycle k (SPEC): the extreme of the model's
    /// velocity, with the sign of the motion towards impact k, from the last
    /// quarter of free arc k through the contact phase up to the end of the
    /// half-cycle, θ = 0. With instantaneous impacts this is the arc's slope at
    /// t_k (a gravity arc is fastest at its end); with a contact phase the peak
    /// may fall inside it, before the crossing; on a lossy inward arc it may
    /// come before the arc's end. Returns (time, velocity mm/s).
    ///
    /// Where θ = 0 lies has two estimates: the model's own zero (z, where its
    /// arcs are pinned) and the rest line (the sensor's zero after the final
    /// rest is subtracted, `prepare.rs`). With instantaneous impacts the kinks
    /// fix z to the noise and both readings end at the arc's zero; with contact
    /// phases the kinks are smoothed out and z may move by a few mm (one-sided
    /// MuJoCo logs: 1.1–1.9 mm inside the inward side, while the rest line is
    /// within 0.12 mm of the engine's θ = 0; README, accuracy), and a peak
    /// inside the contact phase depends on which zero ends the half-cycle. The
    /// truth is taken as anywhere between the two readings (rectangular): v_k
    /// (and its time) is their mean, and [`Model::peak_spread`] their
    /// difference, a model-form term of its uncertainty (`uncertainty.rs`).
    pub fn peak(&self, k: usize) -> (f64, f64) {
        let (shapes, bounds) = (self.shapes(), self.bounds());
        let a = self.reading(k, &shapes, &bounds, false);
        if !self.layout.contacts {
            // Without contact phases both readings end at the arc's zero.
            return a;
        }
        let b = self.reading(k, &shapes, &bounds, true);
        (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1))
    }

    /// The rest-line reading of v_k minus the model-zero reading (mm/s; see
    /// [`Model::peak`]).
    pub fn peak_spread(&self, k: usize) -> f64 {
        if !self.layout.contacts {
            return 0.0;
        }
        let (shapes, bounds) = (self.shapes(), self.bounds());
        self.reading(k, &shapes, &bounds, true).1 - self.reading(k, &shapes, &bounds, false).1
    }

    /// One reading of v_k: the extreme up to the model's zero, or, with
    /// `rest_line`, up to the later of the model's zero and the rest line.
    fn reading(&self, k: usize, shapes: &[Shape], bounds: &[(f64, f64)], rest_line: bool) -> (f64, f64) {
        let v_end_t = bounds[k].0;
        let v_end = self.arc_shaped(k, shapes[k], v_end_t).1;
        let start = if k == 0 { self.release_time() } else { bounds[k - 1].1 };
        let from = v_end_t - 0.25 * (v_end_t - start);
        let to = bounds[k].1;
        let want = if k.is_multiple_of(2) { -1.0 } else { 1.0 };
        // Half-cycle k lies on the outward side for k even.
        let side = -want;
        let mut best = (v_end_t, v_end);
        const N: usize = 400;
        for i in 0..=N {
            let t = from + (to - from) * i as f64 / N as f64;
            // Arc k up to its end, then the contact phase (never arc k+1: its
            // start speed is the speed after the impact).
            let (y, v) = if t > v_end_t && k + 1 < self.m() {
                self.contact_shaped(k, shapes, bounds, t)
            } else {
                self.arc_shaped(k, shapes[k], t)
            };
            let past_rest_line = !rest_line || side * (y + self.zero_line(t)) < 0.0;
            if side * y < 0.0 && past_rest_line {
                break;
            }
            if want * v > want * best.1 {
                best = (t, v);
            }
        }
        (best.0, best.1 + self.q[ix::DRIFT])
    }

    /// The same model with contact phases (δ = 0, lead = lag = `window` s).
    pub fn with_contacts(&self, window: f64) -> Model {
        let layout = Layout {
            impacts: self.m(),
            contacts: true,
            by_direction: self.one_sided,
        };
        let mut q = self.q[..ix::IMPACT0 + self.m()].to_vec();
        q.extend_from_slice(&[0.0, window.ln(), window.ln()]);
        if layout.by_direction {
            q.extend_from_slice(&[0.0, window.ln(), window.ln()]);
        }
        Model { layout, q, ..self.clone() }
    }

    /// Which parameters a fit frees: all but p (tied to p0), the drift (fixed by
    /// the final rest line), and λ and γ in two-sided rocking.
    pub fn free(&self) -> Vec<usize> {
        (0..self.q.len())
            .filter(|&j| j != ix::LN_P && j != ix::DRIFT)
            .filter(|&j| self.one_sided || (j != ix::LAMBDA && j != ix::GAMMA))
            .collect()
    }
}

/// A fitted model with what the fit knows of its own precision.
#[derive(Debug, Clone)]
pub struct Fitted {
    pub model: Model,
    pub fit: FitResult,
    /// Positions of the fitted parameters in `model.q` (the order of the covariance).
    pub free: Vec<usize>,
}

/// The peaks' covariance from the fit ([`Fitted::peak_covariance`]).
#[derive(Debug, Clone)]
pub struct PeakCovariance {
    /// Σ_v (mm²/s²), on the directions the log determines.
    pub cov: Vec<Vec<f64>>,
    /// For each peak whose speed moves along a direction of the parameters
    /// that the log does not determine ([`crate::fit::FitResult::undetermined`])
    /// and that has no bound ([`Fitted::admissible_spread`]), the parameters of
    /// that direction in words: its uncertainty cannot be computed (the
    /// covariance leaves that direction out). None elsewhere.
    pub undetermined: Vec<Option<String>>,
    /// For each undetermined direction with a bound that some peak depends on:
    /// the peaks' spread e over its admissible range, a fully correlated term
    /// Σ_v += e eᵀ of their covariance ([`Fitted::admissible_spread`]).
    pub bounded: Vec<Vec<f64>>,
}

/// Doublings of the step along an undetermined direction before it is taken
/// as unbounded: 2⁴⁰ finite-difference steps (10⁸ in ln u or ln w of a
/// contact, 10⁶ s in a time), far past any physical range.
const DOUBLINGS: usize = 40;

/// Bisections of the last doubling that failed ([`Fitted::admissible_spread`]):
/// the range's end to 2⁻²⁴ of itself.
const BISECTIONS: usize = 24;

/// A peak depends on a direction the log does not determine when one step
/// along it (its largest component one finite-difference step) moves the
/// speed by more than 10⁻⁹ of itself: far above the rounding of the speeds
/// and their central differences (~10⁻¹⁵), so any real dependence counts (the
/// data bound no part of such a direction, so any slope along it is an
/// unbounded uncertainty). Issue U: 4·10⁻⁸ (the outward contacts' lag).
const DEPENDS: f64 = 1e-9;

impl Fitted {
    /// Standard uncertainty and covariance of the peak speeds v_0..v_{n−1} (mm/s),
    /// propagated from the fit's covariance s² (JᵀJ)⁻¹ by the Jacobian of the
    /// speeds (central differences): Σ_v = G Σ_q Gᵀ; for each direction the
    /// log (`tw`, `yw`: the fitted window) does not determine that a peak
    /// depends on, the peaks' spread over its admissible range where it has
    /// one, otherwise which peaks depend on it (then Σ_v understates them and
    /// must not be stated). None when the fit has no covariance.
    pub fn peak_covariance(&self, n: usize, tw: &[f64], yw: &[f64]) -> Option<PeakCovariance> {
        let cov = self.fit.covariance.as_ref()?;
        let n = n.min(self.model.m());
        let speeds = |m: &Model| -> Vec<f64> { (0..n).map(|k| m.peak(k).1).collect() };
        let np = self.free.len();
        let mut g = vec![vec![0.0; np]; n];
        let mut steps = vec![0.0; np];
        for (c, &j) in self.free.iter().enumerate() {
            let h = step_for(&self.model, j);
            steps[c] = h;
            let mut up = self.model.clone();
            up.q[j] += h;
            let mut dn = self.model.clone();
            dn.q[j] -= h;
            let (a, b) = (speeds(&up), speeds(&dn));
            for k in 0..n {
                g[k][c] = (a[k] - b[k]) / (2.0 * h);
            }
        }
        let mut out = vec![vec![0.0; n]; n];
        for a in 0..n {
            for b in 0..n {
                let mut s = 0.0;
                for i in 0..np {
                    for j in 0..np {
                        s += g[a][i] * cov[(i, j)] * g[b][j];
                    }
                }
                out[a][b] = s;
            }
        }
        let v = speeds(&self.model);
        let mut undetermined: Vec<Option<String>> = vec![None; n];
        let mut bounded = Vec::new();
        for dir in &self.fit.undetermined {
            let depends: Vec<bool> = (0..n)
                .map(|k| {
                    let moved: f64 = (0..np).map(|c| g[k][c] * dir[c]).sum();
                    !moved.is_finite() || moved.abs() > DEPENDS * v[k].abs()
                })
                .collect();
            if !depends.contains(&true) {
                continue;
            }
            if let Some(e) = self.admissible_spread(dir, tw, yw, &v) {
                bounded.push(e);
                continue;
            }
            let names: Vec<String> = (0..np)
                .filter(|&c| dir[c].abs() >= 0.1 * steps[c])
                .map(|c| self.model.layout.name(self.free[c]))
                .collect();
            for (k, slot) in undetermined.iter_mut().enumerate() {
                if depends[k] && slot.is_none() {
                    *slot = Some(names.join(", "));
                }
            }
        }
        Some(PeakCovariance {
            cov: out,
            undetermined,
            bounded,
        })
    }

    /// The peaks' spread over the admissible range of a direction `dir` (in
    /// the fitted parameters) that the log does not determine, or None where
    /// that range has no bound.
    ///
    /// The range: every point q + s·dir whose model is valid and whose cost
    /// on the fitted window stays within one residual variance of the fit's,
    /// cost(s) ≤ cost(0) (1 + 1/(n − p)) (the profile's one-σ interval of a
    /// parameter the data see). A direction no residual sees has a flat cost
    /// up to a physical bound: a contact lag whose end falls between two
    /// samples at every impact of its direction moves freely until that end
    /// reaches a sample (then the sample falls inside the contact phase and the
    /// cost rises), or down to a lag of zero, where the peaks stop changing;
    /// a time ordering that [`Model::valid`] refuses ends it too. Searched by
    /// doubling s from one step in each sign, then bisecting the first
    /// doubling refused ([`BISECTIONS`]). Where [`DOUBLINGS`] doublings are all
    /// admissible, the range has a bound only if the peaks have stopped
    /// changing over the last one (by at most [`DEPENDS`] of themselves, as a
    /// lag of zero); otherwise None.
    ///
    /// The truth is taken as anywhere in the range (rectangular), the fitted
    /// point wherever it lies in it: with lo_k ≤ 0 ≤ hi_k the least and
    /// largest change of peak k over the points visited (the doublings, the
    /// bisections and 16 evenly spaced points), the mean square distance of the
    /// fitted peak from the truth is (lo² + lo hi + hi²)/3 (d²/12 for a fit in
    /// the middle of a range of width d, d²/3 at one end, as
    /// `uncertainty::add_zero_spread` and `add_model_spread`). One cause moves
    /// every peak, so the term is fully correlated: e_k is that root mean
    /// square with the sign of peak k's change from one end of the range to
    /// the other.
    pub fn admissible_spread(&self, dir: &DVector<f64>, tw: &[f64], yw: &[f64], v0: &[f64]) -> Option<Vec<f64>> {
        let n = v0.len();
        let at = |s: f64| {
            let mut m = self.model.clone();
            for (c, &j) in self.free.iter().enumerate() {
                m.q[j] += s * dir[c];
            }
            m
        };
        let cost = |m: &Model| {
            let mut r = Vec::new();
            m.residuals(tw, yw, &mut r)
                .then(|| r.iter().map(|x| x * x).sum::<f64>())
                .filter(|c| c.is_finite())
        };
        let c0 = cost(&self.model)?;
        let dof = tw.len().saturating_sub(self.free.len()).max(1) as f64;
        let allowed = c0 * (1.0 + 1.0 / dof);
        let admissible = |s: f64| -> Option<Vec<f64>> {
            let m = at(s);
            cost(&m).filter(|&c| c <= allowed)?;
            let p: Vec<f64> = (0..n).map(|k| m.peak(k).1).collect();
            p.iter().all(|x| x.is_finite()).then_some(p)
        };
        let mut visited: Vec<(f64, Vec<f64>)> = vec![(0.0, v0.to_vec())];
        let mut ends = [0.0; 2];
        for (end, sign) in ends.iter_mut().zip([-1.0, 1.0]) {
            let (mut good, mut refused) = (0.0, None);
            let mut last: Vec<Vec<f64>> = Vec::new();
            let mut s = 1.0;
            for _ in 0..DOUBLINGS {
                match admissible(sign * s) {
                    Some(p) => {
                        good = s;
                        visited.push((sign * s, p.clone()));
                        last.push(p);
                        s *= 2.0;
                    }
                    None => {
                        refused = Some(s);
                        break;
                    }
                }
            }
            match refused {
                Some(mut bad) => {
                    for _ in 0..BISECTIONS {
                        let mid = 0.5 * (good + bad);
                        match admissible(sign * mid) {
                            Some(p) => {
                                good = mid;
                                visited.push((sign * mid, p));
                            }
                            None => bad = mid,
                        }
                    }
                }
                None => {
                    let settled = last.len() >= 2 && {
                        let (a, b) = (&last[last.len() - 2], &last[last.len() - 1]);
                        (0..n).all(|k| (a[k] - b[k]).abs() <= DEPENDS * v0[k].abs())
                    };
                    if !settled {
                        return None;
                    }
                }
            }
            *end = sign * good;
        }
        for i in 1..16 {
            let s = ends[0] + (ends[1] - ends[0]) * i as f64 / 16.0;
            if let Some(p) = admissible(s) {
                visited.push((s, p));
            }
        }
        let first = visited.iter().min_by(|a, b| a.0.total_cmp(&b.0))?;
        let final_ = visited.iter().max_by(|a, b| a.0.total_cmp(&b.0))?;
        let e = (0..n)
            .map(|k| {
                let (lo, hi) = visited
                    .iter()
                    .map(|(_, p)| p[k] - v0[k])
                    .fold((0.0f64, 0.0f64), |(lo, hi), d| (lo.min(d), hi.max(d)));
                let rms = ((lo * lo + lo * hi + hi * hi) / 3.0).sqrt();
                if final_.1[k] >= first.1[k] {
                    rms
                } else {
                    -rms
                }
            })
            .collect();
        Some(e)
    }
}

/// The quintic Hermite interpolant on [0, h] with value, slope and curvature
/// given at both ends, at x, and its slope: the contact phase joins the two free
/// arcs with continuous acceleration, as a compliant contact's force starts and
/// ends at zero (the wall keeps accelerating a few ms into the contact, which is
/// where its velocity peaks).
fn quintic_hermite(start: [f64; 3], end: [f64; 3], h: f64, x: f64) -> (f64, f64) {
    let s = x / h;
    let (s2, s3, s4, s5) = (s * s, s * s * s, s.powi(4), s.powi(5));
    let b = [
        1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5,
        s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5,
        0.5 * (s2 - 3.0 * s3 + 3.0 * s4 - s5),
        10.0 * s3 - 15.0 * s4 + 6.0 * s5,
        -4.0 * s3 + 7.0 * s4 - 3.0 * s5,
        0.5 * (s3 - 2.0 * s4 + s5),
    ];
    let d = [
        -30.0 * s2 + 60.0 * s3 - 30.0 * s4,
        1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4,
        s - 4.5 * s2 + 6.0 * s3 - 2.5 * s4,
        30.0 * s2 - 60.0 * s3 + 30.0 * s4,
        -12.0 * s2 + 28.0 * s3 - 15.0 * s4,
        1.5 * s2 - 4.0 * s3 + 2.5 * s4,
    ];
    let y = b[0] * start[0] + b[1] * h * start[1] + b[2] * h * h * start[2] + b[3] * end[0] + b[4] * h * end[1] + b[5] * h * h * end[2];
    let v = (d[0] * start[0] + d[3] * end[0]) / h + d[1] * start[1] + d[4] * end[1] + h * (d[2] * start[2] + d[5] * end[2]);
    (y, v)
}

/// Finite-difference step of parameter j.
fn step_for(model: &Model, j: usize) -> f64 {
    let l = model.layout;
    let is_contact = l.contacts && j >= ix::IMPACT0 + l.impacts;
    match j {
        _ if is_contact => 1e-4,
        _ if j >= ix::T_R && j != ix::GAMMA => 1e-6,
        ix::LAMBDA | ix::GAMMA => 1e-6 * model.q[j].abs().max(1.0),
        _ => 1e-7 * model.q[j].abs().max(1e-3),
    }
}

/// Fit a [`Model`] by Levenberg–Marquardt ([`crate::fit`]) over [`Model::free`].
pub fn fit_model(model: Model, t: &[f64], y: &[f64], max_iter: usize) -> Option<Fitted> {
    let free = model.free();
    let with = |qf: &[f64]| {
        let mut m = model.clone();
        for (k, &j) in free.iter().enumerate() {
            m.q[j] = qf[k];
        }
        m
    };
    let resid = |qf: &[f64]| {
        let mut r = Vec::with_capacity(t.len());
        with(qf).residuals(t, y, &mut r).then_some(r)
    };
    let q0: Vec<f64> = free.iter().map(|&j| model.q[j]).collect();
    let steps: Vec<f64> = free.iter().map(|&j| step_for(&model, j)).collect();
    let fit = levenberg_marquardt(&q0, &steps, max_iter, &resid)?;
    Some(Fitted {
        model: with(&fit.q),
        fit,
        free,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_sided(contacts: bool) -> Model {
        let mut q = vec![0.0, 0.0, 100f64.ln(), 2f64.ln(), 0.0, 150f64.ln(), 2f64.ln(), 0.0, 0.0];
        q.extend_from_slice(&[0.5, 1.5, 2.4]);
        let m = Model {
            one_sided: false,
            layout: Layout {
                impacts: 3,
                contacts: false,
                by_direction: false,
            },
            t_ref: 0.0,
            min_len: 1e-3,
            lever: f64::INFINITY,
            q,
            filter: None,
            contacts_by_speed: false,
        };
        if contacts {
            m.with_contacts(0.01)
        } else {
            m
        }
    }

    /// Where the lever is known, the gravity arcs and the release solve Eq. 1
    /// itself: y = ±L θ with θ'' = −p² sin(α − θ) (α = atan(A/L) and p = p₀
    /// for the later arcs, α₀ = atan(A₀/L) for the release), by central
    /// differences, zero at the impacts, and the release at rest at t_r.
    #[test]
    fn arcs_solve_eq1_where_the_lever_is_known() {
        let mut m = two_sided(false);
        m.lever = 1000.0;
        let p = m.p();
        assert!((m.p_small() - p * (0.1f64.atan()).cos().sqrt()).abs() < 1e-12);
        for (s, alpha) in [(0, 0.15f64.atan()), (1, 0.1f64.atan()), (2, 0.1f64.atan())] {
            let (ta, tb) = if s == 0 { (m.release_time(), m.impact(0)) } else { m.zeros(s) };
            let sign = if s % 2 == 1 { -1.0 } else { 1.0 };
            assert!(m.arc(s, tb).0.abs() < 1e-9, "arc {s} at its end: {}", m.arc(s, tb).0);
            if s > 0 {
                assert!(m.arc(s, ta).0.abs() < 1e-9, "arc {s} at its start");
            } else {
                assert!(m.arc(0, ta).1.abs() < 1e-9, "the release starts from rest");
            }
            let h = 1e-3;
            for f in [0.1, 0.3, 0.5, 0.7, 0.9] {
                let t = ta + f * (tb - ta);
                let (y, v) = m.arc(s, t);
                let ypp = (m.arc(s, t + h).0 - 2.0 * y + m.arc(s, t - h).0) / (h * h);
                let eq1 = sign * m.lever * (-p * p * (alpha - sign * y / m.lever).sin());
                assert!((ypp - eq1).abs() < 1e-3, "arc {s} at {t}: y'' {ypp} against Eq. 1 {eq1}");
                let vd = (m.arc(s, t + h).0 - m.arc(s, t - h).0) / (2.0 * h);
                assert!((vd - v).abs() < 1e-3, "arc {s} at {t}: slope {v} against {vd}");
            }
        }
    }

    /// The contact phase joins the arcs continuously in value, slope and
    /// curvature (a compliant contact's force starts and ends at zero).
    #[test]
    fn contact_phase_is_continuous() {
        assert_contacts_join(&two_sided(true));
        // The exact arcs too (a known lever), and the peak stays at the arcs' speeds.
        let mut m = two_sided(true);
        m.lever = 1000.0;
        assert_contacts_join(&m);
        for k in 0..2 {
            let (_, v) = m.peak(k);
            let (before, _) = m.speeds(k);
            assert!((v / before - 1.0).abs() < 0.05, "k {k}: peak {v} against the arc's {before}");
        }
    }

    fn assert_contacts_join(m: &Model) {
        // One-sided differences: their error, h y'''/2, is 10⁻⁴ of y'' here.
        let h = 1e-7;
        for k in 0..2 {
            for t in [m.onset(k), m.release_from_contact(k)] {
                let (a, va) = m.eval(t - 1e-9).unwrap();
                let (b, vb) = m.eval(t + 1e-9).unwrap();
                assert!((a - b).abs() < 1e-5 && (va - vb).abs() < 1e-3, "k {k} t {t}: {a} {b} {va} {vb}");
                let before = (m.eval(t - 1e-9).unwrap().1 - m.eval(t - h).unwrap().1) / h;
                let after = (m.eval(t + h).unwrap().1 - m.eval(t + 1e-9).unwrap().1) / h;
                assert!((before - after).abs() < 1e-3 * before.abs().max(1.0), "k {k} t {t}: y'' {before} {after}");
            }
        }
    }

    /// Contact phases that follow the impacts' speeds: impact 0's is the time
    /// leads' own, a later one's lead and lag are both (v̂₀/v̂_k)^½ times
    /// longer, a slower (shorter) arc's contact the longer, and the phases
    /// still join the arcs continuously.
    #[test]
    fn contacts_by_speed_grow_as_the_impacts_slow() {
        let time = two_sided(true);
        let mut speed = time.clone();
        speed.contacts_by_speed = true;
        let (w_time, w_speed) = (time.contact_windows().unwrap(), speed.contact_windows().unwrap());
        assert_eq!(w_time[0], w_speed[0]);
        let v_hat = |k: usize| {
            let p = speed.p();
            if k == 0 {
                150.0 * (p * (speed.impact(0) - speed.release_time())).tanh()
            } else {
                100.0 * (0.5 * p * speed.arc_length(k)).tanh()
            }
        };
        for k in 1..3 {
            let s = (v_hat(0) / v_hat(k)).sqrt();
            assert!(
                (w_speed[k].0 / w_time[k].0 - s).abs() < 1e-12,
                "k {k}: lead {:?} {:?}, s {s}",
                w_speed[k],
                w_time[k]
            );
            assert!(
                (w_speed[k].1 / w_time[k].1 - s).abs() < 1e-12,
                "k {k}: lag {:?} {:?}, s {s}",
                w_speed[k],
                w_time[k]
            );
        }
        assert!(speed.arc_length(2) < speed.arc_length(1) && speed.speed_scale(2) > speed.speed_scale(1));
        assert_contacts_join(&speed);
    }

    /// The quintic reproduces any polynomial of degree ≤ 5 from its end values.
    #[test]
    fn quintic_hermite_is_exact_on_quintics() {
        let c = [0.3, -1.2, 2.0, 0.7, -3.1, 1.9];
        let f = |x: f64| c.iter().enumerate().map(|(i, a)| a * x.powi(i as i32)).sum::<f64>();
        let df = |x: f64| {
            c.iter()
                .enumerate()
                .skip(1)
                .map(|(i, a)| i as f64 * a * x.powi(i as i32 - 1))
                .sum::<f64>()
        };
        let d2f = |x: f64| {
            c.iter()
                .enumerate()
                .skip(2)
                .map(|(i, a)| (i * (i - 1)) as f64 * a * x.powi(i as i32 - 2))
                .sum::<f64>()
        };
        let (x0, h) = (0.4, 0.9);
        for x in [0.0, 0.2, 0.5, 0.9] {
            let (y, v) = quintic_hermite([f(x0), df(x0), d2f(x0)], [f(x0 + h), df(x0 + h), d2f(x0 + h)], h, x);
            assert!((y - f(x0 + x)).abs() < 1e-12 && (v - df(x0 + x)).abs() < 1e-11, "x {x}: {y} {v}");
        }
    }

    /// v_k is read where the wall is fastest: past the onset of contact, where
    /// the free arc's acceleration still acts (the quintic keeps it), not at the
    /// onset; and the free arc there is slower than at its zero.
    #[test]
    fn peak_past_the_onset_of_contact() {
        let (m0, m1) = (two_sided(false), two_sided(true));
        for k in 0..2 {
            assert!((m1.impact(k) - m1.onset(k) - 0.01).abs() < 1e-12);
            let (v_onset, _) = m1.speeds(k);
            assert!((m1.arc(k, m1.onset(k)).1 - v_onset).abs() < 1e-9);
            assert!(v_onset.abs() < m0.speeds(k).0.abs(), "k {k}: a gravity arc is slower before its end");
            let (t_peak, v_peak) = m1.peak(k);
            assert!(
                t_peak > m1.onset(k) && v_peak.abs() > v_onset.abs(),
                "k {k}: peak {t_peak} {v_peak}, onset {v_onset}"
            );
        }
    }

    /// Where the model's zero and the rest line differ, v_k is the mean of the
    /// readings up to each, and the spread is their difference: zero where
    /// they agree, and zero without contact phases (both readings end at the
    /// arc's zero).
    #[test]
    fn peak_between_the_model_zero_and_the_rest_line() {
        let mut m = two_sided(true);
        // A contact that starts 1 ms before the zero and lasts 30 ms after it,
        // into an arc longer (faster at its start) than the one before: the
        // velocity still rises past the model's zero.
        m.q[m.layout.lead(0)] = 0.001f64.ln();
        m.q[m.layout.lag(0)] = 0.03f64.ln();
        m.q[ix::IMPACT0 + 2] = 3.2;
        assert!(m.valid());
        assert!((0..3).all(|k| m.peak_spread(k) == 0.0), "the zero on the rest line");
        // The model's zero 3 mm below the rest line: the half-cycles on the
        // inward side (k odd) end later at the rest line than at the model's zero.
        m.q[ix::ZERO] = -3.0;
        let (shapes, bounds) = (m.shapes(), m.bounds());
        let mut spread = 0.0;
        for k in 0..2 {
            let want = if k % 2 == 0 { -1.0 } else { 1.0 };
            let (a, b) = (m.reading(k, &shapes, &bounds, false), m.reading(k, &shapes, &bounds, true));
            let (t, v) = m.peak(k);
            assert!((v - 0.5 * (a.1 + b.1)).abs() < 1e-12 && (t - 0.5 * (a.0 + b.0)).abs() < 1e-12);
            assert!((m.peak_spread(k) - (b.1 - a.1)).abs() < 1e-12);
            // The rest-line reading searches a longer stretch: never slower.
            assert!(want * (b.1 - a.1) >= 0.0, "k {k}: {a:?} {b:?}");
            if k % 2 == 0 {
                assert_eq!(a, b, "k {k}: the model's zero comes later");
            }
            spread += (b.1 - a.1).abs();
        }
        assert!(spread > 1.0, "the inward half-cycle's reading moved by {spread} mm/s");
        let mut plain = two_sided(false);
        plain.q[ix::ZERO] = -3.0;
        assert!((0..3).all(|k| plain.peak_spread(k) == 0.0), "no contact phases");
    }

    /// A contact that falls between two samples (issue U): its lag moves no
    /// residual until the contact's end reaches the next sample, so it is
    /// undetermined yet bounded, from zero up to that sample. The peaks it
    /// moves get the root mean square distance from their values over that
    /// range (here computed on a fine grid of lags); a direction that moves
    /// no peak and no residual adds nothing.
    #[test]
    fn a_contact_between_two_samples_is_bounded_by_them() {
        // Contacts of 2 ms on either side of t_k = 0.5, 1.5, 2.4 s; samples at
        // 100 Hz, 5 ms off the impacts: none inside a contact.
        let model = two_sided(false).with_contacts(0.002);
        let t: Vec<f64> = (0..239).map(|i| 0.005 + 0.01 * i as f64).collect();
        let y: Vec<f64> = model.eval_many(&t).map(|m| m.unwrap().0).collect();
        let free = model.free();
        let lag = free.iter().position(|&j| j == model.layout.lag(0)).unwrap();
        let fit = FitResult {
            q: free.iter().map(|&j| model.q[j]).collect(),
            cost: 0.0,
            residuals: vec![0.0; t.len()],
            iterations: 0,
            stop: crate::fit::FitStop::Converged,
            covariance: None,
            undetermined: Vec::new(),
        };
        let fitted = Fitted {
            model: model.clone(),
            fit,
            free,
        };
        let v0: Vec<f64> = (0..3).map(|k| model.peak(k).1).collect();
        let mut dir = DVector::zeros(fitted.free.len());
        dir[lag] = 1e-4;
        let e = fitted.admissible_spread(&dir, &t, &y, &v0).expect("bounded");
        // The lag's range: (0, 5 ms] (the contact of impact 0 ends at
        // 0.502 s, the next sample is 0.505 s; impact 1's is 1.502 and 1.505).
        let mut m = model.clone();
        let (mut lo, mut hi) = ([0.0f64; 3], [0.0f64; 3]);
        for i in 1..=5000 {
            m.q[m.layout.lag(0)] = (1e-6 * i as f64).ln();
            for k in 0..3 {
                let d = m.peak(k).1 - v0[k];
                lo[k] = lo[k].min(d);
                hi[k] = hi[k].max(d);
            }
        }
        for k in 0..2 {
            let want = ((lo[k] * lo[k] + lo[k] * hi[k] + hi[k] * hi[k]) / 3.0).sqrt();
            assert!(want > 1.0, "peak {k} depends on the lag: {want} mm/s");
            assert!((e[k].abs() / want - 1.0).abs() < 0.01, "peak {k}: {} against {want}", e[k]);
        }
        // Up to 5 ms no residual moves; beyond, a sample is inside the contact.
        let mut r = Vec::new();
        for (w, seen) in [(0.0049f64, false), (0.0051, true)] {
            m.q[m.layout.lag(0)] = w.ln();
            assert!(m.residuals(&t, &y, &mut r));
            assert_eq!(
                r.iter().any(|r| *r != 0.0),
                seen,
                "lag {w}: {:e}",
                r.iter().fold(0.0f64, |a, r| a.max(r.abs()))
            );
        }
        // The drift is not a fitted parameter; the sensor zero is seen by
        // every residual: one step of it is refused at once, and moves every
        // peak by nothing (the zero line is not part of a speed).
        let zero = fitted.free.iter().position(|&j| j == ix::ZERO).unwrap();
        let mut dz = DVector::zeros(fitted.free.len());
        dz[zero] = 1e-7;
        let e = fitted.admissible_spread(&dz, &t, &y, &v0).expect("bounded at once");
        assert!(e.iter().all(|e| e.abs() < 1e-9), "{e:?}");
    }

    /// Two impacts may not collapse onto one instant.
    #[test]
    fn collapsed_impacts_are_invalid() {
        let mut m = two_sided(false);
        assert!(m.valid());
        m.q[ix::IMPACT0 + 1] = m.q[ix::IMPACT0] + 1e-4;
        assert!(!m.valid());
    }

    /// The exact arc of Eq. 1 on a gravity side, θ'' = −p² sin(α − θ), from its
    /// apex θ_m at t = 0 down to θ = 0 (RK4, 20 000 steps): (time to θ = 0, the
    /// samples (t, θ)).
    fn exact_half_arc(alpha: f64, p: f64, theta_m: f64) -> (f64, Vec<(f64, f64)>) {
        let f = |th: f64| -p * p * (alpha - th).sin();
        let (mut t, mut th, mut w) = (0.0, theta_m, 0.0);
        let h = 1e-5;
        let mut out = vec![(0.0, theta_m)];
        while th > 0.0 {
            let (k1, l1) = (w, f(th));
            let (k2, l2) = (w + 0.5 * h * l1, f(th + 0.5 * h * k1));
            let (k3, l3) = (w + 0.5 * h * l2, f(th + 0.5 * h * k2));
            let (k4, l4) = (w + h * l3, f(th + h * k3));
            let (th1, w1) = (
                th + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4),
                w + h / 6.0 * (l1 + 2.0 * l2 + 2.0 * l3 + l4),
            );
            if th1 <= 0.0 {
                // The last fraction of a step, linearly: enough at h = 10 µs.
                t += h * th / (th - th1);
                break;
            }
            (t, th, w) = (t + h, th1, w1);
            out.push((t, th));
        }
        (t, out)
    }

    /// A 0.7 α arc of a squat wall (α = 0.25): with the amplitude correction the
    /// closed form follows the exact arc of the same length to 3·10⁻⁴ θ_m and its
    /// speed at θ = 0 to 0.2 %; the small-angle A and p miss the shape by
    /// 7·10⁻³ θ_m (the Python check in the commit that added the correction:
    /// 2·10⁻⁴ and 6.8·10⁻³).
    #[test]
    fn amplitude_correction_follows_the_exact_arc() {
        let (alpha, p, lever) = (0.25f64, 2.5f64, 1000.0);
        let theta_m = 0.7 * alpha;
        let (half, samples) = exact_half_arc(alpha, p, theta_m);
        let v_exact = p * (2.0 * (alpha.cos() - (alpha - theta_m).cos())).abs().sqrt() * lever;
        let mut m = two_sided(false);
        m.lever = lever;
        // A = L tan α; the release exact with p₀ = p, so that p_s = p √cos α.
        m.q[ix::LN_A] = (lever * alpha.tan()).ln();
        m.q[ix::LN_P0] = p.ln();
        m.q[ix::LN_A0] = (1e-9f64).ln();
        assert!((m.p_small() / (p * alpha.cos().sqrt()) - 1.0).abs() < 1e-12);
        let arc = |a: f64, pk: f64, tau: f64| (a * (1.0 - (pk * tau).cosh() / (pk * half).cosh()), a * pk * (pk * half).tanh());
        let rms = |a: f64, pk: f64| {
            let s: f64 = samples.iter().map(|&(t, th)| (arc(a, pk, t).0 - lever * th).powi(2)).sum();
            (s / samples.len() as f64).sqrt() / (lever * theta_m)
        };
        let (ak, pk) = m.gravity_arc_params(half);
        let (a0, p0) = (lever * alpha.tan(), p * alpha.cos().sqrt());
        let corrected = rms(ak, pk);
        let small = rms(a0, p0);
        assert!(corrected < 3e-4, "corrected shape error {corrected:.2e}");
        assert!(small > 5e-3, "small-angle shape error {small:.2e}");
        let v = arc(ak, pk, 0.0).1;
        assert!((v / v_exact - 1.0).abs() < 2e-3, "speed {v} against {v_exact}");
    }
}

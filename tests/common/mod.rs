//! Shared by the integration tests: free-rocking logs generated with the project's
//! own solver and a realistic sensor, with their exact velocity peaks.

#![allow(dead_code)]

use rocklab::solver::{simulate_at, Event, Ground, Restraint, RockingModel, Settings, Simulation};
use rocklab::wall::{p_squared_rectangular, slenderness};

/// Deterministic noise (xorshift + Box–Muller), so no extra crate.
pub struct Rng(pub u64);

impl Rng {
    pub fn uniform(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    pub fn normal(&mut self) -> f64 {
        (-2.0 * self.uniform().ln()).sqrt() * (2.0 * std::f64::consts::PI * self.uniform()).cos()
    }
}

/// What a generated test is made of.
pub struct LogSpec {
    /// Inward spring k/I_0 (s⁻²); 0 for two-sided rocking.
    pub kappa: f64,
    pub e_in: f64,
    pub e_out: f64,
    pub fs: f64,
    pub sigma_mm: f64,
    pub drift_mm: f64,
    pub x0_mm: f64,
    pub seed: u64,
}

/// The demo wall above its hinge: h = 2.47 m, b = 0.36 m, lever arm 2.33 m.
pub const LEVER_MM: f64 = 2330.0;

/// Free rocking of `model` released from rest at θ0 at `t_r`, the ground still,
/// tight tolerances: the simulation and θ at each time of `t`.
pub fn free_rocking(model: &RockingModel, t: &[f64], t_r: f64, theta0: f64, duration: f64) -> (Simulation, Vec<f64>) {
    let ground = Ground {
        t0: 0.0,
        dt: 1.0,
        acc: vec![0.0, 0.0],
    };
    let mut settings = Settings::new(duration).with_tolerances(1e-11, 1e-14);
    settings.rest_speed = 1e-9;
    simulate_at(model, &ground, t_r, Some([theta0, 0.0]), &settings, t).expect("valid settings")
}

/// A log (CSV text with `time_s,disp_mm`: hold, release at 1.3 s, rocking, rest;
/// 8 s; quantised to 0.01 mm) and the exact velocity peaks L θ' before each impact.
pub fn synthetic_log(s: &LogSpec) -> (String, Vec<f64>) {
    let (h, b) = (2.47, 0.36);
    let model = RockingModel {
        alpha: slenderness(b, h),
        p2: p_squared_rectangular(h, b),
        i0: 1.0,
        restraint: if s.kappa > 0.0 {
            Restraint::Rotational { k_nm_per_rad: s.kappa }
        } else {
            Restraint::None
        },
        ties: Vec::new(),
        e_in: s.e_in,
        e_out: s.e_out,
        law: None,
        overturn_limit: 1.0,
        linearized: false,
    };
    let duration = 8.0;
    let n = (duration * s.fs) as usize;
    let t: Vec<f64> = (0..n).map(|i| i as f64 / s.fs).collect();
    let t_r = 1.3 + 0.37 / s.fs;
    let theta0 = (s.x0_mm / LEVER_MM).asin();
    let (sim, th) = free_rocking(&model, &t, t_r, theta0, duration);
    let peaks = sim
        .events
        .iter()
        .filter_map(|e| match e {
            Event::Impact { v_before, .. } => Some(LEVER_MM * v_before),
            _ => None,
        })
        .collect();
    let mut rng = Rng(s.seed);
    let mut out = String::from("# synthetic\ntime_s,disp_mm\n");
    for (ti, thi) in t.iter().zip(&th) {
        let x = LEVER_MM * thi.sin() + s.drift_mm * ti / duration + s.sigma_mm * rng.normal();
        out.push_str(&format!("{ti:.4},{:.2}\n", (x * 100.0).round() / 100.0));
    }
    (out, peaks)
}

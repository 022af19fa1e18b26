//! Dormand–Prince 5(4) (Dormand & Prince 1980; Hairer, Nørsett & Wanner, Solving
//! ODEs I, §II.5 and §II.6) with the 4th-order continuous extension of DOPRI5, for
//! a two-dimensional first-order system y' = f(t, y). The caller drives the steps
//! (so that no step straddles a kink of the forcing) and locates events on the
//! dense output.

/// State: [θ, θ'].
pub type State = [f64; 2];

const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const A71: f64 = 35.0 / 384.0;
const A73: f64 = 500.0 / 1113.0;
const A74: f64 = 125.0 / 192.0;
const A75: f64 = -2187.0 / 6784.0;
const A76: f64 = 11.0 / 84.0;
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

#[inline]
fn axpy(y: &State, terms: &[(f64, &State)]) -> State {
    let mut out = *y;
    for (c, k) in terms {
        out[0] += c * k[0];
        out[1] += c * k[1];
    }
    out
}

/// Dense output of one accepted step (DOPRI5's `contd5`).
#[derive(Debug, Clone, Copy)]
pub struct Dense {
    pub t0: f64,
    pub h: f64,
    r: [State; 5],
}

impl Dense {
    /// State at t in [t0, t0 + h].
    pub fn at(&self, t: f64) -> State {
        let s = (t - self.t0) / self.h;
        let s1 = 1.0 - s;
        let r = &self.r;
        let mut y = [0.0; 2];
        for i in 0..2 {
            y[i] = r[0][i] + s * (r[1][i] + s1 * (r[2][i] + s * (r[3][i] + s1 * r[4][i])));
        }
        y
    }
}

/// Result of one attempted step.
pub struct Step {
    pub y1: State,
    /// f(t + h, y1), the first stage of the next step (FSAL).
    pub k7: State,
    /// Scaled error norm (accept when ≤ 1).
    pub err: f64,
    pub dense: Dense,
}

/// Tolerances: the step is accepted when the error of every component is below
/// atol + rtol·|y|.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    pub rtol: f64,
    pub atol: f64,
}

/// One Dormand–Prince step of size h from (t, y) with k1 = f(t, y).
pub fn step(f: &mut impl FnMut(f64, &State) -> State, t: f64, y: &State, k1: &State, h: f64, tol: Tolerances) -> Step {
    let k2 = f(t + C2 * h, &axpy(y, &[(h * A21, k1)]));
    let k3 = f(t + C3 * h, &axpy(y, &[(h * A31, k1), (h * A32, &k2)]));
    let k4 = f(t + C4 * h, &axpy(y, &[(h * A41, k1), (h * A42, &k2), (h * A43, &k3)]));
    let k5 = f(t + C5 * h, &axpy(y, &[(h * A51, k1), (h * A52, &k2), (h * A53, &k3), (h * A54, &k4)]));
    let k6 = f(
        t + h,
        &axpy(y, &[(h * A61, k1), (h * A62, &k2), (h * A63, &k3), (h * A64, &k4), (h * A65, &k5)]),
    );
    let y1 = axpy(y, &[(h * A71, k1), (h * A73, &k3), (h * A74, &k4), (h * A75, &k5), (h * A76, &k6)]);
    let k7 = f(t + h, &y1);
    let mut err2 = 0.0;
    let mut r = [[0.0; 2]; 5];
    for i in 0..2 {
        let e = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        let sc = tol.atol + tol.rtol * y[i].abs().max(y1[i].abs());
        err2 += (e / sc).powi(2);
        let ydiff = y1[i] - y[i];
        let bspl = h * k1[i] - ydiff;
        r[0][i] = y[i];
        r[1][i] = ydiff;
        r[2][i] = bspl;
        r[3][i] = ydiff - h * k7[i] - bspl;
        r[4][i] = h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
    }
    Step {
        y1,
        k7,
        err: (err2 / 2.0).sqrt(),
        dense: Dense { t0: t, h, r },
    }
}

/// Next step size from the error norm (safety 0.9, growth in [0.2, 5]).
pub fn next_h(h: f64, err: f64) -> f64 {
    let fac = if err == 0.0 { 5.0 } else { (0.9 * err.powf(-0.2)).clamp(0.2, 5.0) };
    h * fac
}

/// Root of g on [a, b] given g(a)·g(b) ≤ 0 (Illinois false position, then
/// bisection guard), to |b − a| ≤ xtol.
pub fn find_root(g: impl Fn(f64) -> f64, mut a: f64, mut b: f64, xtol: f64) -> f64 {
    let mut fa = g(a);
    let mut fb = g(b);
    if fa == 0.0 {
        return a;
    }
    if fb == 0.0 {
        return b;
    }
    let mut side = 0;
    for _ in 0..200 {
        if (b - a).abs() <= xtol {
            break;
        }
        let mut c = (a * fb - b * fa) / (fb - fa);
        if !(c > a.min(b) && c < a.max(b)) {
            c = 0.5 * (a + b);
        }
        let fc = g(c);
        if fc == 0.0 {
            return c;
        }
        if fc * fb < 0.0 {
            a = b;
            fa = fb;
            b = c;
            fb = fc;
            side = 0;
        } else {
            b = c;
            fb = fc;
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
        let _ = fa;
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Harmonic oscillator y'' = −y over one period: error well below tolerance,
    /// and the dense output matches the exact solution inside steps.
    #[test]
    fn harmonic_oscillator_and_dense_output() {
        let tol = Tolerances { rtol: 1e-10, atol: 1e-12 };
        let mut f = |_t: f64, y: &State| [y[1], -y[0]];
        let (mut t, mut y) = (0.0, [1.0, 0.0]);
        let mut k1 = f(t, &y);
        let mut h: f64 = 1e-3;
        let end = 2.0 * std::f64::consts::PI;
        let mut worst_dense: f64 = 0.0;
        while t < end {
            let hh = h.min(end - t);
            let s = step(&mut f, t, &y, &k1, hh, tol);
            if s.err <= 1.0 {
                let tm = t + 0.37 * hh;
                let d = s.dense.at(tm);
                worst_dense = worst_dense.max((d[0] - tm.cos()).abs());
                t += hh;
                y = s.y1;
                k1 = s.k7;
            }
            h = next_h(hh, s.err);
        }
        assert!((y[0] - 1.0).abs() < 1e-8 && y[1].abs() < 1e-8, "{y:?}");
        assert!(worst_dense < 1e-8, "dense {worst_dense}");
    }

    #[test]
    fn root_finder() {
        let r = find_root(|x| x * x - 2.0, 0.0, 2.0, 1e-14);
        assert!((r - 2f64.sqrt()).abs() < 1e-12);
    }
}

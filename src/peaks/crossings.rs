//! Rough impact times: zero crossings of the prepared log with hysteresis.

/// Zero crossings of x − rest after `start`, with hysteresis: a new side counts
/// once two consecutive samples lie beyond 2.5 σ on it, or one beyond 5 σ. The
/// crossing time is the linear interpolation of the last sign change before the
/// confirmation. A last side that never confirms its end gets the first sign change
/// after its extreme (the late half-cycles of one-sided rocking are tiny).
pub(super) fn find_crossings(t: &[f64], x: &[f64], rest: f64, sigma: f64, start: usize, max: usize) -> Vec<f64> {
    let y = |i: usize| x[i] - rest;
    let n = x.len();
    let mut out: Vec<f64> = Vec::new();
    let mut side = 1.0; // outward at release
    let mut last_confirm = start;
    let mut i = start;
    while i + 1 < n && out.len() < max {
        let a = -side * y(i);
        let b = -side * y(i + 1);
        if (a > 2.5 * sigma && b > 2.5 * sigma) || a > 5.0 * sigma {
            // Last sign change in [last_confirm, i].
            let mut j = i;
            while j > last_confirm && side * y(j - 1) <= 0.0 {
                j -= 1;
            }
            let j0 = j.saturating_sub(1).max(last_confirm);
            let (ya, yb) = (y(j0), y(j));
            let tc = if j0 < j && ya != yb {
                t[j0] + (t[j] - t[j0]) * ya / (ya - yb)
            } else {
                t[j]
            };
            // Free rocking only slows down: a half-cycle never lasts more than
            // three times the longer of the previous one and the previous one on
            // the same side (the release arc counted from the departure). A later
            // "crossing" is noise at rest (two samples beyond 2.5 σ happen in long
            // records): the motion ended unconfirmed, and the fallback below finds
            // its last crossing.
            if !out.is_empty() && tc - out[out.len() - 1] > 3.0 * longest_recent(t[start], &out) {
                break;
            }
            out.push(tc);
            side = -side;
            last_confirm = i;
        }
        i += 1;
    }
    if out.len() < max && !out.is_empty() {
        // We are on side `side`, confirmed at `last_confirm`. Its end is the first
        // sign change after its extreme, looked for within 1.5 × the previous
        // half-cycle (a later one would be noise at rest, not rocking).
        let prev = if out.len() >= 2 {
            out[out.len() - 1] - out[out.len() - 2]
        } else {
            // The release arc is about half a half-cycle, hence the factor 2 after it.
            2.0 * (out[0] - t[start])
        };
        let t_last = out[out.len() - 1];
        let stop = t.partition_point(|&v| v < t_last + 1.5 * prev).min(n);
        let begin = t.partition_point(|&v| v <= t_last).min(n.saturating_sub(1));
        let mut ext = begin;
        for k in begin..stop {
            if side * y(k) > side * y(ext) {
                ext = k;
            }
        }
        if side * y(ext) > 2.0 * sigma {
            if let Some(j) = (ext..stop.saturating_sub(1)).find(|&k| side * y(k) > 0.0 && side * y(k + 1) <= 0.0) {
                let (ya, yb) = (y(j), y(j + 1));
                out.push(t[j] + (t[j + 1] - t[j]) * ya / (ya - yb));
            }
        }
    }
    out
}

/// The longer of the last two half-cycles before the one ending now (the release
/// arc runs from the departure `t0` to the first crossing).
pub(super) fn longest_recent(t0: f64, out: &[f64]) -> f64 {
    let mut b = vec![t0];
    b.extend_from_slice(out);
    let n = b.len();
    let last = b[n - 1] - b[n - 2];
    if n >= 3 {
        last.max(b[n - 2] - b[n - 3])
    } else {
        last
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossings_with_hysteresis_ignore_noise_at_rest() {
        // 10 cos(π t) from the release at t = 0 to t = 1.5 (crossings at 0.5 and 1.5),
        // then rest with ±1.5 σ noise (σ = 0.01): the noise never counts as a crossing,
        // and the last, unconfirmed half-cycle still gets its end.
        let t: Vec<f64> = (0..400).map(|i| i as f64 * 0.01).collect();
        let x: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, &s)| {
                if s < 1.495 {
                    10.0 * (std::f64::consts::PI * s).cos()
                } else {
                    0.015 * ((i % 3) as f64 - 1.0)
                }
            })
            .collect();
        let c = find_crossings(&t, &x, 0.0, 0.01, 0, 10);
        assert_eq!(c.len(), 2, "{c:?}");
        assert!((c[0] - 0.5).abs() < 1e-3, "{c:?}");
        assert!((c[1] - 1.5).abs() < 0.02, "{c:?}");
    }
}

//! The classic estimator (`Method::SavGol`): the extreme of a smoothed
//! derivative in each half-cycle.

use super::{Impact, Peak, Side};

/// Peak picking on a smoothed derivative: v_k is the extreme of the half-cycle that
/// ends at crossing k (searched up to `half` samples past the crossing, since the
/// smoothed peak is displaced by the window).
pub(super) fn pick_peaks(t: &[f64], v: &[f64], crossings: &[f64], start: usize, half: usize, n_peaks: usize) -> (Vec<Peak>, Vec<Impact>) {
    let idx = |tc: f64| t.partition_point(|&s| s < tc);
    let mut peaks = Vec::new();
    let mut impacts = Vec::new();
    let mut from = start;
    for (k, &tc) in crossings.iter().enumerate().take(n_peaks) {
        let end = (idx(tc) + half).min(v.len() - 1);
        let sign = if k % 2 == 0 { -1.0 } else { 1.0 };
        let mut best = from;
        for i in from..=end {
            if sign * v[i] > sign * v[best] {
                best = i;
            }
        }
        peaks.push(Peak {
            time_s: t[best],
            velocity_mm_s: v[best],
            velocity_u_mm_s: None,
        });
        impacts.push(Impact {
            k,
            time_s: tc,
            entering: if k % 2 == 0 { Side::Inward } else { Side::Outward },
            v_before_mm_s: v[best],
            v_after_mm_s: None,
        });
        from = idx(tc).min(v.len() - 1);
    }
    (peaks, impacts)
}

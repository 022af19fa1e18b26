//! The archive's rows from a reduction's `summary.json`: one row per test
//! ([`TEST_COLUMNS`]) and one per impact ([`IMPACT_COLUMNS`]), as polars frames of a
//! fixed schema (so that the frames of every campaign stack).

use polars::prelude::*;
use serde_json::Value;

use super::ArchiveError;

/// The coefficients of Tables 1–3 (paper Eqs. 3–6), each also with `_u`.
pub const TABLE_VALUES: [&str; 10] = ["e", "e_plus", "e_minus", "r", "r_plus", "r_minus", "r1", "r1_plus", "r1_minus", "r2"];

/// The wall's values taken from summary.json's `wall`.
const WALL: [&str; 5] = ["height_m", "thickness_m", "width_m", "weight_kN", "hinge_height_m"];

/// Text columns of `tests`, then its numbers (see [`test_columns`]).
const TEST_TEXT: [&str; 7] = ["campaign", "test", "rocking", "status", "method", "manifest_sha256", "rocklab_version"];

/// Columns of `impacts` (SPEC "Per-impact coefficients"), after campaign, test, the
/// test's status, sha, k and side.
const IMPACT_NUMBERS: [&str; 7] = ["amplitude_over_alpha", "speed_before_mm_s", "speed_after_mm_s", "e", "e_u", "r", "r_u"];

/// Every column of `tests`, in order.
pub fn test_columns() -> Vec<String> {
    let mut c: Vec<String> = TEST_TEXT.iter().map(|s| s.to_string()).collect();
    c.extend(["slenderness", "alpha_rad", "e_housner"].map(String::from));
    c.extend(WALL.iter().map(|s| s.to_string()));
    for v in TABLE_VALUES {
        c.push(v.to_string());
        c.push(format!("{v}_u"));
    }
    c.push("exclude_from_mean".into());
    c
}

/// A reduction as the archive reads it: its key and its two frames.
pub struct Reduction {
    pub sha256: String,
    pub campaign: String,
    pub tests: DataFrame,
    pub impacts: DataFrame,
    /// Tests none of whose `impacts` is in SPEC's shape (no `side`), so not archived.
    pub impacts_skipped: Vec<String>,
}

/// Read a summary document into its rows.
pub fn reduction(doc: &Value, origin: &str) -> Result<Reduction, ArchiveError> {
    let bad = |m: String| ArchiveError::Summary {
        file: origin.to_string(),
        message: m,
    };
    let text = |k: &str| doc.get(k).and_then(Value::as_str).map(str::to_string);
    let sha256 =
        text("manifest_sha256").ok_or_else(|| bad("no 'manifest_sha256': reduce the campaign again with this rocklab (it adds the key)".into()))?;
    let campaign = text("campaign").ok_or_else(|| bad("no 'campaign'".into()))?;
    let tests = doc.get("tests").and_then(Value::as_array).ok_or_else(|| bad("no 'tests' array".into()))?;
    let num = |v: &Value, k: &str| v.get(k).and_then(Value::as_f64);
    let wall = doc.get("wall").cloned().unwrap_or(Value::Null);
    let (h, t) = (num(&wall, "height_m"), num(&wall, "thickness_m"));
    let mut cols: Vec<Column> = Vec::new();
    let n = tests.len();
    let per_test_text = |k: &str| -> Vec<Option<String>> { tests.iter().map(|t| t.get(k).and_then(Value::as_str).map(str::to_string)).collect() };
    for k in TEST_TEXT {
        let values: Vec<Option<String>> = match k {
            "test" => per_test_text("id"),
            "status" => per_test_text("status"),
            _ => vec![text(k); n],
        };
        cols.push(Column::new(k.into(), values));
    }
    let slenderness = h.zip(t).map(|(h, t)| h / t);
    cols.push(Column::new("slenderness".into(), vec![slenderness; n]));
    for k in ["alpha_rad", "e_housner"] {
        cols.push(Column::new(k.into(), vec![num(doc, k); n]));
    }
    for k in WALL {
        cols.push(Column::new(k.into(), vec![num(&wall, k); n]));
    }
    for v in TABLE_VALUES {
        for k in [v.to_string(), format!("{v}_u")] {
            let values: Vec<Option<f64>> = tests.iter().map(|t| num(t, &k)).collect();
            cols.push(Column::new(k.as_str().into(), values));
        }
    }
    let exclude: Vec<Option<bool>> = tests.iter().map(|t| t.get("exclude_from_mean").and_then(Value::as_bool)).collect();
    cols.push(Column::new("exclude_from_mean".into(), exclude));
    let tests_df = DataFrame::new(n, cols).map_err(|e| bad(e.to_string()))?;
    let (impacts, impacts_skipped) = impact_rows(tests, &campaign, &sha256).map_err(|e| bad(e.to_string()))?;
    Ok(Reduction {
        sha256,
        campaign,
        tests: tests_df,
        impacts,
        impacts_skipped,
    })
}

/// One row per impact in SPEC's shape (with its side, e and r) of every test.
fn impact_rows(tests: &[Value], campaign: &str, sha: &str) -> PolarsResult<(DataFrame, Vec<String>)> {
    let (mut test, mut k, mut side) = (Vec::<String>::new(), Vec::<Option<i64>>::new(), Vec::<Option<String>>::new());
    let mut status = Vec::<Option<String>>::new();
    let mut numbers: Vec<Vec<Option<f64>>> = vec![Vec::new(); IMPACT_NUMBERS.len()];
    let mut skipped = Vec::new();
    for t in tests {
        let id = t.get("id").and_then(Value::as_str).unwrap_or("?");
        let Some(list) = t.get("impacts").and_then(Value::as_array) else {
            continue;
        };
        // An impact without a coefficient (its next peak not read) has no side, e
        // or r: not a row. A test none of whose impacts has them is in the
        // earlier internal shape, and the caller says so.
        let coefficients: Vec<&Value> = list.iter().filter(|i| i.get("side").and_then(Value::as_str).is_some()).collect();
        if coefficients.is_empty() && !list.is_empty() {
            skipped.push(id.to_string());
            continue;
        }
        let test_status = t.get("status").and_then(Value::as_str).map(str::to_string);
        for i in coefficients {
            test.push(id.to_string());
            status.push(test_status.clone());
            k.push(i.get("k").and_then(Value::as_i64));
            side.push(i.get("side").and_then(Value::as_str).map(str::to_string));
            for (col, name) in numbers.iter_mut().zip(IMPACT_NUMBERS) {
                col.push(i.get(name).and_then(Value::as_f64));
            }
        }
    }
    let n = test.len();
    let mut cols = vec![
        Column::new("campaign".into(), vec![campaign.to_string(); n]),
        Column::new("test".into(), test),
        // The test's status: a suspect test's impacts are printed, not vouched for.
        Column::new("status".into(), status),
        Column::new("manifest_sha256".into(), vec![sha.to_string(); n]),
        Column::new("k".into(), k),
        Column::new("side".into(), side),
    ];
    for (col, name) in numbers.into_iter().zip(IMPACT_NUMBERS) {
        cols.push(Column::new(name.into(), col));
    }
    Ok((DataFrame::new(n, cols)?, skipped))
}

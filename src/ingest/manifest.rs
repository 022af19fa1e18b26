//! The campaign manifest (SPEC "Campaign manifest"): parsed in two stages, the raw
//! TOML (unknown keys rejected by name) and a validated [`Campaign`] with the
//! `[channels]` defaults merged into every test and α, e_H chosen with provenance.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{FileError, FileKind};
use crate::ingest::log::{Decimal, Delimiter, LogFormat};
use crate::ingest::text::{parse_toml, read_text};
use crate::peaks::acquisition::Acquisition;
use crate::signal::filter::{Family, LowPass};
pub use crate::wall::Rocking;
use crate::wall::{housner_e, slenderness, Provenance, Wall};

/// Unit of the time column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TimeUnit {
    S,
    Ms,
}

impl TimeUnit {
    /// Factor to seconds.
    pub fn to_s(self) -> f64 {
        match self {
            TimeUnit::S => 1.0,
            TimeUnit::Ms => 1e-3,
        }
    }
}

/// Unit of the displacement column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LengthUnit {
    Mm,
    M,
}

impl LengthUnit {
    /// Factor to millimetres.
    pub fn to_mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::M => 1e3,
        }
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    campaign: RawCampaign,
    wall: RawWall,
    channels: Option<RawChannels>,
    format: Option<RawFormat>,
    acquisition: Option<RawAcquisition>,
    #[serde(default)]
    test: Vec<RawTest>,
}

/// `[acquisition]` or a test's `acquisition = { … }` (SPEC): the data logger's
/// filter on the displacement channel.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAcquisition {
    filter: String,
    order: Option<i64>,
    cutoff_hz: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCampaign {
    name: String,
    rocking: Rocking,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(non_snake_case)]
struct RawWall {
    height_m: f64,
    thickness_m: f64,
    width_m: Option<f64>,
    weight_kN: Option<f64>,
    #[serde(default)]
    hinge_height_m: f64,
    alpha_rad: Option<f64>,
    e_housner: Option<f64>,
}

/// A time channel: column name and unit.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeChannel {
    pub column: String,
    pub unit: TimeUnit,
}

/// A displacement channel: column name, unit and the sensor height above the base.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DisplacementChannel {
    pub column: String,
    pub unit: LengthUnit,
    pub height_m: Option<f64>,
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawChannels {
    time: Option<TimeChannel>,
    displacement: Option<DisplacementChannel>,
    outward_sign: Option<i64>,
    /// Sheet of an `.xlsx` log (default: the first).
    sheet: Option<String>,
    /// Group of a `.tdms` log (default: the one holding the channel).
    group: Option<String>,
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFormat {
    delimiter: Option<String>,
    decimal: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTest {
    id: String,
    file: String,
    imposed_displacement_mm: Option<f64>,
    #[serde(default)]
    exclude_from_mean: bool,
    time: Option<TimeChannel>,
    displacement: Option<DisplacementChannel>,
    outward_sign: Option<i64>,
    channels: Option<RawChannels>,
    format: Option<RawFormat>,
    acquisition: Option<RawAcquisition>,
    sheet: Option<String>,
    group: Option<String>,
}

/// A validated test: every channel resolved.
#[derive(Debug, Clone)]
pub struct TestSpec {
    pub id: String,
    /// Absolute or manifest-relative path, resolved against the manifest's folder.
    pub file: PathBuf,
    pub imposed_displacement_mm: Option<f64>,
    pub exclude_from_mean: bool,
    pub time: TimeChannel,
    pub displacement: DisplacementChannel,
    /// +1 when a positive reading means outward, −1 when it means inward.
    pub outward_sign: f64,
    pub format: LogFormat,
    /// Sheet (`.xlsx`) or group (`.tdms`) holding the channels.
    pub source: crate::ingest::formats::Source,
    /// Lever arm of the sensor about the hinge, m (sensor height − hinge height).
    pub lever_arm_m: f64,
    /// The logger's filter: the test's own `acquisition`, else `[acquisition]`,
    /// else not known.
    pub acquisition: Acquisition,
}

/// A validated campaign.
#[derive(Debug, Clone)]
pub struct Campaign {
    pub name: String,
    pub rocking: Rocking,
    pub manifest_path: PathBuf,
    pub height_m: f64,
    pub thickness_m: f64,
    pub width_m: Option<f64>,
    pub weight_kn: Option<f64>,
    pub hinge_height_m: f64,
    /// α for e_H (SPEC: atan(thickness / height) of the wall as given).
    pub alpha_rad: f64,
    pub alpha_source: Provenance,
    /// e_H, paper Eq. 2, or the manifest's override.
    pub e_housner: f64,
    pub e_housner_source: Provenance,
    pub tests: Vec<TestSpec>,
    /// SHA-256 (hex) of the manifest's text: the key of its reductions in a lab's
    /// archive (`rocklab archive`).
    pub manifest_sha256: String,
}

impl Campaign {
    /// The tested wall, as the core takes it.
    pub fn wall(&self) -> Wall {
        Wall {
            height_m: self.height_m,
            thickness_m: self.thickness_m,
            hinge_height_m: self.hinge_height_m,
            alpha_rad: self.alpha_rad,
            alpha_source: self.alpha_source.clone(),
            e_housner: self.e_housner,
            e_housner_source: self.e_housner_source.clone(),
        }
    }

    /// p² of the rocking part above the hinge (rectangular block), s⁻².
    pub fn p_squared(&self) -> f64 {
        self.wall().rocking_part().p_squared()
    }

    /// Read and validate a manifest file. A directory stands for the
    /// `campaign.toml` in it (what `rocklab init DIR` writes); a directory
    /// without one is refused with what to do.
    pub fn load(path: &Path) -> Result<Campaign> {
        let file = manifest_in(path)?;
        Self::parse(&read_text(&file, FileKind::Manifest)?, &file)
    }

    /// Parse and validate manifest text; `path` names it in errors and resolves the
    /// test files.
    pub fn parse(text: &str, path: &Path) -> Result<Campaign> {
        // A manifest drafted by `rocklab init` and not yet filled in.
        super::scaffold::check_filled(text, path)?;
        let mut c = validate(parse_toml(text, path)?, path).map_err(|e| e.located(path, text))?;
        c.manifest_sha256 = {
            use sha2::{Digest, Sha256};
            Sha256::digest(text.as_bytes()).iter().map(|b| format!("{b:02x}")).collect()
        };
        Ok(c)
    }
}

type Result<T> = std::result::Result<T, FileError>;

/// The manifest a path names: the path itself, or `DIR/campaign.toml` for a
/// directory.
fn manifest_in(path: &Path) -> Result<std::path::PathBuf> {
    if !path.is_dir() {
        return Ok(path.to_path_buf());
    }
    let file = path.join("campaign.toml");
    if file.is_file() {
        return Ok(file);
    }
    Err(bad(
        path,
        format!(
            "a directory without a campaign.toml: pass the campaign's manifest, or draft one with `rocklab init {}`",
            path.display()
        ),
    ))
}

fn bad(path: &Path, msg: impl std::fmt::Display) -> FileError {
    FileError::invalid(path, msg)
}

/// A length within [`crate::limits::LENGTH_M`] (1 mm to 1 km), the refusal naming
/// the key and the range (issue 22).
fn length(path: &Path, key: &str, v: f64) -> Result<f64> {
    crate::limits::LENGTH_M.check(key, v).map_err(|m| bad(path, m))
}

fn sign(path: &Path, where_: &str, v: i64) -> Result<f64> {
    match v {
        1 => Ok(1.0),
        -1 => Ok(-1.0),
        _ => Err(bad(path, format!("{where_}outward_sign = {v}: expected 1 or -1"))),
    }
}

fn parse_format(path: &Path, where_: &str, f: &RawFormat) -> Result<LogFormat> {
    let delimiter = match f.delimiter.as_deref() {
        None => None,
        Some(",") => Some(Delimiter::Comma),
        Some(";") => Some(Delimiter::Semicolon),
        Some("\t") | Some("\\t") | Some("tab") => Some(Delimiter::Tab),
        Some(other) => return Err(bad(path, format!("{where_}delimiter = {other:?}: expected \",\", \";\" or \"\\t\""))),
    };
    let decimal = match f.decimal.as_deref() {
        None => None,
        Some(".") => Some(Decimal::Point),
        Some(",") => Some(Decimal::Comma),
        Some(other) => return Err(bad(path, format!("{where_}decimal = {other:?}: expected \".\" or \",\""))),
    };
    if delimiter == Some(Delimiter::Comma) && decimal == Some(Decimal::Comma) {
        return Err(bad(
            path,
            format!("{where_}delimiter and decimal are both \",\": a log cannot be read that way"),
        ));
    }
    Ok(LogFormat { delimiter, decimal })
}

/// An `acquisition` validated; `where_` names it in errors ("[acquisition]." or
/// "[[test]] id = \"x\": acquisition.").
fn parse_acquisition(path: &Path, where_: &str, a: &RawAcquisition) -> Result<Acquisition> {
    let family = match a.filter.as_str() {
        "none" | "unknown" => {
            if a.order.is_some() || a.cutoff_hz.is_some() {
                return Err(bad(
                    path,
                    format!(
                        "{where_}filter = {:?}: order and cutoff_hz belong to a stated \"bessel\" or \"butterworth\" filter",
                        a.filter
                    ),
                ));
            }
            return Ok(if a.filter == "none" { Acquisition::None } else { Acquisition::Unknown });
        }
        "bessel" => Family::Bessel,
        "butterworth" => Family::Butterworth,
        other => {
            return Err(bad(
                path,
                format!("{where_}filter = {other:?}: expected \"none\", \"bessel\", \"butterworth\" or \"unknown\""),
            ))
        }
    };
    let order = a
        .order
        .ok_or_else(|| bad(path, format!("{where_}order is missing: a {} filter needs its order (1–8)", a.filter)))?;
    if !(1..=8).contains(&order) {
        return Err(bad(path, format!("{where_}order = {order}: expected an order from 1 to 8")));
    }
    let cutoff_hz = a.cutoff_hz.ok_or_else(|| {
        bad(
            path,
            format!("{where_}cutoff_hz is missing: a {} filter needs its −3 dB frequency", a.filter),
        )
    })?;
    // A cut-off within the range of a logger's rate (1 Hz – 1 MHz: limits.rs).
    let cutoff_hz = crate::limits::LOG_RATE_HZ
        .check(&format!("{where_}cutoff_hz"), cutoff_hz)
        .map_err(|m| bad(path, m))?;
    Ok(Acquisition::Stated(LowPass {
        family,
        order: order as usize,
        cutoff_hz,
    }))
}

/// The `[wall]` table validated: height, thickness, α and e_H with provenance.
struct WallValues {
    height_m: f64,
    thickness_m: f64,
    alpha_rad: f64,
    alpha_source: Provenance,
    e_housner: f64,
    e_housner_source: Provenance,
}

fn validate_wall(w: &RawWall, path: &Path) -> Result<WallValues> {
    let height_m = length(path, "[wall].height_m", w.height_m)?;
    let thickness_m = length(path, "[wall].thickness_m", w.thickness_m)?;
    if !(w.hinge_height_m.is_finite() && w.hinge_height_m >= 0.0 && w.hinge_height_m < height_m) {
        return Err(bad(
            path,
            format!("[wall].hinge_height_m = {}: expected 0 ≤ hinge < height ({height_m})", w.hinge_height_m),
        ));
    }
    let (alpha_rad, alpha_source) = match w.alpha_rad {
        Some(a) => {
            if !(a > 0.0 && a < std::f64::consts::FRAC_PI_2) {
                return Err(bad(path, format!("[wall].alpha_rad = {a}: expected 0 < α < π/2")));
            }
            (a, Provenance::Override("[wall].alpha_rad".into()))
        }
        None => (
            slenderness(thickness_m, height_m),
            Provenance::Computed(format!("atan({thickness_m} / {height_m})")),
        ),
    };
    let (e_housner, e_housner_source) = match w.e_housner {
        Some(e) => {
            if !(e > 0.0 && e <= 1.0) {
                return Err(bad(path, format!("[wall].e_housner = {e}: expected 0 < e_H ≤ 1")));
            }
            (e, Provenance::Override("[wall].e_housner".into()))
        }
        None => (housner_e(alpha_rad), Provenance::Computed(format!("Eq. 2, 1 − 1.5 sin²({alpha_rad:.4})"))),
    };
    Ok(WallValues {
        height_m,
        thickness_m,
        alpha_rad,
        alpha_source,
        e_housner,
        e_housner_source,
    })
}

/// What every test inherits: the `[channels]` defaults, the `[format]`, the
/// manifest's folder and the hinge height.
struct Defaults<'a> {
    channels: RawChannels,
    format: LogFormat,
    base: &'a Path,
    hinge_height_m: f64,
    acquisition: Acquisition,
}

/// The channels of one test: its own, then its nested `channels`, then the defaults.
fn test_channels(t: &RawTest, d: &Defaults, path: &Path, where_: &str) -> Result<(TimeChannel, DisplacementChannel, f64)> {
    let nested = t.channels.clone().unwrap_or_default();
    let time = t
        .time
        .clone()
        .or(nested.time)
        .or(d.channels.time.clone())
        .ok_or_else(|| bad(path, format!("{where_}no time channel: set [channels].time or time in this [[test]]")))?;
    let displacement = t
        .displacement
        .clone()
        .or(nested.displacement)
        .or(d.channels.displacement.clone())
        .ok_or_else(|| {
            bad(
                path,
                format!("{where_}no displacement channel: set [channels].displacement or displacement in this [[test]]"),
            )
        })?;
    let outward_sign = sign(
        path,
        where_,
        t.outward_sign.or(nested.outward_sign).or(d.channels.outward_sign).unwrap_or(1),
    )?;
    Ok((time, displacement, outward_sign))
}

/// One `[[test]]` validated, its channels resolved.
fn validate_test(t: &RawTest, d: &Defaults, path: &Path) -> Result<TestSpec> {
    let where_ = format!("[[test]] id = {:?}: ", t.id);
    let (time, displacement, outward_sign) = test_channels(t, d, path, &where_)?;
    if time.column == displacement.column {
        // issue 22: this used to read as "no release found" in every test.
        return Err(bad(
            path,
            format!(
                "{where_}the time and the displacement channels both name column {:?}: expected two columns (check [channels].time.column and [channels].displacement.column)",
                crate::error::excerpt(&time.column, 60)
            ),
        ));
    }
    let sensor_h = displacement.height_m.ok_or_else(|| {
        bad(
            path,
            format!("{where_}displacement.height_m is missing: the sensor height above the base is needed to turn displacement into rotation"),
        )
    })?;
    let sensor_h = length(path, &format!("{where_}displacement.height_m"), sensor_h)?;
    let lever_arm_m = sensor_h - d.hinge_height_m;
    if lever_arm_m <= 0.0 {
        return Err(bad(
            path,
            format!("{where_}sensor height {sensor_h} m is not above the hinge ({} m)", d.hinge_height_m),
        ));
    }
    if t.file.len() > 4096 || Path::new(&t.file).components().any(|c| c.as_os_str().len() > 255) {
        return Err(bad(
            path,
            format!(
                "{where_}file = \"{}\": expected a path of at most 4096 bytes, 255 per name",
                crate::error::excerpt(&t.file, 60)
            ),
        ));
    }
    let format = match &t.format {
        Some(f) => parse_format(path, &format!("{where_}format."), f)?,
        None => d.format,
    };
    if let Some(x) = t.imposed_displacement_mm {
        crate::limits::Range::new(1e-3, 1e4, "mm")
            .check(&format!("{where_}imposed_displacement_mm"), x)
            .map_err(|m| bad(path, m))?;
    }
    let acquisition = match &t.acquisition {
        Some(a) => parse_acquisition(path, &format!("{where_}acquisition."), a)?,
        None => d.acquisition,
    };
    Ok(TestSpec {
        id: t.id.clone(),
        file: d.base.join(&t.file),
        imposed_displacement_mm: t.imposed_displacement_mm,
        exclude_from_mean: t.exclude_from_mean,
        time,
        displacement,
        outward_sign,
        format,
        source: test_source(t, d),
        lever_arm_m,
        acquisition,
    })
}

/// Sheet and group of one test: its own, then its nested `channels`, then the defaults.
fn test_source(t: &RawTest, d: &Defaults) -> crate::ingest::formats::Source {
    let nested = t.channels.as_ref();
    crate::ingest::formats::Source {
        sheet: t.sheet.clone().or(nested.and_then(|c| c.sheet.clone())).or(d.channels.sheet.clone()),
        group: t.group.clone().or(nested.and_then(|c| c.group.clone())).or(d.channels.group.clone()),
    }
}

fn validate(raw: RawManifest, path: &Path) -> Result<Campaign> {
    let w = &raw.wall;
    let wall = validate_wall(w, path)?;
    let defaults = Defaults {
        channels: raw.channels.clone().unwrap_or_default(),
        format: match &raw.format {
            Some(f) => parse_format(path, "[format].", f)?,
            None => LogFormat::default(),
        },
        base: path.parent().unwrap_or_else(|| Path::new(".")),
        hinge_height_m: w.hinge_height_m,
        acquisition: match &raw.acquisition {
            Some(a) => parse_acquisition(path, "[acquisition].", a)?,
            None => Acquisition::Unknown,
        },
    };
    if raw.test.is_empty() {
        return Err(bad(path, "no [[test]] entries: expected at least one test"));
    }
    let mut tests = Vec::with_capacity(raw.test.len());
    let mut seen = std::collections::HashSet::new();
    for t in &raw.test {
        if t.id.trim().is_empty() {
            return Err(bad(path, "[[test]] with an empty id"));
        }
        if !seen.insert(t.id.clone()) {
            return Err(bad(path, format!("[[test]] id = {:?}: duplicate test id", t.id)));
        }
        let test = validate_test(t, &defaults, path)?;
        // One run of the wall is one test: two tests reading the same channels of
        // the same log (a copied [[test]] block whose file was not changed) would
        // count that run twice in the means.
        let same = |o: &TestSpec| {
            o.file == test.file
                && format!("{:?}", o.source) == format!("{:?}", test.source)
                && o.time.column == test.time.column
                && o.displacement.column == test.displacement.column
        };
        if let Some(first) = tests.iter().find(|o| same(o)) {
            return Err(bad(
                path,
                format!(
                    "[[test]] id = {:?}: file = {:?} is the log of test {:?} too, read through the same channels: one run would count twice in the means (a copied [[test]] block whose file was not changed?)",
                    t.id, t.file, first.id
                ),
            ));
        }
        tests.push(test);
    }
    Ok(Campaign {
        manifest_sha256: String::new(),
        name: raw.campaign.name,
        rocking: raw.campaign.rocking,
        manifest_path: path.to_path_buf(),
        height_m: wall.height_m,
        thickness_m: wall.thickness_m,
        width_m: w.width_m,
        weight_kn: w.weight_kN,
        hinge_height_m: w.hinge_height_m,
        alpha_rad: wall.alpha_rad,
        alpha_source: wall.alpha_source,
        e_housner: wall.e_housner,
        e_housner_source: wall.e_housner_source,
        tests,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
[campaign]
name = "c"
rocking = "one-sided"
[wall]
height_m = 2.70
thickness_m = 0.36
hinge_height_m = 0.23
[channels]
time = { column = "time_s", unit = "s" }
displacement = { column = "disp_mm", unit = "mm", height_m = 2.56 }
outward_sign = 1
[[test]]
id = "a"
file = "a.csv"
[[test]]
id = "b"
file = "b.csv"
outward_sign = -1
time = { column = "t_ms", unit = "ms" }
"#;

    #[test]
    fn sheet_and_group_come_from_the_test_then_channels() {
        let text = BASE
            .replace("outward_sign = 1\n[[test]]", "outward_sign = 1\nsheet = \"log\"\ngroup = \"g\"\n[[test]]")
            .replace("file = \"b.csv\"", "file = \"b.csv\"\nsheet = \"other\"");
        let c = Campaign::parse(&text, Path::new("/x/campaign.toml")).unwrap();
        assert_eq!(c.tests[0].source.sheet.as_deref(), Some("log"));
        assert_eq!(c.tests[1].source.sheet.as_deref(), Some("other"));
        assert_eq!(c.tests[1].source.group.as_deref(), Some("g"));
        // The manifest's hash, the archive's key: SHA-256 of its text.
        assert_eq!(c.manifest_sha256.len(), 64);
        let other = Campaign::parse(BASE, Path::new("/x/campaign.toml")).unwrap();
        assert_ne!(c.manifest_sha256, other.manifest_sha256);
    }

    #[test]
    fn defaults_merge_with_overrides() {
        let c = Campaign::parse(BASE, Path::new("/x/campaign.toml")).unwrap();
        assert_eq!(c.tests[0].time.column, "time_s");
        assert_eq!(c.tests[1].time.column, "t_ms");
        assert_eq!(c.tests[1].time.unit, TimeUnit::Ms);
        assert_eq!(c.tests[1].outward_sign, -1.0);
        assert_eq!(c.tests[1].displacement.column, "disp_mm");
        assert!((c.tests[0].lever_arm_m - 2.33).abs() < 1e-12);
        assert_eq!(c.tests[0].file, Path::new("/x/a.csv"));
        assert!(matches!(c.alpha_source, Provenance::Computed(_)));
        assert!((c.e_housner - 0.9738).abs() < 1e-4);
    }

    // Session 13: a [[test]] block copied without changing its file read the same
    // run twice, which then counted twice in the means, without a word.
    #[test]
    fn two_tests_reading_the_same_channels_of_one_log_are_refused() {
        let copied = format!("{BASE}[[test]]\nid = \"a2\"\nfile = \"a.csv\"\n");
        let err = Campaign::parse(&copied, Path::new("m.toml")).unwrap_err().to_string();
        assert!(
            err.contains("m.toml:22:1: [[test]] id = \"a2\": file = \"a.csv\" is the log of test \"a\" too"),
            "{err}"
        );
        // Another channel of the same log (a second sensor) is another reading.
        let other =
            format!("{BASE}[[test]]\nid = \"c\"\nfile = \"a.csv\"\ndisplacement = {{ column = \"disp2_mm\", unit = \"mm\", height_m = 2.0 }}\n");
        let c = Campaign::parse(&other, Path::new("m.toml")).unwrap();
        assert_eq!(c.tests.len(), 3);
    }

    #[test]
    fn unknown_key_is_named() {
        let text = BASE.replace("hinge_height_m = 0.23", "hinge_height_m = 0.23\nhieght = 3");
        let err = Campaign::parse(&text, Path::new("m.toml")).unwrap_err().to_string();
        assert!(err.contains("hieght"), "{err}");
        assert!(err.contains("m.toml"), "{err}");
    }

    #[test]
    fn overrides_are_recorded() {
        let text = BASE.replace("hinge_height_m = 0.23", "hinge_height_m = 0.23\nalpha_rad = 0.12\ne_housner = 0.97");
        let c = Campaign::parse(&text, Path::new("m.toml")).unwrap();
        assert_eq!(c.alpha_rad, 0.12);
        assert_eq!(c.e_housner, 0.97);
        assert!(matches!(c.e_housner_source, Provenance::Override(_)));
    }

    /// `[acquisition]` and the per-test override (SPEC), and located errors.
    #[test]
    fn acquisition_is_read_and_validated() {
        let c = Campaign::parse(BASE, Path::new("m.toml")).unwrap();
        assert_eq!(c.tests[0].acquisition, Acquisition::Unknown, "not stated: not known");
        let stated = format!("{BASE}\n[acquisition]\nfilter = \"bessel\"\norder = 4\ncutoff_hz = 50.0\n");
        let c = Campaign::parse(&stated, Path::new("m.toml")).unwrap();
        let want = LowPass {
            family: Family::Bessel,
            order: 4,
            cutoff_hz: 50.0,
        };
        assert_eq!(c.tests[1].acquisition, Acquisition::Stated(want));
        let own = stated.replace(
            "outward_sign = -1",
            "outward_sign = -1\nacquisition = { filter = \"butterworth\", order = 6, cutoff_hz = 37.5 }",
        );
        let c = Campaign::parse(&own, Path::new("m.toml")).unwrap();
        assert_eq!(c.tests[0].acquisition, Acquisition::Stated(want));
        assert!(matches!(
            c.tests[1].acquisition,
            Acquisition::Stated(LowPass {
                family: Family::Butterworth,
                order: 6,
                ..
            })
        ));
        let none = own.replace("filter = \"butterworth\", order = 6, cutoff_hz = 37.5", "filter = \"none\"");
        assert_eq!(
            Campaign::parse(&none, Path::new("m.toml")).unwrap().tests[1].acquisition,
            Acquisition::None
        );
        for (from, to, says) in [
            (
                "filter = \"bessel\"",
                "filter = \"chebyshev\"",
                "m.toml:23:1: [acquisition].filter = \"chebyshev\": expected",
            ),
            (
                "order = 4",
                "order = 12",
                "m.toml:24:1: [acquisition].order = 12: expected an order from 1 to 8",
            ),
            (
                "cutoff_hz = 50.0",
                "cutoff_hz = -5.0",
                "m.toml:25:1: [acquisition].cutoff_hz = -5: expected a value",
            ),
            ("order = 4\n", "", "[acquisition].order is missing"),
            ("cutoff_hz = 50.0", "cutoff_hz = 50.0\ngain = 2", "gain"),
        ] {
            let err = Campaign::parse(&stated.replace(from, to), Path::new("m.toml")).unwrap_err().to_string();
            assert!(err.contains(says), "{err}");
        }
        let err = Campaign::parse(&own.replace("order = 6", "order = 0"), Path::new("m.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("[[test]] id = \"b\": acquisition.order = 0") && err.contains("m.toml:"),
            "{err}"
        );
    }

    #[test]
    fn bad_sign_and_format_are_rejected() {
        let text = BASE.replace("outward_sign = -1", "outward_sign = 2");
        let err = Campaign::parse(&text, Path::new("m.toml")).unwrap_err().to_string();
        assert!(err.contains("outward_sign = 2"), "{err}");
        let text = format!("{BASE}\n[format]\ndelimiter = \"|\"\n");
        assert!(Campaign::parse(&text, Path::new("m.toml")).is_err());
    }
}

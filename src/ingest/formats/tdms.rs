//! NI TDMS files (`.tdms`) through the `tdms` crate: channels by name (the
//! manifest's `column`), in the group the manifest names (`group = "…"`) or, without
//! one, in the one group that has a channel of that name. Where there is no time
//! channel, the displacement channel's waveform properties give the time:
//! t_i = wf_start_offset + i · wf_increment (NI's waveform convention, s).
//!
//! The `tdms` crate (0.3) is the only pure-Rust TDMS reader on crates.io; it is
//! young, so its calls run inside the caller's `catch_unwind` (see `formats::read`)
//! and its channel iterators, which stop quietly at an unreadable value, are checked
//! against the number of values the file's index announces.

use std::collections::BTreeSet;

use tdms::data_type::TdmsDataType as T;
use tdms::segment::Channel;
use tdms::TDMSFile;

use super::{err, not_found, Channels, Request};
use crate::error::InputError;

pub fn read(req: &Request) -> Result<Channels, InputError> {
    let file = req.file;
    let f = TDMSFile::from_path(file).map_err(|e| err(file, format!("not readable as a TDMS file: {e:?}")))?;
    let group = group_of(req, &f)?;
    let place = format!("group '{group}'");
    let channels = f.channels(&group);
    let disp_ch = *channels
        .get(req.disp_column)
        .ok_or_else(|| not_found(file, "channel", req.disp_column, &place, &channels.keys().cloned().collect::<Vec<_>>()))?;
    let disp = values(req, &f, disp_ch, &place)?;
    let (time, time_in_s, note) = match channels.get(req.time_column) {
        Some(c) => (
            values(req, &f, c, &place)?,
            false,
            format!("TDMS file, {place}, time channel '{}'", req.time_column),
        ),
        None => {
            let (t, note) = waveform_time(req, disp_ch, disp.len(), &place, &channels.keys().cloned().collect::<Vec<_>>())?;
            (t, true, note)
        }
    };
    Ok(Channels {
        time,
        disp,
        time_in_s,
        first_row: 1,
        place,
        notes: vec![note],
    })
}

/// The group to read: the manifest's, or the only one holding the displacement channel.
fn group_of(req: &Request, f: &TDMSFile) -> Result<String, InputError> {
    let groups = f.groups();
    if let Some(g) = &req.source.group {
        return if groups.contains(g) {
            Ok(g.clone())
        } else {
            Err(err(
                req.file,
                format!(
                    "group '{g}' not found (groups: {}). Set 'group' in this [[test]] or [channels]",
                    groups.join(", ")
                ),
            ))
        };
    }
    let holding: Vec<&String> = groups.iter().filter(|g| f.channels(g).contains_key(req.disp_column)).collect();
    match holding.as_slice() {
        [one] => Ok((*one).clone()),
        [] => {
            let all: BTreeSet<String> = groups.iter().flat_map(|g| f.channels(g).into_keys()).collect();
            Err(not_found(
                req.file,
                "channel",
                req.disp_column,
                "any group",
                &all.into_iter().collect::<Vec<_>>(),
            ))
        }
        many => Err(err(
            req.file,
            format!(
                "channel '{}' is in several groups ({}): set group = \"…\" in this [[test]] or [channels]",
                req.disp_column,
                many.iter().map(|g| format!("'{g}'")).collect::<Vec<_>>().join(", ")
            ),
        )),
    }
}

/// A channel's values as f64, checked against the count the index announces.
fn values(req: &Request, f: &TDMSFile, c: &Channel, place: &str) -> Result<Vec<f64>, InputError> {
    let bad = |e: tdms::TdmsError| err(req.file, format!("{place}, channel '{}': not readable: {e:?}", c.path));
    let v: Vec<f64> = match c.data_type {
        T::DoubleFloat(_) | T::DoubleFloatWithUnit(_) => f.channel_data_double_float(c).map_err(bad)?.collect(),
        T::SingleFloat(_) | T::SingleFloatWithUnit(_) => f.channel_data_single_float(c).map_err(bad)?.map(f64::from).collect(),
        T::I32(_) => f.channel_data_i32(c).map_err(bad)?.map(f64::from).collect(),
        T::I16(_) => f.channel_data_i16(c).map_err(bad)?.map(f64::from).collect(),
        ref other => {
            return Err(err(
                req.file,
                format!(
                    "{place}, channel '{}': values of type {other:?}: expected floating-point or integer samples",
                    c.path
                ),
            ))
        }
    };
    // Values the index lays out: the bytes of each chunk over the value size
    // (contiguous data; interleaved segments are not checked).
    let size = T::get_size(c.data_type) as u64;
    let announced: u64 = f
        .segments
        .iter()
        .filter(|s| !s.has_interleaved_data())
        .filter_map(|s| s.get_channel(&c.group_path, &c.path))
        .flat_map(|ch| ch.chunk_positions.iter().map(|p| p.1.saturating_sub(p.0) / size.max(1)))
        .sum();
    if announced != 0 && announced != v.len() as u64 {
        return Err(err(
            req.file,
            format!(
                "{place}, channel '{}': {} values read, the file announces {announced}: the file is damaged or cut short",
                c.path,
                v.len()
            ),
        ));
    }
    Ok(v)
}

/// Time from the waveform properties of the displacement channel.
fn waveform_time(req: &Request, c: &Channel, n: usize, place: &str, names: &[String]) -> Result<(Vec<f64>, String), InputError> {
    let prop = |name: &str| {
        c.properties
            .iter()
            .find(|p| p.name == name)
            .and_then(|p| match (&p.data_type, &p.value.value) {
                (T::DoubleFloat(_), Some(b)) if b.len() == 8 => Some(match p.value.endianness {
                    tdms::segment::Endianness::Little => f64::from_le_bytes(b[..8].try_into().ok()?),
                    tdms::segment::Endianness::Big => f64::from_be_bytes(b[..8].try_into().ok()?),
                }),
                _ => None,
            })
    };
    let Some(dt) = prop("wf_increment") else {
        return Err(err(
            req.file,
            format!(
                "time channel '{}' not found in {place} (channels: {}), and channel '{}' has no waveform property wf_increment (a float) to compute the time from. Set [channels].time.column or override it in this [[test]]",
                req.time_column,
                names.join(", "),
                req.disp_column
            ),
        ));
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(err(
            req.file,
            format!(
                "{place}, channel '{}': wf_increment = {dt}: expected a positive sampling interval (s)",
                c.path
            ),
        ));
    }
    let t0 = prop("wf_start_offset").unwrap_or(0.0);
    let time = (0..n).map(|i| t0 + i as f64 * dt).collect();
    let note = format!(
        "TDMS file, {place}, time from channel '{}': wf_start_offset {t0} s, wf_increment {dt} s",
        c.path
    );
    Ok((time, note))
}

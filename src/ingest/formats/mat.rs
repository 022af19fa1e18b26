//! MATLAB files (`.mat`): variables named by the channels' `column`, real numeric
//! vectors (n×1 or 1×n). Version 5 through `matfile` (pure Rust); version 7.3, which
//! is HDF5 after a 512-byte user block, through `hdf5-pure` (pure Rust: no libhdf5 to
//! install). The version is told from the bytes: the HDF5 signature at offset 0 or
//! 512 means v7.3, anything else is read as v5.
//! Both run inside the caller's `catch_unwind` (see `formats::read`).

use super::{err, not_found, Channels, Request};
use crate::error::InputError;

const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";

pub fn read(req: &Request) -> Result<Channels, InputError> {
    let bytes = crate::ingest::text::read_bytes(req.file)?;
    let is_hdf5 = |at: usize| bytes.get(at..at + 8) == Some(HDF5_SIGNATURE);
    let (version, time, disp) = if is_hdf5(0) || is_hdf5(512) {
        check_hdf5_length(&bytes, if is_hdf5(0) { 0 } else { 512 })
            .map_err(|m| err(req.file, format!("not readable as a MATLAB v7.3 file (HDF5): {m}")))?;
        let f = hdf5_pure::File::from_bytes(bytes).map_err(|e| err(req.file, format!("not readable as a MATLAB v7.3 file (HDF5): {e}")))?;
        ("7.3", read_v73(req, &f, req.time_column)?, read_v73(req, &f, req.disp_column)?)
    } else {
        let f = parse_v5(req, &bytes)?;
        ("5", read_v5(req, &f, req.time_column)?, read_v5(req, &f, req.disp_column)?)
    };
    Ok(Channels {
        time,
        disp,
        time_in_s: false,
        first_row: 1,
        place: String::new(),
        notes: vec![format!("MATLAB v{version} file")],
    })
}

fn parse_v5(req: &Request, bytes: &[u8]) -> Result<matfile::MatFile, InputError> {
    let not_mat = |why: String| err(req.file, format!("not readable as a MATLAB v5 file: {why}"));
    if bytes.len() < 128 || !bytes.starts_with(b"MATLAB") {
        return Err(not_mat("no 'MATLAB 5.0 MAT-file' header (expected a v5 or v7.3 .mat file)".into()));
    }
    check_v5_elements(bytes).map_err(not_mat)?;
    matfile::MatFile::parse(bytes).map_err(|e| not_mat(format!("{e:?}")))
}

/// The top-level data elements of a v5 file must tile it exactly: `matfile` stops
/// quietly at a damaged element, so a file cut short would lose its last variables
/// without a word. Each element: type (u32) and size (u32), then `size` bytes,
/// padded to 8 except compressed ones (MAT-File Format, "Data Element Format").
fn check_v5_elements(bytes: &[u8]) -> Result<(), String> {
    let big_endian = &bytes[126..128] == b"MI";
    let u32_at = |at: usize| -> Option<u32> {
        let b: [u8; 4] = bytes.get(at..at + 4)?.try_into().ok()?;
        Some(if big_endian { u32::from_be_bytes(b) } else { u32::from_le_bytes(b) })
    };
    let mut at = 128usize;
    while at < bytes.len() {
        let (Some(kind), Some(size)) = (u32_at(at), u32_at(at + 4)) else {
            return Err(format!("the data element at byte {at} is cut short (the file is truncated)"));
        };
        let size = size as usize;
        let padded = if kind == 15 { size } else { size.div_ceil(8) * 8 }; // 15: miCOMPRESSED
        let end = at.checked_add(8 + padded).ok_or("a data element's size overflows")?;
        if end > bytes.len() && !(kind != 15 && at + 8 + size == bytes.len()) {
            return Err(format!(
                "the data element at byte {at} announces {size} bytes, the file ends {} bytes after it (the file is truncated or damaged)",
                bytes.len() - at - 8
            ));
        }
        at = end;
    }
    Ok(())
}

fn read_v5(req: &Request, f: &matfile::MatFile, name: &str) -> Result<Vec<f64>, InputError> {
    use matfile::NumericData as N;
    let a = f.find_by_name(name).ok_or_else(|| {
        let names: Vec<String> = f.arrays().iter().map(|a| a.name().to_string()).collect();
        not_found(req.file, "variable", name, "", &names)
    })?;
    vector_shape(req, name, &a.size().iter().map(|&d| d as u64).collect::<Vec<_>>())?;
    let complex = || err(req.file, format!("variable '{name}' is complex: expected real values"));
    let v: Vec<f64> = match a.data() {
        N::Double { real, imag: None } => real.clone(),
        N::Single { real, imag: None } => real.iter().map(|&x| f64::from(x)).collect(),
        N::Int8 { real, imag: None } => real.iter().map(|&x| f64::from(x)).collect(),
        N::UInt8 { real, imag: None } => real.iter().map(|&x| f64::from(x)).collect(),
        N::Int16 { real, imag: None } => real.iter().map(|&x| f64::from(x)).collect(),
        N::UInt16 { real, imag: None } => real.iter().map(|&x| f64::from(x)).collect(),
        N::Int32 { real, imag: None } => real.iter().map(|&x| f64::from(x)).collect(),
        N::UInt32 { real, imag: None } => real.iter().map(|&x| f64::from(x)).collect(),
        N::Int64 { real, imag: None } => real.iter().map(|&x| x as f64).collect(),
        N::UInt64 { real, imag: None } => real.iter().map(|&x| x as f64).collect(),
        _ => return Err(complex()),
    };
    Ok(v)
}

fn read_v73(req: &Request, f: &hdf5_pure::File, name: &str) -> Result<Vec<f64>, InputError> {
    let names = f.root().datasets().unwrap_or_default();
    if !names.iter().any(|n| n == name) {
        return Err(not_found(req.file, "variable", name, "", &names));
    }
    let bad = |e: hdf5_pure::Error| err(req.file, format!("variable '{name}': not readable: {e}"));
    let ds = f.dataset(name).map_err(bad)?;
    vector_shape(req, name, &ds.shape().map_err(bad)?)?;
    ds.read_f64().map_err(bad)
}

/// The HDF5 superblock states where the file ends (its end-of-file address): a
/// file shorter than that was cut short, even where the datasets read are whole
/// (the reader would not notice).
fn check_hdf5_length(bytes: &[u8], base: usize) -> Result<(), String> {
    let version = *bytes.get(base + 8).ok_or("no superblock")?;
    // Offset of the size-of-offsets byte and of the end-of-file address (after the
    // base address and one or two other addresses), by superblock version.
    let (size_at, eof_index, addresses_at) = match version {
        0 => (13, 2, 24),
        1 => (13, 2, 28),
        2 | 3 => (9, 2, 12),
        v => return Err(format!("superblock version {v} is not known")),
    };
    let n = *bytes.get(base + size_at).ok_or("superblock cut short")? as usize;
    if !matches!(n, 2 | 4 | 8) {
        return Err(format!("superblock gives {n}-byte offsets"));
    }
    let address = |i: usize| -> Result<u64, String> {
        let at = base + addresses_at + i * n;
        let raw = bytes.get(at..at + n).ok_or("superblock cut short")?;
        Ok(raw.iter().rev().fold(0u64, |a, &b| (a << 8) | u64::from(b)))
    };
    // libhdf5 (h5py, MATLAB) writes the end of file as the file's length, user block
    // included (a 512-byte user block: base address 512, end = length).
    let end = address(eof_index)?;
    if end > bytes.len() as u64 {
        return Err(format!(
            "the superblock says the file is {end} bytes long, it has {}: the file is truncated",
            bytes.len()
        ));
    }
    Ok(())
}

/// A vector: at most one dimension other than 1.
fn vector_shape(req: &Request, name: &str, shape: &[u64]) -> Result<(), InputError> {
    if shape.iter().filter(|&&d| d != 1).count() > 1 {
        let dims: Vec<String> = shape.iter().map(|d| d.to_string()).collect();
        return Err(err(
            req.file,
            format!("variable '{name}' is a {} array: expected a vector (n×1 or 1×n)", dims.join("×")),
        ));
    }
    Ok(())
}

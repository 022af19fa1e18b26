//! The guard against non-finite numbers in the outputs (issue 22): a run that
//! exits 0 never writes NaN or ±inf.
//!
//! Two checks, both before anything is written:
//! - [`check_serialize`] walks a `Serialize` document (the `summary.json` views)
//!   before serde_json turns a NaN or an infinity into `null`, which the bytes no
//!   longer show; it names the key path (`runs[3].pga_g`).
//! - [`check_bytes`] reads the bytes of a text output at the one writer: a CSV
//!   field, or a word of a Markdown, LaTeX, HTML or SVG file, spelled as Rust
//!   prints a non-finite number (`NaN`, `inf`, `-inf`) or as CSV readers parse it.

use serde::ser::{self, Serialize};

/// Why a document or a file cannot be written.
#[derive(Debug)]
pub struct NonFinite(pub String);

impl std::fmt::Display for NonFinite {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for NonFinite {}
impl ser::Error for NonFinite {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        NonFinite(msg.to_string())
    }
}

/// Fails with the key path of the first NaN or ±inf in `doc`.
pub fn check_serialize<T: Serialize + ?Sized>(doc: &T) -> Result<(), NonFinite> {
    let mut w = Walker { path: Vec::new() };
    doc.serialize(&mut w)
}

/// Fails naming the line and the field of the first non-finite number written
/// where numbers are written in a text output of `name`: a CSV field, a table
/// cell of Markdown (`|`), LaTeX (`&`) or HTML (`<td>`), an SVG attribute value (a
/// coordinate). Prose, captions, SVG labels and the echoed inputs are not numbers
/// (a test or a record may be named "inf"; a manifest comment may say NaN);
/// binary files (PNG) and other kinds pass.
pub fn check_bytes(name: &str, bytes: &[u8]) -> Result<(), NonFinite> {
    let ext = name.rsplit('.').next().unwrap_or("");
    let text = String::from_utf8_lossy(bytes);
    for (i, line) in text.lines().enumerate() {
        let cells: Vec<&str> = match ext {
            "csv" => line.split(',').map(|f| f.trim_matches('"')).collect(),
            "md" if line.trim_start().starts_with('|') => line.split('|').collect(),
            "tex" if line.contains('&') => line.split('&').map(|c| c.trim().trim_end_matches("\\\\")).collect(),
            "html" => line
                .split("<td")
                .skip(1)
                .filter_map(|c| c.split_once('>').map(|(_, r)| r.split("</td>").next().unwrap_or(r)))
                .collect(),
            "svg" => line.split('"').skip(1).step_by(2).flat_map(|v| v.split([' ', ','])).collect(),
            _ => Vec::new(),
        };
        if let Some(k) = cells.iter().position(|c| non_finite_cell(c)) {
            return Err(NonFinite(format!(
                "{name}:{}: a non-finite number (field {}) would be written",
                i + 1,
                k + 1
            )));
        }
    }
    Ok(())
}

/// A cell that reads as NaN or an infinity (`NaN`, `inf`, `-inf`, `Infinity`, any
/// case; in a cell, with what may follow a number: a unit, a `%`, a `±`).
fn non_finite_cell(c: &str) -> bool {
    let c = c.trim();
    let c = c.strip_prefix(['-', '+', '−']).unwrap_or(c).to_ascii_lowercase();
    ["nan", "infinity", "inf"].iter().any(|w| {
        c.strip_prefix(w)
            .is_some_and(|rest| rest.is_empty() || rest.starts_with([' ', '%', '$', '°']))
    })
}

struct Walker {
    path: Vec<String>,
}

impl Walker {
    fn float(&self, v: f64) -> Result<(), NonFinite> {
        if v.is_finite() {
            Ok(())
        } else {
            Err(NonFinite(format!("{} is {v}: a non-finite number would be written", self.where_())))
        }
    }
    fn where_(&self) -> String {
        if self.path.is_empty() {
            "the document".into()
        } else {
            self.path.concat().trim_start_matches('.').to_string()
        }
    }
    fn nested<T: Serialize + ?Sized>(&mut self, key: String, v: &T) -> Result<(), NonFinite> {
        self.path.push(key);
        let r = v.serialize(&mut *self);
        self.path.pop();
        r
    }
}

macro_rules! ok_scalars {
    ($($f:ident: $t:ty),*) => {
        $(fn $f(self, _: $t) -> Result<(), NonFinite> { Ok(()) })*
    };
}

impl<'a> ser::Serializer for &'a mut Walker {
    type Ok = ();
    type Error = NonFinite;
    type SerializeSeq = Seq<'a>;
    type SerializeTuple = Seq<'a>;
    type SerializeTupleStruct = Seq<'a>;
    type SerializeTupleVariant = Seq<'a>;
    type SerializeMap = Map<'a>;
    type SerializeStruct = Map<'a>;
    type SerializeStructVariant = Map<'a>;

    ok_scalars!(serialize_bool: bool, serialize_i8: i8, serialize_i16: i16, serialize_i32: i32, serialize_i64: i64,
        serialize_u8: u8, serialize_u16: u16, serialize_u32: u32, serialize_u64: u64, serialize_char: char,
        serialize_str: &str, serialize_bytes: &[u8]);
    fn serialize_f32(self, v: f32) -> Result<(), NonFinite> {
        self.float(v as f64)
    }
    fn serialize_f64(self, v: f64) -> Result<(), NonFinite> {
        self.float(v)
    }
    fn serialize_none(self) -> Result<(), NonFinite> {
        Ok(())
    }
    fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> Result<(), NonFinite> {
        v.serialize(self)
    }
    fn serialize_unit(self) -> Result<(), NonFinite> {
        Ok(())
    }
    fn serialize_unit_struct(self, _: &'static str) -> Result<(), NonFinite> {
        Ok(())
    }
    fn serialize_unit_variant(self, _: &'static str, _: u32, _: &'static str) -> Result<(), NonFinite> {
        Ok(())
    }
    fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> Result<(), NonFinite> {
        v.serialize(self)
    }
    fn serialize_newtype_variant<T: Serialize + ?Sized>(self, _: &'static str, _: u32, variant: &'static str, v: &T) -> Result<(), NonFinite> {
        self.nested(format!(".{variant}"), v)
    }
    fn serialize_seq(self, _: Option<usize>) -> Result<Seq<'a>, NonFinite> {
        Ok(Seq { w: self, i: 0 })
    }
    fn serialize_tuple(self, _: usize) -> Result<Seq<'a>, NonFinite> {
        Ok(Seq { w: self, i: 0 })
    }
    fn serialize_tuple_struct(self, _: &'static str, _: usize) -> Result<Seq<'a>, NonFinite> {
        Ok(Seq { w: self, i: 0 })
    }
    fn serialize_tuple_variant(self, _: &'static str, _: u32, _: &'static str, _: usize) -> Result<Seq<'a>, NonFinite> {
        Ok(Seq { w: self, i: 0 })
    }
    fn serialize_map(self, _: Option<usize>) -> Result<Map<'a>, NonFinite> {
        Ok(Map { w: self, key: String::new() })
    }
    fn serialize_struct(self, _: &'static str, _: usize) -> Result<Map<'a>, NonFinite> {
        Ok(Map { w: self, key: String::new() })
    }
    fn serialize_struct_variant(self, _: &'static str, _: u32, _: &'static str, _: usize) -> Result<Map<'a>, NonFinite> {
        Ok(Map { w: self, key: String::new() })
    }
}

struct Seq<'a> {
    w: &'a mut Walker,
    i: usize,
}

impl Seq<'_> {
    fn item<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), NonFinite> {
        let key = format!("[{}]", self.i);
        self.i += 1;
        self.w.nested(key, v)
    }
}

macro_rules! seq_impl {
    ($($tr:ident :: $f:ident),*) => {
        $(impl ser::$tr for Seq<'_> {
            type Ok = ();
            type Error = NonFinite;
            fn $f<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), NonFinite> {
                self.item(v)
            }
            fn end(self) -> Result<(), NonFinite> {
                Ok(())
            }
        })*
    };
}
seq_impl!(
    SerializeSeq::serialize_element,
    SerializeTuple::serialize_element,
    SerializeTupleStruct::serialize_field,
    SerializeTupleVariant::serialize_field
);

struct Map<'a> {
    w: &'a mut Walker,
    key: String,
}

impl ser::SerializeMap for Map<'_> {
    type Ok = ();
    type Error = NonFinite;
    fn serialize_key<T: Serialize + ?Sized>(&mut self, k: &T) -> Result<(), NonFinite> {
        self.key = serde_json::to_value(k)
            .map(|v| v.as_str().map_or_else(|| v.to_string(), str::to_string))
            .unwrap_or_default();
        Ok(())
    }
    fn serialize_value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), NonFinite> {
        let key = format!(".{}", std::mem::take(&mut self.key));
        self.w.nested(key, v)
    }
    fn end(self) -> Result<(), NonFinite> {
        Ok(())
    }
}

macro_rules! struct_impl {
    ($($tr:ident),*) => {
        $(impl ser::$tr for Map<'_> {
            type Ok = ();
            type Error = NonFinite;
            fn serialize_field<T: Serialize + ?Sized>(&mut self, key: &'static str, v: &T) -> Result<(), NonFinite> {
                self.w.nested(format!(".{key}"), v)
            }
            fn end(self) -> Result<(), NonFinite> {
                Ok(())
            }
        })*
    };
}
struct_impl!(SerializeStruct, SerializeStructVariant);

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Serialize)]
    struct Run {
        name: String,
        pga_g: f64,
        notes: Vec<Option<f64>>,
    }

    #[test]
    fn finds_the_key_path_of_a_nan() {
        let runs = vec![
            Run {
                name: "a".into(),
                pga_g: 0.1,
                notes: vec![None, Some(1.0)],
            },
            Run {
                name: "b".into(),
                pga_g: f64::NAN,
                notes: vec![],
            },
        ];
        let doc = serde_json::json!({"ok": 1.0});
        assert!(check_serialize(&doc).is_ok());
        let e = check_serialize(&serde_json::json!({"x": 1}))
            .and(check_serialize(&runs[..1]))
            .and(check_serialize(&runs))
            .unwrap_err();
        assert_eq!(e.0, "[1].pga_g is NaN: a non-finite number would be written");
        let e = check_serialize(&vec![Run {
            name: "c".into(),
            pga_g: 0.0,
            notes: vec![None, Some(f64::INFINITY)],
        }])
        .unwrap_err();
        assert!(e.0.starts_with("[0].notes[1] is inf"), "{}", e.0);
    }

    #[test]
    fn finds_non_finite_numbers_where_text_outputs_write_numbers() {
        assert!(check_bytes("a.csv", b"t,theta\n0,1e-3\n").is_ok());
        assert!(check_bytes("a.csv", b"t,theta\n0,NaN\n").unwrap_err().0.starts_with("a.csv:2: "));
        assert!(check_bytes("a.csv", b"t,theta\n0,-inf\n").is_err());
        assert!(check_bytes("a.svg", b"<path d=\"M 1 NaN\"/>").is_err());
        assert!(check_bytes("a.svg", b"<polyline points=\"1,2 3,inf\"/>").is_err());
        assert!(check_bytes("a.md", b"| x | inf |").is_err());
        assert!(check_bytes("a.md", b"| x | -inf % |").is_err());
        assert!(check_bytes("a.tex", b"x & NaN \\\\").is_err());
        assert!(check_bytes("a.html", b"<tr><td class=\"n\">inf</td></tr>").is_err());
        assert!(check_bytes("a.png", b"NaN").is_ok());
        // Names, prose, labels, echoed inputs and quoted bad cells are not numbers.
        assert!(check_bytes("a.html", b"<p>information, infinite, Nancy; width_m = inf</p>").is_ok());
        assert!(check_bytes("a.svg", b"<text x=\"1\">inf</text>").is_ok());
        assert!(check_bytes("t.md", "| inf_1 | error: 'NaN' is not a finite number |".as_bytes()).is_ok());
        assert!(check_bytes("t.tex", b"inf\\_1 & 64 \\\\").is_ok());
        assert!(check_bytes("t.html", b"<td>&#39;inf&#39; is not a finite number</td>").is_ok());
    }
}

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

/// Fails naming the line (and field, for a CSV) of the first non-finite number
/// spelled in the text of `name`; binary files (PNG) and unknown kinds pass.
pub fn check_bytes(name: &str, bytes: &[u8]) -> Result<(), NonFinite> {
    let ext = name.rsplit('.').next().unwrap_or("");
    if !matches!(ext, "csv" | "md" | "tex" | "html" | "svg" | "toml" | "txt") {
        return Ok(());
    }
    let text = String::from_utf8_lossy(bytes);
    for (i, line) in text.lines().enumerate() {
        let hit = if ext == "csv" {
            line.split(',').position(|f| non_finite_word(f.trim().trim_matches('"')))
        } else {
            rust_non_finite_word(line)
        };
        if let Some(k) = hit {
            return Err(NonFinite(format!(
                "{name}:{}: a non-finite number (field/word {}) would be written",
                i + 1,
                k + 1
            )));
        }
    }
    Ok(())
}

/// A CSV field that a reader parses as NaN or an infinity.
fn non_finite_word(f: &str) -> bool {
    let f = f.strip_prefix(['-', '+']).unwrap_or(f).to_ascii_lowercase();
    matches!(f.as_str(), "nan" | "inf" | "infinity")
}

/// The index (1-based count of words) of a word that Rust's `Display` writes for a
/// non-finite f64 (`NaN`, `inf`, `-inf`), unless quoted: an error message that
/// quotes the bad cell of an input ('NaN' is not a finite number) is not a number
/// written (quotes as they are or HTML-escaped: `'`, `"`, `‘’`, `“”`, `&#39;`, `&quot;`).
fn rust_non_finite_word(line: &str) -> Option<usize> {
    let is_word = |c: char| c.is_alphanumeric() || c == '_';
    let opening = |c: Option<char>| matches!(c, Some('\'' | '"' | '‘' | '“' | ';'));
    let closing = |c: Option<char>| matches!(c, Some('\'' | '"' | '’' | '”' | '&'));
    let mut k = 0;
    let mut start = None;
    let chars: Vec<(usize, char)> = line.char_indices().collect();
    for (j, &(i, c)) in chars.iter().enumerate().chain(std::iter::once((chars.len(), &(line.len(), ' ')))) {
        match (is_word(c) && i < line.len(), start) {
            (true, None) => start = Some(j),
            (false, Some(s)) => {
                k += 1;
                let word = &line[chars[s].0..i];
                let before = s.checked_sub(1).map(|b| chars[b].1);
                let after = chars.get(j).map(|x| x.1);
                if (word == "NaN" || word == "inf") && !(opening(before) && closing(after)) {
                    return Some(k - 1);
                }
                start = None;
            }
            _ => {}
        }
    }
    None
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
    fn finds_non_finite_words_in_text_outputs() {
        assert!(check_bytes("a.csv", b"t,theta\n0,1e-3\n").is_ok());
        assert!(check_bytes("a.csv", b"t,theta\n0,NaN\n").unwrap_err().0.starts_with("a.csv:2: "));
        assert!(check_bytes("a.csv", b"t,theta\n0,-inf\n").is_err());
        assert!(check_bytes("a.svg", b"<path d=\"M 1 NaN\"/>").is_err());
        assert!(check_bytes("a.md", b"| x | inf |").is_err());
        assert!(check_bytes("a.html", b"<p>information, infinite, Nancy</p>").is_ok());
        assert!(check_bytes("a.png", b"NaN").is_ok());
        // An error message quoting a bad input cell is not a number written.
        assert!(check_bytes("t.md", "| bad | error: 'NaN' is not a finite number |".as_bytes()).is_ok());
        assert!(check_bytes("t.html", b"<td>&#39;inf&#39; is not a finite number</td>").is_ok());
        assert!(check_bytes("t.md", b"| x | -inf |").is_err());
    }
}

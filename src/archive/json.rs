//! A JSON reader whose numbers are exact: each number's text is parsed by Rust's
//! `str::parse::<f64>` (correctly rounded), so a value read back from summary.json is
//! the f64 that was written. serde_json, as this crate builds it (without its
//! `float_roundtrip` feature, which would rebuild polars with it), may land one ulp
//! off on 17-digit numbers: 0.014936020564324741 read as 0.01493602056432474. The
//! result is a `serde_json::Value`, so the rest of the archive reads it as usual.

use serde_json::{Map, Number, Value};

/// Parse a JSON document; the error says the byte offset.
pub fn parse(text: &str) -> Result<Value, String> {
    let mut p = Parser { s: text.as_bytes(), at: 0 };
    let v = p.value(0)?;
    p.ws();
    if p.at != p.s.len() {
        return Err(p.fail("text after the document"));
    }
    Ok(v)
}

struct Parser<'a> {
    s: &'a [u8],
    at: usize,
}

impl Parser<'_> {
    fn fail(&self, what: &str) -> String {
        format!("{what} at byte {}", self.at)
    }
    fn ws(&mut self) {
        while self.s.get(self.at).is_some_and(|b| b.is_ascii_whitespace()) {
            self.at += 1;
        }
    }
    fn eat(&mut self, b: u8) -> Result<(), String> {
        self.ws();
        if self.s.get(self.at) == Some(&b) {
            self.at += 1;
            Ok(())
        } else {
            Err(self.fail(&format!("expected '{}'", b as char)))
        }
    }
    fn value(&mut self, depth: usize) -> Result<Value, String> {
        if depth > 128 {
            return Err(self.fail("nesting too deep"));
        }
        self.ws();
        match self.s.get(self.at) {
            Some(b'{') => self.object(depth),
            Some(b'[') => self.array(depth),
            Some(b'"') => Ok(Value::String(self.string()?)),
            Some(b't') => self.word("true", Value::Bool(true)),
            Some(b'f') => self.word("false", Value::Bool(false)),
            Some(b'n') => self.word("null", Value::Null),
            Some(_) => self.number(),
            None => Err(self.fail("unexpected end")),
        }
    }
    fn word(&mut self, w: &str, v: Value) -> Result<Value, String> {
        if self.s[self.at..].starts_with(w.as_bytes()) {
            self.at += w.len();
            Ok(v)
        } else {
            Err(self.fail("unexpected character"))
        }
    }
    fn object(&mut self, depth: usize) -> Result<Value, String> {
        self.at += 1;
        let mut m = Map::new();
        self.ws();
        if self.s.get(self.at) == Some(&b'}') {
            self.at += 1;
            return Ok(Value::Object(m));
        }
        loop {
            self.ws();
            let k = self.string()?;
            self.eat(b':')?;
            m.insert(k, self.value(depth + 1)?);
            self.ws();
            match self.s.get(self.at) {
                Some(b',') => self.at += 1,
                Some(b'}') => {
                    self.at += 1;
                    return Ok(Value::Object(m));
                }
                _ => return Err(self.fail("expected ',' or '}'")),
            }
        }
    }
    fn array(&mut self, depth: usize) -> Result<Value, String> {
        self.at += 1;
        let mut v = Vec::new();
        self.ws();
        if self.s.get(self.at) == Some(&b']') {
            self.at += 1;
            return Ok(Value::Array(v));
        }
        loop {
            v.push(self.value(depth + 1)?);
            self.ws();
            match self.s.get(self.at) {
                Some(b',') => self.at += 1,
                Some(b']') => {
                    self.at += 1;
                    return Ok(Value::Array(v));
                }
                _ => return Err(self.fail("expected ',' or ']'")),
            }
        }
    }
    fn number(&mut self) -> Result<Value, String> {
        let start = self.at;
        while self.s.get(self.at).is_some_and(|b| b.is_ascii_digit() || b"+-.eE".contains(b)) {
            self.at += 1;
        }
        let text = std::str::from_utf8(&self.s[start..self.at]).map_err(|_| self.fail("bad number"))?;
        if let Ok(i) = text.parse::<i64>() {
            return Ok(Value::Number(i.into()));
        }
        let f: f64 = text.parse().map_err(|_| self.fail(&format!("'{text}' is not a number")))?;
        Number::from_f64(f).map(Value::Number).ok_or_else(|| self.fail("not a finite number"))
    }
    fn string(&mut self) -> Result<String, String> {
        if self.s.get(self.at) != Some(&b'"') {
            return Err(self.fail("expected a string"));
        }
        self.at += 1;
        let mut out: Vec<u8> = Vec::new();
        loop {
            match self.s.get(self.at).copied() {
                None => return Err(self.fail("unterminated string")),
                Some(b'"') => {
                    self.at += 1;
                    return String::from_utf8(out).map_err(|_| self.fail("invalid UTF-8"));
                }
                Some(b'\\') => {
                    let c = self.escape()?;
                    let mut buf = [0u8; 4];
                    out.extend_from_slice(c.encode_utf8(&mut buf).as_bytes());
                }
                Some(b) => {
                    out.push(b);
                    self.at += 1;
                }
            }
        }
    }
    /// One escape sequence (at the backslash), surrogate pairs joined.
    fn escape(&mut self) -> Result<char, String> {
        let e = *self.s.get(self.at + 1).ok_or_else(|| self.fail("unterminated escape"))?;
        self.at += 2;
        Ok(match e {
            b'"' => '"',
            b'\\' => '\\',
            b'/' => '/',
            b'b' => '\u{8}',
            b'f' => '\u{c}',
            b'n' => '\n',
            b'r' => '\r',
            b't' => '\t',
            b'u' => {
                let hi = self.hex4()?;
                if (0xD800..0xDC00).contains(&hi) && self.s[self.at..].starts_with(b"\\u") {
                    self.at += 2;
                    let lo = self.hex4()?;
                    char::from_u32(0x10000 + ((hi - 0xD800) << 10) + (lo.wrapping_sub(0xDC00) & 0x3FF))
                        .ok_or_else(|| self.fail("bad surrogate pair"))?
                } else {
                    char::from_u32(hi).ok_or_else(|| self.fail("bad \\u escape"))?
                }
            }
            _ => return Err(self.fail("bad escape")),
        })
    }
    fn hex4(&mut self) -> Result<u32, String> {
        let h = self.s.get(self.at..self.at + 4).ok_or_else(|| self.fail("short \\u escape"))?;
        let v = u32::from_str_radix(std::str::from_utf8(h).map_err(|_| self.fail("bad \\u escape"))?, 16).map_err(|_| self.fail("bad \\u escape"))?;
        self.at += 4;
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_exact_and_the_document_equals_serde_json_otherwise() {
        let text = r#"{"a": 0.014936020564324741, "b": [1, -2, 3.5e-3, true, null], "s": "α \"q\" \u00e9 \ud83d\ude00", "o": {}}"#;
        let v = parse(text).unwrap();
        assert_eq!(v["a"].as_f64(), Some("0.014936020564324741".parse::<f64>().unwrap()));
        let reference: Value = serde_json::from_str(text).unwrap();
        assert_eq!(v["b"], reference["b"]);
        assert_eq!(v["s"], reference["s"]);
        assert_eq!(v["o"], reference["o"]);
        for bad in ["", "{", "[1,]", "{\"a\" 1}", "\"x", "1 2", "tru"] {
            assert!(parse(bad).is_err(), "{bad}");
        }
    }
}

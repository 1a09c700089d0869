//! The page's data: typed arrays packed end to end in one buffer (each aligned to four bytes),
//! gzip-compressed and base64-encoded into the page, with a table of where each array lies.
//! The page reads them back as `Float32Array`s, `Uint32Array`s, … without parsing text, so a
//! program of 100 000 moves costs a few megabytes and no JSON parsing.

use base64::Engine as _;
use std::io::Write as _;

/// The element type of a packed array, as the page names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Kind {
    F32,
    U32,
    U16,
    U8,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::F32 => "f32",
            Kind::U32 => "u32",
            Kind::U16 => "u16",
            Kind::U8 => "u8",
        }
    }
}

/// Arrays packed into one buffer.
#[derive(Debug, Default)]
pub(crate) struct Pack {
    buf: Vec<u8>,
    /// Name, type, byte offset, element count.
    table: Vec<(String, Kind, usize, usize)>,
}

impl Pack {
    fn align(&mut self) {
        while !self.buf.len().is_multiple_of(4) {
            self.buf.push(0);
        }
    }

    fn add(&mut self, name: String, kind: Kind, len: usize, bytes: impl FnOnce(&mut Vec<u8>)) {
        self.align();
        let at = self.buf.len();
        bytes(&mut self.buf);
        self.table.push((name, kind, at, len));
    }

    /// Single-precision floats (NaN stands for "none" where the page expects it).
    pub fn f32(&mut self, name: impl Into<String>, v: impl IntoIterator<Item = f32>) {
        let v: Vec<f32> = v.into_iter().collect();
        self.add(name.into(), Kind::F32, v.len(), |b| v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes())));
    }

    /// Unsigned 32-bit integers.
    pub fn u32(&mut self, name: impl Into<String>, v: impl IntoIterator<Item = u32>) {
        let v: Vec<u32> = v.into_iter().collect();
        self.add(name.into(), Kind::U32, v.len(), |b| v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes())));
    }

    /// Unsigned 16-bit integers.
    pub fn u16(&mut self, name: impl Into<String>, v: impl IntoIterator<Item = u16>) {
        let v: Vec<u16> = v.into_iter().collect();
        self.add(name.into(), Kind::U16, v.len(), |b| v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes())));
    }

    /// Bytes (flags, or UTF-8 text such as the G-code).
    pub fn u8(&mut self, name: impl Into<String>, v: &[u8]) {
        self.add(name.into(), Kind::U8, v.len(), |b| b.extend_from_slice(v));
    }

    /// The table for the page: `{name: [type, byte offset, count]}`.
    pub fn table(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        for (name, kind, at, len) in &self.table {
            m.insert(name.clone(), serde_json::json!([kind.name(), at, len]));
        }
        serde_json::Value::Object(m)
    }

    /// Raw size, bytes.
    pub fn len(&self) -> usize {
        self.buf.len()
    }

    /// The buffer gzip-compressed (no file name, no time: the same arrays give the same bytes)
    /// and base64-encoded.
    pub fn encoded(&self) -> String {
        let mut gz = flate2::GzBuilder::new().mtime(0).write(Vec::new(), flate2::Compression::new(6));
        // (writing to a Vec cannot fail)
        gz.write_all(&self.buf).expect("in-memory gzip");
        let z = gz.finish().expect("in-memory gzip");
        base64::engine::general_purpose::STANDARD.encode(z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read as _;

    #[test]
    fn arrays_are_aligned_and_come_back_from_the_encoding() {
        let mut p = Pack::default();
        p.u8("a", &[1, 2, 3]);
        p.f32("b", [1.5f32, f32::NAN]);
        p.u16("c", [7u16]);
        p.u32("d", [0xdead_beef]);
        let t = p.table();
        assert_eq!(t["a"], serde_json::json!(["u8", 0, 3]));
        assert_eq!(t["b"], serde_json::json!(["f32", 4, 2]));
        assert_eq!(t["c"], serde_json::json!(["u16", 12, 1]));
        assert_eq!(t["d"], serde_json::json!(["u32", 16, 1]));
        let z = base64::engine::general_purpose::STANDARD.decode(p.encoded()).unwrap();
        let mut raw = Vec::new();
        flate2::read::GzDecoder::new(&z[..]).read_to_end(&mut raw).unwrap();
        assert_eq!(raw.len(), p.len());
        assert_eq!(f32::from_le_bytes(raw[4..8].try_into().unwrap()), 1.5);
        assert_eq!(u32::from_le_bytes(raw[16..20].try_into().unwrap()), 0xdead_beef);
        // deterministic
        assert_eq!(p.encoded(), p.encoded());
    }
}

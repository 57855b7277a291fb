//! Minecraft's NBT (named binary tags, Java edition: big-endian), as Sponge schematics are
//! stored (gzip-compressed): a reader that refuses what is malformed with the byte where it
//! is (nesting beyond [`MAX_DEPTH`], lengths past the end, unknown tags) and never allocates
//! more than the bytes it has could hold, and a writer.

use std::collections::BTreeMap;

/// The deepest nesting read.
pub const MAX_DEPTH: usize = 64;

/// A tag's value.
#[derive(Clone, Debug, PartialEq)]
pub enum Tag {
    /// 1: a signed byte.
    Byte(i8),
    /// 2: a short.
    Short(i16),
    /// 3: an int.
    Int(i32),
    /// 4: a long.
    Long(i64),
    /// 5: a float.
    Float(f32),
    /// 6: a double.
    Double(f64),
    /// 7: bytes.
    ByteArray(Vec<u8>),
    /// 8: text (Java's modified UTF-8, read as UTF-8).
    String(String),
    /// 9: a list of tags of one type (the type kept for an empty list).
    List(u8, Vec<Tag>),
    /// 10: named tags.
    Compound(BTreeMap<String, Tag>),
    /// 11: ints.
    IntArray(Vec<i32>),
    /// 12: longs.
    LongArray(Vec<i64>),
}

impl Tag {
    /// The type byte.
    pub fn id(&self) -> u8 {
        match self {
            Tag::Byte(_) => 1,
            Tag::Short(_) => 2,
            Tag::Int(_) => 3,
            Tag::Long(_) => 4,
            Tag::Float(_) => 5,
            Tag::Double(_) => 6,
            Tag::ByteArray(_) => 7,
            Tag::String(_) => 8,
            Tag::List(..) => 9,
            Tag::Compound(_) => 10,
            Tag::IntArray(_) => 11,
            Tag::LongArray(_) => 12,
        }
    }

    /// A compound's child.
    pub fn get(&self, name: &str) -> Option<&Tag> {
        match self {
            Tag::Compound(c) => c.get(name),
            _ => None,
        }
    }

    /// An integer tag's value (byte, short, int or long).
    pub fn int(&self) -> Option<i64> {
        match *self {
            Tag::Byte(v) => Some(v as i64),
            Tag::Short(v) => Some(v as i64),
            Tag::Int(v) => Some(v as i64),
            Tag::Long(v) => Some(v),
            _ => None,
        }
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        match end {
            Some(end) => {
                let s = &self.bytes[self.at..end];
                self.at = end;
                Ok(s)
            }
            None => Err(format!(
                "the NBT data ends at byte {} where {n} more bytes were due at byte {} (truncated)",
                self.bytes.len(),
                self.at
            )),
        }
    }

    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn be<const N: usize>(&mut self) -> Result<[u8; N], String> {
        Ok(self.take(N)?.try_into().expect("N bytes"))
    }

    /// A length, refused when negative or when `each`-byte items of it cannot fit.
    fn len(&mut self, each: usize) -> Result<usize, String> {
        let at = self.at;
        let n = i32::from_be_bytes(self.be()?);
        let left = self.bytes.len() - self.at;
        if n < 0 || (n as usize).saturating_mul(each.max(1)) > left {
            return Err(format!(
                "an array or list at byte {at} claims {n} items; {left} bytes are left"
            ));
        }
        Ok(n as usize)
    }

    fn string(&mut self) -> Result<String, String> {
        let n = u16::from_be_bytes(self.be()?) as usize;
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }

    fn payload(&mut self, id: u8, depth: usize) -> Result<Tag, String> {
        if depth > MAX_DEPTH {
            return Err(format!(
                "tags nest deeper than {MAX_DEPTH} at byte {}",
                self.at
            ));
        }
        Ok(match id {
            1 => Tag::Byte(self.u8()? as i8),
            2 => Tag::Short(i16::from_be_bytes(self.be()?)),
            3 => Tag::Int(i32::from_be_bytes(self.be()?)),
            4 => Tag::Long(i64::from_be_bytes(self.be()?)),
            5 => Tag::Float(f32::from_be_bytes(self.be()?)),
            6 => Tag::Double(f64::from_be_bytes(self.be()?)),
            7 => {
                let n = self.len(1)?;
                Tag::ByteArray(self.take(n)?.to_vec())
            }
            8 => Tag::String(self.string()?),
            9 => {
                let item = self.u8()?;
                // An end-typed list must be empty; other items take a byte at least.
                let n = self.len(1)?;
                if item == 0 && n > 0 {
                    return Err(format!(
                        "a list of end tags with {n} items at byte {}",
                        self.at
                    ));
                }
                let mut items = Vec::with_capacity(n.min(4096));
                for _ in 0..n {
                    items.push(self.payload(item, depth + 1)?);
                }
                Tag::List(item, items)
            }
            10 => {
                let mut c = BTreeMap::new();
                loop {
                    let id = self.u8()?;
                    if id == 0 {
                        break;
                    }
                    let name = self.string()?;
                    let value = self.payload(id, depth + 1)?;
                    c.insert(name, value);
                }
                Tag::Compound(c)
            }
            11 => {
                let n = self.len(4)?;
                let raw = self.take(n * 4)?;
                Tag::IntArray(
                    raw.chunks_exact(4)
                        .map(|c| i32::from_be_bytes(c.try_into().expect("4")))
                        .collect(),
                )
            }
            12 => {
                let n = self.len(8)?;
                let raw = self.take(n * 8)?;
                Tag::LongArray(
                    raw.chunks_exact(8)
                        .map(|c| i64::from_be_bytes(c.try_into().expect("8")))
                        .collect(),
                )
            }
            other => {
                return Err(format!(
                    "unknown tag type {other} at byte {}",
                    self.at.saturating_sub(1)
                ));
            }
        })
    }
}

/// Reads uncompressed NBT: the root tag's name and value; every byte must belong to it.
pub fn read(bytes: &[u8]) -> Result<(String, Tag), String> {
    let mut r = Reader { bytes, at: 0 };
    let id = r.u8()?;
    if id != 10 {
        return Err(format!("the root tag is of type {id}, not a compound"));
    }
    let name = r.string()?;
    let value = r.payload(10, 0)?;
    if r.at != bytes.len() {
        return Err(format!("{} bytes follow the root tag", bytes.len() - r.at));
    }
    Ok((name, value))
}

fn write_payload(out: &mut Vec<u8>, tag: &Tag) {
    let len = |out: &mut Vec<u8>, n: usize| out.extend_from_slice(&(n as i32).to_be_bytes());
    match tag {
        Tag::Byte(v) => out.push(*v as u8),
        Tag::Short(v) => out.extend_from_slice(&v.to_be_bytes()),
        Tag::Int(v) => out.extend_from_slice(&v.to_be_bytes()),
        Tag::Long(v) => out.extend_from_slice(&v.to_be_bytes()),
        Tag::Float(v) => out.extend_from_slice(&v.to_be_bytes()),
        Tag::Double(v) => out.extend_from_slice(&v.to_be_bytes()),
        Tag::ByteArray(b) => {
            len(out, b.len());
            out.extend_from_slice(b);
        }
        Tag::String(s) => write_string(out, s),
        Tag::List(id, items) => {
            out.push(*id);
            len(out, items.len());
            for i in items {
                write_payload(out, i);
            }
        }
        Tag::Compound(c) => {
            for (name, value) in c {
                out.push(value.id());
                write_string(out, name);
                write_payload(out, value);
            }
            out.push(0);
        }
        Tag::IntArray(v) => {
            len(out, v.len());
            for x in v {
                out.extend_from_slice(&x.to_be_bytes());
            }
        }
        Tag::LongArray(v) => {
            len(out, v.len());
            for x in v {
                out.extend_from_slice(&x.to_be_bytes());
            }
        }
    }
}

fn write_string(out: &mut Vec<u8>, s: &str) {
    let mut end = s.len().min(u16::MAX as usize);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    out.extend_from_slice(&(end as u16).to_be_bytes());
    out.extend_from_slice(&s.as_bytes()[..end]);
}

/// Writes a root compound named `name`.
pub fn write(name: &str, root: &Tag) -> Vec<u8> {
    let mut out = vec![root.id()];
    write_string(&mut out, name);
    write_payload(&mut out, root);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tags_round_trip_and_hostile_lengths_are_refused() {
        let mut c = BTreeMap::new();
        c.insert("a".to_string(), Tag::Short(-3));
        c.insert("b".to_string(), Tag::ByteArray(vec![1, 2, 3]));
        c.insert(
            "c".to_string(),
            Tag::List(3, vec![Tag::Int(7), Tag::Int(-9)]),
        );
        c.insert("d".to_string(), Tag::IntArray(vec![1, -1]));
        c.insert("e".to_string(), Tag::String("minecraft:stone".into()));
        let root = Tag::Compound(c);
        let bytes = write("Schematic", &root);
        assert_eq!(read(&bytes).unwrap(), ("Schematic".to_string(), root));
        // A byte array claiming 2³¹ − 1 bytes.
        let mut huge = vec![10, 0, 0, 7, 0, 1, b'x'];
        huge.extend_from_slice(&i32::MAX.to_be_bytes());
        assert!(read(&huge).unwrap_err().contains("claims 2147483647 items"));
        // Compounds nested past the limit.
        let mut deep = vec![10, 0, 0];
        for _ in 0..100 {
            deep.extend_from_slice(&[10, 0, 1, b'k']);
        }
        assert!(read(&deep).unwrap_err().contains("nest deeper"));
        assert!(
            read(&bytes[..bytes.len() - 2])
                .unwrap_err()
                .contains("truncated")
        );
    }
}

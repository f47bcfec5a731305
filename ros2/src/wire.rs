//! Plain little-endian CDR (XCDR1) as ROS 2 uses it: a 4-byte encapsulation header, then fields at their natural
//! alignment counted from the end of that header; strings as a `u32` length that counts a terminating NUL;
//! sequences as a `u32` element count and the elements.

use crate::{CDR_LE_HEADER, CdrError};

/// Writes one CDR message into a reusable buffer.
pub struct CdrWriter<'a> {
    out: &'a mut Vec<u8>,
}

impl<'a> CdrWriter<'a> {
    /// Starts a message in `out` (cleared; its capacity is kept, so steady-state encoding does not allocate).
    pub fn new(out: &'a mut Vec<u8>) -> Self {
        out.clear();
        out.extend_from_slice(&CDR_LE_HEADER);
        Self { out }
    }

    fn align(&mut self, n: usize) {
        let body = self.out.len() - CDR_LE_HEADER.len();
        self.out
            .resize(CDR_LE_HEADER.len() + body.next_multiple_of(n), 0);
    }

    /// A `uint8`, `byte` or `char`.
    pub fn u8(&mut self, v: u8) {
        self.out.push(v);
    }
    /// A `bool` (one byte, 0 or 1).
    pub fn bool(&mut self, v: bool) {
        self.out.push(u8::from(v));
    }
    /// A `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }
    /// An `int32`.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.out.extend_from_slice(&v.to_le_bytes());
    }
    /// A `uint64`.
    pub fn u64(&mut self, v: u64) {
        self.align(8);
        self.out.extend_from_slice(&v.to_le_bytes());
    }
    /// A `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.out.extend_from_slice(&v.to_le_bytes());
    }
    /// `float64` values one after another (a fixed array, or a sequence's elements after its count).
    pub fn f64s(&mut self, v: &[f64]) {
        for x in v {
            self.f64(*x);
        }
    }
    /// A sequence's element count (saturating: no message here comes near 4 Gi elements).
    pub fn count(&mut self, n: usize) {
        self.u32(u32::try_from(n).unwrap_or(u32::MAX));
    }
    /// A `string`: length including the NUL, the bytes, the NUL.
    pub fn string(&mut self, s: &str) {
        self.count(s.len() + 1);
        self.out.extend_from_slice(s.as_bytes());
        self.out.push(0);
    }
    /// A `uint8[]` / `byte[]` sequence.
    pub fn bytes(&mut self, b: &[u8]) {
        self.count(b.len());
        self.out.extend_from_slice(b);
    }
}

/// Reads one CDR message; every read names its field, so an error says what was wrong where.
pub struct CdrReader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> CdrReader<'a> {
    /// A reader of `bytes`, after checking the little-endian plain CDR encapsulation header.
    pub fn new(bytes: &'a [u8]) -> Result<Self, CdrError> {
        let header: [u8; 4] =
            bytes
                .get(..4)
                .and_then(|h| h.try_into().ok())
                .ok_or(CdrError::Truncated {
                    field: "encapsulation header",
                    offset: 0,
                    needed: 4,
                    len: bytes.len(),
                })?;
        if header[..2] != CDR_LE_HEADER[..2] {
            return Err(CdrError::Encapsulation(header));
        }
        Ok(Self { bytes, pos: 4 })
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// `n` bytes at alignment `align`.
    pub fn take(
        &mut self,
        field: &'static str,
        n: usize,
        align: usize,
    ) -> Result<&'a [u8], CdrError> {
        let body = self.pos - CDR_LE_HEADER.len();
        let start = CDR_LE_HEADER.len() + body.next_multiple_of(align);
        let truncated = CdrError::Truncated {
            field,
            offset: start,
            needed: n,
            len: self.bytes.len(),
        };
        let end = start.checked_add(n).ok_or_else(|| truncated.clone())?;
        let slice = self.bytes.get(start..end).ok_or(truncated)?;
        self.pos = end;
        Ok(slice)
    }

    fn array<const N: usize>(&mut self, field: &'static str) -> Result<[u8; N], CdrError> {
        let s = self.take(field, N, N)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    /// A `uint8`.
    pub fn u8(&mut self, field: &'static str) -> Result<u8, CdrError> {
        Ok(self.array::<1>(field)?[0])
    }
    /// A `bool`: 0 or 1, anything else refused.
    pub fn bool(&mut self, field: &'static str) -> Result<bool, CdrError> {
        match self.u8(field)? {
            0 => Ok(false),
            1 => Ok(true),
            value => Err(CdrError::NotBool { field, value }),
        }
    }
    /// A `uint32`.
    pub fn u32(&mut self, field: &'static str) -> Result<u32, CdrError> {
        Ok(u32::from_le_bytes(self.array::<4>(field)?))
    }
    /// An `int32`.
    pub fn i32(&mut self, field: &'static str) -> Result<i32, CdrError> {
        Ok(i32::from_le_bytes(self.array::<4>(field)?))
    }
    /// A `uint64`.
    pub fn u64(&mut self, field: &'static str) -> Result<u64, CdrError> {
        Ok(u64::from_le_bytes(self.array::<8>(field)?))
    }
    /// A `float64`.
    pub fn f64(&mut self, field: &'static str) -> Result<f64, CdrError> {
        Ok(f64::from_le_bytes(self.array::<8>(field)?))
    }
    /// `N` `float64` values.
    pub fn f64s<const N: usize>(&mut self, field: &'static str) -> Result<[f64; N], CdrError> {
        let mut a = [0.0; N];
        for v in &mut a {
            *v = self.f64(field)?;
        }
        Ok(a)
    }
    /// A sequence's element count, refused when `min_element_bytes` per element would not fit in what is left
    /// (so a corrupt count never makes a reader allocate or loop for nothing).
    pub fn count(
        &mut self,
        field: &'static str,
        min_element_bytes: usize,
    ) -> Result<usize, CdrError> {
        let n = self.u32(field)?;
        let fits = (n as usize)
            .checked_mul(min_element_bytes.max(1))
            .is_some_and(|b| b <= self.remaining());
        if !fits {
            return Err(CdrError::SequenceLength {
                field,
                count: n.into(),
                reason: "longer than the bytes left",
            });
        }
        Ok(n as usize)
    }
    /// A `string`.
    pub fn string(&mut self, field: &'static str) -> Result<String, CdrError> {
        let len = self.u32(field)? as usize;
        if len == 0 {
            return Err(CdrError::ZeroLengthString(field));
        }
        let s = self.take(field, len, 1)?;
        let (nul, text) = s.split_last().ok_or(CdrError::ZeroLengthString(field))?;
        if *nul != 0 {
            return Err(CdrError::MissingNul(field));
        }
        Ok(std::str::from_utf8(text)
            .map_err(|_| CdrError::NotUtf8(field))?
            .to_owned())
    }
    /// A `uint8[]` sequence, borrowed from the input.
    pub fn bytes(&mut self, field: &'static str) -> Result<&'a [u8], CdrError> {
        let n = self.count(field, 1)?;
        self.take(field, n, 1)
    }
    /// A `float64[]` sequence.
    pub fn f64_seq(&mut self, field: &'static str) -> Result<Vec<f64>, CdrError> {
        let n = self.count(field, 8)?;
        (0..n).map(|_| self.f64(field)).collect()
    }
}

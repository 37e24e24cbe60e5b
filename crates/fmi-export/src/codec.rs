//! Little-endian byte encoding for FMU states, with a bounds-checked reader: a truncated or
//! altered buffer gives an error, never an out-of-bounds read.

/// Why saved state bytes cannot be read back.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StateError {
    /// Fewer bytes than a value needs.
    #[error("state truncated: needs {needed} more bytes at offset {offset}, has {remaining}")]
    Truncated {
        /// Bytes the next value needs.
        needed: usize,
        /// Where it starts.
        offset: usize,
        /// Bytes left.
        remaining: usize,
    },
    /// A list of another length than the model's.
    #[error("state holds {found} {what} where {expected} are expected")]
    Count {
        /// What the list holds.
        what: &'static str,
        /// Its length in the state.
        found: usize,
        /// The length the model needs.
        expected: usize,
    },
    /// Bytes left over after the last value.
    #[error("{0} unexpected bytes at the end of the state")]
    TrailingBytes(usize),
    /// A value outside its range.
    #[error("invalid state: {0}")]
    Invalid(String),
}

/// Appends fixed-size little-endian values to a byte vector.
pub trait Put {
    /// Appends a `u8`.
    fn put_u8(&mut self, v: u8);
    /// Appends a `u32`.
    fn put_u32(&mut self, v: u32);
    /// Appends a `u64`.
    fn put_u64(&mut self, v: u64);
    /// Appends an `f64` bit for bit.
    fn put_f64(&mut self, v: f64);
    /// Appends a length-prefixed byte string.
    fn put_bytes(&mut self, v: &[u8]);
    /// Appends a length-prefixed list of `f64`.
    fn put_f64s(&mut self, v: &[f64]) {
        self.put_u32(v.len() as u32);
        for &x in v {
            self.put_f64(x);
        }
    }
}

impl Put for Vec<u8> {
    fn put_u8(&mut self, v: u8) {
        self.push(v);
    }
    fn put_u32(&mut self, v: u32) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn put_u64(&mut self, v: u64) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn put_f64(&mut self, v: f64) {
        self.extend_from_slice(&v.to_bits().to_le_bytes());
    }
    fn put_bytes(&mut self, v: &[u8]) {
        self.put_u32(v.len() as u32);
        self.extend_from_slice(v);
    }
}

/// Reads what [`Put`] wrote; every read checks the remaining length.
#[derive(Debug)]
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    /// A reader at the start of `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { bytes, at: 0 }
    }

    /// The next `n` bytes.
    pub fn take(&mut self, n: usize) -> Result<&'a [u8], StateError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or(StateError::Truncated {
            needed: n,
            offset: self.at,
            remaining: self.bytes.len() - self.at,
        })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }

    /// Reads a `u8`.
    pub fn u8(&mut self) -> Result<u8, StateError> {
        Ok(self.take(1)?[0])
    }
    /// Reads a `u32`.
    pub fn u32(&mut self) -> Result<u32, StateError> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }
    /// Reads a `u64`.
    pub fn u64(&mut self) -> Result<u64, StateError> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }
    /// Reads an `f64`.
    pub fn f64(&mut self) -> Result<f64, StateError> {
        Ok(f64::from_bits(self.u64()?))
    }
    /// Reads a length-prefixed byte string.
    pub fn bytes(&mut self) -> Result<&'a [u8], StateError> {
        let n = self.u32()? as usize;
        self.take(n)
    }
    /// Reads a length-prefixed list of exactly `expected` `f64`.
    pub fn f64s(&mut self, expected: usize) -> Result<Vec<f64>, StateError> {
        let n = self.count("values", expected)?;
        (0..n).map(|_| self.f64()).collect()
    }
    /// Reads a length-prefixed list of exactly `expected` `f64`, each a finite number: a
    /// model's state is made of numbers its steps produced, which are finite, so NaN or an
    /// infinity is an altered state. `what` names the list in the error.
    pub fn finite_f64s(&mut self, what: &'static str, expected: usize) -> Result<Vec<f64>, StateError> {
        let n = self.count(what, expected)?;
        let values = (0..n).map(|_| self.f64()).collect::<Result<Vec<_>, _>>()?;
        match values.iter().position(|v| !v.is_finite()) {
            Some(i) => Err(StateError::Invalid(format!("{what}[{i}] = {} is not a finite number", values[i]))),
            None => Ok(values),
        }
    }
    /// Reads a `u32` length that must be `expected`; `what` names the list in the error.
    pub fn count(&mut self, what: &'static str, expected: usize) -> Result<usize, StateError> {
        let found = self.u32()? as usize;
        if found == expected {
            Ok(found)
        } else {
            Err(StateError::Count { what, found, expected })
        }
    }
    /// Fails unless every byte was read.
    pub fn finish(&self) -> Result<(), StateError> {
        if self.at == self.bytes.len() {
            Ok(())
        } else {
            Err(StateError::TrailingBytes(self.bytes.len() - self.at))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finite_lists_refuse_nan_and_infinities_by_position() {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut bytes = Vec::new();
            bytes.put_f64s(&[1.0, bad, 3.0]);
            let e = Reader::new(&bytes).finite_f64s("q", 3).unwrap_err().to_string();
            assert_eq!(e, format!("invalid state: q[1] = {bad} is not a finite number"));
        }
        let mut bytes = Vec::new();
        bytes.put_f64s(&[1.0, -2.5, f64::MAX]);
        assert_eq!(Reader::new(&bytes).finite_f64s("q", 3).unwrap(), vec![1.0, -2.5, f64::MAX]);
        assert!(matches!(Reader::new(&bytes).finite_f64s("q", 2), Err(StateError::Count { found: 3, expected: 2, .. })));
    }
}

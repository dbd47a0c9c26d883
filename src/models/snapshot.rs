//! The byte format of FMU states (`fmi2SerializeFMUstate`, `fmi3SerializeFMUState`), owned
//! here: pointer-free, little-endian, versioned and checksummed. An envelope
//! ([`seal`]/[`open`]: magic, format version, model kind, instantiation-token hash, payload
//! length, payload, FNV-1a checksum) around a payload that the instance (its own fields) and
//! the model ([`crate::models::FmuModel::save`]) write with [`ByteWriter`]. Every read is
//! bounds-checked: a truncated, corrupted or foreign buffer gives an error, never an
//! out-of-bounds read.

/// Appends little-endian values to a byte buffer.
#[derive(Default)]
pub struct ByteWriter {
    pub bytes: Vec<u8>,
}

impl ByteWriter {
    pub fn f64(&mut self, x: f64) {
        self.bytes.extend_from_slice(&x.to_bits().to_le_bytes());
    }
    pub fn f64s(&mut self, xs: &[f64]) {
        for &x in xs {
            self.f64(x);
        }
    }
    pub fn u64(&mut self, x: u64) {
        self.bytes.extend_from_slice(&x.to_le_bytes());
    }
    pub fn u32(&mut self, x: u32) {
        self.bytes.extend_from_slice(&x.to_le_bytes());
    }
    pub fn i32(&mut self, x: i32) {
        self.bytes.extend_from_slice(&x.to_le_bytes());
    }
    pub fn u8(&mut self, x: u8) {
        self.bytes.push(x);
    }
    /// A text: its length in bytes, then its UTF-8 bytes.
    pub fn str(&mut self, x: &str) {
        self.u64(x.len() as u64);
        self.raw(x.as_bytes());
    }
    pub fn bool(&mut self, x: bool) {
        self.bytes.push(x as u8);
    }
    pub fn raw(&mut self, b: &[u8]) {
        self.bytes.extend_from_slice(b);
    }
}

/// Reads what a [`ByteWriter`] wrote, refusing to read past the end.
pub struct ByteReader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

/// Why a byte buffer is not a valid state.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SnapshotError(pub String);

impl std::fmt::Display for SnapshotError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl<'a> ByteReader<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        ByteReader { bytes, pos: 0 }
    }

    pub fn take(&mut self, n: usize) -> Result<&'a [u8], SnapshotError> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.bytes.len()).ok_or_else(|| {
            SnapshotError(format!(
                "truncated: needed {n} bytes at offset {}, buffer has {}",
                self.pos,
                self.bytes.len()
            ))
        })?;
        let out = &self.bytes[self.pos..end];
        self.pos = end;
        Ok(out)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], SnapshotError> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    pub fn f64(&mut self) -> Result<f64, SnapshotError> {
        Ok(f64::from_bits(u64::from_le_bytes(self.array()?)))
    }
    /// A finite f64: every number in our states is finite.
    pub fn finite(&mut self, what: &str) -> Result<f64, SnapshotError> {
        let x = self.f64()?;
        if x.is_finite() { Ok(x) } else { Err(SnapshotError(format!("{what} is not finite ({x})"))) }
    }
    pub fn finite_array<const N: usize>(&mut self, what: &str) -> Result<[f64; N], SnapshotError> {
        let mut a = [0.0; N];
        for x in a.iter_mut() {
            *x = self.finite(what)?;
        }
        Ok(a)
    }
    pub fn u64(&mut self) -> Result<u64, SnapshotError> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    pub fn u32(&mut self) -> Result<u32, SnapshotError> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub fn i32(&mut self) -> Result<i32, SnapshotError> {
        Ok(i32::from_le_bytes(self.array()?))
    }
    pub fn u8(&mut self) -> Result<u8, SnapshotError> {
        Ok(self.array::<1>()?[0])
    }
    /// A text written by [`ByteWriter::str`].
    pub fn string(&mut self, what: &str) -> Result<String, SnapshotError> {
        let len =
            usize::try_from(self.u64()?).map_err(|_| SnapshotError(format!("{what}: a length that does not fit")))?;
        let bytes = self.take(len)?;
        String::from_utf8(bytes.to_vec()).map_err(|_| SnapshotError(format!("{what}: not UTF-8 text")))
    }
    pub fn bool(&mut self) -> Result<bool, SnapshotError> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(SnapshotError(format!("invalid boolean byte {b}"))),
        }
    }
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }
}

/// FNV-1a, 64 bit: a checksum against corruption (not a cryptographic hash), and the hash
/// behind the instantiation tokens.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}

/// Serialized FMU states start with this.
const STATE_FORMAT_MAGIC: &[u8; 8] = b"STEWFMU\x00";
/// Version of the format; a state of another version is refused with a message.
pub const STATE_FORMAT_VERSION: u32 = 8;

/// Wraps a payload in the envelope: magic, version, model kind, token hash, length, payload,
/// checksum.
pub fn seal(kind_code: u8, token_hash: u64, payload: &[u8]) -> Vec<u8> {
    let mut w = ByteWriter::default();
    w.raw(STATE_FORMAT_MAGIC);
    w.u32(STATE_FORMAT_VERSION);
    w.u8(kind_code);
    w.u64(token_hash);
    w.u64(payload.len() as u64);
    w.raw(payload);
    let checksum = fnv1a64(&w.bytes);
    w.u64(checksum);
    w.bytes
}

/// Checks the envelope of `bytes` against the model kind and token hash and returns the
/// payload.
pub fn open(bytes: &[u8], kind_code: u8, token_hash: u64) -> Result<&[u8], SnapshotError> {
    let mut r = ByteReader::new(bytes);
    if r.take(8)? != STATE_FORMAT_MAGIC {
        return Err(SnapshotError("not a state of this FMU (wrong magic bytes)".into()));
    }
    let version = r.u32()?;
    if version != STATE_FORMAT_VERSION {
        return Err(SnapshotError(format!("state format version {version}, this binary reads {STATE_FORMAT_VERSION}")));
    }
    let kind = r.u8()?;
    if kind != kind_code {
        return Err(SnapshotError(format!("state of model kind {kind}, this instance is of kind {kind_code}")));
    }
    if r.u64()? != token_hash {
        return Err(SnapshotError("state of a different version of this model (instantiation token differs)".into()));
    }
    let len = usize::try_from(r.u64()?).map_err(|_| SnapshotError("payload length overflows".into()))?;
    let payload = r.take(len)?;
    let sealed = bytes.len() - r.remaining();
    let checksum = r.u64()?;
    if r.remaining() != 0 {
        return Err(SnapshotError(format!("{} unexpected bytes after the checksum", r.remaining())));
    }
    if fnv1a64(bytes.get(..sealed).unwrap_or(&[])) != checksum {
        return Err(SnapshotError("checksum mismatch: the state is corrupted".into()));
    }
    Ok(payload)
}

#[cfg(test)]
mod envelope_tests {
    use super::*;

    #[test]
    fn sealed_payload_opens_and_any_flipped_byte_is_refused() {
        let bytes = seal(1, 42, b"payload");
        assert_eq!(open(&bytes, 1, 42).unwrap(), b"payload");
        assert!(open(&bytes, 2, 42).is_err());
        assert!(open(&bytes, 1, 43).is_err());
        for i in 0..bytes.len() {
            let mut b = bytes.clone();
            b[i] ^= 0x10;
            assert!(open(&b, 1, 42).is_err(), "byte {i}");
        }
        assert!(open(&bytes[..bytes.len() - 1], 1, 42).is_err());
    }
}

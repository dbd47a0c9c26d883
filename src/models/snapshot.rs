//! A small pointer-free, versioned, checksummed byte format for FMU states
//! (`fmi2SerializeFMUstate`). Every read is bounds-checked: a truncated, corrupted or foreign
//! buffer gives an error, never an out-of-bounds read.

use nalgebra::Vector3;

use crate::physics::stand::{LEG_COUNT, Stand};

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
    pub fn bool(&mut self, x: bool) {
        self.bytes.push(x as u8);
    }
    pub fn raw(&mut self, b: &[u8]) {
        self.bytes.extend_from_slice(b);
    }
    /// A stand: mass, inertia, gravity, base joints, platform joints.
    pub fn stand(&mut self, s: &Stand) {
        self.f64(s.mass);
        self.f64s(&s.inertia);
        self.f64(s.gravity);
        for p in s.base_joints.iter().chain(s.platform_joints.iter()) {
            self.f64s(p.as_slice());
        }
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
    pub fn bool(&mut self) -> Result<bool, SnapshotError> {
        match self.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            b => Err(SnapshotError(format!("invalid boolean byte {b}"))),
        }
    }
    /// What [`ByteWriter::stand`] wrote (finite values only).
    pub fn stand(&mut self) -> Result<Stand, SnapshotError> {
        let mass = self.finite("M")?;
        let inertia = self.finite_array::<3>("J")?;
        let gravity = self.finite("g")?;
        let mut joints = [Vector3::zeros(); 2 * LEG_COUNT];
        for j in joints.iter_mut() {
            *j = Vector3::from(self.finite_array::<3>("joint")?);
        }
        Ok(Stand {
            mass,
            inertia,
            gravity,
            base_joints: std::array::from_fn(|k| joints[k]),
            platform_joints: std::array::from_fn(|k| joints[LEG_COUNT + k]),
        })
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

//! The FMI 3.0 C types, transcribed from `fmi3PlatformTypes.h` and `fmi3FunctionTypes.h`.
//! `fmi3Boolean` and `fmi3Clock` are C `bool`, read here as a byte (any non-zero is true), so
//! that an importer's odd byte can never be an invalid Rust `bool`. Callbacks are
//! `Option<fn>`.

#![allow(non_camel_case_types, non_upper_case_globals)]

use std::ffi::{c_char, c_int, c_void};

pub type fmi3Instance = *mut c_void;
pub type fmi3InstanceEnvironment = *mut c_void;
pub type fmi3FMUState = *mut c_void;
pub type fmi3ValueReference = u32;
pub type fmi3Float32 = f32;
pub type fmi3Float64 = f64;
pub type fmi3Int8 = i8;
pub type fmi3UInt8 = u8;
pub type fmi3Int16 = i16;
pub type fmi3UInt16 = u16;
pub type fmi3Int32 = i32;
pub type fmi3UInt32 = u32;
pub type fmi3Int64 = i64;
pub type fmi3UInt64 = u64;
pub type fmi3Boolean = u8;
pub type fmi3Char = c_char;
pub type fmi3String = *const fmi3Char;
pub type fmi3Byte = u8;
pub type fmi3Binary = *const fmi3Byte;
pub type fmi3Clock = u8;

pub const fmi3True: fmi3Boolean = 1;
pub const fmi3False: fmi3Boolean = 0;

/// `fmi3Status`, a C enum (an `int`).
pub type fmi3Status = c_int;
pub const fmi3OK: fmi3Status = 0;
pub const fmi3Warning: fmi3Status = 1;
pub const fmi3Discard: fmi3Status = 2;
pub const fmi3Error: fmi3Status = 3;
pub const fmi3Fatal: fmi3Status = 4;

/// `fmi3DependencyKind`.
pub type fmi3DependencyKind = c_int;
pub const fmi3Independent: fmi3DependencyKind = 0;
pub const fmi3Constant: fmi3DependencyKind = 1;
pub const fmi3Fixed: fmi3DependencyKind = 2;
pub const fmi3Tunable: fmi3DependencyKind = 3;
pub const fmi3Discrete: fmi3DependencyKind = 4;
pub const fmi3Dependent: fmi3DependencyKind = 5;

/// `fmi3IntervalQualifier`.
pub type fmi3IntervalQualifier = c_int;

pub type fmi3LogMessageCallback = crate::fmi::log::Fmi3Logger;
pub type fmi3IntermediateUpdateCallback = crate::fmi::instance::IntermediateUpdate;
pub type fmi3ClockUpdateCallback = Option<unsafe extern "C" fn(fmi3InstanceEnvironment)>;
pub type fmi3LockPreemptionCallback = Option<unsafe extern "C" fn()>;
pub type fmi3UnlockPreemptionCallback = Option<unsafe extern "C" fn()>;

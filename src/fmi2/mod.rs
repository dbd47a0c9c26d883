//! The FMI 2.0 C boundary: the only place with `extern "C"` and raw pointers.
//!
//! | module | what it holds |
//! |---|---|
//! | [`types`] | C types from the FMI headers; callbacks as `Option<fn>` |
//! | [`boundary`] | panic boundary, instance and pointer checks (one wrapper for every export) |
//! | [`state_machine`] | the FMI calling-sequence tables: allowed states per function |
//! | [`logger`] | log categories and messages to the importer (pre-formatted, `%` escaped) |
//! | [`instance`] | an instance: state machine, argument checks, time, FMU states, around a model |
//! | [`exports`] | the exported `fmi2*` functions (thin) |
//!
//! FMI names (`fmi2OK`, `componentEnvironment`) are kept as the standard spells them.

#![allow(non_upper_case_globals, non_snake_case)]

pub mod boundary;
pub mod exports;
pub mod instance;
pub mod logger;
pub mod state_machine;
pub mod types;

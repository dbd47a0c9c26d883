//! The FMI 2.0 C boundary: C types, the FMI 2 calling-sequence table and the exported
//! `fmi2*` functions, a thin layer over [`crate::fmi`] (instance, panic boundary, logging).
//!
//! | module | what it holds |
//! |---|---|
//! | [`types`] | C types from the FMI 2 headers; callbacks as `Option<fn>` |
//! | [`state_machine`] | the FMI 2 calling-sequence tables: allowed states per function |
//! | [`exports`] | the exported `fmi2*` functions (thin) |
//!
//! FMI names (`fmi2OK`, `componentEnvironment`) are kept as the standard spells them.

#![allow(non_upper_case_globals, non_snake_case)]

pub mod exports;
pub mod state_machine;
pub mod types;

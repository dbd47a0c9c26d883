//! The FMI 3.0 C boundary: C types, the FMI 3 calling-sequence table and the exported
//! `fmi3*` functions, a thin layer over [`crate::fmi`] (the same instance, panic boundary and
//! logging as FMI 2). Arrays are whole variables: one value reference per variable, its
//! values in row-major order.
//!
//! | module | what it holds |
//! |---|---|
//! | [`types`] | C types from the FMI 3 headers |
//! | [`state_machine`] | the FMI 3 calling-sequence table: allowed states per function |
//! | [`exports`] | the exported `fmi3*` functions (thin) |
//!
//! FMI names (`fmi3OK`, `instanceEnvironment`) are kept as the standard spells them.

#![allow(non_upper_case_globals, non_snake_case)]

pub mod exports;
pub mod state_machine;
pub mod types;

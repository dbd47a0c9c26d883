//! A compiled co-simulation master for FMI 2 Co-Simulation FMUs: it loads each FMU through its
//! C API as any importer does, connects the instances as an SSP system describes, steps them at
//! a fixed communication step with the Gauss-Seidel or Jacobi scheme of `stewart_fmu.cosim`,
//! and hands only what is asked for (a study's metrics, outputs at an interval) out of the
//! loop. An importer, never linked into the FMU binary: `stewart_fmu._master` (the crate
//! `stewart-master-py`) makes it a Python extension, `stewart-master` a command.
//!
//! - `fmi2`: the C API (function pointers, an instance, its messages);
//! - `fmu`: an FMU unpacked and loaded; `description`: its model description;
//! - `ssd`: an SSP system description; `ssp`: an `.ssp` archive opened into a `System`;
//! - `system`: the components, connections and the run loop; `run`: what a run is given (the
//!   scheme, values, overrides, input tables, the `Observer`) and how it ended;
//! - `study`: a design study's run with its metrics; `record`: outputs at an interval;
//! - `cli`: the command line.

pub mod cli;
pub mod description;
pub mod fmi2;
pub mod fmu;
pub mod record;
pub mod run;
pub mod ssd;
pub mod ssp;
pub mod study;
pub mod system;
mod xml;

pub use fmu::Fmu;
pub use system::{Given, InputTable, Observer, Override, Readings, RunSpec, Scheme, System};

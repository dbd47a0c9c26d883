//! The Rust integration tests, one test binary (the package `tests/Cargo.toml`): each file of
//! `tests/` is a module of it (the helpers in `tests/common/`), so that cargo compiles and links
//! one executable instead of one per file, and its tests share the machine's cores. One file's
//! tests: `cargo test --release --test integration workspace::`; one test: its full name, e.g.
//! `cargo test --release --test integration workspace::power_loss -- --nocapture` (a name filter).

mod common;

mod conservation;
mod direct_problem_and_similarity;
mod drives;
mod fmi3_state_machine;
mod fmi_fuzz;
mod fmi_instances;
mod fmi_panic_boundary;
mod fmi_robustness;
mod fmi_state_machine;
mod fmi_value_cache;
mod hydraulics;
mod machine;
mod machine_oracle_selfcheck;
mod model_description;
mod no_allocation;
mod reliability;
mod special_form_vs_newton_euler;
mod tangents;
mod vector_extensions;
mod workspace;

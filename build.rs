//! Links the FMU binary with `-z nodelete`: importers (FMPy) `dlclose` the library after
//! `fmi2FreeInstance`, and Rust's thread-local destructors registered by a library that is
//! unloaded crash at thread exit (rust-lang/rust #59629, #91979). Keeping the library
//! resident costs nothing.
fn main() {
    let target_os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if target_os == "linux" {
        println!("cargo:rustc-link-arg-cdylib=-Wl,-z,nodelete");
    }
    println!("cargo:rerun-if-changed=build.rs");
}

//! The triple this program is built for: the platform whose binary `cargo build` writes to
//! `target/release` without `--target`.
fn main() {
    println!("cargo:rustc-env=BUILD_FMU_HOST={}", std::env::var("TARGET").expect("cargo sets TARGET"));
}

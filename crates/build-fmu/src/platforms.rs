//! The platforms an FMU can carry a binary for, and how each binary is built here.
//!
//! One FMU file carries one binary per platform, under the folder FMI names for it: FMI 2
//! `binaries/linux64`, `win64`, `darwin64`; FMI 3 `binaries/<arch>-<os>`. FMI 2 has no folder
//! for 64-bit ARM (FMPy and FMI Library load `linux64` there by pointer size), so an FMI 2 FMU
//! carries one Linux architecture, x86-64, and the aarch64 binary goes into FMI 3 FMUs only.
//!
//! How a foreign binary is built (the first that is available):
//! 1. the invoking toolchain has the target's standard library (`rustup target add TRIPLE`):
//!    `cargo rustc --target TRIPLE`;
//! 2. a Rust compiler with the standard library's source (Debian 12's `rustc-web`,
//!    `cargo-web` and `rust-web-src` from bookworm-security, installed by
//!    `tests/setup_cross.sh`; or `STEWART_BUILD_STD_CARGO` and `STEWART_BUILD_STD_RUSTC`):
//!    the standard library compiled for the target with the FMU (`-Zbuild-std`).
//!
//! The linker is the target's C compiler from Debian's cross packages (override it with
//! cargo's own `CARGO_TARGET_<TRIPLE>_LINKER`). macOS binaries link with zig (`ziglang` and
//! `cargo-zigbuild` from PyPI); nothing here can run them, so they are built only on request.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A binary format, for the checks of a file that cannot be loaded here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Elf,
    Pe,
    MachO,
}

/// A platform an FMU can carry a binary for.
#[derive(Debug)]
pub struct Platform {
    /// The FMI 3 platform tuple, also its name on `build-fmu`'s command line.
    pub name: &'static str,
    /// The FMI 2 folder, where FMI 2 has one that importers look in.
    pub fmi2_folder: Option<&'static str>,
    /// Rust's target triple.
    pub triple: &'static str,
    /// The file cargo writes (`libstewart_fmu.so`, `stewart_fmu.dll`, ...).
    pub built_file: &'static str,
    /// The extension of the packaged binary (`<ModelIdentifier><extension>`).
    pub extension: &'static str,
    pub format: Format,
    /// The C compiler that links it when it is built on another platform (Debian's package
    /// names it), or `zig` for macOS.
    pub cross_linker: &'static str,
    /// The Debian package of that linker, for the message when it is missing.
    pub linker_package: &'static str,
    /// Built when `--targets` is not given.
    pub by_default: bool,
}

impl Platform {
    /// The binary's path inside an FMU of FMI `version` (2 or 3), if that version carries it.
    pub fn archive_path(&self, version: u8, model_identifier: &str) -> Option<String> {
        let folder = if version == 2 { self.fmi2_folder? } else { self.name };
        Some(format!("binaries/{folder}/{model_identifier}{}", self.extension))
    }
}

/// Every platform `build-fmu` knows, the default ones first.
pub const PLATFORMS: [Platform; 5] = [
    Platform {
        name: "x86_64-linux",
        fmi2_folder: Some("linux64"),
        triple: "x86_64-unknown-linux-gnu",
        built_file: "libstewart_fmu.so",
        extension: ".so",
        format: Format::Elf,
        cross_linker: "x86_64-linux-gnu-gcc",
        linker_package: "gcc-x86-64-linux-gnu",
        by_default: true,
    },
    Platform {
        name: "aarch64-linux",
        fmi2_folder: None,
        triple: "aarch64-unknown-linux-gnu",
        built_file: "libstewart_fmu.so",
        extension: ".so",
        format: Format::Elf,
        cross_linker: "aarch64-linux-gnu-gcc",
        linker_package: "gcc-aarch64-linux-gnu libc6-dev-arm64-cross",
        by_default: true,
    },
    Platform {
        name: "x86_64-windows",
        fmi2_folder: Some("win64"),
        triple: "x86_64-pc-windows-gnu",
        built_file: "stewart_fmu.dll",
        extension: ".dll",
        format: Format::Pe,
        cross_linker: "x86_64-w64-mingw32-gcc",
        linker_package: "gcc-mingw-w64-x86-64",
        by_default: true,
    },
    Platform {
        name: "x86_64-darwin",
        fmi2_folder: Some("darwin64"),
        triple: "x86_64-apple-darwin",
        built_file: "libstewart_fmu.dylib",
        extension: ".dylib",
        format: Format::MachO,
        cross_linker: "zig",
        linker_package: "(PyPI) ziglang cargo-zigbuild",
        by_default: false,
    },
    Platform {
        name: "aarch64-darwin",
        fmi2_folder: None,
        triple: "aarch64-apple-darwin",
        built_file: "libstewart_fmu.dylib",
        extension: ".dylib",
        format: Format::MachO,
        cross_linker: "zig",
        linker_package: "(PyPI) ziglang cargo-zigbuild",
        by_default: false,
    },
];

/// The lowest macOS version the macOS binaries ask for (Rust's own minimum for its targets).
pub const MACOS_DEPLOYMENT_TARGET: &str = "11.0";

/// The platforms named by `--targets a,b,c` (`all` for every one), or the default ones.
pub fn selected(list: Option<&str>) -> Result<Vec<&'static Platform>, String> {
    let Some(list) = list else {
        return Ok(PLATFORMS.iter().filter(|p| p.by_default).collect());
    };
    if list == "all" {
        return Ok(PLATFORMS.iter().collect());
    }
    let mut chosen = vec![];
    for name in list.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        let platform = PLATFORMS.iter().find(|p| p.name == name || p.triple == name).ok_or_else(|| {
            format!(
                "unknown target {name}: the targets are {} (or all)",
                PLATFORMS.iter().map(|p| p.name).collect::<Vec<_>>().join(", ")
            )
        })?;
        if !chosen.iter().any(|c: &&Platform| c.name == platform.name) {
            chosen.push(platform);
        }
    }
    if chosen.is_empty() {
        return Err("--targets names no target".into());
    }
    // The order of PLATFORMS, whatever the order asked.
    chosen.sort_by_key(|p| PLATFORMS.iter().position(|q| q.name == p.name));
    Ok(chosen)
}

/// The triple of the Rust toolchain that runs this program (the platform of `target/release`).
pub fn host_triple() -> &'static str {
    env!("BUILD_FMU_HOST")
}

/// How one binary gets built.
pub struct Build {
    pub command: Command,
    /// Where the binary is when the command succeeded.
    pub output: PathBuf,
    /// What the progress line says about the toolchain.
    pub how: String,
}

/// The command that builds the FMU binary for `platform` (release profile), or why it cannot
/// be built on this machine (with what to install).
pub fn build_command(platform: &Platform, root: &Path, target_dir: &Path) -> Result<Build, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    if platform.triple == host_triple() {
        let mut command = Command::new(cargo);
        command
            .args(["build", "--release", "-p", "stewart_fmu", "--lib", "--target-dir"])
            .arg(target_dir)
            .current_dir(root);
        return Ok(Build {
            command,
            output: target_dir.join("release").join(platform.built_file),
            how: "this machine's toolchain".into(),
        });
    }
    // A target folder per platform, so that the builds run side by side (cargo lets one build
    // at a time use a target folder).
    let cross_dir = target_dir.join("cross").join(platform.triple);
    let output = cross_dir.join(platform.triple).join("release").join(platform.built_file);
    // `cargo rustc` so that `-D warnings` reaches the FMU crate alone (not the standard
    // library built with it): every target compiles without a warning.
    let base_args = |command: &mut Command| {
        command
            .args(["rustc", "--release", "-p", "stewart_fmu", "--lib", "--target", platform.triple])
            .arg("--target-dir")
            .arg(&cross_dir)
            .current_dir(root);
    };
    if platform.format == Format::MachO {
        return zig_build(platform, root, &cross_dir, output);
    }
    let linker = linker_for(platform)?;
    let linker_variable = format!("CARGO_TARGET_{}_LINKER", platform.triple.to_uppercase().replace('-', "_"));
    if has_target_std(&cargo, platform.triple) {
        let mut command = Command::new(&cargo);
        base_args(&mut command);
        command.args(["--", "-D", "warnings"]).env(&linker_variable, &linker);
        return Ok(Build { command, output, how: format!("the installed {} standard library", platform.triple) });
    }
    let (std_cargo, std_rustc) = build_std_toolchain().ok_or_else(|| {
        format!(
            "no Rust standard library for {triple} here: run `bash tests/setup_cross.sh` (Debian 12: the compiler \
             with the standard library's source and the linkers), or `rustup target add {triple}` where rustup can \
             fetch it, or build this machine's platform only (`--targets {host}`)",
            triple = platform.triple,
            host = PLATFORMS.iter().find(|p| p.triple == host_triple()).map_or(host_triple(), |p| p.name),
        )
    })?;
    let mut command = Command::new(&std_cargo);
    base_args(&mut command);
    command
        .args(["-Zbuild-std=std,panic_unwind", "--", "-D", "warnings"])
        .env("RUSTC", &std_rustc)
        // Cargo's -Z flags on a stable toolchain: the standard library's own build needs them.
        .env("RUSTC_BOOTSTRAP", "1")
        .env_remove("RUSTUP_TOOLCHAIN")
        .env(&linker_variable, &linker);
    Ok(Build {
        command,
        output,
        how: format!("{} with the standard library compiled from its source", rustc_version(&std_rustc)),
    })
}

/// The linker for `platform`: cargo's variable if the user set it, else the Debian cross
/// compiler, which must be installed.
fn linker_for(platform: &Platform) -> Result<String, String> {
    let variable = format!("CARGO_TARGET_{}_LINKER", platform.triple.to_uppercase().replace('-', "_"));
    if let Ok(linker) = std::env::var(&variable) {
        return Ok(linker);
    }
    if on_path(platform.cross_linker) {
        return Ok(platform.cross_linker.into());
    }
    Err(format!(
        "the linker {} for {} is not installed: run `bash tests/setup_cross.sh` (Debian package {}), or set {variable}",
        platform.cross_linker, platform.name, platform.linker_package
    ))
}

/// Whether the toolchain of `cargo` has `triple`'s standard library (rustup's target).
fn has_target_std(cargo: &str, triple: &str) -> bool {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| sibling(cargo, "rustc"));
    let Ok(out) = Command::new(rustc).args(["--print", "target-libdir", "--target", triple]).output() else {
        return false;
    };
    let dir = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    out.status.success()
        && std::fs::read_dir(dir)
            .map(|entries| entries.flatten().any(|e| e.file_name().to_string_lossy().starts_with("libstd-")))
            .unwrap_or(false)
}

/// `rustc` beside `cargo` when cargo is given by path, else `rustc` on the path.
fn sibling(cargo: &str, name: &str) -> String {
    let path = Path::new(cargo);
    match path.parent() {
        Some(dir) if dir.join(name).exists() => dir.join(name).to_string_lossy().into_owned(),
        _ => name.into(),
    }
}

/// A cargo and rustc pair whose sysroot holds the standard library's source:
/// `STEWART_BUILD_STD_CARGO`/`STEWART_BUILD_STD_RUSTC`, else Debian's `/usr/bin/cargo` and
/// `/usr/bin/rustc` (`cargo-web`, `rustc-web`, `rust-web-src`).
fn build_std_toolchain() -> Option<(String, String)> {
    let cargo = std::env::var("STEWART_BUILD_STD_CARGO").unwrap_or_else(|_| "/usr/bin/cargo".into());
    let rustc = std::env::var("STEWART_BUILD_STD_RUSTC").unwrap_or_else(|_| "/usr/bin/rustc".into());
    if !Path::new(&cargo).exists() || !Path::new(&rustc).exists() {
        return None;
    }
    let out = Command::new(&rustc).args(["--print", "sysroot"]).output().ok()?;
    let sysroot = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    sysroot.join("lib/rustlib/src/rust/library/std").exists().then_some((cargo, rustc))
}

/// `rustc 1.96.0` (the compiler's own first words), for the progress line.
pub fn rustc_version(rustc: &str) -> String {
    Command::new(rustc)
        .arg("--version")
        .output()
        .ok()
        .map(|o| String::from_utf8_lossy(&o.stdout).split_whitespace().take(2).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| rustc.to_string())
}

fn on_path(program: &str) -> bool {
    std::env::var_os("PATH")
        .map(|paths| std::env::split_paths(&paths).any(|dir| dir.join(program).is_file()))
        .unwrap_or(false)
}

/// macOS through `cargo zigbuild` (zig as the linker, with its own macOS stubs: no SDK), with
/// the standard library compiled from source as above unless rustup has the target.
fn zig_build(platform: &Platform, root: &Path, cross_dir: &Path, output: PathBuf) -> Result<Build, String> {
    if !on_path("cargo-zigbuild") {
        return Err(format!(
            "{} needs cargo-zigbuild and zig: `pip install ziglang cargo-zigbuild` (PyPI) and put their scripts on PATH",
            platform.name
        ));
    }
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut command = Command::new("cargo-zigbuild");
    command
        .args(["rustc", "--release", "-p", "stewart_fmu", "--lib", "--target", platform.triple])
        .arg("--target-dir")
        .arg(cross_dir)
        .current_dir(root)
        .env("MACOSX_DEPLOYMENT_TARGET", MACOS_DEPLOYMENT_TARGET)
        // rustc strips Apple binaries with rustup's `rust-objcopy`, which other toolchains
        // lack; the release profile compiles no debug information anyway.
        .env("CARGO_PROFILE_RELEASE_STRIP", "none")
        // zig's Mach-O linker takes neither rustc's list of exported symbols (so every symbol
        // but the FMI functions is hidden when compiled, the standard library's too) nor its
        // install name (so it is given: relative, not the build path). `-Z` needs
        // RUSTC_BOOTSTRAP on a stable compiler.
        .env("RUSTFLAGS", "-Zdefault-visibility=hidden -Clink-arg=-Wl,-install_name,@rpath/libstewart_fmu.dylib")
        .env("RUSTC_BOOTSTRAP", "1");
    let how = if has_target_std(&cargo, platform.triple) {
        format!("cargo zigbuild with the installed {} standard library", platform.triple)
    } else {
        let (std_cargo, std_rustc) = build_std_toolchain().ok_or_else(|| {
            format!("no Rust standard library for {}: run `bash tests/setup_cross.sh` first", platform.triple)
        })?;
        command
            .arg("-Zbuild-std=std,panic_unwind")
            .env("CARGO", &std_cargo)
            .env("RUSTC", &std_rustc)
            .env_remove("RUSTUP_TOOLCHAIN");
        format!("cargo zigbuild, {} with the standard library compiled from its source", rustc_version(&std_rustc))
    };
    command.args(["--", "-D", "warnings"]);
    Ok(Build { command, output, how })
}

//! Checks of a binary from its file, whatever its platform (ELF, PE, Mach-O), for binaries
//! this machine cannot load: it exports the FMI 2.0 and FMI 3.0 functions and nothing else;
//! it takes no elementary function from a C library, neither imported nor linked in from a
//! static one such as MinGW's libmingwex (the model's maths is compiled into it, so every
//! platform computes the same bits); it needs only the system's own libraries, and on Linux no
//! glibc newer than [`GLIBC_CEILING`]. Returns a one-line summary for the build log.

use std::path::Path;

use object::read::elf::{Dyn, ElfFile64};
use object::read::macho::{LoadCommandVariant, MachOFile64};
use object::{Endianness, FileKind, Object};

use crate::platforms::{Format, Platform};

/// The C library's functions whose results differ between platforms (they are not required
/// to be correctly rounded): the FMU must take none of them from a C library. Their `float`
/// forms (`sinf`), glibc's `__sin_finite` aliases and Apple's `__sincos_stret` count too
/// ([`c_maths_name`]).
#[rustfmt::skip]
pub const PLATFORM_MATHS: [&str; 35] = [
    "sin", "cos", "tan", "sincos", "sincos_stret", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "asinh",
    "acosh", "atanh", "exp", "exp2", "exp10", "expm1", "log", "log2", "log10", "log1p", "pow", "cbrt", "hypot", "erf",
    "erfc", "lgamma", "tgamma", "fma", "j0", "j1", "y0", "y1",
];

/// The newest glibc the Linux binaries may ask for: Debian 12, Ubuntu 22.04 and RHEL 9 have
/// it. A toolchain that raises it fails the build instead of silently dropping those systems.
pub const GLIBC_CEILING: (u32, u32) = (2, 34);

/// `name` as one of [`PLATFORM_MATHS`] if it is a C library's elementary function: leading
/// underscores, glibc's `_finite` and the `float` suffix `f` removed.
pub fn c_maths_name(name: &str) -> Option<&'static str> {
    let bare = name.trim_start_matches('_');
    let bare = bare.strip_suffix("_finite").unwrap_or(bare);
    PLATFORM_MATHS.iter().copied().find(|m| *m == bare || bare.strip_suffix('f').is_some_and(|b| b == *m))
}

/// The DLLs every Windows 10 or newer has (Rust's standard library needs Windows 10:
/// `ProcessPrng` in `bcryptprimitives.dll`); anything else (MinGW's `libgcc_s_seh-1.dll`,
/// `libwinpthread-1.dll`) would have to be shipped beside the FMU.
const WINDOWS_SYSTEM_DLLS: [&str; 9] = [
    "kernel32.dll",
    "ntdll.dll",
    "msvcrt.dll",
    "bcryptprimitives.dll",
    "advapi32.dll",
    "userenv.dll",
    "ws2_32.dll",
    "api-ms-win-core-synch-l1-2-0.dll",
    "api-ms-win-core-winrt-error-l1-1-0.dll",
];

/// What zig's Mach-O linker exports from every dylib besides the library's own functions
/// (underscore removed): two linker-defined symbols and its compiler runtime's OS-version
/// checks. macOS binds symbols per library (two-level namespaces), so they cannot stand in
/// for a host's.
const ZIG_MACHO_EXPORTS: [&str; 4] =
    ["_mh_dylib_header", "__dso_handle", "__isOSVersionAtLeast", "__isPlatformVersionAtLeast"];

/// The GNU/Linux system libraries the binary may need (glibc and GCC's unwinder).
const LINUX_SYSTEM_LIBRARIES: [&str; 7] = [
    "libc.so.6",
    "libm.so.6",
    "libgcc_s.so.1",
    "libdl.so.2",
    "libpthread.so.0",
    "ld-linux-x86-64.so.2",
    "ld-linux-aarch64.so.1",
];

/// Checks the binary at `path` built for `platform`; the summary names its size, exports and
/// what it needs from the system.
pub fn check(path: &Path, platform: &Platform) -> Result<String, String> {
    let data = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let file = object::File::parse(&*data).map_err(|e| format!("{}: not an object file: {e}", path.display()))?;
    let expected = match platform.format {
        Format::Elf => object::BinaryFormat::Elf,
        Format::Pe => object::BinaryFormat::Pe,
        Format::MachO => object::BinaryFormat::MachO,
    };
    if file.format() != expected {
        return Err(format!("{} is {:?}, expected {expected:?} for {}", path.display(), file.format(), platform.name));
    }
    let arch = file.architecture();
    let expected_arch =
        if platform.name.starts_with("aarch64") { object::Architecture::Aarch64 } else { object::Architecture::X86_64 };
    if arch != expected_arch {
        return Err(format!("{} is built for {arch:?}, not {expected_arch:?}", path.display()));
    }

    let exports = exported_names(&file)?;
    let fmi_functions = || stewart_fmu::fmi2::FUNCTIONS.iter().chain(stewart_fmu::fmi3::FUNCTIONS.iter());
    for name in fmi_functions() {
        if !exports.iter().any(|e| e == name) {
            return Err(format!("{} does not export {name}", path.display()));
        }
    }
    // Exactly the standard's names: a stray `fmi2Probe` or a misspelt function is foreign.
    let foreign: Vec<&str> = exports
        .iter()
        .filter(|e| !fmi_functions().any(|f| f == e))
        .filter(|e| !(platform.format == Format::MachO && ZIG_MACHO_EXPORTS.contains(&e.as_str())))
        .map(|e| e.as_str())
        .collect();
    if !foreign.is_empty() {
        return Err(format!(
            "{} exports {} function{} that {} not FMI's: {}",
            path.display(),
            foreign.len(),
            if foreign.len() == 1 { "" } else { "s" },
            if foreign.len() == 1 { "is" } else { "are" },
            foreign.iter().take(8).copied().collect::<Vec<_>>().join(", ")
        ));
    }

    let imports = file
        .imports()
        .and_then(|table| table.collect::<Result<Vec<_>, _>>())
        .map_err(|e| format!("{}: import table: {e}", path.display()))?;
    let mut maths: Vec<&str> = imports
        .iter()
        .filter_map(|i| i.name().name().and_then(|n| c_maths_name(&String::from_utf8_lossy(n))))
        .collect();
    maths.sort();
    maths.dedup();
    if !maths.is_empty() {
        return Err(format!(
            "{} imports {} from the system's C library: the model's maths must be the crate's own \
             (stewart_fmu::maths), or the platforms give different numbers",
            path.display(),
            maths.join(", ")
        ));
    }
    // A C library's maths linked in (MinGW's libmingwex defines `expm1`, `log2`, `cbrt`, which
    // msvcrt.dll lacks): its functions keep their C names in the symbol table, which the
    // release profile keeps (`strip = "debuginfo"`), where the crate's are Rust paths.
    use object::{ObjectSymbol, ObjectSymbolTable};
    let table = file.symbol_table().ok_or_else(|| {
        format!(
            "{} has no symbol table: nothing shows what is linked into it (build without strip = \"symbols\")",
            path.display()
        )
    })?;
    let mut linked: Vec<&str> =
        table.symbols().filter(|s| s.is_definition()).filter_map(|s| s.name().ok().and_then(c_maths_name)).collect();
    linked.sort();
    linked.dedup();
    if !linked.is_empty() {
        return Err(format!(
            "{} has a C library's {} linked in: the model's maths must be the crate's own (stewart_fmu::maths)",
            path.display(),
            linked.join(", ")
        ));
    }

    let needs = match platform.format {
        Format::Elf => elf_needs(&data)?,
        Format::Pe => pe_needs(&imports)?,
        Format::MachO => macho_needs(&data, &imports)?,
    };
    let fmi = exports.iter().filter(|e| e.starts_with("fmi2") || e.starts_with("fmi3")).count();
    let others = match exports.len() - fmi {
        0 => "and no other".to_string(),
        n => format!("and zig's {n} linker and runtime symbols"),
    };
    Ok(format!("{} KB, {fmi} FMI exports {others}, no platform maths; needs {needs}", data.len().div_ceil(1024)))
}

/// The exported function names (Mach-O's leading underscore removed).
fn exported_names(file: &object::File) -> Result<Vec<String>, String> {
    let exports = file
        .exports()
        .and_then(|table| table.collect::<Result<Vec<_>, _>>())
        .map_err(|e| format!("export table: {e}"))?;
    let macho = file.format() == object::BinaryFormat::MachO;
    Ok(exports
        .iter()
        .map(|e| {
            // An export without a name (by ordinal only) counts as a foreign one.
            let name = e.name().name().map_or_else(|| "(ordinal)".into(), |n| String::from_utf8_lossy(n).into_owned());
            if macho { name.strip_prefix('_').unwrap_or(&name).to_string() } else { name }
        })
        .collect())
}

/// ELF: the needed libraries (system ones only) and the newest glibc symbol version asked.
fn elf_needs(data: &[u8]) -> Result<String, String> {
    if FileKind::parse(data).map_err(|e| e.to_string())? != FileKind::Elf64 {
        return Err("not a 64-bit ELF file".into());
    }
    let elf = ElfFile64::<Endianness>::parse(data).map_err(|e| e.to_string())?;
    let endian = elf.endian();
    let sections = elf.elf_section_table();
    let mut needed = vec![];
    if let Some((dynamic, link)) = sections.dynamic(endian, data).map_err(|e| e.to_string())? {
        let strings = sections.strings(endian, data, link).map_err(|e| e.to_string())?;
        for entry in dynamic {
            if entry.tag(endian) == object::elf::DT_NEEDED {
                let name = entry.string(endian, strings).map_err(|e| e.to_string())?;
                needed.push(String::from_utf8_lossy(name).into_owned());
            }
        }
    }
    if let Some(other) = needed.iter().find(|n| !LINUX_SYSTEM_LIBRARIES.contains(&n.as_str())) {
        return Err(format!("needs {other}, which is not a system library"));
    }
    if needed.iter().any(|n| n == "libm.so.6") {
        return Err("needs libm.so.6: the model's maths must be the crate's own (stewart_fmu::maths)".into());
    }
    // The newest GLIBC_2.N among the version names the dynamic string table holds.
    let mut newest = (2u32, 0u32);
    if let Some(dynstr) = elf.section_by_name(".dynstr") {
        use object::ObjectSection;
        let bytes = dynstr.data().map_err(|e| e.to_string())?;
        for word in bytes.split(|b| *b == 0) {
            let word = String::from_utf8_lossy(word);
            if let Some(version) = word.strip_prefix("GLIBC_") {
                let mut parts = version.split('.').map(|p| p.parse::<u32>().unwrap_or(0));
                let v = (parts.next().unwrap_or(0), parts.next().unwrap_or(0));
                newest = newest.max(v);
            }
        }
    }
    if newest > GLIBC_CEILING {
        return Err(format!(
            "asks for glibc {}.{}, newer than the {}.{} the FMUs promise (docs/platforms.md): a new toolchain or \
             dependency raised it",
            newest.0, newest.1, GLIBC_CEILING.0, GLIBC_CEILING.1
        ));
    }
    let needed = if needed.is_empty() { "no library".to_string() } else { needed.join(", ") };
    Ok(format!("{needed} (glibc {}.{} or newer)", newest.0, newest.1))
}

/// PE: the imported DLLs, which must all be Windows' own.
fn pe_needs(imports: &[object::Import]) -> Result<String, String> {
    let mut dlls: Vec<String> = imports.iter().map(|i| String::from_utf8_lossy(i.library()).into_owned()).collect();
    dlls.sort_by_key(|d| d.to_ascii_lowercase());
    dlls.dedup_by_key(|d| d.to_ascii_lowercase());
    if let Some(other) = dlls.iter().find(|d| !WINDOWS_SYSTEM_DLLS.contains(&d.to_ascii_lowercase().as_str())) {
        return Err(format!(
            "imports {other}, which is not a Windows system DLL (it would have to ship beside the FMU)"
        ));
    }
    Ok(dlls.join(", "))
}

/// Mach-O: libraries from the system only, a relative install name (`@rpath/...`), and the
/// deployment target it asks for.
fn macho_needs(data: &[u8], imports: &[object::Import]) -> Result<String, String> {
    let macho = MachOFile64::<Endianness>::parse(data).map_err(|e| e.to_string())?;
    let endian = macho.endian();
    let mut install_name = None;
    let mut minimum = None;
    let mut commands = macho.macho_load_commands().map_err(|e| e.to_string())?;
    while let Some(command) = commands.next().map_err(|e| e.to_string())? {
        match command.variant().map_err(|e| e.to_string())? {
            LoadCommandVariant::IdDylib(dylib) => {
                let name = command.string(endian, dylib.dylib.name).map_err(|e| e.to_string())?;
                install_name = Some(String::from_utf8_lossy(name).into_owned());
            }
            LoadCommandVariant::BuildVersion(version, _) => {
                let v = version.minos.get(endian);
                minimum = Some(format!("{}.{}", v.0 >> 16, (v.0 >> 8) & 0xff));
            }
            _ => {}
        }
    }
    let install_name = install_name.ok_or("no install name (LC_ID_DYLIB)")?;
    if install_name.starts_with('/') {
        return Err(format!("install name {install_name} is absolute (it must be @rpath/... or the file's name)"));
    }
    let minimum = minimum.ok_or("no deployment target (LC_BUILD_VERSION)")?;
    let mut libraries: Vec<String> =
        imports.iter().map(|i| String::from_utf8_lossy(i.library()).into_owned()).collect();
    libraries.sort();
    libraries.dedup();
    if let Some(other) = libraries.iter().find(|l| !l.starts_with("/usr/lib/") && !l.starts_with("/System/")) {
        return Err(format!("needs {other}, which is not a macOS system library"));
    }
    Ok(format!("{} (install name {install_name}, macOS {minimum} or newer)", libraries.join(", ")))
}

#[cfg(test)]
mod tests {
    //! The checks on small libraries built here with the C compilers the cross set-up
    //! installs: one that passes, and one for each way of failing.
    use std::path::{Path, PathBuf};
    use std::process::Command;

    use super::{c_maths_name, check};
    use crate::platforms::{PLATFORMS, Platform, host_triple};

    fn platform(name: &str) -> &'static Platform {
        PLATFORMS.iter().find(|p| p.name == name).expect("known platform")
    }

    /// This machine's platform, which `cc` builds for.
    fn native() -> &'static str {
        PLATFORMS.iter().find(|p| p.triple == host_triple()).expect("a known host").name
    }

    /// A shared library exporting every FMI function (each returning 0 but `fmi2DoStep`, whose
    /// body is `step`), after the C declarations `head`.
    fn library(compiler: &str, file: &str, head: &str, step: &str, libraries: &[&str]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("build-fmu-file-check-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temporary folder");
        let mut source = String::from(
            "#ifdef _WIN32\n#define EXPORT __declspec(dllexport)\n#else\n#define EXPORT \
             __attribute__((visibility(\"default\")))\n#endif\n",
        );
        source.push_str(head);
        for name in stewart_fmu::fmi2::FUNCTIONS.iter().chain(stewart_fmu::fmi3::FUNCTIONS.iter()) {
            let body = if *name == "fmi2DoStep" { step } else { "return 0;" };
            source.push_str(&format!("EXPORT int {name}(void) {{ {body} }}\n"));
        }
        let c = dir.join(format!("{file}.c"));
        std::fs::write(&c, source).expect("write the C file");
        let out = dir.join(file);
        let status = Command::new(compiler)
            .args(["-shared", "-fPIC", "-O1", "-fvisibility=hidden", "-o"])
            .arg(&out)
            .arg(&c)
            .args(libraries)
            .status()
            .unwrap_or_else(|e| panic!("{compiler} is needed (bash tests/setup_cross.sh installs it): {e}"));
        assert!(status.success(), "{compiler} failed");
        out
    }

    fn checked(path: &Path, on: &str) -> Result<String, String> {
        let result = check(path, platform(on));
        println!("{on} {}: {result:?}", path.file_name().and_then(|n| n.to_str()).unwrap_or(""));
        result
    }

    #[test]
    fn a_library_with_the_fmi_functions_alone_passes_on_linux_and_windows() {
        let so = library("cc", "plain.so", "", "return 0;", &[]);
        let summary = checked(&so, native()).expect("a plain library passes");
        assert!(summary.contains("119 FMI exports and no other"), "{summary}");
        let dll = library("x86_64-w64-mingw32-gcc", "plain.dll", "", "return 0;", &[]);
        let summary = checked(&dll, "x86_64-windows").expect("a plain DLL passes");
        assert!(summary.contains("KERNEL32.dll"), "{summary}");
        // The wrong platform is refused: an ELF file is no Windows binary, nor of another
        // architecture.
        assert!(checked(&so, "x86_64-windows").is_err());
        let other = if native() == "aarch64-linux" { "x86_64-linux" } else { "aarch64-linux" };
        assert!(checked(&so, other).is_err());
    }

    #[test]
    fn the_c_librarys_maths_is_refused_imported_or_linked_in() {
        let call = "volatile double x = 0.3; return (int)(sin(x) + pow(x, 0.3));";
        let so = library("cc", "maths.so", "#include <math.h>\n", call, &["-lm"]);
        let error = checked(&so, native()).expect_err("sin and pow from libm");
        assert!(error.contains("imports pow, sin") || error.contains("libm.so.6"), "{error}");
        // Rust's standard library imports them from msvcrt.dll (MinGW's gcc would link its own).
        let imported = "__declspec(dllimport) double sin(double);\n__declspec(dllimport) double pow(double, double);\n";
        let dll = library("x86_64-w64-mingw32-gcc", "maths.dll", imported, call, &["-lmsvcrt"]);
        let error = checked(&dll, "x86_64-windows").expect_err("sin and pow from msvcrt");
        assert!(error.contains("imports pow, sin"), "{error}");
        // What msvcrt.dll lacks, MinGW links in from libmingwex: no import, but the C name is
        // in the symbol table.
        let call = "volatile double x = 0.3; return (int)(expm1(x) + log2f((float)x));";
        let dll = library("x86_64-w64-mingw32-gcc", "static.dll", "#include <math.h>\n", call, &[]);
        let error = checked(&dll, "x86_64-windows").expect_err("expm1 and log2f from libmingwex");
        assert!(error.contains("expm1") && error.contains("log2"), "{error}");
    }

    #[test]
    fn a_function_that_is_not_fmis_or_a_foreign_dll_is_refused() {
        let head = "EXPORT int helper(void) { return 1; }\nEXPORT int fmi2Probe(void) { return 2; }\n";
        let so = library("cc", "extra.so", head, "return 0;", &[]);
        let error = checked(&so, native()).expect_err("two extra exports");
        assert!(error.contains("helper") && error.contains("fmi2Probe"), "{error}");
        // A DLL linked to MinGW's shared runtime needs a DLL that Windows does not have.
        let dll = library(
            "x86_64-w64-mingw32-gcc",
            "runtime.dll",
            "#include <pthread.h>\n",
            "return (int)pthread_self();",
            &["-lpthread"],
        );
        let error = checked(&dll, "x86_64-windows").expect_err("libwinpthread-1.dll");
        assert!(error.contains("libwinpthread-1.dll"), "{error}");
    }

    #[test]
    fn c_names_of_the_elementary_functions_in_every_spelling() {
        for (name, found) in [
            ("sin", Some("sin")),
            ("_sin", Some("sin")),
            ("sinf", Some("sin")),
            ("__exp_finite", Some("exp")),
            ("___sincos_stret", Some("sincos_stret")),
            ("log2f", Some("log2")),
            ("erf", Some("erf")),
            ("erff", Some("erf")),
            ("ceil", None),
            ("sqrt", None),
            ("fmi2DoStep", None),
            ("modf", None),
        ] {
            assert_eq!(c_maths_name(name), found, "{name}");
        }
    }
}

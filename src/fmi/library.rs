//! Which model an importer may instantiate from this binary. One binary serves every model,
//! packaged once per model under the model's identifier (`StewartPlatform.so`,
//! `StewartController.so`); a token is accepted only if it is one of this binary's for the FMI
//! version asked, and, when the binary was loaded under a model's identifier, that model's.

use super::FmiVersion;
use super::description::{instantiation_token, model_of_token};
use crate::models::ModelKind;

/// The file stem of the shared library this code was loaded from (`StewartPlatform` for
/// `.../binaries/linux64/StewartPlatform.so` or `...\binaries\win64\StewartPlatform.dll`),
/// if the system can tell.
fn loaded_as() -> Option<String> {
    let path = own_file()?;
    Some(file_stem(&path).to_string())
}

/// The stem of a library's path: the last component after `/` or `\`, without `.so`, `.dll`
/// or `.dylib` (in any case: Windows file names are case-insensitive).
fn file_stem(path: &str) -> &str {
    let file = path.rsplit(['/', '\\']).next().unwrap_or(path);
    let lower = file.to_ascii_lowercase();
    match [".so", ".dll", ".dylib"].iter().find(|suffix| lower.ends_with(*suffix)) {
        Some(suffix) => &file[..file.len() - suffix.len()],
        None => file,
    }
}

/// This library's own path, from the dynamic linker (`dladdr` of one of its functions).
#[cfg(unix)]
fn own_file() -> Option<String> {
    use std::ffi::{CStr, c_void};
    let mut info = libc::Dl_info {
        dli_fname: std::ptr::null(),
        dli_fbase: std::ptr::null_mut(),
        dli_sname: std::ptr::null(),
        dli_saddr: std::ptr::null_mut(),
    };
    let address = own_file as *const c_void;
    // SAFETY: dladdr only reads the address and fills the struct we own.
    if unsafe { libc::dladdr(address, &mut info) } == 0 || info.dli_fname.is_null() {
        return None;
    }
    // SAFETY: dladdr returns a NUL-terminated path owned by the dynamic linker.
    Some(unsafe { CStr::from_ptr(info.dli_fname) }.to_string_lossy().into_owned())
}

/// This library's own path, from the module that holds one of its functions
/// (`GetModuleHandleExW` by address, without taking a reference, then `GetModuleFileNameW`;
/// UTF-16, so folders with any characters work).
#[cfg(windows)]
fn own_file() -> Option<String> {
    use std::ffi::c_void;
    const FROM_ADDRESS: u32 = 0x4; // GET_MODULE_HANDLE_EX_FLAG_FROM_ADDRESS
    const UNCHANGED_REFCOUNT: u32 = 0x2; // GET_MODULE_HANDLE_EX_FLAG_UNCHANGED_REFCOUNT
    #[link(name = "kernel32")]
    unsafe extern "system" {
        fn GetModuleHandleExW(flags: u32, address: *const u16, module: *mut *mut c_void) -> i32;
        fn GetModuleFileNameW(module: *mut c_void, name: *mut u16, size: u32) -> u32;
    }
    let mut module = std::ptr::null_mut();
    let address = own_file as *const u16;
    // SAFETY: with FROM_ADDRESS the second argument is an address inside the module, only
    // read; the handle is written to our local.
    if unsafe { GetModuleHandleExW(FROM_ADDRESS | UNCHANGED_REFCOUNT, address, &mut module) } == 0 {
        return None;
    }
    // MAX_PATH first, doubled while the name fills the buffer (up to the longest path Windows
    // has, 32,767 with the `\\?\` prefix): on the heap, the host's thread may have a small stack.
    let mut name = vec![0u16; 260];
    while name.len() <= 32768 {
        // SAFETY: the buffer is ours and its length is passed.
        let length = unsafe { GetModuleFileNameW(module, name.as_mut_ptr(), name.len() as u32) } as usize;
        if length == 0 {
            return None;
        }
        if length < name.len() {
            return Some(String::from_utf16_lossy(&name[..length]));
        }
        name.resize(name.len() * 2, 0);
    }
    None
}

#[cfg(not(any(unix, windows)))]
fn own_file() -> Option<String> {
    None
}

/// The model a token selects, or why it is refused (the message lists what this binary
/// accepts).
pub fn model_for_token(token: &str, version: FmiVersion) -> Result<ModelKind, String> {
    // Case-insensitive: Windows finds `stewartplatform.dll` for `StewartPlatform.dll`.
    let own = loaded_as().and_then(|stem| {
        ModelKind::ALL.iter().copied().find(|k| k.info().model_identifier.eq_ignore_ascii_case(&stem))
    });
    match (model_of_token(token, version), own) {
        (Some(kind), Some(own)) if kind != own => Err(format!(
            "{token} is the token of {}, but this binary was loaded as {} (expected {}); the model description and \
             the binary come from different FMUs",
            kind.info().model_identifier,
            own.info().model_identifier,
            instantiation_token(own, version)
        )),
        (Some(kind), _) => Ok(kind),
        (None, own) => {
            let accepted: Vec<String> = match own {
                Some(k) => vec![format!("{} {}", k.info().model_identifier, instantiation_token(k, version))],
                None => ModelKind::ALL
                    .iter()
                    .map(|k| format!("{} {}", k.info().model_identifier, instantiation_token(*k, version)))
                    .collect(),
            };
            Err(format!(
                "{token} does not belong to this binary (it accepts {}); the model description and the binary come \
                 from different builds",
                accepted.join(", ")
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::file_stem;

    #[test]
    fn the_stem_of_a_library_on_every_platform() {
        assert_eq!(file_stem("/tmp/x/binaries/linux64/StewartPlatform.so"), "StewartPlatform");
        assert_eq!(file_stem(r"C:\Program Files\Stütz FMU\binaries\win64\StewartController.dll"), "StewartController");
        assert_eq!(file_stem("Z:/tmp/binaries/x86_64-windows/StewartPlatform.dll"), "StewartPlatform");
        assert_eq!(file_stem("/Users/a b/binaries/aarch64-darwin/StewartPlatform.dylib"), "StewartPlatform");
        assert_eq!(file_stem("libstewart_fmu.so"), "libstewart_fmu");
        assert_eq!(file_stem(r"C:\FMUs\StewartPlatform.DLL"), "StewartPlatform");
    }
}

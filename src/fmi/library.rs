//! Which model an importer may instantiate from this binary. One binary serves every model,
//! packaged once per model under the model's identifier (`StewartPlatform.so`,
//! `StewartController.so`); a token is accepted only if it is one of this binary's for the FMI
//! version asked, and, when the binary was loaded under a model's identifier, that model's.

use std::ffi::{CStr, c_void};

use super::FmiVersion;
use super::description::{instantiation_token, model_of_token};
use crate::models::ModelKind;

/// The file stem of the shared library this code was loaded from (`StewartPlatform` for
/// `.../binaries/linux64/StewartPlatform.so`), if the dynamic linker can tell.
fn loaded_as() -> Option<String> {
    let mut info = libc::Dl_info {
        dli_fname: std::ptr::null(),
        dli_fbase: std::ptr::null_mut(),
        dli_sname: std::ptr::null(),
        dli_saddr: std::ptr::null_mut(),
    };
    let address = loaded_as as *const c_void;
    // SAFETY: dladdr only reads the address and fills the struct we own.
    if unsafe { libc::dladdr(address, &mut info) } == 0 || info.dli_fname.is_null() {
        return None;
    }
    // SAFETY: dladdr returns a NUL-terminated path owned by the dynamic linker.
    let path = unsafe { CStr::from_ptr(info.dli_fname) }.to_string_lossy().into_owned();
    let file = path.rsplit('/').next()?;
    Some(file.strip_suffix(".so").unwrap_or(file).to_string())
}

/// The model a token selects, or why it is refused (the message lists what this binary
/// accepts).
pub fn model_for_token(token: &str, version: FmiVersion) -> Result<ModelKind, String> {
    let own = loaded_as().and_then(|stem| ModelKind::ALL.iter().copied().find(|k| k.info().model_identifier == stem));
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

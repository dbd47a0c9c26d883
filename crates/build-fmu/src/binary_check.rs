//! Checks of the built library as an importer sees it: `dlopen`, every FMI 2.0 symbol, and
//! `fmi2Instantiate` accepting the model description's GUID and refusing a wrong one.

use std::ffi::{CString, c_void};
use std::path::Path;

use stewart_fmu::fmi2::types::*;

type Instantiate = unsafe extern "C" fn(
    fmi2String,
    fmi2Type,
    fmi2String,
    fmi2String,
    *const fmi2CallbackFunctions,
    fmi2Boolean,
    fmi2Boolean,
) -> fmi2Component;
type FreeInstance = unsafe extern "C" fn(fmi2Component);

pub fn check(library: &Path, guid: &str) -> Result<(), String> {
    let lib = Loaded::open(library, &stewart_fmu::fmi2::FUNCTIONS)?;
    let symbol = |name: &str| lib.symbol(name);
    // SAFETY: the symbols have exactly these C signatures (fmi2FunctionTypes.h).
    let instantiate: Instantiate = unsafe { std::mem::transmute(symbol("fmi2Instantiate")?) };
    // SAFETY: as above.
    let free: FreeInstance = unsafe { std::mem::transmute(symbol("fmi2FreeInstance")?) };
    let callbacks = fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    };
    let name = c"build-fmu-check";
    let good = CString::new(guid).map_err(|_| "GUID contains NUL")?;
    let bad = c"{00000000-0000-0000-0000-000000000000}";
    // SAFETY: valid strings and callbacks that outlive the calls.
    unsafe {
        let c = instantiate(
            name.as_ptr(),
            fmi2CoSimulation,
            good.as_ptr(),
            std::ptr::null(),
            &callbacks,
            fmi2False,
            fmi2False,
        );
        if c.is_null() {
            return Err(format!("fmi2Instantiate refused the model description's GUID {guid}"));
        }
        free(c);
        let c = instantiate(
            name.as_ptr(),
            fmi2CoSimulation,
            bad.as_ptr(),
            std::ptr::null(),
            &callbacks,
            fmi2False,
            fmi2False,
        );
        if !c.is_null() {
            free(c);
            return Err("fmi2Instantiate accepted a foreign GUID".into());
        }
    }
    lib.close()
}

/// The built library, loaded for the checks.
struct Loaded {
    path: CString,
    handle: *mut c_void,
}

impl Loaded {
    /// `dlopen`s the library and checks that it exports every `required` symbol.
    fn open(library: &Path, required: &[&str]) -> Result<Self, String> {
        let path = CString::new(library.to_string_lossy().as_bytes()).map_err(|_| "path contains NUL")?;
        // SAFETY: dlopen of our own freshly built library; its initialisers are Rust's.
        let handle = unsafe { libc::dlopen(path.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
        if handle.is_null() {
            return Err("dlopen failed".into());
        }
        let lib = Loaded { path, handle };
        for name in required {
            lib.symbol(name)?;
        }
        Ok(lib)
    }

    fn symbol(&self, name: &str) -> Result<*mut c_void, String> {
        let c = CString::new(name).map_err(|_| "bad symbol name")?;
        // SAFETY: valid handle and NUL-terminated name.
        let p = unsafe { libc::dlsym(self.handle, c.as_ptr()) };
        if p.is_null() { Err(format!("symbol {name} is not exported")) } else { Ok(p) }
    }

    /// Closes the library and checks that it really leaves the process at its last handle:
    /// nothing in it keeps it resident (no `-z nodelete`, no thread-local destructor or exit
    /// handler registered by a plain instantiate/free), so a host that loads it from many
    /// unpacked copies keeps its memory.
    fn close(self) -> Result<(), String> {
        // SAFETY: handle from dlopen in `open`.
        unsafe { libc::dlclose(self.handle) };
        // SAFETY: RTLD_NOLOAD only looks the library up; a handle it returns is closed at once.
        let still = unsafe { libc::dlopen(self.path.as_ptr(), libc::RTLD_NOW | libc::RTLD_NOLOAD) };
        if still.is_null() {
            return Ok(());
        }
        // SAFETY: handle from dlopen above.
        unsafe { libc::dlclose(still) };
        Err("the library stays loaded after its last dlclose (linked with -z nodelete, or a thread-local destructor \
             or exit handler was registered)"
            .into())
    }
}

type Instantiate3 = unsafe extern "C" fn(
    *const std::ffi::c_char,
    *const std::ffi::c_char,
    *const std::ffi::c_char,
    u8,
    u8,
    u8,
    u8,
    *const u32,
    usize,
    *mut c_void,
    Option<unsafe extern "C" fn(*mut c_void, std::ffi::c_int, *const std::ffi::c_char, *const std::ffi::c_char)>,
    Option<unsafe extern "C" fn(*mut c_void, f64, u8, u8, u8, u8, *mut u8, *mut f64)>,
) -> *mut c_void;
type FreeInstance3 = unsafe extern "C" fn(*mut c_void);

/// The FMI 3 counterpart of [`check`]: every `fmi3*` symbol, and
/// `fmi3InstantiateCoSimulation` accepting the description's token and refusing a wrong one.
pub fn check_fmi3(library: &Path, token: &str) -> Result<(), String> {
    let lib = Loaded::open(library, &stewart_fmu::fmi3::FUNCTIONS)?;
    let symbol = |name: &str| lib.symbol(name);
    // SAFETY: the symbols have exactly these C signatures (fmi3FunctionTypes.h).
    let instantiate: Instantiate3 = unsafe { std::mem::transmute(symbol("fmi3InstantiateCoSimulation")?) };
    // SAFETY: as above.
    let free: FreeInstance3 = unsafe { std::mem::transmute(symbol("fmi3FreeInstance")?) };
    let name = c"build-fmu-check";
    let good = CString::new(token).map_err(|_| "token contains NUL")?;
    let bad = c"{00000000-0000-0000-0000-000000000000}";
    // SAFETY: valid strings; NULL callbacks are allowed.
    unsafe {
        let c = instantiate(
            name.as_ptr(),
            good.as_ptr(),
            std::ptr::null(),
            0,
            0,
            0,
            0,
            std::ptr::null(),
            0,
            std::ptr::null_mut(),
            None,
            None,
        );
        if c.is_null() {
            return Err(format!("fmi3InstantiateCoSimulation refused the model description's token {token}"));
        }
        free(c);
        let c = instantiate(
            name.as_ptr(),
            bad.as_ptr(),
            std::ptr::null(),
            0,
            0,
            0,
            0,
            std::ptr::null(),
            0,
            std::ptr::null_mut(),
            None,
            None,
        );
        if !c.is_null() {
            free(c);
            return Err("fmi3InstantiateCoSimulation accepted a foreign token".into());
        }
    }
    lib.close()
}

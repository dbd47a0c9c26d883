//! Checks of the built library as an importer sees it: `dlopen`, every FMI 2.0 symbol, and
//! `fmi2Instantiate` accepting the model description's GUID and refusing a wrong one.

use std::ffi::{CString, c_void};
use std::path::Path;

use stewart_fmu::fmi2::types::*;

/// The FMI 2.0 functions every FMU must export (common + Co-Simulation; FMPy resolves all 34),
/// plus the Model Exchange ones this binary also provides.
pub const REQUIRED_SYMBOLS: [&str; 44] = [
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
];

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
    let path = CString::new(library.to_string_lossy().as_bytes()).map_err(|_| "path contains NUL")?;
    // SAFETY: dlopen of our own freshly built library; its initialisers are Rust's.
    let handle = unsafe { libc::dlopen(path.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
    if handle.is_null() {
        return Err("dlopen failed".into());
    }
    let symbol = |name: &str| -> Result<*mut c_void, String> {
        let c = CString::new(name).map_err(|_| "bad symbol name")?;
        // SAFETY: valid handle and NUL-terminated name.
        let p = unsafe { libc::dlsym(handle, c.as_ptr()) };
        if p.is_null() { Err(format!("symbol {name} is not exported")) } else { Ok(p) }
    };
    for name in REQUIRED_SYMBOLS {
        symbol(name)?;
    }
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
    // The library is linked with -z nodelete; closing only drops our reference.
    // SAFETY: handle from dlopen above.
    unsafe { libc::dlclose(handle) };
    Ok(())
}

//! Every FMI function in every reachable state, through the exported `extern "C"` functions:
//! the status follows the FMI 2.0 Co-Simulation calling-sequence table (transcribed here from
//! the standard, section 4.2.4 and its table of allowed calls, independently of the crate's own
//! table), an illegal call is logged with the function and the state, and changes nothing.

use crate::common;

use common::fmi_host::Host;
use stewart_fmu::fmi2::exports::*;
use stewart_fmu::fmi2::types::*;

/// Reachable states of a synchronous Co-Simulation FMU (stepInProgress and stepCanceled
/// need asynchronous steps, which this FMU does not offer; fatal is never entered).
const STATES: [&str; 6] = ["instantiated", "initializationMode", "stepComplete", "stepFailed", "terminated", "error"];

/// The standard's table: for each function, the reachable states where it may be called.
fn allowed(function: &str) -> &'static [&'static str] {
    const ALL: &[&str] = &["instantiated", "initializationMode", "stepComplete", "stepFailed", "terminated", "error"];
    const GETS: &[&str] = &["initializationMode", "stepComplete", "stepFailed", "terminated", "error"];
    const SETS: &[&str] = &["instantiated", "initializationMode", "stepComplete"];
    match function {
        "fmi2SetDebugLogging" | "fmi2Reset" => ALL,
        "fmi2SetupExperiment" | "fmi2EnterInitializationMode" => &["instantiated"],
        "fmi2ExitInitializationMode" => &["initializationMode"],
        "fmi2Terminate" => &["stepComplete", "stepFailed"],
        "fmi2GetReal" | "fmi2GetInteger" | "fmi2GetBoolean" | "fmi2GetString" => GETS,
        "fmi2SetReal" | "fmi2SetInteger" | "fmi2SetBoolean" | "fmi2SetString" => SETS,
        "fmi2GetFMUstate"
        | "fmi2SetFMUstate"
        | "fmi2FreeFMUstate"
        | "fmi2SerializedFMUstateSize"
        | "fmi2SerializeFMUstate"
        | "fmi2DeSerializeFMUstate" => ALL,
        "fmi2GetDirectionalDerivative" => GETS,
        "fmi2SetRealInputDerivatives" => SETS,
        "fmi2GetRealOutputDerivatives" => &["stepComplete", "stepFailed", "terminated", "error"],
        "fmi2DoStep" => &["stepComplete"],
        "fmi2CancelStep" => &[],
        "fmi2GetStatus"
        | "fmi2GetRealStatus"
        | "fmi2GetIntegerStatus"
        | "fmi2GetBooleanStatus"
        | "fmi2GetStringStatus" => &["stepComplete", "stepFailed", "terminated"],
        // Model Exchange functions on a Co-Simulation instance.
        _ => &[],
    }
}

/// The functions walked: every one the library exports (`stewart_fmu::fmi2::FUNCTIONS`, the
/// list `build-fmu` checks the binaries against) but `fmi2Instantiate`, which takes no instance.
fn functions() -> impl Iterator<Item = &'static str> {
    stewart_fmu::fmi2::FUNCTIONS.into_iter().filter(|f| *f != "fmi2Instantiate")
}

/// Continuous states of the platform (24 special-form coordinates, work.F, work.dissipated).
const NX: usize = stewart_fmu::simulation::SIMULATION_DIM;
/// Event indicators: twelve stroke limits and the force/moment determinant.
const NZ: usize = stewart_fmu::simulation::state::switching::EVENT_INDICATORS;

/// A fresh instance driven into `state`.
fn instance_in(state: &str) -> Host {
    let mut h = Host::platform("walk");
    match state {
        "instantiated" => {}
        "initializationMode" => {
            h.setup(None);
            assert_eq!(h.enter(), fmi2OK);
        }
        "stepComplete" => assert_eq!(h.initialise(&[]), fmi2OK),
        "stepFailed" => {
            assert_eq!(h.initialise(&[("stops", 0.0), ("joints", 0.0)]), fmi2OK);
            h.set_forces([-1.0e6; 6]); // pulls the platform through the base (no end stops)
            assert_eq!(h.step(1.0), fmi2Discard);
        }
        "terminated" => {
            assert_eq!(h.initialise(&[]), fmi2OK);
            assert_eq!(unsafe { fmi2Terminate(h.c) }, fmi2OK);
        }
        "error" => {
            h.setup(None);
            h.enter();
            h.set("M", -1.0);
            assert_eq!(h.exit(), fmi2Error);
        }
        _ => unreachable!(),
    }
    h.clear_log();
    h
}

/// Calls `function` on the instance with well-formed arguments; returns its status.
fn invoke(h: &mut Host, function: &str) -> fmi2Status {
    let c = h.c;
    let vr_r3 = h.vr("r[3]");
    let vr_f1 = h.vr("F[1]");
    let vr_method = h.vr("solver.method");
    let mut real = 0.0f64;
    let mut int = 0i32;
    let mut status = 0i32;
    let mut text: fmi2String = std::ptr::null();
    let mut buf = [0.0f64; NX];
    unsafe {
        match function {
            "fmi2SetDebugLogging" => fmi2SetDebugLogging(c, fmi2True, 0, std::ptr::null()),
            "fmi2SetupExperiment" => fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0),
            "fmi2EnterInitializationMode" => fmi2EnterInitializationMode(c),
            "fmi2ExitInitializationMode" => fmi2ExitInitializationMode(c),
            "fmi2Terminate" => fmi2Terminate(c),
            "fmi2Reset" => fmi2Reset(c),
            "fmi2GetReal" => fmi2GetReal(c, &vr_r3, 1, &mut real),
            "fmi2GetInteger" => fmi2GetInteger(c, &vr_method, 1, &mut int),
            "fmi2GetBoolean" => fmi2GetBoolean(c, std::ptr::null(), 0, std::ptr::null_mut()),
            "fmi2GetString" => fmi2GetString(c, std::ptr::null(), 0, std::ptr::null_mut()),
            "fmi2SetReal" => fmi2SetReal(c, &vr_f1, 1, &5000.0),
            "fmi2SetInteger" => fmi2SetInteger(c, &vr_method, 1, &1),
            "fmi2SetBoolean" => fmi2SetBoolean(c, std::ptr::null(), 0, std::ptr::null()),
            "fmi2SetString" => fmi2SetString(c, std::ptr::null(), 0, std::ptr::null()),
            "fmi2GetFMUstate" => {
                let mut st: fmi2FMUstate = std::ptr::null_mut();
                let s = fmi2GetFMUstate(c, &mut st);
                if !st.is_null() {
                    fmi2FreeFMUstate(c, &mut st);
                }
                s
            }
            "fmi2SetFMUstate" | "fmi2FreeFMUstate" | "fmi2SerializedFMUstateSize" | "fmi2SerializeFMUstate" => {
                // A state of this instance in its current state (GetFMUstate is allowed in
                // every reachable state).
                let mut st: fmi2FMUstate = std::ptr::null_mut();
                assert_eq!(fmi2GetFMUstate(c, &mut st), fmi2OK);
                let mut size = 0usize;
                let mut bytes = vec![0u8; 4096];
                let s = match function {
                    "fmi2SetFMUstate" => fmi2SetFMUstate(c, st),
                    "fmi2FreeFMUstate" => fmi2FreeFMUstate(c, &mut st),
                    "fmi2SerializedFMUstateSize" => fmi2SerializedFMUstateSize(c, st, &mut size),
                    _ => fmi2SerializeFMUstate(c, st, bytes.as_mut_ptr() as *mut fmi2Byte, bytes.len()),
                };
                if !st.is_null() {
                    fmi2FreeFMUstate(c, &mut st);
                }
                s
            }
            "fmi2DeSerializeFMUstate" => {
                let bytes = h.state_bytes();
                let mut st: fmi2FMUstate = std::ptr::null_mut();
                let s = fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut st);
                if !st.is_null() {
                    fmi2FreeFMUstate(c, &mut st);
                }
                s
            }
            "fmi2GetDirectionalDerivative" => fmi2GetDirectionalDerivative(c, &vr_r3, 1, &vr_f1, 1, &1.0, &mut real),
            "fmi2SetRealInputDerivatives" => fmi2SetRealInputDerivatives(c, &vr_f1, 1, &1, &0.0),
            "fmi2GetRealOutputDerivatives" => fmi2GetRealOutputDerivatives(c, &vr_r3, 1, &1, &mut real),
            "fmi2DoStep" => fmi2DoStep(c, 0.0, 0.01, fmi2True),
            "fmi2CancelStep" => fmi2CancelStep(c),
            "fmi2GetStatus" => fmi2GetStatus(c, fmi2DoStepStatus, &mut status),
            "fmi2GetRealStatus" => fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &mut real),
            "fmi2GetIntegerStatus" => fmi2GetIntegerStatus(c, fmi2PendingStatus, &mut int),
            "fmi2GetBooleanStatus" => fmi2GetBooleanStatus(c, fmi2Terminated, &mut int),
            "fmi2GetStringStatus" => fmi2GetStringStatus(c, fmi2PendingStatus, &mut text),
            "fmi2EnterEventMode" => fmi2EnterEventMode(c),
            "fmi2NewDiscreteStates" => fmi2NewDiscreteStates(c, &mut fmi2EventInfo::default()),
            "fmi2EnterContinuousTimeMode" => fmi2EnterContinuousTimeMode(c),
            "fmi2CompletedIntegratorStep" => fmi2CompletedIntegratorStep(c, fmi2True, &mut int, &mut status),
            "fmi2SetTime" => fmi2SetTime(c, 0.0),
            "fmi2SetContinuousStates" => fmi2SetContinuousStates(c, buf.as_ptr(), NX),
            "fmi2GetDerivatives" => fmi2GetDerivatives(c, buf.as_mut_ptr(), NX),
            "fmi2GetEventIndicators" => fmi2GetEventIndicators(c, buf.as_mut_ptr(), NZ),
            "fmi2GetContinuousStates" => fmi2GetContinuousStates(c, buf.as_mut_ptr(), NX),
            "fmi2GetNominalsOfContinuousStates" => fmi2GetNominalsOfContinuousStates(c, buf.as_mut_ptr(), NX),
            other => panic!("{other}"),
        }
    }
}

#[test]
fn every_function_in_every_state_follows_the_standards_table() {
    let mut checked = 0;
    let mut refused = 0;
    for state in STATES {
        for function in functions() {
            if matches!(function, "fmi2GetTypesPlatform" | "fmi2GetVersion" | "fmi2FreeInstance") {
                continue; // no state: tested below
            }
            let mut h = instance_in(state);
            let before = h.state_bytes();
            let status = invoke(&mut h, function);
            assert!((0..=5).contains(&status));
            let log = h.messages();
            let illegal = log.iter().find(|l| l.message.contains("illegal call sequence"));
            if allowed(function).contains(&state) {
                assert!(illegal.is_none(), "{function} in {state} was refused: {:?}", illegal);
                assert!(status != fmi2Fatal && status != fmi2Pending, "{function} in {state}: status {status}");
            } else {
                assert_eq!(status, fmi2Error, "{function} in {state} must be refused");
                let line =
                    illegal.unwrap_or_else(|| panic!("{function} in {state}: no illegal-call message in {log:?}"));
                assert!(line.message.contains(function) && line.message.contains(state), "{}", line.message);
                assert_eq!(line.category, "logStatusError");
                assert_eq!(line.instance, "walk");
                assert!(h.state_bytes() == before, "{function} in {state} changed the instance");
                refused += 1;
            }
            checked += 1;
        }
    }
    println!("checked {checked} (function, state) pairs; {refused} refused as illegal call sequences");
    assert_eq!(checked, 6 * 40);
}

#[test]
fn functions_without_an_instance() {
    unsafe {
        assert_eq!(std::ffi::CStr::from_ptr(fmi2GetTypesPlatform()).to_str().unwrap(), "default");
        assert_eq!(std::ffi::CStr::from_ptr(fmi2GetVersion()).to_str().unwrap(), "2.0");
        fmi2FreeInstance(std::ptr::null_mut()); // a no-op
        // Every function taking an instance refuses NULL.
        let null = std::ptr::null_mut();
        assert_eq!(fmi2DoStep(null, 0.0, 0.1, 1), fmi2Error);
        assert_eq!(fmi2GetReal(null, std::ptr::null(), 0, std::ptr::null_mut()), fmi2Error);
        assert_eq!(fmi2Reset(null), fmi2Error);
        assert_eq!(fmi2SetFMUstate(null, std::ptr::null_mut()), fmi2Error);
    }
}

#[test]
fn after_an_error_only_the_allowed_calls_work_and_reset_restores_the_start_values() {
    let mut h = instance_in("error");
    assert!(h.messages().is_empty());
    // The error column: gets work (for debugging), steps and sets do not.
    let m = h.get("M");
    assert_eq!(m, -1.0);
    assert_eq!(invoke(&mut h, "fmi2DoStep"), fmi2Error);
    assert_eq!(invoke(&mut h, "fmi2SetReal"), fmi2Error);
    assert_eq!(invoke(&mut h, "fmi2Terminate"), fmi2Error);
    assert_eq!(unsafe { fmi2Reset(h.c) }, fmi2OK);
    let fresh = Host::platform("fresh");
    // Instantiated does not allow fmi2GetReal: compare the start values through a state.
    let (a, b) = (h.state_bytes(), fresh.state_bytes());
    assert_eq!(a, b, "after fmi2Reset the instance equals a new one");
    assert_eq!(h.initialise(&[]), fmi2OK);
    assert_eq!(h.get("M"), 3000.0);
    assert_eq!(h.step(0.01), fmi2OK, "{:?}", h.messages());
}

/// Model Exchange: the life cycle through the exported functions, and the ME table's
/// refusals (no fmi2DoStep, no state changes outside continuous-time mode).
#[test]
fn model_exchange_life_cycle_and_refusals() {
    use stewart_fmu::fmi::FmiVersion;
    use stewart_fmu::fmi::description::instantiation_token;
    use stewart_fmu::models::ModelKind;
    let sink = std::sync::Mutex::new(vec![]);
    let cb = common::fmi_host::callbacks(&sink);
    let guid = std::ffi::CString::new(instantiation_token(ModelKind::Platform, FmiVersion::Fmi2)).unwrap();
    unsafe {
        let c = fmi2Instantiate(c"me".as_ptr(), fmi2ModelExchange, guid.as_ptr(), std::ptr::null(), &cb, 0, 0);
        assert!(!c.is_null());
        let mut x = [0.0; NX];
        let mut dx = [0.0; NX];
        assert_eq!(fmi2GetDerivatives(c, dx.as_mut_ptr(), NX), fmi2Error); // instantiated: not yet
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), fmi2OK);
        assert_eq!(fmi2EnterInitializationMode(c), fmi2OK);
        assert_eq!(fmi2ExitInitializationMode(c), fmi2OK);
        let mut info = fmi2EventInfo::default();
        assert_eq!(fmi2NewDiscreteStates(c, &mut info), fmi2OK);
        assert_eq!(info.newDiscreteStatesNeeded, 0);
        assert_eq!(fmi2SetContinuousStates(c, x.as_ptr(), NX), fmi2Error); // event mode: refused
        assert_eq!(fmi2EnterContinuousTimeMode(c), fmi2OK);
        assert_eq!(fmi2GetContinuousStates(c, x.as_mut_ptr(), NX), fmi2OK);
        assert!((x[2] - 1.9589244164161732).abs() < 1e-15 && x[6] == 1.0);
        assert_eq!(fmi2GetContinuousStates(c, x.as_mut_ptr(), NX - 1), fmi2Error); // wrong nx
        assert_eq!(fmi2SetTime(c, 0.01), fmi2OK);
        assert_eq!(fmi2GetDerivatives(c, dx.as_mut_ptr(), NX), fmi2OK);
        assert!(dx.iter().all(|d| d.abs() < 1e-9), "equilibrium: {dx:?}");
        x[2] += 1e-3;
        assert_eq!(fmi2SetContinuousStates(c, x.as_ptr(), NX), fmi2OK);
        assert_eq!(fmi2GetDerivatives(c, dx.as_mut_ptr(), NX), fmi2OK);
        assert!(dx[2] == 0.0 && dx[5] > 0.0, "raised platform accelerates upward");
        // Event indicators: every leg inside its stroke (positive margins), the determinant
        // of the neutral pose; a wrong count is refused.
        let mut z = [0.0; NZ];
        assert_eq!(fmi2GetEventIndicators(c, z.as_mut_ptr(), NZ), fmi2OK);
        assert!(z[..12].iter().all(|&m| m > 0.2 && m < 0.5), "{z:?}");
        assert!(z[12] != 0.0);
        assert_eq!(fmi2GetEventIndicators(c, z.as_mut_ptr(), NZ - 1), fmi2Error);
        let mut nan_x = x;
        nan_x[0] = f64::NAN;
        assert_eq!(fmi2SetContinuousStates(c, nan_x.as_ptr(), NX), fmi2Error);
        let (mut enter, mut terminate) = (1, 1);
        assert_eq!(fmi2CompletedIntegratorStep(c, 1, &mut enter, &mut terminate), fmi2OK);
        assert_eq!((enter, terminate), (0, 0));
        assert_eq!(fmi2DoStep(c, 0.0, 0.01, 1), fmi2Error); // no Co-Simulation on an ME instance
        assert_eq!(fmi2EnterEventMode(c), fmi2OK);
        assert_eq!(fmi2Terminate(c), fmi2OK);
        fmi2FreeInstance(c);
        // The controller has no Model Exchange.
        let guid = std::ffi::CString::new(instantiation_token(ModelKind::Controller, FmiVersion::Fmi2)).unwrap();
        let c = fmi2Instantiate(c"me".as_ptr(), fmi2ModelExchange, guid.as_ptr(), std::ptr::null(), &cb, 0, 0);
        assert!(c.is_null());
    }
    let log = sink.lock().unwrap();
    assert!(log.iter().any(|l| l.message.contains("illegal call sequence") && l.message.contains("Model Exchange")));
    assert!(log.iter().any(|l| l.message.contains("implements Co-Simulation only")));
}

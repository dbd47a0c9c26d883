//! FMI 3.0: every function in every reachable state of a Co-Simulation and a Model Exchange
//! instance, through the exported `extern "C"` functions. The allowed states are transcribed
//! here from the standard's state machines (FMI 3.0, sections 3.2 and 4.2, and the
//! "allowed function calls" of each state), independently of the crate's own table. An
//! illegal call is refused with `fmi3Error`, logged with the function and the state, and
//! changes nothing. Then 10^5 random calls (random functions, states, value references,
//! array sizes, NaN and infinities, NULL pointers, damaged FMU states).

use crate::common;

use common::fmi3_host::{Host3, Kind};
use common::rng::Rng;
use stewart_fmu::fmi3::exports::*;
use stewart_fmu::fmi3::types::*;
use stewart_fmu::models::ModelKind;

const CS_STATES: [&str; 7] =
    ["instantiated", "initializationMode", "eventMode", "stepMode", "stepDiscarded", "terminated", "error"];
const ME_STATES: [&str; 6] =
    ["instantiated", "initializationMode", "eventMode", "continuousTimeMode", "terminated", "error"];

/// Functions this FMU does not provide (no clocks, no structural parameters, no
/// `providesEvaluateDiscreteStates`, no Scheduled Execution): refused in every state, and
/// never with a change of the instance.
const UNSUPPORTED: [&str; 7] = [
    "fmi3GetClock",
    "fmi3SetClock",
    "fmi3GetIntervalDecimal",
    "fmi3EnterConfigurationMode",
    "fmi3ExitConfigurationMode",
    "fmi3EvaluateDiscreteStates",
    "fmi3ActivateModelPartition",
];

/// The standard's table for the reachable states: where `function` may be called on an
/// instance of `kind`.
fn allowed(function: &str, kind: Kind) -> &'static [&'static str] {
    use Kind::*;
    const EVERY: &[&str] = &[
        "instantiated",
        "initializationMode",
        "eventMode",
        "continuousTimeMode",
        "stepMode",
        "stepDiscarded",
        "terminated",
        "error",
    ];
    // "If a function returns fmi3Error ... it is possible to restore a previously retrieved
    // FMU state by calling fmi3SetFMUState. Otherwise fmi3FreeInstance or fmi3Reset must be
    // called": everything else is refused in the error state.
    const NOT_ERROR: &[&str] = &[
        "instantiated",
        "initializationMode",
        "eventMode",
        "continuousTimeMode",
        "stepMode",
        "stepDiscarded",
        "terminated",
    ];
    const GETS: &[&str] = &[
        "instantiated",
        "initializationMode",
        "eventMode",
        "continuousTimeMode",
        "stepMode",
        "stepDiscarded",
        "terminated",
    ];
    match (function, kind) {
        ("fmi3SetDebugLogging" | "fmi3Reset", _) => EVERY,
        ("fmi3SetFMUState" | "fmi3FreeFMUState" | "fmi3DeserializeFMUState", _) => EVERY,
        ("fmi3GetFMUState" | "fmi3SerializedFMUStateSize" | "fmi3SerializeFMUState", _) => NOT_ERROR,
        ("fmi3GetNumberOfVariableDependencies" | "fmi3GetVariableDependencies", _) => NOT_ERROR,
        ("fmi3EnterInitializationMode", _) => &["instantiated"],
        ("fmi3ExitInitializationMode", _) => &["initializationMode"],
        ("fmi3EnterEventMode", CoSimulation) => &["stepMode"],
        ("fmi3EnterEventMode", ModelExchange) => &["continuousTimeMode"],
        ("fmi3Terminate", CoSimulation) => &["eventMode", "stepMode", "stepDiscarded"],
        ("fmi3Terminate", ModelExchange) => &["eventMode", "continuousTimeMode"],
        ("fmi3GetFloat64" | "fmi3GetInt32" | "fmi3GetBoolean" | "fmi3GetString", _) => GETS,
        // Continuous-time inputs may change in Continuous-Time Mode; discrete ones only at events.
        ("fmi3SetFloat64", _) => &["instantiated", "initializationMode", "eventMode", "continuousTimeMode", "stepMode"],
        ("fmi3SetInt32" | "fmi3SetBoolean" | "fmi3SetString", _) => {
            &["instantiated", "initializationMode", "eventMode", "stepMode"]
        }
        ("fmi3GetDirectionalDerivative" | "fmi3GetAdjointDerivative", _) => {
            &["initializationMode", "eventMode", "continuousTimeMode", "stepMode", "terminated"]
        }
        ("fmi3UpdateDiscreteStates", _) => &["eventMode"],
        ("fmi3GetNumberOfEventIndicators" | "fmi3GetNumberOfContinuousStates", _) => NOT_ERROR,
        ("fmi3EnterContinuousTimeMode", ModelExchange) => &["eventMode"],
        ("fmi3CompletedIntegratorStep" | "fmi3SetContinuousStates", ModelExchange) => &["continuousTimeMode"],
        ("fmi3SetTime", ModelExchange) => &["eventMode", "continuousTimeMode"],
        (
            "fmi3GetContinuousStateDerivatives"
            | "fmi3GetEventIndicators"
            | "fmi3GetContinuousStates"
            | "fmi3GetNominalsOfContinuousStates",
            ModelExchange,
        ) => &["initializationMode", "eventMode", "continuousTimeMode", "terminated"],
        ("fmi3EnterStepMode", CoSimulation) => &["eventMode"],
        ("fmi3GetOutputDerivatives", CoSimulation) => &["stepMode", "stepDiscarded", "terminated"],
        ("fmi3DoStep", CoSimulation) => &["stepMode"],
        // Model Exchange functions on a Co-Simulation instance and the reverse.
        _ => &[],
    }
}

/// The functions walked: every one the library exports (`stewart_fmu::fmi3::FUNCTIONS`, the
/// list `build-fmu` checks the binaries against) that takes an instance, one of each family the
/// FMU answers alike: the gets and sets of the types it has no variables of (`fmi3GetString`
/// stands for them) and the clocks' timings (`fmi3GetIntervalDecimal`) left out.
fn functions() -> Vec<&'static str> {
    let without_variables = ["Float32", "Int8", "UInt8", "Int16", "UInt16", "UInt32", "Int64", "UInt64", "Binary"];
    let timing = ["IntervalFraction", "ShiftDecimal", "ShiftFraction"];
    stewart_fmu::fmi3::FUNCTIONS
        .into_iter()
        .filter(|f| !f.starts_with("fmi3Instantiate") && !["fmi3GetVersion", "fmi3FreeInstance"].contains(f))
        .filter(|f| !without_variables.iter().any(|t| *f == format!("fmi3Get{t}") || *f == format!("fmi3Set{t}")))
        .filter(|f| !timing.iter().any(|t| f.ends_with(t)) && *f != "fmi3SetIntervalDecimal")
        .collect()
}

/// Continuous states of the platform and its event indicators (Model Exchange).
const NX: usize = stewart_fmu::simulation::SIMULATION_DIM;
const NZ: usize = stewart_fmu::simulation::state::switching::EVENT_INDICATORS;

/// A fresh instance driven into `state` (Co-Simulation instances use Event Mode).
fn instance_in(state: &str, kind: Kind) -> Host3 {
    let mut h = Host3::try_new("walk", ModelKind::Platform, kind, true).unwrap_or_else(|l| panic!("{l:?}"));
    let initialise = |h: &mut Host3, values: &[(&str, &[f64])]| {
        assert_eq!(h.initialise(values), fmi3OK, "{:?}", h.messages()); // now in Event Mode
    };
    unsafe {
        match state {
            "instantiated" => {}
            "initializationMode" => assert_eq!(h.enter(), fmi3OK),
            "eventMode" => initialise(&mut h, &[]),
            "stepMode" => {
                initialise(&mut h, &[]);
                assert_eq!(fmi3EnterStepMode(h.c), fmi3OK);
            }
            "continuousTimeMode" => {
                initialise(&mut h, &[]);
                assert_eq!(fmi3EnterContinuousTimeMode(h.c), fmi3OK);
            }
            "stepDiscarded" => {
                initialise(&mut h, &[("stops", &[0.0]), ("joints", &[0.0])]);
                assert_eq!(fmi3EnterStepMode(h.c), fmi3OK);
                h.set("F", &[-1.0e6; 6]); // pulls the platform through the base (no end stops)
                assert_eq!(h.step(1.0).0, fmi3Discard, "{:?}", h.messages());
            }
            "terminated" => {
                initialise(&mut h, &[]);
                assert_eq!(fmi3Terminate(h.c), fmi3OK);
            }
            "error" => {
                assert_eq!(h.enter(), fmi3OK);
                h.set("M", &[-1.0]);
                assert_eq!(h.exit(), fmi3Error);
            }
            _ => unreachable!(),
        }
    }
    h.clear_log();
    h
}

/// Calls `function` on the instance with well-formed arguments; returns its status.
fn invoke(h: &mut Host3, function: &str) -> fmi3Status {
    let c = h.c;
    // The platform's variables, or the cueing FMU's of the same kinds (a Float64[3] output, a
    // Float64[6]-sized input set, an Int32 parameter, a Boolean).
    let platform = h.table.groups.iter().any(|g| g.name == "F");
    let vr_r = h.vr(if platform { "r" } else { "pose.r" });
    let vr_f = if platform { h.vr("F") } else { h.vr("f") };
    let vr_method = h.vr(if platform { "solver.method" } else { "cueing.method" });
    let vr_stops = h.vr(if platform { "stops" } else { "limited" });
    let mut r3 = [0.0f64; 3];
    let mut f6 = [0.0f64; 6];
    let mut int = 0i32;
    let mut boolean = 0u8;
    let mut text: fmi3String = std::ptr::null();
    let mut n = 0usize;
    let (mut b1, mut b2, mut b3, mut b4, mut b5) = (0u8, 0u8, 0u8, 0u8, 0u8);
    let mut real = 0.0f64;
    let mut buf = [0.0f64; NX];
    let seed = [1.0f64; 6];
    let mut sens = [0.0f64; 18];
    unsafe {
        match function {
            "fmi3SetDebugLogging" => fmi3SetDebugLogging(c, fmi3True, 0, std::ptr::null()),
            "fmi3EnterInitializationMode" => fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0),
            "fmi3ExitInitializationMode" => fmi3ExitInitializationMode(c),
            "fmi3EnterEventMode" => fmi3EnterEventMode(c),
            "fmi3Terminate" => fmi3Terminate(c),
            "fmi3Reset" => fmi3Reset(c),
            "fmi3GetFloat64" => fmi3GetFloat64(c, &vr_r, 1, r3.as_mut_ptr(), 3),
            "fmi3GetInt32" => fmi3GetInt32(c, &vr_method, 1, &mut int, 1),
            "fmi3GetBoolean" => fmi3GetBoolean(c, &vr_stops, 1, &mut boolean, 1),
            "fmi3GetString" => fmi3GetString(c, std::ptr::null(), 0, &mut text, 0),
            "fmi3SetFloat64" => fmi3SetFloat64(c, &vr_f, 1, [5000.0; 6].as_ptr(), 6),
            "fmi3SetInt32" => fmi3SetInt32(c, &vr_method, 1, &1, 1),
            "fmi3SetBoolean" => fmi3SetBoolean(c, &vr_stops, 1, &fmi3True, 1),
            "fmi3SetString" => fmi3SetString(c, std::ptr::null(), 0, std::ptr::null(), 0),
            "fmi3GetNumberOfVariableDependencies" => fmi3GetNumberOfVariableDependencies(c, vr_r, &mut n),
            "fmi3GetVariableDependencies" => {
                let mut e = [0usize; 64];
                let mut i = [0u32; 64];
                let mut ie = [0usize; 64];
                let mut k = [0i32; 64];
                // The count from another instance: only the call under test may be refused here.
                let model = if platform { ModelKind::Platform } else { ModelKind::Cueing };
                let other = Host3::try_new("count", model, h.kind, false).unwrap_or_else(|l| panic!("{l:?}"));
                let mut count = 0usize;
                assert_eq!(fmi3GetNumberOfVariableDependencies(other.c, vr_r, &mut count), fmi3OK);
                assert!(count > 0 && count <= 64, "{count}");
                fmi3GetVariableDependencies(
                    c,
                    vr_r,
                    e.as_mut_ptr(),
                    i.as_mut_ptr(),
                    ie.as_mut_ptr(),
                    k.as_mut_ptr(),
                    count,
                )
            }
            "fmi3GetFMUState" => {
                let mut st: fmi3FMUState = std::ptr::null_mut();
                let s = fmi3GetFMUState(c, &mut st);
                if !st.is_null() {
                    fmi3FreeFMUState(c, &mut st);
                }
                s
            }
            "fmi3SetFMUState" | "fmi3FreeFMUState" | "fmi3SerializedFMUStateSize" | "fmi3SerializeFMUState" => {
                // A state of this instance made from its bytes (deserializing is allowed in
                // every state, so the call under test is the only one that can be refused).
                let bytes = fresh_state_bytes_of(model_of(h), h.kind);
                let mut st: fmi3FMUState = std::ptr::null_mut();
                assert_eq!(fmi3DeserializeFMUState(c, bytes.as_ptr(), bytes.len(), &mut st), fmi3OK);
                let mut size = 0usize;
                let mut out = vec![0u8; 8192];
                let s = match function {
                    "fmi3SetFMUState" => fmi3SetFMUState(c, st),
                    "fmi3FreeFMUState" => fmi3FreeFMUState(c, &mut st),
                    "fmi3SerializedFMUStateSize" => fmi3SerializedFMUStateSize(c, st, &mut size),
                    _ => fmi3SerializeFMUState(c, st, out.as_mut_ptr(), out.len()),
                };
                if !st.is_null() {
                    assert_eq!(fmi3FreeFMUState(c, &mut st), fmi3OK);
                }
                s
            }
            "fmi3DeserializeFMUState" => {
                let bytes = fresh_state_bytes_of(model_of(h), h.kind);
                let mut st: fmi3FMUState = std::ptr::null_mut();
                let s = fmi3DeserializeFMUState(c, bytes.as_ptr(), bytes.len(), &mut st);
                if !st.is_null() {
                    fmi3FreeFMUState(c, &mut st);
                }
                s
            }
            "fmi3GetDirectionalDerivative" => {
                fmi3GetDirectionalDerivative(c, &vr_r, 1, &vr_f, 1, seed.as_ptr(), 6, sens.as_mut_ptr(), 3)
            }
            "fmi3GetAdjointDerivative" => {
                fmi3GetAdjointDerivative(c, &vr_r, 1, &vr_f, 1, seed.as_ptr(), 3, sens.as_mut_ptr(), 6)
            }
            "fmi3EnterConfigurationMode" => fmi3EnterConfigurationMode(c),
            "fmi3ExitConfigurationMode" => fmi3ExitConfigurationMode(c),
            "fmi3GetClock" => fmi3GetClock(c, &vr_r, 1, &mut boolean),
            "fmi3SetClock" => fmi3SetClock(c, &vr_r, 1, &boolean),
            "fmi3GetIntervalDecimal" => {
                let mut q = 0i32;
                fmi3GetIntervalDecimal(c, &vr_r, 1, &mut real, &mut q)
            }
            "fmi3EvaluateDiscreteStates" => fmi3EvaluateDiscreteStates(c),
            "fmi3UpdateDiscreteStates" => {
                fmi3UpdateDiscreteStates(c, &mut b1, &mut b2, &mut b3, &mut b4, &mut b5, &mut real)
            }
            "fmi3EnterContinuousTimeMode" => fmi3EnterContinuousTimeMode(c),
            "fmi3CompletedIntegratorStep" => fmi3CompletedIntegratorStep(c, fmi3True, &mut b1, &mut b2),
            "fmi3SetTime" => fmi3SetTime(c, 0.0),
            "fmi3SetContinuousStates" => {
                // The neutral pose (where every walked instance is), from another instance.
                fmi3SetContinuousStates(c, neutral_states().as_ptr(), NX)
            }
            "fmi3GetContinuousStateDerivatives" => fmi3GetContinuousStateDerivatives(c, buf.as_mut_ptr(), NX),
            "fmi3GetEventIndicators" => fmi3GetEventIndicators(c, buf.as_mut_ptr(), NZ),
            "fmi3GetContinuousStates" => fmi3GetContinuousStates(c, buf.as_mut_ptr(), NX),
            "fmi3GetNominalsOfContinuousStates" => fmi3GetNominalsOfContinuousStates(c, buf.as_mut_ptr(), NX),
            "fmi3GetNumberOfEventIndicators" => fmi3GetNumberOfEventIndicators(c, &mut n),
            "fmi3GetNumberOfContinuousStates" => fmi3GetNumberOfContinuousStates(c, &mut n),
            "fmi3EnterStepMode" => fmi3EnterStepMode(c),
            "fmi3GetOutputDerivatives" => fmi3GetOutputDerivatives(c, &vr_r, 1, [1, 1, 1].as_ptr(), f6.as_mut_ptr(), 3),
            "fmi3DoStep" => {
                let mut last = 0.0;
                fmi3DoStep(c, 0.0, 0.01, fmi3True, &mut b1, &mut b2, &mut b3, &mut last)
            }
            "fmi3ActivateModelPartition" => fmi3ActivateModelPartition(c, vr_r, 0.0),
            other => panic!("{other}"),
        }
    }
}

/// The serialized state of a freshly instantiated instance of `kind`.
fn fresh_state_bytes(kind: Kind) -> Vec<u8> {
    fresh_state_bytes_of(ModelKind::Platform, kind)
}

fn fresh_state_bytes_of(model: ModelKind, kind: Kind) -> Vec<u8> {
    Host3::try_new("source", model, kind, true).unwrap_or_else(|l| panic!("{l:?}")).state_bytes()
}

/// The model an instance runs (the platform or the cueing FMU), from its variables.
fn model_of(h: &Host3) -> ModelKind {
    if h.table.groups.iter().any(|g| g.name == "F") { ModelKind::Platform } else { ModelKind::Cueing }
}

/// The Model Exchange states of the neutral pose, read from an initialised instance.
fn neutral_states() -> [f64; NX] {
    let h = instance_in("continuousTimeMode", Kind::ModelExchange);
    let mut x = [0.0; NX];
    assert_eq!(unsafe { fmi3GetContinuousStates(h.c, x.as_mut_ptr(), NX) }, fmi3OK);
    x
}

/// The instance's serialized state; `None` in the error state, where it cannot be taken
/// (nothing observable can change there but through the allowed calls).
fn snapshot(h: &Host3) -> Option<Vec<u8>> {
    let mut st: fmi3FMUState = std::ptr::null_mut();
    if unsafe { fmi3GetFMUState(h.c, &mut st) } != fmi3OK {
        h.clear_log();
        return None;
    }
    unsafe { fmi3FreeFMUState(h.c, &mut st) };
    Some(h.state_bytes())
}

fn walk(kind: Kind, states: &[&str]) -> (usize, usize) {
    let mut checked = 0;
    let mut refused = 0;
    for &state in states {
        for &function in &functions() {
            let mut h = instance_in(state, kind);
            let before = snapshot(&h);
            let status = invoke(&mut h, function);
            assert!((0..=4).contains(&status), "{function} in {state}: status {status}");
            let log = h.messages();
            let illegal = log.iter().find(|l| l.message.contains("illegal call sequence"));
            if UNSUPPORTED.contains(&function) {
                assert_eq!(status, fmi3Error, "{kind:?} {function} in {state} must be refused");
                assert!(!log.is_empty(), "{function} in {state}: refused without a message");
                assert!(snapshot(&h) == before, "{function} in {state} changed the instance");
                refused += 1;
            } else if allowed(function, kind).contains(&state) {
                assert!(illegal.is_none(), "{kind:?} {function} in {state} was refused: {illegal:?}");
                assert_ne!(status, fmi3Fatal, "{function} in {state}");
            } else {
                assert_eq!(status, fmi3Error, "{kind:?} {function} in {state} must be refused");
                let line = illegal
                    .unwrap_or_else(|| panic!("{kind:?} {function} in {state}: no illegal-call message in {log:?}"));
                assert!(line.message.contains(function) && line.message.contains(state), "{}", line.message);
                assert_eq!(line.category, "logStatusError");
                assert!(snapshot(&h) == before, "{function} in {state} changed the instance");
                refused += 1;
            }
            checked += 1;
        }
    }
    (checked, refused)
}

#[test]
fn co_simulation_follows_the_standards_table() {
    let (checked, refused) = walk(Kind::CoSimulation, &CS_STATES);
    println!("Co-Simulation: checked {checked} (function, state) pairs; {refused} refused");
    assert_eq!(checked, CS_STATES.len() * functions().len());
}

#[test]
fn model_exchange_follows_the_standards_table() {
    let (checked, refused) = walk(Kind::ModelExchange, &ME_STATES);
    println!("Model Exchange: checked {checked} (function, state) pairs; {refused} refused");
    assert_eq!(checked, ME_STATES.len() * functions().len());
}

/// The life cycle a Co-Simulation importer without Event Mode runs: Step Mode straight after
/// initialisation, and `fmi3EnterEventMode` refused with its reason.
#[test]
fn co_simulation_without_event_mode() {
    let mut h = Host3::platform("plain", Kind::CoSimulation);
    assert_eq!(h.initialise(&[]), fmi3OK);
    let (status, early) = h.step(0.01);
    assert_eq!((status, early), (fmi3OK, false));
    assert_eq!(unsafe { fmi3EnterEventMode(h.c) }, fmi3Error);
    assert!(h.messages().iter().any(|l| l.message.contains("eventModeUsed = false")), "{:?}", h.messages());
    assert_eq!(unsafe { fmi3EnterStepMode(h.c) }, fmi3Error, "already in Step Mode");
    // Still usable: the refusals changed nothing.
    assert_eq!(h.step(0.01).0, fmi3OK);
    assert!((h.time - 0.02).abs() < 1e-15);
}

#[test]
fn functions_without_an_instance_and_null_instances() {
    unsafe {
        assert_eq!(std::ffi::CStr::from_ptr(fmi3GetVersion()).to_str().unwrap(), "3.0");
        fmi3FreeInstance(std::ptr::null_mut()); // a no-op
        let null = std::ptr::null_mut();
        let (mut a, mut b, mut c, mut t) = (0u8, 0u8, 0u8, 0.0);
        assert_eq!(fmi3DoStep(null, 0.0, 0.1, 1, &mut a, &mut b, &mut c, &mut t), fmi3Error);
        assert_eq!(fmi3GetFloat64(null, std::ptr::null(), 0, std::ptr::null_mut(), 0), fmi3Error);
        assert_eq!(fmi3Reset(null), fmi3Error);
        assert_eq!(fmi3SetFMUState(null, std::ptr::null_mut()), fmi3Error);
        // An FMI 2 instance is not an FMI 3 instance.
        let fmi2 = common::fmi_host::Host::platform("fmi2");
        assert_eq!(fmi3Reset(fmi2.c), fmi3Error);
        // Scheduled Execution is not offered, the wrong model's token is refused.
        let token = std::ffi::CString::new(stewart_fmu::fmi::description::instantiation_token(
            ModelKind::Platform,
            stewart_fmu::fmi::FmiVersion::Fmi3,
        ))
        .unwrap();
        let se = fmi3InstantiateScheduledExecution(
            c"se".as_ptr(),
            token.as_ptr(),
            std::ptr::null(),
            0,
            0,
            std::ptr::null_mut(),
            None,
            None,
            None,
            None,
        );
        assert!(se.is_null());
    }
    let wrong =
        stewart_fmu::fmi::description::instantiation_token(ModelKind::Controller, stewart_fmu::fmi::FmiVersion::Fmi2);
    let refused = Host3::with_token("wrong", ModelKind::Platform, Kind::CoSimulation, false, wrong);
    let log = refused.err().expect("an FMI 2 token must be refused");
    assert!(log.iter().any(|l| l.message.contains("instantiationToken")), "{log:?}");
}

/// After an error only reset, free, logging and restoring a saved state work; a restored
/// state makes the instance usable again, and so does a reset.
#[test]
fn after_an_error_a_saved_state_or_a_reset_recovers() {
    let mut source = instance_in("stepMode", Kind::CoSimulation);
    let good = source.state_bytes();
    source.step(0.01);
    let mut h = instance_in("error", Kind::CoSimulation);
    assert_eq!(invoke(&mut h, "fmi3DoStep"), fmi3Error);
    assert_eq!(invoke(&mut h, "fmi3GetFloat64"), fmi3Error);
    assert_eq!(invoke(&mut h, "fmi3GetFMUState"), fmi3Error);
    unsafe {
        let mut st: fmi3FMUState = std::ptr::null_mut();
        assert_eq!(fmi3DeserializeFMUState(h.c, good.as_ptr(), good.len(), &mut st), fmi3OK);
        assert_eq!(fmi3SetFMUState(h.c, st), fmi3OK, "{:?}", h.messages());
        assert_eq!(fmi3FreeFMUState(h.c, &mut st), fmi3OK);
    }
    assert_eq!(h.step(0.01).0, fmi3OK, "{:?}", h.messages());
    assert_eq!(h.get("r"), source.get("r"), "the restored instance continues as the original");
    let mut e = instance_in("error", Kind::CoSimulation);
    assert_eq!(unsafe { fmi3Reset(e.c) }, fmi3OK);
    assert_eq!(e.state_bytes(), fresh_state_bytes(Kind::CoSimulation), "after fmi3Reset: a new instance");
    assert_eq!(e.initialise(&[]), fmi3OK);
    assert_eq!(e.get("M"), vec![3000.0]);
}

/// `logCalls` names each call with its arguments (inputs and, for getters, what was returned).
#[test]
fn log_calls_carries_the_arguments() {
    let mut h = instance_in("stepMode", Kind::CoSimulation);
    let categories = [c"logCalls".as_ptr()];
    unsafe { assert_eq!(fmi3SetDebugLogging(h.c, fmi3True, 1, categories.as_ptr()), fmi3OK) };
    h.set("F", &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    let r = h.get("r");
    h.step(0.005);
    let log: Vec<String> = h.messages().into_iter().filter(|l| l.category == "logCalls").map(|l| l.message).collect();
    let vr_f = h.vr("F");
    assert!(
        log.iter().any(|m| m.starts_with(&format!(
            "fmi3SetFloat64(valueReferences = [{vr_f}], values = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]) -> fmi3OK"
        ))),
        "{log:?}"
    );
    let shown = format!("values = [{:?}, {:?}, {:?}]", r[0], r[1], r[2]);
    assert!(log.iter().any(|m| m.starts_with("fmi3GetFloat64(") && m.contains(&shown)), "{log:?}");
    assert!(
        log.iter().any(|m| m.starts_with("fmi3DoStep(currentCommunicationPoint = 0.0, communicationStepSize = 0.005)")),
        "{log:?}"
    );
}

/// Values a fuzzed Float64 argument takes: the awkward ones half of the time.
const SPECIALS: [f64; 5] = [f64::NAN, f64::INFINITY, -1e300, 0.0, 5900.715];

#[test]
fn hundred_thousand_random_fmi3_calls() {
    const CALLS: usize = 100_000;
    let mut rng = Rng(0xD1B54A32D192ED03);
    let mut hosts: Vec<Host3> = vec![];
    let mut counts = [0usize; 5];
    let mut calls = 0;
    let names: Vec<&str> = functions();
    while calls < CALLS {
        if hosts.is_empty() || rng.chance(0.002) {
            let kind = if rng.chance(0.7) { Kind::CoSimulation } else { Kind::ModelExchange };
            if rng.chance(0.1) {
                // The controller (no Model Exchange: refused) or a wrong token, freed again.
                let _ = Host3::try_new("other", ModelKind::Controller, kind, rng.chance(0.5));
                let _ = Host3::with_token("bad", ModelKind::Platform, kind, false, "{bad}");
            } else if let Ok(h) = Host3::try_new(
                "fuzz",
                // The cueing FMU too (its cueing.method an Int32 the fuzz sets at random).
                if rng.chance(0.4) { ModelKind::Cueing } else { ModelKind::Platform },
                kind,
                rng.chance(0.5),
            ) {
                hosts.push(h);
            }
            calls += 1;
            if hosts.len() > 5 {
                hosts.swap_remove(0); // frees it
            }
            continue;
        }
        let i = rng.below(hosts.len() as u64) as usize;
        let h = &mut hosts[i];
        let status = if rng.chance(0.5) {
            // A well-formed call of a random function in whatever state the instance is.
            invoke_fuzzed(h, names[rng.below(names.len() as u64) as usize], &mut rng)
        } else {
            invoke_fuzzed(h, ["fmi3DoStep", "fmi3SetFloat64", "fmi3GetFloat64"][rng.below(3) as usize], &mut rng)
        };
        assert!((0..=4).contains(&status), "status {status} is not an FMI 3 status");
        counts[status as usize] += 1;
        calls += 1;
        if h.log.lock().map(|v| v.len()).unwrap_or(0) > 5_000 {
            h.clear_log();
        }
    }
    println!(
        "{calls} random FMI 3 calls: OK {}, Warning {}, Discard {}, Error {}, Fatal {}",
        counts[0], counts[1], counts[2], counts[3], counts[4]
    );
    assert_eq!(counts[4], 0, "no Fatal");
    assert!(counts[0] > 10_000 && counts[3] > 10_000, "the fuzz reaches both success and refusal paths");
}

/// One call with random (often malformed) arguments: random value references and array
/// sizes, non-finite values, NULL arrays, damaged or foreign FMU-state bytes.
fn invoke_fuzzed(h: &mut Host3, function: &str, rng: &mut Rng) -> fmi3Status {
    let c = h.c;
    let n = rng.below(4) as usize;
    let vrs: Vec<u32> =
        (0..n).map(|_| if rng.chance(0.1) { rng.next() as u32 } else { rng.below(310) as u32 }).collect();
    let nv = if rng.chance(0.8) { rng.below(40) as usize } else { rng.below(4) as usize };
    let values: Vec<f64> = (0..nv).map(|_| rng.real(&SPECIALS, 10)).collect();
    let mut out = vec![0.0f64; nv];
    let null = rng.chance(0.05);
    let vp = if null { std::ptr::null() } else { vrs.as_ptr() };
    unsafe {
        match function {
            "fmi3SetFloat64" => fmi3SetFloat64(c, vp, n, values.as_ptr(), nv),
            "fmi3GetFloat64" => {
                fmi3GetFloat64(c, vp, n, if null { std::ptr::null_mut() } else { out.as_mut_ptr() }, nv)
            }
            "fmi3SetInt32" => {
                let ints: Vec<i32> = (0..nv).map(|_| rng.below(5) as i32 - 1).collect();
                fmi3SetInt32(c, vp, n, ints.as_ptr(), nv)
            }
            "fmi3SetBoolean" => {
                let b: Vec<u8> = (0..nv).map(|_| rng.below(3) as u8).collect();
                fmi3SetBoolean(c, vp, n, b.as_ptr(), nv)
            }
            "fmi3DoStep" => {
                let t = if rng.chance(0.9) { h.time } else { rng.real(&SPECIALS, 10) };
                let step = if rng.chance(0.9) { (rng.below(100) + 1) as f64 * 1e-3 } else { rng.real(&SPECIALS, 10) };
                let (mut a, mut b, mut e, mut last) = (0u8, 0u8, 0u8, 0.0);
                let s = fmi3DoStep(c, t, step, fmi3True, &mut a, &mut b, &mut e, &mut last);
                if s == fmi3OK {
                    h.time = last;
                }
                s
            }
            "fmi3SetTime" => fmi3SetTime(c, rng.real(&SPECIALS, 10)),
            "fmi3SetContinuousStates" | "fmi3GetContinuousStates" | "fmi3GetContinuousStateDerivatives" => {
                let mut x: Vec<f64> = (0..NX).map(|_| rng.real(&SPECIALS, 10) * 1e-3).collect();
                let m = if rng.chance(0.8) { NX } else { rng.below(30) as usize };
                match function {
                    "fmi3SetContinuousStates" => fmi3SetContinuousStates(c, x.as_ptr(), m),
                    "fmi3GetContinuousStates" => fmi3GetContinuousStates(c, x.as_mut_ptr(), m),
                    _ => fmi3GetContinuousStateDerivatives(c, x.as_mut_ptr(), m),
                }
            }
            "fmi3DeserializeFMUState" | "fmi3SetFMUState" => {
                let mut bytes = fresh_state_bytes_of(model_of(h), h.kind);
                if rng.chance(0.5) {
                    let k = rng.below(bytes.len() as u64) as usize;
                    bytes[k] ^= 1 << rng.below(8);
                }
                if rng.chance(0.2) {
                    bytes.truncate(rng.below(bytes.len() as u64) as usize);
                }
                let mut st: fmi3FMUState = std::ptr::null_mut();
                let s = fmi3DeserializeFMUState(c, bytes.as_ptr(), bytes.len(), &mut st);
                if !st.is_null() {
                    let s2 = fmi3SetFMUState(c, st);
                    assert!((0..=4).contains(&s2));
                    fmi3FreeFMUState(c, &mut st);
                }
                s
            }
            "fmi3GetDirectionalDerivative" | "fmi3GetAdjointDerivative" => {
                let f = if function == "fmi3GetAdjointDerivative" {
                    fmi3GetAdjointDerivative
                } else {
                    fmi3GetDirectionalDerivative
                };
                f(c, vp, n, vp, n, values.as_ptr(), nv, out.as_mut_ptr(), nv)
            }
            "fmi3GetOutputDerivatives" => {
                let orders: Vec<i32> = (0..n).map(|_| rng.below(4) as i32 - 1).collect();
                fmi3GetOutputDerivatives(c, vp, n, orders.as_ptr(), out.as_mut_ptr(), nv)
            }
            "fmi3GetVariableDependencies" => {
                let k = rng.below(300) as usize;
                let (mut e, mut i, mut ie, mut kinds) =
                    (vec![0usize; k], vec![0u32; k], vec![0usize; k], vec![0i32; k]);
                let dependent = vrs.first().copied().unwrap_or(0);
                fmi3GetVariableDependencies(
                    c,
                    dependent,
                    e.as_mut_ptr(),
                    i.as_mut_ptr(),
                    ie.as_mut_ptr(),
                    kinds.as_mut_ptr(),
                    k,
                )
            }
            other => invoke(h, other),
        }
    }
}

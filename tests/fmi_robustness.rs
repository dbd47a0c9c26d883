//! Bad arguments, bad parameters and physics that cannot go on, through the exported
//! functions: each is answered with the right status and a message that says what is wrong,
//! and leaves the instance as it was.

#![allow(clippy::type_complexity)] // the case tables read best inline

use crate::common;

use common::fmi_host::Host;
use stewart_fmu::fmi2::exports::*;
use stewart_fmu::fmi2::types::*;

fn unchanged_after(h: &mut Host, call: impl FnOnce(&mut Host) -> fmi2Status) -> (fmi2Status, String) {
    let before = h.state_bytes();
    h.clear_log();
    let status = call(h);
    assert_eq!(h.state_bytes(), before, "the call changed the instance");
    (status, h.last_message())
}

#[test]
fn bad_arguments_are_refused_and_change_nothing() {
    let mut h = Host::platform("args");
    assert_eq!(h.initialise(&[]), fmi2OK);
    assert_eq!(h.step(0.1), fmi2OK);
    let vr_f1 = h.vr("F[1]");
    let vr_m = h.vr("M");
    let vr_method = h.vr("solver.method");
    let vr_stops = h.vr("stops");
    type Case = (&'static str, Box<dyn FnOnce(&mut Host) -> fmi2Status>, &'static str);
    let cases: Vec<Case> = vec![
        (
            "NULL vr array",
            Box::new(|h: &mut Host| unsafe { fmi2GetReal(h.c, std::ptr::null(), 2, [0.0f64; 4].as_mut_ptr()) }),
            "argument vr is NULL",
        ),
        (
            "NULL value array",
            Box::new(move |h: &mut Host| unsafe { fmi2SetReal(h.c, &vr_f1, 1, std::ptr::null()) }),
            "argument value is NULL",
        ),
        (
            "unknown value reference",
            Box::new(|h: &mut Host| unsafe { fmi2GetReal(h.c, &9999, 1, [0.0f64; 4].as_mut_ptr()) }),
            "value reference 9999 is not a Real",
        ),
        (
            "Integer value reference to fmi2GetReal",
            Box::new(move |h: &mut Host| unsafe { fmi2GetReal(h.c, &vr_method, 1, [0.0f64; 4].as_mut_ptr()) }),
            "not a Real variable",
        ),
        (
            "Real value reference to fmi2GetInteger",
            Box::new(move |h: &mut Host| unsafe { fmi2GetInteger(h.c, &vr_m, 1, [0i32; 4].as_mut_ptr()) }),
            "not a Integer variable",
        ),
        (
            "fixed parameter after initialisation",
            Box::new(move |h: &mut Host| unsafe { fmi2SetReal(h.c, &vr_m, 1, &1000.0) }),
            "M (fixed parameter) may not be set in state stepComplete",
        ),
        (
            "NaN input",
            Box::new(move |h: &mut Host| unsafe { fmi2SetReal(h.c, &vr_f1, 1, &f64::NAN) }),
            "F[1] = NaN refused",
        ),
        (
            "+inf input",
            Box::new(move |h: &mut Host| unsafe { fmi2SetReal(h.c, &vr_f1, 1, &f64::INFINITY) }),
            "F[1] = inf refused",
        ),
        (
            "Real value reference to fmi2GetBoolean",
            Box::new(|h: &mut Host| unsafe { fmi2GetBoolean(h.c, &1, 1, [0i32; 4].as_mut_ptr()) }),
            "F[1] of type Real, not a Boolean variable",
        ),
        (
            "Boolean value reference to fmi2GetReal",
            Box::new(move |h: &mut Host| unsafe { fmi2GetReal(h.c, &vr_stops, 1, [0.0f64; 4].as_mut_ptr()) }),
            "stops of type Boolean, not a Real variable",
        ),
        (
            "fixed Boolean parameter after initialisation",
            Box::new(move |h: &mut Host| unsafe { fmi2SetBoolean(h.c, &vr_stops, 1, &fmi2False) }),
            "stops (fixed parameter) may not be set in state stepComplete",
        ),
        (
            "zero step",
            Box::new(|h: &mut Host| unsafe { fmi2DoStep(h.c, 0.1, 0.0, 1) }),
            "communicationStepSize must be finite and > 0, got 0",
        ),
        ("negative step", Box::new(|h: &mut Host| unsafe { fmi2DoStep(h.c, 0.1, -0.01, 1) }), "got -0.01"),
        ("NaN step", Box::new(|h: &mut Host| unsafe { fmi2DoStep(h.c, 0.1, f64::NAN, 1) }), "got NaN"),
        ("infinite step", Box::new(|h: &mut Host| unsafe { fmi2DoStep(h.c, 0.1, f64::INFINITY, 1) }), "got inf"),
        (
            "wrong communication point",
            Box::new(|h: &mut Host| unsafe { fmi2DoStep(h.c, 0.3, 0.01, 1) }),
            "currentCommunicationPoint 0.3 does not match the FMU's time 0.1",
        ),
        (
            "communication point a millionth of a step off",
            Box::new(|h: &mut Host| unsafe { fmi2DoStep(h.c, 0.1 + 1e-8, 0.01, 1) }),
            "more than the round-off tolerance",
        ),
        (
            "NaN communication point",
            Box::new(|h: &mut Host| unsafe { fmi2DoStep(h.c, f64::NAN, 0.01, 1) }),
            "currentCommunicationPoint must be finite",
        ),
        (
            "input derivative of order 2",
            Box::new(move |h: &mut Host| unsafe { fmi2SetRealInputDerivatives(h.c, &vr_f1, 1, &2, &1.0) }),
            "order 2",
        ),
        (
            "output derivative of order 2",
            Box::new(|h: &mut Host| unsafe {
                fmi2GetRealOutputDerivatives(h.c, &100, 1, &2, [0.0f64; 4].as_mut_ptr())
            }),
            "maxOutputDerivativeOrder = 1",
        ),
        (
            "derivative of a parameter",
            Box::new(move |h: &mut Host| unsafe { fmi2SetRealInputDerivatives(h.c, &vr_m, 1, &1, &1.0) }),
            "M is not an input",
        ),
        (
            "NULL out-pointer",
            Box::new(|h: &mut Host| unsafe { fmi2GetRealStatus(h.c, fmi2LastSuccessfulTime, std::ptr::null_mut()) }),
            "argument value is NULL",
        ),
        (
            "unknown log category",
            Box::new(|h: &mut Host| unsafe { fmi2SetDebugLogging(h.c, 1, 1, [c"logNothing".as_ptr()].as_ptr()) }),
            "unknown log category \"logNothing\"",
        ),
        (
            "NULL FMU state",
            Box::new(|h: &mut Host| unsafe { fmi2SetFMUstate(h.c, std::ptr::null_mut()) }),
            "FMUstate is NULL",
        ),
    ];
    for (name, call, fragment) in cases {
        let (status, message) = unchanged_after(&mut h, call);
        println!("{name:>40} -> {} : {message}", status_name(status));
        assert_eq!(status, fmi2Error, "{name}");
        assert!(message.contains(fragment), "{name}: message {message:?} lacks {fragment:?}");
    }
    // The instance still works after all that.
    assert_eq!(h.step(0.1), fmi2OK);
    // Round-off in the communication point, as accumulating masters produce, is tolerated.
    let t = h.time + 1e-15;
    assert_eq!(unsafe { fmi2DoStep(h.c, t, 0.1, 1) }, fmi2OK);
}

#[test]
fn non_finite_parameters_and_bad_enumerations_are_refused_when_set() {
    let mut h = Host::platform("set");
    h.setup(None);
    h.enter();
    let vr_method = h.vr("solver.method");
    for (name, value) in [("M", f64::NAN), ("J[2]", f64::INFINITY), ("B[3,1]", f64::NEG_INFINITY), ("r0[3]", f64::NAN)]
    {
        let (status, message) = unchanged_after(&mut h, |h| h.set(name, value));
        assert_eq!(status, fmi2Error);
        assert!(message.contains(name) && message.contains("must be finite"), "{message}");
    }
    let (status, message) = unchanged_after(&mut h, |h| unsafe { fmi2SetInteger(h.c, &vr_method, 1, &7) });
    assert_eq!(status, fmi2Error);
    assert!(message.contains("7 is not a method"), "{message}");
    assert_eq!(h.exit(), fmi2OK);
}

#[test]
fn stepping_past_the_stop_time_is_an_error() {
    let mut h = Host::platform("stop");
    h.setup(Some(0.05));
    h.enter();
    assert_eq!(h.exit(), fmi2OK);
    assert_eq!(h.step(0.05), fmi2OK);
    let (status, message) = unchanged_after(&mut h, |h| h.step(0.01));
    assert_eq!(status, fmi2Error);
    assert!(message.contains("past the stopTime 0.05"), "{message}");
}

/// Each invalid parameter and the message fragment that must name it.
#[test]
fn bad_parameter_sets_are_refused_at_exit_initialization_mode() {
    let b1 = [1.5 * (-10f64).to_radians().cos(), 1.5 * (-10f64).to_radians().sin(), 0.0];
    let a1 = [(-50f64).to_radians().cos(), (-50f64).to_radians().sin(), -0.5];
    let table: Vec<(&str, Vec<(&str, f64)>, &str)> = vec![
        ("zero mass", vec![("M", 0.0)], "parameter M: mass must be positive"),
        ("negative mass", vec![("M", -3000.0)], "parameter M: mass must be positive"),
        ("zero moment of inertia", vec![("J[1]", 0.0)], "parameter J[1]: moment of inertia must be positive"),
        ("negative moment of inertia", vec![("J[2]", -1.0)], "parameter J[2]: moment of inertia must be positive"),
        (
            "triangle inequality",
            vec![("J[3]", 3100.0)],
            "parameter J[3]: moments of inertia violate the strict triangle inequality",
        ),
        (
            "thin plate J3 = J1 + J2",
            vec![("J[3]", 3000.0)],
            "a thin plate) has exactly these moments, but then the paper's second moment I3",
        ),
        (
            "triangle inequality, other axis",
            vec![("J[1]", 3700.0)],
            "parameter J[1]: moments of inertia violate the strict triangle inequality",
        ),
        ("negative gravity", vec![("g", -9.81)], "parameter g: gravity must be >= 0"),
        (
            "coincident base joints",
            vec![("B[2,1]", b1[0]), ("B[2,2]", b1[1]), ("B[2,3]", b1[2])],
            "joints B[1] and B[2] coincide",
        ),
        (
            "coincident platform joints",
            vec![("A[4,1]", a1[0]), ("A[4,2]", a1[1]), ("A[4,3]", a1[2])],
            "joints A[1] and A[4] coincide",
        ),
        (
            "zero-length leg",
            vec![("r0[1]", b1[0] - a1[0]), ("r0[2]", b1[1] - a1[1]), ("r0[3]", b1[2] - a1[2])],
            "leg 1 has zero length",
        ),
        (
            "singular initial pose (yaw 90 degrees) with stopAtSingularity",
            vec![
                ("stops", 0.0),
                ("joints", 0.0),
                ("stopAtSingularity", 1.0),
                ("angles0[3]", std::f64::consts::FRAC_PI_2),
            ],
            "the initial pose is a singular leg arrangement",
        ),
        ("initial pose outside the stroke", vec![("r0[3]", 1.5)], "parameter r0: in the initial pose leg 1 has length"),
        ("initial pose above the stroke", vec![("lmax[4]", 1.7)], "above its stroke limit lmax[4] = 1.7 m"),
        ("empty stroke", vec![("lmin[2]", 2.2)], "parameter lmin[2]: the stroke is empty"),
        ("zero shortest leg", vec![("lmin[6]", 0.0)], "parameter lmin[6]: the shortest leg length must be positive"),
        (
            "zero stop stiffness",
            vec![("stops.stiffness", 0.0)],
            "parameter stops.stiffness: the stop stiffness must be positive",
        ),
        (
            "negative stop damping",
            vec![("stops.damping", -1.0)],
            "parameter stops.damping: the contact damping must be >= 0",
        ),
        (
            "platform joints on the base plane",
            vec![("stops", 0.0), ("joints", 0.0), ("r0[3]", 0.5)],
            "on or across the base plane",
        ),
        (
            "platform joints across the base plane",
            vec![("stops", 0.0), ("joints", 0.0), ("r0[3]", 0.6), ("angles0[1]", 0.5)],
            "on or across the base plane",
        ),
        ("zero relative tolerance", vec![("solver.relTol", 0.0)], "parameter solver.relTol: must be in (0, 1)"),
        ("tolerance below precision", vec![("solver.relTol", 1e-17)], "below what double precision can meet"),
        ("negative absolute tolerance", vec![("solver.absTol", -1e-9)], "parameter solver.absTol: must be > 0"),
        ("zero absolute tolerance", vec![("solver.absTol", 0.0)], "exactly zero (the neutral pose has several)"),
        ("negative maximum step", vec![("solver.maxStep", -0.1)], "parameter solver.maxStep"),
        ("negative RK4 step", vec![("solver.fixedStep", -1e-3)], "parameter solver.fixedStep"),
        (
            "RK4 step below a nanosecond",
            vec![("solver.fixedStep", 1e-300)],
            "parameter solver.fixedStep: must be 0 (one RK4 step per communication step) or at least 1e-9 s, got 1e-300",
        ),
    ];
    for (name, values, fragment) in table {
        let mut h = Host::platform("params");
        h.setup(None);
        h.enter();
        for (n, v) in &values {
            assert_eq!(h.set(n, *v), fmi2OK, "{name}: set {n}");
        }
        h.clear_log();
        let status = h.exit();
        let message = h.last_message();
        println!("{name:>40} -> {} : {message}", status_name(status));
        assert_eq!(status, fmi2Error, "{name}");
        assert!(message.contains(fragment), "{name}: {message:?} lacks {fragment:?}");
        // The error state: only the allowed calls work; reset brings the start values back.
        assert_eq!(h.step(0.01), fmi2Error);
        assert_eq!(unsafe { fmi2Reset(h.c) }, fmi2OK);
        assert_eq!(h.initialise(&[]), fmi2OK);
    }
    // The singular pose reports its condition number; without stopAtSingularity it is a
    // pose like any other.
    let mut h = Host::platform("cond");
    h.setup(None);
    h.enter();
    for (n, v) in
        [("stops", 0.0), ("joints", 0.0), ("stopAtSingularity", 1.0), ("angles0[3]", std::f64::consts::FRAC_PI_2)]
    {
        h.set(n, v);
    }
    h.exit();
    assert!(h.last_message().contains("condition number"), "{}", h.last_message());
    let mut h = Host::platform("singular start");
    assert_eq!(h.initialise(&[("stops", 0.0), ("joints", 0.0), ("angles0[3]", std::f64::consts::FRAC_PI_2)]), fmi2OK);
    assert!(h.get("kappa") > 1e8, "kappa {}", h.get("kappa"));
}

/// Physics that cannot go on: the step is rolled back, fmi2Discard, the status functions
/// answer, outputs stay finite and equal to those before the step.
#[test]
fn impossible_motions_are_discarded_with_roll_back() {
    let cases: Vec<(&str, Vec<(&str, f64)>, [f64; 6], f64, &str)> = vec![
        // Without end stops nothing stops the legs; with them, see the workspace tests.
        (
            "platform pulled through the base",
            vec![("stops", 0.0), ("joints", 0.0)],
            [-1.0e6; 6],
            1.0,
            "passed through the base plane",
        ),
        (
            "platform turned through a singular yaw, stopAtSingularity",
            vec![
                ("stops", 0.0),
                ("joints", 0.0),
                ("stopAtSingularity", 1.0),
                ("g", 0.0),
                ("angles0[3]", 1.35),
                ("w0[3]", 1.0),
            ],
            [0.0; 6],
            0.5,
            "passed through a singular arrangement",
        ),
        ("forces beyond any scale", vec![], [1e300, -1e300, 1e300, -1e300, 1e300, -1e300], 0.1, "rolled back"),
    ];
    for (name, params, forces, h_step, fragment) in cases {
        let mut h = Host::platform("discard");
        assert_eq!(h.initialise(&params), fmi2OK, "{name}");
        assert_eq!(h.step(0.01), fmi2OK);
        let before = h.all_reals();
        h.set_forces(forces);
        h.clear_log();
        let status = h.step(h_step);
        let message = h.last_message();
        println!("{name:>36} -> {} : {message}", status_name(status));
        assert_eq!(status, fmi2Discard, "{name}");
        assert!(message.contains(fragment) && message.contains("rolled back"), "{name}: {message}");
        let mut last = f64::NAN;
        let mut terminated = 0;
        unsafe {
            assert_eq!(fmi2GetRealStatus(h.c, fmi2LastSuccessfulTime, &mut last), fmi2OK);
            assert_eq!(fmi2GetBooleanStatus(h.c, fmi2Terminated, &mut terminated), fmi2OK);
        }
        assert_eq!(last, 0.01, "{name}: last successful time");
        assert_eq!(terminated, fmi2True);
        // Outputs (and everything else) as before the step, apart from the new force inputs
        // and what they determine directly (the accelerations der(v), der(R,2), the power
        // der(work.F), the joints' forces jointForce and the actuators' actuatorForce).
        let after = h.all_reals();
        let f_vrs: Vec<u32> =
            (1..=6).chain(140..=142).chain(152..=160).chain([210]).chain(352..=369).chain(450..=455).collect();
        let real_vrs: Vec<u32> = h
            .table
            .elements()
            .filter(|(_, g, _)| g.var_type.is_real() && !g.fmi3_only)
            .map(|(_, g, i)| g.vr(i))
            .collect();
        for ((vr, a), b) in real_vrs.iter().zip(&after).zip(&before) {
            if !f_vrs.contains(vr) {
                assert_eq!(a, b, "{name}: value reference {vr} changed");
                assert!(f64::from_bits(*a).is_finite());
            }
        }
        assert_eq!(unsafe { fmi2Terminate(h.c) }, fmi2OK);
    }
}

/// An instance stays usable after refusing a state that is not its own or is damaged.
#[test]
fn foreign_state_handles_and_bytes_are_refused() {
    let mut h = Host::platform("state");
    assert_eq!(h.initialise(&[]), fmi2OK);
    let mut bytes = h.state_bytes();
    let before = h.state_bytes();
    for i in [0usize, 9, 13, 40, bytes.len() / 2, bytes.len() - 1] {
        bytes[i] ^= 0x20;
        assert_eq!(h.restore_bytes(&bytes), fmi2Error, "flipped byte {i}");
        bytes[i] ^= 0x20;
    }
    assert_eq!(h.restore_bytes(&bytes[..bytes.len() - 3]), fmi2Error);
    assert_eq!(h.state_bytes(), before);
    assert_eq!(h.restore_bytes(&bytes), fmi2OK);
    // A handle that is not ours.
    let mut fake = [0u64; 4];
    assert_eq!(unsafe { fmi2SetFMUstate(h.c, fake.as_mut_ptr() as fmi2FMUstate) }, fmi2Error);
    let mut fake_ptr = fake.as_mut_ptr() as fmi2FMUstate;
    assert_eq!(unsafe { fmi2FreeFMUstate(h.c, &mut fake_ptr) }, fmi2Error);
}

/// Handles are recognised by address, never by reading through them: a state is freed only by
/// the instance that made it (the controller cannot free the platform's), a stale instance
/// handle is refused, and states left over are freed with their instance.
#[test]
fn states_belong_to_their_instance_and_stale_handles_are_refused() {
    let mut platform = Host::platform("owner");
    assert_eq!(platform.initialise(&[]), fmi2OK);
    let controller = Host::new("thief", stewart_fmu::models::ModelKind::Controller);
    let mut st: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(unsafe { fmi2GetFMUstate(platform.c, &mut st) }, fmi2OK);
    let kept = st;
    assert_eq!(unsafe { fmi2FreeFMUstate(controller.c, &mut st) }, fmi2Error);
    assert_eq!(st, kept, "the refused call leaves the handle alone");
    assert!(
        controller.last_message().contains("not a live FMU state of this instance"),
        "{}",
        controller.last_message()
    );
    assert_eq!(unsafe { fmi2SetFMUstate(controller.c, st) }, fmi2Error);
    // The owner can use and free it; afterwards the handle is stale for the owner too.
    assert_eq!(unsafe { fmi2SetFMUstate(platform.c, st) }, fmi2OK);
    assert_eq!(unsafe { fmi2FreeFMUstate(platform.c, &mut st) }, fmi2OK);
    assert!(st.is_null());
    assert_eq!(unsafe { fmi2SetFMUstate(platform.c, kept) }, fmi2Error);
    // A state not freed by the importer goes with its instance; the instance handle is then
    // stale: refused by every function, and freeing it again does nothing.
    let mut left: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(unsafe { fmi2GetFMUstate(platform.c, &mut left) }, fmi2OK);
    let c = platform.c;
    unsafe { fmi2FreeInstance(c) };
    assert_eq!(unsafe { fmi2DoStep(c, 0.0, 0.01, fmi2True) }, fmi2Error);
    assert_eq!(unsafe { fmi2SetFMUstate(c, left) }, fmi2Error);
    unsafe { fmi2FreeInstance(c) };
    drop(platform); // frees the handle a third time: nothing happens
}

/// The instance name reaches the logger unchanged in every message (it is an argument, not part
/// of the `%`-escaped format string), from instantiation failures to step messages.
#[test]
fn the_instance_name_is_passed_verbatim_in_every_message() {
    let name = "cab%d 100%";
    let mut h = Host::platform(name);
    h.setup(None);
    h.enter();
    h.set("M", -1.0);
    assert_eq!(h.exit(), fmi2Error);
    unsafe { fmi2SetDebugLogging(h.c, fmi2True, 0, std::ptr::null()) };
    assert_eq!(unsafe { fmi2Reset(h.c) }, fmi2OK);
    let sink = std::sync::Mutex::new(vec![]);
    let cb = common::fmi_host::callbacks(&sink);
    let cname = std::ffi::CString::new(name).unwrap();
    let c =
        unsafe { fmi2Instantiate(cname.as_ptr(), fmi2CoSimulation, c"{wrong}".as_ptr(), std::ptr::null(), &cb, 0, 1) };
    assert!(c.is_null());
    let mut lines = h.messages();
    lines.extend(sink.lock().unwrap().iter().cloned());
    assert!(lines.len() >= 3, "{lines:?}");
    for line in &lines {
        assert_eq!(line.instance, name, "{line:?}");
    }
}

/// Solver limits are stated with the real numbers: a tolerance the importer passes is named as
/// such; an RK4 step so small that a communication step needs more internal steps than the
/// limit per call is refused before anything is computed, as a discard the importer can
/// recover from with shorter steps.
#[test]
fn solver_limits_are_reported_with_their_numbers_and_are_recoverable() {
    let mut h = Host::platform("tolerance");
    unsafe { fmi2SetupExperiment(h.c, fmi2True, 1e-17, 0.0, fmi2False, 0.0) };
    h.enter();
    h.clear_log();
    assert_eq!(h.exit(), fmi2Error);
    let message = h.last_message();
    assert!(message.contains("the importer's tolerance") && message.contains("1e-17"), "{message}");
    assert!(!message.contains("parameter solver.relTol"), "{message}");

    let mut h = Host::platform("rk4");
    assert_eq!(h.initialise(&[("solver.method", 2.0), ("solver.fixedStep", 2e-9)]), fmi2OK);
    assert_eq!(h.step(0.001), fmi2OK, "5e5 RK4 steps: within the limit");
    h.clear_log();
    assert_eq!(h.step(0.01), fmi2Discard);
    let message = h.last_message();
    println!("{message}");
    assert!(
        message.contains("needs 5.000e6 steps, more than the limit of 1000000 internal steps per call"),
        "{message}"
    );
    assert!(message.contains("nothing was computed") && message.contains("retry from t = 0.001"), "{message}");
    let mut terminated = fmi2True;
    unsafe { fmi2GetBooleanStatus(h.c, fmi2Terminated, &mut terminated) };
    assert_eq!(terminated, fmi2False, "shorter steps can go on");
}

/// `currentCommunicationPoint` is compared with the FMU's time to round-off of the time and the
/// step: at t = 1e-12 a communication point of 9e-10 is a jump of the clock, refused.
#[test]
fn the_communication_point_tolerance_scales_with_time_and_step() {
    let mut h = Host::platform("clock");
    assert_eq!(h.initialise(&[]), fmi2OK);
    assert_eq!(h.step(1e-12), fmi2OK);
    assert_eq!(unsafe { fmi2DoStep(h.c, 9e-10, 1e-12, fmi2True) }, fmi2Error);
    assert!(
        h.last_message().contains("(difference 8.99e-10, more than the round-off tolerance"),
        "{}",
        h.last_message()
    );
    // A master that multiplies (t = n h) instead of adding meets the FMU's time to an ulp.
    let mut h = Host::platform("multiplying");
    assert_eq!(h.initialise(&[]), fmi2OK);
    for n in 0..1000 {
        let t = n as f64 * 0.001;
        assert_eq!(unsafe { fmi2DoStep(h.c, t, 0.001, fmi2True) }, fmi2OK, "n = {n}: {}", h.last_message());
    }
}

/// A platform whose joints all start below the base hangs under it: legal (a suspended
/// hexapod), but with the default stand a mistyped height, so the importer gets a warning.
#[test]
fn a_platform_starting_below_its_base_is_warned_about() {
    let mut h = Host::platform("below");
    h.setup(None);
    h.enter();
    h.set("stops", 0.0);
    h.set("joints", 0.0);
    h.set("r0[3]", 0.25);
    h.clear_log();
    assert_eq!(h.exit(), fmi2Warning);
    let warning = h.last_message();
    assert!(warning.contains("all platform joints start below the base plane") && warning.contains("r0[3] = 0.25"));
    assert_eq!(h.messages().last().map(|l| l.category.clone()), Some("logStatusWarning".into()));
    assert_eq!(h.step(0.01), fmi2OK, "the instance is usable");
}

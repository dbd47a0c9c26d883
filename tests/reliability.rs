//! Reliability III (the FMI boundary's edge cases, items 1 and 8): the controller at start
//! times far from zero, extreme parameter and input values, and messages that name the cause
//! (the parameter or input at fault, the integrator's instability), numbers in scientific
//! notation, and no output infinite with OK.

use crate::common;

use std::sync::mpsc;
use std::time::Duration;

use common::fmi_host::Host;
use stewart_fmu::fmi2::exports::*;
use stewart_fmu::fmi2::types::*;
use stewart_fmu::models::ModelKind;

/// Runs `f` on its own thread and fails the test if it does not return within `seconds`
/// (a host waiting for ever is the failure to catch).
fn within<T: Send + 'static>(seconds: u64, what: &str, f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(seconds)).unwrap_or_else(|_| panic!("{what}: no answer within {seconds} s"))
}

fn controller_at(start: f64) -> (fmi2Status, String, Option<f64>) {
    let mut h = Host::new("controller", ModelKind::Controller);
    let s = unsafe { fmi2SetupExperiment(h.c, fmi2False, 0.0, start, fmi2False, 0.0) };
    assert_eq!(s, fmi2OK);
    assert_eq!(h.enter(), fmi2OK);
    let status = h.exit();
    let force = (status == fmi2OK).then(|| h.get("F[1]"));
    (status, h.last_message(), force)
}

/// Item 1: the controller initialises at start times long before 0 (its soft-started programme
/// rests there) with the programme's static forces, at once; a start time where a double no
/// longer resolves the communication points is refused with the reason, never iterated on.
#[test]
fn the_controller_starts_far_from_zero_or_says_why_not() {
    let equilibrium = 0.2005 * 3000.0 * 9.81;
    for start in [-100.0, -500.0, -1e6, -8e9] {
        let (status, message, force) = within(20, &format!("start time {start}"), move || controller_at(start));
        let force = force.unwrap_or(f64::NAN);
        println!("controller from t = {start:e}: {status}, F[1] = {force} N");
        assert_eq!(status, fmi2OK, "{message}");
        assert!((force - equilibrium).abs() < 1e-6 * equilibrium, "{force}");
    }
    for start in [-1e300, 1e300, 1e10] {
        let (status, message, _) = within(20, &format!("start time {start}"), move || controller_at(start));
        println!("controller from t = {start:e}: {status}: {message}");
        assert_eq!(status, fmi2Error);
        assert!(message.contains("startTime") && message.contains("resolves only"), "{message}");
        assert!(!message.contains(&"0".repeat(30)), "numbers in scientific notation: {message}");
    }
}

/// Item 8: extreme values are refused naming the parameter at fault, in scientific notation.
#[test]
fn extreme_parameters_are_refused_naming_themselves() {
    for (model, name, value, expected) in [
        (ModelKind::Controller, "A[1,1]", 1e300, "A[1,1]"),
        (ModelKind::Platform, "A[2,3]", -1e300, "A[2,3]"),
        (ModelKind::Platform, "B[4,1]", 1e12, "B[4,1]"),
        (ModelKind::Platform, "M", -1e300, "parameter M"),
        (ModelKind::Controller, "heave.frequency", 1e300, "heave.frequency"),
    ] {
        let mut h = Host::new("extreme", model);
        let status = h.initialise(&[(name, value)]);
        let message = h.last_message();
        println!("{name} = {value:e}: {status}: {message}");
        assert_eq!(status, fmi2Error, "{message}");
        assert!(message.contains(expected), "{message}");
        assert!(!message.contains("coincide"), "the wrong cause: {message}");
        assert!(!message.contains(&"0".repeat(30)), "a number in 300 digits: {message}");
    }
}

/// Item 8: an input that makes the programme impossible is named as the input when an output
/// is read, not blamed on the parameters.
#[test]
fn an_impossible_pose_input_is_named_as_the_input() {
    let mut h = Host::new("external", ModelKind::Controller);
    assert_eq!(h.initialise(&[("programme", 3.0)]), fmi2OK);
    assert_eq!(h.set("pose.r[1]", 1e300), fmi2OK);
    let vr = h.vr("F[1]");
    let mut x = 0.0;
    let status = unsafe { fmi2GetReal(h.c, &vr, 1, &mut x) };
    let message = h.last_message();
    println!("pose.r[1] = 1e300, read F[1]: {status}: {message}");
    assert_eq!(status, fmi2Error);
    assert!(message.contains("inputs pose.*") && message.contains("1e300"), "{message}");
    assert!(!message.contains("current parameters"), "{message}");
}

/// Item 8: kappa at a singular leg arrangement is a finite bound (1/eps), with OK: every leg
/// vertical (the six force lines parallel), so the force/moment matrix has rank 3.
#[test]
fn kappa_at_a_singular_arrangement_is_finite() {
    let mut h = Host::platform("singular");
    let mut values = vec![];
    // Each base joint under its platform joint (the default stand's: radius 1 m, docs/model.md §3).
    for (k, azimuth) in [-50.0f64, 50.0, 70.0, 170.0, 190.0, 290.0].into_iter().enumerate() {
        let (s, c) = azimuth.to_radians().sin_cos();
        values.push((format!("B[{},1]", k + 1), c));
        values.push((format!("B[{},2]", k + 1), s));
    }
    let pairs: Vec<(&str, f64)> = values.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    let mut all = pairs.clone();
    all.push(("stops", 0.0));
    all.push(("joints", 0.0));
    assert_eq!(h.initialise(&all), fmi2OK, "{}", h.last_message());
    let vr = h.vr("kappa");
    let mut kappa = 0.0;
    let status = unsafe { fmi2GetReal(h.c, &vr, 1, &mut kappa) };
    println!("every leg vertical: kappa = {kappa:e} ({status})");
    assert_eq!(status, fmi2OK);
    assert!(kappa.is_finite() && kappa >= 1e15, "{kappa}");
}

/// Item 8: RK4 with end stops too stiff for its step: the discard says the integrator's
/// instability is the likely cause, with the contact's period against the step.
#[test]
fn an_rk4_step_too_long_for_stiff_stops_is_named_as_the_cause() {
    let mut h = Host::platform("stiff");
    assert_eq!(h.initialise(&[("solver.method", 2.0), ("stops.stiffness", 1e15)]), fmi2OK);
    let mut status = fmi2OK;
    for _ in 0..2000 {
        assert_eq!(h.set_forces([0.0; 6]), fmi2OK);
        status = h.step(1e-3);
        if status != fmi2OK {
            break;
        }
    }
    let message = h.messages().iter().rev().find(|l| l.status != fmi2OK).map(|l| l.message.clone()).unwrap_or_default();
    println!("RK4 at 1 ms on stops of 1e15 N/m: {status}: {message}");
    assert_eq!(status, fmi2Discard);
    assert!(message.contains("RK4's instability") && message.contains("contact period"), "{message}");
    assert!(message.contains("solver.fixedStep below"), "{message}");
}

/// Item 8: Model Exchange under an explicit integrator whose steps are too long for the stops
/// (fmusim's default: explicit Euler at 10 ms): the fault names the host's step and the stops'
/// contact period.
#[test]
fn model_exchange_steps_too_long_for_the_stops_are_named() {
    let mut h = Host::with_interface("me", ModelKind::Platform, fmi2ModelExchange);
    assert_eq!(h.initialise(&[]), fmi2OK);
    assert_eq!(h.set_forces([0.0; 6]), fmi2OK);
    let n = stewart_fmu::simulation::SIMULATION_DIM;
    let (mut x, mut dx) = (vec![0.0; n], vec![0.0; n]);
    unsafe {
        let mut info = fmi2EventInfo::default();
        assert_eq!(fmi2NewDiscreteStates(h.c, &mut info), fmi2OK);
        assert_eq!(fmi2EnterContinuousTimeMode(h.c), fmi2OK);
        assert_eq!(fmi2GetContinuousStates(h.c, x.as_mut_ptr(), n), fmi2OK);
    }
    let (mut status, mut t, step) = (fmi2OK, 0.0, 0.01);
    for _ in 0..1000 {
        unsafe {
            status = fmi2GetDerivatives(h.c, dx.as_mut_ptr(), n);
            if status != fmi2OK {
                break;
            }
            t += step;
            for i in 0..n {
                x[i] += step * dx[i];
            }
            status = fmi2SetTime(h.c, t);
            if status == fmi2OK {
                status = fmi2SetContinuousStates(h.c, x.as_ptr(), n);
            }
            if status != fmi2OK {
                break;
            }
            let (mut enter, mut terminate) = (fmi2False, fmi2False);
            status = fmi2CompletedIntegratorStep(h.c, fmi2True, &mut enter, &mut terminate);
            if status != fmi2OK {
                break;
            }
        }
    }
    let message = h.messages().iter().rev().find(|l| l.status != fmi2OK).map(|l| l.message.clone()).unwrap_or_default();
    println!("explicit Euler at 10 ms in Model Exchange, forces 0: {status} at t = {t}: {message}");
    assert_ne!(status, fmi2OK);
    assert!(message.contains("steps 1.000e-2 s") && message.contains("end stops' contact period"), "{message}");
}

/// The fuzz of item 8's kind over the controller: random start times and random values (huge,
/// tiny, negative, zero, not numbers) of random parameters and inputs, then a few steps and
/// reads. Every case answers within its time limit, without a panic; every refusal has a
/// message that names something and prints no 300-digit number.
#[test]
fn the_controller_answers_every_random_setting_with_a_status_and_a_reason() {
    use common::rng::Rng;
    let specials = [0.0, -0.0, 1e300, -1e300, 1e-300, f64::NAN, f64::INFINITY, -1.0, 1e9, -1e9, 0.5, 2.0];
    let table = stewart_fmu::models::variables::VariableTable::new(ModelKind::Controller.info().groups);
    let names: Vec<String> = table
        .elements()
        .filter(|(_, g, _)| {
            !matches!(g.causality, stewart_fmu::models::variables::Causality::Output) && g.name != "time"
        })
        .map(|(_, g, i)| g.element_name(i))
        .collect();
    let mut rng = Rng(0x0123_4567_89ab_cdef);
    let (mut refused, mut ran) = (0, 0);
    for case in 0..300 {
        let start = if rng.chance(0.3) { rng.real(&specials, 20) * 1e3 } else { 0.0 };
        let settings: Vec<(String, f64)> = (0..1 + rng.below(4))
            .map(|_| (names[rng.below(names.len() as u64) as usize].clone(), rng.real(&specials, 24)))
            .collect();
        let inputs: Vec<f64> = (0..6).map(|_| rng.real(&specials, 40) * 1e-4).collect();
        let (outcome, messages) = within(20, &format!("case {case}"), move || {
            let mut h = Host::new("fuzz", ModelKind::Controller);
            unsafe { fmi2SetupExperiment(h.c, fmi2False, 0.0, start, fmi2False, 0.0) };
            h.enter();
            for (n, v) in &settings {
                h.set(n, *v);
            }
            let mut outcome = h.exit();
            if outcome == fmi2OK {
                h.time = start;
                for _ in 0..3 {
                    let l: Vec<f64> = inputs.iter().map(|x| 1.755 + x).collect();
                    let names: Vec<String> = (1..=6).map(|k| format!("l[{k}]")).collect();
                    let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
                    h.set_many(&names, &l);
                    outcome = outcome.max(h.step(1e-3));
                    let vr = h.vr("F[1]");
                    let mut x = 0.0;
                    outcome = outcome.max(unsafe { fmi2GetReal(h.c, &vr, 1, &mut x) });
                }
            }
            (outcome, h.messages())
        });
        for line in &messages {
            assert!(
                line.category != "logStatusFatal" && !line.message.contains("panic"),
                "case {case}: {}",
                line.message
            );
            assert!(!line.message.contains(&"0".repeat(30)), "case {case}: a 300-digit number: {}", line.message);
        }
        if outcome == fmi2OK {
            ran += 1;
        } else {
            refused += 1;
            let last = messages.iter().rev().find(|l| l.status != fmi2OK).expect("a refusal has a message");
            assert!(last.message.len() > 20, "case {case}: {}", last.message);
        }
    }
    println!("controller fuzz: 300 cases, {ran} ran, {refused} refused with a message, none hung or panicked");
    assert!(ran > 20 && refused > 20, "both kinds exercised: {ran} ran, {refused} refused");
}

/// The same fuzz over the cueing FMU in both methods: random start times, random values of
/// random parameters and inputs (huge, tiny, negative, zero, not numbers), random
/// communication steps (1e308 among them), then steps and reads. Every case answers within
/// its time limit, without a panic; every refusal has a message that names something. A
/// step the FMU cannot finish in bounded time is refused with a message (it cuts a step into
/// sub-steps of at most solver.maxStep and solves every mpc.period).
#[test]
fn the_cueing_fmu_answers_every_random_setting_with_a_status_and_a_reason() {
    use common::rng::Rng;
    let specials = [0.0, -0.0, 1e300, -1e300, 1e-300, f64::NAN, f64::INFINITY, -1.0, 1e9, -1e9, 0.5, 2.0];
    let steps = [1e-3, 1e-2, 0.5, 1e308, 1e6, 1e-9];
    let table = stewart_fmu::models::variables::VariableTable::new(ModelKind::Cueing.info().groups);
    let names: Vec<String> = table
        .elements()
        .filter(|(_, g, _)| {
            matches!(
                g.causality,
                stewart_fmu::models::variables::Causality::Parameter | stewart_fmu::models::variables::Causality::Input
            ) && g.var_type.is_real()
        })
        .map(|(_, g, i)| g.element_name(i))
        .collect();
    let mut rng = Rng(0x0fed_cba9_8765_4321);
    let (mut refused, mut ran, mut long_steps_refused) = (0, 0, 0);
    for case in 0..300 {
        let method = case % 2;
        let start = if rng.chance(0.2) { rng.real(&specials, 20) * 1e3 } else { 0.0 };
        let settings: Vec<(String, f64)> = (0..rng.below(4))
            .map(|_| (names[rng.below(names.len() as u64) as usize].clone(), rng.real(&specials, 24)))
            .collect();
        let h_step = steps[rng.below(steps.len() as u64) as usize];
        let inputs: Vec<f64> = (0..6).map(|_| rng.real(&specials, 6)).collect();
        let (outcome, messages, step_status) = within(20, &format!("case {case}"), move || {
            let mut h = Host::new("fuzz", ModelKind::Cueing);
            unsafe { fmi2SetupExperiment(h.c, fmi2False, 0.0, start, fmi2False, 0.0) };
            h.enter();
            let vr = h.vr("cueing.method");
            unsafe { fmi2SetInteger(h.c, &vr, 1, &method) };
            for (n, v) in &settings {
                h.set(n, *v);
            }
            let mut outcome = h.exit();
            let mut step_status = fmi2OK;
            if outcome == fmi2OK {
                h.time = start;
                for i in 0..3 {
                    let names = ["f[1]", "f[2]", "f[3]", "omega[1]", "omega[2]", "omega[3]"];
                    let values: Vec<f64> = (0..6).map(|k| inputs[k] + if k == 2 { 9.81 } else { 0.0 }).collect();
                    h.set_many(&names, &values);
                    let s = h.step(if i == 1 { h_step } else { 1e-3 });
                    if i == 1 {
                        step_status = s;
                    }
                    outcome = outcome.max(s);
                    if s != fmi2OK {
                        break;
                    }
                    let vr = h.vr("pose.r[1]");
                    let mut x = 0.0;
                    outcome = outcome.max(unsafe { fmi2GetReal(h.c, &vr, 1, &mut x) });
                }
            }
            (outcome, h.messages(), step_status)
        });
        for line in &messages {
            assert!(
                line.category != "logStatusFatal" && !line.message.contains("panic"),
                "case {case}: {}",
                line.message
            );
            assert!(!line.message.contains(&"0".repeat(30)), "case {case}: a 300-digit number: {}", line.message);
        }
        if h_step >= 1e6 && step_status != fmi2OK {
            long_steps_refused += 1;
            let last = messages.iter().rev().find(|l| l.status != fmi2OK).expect("a refusal has a message");
            assert!(last.message.contains("internal steps") || last.message.contains("stopTime"), "{}", last.message);
        }
        if outcome == fmi2OK {
            ran += 1;
        } else {
            refused += 1;
            let last = messages.iter().rev().find(|l| l.status != fmi2OK).expect("a refusal has a message");
            assert!(last.message.len() > 20, "case {case}: {}", last.message);
        }
    }
    println!(
        "cueing fuzz: 300 cases (both methods), {ran} ran, {refused} refused with a message ({long_steps_refused} \
         steps of 1e6 s or more among them), none hung or panicked"
    );
    assert!(ran > 20 && refused > 20 && long_steps_refused > 5, "{ran} ran, {refused} refused, {long_steps_refused}");
}

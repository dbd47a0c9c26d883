//! Reads and writes of runs of consecutive elements (the co-simulation cycle's six forces
//! and twelve leg values, each one call that copies): they give what element-by-element
//! calls give, the leg lengths match the geometry of the pose the FMU reports, and the
//! cached values follow every change of the model (steps, parameters) but not a change of
//! an input they do not depend on.

use crate::common;

use common::fmi_host::Host;
use common::fmi3_host::{Host3, Kind};
use stewart_fmu::fmi2::exports::fmi2GetReal;
use stewart_fmu::fmi2::types::*;
use stewart_fmu::fmi3::exports::fmi3GetFloat64;
use stewart_fmu::fmi3::types::*;

fn vrs(h: &Host, names: &[String]) -> Vec<u32> {
    names.iter().map(|n| h.vr(n)).collect()
}

/// One `fmi2GetReal` of all `names`.
fn read(h: &Host, names: &[String]) -> Vec<f64> {
    let vrs = vrs(h, names);
    let mut out = vec![f64::NAN; vrs.len()];
    assert_eq!(unsafe { fmi2GetReal(h.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) }, fmi2OK);
    out
}

fn legs() -> Vec<String> {
    (1..=6).map(|k| format!("l[{k}]")).chain((1..=6).map(|k| format!("ldot[{k}]"))).collect()
}

/// `|r + R A_k - B_k|` from the pose outputs and the joint parameters, each read alone.
fn geometric_lengths(h: &Host) -> Vec<f64> {
    let r: Vec<f64> = (1..=3).map(|i| h.get(&format!("r[{i}]"))).collect();
    (1..=6)
        .map(|k| {
            let d: Vec<f64> = (1..=3)
                .map(|a| {
                    let arm: f64 = (1..=3).map(|b| h.get(&format!("R[{a},{b}]")) * h.get(&format!("A[{k},{b}]"))).sum();
                    r[a - 1] + arm - h.get(&format!("B[{k},{a}]"))
                })
                .collect();
            d.iter().map(|x| x * x).sum::<f64>().sqrt()
        })
        .collect()
}

fn assert_lengths_match_the_pose(h: &Host, what: &str) -> Vec<f64> {
    let l = read(h, &legs());
    let geometry = geometric_lengths(h);
    let worst = l.iter().zip(&geometry).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    println!("{what}: l = {:?}, largest difference from the pose's geometry {worst:.1e} m", &l[..6]);
    assert!(worst < 1e-12, "{what}: {worst}");
    l
}

#[test]
fn runs_read_what_single_reads_give_and_follow_steps_and_parameters() {
    let mut h = Host::platform("runs");
    assert_eq!(h.setup(None), fmi2OK);
    assert_eq!(h.enter(), fmi2OK);
    // Initialization Mode: the legs follow the parameters (a set of a parameter makes every
    // cached value stale).
    let before = assert_lengths_match_the_pose(&h, "initial pose");
    let z0 = h.get("r0[3]");
    assert_eq!(h.set("r0[3]", z0 + 0.02), fmi2OK);
    let raised = assert_lengths_match_the_pose(&h, "r0[3] raised by 2 cm");
    assert!(raised[..6].iter().zip(&before[..6]).all(|(a, b)| a > b), "{raised:?} {before:?}");
    // Parameters set in one call out of order (reference by reference, not as a run): the
    // legs follow too, then back.
    let x0 = h.get("r0[1]");
    assert_eq!(h.set_many(&["r0[3]", "r0[1]"], &[z0 + 0.05, x0 + 0.03]), fmi2OK);
    let moved = assert_lengths_match_the_pose(&h, "r0[3] raised by 5 cm and r0[1] moved by 3 cm in one call");
    assert_ne!(moved[..6], raised[..6]);
    assert_eq!(h.set_many(&["r0[3]", "r0[1]"], &[z0 + 0.02, x0]), fmi2OK);
    assert_eq!(assert_lengths_match_the_pose(&h, "back"), raised);
    assert_eq!(h.exit(), fmi2OK);

    let names = legs();
    let mut last = read(&h, &names);
    for step in 0..40 {
        // Forces as one run: leg feedback around the neutral lengths plus a pattern.
        let f: [f64; 6] = std::array::from_fn(|k| {
            3_000.0 - 2e5 * (last[k] - raised[k]) - 1e3 * last[6 + k] + 400.0 * ((step * (k + 1)) as f64).sin()
        });
        assert_eq!(h.set_forces(f), fmi2OK);
        let forces: Vec<String> = (1..=6).map(|k| format!("F[{k}]")).collect();
        assert_eq!(read(&h, &forces), f.to_vec(), "the forces read back");
        // The legs do not depend on the forces: a set leaves them as they were.
        let after_set = read(&h, &names);
        assert_eq!(
            after_set.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            last.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(h.step(1e-3), fmi2OK);
        let run = read(&h, &names);
        let singles: Vec<f64> = names.iter().map(|n| h.get(n)).collect();
        assert_eq!(run, singles, "step {step}: one run against one value per call");
        let mut reversed_names = names.clone();
        reversed_names.reverse();
        let mut reversed = read(&h, &reversed_names);
        reversed.reverse();
        assert_eq!(run, reversed, "step {step}: references in reverse order");
        assert_ne!(run, last, "step {step}: the legs moved");
        last = run;
    }
    assert_lengths_match_the_pose(&h, "after 40 steps");
}

#[test]
fn fmi3_reads_of_consecutive_arrays_equal_reads_of_each() {
    let mut h = Host3::platform("arrays", Kind::CoSimulation);
    assert_eq!(h.initialise(&[]), fmi3OK);
    for step in 0..20 {
        let f: Vec<f64> = (0..6).map(|k| 3_000.0 + 100.0 * ((step + k) as f64).cos()).collect();
        assert_eq!(h.set("F", &f), fmi3OK);
        assert_eq!(h.get("F"), f);
        assert_eq!(h.step(1e-3).0, fmi3OK);
        let both = [h.vr("l"), h.vr("ldot")];
        let mut out = [f64::NAN; 12];
        assert_eq!(unsafe { fmi3GetFloat64(h.c, both.as_ptr(), 2, out.as_mut_ptr(), 12) }, fmi3OK);
        let each: Vec<f64> = h.get("l").into_iter().chain(h.get("ldot")).collect();
        assert_eq!(out.to_vec(), each, "step {step}");
        // Not consecutive (the arrays in the other order, one twice): the general path gives
        // the same values.
        for (refs, names) in [([h.vr("ldot"), h.vr("l")], ["ldot", "l"]), ([h.vr("l"), h.vr("l")], ["l", "l"])] {
            let mut other = [f64::NAN; 12];
            assert_eq!(unsafe { fmi3GetFloat64(h.c, refs.as_ptr(), 2, other.as_mut_ptr(), 12) }, fmi3OK);
            let expected: Vec<f64> = h.get(names[0]).into_iter().chain(h.get(names[1])).collect();
            assert_eq!(other.to_vec(), expected, "step {step}, {names:?}");
        }
        // The wrong count is still refused on this path.
        assert_eq!(unsafe { fmi3GetFloat64(h.c, both.as_ptr(), 2, out.as_mut_ptr(), 11) }, fmi3Error);
    }
}

/// A host's read of several cache blocks every step (the legs, the pose and the actuators'
/// forces, which follow the inputs): one call gives the bits that a read of each element gives,
/// step after step, for the same references as the last read (kept runs), for other references
/// of the same count, and with the forces' block stale after a set of the forces.
#[test]
fn reads_of_several_blocks_repeated_every_step_give_what_single_reads_give() {
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    let mut h = Host::platform("blocks");
    assert_eq!(h.initialise(&[]), fmi2OK);
    let pose = ["r[1]", "r[2]", "r[3]"].into_iter().map(String::from).chain(
        (1..=3)
            .flat_map(|a| (1..=3).map(move |b| format!("R[{a},{b}]")))
            .chain((1..=3).map(|i| format!("angles[{i}]"))),
    );
    let names: Vec<String> =
        legs().into_iter().chain(pose).chain((1..=6).map(|k| format!("actuatorForce[{k}]"))).collect();
    let mut rotated = names.clone();
    rotated.rotate_left(5);
    for step in 0..30 {
        let f: [f64; 6] = std::array::from_fn(|k| 5_900.0 + 300.0 * ((step * (k + 2)) as f64).sin());
        assert_eq!(h.set_forces(f), fmi2OK);
        for names in [&names, &names, &rotated, &names] {
            let run = read(&h, names);
            let singles: Vec<f64> = names.iter().map(|n| h.get(n)).collect();
            assert_eq!(bits(&run), bits(&singles), "step {step}");
        }
        assert_eq!(read(&h, &names)[27..], f, "step {step}: the forces just set");
        assert_eq!(h.step(1e-3), fmi2OK);
    }
    // FMI 3: whole variables of several blocks, the same every step.
    let mut h = Host3::platform("blocks", Kind::CoSimulation);
    assert_eq!(h.initialise(&[]), fmi3OK);
    let variables = ["l", "ldot", "r", "R", "angles", "actuatorForce"];
    let refs: Vec<u32> = variables.iter().map(|v| h.vr(v)).collect();
    for step in 0..30 {
        let f: Vec<f64> = (0..6).map(|k| 5_900.0 + 300.0 * ((step * (k + 2)) as f64).cos()).collect();
        assert_eq!(h.set("F", &f), fmi3OK);
        for _ in 0..2 {
            let mut out = [f64::NAN; 33];
            assert_eq!(unsafe { fmi3GetFloat64(h.c, refs.as_ptr(), refs.len(), out.as_mut_ptr(), 33) }, fmi3OK);
            let each: Vec<f64> = variables.iter().flat_map(|v| h.get(v)).collect();
            assert_eq!(bits(&out), bits(&each), "step {step}");
        }
        assert_eq!(h.step(1e-3).0, fmi3OK);
    }
}

/// One `fmi2GetReal` of all `names`: the status and the values.
fn try_read(h: &Host, names: &[String]) -> (fmi2Status, Vec<f64>) {
    let vrs = vrs(h, names);
    let mut out = vec![0.0; vrs.len()];
    let s = unsafe { fmi2GetReal(h.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
    (s, out)
}

#[test]
fn a_nan_output_is_refused_on_the_run_path_and_only_where_read() {
    // Joint 1 of the platform and of the base pushed to opposite ends of the doubles: leg 1's
    // length overflows to infinity, and its rate, (d . d') / l, is (inf * 0) / inf.
    let mut h = Host::platform("nan");
    assert_eq!(h.setup(None), fmi2OK);
    assert_eq!(h.enter(), fmi2OK);
    let (a11, b11) = (h.get("A[1,1]"), h.get("B[1,1]"));
    assert_eq!(h.set("A[1,1]", 1.7e308), fmi2OK);
    assert_eq!(h.set("B[1,1]", -1.7e308), fmi2OK);
    // Twice: the first read computes the block, the second copies it.
    for read in ["first", "second"] {
        h.clear_log();
        let (status, values) = try_read(&h, &legs());
        println!("{read} read of the legs: {status}, {values:?}, {:?}", h.last_message());
        assert_eq!(values[0], f64::INFINITY, "l[1]");
        assert!(values[6].is_nan(), "ldot[1] = {}", values[6]);
        assert_eq!(status, fmi2Error, "{read} read");
        assert!(h.last_message().contains("ldot[1] is not a number"), "{}", h.last_message());
    }
    // The same block without the NaN element: read, as one run, with no error.
    let lengths: Vec<String> = legs().into_iter().take(6).collect();
    let (status, values) = try_read(&h, &lengths);
    assert_eq!(status, fmi2OK, "{values:?}");
    assert_eq!(values.len(), 6);
    // The parameters set back: no NaN any more, the run reads again.
    assert_eq!(h.set_many(&["A[1,1]", "B[1,1]"], &[a11, b11]), fmi2OK);
    let (status, values) = try_read(&h, &legs());
    assert_eq!(status, fmi2OK, "{values:?}");
    assert!(values.iter().all(|x| x.is_finite()));
}

#[test]
fn outputs_not_read_for_some_steps_are_computed_again_when_read() {
    // A host that reads the legs every step gets them computed as the step ends; one that
    // stops reading, steps and reads again must get the values of the new state.
    let mut h = Host::platform("decay");
    assert_eq!(h.initialise(&[]), fmi2OK);
    let names = legs();
    let mut previous = read(&h, &names);
    for (pattern, unread_steps) in [(0.0, 0), (1.0, 1), (2.0, 2), (3.0, 0), (4.0, 3)] {
        for _ in 0..=unread_steps {
            let f: [f64; 6] = std::array::from_fn(|k| 3_000.0 + 200.0 * (pattern + k as f64).sin());
            assert_eq!(h.set_forces(f), fmi2OK);
            assert_eq!(h.step(1e-3), fmi2OK);
        }
        let run = read(&h, &names);
        let singles: Vec<f64> = names.iter().map(|n| h.get(n)).collect();
        assert_eq!(run, singles, "after {unread_steps} steps unread");
        assert_ne!(run, previous, "the legs moved");
        assert_lengths_match_the_pose(&h, &format!("after {unread_steps} steps unread"));
        previous = run;
    }
}

/// The controller's measured lengths and rates set in one call (twelve consecutive references
/// over two variables, each run stored in one copy) give what twelve single sets give; a call
/// that also names a value it cannot set, or carries a NaN, sets nothing.
#[test]
fn a_set_over_consecutive_variables_is_the_single_sets_and_all_or_nothing() {
    use stewart_fmu::models::ModelKind;
    let mut one_call = Host::new("one call", ModelKind::Controller);
    let mut singly = Host::new("singly", ModelKind::Controller);
    for h in [&mut one_call, &mut singly] {
        assert_eq!(h.setup(None), fmi2OK);
        assert_eq!(h.enter(), fmi2OK);
        assert_eq!(h.exit(), fmi2OK);
        assert_eq!(h.step(0.01), fmi2OK);
    }
    let names = legs();
    let names: Vec<&str> = names.iter().map(|n| n.as_str()).collect();
    let forces: Vec<String> = (1..=6).map(|k| format!("F[{k}]")).collect();
    let programme = read(&one_call, &(1..=6).map(|k| format!("lp[{k}]")).collect::<Vec<_>>());
    let measured: Vec<f64> =
        (0..12).map(|i| if i < 6 { programme[i] - 1e-3 * (i + 1) as f64 } else { 0.01 * (i as f64 - 8.0) }).collect();
    assert_eq!(one_call.set_many(&names, &measured), fmi2OK);
    for (name, &x) in names.iter().zip(&measured) {
        assert_eq!(singly.set(name, x), fmi2OK);
    }
    let (f, f_singly) = (read(&one_call, &forces), read(&singly, &forces));
    println!("F after one set of l, ldot: {f:?}");
    assert_eq!(f, f_singly);
    assert!(
        f.iter().zip(read(&one_call, &(1..=6).map(|k| format!("Fp[{k}]")).collect::<Vec<_>>())).all(|(a, b)| a != &b)
    );
    // A Real output after the twelve: refused, nothing set; a NaN among them: the same.
    let mut with_output = names.clone();
    with_output.push("F[1]");
    let mut values = measured.iter().map(|x| x + 1e-3).collect::<Vec<_>>();
    values.push(0.0);
    assert_ne!(one_call.set_many(&with_output, &values), fmi2OK);
    let mut with_nan = measured.iter().map(|x| x + 1e-3).collect::<Vec<_>>();
    with_nan[7] = f64::NAN;
    assert_ne!(one_call.set_many(&names, &with_nan), fmi2OK);
    assert_eq!(read(&one_call, &legs().iter().map(|n| n.to_string()).collect::<Vec<_>>()), measured);
    assert_eq!(read(&one_call, &forces), f);
}

//! 10^5 random FMI calls through the exported functions: random functions in whatever state
//! the instances happen to be, random and invalid value references, NaN/inf/huge values,
//! NULL arrays, random FMU-state bytes, instantiation with good and bad GUIDs, frees. The
//! process must survive and every status must be one of the six FMI codes.

use crate::common;

use std::ffi::CString;
use std::sync::Mutex;

use common::fmi_host::{LogSink, callbacks};
use common::rng::Rng;
use stewart_fmu::fmi::FmiVersion;
use stewart_fmu::fmi::description::instantiation_token;
use stewart_fmu::fmi2::exports::*;
use stewart_fmu::fmi2::types::*;
use stewart_fmu::models::ModelKind;

/// Values a fuzzed Real argument takes: the awkward ones two thirds of the time.
const SPECIALS: [f64; 8] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300, -1e300, 0.0, 1e-300, 5900.715];

/// A value reference: a quarter of them arbitrary, the rest among the models' (the cueing
/// FMU's go to 303).
fn random_vr(rng: &mut Rng) -> u32 {
    match rng.below(4) {
        0 => rng.next() as u32,
        _ => rng.below(310) as u32,
    }
}

#[test]
fn hundred_thousand_random_calls() {
    const CALLS: usize = 100_000;
    let mut rng = Rng(0x9E3779B97F4A7C15);
    let sink: Box<LogSink> = Box::new(Mutex::new(vec![]));
    let cbs = callbacks(&sink);
    let silent = fmi2CallbackFunctions { logger: None, ..cbs };
    let good_guid = CString::new(instantiation_token(ModelKind::Platform, FmiVersion::Fmi2)).unwrap();
    // The cueing FMU too, in both methods (cueing.method is an Integer the fuzz sets at random).
    let cueing_guid = CString::new(instantiation_token(ModelKind::Cueing, FmiVersion::Fmi2)).unwrap();
    let mut instances: Vec<fmi2Component> = vec![];
    let mut states: Vec<(fmi2Component, fmi2FMUstate)> = vec![];
    let mut times: Vec<f64> = vec![];
    let mut counts = [0usize; 6];
    let mut calls = 0;
    while calls < CALLS {
        if instances.is_empty() || rng.chance(0.002) {
            let guid = match rng.below(10) {
                0 => c"{bad}".as_ptr(),
                1..=4 => cueing_guid.as_ptr(),
                _ => good_guid.as_ptr(),
            };
            let name = if rng.chance(0.95) { c"fuzz".as_ptr() } else { std::ptr::null() };
            let kind = if rng.chance(0.9) { fmi2CoSimulation } else { rng.below(5) as i32 - 1 };
            let cb: *const fmi2CallbackFunctions = match rng.below(10) {
                0 => std::ptr::null(),
                1..=4 => &silent,
                _ => &cbs,
            };
            let c = unsafe { fmi2Instantiate(name, kind, guid, std::ptr::null(), cb, 0, rng.below(2) as i32) };
            calls += 1;
            if !c.is_null() {
                instances.push(c);
                times.push(0.0);
            }
            if instances.len() > 6 || instances.is_empty() {
                continue;
            }
        }
        let idx = rng.below(instances.len() as u64) as usize;
        let c = if rng.chance(0.01) { std::ptr::null_mut() } else { instances[idx] };
        let n = rng.below(5) as usize;
        let vrs: Vec<u32> = (0..n).map(|_| random_vr(&mut rng)).collect();
        let reals: Vec<f64> = (0..n).map(|_| rng.real(&SPECIALS, 12)).collect();
        let ints: Vec<i32> = (0..n).map(|_| rng.below(5) as i32 - 1).collect();
        let mut out_r = vec![0.0f64; n.max(1)];
        let mut out_i = vec![0i32; n.max(1)];
        let mut out_s: Vec<fmi2String> = vec![std::ptr::null(); n.max(1)];
        let null_arrays = rng.chance(0.1);
        let vp = if null_arrays { std::ptr::null() } else { vrs.as_ptr() };
        let status = unsafe {
            match rng.below(32) {
                0 => fmi2SetupExperiment(
                    c,
                    rng.below(2) as i32,
                    rng.real(&SPECIALS, 12),
                    0.0,
                    rng.below(2) as i32,
                    rng.real(&SPECIALS, 12).abs(),
                ),
                1 => fmi2EnterInitializationMode(c),
                2 | 3 => fmi2ExitInitializationMode(c),
                4 => fmi2Terminate(c),
                5 => fmi2Reset(c),
                6 | 7 => fmi2GetReal(c, vp, n, out_r.as_mut_ptr()),
                8 | 9 => fmi2SetReal(c, vp, n, if null_arrays { std::ptr::null() } else { reals.as_ptr() }),
                10 => fmi2GetInteger(c, vp, n, out_i.as_mut_ptr()),
                11 => fmi2SetInteger(c, vp, n, ints.as_ptr()),
                12 => fmi2GetBoolean(c, vp, n, out_i.as_mut_ptr()),
                13 => fmi2SetBoolean(c, vp, n, ints.as_ptr()),
                14 => fmi2GetString(c, vp, n, out_s.as_mut_ptr()),
                15 => fmi2SetString(c, vp, n, out_s.as_ptr()),
                16..=20 => {
                    // Mostly well-formed steps from the host's view of time.
                    let tc = if rng.chance(0.9) { times[idx] } else { rng.real(&SPECIALS, 12) };
                    let h = if rng.chance(0.9) { (rng.below(1000) + 1) as f64 * 1e-3 } else { rng.real(&SPECIALS, 12) };
                    let s = fmi2DoStep(c, tc, h, 1);
                    if s == fmi2OK && c == instances[idx] {
                        times[idx] = tc + h;
                    }
                    s
                }
                21 => {
                    let mut st: fmi2FMUstate = std::ptr::null_mut();
                    let s = fmi2GetFMUstate(c, &mut st);
                    if !st.is_null() {
                        states.push((c, st));
                    }
                    s
                }
                22 => match states.pop() {
                    Some((owner, st)) if owner == c && rng.chance(0.5) => {
                        let s = fmi2SetFMUstate(c, st);
                        states.push((owner, st));
                        s
                    }
                    Some((owner, mut st)) => {
                        let s = fmi2FreeFMUstate(owner, &mut st);
                        if !st.is_null() {
                            states.push((owner, st));
                        }
                        s
                    }
                    None => fmi2SetFMUstate(c, std::ptr::null_mut()),
                },
                23 => {
                    // Serialize a state, damage it sometimes, deserialize it.
                    let mut st: fmi2FMUstate = std::ptr::null_mut();
                    let s = fmi2GetFMUstate(c, &mut st);
                    if s != fmi2OK || st.is_null() {
                        s
                    } else {
                        let mut size = 0usize;
                        fmi2SerializedFMUstateSize(c, st, &mut size);
                        let mut bytes = vec![0u8; size];
                        fmi2SerializeFMUstate(c, st, bytes.as_mut_ptr() as *mut fmi2Byte, size);
                        fmi2FreeFMUstate(c, &mut st);
                        if rng.chance(0.5) && !bytes.is_empty() {
                            let i = rng.below(bytes.len() as u64) as usize;
                            bytes[i] ^= 1 << rng.below(8);
                        }
                        if rng.chance(0.2) {
                            bytes.truncate(rng.below(bytes.len() as u64 + 1) as usize);
                        }
                        let mut back: fmi2FMUstate = std::ptr::null_mut();
                        let s = fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut back);
                        if !back.is_null() {
                            let s2 = fmi2SetFMUstate(c, back);
                            fmi2FreeFMUstate(c, &mut back);
                            assert!((0..=5).contains(&s2));
                        }
                        s
                    }
                }
                24 => {
                    let garbage: Vec<u8> = (0..rng.below(300)).map(|_| rng.next() as u8).collect();
                    let mut st: fmi2FMUstate = std::ptr::null_mut();
                    let s = fmi2DeSerializeFMUstate(c, garbage.as_ptr() as *const fmi2Byte, garbage.len(), &mut st);
                    if !st.is_null() {
                        fmi2FreeFMUstate(c, &mut st);
                    }
                    s
                }
                25 => fmi2SetRealInputDerivatives(c, vp, n, ints.as_ptr(), reals.as_ptr()),
                26 => fmi2GetRealOutputDerivatives(c, vp, n, ints.as_ptr(), out_r.as_mut_ptr()),
                27 => {
                    let mut r = 0.0;
                    let mut b = 0;
                    match rng.below(4) {
                        0 => fmi2GetRealStatus(c, rng.below(5) as i32 - 1, &mut r),
                        1 => fmi2GetBooleanStatus(c, rng.below(5) as i32 - 1, &mut b),
                        2 => fmi2GetStatus(c, rng.below(5) as i32 - 1, &mut b),
                        _ => fmi2GetIntegerStatus(c, rng.below(5) as i32 - 1, std::ptr::null_mut()),
                    }
                }
                28 => fmi2SetDebugLogging(c, rng.below(2) as i32, 0, std::ptr::null()),
                29 => fmi2CancelStep(c),
                30 => fmi2GetDirectionalDerivative(c, vp, n, vp, n, reals.as_ptr(), out_r.as_mut_ptr()),
                _ => {
                    if rng.chance(0.3) {
                        // Free the instance (its FMU states stay valid memory until freed).
                        let victim = instances.swap_remove(idx);
                        times.swap_remove(idx);
                        fmi2FreeInstance(victim);
                        let mut kept = vec![];
                        for (owner, mut st) in states.drain(..) {
                            if owner == victim {
                                if let Some(&other) = instances.first() {
                                    fmi2FreeFMUstate(other, &mut st);
                                }
                            } else {
                                kept.push((owner, st));
                            }
                        }
                        states = kept;
                        fmi2OK
                    } else {
                        fmi2SetTime(c, rng.real(&SPECIALS, 12))
                    }
                }
            }
        };
        assert!((0..=5).contains(&status), "status {status} is not an FMI status");
        counts[status as usize] += 1;
        calls += 1;
        if sink.lock().map(|v| v.len()).unwrap_or(0) > 10_000 {
            sink.lock().unwrap().clear();
        }
    }
    unsafe {
        for (owner, mut st) in states {
            fmi2FreeFMUstate(owner, &mut st);
        }
        for c in instances {
            fmi2FreeInstance(c);
        }
    }
    println!(
        "{calls} random calls: OK {}, Warning {}, Discard {}, Error {}, Fatal {}, Pending {}",
        counts[0], counts[1], counts[2], counts[3], counts[4], counts[5]
    );
    assert!(calls >= CALLS);
    assert_eq!(counts[4] + counts[5], 0, "no Fatal or Pending");
    assert!(counts[0] > 10_000 && counts[3] > 10_000, "the fuzz reaches both success and refusal paths");
}

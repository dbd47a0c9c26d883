//! Instances are independent: interleaved instances and instances driven concurrently from
//! several threads give bit-identical results to the same runs done one after another.

use crate::common;

use common::fmi_host::Host;
use stewart_fmu::fmi2::types::*;

/// A run of one instance with its own force pattern; every output bit of every step.
fn run(seed: usize, steps: usize) -> Vec<u64> {
    let mut h = Host::platform(&format!("run{seed}"));
    assert_eq!(h.initialise(&[("angles0[1]", 1e-4 * seed as f64)]), fmi2OK);
    let mut out = vec![];
    for i in 0..steps {
        let t = i as f64 * 1e-3;
        let f: [f64; 6] = std::array::from_fn(|k| 5900.715 + 50.0 * ((seed + k) as f64 + 3.0 * t).sin());
        h.set_forces(f);
        assert_eq!(h.step(1e-3), fmi2OK);
        out.extend(h.all_reals());
    }
    out
}

#[test]
fn concurrent_instances_match_sequential_runs_bit_for_bit() {
    let n = 8;
    let steps = 500;
    let sequential: Vec<Vec<u64>> = (0..n).map(|s| run(s, steps)).collect();
    let handles: Vec<_> = (0..n).map(|s| std::thread::spawn(move || run(s, steps))).collect();
    let concurrent: Vec<Vec<u64>> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    for s in 0..n {
        assert!(sequential[s] == concurrent[s], "instance {s} differs when run on a thread");
    }
    // And the runs really differ from each other (the instances do not share anything).
    assert!(sequential[0] != sequential[1]);
}

#[test]
fn interleaved_instances_are_independent() {
    let steps = 300;
    let alone: Vec<Vec<u64>> = (0..3).map(|s| run(s, steps)).collect();
    let mut hosts: Vec<Host> = (0..3).map(|s| Host::platform(&format!("i{s}"))).collect();
    for (s, h) in hosts.iter_mut().enumerate() {
        assert_eq!(h.initialise(&[("angles0[1]", 1e-4 * s as f64)]), fmi2OK);
    }
    let mut outs = vec![vec![]; 3];
    for i in 0..steps {
        let t = i as f64 * 1e-3;
        for (s, h) in hosts.iter_mut().enumerate() {
            let f: [f64; 6] = std::array::from_fn(|k| 5900.715 + 50.0 * ((s + k) as f64 + 3.0 * t).sin());
            h.set_forces(f);
            assert_eq!(h.step(1e-3), fmi2OK);
            outs[s].extend(h.all_reals());
        }
    }
    for s in 0..3 {
        assert!(outs[s] == alone[s], "instance {s} differs when interleaved");
    }
}

#[test]
fn many_instantiate_free_cycles() {
    for i in 0..2000 {
        let mut h = Host::platform("cycle");
        if i % 2 == 0 {
            assert_eq!(h.initialise(&[]), fmi2OK);
            assert_eq!(h.step(1e-3), fmi2OK);
            let bytes = h.state_bytes();
            assert_eq!(h.restore_bytes(&bytes), fmi2OK);
        }
    }
}

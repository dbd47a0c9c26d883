//! The co-simulation hot path does not touch the heap: after initialisation, `fmi2SetReal`
//! (forces), `fmi2DoStep` and `fmi2GetReal` (outputs) allocate nothing, with either
//! integrator. Counted with a global allocator that counts this thread's allocations.

use crate::common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use common::fmi_host::Host;
use stewart_fmu::fmi2::exports::*;
use stewart_fmu::fmi2::types::*;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

#[test]
fn cosimulation_steps_do_not_allocate() {
    for (method, name) in [(1.0, "Dormand-Prince 5(4)"), (2.0, "Runge-Kutta 4")] {
        let mut h = Host::platform("alloc");
        h.setup(None);
        h.enter();
        let vr_method = h.vr("solver.method");
        unsafe { fmi2SetInteger(h.c, &vr_method, 1, &(method as i32)) };
        assert_eq!(h.exit(), fmi2OK);
        let force_vrs: Vec<u32> = (1..=6).collect();
        let output_vrs: Vec<u32> = (100..=134).collect();
        let mut outputs = vec![0.0; output_vrs.len()];
        let mut forces = [0.0; 6];
        unsafe { fmi2GetReal(h.c, output_vrs.as_ptr(), output_vrs.len(), outputs.as_mut_ptr()) };
        // A leg-length feedback around a moving programme keeps the platform up and moving.
        let mut cosim_step = |h: &mut Host, i: usize| {
            for (k, f) in forces.iter_mut().enumerate() {
                let lp = 1.7550860729486566 + 0.01 * (0.003 * i as f64 + k as f64).sin();
                *f = 5900.715 + 2.0e5 * (lp - outputs[21 + k]) - 2.0e4 * outputs[27 + k];
            }
            unsafe {
                assert_eq!(fmi2SetReal(h.c, force_vrs.as_ptr(), 6, forces.as_ptr()), fmi2OK);
                assert_eq!(fmi2DoStep(h.c, h.time, 1e-3, fmi2True), fmi2OK);
                h.time += 1e-3;
                assert_eq!(fmi2GetReal(h.c, output_vrs.as_ptr(), output_vrs.len(), outputs.as_mut_ptr()), fmi2OK);
            }
        };
        for i in 0..10 {
            cosim_step(&mut h, i);
        }
        let before = allocations();
        for i in 10..2010 {
            cosim_step(&mut h, i);
        }
        let during = allocations() - before;
        println!(
            "{name}: {during} heap allocations in 2000 co-simulation steps (set forces, step 1 ms, get 35 outputs)"
        );
        assert_eq!(during, 0, "{name}: the hot path allocated");
    }
}

//! Criterion benches of the hot path, from the right-hand side up to `fmi2DoStep` called
//! through the exported C functions, and the cost of many instances stepped in turn.
//!
//!     cargo bench --bench performance
//!
//! The platform is kept moving (and upright) by a leg-length feedback around a slowly moving
//! programme, computed outside the timed region.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::{Matrix3, Vector3};
use stewart_fmu::fmi::FmiVersion;
use stewart_fmu::fmi::description::instantiation_token;
use stewart_fmu::fmi2::exports::*;
use stewart_fmu::fmi2::types::*;
use stewart_fmu::integration::{Method, SolverSettings};
use stewart_fmu::models::ModelKind;
use stewart_fmu::physics::actuators::HeldForces;
use stewart_fmu::physics::body::state::BodyState;
use stewart_fmu::physics::special_form::SpecialForm;
use stewart_fmu::physics::stand::Stand;
use stewart_fmu::simulation::{PlatformSimulation, Stabilisation, VectorPath};

const U0: f64 = 5900.715;
const L0: f64 = 1.7550860729486566;
const F_VRS: [u32; 6] = [1, 2, 3, 4, 5, 6];
/// l[1..6] and ldot[1..6].
const LEG_VRS: [u32; 12] = [121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132];

fn moving_state() -> BodyState {
    BodyState::from_pose(
        Stand::truck_cabin_neutral_position() + Vector3::new(0.01, -0.02, 0.03),
        Vector3::new(0.05, 0.0, -0.02),
        &stewart_fmu::physics::body::kinematics::rotation_from_angles(&Vector3::new(0.02, -0.01, 0.05)),
        &Vector3::new(0.1, 0.05, -0.1),
    )
}

fn physics(c: &mut Criterion) {
    let stand = Stand::truck_cabin();
    let form = SpecialForm::new(stand.clone());
    let state = moving_state();
    let law = HeldForces { value: [U0 + 10.0, U0 - 5.0, U0, U0 + 3.0, U0 - 2.0, U0], slope: [1.0; 6], t0: 0.0 };
    let y = state.to_vector();
    let mut dy = [0.0; 24];
    c.bench_function("rhs: special-form right-hand side (24 states)", |b| {
        b.iter(|| form.derivative(black_box(0.1), black_box(&y), &law, &mut dy))
    });
    // Each on the fastest vector path of this processor, and on the baseline (SSE2) path
    // (`VectorPath::Baseline`; the same numbers to the bit).
    for (name, method, path) in [
        ("rk4: one RK4 step of 1 ms (+projection, checks)", Method::RungeKutta4, VectorPath::fastest()),
        ("rk4 baseline code: one RK4 step of 1 ms", Method::RungeKutta4, VectorPath::Baseline),
        ("dopri5: one adaptive step of 1 ms (+projection, checks)", Method::DormandPrince45, VectorPath::fastest()),
        ("dopri5 baseline code: one adaptive step of 1 ms", Method::DormandPrince45, VectorPath::Baseline),
    ] {
        let settings = SolverSettings { method, max_step: 1e-3, fixed_step: 1e-3, ..SolverSettings::default() };
        let mut sim = PlatformSimulation::new(stand.clone(), state, settings, Stabilisation::Projection, 0.0).unwrap();
        sim.set_vector_path(path);
        let start = (sim.state, sim.integrator);
        c.bench_function(name, |b| {
            b.iter(|| {
                (sim.state, sim.integrator) = start;
                sim.integrator.dopri5.h_next = 1e-3;
                sim.time = 0.0;
                sim.advance(&law, 1e-3).unwrap();
                black_box(sim.state)
            })
        });
    }
    let _ = Matrix3::<f64>::identity();
}

/// An instance through the exported functions, with the solver chosen.
struct Fmu {
    c: fmi2Component,
    time: f64,
    legs: [f64; 12],
    start: Vec<u8>,
}

impl Fmu {
    fn new(method: i32) -> Fmu {
        let guid = std::ffi::CString::new(instantiation_token(ModelKind::Platform, FmiVersion::Fmi2)).unwrap();
        let cb = quiet_callbacks();
        unsafe {
            let c = fmi2Instantiate(c"bench".as_ptr(), fmi2CoSimulation, guid.as_ptr(), std::ptr::null(), &cb, 0, 0);
            fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0);
            fmi2EnterInitializationMode(c);
            fmi2SetInteger(c, &80, 1, &method);
            fmi2ExitInitializationMode(c);
            let mut f = Fmu { c, time: 0.0, legs: [0.0; 12], start: vec![] };
            f.read_legs();
            f.start = f.save();
            f
        }
    }

    fn save(&self) -> Vec<u8> {
        unsafe {
            let mut st: fmi2FMUstate = std::ptr::null_mut();
            fmi2GetFMUstate(self.c, &mut st);
            let mut size = 0;
            fmi2SerializedFMUstateSize(self.c, st, &mut size);
            let mut bytes = vec![0u8; size];
            fmi2SerializeFMUstate(self.c, st, bytes.as_mut_ptr() as *mut fmi2Byte, size);
            fmi2FreeFMUstate(self.c, &mut st);
            bytes
        }
    }

    /// Back to the start (untimed), so that benchmarks of any length stay in the same regime.
    fn rewind(&mut self) {
        if self.start.is_empty() {
            return;
        }
        unsafe {
            let mut st: fmi2FMUstate = std::ptr::null_mut();
            fmi2DeSerializeFMUstate(self.c, self.start.as_ptr() as *const fmi2Byte, self.start.len(), &mut st);
            fmi2SetFMUstate(self.c, st);
            fmi2FreeFMUstate(self.c, &mut st);
        }
        self.time = 0.0;
        self.read_legs();
    }

    fn read_legs(&mut self) {
        unsafe { fmi2GetReal(self.c, LEG_VRS.as_ptr(), 12, self.legs.as_mut_ptr()) };
    }

    /// Feedback forces around a moving programme (untimed in the doStep bench).
    fn set_forces(&mut self) {
        let mut f = [0.0; 6];
        for k in 0..6 {
            let lp = L0 + 0.02 * (1.5 * self.time + k as f64).sin();
            f[k] = U0 + 2.0e5 * (lp - self.legs[k]) - 2.0e4 * self.legs[6 + k];
        }
        unsafe { fmi2SetReal(self.c, F_VRS.as_ptr(), 6, f.as_ptr()) };
    }

    fn do_step(&mut self) {
        let s = unsafe { fmi2DoStep(self.c, self.time, 1e-3, fmi2True) };
        debug_assert_eq!(s, fmi2OK);
        self.time += 1e-3;
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}

/// Steps per rewind: 2 s of motion.
const EPISODE: u64 = 2000;

/// Runs `iters` steps in episodes of [`EPISODE`] steps, rewinding between episodes, and
/// times whole episodes (one clock read per episode: this VM's clock costs ~0.3 us).
fn episodes(fmu: &mut Fmu, iters: u64, mut step: impl FnMut(&mut Fmu)) -> Duration {
    let mut timed = Duration::ZERO;
    let mut done = 0;
    while done < iters {
        fmu.rewind();
        let n = EPISODE.min(iters - done);
        let t0 = Instant::now();
        for _ in 0..n {
            step(fmu);
        }
        timed += t0.elapsed();
        done += n;
    }
    timed
}

fn fmi_do_step(c: &mut Criterion) {
    for (method, name) in [(2, "RK4"), (1, "DOPRI5")] {
        let mut fmu = Fmu::new(method);
        // Constant forces slightly off equilibrium: the platform drifts slowly through an
        // episode; the cost of a step does not depend on where it is.
        let f: [f64; 6] = std::array::from_fn(|k| U0 * (1.0 + 1e-4 * k as f64));
        c.bench_function(&format!("fmi2DoStep(1 ms), {name}, through the exported C function"), |b| {
            b.iter_custom(|iters| {
                unsafe { fmi2SetReal(fmu.c, F_VRS.as_ptr(), 6, f.as_ptr()) };
                episodes(&mut fmu, iters, |fmu| {
                    unsafe { fmi2SetReal(fmu.c, F_VRS.as_ptr(), 6, f.as_ptr()) };
                    fmu.do_step();
                })
            })
        });
        let mut fmu = Fmu::new(method);
        c.bench_function(
            &format!(
                "co-simulation step: feedback forces, fmi2SetReal(6) + fmi2DoStep(1 ms) + fmi2GetReal(12), {name}"
            ),
            |b| {
                b.iter_custom(|iters| {
                    episodes(&mut fmu, iters, |fmu| {
                        fmu.set_forces();
                        fmu.do_step();
                        fmu.read_legs();
                    })
                })
            },
        );
    }
}

/// FMI 2 callbacks without a logger: nothing is formatted or printed.
fn quiet_callbacks() -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: None,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::null_mut(),
    }
}

/// `fmi2Instantiate` + `fmi2FreeInstance`, and the FMI 3 Co-Simulation counterpart: the
/// token check and the model's start values.
fn instantiation(c: &mut Criterion) {
    let guid = std::ffi::CString::new(instantiation_token(ModelKind::Platform, FmiVersion::Fmi2)).unwrap();
    let token = std::ffi::CString::new(instantiation_token(ModelKind::Platform, FmiVersion::Fmi3)).unwrap();
    let cb = quiet_callbacks();
    c.bench_function("instantiation token (platform, FMI 3)", |b| {
        b.iter(|| instantiation_token(ModelKind::Platform, FmiVersion::Fmi3))
    });
    c.bench_function("fmi2Instantiate + fmi2FreeInstance (platform)", |b| {
        b.iter(|| unsafe {
            let inst = fmi2Instantiate(c"bench".as_ptr(), fmi2CoSimulation, guid.as_ptr(), std::ptr::null(), &cb, 0, 0);
            assert!(!inst.is_null());
            fmi2FreeInstance(inst);
        })
    });
    c.bench_function("fmi3InstantiateCoSimulation + fmi3FreeInstance (platform)", |b| {
        b.iter(|| unsafe {
            let inst = stewart_fmu::fmi3::exports::fmi3InstantiateCoSimulation(
                c"bench".as_ptr(),
                token.as_ptr(),
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
            assert!(!inst.is_null());
            stewart_fmu::fmi3::exports::fmi3FreeInstance(inst);
        })
    });
}

fn many_instances(c: &mut Criterion) {
    let mut group = c.benchmark_group("N instances stepped in turn (co-simulation step each, RK4, 1 ms)");
    for n in [1usize, 10, 100, 1000] {
        let mut fmus: Vec<Fmu> = (0..n).map(|_| Fmu::new(2)).collect();
        group.throughput(criterion::Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter_custom(|iters| {
                let mut timed = Duration::ZERO;
                for i in 0..iters {
                    if i % EPISODE == 0 {
                        fmus.iter_mut().for_each(Fmu::rewind);
                    }
                    let t0 = Instant::now();
                    for f in fmus.iter_mut() {
                        f.set_forces();
                        f.do_step();
                        f.read_legs();
                    }
                    timed += t0.elapsed();
                }
                timed
            })
        });
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default().warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    targets = physics, fmi_do_step, instantiation, many_instances
}
criterion_main!(benches);

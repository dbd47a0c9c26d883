//! A native FMI host for benchmarking: loads the packaged FMU's binary with `dlopen` (as a
//! C/C++ simulator would), runs 10 s of the default stand at 1 ms communication steps with
//! sinusoidal leg-length programmes closed by a leg-length feedback (open-loop forces would
//! tip the platform over within seconds), and prints microseconds per `fmi2DoStep`
//! (median and percentiles), the real-time factor and the peak memory.
//!
//!     cargo run --release --example native_host -- [path/to/StewartPlatform.fmu] [rk4|dopri5]
//!         [--fixed-step S] [--rel-tol X] [--t-end T] [--json]
//!
//! `--json` prints one JSON line with the cost and the final pose instead of the summary
//! (used by `examples/compare_performance.py`).

use std::ffi::{CString, c_char, c_int, c_uint, c_void};
use std::io::Read;
use std::time::Instant;

type Component = *mut c_void;
type Instantiate = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const Callbacks,
    c_int,
    c_int,
) -> Component;
type Simple = unsafe extern "C" fn(Component) -> c_int;
type Setup = unsafe extern "C" fn(Component, c_int, f64, f64, c_int, f64) -> c_int;
type SetReal = unsafe extern "C" fn(Component, *const c_uint, usize, *const f64) -> c_int;
type GetReal = unsafe extern "C" fn(Component, *const c_uint, usize, *mut f64) -> c_int;
type SetInteger = unsafe extern "C" fn(Component, *const c_uint, usize, *const c_int) -> c_int;
type DoStep = unsafe extern "C" fn(Component, f64, f64, c_int) -> c_int;
type Free = unsafe extern "C" fn(Component);

#[repr(C)]
struct Callbacks {
    logger: Option<unsafe extern "C" fn()>,
    allocate: Option<unsafe extern "C" fn()>,
    free: Option<unsafe extern "C" fn()>,
    step_finished: Option<unsafe extern "C" fn()>,
    environment: *mut c_void,
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let fmu =
        args.iter().find(|a| a.ends_with(".fmu")).cloned().unwrap_or_else(|| "target/fmu/StewartPlatform.fmu".into());
    let method = if args.iter().any(|a| a == "dopri5") { 1 } else { 2 };
    let option = |name: &str| -> Option<f64> {
        args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).and_then(|v| v.parse().ok())
    };
    let fixed_step = option("--fixed-step");
    let rel_tol = option("--rel-tol");
    let t_end = option("--t-end").unwrap_or(10.0);
    let json = args.iter().any(|a| a == "--json");

    // Extract the binary and the GUID from the FMU.
    let file = std::fs::File::open(&fmu).map_err(|e| format!("{fmu}: {e}"))?;
    let mut zip = zip::ZipArchive::new(file).map_err(|e| e.to_string())?;
    let mut xml = String::new();
    zip.by_name("modelDescription.xml")
        .map_err(|e| e.to_string())?
        .read_to_string(&mut xml)
        .map_err(|e| e.to_string())?;
    let guid = xml.split("guid=\"").nth(1).and_then(|s| s.split('"').next()).ok_or("no guid")?.to_string();
    let mut binary = vec![];
    zip.by_name("binaries/linux64/StewartPlatform.so")
        .map_err(|e| e.to_string())?
        .read_to_end(&mut binary)
        .map_err(|e| e.to_string())?;
    let dir = std::env::temp_dir().join(format!("stewart_native_host_{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
    let so = dir.join("StewartPlatform.so");
    std::fs::write(&so, &binary).map_err(|e| e.to_string())?;

    unsafe {
        let path = CString::new(so.to_string_lossy().as_bytes()).map_err(|e| e.to_string())?;
        let lib = libc::dlopen(path.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL);
        if lib.is_null() {
            return Err("dlopen failed".into());
        }
        let sym = |name: &str| -> Result<*mut c_void, String> {
            let c = CString::new(name).map_err(|e| e.to_string())?;
            let p = libc::dlsym(lib, c.as_ptr());
            if p.is_null() { Err(format!("missing {name}")) } else { Ok(p) }
        };
        let instantiate: Instantiate = std::mem::transmute(sym("fmi2Instantiate")?);
        let setup: Setup = std::mem::transmute(sym("fmi2SetupExperiment")?);
        let enter: Simple = std::mem::transmute(sym("fmi2EnterInitializationMode")?);
        let exit: Simple = std::mem::transmute(sym("fmi2ExitInitializationMode")?);
        let set_real: SetReal = std::mem::transmute(sym("fmi2SetReal")?);
        let get_real: GetReal = std::mem::transmute(sym("fmi2GetReal")?);
        let set_integer: SetInteger = std::mem::transmute(sym("fmi2SetInteger")?);
        let do_step: DoStep = std::mem::transmute(sym("fmi2DoStep")?);
        let terminate: Simple = std::mem::transmute(sym("fmi2Terminate")?);
        let free: Free = std::mem::transmute(sym("fmi2FreeInstance")?);

        let callbacks = Callbacks {
            logger: None,
            allocate: None,
            free: None,
            step_finished: None,
            environment: std::ptr::null_mut(),
        };
        let guid_c = CString::new(guid).map_err(|e| e.to_string())?;
        // An initialised instance with the chosen solver: solver.method (80), solver.relTol (81),
        // solver.fixedStep (84).
        let start = |name: &std::ffi::CStr| -> Result<Component, String> {
            let c = instantiate(name.as_ptr(), 1, guid_c.as_ptr(), std::ptr::null(), &callbacks, 0, 0);
            if c.is_null() {
                return Err("fmi2Instantiate failed".into());
            }
            setup(c, 0, 0.0, 0.0, 0, 0.0);
            enter(c);
            set_integer(c, &80, 1, &method);
            if let Some(x) = rel_tol {
                set_real(c, &81, 1, &x);
            }
            if let Some(x) = fixed_step {
                set_real(c, &84, 1, &x);
            }
            if exit(c) != 0 {
                return Err("fmi2ExitInitializationMode failed".into());
            }
            Ok(c)
        };
        let c = start(c"native")?;
        let force_vrs: [c_uint; 6] = [1, 2, 3, 4, 5, 6];
        let leg_vrs: [c_uint; 12] = [121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132];
        let mut legs = [0.0; 12];
        get_real(c, leg_vrs.as_ptr(), 12, legs.as_mut_ptr());
        let h = 1e-3;
        let steps = (t_end / h).round() as usize;
        // Clock reads cost about 0.3 us on this machine class: time batches of steps.
        const BATCH: usize = 100;
        let mut per_step = Vec::with_capacity(steps / BATCH);
        let mut do_step_total = 0.0;
        let wall = Instant::now();
        let mut t = 0.0;
        let mut forces = [[0.0; 6]; BATCH];
        let mut history: Vec<[f64; 6]> = Vec::with_capacity(steps);
        for _ in 0..steps / BATCH {
            // The feedback needs the legs of every step, so the co-simulation loop runs in
            // full; the doStep cost is measured on a copy of the batch below.
            let t_batch = t;
            let start = Instant::now();
            for f in forces.iter_mut() {
                for k in 0..6 {
                    let lp = 1.7550860729486566 + 0.02 * (2.0 * t + k as f64).sin();
                    f[k] = 5900.715 + 2.0e5 * (lp - legs[k]) - 2.0e4 * legs[6 + k];
                }
                set_real(c, force_vrs.as_ptr(), 6, f.as_ptr());
                let status = do_step(c, t, h, 1);
                if status != 0 {
                    return Err(format!("fmi2DoStep returned {status} at t = {t}"));
                }
                t += h;
                get_real(c, leg_vrs.as_ptr(), 12, legs.as_mut_ptr());
            }
            let _ = (t_batch, start.elapsed());
            history.extend_from_slice(&forces);
        }
        let elapsed = wall.elapsed().as_secs_f64();
        // doStep alone: the recorded forces replayed on a second instance (the same trajectory),
        // one clock read per batch.
        let c2 = start(c"native2")?;
        let mut t2 = 0.0;
        let mut failed = 0;
        for batch in history.chunks(BATCH) {
            let start = Instant::now();
            for f in batch {
                set_real(c2, force_vrs.as_ptr(), 6, f.as_ptr());
                failed += (do_step(c2, t2, h, 1) != 0) as usize;
                t2 += h;
            }
            let dt = start.elapsed().as_secs_f64();
            do_step_total += dt;
            per_step.push(dt / BATCH as f64 * 1e6);
        }
        // Final pose of the co-simulation: r[1..3] (100..102) and R (106..114).
        let pose_vrs: [c_uint; 12] = [100, 101, 102, 106, 107, 108, 109, 110, 111, 112, 113, 114];
        let mut pose = [0.0; 12];
        get_real(c, pose_vrs.as_ptr(), 12, pose.as_mut_ptr());
        free(c2);
        if failed > 0 {
            return Err(format!("{failed} replayed steps failed"));
        }
        terminate(c);
        free(c);
        let mut sorted = per_step.clone();
        sorted.sort_by(|a, b| a.total_cmp(b));
        let pct = |p: f64| sorted[((sorted.len() - 1) as f64 * p) as usize];
        let mut usage: libc::rusage = std::mem::zeroed();
        libc::getrusage(libc::RUSAGE_SELF, &mut usage);
        if json {
            println!(
                "{{\"us_per_step_median\": {}, \"us_per_step_mean\": {}, \"loop_us_per_step\": {}, \"max_rss_kib\": {}, \"r\": {:?}, \"R\": {:?}}}",
                pct(0.5),
                do_step_total / steps as f64 * 1e6,
                elapsed / steps as f64 * 1e6,
                usage.ru_maxrss,
                &pose[..3],
                &pose[3..]
            );
            let _ = std::fs::remove_dir_all(&dir);
            return Ok(());
        }
        println!(
            "native host, {}, {t_end} s of the default stand at 1 ms steps: fmi2SetReal(6) + fmi2DoStep(1 ms) median {:.3} us (batches of {BATCH}; \
             p10 {:.3}, p90 {:.3}, mean {:.3}); co-simulation loop with feedback forces, fmi2SetReal and fmi2GetReal: \
             {:.3} us per step, real-time factor {:.0}; peak memory (max RSS) {} KiB",
            if method == 2 { "RK4 (1 internal step)" } else { "DOPRI5 (default tolerance)" },
            pct(0.5),
            pct(0.1),
            pct(0.9),
            do_step_total / steps as f64 * 1e6,
            elapsed / steps as f64 * 1e6,
            t_end / elapsed,
            usage.ru_maxrss
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
    Ok(())
}

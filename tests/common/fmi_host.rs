//! A minimal FMI 2.0 host in Rust over the crate's exported `extern "C"` functions (the same
//! symbols the shared library exports), with a logger that records every message.

use std::ffi::{CStr, CString, c_char, c_void};
use std::sync::Mutex;

use stewart_fmu::fmi::FmiVersion;
use stewart_fmu::fmi::description::instantiation_token;
use stewart_fmu::fmi2::exports::*;
use stewart_fmu::fmi2::types::*;
use stewart_fmu::models::ModelKind;
use stewart_fmu::models::variables::VariableTable;

/// One logged message.
#[derive(Clone, Debug)]
pub struct LogLine {
    pub status: fmi2Status,
    pub category: String,
    pub instance: String,
    pub message: String,
}

pub type LogSink = Mutex<Vec<LogLine>>;

/// The logger the FMU calls. FMI declares it C-variadic; this one takes the five fixed
/// arguments only, which is how a variadic call with no variadic arguments arrives on
/// x86-64 System V (the FMU passes a pre-formatted message and no arguments).
unsafe extern "C" fn record(
    env: *mut c_void,
    name: *const c_char,
    status: fmi2Status,
    category: *const c_char,
    message: *const c_char,
) {
    // SAFETY: env is the LogSink we registered; the strings are valid for the call.
    unsafe {
        let sink = &*(env as *const LogSink);
        let text = |p: *const c_char| {
            if p.is_null() { "<NULL>".to_string() } else { CStr::from_ptr(p).to_string_lossy().into_owned() }
        };
        if let Ok(mut v) = sink.lock() {
            v.push(LogLine { status, category: text(category), instance: text(name), message: text(message) });
        }
    }
}

pub fn callbacks(sink: &LogSink) -> fmi2CallbackFunctions {
    type Fixed = unsafe extern "C" fn(*mut c_void, *const c_char, fmi2Status, *const c_char, *const c_char);
    // SAFETY: see `record`; the pointer types differ only in the variadic tail.
    let logger: fmi2CallbackLogger = Some(unsafe {
        std::mem::transmute::<
            Fixed,
            unsafe extern "C" fn(*mut c_void, *const c_char, fmi2Status, *const c_char, *const c_char, ...),
        >(record as Fixed)
    });
    fmi2CallbackFunctions {
        logger,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: sink as *const LogSink as *mut c_void,
    }
}

/// An instance with its log.
pub struct Host {
    pub c: fmi2Component,
    pub log: Box<LogSink>,
    pub table: VariableTable,
    /// Host-side communication point.
    pub time: f64,
    _callbacks: Box<fmi2CallbackFunctions>,
}

// The instance is used from one thread at a time.
unsafe impl Send for Host {}

impl Host {
    pub fn new(name: &str, kind: ModelKind) -> Host {
        Host::with_interface(name, kind, fmi2CoSimulation)
    }

    /// An instance of the interface `fmu_type` (`fmi2CoSimulation` or `fmi2ModelExchange`).
    pub fn with_interface(name: &str, kind: ModelKind, fmu_type: fmi2Type) -> Host {
        let log: Box<LogSink> = Box::new(Mutex::new(vec![]));
        let cb = Box::new(callbacks(&log));
        let name = CString::new(name).unwrap();
        let guid = CString::new(instantiation_token(kind, FmiVersion::Fmi2)).unwrap();
        let c = unsafe {
            fmi2Instantiate(name.as_ptr(), fmu_type, guid.as_ptr(), c"file:///tmp".as_ptr(), &*cb, fmi2False, fmi2False)
        };
        assert!(!c.is_null(), "fmi2Instantiate failed");
        Host { c, log, table: VariableTable::new(kind.info().groups), time: 0.0, _callbacks: cb }
    }

    pub fn platform(name: &str) -> Host {
        Host::new(name, ModelKind::Platform)
    }

    pub fn vr(&self, name: &str) -> u32 {
        for (_, g, i) in self.table.elements() {
            if g.element_name(i) == name {
                return g.vr(i);
            }
        }
        panic!("no variable {name}")
    }

    pub fn messages(&self) -> Vec<LogLine> {
        self.log.lock().unwrap().clone()
    }

    pub fn clear_log(&self) {
        self.log.lock().unwrap().clear();
    }

    pub fn last_message(&self) -> String {
        self.messages().last().map(|l| l.message.clone()).unwrap_or_default()
    }

    pub fn setup(&mut self, stop: Option<f64>) -> fmi2Status {
        unsafe { fmi2SetupExperiment(self.c, fmi2False, 0.0, 0.0, stop.is_some() as i32, stop.unwrap_or(0.0)) }
    }

    pub fn enter(&mut self) -> fmi2Status {
        unsafe { fmi2EnterInitializationMode(self.c) }
    }

    pub fn exit(&mut self) -> fmi2Status {
        unsafe { fmi2ExitInitializationMode(self.c) }
    }

    /// setup + enter + (set values) + exit.
    pub fn initialise(&mut self, values: &[(&str, f64)]) -> fmi2Status {
        assert_eq!(self.setup(None), fmi2OK);
        assert_eq!(self.enter(), fmi2OK);
        for (n, v) in values {
            assert_eq!(self.set(n, *v), fmi2OK, "set {n}");
        }
        self.exit()
    }

    /// Sets a Real, or a Boolean (`value != 0` is true) or Integer parameter by name.
    pub fn set(&mut self, name: &str, value: f64) -> fmi2Status {
        let vr = self.vr(name);
        let ty = self.table.lookup(vr).map(|(g, _)| g.var_type);
        match ty {
            Some(t) if t.is_boolean() => {
                let b = if value != 0.0 { fmi2True } else { fmi2False };
                unsafe { fmi2SetBoolean(self.c, &vr, 1, &b) }
            }
            Some(t) if t.is_integer_like() => unsafe { fmi2SetInteger(self.c, &vr, 1, &(value as i32)) },
            _ => unsafe { fmi2SetReal(self.c, &vr, 1, &value) },
        }
    }

    pub fn get_bool(&self, name: &str) -> bool {
        let vr = self.vr(name);
        let mut x = fmi2False;
        assert_eq!(unsafe { fmi2GetBoolean(self.c, &vr, 1, &mut x) }, fmi2OK, "get {name}");
        x != fmi2False
    }

    pub fn set_many(&mut self, names: &[&str], values: &[f64]) -> fmi2Status {
        let vrs: Vec<u32> = names.iter().map(|n| self.vr(n)).collect();
        unsafe { fmi2SetReal(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }

    pub fn set_forces(&mut self, f: [f64; 6]) -> fmi2Status {
        let names: Vec<String> = (1..=6).map(|k| format!("F[{k}]")).collect();
        let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
        self.set_many(&names, &f)
    }

    pub fn get(&self, name: &str) -> f64 {
        let vr = self.vr(name);
        let mut x = f64::NAN;
        let s = unsafe { fmi2GetReal(self.c, &vr, 1, &mut x) };
        assert_eq!(s, fmi2OK, "get {name}");
        x
    }

    /// Every Real output and parameter of the FMI 2 interface, for "nothing changed"
    /// comparisons.
    pub fn all_reals(&self) -> Vec<u64> {
        let vrs: Vec<u32> = self
            .table
            .elements()
            .filter(|(_, g, _)| g.var_type.is_real() && !g.fmi3_only)
            .map(|(_, g, i)| g.vr(i))
            .collect();
        let mut out = vec![0.0; vrs.len()];
        let s = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
        assert_eq!(s, fmi2OK);
        out.iter().map(|x| x.to_bits()).collect()
    }

    pub fn step(&mut self, h: f64) -> fmi2Status {
        let s = unsafe { fmi2DoStep(self.c, self.time, h, fmi2True) };
        if s == fmi2OK {
            self.time += h;
        }
        s
    }

    /// The instance's complete state as bytes (get + serialize + free).
    pub fn state_bytes(&self) -> Vec<u8> {
        unsafe {
            let mut st: fmi2FMUstate = std::ptr::null_mut();
            assert_eq!(fmi2GetFMUstate(self.c, &mut st), fmi2OK);
            let mut size = 0usize;
            assert_eq!(fmi2SerializedFMUstateSize(self.c, st, &mut size), fmi2OK);
            let mut bytes = vec![0u8; size];
            assert_eq!(fmi2SerializeFMUstate(self.c, st, bytes.as_mut_ptr() as *mut fmi2Byte, size), fmi2OK);
            assert_eq!(fmi2FreeFMUstate(self.c, &mut st), fmi2OK);
            assert!(st.is_null());
            bytes
        }
    }

    pub fn restore_bytes(&mut self, bytes: &[u8]) -> fmi2Status {
        unsafe {
            let mut st: fmi2FMUstate = std::ptr::null_mut();
            let s = fmi2DeSerializeFMUstate(self.c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut st);
            if s != fmi2OK {
                return s;
            }
            let s = fmi2SetFMUstate(self.c, st);
            fmi2FreeFMUstate(self.c, &mut st);
            s
        }
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) };
    }
}

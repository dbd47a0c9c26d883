//! A minimal FMI 3.0 host in Rust over the crate's exported `fmi3*` functions, with a logger
//! that records every message. Variables are addressed as FMI 3 does: one value reference per
//! variable, arrays read and written whole.

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::sync::Mutex;

use stewart_fmu::fmi::FmiVersion;
use stewart_fmu::fmi::description::instantiation_token;
use stewart_fmu::fmi3::exports::*;
use stewart_fmu::fmi3::types::*;
use stewart_fmu::models::ModelKind;
use stewart_fmu::models::variables::{VariableGroup, VariableTable};

use super::fmi_host::LogLine;

pub type LogSink = Mutex<Vec<LogLine>>;

unsafe extern "C" fn record(env: *mut c_void, status: c_int, category: *const c_char, message: *const c_char) {
    // SAFETY: env is the LogSink we registered; the strings are valid for the call.
    unsafe {
        let sink = &*(env as *const LogSink);
        let text = |p: *const c_char| {
            if p.is_null() { "<NULL>".to_string() } else { CStr::from_ptr(p).to_string_lossy().into_owned() }
        };
        if let Ok(mut v) = sink.lock() {
            // FMI 3 messages carry no instance name: the environment identifies the instance.
            v.push(LogLine { status, category: text(category), instance: String::new(), message: text(message) });
        }
    }
}

/// Co-Simulation or Model Exchange.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    CoSimulation,
    ModelExchange,
}

/// An FMI 3 instance with its log.
pub struct Host3 {
    pub c: fmi3Instance,
    pub log: Box<LogSink>,
    pub table: VariableTable,
    pub kind: Kind,
    /// Host-side communication point (Co-Simulation).
    pub time: f64,
}

unsafe impl Send for Host3 {}

impl Host3 {
    /// An instance, or `None` with the log if instantiation was refused.
    pub fn try_new(name: &str, model: ModelKind, kind: Kind, event_mode: bool) -> Result<Host3, Vec<LogLine>> {
        Self::with_token(name, model, kind, event_mode, instantiation_token(model, FmiVersion::Fmi3))
    }

    pub fn with_token(
        name: &str,
        model: ModelKind,
        kind: Kind,
        event_mode: bool,
        token: &str,
    ) -> Result<Host3, Vec<LogLine>> {
        let log: Box<LogSink> = Box::new(Mutex::new(vec![]));
        let env = &*log as *const LogSink as *mut c_void;
        let name = CString::new(name).unwrap();
        let token = CString::new(token).unwrap();
        let c = unsafe {
            match kind {
                Kind::CoSimulation => fmi3InstantiateCoSimulation(
                    name.as_ptr(),
                    token.as_ptr(),
                    c"file:///tmp/".as_ptr(),
                    fmi3False,
                    fmi3False,
                    event_mode as fmi3Boolean,
                    event_mode as fmi3Boolean,
                    std::ptr::null(),
                    0,
                    env,
                    Some(record),
                    None,
                ),
                Kind::ModelExchange => fmi3InstantiateModelExchange(
                    name.as_ptr(),
                    token.as_ptr(),
                    c"file:///tmp/".as_ptr(),
                    fmi3False,
                    fmi3False,
                    env,
                    Some(record),
                ),
            }
        };
        if c.is_null() {
            return Err(log.lock().unwrap().clone());
        }
        Ok(Host3 { c, log, table: VariableTable::new(model.info().groups), kind, time: 0.0 })
    }

    pub fn platform(name: &str, kind: Kind) -> Host3 {
        Host3::try_new(name, ModelKind::Platform, kind, false).unwrap_or_else(|log| panic!("{log:?}"))
    }

    /// The variable `name` (FMI 3 name: `F`, `r`, `M`, `der(v)`).
    pub fn variable(&self, name: &str) -> &'static VariableGroup {
        self.table.groups.iter().find(|g| g.variable_name() == name).unwrap_or_else(|| panic!("no variable {name}"))
    }

    pub fn vr(&self, name: &str) -> u32 {
        self.variable(name).vr(0)
    }

    pub fn messages(&self) -> Vec<LogLine> {
        self.log.lock().unwrap().clone()
    }

    pub fn clear_log(&self) {
        self.log.lock().unwrap().clear();
    }

    pub fn enter(&mut self) -> fmi3Status {
        unsafe { fmi3EnterInitializationMode(self.c, fmi3False, 0.0, 0.0, fmi3False, 0.0) }
    }

    pub fn exit(&mut self) -> fmi3Status {
        unsafe { fmi3ExitInitializationMode(self.c) }
    }

    /// enter + (set values) + exit.
    pub fn initialise(&mut self, values: &[(&str, &[f64])]) -> fmi3Status {
        assert_eq!(self.enter(), fmi3OK);
        for (n, v) in values {
            assert_eq!(self.set(n, v), fmi3OK, "set {n}: {:?}", self.messages());
        }
        self.exit()
    }

    /// Sets a whole Float64, Int32 or Boolean variable (`value != 0` is true).
    pub fn set(&mut self, name: &str, values: &[f64]) -> fmi3Status {
        let g = self.variable(name);
        let vr = g.vr(0);
        unsafe {
            if g.var_type.is_boolean() {
                let b: Vec<fmi3Boolean> = values.iter().map(|&v| (v != 0.0) as fmi3Boolean).collect();
                fmi3SetBoolean(self.c, &vr, 1, b.as_ptr(), b.len())
            } else if g.var_type.is_integer_like() {
                let i: Vec<i32> = values.iter().map(|&v| v as i32).collect();
                fmi3SetInt32(self.c, &vr, 1, i.as_ptr(), i.len())
            } else {
                fmi3SetFloat64(self.c, &vr, 1, values.as_ptr(), values.len())
            }
        }
    }

    pub fn get(&self, name: &str) -> Vec<f64> {
        let g = self.variable(name);
        let vr = g.vr(0);
        let mut out = vec![f64::NAN; g.len()];
        let s = unsafe { fmi3GetFloat64(self.c, &vr, 1, out.as_mut_ptr(), out.len()) };
        assert_eq!(s, fmi3OK, "get {name}: {:?}", self.messages());
        out
    }

    /// One Co-Simulation step from the host's clock; returns the status and `earlyReturn`.
    pub fn step(&mut self, h: f64) -> (fmi3Status, bool) {
        let (mut event, mut terminate, mut early, mut last) = (0u8, 0u8, 0u8, f64::NAN);
        let s =
            unsafe { fmi3DoStep(self.c, self.time, h, fmi3True, &mut event, &mut terminate, &mut early, &mut last) };
        if s == fmi3OK || s == fmi3Warning {
            self.time = last;
        }
        (s, early != 0)
    }

    /// The instance's complete state as bytes (get + serialize + free).
    pub fn state_bytes(&self) -> Vec<u8> {
        unsafe {
            let mut st: fmi3FMUState = std::ptr::null_mut();
            assert_eq!(fmi3GetFMUState(self.c, &mut st), fmi3OK, "{:?}", self.messages());
            let mut size = 0usize;
            assert_eq!(fmi3SerializedFMUStateSize(self.c, st, &mut size), fmi3OK);
            let mut bytes = vec![0u8; size];
            assert_eq!(fmi3SerializeFMUState(self.c, st, bytes.as_mut_ptr(), size), fmi3OK);
            assert_eq!(fmi3FreeFMUState(self.c, &mut st), fmi3OK);
            assert!(st.is_null());
            bytes
        }
    }
}

impl Drop for Host3 {
    fn drop(&mut self) {
        unsafe { fmi3FreeInstance(self.c) };
    }
}

//! FMU states: the instance as pointer-free bytes (format: [`crate::models::snapshot`]), the
//! states the instance owns and the importer's handles to them.

use std::ffi::c_void;

use super::Instance;
use crate::fmi::log::LogCategory;
use crate::fmi::{InterfaceType, ModelState, Status};
use crate::models::AnyModel;
use crate::models::snapshot::{self, ByteReader, ByteWriter, SnapshotError};

/// An FMU state (`fmi2FMUstate`, `fmi3FMUState`): the serialized bytes of an instance. The
/// instance that made it owns it; the importer's handle is its address, recognised by
/// comparison with the instance's own states, never by reading through it.
pub struct FmuState {
    bytes: Vec<u8>,
}

/// A restorable picture of an instance, parsed and validated.
pub(super) struct Snapshot {
    state: ModelState,
    time: f64,
    start_time: f64,
    stop_time: Option<f64>,
    tolerance: Option<f64>,
    terminated: bool,
    last_successful_time: f64,
    model: AnyModel,
}

pub(super) fn option_f64(w: &mut ByteWriter, x: Option<f64>) {
    w.bool(x.is_some());
    w.f64(x.unwrap_or(0.0));
}

pub(super) fn read_option_f64(r: &mut ByteReader, what: &str) -> Result<Option<f64>, SnapshotError> {
    let present = r.bool()?;
    let x = r.f64()?;
    if present {
        if x.is_finite() { Ok(Some(x)) } else { Err(SnapshotError(format!("{what} is not finite"))) }
    } else {
        Ok(None)
    }
}

impl Instance {
    /// The instance as pointer-free bytes (format: [`crate::models::snapshot`]).
    pub fn serialize(&self) -> Vec<u8> {
        let mut payload = ByteWriter::default();
        payload.u8(match self.interface {
            InterfaceType::ModelExchange => 0,
            InterfaceType::CoSimulation => 1,
        });
        payload.u8(self.state as u8);
        payload.f64(self.time);
        payload.f64(self.start_time);
        option_f64(&mut payload, self.stop_time);
        option_f64(&mut payload, self.tolerance);
        payload.bool(self.terminated);
        payload.f64(self.last_successful_time);
        self.model.save(&mut payload);
        snapshot::seal(self.kind.code(), self.token_hash, &payload.bytes)
    }

    pub(super) fn parse(&self, bytes: &[u8]) -> Result<Snapshot, SnapshotError> {
        let payload = snapshot::open(bytes, self.kind.code(), self.token_hash)?;
        let mut p = ByteReader::new(payload);
        let interface = match p.u8()? {
            0 => InterfaceType::ModelExchange,
            1 => InterfaceType::CoSimulation,
            x => return Err(SnapshotError(format!("invalid interface type {x}"))),
        };
        if interface != self.interface {
            return Err(SnapshotError(format!(
                "state of a {} instance, this one is {}",
                interface.name(),
                self.interface.name()
            )));
        }
        let code = p.u8()?;
        let state = ModelState::from_code(code).ok_or_else(|| SnapshotError(format!("invalid model state {code}")))?;
        let time = p.finite("time")?;
        let start_time = p.finite("start time")?;
        let stop_time = read_option_f64(&mut p, "stop time")?;
        let tolerance = read_option_f64(&mut p, "tolerance")?;
        let terminated = p.bool()?;
        let last_successful_time = p.finite("last successful time")?;
        let model = AnyModel::restore(self.kind, &mut p)?;
        if p.remaining() != 0 {
            return Err(SnapshotError(format!("{} unexpected bytes at the end of the model data", p.remaining())));
        }
        Ok(Snapshot { state, time, start_time, stop_time, tolerance, terminated, last_successful_time, model })
    }

    /// Checks bytes without restoring them (deserialization).
    pub fn validate_state_bytes(&self, bytes: &[u8]) -> Result<(), SnapshotError> {
        self.parse(bytes).map(|_| ())
    }

    /// Restores the instance from bytes, all or nothing.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), SnapshotError> {
        let s = self.parse(bytes)?;
        self.state = s.state;
        self.time = s.time;
        self.start_time = s.start_time;
        self.stop_time = s.stop_time;
        self.tolerance = s.tolerance;
        self.terminated = s.terminated;
        self.last_successful_time = s.last_successful_time;
        self.replace_model(s.model);
        self.logger.log(
            Status::Ok,
            LogCategory::Events,
            &format!("FMU state restored: t = {}, state {}", self.time, self.state_name()),
        );
        Ok(())
    }

    /// Index of the state behind an importer's handle among this instance's own states.
    pub(super) fn own_state(&self, handle: *mut c_void) -> Option<usize> {
        self.fmu_states.iter().position(|s| std::ptr::eq(&**s, handle as *const FmuState))
    }

    pub(super) fn state_refused(&self, handle: *mut c_void, what: &str) -> Status {
        if handle.is_null() {
            self.error(&format!("{what} is NULL"))
        } else {
            self.error(&format!(
                "{what} {handle:?} is not a live FMU state of this instance (freed already, made by another \
                 instance, or not an FMU state; to move a state between instances, serialize it)"
            ))
        }
    }

    /// `fmi2GetFMUstate`/`fmi3GetFMUState`: a new state in `*slot` if it is NULL, else the
    /// instance's state `*slot` overwritten.
    pub fn get_fmu_state(&mut self, slot: &mut *mut c_void) -> Status {
        let bytes = self.serialize();
        self.store_fmu_state(slot, bytes)
    }

    pub(super) fn store_fmu_state(&mut self, slot: &mut *mut c_void, bytes: Vec<u8>) -> Status {
        if slot.is_null() {
            let state = Box::new(FmuState { bytes });
            *slot = &*state as *const FmuState as *mut c_void;
            self.fmu_states.push(state);
            return Status::Ok;
        }
        match self.own_state(*slot) {
            Some(i) => {
                if let Some(s) = self.fmu_states.get_mut(i) {
                    s.bytes = bytes;
                }
                Status::Ok
            }
            None => self.state_refused(*slot, "*FMUstate"),
        }
    }

    /// `fmi2SetFMUstate`/`fmi3SetFMUState`.
    pub fn set_fmu_state(&mut self, handle: *mut c_void) -> Status {
        let Some(i) = self.own_state(handle) else { return self.state_refused(handle, "FMUstate") };
        // Taken out while the instance restores from it (no copy), then put back.
        let bytes = self.fmu_states.get_mut(i).map(|s| std::mem::take(&mut s.bytes)).unwrap_or_default();
        let result = self.restore(&bytes);
        if let Some(s) = self.fmu_states.get_mut(i) {
            s.bytes = bytes;
        }
        match result {
            Ok(()) => Status::Ok,
            Err(e) => self.error(&format!("state refused: {e}")),
        }
    }

    /// `fmi2FreeFMUstate`/`fmi3FreeFMUState`: NULL is fine; only this instance's own states.
    pub fn free_fmu_state(&mut self, slot: &mut *mut c_void) -> Status {
        if slot.is_null() {
            return Status::Ok;
        }
        match self.own_state(*slot) {
            Some(i) => {
                self.fmu_states.swap_remove(i);
                *slot = std::ptr::null_mut();
                Status::Ok
            }
            None => self.state_refused(*slot, "*FMUstate"),
        }
    }

    /// `fmi2SerializeFMUstate`/`fmi3SerializeFMUState`: a state's bytes into the importer's
    /// buffer (`out`, all the bytes it gave), which must be large enough.
    pub fn serialize_fmu_state(&self, handle: *mut c_void, out: &mut [u8]) -> Status {
        let bytes = match self.fmu_state_bytes(handle) {
            Ok(bytes) => bytes,
            Err(status) => return status,
        };
        match out.get_mut(..bytes.len()) {
            Some(slots) => {
                slots.copy_from_slice(bytes);
                Status::Ok
            }
            None => self.error(&format!("buffer of {} bytes is too small, the state needs {}", out.len(), bytes.len())),
        }
    }

    /// The bytes of one of this instance's states.
    pub fn fmu_state_bytes(&self, handle: *mut c_void) -> Result<&[u8], Status> {
        match self.own_state(handle).and_then(|i| self.fmu_states.get(i)) {
            Some(s) => Ok(&s.bytes),
            None => Err(self.state_refused(handle, "FMUstate")),
        }
    }

    /// `fmi2DeSerializeFMUstate`/`fmi3DeserializeFMUState`: checked bytes into a new state
    /// (`*slot` NULL) or into one of this instance's states.
    pub fn deserialize_fmu_state(&mut self, bytes: &[u8], slot: &mut *mut c_void) -> Status {
        if let Err(e) = self.validate_state_bytes(bytes) {
            return self.error(&format!("serialized state refused: {e}"));
        }
        self.store_fmu_state(slot, bytes.to_vec())
    }
}

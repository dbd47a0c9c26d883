//! FMU states (FMI 3.0 section 2.2.7).

use super::*;

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFMUState(instance: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    boundary!(instance, F::GetFMUState, args("FMUState = {state:?}"), |inst| {
        let slot = try_out!(inst, state, "FMUState");
        inst.get_fmu_state(slot)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFMUState(instance: fmi3Instance, state: fmi3FMUState) -> fmi3Status {
    boundary!(instance, F::SetFMUState, args("FMUState = {state:?}"), |inst| { inst.set_fmu_state(state) })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeFMUState(instance: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    boundary!(instance, F::FreeFMUState, args("FMUState = {state:?}"), |inst| {
        let slot = try_out!(inst, state, "FMUState");
        inst.free_fmu_state(slot)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    state: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    boundary!(instance, F::SerializedFMUStateSize, args("FMUState = {state:?}"), |inst| {
        let out = try_out!(inst, size, "size");
        match inst.fmu_state_bytes(state) {
            Ok(bytes) => {
                *out = bytes.len();
                Status::Ok
            }
            Err(status) => status,
        }
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    state: fmi3FMUState,
    serialized: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    boundary!(instance, F::SerializeFMUState, args("FMUState = {state:?}, size = {size}"), |inst| {
        let out = try_slice_mut!(inst, serialized, size, "serializedState");
        inst.serialize_fmu_state(state, out)
    })
}

/// # Safety
/// See the documentation of the `exports` module.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serialized: *const fmi3Byte,
    size: usize,
    state: *mut fmi3FMUState,
) -> fmi3Status {
    boundary!(instance, F::DeserializeFMUState, args("size = {size}"), |inst| {
        let bytes = try_slice!(inst, serialized, size, "serializedState");
        let slot = try_out!(inst, state, "FMUState");
        inst.deserialize_fmu_state(bytes, slot)
    })
}

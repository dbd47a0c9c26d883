//! The C boundary's safety net, in one place for both FMI versions (after rustls-ffi's
//! `ffi_panic_boundary!` and pointer macros): every exported function runs its body through
//! [`call`] (or [`no_instance`]), which catches panics, checks the instance pointer, the
//! instance's poisoning and the state table, sets the calling function as the instance's
//! context for its messages, and turns everything into an FMI status.

use std::any::Any;
use std::ffi::c_void;
use std::panic::{AssertUnwindSafe, catch_unwind};

use super::instance::Instance;
use super::registry::{self, Access};
use super::{FmiFunction, Status};

/// A panic's message, if it carried one.
pub fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "(no message)".to_string()
    }
}

/// Runs an exported function's body on a valid instance.
///
/// - `c` not a live instance of this FMI version (NULL, freed, foreign, the other version),
///   or busy with another call (a call from the importer's callback, or from a second thread
///   at the same time): error, without touching the memory behind `c` (there is no logger
///   to tell).
/// - instance poisoned by an earlier panic, or `func` not allowed in its state: logged,
///   error, nothing changes.
/// - body panics: the instance is poisoned, the panic is logged, error.
/// - the instance was freed during the call (from the importer's callback): dropped when the
///   call returns.
///
/// # Safety
/// `c` may be any pointer: it is never dereferenced; the instance is used only if the
/// registry knows `c` as the handle of a live instance of this version.
pub unsafe fn call<F: FmiFunction>(
    c: *mut c_void,
    func: F,
    args: impl FnOnce() -> String,
    body: impl FnOnce(&mut Instance) -> Status,
) -> Status {
    let Access::Granted(busy) = registry::acquire(c, F::VERSION) else {
        return Status::Error;
    };
    let address = busy.instance();
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: the registry granted the handle: a live Box<Instance> no other call is
        // using.
        let instance = unsafe { &mut *(address as *mut Instance) };
        instance.begin(func.name());
        if let Err(status) = instance.check_call(func) {
            return status;
        }
        match catch_unwind(AssertUnwindSafe(|| body(&mut *instance))) {
            Ok(status) => {
                instance.log_call(status, args);
                status
            }
            Err(payload) => {
                instance.poison(&panic_message(payload.as_ref()));
                Status::Error
            }
        }
    }));
    if registry::release(busy) {
        // SAFETY: freed by the importer during the call and now unregistered: nothing else
        // refers to it.
        unsafe { Instance::drop_instance(address) };
    }
    outcome.unwrap_or(Status::Error)
}

/// `fmi2FreeInstance`/`fmi3FreeInstance` (`func` names it): a live, idle instance is dropped
/// now; one a call is running on (freed from the importer's callback) when that call returns;
/// NULL, freed or foreign handles are left alone.
///
/// # Safety
/// `c` may be any pointer: it is never dereferenced; the instance is dropped only if the
/// registry knows `c` as the handle of a live, idle instance of this version.
pub unsafe fn free_instance<F: FmiFunction>(c: *mut c_void, func: F) {
    no_instance((), || {
        if let registry::Free::Now(address) = registry::request_free(c, F::VERSION) {
            // SAFETY: the registry handed the live, idle instance over for dropping.
            let instance = unsafe { &mut *(address as *mut Instance) };
            instance.begin(func.name());
            instance.log_call(Status::Ok, String::new);
            // SAFETY: as above; no reference to it remains.
            unsafe { Instance::drop_instance(address) };
        }
    })
}

/// Fixes the signature of an export's body closure (for type inference in `boundary!`).
pub fn instance_body<F: FnOnce(&mut Instance) -> Status>(body: F) -> F {
    body
}

/// Runs a body that has no instance (`fmi2Instantiate`, `fmi2FreeInstance`,
/// `fmi2GetVersion`...), returning `on_panic` if it panics.
pub fn no_instance<T>(on_panic: T, body: impl FnOnce() -> T) -> T {
    catch_unwind(AssertUnwindSafe(body)).unwrap_or(on_panic)
}

/// A slice from a C array: `Some(&[])` for `n == 0` (whatever the pointer), `None` for a NULL
/// pointer with `n > 0`.
///
/// # Safety
/// A non-NULL `ptr` must point to `n` initialised values that stay valid and unaliased for
/// the call.
#[inline(always)]
pub unsafe fn c_slice<'a, T>(ptr: *const T, n: usize) -> Option<&'a [T]> {
    if ptr.is_null() {
        return null_slice(n);
    }
    // SAFETY: non-NULL, and the caller guarantees `n` valid elements.
    Some(unsafe { std::slice::from_raw_parts(ptr, n) })
}

/// The text of a C string (`None`: NULL, or not UTF-8).
///
/// # Safety
/// A non-NULL `ptr` must point to a NUL-terminated string that stays valid for the call.
pub unsafe fn c_text<'a>(ptr: *const std::ffi::c_char) -> Option<&'a str> {
    if ptr.is_null() {
        return None;
    }
    // SAFETY: non-NULL, and the caller guarantees a NUL-terminated string.
    unsafe { std::ffi::CStr::from_ptr(ptr) }.to_str().ok()
}

/// [`c_slice`] of a NULL pointer, out of the usual path: empty for `n == 0`.
#[cold]
fn null_slice<'a, T>(n: usize) -> Option<&'a [T]> {
    (n == 0).then_some(&[])
}

/// The mutable counterpart of [`c_slice`].
///
/// # Safety
/// As for [`c_slice`], and the memory must be writable.
#[inline(always)]
pub unsafe fn c_slice_mut<'a, T>(ptr: *mut T, n: usize) -> Option<&'a mut [T]> {
    if ptr.is_null() {
        return null_slice_mut(n);
    }
    // SAFETY: non-NULL, and the caller guarantees `n` valid, writable elements.
    Some(unsafe { std::slice::from_raw_parts_mut(ptr, n) })
}

/// [`c_slice_mut`] of a NULL pointer, out of the usual path.
#[cold]
fn null_slice_mut<'a, T>(n: usize) -> Option<&'a mut [T]> {
    (n == 0).then_some(&mut [])
}

/// A C array for a `logCalls` message: up to eight values, then the count.
///
/// # Safety
/// As for [`c_slice`].
pub unsafe fn show<T: std::fmt::Debug>(ptr: *const T, n: usize) -> String {
    const SHOWN: usize = 8;
    // SAFETY: forwarded to the caller.
    match unsafe { c_slice(ptr, n) } {
        None => format!("NULL ({n} values)"),
        Some(s) if n <= SHOWN => format!("{s:?}"),
        Some(s) => format!("{:?}... ({n} values)", &s[..SHOWN]),
    }
}

/// `try_slice!(instance, ptr, n, "name")`: the slice, or log and return an error.
macro_rules! try_slice {
    ($inst:expr, $ptr:expr, $n:expr, $what:expr) => {
        // SAFETY: the importer passes arrays of `n` elements (the FMI calling convention).
        match unsafe { $crate::fmi::boundary::c_slice($ptr, $n) } {
            Some(s) => s,
            None => return $inst.error(&format!("argument {} is NULL with {} elements", $what, $n)),
        }
    };
}

/// Mutable counterpart of `try_slice!`.
macro_rules! try_slice_mut {
    ($inst:expr, $ptr:expr, $n:expr, $what:expr) => {
        // SAFETY: the importer passes writable arrays of `n` elements.
        match unsafe { $crate::fmi::boundary::c_slice_mut($ptr, $n) } {
            Some(s) => s,
            None => return $inst.error(&format!("argument {} is NULL with {} elements", $what, $n)),
        }
    };
}

/// `try_out!(instance, ptr, "name")`: a `&mut T` from an out-pointer, or log and return an
/// error if it is NULL.
macro_rules! try_out {
    ($inst:expr, $ptr:expr, $what:expr) => {
        // SAFETY: a non-NULL out-pointer from the importer points to a writable value.
        match unsafe { $ptr.as_mut() } {
            Some(r) => r,
            None => return $inst.error(&format!("argument {} is NULL", $what)),
        }
    };
}

/// `boundary!(c, function, |inst| body)`: the panic boundary of an exported function that
/// takes an instance (see [`call`]), returning the status as the C int of either version.
/// `boundary!(c, function, args("fmt", ...), |inst| body)` also names the call's arguments
/// for the `logCalls` message (formatted after the body, and only when that category is on,
/// so output arrays show what was returned; [`show`] prints a C array).
macro_rules! boundary {
    ($c:expr, $func:expr, $body:expr) => {
        $crate::fmi::boundary::boundary!($c, $func, args(""), $body)
    };
    ($c:expr, $func:expr, args($($fmt:tt)+), $body:expr) => {{
        // The body is built outside the unsafe block, so its own unsafe operations keep
        // their own blocks and SAFETY comments.
        let body = $crate::fmi::boundary::instance_body($body);
        #[allow(unused_unsafe)]
        // SAFETY: runs during the call, while the importer's arrays are valid (`show` reads
        // `n` elements of a non-NULL pointer, as the body does).
        let args = || unsafe { format!($($fmt)+) };
        // SAFETY: `$c` is the importer's instance pointer, NULL or from our instantiation and
        // not freed, under the FMI calling convention the exports document.
        unsafe { $crate::fmi::boundary::call($c as *mut ::std::ffi::c_void, $func, args, body) }.code()
    }};
}

pub(crate) use {boundary, try_out, try_slice, try_slice_mut};

//! The live instances of this library, so that a handle is dereferenced only when it is one
//! of them. An importer may pass a freed, foreign or other-version handle, free an instance
//! from inside its own logger callback while a call on it is running, or call one instance
//! from two threads at once: the registry recognises all of these by the handle's address
//! alone, without reading the memory behind it.
//!
//! This is the crate's one piece of process-wide mutable state (a handle is all the context
//! the C functions get). It holds no heap memory while no instance is live, so unloading the
//! library leaves nothing behind.

use std::ffi::c_void;
use std::sync::{Mutex, MutexGuard};

use super::FmiVersion;

struct Entry {
    address: usize,
    version: FmiVersion,
    /// A call on the instance is running (the boundary holds a `&mut Instance`).
    busy: bool,
    /// `fmi2FreeInstance`/`fmi3FreeInstance` came while busy: free when the call returns.
    free_requested: bool,
}

/// Sorted by address.
static LIVE: Mutex<Vec<Entry>> = Mutex::new(Vec::new());

fn live() -> MutexGuard<'static, Vec<Entry>> {
    // Nothing panics while the lock is held; a poisoned lock still holds consistent entries.
    LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

fn find(entries: &[Entry], p: *mut c_void) -> Result<usize, usize> {
    entries.binary_search_by_key(&(p as usize), |e| e.address)
}

/// Records a new instance.
pub fn register(p: *mut c_void, version: FmiVersion) {
    let mut entries = live();
    if let Err(at) = find(&entries, p) {
        entries.insert(at, Entry { address: p as usize, version, busy: false, free_requested: false });
    }
}

/// Whether a call may use the instance behind a handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Live, of this FMI version and idle: now marked busy until [`release`].
    Granted,
    /// NULL, freed, foreign, or an instance of the other FMI version.
    Unknown,
    /// A call on it is running (a call from the importer's callback during a call, or from a
    /// second thread at the same time).
    Busy,
}

/// Marks a live, idle instance of `version` busy for one call.
pub fn acquire(p: *mut c_void, version: FmiVersion) -> Access {
    let mut entries = live();
    match find(&entries, p) {
        Ok(i) => match entries.get_mut(i) {
            Some(e) if e.version != version || e.free_requested => Access::Unknown,
            Some(e) if e.busy => Access::Busy,
            Some(e) => {
                e.busy = true;
                Access::Granted
            }
            None => Access::Unknown,
        },
        Err(_) => Access::Unknown,
    }
}

/// Ends a call; `true` if the instance was freed during it and must be dropped now (it is no
/// longer registered).
pub fn release(p: *mut c_void) -> bool {
    let mut entries = live();
    let Ok(i) = find(&entries, p) else { return false };
    let free_now = entries.get(i).is_some_and(|e| e.free_requested);
    if free_now {
        remove_at(&mut entries, i);
    } else if let Some(e) = entries.get_mut(i) {
        e.busy = false;
    }
    free_now
}

/// What to do with an instance the importer frees.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Free {
    /// Unregistered: drop it now.
    Now,
    /// A call on it is running: it is dropped when that call returns.
    Deferred,
    /// Not a live instance of this version (NULL, already freed, foreign): nothing to do.
    Unknown,
}

pub fn request_free(p: *mut c_void, version: FmiVersion) -> Free {
    let mut entries = live();
    let Ok(i) = find(&entries, p) else { return Free::Unknown };
    match entries.get_mut(i) {
        Some(e) if e.version != version || e.free_requested => Free::Unknown,
        Some(e) if e.busy => {
            e.free_requested = true;
            Free::Deferred
        }
        Some(_) => {
            remove_at(&mut entries, i);
            Free::Now
        }
        None => Free::Unknown,
    }
}

fn remove_at(entries: &mut Vec<Entry>, i: usize) {
    entries.remove(i);
    if entries.is_empty() {
        // Give the buffer back: an unloaded library must leave no heap block behind.
        *entries = Vec::new();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn handles_are_recognised_by_address_alone() {
        let a = 0x1000 as *mut c_void;
        let b = 0x2000 as *mut c_void;
        register(a, FmiVersion::Fmi2);
        register(b, FmiVersion::Fmi3);
        assert_eq!(acquire(a, FmiVersion::Fmi3), Access::Unknown, "other version");
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::Granted);
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::Busy, "re-entrant");
        assert_eq!(request_free(a, FmiVersion::Fmi2), Free::Deferred);
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::Unknown, "being freed");
        assert!(release(a), "freed when the running call returns");
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::Unknown, "stale");
        assert_eq!(request_free(a, FmiVersion::Fmi2), Free::Unknown, "double free");
        assert_eq!(request_free(b, FmiVersion::Fmi3), Free::Now);
        assert_eq!(acquire(std::ptr::null_mut(), FmiVersion::Fmi2), Access::Unknown);
    }
}

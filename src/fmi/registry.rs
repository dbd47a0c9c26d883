//! The live instances of this library, so that a handle is dereferenced only when it is one
//! of them. An importer may pass a freed, foreign or other-version handle, free an instance
//! from inside its own logger callback while a call on it is running, or call one instance
//! from two threads at once: the registry recognises all of these by the handle's address
//! alone, without reading the memory behind it.
//!
//! This is the crate's one piece of process-wide mutable state (a handle is all the context
//! the C functions get). It is a fixed open-addressing table of atomics in static memory, so
//! that every call checks its handle with a few instructions and no lock, and unloading the
//! library leaves no heap memory behind. It holds up to [`CAPACITY`] live instances.

use std::ffi::c_void;
use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering};

use super::FmiVersion;

/// Live instances at most (per process and library).
pub const CAPACITY: usize = 1 << 16;
const BITS: u32 = CAPACITY.trailing_zeros();

// Slot states. A live slot is LIVE | version bit, plus BUSY while a call runs on it and
// FREEING once the importer freed it during that call.
const EMPTY: u8 = 0;
const TOMBSTONE: u8 = 1;
const RESERVED: u8 = 2;
const LIVE: u8 = 4;
const FMI3: u8 = 8;
const BUSY: u8 = 16;
const FREEING: u8 = 32;

struct Slot {
    address: AtomicUsize,
    state: AtomicU8,
}

static SLOTS: [Slot; CAPACITY] =
    [const { Slot { address: AtomicUsize::new(0), state: AtomicU8::new(EMPTY) } }; CAPACITY];

fn live_state(version: FmiVersion) -> u8 {
    match version {
        FmiVersion::Fmi2 => LIVE,
        FmiVersion::Fmi3 => LIVE | FMI3,
    }
}

/// The probe sequence of an address: its hash, then the following slots.
fn probe(p: *mut c_void) -> impl Iterator<Item = &'static Slot> {
    // Box addresses are 16-byte aligned: drop those bits, then Fibonacci hashing.
    let start = ((p as usize as u64 >> 4).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - BITS)) as usize;
    (0..CAPACITY).filter_map(move |i| SLOTS.get((start + i) & (CAPACITY - 1)))
}

/// The live slot of `p`, if any.
#[inline(always)]
fn find(p: *mut c_void) -> Option<&'static Slot> {
    if p.is_null() {
        return None;
    }
    // The usual case first: `p` in the slot its hash names (few instances, few collisions).
    for slot in probe(p) {
        let state = slot.state.load(Ordering::Acquire);
        if state & LIVE != 0 && slot.address.load(Ordering::Acquire) == p as usize {
            return Some(slot);
        }
        if state == EMPTY {
            return None;
        }
    }
    None
}

/// Records a new instance; `false` if [`CAPACITY`] instances are live already.
pub fn register(p: *mut c_void, version: FmiVersion) -> bool {
    for slot in probe(p) {
        for free in [EMPTY, TOMBSTONE] {
            if slot.state.compare_exchange(free, RESERVED, Ordering::AcqRel, Ordering::Acquire).is_ok() {
                slot.address.store(p as usize, Ordering::Release);
                slot.state.store(live_state(version), Ordering::Release);
                return true;
            }
        }
    }
    false
}

/// Whether a call may use the instance behind a handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Live, of this FMI version and idle: now marked busy until [`release`] of this call's
    /// [`Busy`] token.
    Granted(Busy),
    /// NULL, freed, foreign, or an instance of the other FMI version.
    Unknown,
    /// A call on it is running (a call from the importer's callback during a call, or from a
    /// second thread at the same time).
    InUse,
}

/// The registry slot of an instance a call is running on: handed back to [`release`], so that
/// ending the call needs no second search.
#[derive(Clone, Copy)]
pub struct Busy(&'static Slot);

impl PartialEq for Busy {
    fn eq(&self, other: &Self) -> bool {
        std::ptr::eq(self.0, other.0)
    }
}

impl Eq for Busy {}

impl std::fmt::Debug for Busy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Busy({:p})", self.0)
    }
}

/// Marks a live, idle instance of `version` busy for one call.
#[inline]
pub fn acquire(p: *mut c_void, version: FmiVersion) -> Access {
    let Some(slot) = find(p) else { return Access::Unknown };
    let idle = live_state(version);
    match slot.state.compare_exchange(idle, idle | BUSY, Ordering::AcqRel, Ordering::Acquire) {
        Ok(_) => Access::Granted(Busy(slot)),
        Err(now) if now & BUSY != 0 && now & FREEING == 0 && now & FMI3 == idle & FMI3 => Access::InUse,
        Err(_) => Access::Unknown,
    }
}

/// Ends a call; `true` if the instance was freed during it and must be dropped now (it is no
/// longer registered).
#[inline]
pub fn release(busy: Busy) -> bool {
    let Busy(slot) = busy;
    // BUSY is set (this call set it), so subtracting it clears exactly that bit, in one atomic
    // instruction that also returns the state before.
    let before = slot.state.fetch_sub(BUSY, Ordering::AcqRel);
    if before & FREEING != 0 {
        // Freed during the call: nothing else may use the slot any more (acquire and
        // request_free refuse a FREEING state), so a plain store ends it.
        slot.state.store(TOMBSTONE, Ordering::Release);
        return true;
    }
    false
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
    let Some(slot) = find(p) else { return Free::Unknown };
    let idle = live_state(version);
    let mut state = slot.state.load(Ordering::Acquire);
    loop {
        let (next, outcome) = if state == idle {
            (TOMBSTONE, Free::Now)
        } else if state == idle | BUSY {
            (idle | BUSY | FREEING, Free::Deferred)
        } else {
            return Free::Unknown; // the other version, or being freed already
        };
        match slot.state.compare_exchange(state, next, Ordering::AcqRel, Ordering::Acquire) {
            Ok(_) => return outcome,
            Err(now) => state = now,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn handles_are_recognised_by_address_alone() {
        let a = 0x1000 as *mut c_void;
        let b = 0x2000 as *mut c_void;
        assert!(register(a, FmiVersion::Fmi2));
        assert!(register(b, FmiVersion::Fmi3));
        assert_eq!(acquire(a, FmiVersion::Fmi3), Access::Unknown, "other version");
        let Access::Granted(busy) = acquire(a, FmiVersion::Fmi2) else { panic!("not granted") };
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::InUse, "re-entrant");
        assert_eq!(request_free(a, FmiVersion::Fmi2), Free::Deferred);
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::Unknown, "being freed");
        assert!(release(busy), "freed when the running call returns");
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::Unknown, "stale");
        assert_eq!(request_free(a, FmiVersion::Fmi2), Free::Unknown, "double free");
        assert_eq!(request_free(b, FmiVersion::Fmi3), Free::Now);
        assert_eq!(acquire(std::ptr::null_mut(), FmiVersion::Fmi2), Access::Unknown);
        // A freed slot is reused.
        assert!(register(a, FmiVersion::Fmi3));
        let Access::Granted(busy) = acquire(a, FmiVersion::Fmi3) else { panic!("not granted") };
        assert!(!release(busy));
        assert_eq!(request_free(a, FmiVersion::Fmi3), Free::Now);
    }
}

//! The live instances of this library, so that a handle is dereferenced only when it is one
//! of them. An importer may pass a freed, foreign or other-version handle, free an instance
//! from inside its own logger callback while a call on it is running, or call one instance
//! from two threads at once: the registry recognises all of these from the handle's value
//! alone, without reading the memory behind it.
//!
//! A handle is the address of the instance's slot in a fixed table of atomics in static
//! memory (the slot holds the instance's address), so that checking a handle is a range test
//! and one atomic operation, with no search and no lock, and unloading the library leaves no
//! heap memory behind. New instances take slots round the table in turn, so that a slot, and
//! with it a stale handle, comes back to life only after [`CAPACITY`] instantiations (an
//! address-keyed table recognised a new instance at a freed one's address at once). This is
//! the crate's one piece of process-wide mutable state (a handle is all the context the C
//! functions get). It holds up to [`CAPACITY`] live instances.

use std::ffi::c_void;
use std::sync::atomic::{AtomicU8, AtomicUsize, Ordering};

use super::FmiVersion;

/// Live instances at most (per process and library).
pub const CAPACITY: usize = 1 << 16;

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
    /// The instance's address while the slot is live.
    instance: AtomicUsize,
    state: AtomicU8,
}

static SLOTS: [Slot; CAPACITY] =
    [const { Slot { instance: AtomicUsize::new(0), state: AtomicU8::new(EMPTY) } }; CAPACITY];

/// Where the next registration starts looking for a free slot.
static NEXT: AtomicUsize = AtomicUsize::new(0);

fn live_state(version: FmiVersion) -> u8 {
    match version {
        FmiVersion::Fmi2 => LIVE,
        FmiVersion::Fmi3 => LIVE | FMI3,
    }
}

/// The handle of a slot: its address.
fn handle_of(slot: &'static Slot) -> *mut c_void {
    slot as *const Slot as *mut c_void
}

/// The slot a handle names, if it is the address of one (NULL and foreign pointers are not).
#[inline(always)]
fn slot_of(handle: *mut c_void) -> Option<&'static Slot> {
    let offset = (handle as usize).wrapping_sub(SLOTS.as_ptr() as usize);
    let size = std::mem::size_of::<Slot>();
    if !offset.is_multiple_of(size) {
        return None;
    }
    SLOTS.get(offset / size)
}

/// Records a new instance: its handle, or `None` if [`CAPACITY`] instances are live already.
pub fn register(instance: *mut c_void, version: FmiVersion) -> Option<*mut c_void> {
    let start = NEXT.fetch_add(1, Ordering::Relaxed);
    for i in 0..CAPACITY {
        let slot = &SLOTS[start.wrapping_add(i) % CAPACITY];
        for free in [EMPTY, TOMBSTONE] {
            if slot.state.compare_exchange(free, RESERVED, Ordering::AcqRel, Ordering::Acquire).is_ok() {
                slot.instance.store(instance as usize, Ordering::Release);
                slot.state.store(live_state(version), Ordering::Release);
                // Later registrations start after this slot.
                NEXT.fetch_max(start.wrapping_add(i + 1), Ordering::Relaxed);
                return Some(handle_of(slot));
            }
        }
    }
    None
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
/// ending the call needs no second check.
#[derive(Clone, Copy)]
pub struct Busy(&'static Slot);

impl Busy {
    /// The instance's address (valid until [`release`]).
    pub fn instance(self) -> *mut c_void {
        self.0.instance.load(Ordering::Acquire) as *mut c_void
    }
}

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
pub fn acquire(handle: *mut c_void, version: FmiVersion) -> Access {
    let Some(slot) = slot_of(handle) else { return Access::Unknown };
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
    /// Unregistered: drop the instance at this address now.
    Now(*mut c_void),
    /// A call on it is running: it is dropped when that call returns.
    Deferred,
    /// Not a live instance of this version (NULL, already freed, foreign): nothing to do.
    Unknown,
}

pub fn request_free(handle: *mut c_void, version: FmiVersion) -> Free {
    let Some(slot) = slot_of(handle) else { return Free::Unknown };
    let idle = live_state(version);
    let mut state = slot.state.load(Ordering::Acquire);
    loop {
        let next = if state == idle {
            TOMBSTONE
        } else if state == idle | BUSY {
            idle | BUSY | FREEING
        } else {
            return Free::Unknown; // the other version, or being freed already
        };
        // The address is read while the slot is still ours: once it is a tombstone, a new
        // registration may take it.
        let instance = slot.instance.load(Ordering::Acquire) as *mut c_void;
        match slot.state.compare_exchange(state, next, Ordering::AcqRel, Ordering::Acquire) {
            Ok(_) if next == TOMBSTONE => return Free::Now(instance),
            Ok(_) => return Free::Deferred,
            Err(now) => state = now,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn handles_are_recognised_by_value_alone() {
        let (x, y) = (0x1000 as *mut c_void, 0x2000 as *mut c_void);
        let a = register(x, FmiVersion::Fmi2).expect("registered");
        let b = register(y, FmiVersion::Fmi3).expect("registered");
        assert_ne!(a, b);
        assert_eq!(acquire(a, FmiVersion::Fmi3), Access::Unknown, "other version");
        let Access::Granted(busy) = acquire(a, FmiVersion::Fmi2) else { panic!("not granted") };
        assert_eq!(busy.instance(), x);
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::InUse, "re-entrant");
        assert_eq!(request_free(a, FmiVersion::Fmi2), Free::Deferred);
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::Unknown, "being freed");
        assert!(release(busy), "freed when the running call returns");
        assert_eq!(acquire(a, FmiVersion::Fmi2), Access::Unknown, "stale");
        assert_eq!(request_free(a, FmiVersion::Fmi2), Free::Unknown, "double free");
        assert_eq!(request_free(b, FmiVersion::Fmi3), Free::Now(y));
        // NULL, the instance's own address, and addresses inside or beside the table that are
        // not a slot's.
        for foreign in [std::ptr::null_mut(), x, a.wrapping_byte_add(1), a.wrapping_byte_add(8)] {
            assert_eq!(acquire(foreign, FmiVersion::Fmi2), Access::Unknown, "{foreign:p}");
            assert_eq!(request_free(foreign, FmiVersion::Fmi2), Free::Unknown, "{foreign:p}");
        }
        let end = SLOTS.as_ptr_range().end as *mut c_void;
        let before = (SLOTS.as_ptr() as *mut c_void).wrapping_byte_sub(std::mem::size_of::<Slot>());
        for outside in [end, before] {
            assert_eq!(acquire(outside, FmiVersion::Fmi2), Access::Unknown, "{outside:p}");
        }
        // A new registration takes another slot: the stale handle stays stale.
        let c = register(x, FmiVersion::Fmi3).expect("registered");
        assert_ne!(c, a);
        assert_eq!(acquire(a, FmiVersion::Fmi3), Access::Unknown, "stale after a new registration");
        let Access::Granted(busy) = acquire(c, FmiVersion::Fmi3) else { panic!("not granted") };
        assert!(!release(busy));
        assert_eq!(request_free(c, FmiVersion::Fmi3), Free::Now(x));
    }
}

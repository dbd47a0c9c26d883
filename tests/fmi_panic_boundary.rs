//! A panic never crosses the C boundary: the boundary every export goes through catches it,
//! logs it in `logStatusFatal`, poisons the instance (which then refuses every call but
//! fmi2Reset and fmi2FreeInstance, saying why), and fmi2Reset brings it back.

use crate::common;

use common::fmi_host::Host;
use stewart_fmu::fmi::Status;
use stewart_fmu::fmi::boundary::call;
use stewart_fmu::fmi2::exports::*;
use stewart_fmu::fmi2::state_machine::Fmi2Function;
use stewart_fmu::fmi2::types::*;

#[test]
fn a_panic_is_caught_and_poisons_the_instance() {
    let mut h = Host::platform("panicky");
    assert_eq!(h.initialise(&[]), fmi2OK);
    assert_eq!(h.step(0.01), fmi2OK);
    // The boundary every export uses, with a body that panics (as a bug in the model would).
    let status = unsafe { call(h.c, Fmi2Function::DoStep, String::new, |_instance| panic!("deliberate test panic")) };
    assert_eq!(status, Status::Error);
    let fatal = h.messages().into_iter().find(|l| l.category == "logStatusFatal").expect("a logStatusFatal message");
    assert!(fatal.message.contains("deliberate test panic") && fatal.message.contains("poisoned"), "{}", fatal.message);
    assert_eq!(fatal.status, fmi2Fatal);

    h.clear_log();
    assert_eq!(h.step(0.01), fmi2Error);
    assert!(h.last_message().contains("poisoned by an internal error"), "{}", h.last_message());
    let vr = h.vr("r[3]");
    let mut x = 0.0;
    assert_eq!(unsafe { fmi2GetReal(h.c, &vr, 1, &mut x) }, fmi2Error);

    assert_eq!(unsafe { fmi2Reset(h.c) }, fmi2OK);
    assert_eq!(h.initialise(&[]), fmi2OK);
    h.time = 0.0;
    assert_eq!(h.step(0.01), fmi2OK);
}

#[test]
fn a_panic_without_a_valid_instance_is_still_contained() {
    let status =
        unsafe { call(std::ptr::null_mut(), Fmi2Function::DoStep, String::new, |_instance| panic!("never runs")) };
    assert_eq!(status, Status::Error);
    let r = stewart_fmu::fmi::boundary::no_instance(7, || -> i32 { panic!("contained") });
    assert_eq!(r, 7);
}

//! Messages to the importer's logger callback, FMI 2 or FMI 3.
//!
//! The FMI 2 logger is printf-like: FMPy and FMI Library run `vsnprintf` on the message. So
//! the message is formatted here, `%` is doubled and NULs are dropped, and it is passed as the
//! format with no arguments: formatting importers print it verbatim, others print it with
//! doubled `%` at worst (never a literal `%s`). The FMI 3 logger takes the message as it is
//! (NULs dropped). The category is always one declared in `<LogCategories>` (a NULL category
//! crashes some importers), and the importer's environment pointer and the instance name are
//! forwarded unchanged.

use std::ffi::{CString, c_char, c_int, c_void};

use super::Status;

/// The FMI 2 logger: `(componentEnvironment, instanceName, status, category, message, ...)`,
/// C-variadic with `message` a printf format. Rust can declare and call such a pointer.
pub type Fmi2Logger =
    Option<unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char, ...)>;
/// The FMI 3 logger: `(instanceEnvironment, status, category, message)`.
pub type Fmi3Logger = Option<unsafe extern "C" fn(*mut c_void, c_int, *const c_char, *const c_char)>;

/// The importer's callback of either version.
#[derive(Clone, Copy)]
pub enum Callback {
    Fmi2(Fmi2Logger),
    Fmi3(Fmi3Logger),
}

impl Callback {
    fn is_some(&self) -> bool {
        match self {
            Callback::Fmi2(f) => f.is_some(),
            Callback::Fmi3(f) => f.is_some(),
        }
    }
}

/// Log categories declared in the model description. Status categories are always on (an
/// importer needs to know why a call failed); the debug categories follow `loggingOn` and
/// `fmi2SetDebugLogging`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LogCategory {
    /// Life cycle: initialisation summary, reset, state restore (debug).
    Events,
    /// Every FMI call with its arguments (debug; verbose).
    Calls,
    Warning,
    Discard,
    Error,
    Fatal,
}

impl LogCategory {
    pub const ALL: [LogCategory; 6] = [
        LogCategory::Events,
        LogCategory::Calls,
        LogCategory::Warning,
        LogCategory::Discard,
        LogCategory::Error,
        LogCategory::Fatal,
    ];

    pub fn name(self) -> &'static str {
        match self {
            LogCategory::Events => "logEvents",
            LogCategory::Calls => "logCalls",
            LogCategory::Warning => "logStatusWarning",
            LogCategory::Discard => "logStatusDiscard",
            LogCategory::Error => "logStatusError",
            LogCategory::Fatal => "logStatusFatal",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|c| c.name() == name)
    }

    pub fn description(self) -> &'static str {
        match self {
            LogCategory::Events => "Life cycle: initialisation summary, reset, FMU state restored (debug)",
            LogCategory::Calls => "Every FMI function call with its arguments (debug, verbose)",
            LogCategory::Warning => "Calls that returned a warning status",
            LogCategory::Discard => {
                "Steps that could not be completed (discard status): what happened, when, to which leg"
            }
            LogCategory::Error => "Calls that returned an error status: which argument, state or parameter was wrong",
            LogCategory::Fatal => "Internal errors (a caught panic); the instance is poisoned",
        }
    }

    /// The category a status message goes to.
    pub fn for_status(status: Status) -> LogCategory {
        match status {
            Status::Warning => LogCategory::Warning,
            Status::Discard => LogCategory::Discard,
            Status::Error => LogCategory::Error,
            Status::Fatal => LogCategory::Fatal,
            Status::Ok => LogCategory::Events,
        }
    }

    fn index(self) -> usize {
        self as usize
    }

    pub fn is_debug(self) -> bool {
        matches!(self, LogCategory::Events | LogCategory::Calls)
    }

    fn c_name(self) -> &'static std::ffi::CStr {
        match self {
            LogCategory::Events => c"logEvents",
            LogCategory::Calls => c"logCalls",
            LogCategory::Warning => c"logStatusWarning",
            LogCategory::Discard => c"logStatusDiscard",
            LogCategory::Error => c"logStatusError",
            LogCategory::Fatal => c"logStatusFatal",
        }
    }
}

/// The importer's logger with the instance's identity and category switches.
pub struct Logger {
    callback: Callback,
    environment: *mut c_void,
    instance_name: CString,
    enabled: [bool; LogCategory::ALL.len()],
}

// SAFETY: the environment pointer is the importer's; we only hand it back to the importer's
// logger. Instances may be driven from worker threads (libcosim), one thread at a time.
unsafe impl Send for Logger {}

impl Logger {
    /// Status categories start on; debug categories follow `logging_on`.
    pub fn new(callback: Callback, environment: *mut c_void, instance_name: CString, logging_on: bool) -> Self {
        let enabled = LogCategory::ALL.map(|c| !c.is_debug() || logging_on);
        Logger { callback, environment, instance_name, enabled }
    }

    pub fn instance_name(&self) -> &str {
        self.instance_name.to_str().unwrap_or("(instance)")
    }

    /// `fmi2SetDebugLogging`/`fmi3SetDebugLogging`: with no categories, switches all debug categories; with a list,
    /// switches exactly the listed categories (status categories included, if listed).
    pub fn set_debug_logging(&mut self, logging_on: bool, categories: &[LogCategory]) {
        if categories.is_empty() {
            for c in LogCategory::ALL.iter().filter(|c| c.is_debug()) {
                self.enabled[c.index()] = logging_on;
            }
        } else {
            for c in categories {
                self.enabled[c.index()] = logging_on;
            }
        }
    }

    /// Whether a message of this category would reach the importer: check before formatting.
    #[inline]
    pub fn is_enabled(&self, category: LogCategory) -> bool {
        self.callback.is_some() && self.enabled[category.index()]
    }

    /// Sends a message (formatted by the caller) to the importer.
    pub fn log(&self, status: Status, category: LogCategory, message: &str) {
        if !self.is_enabled(category) {
            return;
        }
        match self.callback {
            Callback::Fmi2(Some(callback)) => {
                let Ok(text) = CString::new(escape_printf(message)) else { return };
                // SAFETY: the importer gave us this callback for exactly this use; all pointers
                // are valid NUL-terminated strings that outlive the call, and no variadic
                // arguments are passed because the message contains no conversion specification.
                unsafe {
                    callback(
                        self.environment,
                        self.instance_name.as_ptr(),
                        status.code(),
                        category.c_name().as_ptr(),
                        text.as_ptr(),
                    );
                }
            }
            Callback::Fmi3(Some(callback)) => {
                let Ok(text) = CString::new(message.replace('\0', "")) else { return };
                // SAFETY: as above; the FMI 3 logger takes the message as plain text.
                unsafe { callback(self.environment, status.code(), category.c_name().as_ptr(), text.as_ptr()) };
            }
            _ => {}
        }
    }
}

/// Doubles `%` (so printf-style importers print the text verbatim) and drops NULs.
pub fn escape_printf(message: &str) -> String {
    let mut out = String::with_capacity(message.len() + 8);
    for ch in message.chars() {
        match ch {
            '%' => out.push_str("%%"),
            '\0' => {}
            c => out.push(c),
        }
    }
    out
}

/// Logs through an importer's logger before an instance exists (instantiation failures).
pub fn log_without_instance(
    callback: Callback,
    environment: *mut c_void,
    instance_name: &str,
    status: Status,
    message: &str,
) {
    let name = CString::new(instance_name.replace('\0', "")).unwrap_or_default();
    Logger::new(callback, environment, name, true).log(status, LogCategory::for_status(status), message);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_is_doubled_and_nul_dropped() {
        assert_eq!(escape_printf("100% at %s\0!"), "100%% at %%s!");
    }
}

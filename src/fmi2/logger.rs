//! Messages to the importer's logger callback.
//!
//! The FMI 2 logger is printf-like: FMPy and FMI Library run `vsnprintf` on the message. So
//! the message is formatted here, `%` is doubled and NULs are dropped, and it is passed as the
//! format with no arguments: formatting importers print it verbatim, others print it with
//! doubled `%` at worst (never a literal `%s`). The category is always one declared in
//! `<LogCategories>` (a NULL category crashes some importers), and the importer's
//! `componentEnvironment` and the instance name are forwarded unchanged.

use std::ffi::CString;

use super::types::*;

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
            LogCategory::Warning => "Calls that returned fmi2Warning",
            LogCategory::Discard => {
                "Steps that could not be completed (fmi2Discard): what happened, when, to which leg"
            }
            LogCategory::Error => "Calls that returned fmi2Error: which argument, state or parameter was wrong",
            LogCategory::Fatal => "Internal errors (a caught panic); the instance is poisoned",
        }
    }

    /// The category a status message goes to.
    pub fn for_status(status: fmi2Status) -> LogCategory {
        match status {
            fmi2Warning => LogCategory::Warning,
            fmi2Discard => LogCategory::Discard,
            fmi2Error => LogCategory::Error,
            fmi2Fatal => LogCategory::Fatal,
            _ => LogCategory::Events,
        }
    }

    fn index(self) -> usize {
        self as usize
    }

    fn is_debug(self) -> bool {
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
    callback: fmi2CallbackLogger,
    environment: fmi2ComponentEnvironment,
    instance_name: CString,
    enabled: [bool; LogCategory::ALL.len()],
}

// The environment pointer is the importer's; we only hand it back to the importer's logger.
// Instances may be driven from worker threads (libcosim), one thread at a time.
unsafe impl Send for Logger {}

impl Logger {
    /// Status categories start on; debug categories follow `logging_on`.
    pub fn new(
        callback: fmi2CallbackLogger,
        environment: fmi2ComponentEnvironment,
        instance_name: CString,
        logging_on: bool,
    ) -> Self {
        let enabled = LogCategory::ALL.map(|c| !c.is_debug() || logging_on);
        Logger { callback, environment, instance_name, enabled }
    }

    pub fn instance_name(&self) -> &str {
        self.instance_name.to_str().unwrap_or("(instance)")
    }

    /// `fmi2SetDebugLogging`: with no categories, switches all debug categories; with a list,
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
    pub fn log(&self, status: fmi2Status, category: LogCategory, message: &str) {
        if !self.is_enabled(category) {
            return;
        }
        let Some(callback) = self.callback else {
            return;
        };
        let Ok(text) = CString::new(escape_printf(message)) else {
            return;
        };
        // SAFETY: the importer gave us this callback for exactly this use; all pointers are
        // valid NUL-terminated strings that outlive the call, and no variadic arguments are
        // passed because the message contains no conversion specification.
        unsafe {
            callback(self.environment, self.instance_name.as_ptr(), status, category.c_name().as_ptr(), text.as_ptr());
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

/// Logs through an importer's logger before an instance exists (`fmi2Instantiate` failures).
pub fn log_without_instance(
    functions: Option<&fmi2CallbackFunctions>,
    instance_name: &str,
    status: fmi2Status,
    message: &str,
) {
    if let Some(f) = functions {
        let name = CString::new(escape_printf(instance_name)).unwrap_or_default();
        let logger = Logger::new(f.logger, f.componentEnvironment, name, true);
        logger.log(status, LogCategory::for_status(status), message);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_is_doubled_and_nul_dropped() {
        assert_eq!(escape_printf("100% at %s\0!"), "100%% at %%s!");
    }
}

//! The figures docs/model.md quotes, held in benches/results/model.txt by the tests that compute
//! them: tests/python/references.py's scheme for the Rust tests (one line `key: text` per
//! figure set, `#` lines first, the rest sorted). A test whose figures moved fails and says
//! how to write them again: `STEWART_UPDATE_REFERENCES=1 cargo test --release -p
//! stewart-fmu-tests NAME` rewrites its line instead; then review the diff, bring the page up to
//! date, and commit both (tests/python/test_readme.py checks that the page's measured figures
//! are in benches/results/).

use std::path::PathBuf;
use std::sync::Mutex;

/// The tests of this one binary run on threads: one writer at a time.
static WRITING: Mutex<()> = Mutex::new(());

fn results(name: &str) -> PathBuf {
    super::repository().join("benches").join("results").join(name)
}

/// The line `key: text` of benches/results/NAME (with STEWART_UPDATE_REFERENCES=1: written,
/// the other lines kept).
pub fn check_figures(name: &str, key: &str, text: &str) {
    let path = results(name);
    let line = format!("{key}: {text}");
    let prefix = format!("{key}: ");
    if std::env::var("STEWART_UPDATE_REFERENCES").as_deref() == Ok("1") {
        let _one = WRITING.lock().unwrap_or_else(|e| e.into_inner());
        let old = std::fs::read_to_string(&path).unwrap_or_default();
        let (mut head, mut body): (Vec<&str>, Vec<&str>) = (vec![], vec![]);
        for l in old.lines().filter(|l| !l.is_empty() && !l.starts_with(&prefix)) {
            if l.starts_with('#') { head.push(l) } else { body.push(l) }
        }
        body.push(&line);
        body.sort();
        head.extend(body);
        std::fs::write(&path, head.join("\n") + "\n").expect("benches/results is writable");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    let found = committed.lines().find(|l| l.starts_with(&prefix)).unwrap_or("(missing)");
    assert!(
        found == line,
        "benches/results/{name} holds\n  {found}\nbut the code computes now\n  {line}\nIf the change is meant, write \
         it again with STEWART_UPDATE_REFERENCES=1 cargo test --release -p stewart-fmu-tests <this test>, bring the \
         page that quotes it up to date, and commit both"
    );
}

/// [`check_figures`] of a printed line `key: text` (split at its first ": ").
pub fn check_line(name: &str, line: &str) {
    let (key, text) = line.split_once(": ").expect("a line `key: text`");
    check_figures(name, key, text);
}

/// Figures printed by a test, checked against benches/results/model.txt when they go out of
/// scope: after the test's own assertions, so that a physical regression fails those first,
/// with their message, not this file's "write it again".
#[must_use = "bind it (`let _figures = ...`): the check runs when it is dropped"]
pub struct PrintedFigures(String);

impl Drop for PrintedFigures {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            check_line("model.txt", &self.0);
        }
    }
}

/// Prints a line `key: text` of figures, to be held in benches/results/model.txt (the check
/// runs when the value returned is dropped).
pub fn print_figures(line: &str) -> PrintedFigures {
    println!("{line}");
    PrintedFigures(line.to_string())
}

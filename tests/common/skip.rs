//! A test that cannot run here (a shared asset, a system program or a
//! display is missing) says so: on stderr, and as a line of the file
//! `$KAGE_SKIP_LOG` names, which `.ci/run` prints with a count at the end, so
//! a fresh clone's run says what it did not check.

use std::io::Write;

/// Records that the running test skipped (all or part of) its check, and why.
#[allow(dead_code, reason = "each test crate includes this file; not all of them skip")]
pub fn skipped(why: &str) {
    let test = std::thread::current().name().unwrap_or("a test").to_string();
    eprintln!("skipped: {why}");
    if let Some(log) = std::env::var_os("KAGE_SKIP_LOG") {
        if let Ok(mut file) = std::fs::OpenOptions::new().create(true).append(true).open(log) {
            let _ = writeln!(file, "{test}: {why}");
        }
    }
}

//! Failpoints for crash tests: `VIBCAM_FAILPOINT=NAME` or `NAME:N` in the environment
//! aborts the process (as `kill -9` would: no destructors, no flush) at the first, or the
//! `N`-th, time the point `NAME` is reached. Points sit after each write, sync and rename of a
//! checkpoint or an output directory; the tests kill a study at every one in turn and check
//! that resuming loses nothing. Without the variable a point costs one environment lookup the
//! first time and an atomic load after that.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

/// The failpoint setting: the name and the hit count that aborts.
fn setting() -> &'static Option<(String, usize)> {
    static SETTING: OnceLock<Option<(String, usize)>> = OnceLock::new();
    SETTING.get_or_init(|| {
        let v = std::env::var("VIBCAM_FAILPOINT").ok()?;
        match v.split_once(':') {
            Some((name, n)) => Some((name.to_string(), n.parse().ok()?)),
            None => Some((v, 1)),
        }
    })
}

/// Marks the failpoint `name`; aborts the process if the environment says so.
pub fn hit(name: &str) {
    static HITS: AtomicUsize = AtomicUsize::new(0);
    if let Some((target, n)) = setting() {
        if target == name && HITS.fetch_add(1, Ordering::SeqCst) + 1 == *n {
            eprintln!("failpoint {name}: aborting");
            std::process::abort();
        }
    }
}

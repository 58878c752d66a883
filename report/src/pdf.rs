//! `report.pdf`: the page printed by a headless Chromium (its print stylesheet: A4, a page per
//! section), when one is installed. The browser is found on `PATH` (`chromium`,
//! `chromium-browser`, `google-chrome`, `google-chrome-stable`) or named by `VIBCAM_CHROMIUM`;
//! without one the caller says so and the rest of the outputs stand.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The names a Chromium is looked for by on `PATH`, in this order.
pub const BROWSERS: [&str; 4] = [
    "chromium",
    "chromium-browser",
    "google-chrome",
    "google-chrome-stable",
];

/// How long a print may take before the browser is stopped.
const TIMEOUT: Duration = Duration::from_secs(120);

/// Why no PDF was printed.
#[derive(Debug, thiserror::Error)]
pub enum PdfError {
    /// No browser to print with.
    #[error(
        "no report.pdf: no Chromium found (chromium, chromium-browser, google-chrome on PATH, \
         or VIBCAM_CHROMIUM); open report.html in a browser and print it instead"
    )]
    NoBrowser,
    /// The browser ran but gave no PDF.
    #[error("no report.pdf: {browser} did not print the page ({why})")]
    Failed {
        /// The browser run.
        browser: String,
        /// What went wrong.
        why: String,
    },
}

/// The browser to print with: `VIBCAM_CHROMIUM` when set, else the first of [`BROWSERS`] on
/// `PATH`.
pub fn browser() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("VIBCAM_CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|dir| BROWSERS.iter().map(move |b| dir.join(b)))
        .find(|p| p.is_file())
}

/// The PDF of the page `html` (a file), printed by `browser` into `scratch` (a file it may
/// write and that is removed after).
pub fn print(browser: &Path, html: &Path, scratch: &Path) -> Result<Vec<u8>, PdfError> {
    let failed = |why: String| PdfError::Failed {
        browser: browser.display().to_string(),
        why,
    };
    let page = std::path::absolute(html).map_err(|e| failed(e.to_string()))?;
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--no-pdf-header-footer",
        ])
        .arg(format!("--print-to-pdf={}", scratch.display()))
        .arg(format!("file://{}", page.display()))
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| failed(e.to_string()))?;
    let start = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break status,
            Ok(None) if start.elapsed() > TIMEOUT => {
                // a browser that hangs is stopped; its half-written file is not kept
                let _ = child.kill();
                let _ = child.wait();
                let _ = std::fs::remove_file(scratch);
                return Err(failed(format!("no answer in {} s", TIMEOUT.as_secs())));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(100)),
            Err(e) => return Err(failed(e.to_string())),
        }
    };
    let bytes = std::fs::read(scratch);
    let _ = std::fs::remove_file(scratch);
    match bytes {
        Ok(b) if b.starts_with(b"%PDF") => Ok(b),
        Ok(_) => Err(failed("what it wrote is no PDF".into())),
        Err(e) => Err(failed(format!("exit {status}, {e}"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_browser_that_writes_nothing_is_named_and_leaves_no_file() {
        let tmp = tempfile::tempdir().unwrap();
        let html = tmp.path().join("report.html");
        std::fs::write(&html, "<h1>x</h1>").unwrap();
        let scratch = tmp.path().join(".report.pdf.partial");
        // `true` runs and prints nothing
        let e = print(Path::new("true"), &html, &scratch).unwrap_err();
        assert!(e.to_string().contains("did not print the page"), "{e}");
        assert!(!scratch.exists());
        let e = print(Path::new("/no/such/browser"), &html, &scratch).unwrap_err();
        assert!(e.to_string().contains("/no/such/browser"), "{e}");
    }
}

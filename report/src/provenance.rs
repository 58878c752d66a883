//! Who, what and when: the block that opens every `report.txt` and `report.html`, so that a page
//! put into a test report says how it was made. It names the date (UTC), the tool's version and
//! the source's commit, the command as given, every input with its size and SHA-256 (a folder of
//! frames as its file count, total size and one digest over the files' names and digests), the
//! settings used with the defaults marked, and the machine.
//!
//! The front end (the command line, the Python package) states the invocation once, around the
//! job it runs ([`with_invocation`]); the writer of a job's report reads it ([`Provenance::now`])
//! together with the inputs its output directory was given. A job run without a front end (a
//! test, a library caller) says "not stated" instead of guessing.
//!
//! `SOURCE_DATE_EPOCH` (seconds since 1970, the reproducible-builds convention), when set, is
//! the date written: two runs on the same inputs then write the same page.

use sha2::{Digest, Sha256};
use std::cell::RefCell;
use std::fmt::Write as _;
use std::io::Read as _;
use std::path::Path;

/// The tool's version (the workspace's).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The source's commit the program was built from (`git rev-parse HEAD` at build time), when
/// the build had a git checkout.
pub const COMMIT: Option<&str> = option_env!("VIBCAM_COMMIT");

/// One setting of a run as the front end names it (`--nperseg`, `nperseg`).
#[derive(Debug, Clone, PartialEq)]
pub struct Setting {
    /// Its name as the user writes it.
    pub name: String,
    /// Its value as given or defaulted (`(none)` for an optional one left out).
    pub value: String,
    /// Whether the value is the default (not given).
    pub default: bool,
}

/// How the job was asked for: the command as given and every setting.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Invocation {
    /// The command line (arguments quoted where needed) or the Python call.
    pub command: String,
    /// Every setting, in the front end's order.
    pub settings: Vec<Setting>,
}

/// One input of the run.
#[derive(Debug, Clone, PartialEq)]
pub struct InputFile {
    /// The path as given.
    pub path: String,
    /// Its size in bytes (a folder: the sum of its files).
    pub bytes: u64,
    /// The files it holds (1 for a file).
    pub files: usize,
    /// SHA-256 in hex: of the file's bytes; of a folder, of the lines `name  digest` of its
    /// files in name order (as `sha256sum` prints them, run inside the folder). `None` when it
    /// could not be read (the reason in [`InputFile::error`]).
    pub sha256: Option<String>,
    /// Why it could not be read.
    pub error: Option<String>,
}

/// The block opening a report: see the module documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct Provenance {
    /// When the report was written, UTC, RFC 3339 to the second.
    pub date_utc: String,
    /// The tool's version and commit.
    pub version: String,
    /// How it was asked for (`None`: not stated by a front end).
    pub invocation: Option<Invocation>,
    /// Every input.
    pub inputs: Vec<InputFile>,
    /// The machine: host name, operating system, architecture, logical processors.
    pub machine: String,
}

thread_local! {
    static INVOCATION: RefCell<Option<Invocation>> = const { RefCell::new(None) };
}

/// Runs `job` with `invocation` stated for the reports it writes (on this thread), then
/// restores what was stated before.
pub fn with_invocation<T>(invocation: Invocation, job: impl FnOnce() -> T) -> T {
    let before = INVOCATION.with(|c| c.replace(Some(invocation)));
    /// Puts the earlier invocation back, also when the job unwinds.
    struct Restore(Option<Invocation>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let before = self.0.take();
            INVOCATION.with(|c| *c.borrow_mut() = before);
        }
    }
    let _restore = Restore(before);
    job()
}

/// The invocation stated on this thread, if any.
pub fn current_invocation() -> Option<Invocation> {
    INVOCATION.with(|c| c.borrow().clone())
}

/// The files `inputs` name, each once (the force and the responses in one DAQ file are one
/// input), a Photron header followed by the `.mraw` beside it that holds its frames.
fn with_companions(inputs: &[&Path]) -> Vec<std::path::PathBuf> {
    let mut out: Vec<std::path::PathBuf> = Vec::new();
    for p in inputs {
        let mraw = p.with_extension("mraw");
        let companion = vibcam_readers::frames::photron::is_header(p) && mraw.is_file();
        for f in std::iter::once(p.to_path_buf()).chain(companion.then_some(mraw)) {
            if !out.contains(&f) {
                out.push(f);
            }
        }
    }
    out
}

impl Provenance {
    /// The block for a report written now, from `inputs` (hashed here) and the invocation
    /// stated on this thread.
    pub fn now(inputs: &[&Path]) -> Provenance {
        Provenance {
            date_utc: date_utc(),
            version: version(),
            invocation: current_invocation(),
            inputs: with_companions(inputs)
                .iter()
                .map(|p| input_file(p))
                .collect(),
            machine: machine(),
        }
    }

    /// The block as text (the head of `report.txt`), lines of `name: value`, settings one per
    /// line with `(default)` after the defaulted ones.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "date: {}", self.date_utc);
        let _ = writeln!(s, "version: vibcam {}", self.version);
        let _ = writeln!(s, "machine: {}", self.machine);
        match &self.invocation {
            Some(inv) => {
                let _ = writeln!(s, "command: {}", inv.command);
            }
            None => s.push_str("command: not stated (run as a library call)\n"),
        }
        if self.inputs.is_empty() {
            s.push_str("inputs: none\n");
        }
        for i in &self.inputs {
            let _ = writeln!(s, "input: {}", i.line());
        }
        if let Some(inv) = &self.invocation {
            s.push_str("settings:\n");
            for st in &inv.settings {
                let mark = if st.default { " (default)" } else { "" };
                let _ = writeln!(s, "  {} = {}{mark}", st.name, st.value);
            }
        }
        s
    }
}

impl InputFile {
    /// `path, N bytes, sha256 HEX` (a folder: `N files, ...`), or the reason it was not read.
    pub fn line(&self) -> String {
        let size = match self.files {
            1 => format!("{} bytes", self.bytes),
            n => format!("{n} files, {} bytes", self.bytes),
        };
        match (&self.sha256, &self.error) {
            (Some(h), _) => format!("{}, {size}, sha256 {h}", self.path),
            (None, e) => format!(
                "{}: not read ({})",
                self.path,
                e.as_deref().unwrap_or("unknown")
            ),
        }
    }
}

/// The version with the commit: `0.1.0 (commit abc123...)`, or `0.1.0 (commit unknown)`.
pub fn version() -> String {
    format!("{VERSION} (commit {})", COMMIT.unwrap_or("unknown"))
}

/// Now (or `SOURCE_DATE_EPOCH`), UTC, RFC 3339 to the second.
pub fn date_utc() -> String {
    date_at(std::env::var("SOURCE_DATE_EPOCH").ok().as_deref())
}

/// The date written for `SOURCE_DATE_EPOCH` = `epoch` (seconds; not a whole number: now).
fn date_at(epoch: Option<&str>) -> String {
    let epoch = epoch.and_then(|s| s.trim().parse::<u64>().ok());
    let t = match epoch {
        Some(secs) => std::time::UNIX_EPOCH + std::time::Duration::from_secs(secs),
        None => std::time::SystemTime::now(),
    };
    humantime::format_rfc3339_seconds(t).to_string()
}

/// Host name, operating system, architecture and logical processors.
pub fn machine() -> String {
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("COMPUTERNAME").ok())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "unknown host".into());
    let cpus = std::thread::available_parallelism().map_or(0, |n| n.get());
    format!(
        "{host}, {} {}, {cpus} logical processors",
        std::env::consts::OS,
        std::env::consts::ARCH
    )
}

/// SHA-256 and size of a file's bytes, read in blocks.
fn file_digest(path: &Path) -> std::io::Result<(String, u64)> {
    let mut f = std::fs::File::open(path)?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    let mut bytes = 0u64;
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
        bytes += n as u64;
    }
    Ok((hex(&h.finalize()), bytes))
}

/// Lower-case hex of `bytes`.
fn hex(bytes: &[u8]) -> String {
    bytes.iter().fold(String::new(), |mut s, b| {
        let _ = write!(s, "{b:02x}");
        s
    })
}

/// An input described and hashed (see [`InputFile::sha256`]); a folder's files are those
/// directly in it (hidden ones left out), in name order.
pub fn input_file(path: &Path) -> InputFile {
    let shown = path.display().to_string();
    // a pipe or a device was read by the job already: hashing it again would read nothing (a
    // digest of no bytes, silently wrong) or wait for ever; a pattern names no one file
    let described = match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => folder_digest(path),
        Ok(m) if m.is_file() => file_digest(path).map(|(h, n)| (h, n, 1)),
        Ok(_) => Err(std::io::Error::other(
            "not a regular file (a pipe or a device): not hashed",
        )),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(std::io::Error::other(
            "no file or folder of this name (a pattern of files is not hashed)",
        )),
        Err(e) => Err(e),
    };
    match described {
        Ok((sha, bytes, files)) => InputFile {
            path: shown,
            bytes,
            files,
            sha256: Some(sha),
            error: None,
        },
        Err(e) => InputFile {
            path: shown,
            bytes: 0,
            files: 0,
            sha256: None,
            error: Some(e.to_string()),
        },
    }
}

/// A folder's digest (over `name  digest` lines), total size and file count.
fn folder_digest(dir: &Path) -> std::io::Result<(String, u64, usize)> {
    let mut names: Vec<(String, std::path::PathBuf)> = std::fs::read_dir(dir)?
        .filter_map(Result::ok)
        .filter(|e| e.path().is_file())
        .filter_map(|e| {
            let name = e.file_name().to_str()?.to_string();
            (!name.starts_with('.')).then_some((name, e.path()))
        })
        .collect();
    names.sort();
    let mut h = Sha256::new();
    let mut bytes = 0;
    for (name, p) in &names {
        let (d, n) = file_digest(p)?;
        bytes += n;
        h.update(format!("{d}  {name}\n").as_bytes());
    }
    Ok((hex(&h.finalize()), bytes, names.len()))
}

/// The header of `report.html` (`section#provenance`): the same as [`Provenance::text`], as a
/// table (`tr.input` per input, with its `data-sha256`) and the list `ul#settings` (`li.setting`
/// per setting, `.default` on the defaulted ones); `escape` escapes text for HTML.
pub fn html(p: &Provenance, escape: fn(&str) -> String) -> String {
    let mut s = String::from("<section id=\"provenance\"><table class=\"provenance\">");
    let row = |s: &mut String, class: &str, k: &str, v: &str| {
        let _ = write!(
            s,
            "<tr class=\"{class}\"><th>{}</th><td>{}</td></tr>",
            escape(k),
            escape(v)
        );
    };
    row(&mut s, "date", "date (UTC)", &p.date_utc);
    row(
        &mut s,
        "version",
        "version",
        &format!("vibcam {}", p.version),
    );
    let command = p.invocation.as_ref().map_or_else(
        || "not stated (run as a library call)".to_string(),
        |i| i.command.clone(),
    );
    let _ = write!(
        s,
        "<tr class=\"command\"><th>command</th><td><code>{}</code></td></tr>",
        escape(&command)
    );
    for i in &p.inputs {
        let _ = write!(
            s,
            "<tr class=\"input\" data-sha256=\"{}\"><th>input</th><td>{}</td></tr>",
            i.sha256.as_deref().unwrap_or(""),
            escape(&i.line())
        );
    }
    row(&mut s, "machine", "machine", &p.machine);
    s.push_str("</table>");
    if let Some(inv) = &p.invocation {
        // every setting, in columns (a printed report shows them all; defaults in grey)
        let given = inv.settings.iter().filter(|st| !st.default).count();
        let _ = write!(
            s,
            "<p class=\"settings-head\">settings: {given} given, {} default (grey)</p><ul id=\"settings\">",
            inv.settings.len() - given
        );
        for st in &inv.settings {
            let class = if st.default {
                "setting default"
            } else {
                "setting"
            };
            let _ = write!(
                s,
                "<li class=\"{class}\">{} = {}</li>",
                escape(&st.name),
                escape(&st.value)
            );
        }
        s.push_str("</ul>");
    }
    s.push_str("</section>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_and_a_folder_are_hashed_as_sha256sum_does() {
        let tmp = tempfile::tempdir().unwrap();
        let a = tmp.path().join("a.txt");
        std::fs::write(&a, b"abc").unwrap();
        let f = input_file(&a);
        // FIPS 180-2's example: SHA-256("abc")
        let abc = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
        assert_eq!(f.sha256.as_deref(), Some(abc));
        assert_eq!((f.bytes, f.files), (3, 1));
        std::fs::write(tmp.path().join("b.txt"), b"").unwrap();
        std::fs::write(tmp.path().join(".hidden"), b"x").unwrap();
        let d = input_file(tmp.path());
        assert_eq!((d.bytes, d.files), (3, 2));
        // `sha256sum *` inside the folder, hashed again
        let empty = "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855";
        let listing = format!("{abc}  a.txt\n{empty}  b.txt\n");
        let want = hex(&Sha256::digest(listing.as_bytes()));
        assert_eq!(d.sha256.as_deref(), Some(want.as_str()));
        let gone = input_file(&tmp.path().join("missing"));
        assert!(gone.sha256.is_none() && gone.line().contains("not read"));
        // a device (or a pipe) is named as such, never given the digest of no bytes
        let device = input_file(Path::new("/dev/null"));
        assert!(device.sha256.is_none(), "{device:?}");
        assert!(
            device.line().contains("not a regular file"),
            "{}",
            device.line()
        );
    }

    #[test]
    fn the_invocation_holds_only_inside_its_job() {
        assert_eq!(current_invocation(), None);
        let inv = Invocation {
            command: "host-harness modal x.csv".into(),
            settings: vec![Setting {
                name: "--nperseg".into(),
                value: "512".into(),
                default: true,
            }],
        };
        let text = with_invocation(inv.clone(), || Provenance::now(&[]).text());
        assert!(text.contains("command: host-harness modal x.csv"));
        assert!(text.contains("  --nperseg = 512 (default)"));
        assert!(text.contains("inputs: none"));
        assert_eq!(current_invocation(), None);
        let page = html(&Provenance::now(&[]), |s| s.replace('<', "&lt;"));
        assert!(page.contains("not stated"));
    }

    #[test]
    fn a_file_given_twice_is_one_input_and_a_photron_header_brings_its_frames() {
        let tmp = std::env::temp_dir().join(format!("vibcam-twice-{}.lvm", std::process::id()));
        std::fs::write(&tmp, b"force and response").unwrap();
        let p = Provenance::now(&[tmp.as_path(), tmp.as_path()]);
        std::fs::remove_file(&tmp).unwrap();
        assert_eq!(p.inputs.len(), 1);
        assert_eq!(p.text().matches("input: ").count(), 1);
        // a Photron header brings the frames beside it
        let cih = std::env::temp_dir().join(format!("vibcam-rec-{}.cih", std::process::id()));
        std::fs::write(&cih, b"#Camera Information Header").unwrap();
        std::fs::write(cih.with_extension("mraw"), b"frames").unwrap();
        let p = Provenance::now(&[cih.as_path()]);
        std::fs::remove_file(cih.with_extension("mraw")).unwrap();
        std::fs::remove_file(&cih).unwrap();
        let names: Vec<&str> = p.inputs.iter().map(|i| i.path.as_str()).collect();
        assert_eq!(names.len(), 2, "{names:?}");
        assert!(names[1].ends_with(".mraw"), "{names:?}");
    }

    #[test]
    fn the_date_follows_source_date_epoch_when_set() {
        // 1e9 s after 1970-01-01 (the "billennium", a date every tool agrees on)
        assert_eq!(date_at(Some("1000000000")), "2001-09-09T01:46:40Z");
        for now in [date_at(None), date_at(Some("soon"))] {
            assert!(
                now.ends_with('Z') && now.len() == 20 && now > "2026".into(),
                "{now}"
            );
        }
    }
}

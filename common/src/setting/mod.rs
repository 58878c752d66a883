//! Errors that name the user's settings, spelled as the caller's users write them: a
//! [`SpecError`] names a setting by its key (`$gate_px`); [`SpecError::message`] spells it
//! `--gate-px` for the command line and `gate_px` for Python. Every room may refuse a setting
//! this way (a segment longer than the record is found only once the record is read); the
//! rules of each job live in the jobs (`host_harness::jobs`). Also the rules several jobs share: a positive
//! number, ordered bands, the Nyquist frequency.

pub mod table;

/// How a [`SpecError`] spells a setting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Naming {
    /// `--gate-px`.
    Cli,
    /// `gate_px`.
    Python,
}

/// A spec refused: a setting out of range, settings that do not go together, or an input file
/// the constructor read (a points file) that is wrong. Every variant is the user's to fix
/// (exit 2).
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// A setting, or a combination of settings; the text names them by `$key`.
    #[error("{}", spell(.0, Naming::Cli))]
    Setting(String),
    /// An input the spec reads (its error names the file and row).
    #[error(transparent)]
    Input(anyhow::Error),
}

/// The settings a message may name, by key (the Python spelling; the command line's is `--`
/// and the key with `-` for `_`).
pub const KEYS: &[&str] = &[
    "accel",
    "accel_target",
    "adaptive_on",
    "axis",
    "bands",
    "block_s",
    "camera_model",
    "compensate_exposure",
    "delay_s",
    "detrend",
    "efdd_quantity",
    "excitation_col",
    "excitation_fs",
    "exp_window",
    "exposure_ms",
    "f_max_hz",
    "f_min_hz",
    "force",
    "fps",
    "frame_range",
    "frames",
    "frames_shown",
    "free",
    "from",
    "fs",
    "gate_px",
    "geometry",
    "impact",
    "input_col",
    "lost_frames",
    "magnify_px",
    "max_order",
    "merge",
    "min_texture",
    "minutes",
    "mm_per_px",
    "nfft",
    "noverlap",
    "nperseg",
    "oblique_deg",
    "out",
    "output_col",
    "plscf",
    "points",
    "points_out",
    "poles",
    "prominence_db",
    "read_noise",
    "reference",
    "references",
    "region",
    "render",
    "response_col",
    "response_fs",
    "response_quantity",
    "resume",
    "retime",
    "rms_px",
    "roi",
    "roving",
    "roll_deg",
    "runs",
    "saturation",
    "scale",
    "search_px",
    "shake_hz",
    "shake_px",
    "shape_reference",
    "setup",
    "shard",
    "spacing",
    "ssi",
    "ssi_block_rows",
    "ssi_max_order",
    "target_size_mm",
    "targets",
    "threads",
    "threshold",
    "tick_hz",
    "tick_offset",
    "time_offset_s",
    "times",
    "to",
    "tracker",
    "twin",
    "window",
    "world",
    "x",
    "y",
    "window_px",
];

/// `template` with each `$key` spelled for `naming` (unknown `$` words stay as written): how
/// every message, note and report of the library reaches its user.
pub fn spell(template: &str, naming: Naming) -> String {
    let mut out = String::with_capacity(template.len() + 16);
    let mut rest = template;
    while let Some(i) = rest.find('$') {
        out.push_str(&rest[..i]);
        let word = &rest[i + 1..];
        let len = word
            .find(|c: char| !(c.is_ascii_lowercase() || c == '_'))
            .unwrap_or(word.len());
        // the word (letters and `_`: `$fps` in `$fps,`), if it is a known key
        match KEYS.iter().find(|k| **k == &word[..len]) {
            Some(key) => {
                match naming {
                    Naming::Cli => {
                        out.push_str("--");
                        out.push_str(&key.replace('_', "-"));
                    }
                    // Python takes the repeated `--setup` as one list, `setups`
                    Naming::Python => out.push_str(match *key {
                        "setup" => "setups",
                        k => k,
                    }),
                }
                rest = &word[len..];
            }
            None => {
                out.push('$');
                rest = word;
            }
        }
    }
    out.push_str(rest);
    out
}

impl SpecError {
    /// A refused setting; `template` names settings as `$key`.
    pub fn setting(template: impl Into<String>) -> Self {
        SpecError::Setting(template.into())
    }

    /// The message with the settings spelled for `naming`.
    pub fn message(&self, naming: Naming) -> String {
        match self {
            SpecError::Setting(t) => spell(t, naming),
            SpecError::Input(e) => message(e, naming),
        }
    }

    /// The error as the rest of the library carries it: the input's own error (its chain
    /// decides the exit code), or this error (exit 2).
    pub fn into_anyhow(self) -> anyhow::Error {
        match self {
            SpecError::Input(e) => e,
            s => anyhow::Error::new(s),
        }
    }
}

/// Whether `e` is the user's to fix (exit 2): its chain holds a [`vibcam_readers::BadInput`] or a
/// [`SpecError`].
pub fn is_bad_input(e: &anyhow::Error) -> bool {
    e.chain()
        .any(|c| c.is::<vibcam_readers::BadInput>() || c.is::<SpecError>())
}

/// `e` as one line, the settings its chain names spelled for `naming` (the causes joined by
/// `: `, as `{e:#}` writes them).
pub fn message(e: &anyhow::Error, naming: Naming) -> String {
    e.chain()
        .map(|c| match c.downcast_ref::<SpecError>() {
            Some(s) => s.message(naming),
            None => spell(&c.to_string(), naming),
        })
        .collect::<Vec<_>>()
        .join(": ")
}

/// A result of a spec's constructor.
pub type SpecResult<T> = Result<T, SpecError>;

/// `v` is a finite number > 0, else the error names `key`.
pub fn positive(key: &str, v: f64, what: &str) -> SpecResult<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        // `key` with or without its `$`
        let key = key.trim_start_matches('$');
        Err(SpecError::setting(format!(
            "${key} must be positive ({what}), got {v}"
        )))
    }
}

/// The Nyquist rule: every band lies below half the sample rate `fs_hz` (`of`: whose rate, for
/// the message: "the camera's" or "the record's").
pub fn bands_below_nyquist(bands: &[(f64, f64)], fs_hz: f64, of: &str) -> SpecResult<()> {
    match bands.iter().find(|b| b.1 > fs_hz / 2.0) {
        Some((lo, hi)) => Err(SpecError::setting(format!(
            "$bands {lo}-{hi}: reaches above {of} Nyquist frequency ({} Hz at {fs_hz} Hz), \
             where the record has no content; keep every band below it",
            fs_hz / 2.0
        ))),
        None => Ok(()),
    }
}

/// Each band finite with `0 <= lo < hi`, no two overlapping (bands given as numbers; the
/// command line's text is checked by its parser with the same rules).
pub fn bands_ordered(bands: &[(f64, f64)]) -> SpecResult<()> {
    match bands
        .iter()
        .find(|(lo, hi)| !(lo.is_finite() && hi.is_finite() && *lo >= 0.0 && lo < hi))
    {
        Some((lo, hi)) => Err(SpecError::setting(format!(
            "$bands ({lo}, {hi}): need 0 <= lo < hi, finite, in Hz"
        ))),
        None => {
            for (i, a) in bands.iter().enumerate() {
                if let Some(b) = bands[i + 1..].iter().find(|b| a.0 < b.1 && b.0 < a.1) {
                    return Err(SpecError::setting(format!(
                        "$bands ({}, {}) and ({}, {}) overlap: each band holds one mode, and a \
                         mode in two bands would be reported twice; make them disjoint",
                        a.0, a.1, b.0, b.1
                    )));
                }
            }
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_spelled_for_each_caller() {
        let e = SpecError::setting("$gate_px with $targets; $fps, $unknown and $ alone");
        assert_eq!(
            e.message(Naming::Cli),
            "--gate-px with --targets; --fps, $unknown and $ alone"
        );
        assert_eq!(
            e.message(Naming::Python),
            "gate_px with targets; fps, $unknown and $ alone"
        );
        assert_eq!(e.to_string(), e.message(Naming::Cli));
    }

    #[test]
    fn the_nyquist_rule_names_the_band() {
        assert!(bands_below_nyquist(&[(1.0, 50.0)], 100.0, "the camera's").is_ok());
        let e =
            bands_below_nyquist(&[(1.0, 2.0), (40.0, 50.5)], 100.0, "the camera's").unwrap_err();
        assert!(
            e.message(Naming::Python).starts_with("bands 40-50.5"),
            "{e}"
        );
        assert!(bands_ordered(&[(2.0, 1.0)]).is_err());
        assert!(bands_ordered(&[(0.0, f64::INFINITY)]).is_err());
        let e = bands_ordered(&[(1.0, 5.0), (4.0, 8.0)]).unwrap_err();
        assert!(e.message(Naming::Cli).contains("overlap"), "{e}");
        assert!(bands_ordered(&[(1.0, 4.0), (4.0, 8.0)]).is_ok());
    }
}

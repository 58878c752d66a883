//! The records of an experimental modal analysis: the responses (a camera's displacements or a
//! DAQ's transducers) and the force, read from the files people have, brought to one sample
//! rate and one start (docs/method.md §3.13).
//!
//! * `displacement.csv` of `track`/`analyze` (one row per frame and target): each target a
//!   response (`disp_mm`, else the image's `-cy`), lost samples filled as `modal` fills them.
//! * Any other `.csv`: a header of channel names and an optional time column (`t_s`, `time` or
//!   `t`), every other column a channel.
//! * `.npy` (pyidi's `(points, samples, 2)`): channels `point P y`, `point P x`; by default
//!   both are read and [`choose_axis`] keeps the coordinate the hits excited above its noise
//!   (an impact test), else the one that moves more.
//! * `.lvm`, `.tdms`, `.uff`/`.unv` (dataset 58): channels by name, segments joined.
//!
//! **Rates.** From the file (a time column, LVM `Delta_X`, TDMS `wf_increment`, UFF's abscissa
//! increment) or given; both given and stated must agree within 0.1 %. When the two records'
//! rates differ the slower one is **upsampled** to the faster through firmware-core's Fourier
//! upsampler ([`crate::chain::resample::upsample_record`]): the faster record's band above the
//! slower one's Nyquist frequency is kept rather than filtered away, and the slower record, band
//! limited by its own sampling, loses nothing by exact band-limited interpolation; the FRFs are
//! only fitted below the slower record's Nyquist frequency.
//!
//! **Start.** Both records start at their shared trigger; `delay_s > 0` says the response's
//! first sample came that long after the force's (its whole samples are dropped from the
//! force's start; less than half a sample is left, stated), `< 0` the other way.

use super::{excited, impact, impact::ImpactRule};
use crate::bad_input;
use crate::daq::{self, Channel};
use crate::setting::SpecError;
use std::path::Path;

/// The channels read from one file.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Channel names.
    pub names: Vec<String>,
    /// Their unit, when the file states one (the first channel's).
    pub unit: Option<String>,
    /// Sample rate, Hz.
    pub fs_hz: f64,
    /// The samples, one vector per channel, of equal length.
    pub channels: Vec<Vec<f64>>,
    /// What was done on reading (targets left out, samples filled, an axis chosen).
    pub notes: Vec<String>,
    /// From a camera (`displacement.csv` or a pyidi `.npy`).
    pub camera: bool,
    /// The absolute time of the first sample (s since 1904-01-01 UTC), when the file states
    /// it (TDMS `wf_start_time`).
    pub start_time: Option<f64>,
    /// A pyidi `.npy` read without `$response_col`: its channels are every point's y, then
    /// every point's x, until [`choose_axis`] keeps one coordinate.
    pub axis_pending: bool,
}

/// Which reader a file's name asks for.
fn kind(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// The DAQ record of `path`, by its extension.
fn daq_record(path: &Path) -> anyhow::Result<daq::Record> {
    match kind(path).as_str() {
        "lvm" => daq::lvm::read(path),
        "tdms" => daq::tdms::read(path),
        "uff" | "unv" => daq::uff::read(path),
        "npy" => daq::npy::read(path),
        "csv" | "txt" => {
            let text = std::fs::read(path)
                .map_err(|e| bad_input(format!("{}: cannot read: {e}", path.display())))?;
            let time = crate::csvio::header_names(&text).into_iter().find(|c| {
                ["t_s", "time", "t", "time_s"].contains(&c.to_ascii_lowercase().as_str())
            });
            daq::csv::parse(&text, &path.display().to_string(), time.as_deref())
        }
        other => Err(bad_input(format!(
            "{}: cannot tell the format from the extension `.{other}` (.csv, .npy, .lvm, .tdms, \
             .uff or .unv)",
            path.display()
        ))),
    }
}

/// The rate of `channel` of `file`: stated, given as setting `key` (`$response_fs`), or both
/// (then they must agree). The errors name the setting (a [`SpecError`], spelled as the caller
/// spells it).
fn rate(
    channel: &Channel,
    given: Option<f64>,
    file: &str,
    key: &str,
    notes: &mut Vec<String>,
) -> anyhow::Result<f64> {
    let refuse = |m: String| anyhow::Error::new(SpecError::setting(m));
    match (channel.rate_hz(), given) {
        (Some(s), Some(g)) if (s - g).abs() > 1e-3 * g => Err(refuse(format!(
            "{file}: channel `{}` is sampled at {s} Hz by the file, {key} says {g} Hz",
            channel.name
        ))),
        // a rate stated exactly beats one from a rounded time column: the given one is used
        (Some(s), Some(g)) => {
            if s != g {
                notes.push(format!(
                    "{file}: the rate given, {} Hz, used; the file's time column gives {} Hz \
                     (within 0.1 %: rounded times)",
                    rate_text(g),
                    rate_text(s)
                ));
            }
            Ok(g)
        }
        (Some(s), None) => Ok(s),
        (None, Some(g)) => Ok(g),
        (None, None) => Err(refuse(format!(
            "{file}: the file states no sample rate for `{}`: give {key}",
            channel.name
        ))),
    }
}

/// Whether a CSV file is `track`'s `displacement.csv` (columns `frame` and `target`).
fn is_displacement_csv(path: &Path) -> bool {
    let Ok(text) = std::fs::read(path) else {
        return false;
    };
    let cols = crate::csvio::header_names(&text);
    cols.iter().any(|c| c == "frame") && cols.iter().any(|c| c == "target")
}

/// Reads the responses of `path`: the channels `cols` (empty: every channel; see the module
/// documentation), at `fs_hz` when the file states no rate.
pub fn read_responses(path: &Path, cols: &[String], fs_hz: Option<f64>) -> anyhow::Result<Series> {
    let file = path.display().to_string();
    let is_csv = matches!(kind(path).as_str(), "csv" | "txt");
    if is_csv && is_displacement_csv(path) {
        return responses_from_displacement(path, cols, fs_hz);
    }
    let record = daq_record(path)?;
    let first: Vec<String> = record
        .segments
        .first()
        .map(|s| s.iter().map(|c| c.name.clone()).collect())
        .unwrap_or_default();
    let mut notes = record.notes.clone();
    let npy = kind(path) == "npy";
    let wanted = wanted_channels(&first, cols, npy);
    let has = |a: &str| wanted.iter().any(|n| n.ends_with(a));
    let axis_pending = npy && cols.is_empty() && has(" y") && has(" x");
    if wanted.is_empty() {
        return Err(bad_input(format!("{file}: no channels")));
    }
    let chans: Vec<Channel> = wanted
        .iter()
        .map(|n| record.channel(n, &file))
        .collect::<anyhow::Result<_>>()?;
    for c in &chans {
        refuse_empty_or_not_finite(c, &file)?;
    }
    let fs = rate(&chans[0], fs_hz, &file, "$response_fs", &mut notes)?;
    for c in &chans[1..] {
        let r = c.rate_hz().unwrap_or(fs);
        if c.values.len() != chans[0].values.len() || (r - fs).abs() > 1e-6 * fs {
            return Err(bad_input(format!(
                "{file}: channel `{}` has {} samples at {r} Hz, `{}` {} at {fs} Hz: responses \
                 must share one time base",
                c.name,
                c.values.len(),
                chans[0].name,
                chans[0].values.len()
            )));
        }
    }
    let start_time = chans[0].start_time;
    Ok(Series {
        names: wanted,
        unit: chans[0].unit.clone(),
        fs_hz: fs,
        channels: chans.into_iter().map(|c| c.values).collect(),
        notes,
        camera: npy,
        start_time,
        axis_pending,
    })
}

/// The responses of a `displacement.csv` of `track` or `analyze`: each target a channel (or
/// the targets `cols` names), the lost samples filled.
fn responses_from_displacement(
    path: &Path,
    cols: &[String],
    fs_hz: Option<f64>,
) -> anyhow::Result<Series> {
    let file = path.display().to_string();
    use crate::analysis::oma::input::{read, PixelAxis};
    let r = read(path, PixelAxis::Y, fs_hz)?;
    let mut names: Vec<String> = r
        .targets
        .iter()
        .map(|(t, _)| format!("target {t}"))
        .collect();
    let mut channels = r.channels;
    let mut notes: Vec<String> = r
        .left_out
        .iter()
        .map(|(t, why)| format!("target {t} left out: {why}"))
        .collect();
    for ((t, _), n) in r.targets.iter().zip(&r.filled) {
        if *n > 0 {
            notes.push(format!(
                "target {t}: {n} lost samples filled by interpolation"
            ));
        }
    }
    if !cols.is_empty() {
        let mut keep = Vec::new();
        for c in cols {
            let i = names
                .iter()
                .position(|n| n == c || n.trim_start_matches("target ") == c);
            let i = i.ok_or_else(|| {
                bad_input(format!(
                    "{file}: no response `{c}` (its targets: {})",
                    names.join(", ")
                ))
            })?;
            keep.push(i);
        }
        names = keep.iter().map(|&i| names[i].clone()).collect();
        channels = keep.iter().map(|&i| channels[i].clone()).collect();
    }
    Ok(Series {
        names,
        unit: Some(r.unit),
        fs_hz: r.fs_hz,
        channels,
        notes,
        camera: true,
        start_time: None,
        axis_pending: false,
    })
}

/// The channels to read: those named, else (a pyidi `.npy`) every point's y then every point's
/// x, else every channel of the first segment.
fn wanted_channels(first: &[String], cols: &[String], npy: bool) -> Vec<String> {
    if !cols.is_empty() {
        cols.to_vec()
    } else if npy && first.iter().any(|n| n.ends_with(" y") || n.ends_with(" x")) {
        let ys = first.iter().filter(|n| n.ends_with(" y"));
        ys.chain(first.iter().filter(|n| n.ends_with(" x")))
            .cloned()
            .collect()
    } else {
        first.to_vec()
    }
}

/// How much the hits of an impact test (`rule`) excited `responses` above their noise in
/// `band_hz` (the summed early power over the floor of [`excited`]); `None` when the force
/// holds no usable hit or the blocks are too short to tell.
fn excited_score(
    force: &[f64],
    responses: &[&[f64]],
    fs_hz: f64,
    rule: ImpactRule,
    band_hz: (f64, f64),
) -> Option<excited::Excited> {
    let hits = impact::find(force, fs_hz, rule, "force").ok()?;
    excited::excited(responses, &hits, fs_hz, band_hz)
}

/// `v` with only the items at `keep` (ascending), moved, not copied.
fn only<T>(v: &mut Vec<T>, keep: &[usize]) {
    let all = std::mem::take(v);
    *v = all
        .into_iter()
        .enumerate()
        .filter_map(|(i, x)| keep.contains(&i).then_some(x))
        .collect();
}

/// Keeps one coordinate of a pyidi `.npy` read with both ([`Series::axis_pending`]): of an
/// impact test (`rule`), the one whose responses the hits excited more above their noise in
/// `band_hz`; otherwise, or when neither stands out, the one that moves more. Said in the
/// response's notes.
pub fn choose_axis(
    response: &mut Series,
    aligned: &mut Aligned,
    rule: Option<ImpactRule>,
    band_hz: (f64, f64),
) {
    if !response.axis_pending {
        return;
    }
    response.axis_pending = false;
    let ys: Vec<usize> = (0..response.names.len())
        .filter(|&i| response.names[i].ends_with(" y"))
        .collect();
    let xs: Vec<usize> = (0..response.names.len())
        .filter(|&i| response.names[i].ends_with(" x"))
        .collect();
    let score = |idx: &[usize]| {
        let rs: Vec<&[f64]> = idx
            .iter()
            .map(|&i| aligned.responses[i].as_slice())
            .collect();
        rule.and_then(|r| excited_score(&aligned.force, &rs, aligned.fs_hz, r, band_hz))
    };
    let (ey, ex) = (score(&ys), score(&xs));
    let spread = |idx: &[usize]| -> f64 {
        idx.iter()
            .map(|&i| {
                let v = &aligned.responses[i];
                let m = v.iter().sum::<f64>() / v.len().max(1) as f64;
                v.iter().map(|x| (x - m).powi(2)).sum::<f64>()
            })
            .sum()
    };
    let said = |e: &Option<excited::Excited>| {
        e.as_ref()
            .filter(|e| e.lines > 0)
            .map_or("none".to_string(), |e| {
                format!(
                    "{} lines, the strongest {:.0} dB above the noise",
                    e.lines, e.peak_snr_db
                )
            })
    };
    let (sy, sx) = (
        ey.as_ref().map_or(0.0, |e| e.score),
        ex.as_ref().map_or(0.0, |e| e.score),
    );
    let (keep, why) = if sy > 0.0 || sx > 0.0 {
        let y = sy >= sx;
        (
            if y { &ys } else { &xs },
            format!(
                "the hits excite it more above its noise (lines that stand {} dB above the \
                 noise and decay: y {}, x {})",
                excited::ABOVE_FLOOR_DB,
                said(&ey),
                said(&ex)
            ),
        )
    } else {
        let y = spread(&ys) >= spread(&xs);
        (
            if y { &ys } else { &xs },
            "it moves more than the other".to_string(),
        )
    };
    let axis = if keep == &ys { "y" } else { "x" };
    response.notes.push(format!(
        "the points' {axis} coordinate: {why}; $response_col to choose"
    ));
    only(&mut response.names, keep);
    only(&mut response.channels, keep);
    only(&mut aligned.responses, keep);
}

/// A response channel holds samples, every one finite.
fn refuse_empty_or_not_finite(c: &Channel, file: &str) -> anyhow::Result<()> {
    if c.values.is_empty() {
        return Err(bad_input(format!(
            "{file}: response channel `{}` holds no samples",
            c.name
        )));
    }
    if let Some(i) = c.values.iter().position(|v| !v.is_finite()) {
        return Err(bad_input(format!(
            "{file}: response channel `{}`, sample {}: not a finite number ({})",
            c.name,
            i + 1,
            c.values[i]
        )));
    }
    Ok(())
}

/// Reads the force channel `col` of `path` (empty `col`: the file's only channel), at `fs_hz`
/// when the file states no rate.
pub fn read_force(path: &Path, col: &str, fs_hz: Option<f64>) -> anyhow::Result<Series> {
    let file = path.display().to_string();
    let record = daq_record(path)?;
    let name = if col.is_empty() {
        let names: Vec<String> = record
            .segments
            .first()
            .map(|s| s.iter().map(|c| c.name.clone()).collect())
            .unwrap_or_default();
        match names.as_slice() {
            [] => {
                return Err(bad_input(format!(
                    "{file}: holds no channel that can be read as a force"
                )))
            }
            [one] => one.clone(),
            _ => {
                return Err(bad_input(format!(
                    "{file}: {} channels ({}): name the force with $excitation_col",
                    names.len(),
                    names.join(", ")
                )))
            }
        }
    } else {
        col.to_string()
    };
    let c = record.channel(&name, &file)?;
    if let Some(what) = c.unit.as_deref().and_then(not_a_force) {
        return Err(bad_input(format!(
            "{file}: channel `{name}` is in `{}`, a unit of {what}, not of a force: name the \
             hammer's or the force transducer's channel with $excitation_col",
            c.unit.as_deref().unwrap_or_default()
        )));
    }
    let mut notes = record.notes.clone();
    let fs = rate(&c, fs_hz, &file, "$excitation_fs", &mut notes)?;
    if let Some(i) = c.values.iter().position(|v| !v.is_finite()) {
        return Err(bad_input(format!(
            "{file}: channel `{name}`, sample {}: not a finite number",
            i + 1
        )));
    }
    Ok(Series {
        names: vec![name],
        unit: c.unit.clone(),
        fs_hz: fs,
        channels: vec![c.values.clone()],
        notes,
        camera: false,
        axis_pending: false,
        start_time: c.start_time,
    })
}

/// What a unit measures when it is clearly not a force (acceleration, velocity, displacement,
/// time); `None` for a force's units and for units that say nothing of it (volts, counts).
pub fn not_a_force(unit: &str) -> Option<&'static str> {
    let u: String = unit
        .trim()
        .to_ascii_lowercase()
        .replace(['²', ' '], "")
        .replace("^2", "2")
        .replace("**2", "2")
        .replace('µ', "u");
    let u = u.trim_matches(|c| c == '(' || c == ')' || c == '[' || c == ']');
    match u {
        "g" | "gn" | "g's" | "m/s2" | "m/s/s" | "mm/s2" | "in/s2" | "ft/s2" | "gal" => {
            Some("acceleration")
        }
        "m/s" | "mm/s" | "in/s" | "ips" | "ft/s" => Some("velocity"),
        "m" | "mm" | "um" | "nm" | "in" | "mil" | "mils" | "px" | "pixels" => Some("displacement"),
        "s" | "ms" | "sec" | "seconds" => Some("time"),
        _ => None,
    }
}

/// A rate as people write it: to nine significant digits (a rate from a CSV's mean time step
/// is 49999.99999999999 Hz for 50 kHz).
pub fn rate_text(hz: f64) -> String {
    let digits = 8 - hz.abs().log10().floor().clamp(-9.0, 8.0) as i32;
    let scale = 10f64.powi(digits);
    format!("{}", (hz * scale).round() / scale)
}

/// Force and responses at one rate and one start.
#[derive(Debug, Clone, PartialEq)]
pub struct Aligned {
    /// The common rate, Hz.
    pub fs_hz: f64,
    /// The slower record's Nyquist frequency, Hz: the FRFs' top.
    pub nyquist_hz: f64,
    /// The force.
    pub force: Vec<f64>,
    /// The responses.
    pub responses: Vec<Vec<f64>>,
    /// What was done (resampling and why, delay, lengths cut).
    pub notes: Vec<String>,
}

/// A warning when the two records last more than 10 % apart: records of one test last about
/// as long, and a rate given wrong (1500 for 15 kHz) shows here.
fn lengths_disagree(response: &Series, force: &Series) -> Option<String> {
    let (fr, ff) = (response.fs_hz, force.fs_hz);
    let (tr, tf) = (
        response.channels[0].len() as f64 / fr,
        force.channels[0].len() as f64 / ff,
    );
    ((tr - tf).abs() > 0.1 * tr.min(tf)).then(|| {
        format!(
            "warning: the responses last {tr:.4} s at {} Hz, the force {tf:.4} s at {} Hz: \
             records of one test should last about as long; check both rates (a rate given \
             wrong stretches its record)",
            rate_text(fr),
            rate_text(ff)
        )
    })
}

/// The delay of the responses after the force, s: `given` unless it is 0 and both files state
/// when their first sample was taken (TDMS `wf_start_time`), then theirs; the notes say which.
fn stated_delay(
    response: &Series,
    force: &Series,
    given: f64,
    fs: f64,
    notes: &mut Vec<String>,
) -> f64 {
    let stated = match (response.start_time, force.start_time) {
        (Some(r), Some(f)) => Some(r - f),
        _ => None,
    };
    match stated {
        Some(d) if given == 0.0 && (d * fs).abs() >= 0.5 => {
            notes.push(format!(
                "the files state their first samples {} s apart (wf_start_time): the responses \
                 taken as starting {d:.6} s after the force (a delay given, $delay_s, overrides it)",
                d.abs()
            ));
            d
        }
        Some(d) if given != 0.0 && ((d - given) * fs).abs() >= 0.5 => {
            notes.push(format!(
                "the delay given ({given} s) used, though the files state their first samples {d:.6} s \
                 apart (wf_start_time)"
            ));
            given
        }
        _ => given,
    }
}

/// Brings `response` and `force` to one rate (the faster's) and one start (`delay_s`, see the
/// module documentation), of equal length.
pub fn align(response: &Series, force: &Series, delay_s: f64) -> anyhow::Result<Aligned> {
    use crate::chain::resample::upsample_record;
    let (fr, ff) = (response.fs_hz, force.fs_hz);
    let mut notes = Vec::new();
    notes.extend(lengths_disagree(response, force));
    let same = (fr - ff).abs() <= 1e-9 * ff;
    let fs = fr.max(ff);
    let up = |v: &[f64], from: f64| -> anyhow::Result<Vec<f64>> {
        if same || from >= fs {
            Ok(v.to_vec())
        } else {
            upsample_record(v, from, fs)
        }
    };
    if !same {
        let (slow, fast) = if fr < ff {
            ("the responses", "the force")
        } else {
            ("the force", "the responses")
        };
        notes.push(format!(
            "{slow} ({} Hz) upsampled to {} Hz, the rate of {fast}, by Fourier interpolation \
             (firmware-core's upsampler, in overlapping chunks): the band of {fast} above {} Hz \
             is kept, not filtered away, and {slow}, band limited by their own sampling, lose \
             nothing; the FRFs are fitted below {} Hz",
            rate_text(fr.min(ff)),
            rate_text(fs),
            fr.min(ff) / 2.0,
            fr.min(ff) / 2.0
        ));
    }
    let mut f = up(&force.channels[0], ff)?;
    let mut xs: Vec<Vec<f64>> = response
        .channels
        .iter()
        .map(|c| up(c, fr))
        .collect::<anyhow::Result<_>>()?;
    let delay_s = stated_delay(response, force, delay_s, fs, &mut notes);
    drop_delay(delay_s, fs, (&mut f, &mut xs), &mut notes)?;
    let n = f.len().min(xs[0].len());
    if f.len() != xs[0].len() {
        notes.push(format!(
            "the {} record cut to the other's length ({:.4} s)",
            if f.len() > n { "force" } else { "responses'" },
            n as f64 / fs
        ));
    }
    f.truncate(n);
    for x in &mut xs {
        x.truncate(n);
    }
    Ok(Aligned {
        fs_hz: fs,
        nyquist_hz: fr.min(ff) / 2.0,
        force: f,
        responses: xs,
        notes,
    })
}

/// Drops the whole samples of a stated delay from the start of the force (a positive delay) or
/// of the responses (negative), said in `notes`.
fn drop_delay(
    delay_s: f64,
    fs: f64,
    (f, xs): (&mut Vec<f64>, &mut [Vec<f64>]),
    notes: &mut Vec<String>,
) -> anyhow::Result<()> {
    let shift = delay_s * fs;
    let whole = shift.round();
    if whole != 0.0 {
        let k = whole.abs() as usize;
        let (what, len) = if whole > 0.0 {
            ("force", f.len())
        } else {
            ("responses", xs[0].len())
        };
        if k >= len {
            return Err(anyhow::Error::new(SpecError::setting(format!(
                "$delay_s {delay_s}: the {what} record is only {:.4} s long",
                len as f64 / fs
            ))));
        }
        if whole > 0.0 {
            f.drain(..k);
        } else {
            for x in xs.iter_mut() {
                x.drain(..k);
            }
        }
        notes.push(format!(
            "a delay of {} s: the first {k} samples of the {what} dropped{}",
            rate_text(delay_s),
            if (shift - whole).abs() > 1e-6 {
                format!(
                    " ({:.3} of a sample at {} Hz left unaligned)",
                    (shift - whole).abs(),
                    rate_text(fs)
                )
            } else {
                String::new()
            }
        ));
    }
    Ok(())
}

/// The poles of a CSV with the columns `f_hz` and `damping` (a header row; other columns, as in
/// an earlier `modes.csv`, ignored): the modes `ema` is to give. Errors name the file and row.
pub fn read_poles(path: &Path) -> anyhow::Result<Vec<crate::analysis::modal::Pole>> {
    let file = path.display().to_string();
    let (_, header) = crate::csvio::open_with_header(path, &file, true)?;
    if let Some(c) = ["f_hz", "damping"]
        .iter()
        .find(|c| !header.iter().any(|h| h == *c))
    {
        return Err(bad_input(format!(
            "{file}: no column `{c}` (a poles file has `f_hz` and `damping`, as modes.csv)"
        )));
    }
    let cols = crate::csvio::read_columns(path, &["f_hz", "damping"])?;
    let (fs, ds) = (&cols.values[0], &cols.values[1]);
    fs.iter()
        .zip(ds)
        .enumerate()
        .map(|(i, (&f_hz, &damping))| {
            if f_hz > 0.0 && (0.0..1.0).contains(&damping) {
                Ok(crate::analysis::modal::Pole { f_hz, damping })
            } else {
                Err(bad_input(format!(
                    "{file}: row {}: a pole needs a frequency above 0 and a damping ratio from 0 \
                     to below 1, got {f_hz} Hz and {damping}",
                    i + 2
                )))
            }
        })
        .collect()
}

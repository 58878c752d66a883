//! `modal`: output-only modal analysis of a displacement file.

use super::{SpecError, SpecResult};
use crate::analysis::oma::input::{self, PixelAxis, Records};
use crate::analysis::oma::multi_setup::{Merge, SetupRecords};
use crate::analysis::oma::run::Output;
use crate::analysis::oma::OmaSettings;
use crate::analysis::WelchSettings;
use std::path::PathBuf;

/// `modal`'s settings as given.
#[derive(Debug, Clone, PartialEq)]
pub struct ModalInput {
    /// The displacement file (`track`'s `displacement.csv`, or a wide CSV).
    pub displacement: PathBuf,
    /// `$fps`, when the file has no time column.
    pub fps: Option<f64>,
    /// The coordinate of a `displacement.csv` without `disp_mm`.
    pub axis: PixelAxis,
    /// The Welch settings of the cross-spectra.
    pub welch: WelchSettings,
    /// `$bands`, Hz (none: peaks picked automatically).
    pub bands: Option<Vec<(f64, f64)>>,
    /// `$prominence_db` of an automatic peak.
    pub prominence_db: f64,
    /// `$f_min_hz`: the lowest frequency searched.
    pub f_min_hz: Option<f64>,
    /// `$efdd_quantity`: what the records measure (`None`: chosen from the bells).
    pub efdd_quantity: Option<crate::analysis::oma::bell::Quantity>,
    /// `$plscf`: also LSCF on half-spectra.
    pub plscf: bool,
    /// `$poles`: a CSV of the poles SSI gives as its modes (`f_hz`, `damping`: poles picked on
    /// the page's diagram, or an earlier `modes.csv`).
    pub poles: Option<PathBuf>,
    /// `$ssi`: covariance- or data-driven.
    pub ssi: crate::analysis::oma::ssi::SsiKind,
    /// `$ssi_block_rows`.
    pub ssi_block_rows: Option<usize>,
    /// `$ssi_max_order`.
    pub ssi_max_order: Option<usize>,
    /// `$references`: the first file's targets that every setup shares (with `$setup`).
    pub references: Option<Vec<usize>>,
    /// `$setup`: the other setups, each a file and its reference targets (in
    /// `$references`' order).
    pub setups: Vec<(PathBuf, Vec<usize>)>,
    /// `$merge`: how the setups are merged.
    pub merge: Merge,
    /// Output directory.
    pub out: PathBuf,
    /// Replace an earlier `modal` output there.
    pub force: bool,
    /// Also print `report.pdf` (headless Chromium).
    pub pdf: bool,
    /// Draw the figures.
    pub plots: bool,
    /// `$geometry`: the structure's nodes and lines the page draws the shapes on.
    pub geometry: Option<PathBuf>,
}

/// What a `modal` job computed ([`ModalSpec::compute`]).
#[derive(Debug, Clone)]
pub struct ModalComputed {
    /// The records analysed (with `$setup`, one channel per global point).
    pub records: Records,
    /// The modes found.
    pub result: crate::analysis::oma::OmaResult,
    /// With `$setup`: the report's lines on the setups and each setup's part in each mode.
    pub setups: Option<(String, Vec<crate::export::oma::OmaSetupRow>)>,
}

/// A checked `modal` job: its records read, its settings resolved against them.
#[derive(Debug, Clone)]
pub struct ModalSpec {
    input: ModalInput,
    records: Records,
    settings: OmaSettings,
    /// With `$setup`: every setup, the first file's first.
    others: Vec<SetupRecords>,
    /// `$geometry` read.
    geometry: Option<(PathBuf, vibcam_readers::geometry::Geometry)>,
}

/// pLSCF's highest order (`$plscf`): as SSI's default, 20 pole pairs.
pub const PLSCF_MAX_ORDER: usize = 40;

/// The settings of `records` (read from `file`) as `input` gives them, checked against it.
fn settings_for(
    input: &ModalInput,
    records: &Records,
    file: &std::path::Path,
) -> SpecResult<OmaSettings> {
    let fs_hz = records.fs_hz;
    let n = records.channels.first().map_or(0, Vec::len);
    let record = file.display().to_string();
    let mut s =
        crate::analysis::oma::segment_settings(fs_hz, &records.channels, &input.welch, &record)
            .map_err(SpecError::Input)?;
    let df = fs_hz / s.csd.nfft as f64;
    if let Some(f) = input.f_min_hz {
        if !(f.is_finite() && f >= 0.0 && f < fs_hz / 2.0) {
            return Err(SpecError::setting(format!(
                "$f_min_hz {f} must be between 0 and the Nyquist frequency ({} Hz) of {record}",
                fs_hz / 2.0
            )));
        }
        s.peaks.f_min_hz = f.max(df);
        s.ssi.f_range_hz.0 = f;
    }
    let range = vibcam_common::setting::table::number;
    s.peaks.prominence_db = range("modal", "prominence_db", input.prominence_db)?;
    if let Some(b) = &input.bands {
        super::bands_below_nyquist(b, fs_hz, "the record's")?;
        s.bands = b.clone();
    }
    s.ssi.kind = input.ssi;
    s.efdd.quantity = input.efdd_quantity;
    if let Some(i) = input.ssi_block_rows {
        range("modal", "ssi_block_rows", i as f64)?;
        s.ssi.block_rows = i;
    }
    if let Some(m) = input.ssi_max_order {
        range("modal", "ssi_max_order", m as f64)?;
        s.ssi.max_order = m;
    }
    if input.plscf {
        let rule = crate::analysis::ema::lscf::LscfRule {
            max_order: PLSCF_MAX_ORDER,
            ..Default::default()
        };
        // the run lowers the order to the band's lines (`plscf::MIN_ORDER` at least); here the
        // widest band it can have, to the Nyquist frequency
        let lines = ((fs_hz / 2.0 - s.ssi.f_range_hz.0) / df).floor() as usize + 1;
        let least = crate::analysis::oma::plscf::MIN_ORDER + 2;
        if lines < least {
            return Err(SpecError::setting(format!(
                "$plscf: {lines} spectral lines of {record} from {} Hz to the Nyquist frequency, \
                 LSCF needs at least {least}: a longer $nperseg or a lower $f_min_hz",
                s.ssi.f_range_hz.0
            )));
        }
        s.plscf = Some(rule);
    }
    if let Some(file) = &input.poles {
        s.poles = Some(poles_in_range(file, s.ssi.f_range_hz, &record)?);
    }
    if n < 4 * s.ssi.block_rows {
        return Err(SpecError::setting(format!(
            "$ssi_block_rows {}: {record} has {n} samples, at least {} are needed",
            s.ssi.block_rows,
            4 * s.ssi.block_rows
        )));
    }
    Ok(s)
}

/// The channels of `records` (read from `file`) that are the reference targets `refs`.
fn reference_channels(records: &Records, refs: &[usize], file: &str) -> SpecResult<Vec<usize>> {
    let mut out = Vec::with_capacity(refs.len());
    for &t in refs {
        let Some(c) = records.targets.iter().position(|(n, _)| *n == t) else {
            let why = records
                .left_out
                .iter()
                .find(|(n, _)| *n == t)
                .map_or("not in the file".to_string(), |(_, w)| {
                    format!("left out: {w}")
                });
            return Err(SpecError::setting(format!(
                "$references: target {t} of {file}: {why}"
            )));
        };
        if out.contains(&c) {
            return Err(SpecError::setting(format!(
                "$references: target {t} of {file} named twice"
            )));
        }
        out.push(c);
    }
    Ok(out)
}

/// `$setup` and `$references` go together.
fn setup_flags(input: &ModalInput) -> SpecResult<()> {
    match (input.setups.is_empty(), input.references.is_some()) {
        (true, true) => Err(SpecError::setting(
            "$references names the reference targets of several setups: give the other setups \
             with $setup",
        )),
        (false, false) => Err(SpecError::setting(
            "$setup needs $references: the targets of the first file that every setup shares",
        )),
        _ if input.poles.is_some() && (!input.setups.is_empty() || input.bands.is_some()) => {
            Err(SpecError::setting(
                "$poles with $setup or $bands: the poles given are the modes of one record; \
                 bands choose among clusters",
            ))
        }
        _ if input.merge == Merge::Preger && input.setups.is_empty() => Err(SpecError::setting(
            "$merge preger identifies several setups together: give them with $setup and \
             $references",
        )),
        _ => Ok(()),
    }
}

/// The poles of `file` (`$poles`), each within the frequencies SSI analyses of `record`.
fn poles_in_range(
    file: &std::path::Path,
    (lo, hi): (f64, f64),
    record: &str,
) -> SpecResult<Vec<crate::analysis::modal::Pole>> {
    let poles = crate::analysis::ema::input::read_poles(file).map_err(SpecError::Input)?;
    match poles.iter().find(|p| p.f_hz < lo || p.f_hz > hi) {
        Some(p) => Err(SpecError::setting(format!(
            "$poles: the pole at {} Hz lies outside the frequencies analysed in {record}, \
             {lo:.4}-{hi:.4} Hz ($f_min_hz, the Nyquist frequency)",
            p.f_hz
        ))),
        None => Ok(poles),
    }
}

/// Every setup (the first file's first) when `$setup` is given: read, their settings
/// resolved, their references found; none without it.
fn setups(input: &ModalInput, first: &Records) -> SpecResult<Vec<SetupRecords>> {
    let Some(refs) = &input.references else {
        return Ok(Vec::new());
    };
    let name = input.displacement.display().to_string();
    let mut out = vec![SetupRecords {
        records: first.clone(),
        settings: settings_for(input, first, &input.displacement)?,
        references: reference_channels(first, refs, &name)?,
        file: name,
        preger_block_rows: None,
    }];
    for (path, theirs) in &input.setups {
        let file = path.display().to_string();
        if theirs.len() != refs.len() {
            return Err(SpecError::setting(format!(
                "$setup {file}: {} reference targets, $references has {}",
                theirs.len(),
                refs.len()
            )));
        }
        let records = input::read(path, input.axis, input.fps).map_err(SpecError::Input)?;
        if input.merge == Merge::Preger && records.fs_hz != first.fs_hz {
            return Err(SpecError::setting(format!(
                "$merge preger: {file} is sampled at {} Hz, the first file at {} Hz: PreGER \
                 identifies the setups with one model, at one rate (resample, or merge by poser)",
                records.fs_hz, first.fs_hz
            )));
        }
        if records.unit != first.unit {
            return Err(SpecError::setting(format!(
                "$setup {file}: values in {}, the first file's in {}",
                records.unit, first.unit
            )));
        }
        out.push(SetupRecords {
            settings: settings_for(input, &records, path)?,
            references: reference_channels(&records, theirs, &file)?,
            records,
            file,
            preger_block_rows: None,
        });
    }
    if input.merge == Merge::Preger {
        // PreGER's block rows: as given, else SSI's raised for the references' map
        let shortest = out.iter().map(|s| s.records.channels[0].len()).min();
        let first = &out[0].settings.ssi;
        out[0].preger_block_rows = Some(input.ssi_block_rows.unwrap_or_else(|| {
            let n = shortest.unwrap_or(0);
            crate::analysis::oma::preger::block_rows(
                refs.len(),
                first.max_order,
                first.block_rows,
                n,
            )
        }));
    }
    Ok(out)
}

impl ModalSpec {
    /// Reads the displacement file (and every other setup's) and checks the settings against
    /// it.
    pub fn new(input: ModalInput) -> SpecResult<Self> {
        if let Some(b) = &input.bands {
            super::bands_ordered(b)?;
        }
        setup_flags(&input)?;
        let records =
            input::read(&input.displacement, input.axis, input.fps).map_err(SpecError::Input)?;
        let settings = settings_for(&input, &records, &input.displacement)?;
        let others = setups(&input, &records)?;
        let geometry = super::read_geometry(input.geometry.as_deref())?;
        let spec = ModalSpec {
            input,
            records,
            settings,
            others,
            geometry,
        };
        // one record: its targets are the shapes' points, so the geometry is checked now (with
        // setups the global points are known once merged)
        if spec.others.is_empty() {
            spec.wire(&spec.records).map_err(SpecError::Input)?;
        }
        Ok(spec)
    }

    /// The lines of the page's shapes on the targets of `records`: the geometry is checked
    /// against every target of the file (a node of a target left out, too lost or constant, is
    /// no error), then kept on the targets analysed (the shapes' points).
    fn wire(&self, records: &Records) -> anyhow::Result<crate::export::wire::Wire> {
        let kept = records.targets.iter().map(|t| t.0);
        let points: Vec<usize> = kept.chain(records.left_out.iter().map(|t| t.0)).collect();
        let all = crate::export::wire::Wire::on(self.geometry.as_ref(), &points, "target", None)?;
        Ok(all.keep(&(0..records.targets.len()).collect::<Vec<_>>()))
    }

    /// The records read.
    pub fn records(&self) -> &Records {
        &self.records
    }

    /// The analysis settings.
    pub fn settings(&self) -> &OmaSettings {
        &self.settings
    }

    /// The job's results without writing a file: the records (the global points' with
    /// `$setup`), the modes, and with `$setup` the merge's report lines and `setups.csv`'s rows.
    pub fn compute(&self) -> anyhow::Result<ModalComputed> {
        if !self.others.is_empty() {
            let m = crate::analysis::oma::multi_setup::compute(&self.others, self.input.merge)?;
            return Ok(ModalComputed {
                records: m.records,
                result: m.result,
                setups: Some((m.text, m.rows)),
            });
        }
        Ok(ModalComputed {
            result: crate::analysis::oma::analyze(&self.records.channels, &self.settings)?,
            records: self.records.clone(),
            setups: None,
        })
    }

    /// The report and the page of what [`ModalSpec::compute`] found, as [`ModalSpec::run`]
    /// writes them (`report.txt`, `report.html`; the figures drawn in memory).
    pub fn report_and_page(&self, c: &ModalComputed) -> anyhow::Result<(String, String)> {
        use crate::analysis::oma::run;
        let setups = c.setups.as_ref().map_or("", |(text, _)| text.as_str());
        let preamble = format!("{}{setups}", self.preamble());
        let report = run::report(&c.result, &c.records, &self.settings, &preamble);
        let figures = run::figures(&c.result, &self.settings)?;
        let along_x = self.input.axis == PixelAxis::X;
        let inputs = self.inputs();
        let inputs: Vec<&std::path::Path> = inputs.iter().map(|p| p.as_path()).collect();
        let provenance = vibcam_report::provenance::Provenance::now(&inputs);
        let wire = self.wire(&c.records)?;
        let page = crate::analysis::signed_page(&provenance, &report, |report| {
            run::page(
                &c.result,
                &c.records,
                ("modal", along_x),
                (None, Vec::new(), None),
                (crate::plots::page_figures(&figures), wire),
                report,
            )
        });
        Ok((report, page))
    }

    /// The files the job reads: the displacement file, the other setups' files, the poles, the
    /// geometry.
    fn inputs(&self) -> Vec<std::path::PathBuf> {
        let i = &self.input;
        let mut inputs = vec![i.displacement.clone()];
        inputs.extend(i.setups.iter().map(|(p, _)| p.clone()));
        inputs.extend(i.poles.clone());
        inputs.extend(i.geometry.clone());
        inputs
    }

    /// The report's first line: the input.
    fn preamble(&self) -> String {
        format!("input: {}\n", self.input.displacement.display())
    }

    /// Runs the job: the report, and whether it succeeded.
    pub fn run(&self) -> anyhow::Result<crate::analysis::run::Outcome> {
        self.write(&self.compute()?)
    }

    /// Writes what [`ModalSpec::compute`] found into the output directory (with `$setup`,
    /// `setups.csv` too): the report, and whether it succeeded.
    pub fn write(&self, c: &ModalComputed) -> anyhow::Result<crate::analysis::run::Outcome> {
        let i = &self.input;
        let inputs = self.inputs();
        let (text, extra) = match &c.setups {
            Some((text, rows)) => (
                text.as_str(),
                vec![(
                    "setups.csv".to_string(),
                    crate::export::oma::setups_csv(rows),
                )],
            ),
            None => ("", Vec::new()),
        };
        let output = Output {
            out: &i.out,
            force: i.force,
            pdf: i.pdf,
            command: "modal",
            inputs,
            plots: i.plots,
            along_x: i.axis == PixelAxis::X,
            preamble: format!("{}{text}", self.preamble()),
            extra,
            frame: None,
            view: None,
            scrub: None,
            wire: self.wire(&c.records)?,
            magnify: None,
        };
        crate::analysis::oma::run::write(&c.records, &self.settings, &c.result, &output)
    }
}

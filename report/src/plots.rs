//! PNG and SVG figures of study results (and an FRF figure for recordings), drawn with
//! `plotters` and the bundled DejaVu Sans font (no system fontconfig needed).
//!
//! Study figures, each written as `NAME.png` and `NAME.svg`:
//! * `frf_band`: mean |FRF| with its 90 % band (5th..95th percentile) per exposure, transducer
//!   and vision overlaid, one panel per exposure;
//! * `pdf_a`, `pdf_f`: density histograms of the picked amplitude and frequency, one panel per
//!   mode, one curve per exposure (vision) plus the transducer;
//! * `sigma_vs_mu`: sigma_a against mu_a across exposures, per mode;
//! * `band_width`: width of the 90 % band against frequency, per exposure and system.

use crate::export::study::{FrfBandRow, RealizationRow, SummaryRow, System};
use anyhow::Context as _;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Inputs of the study figures.
#[derive(Debug)]
pub struct StudyPlots<'a> {
    /// Study name, used in titles.
    pub title: &'a str,
    /// Unit of the amplitudes.
    pub amplitude_unit: &'a str,
    /// `summary.csv` rows.
    pub summary: &'a [SummaryRow],
    /// `realizations.csv` rows.
    pub realizations: &'a [RealizationRow],
    /// `frf_band.csv` rows.
    pub frf_band: &'a [FrfBandRow],
}

type DrawResult = Result<(), Box<dyn std::error::Error>>;

const FONT: &str = "sans-serif";
const SIZE: (u32, u32) = (1400, 900);

fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font(
            FONT,
            FontStyle::Normal,
            include_bytes!("../assets/DejaVuSans.ttf"),
        );
    });
}

/// Colour of exposure `i` of `n` (blue to red).
fn exposure_colour(i: usize, n: usize) -> RGBColor {
    let t = if n <= 1 {
        1.0
    } else {
        i as f64 / (n - 1) as f64
    };
    RGBColor(
        (40.0 + 200.0 * t) as u8,
        (90.0 + 40.0 * (1.0 - (2.0 * t - 1.0).abs())) as u8,
        (220.0 - 190.0 * t) as u8,
    )
}

/// A labelled, coloured curve.
type Curve = (String, RGBColor, Vec<(f64, f64)>);

const TRANSDUCER: RGBColor = RGBColor(30, 30, 30);

/// A figure drawn in memory: its file name stem (`NAME.png`, `NAME.svg`), the PNG's bytes and
/// the SVG's text. The writer of a job puts both beside its other outputs and embeds the SVG in
/// `report.html` from here (no figure is read back from the disk).
#[derive(Debug, Clone)]
pub struct Figure {
    /// File name stem.
    pub name: String,
    /// `NAME.png`.
    pub png: Vec<u8>,
    /// `NAME.svg`.
    pub svg: String,
}

impl Figure {
    /// Writes `NAME.png` and `NAME.svg` into `dir` (a study's directory); returns the paths.
    pub fn write_into(&self, dir: &Path) -> anyhow::Result<Vec<PathBuf>> {
        let png = dir.join(format!("{}.png", self.name));
        let svg = dir.join(format!("{}.svg", self.name));
        std::fs::write(&png, &self.png)
            .with_context(|| format!("cannot write {}", png.display()))?;
        std::fs::write(&svg, &self.svg)
            .with_context(|| format!("cannot write {}", svg.display()))?;
        Ok(vec![png, svg])
    }
}

impl Figure {
    /// Puts `NAME.png` and `NAME.svg` into a job's staged output.
    pub fn write_staged(&self, out: &crate::outdir::Staged) -> anyhow::Result<()> {
        out.write(&format!("{}.png", self.name), &self.png)?;
        out.write(&format!("{}.svg", self.name), &self.svg)?;
        Ok(())
    }
}

/// The figures as `report.html` takes them: (caption, SVG text).
pub fn page_figures(figures: &[Figure]) -> Vec<(String, String)> {
    figures
        .iter()
        .map(|f| (f.name.clone(), f.svg.clone()))
        .collect()
}

/// Draws one figure as PNG and SVG, in memory, through the same drawing function.
fn both(
    name: &str,
    draw: &dyn Fn(DrawingArea<BitMapBackend, Shift>) -> DrawResult,
    draw_svg: &dyn Fn(DrawingArea<SVGBackend, Shift>) -> DrawResult,
) -> anyhow::Result<Figure> {
    use image::ImageEncoder as _;
    let mut rgb = vec![0u8; SIZE.0 as usize * SIZE.1 as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(root).map_err(|e| anyhow::anyhow!("{name}.png: {e}"))?;
    }
    let mut png = Vec::new();
    image::codecs::png::PngEncoder::new(&mut png)
        .write_image(&rgb, SIZE.0, SIZE.1, image::ExtendedColorType::Rgb8)
        .with_context(|| format!("{name}.png"))?;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw_svg(root).map_err(|e| anyhow::anyhow!("{name}.svg: {e}"))?;
    }
    Ok(Figure {
        name: name.to_string(),
        png,
        svg,
    })
}

macro_rules! figure {
    ($name:expr, $f:expr) => {
        both($name, &|r| $f(r), &|r| $f(r))
    };
}

/// The chart every figure draws in: `f64` on both axes.
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Sizes of a chart, px: caption font, margin, axis label areas, tick and legend font.
#[derive(Debug, Clone, Copy)]
struct Layout {
    caption: u32,
    margin: u32,
    x_label_area: u32,
    y_label_area: u32,
    labels: u32,
}

/// One panel of a multi-panel study figure.
const PANEL: Layout = Layout {
    caption: 18,
    margin: 8,
    x_label_area: 36,
    y_label_area: 60,
    labels: 13,
};

/// The single chart of a figure ([`lines_figure`]).
const SINGLE: Layout = Layout {
    caption: 24,
    margin: 10,
    x_label_area: 40,
    y_label_area: 70,
    labels: 14,
};

/// A chart on `area` over `x` and `y`, its mesh and axis descriptions already drawn.
fn build_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    layout: Layout,
    caption: &str,
    x: Range<f64>,
    y: Range<f64>,
    x_desc: &str,
    y_desc: &str,
) -> Result<Chart<'a, DB>, Box<dyn std::error::Error>>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .caption(caption, (FONT, layout.caption))
        .margin(layout.margin)
        .x_label_area_size(layout.x_label_area)
        .y_label_area_size(layout.y_label_area)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .label_style((FONT, layout.labels))
        .draw()?;
    Ok(chart)
}

/// Draws a line through `points` in `colour`, `width` px wide, labelled `label` in the legend
/// with a short line of the same style.
fn draw_line<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    points: impl IntoIterator<Item = (f64, f64)>,
    colour: RGBColor,
    width: u32,
    label: impl Into<String>,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    chart
        .draw_series(LineSeries::new(points, colour.stroke_width(width)))?
        .label(label)
        .legend(move |(x, y)| {
            PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(width))
        });
    Ok(())
}

/// Draws a dashed curve (a fit beside its data) with its legend entry.
fn draw_dashed<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    points: Vec<(f64, f64)>,
    colour: RGBColor,
    label: impl Into<String>,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let style = colour.stroke_width(2);
    chart
        .draw_series(DashedLineSeries::new(points, 7, 5, style))?
        .label(label)
        .legend(move |(x, y)| {
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (7, 0)], style)
                + PathElement::new(vec![(12, 0), (19, 0)], style)
        });
    Ok(())
}

/// `c` at half its brightness.
fn darker(c: RGBColor) -> RGBColor {
    RGBColor(c.0 / 2, c.1 / 2, c.2 / 2)
}

/// Draws the legend of `chart` in its upper right corner.
fn draw_legend<'a, DB: DrawingBackend + 'a>(chart: &mut Chart<'a, DB>, layout: Layout) -> DrawResult
where
    DB::ErrorType: 'static,
{
    chart
        .configure_series_labels()
        .label_font((FONT, layout.labels))
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

fn exposures(rows: &[SummaryRow]) -> Vec<f64> {
    let mut e: Vec<f64> = rows.iter().map(|r| r.exposure_ms).collect();
    e.sort_by(f64::total_cmp);
    e.dedup();
    e
}

fn finite_range(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if lo.is_finite() && hi.is_finite() {
        if hi > lo {
            Some((lo, hi))
        } else {
            Some((lo - 0.5 * lo.abs().max(1e-9), hi + 0.5 * hi.abs().max(1e-9)))
        }
    } else {
        None
    }
}

/// Every study figure, drawn in memory.
pub fn study_figures(p: &StudyPlots) -> anyhow::Result<Vec<Figure>> {
    register_font();
    if p.summary.is_empty() {
        anyhow::bail!("no study results to plot");
    }
    Ok(vec![
        figure!("frf_band", |r| draw_frf_band(r, p, false))?,
        figure!("band_width", |r| draw_frf_band(r, p, true))?,
        figure!("pdf_a", |r| draw_pdfs(r, p, true))?,
        figure!("pdf_f", |r| draw_pdfs(r, p, false))?,
        figure!("sigma_vs_mu", |r| draw_sigma_mu(r, p))?,
    ])
}

fn draw_frf_band<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    p: &StudyPlots,
    width_only: bool,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let exps = exposures(p.summary);
    let title = if width_only {
        format!("{}: width of the 90 % band of |FRF| (p95 - p05)", p.title)
    } else {
        format!("{}: mean |FRF| and 90 % band per exposure", p.title)
    };
    let root = root.titled(&title, (FONT, 26))?;
    let cols = (exps.len() as f64).sqrt().ceil().max(1.0) as usize;
    let rows = exps.len().div_ceil(cols).max(1);
    let panels = root.split_evenly((rows, cols));
    let x_range = finite_range(p.frf_band.iter().map(|r| r.freq_hz)).unwrap_or((0.0, 1.0));
    let value = |r: &FrfBandRow| {
        if width_only {
            r.p95_abs - r.p05_abs
        } else {
            r.p95_abs
        }
    };
    let y_max = p
        .frf_band
        .iter()
        .map(value)
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        * 1.05;
    for (panel, &e) in panels.iter().zip(&exps) {
        let mut chart = build_chart(
            panel,
            PANEL,
            &format!("exposure {e} ms"),
            x_range.0..x_range.1,
            0.0..y_max.max(1e-12),
            "frequency (Hz)",
            &format!("|FRF| ({})", p.amplitude_unit),
        )?;
        for (system, colour) in [
            (System::Transducer, TRANSDUCER),
            (System::Vision, RGBColor(210, 40, 40)),
            (System::VisionCompensated, RGBColor(40, 150, 60)),
        ] {
            draw_frf_system(&mut chart, p, e, system, colour, width_only)?;
        }
        draw_legend(&mut chart, PANEL)?;
    }
    root.present()?;
    Ok(())
}

/// One system's curve in a panel of [`draw_frf_band`] (exposure `e` ms): the band's width, or
/// the mean |FRF| over its shaded 90 % band.
fn draw_frf_system<DB: DrawingBackend>(
    chart: &mut Chart<DB>,
    p: &StudyPlots,
    e: f64,
    system: System,
    colour: RGBColor,
    width_only: bool,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let rows: Vec<&FrfBandRow> = p
        .frf_band
        .iter()
        .filter(|r| r.system == system && r.exposure_ms == e)
        .filter(|r| r.mean_abs.is_finite() && r.p05_abs.is_finite())
        .collect();
    if rows.is_empty() {
        return Ok(());
    }
    if width_only {
        draw_line(
            chart,
            rows.iter().map(|r| (r.freq_hz, r.p95_abs - r.p05_abs)),
            colour,
            2,
            system.name(),
        )?;
    } else {
        let band: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (r.freq_hz, r.p95_abs))
            .chain(rows.iter().rev().map(|r| (r.freq_hz, r.p05_abs)))
            .collect();
        chart.draw_series(std::iter::once(Polygon::new(band, colour.mix(0.2))))?;
        draw_line(
            chart,
            rows.iter().map(|r| (r.freq_hz, r.mean_abs)),
            colour,
            2,
            format!("{} mean, 90 % band shaded", system.name()),
        )?;
    }
    Ok(())
}

fn draw_pdfs<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    p: &StudyPlots,
    amplitude: bool,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let what = if amplitude {
        format!("resonant amplitude ({})", p.amplitude_unit)
    } else {
        "resonance frequency (Hz)".to_string()
    };
    let root = root.titled(
        &format!("{}: PDF of the {what} per mode", p.title),
        (FONT, 26),
    )?;
    let mut modes: Vec<usize> = p.summary.iter().map(|r| r.mode).collect();
    modes.sort();
    modes.dedup();
    let exps = exposures(p.summary);
    let panels = root.split_evenly((1, modes.len().max(1)));
    let get = |r: &RealizationRow| if amplitude { r.a } else { r.f_hz };
    for (panel, &m) in panels.iter().zip(&modes) {
        let vals: Vec<&RealizationRow> = p.realizations.iter().filter(|r| r.mode == m).collect();
        let Some((lo, hi)) = finite_range(vals.iter().map(|r| get(r))) else {
            continue;
        };
        // curves: transducer (one exposure's rows, they repeat) and vision per exposure
        let mut curves: Vec<Curve> = Vec::new();
        let bins = 30;
        if let Some(&e0) = exps.first() {
            let t: Vec<f64> = vals
                .iter()
                .filter(|r| r.system == System::Transducer && r.exposure_ms == e0)
                .map(|r| get(r))
                .collect();
            curves.push((
                "transducer".into(),
                TRANSDUCER,
                vibcam_common::stats::density_histogram(&t, lo, hi, bins),
            ));
        }
        for (i, &e) in exps.iter().enumerate() {
            let v: Vec<f64> = vals
                .iter()
                .filter(|r| r.system == System::Vision && r.exposure_ms == e)
                .map(|r| get(r))
                .collect();
            curves.push((
                format!("vision {e} ms"),
                exposure_colour(i, exps.len()),
                vibcam_common::stats::density_histogram(&v, lo, hi, bins),
            ));
        }
        let y_max = curves
            .iter()
            .flat_map(|c| c.2.iter().map(|p| p.1))
            .fold(0.0f64, f64::max)
            * 1.1;
        let mut chart = build_chart(
            panel,
            PANEL,
            &format!("mode {m}"),
            lo..hi,
            0.0..y_max.max(1e-12),
            &what,
            "probability density",
        )?;
        for (label, colour, pts) in curves {
            let width = if label == "transducer" { 3 } else { 2 };
            draw_line(&mut chart, pts, colour, width, label)?;
        }
        draw_legend(&mut chart, PANEL)?;
    }
    root.present()?;
    Ok(())
}

fn draw_sigma_mu<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, p: &StudyPlots) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let root = root.titled(
        &format!(
            "{}: standard deviation against mean of the resonant amplitude across exposures",
            p.title
        ),
        (FONT, 24),
    )?;
    let mut modes: Vec<usize> = p.summary.iter().map(|r| r.mode).collect();
    modes.sort();
    modes.dedup();
    let panels = root.split_evenly((1, modes.len().max(1)));
    for (panel, &m) in panels.iter().zip(&modes) {
        let rows: Vec<&SummaryRow> = p
            .summary
            .iter()
            .filter(|r| r.mode == m && r.mu_a.is_finite() && r.sigma_a.is_finite())
            .collect();
        let (Some(xr), Some(yr)) = (
            finite_range(rows.iter().map(|r| r.mu_a)),
            finite_range(rows.iter().map(|r| r.sigma_a)),
        ) else {
            continue;
        };
        let pad = |(a, b): (f64, f64)| (a - 0.1 * (b - a), b + 0.2 * (b - a));
        let (xr, yr) = (pad(xr), pad(yr));
        let mut chart = build_chart(
            panel,
            PANEL,
            &format!("mode {m}"),
            xr.0..xr.1,
            yr.0..yr.1,
            &format!("mu_a ({})", p.amplitude_unit),
            &format!("sigma_a ({})", p.amplitude_unit),
        )?;
        let mut vis: Vec<&&SummaryRow> =
            rows.iter().filter(|r| r.system == System::Vision).collect();
        vis.sort_by(|a, b| a.exposure_ms.total_cmp(&b.exposure_ms));
        let red = RGBColor(210, 40, 40);
        draw_line(
            &mut chart,
            vis.iter().map(|r| (r.mu_a, r.sigma_a)),
            red,
            2,
            "vision, by exposure",
        )?;
        chart.draw_series(vis.iter().map(|r| {
            EmptyElement::at((r.mu_a, r.sigma_a))
                + Circle::new((0, 0), 5, red.filled())
                + Text::new(format!("{} ms", r.exposure_ms), (8, -14), (FONT, 13))
        }))?;
        if let Some(t) = rows.iter().find(|r| r.system == System::Transducer) {
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((t.mu_a, t.sigma_a))
                        + Cross::new((0, 0), 8, TRANSDUCER.stroke_width(3))
                        + Text::new("transducer", (10, 6), (FONT, 13)),
                ))?
                .label("transducer")
                .legend(|(x, y)| Cross::new((x + 10, y), 6, TRANSDUCER.stroke_width(2)));
        }
        draw_legend(&mut chart, PANEL)?;
    }
    root.present()?;
    Ok(())
}

/// Labelled curves `(label, x, y)` drawn as `lines` says (an FRF's magnitude, an FRF in dB,
/// tracks over time), as `NAME.png` and `NAME.svg`.
pub fn lines_figure(
    name: &str,
    title: &str,
    y_label: &str,
    curves: &[(&str, &[f64], &[f64])],
    lines: Lines,
) -> anyhow::Result<Figure> {
    register_font();
    figure!(name, |r| draw_lines(r, title, y_label, curves, lines))
}

/// How [`lines_figure`] draws a figure: an FRF (frequency axis, values from 0, the first curve
/// the transducer's, thick lines), an FRF in dB (frequency axis, the values' own range) or
/// tracks (time axis, the values' own range, thin lines in the exposure colours).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lines {
    /// An FRF's magnitude: frequency axis, values from 0, the first curve the transducer's.
    Frf,
    /// An FRF in decibels: frequency axis, the values' own range (negative included).
    FrfDb,
    /// Tracks over time: time axis, the values' own range, thin lines.
    Tracks,
    /// Measured FRFs and their fits (a fit labelled as its data with [`FIT`] after, drawn
    /// after it): frequency axis, the values' own range; each response's data solid in its
    /// colour, its fit dashed in a darker shade of it.
    FrfFit,
}

/// The most curves a [`lines_figure`] names one by one in its legend; with more it names the
/// first and the last, and says the colours of the others run between.
pub const LEGEND_MAX: usize = 10;

/// What ends a fit's label in a [`Lines::FrfFit`] figure.
pub const FIT: &str = " fit";

fn draw_lines<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    y_label: &str,
    curves: &[(&str, &[f64], &[f64])],
    lines: Lines,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let xr = finite_range(curves.iter().flat_map(|c| c.1.iter().copied())).unwrap_or((0.0, 1.0));
    let values = || curves.iter().flat_map(|c| c.2.iter().copied());
    let (y_range, x_label) = match lines {
        Lines::Frf => {
            let y_max = values().filter(|v| v.is_finite()).fold(0.0f64, f64::max) * 1.05;
            (0.0..y_max.max(1e-12), "frequency (Hz)")
        }
        Lines::Tracks | Lines::FrfDb | Lines::FrfFit => {
            let (lo, hi) = finite_range(values()).unwrap_or((-1.0, 1.0));
            let pad = ((hi - lo) * 0.05).max(1e-9);
            let x_label = if lines == Lines::Tracks {
                "time (s)"
            } else {
                "frequency (Hz)"
            };
            (lo - pad..hi + pad, x_label)
        }
    };
    let mut chart = build_chart(&root, SINGLE, title, xr.0..xr.1, y_range, x_label, y_label)?;
    for (i, (label, x, y)) in curves.iter().enumerate() {
        let points = x
            .iter()
            .zip(y.iter())
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(x, y)| (*x, *y));
        let (colour, width) = match lines {
            Lines::Frf if i == 0 => (TRANSDUCER, 2),
            Lines::Frf | Lines::FrfDb => (exposure_colour(i, curves.len().max(2)), 2),
            Lines::Tracks => (exposure_colour(i, curves.len().max(2)), 1),
            Lines::FrfFit => {
                // a fit takes the colour of the data drawn before it
                let data = |c: &&(&str, &[f64], &[f64])| !c.0.ends_with(FIT);
                let k = curves.iter().filter(data).count();
                let j = curves[..=i].iter().filter(data).count().max(1) - 1;
                (exposure_colour(j, k.max(2)), 1)
            }
        };
        // many curves: the legend names the first and the last (the colours run between)
        let crowd = curves.len() > LEGEND_MAX && i > 0 && i + 1 < curves.len();
        if lines == Lines::FrfFit && label.ends_with(FIT) {
            draw_dashed(&mut chart, points.collect(), darker(colour), *label)?;
        } else if crowd {
            chart.draw_series(LineSeries::new(points, colour.stroke_width(width)))?;
        } else {
            draw_line(&mut chart, points, colour, width, *label)?;
        }
        if crowd && i == 1 {
            let between = format!(
                "{} .. {}: colours between",
                curves[1].0,
                curves[curves.len() - 2].0
            );
            draw_line(
                &mut chart,
                std::iter::empty(),
                RGBColor(150, 150, 150),
                1,
                between,
            )?;
        }
    }
    draw_legend(&mut chart, SINGLE)?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_legend_of_many_tracks_names_the_first_and_the_last() {
        let t: Vec<f64> = (0..50).map(f64::from).collect();
        let ys: Vec<Vec<f64>> = (0..28)
            .map(|k| t.iter().map(|v| v * f64::from(k)).collect())
            .collect();
        let names: Vec<String> = (1..=28).map(|k| format!("target {k}")).collect();
        let curves: Vec<(&str, &[f64], &[f64])> = names
            .iter()
            .zip(&ys)
            .map(|(n, y)| (n.as_str(), t.as_slice(), y.as_slice()))
            .collect();
        let f = lines_figure("tracks", "Tracks", "px", &curves, Lines::Tracks).unwrap();
        // the SVG writes each text on a line of its own
        let lines: Vec<&str> = f.svg.lines().collect();
        for named in [
            "target 1",
            "target 28",
            "target 2 .. target 27: colours between",
        ] {
            assert!(lines.contains(&named), "{named}");
        }
        assert!(!lines.contains(&"target 14"));
        // ten or fewer: each by name
        let f = lines_figure(
            "tracks",
            "Tracks",
            "px",
            &curves[..LEGEND_MAX],
            Lines::Tracks,
        );
        assert!(f.unwrap().svg.lines().any(|l| l == "target 10"));
    }

    #[test]
    fn a_db_range_ends_forty_db_under_the_first_curves_floor() {
        // the first curve from -20 to 0 dB (5th percentile -19), a second of rounding noise
        let first: Vec<f64> = (0..=100).map(|i| -20.0 + 0.2 * f64::from(i)).collect();
        let noise = vec![-3000.0; 101];
        let (lo, hi) = db_range(&[first.clone(), noise]).unwrap();
        assert_eq!(hi, 0.0);
        assert!((lo - (-19.0 - DB_BELOW_FLOOR)).abs() < 1e-9, "{lo}");
        // curves within the reach keep their own lowest value
        let near: Vec<f64> = first.iter().map(|v| v - 10.0).collect();
        assert_eq!(db_range(&[first, near]).unwrap(), (-30.0, 0.0));
        assert_eq!(db_range(&[]), None);
    }

    fn sample() -> (Vec<SummaryRow>, Vec<RealizationRow>, Vec<FrfBandRow>) {
        let mut s = Vec::new();
        let mut r = Vec::new();
        let mut f = Vec::new();
        for (i, e) in [40.0, 180.0].into_iter().enumerate() {
            for m in 1..=2 {
                for system in [System::Transducer, System::Vision] {
                    let drop = if system == System::Vision {
                        1.0 - 0.1 * i as f64
                    } else {
                        1.0
                    };
                    s.push(SummaryRow {
                        system,
                        exposure_ms: e,
                        mode: m,
                        runs: 5,
                        mu_f_hz: 2.0 * m as f64,
                        sigma_f_hz: 0.1,
                        mu_a: 4.0 * drop,
                        sigma_a: 0.3 * drop,
                        e2pr: e / 1000.0 * 2.0,
                        chi_mu: None,
                        chi_sigma: None,
                        a_coverage: None,
                        f_coverage: None,
                    });
                    for run in 0..5 {
                        r.push(RealizationRow {
                            run,
                            exposure_ms: e,
                            system,
                            mode: m,
                            f_hz: 2.0 * m as f64 + 0.01 * run as f64,
                            a: 4.0 * drop + 0.1 * run as f64,
                        });
                    }
                }
            }
            for k in 0..50 {
                for system in [System::Transducer, System::Vision] {
                    let x = k as f64 * 0.1;
                    let v = 1.0 / (1.0 + (x - 2.0).powi(2) * 10.0);
                    f.push(FrfBandRow {
                        system,
                        exposure_ms: e,
                        freq_hz: x,
                        mean_abs: v,
                        p05_abs: 0.8 * v,
                        p95_abs: if k == 7 { f64::NAN } else { 1.2 * v },
                    });
                }
            }
        }
        (s, r, f)
    }

    #[test]
    fn study_figures_are_drawn_as_png_and_svg() {
        let (s, r, f) = sample();
        let p = StudyPlots {
            title: "test",
            amplitude_unit: "mm/kN",
            summary: &s,
            realizations: &r,
            frf_band: &f,
        };
        let figures = study_figures(&p).unwrap();
        assert_eq!(figures.len(), 5);
        for fig in &figures {
            let img = image::load_from_memory(&fig.png).unwrap();
            assert_eq!((img.width(), img.height()), SIZE);
            assert!(fig.svg.contains("<svg"), "{}", fig.name);
            assert!(fig.svg.contains("mode 1") || fig.svg.contains("exposure"));
        }
        let dir = tempfile::tempdir().unwrap();
        let paths = figures[0].write_into(dir.path()).unwrap();
        assert_eq!(paths.len(), 2);
        assert!(paths.iter().all(|p| p.exists()));
        let empty = StudyPlots {
            title: "empty",
            amplitude_unit: "",
            summary: &[],
            realizations: &[],
            frf_band: &[],
        };
        assert!(study_figures(&empty).is_err());
    }

    #[test]
    fn an_frf_figure_is_drawn_in_memory() {
        let f: Vec<f64> = (0..100).map(|k| k as f64 * 0.1).collect();
        let a: Vec<f64> = f.iter().map(|x| 1.0 / (1.0 + (x - 5.0).powi(2))).collect();
        let fig = lines_figure(
            "frf",
            "t",
            "|H|",
            &[("acc", &f, &a), ("vis", &f, &a)],
            Lines::Frf,
        )
        .unwrap();
        assert_eq!(fig.name, "frf");
        assert!(fig.png.starts_with(b"\x89PNG"));
        assert!(fig.svg.contains("vis"));
    }
}

/// One mode shape to plot: its label, the real part of each component (normalised), and
/// whether it is a reference (drawn dashed, grey).
#[derive(Debug)]
pub struct ShapeCurve<'a> {
    /// Legend label.
    pub label: String,
    /// Component values, one per target, in the order of the positions.
    pub values: &'a [f64],
    /// A reference shape (dashed) rather than a measured one.
    pub reference: bool,
}

/// `shapes.png` / `shapes.svg`: each mode shape (real part, unit largest modulus) against the
/// targets' positions along the structure, with its points marked, and reference shapes dashed.
pub fn shape_figure(
    name: &str,
    title: &str,
    x_label: &str,
    positions: &[f64],
    curves: &[ShapeCurve],
) -> anyhow::Result<Figure> {
    register_font();
    figure!(name, |r| draw_shapes(r, title, x_label, positions, curves))
}

fn draw_shapes<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    x_label: &str,
    positions: &[f64],
    curves: &[ShapeCurve],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let (lo, hi) = finite_range(positions.iter().copied()).unwrap_or((0.0, 1.0));
    let pad = ((hi - lo) * 0.05).max(1.0);
    let mut chart = build_chart(
        &root,
        SINGLE,
        title,
        (lo - pad)..(hi + pad),
        -1.15..1.15,
        x_label,
        "shape (real part, unit largest modulus)",
    )?;
    chart.draw_series(LineSeries::new(
        [(lo - pad, 0.0), (hi + pad, 0.0)],
        BLACK.mix(0.4).stroke_width(1),
    ))?;
    let measured = curves.iter().filter(|c| !c.reference).count();
    let mut i = 0;
    for c in curves {
        let points: Vec<(f64, f64)> = positions
            .iter()
            .zip(c.values)
            .map(|(x, y)| (*x, *y))
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        if c.reference {
            let grey = RGBColor(120, 120, 120);
            chart
                .draw_series(DashedLineSeries::new(
                    points.clone(),
                    8,
                    6,
                    grey.stroke_width(2),
                ))?
                .label(c.label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], grey.stroke_width(2))
                });
            continue;
        }
        let colour = exposure_colour(i, measured.max(2));
        i += 1;
        draw_line(&mut chart, points.clone(), colour, 2, c.label.clone())?;
        chart.draw_series(points.iter().map(|&p| Circle::new(p, 5, colour.filled())))?;
    }
    // upper left: shapes normalised to the largest component usually peak at the far end
    chart
        .configure_series_labels()
        .label_font((FONT, SINGLE.labels))
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// The singular values of an output-only analysis: one curve per singular value in dB
/// (`10 log10 s`) over `freq_hz`, the first [`SVD_CURVES`] only (the others, of many targets,
/// are the noise's and often numerically zero; `svd.csv` holds them all), the picked lines
/// `(f_hz, s1, label)` marked and labelled, written as `NAME.png` and `NAME.svg`.
pub fn svd_figure(
    name: &str,
    title: &str,
    freq_hz: &[f64],
    s: &[Vec<f64>],
    picks: &[(f64, f64, String)],
) -> anyhow::Result<Figure> {
    let k = s.first().map_or(0, Vec::len).min(SVD_CURVES);
    let curves: Vec<(String, Vec<f64>)> = (0..k)
        .map(|i| (format!("s{}", i + 1), s.iter().map(|sv| sv[i]).collect()))
        .collect();
    db_figure(
        name,
        (title, "singular value (dB)"),
        freq_hz,
        &curves,
        picks,
    )
}

/// Power spectra in dB (`10 log10 p`) over `freq_hz` (the line at 0 Hz left out), one curve
/// per `(label, values)`, the lines `(f_hz, value, label)` marked, drawn as `NAME.png` and
/// `NAME.svg`; `(title, y_label)`.
pub fn db_figure(
    name: &str,
    (title, y_label): (&str, &str),
    freq_hz: &[f64],
    curves: &[(String, Vec<f64>)],
    picks: &[(f64, f64, String)],
) -> anyhow::Result<Figure> {
    register_font();
    let k = curves.len();
    let curves: Vec<Curve> = curves
        .iter()
        .enumerate()
        .map(|(i, (label, v))| {
            (
                label.clone(),
                exposure_colour(i, k),
                freq_hz
                    .iter()
                    .zip(v)
                    .skip(1)
                    .map(|(&f, &p)| (f, decibels(p)))
                    .collect(),
            )
        })
        .collect();
    let xr = finite_range(freq_hz.iter().copied()).unwrap_or((0.0, 1.0));
    figure!(name, |r| draw_svd(r, (title, y_label), xr, &curves, picks))
}

/// The singular values a figure draws.
pub const SVD_CURVES: usize = 4;

/// How far below the first curve's floor (its 5th percentile) a dB figure reaches: what lies
/// further down (a singular value of rounding noise at -3000 dB) would flatten every peak.
pub const DB_BELOW_FLOOR: f64 = 40.0;

/// The value range of a dB figure: from the lowest value, but no further than
/// [`DB_BELOW_FLOOR`] under the first curve's 5th percentile, to the highest.
pub fn db_range(curves: &[Vec<f64>]) -> Option<(f64, f64)> {
    let (lo, hi) = finite_range(curves.iter().flatten().copied())?;
    let mut first: Vec<f64> = curves
        .first()?
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    first.sort_by(f64::total_cmp);
    let floor = first
        .get(first.len() / 20)
        .map_or(lo, |p| p - DB_BELOW_FLOOR);
    Some((lo.max(floor).min(hi), hi))
}

fn decibels(v: f64) -> f64 {
    10.0 * v.max(f64::MIN_POSITIVE).log10()
}

fn draw_svd<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    (title, y_label): (&str, &str),
    xr: (f64, f64),
    curves: &[Curve],
    picks: &[(f64, f64, String)],
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let values: Vec<Vec<f64>> = curves
        .iter()
        .map(|c| c.2.iter().map(|p| p.1).collect())
        .collect();
    let (lo, hi) = db_range(&values).unwrap_or((-1.0, 1.0));
    let mut chart = build_chart(
        &root,
        SINGLE,
        title,
        xr.0..xr.1,
        lo - 3.0..hi + 6.0,
        "frequency (Hz)",
        y_label,
    )?;
    for (label, colour, points) in curves {
        // what lies below the range runs along the chart's floor
        draw_line(
            &mut chart,
            points.iter().map(|&(f, v)| (f, v.max(lo - 3.0))),
            *colour,
            1,
            label.clone(),
        )?;
    }
    for (f, v, label) in picks {
        chart.draw_series(std::iter::once(
            EmptyElement::at((*f, decibels(*v)))
                + Circle::new((0, 0), 5, TRANSDUCER.stroke_width(2))
                + Text::new(label.clone(), (6, -16), (FONT, 13)),
        ))?;
    }
    draw_legend(&mut chart, SINGLE)?;
    root.present()?;
    Ok(())
}

pub use crate::export::picker::PoleKind;

/// A stabilisation diagram: every pole `(f_hz, order, kind)`: a grey dot, a cross (stable),
/// a filled blue disk (in a mode's cluster) or an open orange square (in a rejected
/// cluster); the modes' frequencies as vertical lines, as `NAME.png` and `NAME.svg`.
pub fn stabilisation_figure(
    name: &str,
    title: &str,
    poles: &[(f64, usize, PoleKind)],
    modes_hz: &[f64],
    f_max_hz: f64,
) -> anyhow::Result<Figure> {
    register_font();
    figure!(name, |r| draw_stabilisation(
        r, title, poles, modes_hz, f_max_hz
    ))
}

fn draw_stabilisation<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    title: &str,
    poles: &[(f64, usize, PoleKind)],
    modes_hz: &[f64],
    f_max_hz: f64,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let top = poles.iter().map(|p| p.1).max().unwrap_or(2) as f64 + 2.0;
    root.fill(&WHITE)?;
    let mut chart = build_chart(
        &root,
        SINGLE,
        title,
        0.0..f_max_hz,
        0.0..top,
        "frequency (Hz)",
        "model order",
    )?;
    for &f in modes_hz {
        chart.draw_series(LineSeries::new(
            [(f, 0.0), (f, top)],
            RGBColor(200, 60, 40).stroke_width(1),
        ))?;
    }
    let of = |k: PoleKind| poles.iter().filter(move |p| p.2 == k);
    let grey = RGBColor(170, 170, 170);
    chart
        .draw_series(of(PoleKind::Pole).map(|p| Circle::new((p.0, p.1 as f64), 2, grey.filled())))?
        .label("pole")
        .legend(move |(x, y)| Circle::new((x + 10, y), 3, grey.filled()));
    chart
        .draw_series(
            of(PoleKind::Stable)
                .map(|p| Cross::new((p.0, p.1 as f64), 4, TRANSDUCER.stroke_width(1))),
        )?
        .label("stable (f, damping, MAC)")
        .legend(|(x, y)| Cross::new((x + 10, y), 4, TRANSDUCER.stroke_width(1)));
    let blue = RGBColor(30, 90, 200);
    chart
        .draw_series(of(PoleKind::Mode).map(|p| Circle::new((p.0, p.1 as f64), 4, blue.filled())))?
        .label("cluster: a mode")
        .legend(move |(x, y)| Circle::new((x + 10, y), 4, blue.filled()));
    let orange = RGBColor(230, 120, 20);
    chart
        .draw_series(of(PoleKind::Rejected).map(|p| {
            let (x, y) = (p.0, p.1 as f64);
            EmptyElement::at((x, y)) + Rectangle::new([(-4, -4), (4, 4)], orange.stroke_width(2))
        }))?
        .label("cluster: rejected (report)")
        .legend(move |(x, y)| {
            Rectangle::new([(x + 6, y - 4), (x + 14, y + 4)], orange.stroke_width(2))
        });
    draw_legend(&mut chart, SINGLE)?;
    root.present()?;
    Ok(())
}

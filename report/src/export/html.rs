//! `report.html`: one self-contained page per analysis (inline SVG, the frame as an inline PNG,
//! inline script; no network, no CDN: it opens from a USB stick on an offline lab PC). What it
//! shows, each part when the analysis has it: the first frame with each target's window,
//! number and lost-frame count; the figures the command drew (tracks, spectra or singular
//! values, stabilisation diagram, FRFs with their fit), inlined from their SVG; the table of
//! modes (with intervals); the MAC matrix; each mode shape animated as a wireframe ([`Wire`]:
//! a geometry's lines and nodes, the tracking's groups, or the points in number order; on the
//! frame when there is one, else in a plain 2-D view; a scale slider, play and pause); the
//! pole picker of `ema` and `modal` ([`super::picker`]); and the text of `report.txt`.
//!
//! Elements the browser tests find: `svg#frame` with one `g.marker` per target, `table#modes`,
//! `svg#mac` with `rect.mac-cell`s, one `svg.mode-shape` per mode (its `line.wire`s and
//! `circle.shape-dot`s move; `p#wire` says where the lines come from),
//! `button#play`, `input#scale`, `pre#report-text`, `div#banner` (no mode found, and why),
//! `section#provenance` (the header: [`crate::provenance::html`]).

use num_complex::Complex64;
use std::fmt::Write as _;

/// A grey frame for the page (made by the readers: [`vibcam_readers::frames::GreyFrame::to_image`]).
pub use vibcam_readers::frames::FrameImage;

/// A table's header row from its column names.
pub fn header(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

/// An interval `(lo, hi)` as a table cell, `lo .. hi` to `decimals` places (empty without one).
pub fn range_cell(range: Option<(f64, f64)>, decimals: usize) -> String {
    range.map_or(String::new(), |(lo, hi)| {
        format!("{lo:.decimals$} .. {hi:.decimals$}")
    })
}

/// One mode as a row of the page's table of modes.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeCells<'a> {
    /// Mode number.
    pub mode: usize,
    /// The method that found it, when the table has a method column.
    pub method: Option<&'a str>,
    /// Natural frequency, Hz, and its 95 % interval.
    pub f_hz: (f64, Option<(f64, f64)>),
    /// Damping ratio (when the method gives one) and its 95 % interval.
    pub damping: (Option<f64>, Option<(f64, f64)>),
}

/// The page's table of modes (header, rows): mode, method (`with_method`), frequency to 4
/// places, damping to 5, each with its 95 % interval.
pub fn modes_table(modes: &[ModeCells], with_method: bool) -> (Vec<String>, Vec<Vec<String>>) {
    let rows = modes
        .iter()
        .map(|m| {
            let mut row = vec![m.mode.to_string()];
            if with_method {
                row.push(m.method.unwrap_or_default().to_string());
            }
            row.extend([
                format!("{:.4}", m.f_hz.0),
                range_cell(m.f_hz.1, 4),
                m.damping.0.map_or(String::new(), |z| format!("{z:.5}")),
                range_cell(m.damping.1, 5),
            ]);
            row
        })
        .collect();
    let mut names = vec!["mode"];
    if with_method {
        names.push("method");
    }
    names.extend(["f (Hz)", "95 % interval", "damping", "95 % interval"]);
    (header(&names), rows)
}

/// A target on the frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// Target number.
    pub target: usize,
    /// Position in the first frame, px.
    pub xy: (f64, f64),
    /// Its window (w, h), px, when it has one.
    pub window: Option<(f64, f64)>,
    /// Frames it was lost in.
    pub lost: usize,
}

/// A static reference on the frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceMarker {
    /// Reference number (`rK`).
    pub number: usize,
    /// Its anchor, px.
    pub xy: (f64, f64),
    /// Left out of the camera's motion (lost or moving).
    pub left_out: bool,
}

/// A dot at `xy` (px, pixel centres at integers) with its `tip` (the tooltip) and its label
/// at `at` (text anchor and baseline; none when the label found no free place), sized by
/// `stroke`, in `colours` (dot, label).
fn dot(
    s: &mut String,
    xy: (f64, f64),
    stroke: f64,
    colours: (&str, &str),
    (label, tip, at): (&str, &str, Option<(f64, f64)>),
) {
    let xy = (xy.0 + 0.5, xy.1 + 0.5);
    let _ = write!(
        s,
        "<title>{}</title><circle cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"{}\"/>",
        escape(tip),
        xy.0,
        xy.1,
        2.0 * stroke,
        colours.0,
    );
    if let Some((x, y)) = at {
        let _ = write!(
            s,
            "<text class=\"label\" x=\"{x}\" y=\"{y}\" fill=\"{}\" font-size=\"{}\" stroke=\"#000\" stroke-width=\"{}\">{}</text>",
            colours.1,
            12.0 * stroke,
            0.3 * stroke,
            escape(label)
        );
    }
}

/// A mode shape to animate.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeAnimation {
    /// Its label (`mode 1, 7.105 Hz (ssi)`).
    pub label: String,
    /// The shape per target (normalised), in the targets' order of [`Report::markers`] or of
    /// the page's own line when there are no markers.
    pub shape: Vec<Complex64>,
}

pub use super::wire::{number_order, Unit, Wire};

/// What a page shows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Report {
    /// The page's title (`modal: ...`).
    pub title: String,
    /// The first frame, when there is one.
    pub frame: Option<FrameImage>,
    /// The targets (positions; on the frame when there is one).
    pub markers: Vec<Marker>,
    /// Static references (`--reference`), drawn as `g.reference` labelled `rK`.
    pub references: Vec<ReferenceMarker>,
    /// The motion's direction in the image, a unit vector (y up: `(0, -1)`).
    pub direction: (f64, f64),
    /// Figures: caption and SVG text.
    pub figures: Vec<(String, String)>,
    /// The table of modes: header and rows.
    pub modes: Option<(Vec<String>, Vec<Vec<String>>)>,
    /// The MAC matrix of the shapes: labels and values.
    pub mac: Option<MacMatrix>,
    /// Mode shapes to animate.
    pub shapes: Vec<ShapeAnimation>,
    /// The lines the shapes are drawn with.
    pub wire: Wire,
    /// The text report.
    pub text: String,
    /// The frame scrubber (`track`, `analyze` with frames).
    pub scrub: Option<super::scrub::Scrubber>,
    /// The pole picker (`ema`, `modal`); it takes the place of the figure [`STABILISATION`].
    pub picker: Option<super::picker::Picker>,
    /// A banner under the title (`div#banner`): its heading and the reasons listed (an
    /// identification that found no mode, and why).
    pub banner: Option<(String, Vec<String>)>,
    /// The header under the title: date, version, command, inputs, settings, machine.
    pub provenance: Option<crate::provenance::Provenance>,
    /// Each mode's magnified video.
    pub videos: Vec<Video>,
}

/// A video on the page (`video.magnified`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Video {
    /// Its caption.
    pub label: String,
    /// Its source: a `data:` URI, or a file beside the page.
    pub src: String,
    /// The mode's displacement field over the frame (an SVG; empty: none).
    pub figure: String,
}

impl Report {
    /// The page with `videos`.
    pub fn with_videos(mut self, videos: Vec<Video>) -> Report {
        self.videos = videos;
        self
    }
}

/// The caption (figure name) of the static stabilisation diagram a page's picker replaces.
pub const STABILISATION: &str = "stabilisation";

/// `s` with `&`, `<`, `>` and `"` escaped for HTML text and attributes.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            c => o.push(c),
        }
    }
    o
}

/// `s` as a JSON string literal safe inside an HTML `<script>` block: `<`, `>` and `&` as
/// `\u` escapes, so that no `</script>`, `<!--` or `<script` in it changes how the page's
/// parser reads the block.
pub fn json_string_in_script(s: &str) -> String {
    serde_json::Value::String(s.to_string())
        .to_string()
        .replace('<', "\\u003c")
        .replace('>', "\\u003e")
        .replace('&', "\\u0026")
}

/// Standard base64 (RFC 4648) of `bytes`.
pub fn base64(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut o = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        o.push(T[(n >> 18) as usize & 63] as char);
        o.push(T[(n >> 12) as usize & 63] as char);
        o.push(if c.len() > 1 {
            T[(n >> 6) as usize & 63] as char
        } else {
            '='
        });
        o.push(if c.len() > 2 {
            T[n as usize & 63] as char
        } else {
            '='
        });
    }
    o
}

/// An SVG file's text ready to inline: anything before `<svg` (an XML declaration) dropped,
/// the figure scaled to the page's width.
pub fn inline_svg(svg: &str) -> String {
    let start = svg.find("<svg").unwrap_or(0);
    svg[start..].replacen("<svg ", "<svg class=\"figure\" ", 1)
}

/// A finite number for the page's script (`null` otherwise).
fn js(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "null".into()
    }
}

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;max-width:1200px}\
svg.figure{max-width:100%;height:auto;border:1px solid #ddd}\
table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}\
pre{background:#f6f6f6;padding:1em;overflow-x:auto}\
.mode{display:inline-block;margin:0 1em 1em 0;vertical-align:top}\
.mode svg{border:1px solid #ddd;background:#fff}\
#frame{max-width:100%;height:auto}\
#banner{border:2px solid #c83c28;background:#fff4f2;padding:.5em 1em;margin:1em 0}\
#provenance{font-size:90%;margin:0 0 1em 0}#provenance th{text-align:left;vertical-align:top}\
#provenance td{text-align:left;word-break:break-all}\
#settings{columns:3 16em;font-size:85%;margin:.3em 0;padding-left:1.2em}\
#settings .default{color:#888}.settings-head{margin:.5em 0 0 0;font-size:90%}\
@media print{@page{size:A4;margin:14mm}\
body{margin:0;max-width:none;font-size:10pt}\
h2{break-before:page}h2:first-of-type{break-before:auto}\
figure,svg,table,.mode,#banner,#provenance{break-inside:avoid}\
button,input,#save-poles,#clear-poles,#poles-csv,#pole-hover{display:none}\
pre{white-space:pre-wrap;font-size:8pt}svg.figure,#frame{max-width:100%}}";

/// The page's script: animates every `svg.mode-shape` from the data in `#shape-data`; printed,
/// each shape stands still at its extreme (phase 0: the real part at full scale).
const SCRIPT: &str = r#"(function(){
var data=JSON.parse(document.getElementById('shape-data').textContent);
var playing=true,scale=1,t0=performance.now(),phase=0;
var play=document.getElementById('play'),slider=document.getElementById('scale');
if(play){play.addEventListener('click',function(){playing=!playing;play.textContent=playing?'pause':'play';if(playing){t0=performance.now()-phase/(2*Math.PI)*1200;}});}
if(slider){slider.addEventListener('input',function(){scale=parseFloat(slider.value);draw();});}
function draw(){
 var svgs=document.querySelectorAll('svg.mode-shape');
 for(var m=0;m<svgs.length;m++){
  var d=data.modes[m],base=data.base,amp=data.amplitude*scale,pts=[];
  for(var i=0;i<base.length;i++){
   var v=d.re[i]*Math.cos(phase)-d.im[i]*Math.sin(phase);
   pts.push([(base[i][0]+data.dir[0]*amp*v).toFixed(2),(base[i][1]+data.dir[1]*amp*v).toFixed(2)]);
  }
  var dots=svgs[m].querySelectorAll('circle.shape-dot');
  for(var j=0;j<dots.length&&j<pts.length;j++){dots[j].setAttribute('cx',pts[j][0]);dots[j].setAttribute('cy',pts[j][1]);}
  var wires=svgs[m].querySelectorAll('line.wire');
  for(var k=0;k<wires.length;k++){var a=pts[+wires[k].getAttribute('data-a')],b=pts[+wires[k].getAttribute('data-b')];if(a&&b){wires[k].setAttribute('x1',a[0]);wires[k].setAttribute('y1',a[1]);wires[k].setAttribute('x2',b[0]);wires[k].setAttribute('y2',b[1]);}}
  svgs[m].setAttribute('data-phase',phase.toFixed(4));
 }
}
function tick(now){if(playing){phase=((now-t0)/1200)*2*Math.PI%(2*Math.PI);draw();}requestAnimationFrame(tick);}
function still(){playing=false;phase=0;draw();if(play){play.textContent='play';}}
window.addEventListener('beforeprint',still);
if(window.matchMedia){var pm=window.matchMedia('print');if(pm.matches){still();}if(pm.addEventListener){pm.addEventListener('change',function(e){if(e.matches){still();}});}}
draw();requestAnimationFrame(tick);
})();"#;

/// The page: the first frame with the targets, the modes, the animated shapes, the MAC, the
/// figures and the report's text, each section where the report has it.
pub fn report_html(r: &Report) -> String {
    let mut s = String::from("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">");
    let _ = write!(
        s,
        "<meta name=\"viewport\" content=\"width=device-width\"><title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
        escape(&r.title),
        escape(&r.title)
    );
    if let Some(p) = &r.provenance {
        s.push_str(&crate::provenance::html(p, escape));
    }
    if let Some((head, reasons)) = &r.banner {
        let _ = write!(
            s,
            "<div id=\"banner\"><strong>{}</strong><ul>",
            escape(head)
        );
        for why in reasons {
            let _ = write!(s, "<li>{}</li>", escape(why));
        }
        s.push_str("</ul></div>\n");
    }
    let view = View::of(r);
    let frame_image = r.frame.as_ref().map(|f| {
        format!(
            "<image href=\"data:image/png;base64,{}\" x=\"0\" y=\"0\" width=\"{}\" height=\"{}\"/>",
            base64(&f.png),
            f.width,
            f.height
        )
    });
    if let Some(img) = &frame_image {
        frame_section(&mut s, r, &view, img);
    }
    if let Some(sc) = &r.scrub {
        super::scrub::section(&mut s, sc, base64);
    }
    if let Some((head, rows)) = &r.modes {
        modes_section(&mut s, head, rows);
    }
    // one point has no shape to see (every mode moves one dot) and its MAC is 1 for any two
    // modes; one mode has no other to compare with: such sections say nothing, so are left out
    let one_point = r.shapes.first().is_some_and(|m| m.shape.len() < 2);
    if one_point {
        s.push_str(
            "<p id=\"one-point\">One point measured: its modes have no shape to animate and \
             no MAC to compare them by.</p>\n",
        );
    } else if !r.shapes.is_empty() {
        shapes_section(&mut s, r, &view, frame_image.as_deref());
    }
    match &r.mac {
        Some((labels, m)) if labels.len() >= 2 && !one_point => mac_section(&mut s, labels, m),
        _ => {}
    }
    videos_section(&mut s, &r.videos);
    // the picker draws the stabilisation diagram: its static figure stays a file only
    let shown = r
        .figures
        .iter()
        .filter(|(caption, _)| r.picker.is_none() || caption != STABILISATION);
    for (caption, svg) in shown {
        let _ = writeln!(
            s,
            "<figure><figcaption>{}</figcaption>{}</figure>",
            escape(caption),
            inline_svg(svg)
        );
    }
    if let Some(p) = &r.picker {
        super::picker::section(&mut s, p);
    }
    let _ = write!(
        s,
        "<h2>Report</h2>\n<pre id=\"report-text\">{}</pre>\n</body></html>\n",
        escape(&r.text)
    );
    s
}

/// The magnified videos, one figure each (none: nothing).
fn videos_section(s: &mut String, videos: &[Video]) {
    if videos.is_empty() {
        return;
    }
    s.push_str(
        "<h2>Each mode magnified</h2>\n<p>The first frame moving in one mode alone, one period \
         looped, magnified as the caption says (the report below tells how); under it the \
         mode's displacement field over the frame: red along the motion's direction, blue \
         against it, an arrow at some of the points.</p>\n",
    );
    for (i, v) in videos.iter().enumerate() {
        let _ = writeln!(
            s,
            "<figure><figcaption>{}</figcaption><video class=\"magnified\" id=\"magnified-{}\" \
             src=\"{}\" controls loop autoplay muted playsinline></video>{}</figure>",
            escape(&v.label),
            i + 1,
            escape(&v.src),
            v.figure
        );
    }
}

/// Where the targets are drawn: the frame's size (or a line of the targets' own) and their
/// points, and the view box of a shape (the frame, or the targets' bounding box with a margin).
#[derive(Debug)]
struct View {
    w: f64,
    h: f64,
    base: Vec<(f64, f64)>,
    view_box: (f64, f64, f64, f64),
}

impl View {
    fn of(r: &Report) -> View {
        // where the targets are: on the frame, or on a line of their own
        let (w, h, base): (f64, f64, Vec<(f64, f64)>) = match &r.frame {
            Some(f) => (
                f64::from(f.width),
                f64::from(f.height),
                // px have their origin at the top-left pixel's centre, the image at its corner
                r.markers
                    .iter()
                    .map(|m| (m.xy.0 + 0.5, m.xy.1 + 0.5))
                    .collect(),
            ),
            None => {
                let n = r
                    .markers
                    .len()
                    .max(r.shapes.first().map_or(0, |m| m.shape.len()));
                let w = 80.0 * (n as f64 + 1.0);
                let pts =
                    match r.markers.iter().all(|m| m.xy.0.is_finite()) && !r.markers.is_empty() {
                        true => r.markers.iter().map(|m| m.xy).collect(),
                        false => (0..n).map(|i| (80.0 * (i as f64 + 1.0), 150.0)).collect(),
                    };
                (w, 300.0, pts)
            }
        };
        let (bx0, by0, bx1, by1) = bounds(&base);
        // the view of a shape: the frame, or the targets' bounding box with a margin
        let (vx, vy, vw, vh) = if r.frame.is_some() || base.is_empty() {
            (0.0, 0.0, w, h)
        } else {
            let m = 0.25 * ((bx1 - bx0).max(by1 - by0)).max(100.0);
            (bx0 - m, by0 - m, bx1 - bx0 + 2.0 * m, by1 - by0 + 2.0 * m)
        };
        View {
            w,
            h,
            base,
            view_box: (vx, vy, vw, vh),
        }
    }
}

/// The first frame, each target's window, number and lost frames, the references.
fn frame_section(s: &mut String, r: &Report, view: &View, img: &str) {
    let (w, h) = (view.w, view.h);
    let shown = if w < 700.0 { 700.0 } else { w.min(1100.0) };
    let _ = write!(
        s,
        "<h2>The first frame and the targets</h2>\n<svg id=\"frame\" viewBox=\"0 0 {w} {h}\" width=\"{shown}\" xmlns=\"http://www.w3.org/2000/svg\">{img}",
    );
    // 1.2 screen pixels in the frame's pixels: lines, dots and labels keep one size on the
    // screen whatever the frame's (12 px labels over a 165 px frame would cover it)
    let stroke = 1.2 * w / shown;
    // the targets' numbers, then the references', each where it covers no other
    let texts: Vec<(String, (f64, f64))> = r
        .markers
        .iter()
        .map(|m| (m.target.to_string(), m.xy))
        .chain(
            r.references
                .iter()
                .map(|m| (format!("r{}", m.number), m.xy)),
        )
        .collect();
    let anchors: Vec<((f64, f64), usize)> = texts
        .iter()
        .map(|(t, xy)| ((xy.0 + 0.5, xy.1 + 0.5), t.chars().count()))
        .collect();
    let at = super::labels::place(&anchors, 3.0 * stroke, 12.0 * stroke, (w, h));
    for (i, m) in r.markers.iter().enumerate() {
        let xy = (m.xy.0 + 0.5, m.xy.1 + 0.5);
        let _ = write!(
            s,
            "<g class=\"marker\" data-target=\"{}\" data-lost=\"{}\">",
            m.target, m.lost
        );
        if let Some((ww, wh)) = m.window {
            let _ = write!(
                s,
                "<rect x=\"{}\" y=\"{}\" width=\"{ww}\" height=\"{wh}\" fill=\"none\" stroke=\"#00c8ff\" stroke-width=\"{stroke}\"/>",
                xy.0 - ww / 2.0,
                xy.1 - wh / 2.0
            );
        }
        let tip = format!("target {}: {} frames lost", m.target, m.lost);
        // a target with lost frames is drawn orange; the counts are listed under the frame
        let colours = match m.lost {
            0 => ("#ff3030", "#ffe000"),
            _ => ("#ff9900", "#ff9900"),
        };
        dot(s, m.xy, stroke, colours, (&texts[i].0, &tip, at[i]));
        s.push_str("</g>");
    }
    let n = r.markers.len();
    for (k, m) in r.references.iter().enumerate() {
        let _ = write!(s, "<g class=\"reference\" data-reference=\"{}\">", m.number);
        let tip = format!(
            "reference r{}{}",
            m.number,
            if m.left_out { ", left out" } else { "" }
        );
        let colours = ("#30ff60", "#30ff60");
        dot(s, m.xy, stroke, colours, (&texts[n + k].0, &tip, at[n + k]));
        s.push_str("</g>");
    }
    s.push_str("</svg>\n");
    lost_summary(s, r);
}

/// Under the frame: which targets lost frames and how many (all of them in one phrase when
/// they lost the same count), the references left out.
fn lost_summary(s: &mut String, r: &Report) {
    let lost: Vec<&Marker> = r.markers.iter().filter(|m| m.lost > 0).collect();
    let left_out: Vec<String> = r
        .references
        .iter()
        .filter(|m| m.left_out)
        .map(|m| format!("r{}", m.number))
        .collect();
    if lost.is_empty() && left_out.is_empty() {
        return;
    }
    s.push_str("<p id=\"lost\">");
    let same = lost.windows(2).all(|p| p[0].lost == p[1].lost);
    match (lost.len(), same) {
        (0, _) => {}
        (k, true) if k == r.markers.len() && k > 1 => {
            let _ = write!(s, "Every target lost {} frames.", lost[0].lost);
        }
        _ => {
            let each: Vec<String> = lost
                .iter()
                .map(|m| format!("{} ({})", m.target, m.lost))
                .collect();
            let _ = write!(s, "Frames lost, by target: {}.", each.join(", "));
        }
    }
    if !left_out.is_empty() {
        let _ = write!(
            s,
            " References left out of the camera's motion: {}.",
            left_out.join(", ")
        );
    }
    s.push_str("</p>\n");
}

/// The modes' table.
fn modes_section(s: &mut String, head: &[String], rows: &[Vec<String>]) {
    s.push_str("<h2>Modes</h2>\n<table id=\"modes\"><tr>");
    for h in head {
        let _ = write!(s, "<th>{}</th>", escape(h));
    }
    s.push_str("</tr>\n");
    for row in rows {
        s.push_str("<tr>");
        for c in row {
            let _ = write!(s, "<td>{}</td>", escape(c));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
}

/// An SVG view box: x, y, width, height.
type ViewBox = (f64, f64, f64, f64);

/// Where a page's shapes are drawn: each point's place, the view box, whether over the frame.
/// A geometry's nodes in millimetres give a plain view (y up); in pixels, places on the frame;
/// without nodes, the targets where they were tracked ([`View`]).
fn shape_places(r: &Report, view: &View) -> (Vec<(f64, f64)>, ViewBox, bool) {
    let n = r.shapes.first().map_or(0, |m| m.shape.len());
    let (base, plain) = match &r.wire.nodes {
        Some((xy, Unit::Mm)) if xy.len() == n => (xy.iter().map(|p| (p.0, -p.1)).collect(), true),
        Some((xy, Unit::Px)) if xy.len() == n => (
            xy.iter().map(|p| (p.0 + 0.5, p.1 + 0.5)).collect(),
            r.frame.is_none(),
        ),
        _ => return (view.base.clone(), view.view_box, r.frame.is_some()),
    };
    if !plain {
        return (base, (0.0, 0.0, view.w, view.h), true);
    }
    // a margin of a fifth of the structure's size around it, and a view at least half as
    // tall as wide (a beam along x has room to move)
    let (x0, y0, x1, y1) = bounds(&base);
    let m = 0.2 * (x1 - x0).max(y1 - y0).max(1e-9);
    let (w, h) = (x1 - x0 + 2.0 * m, y1 - y0 + 2.0 * m);
    let (w, h) = (w.max(0.5 * h), h.max(0.5 * w));
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    (base, (cx - 0.5 * w, cy - 0.5 * h, w, h), false)
}

/// The bounding box of `points`: (x min, y min, x max, y max).
fn bounds(points: &[(f64, f64)]) -> (f64, f64, f64, f64) {
    points.iter().fold(
        (
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), p| (a.min(p.0), b.min(p.1), c.max(p.0), d.max(p.1)),
    )
}

/// Each mode's shape animated as a wireframe over the frame (or in a plain view), and the data
/// its script reads.
fn shapes_section(s: &mut String, r: &Report, view: &View, frame_image: Option<&str>) {
    let (base, (vx, vy, vw, vh), on_frame) = shape_places(r, view);
    let base = &base;
    let (lines, from) = if r.wire.from.is_empty() {
        (
            number_order(base),
            "Lines join the points in number order, broken where a step is longer than 1.5 \
             times the median step (no geometry was given)."
                .to_string(),
        )
    } else {
        (r.wire.lines.clone(), r.wire.from.clone())
    };
    let lines: Vec<(usize, usize)> = lines
        .into_iter()
        .filter(|&(a, b)| a < base.len() && b < base.len())
        .collect();
    let _ = write!(
        s,
        "<h2>Mode shapes</h2>\n<p id=\"wire\">{}</p>\n<p><button id=\"play\">pause</button> scale \
         <input id=\"scale\" type=\"range\" min=\"0\" max=\"5\" step=\"0.05\" value=\"1\"></p>\n",
        escape(&from)
    );
    let stroke = (vw.max(vh) / 300.0).max(1.0);
    for (i, m) in r.shapes.iter().enumerate() {
        let _ = write!(
            s,
            "<div class=\"mode\"><div>{}</div><svg class=\"mode-shape\" data-mode=\"{}\" viewBox=\"{vx} {vy} {vw} {vh}\" width=\"{}\" xmlns=\"http://www.w3.org/2000/svg\">",
            escape(&m.label),
            i + 1,
            if r.frame.is_some() { 540.0 } else { 360.0 }
        );
        if let (Some(img), true) = (frame_image, on_frame) {
            let _ = write!(s, "<g opacity=\"0.6\">{img}</g>");
        }
        for (class, colour, width, dash) in [
            ("wire-rest", "#bbb", stroke, " stroke-dasharray=\"4\""),
            ("wire", "#e0301e", 1.5 * stroke, ""),
        ] {
            for &(a, b) in &lines {
                let _ = write!(
                    s,
                    "<line class=\"{class}\" data-a=\"{a}\" data-b=\"{b}\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{colour}\" stroke-width=\"{width}\"{dash}/>",
                    base[a].0, base[a].1, base[b].0, base[b].1
                );
            }
        }
        for p in base {
            let _ = write!(
                s,
                "<circle class=\"shape-dot\" cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"#1e5ae0\"/>",
                p.0,
                p.1,
                2.0 * stroke
            );
        }
        s.push_str("</svg></div>\n");
    }
    // the largest component moves a tenth of the view (times the slider)
    shape_data(s, r, base, 0.1 * vw.min(vh));
}

/// The data the shapes' script reads (the points' places, the motion's direction, the
/// amplitude, each mode's complex shape) and the script.
fn shape_data(s: &mut String, r: &Report, base: &[(f64, f64)], amplitude: f64) {
    let modes: Vec<String> = r
        .shapes
        .iter()
        .map(|m| {
            let re: Vec<String> = m.shape.iter().map(|c| js(c.re)).collect();
            let im: Vec<String> = m.shape.iter().map(|c| js(c.im)).collect();
            format!("{{\"re\":[{}],\"im\":[{}]}}", re.join(","), im.join(","))
        })
        .collect();
    let basej: Vec<String> = base
        .iter()
        .map(|p| format!("[{},{}]", js(p.0), js(p.1)))
        .collect();
    let _ = write!(
        s,
        "<script type=\"application/json\" id=\"shape-data\">{{\"base\":[{}],\"dir\":[{},{}],\"amplitude\":{},\"modes\":[{}]}}</script>\n<script>{SCRIPT}</script>\n",
        basej.join(","),
        js(r.direction.0),
        js(r.direction.1),
        js(amplitude),
        modes.join(",")
    );
}

/// The MAC matrix of the shapes as a coloured grid.
fn mac_section(s: &mut String, labels: &[String], m: &[Vec<f64>]) {
    let n = labels.len();
    let cell = 40.0;
    let pad = 110.0;
    let size = pad + cell * n as f64;
    // the column labels lean right at 60 degrees: the last one reaches past the grid by half
    // its length (11 px text, 0.6 em a character)
    let longest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0) as f64;
    let wide = size + (0.5 * 0.6 * 11.0 * longest - 0.4 * cell).max(0.0);
    let _ = write!(
        s,
        "<h2>MAC of the mode shapes</h2>\n<svg id=\"mac\" viewBox=\"0 0 {wide} {size}\" width=\"{}\" xmlns=\"http://www.w3.org/2000/svg\" font-size=\"11\">",
        wide.min(700.0 * wide / size)
    );
    for (i, row) in m.iter().enumerate() {
        let _ = write!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
            pad - 4.0,
            pad + cell * (i as f64 + 0.6),
            escape(&labels[i])
        );
        for (j, v) in row.iter().enumerate() {
            let g = (255.0 * (1.0 - v.clamp(0.0, 1.0))) as u8;
            let _ = write!(
                s,
                "<rect class=\"mac-cell\" x=\"{}\" y=\"{}\" width=\"{cell}\" height=\"{cell}\" fill=\"rgb({g},{g},255)\"><title>{:.3}</title></rect><text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"{}\">{:.2}</text>",
                pad + cell * j as f64,
                pad + cell * i as f64,
                v,
                pad + cell * (j as f64 + 0.5),
                pad + cell * (i as f64 + 0.6),
                if *v > 0.5 { "#fff" } else { "#000" },
                v
            );
        }
    }
    for (j, l) in labels.iter().enumerate() {
        let x = pad + cell * (j as f64 + 0.6);
        let _ = write!(
            s,
            "<text x=\"{x}\" y=\"{}\" transform=\"rotate(-60 {x} {})\">{}</text>",
            pad - 4.0,
            pad - 4.0,
            escape(l)
        );
    }
    s.push_str("</svg>\n");
}

/// The modes' labels and the MAC matrix of their shapes, row by row.
pub type MacMatrix = (Vec<String>, Vec<Vec<f64>>);

/// The page's MAC matrix and animations of `modes` (each its label and shape, in the order of
/// the table), each animation labelled `prefix` and the mode's label; no MAC without modes.
pub fn mac_and_animations(
    modes: &[(String, &[Complex64])],
    prefix: &str,
) -> (Option<MacMatrix>, Vec<ShapeAnimation>) {
    let labels: Vec<String> = modes.iter().map(|(l, _)| l.clone()).collect();
    let shapes: Vec<&[Complex64]> = modes.iter().map(|(_, s)| *s).collect();
    let animations = modes
        .iter()
        .map(|(l, s)| ShapeAnimation {
            label: format!("{prefix}{l}"),
            shape: s.to_vec(),
        })
        .collect();
    let mac = (!labels.is_empty()).then(|| (labels, mac_matrix(&shapes)));
    (mac, animations)
}

/// The MAC matrix of `shapes` (each a complex vector of one length).
pub fn mac_matrix(shapes: &[&[Complex64]]) -> Vec<Vec<f64>> {
    shapes
        .iter()
        .map(|a| {
            shapes
                .iter()
                .map(|b| {
                    let ab: Complex64 = a.iter().zip(b.iter()).map(|(x, y)| x.conj() * y).sum();
                    let aa: f64 = a.iter().map(|x| x.norm_sqr()).sum();
                    let bb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
                    if aa > 0.0 && bb > 0.0 {
                        ab.norm_sqr() / (aa * bb)
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_of_known_strings() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }

    #[test]
    fn a_page_holds_its_parts_and_no_address() {
        let r = Report {
            title: "modal: <test>".into(),
            markers: (1..=3)
                .map(|t| Marker {
                    target: t,
                    xy: (10.0 * t as f64, 20.0),
                    window: Some((9.0, 9.0)),
                    lost: t - 1,
                })
                .collect(),
            frame: Some(FrameImage {
                width: 40,
                height: 30,
                png: vec![1, 2, 3],
            }),
            direction: (0.0, -1.0),
            shapes: vec![ShapeAnimation {
                label: "mode 1".into(),
                shape: vec![Complex64::new(1.0, 0.0); 3],
            }],
            mac: Some((vec!["1".into()], vec![vec![1.0]])),
            modes: Some((vec!["f_hz".into()], vec![vec!["7.1".into()]])),
            text: "a < b".into(),
            ..Report::default()
        };
        let html = report_html(&r);
        // one mode: no MAC to draw
        assert!(!html.contains("id=\"mac\""));
        let two = Report {
            mac: Some((
                vec!["1".into(), "2".into()],
                vec![vec![1.0, 0.1], vec![0.1, 1.0]],
            )),
            ..r.clone()
        };
        assert!(report_html(&two).contains("id=\"mac\""));
        // one point: neither animation nor MAC, and a word why
        let single = Report {
            shapes: vec![ShapeAnimation {
                label: "mode 1".into(),
                shape: vec![Complex64::new(1.0, 0.0)],
            }],
            ..two.clone()
        };
        let one = report_html(&single);
        assert!(one.contains("id=\"one-point\""));
        assert!(!one.contains("class=\"mode-shape\"") && !one.contains("id=\"mac\""));
        assert_eq!(html.matches("class=\"marker\"").count(), 3);
        assert_eq!(html.matches("class=\"mode-shape\"").count(), 1);
        assert!(html.contains("Frames lost, by target: 2 (1), 3 (2)."));
        assert!(html.contains("<title>target 3: 2 frames lost</title>"));
        assert!(html.contains("modal: &lt;test&gt;"));
        assert!(html.contains("a &lt; b"));
        // no address but the SVG namespace (an identifier, never fetched)
        let without_ns = html.replace("http://www.w3.org/2000/svg", "");
        assert!(!without_ns.contains("http://") && !without_ns.contains("https://"));
    }
}

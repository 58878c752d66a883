//! The pole picker of `report.html` (`ema`, `modal`): the stabilisation diagram drawn as the
//! page's own SVG, each pole a circle one clicks to pick or unpick, its frequency, damping, order and MPC
//! shown on hover; the picked poles listed in a table and saved as `poles.csv` (`f_hz`,
//! `damping`, `order`, `mpc`), the file a run with `$poles` takes to give exactly those modes.
//! Frequencies and damping ratios are the structure's (an exponential window's damping
//! removed) and are written at full precision, so the run gets the very poles clicked.
//!
//! Elements the browser tests find: `svg#pole-picker` with one `circle.pole` per pole (its
//! `data-i` the pole's index in `#pole-data`, class `picked` once clicked), `#pole-hover` (the
//! pole under the pointer), `table#picked` (a row per picked pole), `a#save-poles` (downloads
//! `poles.csv`; its `data-count` the poles in it), `textarea#poles-csv` (the same text) and
//! `button#clear-poles`.

use std::fmt::Write as _;

/// What a pole of a stabilisation diagram is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoleKind {
    /// Not stable from the order below.
    Pole,
    /// Stable, in no cluster of two or more.
    Stable,
    /// In a cluster reported as a mode.
    Mode,
    /// In a cluster rejected (its reason in the report).
    Rejected,
}

/// One pole of the diagram.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PickPole {
    /// Where the diagram draws it: the frequency the fit found, Hz.
    pub at_hz: f64,
    /// Its model order.
    pub order: usize,
    /// Stable, in a mode's cluster, ...
    pub kind: PoleKind,
    /// The structure's undamped natural frequency, Hz (what `poles.csv` holds).
    pub f_hz: f64,
    /// The structure's damping ratio (what `poles.csv` holds).
    pub damping: f64,
    /// Its shape's modal phase collinearity (NaN: none).
    pub mpc: f64,
}

/// What the picker shows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Picker {
    /// Every pole of the diagram.
    pub poles: Vec<PickPole>,
    /// The diagram's frequency axis, Hz.
    pub f_range: (f64, f64),
    /// The modes reported, Hz (vertical lines).
    pub modes_hz: Vec<f64>,
    /// How the saved file is used, one sentence of HTML-safe text (settings as `$key`).
    pub rerun: String,
}

/// The diagram's size and plot area, px: width, height, left, right, top, bottom.
const W: f64 = 900.0;
const H: f64 = 430.0;
const AREA: (f64, f64, f64, f64) = (70.0, 885.0, 15.0, 385.0);

/// About `n` round steps over `lo..hi`: the ticks (1, 2 or 5 times a power of ten apart).
fn ticks(lo: f64, hi: f64, n: f64) -> Vec<f64> {
    let span = hi - lo;
    if !(span.is_finite() && span > 0.0) {
        return vec![lo];
    }
    let raw = span / n;
    let p = 10f64.powf(raw.log10().floor());
    // the round step nearest to the raw one (by ratio)
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .min_by(|a, b| (a / raw).ln().abs().total_cmp(&(b / raw).ln().abs()))
        .unwrap_or(p);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A tick's label: no more decimals than its step needs.
fn tick_label(v: f64, step: f64) -> String {
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    format!("{v:.decimals$}")
}

/// The class of a pole's circle.
fn class(kind: PoleKind) -> &'static str {
    match kind {
        PoleKind::Pole => "pole",
        PoleKind::Stable => "pole stable",
        PoleKind::Mode => "pole mode",
        PoleKind::Rejected => "pole rejected",
    }
}

/// A number for the page's data: shortest round-trip, `null` when not finite.
fn json_num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "null".into()
    }
}

/// The section: heading, how to use it, the diagram, the picked poles and the saved file.
pub fn section(s: &mut String, p: &Picker) {
    let (lo, hi) = p.f_range;
    let top = p.poles.iter().map(|q| q.order).max().unwrap_or(2) as f64 + 2.0;
    let (x0, x1, y0, y1) = AREA;
    let x = |f: f64| x0 + (f - lo) / (hi - lo) * (x1 - x0);
    let y = |o: f64| y1 - o / top * (y1 - y0);
    let _ = write!(
        s,
        "<h2>Pick poles</h2>\n<p>Click the poles that are modes (once more to drop one); the \
         pointer shows a pole's frequency, damping and MPC. {} Damping is the structure's (an \
         exponential window's removed). Grey: a pole; green ring: stable; blue: in a mode's \
         cluster; orange ring: in a rejected cluster; dashed lines: the modes found.</p>\n<style>{PICK_STYLE}</style>\n<svg id=\"pole-picker\" \
         viewBox=\"0 0 {W} {H}\" width=\"{W}\" xmlns=\"http://www.w3.org/2000/svg\" \
         font-size=\"12\"><rect x=\"{x0}\" y=\"{y0}\" width=\"{}\" height=\"{}\" fill=\"#fff\" \
         stroke=\"#888\"/>",
        p.rerun,
        x1 - x0,
        y1 - y0
    );
    axes(s, (lo, hi), top, x, y);
    for &f in p.modes_hz.iter().filter(|f| (lo..=hi).contains(*f)) {
        let _ = write!(
            s,
            "<line class=\"mode-line\" x1=\"{0:.2}\" x2=\"{0:.2}\" y1=\"{y0}\" y2=\"{y1}\"/>",
            x(f)
        );
    }
    for (i, q) in p.poles.iter().enumerate() {
        if !(lo..=hi).contains(&q.at_hz) {
            continue;
        }
        let _ = write!(
            s,
            "<circle class=\"{}\" data-i=\"{i}\" cx=\"{:.2}\" cy=\"{:.2}\" r=\"4\"><title>{}</title></circle>",
            class(q.kind),
            x(q.at_hz),
            y(q.order as f64),
            describe(q)
        );
    }
    s.push_str("</svg>\n");
    let data: Vec<String> = p
        .poles
        .iter()
        .map(|q| {
            format!(
                "[{},{},{},{}]",
                json_num(q.f_hz),
                json_num(q.damping),
                q.order,
                json_num(q.mpc)
            )
        })
        .collect();
    let _ = write!(
        s,
        "<div id=\"pole-hover\">&nbsp;</div>\n<table id=\"picked\"><thead><tr><th>f, Hz</th>\
         <th>damping, %</th><th>order</th><th>MPC</th></tr></thead><tbody></tbody></table>\n\
         <p><a id=\"save-poles\" download=\"poles.csv\" href=\"#\">save poles.csv</a> \
         <button id=\"clear-poles\" type=\"button\">clear</button></p>\n<textarea id=\"poles-csv\" \
         rows=\"4\" cols=\"60\" readonly></textarea>\n<script type=\"application/json\" \
         id=\"pole-data\">{{\"poles\":[{}]}}</script>\n<script>{PICK_SCRIPT}</script>\n",
        data.join(",")
    );
}

/// The frequency and order axes: ticks, labels and titles.
fn axes(
    s: &mut String,
    (lo, hi): (f64, f64),
    top: f64,
    x: impl Fn(f64) -> f64,
    y: impl Fn(f64) -> f64,
) {
    let (x0, x1, y0, y1) = AREA;
    let fx = ticks(lo, hi, 10.0);
    let step = fx.get(1).zip(fx.first()).map_or(1.0, |(b, a)| b - a);
    for f in &fx {
        let _ = write!(
            s,
            "<line x1=\"{0:.2}\" x2=\"{0:.2}\" y1=\"{y1}\" y2=\"{1}\" stroke=\"#888\"/><text x=\"{0:.2}\" y=\"{2}\" text-anchor=\"middle\">{3}</text>",
            x(*f),
            y1 + 5.0,
            y1 + 18.0,
            tick_label(*f, step)
        );
    }
    for o in ticks(0.0, top, 6.0) {
        let _ = write!(
            s,
            "<line x1=\"{0}\" x2=\"{x0}\" y1=\"{1:.2}\" y2=\"{1:.2}\" stroke=\"#888\"/><text x=\"{2}\" y=\"{3:.2}\" text-anchor=\"end\">{o}</text>",
            x0 - 5.0,
            y(o),
            x0 - 8.0,
            y(o) + 4.0
        );
    }
    let _ = write!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">frequency (Hz)</text><text x=\"16\" y=\"{2}\" transform=\"rotate(-90 16 {2})\" text-anchor=\"middle\">model order</text>",
        (x0 + x1) / 2.0,
        y1 + 36.0,
        (y0 + y1) / 2.0
    );
}

/// A pole in words, as its hover title shows it (digits and words: no HTML to escape).
fn describe(q: &PickPole) -> String {
    let mpc = if q.mpc.is_finite() {
        format!("{:.3}", q.mpc)
    } else {
        "-".into()
    };
    format!(
        "{:.3} Hz, damping {:.3} %, order {}, MPC {mpc}",
        q.f_hz,
        100.0 * q.damping,
        q.order
    )
}

const PICK_STYLE: &str = "#pole-picker{max-width:100%;height:auto;border:1px solid #ddd}\
#pole-picker .pole{fill:#bbb;cursor:pointer}\
#pole-picker .pole.stable{fill:#fff;stroke:#2a7;stroke-width:1.5}\
#pole-picker .pole.mode{fill:#1e5ac8}\
#pole-picker .pole.rejected{fill:#fff;stroke:#e67814;stroke-width:1.5}\
#pole-picker .pole:hover{stroke:#000;stroke-width:2}\
#pole-picker .pole.picked{fill:#d62728;stroke:#000;stroke-width:2;r:6}\
#pole-picker .mode-line{stroke:#c83c28;stroke-width:1;stroke-dasharray:4 3}\
#pole-hover{font-family:monospace;min-height:1.3em}\
#poles-csv{font-family:monospace}";

/// The picker's script: picks on click, the hover line, the table and the saved file.
const PICK_SCRIPT: &str = r#"(function(){
var poles=JSON.parse(document.getElementById('pole-data').textContent).poles;
var svg=document.getElementById('pole-picker'),hover=document.getElementById('pole-hover');
var body=document.querySelector('#picked tbody'),save=document.getElementById('save-poles');
var text=document.getElementById('poles-csv'),picked={};
function fix(v,n){return v===null?'-':v.toFixed(n);}
function words(p){return fix(p[0],3)+' Hz, damping '+(p[1]===null?'-':(100*p[1]).toFixed(3))+' %, order '+p[2]+', MPC '+fix(p[3],3);}
function update(){
 var ks=Object.keys(picked).map(Number).sort(function(a,b){return poles[a][0]-poles[b][0];});
 var csv='f_hz,damping,order,mpc\n',rows='';
 ks.forEach(function(k){var p=poles[k];
  csv+=String(p[0])+','+String(p[1])+','+p[2]+','+(p[3]===null?'':String(p[3]))+'\n';
  rows+='<tr data-i="'+k+'"><td>'+fix(p[0],3)+'</td><td>'+(100*p[1]).toFixed(3)+'</td><td>'+p[2]+'</td><td>'+fix(p[3],3)+'</td></tr>';});
 body.innerHTML=rows;text.value=csv;
 save.setAttribute('href','data:text/csv;charset=utf-8,'+encodeURIComponent(csv));
 save.setAttribute('data-count',String(ks.length));
}
svg.addEventListener('click',function(e){
 var c=e.target;if(!c.classList||!c.classList.contains('pole'))return;
 var k=Number(c.getAttribute('data-i'));
 if(picked[k]){delete picked[k];c.classList.remove('picked');}else{picked[k]=true;c.classList.add('picked');}
 update();
});
svg.addEventListener('mouseover',function(e){
 var c=e.target;if(c.classList&&c.classList.contains('pole')){hover.textContent=words(poles[Number(c.getAttribute('data-i'))]);}
});
document.getElementById('clear-poles').addEventListener('click',function(){
 picked={};var cs=svg.querySelectorAll('circle.picked');for(var i=0;i<cs.length;i++)cs[i].classList.remove('picked');update();
});
update();
})();"#;

#[cfg(test)]
mod tests {
    use super::*;

    fn pole(at_hz: f64, order: usize, kind: PoleKind) -> PickPole {
        PickPole {
            at_hz,
            order,
            kind,
            f_hz: at_hz,
            damping: 0.01,
            mpc: f64::NAN,
        }
    }

    #[test]
    fn ticks_are_round_and_inside() {
        assert_eq!(
            ticks(0.0, 100.0, 10.0),
            (0..=10).map(|k| 10.0 * k as f64).collect::<Vec<_>>()
        );
        let t = ticks(60.0, 2424.0, 10.0);
        assert_eq!(t.first(), Some(&200.0));
        assert_eq!(t.last(), Some(&2400.0));
        assert_eq!(ticks(5.0, 5.0, 10.0), vec![5.0]);
        assert_eq!(tick_label(0.25, 0.05), "0.25");
        assert_eq!(tick_label(1200.0, 200.0), "1200");
    }

    #[test]
    fn a_circle_per_pole_in_range_and_full_precision_data() {
        let mut p = Picker {
            poles: vec![
                pole(10.0, 4, PoleKind::Pole),
                pole(20.0, 6, PoleKind::Mode),
                pole(500.0, 6, PoleKind::Stable),
            ],
            f_range: (0.0, 100.0),
            modes_hz: vec![20.0],
            rerun: "Run again with $poles.".into(),
        };
        p.poles[1].f_hz = 20.123456789012345;
        let mut s = String::new();
        section(&mut s, &p);
        let exact = format!("[{},0.01,6,null]", p.poles[1].f_hz);
        let back: f64 = exact[1..].split(',').next().unwrap().parse().unwrap();
        assert_eq!(back, p.poles[1].f_hz, "{exact}");
        assert_eq!(s.matches("<circle class=\"pole").count(), 2);
        assert!(s.contains("class=\"pole mode\" data-i=\"1\""));
        assert!(s.contains(&exact), "{exact}");
        assert!(s.contains("20.123 Hz, damping 1.000 %, order 6, MPC -"));
        assert_eq!(s.matches("class=\"mode-line\"").count(), 1);
        assert!(!s.contains("NaN"));
    }
}

//! The frame scrubber of `report.html` (`track`, `analyze` without an accelerometer): frames spread through the record
//! (and the first frame of each loss), each with every target's window drawn where it was
//! tracked, or marked lost (red, dashed, at its last position seen, with the check or flag
//! that took it away); a slider over them; and each target's match score over every frame. A
//! user sees in a minute whether the windows stayed on the targets.
//!
//! Elements the browser tests find: `input#frame-slider`, `svg#scrub` with `image#scrub-image`
//! and one `g.scrub-target` per target (its `rect`, class `lost` when lost in the frame shown,
//! its `data-x`/`data-y` the position drawn), `span#frame-label`, `svg#scores` with one
//! `polyline.score-line` per target with scores.

use std::fmt::Write as _;

/// One frame of the scrubber.
#[derive(Debug, Clone, PartialEq)]
pub struct ScrubFrame {
    /// The frame's number in the record, 0-based.
    pub index: usize,
    /// The frame as a PNG (scaled down; drawn over the frame's own pixel size).
    pub png: Vec<u8>,
    /// Per target its position in the image, px (`None`: lost in this frame).
    pub positions: Vec<Option<(f64, f64)>>,
    /// Per target why it is lost in this frame (the check or the flags), empty when it is not.
    pub why: Vec<String>,
}

/// What the scrubber shows.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scrubber {
    /// The frame's size, px.
    pub size: (u32, u32),
    /// Per target its number and window (w, h), px.
    pub targets: Vec<(usize, (f64, f64))>,
    /// Per target its first position, px (where a target lost from the start is drawn).
    pub first: Vec<(f64, f64)>,
    /// The frames shown.
    pub frames: Vec<ScrubFrame>,
    /// Per target its match score in every frame of the record (`None`: none), when the tracker
    /// has one.
    pub scores: Vec<Vec<Option<f32>>>,
}

/// A finite number for the script (`null` otherwise).
fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "null".into()
    }
}

/// A string as a JSON string literal safe inside a `<script>` (quotes, backslashes, `<`).
fn json_str(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The scrubber's section; `base64` encodes a frame's PNG.
pub fn section(s: &mut String, sc: &Scrubber, base64: impl Fn(&[u8]) -> String) {
    let Some(first) = sc.frames.first() else {
        return;
    };
    let (w, h) = (f64::from(sc.size.0), f64::from(sc.size.1));
    let stroke = (w.max(h) / 400.0).max(1.0);
    let _ = write!(
        s,
        "<h2>Check the track</h2>\n<p>{} frames of the record (spread through it, and the first \
         frame of each loss): each window where it was tracked; red and dashed where the target \
         is lost in that frame, at its last position seen.</p>\n<p><input type=\"range\" \
         id=\"frame-slider\" min=\"0\" max=\"{}\" value=\"0\" step=\"1\" style=\"width:60%\"> \
         <span id=\"frame-label\">frame {}</span></p>\n<svg id=\"scrub\" viewBox=\"0 0 {w} {h}\" \
         width=\"{}\" xmlns=\"http://www.w3.org/2000/svg\"><image id=\"scrub-image\" \
         href=\"data:image/png;base64,{}\" x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\"/>",
        sc.frames.len(),
        sc.frames.len() - 1,
        first.index + 1,
        if w < 700.0 { 700.0 } else { w.min(1100.0) },
        base64(&first.png)
    );
    for (number, (ww, wh)) in &sc.targets {
        let _ = write!(
            s,
            "<g class=\"scrub-target\" data-target=\"{number}\"><rect width=\"{ww}\" \
             height=\"{wh}\" fill=\"none\" stroke-width=\"{stroke}\"/><text font-size=\"{}\" \
             stroke=\"#000\" stroke-width=\"{}\">{number}</text></g>",
            10.0 * stroke,
            0.25 * stroke
        );
    }
    s.push_str("</svg>\n");
    scores_figure(s, sc);
    let mut data = String::from("{\"frames\":[");
    for (i, f) in sc.frames.iter().enumerate() {
        let pos: Vec<String> = f
            .positions
            .iter()
            .map(|p| p.map_or("null".into(), |(x, y)| format!("[{},{}]", num(x), num(y))))
            .collect();
        let why: Vec<String> = f.why.iter().map(|w| json_str(w)).collect();
        let _ = write!(
            data,
            "{}{{\"index\":{},\"png\":\"{}\",\"pos\":[{}],\"why\":[{}]}}",
            if i > 0 { "," } else { "" },
            f.index,
            base64(&f.png),
            pos.join(","),
            why.join(",")
        );
    }
    let windows: Vec<String> = sc
        .targets
        .iter()
        .map(|(_, (ww, wh))| format!("[{},{}]", num(*ww), num(*wh)))
        .collect();
    let first: Vec<String> = sc
        .first
        .iter()
        .map(|(x, y)| format!("[{},{}]", num(*x), num(*y)))
        .collect();
    let _ = write!(
        data,
        "],\"windows\":[{}],\"first\":[{}]}}",
        windows.join(","),
        first.join(",")
    );
    let _ = write!(
        s,
        "<script type=\"application/json\" id=\"scrub-data\">{data}</script>\n<script>{SCRIPT}</script>\n"
    );
}

/// Each target's score over the record, one line each, in a range set by the scores.
fn scores_figure(s: &mut String, sc: &Scrubber) {
    let all: Vec<f32> = sc.scores.iter().flatten().flatten().copied().collect();
    if all.is_empty() {
        return;
    }
    let lo = f64::from(all.iter().copied().fold(1.0f32, f32::min)).min(0.9);
    let lo = (lo * 20.0).floor() / 20.0;
    let n = sc.scores.iter().map(Vec::len).max().unwrap_or(0).max(2);
    let (pw, ph, left, top) = (900.0, 220.0, 50.0, 10.0);
    let x = |k: usize| left + (pw - left - 10.0) * k as f64 / (n - 1) as f64;
    let y = |v: f64| top + (ph - top - 30.0) * (1.0 - (v - lo) / (1.0 - lo));
    let _ = write!(
        s,
        "<h3>Each target's match score (ZNCC against its first window) in every frame</h3>\n\
         <svg id=\"scores\" viewBox=\"0 0 {pw} {ph}\" width=\"{pw}\" \
         xmlns=\"http://www.w3.org/2000/svg\" class=\"figure\"><g font-size=\"11\">\
         <text x=\"4\" y=\"{}\">1</text><text x=\"4\" y=\"{}\">{lo}</text>\
         <text x=\"{left}\" y=\"{}\">frame 1</text><text x=\"{}\" y=\"{}\" \
         text-anchor=\"end\">frame {n}</text></g>",
        y(1.0) + 4.0,
        y(lo),
        ph - 8.0,
        pw - 10.0,
        ph - 8.0
    );
    for (t, scores) in sc.scores.iter().enumerate() {
        if scores.iter().all(Option::is_none) {
            continue;
        }
        let number = sc.targets.get(t).map_or(t + 1, |p| p.0);
        let pts: Vec<String> = scores
            .iter()
            .enumerate()
            .filter_map(|(k, v)| v.map(|v| format!("{:.1},{:.1}", x(k), y(f64::from(v)))))
            .collect();
        let hue = (t * 137) % 360;
        let _ = write!(
            s,
            "<polyline class=\"score-line\" data-target=\"{number}\" fill=\"none\" \
             stroke=\"hsl({hue},70%,40%)\" stroke-width=\"1\" points=\"{}\"><title>target \
             {number}</title></polyline>",
            pts.join(" ")
        );
    }
    s.push_str("</svg>\n");
}

/// The scrubber's script: the slider shows a frame, its image and every window.
const SCRIPT: &str = r#"(function(){
var d=JSON.parse(document.getElementById('scrub-data').textContent);
var slider=document.getElementById('frame-slider'),img=document.getElementById('scrub-image');
var label=document.getElementById('frame-label'),gs=document.querySelectorAll('g.scrub-target');
function show(i){
 var f=d.frames[i];img.setAttribute('href','data:image/png;base64,'+f.png);
 var lost=0;
 for(var t=0;t<gs.length;t++){
  var p=f.pos[t],at=p;
  if(!at){for(var j=i-1;j>=0&&!at;j--){at=d.frames[j].pos[t];}if(!at){at=d.first[t];}}
  var r=gs[t].querySelector('rect'),tx=gs[t].querySelector('text'),w=d.windows[t];
  r.setAttribute('x',at[0]+0.5-w[0]/2);r.setAttribute('y',at[1]+0.5-w[1]/2);
  tx.setAttribute('x',at[0]+0.5+w[0]/2+2);tx.setAttribute('y',at[1]+0.5-w[1]/2);
  gs[t].setAttribute('data-x',at[0]);gs[t].setAttribute('data-y',at[1]);
  var name=gs[t].getAttribute('data-target');
  if(p){r.setAttribute('class','');r.setAttribute('stroke','#00c8ff');r.removeAttribute('stroke-dasharray');tx.setAttribute('fill','#ffe000');tx.textContent=name;}
  else{lost++;tx.setAttribute('x',at[0]+0.5-w[0]/2);tx.setAttribute('y',at[1]+0.5+w[1]/2+parseFloat(tx.getAttribute('font-size')));r.setAttribute('class','lost');r.setAttribute('stroke','#ff2020');r.setAttribute('stroke-dasharray','4 3');tx.setAttribute('fill','#ff4040');tx.textContent=name+' lost'+(f.why[t]?' ('+f.why[t]+')':'');}
 }
 label.textContent='frame '+(f.index+1)+(lost?', '+lost+' lost':'');
 slider.setAttribute('data-frame',f.index);
}
slider.addEventListener('input',function(){show(parseInt(slider.value,10));});
show(0);
})();"#;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_section_holds_a_window_per_target_and_every_frame_in_its_data() {
        let frame = |index: usize, lost: bool| ScrubFrame {
            index,
            png: vec![1, 2, 3],
            positions: vec![Some((10.0, 12.0)), (!lost).then_some((30.0, 12.0))],
            why: vec![
                String::new(),
                if lost {
                    "forward-backward".into()
                } else {
                    String::new()
                },
            ],
        };
        let sc = Scrubber {
            size: (64, 32),
            targets: vec![(1, (9.0, 9.0)), (2, (9.0, 9.0))],
            first: vec![(10.0, 12.0), (30.0, 12.0)],
            frames: vec![frame(0, false), frame(7, true)],
            scores: vec![vec![Some(1.0), Some(0.98)], vec![Some(1.0), None]],
        };
        let mut s = String::new();
        section(&mut s, &sc, |b| format!("B{}", b.len()));
        assert_eq!(s.matches("class=\"scrub-target\"").count(), 2);
        assert!(s.contains("id=\"frame-slider\" min=\"0\" max=\"1\""));
        assert!(s.contains("\"index\":7,\"png\":\"B3\",\"pos\":[[10.000,12.000],null]"));
        assert!(s.contains("\"why\":[\"\",\"forward-backward\"]"));
        assert_eq!(s.matches("polyline class=\"score-line\"").count(), 2);
        // no frame, no section
        let mut empty = String::new();
        section(&mut empty, &Scrubber::default(), |_| String::new());
        assert!(empty.is_empty());
        assert_eq!(json_str("a\"</script>"), "\"a\\\"\\u003c/script\\u003e\"");
    }
}

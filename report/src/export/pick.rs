//! `pick.html`: a self-contained page to choose the points `track --points` follows. Frames of
//! the recording (a slider between them), where a click adds a window centred there (its size
//! and group editable), a drag moves one, Delete (or Backspace) removes the selected one, the
//! points of an existing file are shown, and "save points.csv" downloads the file in the
//! format `track --points` reads: `target,x,y,w,h,group`, `x, y` in px with the origin at the
//! centre of the top-left pixel (the page's image has it at the pixel's corner: half a pixel
//! apart), `w, h` whole and at least 3, every window inside the frame.
//!
//! Elements the browser tests use: `svg#pick` (the image, one `g.window` per point),
//! `input#frame-slider`, `input#size-w`, `input#size-h`, `input#group`, `button#save`,
//! `table#points`; `window.vibcamPointsCsv()` returns the text "save" downloads.

use super::html::{base64, escape, json_string_in_script, FrameImage};
use std::fmt::Write as _;

/// A point shown at the start (from `--points`).
#[derive(Debug, Clone, PartialEq)]
pub struct PickPoint {
    /// Target number.
    pub target: usize,
    /// Centre, px (origin at the centre of the top-left pixel).
    pub xy: (f64, f64),
    /// Window, px.
    pub size: (u32, u32),
    /// Group.
    pub group: Option<u32>,
}

const SCRIPT: &str = r#"(function(){
var data=JSON.parse(document.getElementById('pick-data').textContent);
var svg=document.getElementById('pick'),img=document.getElementById('frame-image');
var slider=document.getElementById('frame-slider'),label=document.getElementById('frame-label');
var sw=document.getElementById('size-w'),sh=document.getElementById('size-h'),sg=document.getElementById('group');
var pts=data.points.map(function(p){return {target:p.target,x:p.x,y:p.y,w:p.w,h:p.h,group:p.group};});
var sel=-1,drag=null,W=data.width,H=data.height;
function clamp(p){var hw=(p.w-1)/2,hh=(p.h-1)/2;p.x=Math.min(Math.max(p.x,hw),W-1-hw);p.y=Math.min(Math.max(p.y,hh),H-1-hh);}
function toPx(ev){var pt=svg.createSVGPoint();pt.x=ev.clientX;pt.y=ev.clientY;var q=pt.matrixTransform(svg.getScreenCTM().inverse());return {x:q.x-0.5,y:q.y-0.5};}
function render(){
 var old=svg.querySelectorAll('g.window');for(var i=0;i<old.length;i++){old[i].remove();}
 var ns='http://www.w3.org/2000/svg';
 pts.forEach(function(p,i){
  var g=document.createElementNS(ns,'g');g.setAttribute('class','window');g.setAttribute('data-target',p.target);
  var r=document.createElementNS(ns,'rect');
  r.setAttribute('x',p.x+0.5-p.w/2);r.setAttribute('y',p.y+0.5-p.h/2);r.setAttribute('width',p.w);r.setAttribute('height',p.h);
  r.setAttribute('fill','rgba(0,200,255,0.08)');r.setAttribute('stroke',i===sel?'#ff3030':'#00c8ff');r.setAttribute('stroke-width',Math.max(W,H)/400+0.5);
  r.addEventListener('mousedown',function(ev){if(tool.value!=='window')return;ev.stopPropagation();sel=i;drag={i:i,start:toPx(ev),x:p.x,y:p.y,moved:false};sw.value=p.w;sh.value=p.h;sg.value=p.group==null?'':p.group;render();});
  var t=document.createElementNS(ns,'text');t.setAttribute('x',p.x+0.5-p.w/2);t.setAttribute('y',p.y+0.5-p.h/2-1);t.setAttribute('fill','#ffe000');t.setAttribute('font-size',Math.max(10,Math.max(W,H)/50));
  t.textContent=p.target+(p.group!=null?' (group '+p.group+')':'');
  g.appendChild(r);g.appendChild(t);svg.appendChild(g);
 });
 var tb=document.getElementById('points');var rows='<tr><th>target</th><th>x</th><th>y</th><th>w</th><th>h</th><th>group</th></tr>';
 pts.forEach(function(p){rows+='<tr><td>'+p.target+'</td><td>'+p.x.toFixed(2)+'</td><td>'+p.y.toFixed(2)+'</td><td>'+p.w+'</td><td>'+p.h+'</td><td>'+(p.group==null?'':p.group)+'</td></tr>';});
 tb.innerHTML=rows;
}
function size(v){v=Math.round(parseFloat(v));return isFinite(v)&&v>=3?v:21;}
var tool=document.getElementById('tool'),brushR=document.getElementById('brush-r'),regionText=document.getElementById('region');
var reg=[],stroke=false;
function r1(v){return Math.round(v*10)/10;}
function regionString(){
 if(reg.length===0)return '';
 var v=reg.map(function(q){return r1(q.x)+','+r1(q.y);}).join(';');
 var t=tool.value,r=parseFloat(brushR.value);
 if(t==='line')return 'line:'+v;
 if(t==='brush')return 'brush:'+(isFinite(r)&&r>0?r:10)+':'+v;
 return v;
}
function drawRegion(){
 var old=svg.querySelectorAll('.region');for(var i=0;i<old.length;i++){old[i].remove();}
 if(reg.length===0){regionText.value='';return;}
 var ns='http://www.w3.org/2000/svg',t=tool.value;
 var e=document.createElementNS(ns,t==='polygon'?'polygon':'polyline');e.setAttribute('class','region');
 e.setAttribute('points',reg.map(function(q){return (q.x+0.5)+','+(q.y+0.5);}).join(' '));
 var r=parseFloat(brushR.value);
 e.setAttribute('fill',t==='polygon'?'rgba(255,200,0,0.12)':'none');
 e.setAttribute('stroke',t==='brush'?'rgba(255,200,0,0.35)':'#ffc800');
 e.setAttribute('stroke-width',t==='brush'?2*(isFinite(r)&&r>0?r:10):Math.max(W,H)/400+0.5);
 e.setAttribute('stroke-linecap','round');e.setAttribute('stroke-linejoin','round');
 svg.appendChild(e);regionText.value=regionString();
}
tool.addEventListener('change',function(){reg=[];drawRegion();});
brushR.addEventListener('change',drawRegion);
document.getElementById('clear-region').addEventListener('click',function(){reg=[];drawRegion();});
window.vibcamRegion=regionString;
svg.addEventListener('mousedown',function(ev){
 if(ev.button!==0)return;var q=toPx(ev);
 if(tool.value!=='window'){
  if(tool.value==='brush'){if(!stroke){reg=[];}stroke=true;}
  reg.push(q);drawRegion();return;
 }
 var next=pts.reduce(function(a,p){return Math.max(a,p.target);},0)+1;
 var g=sg.value===''?null:Math.max(0,Math.round(parseFloat(sg.value)));
 var p={target:next,x:q.x,y:q.y,w:Math.min(size(sw.value),W),h:Math.min(size(sh.value),H),group:isFinite(g)?g:null};clamp(p);
 pts.push(p);sel=pts.length-1;render();
});
window.addEventListener('mousemove',function(ev){
 if(stroke){var q=toPx(ev),l=reg[reg.length-1];if(Math.hypot(q.x-l.x,q.y-l.y)>=2){reg.push(q);drawRegion();}return;}
 if(!drag)return;var q=toPx(ev);var p=pts[drag.i];p.x=drag.x+q.x-drag.start.x;p.y=drag.y+q.y-drag.start.y;clamp(p);drag.moved=true;render();});
window.addEventListener('mouseup',function(){drag=null;stroke=false;});
window.addEventListener('keydown',function(ev){
 if((ev.key==='Delete'||ev.key==='Backspace')&&sel>=0&&document.activeElement.tagName!=='INPUT'){pts.splice(sel,1);sel=-1;
  pts.forEach(function(p,i){p.target=i+1;});render();ev.preventDefault();}
});
function edit(){if(sel<0)return;var p=pts[sel];p.w=Math.min(size(sw.value),W);p.h=Math.min(size(sh.value),H);
 var g=sg.value===''?null:Math.round(parseFloat(sg.value));p.group=(g!=null&&isFinite(g)&&g>=0)?g:null;clamp(p);render();}
sw.addEventListener('change',edit);sh.addEventListener('change',edit);sg.addEventListener('change',edit);
if(slider){slider.addEventListener('input',function(){var f=data.frames[parseInt(slider.value)];img.setAttribute('href','data:image/png;base64,'+f.png);label.textContent=f.label;});}
window.vibcamPointsCsv=function(){
 var grouped=pts.some(function(p){return p.group!=null;});
 var s='target,x,y,w,h'+(grouped?',group':'')+'\n';
 pts.forEach(function(p){s+=p.target+','+p.x.toFixed(3)+','+p.y.toFixed(3)+','+p.w+','+p.h+(grouped?','+(p.group==null?0:p.group):'')+'\n';});
 return s;
};
document.getElementById('save').addEventListener('click',function(){
 var a=document.createElement('a');a.href=URL.createObjectURL(new Blob([window.vibcamPointsCsv()],{type:'text/csv'}));
 a.download='points.csv';document.body.appendChild(a);a.click();a.remove();
});
render();
})();"#;

/// The points file `track --points` reads: `target,x,y,w,h[,group]` (a `group` column when any
/// point has one, empty for the others: no group), the format of the page's "save points.csv".
pub fn points_csv(points: &[PickPoint]) -> String {
    let grouped = points.iter().any(|p| p.group.is_some());
    let mut csv = String::from(if grouped {
        "target,x,y,w,h,group\n"
    } else {
        "target,x,y,w,h\n"
    });
    for p in points {
        csv.push_str(&format!(
            "{},{},{},{},{}",
            p.target, p.xy.0, p.xy.1, p.size.0, p.size.1
        ));
        if grouped {
            csv.push_str(&format!(
                ",{}",
                p.group.map_or(String::new(), |g| g.to_string())
            ));
        }
        csv.push('\n');
    }
    csv
}

/// The page's region tools: what a click adds (a window, or the vertices of a polygon, a line
/// or a brush stroke) and the region as the text `pick` takes for its region.
const REGION_TOOLS: &str = "<p>click to add <select id=\"tool\"><option value=\"window\">a \
    window</option><option value=\"polygon\">a polygon's vertex</option><option \
    value=\"line\">a line's vertex</option><option value=\"brush\">a brush stroke \
    (drag)</option></select> brush radius <input id=\"brush-r\" type=\"number\" min=\"1\" \
    value=\"10\" style=\"width:4em\"> px <button id=\"clear-region\">clear region</button><br>\
    region <input id=\"region\" readonly size=\"60\"> for <code>pick</code>'s region (with its \
    spacing, least texture and direction): it keeps the places of a grid in it whose window has \
    the texture to track</p>\n";

/// The page: `frames` (label and image; the first shown), `points` at the start.
pub fn pick_html(title: &str, frames: &[(String, FrameImage)], points: &[PickPoint]) -> String {
    let (w, h) = frames.first().map_or((1, 1), |(_, f)| (f.width, f.height));
    let mut s = String::from("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">");
    let _ = write!(
        s,
        "<title>{}</title><style>body{{font-family:sans-serif;margin:1em}}#pick{{border:1px solid #888;cursor:crosshair;max-width:100%;height:auto}}table{{border-collapse:collapse}}td,th{{border:1px solid #ccc;padding:2px 6px}}</style></head><body>\n<h1>{}</h1>\n",
        escape(title),
        escape(title)
    );
    s.push_str(
        "<p>Click to add a window centred there; drag a window to move it; select one and press \
         Delete to remove it; window size and group apply to new windows and to the selected \
         one. \"save points.csv\" downloads the file <code>track --points</code> reads.</p>\n",
    );
    let _ = writeln!(
        s,
        "<p>window <input id=\"size-w\" type=\"number\" min=\"3\" value=\"21\" style=\"width:4em\"> x \
         <input id=\"size-h\" type=\"number\" min=\"3\" value=\"21\" style=\"width:4em\"> px, group \
         <input id=\"group\" type=\"number\" min=\"0\" style=\"width:4em\"> \
         <button id=\"save\">save points.csv</button></p>"
    );
    s.push_str(REGION_TOOLS);
    if frames.len() > 1 {
        let _ = writeln!(
            s,
            "<p>frame <input id=\"frame-slider\" type=\"range\" min=\"0\" max=\"{}\" value=\"0\"> <span id=\"frame-label\">{}</span></p>",
            frames.len() - 1,
            escape(&frames[0].0)
        );
    } else {
        let _ = writeln!(
            s,
            "<p><span id=\"frame-label\">{}</span></p>",
            escape(frames.first().map_or("", |f| f.0.as_str()))
        );
    }
    let display = if w < 700 { 700 } else { w.min(1400) };
    let _ = write!(
        s,
        "<svg id=\"pick\" viewBox=\"0 0 {w} {h}\" width=\"{display}\" xmlns=\"http://www.w3.org/2000/svg\"><image id=\"frame-image\" href=\"data:image/png;base64,{}\" x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" preserveAspectRatio=\"none\" style=\"image-rendering:pixelated\"/></svg>\n<table id=\"points\"></table>\n",
        frames.first().map_or(String::new(), |(_, f)| base64(&f.png))
    );
    let frames_json: Vec<String> = frames
        .iter()
        .map(|(l, f)| {
            format!(
                "{{\"label\":{},\"png\":\"{}\"}}",
                json_string_in_script(l),
                base64(&f.png)
            )
        })
        .collect();
    let points_json: Vec<String> = points
        .iter()
        .map(|p| {
            format!(
                "{{\"target\":{},\"x\":{},\"y\":{},\"w\":{},\"h\":{},\"group\":{}}}",
                p.target,
                p.xy.0,
                p.xy.1,
                p.size.0,
                p.size.1,
                p.group.map_or("null".to_string(), |g| g.to_string())
            )
        })
        .collect();
    let _ = write!(
        s,
        "<script type=\"application/json\" id=\"pick-data\">{{\"width\":{w},\"height\":{h},\"frames\":[{}],\"points\":[{}]}}</script>\n<script>{SCRIPT}</script>\n</body></html>\n",
        frames_json.join(","),
        points_json.join(",")
    );
    s
}

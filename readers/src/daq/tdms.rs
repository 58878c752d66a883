//! NI TDMS files (binary; NI's "TDMS File Format Internal Structure"): a sequence of segments,
//! each a 28-byte lead-in (`TDSm`, the table-of-contents flags, the version, the offsets of the
//! next segment and of the raw data), optional metadata (the objects `/'group'/'channel'`, each
//! with its raw-data index and properties) and raw data in chunks. A segment without metadata,
//! or an object whose index says "as before", takes the previous segment's; without the
//! new-object-list flag a segment's objects are the previous list with its own added or
//! updated.
//!
//! Read: numeric channels (integers of 8 to 64 bits, 32 and 64-bit floats, also "with unit"),
//! contiguous or interleaved, little or big endian, over any number of segments and chunks; the
//! sample interval from the channel's `wf_increment`, the unit from `unit_string`. Refused with
//! a message naming the file and the channel: DAQmx raw data (its scalers are not applied here),
//! strings, timestamps and booleans as a signal. Channels are named by their TDMS channel name,
//! or `group/channel` where two groups share a name. Checked against npTDMS's reading of files
//! npTDMS wrote (`tests/data/tdms`, `scripts/tdms_fixtures.py`).

use super::{Channel, Record};
use crate::bad_input;
use std::collections::HashMap;
use std::path::Path;

const TOC_META: u32 = 1 << 1;
const TOC_NEW_LIST: u32 = 1 << 2;
const TOC_RAW: u32 = 1 << 3;
const TOC_INTERLEAVED: u32 = 1 << 5;
const TOC_BIG_ENDIAN: u32 = 1 << 6;
const TOC_DAQMX: u32 = 1 << 7;
/// The type code of a timestamp (16 bytes).
const TIMESTAMP: u32 = 0x44;

/// Reads the TDMS file `path`.
pub fn read(path: &Path) -> anyhow::Result<Record> {
    let bytes = std::fs::read(path)
        .map_err(|e| bad_input(format!("{}: cannot read: {e}", path.display())))?;
    parse(&bytes, &path.display().to_string())
}

/// A channel's raw-data index in a segment.
#[derive(Debug, Clone, Copy)]
struct Index {
    dtype: u32,
    count: u64,
}

/// What the file says of one object.
#[derive(Debug, Default)]
struct Object {
    index: Option<Index>,
    increment: Option<f64>,
    start: Option<f64>,
    unit: Option<String>,
    /// `wf_start_time`: the absolute time of the first sample, s since 1904-01-01 UTC.
    start_time: Option<f64>,
    values: Vec<f64>,
    /// Set when its data cannot be read as numbers (the type's name).
    unreadable: Option<String>,
}

/// Size in bytes of a numeric TDMS type, and whether it is one.
fn size_of(dtype: u32) -> Option<usize> {
    match dtype {
        1 | 5 | 0x21 => Some(1),
        2 | 6 => Some(2),
        3 | 7 | 9 | 0x19 => Some(4),
        4 | 8 | 10 | 0x1A => Some(8),
        TIMESTAMP => Some(16),
        _ => None,
    }
}

/// The name of a type that is not read as a signal.
fn unreadable(dtype: u32) -> Option<&'static str> {
    match dtype {
        0x20 => Some("strings"),
        0x21 => Some("booleans"),
        TIMESTAMP => Some("timestamps"),
        0xFFFF_FFFF => Some("DAQmx raw data"),
        t if size_of(t).is_none() => Some("an unknown data type"),
        _ => None,
    }
}

/// A little cursor with the segment's byte order.
struct Cur<'a> {
    b: &'a [u8],
    at: usize,
    big: bool,
    file: &'a str,
}

impl Cur<'_> {
    fn take(&mut self, n: usize) -> anyhow::Result<&[u8]> {
        let end = self.at.checked_add(n).filter(|e| *e <= self.b.len());
        let Some(end) = end else {
            return Err(bad_input(format!(
                "{}: cut short at byte {} (wanted {n} more)",
                self.file, self.at
            )));
        };
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    /// `N` bytes in little-endian order (reversed when the segment is big endian).
    fn le<const N: usize>(&mut self) -> anyhow::Result<[u8; N]> {
        let mut b: [u8; N] = self.take(N)?.try_into().unwrap_or([0; N]);
        if self.big {
            b.reverse();
        }
        Ok(b)
    }
    fn u32(&mut self) -> anyhow::Result<u32> {
        self.le().map(u32::from_le_bytes)
    }
    fn u64(&mut self) -> anyhow::Result<u64> {
        self.le().map(u64::from_le_bytes)
    }
    fn string(&mut self) -> anyhow::Result<String> {
        let n = self.u32()? as usize;
        Ok(String::from_utf8_lossy(self.take(n)?).into_owned())
    }
    /// One value of a numeric type, as f64; a timestamp as seconds since 1904-01-01 UTC
    /// (TDMS's epoch; a microsecond's resolution in an f64).
    fn value(&mut self, dtype: u32) -> anyhow::Result<f64> {
        let n = size_of(dtype).unwrap_or(0);
        let b = self.take(n)?;
        if dtype == TIMESTAMP {
            // little endian: fractions (u64, 2^-64 s) then seconds (i64); big endian: seconds
            // then fractions, each big endian
            let (w0, w1): ([u8; 8], [u8; 8]) = (
                b[..8].try_into().unwrap_or([0; 8]),
                b[8..].try_into().unwrap_or([0; 8]),
            );
            let (secs, frac) = if self.big {
                (i64::from_be_bytes(w0), u64::from_be_bytes(w1))
            } else {
                (i64::from_le_bytes(w1), u64::from_le_bytes(w0))
            };
            return Ok(secs as f64 + frac as f64 / 18_446_744_073_709_551_616.0);
        }
        let mut a = [0u8; 8];
        a[..n.min(8)].copy_from_slice(&b[..n.min(8)]);
        let big = self.big;
        macro_rules! num {
            ($t:ty, $k:expr) => {{
                let arr: [u8; $k] = a[..$k].try_into().unwrap_or([0; $k]);
                (if big {
                    <$t>::from_be_bytes(arr)
                } else {
                    <$t>::from_le_bytes(arr)
                }) as f64
            }};
        }
        Ok(match dtype {
            1 => num!(i8, 1),
            2 => num!(i16, 2),
            3 => num!(i32, 4),
            4 => num!(i64, 8),
            5 | 0x21 => num!(u8, 1),
            6 => num!(u16, 2),
            7 => num!(u32, 4),
            8 => num!(u64, 8),
            9 | 0x19 => num!(f32, 4),
            10 | 0x1A => num!(f64, 8),
            _ => f64::NAN,
        })
    }
}

/// Parses the bytes of a TDMS file; `file` names it in errors.
pub fn parse(bytes: &[u8], file: &str) -> anyhow::Result<Record> {
    let mut objects: HashMap<String, Object> = HashMap::new();
    let mut order: Vec<String> = Vec::new();
    let mut list: Vec<String> = Vec::new();
    // the paths in `list`, for constant-time membership (files with 10^5 channels)
    let mut in_list: std::collections::HashSet<String> = std::collections::HashSet::new();
    let mut at = 0usize;
    let mut seg = 0;
    while at + 28 <= bytes.len() {
        seg += 1;
        if &bytes[at..at + 4] != b"TDSm" {
            return Err(bad_input(format!(
                "{file}: segment {seg} at byte {at} does not start with `TDSm`: not a TDMS \
                 file, or a damaged one"
            )));
        }
        let toc = u32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap_or([0; 4]));
        let big = toc & TOC_BIG_ENDIAN != 0;
        let mut c = Cur {
            b: bytes,
            at: at + 12,
            big,
            file,
        };
        let next = c.u64()?;
        let raw_offset = c.u64()?;
        let lead = at + 28;
        // a segment still being written has next offset all ones: it runs to the end
        let end = if next == u64::MAX {
            bytes.len()
        } else {
            usize::try_from(next)
                .ok()
                .and_then(|n| lead.checked_add(n))
                .filter(|e| *e <= bytes.len())
                .ok_or_else(|| {
                    bad_input(format!(
                        "{file}: segment {seg} states {next} bytes, more than the file holds"
                    ))
                })?
        };
        let raw_start = usize::try_from(raw_offset)
            .ok()
            .and_then(|r| lead.checked_add(r))
            .filter(|r| *r <= end)
            .ok_or_else(|| {
                bad_input(format!(
                    "{file}: segment {seg}: raw data offset past its end"
                ))
            })?;
        if toc & TOC_DAQMX != 0 {
            return Err(bad_input(format!(
                "{file}: segment {seg} holds DAQmx raw data, whose scalers are not applied \
                 here; save the channels as scaled values (LabVIEW's TDMS Convert Format, or \
                 npTDMS) and read that file"
            )));
        }
        if toc & TOC_META != 0 {
            if toc & TOC_NEW_LIST != 0 {
                list.clear();
                in_list.clear();
            }
            c.at = lead;
            let n = c.u32()?;
            for _ in 0..n {
                let path = c.string()?;
                let raw = c.u32()?;
                if !objects.contains_key(&path) {
                    order.push(path.clone());
                }
                let o = objects.entry(path.clone()).or_default();
                match raw {
                    0xFFFF_FFFF => {
                        o.index = None;
                        if in_list.remove(&path) {
                            list.retain(|p| *p != path);
                        }
                    }
                    0 => {
                        if o.index.is_some() && in_list.insert(path.clone()) {
                            list.push(path.clone());
                        }
                    }
                    0x6912_0000 | 0x6913_0000 => {
                        return Err(bad_input(format!(
                            "{file}: channel {path} holds DAQmx raw data, whose scalers are \
                             not applied here; save the channels as scaled values and read \
                             that file"
                        )));
                    }
                    len => {
                        let dtype = c.u32()?;
                        let _dim = c.u32()?;
                        let count = c.u64()?;
                        if len >= 28 {
                            let _bytes = c.u64()?;
                        }
                        o.index = Some(Index { dtype, count });
                        if in_list.insert(path.clone()) {
                            list.push(path.clone());
                        }
                    }
                }
                let props = c.u32()?;
                for _ in 0..props {
                    let name = c.string()?;
                    let t = c.u32()?;
                    match t {
                        0x20 => {
                            let v = c.string()?;
                            if name == "unit_string" {
                                o.unit = Some(v);
                            }
                        }
                        t if size_of(t).is_some() => {
                            let v = c.value(t)?;
                            match name.as_str() {
                                "wf_increment" => o.increment = Some(v),
                                "wf_start_offset" => o.start = Some(v),
                                "wf_start_time" if t == TIMESTAMP => o.start_time = Some(v),
                                _ => {}
                            }
                        }
                        // complex single and double: no setting of ours; stepped over
                        0x0008_000C => {
                            c.take(8)?;
                        }
                        0x0010_000D => {
                            c.take(16)?;
                        }
                        other => {
                            return Err(bad_input(format!(
                                "{file}: segment {seg}, object {path}: property `{name}` of \
                                 unknown type {other:#x}"
                            )))
                        }
                    }
                }
            }
        }
        if toc & TOC_RAW != 0 {
            // the channels of this segment's raw data, in order, with their indexes
            let chans: Vec<(String, Index)> = list
                .iter()
                .filter_map(|p| objects[p].index.map(|i| (p.clone(), i)))
                .collect();
            for (p, i) in &chans {
                if size_of(i.dtype).is_none() {
                    // its values' size is unknown: nothing after them can be found
                    return Err(bad_input(format!(
                        "{file}: segment {seg}: channel {p} holds raw data of type {:#x}, \
                         which is not a TDMS data type read here",
                        i.dtype
                    )));
                }
                if let Some(what) = unreadable(i.dtype) {
                    if let Some(o) = objects.get_mut(p) {
                        o.unreadable = Some(what.into());
                    }
                }
            }
            // sizes from the file: no overflow, no more than the segment holds
            let chunk = chans
                .iter()
                .try_fold(0usize, |acc, (_, i)| {
                    usize::try_from(i.count)
                        .ok()
                        .and_then(|n| n.checked_mul(size_of(i.dtype).unwrap_or(0)))
                        .and_then(|b| acc.checked_add(b))
                })
                .ok_or_else(|| {
                    bad_input(format!(
                        "{file}: segment {seg}: its channels' value counts overflow"
                    ))
                })?;
            if toc & TOC_INTERLEAVED != 0 && chans.windows(2).any(|w| w[0].1.count != w[1].1.count)
            {
                return Err(bad_input(format!(
                    "{file}: segment {seg}: interleaved channels of different lengths"
                )));
            }
            if chans.iter().any(|(_, i)| i.dtype == 0x20) {
                return Err(bad_input(format!(
                    "{file}: segment {seg} holds a string channel among its raw data; not read"
                )));
            }
            let total = end - raw_start;
            if chunk > 0 {
                if total % chunk != 0 {
                    return Err(bad_input(format!(
                        "{file}: segment {seg}: {total} bytes of raw data are not a whole \
                         number of its {chunk}-byte chunks"
                    )));
                }
                c.at = raw_start;
                for _ in 0..total / chunk {
                    if toc & TOC_INTERLEAVED != 0 {
                        let n = chans.first().map_or(0, |(_, i)| i.count);
                        for _ in 0..n {
                            for (p, i) in &chans {
                                let v = c.value(i.dtype)?;
                                if let Some(o) =
                                    objects.get_mut(p).filter(|o| o.unreadable.is_none())
                                {
                                    o.values.push(v);
                                }
                            }
                        }
                    } else {
                        for (p, i) in &chans {
                            for _ in 0..i.count {
                                let v = c.value(i.dtype)?;
                                if let Some(o) =
                                    objects.get_mut(p).filter(|o| o.unreadable.is_none())
                                {
                                    o.values.push(v);
                                }
                            }
                        }
                    }
                }
            }
        }
        at = end;
    }
    if at < bytes.len() {
        return Err(bad_input(if seg == 0 {
            format!("{file}: too short to be a TDMS file")
        } else {
            format!(
                "{file}: {} bytes after segment {seg} are no whole segment (a file cut short?)",
                bytes.len() - at
            )
        }));
    }
    // channels: paths /'group'/'channel'
    let mut named: Vec<(String, String, &Object)> = Vec::new();
    for p in &order {
        let parts = split_path(p);
        if parts.len() == 2 {
            named.push((parts[0].clone(), parts[1].clone(), &objects[p]));
        }
    }
    if named.is_empty() {
        return Err(bad_input(format!("{file}: holds no channel")));
    }
    let mut uses: HashMap<&str, usize> = HashMap::new();
    for (_, ch, _) in &named {
        *uses.entry(ch.as_str()).or_default() += 1;
    }
    let mut channels = Vec::with_capacity(named.len());
    for (g, ch, o) in &named {
        let shared = uses[ch.as_str()] > 1;
        let name = if shared {
            format!("{g}/{ch}")
        } else {
            ch.clone()
        };
        if let Some(what) = &o.unreadable {
            // kept, empty: reading it as a signal names why
            channels.push(Channel {
                name: format!("{name} ({what}, not read)"),
                unit: None,
                delta_x: None,
                x0: None,
                values: Vec::new(),
                x: None,
                start_time: None,
            });
            continue;
        }
        channels.push(Channel {
            name,
            unit: o.unit.clone(),
            delta_x: o.increment,
            x0: o.start,
            values: o.values.clone(),
            x: None,
            start_time: o.start_time,
        });
    }
    Ok(Record {
        segments: vec![channels],
        notes: Vec::new(),
    })
}

/// `/'group'/'channel'` -> `[group, channel]` (`''` inside a name is one `'`).
fn split_path(p: &str) -> Vec<String> {
    let mut out = Vec::new();
    let b: Vec<char> = p.chars().collect();
    let mut i = 0;
    while i < b.len() {
        if b[i] == '/' && b.get(i + 1) == Some(&'\'') {
            i += 2;
            let mut s = String::new();
            while i < b.len() {
                if b[i] == '\'' {
                    if b.get(i + 1) == Some(&'\'') {
                        s.push('\'');
                        i += 2;
                        continue;
                    }
                    i += 1;
                    break;
                }
                s.push(b[i]);
                i += 1;
            }
            out.push(s);
        } else {
            i += 1;
        }
    }
    out
}

/// The bytes of one TDMS segment: the lead-in (`TDSm`, the table of contents `toc`, version
/// 4713, the lengths; little-endian unless `toc` says big-endian) followed by `meta` and
/// `raw` as given. What this crate's tests and the command line's tests give the reader.
pub fn segment(toc: u32, meta: &[u8], raw: &[u8]) -> Vec<u8> {
    let big = toc & TOC_BIG_ENDIAN != 0;
    let u32b = |v: u32| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let u64b = |v: u64| {
        if big {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        }
    };
    let mut out = b"TDSm".to_vec();
    out.extend(toc.to_le_bytes());
    out.extend(u32b(4713));
    out.extend(u64b((meta.len() + raw.len()) as u64));
    out.extend(u64b(meta.len() as u64));
    out.extend(meta);
    out.extend(raw);
    out
}

/// A property of a TDMS object: its name, its type code and its value's bytes as stored.
pub type Property<'a> = (&'a str, u32, Vec<u8>);
/// A TDMS object: its path, its raw-data index (type code, count of values) or none, and its
/// properties.
pub type ObjectBytes<'a> = (&'a str, Option<(u32, u64)>, Vec<Property<'a>>);

/// The bytes of a little-endian TDMS segment with a new object list: `objects`, then `raw`
/// (contiguous). What this crate's tests and the command line's tests give the reader.
pub fn encode_le(objects: &[ObjectBytes<'_>], raw: &[u8]) -> Vec<u8> {
    let s = |m: &mut Vec<u8>, t: &str| {
        m.extend((t.len() as u32).to_le_bytes());
        m.extend(t.as_bytes());
    };
    let mut meta = Vec::new();
    meta.extend((objects.len() as u32).to_le_bytes());
    for (path, index, props) in objects {
        s(&mut meta, path);
        match index {
            Some((t, n)) => {
                meta.extend(20u32.to_le_bytes());
                meta.extend(t.to_le_bytes());
                meta.extend(1u32.to_le_bytes());
                meta.extend(n.to_le_bytes());
            }
            None => meta.extend(0xFFFF_FFFFu32.to_le_bytes()),
        }
        meta.extend((props.len() as u32).to_le_bytes());
        for (name, t, v) in props {
            s(&mut meta, name);
            meta.extend(t.to_le_bytes());
            meta.extend(v);
        }
    }
    segment(TOC_META | TOC_NEW_LIST | TOC_RAW, &meta, raw)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A big-endian segment with interleaved raw data, built by hand: an int32 and a float64
    /// channel, two values each, two chunks.
    fn interleaved_big_endian() -> Vec<u8> {
        let mut meta = Vec::new();
        let s = |m: &mut Vec<u8>, t: &str| {
            m.extend((t.len() as u32).to_be_bytes());
            m.extend(t.as_bytes());
        };
        // a channel: its path, a raw-data index of 20 bytes (type, dimension 1, two values)
        // and the count of its properties
        let channel = |m: &mut Vec<u8>, path: &str, dtype: u32, properties: u32| {
            s(m, path);
            for w in [20, dtype, 1] {
                m.extend(w.to_be_bytes());
            }
            m.extend(2u64.to_be_bytes());
            m.extend(properties.to_be_bytes());
        };
        meta.extend(2u32.to_be_bytes());
        channel(&mut meta, "/'g'/'a'", 3, 0);
        channel(&mut meta, "/'g'/'b''s'", 10, 1);
        s(&mut meta, "wf_increment");
        meta.extend(10u32.to_be_bytes());
        meta.extend(0.5f64.to_be_bytes());
        let mut raw = Vec::new();
        for (a, b) in [(1i32, 1.5f64), (-2, 2.5), (3, 3.5), (-4, 4.5)] {
            raw.extend(a.to_be_bytes());
            raw.extend(b.to_be_bytes());
        }
        let toc = TOC_META | TOC_NEW_LIST | TOC_RAW | TOC_INTERLEAVED | TOC_BIG_ENDIAN;
        segment(toc, &meta, &raw)
    }

    #[test]
    fn interleaved_big_endian_chunks_are_read() {
        let r = parse(&interleaved_big_endian(), "x.tdms").unwrap();
        let a = r.channel("a", "x.tdms").unwrap();
        assert_eq!(a.values, vec![1.0, -2.0, 3.0, -4.0]);
        let b = r.channel("b's", "x.tdms").unwrap();
        assert_eq!(b.values, vec![1.5, 2.5, 3.5, 4.5]);
        assert_eq!(b.rate_hz(), Some(2.0));
        // cut short: named
        let mut cut = interleaved_big_endian();
        cut.truncate(cut.len() - 3);
        let e = format!("{:#}", parse(&cut, "cut.tdms").unwrap_err());
        assert!(e.contains("cut.tdms: segment 1 states"), "{e}");
    }

    /// A timestamp: `secs` since 1904 and `frac` of a second (little endian: fraction first).
    fn stamp(secs: i64, frac: f64) -> Vec<u8> {
        let mut v = ((frac * 18_446_744_073_709_551_616.0) as u64)
            .to_le_bytes()
            .to_vec();
        v.extend(secs.to_le_bytes());
        v
    }

    #[test]
    fn timestamps_as_properties_and_as_a_channel_are_read_not_a_panic() {
        let mut raw = Vec::new();
        for v in [1.0f64, 2.0, 3.0] {
            raw.extend(v.to_le_bytes());
        }
        for k in 0..3 {
            raw.extend(stamp(3_800_000_000 + k, 0.25));
        }
        let f = encode_le(
            &[
                (
                    "/",
                    None,
                    vec![("started", TIMESTAMP, stamp(3_800_000_000, 0.0))],
                ),
                (
                    "/'g'/'force'",
                    Some((10, 3)),
                    vec![
                        ("wf_increment", 10, 0.001f64.to_le_bytes().to_vec()),
                        ("wf_start_time", TIMESTAMP, stamp(3_800_000_000, 0.5)),
                        ("unit_string", 0x20, {
                            let mut v = 1u32.to_le_bytes().to_vec();
                            v.push(b'N');
                            v
                        }),
                    ],
                ),
                ("/'g'/'time'", Some((TIMESTAMP, 3)), vec![]),
            ],
            &raw,
        );
        let r = parse(&f, "wf.tdms").unwrap();
        let c = r.channel("force", "wf.tdms").unwrap();
        assert_eq!(c.values, vec![1.0, 2.0, 3.0]);
        assert_eq!(c.start_time, Some(3_800_000_000.5));
        assert_eq!(c.unit.as_deref(), Some("N"));
        assert!(r.segments[0][1].name.contains("timestamps, not read"));
    }

    #[test]
    fn raw_data_of_an_unknown_type_is_refused_not_read_without_end() {
        // type 0 (void) with 2^36 values beside one float: no size to step over them
        let f = encode_le(
            &[
                ("/'g'/'void'", Some((0, 1 << 36)), vec![]),
                ("/'g'/'x'", Some((10, 1)), vec![]),
            ],
            &1.0f64.to_le_bytes(),
        );
        let e = parse(&f, "void.tdms").unwrap_err().to_string();
        assert!(e.contains("type 0x0"), "{e}");
    }

    #[test]
    fn paths_split_with_quotes_doubled() {
        assert_eq!(split_path("/'g'/'it''s'"), vec!["g", "it's"]);
        assert_eq!(split_path("/'g'"), vec!["g"]);
    }
}

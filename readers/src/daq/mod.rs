//! Records of a data acquisition system (a DAQ): the force of a hammer or shaker and the
//! accelerometers, sampled at their own rate, as channels by name. Readers of the files
//! laboratories write: LabVIEW measurement files ([`lvm`]), NI TDMS files ([`tdms`]) and
//! universal files' dataset 58 ([`uff`]), CSV with an optional time column ([`csv`](mod@csv));
//! and NumPy arrays ([`npy`], pyidi's displacements). Errors name the file, the line and the channel.

pub mod csv;
pub mod lvm;
pub mod npy;
pub mod tdms;
pub mod uff;

/// One channel of a DAQ record.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// Its name in the file.
    pub name: String,
    /// Its unit, when the file states one.
    pub unit: Option<String>,
    /// Sample interval, s (LabVIEW's `Delta_X`), when stated.
    pub delta_x: Option<f64>,
    /// Time of the first sample, s (`X0`), when stated.
    pub x0: Option<f64>,
    /// The samples, in order.
    pub values: Vec<f64>,
    /// The channel's own time column, when the file has one (`X_Columns` `One` or `Multi`).
    pub x: Option<Vec<f64>>,
    /// The absolute time of the first sample, s since 1904-01-01 UTC, when the file states it
    /// (TDMS `wf_start_time`).
    pub start_time: Option<f64>,
}

impl Channel {
    /// The sample rate, Hz, from `delta_x`.
    pub fn rate_hz(&self) -> Option<f64> {
        self.delta_x.filter(|d| *d > 0.0).map(|d| 1.0 / d)
    }
}

/// A DAQ record: its segments (a LabVIEW file may hold several, each with its own header), each
/// a list of channels.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The segments in file order.
    pub segments: Vec<Vec<Channel>>,
    /// What the reader found doubtful but read (a count the header states and the data do
    /// not reach), each line to be shown to the user.
    pub notes: Vec<String>,
}

impl Record {
    /// The channel `name` over the whole record: its segments' samples one after the other
    /// (a continuous acquisition written in segments). Errors name `file`, the channel and
    /// what is wrong: no such channel (the names there are listed), a segment without it, or
    /// segments with different sample intervals.
    pub fn channel(&self, name: &str, file: &str) -> anyhow::Result<Channel> {
        let mut out: Option<Channel> = None;
        for (s, seg) in self.segments.iter().enumerate() {
            if seg.iter().filter(|c| c.name == name).count() > 1 {
                return Err(crate::bad_input(format!(
                    "{file}: two channels are named `{name}`{}: which one is meant cannot be \
                     told; rename one in the file",
                    if self.segments.len() > 1 {
                        format!(" in segment {}", s + 1)
                    } else {
                        String::new()
                    }
                )));
            }
            let Some(c) = seg.iter().find(|c| c.name == name) else {
                let names: Vec<&str> = seg.iter().map(|c| c.name.as_str()).collect();
                return Err(crate::bad_input(format!(
                    "{file}: no channel `{name}`{} (its channels: {})",
                    if self.segments.len() > 1 {
                        format!(" in segment {}", s + 1)
                    } else {
                        String::new()
                    },
                    names.join(", ")
                )));
            };
            match &mut out {
                None => out = Some(c.clone()),
                Some(o) => {
                    if o.delta_x != c.delta_x {
                        return Err(crate::bad_input(format!(
                            "{file}: channel `{name}` has sample interval {:?} s in segment 1 \
                             but {:?} s in segment {}",
                            o.delta_x,
                            c.delta_x,
                            s + 1
                        )));
                    }
                    o.values.extend_from_slice(&c.values);
                    if let (Some(ox), Some(cx)) = (&mut o.x, &c.x) {
                        ox.extend_from_slice(cx);
                    }
                }
            }
        }
        out.ok_or_else(|| crate::bad_input(format!("{file}: holds no data segment")))
    }
}

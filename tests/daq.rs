//! The DAQ readers against their writers' own readings.

use host_harness::daq::{lvm, npy, tdms, uff};
use std::path::Path;

/// Letters and digits only: the two readers decode a non-UTF-8 byte differently (lvm_read drops
/// it, ours reads the file as Latin-1).
fn plain(s: &str) -> String {
    s.chars().filter(char::is_ascii).collect()
}

/// Every file of lvm_read's test set (tests/data/lvm, MIT) read by `daq::lvm` gives, channel by
/// channel and sample by sample, the values lvm_read gives (tests/data/lvm/expected.json,
/// written by scripts/lvm_fixtures.py): comma and point decimals, no, one and several time
/// columns, comments, empty fields.
#[test]
fn labview_files_read_as_lvm_read_reads_them() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/lvm");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let files = expected["files"].as_object().unwrap();
    assert_eq!(files.len(), 6);
    let mut compared = 0;
    for (name, segments) in files {
        let record = lvm::read(&dir.join(name)).unwrap();
        let segments = segments.as_array().unwrap();
        assert_eq!(record.segments.len(), segments.len(), "{name}");
        for (seg, want) in record.segments.iter().zip(segments) {
            let names: Vec<&str> = want["names"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_str().unwrap())
                .collect();
            let columns = want["columns"].as_array().unwrap();
            for (c, col) in columns.iter().enumerate() {
                let col: Vec<Option<f64>> =
                    col.as_array().unwrap().iter().map(|v| v.as_f64()).collect();
                if names[c] == "Comment" {
                    // text, which lvm_read reads as NaN; not a channel
                    assert!(col.iter().all(Option::is_none), "{name}");
                    continue;
                }
                let (values, what) = match names[c] {
                    // a time column: the next channel's
                    "X_Value" => {
                        let ch = seg
                            .iter()
                            .find(|ch| plain(&ch.name) == plain(names[c + 1]))
                            .unwrap();
                        (ch.x.clone().unwrap(), format!("time of {}", ch.name))
                    }
                    other => {
                        let ch = seg
                            .iter()
                            .find(|ch| plain(&ch.name) == plain(other))
                            .unwrap_or_else(|| panic!("{name}: no channel {other}"));
                        (ch.values.clone(), ch.name.clone())
                    }
                };
                // lvm_read fills a channel's missing samples with NaN: ours ends there
                let n = col.iter().take_while(|v| v.is_some()).count();
                assert!(col[n..].iter().all(Option::is_none), "{name} {what}");
                assert_eq!(values.len(), n, "{name} {what}");
                for (a, b) in values.iter().zip(&col) {
                    assert_eq!(Some(*a), *b, "{name} {what}");
                    compared += 1;
                }
            }
        }
    }
    // every sample of every channel and time column of the six files
    assert_eq!(compared, 140);
    // a comma decimal file states its rate: 25.6 kHz
    let short = lvm::read(&dir.join("short.lvm")).unwrap();
    let f = short.channel("Excitation (Trigger)", "short.lvm").unwrap();
    assert_eq!(f.rate_hz(), Some(25_600.0));
    assert_eq!(f.unit.as_deref(), Some("Newtons"));
}

/// Every dataset 58 pyuff wrote (tests/data/uff: time records in ASCII, binary 58b and single
/// precision, a complex FRF on an uneven abscissa; scripts/uff_fixtures.py) read by `daq::uff`
/// gives pyuff's own reading of it, value for value (tests/data/uff/expected.json).
#[test]
fn universal_files_read_as_pyuff_reads_them() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/uff");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let files = expected["files"].as_object().unwrap();
    assert_eq!(files.len(), 4);
    let mut compared = 0;
    let num = |v: &serde_json::Value| -> Vec<f64> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    for (name, sets) in files {
        let got = uff::read_complex(&dir.join(name)).unwrap();
        let sets = sets.as_array().unwrap();
        assert_eq!(got.len(), sets.len(), "{name}");
        for (f, want) in got.iter().zip(sets) {
            let int = |k: &str| want[k].as_i64().unwrap();
            assert_eq!(f.func_type, int("func_type"), "{name}");
            assert_eq!(f.response, (int("rsp_node"), int("rsp_dir")), "{name}");
            assert_eq!(f.reference, (int("ref_node"), int("ref_dir")), "{name}");
            let (x, re, im) = (num(&want["x"]), num(&want["re"]), num(&want["im"]));
            assert_eq!(f.data.len(), re.len(), "{name}");
            let xs: Vec<f64> = match (&f.x, f.even) {
                (Some(x), _) => x.clone(),
                (None, Some((x0, dx))) => (0..f.data.len()).map(|i| x0 + i as f64 * dx).collect(),
                _ => unreachable!(),
            };
            assert_eq!(xs, x, "{name}: abscissa");
            for (k, c) in f.data.iter().enumerate() {
                assert_eq!((c.re, c.im), (re[k], im[k]), "{name} point {k}");
                compared += 1;
            }
        }
    }
    assert_eq!(compared, 3 * 2 * 300 + 7);
    // as channels: the time records by NODE:DIR, the force's unit and rate from the file (its
    // increment is written to six digits, 4.88281e-4 s for 1/2048: 2048.003 Hz)
    let r = uff::read(&dir.join("time_binary.uff")).unwrap();
    let force = r.channel("1:3", "time_binary.uff").unwrap();
    assert_eq!(force.unit.as_deref(), Some("N"));
    assert!((force.rate_hz().unwrap() - 2048.0).abs() < 0.01);
    assert_eq!(r.channel("2:3", "t").unwrap().values.len(), 300);
    let e = format!("{:#}", uff::read(&dir.join("frf_uneven.uff")).unwrap_err());
    assert!(
        e.contains("`3:-2` is complex (function type 4), not a time record"),
        "{e}"
    );
    // a file cut inside its data names the line
    let text = std::fs::read_to_string(dir.join("time_ascii.uff")).unwrap();
    let cut: String = text.lines().take(40).map(|l| format!("{l}\n")).collect();
    let e = format!("{:#}", uff::parse(cut.as_bytes(), "cut.uff").unwrap_err());
    assert!(e.contains("cut.uff: line 40: dataset 58 ends after"), "{e}");
}

/// A TDMS file npTDMS wrote (tests/data/tdms/hammer.tdms: two groups, float64, float32, int16
/// and uint8 channels over three segments, one of them without the second group;
/// scripts/tdms_fixtures.py) read by `daq::tdms` gives npTDMS's own reading, value for value,
/// with the sample interval and unit of its properties; a name two groups share is
/// `group/channel`.
#[test]
fn tdms_files_read_as_nptdms_reads_them() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/tdms");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let want = expected["files"]["hammer.tdms"].as_array().unwrap();
    let r = tdms::read(&dir.join("hammer.tdms")).unwrap();
    let mut compared = 0;
    for c in want {
        let (g, ch) = (c["group"].as_str().unwrap(), c["channel"].as_str().unwrap());
        let name = if ch == "force" {
            format!("{g}/{ch}")
        } else {
            ch.to_string()
        };
        let got = r.channel(&name, "hammer.tdms").unwrap();
        let values: Vec<f64> = c["values"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(got.values, values, "{name}");
        compared += values.len();
        assert_eq!(got.delta_x, c["wf_increment"].as_f64(), "{name}");
        assert_eq!(got.unit.as_deref(), c["unit"].as_str(), "{name}");
    }
    assert_eq!(compared, 400 + 400 + 60 + 60);
    let e = format!("{:#}", r.channel("force", "hammer.tdms").unwrap_err());
    assert!(e.contains("no channel `force`"), "{e}");
    let e = format!(
        "{:#}",
        tdms::parse(b"TDSm\x0e\0\0\0", "cut.tdms").unwrap_err()
    );
    assert!(e.contains("cut.tdms"), "{e}");
}

/// NumPy arrays NumPy wrote (tests/data/npy: pyidi's displacement shape (3, 40, 2) in float64, a
/// big-endian float32 array in Fortran order, int16; scripts/npy_fixtures.py) read by
/// `daq::npy` give NumPy's values, element for element, as the channels the shapes name.
#[test]
fn npy_arrays_read_as_numpy_reads_them() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/npy");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("expected.json")).unwrap()).unwrap();
    let mut compared = 0;
    for (name, want) in expected.as_object().unwrap() {
        let shape: Vec<usize> = want["shape"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_u64().unwrap() as usize)
            .collect();
        let values: Vec<f64> = want["values"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let r = npy::read(&dir.join(name)).unwrap();
        let ch = &r.segments[0];
        // C order of the expected values: element [p][i][k] at (p * n + i) * 2 + k
        match shape.as_slice() {
            [n] => {
                assert_eq!(ch[0].values.len(), *n, "{name}");
                assert_eq!(ch[0].values, values, "{name}");
            }
            [p, n] => {
                for j in 0..*p {
                    assert_eq!(ch[j].name, format!("point {}", j + 1));
                    assert_eq!(ch[j].values, values[j * n..(j + 1) * n], "{name}");
                }
            }
            [p, n, 2] => {
                for j in 0..*p {
                    for (k, axis) in ["y", "x"].iter().enumerate() {
                        let c = &ch[2 * j + k];
                        assert_eq!(c.name, format!("point {} {axis}", j + 1));
                        let want: Vec<f64> = (0..*n).map(|i| values[(j * n + i) * 2 + k]).collect();
                        assert_eq!(c.values, want, "{name}");
                    }
                }
            }
            other => panic!("{other:?}"),
        }
        compared += values.len();
    }
    assert_eq!(compared, 240 + 50 + 30);
    let e = format!("{:#}", npy::parse(b"hello world!", "x.npy").unwrap_err());
    assert!(e.contains("x.npy: not a NumPy .npy file"), "{e}");
}

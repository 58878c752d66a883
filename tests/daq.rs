//! The DAQ readers against their writers' own readings.

use host_harness::daq::lvm;
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

//! The host's file readers on arbitrary bytes: the frame loader (PNG, TIFF, JPEG, multi-page
//! TIFF), the camera files' headers and frames (Phantom `.cine`; Photron `.cih` with a 16-byte
//! `.mraw` beside it), the accelerometer CSV reader and the DAQ readers (TDMS, LabVIEW `.lvm`,
//! universal file 58, NumPy `.npy`, CSV) must return an error, never panic nor
//! allocate what a header claims before checking it against the file (the seeds `seed_*` are
//! a small valid cine, cih and JPEG).
#![no_main]
use host_harness::frames::{FrameRange, FrameSource, GreyFrame};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("vibcam-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    for name in ["f.png", "f.tif", "f.jpg"] {
        let p = dir.join(name);
        if std::fs::write(&p, data).is_ok() {
            let _ = host_harness::frames::load_frame(&p);
            let _ = host_harness::frames::for_each_tiff_page(&p, |_, _| Ok(()));
        }
    }
    let _ = host_harness::frames::files::jpeg_truncation(data);
    // camera files: the header, then every frame (a range, as --frame-range reads it)
    let cine = dir.join("f.cine");
    let cih = dir.join("f.cih");
    if std::fs::write(&cine, data).is_ok()
        && std::fs::write(&cih, data).is_ok()
        && std::fs::write(dir.join("f.mraw"), [7u8; 16]).is_ok()
    {
        for source in [FrameSource::Cine(cine), FrameSource::Photron(cih)] {
            let _ = source.recorded_rate();
            let _ = source.for_each(100.0, |_, f: &GreyFrame| {
                std::hint::black_box(f.dimensions());
                Ok(())
            });
            let range = FrameRange {
                first: 2,
                last: Some(3),
            };
            if let Ok(s) = source.ranged(Some(range)) {
                let _ = s.recorded_rate();
                let _ = s.for_each(100.0, |_, _| Ok(()));
            }
        }
    }
    let p = dir.join("a.csv");
    if std::fs::write(&p, data).is_ok() {
        let _ = host_harness::analysis::load_accel(&p, 2048.0, "base_acc", "tip_acc", Some("t_s"));
    }
    // the DAQ readers on the bytes as they are, every channel then taken by name
    use host_harness::daq;
    let name = "fuzz";
    let text = String::from_utf8_lossy(data);
    for record in [
        daq::tdms::parse(data, name),
        daq::lvm::parse(&text, name),
        daq::uff::parse(data, name).map(|_| daq::Record {
            segments: Vec::new(),
            notes: Vec::new(),
        }),
        daq::npy::parse(data, name),
        daq::csv::parse(data, name, Some("t_s")),
        daq::csv::parse(data, name, None),
    ]
    .into_iter()
    .flatten()
    {
        for seg in &record.segments {
            for c in seg {
                let _ = record.channel(&c.name, name);
            }
        }
    }
});

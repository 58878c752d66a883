//! The host's file readers on arbitrary bytes: the frame loader (PNG, TIFF, multi-page TIFF)
//! and the accelerometer CSV reader must return an error, never panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir().join(format!("vibcam-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    for name in ["f.png", "f.tif"] {
        let p = dir.join(name);
        if std::fs::write(&p, data).is_ok() {
            let _ = host_harness::frames::load_frame(&p);
            let _ = host_harness::frames::for_each_tiff_page(&p, |_, _| Ok(()));
        }
    }
    let p = dir.join("a.csv");
    if std::fs::write(&p, data).is_ok() {
        let _ = host_harness::analysis::load_accel(&p, 2048.0, "base_acc", "tip_acc", Some("t_s"));
    }
});

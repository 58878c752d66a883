//! The committed C header is what cbindgen makes of firmware-core-ffi today: a changed ABI must
//! come with its header. Run by `firmware-core-ffi/c/run.sh` (CI's C ABI step):
//! `cargo run --manifest-path firmware-core-ffi/header-check/Cargo.toml`; with `VIBCAM_BLESS=1`
//! it rewrites the header. Exits non-zero (a panic naming what differs) when the header is stale.

fn main() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let config = cbindgen::Config::from_file(format!("{dir}/cbindgen.toml")).unwrap();
    let mut generated = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen reads the crate")
        .write(&mut generated);
    let generated = String::from_utf8(generated).unwrap();
    let path = format!("{dir}/include/vibcam.h");
    if std::env::var_os("VIBCAM_BLESS").is_some() {
        std::fs::write(&path, &generated).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == generated,
        "{path} is not what cbindgen generates from the crate: rerun with VIBCAM_BLESS=1"
    );
    // the declarations C firmware relies on
    for name in [
        "vc_centroid_u8",
        "vc_centroid_u16",
        "vc_tracker_init",
        "vc_tracker_push_row_u8",
        "vc_tracker_finish_frame",
        "vc_tracker_window",
        "vc_multi_init",
        "vc_multi_push_row_u8",
        "vc_multi_targets",
        "vc_multi_next_frame",
        "vc_fdd4_init",
        "vc_fdd4_push",
        "vc_fdd4_line",
        "vc_fdd4_peaks",
        "vc_pipeline_init",
        "vc_pipeline_push_adc",
        "vc_pipeline_push_frame",
        "vc_pipeline_h1",
        "vc_pipeline_peak",
        "VC_TRACKER_WORDS",
        "VC_PIPELINE_WORDS",
    ] {
        assert!(generated.contains(name), "{name} missing from the header");
    }
    println!("{path}: current");
}

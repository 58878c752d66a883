//! The committed C header is what cbindgen makes of the crate today: a changed ABI must come
//! with its header (`VIBCAM_BLESS=1 cargo test -p firmware-core-ffi --test header` rewrites it).

#[test]
fn the_committed_header_is_current() {
    let dir = env!("CARGO_MANIFEST_DIR");
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
}

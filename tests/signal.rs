//! End-to-end tests of the signal commands (`frf`, `upsample`): CSV inputs written to a
//! temporary directory, outputs checked against closed forms computed here.

mod frf {
    //! `host-harness frf`: H1 of a known gain and of a known resonator, peaks in bands, and the
    //! bad-input cases (exit code 2, message naming row and column).

    use crate::util::assert_contains;
    use crate::util::{harness, words};
    use host_harness::testing::uniform_noise as noise;
    use std::f64::consts::PI;
    use std::path::{Path, PathBuf};

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn csv_of(cols: &[(&str, &[f64])]) -> String {
        let mut s = cols.iter().map(|c| c.0).collect::<Vec<_>>().join(",") + "\n";
        for i in 0..cols[0].1.len() {
            let row: Vec<String> = cols.iter().map(|c| format!("{:e}", c.1[i])).collect();
            s += &row.join(",");
            s += "\n";
        }
        s
    }

    /// Rows of the output CSV as numbers, after checking the header.
    fn read_out(path: &Path) -> Vec<[f64; 5]> {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("freq_hz,h1_re,h1_im,h1_abs,coherence"));
        lines
            .map(|l| {
                let v: Vec<f64> = l.split(',').map(|c| c.parse().unwrap()).collect();
                [v[0], v[1], v[2], v[3], v[4]]
            })
            .collect()
    }

    /// `host-harness frf --input input --x x --y y --out out` and `extra`: (exit code, stdout,
    /// stderr).
    fn run(
        input: &Path,
        (x, y): (&str, &str),
        out: &Path,
        extra: &[&str],
    ) -> (i32, String, String) {
        let mut args = words(
            "frf --input {} --x {} --y {}",
            &[input.to_str().unwrap(), x, y],
        );
        args.extend_from_slice(&["--out", out.to_str().unwrap()]);
        args.extend_from_slice(extra);
        let out = harness(&args);
        (
            out.status.code().unwrap_or(-1),
            String::from_utf8_lossy(&out.stdout).into_owned(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    }

    #[test]
    fn known_gain_with_explicit_settings() {
        let dir = tempfile::tempdir().unwrap();
        let x = noise(1, 3000);
        // an offset (removed by the detrend) and a gain of -1.75 in other units
        let y: Vec<f64> = x.iter().map(|v| -1.75e-3 * v + 4.0).collect();
        let input = write(
            dir.path(),
            "in.csv",
            &csv_of(&[("force", &x), ("disp", &y)]),
        );
        let out = dir.path().join("frf.csv");
        let settings = [
            "--fs",
            "50",
            "--window",
            "hamming",
            "--nperseg",
            "400",
            "--noverlap",
            "100",
            "--nfft",
            "1000",
        ];
        let (code, stdout, stderr) = run(&input, ("force", "disp"), &out, &settings);
        assert_eq!(code, 0, "{stderr}");
        assert!(stdout.is_empty(), "no --bands, nothing on stdout: {stdout}");
        // scipy's segment count: (3000 - 400) / 300 + 1 = 9
        assert!(stderr.contains("9 segment"), "{stderr}");
        let rows = read_out(&out);
        assert_eq!(rows.len(), 501);
        for (k, r) in rows.iter().enumerate() {
            assert!(
                (r[0] - k as f64 * 0.05).abs() < 1e-9,
                "bin {k}: {} Hz",
                r[0]
            );
            if k == 0 {
                continue; // the detrended DC bin holds only the window's leftovers
            }
            assert!((r[1] / -1.75e-3 - 1.0).abs() < 1e-5, "bin {k}: {r:?}");
            assert!(r[2].abs() < 1e-5 * 1.75e-3, "bin {k}: {r:?}");
            assert!((r[3] / 1.75e-3 - 1.0).abs() < 1e-5, "bin {k}: {r:?}");
            assert!((r[4] - 1.0).abs() < 1e-5, "bin {k}: {r:?}");
        }
    }

    #[test]
    fn scipy_defaults() {
        let dir = tempfile::tempdir().unwrap();
        let x = noise(2, 1000);
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
        let input = write(dir.path(), "in.csv", &csv_of(&[("a", &x), ("b", &y)]));
        let out = dir.path().join("frf.csv");
        let (code, _, stderr) = run(&input, ("a", "b"), &out, &["--fs", "256"]);
        assert_eq!(code, 0, "{stderr}");
        // nperseg 256, noverlap 128, nfft 256: (1000 - 256) / 128 + 1 = 6 segments, 129 bins
        assert_contains(
            &stderr,
            &["6 segment", "nperseg 256, noverlap 128, nfft 256"],
        );
        let rows = read_out(&out);
        assert_eq!(rows.len(), 129);
        assert!((rows[1][0] - 1.0).abs() < 1e-12);
        assert!(rows[1..].iter().all(|r| (r[1] - 2.0).abs() < 2e-5));
    }

    /// `y` = `x` through `y[n] = x[n] + a1 y[n-1] + a2 y[n-2]`; its exact frequency response.
    fn resonator(x: &[f64], f0: f64, r: f64, fs: f64) -> (Vec<f64>, impl Fn(f64) -> (f64, f64)) {
        let (a1, a2) = (2.0 * r * (2.0 * PI * f0 / fs).cos(), -r * r);
        let (mut y1, mut y2) = (0.0, 0.0);
        let y = x
            .iter()
            .map(|&v| {
                let o = v + a1 * y1 + a2 * y2;
                y2 = y1;
                y1 = o;
                o
            })
            .collect();
        let h = move |f: f64| {
            let w = 2.0 * PI * f / fs;
            // 1 / (1 - a1 e^{-iw} - a2 e^{-2iw})
            let re = 1.0 - a1 * w.cos() - a2 * (2.0 * w).cos();
            let im = a1 * w.sin() + a2 * (2.0 * w).sin();
            let d = re * re + im * im;
            (re / d, -im / d)
        };
        (y, h)
    }

    #[test]
    fn bands_print_the_resonance_peaks() {
        let dir = tempfile::tempdir().unwrap();
        let fs = 100.0;
        let x = noise(3, 40_000);
        let (y1, h1) = resonator(&x, 8.0, 0.96, fs);
        let (y2, h2) = resonator(&x, 31.0, 0.95, fs);
        let y: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a + b).collect();
        let h = |f: f64| {
            let (a, b) = (h1(f), h2(f));
            (a.0 + b.0, a.1 + b.1)
        };
        let input = write(dir.path(), "in.csv", &csv_of(&[("x", &x), ("y", &y)]));
        let out = dir.path().join("frf.csv");
        let settings = ["--fs", "100", "--nperseg", "1000", "--bands", "5-15,25-40"];
        let (code, stdout, stderr) = run(&input, ("x", "y"), &out, &settings);
        assert_eq!(code, 0, "{stderr}");
        let lines: Vec<&str> = stdout.lines().collect();
        assert_eq!(lines.len(), 3, "{stdout}");
        assert_eq!(lines[0], "band,f_hz,amplitude");
        let df = 0.1;
        for (line, (lo, hi), label) in [
            (lines[1], (50usize, 150usize), "5-15"),
            (lines[2], (250, 400), "25-40"),
        ] {
            let f: Vec<&str> = line.split(',').collect();
            assert_eq!(f[0], label);
            let (got_f, got_a): (f64, f64) = (f[1].parse().unwrap(), f[2].parse().unwrap());
            // closed form: bin of the largest |Im H| in the band, and |H| there
            let k = (lo..=hi)
                .max_by(|&a, &b| {
                    h(a as f64 * df)
                        .1
                        .abs()
                        .total_cmp(&h(b as f64 * df).1.abs())
                })
                .unwrap();
            assert!(
                (got_f - k as f64 * df).abs() <= df + 1e-6,
                "{label}: {got_f} vs bin {k}"
            );
            let (re, im) = h(got_f);
            let want = (re * re + im * im).sqrt();
            assert!(
                (got_a / want - 1.0).abs() < 0.05,
                "{label}: {got_a} vs {want}"
            );
            // the output file holds the same amplitude at that frequency
            let rows = read_out(&out);
            let row = rows.iter().find(|r| (r[0] - got_f).abs() < 1e-6).unwrap();
            assert!((row[3] - got_a).abs() <= 1e-6 * got_a);
        }
    }

    /// Runs frf on `text` and returns (exit code, stderr).
    fn run_bad(text: &str, extra: &[&str]) -> (i32, String) {
        let dir = tempfile::tempdir().unwrap();
        let input = write(dir.path(), "bad.csv", text);
        let out = dir.path().join("o.csv");
        let mut args = Vec::new();
        // defaults unless the case sets them itself
        for (flag, value) in [("--fs", "10"), ("--nperseg", "2")] {
            if !extra.contains(&flag) {
                args.extend_from_slice(&[flag, value]);
            }
        }
        args.extend_from_slice(extra);
        let (code, _, stderr) = run(&input, ("x", "y"), &out, &args);
        assert!(!out.exists() || code == 0, "no output file on error");
        (code, stderr)
    }

    #[test]
    fn bad_csv_names_row_and_column() {
        let ok = "x,y\n1,2\n3,4\n5,6\n7,8\n";
        assert_eq!(run_bad(ok, &[]).0, 0);
        let cases: [(&str, &[&str]); 5] = [
            ("x,z\n1,2\n3,4\n", &["no column named `y`", "x, z"]),
            ("x,y\n1,2\n3,abc\n5,6\n", &["row 3", "`y`", "abc"]),
            ("x,y\n1,2\nNaN,4\n5,6\n", &["row 3", "`x`", "finite"]),
            ("x,y\n1,2\n3,4\n5\n7,8\n", &["row 4", "`y`", "missing"]),
            ("x,y\n1,2\n3,\n", &["row 3", "`y`"]),
        ];
        for (csv, needles) in cases {
            let (code, err) = run_bad(csv, &[]);
            assert_eq!(code, 2, "{err}");
            assert!(
                needles.iter().all(|n| err.contains(n)),
                "{needles:?}: {err}"
            );
        }
    }

    #[test]
    fn bad_settings_exit_2() {
        let ok = "x,y\n1,2\n3,4\n5,6\n7,8\n";
        for (extra, needle) in [
            (&["--noverlap", "2"][..], "noverlap"),
            (&["--nfft", "1"][..], "nfft"),
            (&["--nperseg", "5"][..], "record length (4 samples)"),
            (&["--nperseg", "0"][..], "nperseg"),
            (&["--fs", "0"][..], "--fs"),
            (&["--bands", "1-x"][..], "--bands"),
            // above the Nyquist frequency (5 Hz): the rule every band of every command passes
            (
                &["--bands", "8-9"][..],
                "--bands 8-9: reaches above the record's Nyquist",
            ),
        ] {
            let (code, err) = run_bad(ok, extra);
            assert_eq!(code, 2, "{extra:?}: {err}");
            assert!(err.contains(needle), "{extra:?}: {err}");
        }
        // a capacity the build does not have is a clear error, not a crash
        let (code, err) = run_bad(ok, &["--nperseg", "4", "--nfft", "70000"]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains("65536"), "{err}");
    }
}

mod upsample {
    //! `host-harness upsample`: a band-limited sinusoid matches its analytic values; bad input
    //! exits with code 2 naming the row, column or rates.

    use crate::util::{harness, words};
    use std::path::Path;
    use std::process::Output;

    /// `host-harness upsample --input input --col col --from 120 --to 2048 --out out`.
    fn upsample(input: &Path, col: &str, out: &Path) -> Output {
        harness(&words(
            "upsample --input {} --col {} --from 120 --to 2048 --out {}",
            &[input.to_str().unwrap(), col, out.to_str().unwrap()],
        ))
    }

    /// A 7 Hz sinusoid of amplitude `amp` (whole cycles in 1 s at 120 fps) upsampled to
    /// 2048 Hz matches `amp sin(2 pi 7 t)` within `1e-4 amp` at every output sample.
    fn sinusoid_matches_the_analytic_values(amp: f64) {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("x.csv");
        let out = dir.path().join("y.csv");
        let mut text = String::from("t,x\n");
        let f = 7.0;
        for i in 0..120 {
            let t = i as f64 / 120.0;
            text.push_str(&format!(
                "{t},{}\n",
                amp * (std::f64::consts::TAU * f * t).sin()
            ));
        }
        std::fs::write(&input, text).unwrap();
        let o = upsample(&input, "x", &out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(&out).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("t_s,value"));
        let rows: Vec<(f64, f64)> = lines
            .map(|l| {
                let (a, b) = l.split_once(',').unwrap();
                (a.parse().unwrap(), b.parse().unwrap())
            })
            .collect();
        assert_eq!(rows.len(), 2048);
        for (t, v) in rows {
            let want = amp * (std::f64::consts::TAU * f * t).sin();
            assert!((v - want).abs() < 1e-4 * amp, "t = {t}: {v} vs {want}");
        }
    }

    #[test]
    fn sinusoid_120_to_2048_matches_the_analytic_values() {
        sinusoid_matches_the_analytic_values(1.0);
    }

    /// Values whose f32 transform would overflow (1e37: the sums reach 1e39 > f32::MAX) are
    /// scaled into range, not written as NaN.
    #[test]
    fn values_beyond_the_f32_range_are_scaled_not_nan() {
        sinusoid_matches_the_analytic_values(1e37);
    }

    #[test]
    fn bad_input_exits_2_with_a_precise_message() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("y.csv");
        let cases: [(&str, &str, &[&str]); 4] = [
            ("x\n1\nfoo\n", "x", &["row 3", "`x`"]),
            ("x\n1\nNaN\n", "x", &["row 3", "not a finite"]),
            ("x\n1\n2\n", "y", &["no column named `y`"]),
            ("x\n1\n2\n3\n", "x", &["integer number of samples"]),
        ];
        let o = harness(&words(
            "upsample --input x.csv --col x --from 0 --to 2048 --out y.csv",
            &[],
        ));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("--from: must be a positive sample rate in Hz, got 0"),
            "{err}"
        );
        for (i, (csv, col, needles)) in cases.iter().enumerate() {
            let input = dir.path().join(format!("in{i}.csv"));
            std::fs::write(&input, csv).unwrap();
            let o = upsample(&input, col, &out);
            assert_eq!(o.status.code(), Some(2), "case {i}");
            let err = String::from_utf8_lossy(&o.stderr);
            for n in *needles {
                assert!(err.contains(n), "case {i}: `{n}` not in {err}");
            }
        }
    }
}

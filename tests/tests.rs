//! Workspace-level end-to-end tests: one test binary with a module per area, driving the
//! `host-harness` binary and both crates together.

#[allow(dead_code)]
mod util;

mod adversarial;
mod analyze;
mod centroid;
mod daq;
mod defects;
mod ema;
mod field;
mod formats;
mod golden;
mod hostile;
mod modal;
mod plan;
mod robustness;
mod settings;
mod signal;
mod study;
mod targets;
mod trackers;
mod view;

#[test]
fn help_lists_every_subcommand() {
    let out = util::harness(&["--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    // the first word of each line of the "Commands:" section, so that a word in a description
    // cannot stand in for a missing subcommand
    let listed: Vec<&str> = text
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    for cmd in [
        "study",
        "merge",
        "centroid",
        "frf",
        "upsample",
        "analyze",
        "render",
        "plan",
        "modal",
        "simulate-field",
    ] {
        assert!(
            listed.contains(&cmd),
            "--help lists {listed:?}, not `{cmd}`"
        );
    }
}

/// Every tracked text file of the workspace below `dir` with one of `exts`.
fn workspace_files(exts: &[&str]) -> Vec<std::path::PathBuf> {
    fn walk(d: &std::path::Path, exts: &[&str], out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(d).unwrap().flatten() {
            let p = e.path();
            let name = e.file_name().to_string_lossy().into_owned();
            if p.is_dir() {
                if !name.starts_with('.') && name != "target" && name != "corpus" {
                    walk(&p, exts, out);
                }
            } else if exts.iter().any(|x| name.ends_with(x)) {
                out.push(p);
            }
        }
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut v = Vec::new();
    walk(&root, exts, &mut v);
    v
}

#[test]
fn the_docs_stand_on_their_own_and_the_readme_is_a_front_page() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(
        lines <= 250,
        "README.md has {lines} lines; measured tables go to docs/"
    );
    // users have neither the design document nor the tracker: cite docs/method.md sections
    let issue = |l: &str| {
        let l = l.to_ascii_lowercase();
        ["issue ", "issues "].iter().any(|w| {
            l.match_indices(w).any(|(i, _)| {
                l[i + w.len()..]
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_ascii_digit() || c == '#')
            })
        })
    };
    let mut found = Vec::new();
    for p in workspace_files(&[".md", ".rs", ".toml", ".py", ".sh"]) {
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        for (n, l) in text.lines().enumerate() {
            // this test names what it looks for
            if p.ends_with("tests/tests.rs") {
                break;
            }
            if l.contains("SPEC") || issue(l) {
                found.push(format!("{}:{}: {l}", p.display(), n + 1));
            }
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// The workspace's crates by layer, bottom first: a crate may depend on crates of the layers
/// below its own, never on one of its own layer or above (ARCHITECTURE.md draws them).
const LAYERS: [&[&str]; 8] = [
    &["firmware-core"],
    &["vibcam-readers", "firmware-core-ffi", "vibcam-fft"],
    &["vibcam-common"],
    &["vibcam-chain", "vibcam-model", "vibcam-report"],
    &["vibcam-identify", "vibcam-track", "vibcam-sim"],
    &["vibcam-cli"],
    &["host-harness"],
    &["vibcam-python"],
];

/// Cargo's own dependency graph (`cargo metadata`) between the workspace's crates: every crate
/// in a layer, every dependency (normal, build or dev) on a lower layer; so no cycle.
#[test]
fn the_crates_depend_only_on_layers_below_theirs() {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let layer = |name: &str| LAYERS.iter().position(|l| l.contains(&name));
    let mut bad = Vec::new();
    let packages = meta["packages"].as_array().unwrap();
    let names: Vec<&str> = packages
        .iter()
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    for p in packages {
        let name = p["name"].as_str().unwrap();
        let Some(own) = layer(name) else {
            bad.push(format!("{name} is in no layer"));
            continue;
        };
        for d in p["dependencies"].as_array().unwrap() {
            let dep = d["name"].as_str().unwrap();
            if !names.contains(&dep) {
                continue;
            }
            if layer(dep).is_none_or(|l| l >= own) {
                bad.push(format!(
                    "{name} depends on {dep}, not on a layer below its own"
                ));
            }
        }
    }
    assert!(names.len() >= 5, "{names:?}");
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// Each host-side crate's rooms (its top-level modules) in the order data flows; a module may
/// use its own room and those before it, never one after it (in host-harness, `cli` calls them
/// all). ARCHITECTURE.md explains each order. host-harness's first room holds the crates below
/// it, re-exported under their module names.
const ROOMS: [(&str, &[&[&str]]); 7] = [
    ("common", &[&["stats"], &["uncertainty"]]),
    (
        "report",
        &[&["outdir", "provenance", "pdf"], &["export"], &["plots"]],
    ),
    ("identify", &[&["modal"], &["oma"], &["ema"]]),
    (
        "track",
        &[
            &["tracks"],
            &["verify"],
            &["choose"],
            &["shared_motion"],
            &["points"],
            &["region"],
            &["follow"],
            &["camera_motion"],
            &["view"],
            &["magnify"],
        ],
    ),
    (
        "sim",
        &[
            &["imaging"],
            &["study"],
            &["recording"],
            &["plan"],
            &["calibrate"],
        ],
    ),
    ("cli", &[&["flags", "process"], &["study", "merge"]]),
    (
        "host-harness",
        &[
            &[
                "frames",
                "daq",
                "csvio",
                "bad_input",
                "BadInput",
                "stats",
                "uncertainty",
                "testing",
                "failpoint",
                "lost_frames",
                "setting",
                "geometry",
                "chain",
                "model",
                "outdir",
                "export",
                "plots",
                "imaging",
                "study",
                "recording",
                "plan",
                "calibrate",
            ],
            &["analysis"],
            &["jobs"],
        ],
    ),
];

/// The rooms a source text names as `crate::ROOM` (also inside `use crate::{a, b::c}`),
/// comments left out.
fn crate_paths(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            rest = &rest[i + "crate::".len()..];
            if let Some(group) = rest.strip_prefix('{') {
                let end = group.find('}').unwrap_or(group.len());
                for item in group[..end].split(',') {
                    let name: String = item
                        .trim()
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    out.push(name);
                }
            } else {
                out.push(
                    rest.chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect(),
                );
            }
        }
    }
    out
}

#[test]
fn no_room_of_a_crate_uses_one_after_it() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut bad = Vec::new();
    let mut unknown = Vec::new();
    let mut checked = 0;
    for (krate, rooms) in ROOMS {
        let src = root.join(krate).join("src").canonicalize().unwrap();
        let rank = |room: &str| rooms.iter().position(|r| r.contains(&room));
        for p in workspace_files(&[".rs"]) {
            let p = p.canonicalize().unwrap();
            let Ok(rel) = p.strip_prefix(&src) else {
                continue;
            };
            checked += 1;
            let room = rel
                .components()
                .next()
                .unwrap()
                .as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string();
            if room == "lib" || room == "main" || room == "cli" {
                continue;
            }
            let Some(own) = rank(&room) else {
                // a crate whose rooms do not all stand in an order (common's) lists only those
                // that use one another
                if krate != "common" {
                    unknown.push(format!("{krate}: {room}"));
                }
                continue;
            };
            let text = std::fs::read_to_string(&p).unwrap();
            for used in crate_paths(&text) {
                match rank(&used) {
                    Some(r) if r > own => {
                        bad.push(format!("{krate}/src/{}: crate::{used}", rel.display()))
                    }
                    _ => {}
                }
            }
        }
    }
    assert!(checked > 100, "only {checked} source files found");
    unknown.sort();
    unknown.dedup();
    assert!(unknown.is_empty(), "rooms not in ROOMS: {unknown:?}");
    bad.sort();
    bad.dedup();
    assert!(bad.is_empty(), "uses of a later room:\n{}", bad.join("\n"));
}

/// `cli/` (and the `vibcam-cli` crate) parses flags into a checked request and calls the
/// library: no file is written, staged or formatted there (every writer is in `export/`, every
/// output directory is staged by the library call).
#[test]
fn the_cli_writes_no_file_itself() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let forbidden = [
        "std::fs",
        "fs::write",
        "File::create",
        "OpenOptions",
        "write_atomic",
        "csv::Writer",
        "Staged",
    ];
    let mut files = vec![src.join("cli.rs")];
    // and the command line's common ground below host-harness (the study's binary)
    let common = src.join("../../cli/src");
    for dir in [src.join("cli"), common] {
        for e in std::fs::read_dir(dir).unwrap() {
            files.push(e.unwrap().path());
        }
    }
    assert!(files.len() > 10, "only {} cli files", files.len());
    let mut bad = Vec::new();
    for p in files {
        let text = std::fs::read_to_string(&p).unwrap();
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for f in forbidden {
                if code.contains(f) {
                    bad.push(format!("{}:{}: {f}", p.display(), i + 1));
                }
            }
        }
    }
    assert!(
        bad.is_empty(),
        "cli/ writes files itself:\n{}",
        bad.join("\n")
    );
}

/// The Python extension is built (by `pip install ./python`) with the features the workspace's
/// tests resolve for every package they share, so that CI's wheel reuses the host-harness the
/// test step compiled (the other half: the same profile settings, the build scripts' debug info
/// in the workspace's Cargo.toml). A dev-dependency that turns on a new feature of a shared
/// crate (serde, syn, either, ...) would make the wheel build host-harness and its
/// dependencies once more, minutes on two cores: python/Cargo.toml then names that feature too.
#[test]
fn the_python_wheel_reuses_the_workspace_build() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let tree = |args: &[&str]| -> std::collections::BTreeSet<String> {
        let out = std::process::Command::new(env!("CARGO"))
            .current_dir(&root)
            .args(["tree", "--locked", "--prefix", "none", "-f", "{p} [{f}]"])
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "cargo tree {args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .map(|l| l.trim_end_matches(" (*)").to_string())
            .collect()
    };
    let workspace = tree(&["--workspace"]);
    let wheel = tree(&["-p", "vibcam-python", "-e", "normal,build"]);
    assert!(wheel.len() > 50, "{} packages in the wheel", wheel.len());
    // host-harness itself is built without its command line for the wheel (no clap in the
    // Python package's tree): its library is compiled once more there, nothing else
    let other: Vec<_> = wheel
        .difference(&workspace)
        .filter(|p| !p.starts_with("host-harness v"))
        .collect();
    assert!(
        other.is_empty(),
        "the wheel builds these with features the tests do not: {other:?}"
    );
    assert!(
        !wheel.iter().any(|p| p.starts_with("clap")),
        "clap is in the Python package's tree"
    );
}

/// The folders of the host side's crates (each with a `src/`), bottom layer first.
const HOST_CRATES: [&str; 9] = [
    "readers",
    "common",
    "chain",
    "model",
    "report",
    "identify",
    "track",
    "sim",
    "host-harness",
];

/// No two files of a host-side crate use each other, directly or through others: every
/// `crate::a::b`, `super::x` and `self::y` path (also inside `use a::{b, c::d}`, test modules and
/// comments left out) is resolved to the file of the longest module it names, and the graph of
/// files has no circle. (A circle makes a file impossible to read without the other.)
#[test]
fn no_two_files_of_a_crate_use_each_other() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut circles = Vec::new();
    let mut files = 0;
    for krate in HOST_CRATES {
        let src = root.join(krate).join("src").canonicalize().unwrap();
        let (n, c) = file_circles(&src);
        assert!(n > 1, "{krate}: only {n} files");
        files += n;
        circles.extend(c.into_iter().map(|c| format!("{krate}: {c}")));
    }
    assert!(files > 100, "only {files} files");
    assert!(
        circles.is_empty(),
        "files that use each other:\n{}",
        circles.join("\n")
    );
}

/// The number of source files under `src` and the circles between them (each as `a -> b -> a`).
fn file_circles(src: &std::path::Path) -> (usize, Vec<String>) {
    use std::collections::{BTreeMap, BTreeSet};
    // module path -> file
    let mut files: BTreeMap<Vec<String>, String> = BTreeMap::new();
    for p in workspace_files(&[".rs"]) {
        let p = p.canonicalize().unwrap();
        let Ok(rel) = p.strip_prefix(src) else {
            continue;
        };
        let mut m: Vec<String> = rel
            .with_extension("")
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        if m.last()
            .is_some_and(|l| l == "mod" || l == "lib" || l == "main")
        {
            m.pop();
        }
        files.insert(m, rel.display().to_string());
    }
    let resolve = |parts: &[String]| {
        (1..=parts.len())
            .rev()
            .find_map(|k| files.get(&parts[..k]).cloned())
    };
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (module, file) in &files {
        let text = std::fs::read_to_string(src.join(file)).unwrap();
        let text = text.split("#[cfg(test)]").next().unwrap_or("");
        let mut deps = BTreeSet::new();
        for line in text.lines() {
            let code = line.split("//").next().unwrap_or("");
            for head in ["crate::", "super::", "self::"] {
                let mut rest = code;
                while let Some(i) = rest.find(head) {
                    // `crate::` inside a longer word (`my_crate::`) is no path of ours
                    let before = rest[..i].chars().last();
                    rest = &rest[i + head.len()..];
                    if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                        continue;
                    }
                    let mut base: Vec<String> = match head {
                        "crate::" => Vec::new(),
                        // the parent module: one up from the file's module (a mod.rs is its
                        // folder's module, so one up is the folder's parent too)
                        "super::" => module[..module.len().saturating_sub(1)].to_vec(),
                        _ => module.clone(),
                    };
                    let path: String = rest
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':')
                        .collect();
                    let mut parts: Vec<String> = path
                        .split("::")
                        .filter(|s| !s.is_empty())
                        .map(String::from)
                        .collect();
                    while parts.first().is_some_and(|p| p == "super") {
                        parts.remove(0);
                        base.pop();
                    }
                    let after = &rest[path.len()..];
                    let group = after
                        .strip_prefix('{')
                        .map(|g| &g[..g.find('}').unwrap_or(g.len())]);
                    let mut whole = base.clone();
                    whole.extend(parts.iter().cloned());
                    deps.extend(resolve(&whole));
                    for item in group.into_iter().flat_map(|g| g.split(',')) {
                        let mut p = whole.clone();
                        p.extend(
                            item.trim()
                                .split("::")
                                .map(|s| {
                                    s.chars()
                                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                                        .collect::<String>()
                                })
                                .filter(|s| !s.is_empty()),
                        );
                        deps.extend(resolve(&p));
                    }
                }
            }
        }
        deps.remove(file);
        edges.insert(file.clone(), deps);
    }
    // a circle: a file reached again from itself (depth-first, the path kept)
    fn visit(
        f: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
        circles: &mut Vec<String>,
    ) {
        if let Some(i) = path.iter().position(|p| p == f) {
            circles.push(format!("{} -> {f}", path[i..].join(" -> ")));
            return;
        }
        if !done.insert(f.to_string()) {
            return;
        }
        path.push(f.to_string());
        for d in edges.get(f).into_iter().flatten() {
            visit(d, edges, path, done, circles);
        }
        path.pop();
    }
    let (mut done, mut circles) = (BTreeSet::new(), Vec::new());
    for f in edges.keys() {
        visit(f, &edges, &mut Vec::new(), &mut done, &mut circles);
    }
    (files.len(), circles)
}

/// ARCHITECTURE.md names every module of host-harness and firmware-core (each source file's
/// name, or its folder's for a `mod.rs`, as a word) and every crate of the workspace: a new
/// module comes with its line in the map.
#[test]
fn the_architecture_names_every_module_and_crate() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let map = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let words: std::collections::BTreeSet<&str> = map
        .split(|c: char| !(c.is_alphanumeric() || c == '_' || c == '-'))
        .collect();
    let mut missing = Vec::new();
    let mut checked = 0;
    for krate in HOST_CRATES.iter().chain(&["firmware-core"]) {
        let src = root.join(krate).join("src").canonicalize().unwrap();
        for p in workspace_files(&[".rs"]) {
            let p = p.canonicalize().unwrap();
            let Ok(rel) = p.strip_prefix(&src) else {
                continue;
            };
            let stem = rel.file_stem().unwrap().to_string_lossy().into_owned();
            let name = match stem.as_str() {
                "lib" | "main" => continue,
                "mod" => rel
                    .parent()
                    .and_then(|d| d.file_name())
                    .unwrap()
                    .to_string_lossy()
                    .into_owned(),
                _ => stem,
            };
            checked += 1;
            if !words.contains(name.as_str()) {
                missing.push(format!("{krate}/src/{}", rel.display()));
            }
        }
    }
    assert!(checked > 80, "only {checked} modules found");
    for krate in
        HOST_CRATES
            .iter()
            .chain(&["firmware-core", "firmware-core-ffi", "python", "mcu-demo"])
    {
        if !map.contains(&format!("`{krate}/`")) {
            missing.push(format!("crate {krate}"));
        }
    }
    assert!(
        missing.is_empty(),
        "ARCHITECTURE.md does not name:\n{}",
        missing.join("\n")
    );
}

/// Every `$key` a message of the library or of the Python binding writes is a known
/// setting (else the user would read `$key`, or `$$key`), and every known setting is a flag
/// of the command line (a field of a clap `Args`, or an alias), so that each message names
/// it the user's way (Python spells it as the key, its arguments' names). The words of two macros' metavariables (plots.rs,
/// daq/tdms.rs) and of this module's own documentation are not messages.
#[test]
fn every_setting_a_message_names_is_a_flag_of_the_command_line() {
    use host_harness::setting::KEYS;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut files = Vec::new();
    fn walk(d: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
        for e in std::fs::read_dir(d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    for krate in HOST_CRATES.iter().chain(&["python"]) {
        walk(&root.join(krate).join("src"), &mut files);
    }
    let not_messages = ["dir", "name", "f", "t", "k", "key", "unknown", "e"];
    let mut unknown = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let b = text.as_bytes();
        for (i, _) in text.match_indices('$') {
            if i > 0 && (b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'$') {
                // `decimals$e` (a format width) is no setting; `$$key` is one doubled
                if b[i - 1] != b'$' {
                    continue;
                }
            }
            let w: String = text[i + 1..]
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || *c == '_')
                .collect();
            if w.is_empty() || not_messages.contains(&w.as_str()) {
                continue;
            }
            let doubled = text[i + 1..].starts_with('$');
            if doubled || !KEYS.contains(&w.as_str()) {
                unknown.push(format!("{}: ${w}", f.display()));
            }
        }
    }
    assert!(
        unknown.is_empty(),
        "messages name unknown settings: {unknown:?}"
    );
    // every long flag of every subcommand, as clap knows them (aliases included)
    use clap::CommandFactory as _;
    let mut flags = std::collections::BTreeSet::new();
    for sub in host_harness::cli::Cli::command().get_subcommands() {
        for arg in sub.get_arguments() {
            flags.extend(arg.get_long().map(str::to_string));
            flags.extend(
                arg.get_all_aliases()
                    .unwrap_or_default()
                    .into_iter()
                    .map(str::to_string),
            );
        }
    }
    assert!(
        flags.contains("nperseg") && flags.contains("frames"),
        "{flags:?}"
    );
    for key in KEYS {
        let flag = key.replace('_', "-");
        assert!(
            flags.contains(&flag),
            "${key} is no flag of the command line"
        );
    }
}

/// docs/cli.md documents every flag of every command: each long flag clap knows for a
/// subcommand is named in that command's section (`## NAME`), so a flag added to the command
/// line without its documentation fails here.
#[test]
fn docs_cli_names_every_flag_of_every_command() {
    use clap::CommandFactory as _;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let doc = std::fs::read_to_string(root.join("docs/cli.md")).unwrap();
    let section = |name: &str| -> String {
        let head = format!("\n## {name}\n");
        let Some(start) = doc.find(&head) else {
            return String::new();
        };
        let rest = &doc[start + head.len()..];
        rest[..rest.find("\n## ").unwrap_or(rest.len())].to_string()
    };
    let mut missing = Vec::new();
    for sub in host_harness::cli::Cli::command().get_subcommands() {
        let text = section(sub.get_name());
        for arg in sub.get_arguments() {
            if let Some(long) = arg.get_long().filter(|l| *l != "help") {
                if !text.contains(&format!("--{long}")) {
                    missing.push(format!("{} --{long}", sub.get_name()));
                }
            }
        }
    }
    assert!(
        missing.is_empty(),
        "flags docs/cli.md does not document: {missing:?}"
    );
}

/// The library names a setting by its key (`$nperseg`); the command line spells it `--nperseg`
/// and Python `nperseg` (`setting::spell`). So no text of the library spells a flag itself,
/// except the command lines it writes for the user to run (a recording's README, the command
/// an analysis was asked with): a literal naming `host-harness`, one that is a whole argument
/// (`"--fps"`) or a piece of one (`" --reference FILE"`), or a command with its flags
/// (`"render --recording"`, `track --points`).
#[test]
fn no_library_text_spells_a_flag_of_the_command_line() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut spelled = Vec::new();
    for krate in HOST_CRATES {
        for f in rust_files(&root.join(krate).join("src")) {
            if f.to_string_lossy().contains("/src/cli") {
                continue;
            }
            let text = std::fs::read_to_string(&f).unwrap();
            // the library's code, before its unit tests
            let code = text.split("\n#[cfg(test)]").next().unwrap_or_default();
            for (line, lit) in string_literals(code) {
                let command = lit.contains("host-harness ")
                    || lit.starts_with("--") && !lit.contains(' ')
                    || lit.starts_with(" --")
                    || ["render --", "analyze --", "track --", "ema --"]
                        .iter()
                        .any(|c| lit.contains(c));
                let flag = lit.match_indices("--").any(|(i, _)| {
                    lit[i + 2..].starts_with(|c: char| c.is_ascii_lowercase())
                        && (i == 0 || !lit.as_bytes()[i - 1].is_ascii_alphanumeric())
                });
                if flag && !command {
                    spelled.push(format!("{}:{line}: {lit}", f.display()));
                }
            }
        }
    }
    assert!(
        spelled.is_empty(),
        "library texts that spell a flag (name it `$key`):\n{}",
        spelled.join("\n")
    );
}

/// Every `.rs` file below `dir`.
fn rust_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out
}

/// The string literals of Rust source `code` with the line each starts on (comments, character
/// literals and raw strings' `#` handled; escapes kept as written).
fn string_literals(code: &str) -> Vec<(usize, String)> {
    let b = code.as_bytes();
    let (mut i, mut line, mut out) = (0, 1, Vec::new());
    while i < b.len() {
        match b[i] {
            b'\n' => line += 1,
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
                continue;
            }
            b'\'' if b.get(i + 2) == Some(&b'\'') || b.get(i + 1) == Some(&b'\\') => {
                // a character literal: '"', '\'', '\\'
                let end = code[i + 2..].find('\'').map_or(b.len(), |k| i + 3 + k);
                i = end;
                continue;
            }
            b'"' => {
                let raw = i > 0 && (b[i - 1] == b'r' || b[i - 1] == b'#');
                let hashes = code[..i].len() - code[..i].trim_end_matches('#').len();
                let close = format!("\"{}", "#".repeat(hashes));
                let (start, mut j) = (line, i + 1);
                while j < b.len() {
                    if !raw && b[j] == b'\\' {
                        j += 2;
                        continue;
                    }
                    if code[j..].starts_with(&close) {
                        break;
                    }
                    j += 1;
                }
                let lit = &code[i + 1..j.min(b.len())];
                line += lit.matches('\n').count();
                out.push((start, lit.to_string()));
                i = j + close.len();
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// Every function of more than 80 lines outside firmware-core (test modules left out) is one of
/// the file parsers and numeric kernels ARCHITECTURE.md names ("Long functions, by name"), and
/// they are at most twelve. A function's lines run from its `fn` line to the `}` at its
/// indentation.
#[test]
fn long_functions_are_the_named_parsers_and_kernels() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let map = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let named = map
        .split("## Long functions, by name")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("ARCHITECTURE.md has a section \"Long functions, by name\"");
    let indent = |l: &str| l.len() - l.trim_start().len();
    let mut long = Vec::new();
    let mut files = 0;
    for krate in HOST_CRATES.iter().chain(&["python", "firmware-core-ffi"]) {
        let src = root.join(krate).join("src").canonicalize().unwrap();
        for p in workspace_files(&[".rs"]) {
            let p = p.canonicalize().unwrap();
            let Ok(rel) = p.strip_prefix(&src) else {
                continue;
            };
            files += 1;
            let text = std::fs::read_to_string(&p).unwrap();
            let lines: Vec<&str> = text.lines().collect();
            let closing = |from: usize, at: usize| {
                (from..lines.len())
                    .find(|&k| indent(lines[k]) == at && lines[k].trim_start().starts_with('}'))
                    .unwrap_or(lines.len() - 1)
            };
            let mut i = 0;
            while i < lines.len() {
                let l = lines[i].trim_start();
                if l.starts_with("#[cfg(test)]")
                    && lines
                        .get(i + 1)
                        .is_some_and(|n| n.trim_start().starts_with("mod "))
                {
                    i = closing(i + 2, indent(lines[i + 1])) + 1;
                    continue;
                }
                let words: Vec<&str> = l.split_whitespace().collect();
                let at_fn = words
                    .iter()
                    .take_while(|w| w.starts_with("pub") || ["const", "unsafe"].contains(w))
                    .count();
                if words.get(at_fn) == Some(&"fn") && !l.ends_with(';') {
                    let name: String = words[at_fn + 1]
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    let open = (i..lines.len())
                        .find(|&k| lines[k].trim_end().ends_with('{') || lines[k].ends_with(';'))
                        .unwrap_or(i);
                    if lines[open].ends_with(';') {
                        i = open + 1;
                        continue;
                    }
                    let end = closing(open + 1, indent(lines[i]));
                    if end + 1 - i > 80 {
                        long.push((format!("{krate}/src/{}", rel.display()), name, end + 1 - i));
                    }
                    i = end + 1;
                    continue;
                }
                i += 1;
            }
        }
    }
    assert!(files > 150, "only {files} source files read");
    let unnamed: Vec<String> = long
        .iter()
        .filter(|(file, name, _)| !named.contains(&format!("`{file}` `{name}`")))
        .map(|(file, name, n)| format!("{file} {name}: {n} lines"))
        .collect();
    assert!(
        unnamed.is_empty(),
        "functions over 80 lines that ARCHITECTURE.md does not name (split them, or name a \
         parser or a kernel there):\n{}",
        unnamed.join("\n")
    );
    assert!(long.len() <= 12, "{} functions over 80 lines", long.len());
}

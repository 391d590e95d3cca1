//! The single-file command end to end on the bundled drawings: every format
//! (4.1 / 2.2, ASCII / binary) is read back by the independent reader with the
//! counts `--stats` reports, the meshes are valid, and the formats agree.
//! Meshes are written under target/test-out/cli_mesh/ (CI runs gmsh on them).

mod support;

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_triwild"))
}

/// Run `cmd` and assert it succeeded (`what` and its stderr in the message).
fn succeeds(cmd: &mut Command, what: &str) -> std::process::Output {
    let run = cmd.output().unwrap();
    assert!(
        run.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    run
}

fn drawings() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg");
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "svg"))
        .collect();
    v.sort();
    assert!(v.len() >= 4, "data/svg holds the bundled drawings");
    v
}

const FORMATS: [(&str, &[&str]); 4] = [
    ("v41-ascii", &[]),
    ("v41-binary", &["--binary"]),
    ("v22-ascii", &["--msh-version", "2.2"]),
    ("v22-binary", &["--msh-version", "2.2", "--binary"]),
];

#[test]
fn bundled_drawings_mesh_in_every_format_and_read_back_alike() {
    let out = support::out_dir("cli_mesh");
    for svg in drawings() {
        let stem = svg.file_stem().unwrap().to_string_lossy().to_string();
        let mut first: Option<support::Msh> = None;
        for (name, flags) in FORMATS {
            let msh = out.join(format!("{stem}-{name}.msh"));
            let run = succeeds(
                bin()
                    .arg(&svg)
                    .arg("-o")
                    .arg(&msh)
                    .args(flags)
                    .arg("--stats"),
                &format!("{stem} {name}"),
            );
            let stats: serde_json::Value =
                serde_json::from_slice(&run.stdout).expect("--stats is one JSON object");
            let report = support::check_msh(&msh);
            report.assert_valid(&format!("{stem} {name}"));
            assert_eq!(
                report.triangles as u64,
                stats["output"]["triangles"].as_u64().unwrap(),
                "{stem} {name}"
            );
            assert_eq!(
                report.nodes as u64,
                stats["output"]["nodes"].as_u64().unwrap(),
                "{stem} {name}"
            );
            // 2.2 writes each line element of each physical curve; 4.1 writes
            // an edge on several physical curves once
            let feature_edges = stats["output"]["feature_edges"].as_u64().unwrap();
            if name.starts_with("v22") {
                assert_eq!(report.lines as u64, feature_edges, "{stem} {name}");
            } else {
                assert!(report.lines as u64 <= feature_edges, "{stem} {name}");
            }
            assert!(report.triangles > 0 && report.lines > 0);
            // The mesh covers the padded box: its area is the box's.
            assert!(report.area > 0.0 && report.area.is_finite());
            let min_angle = stats["quality"]["min_angle_deg"].as_f64().unwrap();
            assert!(min_angle > 0.0, "{stem}: min angle {min_angle}");
            // Regions (default `--regions shape`): the background plus the filled
            // shapes, whose areas add up to the whole mesh.
            let m = support::read_msh(&msh).unwrap();
            assert!(
                m.physical_names
                    .iter()
                    .any(|((dim, _), n)| *dim == 2 && n == "background"),
                "{stem} {name}: physical surface `background`"
            );
            let regions = stats["regions"]["surfaces"]
                .as_array()
                .or_else(|| stats["regions"]["regions"].as_array())
                .expect("--stats lists the regions");
            let sum: f64 = regions.iter().map(|r| r["area"].as_f64().unwrap()).sum();
            assert!(
                (sum - report.area).abs() <= 1e-9 * report.area,
                "{stem} {name}: region areas {sum} vs mesh area {}",
                report.area
            );
            match &first {
                None => first = Some(m),
                Some(f) => {
                    // 4.1 lists nodes by entity, 2.2 by tag: compare them by tag.
                    let by_tag = |x: &support::Msh| {
                        let mut n = x.nodes.clone();
                        n.sort_by_key(|v| v.0);
                        n
                    };
                    assert_eq!(
                        by_tag(f),
                        by_tag(&m),
                        "{stem} {name}: same nodes, bit for bit"
                    );
                    let is_line = |etype: i32| matches!(etype, 1 | 8 | 26);
                    let conn = |x: &support::Msh| {
                        x.elements
                            .iter()
                            .filter(|e| !is_line(e.etype))
                            .map(|e| (e.etype, e.nodes.clone(), e.physical.clone()))
                            .collect::<Vec<_>>()
                    };
                    assert_eq!(
                        conn(f),
                        conn(&m),
                        "{stem} {name}: same triangles and groups"
                    );
                    // the same edges carry line elements (4.1 writes each once)
                    let edges = |x: &support::Msh| {
                        x.elements
                            .iter()
                            .filter(|e| is_line(e.etype))
                            .map(|e| (e.nodes[0].min(e.nodes[1]), e.nodes[0].max(e.nodes[1])))
                            .collect::<std::collections::BTreeSet<_>>()
                    };
                    assert_eq!(edges(f), edges(&m), "{stem} {name}: same line edges");
                    assert_eq!(
                        f.physical_names, m.physical_names,
                        "{stem} {name}: same group names"
                    );
                }
            }
        }
    }
}

#[test]
fn the_readme_command_writes_mesh_preview_and_stats() {
    let out = support::out_dir("cli_readme");
    let svg = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg/ello.svg");
    let (msh, preview) = (out.join("ello.msh"), out.join("ello.svg"));
    let run = succeeds(
        bin()
            .arg(&svg)
            .arg("-o")
            .arg(&msh)
            .arg("--preview")
            .arg(&preview)
            .arg("--stats"),
        "triwild",
    );
    support::check_msh(&msh).assert_valid("ello");
    let svg_text = std::fs::read_to_string(&preview).unwrap();
    assert!(svg_text.starts_with("<?xml") || svg_text.starts_with("<svg"));
    assert!(
        svg_text.contains("<path") || svg_text.contains("<polygon") || svg_text.contains("<line")
    );
    let stats: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    for key in ["input", "params", "times", "output", "quality", "optimize"] {
        assert!(stats.get(key).is_some(), "--stats has {key}");
    }
    // ello has no sharp input angle: the optimizer reaches its goal, α = 10°.
    assert!(
        stats["quality"]["min_angle_deg"].as_f64().unwrap() > 10.0,
        "{}",
        stats["quality"]
    );
    assert_eq!(
        stats["optimize"]["stop"], "quality",
        "{}",
        stats["optimize"]
    );
    assert_eq!(stats["optimize"]["off_curve_left"], 0);
    // the process's peak memory, read after the mesh was written (Linux)
    if cfg!(target_os = "linux") {
        let mb = stats["peak_memory_mb"].as_f64().expect("peak_memory_mb");
        assert!(mb > 1.0 && mb < 4096.0, "peak memory {mb} MiB");
    }
}

#[test]
fn the_default_output_sits_beside_the_input() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-default-out");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("drawing.svg");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg/star-evenodd.svg"),
        &svg,
    )
    .unwrap();
    let run = succeeds(bin().arg(&svg).arg("-q"), "triwild -q");
    assert!(
        run.stderr.is_empty() && run.stdout.is_empty(),
        "-q and no --stats: silent"
    );
    support::check_msh(&dir.join("drawing.msh")).assert_valid("default output");
}

/// `--format vtu`, or an output named `.vtu`, writes the VTK file of the mesh:
/// the flag wins over the output's name (any name; not `.msh` here, since CI
/// reads every .msh under target/test-out with gmsh), the default output takes
/// the extension `.vtu`, and the points are the .msh file's nodes in order.
#[test]
fn the_vtu_format_follows_the_flag_else_the_output_name() {
    let dir = support::out_dir("cli_vtu");
    let svg = dir.join("drawing.svg");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg/star-evenodd.svg"),
        &svg,
    )
    .unwrap();
    let by_name = dir.join("by-name.vtu");
    succeeds(bin().arg(&svg).arg("-q").arg("-o").arg(&by_name), "-o .vtu");
    let by_flag = dir.join("by-flag.mesh");
    let flag = ["-q", "--format", "vtu", "-o"];
    succeeds(bin().arg(&svg).args(flag).arg(&by_flag), "--format vtu");
    succeeds(bin().arg(&svg).args(["-q", "--format", "vtu"]), "default");
    let msh = dir.join("drawing.msh");
    succeeds(bin().arg(&svg).arg("-q").arg("-o").arg(&msh), ".msh");
    let vtu = std::fs::read(&by_name).unwrap();
    assert!(vtu.starts_with(b"<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\""));
    assert_eq!(std::fs::read(&by_flag).unwrap(), vtu);
    assert_eq!(std::fs::read(dir.join("drawing.vtu")).unwrap(), vtu);
    // the .msh file's nodes, in its node order
    let nodes = triwild::read_msh_file(&msh).unwrap().nodes;
    let text = String::from_utf8(vtu).unwrap();
    let points: Vec<f64> = text
        .split("NumberOfComponents=\"3\" format=\"ascii\">\n")
        .nth(1)
        .and_then(|s| s.split("</DataArray>").next())
        .unwrap()
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    let xyz: Vec<f64> = nodes.iter().flat_map(|p| [p.x, p.y, 0.0]).collect();
    assert_eq!(points, xyz);
}

#[test]
fn named_shapes_give_named_physical_curves() {
    // star-evenodd.svg has ids `path1` (filled) and `frame` (stroked).
    let out = support::out_dir("cli_names");
    let svg = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg/star-evenodd.svg");
    let msh = out.join("star.msh");
    let run = bin()
        .arg(&svg)
        .arg("-o")
        .arg(&msh)
        .args(["--strokes", "line"])
        .output()
        .unwrap();
    assert!(run.status.success());
    let m = support::read_msh(&msh).unwrap();
    let curves: Vec<&String> = m
        .physical_names
        .iter()
        .filter(|((dim, _), _)| *dim == 1)
        .map(|(_, n)| n)
        .collect();
    // `path1` is filled, so its surface is `path1` and its curve, written after it,
    // `path1-curve` (names are unique in a file); `frame` is not filled (its
    // stroke kept as a centre line).
    assert!(curves.iter().any(|n| *n == "path1-curve"), "{curves:?}");
    assert!(curves.iter().any(|n| *n == "frame"), "{curves:?}");
    assert!(
        m.physical_names
            .iter()
            .any(|((dim, _), n)| *dim == 2 && n == "path1"),
        "{:?}",
        m.physical_names
    );
}

#[test]
fn the_strokes_flag_makes_areas_lines_or_nothing_and_the_stats_count_them() {
    // star-evenodd.svg: a filled star and a frame stroked 1 unit wide
    let out = support::out_dir("cli_strokes");
    let svg = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/svg/star-evenodd.svg");
    let run = |flags: &[&str]| {
        let msh = out.join(format!("star{}.msh", flags.join("")));
        let run = succeeds(
            bin()
                .arg(&svg)
                .arg("-o")
                .arg(&msh)
                .arg("--stats")
                .args(flags),
            &format!("{flags:?}"),
        );
        support::check_msh(&msh).assert_valid(&format!("{flags:?}"));
        let stats: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
        let surfaces: Vec<(String, f64)> = stats["regions"]["surfaces"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| {
                (
                    s["name"].as_str().unwrap().to_owned(),
                    s["area"].as_f64().unwrap(),
                )
            })
            .collect();
        (stats["input"]["paint"].clone(), surfaces)
    };
    let (paint, surfaces) = run(&[]);
    assert_eq!(paint["strokes_as_areas"], 1);
    let frame = surfaces
        .iter()
        .find(|s| s.0 == "frame-stroke")
        .expect("frame-stroke");
    // a 1-wide square ring with miter joins around a 198 square
    assert!(
        (frame.1 - (199.0f64.powi(2) - 197.0f64.powi(2))).abs() < 1e-6,
        "{frame:?}"
    );
    let (paint, surfaces) = run(&["--strokes", "line"]);
    assert_eq!(paint["strokes_as_lines"], 1);
    assert!(
        !surfaces.iter().any(|s| s.0.contains("stroke")),
        "{surfaces:?}"
    );
    let (paint, _) = run(&["--strokes", "ignore"]);
    assert_eq!(paint["strokes_ignored"], 1);
    let bad = bin()
        .arg(&svg)
        .args(["-o", "/dev/null", "--min-opacity", "2"])
        .output()
        .unwrap();
    assert_eq!(
        bad.status.code(),
        Some(2),
        "an opacity above 1 is a usage error"
    );
}

#[test]
fn units_and_scale_flags_reach_the_mesh_and_the_stats() {
    // an A4 page in millimetres with a 100 × 50 mm rectangle
    let out = support::out_dir("cli_units");
    let svg = out.join("a4.svg");
    std::fs::write(
        &svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="210mm" height="297mm" viewBox="0 0 210 297"><rect id="plate" x="10" y="20" width="100" height="50" fill="grey"/></svg>"#,
    )
    .unwrap();
    let px_per_mm = 96.0 / 25.4;
    let cases: [(&[&str], &str, f64, f64); 3] = [
        (&[], "user", 1.0, 5000.0),
        (
            &["--units", "px"],
            "px",
            1.0,
            5000.0 * px_per_mm * px_per_mm,
        ),
        (&["--units=user", "--scale", "2"], "user", 2.0, 4.0 * 5000.0),
    ];
    for (i, (flags, units, scale, area)) in cases.into_iter().enumerate() {
        let msh = out.join(format!("a4-{i}.msh"));
        let run = succeeds(
            bin()
                .arg(&svg)
                .arg("-o")
                .arg(&msh)
                .args(["--linear", "--cut-outside", "--stats"])
                .args(flags),
            &format!("{flags:?}"),
        );
        let stats: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
        assert_eq!(stats["params"]["units"], units, "{flags:?}");
        assert_eq!(stats["params"]["scale"], scale, "{flags:?}");
        let got = stats["regions"]["surfaces"][0]["area"].as_f64().unwrap();
        assert!(
            ((got - area) / area).abs() < 1e-6,
            "{flags:?}: area {got}, expected {area}"
        );
        let report = support::check_msh(&msh);
        report.assert_valid(&format!("{flags:?}"));
        assert!(
            ((report.area - area) / area).abs() < 1e-6,
            "{flags:?}: .msh area {}",
            report.area
        );
    }
    // `features` shares the flags: its d is in the output units
    let features = |flags: &[&str]| {
        let json = out.join("a4.features.json");
        succeeds(
            bin()
                .args(["features"])
                .arg(&svg)
                .arg("-o")
                .arg(&json)
                .args(flags),
            "triwild",
        );
        let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
        v["d"].as_f64().unwrap()
    };
    let d = features(&[]);
    assert!((d - 12_500f64.sqrt()).abs() < 1e-9, "d = {d}");
    assert_eq!(features(&["--scale", "0.5"]), d / 2.0);
    // a bad scale is a usage error, and --help says what the flags do
    for bad in ["0", "-1", "nan"] {
        let run = bin()
            .arg(&svg)
            .arg(format!("--scale={bad}"))
            .output()
            .unwrap();
        assert_eq!(run.status.code(), Some(2), "--scale {bad}");
        assert!(
            String::from_utf8_lossy(&run.stderr).contains("scale"),
            "--scale {bad}"
        );
    }
    let help = bin().arg("--help").output().unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("--units") && help.contains("viewBox") && help.contains("--scale"));
}

#[test]
fn the_mesh_is_the_same_for_every_thread_count() {
    // `--threads` changes who does the work, never the result: byte for byte,
    // on a drawing with strokes, clip paths and many shapes to classify.
    let out = support::out_dir("cli_threads");
    for svg in drawings() {
        let stem = svg.file_stem().unwrap().to_string_lossy().into_owned();
        let mut first: Option<Vec<u8>> = None;
        for threads in ["1", "2", "4", "0"] {
            let msh = out.join(format!("{stem}-t{threads}.msh"));
            succeeds(
                bin()
                    .arg(&svg)
                    .arg("-o")
                    .arg(&msh)
                    .args(["--threads", threads]),
                &format!("{stem} --threads {threads}"),
            );
            let bytes = std::fs::read(&msh).unwrap();
            match &first {
                None => first = Some(bytes),
                Some(b) => assert!(*b == bytes, "{stem}: --threads {threads} differs from 1"),
            }
        }
    }
}

#[test]
fn a_path_painted_many_times_meshes_as_one_and_the_stats_count_the_copies() {
    // 200 copies of one filled blob, the topmost red; a rect between the first
    // two stays (duplicates merge at load).
    let out = support::out_dir("cli_duplicates");
    let blob = "M30 30C40 20 60 20 70 30C80 40 80 60 70 70C60 80 40 80 30 70Z";
    let mut body = format!(r##"<path fill="#0000ff" d="{blob}"/><rect width="40" height="40"/>"##);
    for k in 1..200 {
        let colour = if k == 199 { "#ff0000" } else { "#0000ff" };
        body.push_str(&format!(r#"<path fill="{colour}" d="{blob}"/>"#));
    }
    let svg = out.join("duplicates.svg");
    std::fs::write(
        &svg,
        format!(r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">{body}</svg>"#),
    )
    .unwrap();
    let msh = out.join("duplicates.msh");
    let run = succeeds(
        bin()
            .arg(&svg)
            .arg("-o")
            .arg(&msh)
            .args(["--stats", "--regions", "colour"]),
        "triwild",
    );
    support::check_msh(&msh).assert_valid("duplicates");
    let stats: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(stats["input"]["shapes"], 2);
    assert_eq!(stats["input"]["paint"]["duplicates_merged"], 199);
    let names: Vec<&str> = stats["regions"]["surfaces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert!(names.contains(&"fill-#ff0000"), "{names:?}");
    assert!(!names.contains(&"fill-#0000ff"), "{names:?}");
}

#[test]
fn the_size_preview_shades_a_graded_mesh_with_a_legend() {
    let out = support::out_dir("cli_preview_size");
    let plate = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/plate.svg");
    let (msh, preview, plain) = (
        out.join("plate.msh"),
        out.join("plate-size.svg"),
        out.join("plate.svg"),
    );
    let graded = [
        "--cut-outside",
        "--edge-length-abs",
        "5",
        "--size-expr",
        "0.5 + 0.05*x",
    ];
    succeeds(
        bin()
            .arg(&plate)
            .arg("-o")
            .arg(&msh)
            .args(graded)
            .arg("--preview")
            .arg(&preview)
            .arg("--preview-size"),
        "--preview-size",
    );
    support::check_msh(&msh).assert_valid("plate graded");
    let svg = std::fs::read_to_string(&preview).unwrap();
    assert!(svg.contains("id=\"size-legend\"") && svg.contains("edge / h"));
    usvg::Tree::from_str(&svg, &usvg::Options::default()).expect("the preview is valid SVG");
    // the fills of the shaded triangles (closed outlines per colour, a colour's
    // path data in several elements when long), legend aside
    let mut fills: Vec<(String, usize)> = Vec::new();
    for l in svg.lines().filter(|l| l.starts_with("<path fill=\"#")) {
        let colour = l["<path fill=\"".len()..].split('"').next().unwrap();
        let n = l.matches('Z').count();
        match fills.iter_mut().find(|f| f.0 == colour) {
            Some(f) => f.1 += n,
            None => fills.push((colour.to_owned(), n)),
        }
    }
    let triangles: usize = fills.iter().map(|f| f.1).sum();
    assert!(fills.len() >= 2, "distinct fills: {fills:?}");
    // most triangles are within [4/5, 4/3] of the field: the neutral fill
    let neutral = fills.iter().find(|f| f.0 == "#f7f7f7").map_or(0, |f| f.1);
    assert!(2 * neutral > triangles, "{fills:?}");
    // the mesh as written: as many triangles
    let stats = succeeds(
        bin()
            .arg(&plate)
            .arg("-o")
            .arg(out.join("plate-plain.msh"))
            .args(graded)
            .arg("--preview")
            .arg(&plain)
            .arg("--stats"),
        "plain preview",
    );
    let stats: serde_json::Value = serde_json::from_slice(&stats.stdout).unwrap();
    assert_eq!(
        stats["output"]["triangles"].as_u64(),
        Some(triangles as u64)
    );
    // without the flag: region colours, no legend
    let svg = std::fs::read_to_string(&plain).unwrap();
    assert!(!svg.contains("size-legend") && svg.contains("<path fill=\"#4060a0"));
    // the flag needs a preview
    let run = bin()
        .arg(&plate)
        .arg("-o")
        .arg(&msh)
        .arg("--preview-size")
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
}

//! Periodic cells (`--periodic`): a disk of radius 0.3 in a unit cell, at the
//! centre, at a corner (four quarters) and on a side (two halves), is one
//! region of area π·0.09 at order 3; every node on a periodic side has a
//! partner on the opposite side at the same coordinate along it, bit for bit,
//! and the file's `$Periodic` section (read back here with its own parser)
//! says so. The meshes go to `target/test-out/periodic/` (CI's mshcheck
//! validates them).

mod support;

use std::collections::{HashMap, HashSet};
use std::path::Path;
use std::process::Command;
use triwild::{MshOptions, MshVersion, Params, Periodic, PeriodicAxes, RegionOptions};

fn disk(cx: f64, cy: f64) -> String {
    format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1 1" width="100" height="100"><circle id="fibre" cx="{cx}" cy="{cy}" r="0.3" fill="#000"/></svg>"##
    )
}

/// A `$Periodic` link of MSH 4.1 as written: entity, master, affine map, pairs.
struct Link {
    dim: i32,
    affine: Vec<f64>,
    pairs: Vec<(u64, u64)>,
}

/// The `$Periodic` section of an ASCII MSH 4.1 file.
fn periodic_section(text: &str) -> Vec<Link> {
    let start = text.find("$Periodic\n").expect("a $Periodic section") + "$Periodic\n".len();
    let end = text.find("$EndPeriodic").expect("$EndPeriodic");
    let mut tok = text[start..end].split_whitespace();
    let mut next = || tok.next().expect("a token of $Periodic");
    let n: usize = next().parse().unwrap();
    (0..n)
        .map(|_| {
            let dim: i32 = next().parse().unwrap();
            let _tag: i32 = next().parse().unwrap();
            let _master: i32 = next().parse().unwrap();
            let na: usize = next().parse().unwrap();
            let affine: Vec<f64> = (0..na).map(|_| next().parse().unwrap()).collect();
            let np: usize = next().parse().unwrap();
            let pairs = (0..np)
                .map(|_| (next().parse().unwrap(), next().parse().unwrap()))
                .collect();
            Link { dim, affine, pairs }
        })
        .collect()
}

/// Check a periodic unit-cell mesh file: valid (the independent checker),
/// every side node paired, each pair the master translated by the period bit
/// for bit. Returns the number of node pairs of curves.
fn check_file(path: &Path, axes: PeriodicAxes) -> usize {
    support::check_msh(path).assert_valid(&path.display().to_string());
    let msh = support::read_msh(path).expect("the file reads back");
    let text = std::fs::read_to_string(path).unwrap();
    let links = periodic_section(&text);
    let at: HashMap<u64, [f64; 3]> = msh.nodes.iter().copied().collect();
    let mut slaves: [HashSet<u64>; 2] = Default::default();
    let mut curve_pairs = 0;
    for l in &links {
        assert_eq!(l.affine.len(), 16);
        let (tx, ty) = (l.affine[3], l.affine[7]);
        for &(s, m) in &l.pairs {
            let (ps, pm) = (at[&s], at[&m]);
            assert_eq!(
                [ps[0], ps[1]],
                [pm[0] + tx, pm[1] + ty],
                "node {s} is not node {m} translated by ({tx}, {ty})"
            );
            if l.dim == 1 {
                curve_pairs += 1;
                if tx != 0.0 {
                    slaves[0].insert(s);
                }
                if ty != 0.0 {
                    slaves[1].insert(s);
                }
            }
        }
    }
    // every node on the right (top) side is a slave of a curve link; the
    // sides hold as many nodes as their partners
    let on = |f: &dyn Fn(&[f64; 3]) -> bool| -> HashSet<u64> {
        msh.nodes
            .iter()
            .filter(|(_, p)| f(p))
            .map(|(t, _)| *t)
            .collect()
    };
    let sides = [
        (
            axes != PeriodicAxes::Y,
            on(&|p| p[0] == 1.0),
            on(&|p| p[0] == 0.0),
        ),
        (
            axes != PeriodicAxes::X,
            on(&|p| p[1] == 0.0),
            on(&|p| p[1] == -1.0),
        ),
    ];
    for (axis, (periodic, slave_side, master_side)) in sides.iter().enumerate() {
        if !periodic {
            assert!(slaves[axis].is_empty());
            continue;
        }
        assert_eq!(
            slave_side, &slaves[axis],
            "axis {axis}: unpaired side nodes"
        );
        assert_eq!(slave_side.len(), master_side.len(), "axis {axis}");
    }
    curve_pairs
}

fn mesh_cell(name: &str, svg: &str, axes: PeriodicAxes, version: MshVersion) -> triwild::Meshed {
    let drawing = triwild::load_bytes(svg.as_bytes(), &triwild::LoadOptions::DEFAULT)
        .expect("the drawing loads");
    let params = Params::DEFAULT.with_periodic(Some(Periodic::new(axes)));
    let meshed =
        triwild::mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT).expect("the cell meshes");
    let path = support::out_dir("periodic").join(format!("{name}.msh"));
    let opts = MshOptions {
        version,
        ..MshOptions::DEFAULT
    };
    triwild::write_msh(&meshed.mesh, &path, opts).expect("write the mesh");
    meshed
}

#[test]
fn a_disk_anywhere_in_the_cell_is_one_region_of_its_area_and_the_sides_match() {
    let want = std::f64::consts::PI * 0.09;
    for (name, cx, cy, crossings) in [
        ("centre", 0.5, 0.5, 0),
        ("corner", 0.0, 0.0, 8),
        ("side", 0.0, 0.5, 4),
    ] {
        let m = mesh_cell(name, &disk(cx, cy), PeriodicAxes::Xy, MshVersion::V41);
        let fibres: Vec<_> = m
            .report
            .regions
            .surfaces
            .iter()
            .filter(|s| s.name != "background")
            .collect();
        assert_eq!(fibres.len(), 1, "{name}: {:?}", m.report.regions.surfaces);
        let got = fibres[0].area;
        assert!(
            ((got - want) / want).abs() < 1e-9,
            "{name}: fibre area {got}, not {want}"
        );
        let p = m.report.periodic.as_ref().expect("a periodic report");
        assert!(p.pairs > 8, "{name}: {p:?}");
        assert_eq!((p.unpaired, p.max_mismatch), (0, 0.0), "{name}: {p:?}");
        let pairs = &m.mesh.periodic.as_ref().expect("the mesh's pairs").pairs;
        assert_eq!(pairs.len(), p.pairs);
        // the fibre's outline meets the sides at partner nodes
        let outline: HashSet<u32> = (0..m.mesh.line_count())
            .filter(|&l| m.mesh.curves[m.mesh.line_group[l] as usize] == "fibre")
            .flat_map(|l| m.mesh.line(l)[..2].to_vec())
            .collect();
        let cell_sides = |q: kurbo::Point| q.x == 0.0 || q.x == 1.0 || q.y == 0.0 || q.y == -1.0;
        let on_sides = outline
            .iter()
            .filter(|&&v| cell_sides(m.mesh.nodes[v as usize]))
            .count();
        assert_eq!(
            on_sides, crossings,
            "{name}: the outline's ends on the sides"
        );
        for name in ["left", "right", "bottom", "top"] {
            assert!(m.mesh.curves.iter().any(|c| c == name), "no curve {name}");
        }
        let path = support::out_dir("periodic").join(format!("{name}.msh"));
        assert!(check_file(&path, PeriodicAxes::Xy) > 0);
    }
}

#[test]
fn one_axis_pairs_only_its_sides_and_2_2_writes_the_section() {
    let m = mesh_cell("side_x", &disk(0.0, 0.5), PeriodicAxes::X, MshVersion::V41);
    let p = m.report.periodic.as_ref().expect("a periodic report");
    assert_eq!((p.unpaired, p.max_mismatch), (0, 0.0), "{p:?}");
    assert!(
        m.mesh
            .periodic
            .as_ref()
            .unwrap()
            .pairs
            .iter()
            .all(|p| p.axis == 0)
    );
    check_file(
        &support::out_dir("periodic").join("side_x.msh"),
        PeriodicAxes::X,
    );
    // the disk through the bottom side is cut there, not wrapped
    let m = mesh_cell(
        "bottom_x",
        &disk(0.5, 1.0),
        PeriodicAxes::X,
        MshVersion::V41,
    );
    let fibre = m
        .report
        .regions
        .surfaces
        .iter()
        .find(|s| s.name == "fibre")
        .unwrap();
    let half = std::f64::consts::PI * 0.09 / 2.0;
    assert!(((fibre.area - half) / half).abs() < 1e-9, "{}", fibre.area);

    mesh_cell(
        "corner_22",
        &disk(0.0, 0.0),
        PeriodicAxes::Xy,
        MshVersion::V22,
    );
    let path = support::out_dir("periodic").join("corner_22.msh");
    support::check_msh(&path).assert_valid("corner_22");
    let text = std::fs::read_to_string(&path).unwrap();
    let section = &text[text.find("$Periodic\n").expect("2.2 $Periodic")..];
    assert!(
        section
            .lines()
            .nth(3)
            .unwrap()
            .starts_with("Affine 1.0 0.0 0.0 1.0")
    );
}

#[test]
fn bad_periodic_input_is_one_line_and_exit_2() {
    let dir = support::out_dir("periodic-errors");
    let no_view_box = dir.join("no_viewbox.svg");
    std::fs::write(
        &no_view_box,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="10" height="10"><rect x="1" y="1" width="3" height="3"/></svg>"#,
    )
    .unwrap();
    let cell = dir.join("cell.svg");
    std::fs::write(&cell, disk(0.5, 0.5)).unwrap();
    let cases: [(&Path, &[&str], &str); 5] = [
        (&no_view_box, &["--periodic"], "viewbox"),
        (&cell, &["--periodic", "--cell", "0,0,0,1"], "cell"),
        (&cell, &["--periodic", "--cell=0,1,1,0"], "cell"),
        (&cell, &["--periodic", "--mesher", "cdt"], "cdt"),
        (&cell, &["--periodic", "--cut-outside"], "cut-outside"),
    ];
    for (input, flags, word) in cases {
        let out = dir.join("out.msh");
        let run = Command::new(env!("CARGO_BIN_EXE_triwild"))
            .arg(input)
            .arg("-o")
            .arg(&out)
            .args(flags)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{flags:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{flags:?}: {err}");
        assert!(err.to_lowercase().contains(word), "{flags:?}: {err}");
        assert!(!out.exists(), "{flags:?} wrote a mesh");
    }
    // --cell meshes a drawing without a viewBox
    let run = Command::new(env!("CARGO_BIN_EXE_triwild"))
        .arg(&no_view_box)
        .arg("-o")
        .arg(dir.join("cell.msh"))
        .args(["--periodic=x", "--cell=0,-5,5,0"])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// The area inside a closed path of cubic Béziers (output coordinates, y
/// up): Green's theorem, ∮ x dy by 8-point Gauss–Legendre per segment
/// (exact for the degree-5 integrand).
fn cubic_path_area(segments: &[[(f64, f64); 4]]) -> f64 {
    let (g, w) = (
        [
            -0.960_289_856_497_536_3,
            -0.796_666_477_413_626_7,
            -0.525_532_409_916_329,
            -0.183_434_642_495_649_8,
            0.183_434_642_495_649_8,
            0.525_532_409_916_329,
            0.796_666_477_413_626_7,
            0.960_289_856_497_536_3,
        ],
        [
            0.101_228_536_290_376_26,
            0.222_381_034_453_374_47,
            0.313_706_645_877_887_3,
            0.362_683_783_378_362,
            0.362_683_783_378_362,
            0.313_706_645_877_887_3,
            0.222_381_034_453_374_47,
            0.101_228_536_290_376_26,
        ],
    );
    let mut area = 0.0;
    for c in segments {
        for k in 0..8 {
            let t = 0.5 * (g[k] + 1.0);
            let s = 1.0 - t;
            let b = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
            let d = [
                -3.0 * s * s,
                3.0 * s * s - 6.0 * s * t,
                6.0 * s * t - 3.0 * t * t,
                3.0 * t * t,
            ];
            let x: f64 = (0..4).map(|i| b[i] * c[i].0).sum();
            let dy: f64 = (0..4).map(|i| d[i] * c[i].1).sum();
            area += 0.5 * w[k] * x * dy;
        }
    }
    area
}

#[test]
fn a_cubic_blob_through_a_corner_and_a_tangent_disk_keep_their_areas() {
    // a blob of four cubics around the corner (1, 1) of the SVG cell (output
    // (1, -1)): its four pieces are one region of the blob's area
    let pts: [[(f64, f64); 4]; 4] = [
        [(0.75, 1.0), (0.75, 0.8), (0.9, 0.72), (1.05, 0.78)],
        [(1.05, 0.78), (1.2, 0.84), (1.3, 0.95), (1.25, 1.1)],
        [(1.25, 1.1), (1.2, 1.25), (1.0, 1.3), (0.9, 1.22)],
        [(0.9, 1.22), (0.8, 1.14), (0.75, 1.2), (0.75, 1.0)],
    ];
    let mut d = format!("M {} {}", pts[0][0].0, pts[0][0].1);
    for c in &pts {
        d += &format!(
            " C {} {} {} {} {} {}",
            c[1].0, c[1].1, c[2].0, c[2].1, c[3].0, c[3].1
        );
    }
    let svg = format!(
        r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1 1"><path id="blob" d="{d} Z" fill="#000"/></svg>"##
    );
    // in output coordinates (y up) the path runs the other way round
    let flipped: Vec<[(f64, f64); 4]> = pts.iter().map(|c| c.map(|(x, y)| (x, -y))).collect();
    let want = cubic_path_area(&flipped).abs();
    let m = mesh_cell("blob", &svg, PeriodicAxes::Xy, MshVersion::V41);
    let got = m
        .report
        .regions
        .surfaces
        .iter()
        .find(|s| s.name == "blob")
        .unwrap()
        .area;
    assert!(
        ((got - want) / want).abs() < 1e-9,
        "blob area {got}, not {want}"
    );
    let p = m.report.periodic.as_ref().unwrap();
    assert_eq!((p.unpaired, p.max_mismatch), (0, 0.0), "{p:?}");
    check_file(
        &support::out_dir("periodic").join("blob.msh"),
        PeriodicAxes::Xy,
    );

    // a disk touching the left side: it meets the side at one node, and its
    // partner on the right side is a node too. Its outline beside the side is
    // meshed within ε, not exact (kept exact, the cusp of background between
    // it and the fixed side left elements of 3° with a Jacobian ratio near
    // 0), and a warning says so
    let m = mesh_cell(
        "tangent",
        &disk(0.3, 0.5),
        PeriodicAxes::Xy,
        MshVersion::V41,
    );
    let fibre = m
        .report
        .regions
        .surfaces
        .iter()
        .find(|s| s.name == "fibre")
        .unwrap();
    let want = std::f64::consts::PI * 0.09;
    assert!(((fibre.area - want) / want).abs() < 1e-3, "{}", fibre.area);
    assert!(
        m.report
            .warnings
            .iter()
            .any(|w| w.contains("within mu") && w.contains("cell's sides")),
        "{:?}",
        m.report.warnings
    );
    assert!(
        m.report
            .quality
            .unforced
            .as_ref()
            .is_some_and(|q| q.min_angle_deg >= 10.0)
    );
    let touch = m
        .mesh
        .nodes
        .iter()
        .filter(|q| (q.x == 0.0 || q.x == 1.0) && q.y == -0.5)
        .count();
    assert_eq!(touch, 2, "the touching point and its partner");
    check_file(
        &support::out_dir("periodic").join("tangent.msh"),
        PeriodicAxes::Xy,
    );
}

/// The effective conductivity tensor of a periodic linear mesh: the cell
/// problem ∫ k (∇χ_j + e_j)·∇v = 0 for periodic χ_j, v, solved with P1
/// elements (a node on the right or top side is its partner's unknown) by
/// conjugate gradients; K_ij = ∫ k (e_i + ∇χ_i)·(e_j + ∇χ_j) / |Y|.
fn homogenize_p1(mesh: &triwild::FemMesh, k_of: &dyn Fn(&str) -> f64) -> [[f64; 2]; 2] {
    let n = mesh.nodes.len();
    let pairs = &mesh.periodic.as_ref().expect("a periodic mesh").pairs;
    let mut master: Vec<usize> = (0..n).collect();
    for p in pairs {
        master[p.node as usize] = p.master as usize;
    }
    let root = |mut v: usize| {
        while master[v] != v {
            v = master[v];
        }
        v
    };
    let dof: Vec<usize> = (0..n).map(root).collect();
    // element gradients and weights
    let mut elems = Vec::new();
    let mut rows: Vec<HashMap<usize, f64>> = vec![HashMap::new(); n];
    let mut area = 0.0;
    for t in 0..mesh.triangle_count() {
        let c = mesh.triangle(t);
        let [a, b, d] = [0, 1, 2].map(|i| mesh.nodes[c[i] as usize]);
        let det = (b.x - a.x) * (d.y - a.y) - (d.x - a.x) * (b.y - a.y);
        let g = [
            [(b.y - d.y) / det, (d.x - b.x) / det],
            [(d.y - a.y) / det, (a.x - d.x) / det],
            [(a.y - b.y) / det, (b.x - a.x) / det],
        ];
        let w = k_of(&mesh.surfaces[mesh.triangle_group[t] as usize]) * 0.5 * det;
        area += 0.5 * det;
        let ids = [0, 1, 2].map(|i| dof[c[i] as usize]);
        for i in 0..3 {
            for j in 0..3 {
                *rows[ids[i]].entry(ids[j]).or_default() +=
                    w * (g[i][0] * g[j][0] + g[i][1] * g[j][1]);
            }
        }
        elems.push((ids, g, w));
    }
    let fixed = dof[0];
    let apply = |x: &[f64]| -> Vec<f64> {
        let mut y = vec![0.0; n];
        for (i, row) in rows.iter().enumerate() {
            if i != fixed {
                y[i] = row
                    .iter()
                    .filter(|(j, _)| **j != fixed)
                    .map(|(j, v)| v * x[*j])
                    .sum();
            }
        }
        y
    };
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut chi = [vec![0.0; n], vec![0.0; n]];
    for (axis, x) in chi.iter_mut().enumerate() {
        let mut b = vec![0.0; n];
        for (ids, g, w) in &elems {
            for i in 0..3 {
                b[ids[i]] -= w * g[i][axis];
            }
        }
        b[fixed] = 0.0;
        let mut r = b.clone();
        let mut p = r.clone();
        let mut rr = dot(&r, &r);
        let stop = 1e-28 * rr.max(1e-300);
        for _ in 0..10 * n {
            if rr <= stop {
                break;
            }
            let ap = apply(&p);
            let alpha = rr / dot(&p, &ap);
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            let next = dot(&r, &r);
            for i in 0..n {
                p[i] = r[i] + next / rr * p[i];
            }
            rr = next;
        }
    }
    let mut k = [[0.0; 2]; 2];
    for (ids, g, w) in &elems {
        let grad = |x: &[f64], axis: usize| {
            let mut v = [0.0, 0.0];
            for i in 0..3 {
                v[0] += x[ids[i]] * g[i][0];
                v[1] += x[ids[i]] * g[i][1];
            }
            v[axis] += 1.0;
            v
        };
        let (gx, gy) = (grad(&chi[0], 0), grad(&chi[1], 1));
        let gs = [gx, gy];
        for i in 0..2 {
            for j in 0..2 {
                k[i][j] += w * (gs[i][0] * gs[j][0] + gs[i][1] * gs[j][1]) / area;
            }
        }
    }
    k
}

#[test]
fn a_laminate_has_the_harmonic_and_arithmetic_means() {
    let svg = r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 1 1"><rect id="stiff" x="0.25" y="0" width="0.5" height="1" fill="#000"/></svg>"##;
    let drawing = triwild::load_bytes(svg.as_bytes(), &triwild::LoadOptions::DEFAULT)
        .expect("the drawing loads");
    let params = Params::DEFAULT
        .with_order(triwild::Order::Linear)
        .with_periodic(Some(Periodic::new(PeriodicAxes::Xy)));
    let m =
        triwild::mesh_drawing(&drawing, &params, &RegionOptions::DEFAULT).expect("the cell meshes");
    let k = homogenize_p1(&m.mesh, &|name| if name == "stiff" { 10.0 } else { 1.0 });
    let (harmonic, arithmetic) = (20.0 / 11.0, 5.5);
    assert!((k[0][0] - harmonic).abs() < 1e-8 * harmonic, "{k:?}");
    assert!((k[1][1] - arithmetic).abs() < 1e-8 * arithmetic, "{k:?}");
    assert!(k[0][1].abs() < 1e-8, "{k:?}");
    // without the pairs (each side on its own), the cell problem is another
    // one: the means are not what it gives
    let mut open = m.mesh.clone();
    if let Some(p) = &mut open.periodic {
        p.pairs.clear();
    }
    let k_open = homogenize_p1(&open, &|name| if name == "stiff" { 10.0 } else { 1.0 });
    assert!((k_open[0][0] - harmonic).abs() > 1e-3, "{k_open:?}");
}

//! End-to-end tests of `eigs`, `heat`, `distance`, `signature`, `segment`, `embed` and
//! `perturb`: the numbers in the files and the summaries, and the errors.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;
use std::process::Command;

use spectral_mesh::io::read_mesh;

const SPHERE: &str = "sphere:res=2";

mod common;
use common::*;

fn rows(p: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The number after `key` in a summary line, e.g. `number_after(out, "relative change ")`.
fn number_after(text: &str, key: &str) -> f64 {
    let i = text
        .find(key)
        .unwrap_or_else(|| panic!("'{key}' not in {text}"))
        + key.len();
    let rest = &text[i..];
    let end = rest
        .find(|c: char| !(c.is_ascii_digit() || "+-.eE".contains(c)))
        .unwrap_or(rest.len());
    rest[..end]
        .parse()
        .unwrap_or_else(|_| panic!("no number after '{key}' in {text}"))
}

#[test]
fn eigs_summary_and_eigenvalues_are_right_for_the_sphere() {
    let (_dir, out, [ev, plot]) = ok_writing(
        "eigs sphere:res=2 -k 16 --eigenvalues-txt {} --plot {}",
        ["ev.txt", "spectrum.png"],
    );
    let v = values(&ev);
    assert_eq!(v.len(), 16);
    assert!(v.windows(2).all(|w| w[0] <= w[1]), "not ascending: {v:?}");
    assert!(v[0].abs() < 1e-8 * v[15], "first eigenvalue {}", v[0]);
    assert!(v[1] > 1e-3);
    // One component: one zero eigenvalue, detected and matched.
    assert!(out.contains("near-zero eigenvalues"), "{out}");
    assert!(out.contains(": 1; expected 1"), "{out}");
    // The sphere's first non-zero eigenvalue is triple (l = 1) and the next is 5-fold.
    assert!(out.contains("x3 [1..3]"), "{out}");
    assert!(out.contains("x5 [4..8]"), "{out}");
    assert!(number_after(&out, "orthogonality error max |X^T B X - I| = ") < 1e-8);
    assert!(number_after(&out, "relative residuals: min ") <= number_after(&out, ", max "));
    assert!(std::fs::metadata(&plot).unwrap().len() > 1000);
}

#[test]
fn eigs_dirichlet_refuses_a_closed_mesh_and_pins_the_disk() {
    let e = err_with("eigs sphere:res=2 -k 5 --dirichlet-boundary", &[]);
    assert!(
        e.contains("--dirichlet-boundary") && e.contains("closed"),
        "{e}"
    );
    let (_dir, out, [ev]) = ok_writing(
        "eigs disk:res=2 -k 6 --dirichlet-boundary --eigenvalues-txt {}",
        ["ev.txt"],
    );
    let v = values(&ev);
    assert!(v[0] > 1e-3, "Dirichlet spectrum starts above 0: {v:?}");
    assert!(out.contains(": 0; expected 0"), "{out}");
}

#[test]
fn heat_basis_function_peaks_at_the_anchor_and_keeps_the_mass() {
    let (_dir, out, [txt, png]) = ok_writing(
        "heat sphere:res=2 --anchor 7 --t 0.05 -k 30 -o {} -o {} --size 200",
        ["h.txt", "h.png"],
    );
    let f = values(&txt);
    assert_eq!(f.len(), 162);
    let argmax = (0..f.len()).fold(0, |b, i| if f[i] > f[b] { i } else { b });
    assert_eq!(argmax, 7);
    assert!(out.contains("at vertex 7"), "{out}");
    assert!(number_after(&out, "relative change ") < 1e-8, "{out}");
    assert!(png.is_file());
}

#[test]
fn heat_diffuses_an_indicator_and_conserves_its_mass() {
    let (_dir, out, [txt]) = ok_writing(
        "heat sphere:res=2 --indicator 0,0.4 --t 0.02 -k 30 -o {}",
        ["h.txt"],
    );
    let f = values(&txt);
    let m_in = number_after(&out, "input ");
    let m_out = number_after(&out, "output ");
    assert!(m_in > 0.0);
    assert!((m_in - m_out).abs() < 1e-8 * m_in, "{out}");
    // The heat spreads: the values are below the indicator's 1 and above 0 far away.
    assert!(f.iter().all(|v| *v < 1.0));
    // A bad indicator is refused, naming the option.
    let e = err_with("heat sphere:res=2 --indicator 0 -o {}", &[&txt]);
    assert!(e.contains("--indicator"), "{e}");
    let e = err_with("heat sphere:res=2 --indicator 999,0.1 -o x.txt", &[]);
    assert!(e.contains("999") && e.contains("162"), "{e}");
}

#[test]
fn distance_is_zero_at_the_source_and_symmetric() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (11usize, 95usize);
    let da = dir.path().join("a.txt");
    let db = dir.path().join("b.txt");
    let ap = dir.path().join("all.npy");
    for (src, p) in [(a, &da), (b, &db)] {
        ok(&[
            "distance",
            SPHERE,
            "--source",
            &src.to_string(),
            "--distance",
            "diffusion:t=0.1",
            "-k",
            "30",
            "-o",
            s(p),
        ]);
    }
    ok_with(
        "distance sphere:res=2 --source 11 --distance diffusion:t=0.1 -k 30 --all-pairs {}",
        &[&ap],
    );
    let (fa, fb) = (values(&da), values(&db));
    assert_eq!(fa[a], 0.0);
    assert_eq!(fb[b], 0.0);
    assert!(fa[b] > 0.0);
    assert!(
        (fa[b] - fb[a]).abs() <= 1e-10 * fa[b],
        "{} vs {}",
        fa[b],
        fb[a]
    );
    // The .npy: header then 162 x 162 little-endian doubles, symmetric, row a = run a.
    let bytes = std::fs::read(&ap).unwrap();
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    let hlen = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + hlen) % 64, 0);
    let header = std::str::from_utf8(&bytes[10..10 + hlen]).unwrap();
    // The library's .npy writer (npyz) writes the shape as `(162, 162, )`.
    assert!(
        header.contains("'shape': (162, 162") && header.contains("'fortran_order': False"),
        "{header}"
    );
    let m: Vec<f64> = bytes[10 + hlen..]
        .chunks(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    assert_eq!(m.len(), 162 * 162);
    assert_eq!(m[a * 162 + b], m[b * 162 + a]);
    for j in 0..162 {
        assert!((m[a * 162 + j] - fa[j]).abs() <= 1e-9 * (1.0 + fa[j]));
    }
}

#[test]
fn bad_filters_are_refused_with_the_reason() {
    let e = err_with(
        "distance sphere:res=2 -k 10 --distance custom-w:s+ -o never.txt",
        &[],
    );
    assert!(e.contains("custom-w:s+") && e.contains("expression"), "{e}");
    let e = err_with(
        "distance sphere:res=2 -k 10 --distance custom-w:-s -o never.txt",
        &[],
    );
    assert!(e.contains("not strictly positive"), "{e}");
    let e = err_with(
        "distance sphere:res=2 --distance gaussian:t=1 -o never.txt",
        &[],
    );
    assert!(e.contains("unknown filter 'gaussian'"), "{e}");
    let e = err_with("embed sphere:res=2 --filter poly -o never.off", &[]);
    assert!(e.contains("--filter poly") && e.contains("needs p"), "{e}");
    assert!(!Path::new("never.txt").exists() && !Path::new("never.off").exists());
}

#[test]
fn signature_writes_one_column_per_time_and_draws_the_chosen_one() {
    let (dir, out, [txt, ply]) = ok_writing(
        "signature sphere:res=2 --kind hks --times 0.01,0.1,1 -k 30 --column 1 -o {} -o {}",
        ["hks.txt", "hks.ply"],
    );
    let r = rows(&txt);
    assert_eq!(r.len(), 162);
    assert!(r.iter().all(|row| row.len() == 3));
    // HKS decreases with time at every vertex.
    assert!(r.iter().all(|row| row[0] > row[1] && row[1] > row[2]));
    assert!(out.contains("column 1 (t = 0.1)"), "{out}");
    assert!(ply.is_file());
    let e = err(&[
        "signature",
        SPHERE,
        "--times",
        "0.1",
        "--column",
        "3",
        "-k",
        "10",
        "-o",
        s(&dir.path().join("x.txt")),
    ]);
    assert!(e.contains("--column 3"), "{e}");
}

#[test]
fn segment_labels_every_vertex_and_reports_the_patch_count() {
    let (dir, [labels, png]) = temp_paths(["labels.txt", "labels.png"]);
    // Two spheres' worth of bumps: the Fiedler-like field of an elongated shape.
    let field = dir.path().join("f.txt");
    let mesh = read_mesh_shape(SPHERE);
    let f: Vec<String> = mesh
        .positions()
        .iter()
        .map(|p| format!("{}", (3.0 * p[0]).cos() + 0.1 * p[2]))
        .collect();
    std::fs::write(&field, f.join("\n")).unwrap();
    for sig in ["hks:t=0.05".to_string(), format!("field:{}", s(&field))] {
        let _ = std::fs::remove_file(&labels);
        let out = ok(&[
            "segment",
            SPHERE,
            "--signature",
            &sig,
            "--persistence",
            "0.01",
            "-k",
            "30",
            "-o",
            s(&labels),
            "-o",
            s(&png),
            "--size",
            "200",
            "--force",
        ]);
        let l = values(&labels);
        assert_eq!(l.len(), 162);
        let mut distinct: Vec<i64> = l.iter().map(|x| *x as i64).collect();
        distinct.sort();
        distinct.dedup();
        let count = number_after(&out, "patches: ") as usize;
        assert_eq!(count, distinct.len(), "{out}");
        assert_eq!(*distinct.last().unwrap() as usize, count - 1);
        assert_eq!(out.matches("genus").count(), count, "{out}");
    }
}

fn read_mesh_shape(spec: &str) -> spectral_mesh::Mesh {
    let s = spectral_mesh::shapes::parse_shape(spec).unwrap();
    spectral_mesh::shapes::build(&s).unwrap()
}

#[test]
fn embed_keeps_the_triangles_and_realizes_the_distance() {
    let (_dir, [off, coords, dist]) = temp_paths(["e.off", "c.txt", "d.txt"]);
    ok_with(
        "embed sphere:res=2 --filter commute --dims 29 -k 30 -o {} --coords {}",
        &[&off, &coords],
    );
    let m = read_mesh(&off).unwrap().mesh;
    let orig = read_mesh_shape(SPHERE);
    assert_eq!(m.n_triangles(), orig.n_triangles());
    assert_eq!(m.triangles(), orig.triangles());
    let c = rows(&coords);
    assert_eq!(c.len(), 162);
    assert!(c.iter().all(|r| r.len() == 29));
    // With every non-zero pair, embedded Euclidean distance = the commute distance.
    ok_with(
        "distance sphere:res=2 --distance commute --source 4 -k 30 -o {}",
        &[&dist],
    );
    let d = values(&dist);
    for j in [0usize, 50, 161] {
        let e: f64 = (0..29)
            .map(|i| (c[4][i] - c[j][i]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((e - d[j]).abs() < 1e-9 * (1.0 + d[j]), "{e} vs {}", d[j]);
    }
}

#[test]
fn perturb_noise_moves_vertices_and_keeps_the_connectivity() {
    let (_dir, out, [off, map]) = ok_writing(
        "perturb sphere:res=2 --apply noise:0.1,seed=4 -o {} --map {}",
        ["p.off", "map.txt"],
    );
    let p = read_mesh(&off).unwrap().mesh;
    let o = read_mesh_shape(SPHERE);
    assert_eq!(p.triangles(), o.triangles());
    let moved = p
        .positions()
        .iter()
        .zip(o.positions())
        .filter(|(a, b)| a != b)
        .count();
    assert!(moved > 150, "only {moved} vertices moved");
    assert!(number_after(&out, "displacement: mean ") > 0.0, "{out}");
    // The map sends vertex i to itself: a corner of one of its triangles with weight 1.
    let r = rows(&map);
    assert_eq!(r.len(), 162);
    for (i, row) in r.iter().enumerate() {
        let tri = o.triangles()[row[0] as usize];
        let c = tri.iter().position(|&v| v == i).unwrap();
        assert_eq!(row[1 + c], 1.0);
    }
}

#[test]
fn perturb_chain_map_reproduces_resampled_positions() {
    let (_dir, _, [off, map]) = ok_writing(
        "perturb sphere:res=2 --apply resample:1.5 --apply scale:1 --apply resample:1.5,seed=2 -o {} --map {}",
        ["p.off", "map.txt"],
    );
    let p = read_mesh(&off).unwrap().mesh;
    let o = read_mesh_shape(SPHERE);
    let r = rows(&map);
    assert_eq!(r.len(), p.n_vertices());
    assert!(p.n_vertices() > 300);
    // Resampling keeps every vertex on the original surface: the map gives it back.
    for (row, q) in r.iter().zip(p.positions()) {
        let tri = o.triangles()[row[0] as usize];
        assert!((row[1] + row[2] + row[3] - 1.0).abs() < 1e-12);
        for d in 0..3 {
            let x: f64 = (0..3).map(|c| row[1 + c] * o.positions()[tri[c]][d]).sum();
            assert!((x - q[d]).abs() < 1e-9, "{x} vs {}", q[d]);
        }
    }
    let e = err_with("perturb sphere:res=2 --apply wobble:3 -o {}", &[&off]);
    assert!(e.contains("--apply wobble:3"), "{e}");
}

#[test]
fn outputs_are_never_overwritten_without_force() {
    let (dir, [txt]) = temp_paths(["h.txt"]);
    std::fs::write(&txt, "keep me\n").unwrap();
    for args in [
        vec!["heat", SPHERE, "-k", "5", "-o", s(&txt)],
        vec!["distance", SPHERE, "-k", "5", "-o", s(&txt)],
        vec!["signature", SPHERE, "-k", "5", "-o", s(&txt)],
        vec!["segment", SPHERE, "-k", "5", "-o", s(&txt)],
        vec!["eigs", SPHERE, "-k", "5", "--eigenvalues-txt", s(&txt)],
        vec!["embed", SPHERE, "-k", "5", "--coords", s(&txt)],
        vec![
            "perturb",
            SPHERE,
            "--apply",
            "scale:2",
            "-o",
            "x.off",
            "--map",
            s(&txt),
        ],
    ] {
        let e = err(&args);
        assert!(e.contains("already exists") && e.contains("--force"), "{e}");
        assert_eq!(std::fs::read_to_string(&txt).unwrap(), "keep me\n");
    }
    assert!(!Path::new("x.off").exists());
    ok_with("heat sphere:res=2 -k 5 -o {} --force", &[&txt]);
    assert_eq!(values(&txt).len(), 162);
    // Unknown output types are refused before any computation.
    let e = err(&["heat", SPHERE, "-o", s(&dir.path().join("h.jpg"))]);
    assert!(
        e.contains("h.jpg") && e.contains("unknown output type"),
        "{e}"
    );
}

#[test]
fn eigs_npz_reads_back_with_the_same_eigenvalues() {
    let (dir, _, [npz, ev]) = ok_writing(
        "eigs sphere:res=2 -k 12 --laplacian voronoi-cot -o {} --eigenvalues-txt {}",
        ["basis.npz", "ev.txt"],
    );
    let (basis, meta) = spectral_mesh::spectral::store::load_npz(&npz).unwrap();
    let v = values(&ev);
    assert_eq!(
        basis.values, v,
        "the text and the archive agree bit for bit"
    );
    assert_eq!(basis.n, 162);
    assert_eq!(meta.k, 12);
    assert_eq!(basis.laplacian.name(), "voronoi-cot");
    assert!(basis.values[0].abs() < 1e-8);
    // No temporary file is left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(names.len(), 2);
    // Refuses to overwrite, and a wrong extension.
    let e = err_with("eigs sphere:res=2 -k 3 -o {}", &[&npz]);
    assert!(e.contains("already exists"), "{e}");
    let e = err(&[
        "eigs",
        SPHERE,
        "-k",
        "3",
        "-o",
        s(&dir.path().join("b.npy")),
    ]);
    assert!(e.contains(".npz"), "{e}");
    // NumPy reads it, when available.
    let script = format!(
        "import numpy as np\nf = np.load(r'{}')\nprint(f['eigenvalues'].shape, f['eigenvectors'].shape)\nprint(repr(float(f['eigenvalues'][5])))",
        npz.display()
    );
    match Command::new("python3").args(["-c", &script]).output() {
        Ok(o) if o.status.success() => {
            let text = String::from_utf8_lossy(&o.stdout);
            assert!(text.contains("(12,) (162, 12)"), "{text}");
            let last: f64 = text.lines().last().unwrap().trim().parse().unwrap();
            assert_eq!(last, v[5]);
        }
        _ => eprintln!("skipped the NumPy check: python3 with numpy is not available"),
    }
}

#[test]
fn cache_is_filled_then_used() {
    let (_dir, [cache, a, b]) = temp_paths(["cache", "a.txt", "b.txt"]);
    let first = ok_with("distance sphere:res=2 -k 8 --cache {} -o {}", &[&cache, &a]);
    assert!(first.contains("computed and stored in"), "{first}");
    let second = ok_with("distance sphere:res=2 -k 8 --cache {} -o {}", &[&cache, &b]);
    assert!(second.contains("loaded from"), "{second}");
    assert_eq!(values(&a), values(&b));
}

#[test]
fn eigs_certify_counts_the_sphere_clusters_and_float32_is_the_float64_basis_rounded() {
    // 1 + 3 + 5 = 9 pairs end a cluster of the sphere's spectrum: the inertia count agrees.
    let out = ok(&["eigs", "sphere:res=2", "-k", "9", "--certify"]);
    assert!(
        out.contains("certified: no eigenvalue up to lambda_9 was skipped"),
        "{out}"
    );
    assert!(out.contains("certificate time:"), "{out}");
    let (dir, [b64, b32]) = temp_paths(["b64.npz", "b32.npz"]);
    ok_with("eigs sphere:res=2 -k 9 -o {}", &[&b64]);
    let out = ok_with("eigs sphere:res=2 -k 9 --dtype float32 -o {}", &[&b32]);
    assert!(out.contains("basis (float32)"), "{out}");
    let (x64, _) = spectral_mesh::spectral::store::load_npz(&b64).unwrap();
    let (x32, m32) = spectral_mesh::spectral::store::load_npz(&b32).unwrap();
    assert_eq!(m32.dtype.name(), "float32");
    let round = |v: &[f64]| -> Vec<f64> { v.iter().map(|&x| f64::from(x as f32)).collect() };
    assert_eq!(x32.values, round(&x64.values));
    assert_eq!(x32.vectors, round(&x64.vectors));
    let bad = dir.path().join("bad.npz");
    let e = err_with("eigs sphere:res=2 -k 3 --dtype float16 -o {}", &[&bad]);
    assert!(e.contains("--dtype"), "{e}");
    assert!(!bad.exists());
}

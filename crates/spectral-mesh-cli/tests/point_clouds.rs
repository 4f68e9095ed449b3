//! Point files through the spectral commands: the right number of zero eigenvalues (one per
//! separate piece), finite fields, pictures with coloured discs where the points are, point
//! sets as .ply, and refusals that name what does not apply.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::fmt::Write as _;
use std::path::Path;

use spectral_mesh::Mesh;
use spectral_mesh::io::{Input, read_input};
use spectral_mesh_render::raster::{Camera, RenderOptions, View};

mod common;
use common::*;

/// `n` points on the sphere of radius `r` centred at `c` (Fibonacci lattice).
fn sphere(n: usize, r: f64, c: [f64; 3]) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let (rs, th) = (r * (1.0 - y * y).sqrt(), golden * i as f64); // ring radius, angle
            [c[0] + rs * th.cos(), c[1] + r * y, c[2] + rs * th.sin()]
        })
        .collect()
}

/// Two unit spheres of 700 points each, 3 apart, and a small third one: three pieces.
fn three_pieces() -> Vec<[f64; 3]> {
    let mut p = sphere(700, 1.0, [0.0, 0.0, 0.0]);
    p.extend(sphere(700, 1.0, [3.0, 0.0, 0.0]));
    p.extend(sphere(300, 0.5, [0.0, 3.0, 0.0]));
    p
}

fn write_xyz(path: &Path, pts: &[[f64; 3]]) {
    let mut s = String::from("# three separate spheres\n");
    for p in pts {
        writeln!(s, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn a_point_file_gives_one_zero_eigenvalue_per_piece_and_finite_fields() {
    let dir = tempfile::tempdir().unwrap();
    let pts = three_pieces();
    let xyz = dir.path().join("pieces.xyz");
    write_xyz(&xyz, &pts);
    let f = xyz.to_str().unwrap();
    let ev = dir.path().join("ev.txt");
    let out = ok(&[
        "eigs",
        f,
        "-k",
        "12",
        "--eigenvalues-txt",
        ev.to_str().unwrap(),
    ]);
    assert!(out.contains("point cloud"), "{out}");
    assert!(out.contains("robust discretization"), "{out}");
    assert!(!out.contains("MISMATCH"), "{out}");
    let ev = values(&ev);
    assert_eq!(ev.len(), 12);
    let top = ev.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let zeros = ev.iter().filter(|v| v.abs() <= 1e-9 * top).count();
    assert_eq!(zeros, 3, "{ev:?}");
    // The first non-zero pairs: l = 1 of the two unit spheres, 2 (x 6), within 2%.
    for v in &ev[3..9] {
        assert!((v - 2.0).abs() < 0.04, "{ev:?}");
    }

    // Fewer pairs than pieces: every pair is a zero one, as expected (no mismatch), and a
    // distance is refused with the reason.
    let out = ok(&["eigs", f, "-k", "2"]);
    assert!(out.contains("): 2; expected 2 (3 components)"), "{out}");
    assert!(!out.contains("MISMATCH"), "{out}");
    let e = err(&["distance", f, "-k", "3", "-o", "x.txt"]);
    assert!(e.contains("separate pieces"), "{e}");

    let d = dir.path().join("d.txt");
    ok(&["distance", f, "-k", "20", "-o", d.to_str().unwrap()]);
    let dv = values(&d);
    assert_eq!(dv.len(), pts.len());
    assert!(dv.iter().all(|v| v.is_finite() && *v >= 0.0));
    assert!(dv.iter().any(|v| *v > 0.0));

    let h = dir.path().join("h.txt");
    ok(&[
        "heat",
        f,
        "-k",
        "20",
        "--t",
        "0.01",
        "-o",
        h.to_str().unwrap(),
    ]);
    let hv = values(&h);
    assert_eq!(hv.len(), pts.len());
    assert!(hv.iter().all(|v| v.is_finite()));
    // Heat from the anchor (largest x: on the second sphere) stays on its piece.
    let anchor_piece = 700..1400;
    let outside: f64 = hv
        .iter()
        .enumerate()
        .filter(|(i, _)| !anchor_piece.contains(i))
        .map(|(_, v)| v.abs())
        .fold(0.0, f64::max);
    let inside = hv[anchor_piece].iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(outside < 1e-6 * inside, "{outside} vs {inside}");
}

#[test]
fn a_point_cloud_field_picture_has_coloured_discs_where_the_points_are() {
    let dir = tempfile::tempdir().unwrap();
    let pts = sphere(1500, 1.0, [0.0, 0.0, 0.0]);
    let xyz = dir.path().join("ball.xyz");
    write_xyz(&xyz, &pts);
    let png = dir.path().join("d.png");
    let ply = dir.path().join("d.ply");
    let wrl = dir.path().join("d.wrl");
    let size = 240u32;
    ok(&[
        "distance",
        xyz.to_str().unwrap(),
        "-k",
        "20",
        "-o",
        png.to_str().unwrap(),
        "-o",
        ply.to_str().unwrap(),
        "-o",
        wrl.to_str().unwrap(),
        "--size",
        &size.to_string(),
        "--levels",
        "0",
        "--no-critical-points",
        "--no-colorbar",
    ]);
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!((info.width, info.height), (size, size));
    let px = |x: u32, y: u32| {
        let o = ((y * size + x) * 4) as usize;
        [buf[o], buf[o + 1], buf[o + 2]]
    };
    let coloured = |c: [u8; 3]| {
        let (lo, hi) = (c.iter().min().unwrap(), c.iter().max().unwrap());
        hi - lo > 40
    };
    // Project every point with the camera the picture used (no colour bar: the whole width).
    let mesh = Mesh::new(pts.clone(), vec![[0, 1, 2]]).unwrap();
    let opts = RenderOptions {
        width: size,
        height: size,
        view: View::Iso,
        ..RenderOptions::default()
    };
    let cam = Camera::fit(&mesh, &opts, size);
    let hits = pts
        .iter()
        .filter(|p| {
            let [x, y, _] = cam.project(**p);
            coloured(px(x as u32, y as u32))
        })
        .count();
    assert!(hits * 100 >= pts.len() * 95, "{hits} of {}", pts.len());
    // Away from the sphere the background stays white.
    assert_eq!(px(2, 2), [255, 255, 255]);
    assert_eq!(px(size - 3, size - 3), [255, 255, 255]);
    // The .ply is a point set that reads back as a point cloud, the .wrl a PointSet.
    let text = std::fs::read_to_string(&ply).unwrap();
    assert!(text.contains("property double value") && !text.contains("element face"));
    match read_input(&ply).unwrap() {
        Input::Points(p) => assert_eq!(p.cloud.n_points(), pts.len()),
        Input::Mesh(_) => panic!("the .ply of a point cloud read back as a mesh"),
    }
    let w = std::fs::read_to_string(&wrl).unwrap();
    assert!(
        w.contains("PointSet") && !w.contains("IndexedFaceSet"),
        "{w:.400}"
    );
}

#[test]
fn what_does_not_apply_to_a_point_cloud_says_so_by_name() {
    let (dir, [xyz]) = temp_paths(["ball.xyz"]);
    write_xyz(&xyz, &sphere(200, 1.0, [0.0; 3]));
    let f = xyz.to_str().unwrap();
    let e = err(&["eigs", f, "-k", "5", "--laplacian", "fem"]);
    assert!(
        e.contains("--laplacian fem does not apply to a point cloud"),
        "{e}"
    );
    let e = err(&["convert", f, dir.path().join("x.off").to_str().unwrap()]);
    assert!(e.contains("convert does not apply to a point cloud"), "{e}");
    let e = err(&["distance", f, "--repair", "-o", "x.txt"]);
    assert!(
        e.contains("--repair does not apply to a point cloud"),
        "{e}"
    );
    // The help lists robust and says what applies to point clouds.
    let help = ok_with("distance --help", &[]);
    assert!(
        help.contains("robust") && help.to_lowercase().contains("point cloud"),
        "{help}"
    );
}

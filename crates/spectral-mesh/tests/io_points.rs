//! Point-cloud reading: every format, `read_input`'s choice between mesh and points, and
//! every error naming the file, the line and the problem.

#![allow(clippy::unwrap_used)]

mod io_util;

use io_util::{check, check_all};

use spectral_mesh::io::{
    Input, IoError, PointFormat, read_input, read_input_from_bytes, read_mesh_from_bytes,
    read_points_from_bytes,
};

fn points(src: &[u8], name: &str) -> spectral_mesh::io::LoadedPoints {
    match read_input_from_bytes(src, name).unwrap() {
        Input::Points(p) => p,
        Input::Mesh(_) => panic!("{name}: read as a mesh"),
    }
}

fn err(src: &[u8], name: &str) -> IoError {
    match read_input_from_bytes(src, name) {
        Ok(i) => panic!("{name}: expected an error, got {} points", i.n_points()),
        Err(e) => e,
    }
}

#[test]
fn text_formats_read_positions_normals_comments_counts_and_headers() {
    let p = points(b"# a comment\n0 0 0\n\n1 2 3 # trailing\n4 5 6\n", "a.xyz");
    assert_eq!(p.format, PointFormat::Xyz);
    assert_eq!(
        p.cloud.positions(),
        &[[0.0, 0.0, 0.0], [1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]
    );
    assert!(p.cloud.normals().is_none());
    let p = points(b"0 0 0 0 0 1\n1 0 0 0 0 2\n", "b.txt");
    assert_eq!(p.cloud.normals().unwrap()[1], [0.0, 0.0, 2.0]);
    // .pts with a count line, commas and semicolons, a column header.
    let p = points(b"2\n0,0,0\n1;1;1\n", "c.pts");
    assert_eq!(p.cloud.n_points(), 2);
    let p = points(b"x y z nx ny nz\n0 0 0 1 0 0\n", "d.csv");
    assert_eq!(p.cloud.n_points(), 1);
    assert!(p.warnings[0].contains("column header"), "{:?}", p.warnings);
    // All-zero normals are dropped; some zero ones are kept as unknown.
    let p = points(b"0 0 0 0 0 0\n1 0 0 0 0 0\n", "e.xyz");
    assert!(p.cloud.normals().is_none());
    assert!(
        p.warnings
            .iter()
            .any(|w| w.contains("every normal is zero"))
    );
    let p = points(b"0 0 0 0 0 0\n1 0 0 0 0 1\n", "f.xyz");
    assert_eq!(p.cloud.n_normals(), 1);
    // No extension: the content decides.
    let p = points(b"0.5 1 2\n3 4 5\n", "noext");
    assert_eq!(p.cloud.n_points(), 2);
    assert!(p.warnings[0].contains("point list"));
}

#[test]
fn ply_without_faces_is_a_point_cloud_and_with_faces_a_mesh() {
    let ascii = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n";
    let p = points(ascii, "v.ply");
    assert_eq!(p.format, PointFormat::Ply);
    assert_eq!(p.cloud.n_points(), 3);
    assert_eq!(p.cloud.normals().unwrap()[2], [0.0, 0.0, 1.0]);
    // The mesh reader still refuses it, with the message it always gave.
    let e = read_mesh_from_bytes(ascii, "v.ply").unwrap_err();
    assert_eq!(
        e.to_string(),
        "v.ply: the PLY file has no 'face' element (a point cloud is not a mesh)"
    );
    // Binary little-endian doubles, as CGAL writes them.
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n".to_vec();
    for v in [1.0f64, 2.0, 3.0, -1.0, 0.5, 0.25] {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    let p = points(&bin, "b.ply");
    assert_eq!(p.cloud.positions(), &[[1.0, 2.0, 3.0], [-1.0, 0.5, 0.25]]);
    // A truncated payload is an error naming the file.
    // (The header's counts are checked against the payload first: the error names the
    // element's header line.)
    let e = err(&bin[..bin.len() - 5], "cut.ply");
    assert!(e.to_string().starts_with("cut.ply:3: "), "{e}");
    assert!(e.to_string().contains("truncated"), "{e}");
    // With faces: a mesh.
    let mesh = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    assert!(matches!(
        read_input_from_bytes(mesh, "m.ply").unwrap(),
        Input::Mesh(_)
    ));
    // A face element with no faces: points.
    let none = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n";
    assert_eq!(points(none, "z.ply").cloud.n_points(), 1);
    // read_points ignores faces, with a warning.
    let p = read_points_from_bytes(mesh, "m.ply").unwrap();
    assert!(p.warnings.iter().any(|w| w.contains("faces")));
    // Other mesh formats go to the mesh reader.
    let off = b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    assert!(matches!(
        read_input_from_bytes(off, "t.off").unwrap(),
        Input::Mesh(_)
    ));
}

#[test]
fn every_text_error_names_the_file_the_line_and_the_problem() {
    #[rustfmt::skip]
    let cases: &[(&[u8], &str, &str)] = &[
        (b"0 0 0\n1 2\n", "a.xyz:2: ", "2 values on this line, but line 1 has 3"),
        (b"# c\n1 2 3 4\n", "a.xyz:2: ", "expected 3 (x y z) or 6"),
        (b"0 0 0\n1 zz 3\n", "a.xyz:2: ", "y = \"zz\" is not a number"),
        (b"0 0 0\n1 nan 3\n", "a.xyz:2: ", "non-finite coordinate (y = nan)"),
        (b"0 0 0 0 inf 0\n", "a.xyz:1: ", "non-finite normal component (ny = inf)"),
        (b"3\n0 0 0\n1 1 1\n", "a.pts:1: ", "says 3 points but the file has 2"),
        (b"0 0 0\n\xff\xfe 1 1\n", "a.xyz:2: ", "not text"),
        (b"# only comments\n\n", "a.xyz: ", "no points"),
        (b"", "a.xyz: ", "empty"),
    ];
    check_all(err, cases);
    let e = err(b"0 0 0\n1 2\n", "dir/x.txt");
    assert_eq!(e.path(), "dir/x.txt");
    assert_eq!(e.line(), Some(2));
    // PLY vertex records with NaN or missing properties.
    let mut ply = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\nproperty double z\nend_header\n".to_vec();
    for v in [0.0f64, 0.0, 0.0, 1.0, f64::NAN, 0.0] {
        ply.extend_from_slice(&v.to_le_bytes());
    }
    check(
        &err(&ply, "n.ply"),
        "n.ply: ",
        "vertex 1 has a non-finite coordinate (y = NaN)",
    );
    let noz = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n";
    check(&err(noz, "z.ply"), "z.ply: ", "no 'z' property");
}

#[test]
fn shared_point_clouds_load_with_their_counts() {
    let Some(dir) = spectral_mesh_testkit::shared_points() else {
        return;
    };
    for (f, n, normals) in [
        ("sphere_20k.xyz", 21000, 0),
        ("kitten.xyz", 5210, 5210),
        ("blobby.xyz", 3288, 0),
        ("fin90_with_PCA_normals.xyz", 757, 757),
        ("hippo1.ply", 6104, 6104),
        ("oni.ply", 1435, 1435),
    ] {
        let Input::Points(p) = read_input(&dir.join(f)).unwrap() else {
            panic!("{f}: read as a mesh");
        };
        assert_eq!(p.cloud.n_points(), n, "{f}");
        assert_eq!(p.cloud.n_normals(), normals, "{f}");
    }
}

//! Every kind of bad input gives an error naming the file, the line and the problem.

#![allow(clippy::unwrap_used)]

mod io_util;

use io_util::{check, check_all};

use spectral_mesh::io::{IoError, read_mesh, read_mesh_from_bytes};

fn err(src: &[u8], name: &str) -> IoError {
    match read_mesh_from_bytes(src, name) {
        Ok(l) => panic!(
            "{name}: expected an error, got {} vertices / {} triangles",
            l.mesh.n_vertices(),
            l.mesh.n_triangles()
        ),
        Err(e) => e,
    }
}

const TETRA_HEAD: &str = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n";

#[test]
fn off_index_out_of_range_message_is_exact() {
    let src = format!("{TETRA_HEAD}3 0 2 1\n3 0 1 9\n3 1 2 3\n3 0 3 2\n");
    let e = err(src.as_bytes(), "dir/t.off");
    assert_eq!(
        e.to_string(),
        "dir/t.off:8: face 1 refers to vertex 9 but the file has 4 vertices"
    );
    assert_eq!(e.path(), "dir/t.off");
    assert_eq!(e.line(), Some(8));
    let src = format!("{TETRA_HEAD}3 0 2 -1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
    check(
        &err(src.as_bytes(), "t.off"),
        "t.off:7: ",
        "refers to vertex -1",
    );
}

#[test]
fn off_truncated_and_wrong_counts() {
    #[rustfmt::skip]
    let cases = [
        // Truncated inside the vertices.
        ("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1".into(), "t.off:5: ", "ends inside vertex 2 of 4"),
        // Header promises more faces than there are.
        (format!("{TETRA_HEAD}3 0 2 1\n3 0 1 3\n"), "t.off:9: ", "after 2 of 4 faces"),
        // Truncated inside a face.
        (format!("{TETRA_HEAD}3 0 2 1\n3 0 1"), "t.off:8: ", "inside face 1"),
        // Header promises more vertices: the faces get read as coordinates and run out.
        ("OFF\n5 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n".into(), "t.off:7: ",
         "ends inside vertex 4 of 5"),
        // Counts that are not numbers.
        ("OFF\nfour 4 0\n".into(), "t.off:2: ", "vertex count 'four'"),
        ("OFF\n".into(), "t.off:", "before the vertex count"),
    ];
    check_all::<String>(err, &cases);
}

#[test]
fn off_non_finite_and_non_numeric_coordinates() {
    #[rustfmt::skip]
    let cases: &[(&[u8], &str, &str)] = &[
        (b"OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
         "n.off:4: ", "vertex 1 has a non-finite coordinate (y = NaN)"),
        (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 inf\n3 0 1 2\n",
         "n.off:5: ", "non-finite coordinate (z = inf)"),
        (b"OFF\n3 1 0\n0 0 0\n1 0 x0\n0 1 0\n3 0 1 2\n",
         "n.off:4: ", "coordinate z 'x0' is not a number"),
    ];
    check_all(err, cases);
}

#[test]
fn off_small_faces_and_repeated_vertices() {
    #[rustfmt::skip]
    let cases = [
        (format!("{TETRA_HEAD}2 0 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n"), "f.off:7: ",
         "face 0 has 2 vertices; a face needs at least 3"),
        (format!("{TETRA_HEAD}3 0 2 1\n3 0 1 3\n4 1 2 3 1\n3 0 3 2\n"), "f.off:9: ",
         "face 2 uses vertex 1 more than once"),
    ];
    check_all::<String>(err, &cases);
}

#[test]
fn empty_meshes_and_empty_files() {
    #[rustfmt::skip]
    let cases: &[(&[u8], &str, &str)] = &[
        (b"OFF\n0 0 0\n", "e.off: ", "empty"),
        (b"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", "e.off: ", "no faces"),
        (b"", "e.off: ", "empty"),
        (b"# only a comment\n", "e.off: ", "no content"),
        (b"v 0 0 0\n", "e.obj: ", "no faces"),
    ];
    check_all(err, cases);
}

#[test]
fn unknown_format_and_unreadable_file() {
    let e = err(b"hello world\n", "notes.txt");
    assert!(matches!(e, IoError::UnknownFormat { .. }));
    check(&e, "notes.txt: ", "unknown mesh format");
    let e = err(b"\x00\x01\x02", "blob");
    assert!(matches!(e, IoError::UnknownFormat { .. }));
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("missing.off");
    let e = read_mesh(&p).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }));
    check(&e, &p.display().to_string(), "cannot read");
    // A folder is not readable as a file either.
    let e = read_mesh(dir.path()).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }), "{e}");
}

#[test]
fn obj_errors_name_lines_and_one_based_indices() {
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    #[rustfmt::skip]
    let cases = [
        (format!("{head}f 1 2 4\n"), "m.obj:4: ",
         "face 0 refers to vertex 4 but the file has 3 vertices"),
        (format!("{head}f 1 2 0\n"), "m.obj:4: ", "OBJ indices start at 1"),
        (format!("{head}\nf -1 -2 -4\n"), "m.obj:5: ",
         "refers to vertex -4 (relative) but only 3 vertices"),
        (format!("{head}f 1 2\n"), "m.obj:4: ", "face 0 has 2 vertices"),
        (format!("{head}f 1 2 2\n"), "m.obj:4: ", "uses vertex 2 more than once"),
        ("v 0 0\nf 1 2 3\n".into(), "m.obj:1: ", "vertex 1 has 2 coordinates"),
        ("v 0 0 0\nv 0 -inf 0\nv 0 1 0\nf 1 2 3\n".into(),
         "m.obj:2: ", "vertex 2 has a non-finite coordinate (y = -inf)"),
        (format!("{head}f 1/x 2 3\n"), "m.obj:4: ", "not of the form"),
    ];
    check_all::<String>(err, &cases);
}

const PLY_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn ply_errors() {
    // Index out of range, with the line of the face in an ASCII file.
    check(
        &err(
            format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n").as_bytes(),
            "p.ply",
        ),
        "p.ply:13: ",
        "face 0 refers to vertex 5 but the file has 3 vertices",
    );
    // Truncated ASCII payload.
    let e = err(format!("{PLY_HEAD}0 0 0\n1 0 0\n").as_bytes(), "p.ply");
    assert!(e.to_string().starts_with("p.ply:"), "{e}");
    assert!(e.line().is_some(), "{e}");
    // NaN coordinate: refused by the ASCII grammar already, on its line.
    check(
        &err(
            format!("{PLY_HEAD}0 0 0\n1 NaN 0\n0 1 0\n3 0 1 2\n").as_bytes(),
            "p.ply",
        ),
        "p.ply:11: ",
        "PLY",
    );
    // NaN in a binary file: refused by our check.
    let mut b = PLY_HEAD
        .replace("ascii", "binary_little_endian")
        .into_bytes();
    for c in [0.0f32, 0.0, 0.0, 1.0, f32::NAN, 0.0, 0.0, 1.0, 0.0] {
        b.extend(c.to_le_bytes());
    }
    b.push(3);
    for i in [0i32, 1, 2] {
        b.extend(i.to_le_bytes());
    }
    check(
        &err(&b, "b.ply"),
        "b.ply: ",
        "vertex 1 has a non-finite coordinate (y = NaN)",
    );
    // Truncated binary payload.
    let mut b = PLY_HEAD
        .replace("ascii", "binary_little_endian")
        .into_bytes();
    b.extend([0u8; 20]);
    let e = err(&b, "b.ply");
    // Found before reading: the header's counts need more bytes than the payload has.
    check(
        &e,
        "b.ply:3: ",
        "element 'vertex' announces 3 records, more than the 20 bytes of binary payload",
    );
    // No faces: a point cloud.
    let src = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
    check(
        &err(src.as_bytes(), "p.ply"),
        "p.ply: ",
        "no 'face' element",
    );
    // A malformed header line.
    let e = err(
        b"ply\nformat ascii 1.0\nelement vertex three\nend_header\n",
        "h.ply",
    );
    check(&e, "h.ply:3: ", "PLY");
}

#[test]
fn stl_errors() {
    // Binary STL whose size does not match its triangle count.
    let mut b = vec![0u8; 80];
    b.extend(5u32.to_le_bytes());
    b.extend([0u8; 100]);
    check(&err(&b, "x.stl"), "x.stl: ", "announces 5 triangles");
    // Too short to be anything.
    check(&err(b"abc", "x.stl"), "x.stl: ", "not an STL file");
    // Malformed ASCII.
    let src = "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\n";
    check(
        &err(src.as_bytes(), "x.stl"),
        "x.stl:5: ",
        "ASCII STL, facet 0",
    );
    // Non-finite binary coordinate.
    let mut b = vec![0u8; 80];
    b.extend(1u32.to_le_bytes());
    b.extend([0u8; 12]);
    for c in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, f32::NAN, 1.0, 0.0] {
        b.extend(c.to_le_bytes());
    }
    b.extend([0u8; 2]);
    check(&err(&b, "x.stl"), "x.stl: ", "non-finite");
}

//! Reading every supported format and variant, and format detection.

#![allow(clippy::unwrap_used)]

use spectral_mesh::io::{MeshFormat, read_mesh_from_bytes};

fn load(text: &str, name: &str) -> spectral_mesh::io::LoadedMesh {
    match read_mesh_from_bytes(text.as_bytes(), name) {
        Ok(l) => l,
        Err(e) => panic!("{name} failed: {e}"),
    }
}

// ---------------------------------------------------------------- OFF

#[test]
fn off_plain_with_comments_blank_lines_and_split_counts() {
    let src = "# leading comment\n\nOFF # header comment\n4\n\n2 # face count\n0\n\
               0 0 0 # v0\n1 0 0\n\n0 1 0\n0 0 1 #last\n3 0 2 1 # f0\n3 0 1 3\n";
    let l = load(src, "a.off");
    assert_eq!(l.format, MeshFormat::Off);
    assert_eq!(l.mesh.n_vertices(), 4);
    assert_eq!(l.mesh.triangles(), &[[0, 2, 1], [0, 1, 3]]);
    assert_eq!(l.mesh.positions()[3], [0.0, 0.0, 1.0]);
    assert_eq!(l.polygons_triangulated, 0);
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
}

#[test]
fn off_counts_on_header_line_and_nonzero_edge_count_ignored() {
    let l = load("OFF 3 1 99\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "t.off");
    assert_eq!(l.mesh.n_triangles(), 1);
    assert!(l.warnings.is_empty());
    // Without an edge count: accepted with a warning.
    let l = load("OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "t.off");
    assert_eq!(l.mesh.positions()[1], [1.0, 0.0, 0.0]);
    assert!(l.warnings.iter().any(|w| w.contains("edge count")));
}

#[test]
fn off_coff_colours_rgba_bytes() {
    let src = "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2\n";
    let l = load(src, "c.off");
    let c = l.vertex_colors.expect("colours");
    assert_eq!(c, vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    // Float colours in [0, 1] with 3 components are kept as they are.
    let src = "COFF\n3 1 0\n0 0 0 0.5 0 0\n1 0 0 0 0.25 0\n0 1 0 0 0 1\n3 0 1 2\n";
    let c = load(src, "c.off").vertex_colors.expect("colours");
    assert_eq!(c[0], [0.5, 0.0, 0.0]);
    assert_eq!(c[1], [0.0, 0.25, 0.0]);
}

#[test]
fn off_noff_cnoff_stoff_stcnoff() {
    let l = load(
        "NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n",
        "n.off",
    );
    assert_eq!(l.mesh.positions()[2], [0.0, 1.0, 0.0]);
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    let l = load(
        "CNOFF\n3 1 0\n0 0 0 0 0 1 1 0 0 1\n1 0 0 0 0 1 0 1 0 1\n0 1 0 0 0 1 0 0 1 1\n3 0 1 2\n",
        "cn.off",
    );
    assert_eq!(l.vertex_colors.expect("colours")[1], [0.0, 1.0, 0.0]);
    assert_eq!(l.mesh.positions()[1], [1.0, 0.0, 0.0]);
    let l = load(
        "STOFF\n3 1 0\n0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n",
        "st.off",
    );
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    assert_eq!(l.mesh.n_vertices(), 3);
    let l = load(
        "STCNOFF\n3 1 0\n0 0 0 0 0 1 9 9 9 0 0\n1 0 0 0 0 1 9 9 9 1 0\n0 1 0 0 0 1 9 9 9 0 1\n3 0 1 2\n",
        "stcn.off",
    );
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    assert_eq!(l.vertex_colors.expect("colours")[0], [9.0 / 255.0; 3]);
}

#[test]
fn off_four_dimensional_and_binary_are_refused_clearly() {
    let e = read_mesh_from_bytes(b"4OFF\n3 1 0\n0 0 0 1\n", "x.off").unwrap_err();
    assert!(e.to_string().starts_with("x.off:1: "), "{e}");
    assert!(e.to_string().contains("not supported"), "{e}");
    let e = read_mesh_from_bytes(b"OFF BINARY\n", "x.off").unwrap_err();
    assert!(e.to_string().contains("binary OFF"), "{e}");
}

#[test]
fn off_polygons_and_face_colours() {
    // A unit square as one quad (with a face colour) plus a pentagon roof.
    let src = "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 1.5 0\n\
               4 0 1 2 3 255 0 0\n4 3 2 4 3\n";
    // The second face claims 4 vertices but lists 3 + colour "3": an index 3 is repeated.
    let e = read_mesh_from_bytes(src.as_bytes(), "p.off").unwrap_err();
    assert!(
        e.to_string()
            .contains("p.off:9: face 1 uses vertex 3 more than once"),
        "{e}"
    );
    let src = "OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 1.5 0\n\
               4 0 1 2 3 255 0 0\n3 3 2 4 0.1 0.2 0.3 1\n";
    let l = load(src, "p.off");
    assert_eq!(l.mesh.n_triangles(), 3);
    assert_eq!(l.polygons_triangulated, 1);
    assert!((l.mesh.area() - 1.25).abs() < 1e-12);
    // Every triangle keeps the polygon's (counter-clockwise) winding.
    for n in l.mesh.triangle_normals() {
        assert!(n[2] > 0.99);
    }
}

#[test]
fn off_leading_comment_block_before_header() {
    let src = "# Output of a tool\n#CBP\n# ENDCBP\n\nOFF\n3 1 0\n\n# 3 vertices\n0 0 0\n1 0 0\n0 1 0\n\n# 1 facet\n3 0 1 2\n";
    let l = load(src, "s.off");
    assert_eq!(l.mesh.n_triangles(), 1);
}

#[test]
fn off_without_header_keyword_is_read_with_a_warning() {
    let l = load("3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "h.off");
    assert_eq!(l.mesh.n_triangles(), 1);
    assert!(l.warnings.iter().any(|w| w.contains("header")));
}

// ---------------------------------------------------------------- OBJ

#[test]
fn obj_slashes_negative_indices_polygons_and_ignored_statements() {
    let src = "# comment\nmtllib x.mtl\no thing\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\ng group\nusemtl m\ns 1\n\
               f 1/1/1 2/2/1 3/3/1 4/1/1\n\
               v 0 0 1\nf -1//1 -4//1 -5//1\nf 5/1 2/2 1/3\n";
    let l = load(src, "m.obj");
    assert_eq!(l.format, MeshFormat::Obj);
    assert_eq!(l.mesh.n_vertices(), 5);
    assert_eq!(l.polygons_triangulated, 1);
    assert_eq!(l.mesh.n_triangles(), 4);
    // -1 is vertex 5 (index 4), -4 is vertex 2 (index 1), -5 is vertex 1 (index 0).
    assert_eq!(l.mesh.triangles()[2], [4, 1, 0]);
    assert_eq!(l.mesh.triangles()[3], [4, 1, 0]);
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
}

#[test]
fn obj_vertex_colours_continuation_and_unknown_statements() {
    let src = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nf 1 \\\n 2 3\nfoo bar\n";
    let l = load(src, "c.obj");
    assert_eq!(l.mesh.triangles(), &[[0, 1, 2]]);
    assert_eq!(l.vertex_colors.expect("colours")[2], [0.0, 0.0, 1.0]);
    assert!(
        l.warnings.iter().any(|w| w.contains("foo")),
        "{:?}",
        l.warnings
    );
}

// ---------------------------------------------------------------- PLY

fn ply_ascii(face_prop: &str) -> String {
    format!(
        "ply\nformat ascii 1.0\ncomment hi\nelement vertex 4\nproperty float x\nproperty double y\n\
         property int z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face 1\nproperty list uchar uint {face_prop}\nend_header\n\
         0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 2 255 255 255\n4 0 1 2 3\n"
    )
}

#[test]
fn ply_ascii_mixed_types_colours_and_both_index_names() {
    for name in ["vertex_indices", "vertex_index"] {
        let l = load(&ply_ascii(name), "a.ply");
        assert_eq!(l.format, MeshFormat::Ply);
        assert_eq!(l.mesh.n_vertices(), 4);
        assert_eq!(l.mesh.n_triangles(), 2);
        assert_eq!(l.polygons_triangulated, 1);
        assert_eq!(l.mesh.positions()[3], [0.0, 1.0, 2.0]);
        let c = l.vertex_colors.expect("colours");
        assert_eq!(c[1], [0.0, 1.0, 0.0]);
        assert_eq!(c[3], [1.0, 1.0, 1.0]);
    }
}

/// A binary PLY of a tetrahedron with float x, double y, short z and int indices.
fn ply_binary(big_endian: bool) -> Vec<u8> {
    let p = [
        [0.1f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ];
    let t = [[0i32, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut b = format!(
        "ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty double y\n\
         property short z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    for v in p {
        let (x, y, z) = (v[0], f64::from(v[1]), v[2] as i16);
        if big_endian {
            b.extend(x.to_be_bytes());
            b.extend(y.to_be_bytes());
            b.extend(z.to_be_bytes());
        } else {
            b.extend(x.to_le_bytes());
            b.extend(y.to_le_bytes());
            b.extend(z.to_le_bytes());
        }
    }
    for f in t {
        b.push(3);
        for i in f {
            b.extend(if big_endian {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
    }
    b
}

#[test]
fn ply_binary_both_endians() {
    for be in [false, true] {
        let l = read_mesh_from_bytes(&ply_binary(be), "b.ply").unwrap();
        assert_eq!(l.mesh.n_vertices(), 4);
        assert_eq!(l.mesh.triangles()[1], [0, 1, 3]);
        assert_eq!(l.mesh.positions()[0], [f64::from(0.1f32), 0.0, 0.0]);
        assert_eq!(l.mesh.positions()[3], [0.0, 0.0, 1.0]);
        assert!(l.vertex_colors.is_none());
    }
}

// ---------------------------------------------------------------- STL

const STL_ASCII: &str = "solid two\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n  endloop\n endfacet\n\
 facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 1 0\n   vertex 0 1 -0\n  endloop\n endfacet\nendsolid two\n";

#[test]
fn stl_ascii_welds_shared_corners() {
    let l = load(STL_ASCII, "two.stl");
    assert_eq!(l.format, MeshFormat::Stl);
    assert_eq!(l.mesh.n_vertices(), 4);
    assert_eq!(l.mesh.triangles(), &[[0, 1, 2], [0, 2, 3]]);
    // "solid" without a name is fine too.
    let l = load(&STL_ASCII.replacen("solid two", "solid", 1), "two.stl");
    assert_eq!(l.mesh.n_triangles(), 2);
}

fn stl_binary(header: &[u8], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b[..header.len()].copy_from_slice(header);
    b.extend((tris.len() as u32).to_le_bytes());
    for t in tris {
        b.extend([0u8; 12]);
        for v in t {
            for c in v {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

#[test]
fn stl_binary_welds_and_is_detected_even_with_a_solid_header() {
    let tris = [
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[1.0, 0.0, 0.0], [-0.0, 1.0, 0.0], [1.0, 1.0, 0.5]],
        [[2.0, 2.0, 2.0], [2.0, 2.0, 2.0], [3.0, 2.0, 2.0]],
    ];
    for header in [&b"binary"[..], &b"solid but actually binary"[..]] {
        let b = stl_binary(header, &tris);
        // No extension: detected from the content.
        let l = read_mesh_from_bytes(&b, "upload").unwrap();
        assert_eq!(l.format, MeshFormat::Stl);
        assert_eq!(l.mesh.n_vertices(), 4, "welded, degenerate facet dropped");
        assert_eq!(l.mesh.triangles(), &[[0, 1, 2], [1, 2, 3]]);
        assert!(l.warnings.iter().any(|w| w.contains("identical corners")));
    }
}

// ---------------------------------------------------------------- detection

#[test]
fn format_from_extension_content_and_lies() {
    let off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    // Missing extension.
    let l = load(off, "upload");
    assert_eq!(l.format, MeshFormat::Off);
    assert!(!l.warnings.is_empty());
    // Lying extension.
    let l = load(off, "lies.obj");
    assert_eq!(l.format, MeshFormat::Off);
    assert!(
        l.warnings.iter().any(|w| w.contains("says OBJ")),
        "{:?}",
        l.warnings
    );
    let l = load(&ply_ascii("vertex_indices"), "x.stl");
    assert_eq!(l.format, MeshFormat::Ply);
    let l = load("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "noext");
    assert_eq!(l.format, MeshFormat::Obj);
    let l = load(STL_ASCII, "x.OFF");
    assert_eq!(l.format, MeshFormat::Stl);
    // Upper-case extensions are fine.
    assert_eq!(load(off, "A.OFF").format, MeshFormat::Off);
}

#[test]
fn mesh_format_parse_display_and_from_path() {
    use std::path::Path;
    for f in MeshFormat::ALL {
        assert_eq!(f.to_string().parse::<MeshFormat>().unwrap(), f);
        assert_eq!(f.extension().parse::<MeshFormat>().unwrap(), f);
    }
    assert_eq!(".Ply".parse::<MeshFormat>().unwrap(), MeshFormat::Ply);
    assert!("vrml".parse::<MeshFormat>().is_err());
    assert_eq!(
        MeshFormat::from_path(Path::new("a/b.Obj")),
        Some(MeshFormat::Obj)
    );
    assert_eq!(MeshFormat::from_path(Path::new("a/b")), None);
    assert_eq!(MeshFormat::from_path(Path::new("a/b.txt")), None);
}

#[test]
fn large_polygon_is_fanned_with_a_warning() {
    // A convex 80-gon: above the ear-clipping limit, so it is fanned and a warning says so.
    let k = 80;
    let mut src = format!("OFF\n{k} 1 0\n");
    for i in 0..k {
        let a = std::f64::consts::TAU * f64::from(i) / f64::from(k);
        src.push_str(&format!("{} {} 0\n", a.cos(), a.sin()));
    }
    src.push_str(&format!("{k}"));
    for i in 0..k {
        src.push_str(&format!(" {i}"));
    }
    src.push('\n');
    let l = load(&src, "big.off");
    assert_eq!(l.mesh.n_triangles(), 78);
    assert_eq!(l.polygons_triangulated, 1);
    assert!(
        l.warnings.iter().any(|w| w.contains("fan")),
        "{:?}",
        l.warnings
    );
    assert_eq!(l.mesh.triangles()[5], [0, 6, 7]);
}

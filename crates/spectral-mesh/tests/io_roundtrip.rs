//! Writing then reading gives back bit-identical positions and identical triangles.

#![allow(clippy::unwrap_used)]

use spectral_mesh::Mesh;
use spectral_mesh::io::{
    IoError, MeshFormat, WriteOptions, read_mesh, read_mesh_from_bytes, write_mesh, write_mesh_to,
};

/// A small mesh with awkward coordinates: thirds, tiny, huge, subnormal, negative zero.
fn awkward() -> Mesh {
    let p = vec![
        [1.0 / 3.0, -0.0, 0.1 + 0.2],
        [1e-300, 5e-324, -2.5e300],
        [std::f64::consts::PI, -1.0 / 7.0, 123_456_789.123_456_79],
        [0.0, 1.0, f64::MIN_POSITIVE],
        [-1e-7, 7e22, 2.0f64.sqrt()],
    ];
    let t = vec![[0, 1, 2], [0, 2, 3], [3, 2, 4], [4, 1, 0]];
    Mesh::new(p, t).unwrap()
}

fn same_bits(a: &Mesh, b: &Mesh) {
    assert_eq!(a.n_vertices(), b.n_vertices());
    for (p, q) in a.positions().iter().zip(b.positions()) {
        assert_eq!(p.map(f64::to_bits), q.map(f64::to_bits), "{p:?} vs {q:?}");
    }
    assert_eq!(a.triangles(), b.triangles());
}

#[test]
fn off_obj_ply_round_trips_are_bit_exact() {
    let m = awkward();
    let cases = [
        (MeshFormat::Off, false),
        (MeshFormat::Obj, false),
        (MeshFormat::Ply, false),
        (MeshFormat::Ply, true),
    ];
    for (format, binary) in cases {
        let opts = WriteOptions {
            binary,
            ..WriteOptions::default()
        };
        let mut buf = Vec::new();
        write_mesh_to(&mut buf, format, &m, &opts).unwrap();
        let name = format!("rt.{}", format.extension());
        let l = read_mesh_from_bytes(&buf, &name).unwrap();
        assert_eq!(l.format, format);
        same_bits(&m, &l.mesh);
        assert!(l.warnings.is_empty(), "{format}: {:?}", l.warnings);
    }
}

#[test]
fn colours_and_scalar_survive_and_scalar_is_in_the_ply() {
    let m = awkward();
    let colors: Vec<[u8; 3]> = (0..5).map(|i| [i * 50, 255 - i * 50, 7]).collect();
    let scalar: Vec<f64> = (0..5).map(|i| f64::from(i) / 3.0 - 1e-17).collect();
    for format in [MeshFormat::Off, MeshFormat::Obj, MeshFormat::Ply] {
        for binary in [false, true] {
            let opts = WriteOptions {
                format: None,
                vertex_colors: Some(colors.clone()),
                vertex_scalar: Some(("heat_t05".to_string(), scalar.clone())),
                binary,
            };
            let mut buf = Vec::new();
            write_mesh_to(&mut buf, format, &m, &opts).unwrap();
            let l = read_mesh_from_bytes(&buf, &format!("c.{}", format.extension())).unwrap();
            same_bits(&m, &l.mesh);
            let got = l.vertex_colors.expect("colours read back");
            for (g, c) in got.iter().zip(&colors) {
                assert_eq!(g.map(|x| (x * 255.0).round() as u8), *c, "{format}");
            }
            if format == MeshFormat::Ply {
                // Check the scalar with an independent PLY parser.
                use ply_rs_bw::parser::Parser;
                use ply_rs_bw::ply::{DefaultElement, Property};
                let ply = Parser::<DefaultElement>::new()
                    .read_ply(&mut std::io::Cursor::new(&buf))
                    .unwrap();
                let vs = &ply.payload["vertex"];
                for (v, s) in vs.iter().zip(&scalar) {
                    assert_eq!(v["heat_t05"], Property::Double(*s));
                }
            }
        }
    }
}

#[test]
fn stl_round_trip_is_exact_for_f32_coordinates() {
    #[rustfmt::skip]
    let p = vec![
        [0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.0, 0.25, 0.0], [0.0, 0.0, f64::from(0.1f32)],
    ];
    // Vertices in order of first appearance, as welding numbers them.
    let t = vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]];
    let m = Mesh::new(p, t).unwrap();
    for binary in [false, true] {
        let mut buf = Vec::new();
        let opts = WriteOptions {
            binary,
            ..WriteOptions::default()
        };
        write_mesh_to(&mut buf, MeshFormat::Stl, &m, &opts).unwrap();
        let l = read_mesh_from_bytes(&buf, "r.stl").unwrap();
        same_bits(&m, &l.mesh);
    }
}

#[test]
fn write_mesh_goes_through_a_temporary_file_and_leaves_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let m = awkward();
    let path = dir.path().join("out.ply");
    write_mesh(&path, &m, &WriteOptions::default()).unwrap();
    // Overwrite with another format forced by the options.
    let opts = WriteOptions {
        format: Some(MeshFormat::Off),
        ..WriteOptions::default()
    };
    write_mesh(&path, &m, &opts).unwrap();
    let l = read_mesh(&path).unwrap();
    assert_eq!(
        l.format,
        MeshFormat::Off,
        "content sniffing beats the extension"
    );
    same_bits(&m, &l.mesh);
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["out.ply".to_string()]);

    // A folder that does not exist: an error naming the path, and no file.
    let bad = dir.path().join("nope").join("x.off");
    let e = write_mesh(&bad, &m, &WriteOptions::default()).unwrap_err();
    assert!(matches!(e, IoError::Io { .. }));
    assert!(e.to_string().contains("x.off"), "{e}");
    assert!(!bad.exists());
    // Unknown extension and no format.
    let e = write_mesh(&dir.path().join("x.vrml"), &m, &WriteOptions::default()).unwrap_err();
    assert!(matches!(e, IoError::UnknownFormat { .. }), "{e}");
}

#[test]
fn inconsistent_write_options_are_refused_without_writing() {
    let dir = tempfile::tempdir().unwrap();
    let m = awkward();
    let path = dir.path().join("x.ply");
    let opts = WriteOptions {
        vertex_colors: Some(vec![[0, 0, 0]; 2]),
        ..WriteOptions::default()
    };
    let e = write_mesh(&path, &m, &opts).unwrap_err();
    assert!(
        e.to_string()
            .contains("2 vertex colours given for 5 vertices"),
        "{e}"
    );
    assert!(e.to_string().contains("x.ply"), "{e}");
    assert!(!path.exists());
    for name in ["has space", "", "x", "a.b"] {
        let opts = WriteOptions {
            vertex_scalar: Some((name.to_string(), vec![0.0; 5])),
            ..WriteOptions::default()
        };
        assert!(write_mesh(&path, &m, &opts).is_err(), "{name:?}");
    }
    let opts = WriteOptions {
        vertex_scalar: Some(("s".to_string(), vec![0.0; 4])),
        ..WriteOptions::default()
    };
    assert!(write_mesh(&path, &m, &opts).is_err());
    assert!(!path.exists());
}

//! Property tests of the writers and readers (`io`): for random meshes (one triangle to
//! dozens, unreferenced vertices, coordinates from subnormal to 1e308, negative zero),
//! every format we write reads back as the same mesh to the format's precision:
//! - OFF, OBJ, PLY ASCII and PLY binary: the same positions bit for bit and the same
//!   triangles, with and without vertex colours (which come back to the byte);
//! - STL ASCII and binary: the corners of every triangle rounded to `f32`, in order, with
//!   equal corners welded; a mesh STL cannot hold (a coordinate beyond the `f32` range, a
//!   triangle whose corners coincide in `f32`) is refused by the writer, not written;
//! - a file of an empty mesh, and one with a NaN or infinite coordinate, is refused with an
//!   error naming the file (and the line, for text formats) and the problem;
//! - per-vertex field files write and read back bit for bit (and `numpy.loadtxt` reads the
//!   same bits: `field_text_reads_back_in_numpy`, run when `SPECTRAL_MESH_PYTHON` names a
//!   Python with NumPy).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use proptest::prelude::*;
use spectral_mesh::Mesh;
use spectral_mesh::io::{
    IoError, MeshFormat, WriteOptions, field_to_text, read_field_text, read_mesh_from_bytes,
    write_mesh_to,
};

/// A coordinate: ordinary, huge (up to 1e308), tiny (down to subnormal), or special.
fn coordinate() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -1e3..1e3f64,
        1 => (-1.0..1.0f64, 290..=307i32).prop_map(|(m, e)| m * 10f64.powi(e)),
        1 => (-1.0..1.0f64, 300..=320i32).prop_map(|(m, e)| m / 10f64.powi(e)),
        1 => prop::sample::select(vec![
            0.0,
            -0.0,
            1.0,
            f64::MAX,
            -f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
            1.0 / 3.0,
            0.1,
        ]),
        1 => any::<f64>().prop_filter("finite", |x| x.is_finite()),
    ]
}

/// A mesh with `3..=24` vertices and `1..=40` triangles of distinct corners; some vertices
/// may be unused.
fn mesh() -> impl Strategy<Value = Mesh> {
    (3usize..=24)
        .prop_flat_map(|n| {
            let pos = prop::collection::vec([coordinate(), coordinate(), coordinate()], n);
            let tri = prop::collection::vec(
                prop::sample::subsequence((0..n).collect::<Vec<_>>(), 3).prop_shuffle(),
                1..=40,
            );
            (pos, tri)
        })
        .prop_map(|(p, t)| {
            let t = t.into_iter().map(|v| [v[0], v[1], v[2]]).collect();
            Mesh::new(p, t).unwrap()
        })
}

/// A mesh with one triangle.
fn one_triangle() -> impl Strategy<Value = Mesh> {
    prop::collection::vec([coordinate(), coordinate(), coordinate()], 3)
        .prop_map(|p| Mesh::new(p, vec![[0, 1, 2]]).unwrap())
}

fn write(mesh: &Mesh, format: MeshFormat, opts: &WriteOptions) -> Result<Vec<u8>, IoError> {
    let mut buf = Vec::new();
    write_mesh_to(&mut buf, format, mesh, opts)?;
    Ok(buf)
}

fn bits(m: &Mesh) -> Vec<[u64; 3]> {
    m.positions().iter().map(|p| p.map(f64::to_bits)).collect()
}

/// The lossless formats: (format, binary).
const EXACT: [(MeshFormat, bool); 4] = [
    (MeshFormat::Off, false),
    (MeshFormat::Obj, false),
    (MeshFormat::Ply, false),
    (MeshFormat::Ply, true),
];

fn exact_round_trip(m: &Mesh, colours: Option<Vec<[u8; 3]>>) -> Result<(), TestCaseError> {
    for (format, binary) in EXACT {
        let opts = WriteOptions {
            binary,
            vertex_colors: colours.clone(),
            ..WriteOptions::default()
        };
        let buf = write(m, format, &opts).unwrap();
        let name = format!("rt.{}", format.extension());
        let l = read_mesh_from_bytes(&buf, &name)
            .map_err(|e| TestCaseError::fail(format!("{format} binary={binary}: {e}")))?;
        prop_assert_eq!(l.format, format);
        prop_assert_eq!(bits(&l.mesh), bits(m), "{} binary={}", format, binary);
        prop_assert_eq!(l.mesh.triangles(), m.triangles());
        if let Some(c) = &colours {
            let got = l
                .vertex_colors
                .as_ref()
                .ok_or_else(|| TestCaseError::fail(format!("{format}: colours lost")))?;
            let bytes: Vec<[u8; 3]> = got
                .iter()
                .map(|c| c.map(|x| (f64::from(x) * 255.0).round() as u8))
                .collect();
            prop_assert_eq!(&bytes, c, "{} binary={}: colours", format, binary);
        }
    }
    Ok(())
}

/// What an STL file of `m` must read back as, or `None` when STL cannot hold `m`: the
/// corners of each triangle rounded to f32 (as f64).
fn stl_expectation(m: &Mesh) -> Option<Vec<[[f64; 3]; 3]>> {
    let mut out = Vec::new();
    for t in 0..m.n_triangles() {
        let c = m.corners(t).map(|p| p.map(|x| x as f32));
        if c.iter().flatten().any(|x| !x.is_finite()) {
            return None;
        }
        let key = |p: [f32; 3]| p.map(|x| (x + 0.0).to_bits());
        if key(c[0]) == key(c[1]) || key(c[1]) == key(c[2]) || key(c[0]) == key(c[2]) {
            return None;
        }
        out.push(c.map(|p| p.map(f64::from)));
    }
    Some(out)
}

fn stl_round_trip(m: &Mesh) -> Result<(), TestCaseError> {
    let want = stl_expectation(m);
    for binary in [false, true] {
        let opts = WriteOptions {
            binary,
            ..WriteOptions::default()
        };
        match (write(m, MeshFormat::Stl, &opts), &want) {
            (Err(e), None) => {
                let msg = e.to_string();
                prop_assert!(msg.contains("f32"), "unclear refusal: {}", msg);
            }
            (Err(e), Some(_)) => {
                return Err(TestCaseError::fail(format!("STL writer refused: {e}")));
            }
            (Ok(_), None) => {
                return Err(TestCaseError::fail(
                    "STL writer accepted a mesh that STL cannot hold",
                ));
            }
            (Ok(buf), Some(want)) => {
                let l = read_mesh_from_bytes(&buf, "rt.stl")
                    .map_err(|e| TestCaseError::fail(format!("binary={binary}: {e}")))?;
                prop_assert_eq!(l.mesh.n_triangles(), want.len());
                for (t, w) in want.iter().enumerate() {
                    let got = l.mesh.corners(t);
                    for k in 0..3 {
                        // -0 and +0 weld: compare values, not bits.
                        prop_assert_eq!(got[k], w[k], "binary={} triangle {}", binary, t);
                    }
                }
                // Welding: one vertex per distinct corner position.
                let mut keys: Vec<[u64; 3]> = want
                    .iter()
                    .flatten()
                    .map(|p| p.map(|x| (x + 0.0).to_bits()))
                    .collect();
                keys.sort_unstable();
                keys.dedup();
                prop_assert_eq!(l.mesh.n_vertices(), keys.len());
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 512,
        failure_persistence: Some(Box::new(
            proptest::test_runner::FileFailurePersistence::WithSource("proptest-regressions"),
        )),
        ..ProptestConfig::default()
    })]

    #[test]
    fn lossless_formats_round_trip_bit_for_bit(m in mesh()) {
        exact_round_trip(&m, None)?;
    }

    #[test]
    fn one_triangle_round_trips(m in one_triangle()) {
        exact_round_trip(&m, None)?;
        stl_round_trip(&m)?;
    }

    #[test]
    fn colours_round_trip_to_the_byte(
        (m, c) in mesh().prop_flat_map(|m| {
            let n = m.n_vertices();
            (Just(m), prop::collection::vec(any::<[u8; 3]>(), n))
        })
    ) {
        exact_round_trip(&m, Some(c))?;
    }

    #[test]
    fn dark_colours_round_trip_to_the_byte(
        (m, c) in mesh().prop_flat_map(|m| {
            let n = m.n_vertices();
            (Just(m), prop::collection::vec([0u8..=1, 0u8..=1, 0u8..=1], n))
        })
    ) {
        exact_round_trip(&m, Some(c))?;
    }

    #[test]
    fn stl_round_trips_to_f32_or_refuses(m in mesh()) {
        stl_round_trip(&m)?;
    }

    #[test]
    fn non_finite_coordinates_are_refused_by_every_reader(
        m in mesh(),
        pick in any::<prop::sample::Index>(),
        d in 0usize..3,
        bad in prop::sample::select(vec!["nan", "NaN", "inf", "-inf", "1e999", "-infinity"]),
    ) {
        let v = pick.index(m.n_vertices());
        let value: f64 = bad.parse().unwrap();
        for (format, binary) in EXACT {
            let opts = WriteOptions { binary, ..WriteOptions::default() };
            let buf = write(&m, format, &opts).unwrap();
            let broken = spoil(&buf, format, binary, m.n_vertices(), v, d, bad, value);
            let name = format!("bad.{}", format.extension());
            match read_mesh_from_bytes(&broken, &name) {
                Ok(_) => return Err(TestCaseError::fail(format!("{format} binary={binary}: {bad} accepted"))),
                Err(e) => {
                    let msg = e.to_string();
                    prop_assert!(msg.starts_with(&name), "{}", msg);
                    prop_assert!(msg.contains("non-finite"), "{}", msg);
                    prop_assert_eq!(e.line().is_some(), !binary, "{}", msg);
                }
            }
        }
        // STL: the first facet's first corner.
        if stl_expectation(&m).is_some() {
            for binary in [false, true] {
                let opts = WriteOptions { binary, ..WriteOptions::default() };
                let mut buf = write(&m, MeshFormat::Stl, &opts).unwrap();
                if binary {
                    let at = 84 + 12 + 4 * d;
                    buf[at..at + 4].copy_from_slice(&(value as f32).to_le_bytes());
                } else {
                    let text = String::from_utf8(buf).unwrap();
                    let line = text.lines().position(|l| l.trim_start().starts_with("vertex")).unwrap();
                    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
                    let mut tok: Vec<String> = lines[line].split_whitespace().map(str::to_string).collect();
                    tok[1 + d] = bad.to_string();
                    lines[line] = tok.join(" ");
                    buf = (lines.join("\n") + "\n").into_bytes();
                }
                let e = read_mesh_from_bytes(&buf, "bad.stl").map(|_| ()).unwrap_err();
                prop_assert_eq!(e.line(), (!binary).then_some(4), "{}", e);
                let e = e.to_string();
                prop_assert!(e.starts_with("bad.stl") && e.contains("non-finite"), "{}", e);
            }
        }
    }

    #[test]
    fn field_files_round_trip_bit_for_bit(
        v in prop::collection::vec(prop_oneof![coordinate(), any::<f64>().prop_filter("finite", |x| x.is_finite())], 0..64)
    ) {
        let text = field_to_text(&v).unwrap();
        let back = read_field_text(&text, "f.txt", Some(v.len())).unwrap();
        prop_assert_eq!(
            back.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
    }

    #[test]
    fn field_files_with_nan_are_refused(
        mut v in prop::collection::vec(-1e3..1e3f64, 1..32),
        pick in any::<prop::sample::Index>(),
        bad in prop::sample::select(vec![f64::NAN, f64::INFINITY, f64::NEG_INFINITY]),
    ) {
        let i = pick.index(v.len());
        v[i] = bad;
        let e = field_to_text(&v).unwrap_err().to_string();
        prop_assert!(e.contains(&format!("value {i} is")), "{}", e);
        // The same value typed into a file is refused at its line.
        let mut text = field_to_text(&vec![1.0; v.len()]).unwrap();
        let mut lines: Vec<&str> = text.lines().collect();
        let b = format!("{bad}");
        lines[i] = &b;
        text = lines.join("\n");
        let e = read_field_text(&text, "f.txt", None).unwrap_err();
        prop_assert_eq!(e.line(), Some(i + 1));
        prop_assert!(e.to_string().contains("not a finite number"), "{}", e);
    }
}

/// `buf` (a mesh written in `format`) with coordinate `d` of vertex `v` (of `n`) replaced:
/// the token `bad` in text formats, the `f64` `value` in binary PLY.
#[allow(clippy::too_many_arguments)]
fn spoil(
    buf: &[u8],
    format: MeshFormat,
    binary: bool,
    n: usize,
    v: usize,
    d: usize,
    bad: &str,
    value: f64,
) -> Vec<u8> {
    if binary {
        let end = b"end_header\n";
        let at = buf.windows(end.len()).position(|w| w == end).unwrap() + end.len();
        let mut out = buf.to_vec();
        let o = at + 24 * v + 8 * d;
        out[o..o + 8].copy_from_slice(&value.to_le_bytes());
        return out;
    }
    let text = String::from_utf8(buf.to_vec()).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    // Index of the first vertex line.
    let first = match format {
        MeshFormat::Off => 2,
        MeshFormat::Obj => 1,
        _ => lines.iter().position(|l| l == "end_header").unwrap() + 1,
    };
    assert!(v < n);
    let line = &mut lines[first + v];
    let mut tok: Vec<String> = line.split_whitespace().map(str::to_string).collect();
    let skip = usize::from(format == MeshFormat::Obj);
    tok[skip + d] = bad.to_string();
    *line = tok.join(" ");
    (lines.join("\n") + "\n").into_bytes()
}

#[test]
fn empty_meshes_are_refused_in_every_format() {
    let cases: [(&str, &[u8]); 8] = [
        ("empty.off", b"OFF\n0 0 0\n"),
        ("vertices-only.off", b"OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"),
        ("empty.obj", b"# nothing\n"),
        ("vertices-only.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        (
            "empty.ply",
            b"ply\nformat ascii 1.0\nelement vertex 0\nproperty double x\nproperty double y\n\
              property double z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
        ),
        ("empty.stl", b"solid e\nendsolid e\n"),
        ("empty-binary.stl", &[0u8; 84]),
        ("nothing.off", b""),
    ];
    for (name, bytes) in cases {
        let e = read_mesh_from_bytes(bytes, name).map(|_| ()).unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with(name), "{msg}");
        assert!(msg.contains("empty"), "{name}: {msg}");
    }
    // And the mesh type itself cannot be empty, so no writer ever sees one.
    assert!(Mesh::new(vec![], vec![]).is_err());
    assert!(Mesh::new(vec![[0.0; 3]; 3], vec![]).is_err());
}

/// The text `field_to_text` writes is read by `numpy.loadtxt` as the same `f64`s, bit for
/// bit. Needs `SPECTRAL_MESH_PYTHON` (a Python with NumPy, e.g. the conformance venv's,
/// `bash scripts/setup-python.sh`); skipped when it is unset.
#[test]
fn field_text_reads_back_in_numpy() {
    let Ok(py) = std::env::var("SPECTRAL_MESH_PYTHON") else {
        eprintln!("skipped: SPECTRAL_MESH_PYTHON is not set");
        return;
    };
    let mut v = vec![
        0.0,
        -0.0,
        5e-324,
        -2.2250738585072014e-308,
        f64::MIN_POSITIVE,
        f64::MAX,
        -f64::MAX,
        0.1,
        1.0 / 3.0,
        1e22,
        1e23,
        123_456_789.123_456_79,
        -1e-7,
        9007199254740993.0,
    ];
    // And a deterministic spread of bit patterns.
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    while v.len() < 2000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let f = f64::from_bits(x);
        if f.is_finite() {
            v.push(f);
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("field.txt");
    spectral_mesh::io::write_field(&path, &v).unwrap();
    let script = "import sys, numpy as np\n\
                  a = np.loadtxt(sys.argv[1], dtype=np.float64, ndmin=1)\n\
                  sys.stdout.write('\\n'.join(format(int(b), 'x') for b in a.view(np.uint64)))\n";
    let out = std::process::Command::new(&py)
        .args(["-c", script])
        .arg(&path)
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: Vec<u64> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| u64::from_str_radix(l, 16).unwrap())
        .collect();
    assert_eq!(got.len(), v.len());
    for (i, (g, w)) in got.iter().zip(&v).enumerate() {
        assert_eq!(*g, w.to_bits(), "value {i}: {w:?}");
    }
}

//! Point files and the one entry point that reads a mesh or a point cloud:
//! `io::read_input_from_bytes` with a file name picked by the first byte (`.xyz`, `.pts`,
//! `.txt`, `.csv`, `.ply`, no extension, a mesh extension, ...; `io/points.rs`, and
//! `io/ply.rs` for vertex-only PLY). Checks: an error names the input and a line that
//! exists; a point cloud has at least one point, finite coordinates, and normals (when
//! kept) one per point, finite and not all zero; a mesh passes the mesh readers' checks; a
//! point cloud written back as `x y z [nx ny nz]` lines (shortest round-trip decimals)
//! reads back bit for bit.

use spectral_mesh::io::{Input, read_input_from_bytes};

const NAMES: [&str; 12] = [
    "p.xyz",
    "p.pts",
    "p.txt",
    "p.csv",
    "p.ply",
    "P.XYZ",
    "p",
    "upload",
    "p.off",
    "p.obj",
    "p.stl",
    "dir/sub/x.pts",
];

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    crate::named(data, &NAMES, |name, rest| {
        let input = match read_input_from_bytes(rest, name) {
            Ok(i) => i,
            Err(e) => {
                crate::check_error(rest, name, &e);
                return;
            }
        };
        let p = match input {
            Input::Mesh(m) => {
                crate::check_loaded_mesh(&m);
                return;
            }
            Input::Points(p) => p,
        };
        let cloud = &p.cloud;
        let n = cloud.n_points();
        assert!(n > 0, "an empty point cloud returned as Ok");
        assert_eq!(cloud.positions().len(), n);
        assert!(
            cloud.positions().iter().flatten().all(|c| c.is_finite()),
            "non-finite coordinate returned as Ok"
        );
        if let Some(nr) = cloud.normals() {
            assert_eq!(nr.len(), n, "one normal per point");
            assert!(
                nr.iter().flatten().all(|c| c.is_finite()),
                "non-finite normal"
            );
            assert!(
                nr.iter().any(|v| v.iter().any(|&c| c != 0.0)),
                "every normal is zero but they were kept"
            );
        }
        // Written back as text and read again: the same bits.
        let mut text = String::new();
        for (i, q) in cloud.positions().iter().enumerate() {
            text.push_str(&format!("{:?} {:?} {:?}", q[0], q[1], q[2]));
            if let Some(nr) = cloud.normals() {
                text.push_str(&format!(" {:?} {:?} {:?}", nr[i][0], nr[i][1], nr[i][2]));
            }
            text.push('\n');
        }
        let back = match read_input_from_bytes(text.as_bytes(), "rt.xyz") {
            Ok(Input::Points(b)) => b,
            Ok(Input::Mesh(_)) => panic!("written points read back as a mesh"),
            Err(e) => panic!("written points do not read back: {e}"),
        };
        let bits = |v: &[[f64; 3]]| v.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(back.cloud.positions()),
            bits(cloud.positions()),
            "positions round trip"
        );
        assert_eq!(
            back.cloud.normals().map(bits),
            cloud.normals().map(bits),
            "normals round trip"
        );
    });
}

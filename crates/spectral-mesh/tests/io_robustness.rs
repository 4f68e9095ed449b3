//! Fuzz-like robustness: truncated files and garbage never panic; they give Ok or Err.

#![allow(clippy::unwrap_used)]

use spectral_mesh::Mesh;
use spectral_mesh::io::{MeshFormat, WriteOptions, read_mesh_from_bytes, write_mesh_to};

/// Small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Feeds `bytes` under `name`; only checks that it returns (a panic fails the test), and
/// that an Ok mesh satisfies the Mesh invariants.
fn feed(bytes: &[u8], name: &str) -> bool {
    match read_mesh_from_bytes(bytes, name) {
        Ok(l) => {
            let m = &l.mesh;
            assert!(m.n_vertices() > 0 && m.n_triangles() > 0);
            assert!(m.positions().iter().flatten().all(|c| c.is_finite()));
            true
        }
        Err(e) => {
            assert!(e.to_string().starts_with(name), "{e}");
            false
        }
    }
}

/// Truncations at several offsets plus byte flips and token garbage.
fn torture(bytes: &[u8], name: &str, rng: &mut Rng) {
    let n = bytes.len();
    let mut cuts: Vec<usize> = vec![0, 1, 2, 3, 4, 5, 8, 13, n / 2, n.saturating_sub(1)];
    for k in 1..8 {
        cuts.push(n * k / 8);
    }
    for _ in 0..4 {
        cuts.push(rng.below(n + 1));
    }
    for &c in &cuts {
        feed(&bytes[..c.min(n)], name);
    }
    // Random byte changes in a copy.
    for _ in 0..6 {
        let mut b = bytes.to_vec();
        for _ in 0..1 + rng.below(8) {
            if !b.is_empty() {
                let i = rng.below(b.len());
                b[i] = rng.next() as u8;
            }
        }
        feed(&b, name);
    }
    // Insert garbage tokens at random places.
    let junk: [&[u8]; 8] = [
        b" -1 ",
        b" 99999999999999999999 ",
        b" nan ",
        b"\n#",
        b" 1e999 ",
        b"\n3 0 0 0\n",
        b"\xff\xfe",
        b" 4294967296 ",
    ];
    for _ in 0..6 {
        let mut b = bytes.to_vec();
        let i = rng.below(b.len() + 1);
        let j = junk[rng.below(junk.len())];
        b.splice(i..i, j.iter().copied());
        feed(&b, name);
    }
}

fn tetra() -> Mesh {
    #[rustfmt::skip]
    let corners = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let faces = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    Mesh::new(corners, faces).unwrap()
}

#[test]
fn shared_off_files_truncated_and_mangled_never_panic() {
    let Some(names) = spectral_mesh_testkit::shared_mesh_files(Some("off")) else {
        return;
    };
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut count = 0;
    for p in names {
        let bytes = std::fs::read(&p).unwrap();
        // The full file must load; a cut just before the end must not.
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        assert!(feed(&bytes, &name), "{name}");
        // Start of the last line that is neither blank nor a comment: the last face.
        let mut last_line_start = 0;
        let mut pos = 0;
        for line in bytes.split(|&b| b == b'\n') {
            let t = line.trim_ascii();
            if !t.is_empty() && !t.starts_with(b"#") {
                last_line_start = pos;
            }
            pos += line.len() + 1;
        }
        assert!(
            !feed(&bytes[..last_line_start], &name),
            "{name} without its last face should fail"
        );
        torture(&bytes, &name, &mut rng);
        count += 1;
    }
    assert!(count > 0);
}

#[test]
fn every_format_survives_truncation_and_garbage() {
    let mut rng = Rng(42);
    let m = tetra();
    for format in MeshFormat::ALL {
        for binary in [false, true] {
            let opts = WriteOptions {
                binary,
                vertex_colors: Some(vec![[1, 2, 3]; 4]),
                ..WriteOptions::default()
            };
            let mut buf = Vec::new();
            write_mesh_to(&mut buf, format, &m, &opts).unwrap();
            let name = format!("f.{}", format.extension());
            assert!(feed(&buf, &name));
            torture(&buf, &name, &mut rng);
            torture(&buf, "noext", &mut rng);
        }
    }
    // Pure garbage under every name.
    for _ in 0..200 {
        let len = rng.below(300);
        let b: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
        for name in ["g.off", "g.obj", "g.ply", "g.stl", "g"] {
            feed(&b, name);
        }
    }
    // Garbage after a valid header.
    for head in [
        &b"OFF\n"[..],
        b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
        b"ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nend_header\n",
        b"solid x\n",
    ] {
        for _ in 0..50 {
            let mut b = head.to_vec();
            let len = rng.below(200);
            b.extend((0..len).map(|_| rng.next() as u8));
            feed(&b, "h.off");
            feed(&b, "h.ply");
            feed(&b, "h.stl");
        }
    }
}

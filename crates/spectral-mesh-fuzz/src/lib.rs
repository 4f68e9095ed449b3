//! The checks behind the fuzz targets, one module per target in [`targets`], and the
//! helpers they share.
//!
//! Every target feeds bytes to a library entry point and then asserts what the library
//! promises: a clean `Err` whose message names the input, or a valid result (a [`Mesh`]
//! that holds its invariants and survives a write-then-read round trip). A panic, an
//! abort, a hang (libFuzzer's `-timeout`) or an allocation over `-rss_limit_mb` is a
//! finding.
//!
//! Two callers: libFuzzer (`fuzz/fuzz_targets/NAME.rs`, one line each, built by
//! `cargo fuzz`), and this crate's tests, which replay every committed seed
//! (`fuzz/seeds/NAME`) and every regression input (`fuzz/regressions/NAME`) as ordinary
//! tests of the workspace, so CI checks them without building instrumented binaries.

#![allow(clippy::unwrap_used, clippy::expect_used)]

pub mod targets;

use arbitrary::{Arbitrary, Unstructured};
use spectral_mesh::Mesh;
use spectral_mesh::io::{IoError, LoadedMesh, MeshFormat, WriteOptions};

/// Runs `check` on a file named by the first byte of `data` (picked among `names`) whose
/// content is the rest of the bytes; an empty input is nothing to check.
pub fn named(data: &[u8], names: &[&'static str], check: impl FnOnce(&'static str, &[u8])) {
    if let Some((&b, rest)) = data.split_first() {
        check(names[usize::from(b) % names.len()], rest);
    }
}

/// Asserts the invariants [`Mesh::new`] promises (a reader must never hand out a mesh
/// that breaks them).
pub fn check_mesh(m: &Mesh) {
    let n = m.n_vertices();
    assert!(n > 0 && m.n_triangles() > 0, "empty mesh returned as Ok");
    assert!(
        m.positions().iter().flatten().all(|c| c.is_finite()),
        "non-finite coordinate returned as Ok"
    );
    for t in m.triangles() {
        assert!(t.iter().all(|&i| i < n), "index out of range: {t:?}");
        assert!(
            t[0] != t[1] && t[1] != t[2] && t[0] != t[2],
            "repeated vertex: {t:?}"
        );
    }
}

/// Number of lines of `bytes` (a line number in an error may be at most this plus one).
fn line_count(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b == b'\n').count() + 1
}

/// Checks a reader's result for `bytes` read under `name`: an `Err` names the file (and a
/// line that exists), an `Ok` mesh is valid, with colours for every vertex in `[0, 1]`.
pub fn check_loaded(bytes: &[u8], name: &str, r: &Result<LoadedMesh, IoError>) {
    match r {
        Ok(l) => check_loaded_mesh(l),
        Err(e) => check_error(bytes, name, e),
    }
}

/// A mesh a reader returned: valid, with colours for every vertex in `[0, 1]`.
pub fn check_loaded_mesh(l: &LoadedMesh) {
    check_mesh(&l.mesh);
    if let Some(c) = &l.vertex_colors {
        assert_eq!(c.len(), l.mesh.n_vertices(), "one colour per vertex");
        assert!(
            c.iter().flatten().all(|x| (0.0..=1.0).contains(x)),
            "colour outside [0, 1]"
        );
    }
}

/// A reader's error for `bytes` read under `name`: it names the file first, and a line
/// that exists (or the one after the last).
pub fn check_error(bytes: &[u8], name: &str, e: &IoError) {
    let text = e.to_string();
    assert!(
        text.starts_with(name),
        "error does not name the input: {text}"
    );
    assert_eq!(e.path(), name);
    if let Some(line) = e.line() {
        assert!(
            line >= 1 && line <= line_count(bytes) + 1,
            "error names line {line} of a {}-line input: {text}",
            line_count(bytes)
        );
    }
}

/// Writes `m` in `format` and reads it back: OFF, OBJ and PLY (ASCII and binary) give the
/// same positions bit for bit and the same triangles; STL gives the same after rounding to
/// `f32` when `m` came from an STL file (its coordinates are `f32` already, its vertices
/// all used, in order of first use).
pub fn check_round_trip(m: &Mesh, format: MeshFormat, binary: bool) {
    let opts = WriteOptions {
        binary,
        ..WriteOptions::default()
    };
    let mut buf = Vec::new();
    if let Err(e) = spectral_mesh::io::write_mesh_to(&mut buf, format, m, &opts) {
        // Only STL may refuse a mesh (coordinates outside the f32 range).
        assert_eq!(
            format,
            MeshFormat::Stl,
            "{format} writer refused a valid mesh: {e}"
        );
        return;
    }
    let name = format!("round-trip.{}", format.extension());
    let back = match spectral_mesh::io::read_mesh_from_bytes(&buf, &name) {
        Ok(l) => l,
        Err(e) => panic!("{format} (binary: {binary}) output does not read back: {e}"),
    };
    assert_eq!(back.format, format);
    let b = &back.mesh;
    assert_eq!(b.n_vertices(), m.n_vertices(), "{format}: vertex count");
    assert_eq!(b.triangles(), m.triangles(), "{format}: triangles");
    for (p, q) in m.positions().iter().zip(b.positions()) {
        assert_eq!(
            p.map(f64::to_bits),
            q.map(f64::to_bits),
            "{format}: {p:?} read back as {q:?}"
        );
    }
}

/// Reads `bytes` as `name`, checks the result, and round-trips an `Ok` mesh through the
/// writer of the format it was read as.
pub fn read_and_check(bytes: &[u8], name: &str) -> Option<LoadedMesh> {
    let r = spectral_mesh::io::read_mesh_from_bytes(bytes, name);
    check_loaded(bytes, name, &r);
    let l = r.ok()?;
    match l.format {
        MeshFormat::Stl => {
            if l.mesh.n_vertices() == used_vertices(&l.mesh) {
                check_round_trip(&l.mesh, MeshFormat::Stl, true);
            }
        }
        MeshFormat::Ply => {
            check_round_trip(&l.mesh, MeshFormat::Ply, false);
            check_round_trip(&l.mesh, MeshFormat::Ply, true);
        }
        f => check_round_trip(&l.mesh, f, false),
    }
    Some(l)
}

fn used_vertices(m: &Mesh) -> usize {
    let mut used = vec![false; m.n_vertices()];
    for t in m.triangles() {
        for &v in t {
            used[v] = true;
        }
    }
    used.iter().filter(|&&u| u).count()
}

/// A small mesh drawn from fuzzer bytes: up to `max_vertices` positions on a coarse
/// integer grid (so coincident points, collinear and zero-area triangles are common),
/// times a scale from `1e-300` to `1e300`, and triangles over them (repeated corners are
/// dropped, since [`Mesh::new`] refuses them). `None` when nothing valid came out.
pub fn arbitrary_mesh(u: &mut Unstructured<'_>, max_vertices: usize) -> Option<Mesh> {
    let scale_exp = i16::from(i8::arbitrary(u).ok()?).clamp(-100, 100) * 3;
    let scale = 10f64.powi(i32::from(scale_exp));
    let n = usize::from(u8::arbitrary(u).ok()?).clamp(3, max_vertices.max(3));
    let mut positions = Vec::with_capacity(n);
    for _ in 0..n {
        let p = <[i8; 3]>::arbitrary(u).ok()?;
        positions.push(p.map(|c| f64::from(c) * scale));
    }
    let mut triangles = Vec::new();
    // `Unstructured` yields zeros once the input is used up: stop there.
    while !u.is_empty() && triangles.len() < 4 * max_vertices {
        let t = <[u8; 3]>::arbitrary(u).ok()?.map(|i| usize::from(i) % n);
        if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
            triangles.push(t);
        }
    }
    Mesh::new(positions, triangles).ok()
}

//! Eigenbasis archives (`spectral::store::load_npz_from_reader`, what `load_npz` and the
//! basis cache of `eigs --cache` read): the input is split at `NPYSEP` into the `.npy`
//! members `eigenvalues`, `eigenvectors`, `mass_data`, `mass_indices`, `mass_indptr`,
//! `mass_shape`, `residuals`, `meta` (in that order), zipped (stored, so the fuzzer's
//! changes reach the arrays instead of failing a checksum); with the first byte `0x80`
//! the rest is read as a whole archive. A loaded basis is consistent: `n x k` finite
//! vectors, `k` finite values, an `n x n` mass.

use std::io::{Cursor, Write};

use spectral_mesh::spectral::store::load_npz_from_reader;

const NAMES: [&str; 8] = [
    "eigenvalues",
    "eigenvectors",
    "mass_data",
    "mass_indices",
    "mass_indptr",
    "mass_shape",
    "residuals",
    "meta",
];

fn split<'a>(data: &'a [u8], sep: &[u8]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut rest = data;
    while let Some(i) = rest.windows(sep.len()).position(|w| w == sep) {
        out.push(&rest[..i]);
        rest = &rest[i + sep.len()..];
    }
    out.push(rest);
    out
}

/// Runs one input of the target (what libFuzzer calls, and what the seed replay calls).
pub fn run(data: &[u8]) {
    let archive = if data.first() == Some(&0x80) {
        data[1..].to_vec()
    } else {
        let mut buf = Cursor::new(Vec::new());
        let mut zip = zip::ZipWriter::new(&mut buf);
        let opts = zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Stored);
        for (name, part) in NAMES.iter().zip(split(data, b"NPYSEP")) {
            if zip.start_file(format!("{name}.npy"), opts).is_err() || zip.write_all(part).is_err()
            {
                return;
            }
        }
        if zip.finish().is_err() {
            return;
        }
        buf.into_inner()
    };
    match load_npz_from_reader(Cursor::new(&archive), "fuzz.npz") {
        Ok((b, meta)) => {
            assert!(b.n >= 1 && b.k() >= 1);
            assert_eq!((b.n, b.k()), (meta.n, meta.k));
            assert_eq!(b.values.len(), b.k());
            assert_eq!(b.vectors.len(), b.n * b.k());
            assert!(b.values.iter().chain(&b.vectors).all(|x| x.is_finite()));
            assert_eq!((b.mass.nrows(), b.mass.ncols()), (b.n, b.n));
            assert!(b.residuals.is_empty() || b.residuals.len() == b.k());
        }
        Err(e) => assert!(e.to_string().starts_with("fuzz.npz"), "{e}"),
    }
}

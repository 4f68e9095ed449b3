//! The disk cache of the learning operators: one `.npz` archive per shape and parameters,
//! named by the shape's content hash and a hash of the parameters.
//!
//! Arrays (all readable by `numpy.load`; the names are those of DiffusionNet's cache):
//! `frames` `(n, 3, 3)`, `mass` `(n,)`, `evals` `(k,)`, `evecs` `(n, k)` (Fortran order),
//! and `L`, `gradX`, `gradY` in SciPy's CSC layout (`L_data`, `L_indices`, `L_indptr`,
//! `L_shape`, ...; `scipy.sparse.csc_matrix((data, indices, indptr), shape=shape)`), all
//! float64 (int64 indices); `meta`, a JSON document as a uint8 array ([`CacheMeta`]).

use std::path::{Path, PathBuf};

use super::{LearningError, LearningOperators, LearningParams, LearningShape, compute_operators};
use crate::cancel::CancelToken;
use crate::linalg::EigenProgress;
use crate::spectral::store::{NpzReader, NpzWriter, StoreError, io_err, npy_1d, write_npy_f64};

/// Version of the archive layout; a change makes every older file a cache miss.
pub const CACHE_FORMAT_VERSION: u32 = 1;

/// What a cache archive says about how it was made; a file is used only when all of it
/// matches the request.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CacheMeta {
    /// [`CACHE_FORMAT_VERSION`].
    pub format_version: u32,
    /// The shape's content hash ([`LearningShape::content_hash`]).
    pub content_hash: String,
    /// [`cache_key`] of the request (the content hash, the parameters, the given normals).
    pub key: String,
    /// The parameters.
    pub params: LearningParams,
    /// Number of vertices.
    pub n: usize,
    /// Number of eigenpairs.
    pub k: usize,
    /// The program that wrote the file.
    pub generator: String,
}

/// The key of a request: BLAKE3 (hex) of the format version, the shape's content hash,
/// the parameters (JSON) and, when given, the normals (little-endian f64).
pub fn cache_key(
    content_hash: &str,
    normals: Option<&[[f64; 3]]>,
    params: &LearningParams,
) -> String {
    let mut h = blake3::Hasher::new();
    h.update(&CACHE_FORMAT_VERSION.to_le_bytes());
    h.update(content_hash.as_bytes());
    h.update(&serde_json::to_vec(params).unwrap_or_default());
    match normals {
        None => {
            h.update(b"estimated normals");
        }
        Some(nr) => {
            h.update(b"given normals");
            for v in nr {
                for c in v {
                    h.update(&c.to_le_bytes());
                }
            }
        }
    }
    h.finalize().to_hex().to_string()
}

/// The archive's file name: the first 16 digits of the content hash and of the key.
pub fn cache_file_name(content_hash: &str, key: &str) -> String {
    format!(
        "{}-{}.npz",
        &content_hash[..content_hash.len().min(16)],
        &key[..key.len().min(16)]
    )
}

/// Writes `ops` to `path` (atomically: a temporary file renamed into place) with `meta`.
pub fn save_operators(
    ops: &LearningOperators,
    path: &Path,
    meta: &CacheMeta,
) -> Result<(), StoreError> {
    let e = io_err(path);
    let (n, k) = (ops.n() as u64, ops.k() as u64);
    let meta_json = serde_json::to_vec(meta).map_err(|err| StoreError::Format {
        path: path.display().to_string(),
        reason: err.to_string(),
    })?;
    let frames: Vec<f64> = ops.frames.iter().flatten().flatten().copied().collect();
    let meta = npy_1d(&meta_json).map_err(&e)?;
    crate::io::write_atomic_with(path, |file| {
        let mut npz = NpzWriter::new(std::io::BufWriter::new(file));
        // Stored, not deflated (as NumPy's `savez`): the cache is read far more often than
        // it is written, and deflate shrinks floating-point data little. Every array is
        // streamed from the operators (no copy as bytes first).
        for (name, data, shape, fortran) in [
            ("frames", &frames[..], &[n, 3, 3][..], false),
            ("mass", &ops.mass[..], &[n][..], false),
            ("evals", &ops.evals[..], &[k][..], false),
            ("evecs", &ops.evecs[..], &[n, k][..], true),
        ] {
            write_npy_f64(npz.start(name, false)?, data, shape, fortran)?;
        }
        for (name, m) in [
            ("L", &ops.laplacian),
            ("gradX", &ops.grad_x),
            ("gradY", &ops.grad_y),
        ] {
            npz.add_csc(name, m)?;
        }
        npz.add("meta", &meta, false)?;
        npz.finish()
    })
    .map_err(|err| e(err.source))
}

/// Reads an archive written by [`save_operators`]: the operators and the metadata. Every
/// array is checked (sizes against the metadata, CSC structure, finiteness) so that a
/// damaged file gives [`StoreError::Format`], never a panic.
pub fn load_operators(path: &Path) -> Result<(LearningOperators, CacheMeta), StoreError> {
    let mut npz = NpzReader::open(path)?;
    let meta: CacheMeta = npz.meta()?;
    let (n, k) = (meta.n, meta.k);
    let mut f64s = |name: &str, len: usize, fortran: bool| -> Result<Vec<f64>, StoreError> {
        let f = npz.array(name)?;
        let order = if fortran {
            npyz::Order::Fortran
        } else {
            npyz::Order::C
        };
        if f.order() != order {
            return Err(npz.error(format!("array '{name}' is not in the order written")));
        }
        let v = npz.f64s_of(f, name)?;
        if v.len() != len {
            return Err(npz.error(format!("array '{name}' has {} values, not {len}", v.len())));
        }
        npz.check_finite(&v, name)?;
        Ok(v)
    };
    let frames_flat = f64s("frames", 9 * n, false)?;
    let mass = f64s("mass", n, false)?;
    let evals = f64s("evals", k, false)?;
    let evecs = f64s("evecs", n * k, true)?;
    let laplacian = npz.square_csc("L", n)?;
    let grad_x = npz.square_csc("gradX", n)?;
    let grad_y = npz.square_csc("gradY", n)?;
    let frames = frames_flat
        .chunks_exact(9)
        .map(|c| [[c[0], c[1], c[2]], [c[3], c[4], c[5]], [c[6], c[7], c[8]]])
        .collect();
    Ok((
        LearningOperators {
            frames,
            mass,
            laplacian,
            evals,
            evecs,
            grad_x,
            grad_y,
        },
        meta,
    ))
}

/// The operators of `shape` from the cache folder `cache_dir` when a matching archive is
/// there, otherwise computed ([`compute_operators`]) and stored there (the folder is
/// created). An archive is used only when its metadata names the same content hash, key
/// (parameters and normals), format version and sizes; an unreadable or different one is
/// recomputed and overwritten. Returns the operators, `true` when they came from the
/// cache, and the archive's path.
pub fn load_or_compute(
    cache_dir: &Path,
    shape: LearningShape<'_>,
    normals: Option<&[[f64; 3]]>,
    params: &LearningParams,
    progress: &mut dyn FnMut(EigenProgress),
    cancel: &CancelToken,
) -> Result<(LearningOperators, bool, PathBuf), LearningError> {
    let content_hash = shape.content_hash();
    let key = cache_key(&content_hash, normals, params);
    let path = cache_dir.join(cache_file_name(&content_hash, &key));
    if path.is_file()
        && let Ok((ops, meta)) = load_operators(&path)
        && meta.format_version == CACHE_FORMAT_VERSION
        && meta.content_hash == content_hash
        && meta.key == key
        && meta.params == *params
        && meta.n == shape.n()
        && meta.k == params.k_eig
    {
        return Ok((ops, true, path));
    }
    let ops = compute_operators(shape, normals, params, progress, cancel)?;
    std::fs::create_dir_all(cache_dir).map_err(io_err(cache_dir))?;
    let meta = CacheMeta {
        format_version: CACHE_FORMAT_VERSION,
        content_hash,
        key,
        params: params.clone(),
        n: ops.n(),
        k: ops.k(),
        generator: format!("spectral-mesh {}", env!("CARGO_PKG_VERSION")),
    };
    save_operators(&ops, &path, &meta)?;
    Ok((ops, false, path))
}
